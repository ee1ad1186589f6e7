//! Figures of the report documents, each written as PNG and SVG: learning
//! curves with error bars beside the thesis's (`docs/spec/reference-results.md` §3.2,
//! §3.4), per-position errors (§5, §6), top-down snapshots of actual versus
//! predicted end configurations (predicted bodies translucent, as in the
//! thesis's figures), constant-feedback errors per message (§7) and Move to
//! Target errors over steps with the final block poses (§8).
//!
//! Every entry point is a pure function from a report to files in a
//! directory; it returns the paths it wrote. Text is laid out with the
//! DejaVu Sans font embedded in the binary (`assets/fonts/`), so no system
//! font library is needed.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use learner::eval::MeanStd;
use learner::{ObjectState, Poses, ACTUATOR_ID, BLUE_ID, RED_ID};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Deserialize;

use super::reference::{self, Ms};
use crate::models::ModelKind;
use crate::results::push_task::{BlockCurve, CurveEntry, EndPoses, PositionSummary};
use crate::results::{FeedbackReport, MttReport, PushReport};

/// What can go wrong while writing figures.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The output directory cannot be created.
    #[error("cannot create the figure directory {path}: {source}")]
    Dir {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The embedded font or scene cannot be read (a broken build).
    #[error("embedded {what} unusable: {reason}")]
    Embedded { what: &'static str, reason: String },
    /// Drawing or writing one figure failed.
    #[error("cannot write the figure {path}: {reason}")]
    Draw { path: PathBuf, reason: String },
    /// A line of a measurement table does not parse.
    #[error("line {line} of the measurements: {reason}")]
    Table { line: usize, reason: String },
}

const FONT: &[u8] = include_bytes!("../../../../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font once as "sans-serif".
fn font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
                .map_err(|_| "not a TrueType font".to_owned())
        })
        .clone()
        .map_err(|reason| PlotError::Embedded {
            what: "font",
            reason,
        })
}

/// Drawing errors are reported as text: plotters' error types are generic
/// over the backend.
type Drawn = Result<(), String>;

trait OrText<T> {
    fn or_text(self) -> Result<T, String>;
}

impl<T, E: std::fmt::Display> OrText<T> for Result<T, E> {
    fn or_text(self) -> Result<T, String> {
        self.map_err(|e| e.to_string())
    }
}

/// One figure, drawable on any backend.
trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Drawn;
}

/// Writes `figure` as `dir/stem.png` and `dir/stem.svg`.
fn write(
    figure: &impl Figure,
    dir: &Path,
    stem: &str,
    written: &mut Vec<PathBuf>,
) -> Result<(), PlotError> {
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    let failed = |path: &Path| {
        let path = path.to_path_buf();
        move |reason| PlotError::Draw { path, reason }
    };
    {
        let root = BitMapBackend::new(&png, figure.size()).into_drawing_area();
        figure
            .draw(&root)
            .and_then(|()| root.present().or_text())
            .map_err(failed(&png))?;
    }
    {
        let root = SVGBackend::new(&svg, figure.size()).into_drawing_area();
        figure
            .draw(&root)
            .and_then(|()| root.present().or_text())
            .map_err(failed(&svg))?;
    }
    written.push(png);
    written.push(svg);
    Ok(())
}

fn prepare(dir: &Path) -> Result<(), PlotError> {
    font()?;
    std::fs::create_dir_all(dir).map_err(|source| PlotError::Dir {
        path: dir.to_path_buf(),
        source,
    })
}

// ---------------------------------------------------------------- colours

const OURS: RGBColor = RGBColor(31, 119, 180);
const THESIS: RGBColor = RGBColor(214, 95, 14);
const EXTRA: RGBColor = RGBColor(44, 160, 44);
const ACTUATOR: RGBColor = RGBColor(60, 60, 60);
const BLUE_BLOCK: RGBColor = RGBColor(40, 90, 220);
const RED_BLOCK: RGBColor = RGBColor(220, 50, 40);
const TARGET: RGBColor = RGBColor(120, 120, 120);
/// Opacity of predicted (and target) bodies in the snapshots.
const TRANSLUCENT: f64 = 0.3;

/// A distinct colour for the k-th line of a family.
fn palette(k: usize) -> RGBColor {
    const COLOURS: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    COLOURS[k % COLOURS.len()]
}

fn body_colour(id: u32) -> RGBColor {
    match id {
        ACTUATOR_ID => ACTUATOR,
        RED_ID => RED_BLOCK,
        _ => BLUE_BLOCK,
    }
}

// ------------------------------------------------------------ axis ranges

/// A value axis from 0 to a bit above the largest of `tops` (so that every
/// error bar fits), or 0…1 when there is nothing finite to show.
fn value_range(tops: impl IntoIterator<Item = f64>) -> Range<f64> {
    let top = tops
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    if top > 0.0 {
        0.0..top * 1.08
    } else {
        0.0..1.0
    }
}

/// `lo…hi` widened by `pad` on both sides (and to a minimal width).
fn padded(lo: f64, hi: f64, pad: f64) -> Range<f64> {
    if lo.is_finite() && hi.is_finite() && lo <= hi {
        (lo - pad)..(hi + pad).max(lo + pad)
    } else {
        -1.0..1.0
    }
}

// ----------------------------------------------------------- error panels

/// One series of a panel: points with optional error bars.
struct Series {
    label: String,
    colour: RGBColor,
    /// (x, mean, std); std 0 draws no bar.
    points: Vec<(f64, f64, f64)>,
    bars: bool,
}

impl Series {
    fn tops(&self) -> impl Iterator<Item = f64> + '_ {
        self.points.iter().map(|&(_, m, s)| m + s)
    }
}

/// Points of `ours`, and of the thesis's values where it has them.
fn ours(label: &str, points: Vec<(f64, MeanStd)>) -> Series {
    Series {
        label: label.to_owned(),
        colour: OURS,
        points: points
            .into_iter()
            .map(|(x, m)| (x, m.mean, m.std))
            .collect(),
        bars: true,
    }
}

fn thesis(points: Vec<(f64, Ms)>) -> Option<Series> {
    (!points.is_empty()).then(|| Series {
        label: "thesis".to_owned(),
        colour: THESIS,
        points: points.into_iter().map(|(x, Ms(m, s))| (x, m, s)).collect(),
        bars: true,
    })
}

struct Panel {
    title: String,
    x_desc: String,
    y_desc: String,
    x_range: Range<f64>,
    /// Drawn at x + offset·k for the k-th series, so bars do not overlap.
    offset: f64,
    /// x is a count (training runs, messages, steps): labels without decimals.
    counts: bool,
    series: Vec<Series>,
}

impl Panel {
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Drawn {
        let y_range = value_range(self.series.iter().flat_map(Series::tops));
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(52)
            .build_cartesian_2d(self.x_range.clone(), y_range)
            .or_text()?;
        let whole = |x: &f64| format!("{x:.0}");
        let mut mesh = chart.configure_mesh();
        if self.counts {
            mesh.x_label_formatter(&whole);
        }
        mesh.x_desc(self.x_desc.as_str())
            .y_desc(self.y_desc.as_str())
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            .light_line_style(WHITE)
            .draw()
            .or_text()?;
        let centre = (self.series.len() as f64 - 1.0) / 2.0;
        for (k, s) in self.series.iter().enumerate() {
            let shift = self.offset * (k as f64 - centre);
            let colour = s.colour;
            let line: Vec<(f64, f64)> = s.points.iter().map(|&(x, m, _)| (x + shift, m)).collect();
            chart
                .draw_series(LineSeries::new(line, colour.stroke_width(2)))
                .or_text()?
                .label(s.label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            if s.bars {
                chart
                    .draw_series(s.points.iter().map(|&(x, m, sd)| {
                        ErrorBar::new_vertical(x + shift, m - sd, m, m + sd, colour.filled(), 6)
                    }))
                    .or_text()?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(("sans-serif", 11))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .or_text()
    }
}

/// Panels side by side (`columns` per row).
struct Grid {
    title: String,
    columns: usize,
    panel_size: (u32, u32),
    panels: Vec<Panel>,
}

impl Figure for Grid {
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(self.columns.max(1)).max(1);
        (
            self.panel_size.0 * self.columns as u32,
            self.panel_size.1 * rows as u32 + 30,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Drawn {
        root.fill(&WHITE).or_text()?;
        let body = root.titled(&self.title, ("sans-serif", 17)).or_text()?;
        let rows = self.panels.len().div_ceil(self.columns.max(1)).max(1);
        let areas = body.split_evenly((rows, self.columns.max(1)));
        for (panel, area) in self.panels.iter().zip(&areas) {
            panel.draw(area)?;
        }
        Ok(())
    }
}

// ------------------------------------------------------- learning curves

fn curve_grid(model: ModelKind, results: &[CurveEntry], interacting: bool) -> Grid {
    let source = match model {
        ModelKind::Gate => "§3.4",
        ModelKind::Interaction => "§3.2",
    };
    let n_max = results.iter().map(|e| e.train_runs).max().unwrap_or(1) as f64;
    let refs = |get: fn(&reference::CurveRef) -> Ms| -> Option<Series> {
        thesis(
            results
                .iter()
                .filter_map(|e| {
                    reference::curve(model, e.train_runs).map(|r| (e.train_runs as f64, get(r)))
                })
                .collect(),
        )
    };
    let mine = |get: fn(&CurveEntry) -> MeanStd| -> Series {
        ours(
            "ours",
            results
                .iter()
                .map(|e| (e.train_runs as f64, get(e)))
                .collect(),
        )
    };
    let panel = |title: &str, y: &str, mut series: Vec<Series>, reference: Option<Series>| {
        series.extend(reference);
        Panel {
            title: title.to_owned(),
            x_desc: "training runs".to_owned(),
            y_desc: y.to_owned(),
            x_range: 0.0..n_max + 1.0,
            offset: 0.35,
            counts: true,
            series,
        }
    };
    let panels = if interacting {
        let quirk = Series {
            label: "ours, script's (mean+std)/2".to_owned(),
            colour: EXTRA,
            points: results
                .iter()
                .map(|e| {
                    (
                        e.train_runs as f64,
                        e.blue.interacting.actuator_pos_err_script_quirk,
                        0.0,
                    )
                })
                .collect(),
            bars: false,
        };
        vec![
            panel(
                "block position",
                "error [m]",
                vec![mine(|e| e.blue.interacting.block_pos_err)],
                refs(|r| r.pos_interacting),
            ),
            panel(
                "block orientation",
                "error [rad]",
                vec![mine(|e| e.blue.interacting.block_ori_err)],
                refs(|r| r.ori_interacting),
            ),
            panel(
                "actuator position",
                "error [m]",
                vec![mine(|e| e.blue.interacting.actuator_pos_err), quirk],
                refs(|r| r.actuator_interacting_quirk),
            ),
        ]
    } else {
        vec![
            panel(
                "block position",
                "error [m]",
                vec![mine(|e| e.blue.block_pos_err)],
                refs(|r| r.pos),
            ),
            panel(
                "block orientation",
                "error [rad]",
                vec![mine(|e| e.blue.block_ori_err)],
                refs(|r| r.ori),
            ),
            panel(
                "actuator position",
                "error [m]",
                vec![mine(|e| e.blue.actuator_pos_err)],
                refs(|r| r.actuator),
            ),
        ]
    };
    let which = if interacting {
        "15 interacting test positions"
    } else {
        "all 21 test positions"
    };
    Grid {
        title: format!(
            "{model} model, learning curve over {which}: mean ± mean per-position std (thesis {source})"
        ),
        columns: 3,
        panel_size: (420, 340),
        panels,
    }
}

// ------------------------------------------------------ per-position errors

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

fn positions_grid(report: &PushReport, model: ModelKind, entry: &CurveEntry) -> Grid {
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
            "{model} model, {variant}, {} training runs: per test position, mean ± std over {} folds",
            entry.train_runs, entry.folds
        ),
        columns: 2,
        panel_size: (560, 330),
        panels,
    }
}

// ----------------------------------------------------------- snapshots

/// The bodies' footprints in the world's scenes (`sim-plugin/scenes/`).
#[derive(Clone, Debug, PartialEq)]
pub enum Footprint {
    Circle { radius: f64 },
    Rectangle { length: f64, width: f64 },
}

#[derive(Deserialize)]
struct SceneFile {
    body: Vec<BodyFile>,
}

#[derive(Deserialize)]
struct BodyFile {
    id: u32,
    shape: ShapeFile,
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
enum ShapeFile {
    Sphere { radius: f64 },
    Box { size: [f64; 3] },
}

/// Footprints by body id, read from the embedded two-block scene (which
/// holds every body of the one-block scene with the same shapes).
///
/// # Errors
/// The embedded scene does not parse (a broken build).
pub fn footprints() -> Result<Vec<(u32, Footprint)>, PlotError> {
    let scene: SceneFile = toml::from_str(include_str!(
        "../../../../sim-plugin/scenes/two_blocks.toml"
    ))
    .map_err(|e| PlotError::Embedded {
        what: "scene",
        reason: e.to_string(),
    })?;
    Ok(scene
        .body
        .into_iter()
        .map(|b| {
            let shape = match b.shape {
                ShapeFile::Sphere { radius } => Footprint::Circle { radius },
                ShapeFile::Box { size } => Footprint::Rectangle {
                    length: size[0],
                    width: size[1],
                },
            };
            (b.id, shape)
        })
        .collect())
}

/// The outline of `shape` at `pose`, in world coordinates.
fn outline(shape: &Footprint, pose: ObjectState) -> Vec<(f64, f64)> {
    match *shape {
        Footprint::Circle { radius } => (0..32)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::TAU / 32.0;
                (pose.x + radius * a.cos(), pose.y + radius * a.sin())
            })
            .collect(),
        Footprint::Rectangle { length, width } => {
            let (s, c) = pose.theta.sin_cos();
            [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
                .iter()
                .map(|&(u, v)| {
                    let (dx, dy) = (u * length / 2.0, v * width / 2.0);
                    (pose.x + c * dx - s * dy, pose.y + s * dx + c * dy)
                })
                .collect()
        }
    }
}

/// A body drawn in a snapshot.
#[derive(Clone, Debug)]
struct Body {
    outline: Vec<(f64, f64)>,
    colour: RGBColor,
    opacity: f64,
}

struct Snapshot {
    title: String,
    bodies: Vec<Body>,
}

fn bodies(poses: &Poses, shapes: &[(u32, Footprint)], opacity: f64) -> Vec<Body> {
    std::iter::once((ACTUATOR_ID, poses.actuator))
        .chain(poses.blocks.iter().map(|(&id, &s)| (id, s)))
        .filter(|(_, s)| s.x.is_finite() && s.y.is_finite() && s.theta.is_finite())
        .filter_map(|(id, s)| {
            let shape = shapes.iter().find(|(i, _)| *i == id)?;
            Some(Body {
                outline: outline(&shape.1, s),
                colour: body_colour(id),
                opacity,
            })
        })
        .collect()
}

/// A square region (same span in x and y) that holds every body of every
/// snapshot, with a margin.
fn square_bounds(snapshots: &[Snapshot]) -> (Range<f64>, Range<f64>) {
    let points = snapshots
        .iter()
        .flat_map(|s| &s.bodies)
        .flat_map(|b| &b.outline);
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !(x0 <= x1 && y0 <= y1) {
        return (-1.0..1.0, -1.0..1.0);
    }
    let half = (x1 - x0).max(y1 - y0) / 2.0 + 0.05;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    ((cx - half)..(cx + half), (cy - half)..(cy + half))
}

/// Widens the narrower of the two ranges so that a metre is as long in x
/// as in y on a plotting area of `pixels` (bodies keep their shapes).
fn fit_aspect(x: Range<f64>, y: Range<f64>, pixels: (u32, u32)) -> (Range<f64>, Range<f64>) {
    let (w, h) = (f64::from(pixels.0.max(1)), f64::from(pixels.1.max(1)));
    let (dx, dy) = (x.end - x.start, y.end - y.start);
    let widen = |r: Range<f64>, span: f64| {
        let c = (r.start + r.end) / 2.0;
        (c - span / 2.0)..(c + span / 2.0)
    };
    if dx / w < dy / h {
        (widen(x, dy / h * w), y)
    } else {
        (x, widen(y, dx / w * h))
    }
}

struct SnapshotGrid {
    title: String,
    columns: usize,
    /// Side of one (square) plotting area in pixels.
    side: u32,
    snapshots: Vec<Snapshot>,
}

const SNAP_MARGIN: u32 = 4;
const SNAP_X_LABELS: u32 = 22;
const SNAP_Y_LABELS: u32 = 34;
const SNAP_TITLE: u32 = 18;

impl Figure for SnapshotGrid {
    fn size(&self) -> (u32, u32) {
        let columns = self.columns.max(1);
        let rows = self.snapshots.len().div_ceil(columns).max(1);
        (
            (self.side + SNAP_Y_LABELS + 2 * SNAP_MARGIN) * columns as u32,
            (self.side + SNAP_X_LABELS + SNAP_TITLE + 2 * SNAP_MARGIN) * rows as u32 + 30,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Drawn {
        root.fill(&WHITE).or_text()?;
        let body = root.titled(&self.title, ("sans-serif", 17)).or_text()?;
        let columns = self.columns.max(1);
        let rows = self.snapshots.len().div_ceil(columns).max(1);
        let (x_range, y_range) = square_bounds(&self.snapshots);
        for (snap, area) in self
            .snapshots
            .iter()
            .zip(&body.split_evenly((rows, columns)))
        {
            let area = area.titled(&snap.title, ("sans-serif", 12)).or_text()?;
            let (w, h) = area.dim_in_pixel();
            let plot_px = (
                w.saturating_sub(2 * SNAP_MARGIN + SNAP_Y_LABELS),
                h.saturating_sub(2 * SNAP_MARGIN + SNAP_X_LABELS),
            );
            let (x_range, y_range) = fit_aspect(x_range.clone(), y_range.clone(), plot_px);
            let mut chart = ChartBuilder::on(&area)
                .margin(SNAP_MARGIN)
                .x_label_area_size(SNAP_X_LABELS)
                .y_label_area_size(SNAP_Y_LABELS)
                .build_cartesian_2d(x_range, y_range)
                .or_text()?;
            chart
                .configure_mesh()
                .x_labels(5)
                .y_labels(5)
                .label_style(("sans-serif", 9))
                .light_line_style(WHITE)
                .bold_line_style(BLACK.mix(0.08))
                .draw()
                .or_text()?;
            chart
                .draw_series(
                    snap.bodies
                        .iter()
                        .map(|b| Polygon::new(b.outline.clone(), b.colour.mix(b.opacity).filled())),
                )
                .or_text()?;
        }
        Ok(())
    }
}

fn push_snapshots(
    report: &PushReport,
    model: ModelKind,
    entry: &CurveEntry,
    shapes: &[(u32, Footprint)],
) -> SnapshotGrid {
    let snapshots = entry
        .end_poses
        .iter()
        .map(|e: &EndPoses| {
            // The prediction on top, translucent, so that both stay visible.
            let mut bodies = bodies(&e.actual, shapes, 1.0);
            bodies.extend(self::bodies(&e.predicted, shapes, TRANSLUCENT));
            Snapshot {
                title: format!("x0 = {:.3}", e.x0),
                bodies,
            }
        })
        .collect();
    SnapshotGrid {
        title: format!(
            "{model} model, {}, {} training runs, fold 1: actual end of each test run (opaque) and the chained prediction (translucent)",
            report.variant, entry.train_runs
        ),
        columns: 7,
        side: 170,
        snapshots,
    }
}

// --------------------------------------------------------- entry points

fn stem(report: &PushReport, model: ModelKind) -> String {
    format!("push-task-{model}-{}", report.variant)
}

/// The figures of a push-task report: learning curves (when it has more
/// than one N_train), per-position errors and snapshots for each N_train.
///
/// # Errors
/// The directory cannot be created or a figure cannot be written.
pub fn push(report: &PushReport, model: ModelKind, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let shapes = footprints()?;
    let stem = stem(report, model);
    let mut written = Vec::new();
    if report.results.len() > 1 {
        write(
            &curve_grid(model, &report.results, false),
            dir,
            &format!("{stem}-curve"),
            &mut written,
        )?;
        if report.variant != "two-objects" {
            write(
                &curve_grid(model, &report.results, true),
                dir,
                &format!("{stem}-curve-interacting"),
                &mut written,
            )?;
        }
    }
    for entry in &report.results {
        let n = entry.train_runs;
        write(
            &positions_grid(report, model, entry),
            dir,
            &format!("{stem}-positions-n{n}"),
            &mut written,
        )?;
        if !entry.end_poses.is_empty() {
            write(
                &push_snapshots(report, model, entry, &shapes),
                dir,
                &format!("{stem}-snapshots-n{n}"),
                &mut written,
            )?;
        }
    }
    Ok(written)
}

/// The figure of a constant-feedback report: the errors of every message's
/// prediction over the run, one line per run.
///
/// # Errors
/// As [`push`].
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
        x_desc: "message".to_owned(),
        y_desc: format!("error [{unit}]"),
        x_range: 0.0..longest + 1.0,
        offset: 0.0,
        counts: true,
        series: report
            .runs
            .iter()
            .enumerate()
            .map(|(k, r)| Series {
                label: format!("x0 = {:.2}", r.x0),
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
            "{model} model, constant feedback at {} Hz: error of each message's prediction",
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

/// The figures of a Move-to-Target report: the block's errors to the target
/// over the steps, one line per run and a row per target; and the final
/// block poses (opaque) over the target pose (translucent).
///
/// # Errors
/// As [`push`].
pub fn move_to_target(
    report: &MttReport,
    model: ModelKind,
    dir: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let shapes = footprints()?;
    let max_steps = report.max_steps as f64;
    let mut panels = Vec::new();
    for (t, target) in report.targets.iter().enumerate() {
        let [x, y, ori] = target.target;
        for (what, unit) in [("position", "m"), ("orientation", "rad")] {
            panels.push(Panel {
                title: format!("target {} ({x}, {y}, {ori:.2}): {what}", t + 1),
                x_desc: "step".to_owned(),
                y_desc: format!("error [{unit}]"),
                x_range: 0.0..max_steps,
                offset: 0.0,
                counts: true,
                series: target
                    .runs
                    .iter()
                    .enumerate()
                    .map(|(k, r)| {
                        let values = if unit == "m" {
                            &r.trace.pos_err
                        } else {
                            &r.trace.ori_err
                        };
                        Series {
                            label: format!(
                                "run {} ({})",
                                k + 1,
                                if r.reached { "reached" } else { "failed" }
                            ),
                            colour: palette(k),
                            points: r
                                .trace
                                .steps
                                .iter()
                                .zip(values)
                                .map(|(&s, &v)| (s as f64, v, 0.0))
                                .collect(),
                            bars: false,
                        }
                    })
                    .collect(),
            });
        }
    }
    let mut written = Vec::new();
    let stem = format!("move-to-target-{model}");
    write(
        &Grid {
            title: format!(
                "{model} model, Move to Target: the block's error to the target over the steps"
            ),
            columns: 2,
            panel_size: (560, 300),
            panels,
        },
        dir,
        &format!("{stem}-errors"),
        &mut written,
    )?;
    let block_shape = shapes
        .iter()
        .find(|(id, _)| *id == BLUE_ID)
        .map(|(_, s)| s.clone())
        .ok_or(PlotError::Embedded {
            what: "scene",
            reason: "no blue block".to_owned(),
        })?;
    let snapshots = report
        .targets
        .iter()
        .enumerate()
        .map(|(t, target)| {
            let [x, y, theta] = target.target;
            let mut bodies = vec![Body {
                outline: outline(&block_shape, ObjectState::new(x, y, theta)),
                colour: TARGET,
                opacity: TRANSLUCENT,
            }];
            bodies.extend(
                target
                    .runs
                    .iter()
                    .enumerate()
                    .filter(|(_, r)| {
                        let b = r.final_block;
                        b.x.is_finite() && b.y.is_finite() && b.theta.is_finite()
                    })
                    .map(|(k, r)| Body {
                        outline: outline(&block_shape, r.final_block),
                        colour: palette(k),
                        opacity: 0.8,
                    }),
            );
            Snapshot {
                title: format!(
                    "target {} ({}/{} reached)",
                    t + 1,
                    target.summary.reached,
                    target.summary.runs
                ),
                bodies,
            }
        })
        .collect();
    write(
        &SnapshotGrid {
            title: format!("{model} model, Move to Target: final block poses (one colour per run) over the target (grey, translucent)"),
            columns: report.targets.len().clamp(1, 4),
            side: 260,
            snapshots,
        },
        dir,
        &format!("{stem}-final"),
        &mut written,
    )?;
    Ok(written)
}

// ------------------------------------------------------------ cost growth

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
/// As [`push`].
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

// ----------------------------------------------------------- AITM scaling

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
        let body = root.titled(&self.title, ("sans-serif", 17)).or_text()?;
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
/// As [`push`].
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
    use std::collections::BTreeMap;

    use learner::eval::{BlockError, RunErrors};
    use learner::ModelStats;

    use super::*;
    use crate::results::move_to_target::{ErrorTrace, MttRun, TargetSummary};
    use crate::results::push_task::{summarise, PushJobResult};
    use crate::results::run_info::{Counters, RunInfo};
    use crate::results::{Setup, TargetEntry};

    /// A fresh directory under the system's temporary one.
    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("pushlearn-plot-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn count(path: &Path, tag: &str) -> usize {
        let text = std::fs::read_to_string(path).unwrap();
        text.matches(&format!("<{tag}")).count()
    }

    /// The SVG's polylines of stroke width 2: data lines and legend
    /// samples (the mesh is thinner).
    fn thick_polylines(svg: &str) -> Vec<&str> {
        svg.split("<polyline")
            .skip(1)
            .filter(|l| l.contains("stroke-width=\"2\""))
            .collect()
    }

    /// Points of one polyline from [`thick_polylines`].
    fn polyline_points(line: &str) -> usize {
        line.split("points=\"").nth(1).map_or(0, |p| {
            p.split('"').next().unwrap_or("").split_whitespace().count()
        })
    }

    fn is_png(path: &Path) -> bool {
        std::fs::read(path)
            .unwrap()
            .starts_with(b"\x89PNG\r\n\x1a\n")
    }

    fn push_report(train_runs: &[usize], folds: usize) -> PushReport {
        let xs = learner::eval::test_positions().to_vec();
        let jobs: Vec<PushJobResult> = train_runs
            .iter()
            .flat_map(|&n| (0..folds).map(move |f| (n, f)))
            .map(|(n, fold)| {
                let errors = (0..xs.len())
                    .map(|i| RunErrors {
                        actuator: 0.001 * (fold + 1) as f64,
                        blocks: BTreeMap::from([(
                            BLUE_ID,
                            BlockError {
                                pos: 0.1 / n as f64 + 0.01 * (i % 3) as f64,
                                ori: 0.5 / n as f64,
                            },
                        )]),
                    })
                    .collect();
                let end_poses = xs
                    .iter()
                    .map(|&x0| {
                        let mut actual = Poses {
                            actuator: ObjectState::new(x0, 0.75, 0.0),
                            ..Poses::default()
                        };
                        actual
                            .blocks
                            .insert(BLUE_ID, ObjectState::new(0.0, 0.8, 0.3));
                        let mut predicted = actual.clone();
                        predicted
                            .blocks
                            .insert(BLUE_ID, ObjectState::new(0.1, 0.7, -0.2));
                        EndPoses {
                            x0,
                            actual,
                            predicted,
                        }
                    })
                    .collect();
                PushJobResult {
                    n_train: n,
                    fold,
                    training_starts: vec![0.0; n],
                    errors,
                    end_poses,
                    keypoints: Vec::new(),
                    selection: Default::default(),
                    nodes: ModelStats::default(),
                    counters: Counters::default(),
                    timing: Default::default(),
                }
            })
            .collect();
        PushReport {
            setup: Setup::for_tests("push-task", "gate"),
            variant: "random".into(),
            folds,
            train_runs: train_runs.to_vec(),
            results: summarise(&xs, &[BLUE_ID], train_runs, &jobs).unwrap(),
            run: RunInfo::default(),
        }
    }

    #[test]
    fn push_figures_have_a_bar_per_point_and_a_body_per_pose() {
        let dir = scratch("push");
        let report = push_report(&[1, 3, 30], 2);
        let written = push(&report, ModelKind::Gate, &dir.join("nested")).unwrap();
        // Two curves, then per N_train the positions and the snapshots; each
        // as PNG and SVG.
        assert_eq!(written.len(), 2 * (2 + 3 * 2));
        for path in &written {
            let ext = path.extension().and_then(|e| e.to_str());
            assert!(path.is_file(), "{}", path.display());
            match ext {
                Some("png") => assert!(is_png(path), "{}", path.display()),
                Some("svg") => {
                    let text = std::fs::read_to_string(path).unwrap();
                    assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
                }
                _ => panic!("unexpected file {}", path.display()),
            }
        }
        let svg = |stem: &str| {
            dir.join("nested")
                .join(format!("push-task-gate-random-{stem}.svg"))
        };
        // Learning curve: 3 panels × (3 of ours + 3 of the thesis's) bars,
        // each drawn with one dot.
        assert_eq!(count(&svg("curve"), "circle"), 18);
        // The interacting curve has no thesis bars for the script's values.
        assert_eq!(count(&svg("curve-interacting"), "circle"), 18);
        // Per position: 2 panels × 21 bars of ours; no thesis table for the
        // random variant.
        assert_eq!(count(&svg("positions-n3"), "circle"), 42);
        // Snapshots: 21 runs × (actuator + block) × (actual + predicted).
        assert_eq!(count(&svg("snapshots-n1"), "polygon"), 84);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn fixed_three_positions_show_the_thesis_table() {
        let dir = scratch("fixed");
        let mut report = push_report(&[3], 2);
        report.variant = "fixed-three".into();
        push(&report, ModelKind::Interaction, &dir).unwrap();
        let svg = dir.join("push-task-interaction-fixed-three-positions-n3.svg");
        // 2 panels × 21 positions × (ours + §5.2).
        assert_eq!(count(&svg, "circle"), 84);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn mtt_report(runs_per_target: usize) -> MttReport {
        let run = |k: usize| MttRun {
            reached: k % 2 == 0,
            steps: 100,
            pos_err: 0.2,
            ori_err: 0.1,
            final_block: ObjectState::new(0.5, 0.6, -2.0 + 0.1 * k as f64),
            trace: ErrorTrace {
                steps: vec![0, 10, 20, 30],
                pos_err: vec![0.7, 0.5, 0.4, 0.2],
                ori_err: vec![2.1, 1.0, 0.5, 0.1],
            },
        };
        let runs: Vec<MttRun> = (0..runs_per_target).map(run).collect();
        MttReport {
            setup: Setup::for_tests("move-to-target", "gate"),
            repetitions: runs_per_target,
            max_steps: 3000,
            targets: vec![
                TargetEntry {
                    target: [0.6, 0.7, -2.1],
                    summary: TargetSummary::of(&runs),
                    runs: runs.clone(),
                    nodes_after_training: Default::default(),
                },
                TargetEntry {
                    target: [-0.6, -0.7, 0.0],
                    summary: TargetSummary::of(&runs),
                    runs,
                    nodes_after_training: Default::default(),
                },
            ],
            run: RunInfo::default(),
        }
    }

    #[test]
    fn move_to_target_figures_draw_a_line_per_run_and_a_block_per_end() {
        let dir = scratch("mtt");
        let polylines = |runs: usize| {
            let written = move_to_target(&mtt_report(runs), ModelKind::Gate, &dir).unwrap();
            assert_eq!(written.len(), 4);
            assert!(written
                .iter()
                .filter(|p| p.extension().is_some_and(|e| e == "png"))
                .all(|p| is_png(p)));
            let final_svg = dir.join("move-to-target-gate-final.svg");
            // The target and each run's final block, per target.
            assert_eq!(count(&final_svg, "polygon"), 2 * (1 + runs));
            count(&dir.join("move-to-target-gate-errors.svg"), "polyline")
        };
        // One more run adds, in each of the 2 × 2 panels, its line and its
        // legend entry.
        assert_eq!(polylines(4) - polylines(3), 4 * 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_uncreatable_directory_is_a_clear_error() {
        let dir = scratch("blocked");
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a-file");
        std::fs::write(&file, "").unwrap();
        let err = push(
            &push_report(&[1], 1),
            ModelKind::Gate,
            &file.join("figures"),
        )
        .unwrap_err();
        assert!(matches!(err, PlotError::Dir { .. }), "{err}");
        assert!(
            err.to_string()
                .contains("cannot create the figure directory"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn value_axes_cover_every_bar() {
        let r = value_range([0.1, 0.35, f64::NAN, 0.2]);
        assert_eq!(r.start, 0.0);
        assert!(r.end > 0.35 && r.end < 0.4);
        assert_eq!(value_range([f64::NAN]), 0.0..1.0);
        assert_eq!(value_range([0.0]), 0.0..1.0);
        let p = padded(-0.35, 0.35, 0.03);
        assert!(p.start < -0.35 && p.end > 0.35);
    }

    #[test]
    fn snapshots_keep_metres_square_and_hold_every_body() {
        let (x, y) = fit_aspect(-0.5..0.5, 0.0..1.0, (400, 200));
        assert!(((x.end - x.start) / 400.0 - (y.end - y.start) / 200.0).abs() < 1e-12);
        assert!(x.start <= -0.5 && x.end >= 0.5 && y.start <= 0.0 && y.end >= 1.0);
        let (x, y) = fit_aspect(-0.5..0.5, 0.0..1.0, (100, 300));
        assert!(((x.end - x.start) / 100.0 - (y.end - y.start) / 300.0).abs() < 1e-12);
        assert!(y.start <= 0.0 && y.end >= 1.0);

        let shapes = footprints().unwrap();
        let mut poses = Poses {
            actuator: ObjectState::new(-0.3, 0.75, 0.0),
            ..Poses::default()
        };
        poses
            .blocks
            .insert(BLUE_ID, ObjectState::new(0.2, 0.9, 1.0));
        let snap = Snapshot {
            title: String::new(),
            bodies: bodies(&poses, &shapes, 1.0),
        };
        let (x, y) = square_bounds(std::slice::from_ref(&snap));
        assert!((x.end - x.start - (y.end - y.start)).abs() < 1e-12);
        for &(px, py) in snap.bodies.iter().flat_map(|b| &b.outline) {
            assert!(
                x.contains(&px) && y.contains(&py),
                "({px}, {py}) outside {x:?} × {y:?}"
            );
        }
    }

    #[test]
    fn bodies_have_the_scene_sizes_and_turn_with_theta() {
        let shapes = footprints().unwrap();
        let get = |id| {
            shapes
                .iter()
                .find(|(i, _)| *i == id)
                .map(|(_, s)| s.clone())
        };
        assert_eq!(get(ACTUATOR_ID), Some(Footprint::Circle { radius: 0.025 }));
        assert_eq!(
            get(BLUE_ID),
            Some(Footprint::Rectangle {
                length: 0.5,
                width: 0.1
            })
        );
        assert_eq!(
            get(RED_ID),
            Some(Footprint::Rectangle {
                length: 0.3,
                width: 0.3
            })
        );
        // The blue block turned by 90°: its long side along y.
        let corners = outline(
            &Footprint::Rectangle {
                length: 0.5,
                width: 0.1,
            },
            ObjectState::new(1.0, 2.0, std::f64::consts::FRAC_PI_2),
        );
        let ys: Vec<f64> = corners.iter().map(|c| c.1).collect();
        let xs: Vec<f64> = corners.iter().map(|c| c.0).collect();
        let span = |v: &[f64]| {
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
        };
        assert!((span(&ys) - 0.5).abs() < 1e-12 && (span(&xs) - 0.1).abs() < 1e-12);
        // A circle's outline lies on its radius.
        let circle = outline(
            &Footprint::Circle { radius: 0.025 },
            ObjectState::new(0.1, 0.2, 0.0),
        );
        assert!(circle
            .iter()
            .all(|&(x, y)| ((x - 0.1).hypot(y - 0.2) - 0.025).abs() < 1e-12));
    }

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
