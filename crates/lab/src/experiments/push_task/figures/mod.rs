//! The push-task figures: learning curves, per-position errors and
//! snapshots of the test runs' ends.

mod curves;
mod positions;

use std::path::{Path, PathBuf};

use crate::report::plot::draw::{prepare, write};
use crate::report::plot::snapshots::{footprints, push_snapshots};
use crate::report::plot::PlotError;
use curves::curve_grid;
pub use curves::ReferenceLine;
use drive::results::PushReport;
use learner::registry::ModelKind;
use positions::positions_grid;

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
    write_curves(report, model, &[], dir, &mut written)?;
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

/// The learning-curve figures of `report` (the same names as [`push`]
/// writes) with the reference rows drawn beside them: the reproduction's
/// page, which runs the references, shows these.
///
/// # Errors
/// The directory cannot be created or a figure cannot be written.
pub fn curves_with_references(
    report: &PushReport,
    model: ModelKind,
    references: &[ReferenceLine<'_>],
    dir: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    prepare(dir)?;
    let mut written = Vec::new();
    write_curves(report, model, references, dir, &mut written)?;
    Ok(written)
}

fn write_curves(
    report: &PushReport,
    model: ModelKind,
    references: &[ReferenceLine<'_>],
    dir: &Path,
    written: &mut Vec<PathBuf>,
) -> Result<(), PlotError> {
    if report.results.len() < 2 {
        return Ok(());
    }
    let stem = stem(report, model);
    write(
        &curve_grid(model, &report.results, false, references),
        dir,
        &format!("{stem}-curve"),
        written,
    )?;
    if report.variant != "two-objects" {
        write(
            &curve_grid(model, &report.results, true, references),
            dir,
            &format!("{stem}-curve-interacting"),
            written,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use learner::eval::{BlockError, RunErrors};
    use learner::{ModelStats, ObjectState, Poses, BLUE_ID};

    use super::*;
    use crate::report::plot::test_support::{count, is_png, scratch, thick_polylines};
    use drive::results::push_task::{summarise, EndPoses, PushJobResult};
    use drive::results::run_info::{Counters, RunInfo};
    use drive::results::Setup;

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
            transfer: None,
            folds,
            train_runs: train_runs.to_vec(),
            results: summarise(&xs, &[BLUE_ID], train_runs, &jobs).unwrap(),
            run: RunInfo::default(),
        }
    }

    #[test]
    fn curves_with_references_add_their_lines_and_only_the_curves() {
        let dir = scratch("push-references");
        let report = push_report(&[1, 3, 30], 2);
        let reference = push_report(&[1, 3, 30], 2);
        let lines = [
            ReferenceLine {
                label: "still: nothing moves",
                results: &reference.results,
                actuator: false,
            },
            ReferenceLine {
                label: "oracle: true parameters, latency unknown",
                results: &reference.results[..2],
                actuator: true,
            },
        ];
        let written = curves_with_references(&report, ModelKind::Gate, &lines, &dir).unwrap();
        // The two curves (PNG and SVG each), nothing else.
        assert_eq!(written.len(), 4);
        let text = std::fs::read_to_string(dir.join("push-task-gate-random-curve.svg")).unwrap();
        assert!(text.contains("still: nothing moves"));
        assert!(text.contains("latency unknown"));
        // Their lines have no bars: still 3 panels × (3 of ours + 3 thesis).
        assert_eq!(
            count(&dir.join("push-task-gate-random-curve.svg"), "circle"),
            18
        );
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
        // Every figure says how many folds it shows; the snapshots have
        // metre axes, a legend, and each run's start as outlines (actuator
        // and block: stroke width 2, as the legend's samples of the curves).
        let text = |stem: &str| std::fs::read_to_string(svg(stem)).unwrap();
        assert!(text("curve").contains("2 folds"));
        assert!(text("positions-n3").contains("over 2 folds"));
        assert!(text("positions-n1").contains("1 training run:"));
        let snapshots = text("snapshots-n1");
        for label in [
            "x [m]",
            "y [m]",
            "start",
            "actual end",
            "predicted end",
            "fold 1 of 2",
        ] {
            assert!(snapshots.contains(label), "no {label:?} in the snapshots");
        }
        assert_eq!(thick_polylines(&snapshots).len(), 21 * 2);
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
}
