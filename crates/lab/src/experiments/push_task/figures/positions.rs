//! Errors per test position for one N_train, beside the thesis's tables
//! where it has them (`docs/spec/reference-results.md` §5, §6).

use learner::eval::MeanStd;
use learner::{BLUE_ID, RED_ID};

use crate::report::plot::draw::{ours, padded, thesis, Grid, Panel};
use crate::report::plural;
use crate::report::reference::{self, Ms};
use drive::results::push_task::{BlockCurve, CurveEntry, PositionSummary};
use drive::results::PushReport;
use learner::registry::ModelKind;

/// The thesis's per-position values for this entry: (x0, position,
/// orientation) per block id.
fn position_refs(
    variant: &str,
    model: ModelKind,
    train_runs: usize,
    id: u32,
) -> Vec<(f64, Ms, Ms)> {
    match variant {
        "fixed-three" if train_runs == 3 => reference::fixed_three(model)
            .iter()
            .map(|r| (r.x0, r.pos, r.ori))
            .collect(),
        "two-objects" => reference::two_objects(train_runs)
            .map(|t| {
                t.iter()
                    .map(|r| {
                        if id == RED_ID {
                            (r.x0, r.red_pos, r.red_ori)
                        } else {
                            (r.x0, r.blue_pos, r.blue_ori)
                        }
                    })
                    .collect()
            })
            .unwrap_or_default(),
        _ => Vec::new(),
    }
}

fn position_panels(block: &BlockCurve, name: &str, refs: &[(f64, Ms, Ms)]) -> [Panel; 2] {
    let xs: Vec<f64> = block.per_position.iter().map(|p| p.x0).collect();
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let panel = |what: &str,
                 unit: &str,
                 get: fn(&PositionSummary) -> MeanStd,
                 r: fn(&(f64, Ms, Ms)) -> Ms| {
        let mut series = vec![ours(
            "ours",
            block.per_position.iter().map(|p| (p.x0, get(p))).collect(),
        )];
        series.extend(thesis(refs.iter().map(|t| (t.0, r(t))).collect()));
        Panel {
            title: format!("{name} {what}"),
            x_desc: "test start x0 [m]".to_owned(),
            y_desc: format!("error [{unit}]"),
            x_range: padded(lo, hi, 0.03),
            offset: 0.008,
            counts: false,
            series,
        }
    };
    [
        panel("position", "m", |p| p.block_pos_err, |t| t.1),
        panel("orientation", "rad", |p| p.block_ori_err, |t| t.2),
    ]
}

pub(super) fn positions_grid(report: &PushReport, model: ModelKind, entry: &CurveEntry) -> Grid {
    let variant = report.variant.as_str();
    let mut panels = Vec::new();
    if let Some(red) = &entry.red {
        let refs = position_refs(variant, model, entry.train_runs, RED_ID);
        panels.extend(position_panels(red, "red block", &refs));
    }
    let refs = position_refs(variant, model, entry.train_runs, BLUE_ID);
    panels.extend(position_panels(&entry.blue, "blue block", &refs));
    Grid {
        title: format!(
            "{model} model, {variant}, {}: per test position, mean ± std over {}",
            plural(entry.train_runs, "training run"),
            plural(entry.folds, "fold")
        ),
        columns: 2,
        panel_size: (560, 330),
        panels,
    }
}
