//! Learning curves of several learners on one figure (`docs/results.md`,
//! "Baselines"): the same push task, one series per learner.

use std::path::{Path, PathBuf};

use learner::eval::MeanStd;

use super::draw::{coloured, prepare, write, Grid, Panel};
use super::PlotError;
use crate::report::plural;
use drive::results::push_task::CurveEntry;
use drive::results::PushReport;
use learner::registry::ModelKind;

/// Draws `dir/{stem}.png` and `.svg`: block position, block orientation and
/// actuator error over the training runs (all 21 test positions, mean ±
/// mean per-position std), one series per `(label, report)`.
///
/// # Errors
/// The directory cannot be created or the figure cannot be written.
pub fn learners(
    curves: &[(String, &PushReport)],
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let n_max = curves
        .iter()
        .flat_map(|(_, r)| r.results.iter().map(|e| e.train_runs))
        .max()
        .unwrap_or(1) as f64;
    let folds = curves.iter().map(|(_, r)| r.folds).max().unwrap_or(0);
    // A reference's actuator never moves: 0.75 m after a run, off the scale
    // of every learner's actuator; it is in the tables.
    let still = |report: &PushReport| {
        ModelKind::of_report_name(&report.setup.model).is_some_and(ModelKind::is_reference)
    };
    let panel = |title: &str, y: &str, get: fn(&CurveEntry) -> MeanStd, actuator: bool| Panel {
        title: title.to_owned(),
        x_desc: "training runs (N_train)".to_owned(),
        y_desc: y.to_owned(),
        x_range: 0.0..n_max + 1.0,
        offset: 0.3,
        counts: true,
        // Left out with no points rather than no series, so that every
        // learner keeps its colour in every panel.
        series: coloured(curves.iter().map(|(label, report)| {
            let points = report
                .results
                .iter()
                .filter(|_| !(actuator && still(report)))
                .map(|e| {
                    let m = get(e);
                    (e.train_runs as f64, m.mean, m.std)
                })
                .collect();
            (label.clone(), points)
        })),
    };
    let grid = Grid {
        title: format!(
            "push task, all 21 test positions, {}: mean ± mean per-position std",
            plural(folds, "fold")
        ),
        columns: 3,
        panel_size: (420, 340),
        panels: vec![
            panel(
                "block position",
                "error [m]",
                |e| e.blue.block_pos_err,
                false,
            ),
            panel(
                "block orientation",
                "error [rad]",
                |e| e.blue.block_ori_err,
                false,
            ),
            panel(
                "actuator position",
                "error [m]",
                |e| e.blue.actuator_pos_err,
                true,
            ),
        ],
    };
    let mut written = Vec::new();
    write(&grid, dir, stem, &mut written)?;
    Ok(written)
}

/// Draws `dir/{stem}.png` and `.svg`: block position and orientation error
/// on each of `conditions` (the x axis numbers them; the title names
/// them), one series per `(label, reports)`, `reports[c]` the learner's
/// push task on condition `c` (its first number of training runs).
///
/// # Errors
/// The directory cannot be created or the figure cannot be written.
pub fn by_condition(
    conditions: &[String],
    rows: &[(String, Vec<&PushReport>)],
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let first = rows
        .iter()
        .flat_map(|(_, reports)| reports.iter())
        .find_map(|r| r.results.first());
    let (n_train, folds) = first.map_or((0, 0), |e| (e.train_runs, e.folds));
    let panel = |title: &str, y: &str, get: fn(&CurveEntry) -> MeanStd| Panel {
        title: title.to_owned(),
        x_desc: "condition (see the title)".to_owned(),
        y_desc: y.to_owned(),
        x_range: 0.0..conditions.len() as f64 + 1.0,
        offset: 0.12,
        counts: true,
        series: coloured(rows.iter().map(|(label, reports)| {
            let points = reports
                .iter()
                .enumerate()
                .filter_map(|(c, r)| {
                    let m = get(r.results.first()?);
                    Some(((c + 1) as f64, m.mean, m.std))
                })
                .collect();
            (label.clone(), points)
        })),
    };
    let names: Vec<String> = conditions
        .iter()
        .enumerate()
        .map(|(c, name)| format!("{} {name}", c + 1))
        .collect();
    let grid = Grid {
        title: format!(
            "new objects, trained on → tested on: {}; {}, {}: mean ± mean per-position std",
            names.join(", "),
            plural(n_train, "training run"),
            plural(folds, "fold")
        ),
        columns: 2,
        panel_size: (560, 380),
        panels: vec![
            panel("block position", "error [m]", |e| e.blue.block_pos_err),
            panel("block orientation", "error [rad]", |e| e.blue.block_ori_err),
        ],
    };
    let mut written = Vec::new();
    write(&grid, dir, stem, &mut written)?;
    Ok(written)
}
