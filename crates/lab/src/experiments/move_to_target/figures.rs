//! The Move-to-Target figures (`docs/spec/reference-results.md` §8).

use std::path::{Path, PathBuf};

use learner::{ObjectState, BLUE_ID};

use crate::report::plot::draw::{palette, prepare, write, Grid, Panel, Series, TARGET};
use crate::report::plot::snapshots::{
    footprints, outline, Body, LegendEntry, Look, Snapshot, SnapshotGrid,
};
use crate::report::plot::PlotError;
use crate::report::plural;
use drive::results::MttReport;
use drive::scene::RATE_HZ;
use learner::registry::ModelKind;

/// The figures of a Move-to-Target report: the block's errors to the target
/// over the steps, one line per run and a row per target; and the final
/// block poses (one colour per run) under the target pose (an outline on
/// top, so that runs ending on it do not hide it).
///
/// # Errors
/// As [`figures`](crate::experiments::push_task::figures).
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
                x_desc: format!("step (message at {RATE_HZ} Hz)"),
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
                "{model} model, Move to Target, {} per target: the block's error to the target over the steps",
                plural(report.repetitions, "repetition")
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
            let mut bodies: Vec<Body> = target
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
                    look: Look::Filled(0.6),
                })
                .collect();
            bodies.push(Body {
                outline: outline(&block_shape, ObjectState::new(x, y, theta)),
                colour: TARGET,
                look: Look::Outline,
            });
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
    let mut legend = vec![LegendEntry {
        label: "target".to_owned(),
        colour: TARGET,
        look: Look::Outline,
    }];
    legend.extend((0..report.repetitions).map(|k| LegendEntry {
        label: format!("run {} final pose", k + 1),
        colour: palette(k),
        look: Look::Filled(0.6),
    }));
    write(
        &SnapshotGrid {
            title: format!(
                "{model} model, Move to Target, {} per target: the block's final poses and the target",
                plural(report.repetitions, "repetition")
            ),
            columns: report.targets.len().clamp(1, 4),
            side: 260,
            snapshots,
            legend,
        },
        dir,
        &format!("{stem}-final"),
        &mut written,
    )?;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::test_support::{count, is_png, scratch, thick_polylines};
    use drive::results::move_to_target::{ErrorTrace, MttRun, TargetSummary};
    use drive::results::run_info::RunInfo;
    use drive::results::{Setup, TargetEntry};

    fn mtt_report(runs_per_target: usize) -> MttReport {
        let run = |k: usize| MttRun {
            reached: k.is_multiple_of(2),
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
            training_starts: Vec::new(),
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
            // Each run's final block, then the target's outline on top of
            // them, per target.
            assert_eq!(count(&final_svg, "polygon"), 2 * runs);
            let text = std::fs::read_to_string(&final_svg).unwrap();
            let outlines = thick_polylines(&text);
            assert_eq!(outlines.len(), 2);
            let last_block = text.rfind("<polygon").unwrap();
            let last_target = text.rfind("stroke-width=\"2\"").unwrap();
            assert!(
                last_target > last_block,
                "the target is drawn under a block"
            );
            for label in [
                "x [m]",
                "y [m]",
                "target",
                "run 1 final pose",
                "repetitions per target",
            ] {
                assert!(text.contains(label), "no {label:?} in the final poses");
            }
            count(&dir.join("move-to-target-gate-errors.svg"), "polyline")
        };
        // One more run adds, in each of the 2 × 2 panels, its line and its
        // legend entry.
        assert_eq!(polylines(4) - polylines(3), 4 * 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
