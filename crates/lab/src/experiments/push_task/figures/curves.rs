//! Learning curves: errors over N_train beside the thesis's
//! (`docs/spec/reference-results.md` §3.2, §3.4).

use learner::eval::MeanStd;

use crate::report::plot::draw::{ours, thesis, Grid, Panel, Series, EXTRA, REFERENCES};
use crate::report::plural;
use crate::report::reference::{self, Ms};
use drive::results::push_task::CurveEntry;
use learner::registry::{ModelKind, ThesisModel};

/// A reference row drawn beside a learning curve: its label and its
/// errors at the curve's numbers of training runs.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceLine<'a> {
    pub label: &'a str,
    pub results: &'a [CurveEntry],
    /// Drawn in the actuator's panel too: `still`'s actuator, which never
    /// moves, is off that panel's scale.
    pub actuator: bool,
}

/// The curves of `results`, beside the thesis's and the `references`'
/// errors (`docs/models.md` "Reference rows"), which learn nothing.
pub(super) fn curve_grid(
    model: ModelKind,
    results: &[CurveEntry],
    interacting: bool,
    references: &[ReferenceLine<'_>],
) -> Grid {
    let source = match model.family() {
        ThesisModel::Gate => "§3.4",
        ThesisModel::Interaction => "§3.2",
    };
    let n_max = results.iter().map(|e| e.train_runs).max().unwrap_or(1) as f64;
    let folds = results.iter().map(|e| e.folds).max().unwrap_or(0);
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
    let reference_lines = |get: fn(&CurveEntry) -> MeanStd, actuator: bool| -> Vec<Series> {
        references
            .iter()
            .zip(REFERENCES.iter().cycle())
            .filter(|(r, _)| r.actuator || !actuator)
            .map(|(r, &colour)| Series {
                label: r.label.to_owned(),
                colour,
                points: results
                    .iter()
                    .filter_map(|e| {
                        let at = r.results.iter().find(|f| f.train_runs == e.train_runs)?;
                        Some((e.train_runs as f64, get(at).mean, 0.0))
                    })
                    .collect(),
                bars: false,
            })
            .collect()
    };
    let panel = |title: &str, y: &str, mut series: Vec<Series>, reference: Option<Series>| {
        series.extend(reference);
        Panel {
            title: title.to_owned(),
            x_desc: "training runs (N_train)".to_owned(),
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
                {
                    let get = |e: &CurveEntry| e.blue.interacting.block_pos_err;
                    let mut series = vec![mine(get)];
                    series.extend(reference_lines(get, false));
                    series
                },
                refs(|r| r.pos_interacting),
            ),
            panel(
                "block orientation",
                "error [rad]",
                {
                    let get = |e: &CurveEntry| e.blue.interacting.block_ori_err;
                    let mut series = vec![mine(get)];
                    series.extend(reference_lines(get, false));
                    series
                },
                refs(|r| r.ori_interacting),
            ),
            panel(
                "actuator position",
                "error [m]",
                {
                    let get = |e: &CurveEntry| e.blue.interacting.actuator_pos_err;
                    let mut series = vec![mine(get), quirk];
                    series.extend(reference_lines(get, true));
                    series
                },
                refs(|r| r.actuator_interacting_quirk),
            ),
        ]
    } else {
        vec![
            panel(
                "block position",
                "error [m]",
                {
                    let get = |e: &CurveEntry| e.blue.block_pos_err;
                    let mut series = vec![mine(get)];
                    series.extend(reference_lines(get, false));
                    series
                },
                refs(|r| r.pos),
            ),
            panel(
                "block orientation",
                "error [rad]",
                {
                    let get = |e: &CurveEntry| e.blue.block_ori_err;
                    let mut series = vec![mine(get)];
                    series.extend(reference_lines(get, false));
                    series
                },
                refs(|r| r.ori),
            ),
            panel(
                "actuator position",
                "error [m]",
                {
                    let get = |e: &CurveEntry| e.blue.actuator_pos_err;
                    let mut series = vec![mine(get)];
                    series.extend(reference_lines(get, true));
                    series
                },
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
            "{model} model, learning curve over {which}, {}: mean ± mean per-position std (thesis {source})",
            plural(folds, "fold")
        ),
        columns: 3,
        panel_size: (420, 340),
        panels,
    }
}
