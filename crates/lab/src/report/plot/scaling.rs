//! The AITM scaling figure of `docs/performance.md`: µs per call against
//! the map's size, log-log, from the benchmark's CSV.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::draw::{palette, prepare, titled, write, Drawn, Figure, OrText, Series};
use super::PlotError;

/// One row of `target/aitm_scaling.csv`, written by `cargo bench -p learner
/// --bench aitm_scaling`: µs per call of one map size and search.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalingRow {
    /// Input distribution ("runs", "uniform").
    pub shape: String,
    pub nodes: usize,
    /// "index" or "scan".
    pub search: String,
    pub along_us: f64,
    pub near_us: f64,
    pub far_us: f64,
    pub update_us: f64,
}

/// The header the benchmark writes (its times are in ns).
const SCALING_HEADER: &str =
    "shape,nodes,search,along_query_ns,near_query_ns,far_query_ns,update_ns";

/// Parses the benchmark's CSV.
///
/// # Errors
/// [`PlotError::Table`] naming the first line that is not the expected
/// header or a row of positive finite times.
pub fn parse_scaling_csv(text: &str) -> Result<Vec<ScalingRow>, PlotError> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, header)) if header.trim() == SCALING_HEADER => {}
        _ => {
            return Err(PlotError::Table {
                line: 1,
                reason: format!("expected the header \"{SCALING_HEADER}\""),
            })
        }
    }
    let mut rows = Vec::new();
    for (k, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let bad = |reason: String| PlotError::Table {
            line: k + 1,
            reason,
        };
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let [shape, nodes, search, times @ ..] = cells.as_slice() else {
            return Err(bad("fewer than 7 fields".into()));
        };
        let nodes: usize = nodes
            .parse()
            .map_err(|_| bad(format!("node count {nodes:?} is not a whole number")))?;
        let times: Vec<f64> = times
            .iter()
            .map(|t| match t.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(v / 1e3),
                _ => Err(bad(format!("time {t:?} is not a positive number of ns"))),
            })
            .collect::<Result<_, _>>()?;
        let [along_us, near_us, far_us, update_us] = times[..] else {
            return Err(bad(format!("{} times instead of 4", times.len())));
        };
        if nodes == 0 {
            return Err(bad("a map of 0 nodes".into()));
        }
        rows.push(ScalingRow {
            shape: (*shape).to_owned(),
            nodes,
            search: (*search).to_owned(),
            along_us,
            near_us,
            far_us,
            update_us,
        });
    }
    Ok(rows)
}

/// Log-log panels of µs per call against nodes, one per input shape.
struct LogLog {
    title: String,
    panels: Vec<(String, Vec<Series>)>,
}

impl Figure for LogLog {
    fn size(&self) -> (u32, u32) {
        (560 * self.panels.len().max(1) as u32, 430)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Drawn {
        root.fill(&WHITE).or_text()?;
        let body = titled(root, &self.title)?;
        let areas = body.split_evenly((1, self.panels.len().max(1)));
        let all = || {
            self.panels
                .iter()
                .flat_map(|(_, s)| s)
                .flat_map(|s| &s.points)
        };
        let span = |get: fn(&(f64, f64, f64)) -> f64| {
            all()
                .map(get)
                .fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                })
        };
        let (x_lo, x_hi) = span(|p| p.0);
        let (y_lo, y_hi) = span(|p| p.1);
        // No point at all leaves the spans at +∞.
        if !(x_lo > 0.0 && y_lo > 0.0 && x_lo.is_finite() && y_lo.is_finite()) {
            return Err("no measurements to draw".into());
        }
        for ((title, series), area) in self.panels.iter().zip(&areas) {
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 15))
                .margin(8)
                .x_label_area_size(34)
                .y_label_area_size(52)
                .build_cartesian_2d(
                    (x_lo / 1.5..x_hi * 1.5).log_scale(),
                    (y_lo / 1.5..y_hi * 1.5).log_scale(),
                )
                .or_text()?;
            chart
                .configure_mesh()
                .x_desc("nodes in the map")
                .y_desc("µs per call")
                .x_label_formatter(&|x| format!("{x:.0}"))
                .label_style(("sans-serif", 11))
                .axis_desc_style(("sans-serif", 12))
                .draw()
                .or_text()?;
            for s in series {
                let colour = s.colour;
                let line: Vec<(f64, f64)> = s.points.iter().map(|&(x, y, _)| (x, y)).collect();
                chart
                    .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                    .or_text()?
                    .label(s.label.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                    });
                chart
                    .draw_series(line.into_iter().map(|p| Circle::new(p, 3, colour.filled())))
                    .or_text()?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .label_font(("sans-serif", 11))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .draw()
                .or_text()?;
        }
        Ok(())
    }
}

/// The AITM-alone figure `dir/aitm-scaling.{png,svg}`: query (along, near,
/// far) and update time through the index, and the scan's near query,
/// against the node count, log-log, one panel per input shape.
///
/// # Errors
/// As [`push`](super::push).
pub fn aitm_scaling(rows: &[ScalingRow], dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let mut shapes: Vec<&str> = Vec::new();
    for r in rows {
        if !shapes.contains(&r.shape.as_str()) {
            shapes.push(&r.shape);
        }
    }
    type Get = fn(&ScalingRow) -> f64;
    let kinds: [(&str, &str, Get); 5] = [
        ("index", "query along a run", |r| r.along_us),
        ("index", "query near, random", |r| r.near_us),
        ("index", "query far", |r| r.far_us),
        ("index", "update", |r| r.update_us),
        ("scan", "scan: query near", |r| r.near_us),
    ];
    let panels = shapes
        .iter()
        .map(|&shape| {
            let series = kinds
                .iter()
                .enumerate()
                .map(|(k, &(search, label, get))| {
                    let mut points: Vec<(f64, f64, f64)> = rows
                        .iter()
                        .filter(|r| r.shape == shape && r.search == search)
                        .map(|r| (r.nodes as f64, get(r), 0.0))
                        .collect();
                    points.sort_by(|a, b| a.0.total_cmp(&b.0));
                    Series {
                        label: label.to_owned(),
                        colour: palette(k),
                        points,
                        bars: false,
                    }
                })
                .filter(|s| !s.points.is_empty())
                .collect();
            (format!("{shape} inputs"), series)
        })
        .collect();
    let figure = LogLog {
        title: "One AITM (8 inputs, 3 outputs): time per call against map size".to_owned(),
        panels,
    };
    let mut written = Vec::new();
    write(&figure, dir, "aitm-scaling", &mut written)?;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{is_png, polyline_points, scratch, thick_polylines};
    use super::*;

    #[test]
    fn the_scaling_table_parses_and_names_the_line_it_cannot_read() {
        let header = SCALING_HEADER;
        let rows = parse_scaling_csv(&format!(
            "{header}\nruns,1000,index,780,860,1700,1100\n\nruns,1000,scan,2040,2060,1700,2510\n"
        ))
        .unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(
            rows[0],
            ScalingRow {
                shape: "runs".into(),
                nodes: 1000,
                search: "index".into(),
                along_us: 0.78,
                near_us: 0.86,
                far_us: 1.7,
                update_us: 1.1,
            }
        );
        let line_of = |text: &str| match parse_scaling_csv(text) {
            Err(PlotError::Table { line, .. }) => line,
            other => panic!("{other:?}"),
        };
        assert_eq!(line_of("shape,nodes,search,query_ns,update_ns\n"), 1);
        assert_eq!(line_of(&format!("{header}\nruns,1000,index,1,2,3\n")), 2);
        assert_eq!(
            line_of(&format!(
                "{header}\nruns,1000,index,1,2,3,4\nruns,x,index,1,2,3,4\n"
            )),
            3
        );
        assert_eq!(line_of(&format!("{header}\nruns,10,index,1,NaN,3,4\n")), 2);
        assert_eq!(line_of(&format!("{header}\nruns,10,index,1,-2,3,4\n")), 2);
        assert_eq!(line_of(&format!("{header}\nruns,0,index,1,2,3,4\n")), 2);
    }

    #[test]
    fn aitm_scaling_draws_a_line_per_kind_and_shape() {
        let row = |shape: &str, nodes, search: &str, t: f64| ScalingRow {
            shape: shape.into(),
            nodes,
            search: search.into(),
            along_us: t,
            near_us: 2.0 * t,
            far_us: 3.0 * t,
            update_us: 4.0 * t,
        };
        let rows = [
            row("runs", 1_000, "index", 1.0),
            row("runs", 1_000_000, "index", 1.5),
            row("runs", 10_000, "index", 1.2),
            row("runs", 1_000, "scan", 2.0),
            row("runs", 100_000, "scan", 200.0),
            row("uniform", 1_000, "index", 4.0),
            row("uniform", 10_000, "index", 9.0),
        ];
        let dir = scratch("scaling");
        let written = aitm_scaling(&rows, &dir).unwrap();
        assert_eq!(
            written,
            vec![dir.join("aitm-scaling.png"), dir.join("aitm-scaling.svg")]
        );
        assert!(is_png(&written[0]));
        // runs: 4 index kinds + the scan; uniform: the 4 index kinds only.
        // Each has a data line and a legend sample of stroke width 2; the
        // runs index lines join their three sizes (sorted by node count),
        // every other line two points.
        let svg = std::fs::read_to_string(&written[1]).unwrap();
        let thick = thick_polylines(&svg);
        assert_eq!(thick.len(), 2 * 9);
        let with = |n| thick.iter().filter(|l| polyline_points(l) == n).count();
        assert_eq!((with(3), with(2)), (4, 14));
        assert!(svg.contains("uniform inputs") && svg.contains("scan: query near"));
        assert!(aitm_scaling(&[], &dir).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
