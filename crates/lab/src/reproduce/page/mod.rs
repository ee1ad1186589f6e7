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
//!
//! This module is the template engine (the directives, the inline values,
//! the lookups every section shares); each section of the page is rendered
//! by a module of its own: `targets` (the issue's targets and those beyond
//! the thesis), `calibration`, `curves` (learning curves, baselines,
//! the changes beyond the thesis, the actuator's folds), `ablation` (the
//! sweep), `objects` (the new-object experiments), `references` (the
//! reference rows and the normalised score), `move_to_target`,
//! `latency`, `selectors` and `documents` (a document's report and
//! every command).

mod ablation;
mod calibration;
mod curves;
mod documents;
mod latency;
mod move_to_target;
mod objects;
mod references;
mod selectors;
mod targets;

use learner::eval::MeanStd;

use crate::report::reference::Ms;
use crate::reproduce::manifest::Entry;
use crate::reproduce::{Reproduction, TEMPLATE};
use crate::spec::Document;
use ablation::ablation;
use calibration::calibration;
use curves::{actuator_folds, baselines, beyond_ablation, curves};
use documents::{commands, report};
use drive::results::push_task::CurveEntry;
use drive::results::{MttReport, PushReport};
use latency::latency;
use learner::registry::ModelKind;
use move_to_target::{beyond_move_to_target, move_to_target};
use objects::{beyond_objects, cross_objects};
use selectors::selectors;
use targets::{beyond_targets, targets};

pub use curves::{baseline_curves, beyond_curves, curves_and_references};
pub use objects::{object_reports, ObjectRow};

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
    /// `cross-objects`: trained on one object, tested on each other one.
    CrossObjects,
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
            "cross-objects" => Block::CrossObjects,
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
        Block::CrossObjects => cross_objects(results),
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

fn entry_of<'r>(results: &'r Reproduction, name: &str) -> Result<&'r Entry, String> {
    results
        .produced
        .iter()
        .find(|p| p.entry.name == name)
        .map(|p| &p.entry)
        .ok_or_else(|| format!("no document `{name}` in this reproduction"))
}

/// The blue block's position and orientation and the actuator's mean
/// errors, as `p / o / a`.
fn errors(e: &CurveEntry) -> String {
    format!(
        "{:.4} / {:.4} / {:.4}",
        e.blue.block_pos_err.mean, e.blue.block_ori_err.mean, e.blue.actuator_pos_err.mean
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reproduce::{Produced, Reproduction};
    use drive::results::test_support::push_report;

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
        crate::reproduce::manifest::full()
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
        let entry = crate::reproduce::manifest::sweeps(true).remove(0);
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
