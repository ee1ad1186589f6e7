//! The constant-feedback experiment's terminal tables (§7, qualitative).

use std::io::{self, Write};

use crate::report::layout::{Cell, Column, Kind, Printout, Table};
use crate::report::table::{learner_title, run_info, whole};
use drive::results::FeedbackReport;
use learner::registry::ModelKind;
use learner::BLUE_ID;

/// The constant-feedback report: per run, the error of each chained
/// prediction (qualitative, `docs/spec/experiments.md` §3.4).
///
/// # Errors
/// Writing to `out`.
pub fn feedback(out: &mut impl Write, report: &FeedbackReport, model: ModelKind) -> io::Result<()> {
    feedback_printout(report, model).write_text(out)
}

/// The constant-feedback report's tables, one per run.
#[must_use]
pub fn feedback_printout(report: &FeedbackReport, model: ModelKind) -> Printout {
    let tables = report
        .runs
        .iter()
        .enumerate()
        .map(|(k, run)| {
            let mut t = Table::new(
                format!("run-{}", k + 1),
                format!(
                    "run from x0 = {:.3}: error of the prediction for each message",
                    run.x0
                ),
                vec![
                    Column::new("message", 7, true, Kind::Text),
                    Column::new("block [m]", 12, true, Kind::Number { decimals: 4 }),
                    Column::new("block [rad]", 12, true, Kind::Number { decimals: 4 }),
                    Column::new("actuator [m]", 12, true, Kind::Number { decimals: 4 }),
                ],
            );
            for (i, e) in run.errors.iter().enumerate() {
                let block = e.blocks.get(&BLUE_ID);
                t.rows.push(vec![
                    whole(i + 2),
                    Cell::Number(block.map_or(f64::NAN, |b| b.pos)),
                    Cell::Number(block.map_or(f64::NAN, |b| b.ori)),
                    Cell::Number(e.actuator),
                ]);
            }
            t
        })
        .collect();
    Printout {
        stem: format!("push-task-{}-constant-feedback", report.setup.model),
        head: vec![format!(
            "Push task with constant feedback, {}, {} Hz, mode {} (qualitative; the thesis shows images, §7)",
            learner_title(&report.setup, model),
            report.publish_rate_hz,
            report.setup.mode
        )],
        tables,
        foot: run_info(&report.run),
    }
}
