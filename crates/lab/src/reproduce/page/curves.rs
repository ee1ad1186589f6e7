//! Learning curves beside the harsher latency and the thesis, the baselines,
//! the changes beyond the thesis one by one, and the actuator's folds.

use std::fmt::Write as _;

use learner::eval::MeanStd;

use super::objects::learner_label;
use super::references::{reference_label, References};
use super::{entry_at, ms, push_doc, thesis_ms};
use crate::experiments::push_task::figures::ReferenceLine;
use crate::report::reference;
use crate::reproduce::manifest::{references, STILL};
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
    // The reference rows of each timing, in the columns' order.
    let timings: Vec<References> = ["", "-latency5", "-lockstep"]
        .into_iter()
        .map(|suffix| References::of_timing(results, suffix))
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
            "| N | block position: {columns} | block orientation: {columns} | actuator: {columns} | normalised, L_max {LATENCY_MAX_STEPS}: position / orientation |"
        );
        let _ = writeln!(
            out,
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
        );
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
            let _ = writeln!(
                line,
                "| {} |",
                normalised(&timings[0], rows[0], n, interacting)?
            );
            out.push_str(&line);
        }
        // The references learn nothing: one row each, at one training run.
        let n = 1;
        for (i, (reference, _)) in references().into_iter().enumerate() {
            let rows: Vec<&CurveEntry> = timings
                .iter()
                .map(|t| entry_at(t.reports()[i], reference, n))
                .collect::<Result<_, _>>()?;
            let label = reference_label(reference).unwrap_or(reference);
            let mut line = format!("| {label} (N = {n}) ");
            for pick in &pick {
                for row in &rows {
                    let _ = write!(line, "| {} ", ms(pick(row, interacting)));
                }
                line.push_str("| – ");
            }
            let _ = writeln!(
                line,
                "| {} |",
                normalised(&timings[0], rows[0], n, interacting)?
            );
            out.push_str(&line);
        }
        out.push('\n');
    }
    Ok(out)
}

/// The normalised score of a curve's row (all 21 positions, or the 15
/// interacting ones against the references' same positions).
fn normalised(
    references: &References,
    e: &CurveEntry,
    n: usize,
    interacting: bool,
) -> Result<String, String> {
    if !interacting {
        return references.normalised(e, n);
    }
    let at = |reference: &str| {
        let report = references
            .reports()
            .iter()
            .find(|r| r.setup.model == reference)
            .ok_or_else(|| format!("no reference `{reference}`"))?;
        entry_at(report, reference, n)
    };
    let (still, oracle) = (at(STILL)?, at("oracle-unknown")?);
    let score = |get: fn(&CurveEntry) -> f64| {
        super::references::normalised(get(e), get(still), get(oracle))
            .map_or_else(|| "–".to_owned(), |v| format!("{v:.2}"))
    };
    Ok(format!(
        "{} / {}",
        score(|e| e.blue.interacting.block_pos_err.mean),
        score(|e| e.blue.interacting.block_ori_err.mean)
    ))
}

/// A thesis model's learning curve and the reference rows drawn beside it.
pub type CurveWithReferences<'r> = (ModelKind, &'r PushReport, Vec<ReferenceLine<'r>>);

/// The thesis's models' default learning curves, each with the reference
/// rows of that timing, for the §3 figures.
///
/// # Errors
/// A document the reproduction does not have.
pub fn curves_and_references(
    results: &Reproduction,
) -> Result<Vec<CurveWithReferences<'_>>, String> {
    let references = References::of_timing(results, "")?;
    let lines: Vec<ReferenceLine<'_>> = references
        .reports()
        .iter()
        .map(|r| ReferenceLine {
            label: reference_label(&r.setup.model).unwrap_or("reference"),
            results: &r.results,
            actuator: r.setup.model != STILL,
        })
        .collect();
    [ModelKind::Gate, ModelKind::Interaction]
        .into_iter()
        .map(|model| {
            Ok((
                model,
                push_doc(results, &format!("push-task-{model}"))?,
                lines.clone(),
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
    .map(str::to_owned)
    .chain(
        crate::reproduce::manifest::BASELINES
            .iter()
            .map(crate::reproduce::manifest::Baseline::document),
    )
    .chain(reference_names());
    names
        .map(|name| {
            let report = push_doc(results, &name)?;
            let label = match (&report.setup.learner, report.setup.model.as_str()) {
                (Some(l), model) => format!("{model} {} (Python)", l.version),
                (None, model @ ("gate" | "interaction")) => format!("{model} (thesis model, Rust)"),
                (None, model) => {
                    reference_label(model).map_or_else(|| format!("{model} (Rust)"), str::to_owned)
                }
            };
            Ok((label, report))
        })
        .collect()
}

/// The default timing's reference documents, in the manifest's order.
fn reference_names() -> impl Iterator<Item = String> {
    references()
        .into_iter()
        .map(|(name, _)| crate::reproduce::manifest::reference_entry_name(name, ""))
}

/// Gate, interaction and every baseline (kNN, GP, MLP ensemble) at the
/// baseline table's training runs, all 21 positions: one row per learner
/// and N.
pub(super) fn baselines(results: &Reproduction) -> Result<String, String> {
    let references = References::of_timing(results, "")?;
    let mut out = String::from(
        "| learner | N | block position [m] | block orientation [rad] | actuator [m] | normalised: position / orientation | folds |\n|---|---|---|---|---|---|---|\n",
    );
    for (label, report) in baseline_curves(results)? {
        let name = &report.setup.model;
        for n in crate::reproduce::manifest::BASELINE_RUNS {
            let e = entry_at(report, name, n)?;
            let _ = writeln!(
                out,
                "| {label} | {n} | {} | {} | {} | {} | {} |",
                ms(e.blue.block_pos_err),
                ms(e.blue.block_ori_err),
                ms(e.blue.actuator_pos_err),
                references.normalised(e, n)?,
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
            .map(crate::reproduce::manifest::Baseline::document),
    );
    names.extend(reference_names());
    names
        .iter()
        .map(|name| {
            let report = push_doc(results, name)?;
            Ok((learner_label(&report.setup), report))
        })
        .collect()
}

/// One row per curve of [`beyond_curves`]: block position / orientation
/// at each of `manifest::BEYOND_RUNS`, the actuator at the first and the
/// third, and the normalised scores at the first and the last.
pub(super) fn beyond_ablation(results: &Reproduction) -> Result<String, String> {
    let runs = crate::reproduce::manifest::BEYOND_RUNS;
    let references = References::of_timing(results, "")?;
    let (first, last) = (runs[0], runs[runs.len() - 1]);
    let mut out = String::from("| model |");
    for n in runs {
        let _ = write!(out, " N = {n}: position [m] / orientation [rad] |");
    }
    let _ = writeln!(
        out,
        " actuator [m], N = {} / {} | normalised, N = {first}: position / orientation | normalised, N = {last} |",
        runs[0], runs[2]
    );
    out.push_str(&"|---".repeat(runs.len() + 4));
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
            " {:.4} / {:.4} | {} | {} |",
            a.blue.actuator_pos_err.mean,
            b.blue.actuator_pos_err.mean,
            references.normalised(a, first)?,
            references.normalised(entry_at(report, name, last)?, last)?
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
