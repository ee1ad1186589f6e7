//! The targets, seed 1 beside the spread of the other seeds, met or
//! missed; and the targets of the models beyond the thesis.

use std::fmt::Write as _;

use super::{entry_at, mtt_doc, push_doc, reached, runs};
use crate::report::reference;
use crate::reproduce::manifest::SPREAD_SEEDS;
use crate::reproduce::Reproduction;
use drive::results::push_task::CurveEntry;
use drive::results::{MttReport, PushReport};
use learner::registry::ModelKind;

/// One target row: seed 1, the other seeds' range, met or not.
pub(super) struct TargetRow {
    what: String,
    thesis: String,
    /// Seed 1, then the spread seeds, in order.
    values: Vec<f64>,
    decimals: usize,
    /// Whether a value meets the target.
    meets: Box<dyn Fn(f64) -> bool>,
}

pub(super) fn targets(results: &Reproduction) -> Result<String, String> {
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

/// The targets for gate+, each against its measured value.
pub(super) fn beyond_targets(results: &Reproduction) -> Result<String, String> {
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
    let baselines: Vec<&PushReport> = crate::reproduce::manifest::BASELINES
        .iter()
        .map(|b| push_doc(results, &b.document()))
        .collect::<Result<_, _>>()?;
    let mut worse = Vec::new();
    for n in crate::reproduce::manifest::BEYOND_RUNS {
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
        "better than every baseline (kNN, GP, MLP ensemble; block position and orientation) at every N".to_owned(),
        if worse.is_empty() {
            "better at every N".to_owned()
        } else {
            format!("not better at {}", worse.join(", "))
        },
        worse.is_empty(),
    );
    Ok(out)
}
