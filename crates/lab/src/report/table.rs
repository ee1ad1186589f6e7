//! The pieces every experiment's terminal tables are made of, in the
//! thesis's layout: every value of ours is followed by the thesis's value in
//! brackets where the thesis has one (`[…]`, source section in the table's
//! title; `reference` reads the numbers from `crates/lab/data/reference.toml`).
//! The tables themselves live with their experiments (`crate::experiments`).

use super::layout::{Cell, Column, Kind};
use super::plural;
use drive::results::run_info::RunInfo;
use drive::results::Setup;
use learner::registry::ModelKind;

/// Ours ± spread beside [the thesis's]: 33 characters.
#[must_use]
pub fn error_column(head: &str) -> Column {
    Column::new(head, 33, false, Kind::Error { thesis: true })
}

/// Ours ± spread alone.
#[must_use]
pub fn own_error_column(head: &str) -> Column {
    Column::new(head, 15, false, Kind::Error { thesis: false })
}

/// A count over folds beside [the thesis's]: 34 characters.
#[must_use]
pub fn count_column(head: &str) -> Column {
    Column::new(head, 34, false, Kind::Count { thesis: true })
}

#[must_use]
pub fn own_count_column(head: &str) -> Column {
    Column::new(head, 16, false, Kind::Count { thesis: false })
}

/// A column of composed cells with these CSV fields.
#[must_use]
pub fn composed(head: &str, width: usize, fields: &[&str]) -> Column {
    Column::new(
        head,
        width,
        false,
        Kind::Composed(fields.iter().map(|&f| f.to_owned()).collect()),
    )
}

#[must_use]
pub fn n_train_column() -> Column {
    Column::new("N_train", 7, true, Kind::Text)
}

#[must_use]
pub fn whole(n: usize) -> Cell {
    Cell::Text(n.to_string())
}

/// "gate model", or for an external learner its name, version and the
/// built-in model whose thesis values stand beside it.
#[must_use]
pub fn learner_title(setup: &Setup, reference: ModelKind) -> String {
    match &setup.learner {
        None => format!("{} model", setup.model),
        Some(record) => format!(
            "learner '{}' {} ({}; thesis values: the {} model's)",
            setup.model,
            record.version,
            record.source,
            reference.family()
        ),
    }
}

/// The footer every experiment prints: messages, the 2/f requirement,
/// corrections.
#[must_use]
pub fn run_info(run: &RunInfo) -> Vec<String> {
    let mut lines = vec![String::new()];
    lines.push(match &run.timing {
        Some(t) => format!(
            "{} in {:.1} s on {}; handling {:.3} ms mean, p50 {:.1} µs, \
             p99 {:.1} µs, {:.3} ms max; {} ({:.4} %) over the {:.0} ms budget \
             [thesis: well under 0.1 %]",
            plural(run.messages as usize, "message"),
            t.wall_seconds,
            plural(t.workers, "worker"),
            t.mean_handling_ms,
            t.p50_handling_us,
            t.p99_handling_us,
            t.max_handling_ms,
            t.too_slow,
            100.0 * t.too_slow_fraction,
            run.budget_seconds * 1e3
        ),
        None => format!(
            "{}; handling times not in this document (it is kept free of \
             machine-dependent numbers; `pushlearn reproduce` writes them to docs/results/timing.md)",
            plural(run.messages as usize, "message")
        ),
    });
    lines.push(format!(
        "{} (SetPose), {} after resets, {}",
        plural(run.reset_errors as usize, "start-position correction"),
        plural(run.ignored as usize, "dropped message"),
        plural(run.parse_errors as usize, "unparseable state")
    ));
    lines
}
