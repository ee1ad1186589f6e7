//! Terminal tables in the thesis's layout: every value of ours is followed by
//! the thesis's value in brackets where the thesis has one (`[…]`, source
//! section in the table's title; `reference.rs` holds the numbers).

use std::io::{self, Write};

use learner::eval::GOAL_TOLERANCE;
use learner::{MapName, BLUE_ID};

use super::layout::{field, text, Cell, Column, Kind, Printout, Table};
use super::plural;
use super::reference::{self, Ms};
use drive::results::move_to_target::{REPETITIONS, TARGETS};
use drive::results::nodes::{MapSummary, NodeSummary};
use drive::results::push_task::{BlockCurve, CurveEntry};
use drive::results::run_info::RunInfo;
use drive::results::{FeedbackReport, MttReport, PushReport};
use learner::registry::ModelKind;

/// Ours ± spread beside [the thesis's]: 33 characters.
fn error_column(head: &str) -> Column {
    Column::new(head, 33, false, Kind::Error { thesis: true })
}

/// Ours ± spread alone.
fn own_error_column(head: &str) -> Column {
    Column::new(head, 15, false, Kind::Error { thesis: false })
}

/// A count over folds beside [the thesis's]: 34 characters.
fn count_column(head: &str) -> Column {
    Column::new(head, 34, false, Kind::Count { thesis: true })
}

fn own_count_column(head: &str) -> Column {
    Column::new(head, 16, false, Kind::Count { thesis: false })
}

/// A column of composed cells with these CSV fields.
fn composed(head: &str, width: usize, fields: &[&str]) -> Column {
    Column::new(
        head,
        width,
        false,
        Kind::Composed(fields.iter().map(|&f| f.to_owned()).collect()),
    )
}

fn n_train_column() -> Column {
    Column::new("N_train", 7, true, Kind::Text)
}

fn whole(n: usize) -> Cell {
    Cell::Text(n.to_string())
}

/// "gate model", or for an external learner its name, version and the
/// built-in model whose thesis values stand beside it.
fn learner_title(setup: &drive::results::Setup, reference: ModelKind) -> String {
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

/// The terminal report of a push-task experiment.
///
/// # Errors
/// Writing to `out`.
pub fn push(out: &mut impl Write, report: &PushReport, model: ModelKind) -> io::Result<()> {
    push_printout(report, model).write_text(out)
}

/// The push-task report's tables (without the key-point section, which
/// [`crate::report::draft::keypoint_table`] adds).
#[must_use]
pub fn push_printout(report: &PushReport, model: ModelKind) -> Printout {
    // The thesis pushed only its own blocks: its values do not apply to
    // the new-object experiments.
    let (experiment, thesis) = match &report.transfer {
        Some(t) => (format!("new objects, {}", t.label()), false),
        None => (report.variant.clone(), true),
    };
    let head = vec![
        format!(
            "Push task ({experiment}), {}, {}, mode {}, seed {}",
            learner_title(&report.setup, model),
            plural(report.folds, "fold"),
            report.setup.mode,
            report.setup.seed
        ),
        "errors after 150 chained predictions; ours, then [the thesis's] where it has the value"
            .to_owned(),
    ];
    let mut tables = match report.variant.as_str() {
        "fixed-three" => report.results.iter().map(|e| positions(e, model)).collect(),
        "two-objects" => report.results.iter().map(two_objects).collect(),
        _ => curve(&report.results, model, thesis),
    };
    tables.push(nodes(&report.results, model));
    Printout {
        stem: match &report.transfer {
            Some(t) => format!("push-task-{}-{}", report.setup.model, t.slug()),
            None => format!("push-task-{}-{}", report.setup.model, report.variant),
        },
        head,
        tables,
        foot: run_info(&report.run),
    }
}

fn curve(results: &[CurveEntry], model: ModelKind, thesis: bool) -> Vec<Table> {
    let source = match model {
        ModelKind::Gate | ModelKind::GatePlus => "§3.4",
        ModelKind::Interaction => "§3.2",
    };
    let mut all = Table::new(
        "learning-curve",
        format!(
            "Learning curve, all 21 test positions: mean of per-position means ± mean of per-position stds [{source}]"
        ),
        vec![
            n_train_column(),
            error_column("block position [m]"),
            error_column("block orientation [rad]"),
            error_column("actuator position [m]"),
        ],
    );
    for e in results {
        let r = reference::curve(model, e.train_runs).filter(|_| thesis);
        let f = e.folds;
        all.rows.push(vec![
            whole(e.train_runs),
            Cell::spread(e.blue.block_pos_err, f, r.map(|r| r.pos)),
            Cell::spread(e.blue.block_ori_err, f, r.map(|r| r.ori)),
            Cell::spread(e.blue.actuator_pos_err, f, r.map(|r| r.actuator)),
        ]);
    }
    let mut interacting = Table::new(
        "learning-curve-interacting",
        format!(
            "The 15 interacting test positions (−0.245 … 0.245) [{source}]; last column: the thesis \
             script's actuator value, mean of (mean + std) / 2 (docs/spec/experiments.md §7.4)"
        ),
        vec![
            n_train_column(),
            error_column("block position [m]"),
            error_column("block orientation [rad]"),
            own_error_column("actuator [m]"),
            Column::new(
                "actuator, script's value [m]",
                24,
                false,
                Kind::Composed(vec![
                    "actuator, script's value [m]".into(),
                    "actuator, script's value, thesis [m]".into(),
                ]),
            ),
        ],
    );
    for e in results {
        let r = reference::curve(model, e.train_runs).filter(|_| thesis);
        let i = &e.blue.interacting;
        let f = e.folds;
        interacting.rows.push(vec![
            whole(e.train_runs),
            Cell::spread(i.block_pos_err, f, r.map(|r| r.pos_interacting)),
            Cell::spread(i.block_ori_err, f, r.map(|r| r.ori_interacting)),
            Cell::spread(i.actuator_pos_err, f, None),
            Cell::Composed {
                text: format!(
                    "{:<6.4} {}",
                    i.actuator_pos_err_script_quirk,
                    r.map_or_else(String::new, |r| format!(
                        "[{:.4}]",
                        r.actuator_interacting_quirk.0
                    ))
                ),
                fields: vec![
                    field(i.actuator_pos_err_script_quirk),
                    r.map_or_else(String::new, |r| field(r.actuator_interacting_quirk.0)),
                ],
            },
        ]);
    }
    vec![all, interacting]
}

fn positions(entry: &CurveEntry, model: ModelKind) -> Table {
    let (source, table) = match model {
        ModelKind::Gate | ModelKind::GatePlus => ("§5.3", reference::fixed_three(model)),
        ModelKind::Interaction => ("§5.2", reference::fixed_three(model)),
    };
    // The thesis's table is for its three selected runs only.
    let table = (entry.train_runs == 3).then_some(table);
    let f = entry.folds;
    let mut t = Table::new(
        format!("positions-n{}", entry.train_runs),
        format!(
            "{}, per test position: mean ± population std over {} [{source}]",
            plural(entry.train_runs, "selected training run"),
            plural(f, "fold")
        ),
        vec![
            Column::new("#", 3, true, Kind::Text),
            Column::new("x0 [m]", 7, true, Kind::Number { decimals: 3 }),
            error_column("position error [m]"),
            error_column("orientation error [rad]"),
            own_error_column("actuator [m]"),
        ],
    );
    for (i, p) in entry.blue.per_position.iter().enumerate() {
        let r = table.and_then(|t| t.get(i));
        t.rows.push(vec![
            whole(i + 1),
            Cell::Number(p.x0),
            Cell::spread(p.block_pos_err, f, r.map(|r| r.pos)),
            Cell::spread(p.block_ori_err, f, r.map(|r| r.ori)),
            Cell::spread(p.actuator_pos_err, f, None),
        ]);
    }
    t.footer.push(summary_line(&entry.blue, f));
    t
}

fn summary_line(blue: &BlockCurve, folds: usize) -> String {
    let ms = |m| {
        text(
            &Cell::spread(m, folds, None),
            &Kind::Error { thesis: false },
        )
    };
    format!(
        "  over all positions: position {}, orientation {}, actuator {}",
        ms(blue.block_pos_err),
        ms(blue.block_ori_err),
        ms(blue.actuator_pos_err)
    )
}

fn two_objects(entry: &CurveEntry) -> Table {
    let table = reference::two_objects(entry.train_runs);
    let source = match entry.train_runs {
        6 => "§6.1",
        7 => "§6.2",
        _ => "no thesis table for this N_train",
    };
    let f = entry.folds;
    let mut t = Table::new(
        format!("two-objects-n{}", entry.train_runs),
        format!(
            "Two objects, {}, per test position: mean ± population std over {} [{source}]",
            plural(entry.train_runs, "training run"),
            plural(f, "fold")
        ),
        vec![
            Column::new("#", 3, true, Kind::Text),
            Column::new("x0 [m]", 7, true, Kind::Number { decimals: 2 }),
            error_column("red position [m]"),
            error_column("red orientation [rad]"),
            error_column("blue position [m]"),
            error_column("blue orientation [rad]"),
        ],
    );
    let red = entry.red.as_ref();
    for (i, blue) in entry.blue.per_position.iter().enumerate() {
        let r = table.and_then(|t| t.get(i));
        let red_at = red.and_then(|c| c.per_position.get(i));
        let red_cell =
            |get: fn(&drive::results::push_task::PositionSummary) -> learner::eval::MeanStd,
             thesis: Option<Ms>| Cell::Spread {
                ours: red_at.map(get),
                folds: f,
                thesis,
            };
        t.rows.push(vec![
            whole(i + 1),
            Cell::Number(blue.x0),
            red_cell(|p| p.block_pos_err, r.map(|r| r.red_pos)),
            red_cell(|p| p.block_ori_err, r.map(|r| r.red_ori)),
            Cell::spread(blue.block_pos_err, f, r.map(|r| r.blue_pos)),
            Cell::spread(blue.block_ori_err, f, r.map(|r| r.blue_ori)),
        ]);
    }
    t.footer.push(summary_line(&entry.blue, f));
    t
}

fn nodes(results: &[CurveEntry], model: ModelKind) -> Table {
    let built_in = results
        .iter()
        .any(|e| e.nodes.map(&MapName::Gate).is_some() || e.nodes.map(&MapName::Acs).is_some());
    if !built_in {
        return own_nodes(results);
    }
    let get = |n: &NodeSummary, name: &MapName, f: fn(&MapSummary) -> learner::eval::MeanStd| {
        n.map(name).map(f)
    };
    let count = |ours, folds, thesis| Cell::Spread {
        ours,
        folds,
        thesis,
    };
    match model {
        ModelKind::Gate | ModelKind::GatePlus => {
            let mut t = Table::new(
                "nodes",
                "Node counts when training ended: mean (population std) over folds [§4.2; thesis: random training data]",
                vec![
                    n_train_column(),
                    count_column("object updates"),
                    count_column("object nodes"),
                    count_column("gate updates"),
                    count_column("gate nodes"),
                    own_count_column("actuator nodes"),
                ],
            );
            let predictor = MapName::Predictor(BLUE_ID);
            for e in results {
                let r = reference::GATE_NODES
                    .iter()
                    .find(|r| r.train_runs == e.train_runs);
                let f = e.folds;
                t.rows.push(vec![
                    whole(e.train_runs),
                    count(
                        get(&e.nodes, &predictor, |m| m.update_calls),
                        f,
                        r.map(|r| r.object_updates),
                    ),
                    count(
                        get(&e.nodes, &predictor, |m| m.nodes),
                        f,
                        r.map(|r| r.object_nodes),
                    ),
                    count(
                        get(&e.nodes, &MapName::Gate, |m| m.update_calls),
                        f,
                        r.map(|r| Ms(r.gate_updates, 0.0)),
                    ),
                    count(
                        get(&e.nodes, &MapName::Gate, |m| m.nodes),
                        f,
                        r.map(|r| r.gate_nodes),
                    ),
                    count(get(&e.nodes, &MapName::Actuator, |m| m.nodes), f, None),
                ]);
            }
            t
        }
        ModelKind::Interaction => {
            let mut t = Table::new(
                "nodes",
                "Node counts when training ended: mean (population std) over folds [§4.1; thesis: random \
                 training data; its AC columns are the script's values, docs/spec/experiments.md §7.5]",
                vec![
                    n_train_column(),
                    own_count_column("largest AC upd."),
                    own_count_column("largest AC nodes"),
                    count_column("AC updates (script)"),
                    count_column("AC nodes (script)"),
                    count_column("# ACs"),
                    count_column("ACS updates"),
                    count_column("ACS nodes"),
                ],
            );
            for e in results {
                let r = reference::INTERACTION_NODES
                    .iter()
                    .find(|r| r.train_runs == e.train_runs);
                let acs = e.nodes.acs.as_ref();
                let f = e.folds;
                t.rows.push(vec![
                    whole(e.train_runs),
                    count(acs.map(|a| a.largest_update_calls), f, None),
                    count(acs.map(|a| a.largest_nodes), f, None),
                    count(
                        acs.map(|a| a.script_quirk.update_calls),
                        f,
                        r.map(|r| r.ac_updates),
                    ),
                    count(acs.map(|a| a.script_quirk.nodes), f, r.map(|r| r.ac_nodes)),
                    count(acs.map(|a| a.count), f, r.map(|r| r.ac_count)),
                    count(
                        get(&e.nodes, &MapName::Acs, |m| m.update_calls),
                        f,
                        r.map(|r| Ms(r.acs_updates, 0.0)),
                    ),
                    count(
                        get(&e.nodes, &MapName::Acs, |m| m.nodes),
                        f,
                        r.map(|r| r.acs_nodes),
                    ),
                ]);
            }
            t
        }
    }
}

/// The node table of a learner of its own (an external learner): its maps'
/// update calls and nodes and its further numbers, by its own names, with
/// its labels below. The thesis has no values for them.
fn own_nodes(results: &[CurveEntry]) -> Table {
    let maps: std::collections::BTreeSet<&String> =
        results.iter().flat_map(|e| e.nodes.maps.keys()).collect();
    let extras: std::collections::BTreeSet<&String> =
        results.iter().flat_map(|e| e.nodes.extra.keys()).collect();
    let mut columns = vec![n_train_column()];
    for name in &maps {
        columns.push(own_count_column(&format!("{name} updates")));
        columns.push(own_count_column(&format!("{name} nodes")));
    }
    for name in &extras {
        columns.push(own_count_column(name));
    }
    let mut t = Table::new(
        "nodes",
        "The learner's own statistics when training ended: mean (population std) over folds"
            .to_owned(),
        columns,
    );
    for e in results {
        let f = e.folds;
        let mut row = vec![whole(e.train_runs)];
        for name in &maps {
            let map = e.nodes.maps.get(*name);
            row.push(Cell::Spread {
                ours: map.map(|m| m.update_calls),
                folds: f,
                thesis: None,
            });
            row.push(Cell::Spread {
                ours: map.map(|m| m.nodes),
                folds: f,
                thesis: None,
            });
        }
        for name in &extras {
            row.push(Cell::Spread {
                ours: e.nodes.extra.get(*name).copied(),
                folds: f,
                thesis: None,
            });
        }
        t.rows.push(row);
    }
    let mut labels: std::collections::BTreeMap<&String, Vec<&String>> = Default::default();
    for e in results {
        for (key, values) in &e.nodes.labels {
            let seen = labels.entry(key).or_default();
            for v in values {
                if !seen.contains(&v) {
                    seen.push(v);
                }
            }
        }
    }
    for (key, values) in labels {
        let values: Vec<&str> = values.iter().map(|v| v.as_str()).collect();
        t.footer.push(format!("{key}: {}", values.join(", ")));
    }
    t
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
    let source = match model {
        ModelKind::Gate | ModelKind::GatePlus => "§8.2",
        ModelKind::Interaction => "§8.1",
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
    use drive::results::test_support::{mtt_report, push_report};

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

    #[test]
    fn learning_curve_table_shows_the_thesis_beside_ours() {
        let report = push_report("random", &[1, 3]);
        let mut text = Vec::new();
        push(&mut text, &report, ModelKind::Gate).unwrap();
        let text = String::from_utf8(text).unwrap();
        // §3.4 row N_train = 3, all positions and interacting.
        assert!(text.contains("[0.1405 ± 0.1292]"), "{text}");
        assert!(text.contains("[0.1557 ± 0.1154]"), "{text}");
        // §4.2 node counts, N_train = 1.
        assert!(text.contains("[3.7 (0.46)]"), "{text}");
        assert!(text.contains("400 messages"), "{text}");
        let mut fixed = Vec::new();
        let report = push_report("fixed-three", &[3]);
        push(&mut fixed, &report, ModelKind::Interaction).unwrap();
        let fixed = String::from_utf8(fixed).unwrap();
        // §5.2 position 9 (x0 = −0.07).
        assert!(fixed.contains("[0.0536 ± 0.0205]"), "{fixed}");
        assert!(fixed.contains("-0.070"), "{fixed}");
    }
}
