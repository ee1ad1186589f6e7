//! The push task's terminal tables beside the thesis's (§3.2, §3.4, §4, §5, §6).

use std::io::{self, Write};

use crate::report::layout::{field, text, Cell, Column, Kind, Printout, Table};
use crate::report::plural;
use crate::report::reference::{self, Ms};
use crate::report::table::{
    count_column, error_column, learner_title, n_train_column, own_count_column, own_error_column,
    run_info, whole,
};
use drive::results::nodes::{MapSummary, NodeSummary};
use drive::results::push_task::{BlockCurve, CurveEntry};
use drive::results::PushReport;
use learner::registry::{ModelKind, ThesisModel};
use learner::{MapName, BLUE_ID};

/// The terminal report of a push-task experiment.
///
/// # Errors
/// Writing to `out`.
pub fn push(out: &mut impl Write, report: &PushReport, model: ModelKind) -> io::Result<()> {
    push_printout(report, model).write_text(out)
}

/// The push-task report's tables (without the key-point section, which
/// [`crate::experiments::draft::keypoint_table`] adds).
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
    let source = match model.family() {
        ThesisModel::Gate => "§3.4",
        ThesisModel::Interaction => "§3.2",
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
    let (source, table) = match model.family() {
        ThesisModel::Gate => ("§5.3", reference::fixed_three(model)),
        ThesisModel::Interaction => ("§5.2", reference::fixed_three(model)),
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
    match model.family() {
        ThesisModel::Gate => {
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
                let r = reference::gate_nodes(e.train_runs);
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
        ThesisModel::Interaction => {
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
                let r = reference::interaction_nodes(e.train_runs);
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

#[cfg(test)]
mod tests {
    use super::*;
    use drive::results::test_support::push_report;

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
