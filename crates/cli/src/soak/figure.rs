//! The soak's figure (`pushlearn ctl soak --plots DIR`): the world's and the
//! learner's resident memory, the journal against its bound, and the state
//! directory's bytes over the run.

use std::path::{Path, PathBuf};

use super::{Sample, SoakReport};
use lab::report::plot::draw::{palette, prepare, write, Grid, Panel, Series};
use lab::report::plot::PlotError;

/// Draws `soak.png` and `soak.svg` into `dir`.
///
/// # Errors
/// As [`figures`](lab::experiments::push_task::figures).
pub fn soak(report: &SoakReport, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    // Minutes for a long run, seconds for a short one.
    let (scale, unit) = if report.load.seconds >= 120.0 {
        (1.0 / 60.0, "min")
    } else {
        (1.0, "s")
    };
    let x_desc = format!("time [{unit}]");
    let x_range = 0.0..(report.load.seconds * scale).max(f64::EPSILON);
    let line = |k: usize, label: &str, points: Vec<(f64, f64)>| Series {
        label: label.to_owned(),
        colour: palette(k),
        points: points
            .into_iter()
            .map(|(x, y)| (x * scale, y, 0.0))
            .collect(),
        bars: false,
    };
    let learner = |get: fn(&Sample) -> f64| -> Vec<(f64, f64)> {
        report.samples.iter().map(|s| (s.seconds, get(s))).collect()
    };
    let panel = |title: &str, y_desc: &str, series: Vec<Series>| Panel {
        title: title.to_owned(),
        x_desc: x_desc.clone(),
        y_desc: y_desc.to_owned(),
        x_range: x_range.clone(),
        offset: 0.0,
        counts: false,
        series,
    };
    let memory = panel(
        "resident memory",
        "RSS [MiB]",
        vec![
            line(
                0,
                "world (pushlearn-sim)",
                report
                    .load
                    .rss_kib
                    .iter()
                    .map(|&(t, kib)| (t, kib as f64 / 1024.0))
                    .collect(),
            ),
            line(
                1,
                "learner (pushlearn learn)",
                learner(|s| s.learner_rss_kib as f64 / 1024.0),
            ),
        ],
    );
    let bound = report.journal_bound() as f64;
    let journal = panel(
        "journal records on disk",
        "records",
        vec![
            line(2, "journal", learner(|s| s.on_disk.journal_records as f64)),
            line(
                3,
                "bound: 2 × --snapshot-every",
                vec![(0.0, bound), (report.load.seconds, bound)],
            ),
        ],
    );
    let bytes = panel(
        "state directory",
        "size [KiB]",
        vec![
            line(
                2,
                "journal",
                learner(|s| s.on_disk.journal_bytes as f64 / 1024.0),
            ),
            line(
                4,
                "snapshots",
                learner(|s| s.on_disk.snapshot_bytes as f64 / 1024.0),
            ),
        ],
    );
    let grid = Grid {
        title: format!(
            "Soak: pushlearn learn --state beside {} subscribers, {:.0} s",
            report.load.clients, report.load.seconds
        ),
        columns: 3,
        panel_size: (440, 340),
        panels: vec![memory, journal, bytes],
    };
    let mut written = Vec::new();
    write(&grid, dir, "soak", &mut written)?;
    Ok(written)
}
