//! The ablation's figure (`docs/results.md`, "Ablation"): for each model,
//! the blue block's errors over the training runs, one series per
//! configuration, mean and spread over the sweep's seeds.

use std::path::{Path, PathBuf};

use super::summary::{change_label, Metric, Summary};
use crate::report::plot::draw::{coloured, prepare, write, Grid, Panel};
use crate::report::plot::PlotError;
use crate::report::plural;

/// How many times the defaults' largest error a configuration may reach
/// and still be drawn: a diverging one (η = 0.2 reaches kilometres) would
/// flatten every other series to the axis.
const OFF_SCALE: f64 = 10.0;

/// Draws `dir/{stem}.png` and `.svg`: a row of two panels (position,
/// orientation) per model of `summary`, over the training runs, one series
/// per configuration named by what it changes. A series more than
/// [`OFF_SCALE`] times the model's defaults is not drawn; the panel's
/// title names it.
///
/// # Errors
/// The directory cannot be created or the figure cannot be written.
pub fn ablation(summary: &Summary, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let runs = summary.train_runs();
    let n_max = runs.iter().copied().max().unwrap_or(1) as f64;
    let configurations = summary.configurations();
    let mut models: Vec<&str> = Vec::new();
    for (_, _, model) in &configurations {
        if !models.contains(model) {
            models.push(model);
        }
    }
    let points = |id: &str, metric: Metric| -> Vec<(f64, f64, f64)> {
        runs.iter()
            .filter_map(|&n| {
                let (mean, spread) = summary.row(id, n)?.mean_spread(metric);
                Some((n as f64, mean, spread))
            })
            .collect()
    };
    let panel = |model: &str, metric: Metric, title: &str, y: &str| {
        let limit = summary.defaults_of(model).map(|d| {
            OFF_SCALE
                * points(d, metric)
                    .iter()
                    .map(|&(_, mean, _)| mean)
                    .fold(0.0, f64::max)
        });
        let (drawn, off): (Vec<_>, Vec<_>) = configurations
            .iter()
            .filter(|(_, _, m)| *m == model)
            .map(|(id, options, _)| (change_label(options), points(id, metric)))
            .partition(|(_, p)| limit.is_none_or(|l| p.iter().all(|&(_, mean, _)| mean <= l)));
        let off: Vec<String> = off.into_iter().map(|(label, _)| label).collect();
        Panel {
            title: if off.is_empty() {
                format!("{model}: {title}")
            } else {
                format!("{model}: {title} (off the scale: {})", off.join(", "))
            },
            x_desc: "training runs (N_train)".to_owned(),
            y_desc: y.to_owned(),
            x_range: 0.0..n_max + 1.0,
            offset: 0.12,
            counts: true,
            series: coloured(drawn),
        }
    };
    let panels = models
        .iter()
        .flat_map(|model| {
            [
                panel(model, Metric::BlockPosition, "block position", "error [m]"),
                panel(
                    model,
                    Metric::BlockOrientation,
                    "block orientation",
                    "error [rad]",
                ),
            ]
        })
        .collect();
    let grid = Grid {
        title: format!(
            "ablation, push task, {}, {}: mean ± spread over seeds of each seed's mean error",
            plural(summary.seeds.len(), "seed"),
            plural(summary.folds, "fold")
        ),
        columns: 2,
        panel_size: (620, 440),
        panels,
    };
    let mut written = Vec::new();
    write(&grid, dir, stem, &mut written)?;
    Ok(written)
}
