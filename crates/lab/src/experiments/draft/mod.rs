//! The thesis draft's push-task tables (draft §6.1.2, Tables 6.1 "Test1"
//! and 6.2 "Test2", chapter 6 of the thesis draft): per
//! model configuration the actuator's and the block's key-point score —
//! final difference, accumulated difference and mean difference — as the
//! mean over the test runs, ours beside the draft's.
//!
//! Also the key-point section that follows every push-task table.

use std::collections::BTreeMap;
use std::io::{self, Write};

use learner::interaction::SelectorKind;
use learner::keypoints::KeyPointScore;
use learner::{ACTUATOR_ID, BLUE_ID};
use serde::{Deserialize, Serialize};

use crate::report::layout::{field, Cell, Column, Kind, Printout, Table};
use crate::report::plural;
use drive::results::push_task::{CurveEntry, SelectionCount};
use drive::results::{PushReport, Setup};
use learner::registry::{ConfigFlag, ModelKind, ModelOptions};

/// (final dif, cumDif, mean dif) as printed in the draft (3 decimals).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DraftNumbers {
    pub final_dif: f64,
    pub cum_dif: f64,
    pub mean_dif: f64,
}

const fn n(final_dif: f64, cum_dif: f64, mean_dif: f64) -> DraftNumbers {
    DraftNumbers {
        final_dif,
        cum_dif,
        mean_dif,
    }
}

/// One row of the draft's tables and how we run it.
#[derive(Clone, Debug, PartialEq)]
pub struct DraftRow {
    /// The row's name in the draft.
    pub name: &'static str,
    pub model: ModelKind,
    pub options: ModelOptions,
    pub train_runs: usize,
    /// Table 6.1 (actuator).
    pub actuator: DraftNumbers,
    /// Table 6.2 (block).
    pub block: DraftNumbers,
}

/// The draft's rows, in its order, with its numbers (Tables 6.1 and 6.2).
///
/// Row names, as we read them (the draft defines none of the abbreviations;
/// docs/results.md, "The thesis draft's variants", gives the reasons):
/// * "Pairwise AC DT": the pairwise interaction model with Abstract
///   Collections and the decision-tree selector (draft §3.2, §4.2);
/// * "Gate HG HA": the gate model with hard-coded gate (bit 32) and
///   hard-coded actuator (bit 16), with the velocity features of the draft's
///   object states (§4.3.1, bit 1 USE_DYNS);
/// * "ITM η x": all AITM learning rates of the forward models x;
/// * "NoAV": no angular velocity feature; "NoDyns": no velocity features
///   (USE_DYNS off);
/// * "3 Train" / "10 Train": the number of training runs.
#[must_use]
pub fn rows() -> Vec<DraftRow> {
    let pairwise = ModelOptions {
        selector: SelectorKind::Tree,
        ..ModelOptions::default()
    };
    let hg_ha = |dyns: bool, eta: f64, no_av: bool| {
        let mut flags = vec![ConfigFlag::HardCodedGate, ConfigFlag::HardCodedActuator];
        if dyns {
            flags.insert(0, ConfigFlag::UseDyns);
        }
        ModelOptions {
            flags,
            eta,
            no_angular_velocity: no_av,
            ..ModelOptions::default()
        }
    };
    let row = |name, model, options, train_runs, actuator, block| DraftRow {
        name,
        model,
        options,
        train_runs,
        actuator,
        block,
    };
    use ModelKind::{Gate, Interaction};
    vec![
        row(
            "Pairwise AC DT 3 Train",
            Interaction,
            pairwise.clone(),
            3,
            n(0.001, 0.095, 0.001),
            n(0.209, 14.051, 0.094),
        ),
        row(
            "Pairwise AC DT 10 Train",
            Interaction,
            pairwise,
            10,
            n(0.053, 3.929, 0.026),
            n(0.142, 10.841, 0.073),
        ),
        row(
            "Gate HG HA 3 Train",
            Gate,
            hg_ha(true, 0.0, false),
            3,
            n(0.001, 0.128, 0.001),
            n(0.048, 3.061, 0.021),
        ),
        row(
            "Gate HG HA 10 Train ITM η 0.0",
            Gate,
            hg_ha(true, 0.0, false),
            10,
            n(0.001, 0.127, 0.001),
            n(0.052, 3.189, 0.021),
        ),
        row(
            "Gate HG HA 10 Train ITM η 0.1",
            Gate,
            hg_ha(true, 0.1, false),
            10,
            n(0.001, 0.122, 0.001),
            n(0.046, 2.968, 0.020),
        ),
        row(
            "Gate HG HA 10 Train ITM η 0.2",
            Gate,
            hg_ha(true, 0.2, false),
            10,
            n(0.001, 0.122, 0.001),
            n(0.061, 3.538, 0.024),
        ),
        row(
            "Gate HG HA 10 Train NoAV",
            Gate,
            hg_ha(true, 0.0, true),
            10,
            n(0.001, 0.135, 0.001),
            n(0.050, 2.859, 0.019),
        ),
        row(
            "Gate HG HA 10 Train NoDyns",
            Gate,
            hg_ha(false, 0.0, false),
            10,
            n(0.001, 0.130, 0.001),
            n(0.068, 4.670, 0.031),
        ),
    ]
}

/// Our result for one row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DraftRowResult {
    pub name: String,
    pub model: ModelKind,
    pub config: u32,
    pub eta: f64,
    pub selector: SelectorKind,
    pub no_angular_velocity: bool,
    pub train_runs: usize,
    /// Mean key-point scores over the test runs (and folds).
    pub actuator: KeyPointScore,
    pub block: KeyPointScore,
    /// The draft's numbers.
    pub draft_actuator: DraftNumbers,
    pub draft_block: DraftNumbers,
    /// The final thesis's errors of the same runs, for comparison.
    pub block_pos_err: f64,
    pub block_ori_err: f64,
    pub actuator_pos_err: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selection: Option<SelectionCount>,
}

impl DraftRowResult {
    /// Our numbers for `row` from its one-entry push report.
    #[must_use]
    pub fn of(row: &DraftRow, entry: &CurveEntry) -> Self {
        let get = |id| entry.keypoints.get(&id).copied().unwrap_or_default();
        Self {
            name: row.name.to_owned(),
            model: row.model,
            config: row.options.config_number(),
            eta: row.options.eta,
            selector: row.options.selector,
            no_angular_velocity: row.options.no_angular_velocity,
            train_runs: row.train_runs,
            actuator: get(ACTUATOR_ID),
            block: get(BLUE_ID),
            draft_actuator: row.actuator,
            draft_block: row.block,
            block_pos_err: entry.blue.block_pos_err.mean,
            block_ori_err: entry.blue.block_ori_err.mean,
            actuator_pos_err: entry.blue.actuator_pos_err.mean,
            selection: entry.selection,
        }
    }
}

/// `pushlearn experiment push-task --report draft`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DraftReport {
    #[serde(flatten)]
    pub setup: Setup,
    pub folds: usize,
    pub test_positions: Vec<f64>,
    pub rows: Vec<DraftRowResult>,
    /// The full push report of every row, in row order.
    pub reports: Vec<PushReport>,
}

/// Our score beside [the draft's], and both as CSV fields.
fn score_cell(ours: f64, draft: f64, width: usize, draft_width: usize) -> Cell {
    Cell::Composed {
        text: format!("{ours:>width$.3} [{draft:>draft_width$.3}]"),
        fields: vec![field(ours), field(draft)],
    }
}

/// Tables 6.1 and 6.2 in the draft's layout, ours then [the draft's].
///
/// # Errors
/// Writing to `out`.
pub fn tables(out: &mut impl Write, report: &DraftReport) -> io::Result<()> {
    printout(report).write_text(out)
}

/// The draft's tables, and the final thesis's errors of the same runs.
#[must_use]
pub fn printout(report: &DraftReport) -> Printout {
    let head = vec![
        format!(
            "Push task, thesis draft protocol: {} per row, {}, mode {}, seed {}",
            plural(report.test_positions.len(), "test run"),
            plural(report.folds, "fold"),
            report.setup.mode,
            report.setup.seed
        ),
        "key-point score (draft §6.1.2), mean over the test runs; ours, then [the draft's]"
            .to_owned(),
    ];
    let width = report
        .rows
        .iter()
        .map(|r| r.name.chars().count())
        .max()
        .unwrap_or(0)
        .max("Model configuration".len());
    let name_column = || Column::new("Model configuration", width, false, Kind::Text);
    let mut tables = Vec::new();
    for (name, title, part) in [
        ("table-6.1", "Table 6.1 (Test1)", "Actuator"),
        ("table-6.2", "Table 6.2 (Test2)", "Block"),
    ] {
        let score = |what: &str, width: usize| {
            let head = format!("{part} {what}");
            Column::new(
                &head,
                width,
                true,
                Kind::Composed(vec![head.clone(), format!("{head}, draft")]),
            )
        };
        let mut t = Table::new(
            name,
            title,
            vec![
                name_column(),
                score("final dif", 15),
                score("cumDif", 17),
                score("mean dif", 15),
            ],
        );
        for r in &report.rows {
            let (ours, draft) = if part == "Actuator" {
                (&r.actuator, &r.draft_actuator)
            } else {
                (&r.block, &r.draft_block)
            };
            t.rows.push(vec![
                Cell::Text(r.name.clone()),
                score_cell(ours.final_dif, draft.final_dif, 7, 0),
                score_cell(ours.cum_dif, draft.cum_dif, 8, 6),
                score_cell(ours.mean_dif, draft.mean_dif, 7, 0),
            ]);
        }
        tables.push(t);
    }
    let mut t = Table::new(
        "errors",
        "Same runs, final thesis errors (docs/spec/experiments.md §7.2) and AC selector agreement",
        vec![
            name_column(),
            Column::new("block pos [m]", 13, true, Kind::Number { decimals: 4 }),
            Column::new("block ori [rad]", 15, true, Kind::Number { decimals: 4 }),
            Column::new("actuator [m]", 12, true, Kind::Number { decimals: 4 }),
            selection_column(),
        ],
    );
    for r in &report.rows {
        t.rows.push(vec![
            Cell::Text(r.name.clone()),
            Cell::Number(r.block_pos_err),
            Cell::Number(r.block_ori_err),
            Cell::Number(r.actuator_pos_err),
            selection_cell(r.selection.as_ref()),
        ]);
    }
    tables.push(t);
    Printout {
        stem: "push-task-draft".to_owned(),
        head,
        tables,
        foot: Vec::new(),
    }
}

fn selection_column() -> Column {
    Column::new(
        "selector [%]",
        12,
        true,
        Kind::Composed(vec!["selector agreement [%]".to_owned()]),
    )
}

fn selection_cell(s: Option<&SelectionCount>) -> Cell {
    let accuracy = s.and_then(SelectionCount::accuracy);
    Cell::Composed {
        text: accuracy.map_or_else(|| "–".to_owned(), |a| format!("{:.1} %", 100.0 * a)),
        fields: vec![accuracy.map_or_else(String::new, |a| field(100.0 * a))],
    }
}

/// The key-point scores of a push-task report beside its position and
/// orientation errors, per N_train, and the AC selector's agreement where
/// the model has one.
#[must_use]
pub fn keypoint_table(report: &PushReport) -> Table {
    let score = |who: &str| {
        Column::new(
            who,
            26,
            true,
            Kind::Composed(
                ["final", "accumulated", "mean per prediction"]
                    .iter()
                    .map(|w| format!("{who} key-point score, {w}"))
                    .collect(),
            ),
        )
    };
    let mut t = Table::new(
        "keypoints",
        "Key-point score (thesis draft §6.1.2; mean over test runs: final / accumulated / mean per prediction)",
        vec![
            Column::new("N_train", 7, true, Kind::Text),
            score("actuator"),
            score("block 15"),
            Column::new("block pos [m]", 13, true, Kind::Number { decimals: 4 }),
            Column::new("block ori [rad]", 15, true, Kind::Number { decimals: 4 }),
            selection_column(),
        ],
    );
    for e in &report.results {
        let cell = |m: &BTreeMap<u32, KeyPointScore>, id| {
            m.get(&id).map_or_else(
                || Cell::Composed {
                    text: "–".to_owned(),
                    fields: vec![String::new(); 3],
                },
                |s| Cell::Composed {
                    text: format!("{:.3} / {:.3} / {:.4}", s.final_dif, s.cum_dif, s.mean_dif),
                    fields: vec![field(s.final_dif), field(s.cum_dif), field(s.mean_dif)],
                },
            )
        };
        t.rows.push(vec![
            Cell::Text(e.train_runs.to_string()),
            cell(&e.keypoints, ACTUATOR_ID),
            cell(&e.keypoints, BLUE_ID),
            Cell::Number(e.blue.block_pos_err.mean),
            Cell::Number(e.blue.block_ori_err.mean),
            selection_cell(e.selection.as_ref()),
        ]);
    }
    t
}

/// The thesis draft's tables.
pub struct DraftTables;

impl super::Experiment for DraftTables {
    type Report = DraftReport;

    fn setup(report: &DraftReport) -> &Setup {
        &report.setup
    }

    fn runs(report: &DraftReport) -> Vec<&drive::results::run_info::RunInfo> {
        report.reports.iter().map(|r| &r.run).collect()
    }

    fn without_timing(mut report: DraftReport) -> DraftReport {
        for row in &mut report.reports {
            row.run = std::mem::take(&mut row.run).without_timing();
        }
        report
    }

    /// Without the per-fold detail of each row's report.
    fn without_folds(mut report: DraftReport) -> DraftReport {
        report.reports = std::mem::take(&mut report.reports)
            .into_iter()
            .map(super::push_task::PushTask::without_folds)
            .collect();
        report
    }

    fn printout(report: &DraftReport) -> Result<Printout, drive::results::UnknownModel> {
        Ok(printout(report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_follow_the_draft() {
        let rows = rows();
        assert_eq!(rows.len(), 8);
        let names: Vec<&str> = rows.iter().map(|r| r.name).collect();
        assert_eq!(names[0], "Pairwise AC DT 3 Train");
        assert_eq!(names[7], "Gate HG HA 10 Train NoDyns");
        // Every row's options configure its model.
        for r in &rows {
            assert!(r.model.check(&r.options, 100).is_ok(), "{}", r.name);
        }
        // HG HA is bits 16 and 32; the base rows add USE_DYNS, NoDyns not.
        assert_eq!(rows[2].options.config_number(), 1 | 16 | 32);
        assert_eq!(rows[7].options.config_number(), 16 | 32);
        assert!(rows[6].options.no_angular_velocity);
        assert_eq!(
            rows[3..6].iter().map(|r| r.options.eta).collect::<Vec<_>>(),
            [0.0, 0.1, 0.2]
        );
        assert_eq!(rows[1].options.selector, SelectorKind::Tree);
        // The draft's numbers are consistent: mean ≈ cumDif / ~149
        // predictions, up to its 3-decimal rounding.
        for r in &rows {
            for d in [r.actuator, r.block] {
                assert!(
                    (d.cum_dif / 149.0 - d.mean_dif).abs() < 0.0035,
                    "{}",
                    r.name
                );
            }
        }
    }

    #[test]
    fn tables_print_both_columns() {
        let rows = rows();
        let result = |r: &DraftRow| DraftRowResult {
            name: r.name.into(),
            model: r.model,
            config: r.options.config_number(),
            eta: r.options.eta,
            selector: r.options.selector,
            no_angular_velocity: r.options.no_angular_velocity,
            train_runs: r.train_runs,
            actuator: KeyPointScore {
                final_dif: 0.002,
                cum_dif: 0.25,
                mean_dif: 0.0017,
                predictions: 150,
            },
            block: KeyPointScore::default(),
            draft_actuator: r.actuator,
            draft_block: r.block,
            block_pos_err: 0.01,
            block_ori_err: 0.02,
            actuator_pos_err: 0.0,
            selection: Some(SelectionCount {
                samples: 4,
                agreed: 3,
                unknown: 0,
            }),
        };
        let report = DraftReport {
            setup: Setup {
                experiment: "push-task".into(),
                model: "draft".into(),
                mode: "lockstep".into(),
                latency_max_steps: None,
                learner: None,
                seed: 1,
            },
            folds: 1,
            test_positions: vec![0.0; 20],
            rows: rows.iter().map(result).collect(),
            reports: Vec::new(),
        };
        let mut out = Vec::new();
        tables(&mut out, &report).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("Table 6.1 (Test1)") && text.contains("Table 6.2 (Test2)"));
        assert!(
            text.lines()
                .any(|l| l.starts_with("Pairwise AC DT 10 Train ") && l.contains("0.002 [0.053]")),
            "{text}"
        );
        assert!(text.contains("14.051"), "{text}");
        assert!(text.contains("75.0 %"), "{text}");
    }
}
