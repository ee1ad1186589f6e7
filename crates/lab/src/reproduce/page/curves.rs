//! Learning curves beside the harsher latency and the thesis, the baselines,
//! the changes beyond the thesis one by one, and the actuator's folds.

use std::fmt::Write as _;

use learner::eval::MeanStd;

use super::objects::{learner_label, FLOOR_LABEL};
use super::{entry_at, ms, push_doc, thesis_ms};
use crate::report::reference;
use crate::reproduce::Reproduction;
use drive::experiment::{LATENCY_MAX_STEPS, LATENCY_MAX_STEPS_HARSH};
use drive::results::push_task::CurveEntry;
use drive::results::PushReport;
use learner::registry::ModelKind;

pub(super) fn curves(results: &Reproduction, model: ModelKind) -> Result<String, String> {
    let names = [
        format!("push-task-{model}"),
        format!("push-task-{model}-latency5"),
        format!("push-task-{model}-lockstep"),
    ];
    let reports: Vec<&PushReport> = names
        .iter()
        .map(|n| push_doc(results, n))
        .collect::<Result<_, _>>()?;
    // The floor of each timing: what no learner can go below there.
    let floor_names = [
        "beyond-push-floor",
        "push-task-floor-latency5",
        "push-task-floor-lockstep",
    ];
    let floors: Vec<&CurveEntry> = floor_names
        .iter()
        .map(|n| {
            push_doc(results, n)?
                .results
                .first()
                .ok_or_else(|| format!("`{n}` has no results"))
        })
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
        for entry in &reports[0].results {
            let n = entry.train_runs;
            let rows: Vec<&CurveEntry> = names
                .iter()
                .zip(&reports)
                .map(|(name, r)| entry_at(r, name, n))
                .collect::<Result<_, _>>()?;
            let r = reference::curve(model, n);
            let mut line = format!("| {n} ");
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
        let mut line = format!("| {FLOOR_LABEL} ");
        for pick in &pick {
            for floor in &floors {
                let _ = write!(line, "| {} ", ms(pick(floor, interacting)));
            }
            line.push_str("| – ");
        }
        line.push_str("|\n");
        out.push_str(&line);
        out.push('\n');
    }
    Ok(out)
}

/// The thesis's models' default learning curves, each with the floor's
/// errors at that timing, for the §3 figures.
///
/// # Errors
/// A document the reproduction does not have.
pub fn curves_and_floor(
    results: &Reproduction,
) -> Result<Vec<(ModelKind, &PushReport, &CurveEntry)>, String> {
    let floor = push_doc(results, "beyond-push-floor")?
        .results
        .first()
        .ok_or("`beyond-push-floor` has no results")?;
    [ModelKind::Gate, ModelKind::Interaction]
        .into_iter()
        .map(|model| {
            Ok((
                model,
                push_doc(results, &format!("push-task-{model}"))?,
                floor,
            ))
        })
        .collect()
}

/// The curves the baseline table and figure compare: the thesis's models'
/// default curves and the baselines', each with its label.
///
/// # Errors
/// A document the reproduction does not have.
pub fn baseline_curves(results: &Reproduction) -> Result<Vec<(String, &PushReport)>, String> {
    let names = [
        "push-task-gate",
        "push-task-interaction",
        "beyond-push-hybrid",
    ]
    .into_iter()
    .chain(
        crate::reproduce::manifest::BASELINES
            .iter()
            .map(|(name, ..)| *name),
    )
    .chain(["beyond-push-floor"]);
    names
        .map(|name| {
            let report = push_doc(results, name)?;
            let label = match (&report.setup.learner, report.setup.model.as_str()) {
                (Some(l), model) => format!("{model} {} (Python)", l.version),
                (None, model @ ("gate" | "interaction")) => format!("{model} (thesis model, Rust)"),
                (None, drive::floor::NAME) => FLOOR_LABEL.to_owned(),
                (None, model) => format!("{model} (Rust)"),
            };
            Ok((label, report))
        })
        .collect()
}

/// Gate, interaction and every baseline (kNN, GP, MLP ensemble) at the
/// baseline table's training runs, all 21 positions: one row per learner
/// and N.
pub(super) fn baselines(results: &Reproduction) -> Result<String, String> {
    let mut out = String::from(
        "| learner | N | block position [m] | block orientation [rad] | actuator [m] | folds |\n|---|---|---|---|---|---|\n",
    );
    for (label, report) in baseline_curves(results)? {
        let name = &report.setup.model;
        for n in crate::reproduce::manifest::BASELINE_RUNS {
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
/// model, each change on it, gate+, and every baseline.
///
/// # Errors
/// A document the reproduction does not have.
pub fn beyond_curves(results: &Reproduction) -> Result<Vec<(String, &PushReport)>, String> {
    let mut names = vec![String::from("push-task-gate")];
    names.extend(
        crate::reproduce::manifest::beyond_models()
            .into_iter()
            .map(|(name, ..)| format!("beyond-push-{name}")),
    );
    names.extend(
        crate::reproduce::manifest::HYBRIDS
            .iter()
            .map(|(name, _)| format!("beyond-push-{name}")),
    );
    names.extend(
        crate::reproduce::manifest::BASELINES
            .iter()
            .map(|(n, ..)| (*n).to_owned()),
    );
    names.push("beyond-push-floor".to_owned());
    names
        .iter()
        .map(|name| {
            let report = push_doc(results, name)?;
            Ok((learner_label(&report.setup), report))
        })
        .collect()
}

/// One row per curve of [`beyond_curves`]: block position / orientation
/// at each of `manifest::BEYOND_RUNS`, and the actuator at the first and
/// the third.
pub(super) fn beyond_ablation(results: &Reproduction) -> Result<String, String> {
    let runs = crate::reproduce::manifest::BEYOND_RUNS;
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

pub(super) fn actuator_folds(report: &PushReport) -> Result<String, String> {
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
