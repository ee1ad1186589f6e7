//! Move to Target: reached targets per model and timing setting, and the
//! improved models on the thesis's and the sampled targets.

use std::fmt::Write as _;

use super::{mtt_doc, reached, runs};
use crate::report::reference;
use crate::reproduce::Reproduction;
use drive::experiment::{LATENCY_MAX_STEPS, LATENCY_MAX_STEPS_HARSH};
use drive::results::MttReport;
use learner::registry::ModelKind;

/// Reached per thesis target (of 5) and mean steps for the thesis's gate
/// model, forward-check and gate+, then reached of the sampled targets.
pub(super) fn beyond_move_to_target(results: &Reproduction) -> Result<String, String> {
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
        "beyond-mtt-hybrid",
    ] {
        let r = mtt_doc(results, name)?;
        let _ = writeln!(out, "| {} | {} |", r.setup.model, mtt_cells(r));
    }
    out.push_str("\n| Model | Sampled targets reached | Mean steps (failures count the limit) | Mean steps of the reached |\n|---|---|---|---|\n");
    for name in [
        "beyond-sampled-gate",
        "beyond-sampled-gate-plus",
        "beyond-sampled-hybrid",
    ] {
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

pub(super) fn move_to_target(results: &Reproduction) -> Result<String, String> {
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
pub(super) fn reached_and_steps(per_target: impl Iterator<Item = (usize, f64)> + Clone) -> String {
    let reached: Vec<String> = per_target.clone().map(|(r, _)| r.to_string()).collect();
    let steps: Vec<String> = per_target.clone().map(|(_, s)| format!("{s:.0}")).collect();
    let total: usize = per_target.map(|(r, _)| r).sum();
    format!("{} | {total} | {}", reached.join(" | "), steps.join(" / "))
}

/// [`reached_and_steps`] of one of our documents.
pub(super) fn mtt_cells(r: &MttReport) -> String {
    reached_and_steps(
        r.targets
            .iter()
            .map(|t| (t.summary.reached, t.summary.steps)),
    )
}

/// [`reached_and_steps`] of the thesis's table for `model`.
pub(super) fn thesis_mtt_cells(model: ModelKind) -> String {
    reached_and_steps(
        reference::move_to_target(model)
            .iter()
            .map(|r| (r.reached, r.steps)),
    )
}
