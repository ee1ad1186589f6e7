//! The default latency maximum beside the harsher one.

use std::fmt::Write as _;

use super::{entry_at, errors, mtt_doc, push_doc, reached, runs};
use crate::reproduce::Reproduction;
use drive::experiment::{LATENCY_MAX_STEPS, LATENCY_MAX_STEPS_HARSH};
use drive::results::push_task::CurveEntry;
use learner::registry::ModelKind;

/// The `n`-run entries of document `base` and of its harsh-latency twin.
pub(super) fn with_harsh<'r>(
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

pub(super) fn latency(results: &Reproduction) -> Result<String, String> {
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
