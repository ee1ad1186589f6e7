//! What every figure is drawn with: the embedded font, writing a figure as
//! PNG and SVG, the colours, axis ranges, and panels of points with error
//! bars laid out in a grid.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use learner::eval::MeanStd;
use learner::{ACTUATOR_ID, RED_ID};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::PlotError;
use crate::report::reference::Ms;

const FONT: &[u8] = include_bytes!("../../../../../assets/fonts/DejaVuSans.ttf");

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
pub type Drawn = Result<(), String>;

pub trait OrText<T> {
    fn or_text(self) -> Result<T, String>;
}

impl<T, E: std::fmt::Display> OrText<T> for Result<T, E> {
    fn or_text(self) -> Result<T, String> {
        self.map_err(|e| e.to_string())
    }
}

/// One figure, drawable on any backend.
pub trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Drawn;
}

/// Writes `figure` as `dir/stem.png` and `dir/stem.svg`, each whole: drawn
/// under a temporary name (the PNG encoder picks its format by the
/// extension, so it stays `.png`) or in memory, then renamed into place.
pub fn write(
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
    let partial_png = dir.join(format!(".{stem}.partial.png"));
    {
        let root = BitMapBackend::new(&partial_png, figure.size()).into_drawing_area();
        figure
            .draw(&root)
            .and_then(|()| root.present().or_text())
            .map_err(failed(&png))?;
    }
    std::fs::rename(&partial_png, &png).map_err(|err| {
        let _ = std::fs::remove_file(&partial_png);
        failed(&png)(err.to_string())
    })?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, figure.size()).into_drawing_area();
        figure
            .draw(&root)
            .and_then(|()| root.present().or_text())
            .map_err(failed(&svg))?;
    }
    drive::output::write_atomically(&svg, text.as_bytes())
        .map_err(|err| failed(&svg)(err.to_string()))?;
    written.push(png);
    written.push(svg);
    Ok(())
}

pub fn prepare(dir: &Path) -> Result<(), PlotError> {
    font()?;
    std::fs::create_dir_all(dir).map_err(|source| PlotError::Dir {
        path: dir.to_path_buf(),
        source,
    })
}

// ----------------------------------------------------------------- titles

/// Font size of a figure's title, and the smallest it is shrunk to before
/// it is broken onto a second line.
const TITLE_SIZE: u32 = 17;
const TITLE_MIN_SIZE: u32 = 13;

/// `title` as the lines it is drawn on: one if it fits (per `fits`), else
/// two, broken at the space nearest its middle (a title of one word stays
/// whole).
fn title_lines(title: &str, fits: impl Fn(&str) -> bool) -> Vec<String> {
    if fits(title) {
        return vec![title.to_owned()];
    }
    let middle = title.len() / 2;
    let split = title
        .match_indices(' ')
        .map(|(at, _)| at)
        .min_by_key(|&at| at.abs_diff(middle));
    match split {
        Some(at) => vec![title[..at].to_owned(), title[at + 1..].to_owned()],
        None => vec![title.to_owned()],
    }
}

/// Draws `title` across the top of `root` and returns the area below it.
/// A title wider than the canvas is drawn smaller, and then on two lines,
/// so that it is never clipped.
pub fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>, String> {
    let width = root.dim_in_pixel().0.saturating_sub(16);
    let fits = |text: &str, size: u32| {
        root.estimate_text_size(text, &TextStyle::from(("sans-serif", size).into_font()))
            .is_ok_and(|(w, _)| w <= width)
    };
    let size = (TITLE_MIN_SIZE..=TITLE_SIZE)
        .rev()
        .find(|&size| fits(title, size))
        .unwrap_or(TITLE_MIN_SIZE);
    let mut body = root.clone();
    for line in title_lines(title, |t| fits(t, size)) {
        body = body.titled(&line, ("sans-serif", size)).or_text()?;
    }
    Ok(body)
}

// ---------------------------------------------------------------- colours

const OURS: RGBColor = RGBColor(31, 119, 180);
const THESIS: RGBColor = RGBColor(214, 95, 14);
pub const EXTRA: RGBColor = RGBColor(44, 160, 44);
const ACTUATOR: RGBColor = RGBColor(60, 60, 60);
const BLUE_BLOCK: RGBColor = RGBColor(40, 90, 220);
const RED_BLOCK: RGBColor = RGBColor(220, 50, 40);
pub const TARGET: RGBColor = RGBColor(0, 0, 0);
/// The reference rows' lines, in the manifest's order (`still`, the oracle
/// that knows the latency, the one that does not), greys: references, not
/// learners.
pub const REFERENCES: [RGBColor; 3] = [
    RGBColor(70, 70, 70),
    RGBColor(165, 165, 165),
    RGBColor(120, 120, 120),
];
/// Opacity of predicted bodies in the snapshots.
pub const TRANSLUCENT: f64 = 0.3;

/// A distinct colour for the k-th line of a family.
/// A position tick in metres, to 0.1 m: the ticks of a range around 0
/// land on −0.0 as often as on 0.0, and "-0.0" is noise.
pub fn metres_tick(v: &f64) -> String {
    let text = format!("{v:.1}");
    match text.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_owned(),
        _ => text,
    }
}

pub fn palette(k: usize) -> RGBColor {
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

pub fn body_colour(id: u32) -> RGBColor {
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
pub fn padded(lo: f64, hi: f64, pad: f64) -> Range<f64> {
    if lo.is_finite() && hi.is_finite() && lo <= hi {
        (lo - pad)..(hi + pad).max(lo + pad)
    } else {
        -1.0..1.0
    }
}

// ----------------------------------------------------------- error panels

/// One series of a panel: points with optional error bars.
pub struct Series {
    pub label: String,
    pub colour: RGBColor,
    /// (x, mean, std); std 0 draws no bar.
    pub points: Vec<(f64, f64, f64)>,
    pub bars: bool,
}

/// One series per `(label, points)`, in the palette's colours, with bars:
/// the several-learners figures' way of drawing their series.
pub fn coloured(series: impl IntoIterator<Item = (String, Vec<(f64, f64, f64)>)>) -> Vec<Series> {
    series
        .into_iter()
        .enumerate()
        .map(|(k, (label, points))| Series {
            label,
            colour: palette(k),
            points,
            bars: true,
        })
        .collect()
}

impl Series {
    fn tops(&self) -> impl Iterator<Item = f64> + '_ {
        self.points.iter().map(|&(_, m, s)| m + s)
    }
}

/// Points of `ours`, and of the thesis's values where it has them.
pub fn ours(label: &str, points: Vec<(f64, MeanStd)>) -> Series {
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

pub fn thesis(points: Vec<(f64, Ms)>) -> Option<Series> {
    (!points.is_empty()).then(|| Series {
        label: "thesis".to_owned(),
        colour: THESIS,
        points: points.into_iter().map(|(x, Ms(m, s))| (x, m, s)).collect(),
        bars: true,
    })
}

pub struct Panel {
    pub title: String,
    pub x_desc: String,
    pub y_desc: String,
    pub x_range: Range<f64>,
    /// Drawn at x + offset·k for the k-th series, so bars do not overlap.
    pub offset: f64,
    /// x is a count (training runs, messages, steps): labels without decimals.
    pub counts: bool,
    pub series: Vec<Series>,
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
pub struct Grid {
    pub title: String,
    pub columns: usize,
    pub panel_size: (u32, u32),
    pub panels: Vec<Panel>,
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
        let body = titled(root, &self.title)?;
        let rows = self.panels.len().div_ceil(self.columns.max(1)).max(1);
        let areas = body.split_evenly((rows, self.columns.max(1)));
        for (panel, area) in self.panels.iter().zip(&areas) {
            panel.draw(area)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_titles_break_near_the_middle_and_short_ones_stay_whole() {
        let fits = |t: &str| t.len() <= 30;
        assert_eq!(title_lines("a short title", fits), ["a short title"]);
        let lines = title_lines(
            "gate model, Move to Target: final block poses over the target",
            fits,
        );
        assert_eq!(
            lines,
            [
                "gate model, Move to Target:",
                "final block poses over the target"
            ]
        );
        assert_eq!(title_lines("unbreakable", |_| false), ["unbreakable"]);
    }

    #[test]
    fn a_title_wider_than_the_canvas_is_drawn_on_two_lines() {
        font().unwrap();
        let draw = |width: u32| {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (width, 200)).into_drawing_area();
                let body = titled(
                    &root,
                    "gate model, Move to Target, 5 repetitions per target: the block's final poses and the target",
                )
                .unwrap();
                assert!(body.dim_in_pixel().1 < 200);
                root.present().unwrap();
            }
            svg.matches("<text").count()
        };
        assert_eq!(draw(1400), 1);
        assert_eq!(draw(500), 2);
    }

    #[test]
    fn a_metre_tick_has_no_negative_zero() {
        assert_eq!(metres_tick(&-0.0), "0.0");
        assert_eq!(metres_tick(&-0.04), "0.0");
        assert_eq!(metres_tick(&-0.05000001), "-0.1");
        assert_eq!(metres_tick(&0.5), "0.5");
        assert_eq!(metres_tick(&-0.5), "-0.5");
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
}
