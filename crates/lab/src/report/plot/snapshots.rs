//! Top-down snapshots: the bodies' footprints from the embedded scene, drawn
//! at given poses (predicted ones translucent, as in the thesis's figures),
//! metres square.

use std::ops::Range;

use learner::{ObjectState, Poses, ACTUATOR_ID};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Deserialize;

use super::draw::{body_colour, metres_tick, titled, Drawn, Figure, OrText, TRANSLUCENT};
use super::PlotError;
use crate::report::plural;
use drive::results::push_task::{CurveEntry, EndPoses};
use drive::results::PushReport;
use drive::scene::{push_task_blocks, PUSH_TASK_START_Y};
use learner::registry::ModelKind;

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
        "../../../../../sim-plugin/scenes/two_blocks.toml"
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
pub(crate) fn outline(shape: &Footprint, pose: ObjectState) -> Vec<(f64, f64)> {
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

/// How a body is drawn: filled with an opacity, or as an outline only (what
/// must stay visible over filled bodies: starts, targets).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Look {
    Filled(f64),
    Outline,
}

/// A body drawn in a snapshot.
#[derive(Clone, Debug)]
pub(crate) struct Body {
    pub(crate) outline: Vec<(f64, f64)>,
    pub(crate) colour: RGBColor,
    pub(crate) look: Look,
}

/// An entry of a snapshot figure's legend: a swatch drawn as the bodies it
/// names.
#[derive(Clone, Debug)]
pub(crate) struct LegendEntry {
    pub(crate) label: String,
    pub(crate) colour: RGBColor,
    pub(crate) look: Look,
}

/// Colour of the start outlines.
const START: RGBColor = RGBColor(20, 20, 20);

pub(crate) struct Snapshot {
    pub(crate) title: String,
    pub(crate) bodies: Vec<Body>,
}

fn bodies(poses: &Poses, shapes: &[(u32, Footprint)], look: Look) -> Vec<Body> {
    std::iter::once((ACTUATOR_ID, poses.actuator))
        .chain(poses.blocks.iter().map(|(&id, &s)| (id, s)))
        .filter(|(_, s)| s.x.is_finite() && s.y.is_finite() && s.theta.is_finite())
        .filter_map(|(id, s)| {
            let shape = shapes.iter().find(|(i, _)| *i == id)?;
            Some(Body {
                outline: outline(&shape.1, s),
                colour: if look == Look::Outline {
                    START
                } else {
                    body_colour(id)
                },
                look,
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

pub(crate) struct SnapshotGrid {
    pub(crate) title: String,
    pub(crate) columns: usize,
    /// Side of one (square) plotting area in pixels.
    pub(crate) side: u32,
    pub(crate) snapshots: Vec<Snapshot>,
    pub(crate) legend: Vec<LegendEntry>,
}

const SNAP_MARGIN: u32 = 4;
const SNAP_X_LABELS: u32 = 34;
const SNAP_Y_LABELS: u32 = 46;
const SNAP_TITLE: u32 = 18;
const LEGEND_HEIGHT: u32 = 22;

fn draw_body<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    body: &Body,
) -> Drawn {
    match body.look {
        Look::Filled(opacity) => chart
            .draw_series(std::iter::once(Polygon::new(
                body.outline.clone(),
                body.colour.mix(opacity).filled(),
            )))
            .map(|_| ())
            .or_text(),
        Look::Outline => {
            let mut closed = body.outline.clone();
            closed.extend(body.outline.first().copied());
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed,
                    body.colour.stroke_width(2),
                )))
                .map(|_| ())
                .or_text()
        }
    }
}

/// The legend as one centred row of swatches and labels.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Drawn {
    const SWATCH: i32 = 18;
    const GAP: i32 = 6;
    const SPACE: i32 = 18;
    let style = TextStyle::from(("sans-serif", 12).into_font());
    let widths: Vec<i32> = entries
        .iter()
        .map(|e| {
            area.estimate_text_size(&e.label, &style)
                .map_or(0, |(w, _)| i32::try_from(w).unwrap_or(0))
        })
        .collect();
    let total: i32 = widths.iter().map(|w| SWATCH + GAP + w + SPACE).sum::<i32>() - SPACE;
    let width = i32::try_from(area.dim_in_pixel().0).unwrap_or(i32::MAX);
    let mut x = ((width - total) / 2).max(4);
    for (e, w) in entries.iter().zip(widths) {
        let corners = [(x, 5), (x + SWATCH, 16)];
        match e.look {
            Look::Filled(opacity) => {
                area.draw(&Rectangle::new(corners, e.colour.mix(opacity).filled()))
            }
            Look::Outline => area.draw(&Rectangle::new(corners, e.colour.stroke_width(2))),
        }
        .or_text()?;
        area.draw(&Text::new(
            e.label.clone(),
            (x + SWATCH + GAP, 4),
            style.clone(),
        ))
        .or_text()?;
        x += SWATCH + GAP + w + SPACE;
    }
    Ok(())
}

impl Figure for SnapshotGrid {
    fn size(&self) -> (u32, u32) {
        let columns = self.columns.max(1);
        let rows = self.snapshots.len().div_ceil(columns).max(1);
        (
            (self.side + SNAP_Y_LABELS + 2 * SNAP_MARGIN) * columns as u32,
            (self.side + SNAP_X_LABELS + SNAP_TITLE + 2 * SNAP_MARGIN) * rows as u32
                + 30
                + LEGEND_HEIGHT,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Drawn {
        root.fill(&WHITE).or_text()?;
        let body = titled(root, &self.title)?;
        let (legend, body) = body.split_vertically(LEGEND_HEIGHT);
        draw_legend(&legend, &self.legend)?;
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
                .x_desc("x [m]")
                .y_desc("y [m]")
                .x_label_formatter(&metres_tick)
                .y_label_formatter(&metres_tick)
                .label_style(("sans-serif", 9))
                .axis_desc_style(("sans-serif", 10))
                .light_line_style(WHITE)
                .bold_line_style(BLACK.mix(0.08))
                .draw()
                .or_text()?;
            // In order: what comes later is drawn on top.
            for b in &snap.bodies {
                draw_body(&mut chart, b)?;
            }
        }
        Ok(())
    }
}

pub(crate) fn push_snapshots(
    report: &PushReport,
    model: ModelKind,
    entry: &CurveEntry,
    shapes: &[(u32, Footprint)],
) -> SnapshotGrid {
    let snapshots = entry
        .end_poses
        .iter()
        .map(|e: &EndPoses| {
            // The start under the ends; the prediction on top, translucent,
            // so that both ends stay visible.
            let start = Poses {
                actuator: ObjectState::new(e.x0, PUSH_TASK_START_Y, 0.0),
                blocks: push_task_blocks()
                    .into_iter()
                    .filter(|(id, _)| e.actual.blocks.contains_key(id))
                    .collect(),
            };
            let mut bodies = bodies(&start, shapes, Look::Outline);
            bodies.extend(self::bodies(&e.actual, shapes, Look::Filled(1.0)));
            bodies.extend(self::bodies(
                &e.predicted,
                shapes,
                Look::Filled(TRANSLUCENT),
            ));
            Snapshot {
                title: format!("x0 = {:.3} m", e.x0),
                bodies,
            }
        })
        .collect();
    let blue = body_colour(learner::BLUE_ID);
    SnapshotGrid {
        title: format!(
            "{model} model, {}, {}, fold 1 of {}: each test run's start, actual end and chained prediction",
            report.variant,
            plural(entry.train_runs, "training run"),
            entry.folds
        ),
        columns: 7,
        side: 170,
        snapshots,
        legend: vec![
            LegendEntry {
                label: "start".to_owned(),
                colour: START,
                look: Look::Outline,
            },
            LegendEntry {
                label: "actual end".to_owned(),
                colour: blue,
                look: Look::Filled(1.0),
            },
            LegendEntry {
                label: "predicted end (chained, translucent)".to_owned(),
                colour: blue,
                look: Look::Filled(TRANSLUCENT),
            },
        ],
    }
}

#[cfg(test)]
mod tests {
    use learner::{BLUE_ID, RED_ID};

    use super::*;

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
            bodies: bodies(&poses, &shapes, Look::Filled(1.0)),
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
}
