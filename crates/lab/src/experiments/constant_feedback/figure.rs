//! The constant-feedback figure (`docs/spec/reference-results.md` §7).

use std::path::{Path, PathBuf};

use learner::BLUE_ID;

use crate::report::plot::draw::{palette, prepare, write, Grid, Panel, Series};
use crate::report::plot::PlotError;
use drive::results::FeedbackReport;
use learner::registry::ModelKind;

/// The figure of a constant-feedback report: the errors of every message's
/// prediction over the run, one line per run.
///
/// # Errors
/// As [`figures`](crate::experiments::push_task::figures).
pub fn feedback(
    report: &FeedbackReport,
    model: ModelKind,
    dir: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let longest = report
        .runs
        .iter()
        .map(|r| r.errors.len())
        .max()
        .unwrap_or(1) as f64;
    let panel = |title: &str, unit: &str, get: &dyn Fn(&learner::eval::RunErrors) -> f64| Panel {
        title: title.to_owned(),
        x_desc: format!("message (at {} Hz)", report.publish_rate_hz),
        y_desc: format!("error [{unit}]"),
        x_range: 0.0..longest + 1.0,
        offset: 0.0,
        counts: true,
        series: report
            .runs
            .iter()
            .enumerate()
            .map(|(k, r)| Series {
                label: format!("run from x0 = {:.2} m", r.x0),
                colour: palette(k),
                points: r
                    .errors
                    .iter()
                    .enumerate()
                    .map(|(i, e)| ((i + 1) as f64, get(e), 0.0))
                    .collect(),
                bars: false,
            })
            .collect(),
    };
    let block = |e: &learner::eval::RunErrors, ori: bool| {
        e.blocks
            .get(&BLUE_ID)
            .map_or(f64::NAN, |b| if ori { b.ori } else { b.pos })
    };
    let grid = Grid {
        title: format!(
            "{model} model, constant feedback at {} Hz, one run per start (no training phase, no folds): error of each message's prediction",
            report.publish_rate_hz
        ),
        columns: 3,
        panel_size: (420, 320),
        panels: vec![
            panel("actuator position", "m", &|e| e.actuator),
            panel("block position", "m", &|e| block(e, false)),
            panel("block orientation", "rad", &|e| block(e, true)),
        ],
    };
    let mut written = Vec::new();
    write(
        &grid,
        dir,
        &format!("push-task-{model}-constant-feedback"),
        &mut written,
    )?;
    Ok(written)
}
