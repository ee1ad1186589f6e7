//! Move to Target's terminal table beside the thesis's (§8).

use std::io::{self, Write};

use crate::report::layout::{field, Cell, Column, Kind, Printout, Table};
use crate::report::plural;
use crate::report::reference::{self};
use crate::report::table::{composed, learner_title, run_info};
use drive::results::move_to_target::{REPETITIONS, TARGETS};
use drive::results::MttReport;
use learner::eval::GOAL_TOLERANCE;
use learner::registry::{ModelKind, ThesisModel};

/// The Move-to-Target report in the layout of the thesis's §8 tables.
///
/// # Errors
/// Writing to `out`.
pub fn move_to_target(
    out: &mut impl Write,
    report: &MttReport,
    model: ModelKind,
) -> io::Result<()> {
    move_to_target_printout(report, model).write_text(out)
}

/// The Move-to-Target report's table.
#[must_use]
pub fn move_to_target_printout(report: &MttReport, model: ModelKind) -> Printout {
    let source = match model.family() {
        ThesisModel::Gate => "§8.2",
        ThesisModel::Interaction => "§8.1",
    };
    let head = vec![format!(
        "Move to Target, {}, {}, at most {} steps, mode {}, seed {}",
        learner_title(&report.setup, model),
        plural(report.repetitions, "repetition"),
        report.max_steps,
        report.setup.mode,
        report.setup.seed
    )];
    let mut t = Table::new(
        "targets",
        format!(
            "Reached: the block within {GOAL_TOLERANCE} of the target in (x, y, wrapped θ), \
             judged from the world; Pos/Ori: mean remaining error of the runs that failed; \
             # steps: mean over all runs (failures count {}), in brackets over the successful \
             ones; Final: mean remaining error of every run; [thesis {source}]",
            report.max_steps
        ),
        vec![
            composed(
                "Target (x, y, θ)",
                28,
                &["target x [m]", "target y [m]", "target θ [rad]"],
            ),
            composed("Reached", 12, &["reached", "runs", "thesis reached"]),
            composed(
                "Pos [m]",
                16,
                &[
                    "pos error of failed runs [m]",
                    "thesis pos error of failed runs [m]",
                ],
            ),
            composed(
                "Ori [rad]",
                16,
                &[
                    "ori error of failed runs [rad]",
                    "thesis ori error of failed runs [rad]",
                ],
            ),
            composed(
                "# steps",
                36,
                &[
                    "steps, all runs",
                    "steps, successful runs",
                    "thesis steps, all runs",
                    "thesis steps, successful runs",
                ],
            ),
            composed(
                "Final pos / ori",
                16,
                &["pos error of all runs [m]", "ori error of all runs [rad]"],
            ),
        ],
    );
    let mut every = Table::new(
        "runs",
        "Every test run: whether the world found the block at the target, the actions \
         sent, and the block's final distance and angle to the target"
            .to_owned(),
        vec![
            Column::new("Target", 6, true, Kind::Number { decimals: 0 }),
            Column::new("Run", 4, true, Kind::Number { decimals: 0 }),
            Column::new("Reached", 8, false, Kind::Text),
            Column::new("Steps", 6, true, Kind::Number { decimals: 0 }),
            Column::new("Pos [m]", 9, true, Kind::Number { decimals: 4 }),
            Column::new("Ori [rad]", 9, true, Kind::Number { decimals: 4 }),
        ],
    );
    for entry in &report.targets {
        let s = &entry.summary;
        let [x, y, theta] = entry.target;
        let r = TARGETS
            .iter()
            .position(|t| t.x == x && t.y == y && t.theta == theta)
            .filter(|_| report.repetitions == REPETITIONS)
            .and_then(|i| reference::move_to_target(model).get(i));
        let opt = |v: Option<f64>, digits: usize| {
            v.map_or_else(|| "–".to_owned(), |v| format!("{v:.digits$}"))
        };
        let steps = |all: f64, reached: Option<f64>, some_failed: bool| {
            if some_failed {
                format!("{all:.1} ({})", opt(reached, 1))
            } else {
                format!("{all:.1}")
            }
        };
        let ours_steps = steps(s.steps, s.steps_reached, s.reached < s.runs);
        let (r_reached, r_pos, r_ori, r_steps) = r.map_or_else(
            || (String::new(), String::new(), String::new(), String::new()),
            |r| {
                (
                    format!("[{}]", r.reached),
                    format!("[{}]", opt(r.pos, 2)),
                    format!("[{}]", opt(r.ori, 3)),
                    format!(
                        "[{}]",
                        steps(r.steps, r.steps_reached, r.reached < report.repetitions)
                    ),
                )
            },
        );
        let some = |v: Option<f64>| v.map_or_else(String::new, field);
        let thesis = |f: &dyn Fn(&reference::MttRef) -> String| r.map_or_else(String::new, f);
        t.rows.push(vec![
            Cell::Composed {
                text: format!("({x}, {y}, {theta:.4})"),
                fields: vec![field(x), field(y), field(theta)],
            },
            Cell::Composed {
                text: format!("{}/{} {r_reached}", s.reached, s.runs),
                fields: vec![
                    s.reached.to_string(),
                    s.runs.to_string(),
                    thesis(&|r| r.reached.to_string()),
                ],
            },
            Cell::Composed {
                text: format!("{} {r_pos}", opt(s.pos_err_failed, 3)),
                fields: vec![some(s.pos_err_failed), thesis(&|r| some(r.pos))],
            },
            Cell::Composed {
                text: format!("{} {r_ori}", opt(s.ori_err_failed, 3)),
                fields: vec![some(s.ori_err_failed), thesis(&|r| some(r.ori))],
            },
            Cell::Composed {
                text: format!("{ours_steps} {r_steps}"),
                fields: vec![
                    field(s.steps),
                    some(s.steps_reached),
                    thesis(&|r| field(r.steps)),
                    thesis(&|r| some(r.steps_reached)),
                ],
            },
            Cell::Composed {
                text: format!("{} / {}", opt(s.pos_err_all, 3), opt(s.ori_err_all, 3)),
                fields: vec![some(s.pos_err_all), some(s.ori_err_all)],
            },
        ]);
    }
    for (k, entry) in report.targets.iter().enumerate() {
        for (repetition, run) in entry.runs.iter().enumerate() {
            every.rows.push(vec![
                Cell::Number((k + 1) as f64),
                Cell::Number((repetition + 1) as f64),
                Cell::Text(if run.reached { "yes" } else { "no" }.to_owned()),
                Cell::Number(run.steps as f64),
                Cell::Number(run.pos_err),
                Cell::Number(run.ori_err),
            ]);
        }
    }
    Printout {
        stem: format!("move-to-target-{}", report.setup.model),
        head,
        tables: vec![t, every],
        foot: run_info(&report.run),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drive::results::test_support::mtt_report;

    #[test]
    fn move_to_target_table_shows_no_reference_for_one_repetition() {
        let report = mtt_report();
        let mut text = Vec::new();
        move_to_target(&mut text, &report, ModelKind::Interaction).unwrap();
        let text = String::from_utf8(text).unwrap();
        assert!(text.contains("0/1"), "{text}");
        assert!(text.contains("3000.0 (–)"), "{text}");
        // One repetition is not the thesis's protocol: no reference shown.
        assert!(!text.contains("2689.2"), "{text}");
    }
}
