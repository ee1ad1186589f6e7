//! The ablation sweep: each configuration by training runs, against the
//! defaults.

use std::fmt::Write as _;

use super::{change, error};
use crate::reproduce::Reproduction;
use crate::sweep::summary::{change_label, Metric};

/// The ablation's summary: one row per configuration, the blue block's
/// position / orientation error (mean over seeds) at each number of
/// training runs, and the change against the model's defaults at 10 runs
/// (or the largest number below).
pub(super) fn ablation(results: &Reproduction) -> Result<String, String> {
    let name = crate::reproduce::manifest::ABLATION;
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
