//! The new-object experiments: each learner by training and test object.

use std::fmt::Write as _;

use super::references::{reference_label, References};
use super::{entry_at, push_doc};
use crate::reproduce::Reproduction;
use drive::results::{PushReport, Setup};

/// A learner's label and its report on each new-object condition.
pub type ObjectRow<'r> = (String, Vec<&'r PushReport>);

/// A learner as the page's tables and figures name it: a Python learner by
/// its model and version, the thesis's models as such, the reference rows
/// by what they are, the others by name.
pub(super) fn learner_label(setup: &Setup) -> String {
    match (&setup.learner, setup.model.as_str()) {
        (Some(l), model) => format!("{model} {} (Python)", l.version),
        (None, model @ ("gate" | "interaction")) => format!("{model} (thesis model)"),
        (None, model) => reference_label(model).map_or_else(|| model.to_owned(), str::to_owned),
    }
}

/// The new-object experiments: the conditions' labels, and for each
/// learner (label) its report on each condition, in the manifest's order.
///
/// # Errors
/// A document the reproduction does not have.
pub fn object_reports(results: &Reproduction) -> Result<(Vec<String>, Vec<ObjectRow<'_>>), String> {
    use crate::reproduce::manifest::{object_entry_name, object_learners, transfers};
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
/// training runs, and its normalised score against that condition's
/// reference rows.
pub(super) fn beyond_objects(results: &Reproduction) -> Result<String, String> {
    let (conditions, rows) = object_reports(results)?;
    let references = crate::reproduce::manifest::transfers()
        .iter()
        .map(|t| References::of_objects(results, t))
        .collect::<Result<Vec<_>, _>>()?;
    let mut out = String::from("| learner |");
    for c in &conditions {
        let _ = write!(out, " {c} |");
    }
    out.push('\n');
    out.push_str(&"|---".repeat(conditions.len() + 1));
    out.push_str("|\n");
    for (label, reports) in rows {
        let _ = write!(out, "| {label} |");
        for (report, references) in reports.iter().zip(&references) {
            out.push_str(&block_cell(
                report,
                crate::reproduce::manifest::OBJECT_RUNS,
                references,
            )?);
        }
        out.push('\n');
    }
    Ok(out)
}

/// A table cell: the block's position / orientation error after `n`
/// training runs, with the normalised scores in brackets.
fn block_cell(report: &PushReport, n: usize, references: &References) -> Result<String, String> {
    let e = entry_at(report, &report.setup.model, n)?;
    Ok(format!(
        " {:.3} / {:.3} ({}) |",
        e.blue.block_pos_err.mean,
        e.blue.block_ori_err.mean,
        references.normalised(e, n)?
    ))
}

/// The cross-object table: one row per learner and number of training
/// runs, one column per condition (trained on one object, tested on
/// another): block position / orientation error.
pub(super) fn cross_objects(results: &Reproduction) -> Result<String, String> {
    use crate::reproduce::manifest::{
        cross_entry_name, cross_transfers, CROSS_LEARNERS, CROSS_RUNS,
    };
    let conditions = cross_transfers();
    let references = conditions
        .iter()
        .map(|t| References::of_cross(results, t))
        .collect::<Result<Vec<_>, _>>()?;
    let mut out = String::from("| learner | N |");
    for c in &conditions {
        let _ = write!(out, " {} |", c.label());
    }
    out.push('\n');
    out.push_str(&"|---".repeat(conditions.len() + 2));
    out.push_str("|\n");
    for learner in CROSS_LEARNERS {
        let reports = conditions
            .iter()
            .map(|t| push_doc(results, &cross_entry_name(learner, t)))
            .collect::<Result<Vec<_>, _>>()?;
        let label = learner_label(&reports[0].setup);
        for n in CROSS_RUNS {
            let _ = write!(out, "| {label} | {n} |");
            for (report, references) in reports.iter().zip(&references) {
                out.push_str(&block_cell(report, n, references)?);
            }
            out.push('\n');
        }
    }
    Ok(out)
}
