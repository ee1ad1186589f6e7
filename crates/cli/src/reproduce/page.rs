//! `docs/results.md` from its hand-written template and the reproduction's
//! documents. The template is Markdown with two kinds of placeholders:
//!
//! * a line `<!-- reproduce: KIND [ARG] -->` becomes a generated block
//!   (see [`Block`]): a table beside the thesis's numbers, a document's
//!   terminal report with its command, …;
//! * `{{NAME:PATH}}` or `{{NAME:PATH:D}}` inside prose becomes the number at
//!   the JSON `PATH` of document `NAME` (`results[4].block_pos_err.mean`),
//!   with `D` decimals (default 4), so that numbers quoted in sentences are
//!   generated too.
//!
//! Nothing else of the template changes, except that an HTML comment
//! opening it (notes for its editors) is dropped; an unknown placeholder,
//! document or path is an error naming it, never an empty cell.

use std::fmt::Write as _;

use learner::eval::MeanStd;

use super::calibration::CalibrationRow;
use super::manifest::{Entry, SPREAD_SEEDS};
use super::{Reproduction, RESULTS_DIR, TEMPLATE};
use crate::experiment::{LATENCY_MAX_STEPS, LATENCY_MAX_STEPS_HARSH};
use crate::models::ModelKind;
use crate::report::reference::{self, Ms};
use crate::results::push_task::{CurveEntry, SelectionCount};
use crate::results::{MttReport, PushReport, Setup};
use crate::spec::Document;
use crate::sweep::summary::{change_label, Metric};

/// How a generated block's line starts.
const DIRECTIVE: &str = "<!-- reproduce:";

/// Why the page cannot be generated.
#[derive(Debug, thiserror::Error)]
pub enum PageError {
    #[error("{TEMPLATE} line {line}: {message}")]
    Template { line: usize, message: String },
}

/// What a `<!-- reproduce: … -->` line expands to.
enum Block<'a> {
    /// `targets`: the issue's targets, seed 1 and the spread of seeds 2–5.
    Targets,
    /// `calibration`: the sweep's table and the facts the thesis states.
    Calibration,
    /// `curves MODEL`: the learning curve beside lockstep, the harsh latency
    /// and the thesis.
    Curves(ModelKind),
    /// `report NAME`: the command and the terminal report of one document.
    Report(&'a str),
    /// `move-to-target`: reached targets per model and timing setting.
    MoveToTarget,
    /// `latency`: the default latency maximum beside the harsh one.
    Latency,
    /// `actuator-folds NAME`: the per-fold actuator errors of a curve.
    ActuatorFolds(&'a str),
    /// `selectors`: the interaction model's selectors on the draft protocol.
    Selectors,
    /// The baselines beside the built-in models (`manifest::BASELINES`).
    Baselines,
    /// `beyond-targets`: the improved models' targets, met or missed.
    BeyondTargets,
    /// `beyond-ablation`: the push task's curve of each change and gate+.
    BeyondAblation,
    /// `beyond-objects`: the new-object experiments, learner by condition.
    BeyondObjects,
    /// `beyond-move-to-target`: Move to Target, thesis's and sampled targets.
    BeyondMoveToTarget,
    /// `ablation`: the ablation sweep, configuration by training runs.
    Ablation,
    /// `commands`: every experiment's stand-alone command.
    Commands,
}

impl<'a> Block<'a> {
    fn parse(text: &'a str) -> Result<Self, String> {
        let mut words = text.split_whitespace();
        let kind = words.next().unwrap_or_default();
        let arg = words.next();
        let model = |arg: Option<&str>| match arg {
            Some("gate") => Ok(ModelKind::Gate),
            Some("interaction") => Ok(ModelKind::Interaction),
            other => Err(format!(
                "`{kind}` needs a model (gate or interaction), got {other:?}"
            )),
        };
        let name =
            |arg: Option<&'a str>| arg.ok_or_else(|| format!("`{kind}` needs a document name"));
        let block = match kind {
            "targets" => Block::Targets,
            "calibration" => Block::Calibration,
            "curves" => Block::Curves(model(arg)?),
            "report" => Block::Report(name(arg)?),
            "move-to-target" => Block::MoveToTarget,
            "latency" => Block::Latency,
            "actuator-folds" => Block::ActuatorFolds(name(arg)?),
            "selectors" => Block::Selectors,
            "baselines" => Block::Baselines,
            "beyond-targets" => Block::BeyondTargets,
            "beyond-ablation" => Block::BeyondAblation,
            "beyond-move-to-target" => Block::BeyondMoveToTarget,
            "beyond-objects" => Block::BeyondObjects,
            "ablation" => Block::Ablation,
            "commands" => Block::Commands,
            other => return Err(format!("unknown block `{other}`")),
        };
        if words.next().is_some() {
            return Err(format!("`{text}` has more arguments than `{kind}` takes"));
        }
        Ok(block)
    }
}

/// The page: `template` with every placeholder replaced.
///
/// # Errors
/// A placeholder that is unknown or names a document or value the
/// reproduction does not have.
pub fn generate(template: &str, results: &Reproduction) -> Result<String, PageError> {
    let mut page = String::new();
    // A comment opening the template is for its editors, not the page.
    let skip = if template.starts_with("<!--") && !template.starts_with(DIRECTIVE) {
        template
            .lines()
            .position(|l| l.contains("-->"))
            .map_or(0, |end| end + 1)
    } else {
        0
    };
    for (i, line) in template.lines().enumerate().skip(skip) {
        let error = |message: String| PageError::Template {
            line: i + 1,
            message,
        };
        if let Some(directive) = line
            .trim()
            .strip_prefix(DIRECTIVE)
            .and_then(|rest| rest.strip_suffix("-->"))
        {
            let block = Block::parse(directive.trim()).map_err(error)?;
            page.push_str(&render(&block, results).map_err(error)?);
            // A blank line after each block, so that adjacent blocks stay
            // separate Markdown blocks.
            if !page.ends_with("\n\n") {
                page.push('\n');
            }
        } else {
            page.push_str(&inline_values(line, results).map_err(error)?);
            page.push('\n');
        }
    }
    Ok(page)
}

fn inline_values(line: &str, results: &Reproduction) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = line;
    while let Some(start) = rest.find("{{") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 2..];
        let end = after
            .find("}}")
            .ok_or_else(|| "`{{` without `}}`".to_owned())?;
        out.push_str(&value(&after[..end], results)?);
        rest = &after[end + 2..];
    }
    out.push_str(rest);
    Ok(out)
}

/// `NAME:PATH[:D]`.
fn value(spec: &str, results: &Reproduction) -> Result<String, String> {
    let mut parts = spec.split(':');
    let (Some(name), Some(path)) = (parts.next(), parts.next()) else {
        return Err(format!("`{{{{{spec}}}}}` is not NAME:PATH[:DECIMALS]"));
    };
    let decimals: usize = match parts.next() {
        Some(d) => d
            .parse()
            .map_err(|_| format!("`{d}` in `{{{{{spec}}}}}` is not a number of decimals"))?,
        None => 4,
    };
    let text = match (results.document(name), results.sweep(name)) {
        (Some(document), _) => document.to_json(),
        (None, Some(summary)) => summary.to_json(),
        (None, None) => return Err(format!("no document `{name}` in this reproduction")),
    }
    .map_err(|e| format!("cannot serialise `{name}`: {e}"))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("cannot read `{name}` back: {e}"))?;
    let mut at = &json;
    for step in path.split('.') {
        let (key, indices) = match step.find('[') {
            Some(i) => (&step[..i], &step[i..]),
            None => (step, ""),
        };
        if !key.is_empty() {
            at = at
                .get(key)
                .ok_or_else(|| format!("`{name}` has no `{key}` in `{path}`"))?;
        }
        for index in indices.split('[').filter(|s| !s.is_empty()) {
            let i: usize = index
                .trim_end_matches(']')
                .parse()
                .map_err(|_| format!("`[{index}` in `{path}` is not an index"))?;
            at = at
                .get(i)
                .ok_or_else(|| format!("`{name}`: `{path}` has no entry {i}"))?;
        }
    }
    match at {
        serde_json::Value::Number(n) if n.is_f64() => {
            Ok(format!("{:.decimals$}", n.as_f64().unwrap_or(f64::NAN)))
        }
        serde_json::Value::Number(n) => Ok(n.to_string()),
        other => Err(format!("`{name}:{path}` is {other}, not a number")),
    }
}

fn render(block: &Block<'_>, results: &Reproduction) -> Result<String, String> {
    match block {
        Block::Targets => targets(results),
        Block::Calibration => Ok(calibration(&results.calibration)),
        Block::Curves(model) => curves(results, *model),
        Block::Report(name) => report(results, name),
        Block::MoveToTarget => move_to_target(results),
        Block::Latency => latency(results),
        Block::ActuatorFolds(name) => actuator_folds(push_doc(results, name)?),
        Block::Selectors => selectors(results),
        Block::Baselines => baselines(results),
        Block::BeyondTargets => beyond_targets(results),
        Block::BeyondAblation => beyond_ablation(results),
        Block::BeyondMoveToTarget => beyond_move_to_target(results),
        Block::BeyondObjects => beyond_objects(results),
        Block::Ablation => ablation(results),
        Block::Commands => Ok(commands(results)),
    }
}

fn push_doc<'r>(results: &'r Reproduction, name: &str) -> Result<&'r PushReport, String> {
    match results.document(name) {
        Some(Document::Push(r)) => Ok(r),
        Some(_) => Err(format!("`{name}` is not a push-task document")),
        None => Err(format!("no document `{name}` in this reproduction")),
    }
}

fn mtt_doc<'r>(results: &'r Reproduction, name: &str) -> Result<&'r MttReport, String> {
    match results.document(name) {
        Some(Document::MoveToTarget(r)) => Ok(r),
        Some(_) => Err(format!("`{name}` is not a move-to-target document")),
        None => Err(format!("no document `{name}` in this reproduction")),
    }
}

fn entry_at<'r>(report: &'r PushReport, name: &str, n: usize) -> Result<&'r CurveEntry, String> {
    report
        .results
        .iter()
        .find(|e| e.train_runs == n)
        .ok_or_else(|| format!("`{name}` has no results for {n} training runs"))
}

fn reached(report: &MttReport) -> usize {
    report.targets.iter().map(|t| t.summary.reached).sum()
}

fn runs(report: &MttReport) -> usize {
    report.targets.iter().map(|t| t.summary.runs).sum()
}

fn ms(m: MeanStd) -> String {
    format!("{:.4} ± {:.4}", m.mean, m.std)
}

fn thesis_ms(r: Ms) -> String {
    format!("{:.4} ± {:.4}", r.0, r.1)
}

/// One target row: seed 1, the other seeds' range, met or not.
struct TargetRow {
    what: String,
    thesis: String,
    /// Seed 1, then the spread seeds, in order.
    values: Vec<f64>,
    decimals: usize,
    /// Whether a value meets the target.
    meets: Box<dyn Fn(f64) -> bool>,
}

fn targets(results: &Reproduction) -> Result<String, String> {
    let mut rows = Vec::new();
    let seeds = |base: &str| -> Vec<String> {
        std::iter::once(base.to_owned())
            .chain(SPREAD_SEEDS.iter().map(|s| format!("{base}-seed{s}")))
            .collect()
    };
    for (model, n, pos, ori, actuator) in [
        (ModelKind::Gate, 10, 0.049, 0.15, Some(0.0022)),
        (ModelKind::Gate, 30, 0.036, 0.109, None),
        (ModelKind::Interaction, 10, 0.117, 0.327, None),
        (ModelKind::Interaction, 30, 0.086, 0.250, None),
    ] {
        let names = seeds(&format!("push-task-{model}"));
        let entries: Vec<&CurveEntry> = names
            .iter()
            .map(|name| entry_at(push_doc(results, name)?, name, n))
            .collect::<Result<_, _>>()?;
        let mut add =
            |what: &str, target: f64, unit: &str, pick: fn(&CurveEntry) -> f64, decimals| {
                rows.push(TargetRow {
                    what: format!("{model}, {n} runs: {what}"),
                    thesis: format!("≤ {target} {unit}"),
                    values: entries.iter().map(|e| pick(e)).collect(),
                    decimals,
                    meets: Box::new(move |v| v <= target),
                });
            };
        add("block position", pos, "m", |e| e.blue.block_pos_err.mean, 3);
        add(
            "block orientation",
            ori,
            "rad",
            |e| e.blue.block_ori_err.mean,
            3,
        );
        if let Some(actuator) = actuator {
            add(
                "actuator",
                actuator,
                "m",
                |e| e.blue.actuator_pos_err.mean,
                4,
            );
        }
    }
    for (model, least) in [(ModelKind::Gate, 19), (ModelKind::Interaction, 14)] {
        let names = seeds(&format!("move-to-target-{model}"));
        let reports: Vec<&MttReport> = names
            .iter()
            .map(|name| mtt_doc(results, name))
            .collect::<Result<_, _>>()?;
        let total = reports.first().map_or(0, |r| runs(r));
        rows.push(TargetRow {
            what: format!("Move to Target, {model}: reached of {total}"),
            thesis: format!("≥ {least}"),
            values: reports.iter().map(|r| reached(r) as f64).collect(),
            decimals: 0,
            meets: Box::new(move |v| v >= f64::from(least)),
        });
    }
    let mut out = String::new();
    let (first, last) = (SPREAD_SEEDS[0], SPREAD_SEEDS[SPREAD_SEEDS.len() - 1]);
    let _ = writeln!(
        out,
        "| Target (20 folds, default mode) | Thesis | Ours, seed 1 | Seeds {first}–{last}: min – max | Met (seed 1) | Seeds 1–{last} meeting it |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|");
    for row in rows {
        let d = row.decimals;
        let others = &row.values[1..];
        let min = others.iter().copied().fold(f64::INFINITY, f64::min);
        let max = others.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let seed1 = row.values[0];
        let met = row.values.iter().filter(|&&v| (row.meets)(v)).count();
        let _ = writeln!(
            out,
            "| {} | {} | {seed1:.d$} | {min:.d$} – {max:.d$} | {} | {met} of {} |",
            row.what,
            row.thesis,
            if (row.meets)(seed1) { "yes" } else { "no" },
            row.values.len()
        );
    }
    Ok(out)
}

fn calibration(rows: &[CalibrationRow]) -> String {
    let mut out = String::from("```\n");
    let _ = writeln!(
        out,
        "{:>7}  {:>13}  {:>8}  {:>8}  {:>9}  {:>11}  {:>9}",
        "x0", "first contact", "x", "y", "yaw", "translation", "rotation"
    );
    for r in rows {
        let contact = r
            .first_contact_message
            .map_or_else(|| "-".to_owned(), |m| m.to_string());
        let _ = writeln!(
            out,
            "{:>7.3}  {:>13}  {:>8.4}  {:>8.4}  {:>9.4}  {:>11.4}  {:>9.4}",
            r.x0, contact, r.block_x, r.block_y, r.block_yaw, r.translation, r.rotation
        );
    }
    out.push_str("```\n\n");
    let contact = rows.iter().filter_map(|r| r.first_contact_message).min();
    let central = rows.iter().find(|r| r.x0 == 0.0);
    let largest = rows
        .iter()
        .max_by(|a, b| a.rotation.abs().total_cmp(&b.rotation.abs()));
    let misses: Vec<String> = rows
        .iter()
        .filter(|r| r.first_contact_message.is_none())
        .map(|r| format!("{:.3}", r.x0))
        .collect();
    let _ = writeln!(out, "| Fact | Thesis | Ours |");
    let _ = writeln!(out, "|---|---|---|");
    let _ = writeln!(
        out,
        "| messages to reach the block | ≈ 35 | contact in message {} |",
        contact.map_or_else(|| "– (never)".to_owned(), |m| m.to_string())
    );
    let _ = writeln!(
        out,
        "| central push, translation | up to 0.6 m | {} |",
        central.map_or_else(|| "–".to_owned(), |r| format!("{:.3} m", r.translation))
    );
    let _ = writeln!(
        out,
        "| largest rotation | 1.02 rad at about 0.105 m from the centre | {} |",
        largest.map_or_else(
            || "–".to_owned(),
            |r| format!("{:.3} rad at x0 = {:.3} m", r.rotation.abs(), r.x0)
        )
    );
    let _ = writeln!(
        out,
        "| test positions that miss the block | 6 of 21 | {} of {} ({}) |",
        misses.len(),
        rows.len(),
        misses.join(", ")
    );
    out
}

fn curves(results: &Reproduction, model: ModelKind) -> Result<String, String> {
    let names = [
        format!("push-task-{model}"),
        format!("push-task-{model}-latency5"),
        format!("push-task-{model}-lockstep"),
    ];
    let reports: Vec<&PushReport> = names
        .iter()
        .map(|n| push_doc(results, n))
        .collect::<Result<_, _>>()?;
    let mut out = String::new();
    for interacting in [false, true] {
        let _ = writeln!(
            out,
            "{model}, {}\n",
            if interacting {
                "15 interacting positions"
            } else {
                "all 21 positions"
            }
        );
        let columns = format!(
            "L_max {LATENCY_MAX_STEPS} | L_max {LATENCY_MAX_STEPS_HARSH} | lockstep | thesis"
        );
        let _ = writeln!(
            out,
            "| N | block position: {columns} | block orientation: {columns} | actuator: {columns} |"
        );
        let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for entry in &reports[0].results {
            let n = entry.train_runs;
            let rows: Vec<&CurveEntry> = names
                .iter()
                .zip(&reports)
                .map(|(name, r)| entry_at(r, name, n))
                .collect::<Result<_, _>>()?;
            let r = reference::curve(model, n);
            let mut line = format!("| {n} ");
            let pick: [fn(&CurveEntry, bool) -> MeanStd; 3] = [
                |e, i| {
                    if i {
                        e.blue.interacting.block_pos_err
                    } else {
                        e.blue.block_pos_err
                    }
                },
                |e, i| {
                    if i {
                        e.blue.interacting.block_ori_err
                    } else {
                        e.blue.block_ori_err
                    }
                },
                |e, i| {
                    if i {
                        e.blue.interacting.actuator_pos_err
                    } else {
                        e.blue.actuator_pos_err
                    }
                },
            ];
            for (column, pick) in pick.iter().enumerate() {
                for row in &rows {
                    let _ = write!(line, "| {} ", ms(pick(row, interacting)));
                }
                let thesis = r.map(|r| match (column, interacting) {
                    (0, false) => thesis_ms(r.pos),
                    (0, true) => thesis_ms(r.pos_interacting),
                    (1, false) => thesis_ms(r.ori),
                    (1, true) => thesis_ms(r.ori_interacting),
                    (_, false) => thesis_ms(r.actuator),
                    // The thesis's figure plots the script's value here.
                    (_, true) => format!("{:.4} (script's value)", r.actuator_interacting_quirk.0),
                });
                let _ = write!(line, "| {} ", thesis.unwrap_or_else(|| "–".into()));
            }
            line.push_str("|\n");
            out.push_str(&line);
        }
        out.push('\n');
    }
    Ok(out)
}

/// The curves the baseline table and figure compare: the thesis's models'
/// default curves and the baselines', each with its label.
///
/// # Errors
/// A document the reproduction does not have.
pub fn baseline_curves(results: &Reproduction) -> Result<Vec<(String, &PushReport)>, String> {
    let names = ["push-task-gate", "push-task-interaction"]
        .into_iter()
        .chain(super::manifest::BASELINES.iter().map(|(name, ..)| *name));
    names
        .map(|name| {
            let report = push_doc(results, name)?;
            let label = match &report.setup.learner {
                Some(l) => format!("{} {} (Python)", report.setup.model, l.version),
                None => format!("{} (thesis model, Rust)", report.setup.model),
            };
            Ok((label, report))
        })
        .collect()
}

/// Gate, interaction, kNN and GP at the baseline table's training runs, all
/// 21 positions: one row per learner and N.
fn baselines(results: &Reproduction) -> Result<String, String> {
    let mut out = String::from(
        "| learner | N | block position [m] | block orientation [rad] | actuator [m] | folds |\n|---|---|---|---|---|---|\n",
    );
    for (label, report) in baseline_curves(results)? {
        let name = &report.setup.model;
        for n in super::manifest::BASELINE_RUNS {
            let e = entry_at(report, name, n)?;
            let _ = writeln!(
                out,
                "| {label} | {n} | {} | {} | {} | {} |",
                ms(e.blue.block_pos_err),
                ms(e.blue.block_ori_err),
                ms(e.blue.actuator_pos_err),
                report.folds
            );
        }
    }
    Ok(out)
}

/// Every learning curve of "Beyond the thesis", labelled: the thesis's gate
/// model, each change on it, gate+, and the two baselines.
///
/// # Errors
/// A document the reproduction does not have.
pub fn beyond_curves(results: &Reproduction) -> Result<Vec<(String, &PushReport)>, String> {
    let mut names = vec![String::from("push-task-gate")];
    names.extend(
        super::manifest::beyond_models()
            .into_iter()
            .map(|(name, ..)| format!("beyond-push-{name}")),
    );
    names.extend(
        super::manifest::BASELINES
            .iter()
            .map(|(n, ..)| (*n).to_owned()),
    );
    names
        .iter()
        .map(|name| {
            let report = push_doc(results, name)?;
            Ok((learner_label(&report.setup), report))
        })
        .collect()
}

/// An error in the ablation's table: three decimals, or for one that has
/// run away (a diverging configuration) its order of magnitude.
fn error(value: f64) -> String {
    if value.abs() < 100.0 {
        format!("{value:.3}")
    } else {
        format!("{value:.1e}")
    }
}

/// A ratio to the defaults' error as a change: `-20 %`, or `×1234` past ten
/// times.
fn change(ratio: f64) -> String {
    if ratio > 10.0 {
        format!("×{ratio:.0}")
    } else {
        format!("{:+.0} %", 100.0 * (ratio - 1.0))
    }
}

/// The ablation's summary: one row per configuration, the blue block's
/// position / orientation error (mean over seeds) at each number of
/// training runs, and the change against the model's defaults at 10 runs
/// (or the largest number below).
fn ablation(results: &Reproduction) -> Result<String, String> {
    let name = super::manifest::ABLATION;
    let summary = results
        .sweep(name)
        .ok_or_else(|| format!("no sweep `{name}` in this reproduction"))?;
    let runs = summary.train_runs();
    let at = runs
        .iter()
        .copied()
        .filter(|&n| n <= 10)
        .max()
        .or_else(|| runs.first().copied())
        .ok_or_else(|| format!("the sweep `{name}` has no rows"))?;
    let mut out = String::from("| model | change |");
    for n in &runs {
        let _ = write!(out, " N = {n} |");
    }
    let _ = writeln!(out, " vs defaults at N = {at} |");
    out.push_str("|---|---|");
    out.push_str(&"---|".repeat(runs.len() + 1));
    out.push('\n');
    let pos_ori = |row: &crate::sweep::summary::Row| {
        (
            row.mean_spread(Metric::BlockPosition).0,
            row.mean_spread(Metric::BlockOrientation).0,
        )
    };
    for (id, options, model) in summary.configurations() {
        let _ = write!(out, "| {model} | {} |", change_label(options));
        for &n in &runs {
            match summary.row(id, n) {
                Some(row) => {
                    let (pos, ori) = pos_ori(row);
                    let _ = write!(out, " {} / {} |", error(pos), error(ori));
                }
                None => out.push_str(" – |"),
            }
        }
        let defaults = summary.defaults_of(model).and_then(|d| summary.row(d, at));
        match (defaults, summary.row(id, at)) {
            (Some(base), Some(row)) if base.configuration != row.configuration => {
                let ((p0, o0), (p, o)) = (pos_ori(base), pos_ori(row));
                let _ = writeln!(out, " {} / {} |", change(p / p0), change(o / o0));
            }
            _ => out.push_str(" – |\n"),
        }
    }
    let _ = writeln!(
        out,
        "\nBlock position [m] / orientation [rad]: each the mean over the {} of the learning curve's mean error ({} each, all 21 test positions); {}.",
        crate::report::plural(summary.seeds.len(), "seed"),
        crate::report::plural(summary.folds, "fold"),
        summary.shape
    );
    Ok(out)
}

/// A learner as the page's tables and figures name it: a Python learner by
/// its model and version, the thesis's models as such, the others by name.
fn learner_label(setup: &Setup) -> String {
    match (&setup.learner, setup.model.as_str()) {
        (Some(l), model) => format!("{model} {} (Python)", l.version),
        (None, model @ ("gate" | "interaction")) => format!("{model} (thesis model)"),
        (None, model) => model.to_owned(),
    }
}

/// A learner's label and its report on each new-object condition.
pub type ObjectRow<'r> = (String, Vec<&'r PushReport>);

/// The new-object experiments: the conditions' labels, and for each
/// learner (label) its report on each condition, in the manifest's order.
///
/// # Errors
/// A document the reproduction does not have.
pub fn object_reports(results: &Reproduction) -> Result<(Vec<String>, Vec<ObjectRow<'_>>), String> {
    use super::manifest::{object_entry_name, object_learners, transfers};
    let conditions = transfers();
    let labels = conditions.iter().map(|t| t.label()).collect();
    let rows = object_learners()
        .into_iter()
        .map(|(name, _)| {
            let reports = conditions
                .iter()
                .map(|t| push_doc(results, &object_entry_name(name, t)))
                .collect::<Result<Vec<_>, _>>()?;
            Ok((learner_label(&reports[0].setup), reports))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok((labels, rows))
}

/// One row per learner of [`object_reports`], one column per condition:
/// block position / orientation error after `manifest::OBJECT_RUNS`
/// training runs.
fn beyond_objects(results: &Reproduction) -> Result<String, String> {
    let (conditions, rows) = object_reports(results)?;
    let mut out = String::from("| learner |");
    for c in &conditions {
        let _ = write!(out, " {c} |");
    }
    out.push('\n');
    out.push_str(&"|---".repeat(conditions.len() + 1));
    out.push_str("|\n");
    for (label, reports) in rows {
        let _ = write!(out, "| {label} |");
        for report in reports {
            let name = &report.setup.model;
            let e = entry_at(report, name, super::manifest::OBJECT_RUNS)?;
            let _ = write!(
                out,
                " {:.3} / {:.3} |",
                e.blue.block_pos_err.mean, e.blue.block_ori_err.mean
            );
        }
        out.push('\n');
    }
    Ok(out)
}

/// One row per curve of [`beyond_curves`]: block position / orientation
/// at each of `manifest::BEYOND_RUNS`, and the actuator at the first and
/// the third.
fn beyond_ablation(results: &Reproduction) -> Result<String, String> {
    let runs = super::manifest::BEYOND_RUNS;
    let mut out = String::from("| model |");
    for n in runs {
        let _ = write!(out, " N = {n}: position [m] / orientation [rad] |");
    }
    let _ = writeln!(out, " actuator [m], N = {} / {} |", runs[0], runs[2]);
    out.push_str(&"|---".repeat(runs.len() + 2));
    out.push_str("|\n");
    for (label, report) in beyond_curves(results)? {
        let name = &report.setup.model;
        let _ = write!(out, "| {label} |");
        for n in runs {
            let e = entry_at(report, name, n)?;
            let _ = write!(
                out,
                " {:.4} / {:.4} |",
                e.blue.block_pos_err.mean, e.blue.block_ori_err.mean
            );
        }
        let (a, b) = (
            entry_at(report, name, runs[0])?,
            entry_at(report, name, runs[2])?,
        );
        let _ = writeln!(
            out,
            " {:.4} / {:.4} |",
            a.blue.actuator_pos_err.mean, b.blue.actuator_pos_err.mean
        );
    }
    Ok(out)
}

/// The issue's targets for gate+, each against its measured value.
fn beyond_targets(results: &Reproduction) -> Result<String, String> {
    let plus = push_doc(results, "beyond-push-gate-plus")?;
    let at = |n| entry_at(plus, "beyond-push-gate-plus", n);
    let gate_mtt = reference::move_to_target(ModelKind::Gate);
    let mtt = mtt_doc(results, "beyond-mtt-gate-plus")?;
    let sampled = mtt_doc(results, "beyond-sampled-gate-plus")?;
    let ten = reference::curve(ModelKind::Gate, 10)
        .ok_or("the thesis's gate curve has no 10-run value")?;
    let mut out = String::from("| Target | Ours (gate+) | Met |\n|---|---|---|\n");
    let mut row = |what: String, ours: String, met: bool| {
        let _ = writeln!(
            out,
            "| {what} | {ours} | {} |",
            if met { "yes" } else { "no" }
        );
    };
    let e10 = at(10)?;
    let (half_pos, half_ori) = (0.025, 0.075);
    row(
        format!("10 runs: block position ≤ {half_pos} m (half the thesis's gate model)"),
        format!("{:.4}", e10.blue.block_pos_err.mean),
        e10.blue.block_pos_err.mean <= half_pos,
    );
    row(
        format!("10 runs: block orientation ≤ {half_ori} rad"),
        format!("{:.4}", e10.blue.block_ori_err.mean),
        e10.blue.block_ori_err.mean <= half_ori,
    );
    let e3 = at(3)?;
    row(
        format!(
            "3 runs: block position ≤ {:.3} m (the thesis's 10-run value)",
            ten.pos.0
        ),
        format!("{:.4}", e3.blue.block_pos_err.mean),
        e3.blue.block_pos_err.mean <= ten.pos.0,
    );
    row(
        format!("3 runs: block orientation ≤ {:.3} rad", ten.ori.0),
        format!("{:.4}", e3.blue.block_ori_err.mean),
        e3.blue.block_ori_err.mean <= ten.ori.0,
    );
    row(
        format!(
            "Move to Target, the thesis's targets: {} of {}",
            runs(mtt),
            runs(mtt)
        ),
        format!("{} of {}", reached(mtt), runs(mtt)),
        reached(mtt) == runs(mtt),
    );
    let share = reached(sampled) as f64 / runs(sampled).max(1) as f64;
    row(
        format!(
            "Move to Target, {} sampled targets: ≥ 95 % reached",
            runs(sampled)
        ),
        format!(
            "{} of {} ({:.0} %)",
            reached(sampled),
            runs(sampled),
            100.0 * share
        ),
        share >= 0.95,
    );
    for (k, (t, thesis)) in mtt.targets.iter().zip(gate_mtt.iter()).enumerate() {
        let limit = 0.7 * thesis.steps;
        row(
            format!(
                "target {}: mean steps ≤ 0.7 × the thesis's {:.0} = {limit:.0}",
                k + 1,
                thesis.steps
            ),
            format!("{:.0}", t.summary.steps),
            t.summary.steps <= limit,
        );
    }
    let baselines: Vec<&PushReport> = super::manifest::BASELINES
        .iter()
        .map(|(name, ..)| push_doc(results, name))
        .collect::<Result<_, _>>()?;
    let mut worse = Vec::new();
    for n in super::manifest::BEYOND_RUNS {
        let ours = at(n)?;
        for b in &baselines {
            let theirs = entry_at(b, &b.setup.model, n)?;
            if ours.blue.block_pos_err.mean >= theirs.blue.block_pos_err.mean
                || ours.blue.block_ori_err.mean >= theirs.blue.block_ori_err.mean
            {
                worse.push(format!("N = {n} vs {}", b.setup.model));
            }
        }
    }
    row(
        "better than kNN and GP (block position and orientation) at every N".to_owned(),
        if worse.is_empty() {
            "better at every N".to_owned()
        } else {
            format!("not better at {}", worse.join(", "))
        },
        worse.is_empty(),
    );
    Ok(out)
}

/// Reached per thesis target (of 5) and mean steps for the thesis's gate
/// model, forward-check and gate+, then reached of the sampled targets.
fn beyond_move_to_target(results: &Reproduction) -> Result<String, String> {
    let mut out = String::from(
        "| Model | Target 1 | Target 2 | Target 3 | Target 4 | Reached | Mean steps (1–4) |\n|---|---|---|---|---|---|---|\n",
    );
    let _ = writeln!(
        out,
        "| gate, thesis | {} |",
        thesis_mtt_cells(ModelKind::Gate)
    );
    for name in [
        "move-to-target-gate",
        "beyond-mtt-forward-check",
        "beyond-mtt-gate-plus",
    ] {
        let r = mtt_doc(results, name)?;
        let _ = writeln!(out, "| {} | {} |", r.setup.model, mtt_cells(r));
    }
    out.push_str("\n| Model | Sampled targets reached | Mean steps (failures count the limit) | Mean steps of the reached |\n|---|---|---|---|\n");
    for name in ["beyond-sampled-gate", "beyond-sampled-gate-plus"] {
        let r = mtt_doc(results, name)?;
        let steps: Vec<f64> = r.targets.iter().map(|t| t.summary.steps).collect();
        let reached_steps: Vec<f64> = r
            .targets
            .iter()
            .filter_map(|t| t.summary.steps_reached)
            .collect();
        let mean = |v: &[f64]| {
            if v.is_empty() {
                "–".to_owned()
            } else {
                format!("{:.0}", v.iter().sum::<f64>() / v.len() as f64)
            }
        };
        let _ = writeln!(
            out,
            "| {} | {} of {} | {} | {} |",
            r.setup.model,
            reached(r),
            runs(r),
            mean(&steps),
            mean(&reached_steps)
        );
    }
    Ok(out)
}

fn entry_of<'r>(results: &'r Reproduction, name: &str) -> Result<&'r Entry, String> {
    results
        .produced
        .iter()
        .find(|p| p.entry.name == name)
        .map(|p| &p.entry)
        .ok_or_else(|| format!("no document `{name}` in this reproduction"))
}

fn report(results: &Reproduction, name: &str) -> Result<String, String> {
    let entry = entry_of(results, name)?;
    let document = results
        .document(name)
        .ok_or_else(|| format!("no document `{name}`"))?;
    let mut text = Vec::new();
    document
        .write_tables(&mut text)
        .map_err(|e| format!("cannot render `{name}`: {e}"))?;
    let text = String::from_utf8_lossy(&text);
    Ok(format!(
        "```sh\n{}\n```\n\n```\n{}```\n",
        entry.command(RESULTS_DIR),
        text
    ))
}

fn move_to_target(results: &Reproduction) -> Result<String, String> {
    let mut out = String::from(
        "| Model | Setting | Target 1 | Target 2 | Target 3 | Target 4 | Reached | Mean steps (1–4) |\n|---|---|---|---|---|---|---|---|\n",
    );
    for model in [ModelKind::Gate, ModelKind::Interaction] {
        let _ = writeln!(out, "| {model} | thesis | {} |", thesis_mtt_cells(model));
        for (suffix, setting) in [
            ("", format!("L_max {LATENCY_MAX_STEPS} (default)")),
            ("-latency5", format!("L_max {LATENCY_MAX_STEPS_HARSH}")),
            ("-lockstep", "lockstep".to_owned()),
        ] {
            let name = format!("move-to-target-{model}{suffix}");
            let r = mtt_doc(results, &name)?;
            let _ = writeln!(out, "| {model} | {setting} | {} |", mtt_cells(r));
        }
    }
    Ok(out)
}

/// A Move-to-Target row's cells: reached per target, their sum, and the
/// targets' mean steps (failures count the limit), `r | r | … | n | s / s / …`.
fn reached_and_steps(per_target: impl Iterator<Item = (usize, f64)> + Clone) -> String {
    let reached: Vec<String> = per_target.clone().map(|(r, _)| r.to_string()).collect();
    let steps: Vec<String> = per_target.clone().map(|(_, s)| format!("{s:.0}")).collect();
    let total: usize = per_target.map(|(r, _)| r).sum();
    format!("{} | {total} | {}", reached.join(" | "), steps.join(" / "))
}

/// [`reached_and_steps`] of one of our documents.
fn mtt_cells(r: &MttReport) -> String {
    reached_and_steps(
        r.targets
            .iter()
            .map(|t| (t.summary.reached, t.summary.steps)),
    )
}

/// [`reached_and_steps`] of the thesis's table for `model`.
fn thesis_mtt_cells(model: ModelKind) -> String {
    reached_and_steps(
        reference::move_to_target(model)
            .iter()
            .map(|r| (r.reached, r.steps)),
    )
}

/// The blue block's position and orientation and the actuator's mean
/// errors, as `p / o / a`.
fn errors(e: &CurveEntry) -> String {
    format!(
        "{:.4} / {:.4} / {:.4}",
        e.blue.block_pos_err.mean, e.blue.block_ori_err.mean, e.blue.actuator_pos_err.mean
    )
}

/// The `n`-run entries of document `base` and of its harsh-latency twin.
fn with_harsh<'r>(
    results: &'r Reproduction,
    base: &str,
    n: usize,
) -> Result<(&'r CurveEntry, &'r CurveEntry), String> {
    let harsh = format!("{base}-latency5");
    Ok((
        entry_at(push_doc(results, base)?, base, n)?,
        entry_at(push_doc(results, &harsh)?, &harsh, n)?,
    ))
}

fn latency(results: &Reproduction) -> Result<String, String> {
    let mut out = format!(
        "| Experiment | Value | L_max {LATENCY_MAX_STEPS} (default) | L_max {LATENCY_MAX_STEPS_HARSH} |\n|---|---|---|---|\n"
    );
    for model in [ModelKind::Gate, ModelKind::Interaction] {
        for n in [1, 10, 30] {
            let (ea, eb) = with_harsh(results, &format!("push-task-{model}"), n)?;
            let _ = writeln!(
                out,
                "| curve, {model}, N = {n} | block pos / ori / actuator | {} | {} |",
                errors(ea),
                errors(eb)
            );
        }
    }
    for model in [ModelKind::Gate, ModelKind::Interaction] {
        let (ea, eb) = with_harsh(results, &format!("fixed-three-{model}"), 3)?;
        let _ = writeln!(
            out,
            "| fixed three, {model} | block pos / ori / actuator, all positions | {} | {} |",
            errors(ea),
            errors(eb)
        );
    }
    for runs in [6, 7] {
        let (ea, eb) = with_harsh(results, &format!("two-objects-{runs}"), runs)?;
        let red = |e: &CurveEntry| {
            e.red.as_ref().map_or_else(
                || "–".to_owned(),
                |r| format!("{:.4} / {:.4}", r.block_pos_err.mean, r.block_ori_err.mean),
            )
        };
        let _ = writeln!(
            out,
            "| two objects, {runs} runs | red pos / ori | {} | {} |",
            red(ea),
            red(eb)
        );
    }
    for model in [ModelKind::Gate, ModelKind::Interaction] {
        let a = mtt_doc(results, &format!("move-to-target-{model}"))?;
        let b = mtt_doc(results, &format!("move-to-target-{model}-latency5"))?;
        let _ = writeln!(
            out,
            "| Move to Target, {model} | reached of {} | {} | {} |",
            runs(a),
            reached(a),
            reached(b)
        );
    }
    Ok(out)
}

fn actuator_folds(report: &PushReport) -> Result<String, String> {
    let mut out = String::from(
        "| N | folds ≥ 0.01 m | their values | the other folds (mean ± std) |\n|---|---|---|---|\n",
    );
    for e in &report.results {
        let (bad, good): (Vec<f64>, Vec<f64>) =
            e.actuator_pos_err_by_fold.iter().partition(|&&v| v >= 0.01);
        let mut bad_sorted = bad.clone();
        bad_sorted.sort_by(f64::total_cmp);
        let values: Vec<String> = bad_sorted.iter().map(|v| format!("{v:.3}")).collect();
        let good = if good.is_empty() {
            "–".to_owned()
        } else {
            ms(MeanStd::of(&good))
        };
        let _ = writeln!(
            out,
            "| {} | {} of {} | {} | {good} |",
            e.train_runs,
            bad.len(),
            e.actuator_pos_err_by_fold.len(),
            if values.is_empty() {
                "–".to_owned()
            } else {
                values.join(", ")
            }
        );
    }
    Ok(out)
}

fn selectors(results: &Reproduction) -> Result<String, String> {
    let mut out = String::from(
        "| Selector | N_train | selector agreement | actuator key-point | block key-point | block pos | block ori |\n|---|---|---|---|---|---|---|\n",
    );
    for p in &results.produced {
        let Some(kind) = p.entry.name.strip_prefix("selector-") else {
            continue;
        };
        let Document::Push(report) = &p.document else {
            return Err(format!("`{}` is not a push-task document", p.entry.name));
        };
        for e in &report.results {
            let score = |id: u32| {
                e.keypoints.get(&id).map_or_else(
                    || "–".to_owned(),
                    |s| format!("{:.3} / {:.3} / {:.4}", s.final_dif, s.cum_dif, s.mean_dif),
                )
            };
            let agreement = e
                .selection
                .as_ref()
                .and_then(SelectionCount::accuracy)
                .map_or_else(|| "–".to_owned(), |a| format!("{:.1} %", 100.0 * a));
            let _ = writeln!(
                out,
                "| {kind} | {} | {agreement} | {} | {} | {:.4} | {:.4} |",
                e.train_runs,
                score(learner::ACTUATOR_ID),
                score(learner::BLUE_ID),
                e.blue.block_pos_err.mean,
                e.blue.block_ori_err.mean
            );
        }
    }
    Ok(out)
}

fn commands(results: &Reproduction) -> String {
    let mut out = String::from("```sh\n");
    for p in &results.produced {
        let _ = writeln!(out, "{}", p.entry.command(RESULTS_DIR));
    }
    for swept in &results.sweeps {
        let _ = writeln!(out, "{}", swept.entry.command());
    }
    out.push_str("```\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reproduce::{Produced, Reproduction};
    use crate::results::test_support::push_report;

    fn reproduction() -> Reproduction {
        let entry = manifest_entry("push-task-gate");
        Reproduction {
            calibration: Vec::new(),
            produced: vec![Produced {
                entry,
                document: Document::Push(push_report("random", &[1, 10])),
                timing: Vec::new(),
            }],
            sweeps: Vec::new(),
            wall_seconds: 0.0,
        }
    }

    fn manifest_entry(name: &str) -> Entry {
        super::super::manifest::full()
            .into_iter()
            .find(|e| e.name == name)
            .expect("entry")
    }

    #[test]
    fn prose_keeps_its_text_and_gets_its_numbers() {
        let results = reproduction();
        let template = "# Title\n\nAfter one run the error is {{push-task-gate:results[0].block_pos_err.mean:3}} m.\n";
        let page = generate(template, &results).unwrap();
        let expected = format!(
            "# Title\n\nAfter one run the error is {:.3} m.\n",
            push_report("random", &[1, 10]).results[0]
                .blue
                .block_pos_err
                .mean
        );
        assert_eq!(page, expected);
    }

    #[test]
    fn blocks_expand_and_unknown_ones_are_named_with_their_line() {
        let results = reproduction();
        let page = generate(
            "a\n<!-- reproduce: report push-task-gate -->\nb\n",
            &results,
        )
        .unwrap();
        assert!(page.starts_with("a\n```sh\npushlearn experiment push-task --model gate"));
        assert!(page.contains("Push task (random), gate model"));
        // A blank line keeps the block apart from what follows.
        assert!(page.ends_with("```\n\nb\n"), "{page}");
        let page = generate("<!-- notes\nfor editors -->\n# Page\n", &results).unwrap();
        assert_eq!(page, "# Page\n");
        let err = generate("x\n<!-- reproduce: tables -->\n", &results).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!("{TEMPLATE} line 2: unknown block `tables`")
        );
        let err = generate("{{push-task-gate:results[9].x}}\n", &results).unwrap_err();
        assert!(err.to_string().contains("has no entry 9"), "{err}");
        let err = generate("{{nothing:a}}\n", &results).unwrap_err();
        assert!(err.to_string().contains("no document `nothing`"), "{err}");
        let err = generate("<!-- reproduce: curves gate -->\n", &results).unwrap_err();
        assert!(err.to_string().contains("push-task-gate-latency5"), "{err}");
    }

    #[test]
    fn the_ablation_table_has_a_row_per_configuration_and_compares_with_the_defaults() {
        use crate::sweep::summary::{Row, SeedErrors, Summary};
        let row = |id: &str, options: &str, model: &str, n: usize, pos: f64| Row {
            configuration: id.into(),
            options: options.into(),
            model: model.into(),
            train_runs: n,
            seeds: [1, 2]
                .map(|seed| SeedErrors {
                    seed,
                    block_pos_err: pos,
                    block_ori_err: 3.0 * pos,
                    actuator_pos_err: 0.0,
                })
                .to_vec(),
        };
        let mut results = reproduction();
        let entry = super::super::manifest::sweeps(true).remove(0);
        let err = generate("<!-- reproduce: ablation -->\n", &results).unwrap_err();
        assert!(err.to_string().contains("no sweep `ablation`"), "{err}");
        results.sweeps.push(crate::reproduce::Swept {
            entry,
            summary: Summary {
                shape: "3 configurations × 2 seeds × 2 training-run counts × 2 folds = 24 jobs"
                    .into(),
                seeds: vec![1, 2],
                folds: 2,
                rows: vec![
                    row("a", "model=gate", "gate", 1, 0.2),
                    row("a", "model=gate", "gate", 10, 0.1),
                    row("b", "flag=use-dyns model=gate", "gate", 1, 0.3),
                    row("b", "flag=use-dyns model=gate", "gate", 10, 0.08),
                    row(
                        "c",
                        "model=interaction selector=tree",
                        "interaction",
                        10,
                        0.5,
                    ),
                ],
            },
            timing: None,
        });
        let page = generate("<!-- reproduce: ablation -->\n", &results).unwrap();
        let lines: Vec<&str> = page.lines().collect();
        assert_eq!(
            lines[0],
            "| model | change | N = 1 | N = 10 | vs defaults at N = 10 |"
        );
        assert_eq!(
            lines[2],
            "| gate | defaults | 0.200 / 0.600 | 0.100 / 0.300 | – |"
        );
        assert_eq!(
            lines[3],
            "| gate | flag=use-dyns | 0.300 / 0.900 | 0.080 / 0.240 | -20 % / -20 % |"
        );
        // No defaults row for the interaction model: nothing to compare with.
        assert_eq!(
            lines[4],
            "| interaction | selector=tree | – | 0.500 / 1.500 | – |"
        );
        assert!(page.contains("over the 2 seeds"), "{page}");
        assert_eq!(error(7_531_199.0), "7.5e6");
        assert_eq!(change(12.4), "×12");
    }
}
