//! The cost-growth figure of `docs/performance.md`: per-message work
//! against the model's size.

use std::path::{Path, PathBuf};

use super::draw::{palette, prepare, write, Grid, Panel, Series};
use super::PlotError;

/// Per-message work of one model over one training run, after the model
/// learnt it: the cost-growth figure of docs/performance.md.
#[derive(Debug, Clone, PartialEq)]
pub struct CostPoint {
    /// The model's name ("gate", "interaction").
    pub model: String,
    /// Training runs learnt so far, this one included.
    pub runs: usize,
    /// Nodes in all the model's maps after the run.
    pub nodes: usize,
    /// Median of the run's per-message times, in µs.
    pub p50_us: f64,
    /// 99th percentile of the run's per-message times, in µs.
    pub p99_us: f64,
}

/// `points` as CSV with a header line, one row per point in order.
#[must_use]
pub fn cost_csv(points: &[CostPoint]) -> String {
    let mut out = String::from("model,runs,nodes,p50_us,p99_us\n");
    for p in points {
        out.push_str(&format!(
            "{},{},{},{:.3},{:.3}\n",
            p.model, p.runs, p.nodes, p.p50_us, p.p99_us
        ));
    }
    out
}

/// The cost-growth figure `dir/cost-growth.{png,svg}`: per-message time
/// against the model's node count, one line per model, p50 and p99 in two
/// panels (their scales differ by an order of magnitude).
///
/// # Errors
/// As [`push`](super::push).
pub fn cost_growth(
    points: &[CostPoint],
    title: &str,
    dir: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let mut models: Vec<&str> = Vec::new();
    for p in points {
        if !models.contains(&p.model.as_str()) {
            models.push(&p.model);
        }
    }
    let most = points.iter().map(|p| p.nodes).max().unwrap_or(1) as f64;
    let panel = |what: &str, get: fn(&CostPoint) -> f64| Panel {
        title: format!("{what} per message"),
        x_desc: "nodes in all maps".to_owned(),
        y_desc: "update + act + predict [µs]".to_owned(),
        x_range: 0.0..most * 1.02,
        offset: 0.0,
        counts: true,
        series: models
            .iter()
            .enumerate()
            .map(|(k, &model)| Series {
                label: model.to_owned(),
                colour: palette(k),
                points: points
                    .iter()
                    .filter(|p| p.model == model)
                    .map(|p| (p.nodes as f64, get(p), 0.0))
                    .collect(),
                bars: false,
            })
            .collect(),
    };
    let grid = Grid {
        title: title.to_owned(),
        columns: 2,
        panel_size: (520, 360),
        panels: vec![panel("p50", |p| p.p50_us), panel("p99", |p| p.p99_us)],
    };
    let mut written = Vec::new();
    write(&grid, dir, "cost-growth", &mut written)?;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{is_png, polyline_points, scratch, thick_polylines};
    use super::*;

    #[test]
    fn cost_growth_writes_the_csv_rows_and_a_line_per_model_and_panel() {
        let point = |model: &str, runs, nodes, p50_us, p99_us| CostPoint {
            model: model.to_owned(),
            runs,
            nodes,
            p50_us,
            p99_us,
        };
        let points = [
            point("gate", 1, 120, 1.5, 9.25),
            point("interaction", 1, 300, 2.0, 12.0),
            point("gate", 2, 240, 1.75, 10.0),
        ];
        assert_eq!(
            cost_csv(&points),
            "model,runs,nodes,p50_us,p99_us\n\
             gate,1,120,1.500,9.250\n\
             interaction,1,300,2.000,12.000\n\
             gate,2,240,1.750,10.000\n"
        );
        let dir = scratch("cost");
        let written = cost_growth(&points, "cost", &dir).unwrap();
        assert_eq!(
            written,
            vec![dir.join("cost-growth.png"), dir.join("cost-growth.svg")]
        );
        assert!(is_png(&written[0]));
        // Two panels of two models: four data lines and four legend
        // samples, the only polylines of stroke width 2 (the mesh is thinner);
        // gate's data lines join its two points.
        let svg = std::fs::read_to_string(&written[1]).unwrap();
        let thick = thick_polylines(&svg);
        assert_eq!(thick.len(), 8);
        let gate_points = |l: &&&str| l.contains("stroke=\"#1F77B4\"") && polyline_points(l) == 2;
        assert_eq!(thick.iter().filter(gate_points).count(), 4);
        assert!(svg.contains("p99 per message") && svg.contains("interaction"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
