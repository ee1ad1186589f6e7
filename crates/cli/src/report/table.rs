//! Terminal tables in the thesis's layout: every value of ours is followed by
//! the thesis's value in brackets where the thesis has one (`[…]`, source
//! section in the table's title; `reference.rs` holds the numbers).

use std::io::{self, Write};

use learner::eval::MeanStd;
use learner::{MapName, BLUE_ID};

use super::reference::{self, Ms};
use crate::models::ModelKind;
use crate::results::move_to_target::{REPETITIONS, TARGETS};
use crate::results::nodes::{MapSummary, NodeSummary};
use crate::results::push_task::{BlockCurve, CurveEntry};
use crate::results::run_info::RunInfo;
use crate::results::{FeedbackReport, MttReport, PushReport};

fn ms(m: MeanStd) -> String {
    format!("{:.4} ± {:.4}", m.mean, m.std)
}

fn thesis(r: Option<Ms>) -> String {
    r.map_or_else(String::new, |Ms(m, s)| format!("[{m:.4} ± {s:.4}]"))
}

fn cell(ours: MeanStd, reference: Option<Ms>) -> String {
    format!("{:<15} {:<17}", ms(ours), thesis(reference))
}

fn count(m: MeanStd) -> String {
    format!("{:.2} ({:.2})", m.mean, m.std)
}

fn thesis_count(r: Option<Ms>) -> String {
    r.map_or_else(String::new, |Ms(m, s)| format!("[{m} ({s})]"))
}

fn count_cell(ours: Option<MeanStd>, reference: Option<Ms>) -> String {
    let ours = ours.map_or_else(|| "–".to_owned(), count);
    format!("{ours:<16} {:<17}", thesis_count(reference))
}

/// The terminal report of a push-task experiment.
///
/// # Errors
/// Writing to `out`.
/// "gate model", or for an external learner its name, version and the
/// built-in model whose thesis values stand beside it.
fn learner_title(setup: &crate::results::Setup, reference: ModelKind) -> String {
    match &setup.learner {
        None => format!("{} model", setup.model),
        Some(record) => format!(
            "learner '{}' {} ({}; thesis values: the {reference} model's)",
            setup.model, record.version, record.source
        ),
    }
}

pub fn push(out: &mut impl Write, report: &PushReport, model: ModelKind) -> io::Result<()> {
    writeln!(
        out,
        "Push task ({}), {}, {} folds, mode {}, seed {}",
        report.variant,
        learner_title(&report.setup, model),
        report.folds,
        report.setup.mode,
        report.setup.seed
    )?;
    writeln!(
        out,
        "errors after 150 chained predictions; ours, then [the thesis's] where it has the value"
    )?;
    match report.variant.as_str() {
        "fixed-three" => {
            for entry in &report.results {
                positions(out, entry, model)?;
            }
        }
        "two-objects" => {
            for entry in &report.results {
                two_objects(out, entry)?;
            }
        }
        _ => curve(out, &report.results, model)?,
    }
    nodes(out, &report.results, model)?;
    run_info(out, &report.run)
}

fn curve(out: &mut impl Write, results: &[CurveEntry], model: ModelKind) -> io::Result<()> {
    let source = match model {
        ModelKind::Gate => "§3.4",
        ModelKind::Interaction => "§3.2",
    };
    writeln!(out)?;
    writeln!(
        out,
        "Learning curve, all 21 test positions: mean of per-position means ± mean of per-position stds [{source}]"
    )?;
    writeln!(
        out,
        "{:>7}  {:<33}  {:<33}  {:<33}",
        "N_train", "block position [m]", "block orientation [rad]", "actuator position [m]"
    )?;
    for e in results {
        let r = reference::curve(model, e.train_runs);
        writeln!(
            out,
            "{:>7}  {}  {}  {}",
            e.train_runs,
            cell(e.blue.block_pos_err, r.map(|r| r.pos)),
            cell(e.blue.block_ori_err, r.map(|r| r.ori)),
            cell(e.blue.actuator_pos_err, r.map(|r| r.actuator)),
        )?;
    }
    writeln!(out)?;
    writeln!(
        out,
        "The 15 interacting test positions (−0.245 … 0.245) [{source}]; last column: the thesis \
         script's actuator value, mean of (mean + std) / 2 (docs/spec/experiments.md §7.4)"
    )?;
    writeln!(
        out,
        "{:>7}  {:<33}  {:<33}  {:<15}  {:<24}",
        "N_train",
        "block position [m]",
        "block orientation [rad]",
        "actuator [m]",
        "actuator, script's value"
    )?;
    for e in results {
        let r = reference::curve(model, e.train_runs);
        let i = &e.blue.interacting;
        let quirk_ref = r.map_or_else(String::new, |r| {
            format!("[{:.4}]", r.actuator_interacting_quirk.0)
        });
        writeln!(
            out,
            "{:>7}  {}  {}  {:<15}  {:<6.4} {}",
            e.train_runs,
            cell(i.block_pos_err, r.map(|r| r.pos_interacting)),
            cell(i.block_ori_err, r.map(|r| r.ori_interacting)),
            ms(i.actuator_pos_err),
            i.actuator_pos_err_script_quirk,
            quirk_ref,
        )?;
    }
    Ok(())
}

fn positions(out: &mut impl Write, entry: &CurveEntry, model: ModelKind) -> io::Result<()> {
    let (source, table) = match model {
        ModelKind::Gate => ("§5.3", reference::fixed_three(model)),
        ModelKind::Interaction => ("§5.2", reference::fixed_three(model)),
    };
    // The thesis's table is for its three selected runs only.
    let table = (entry.train_runs == 3).then_some(table);
    writeln!(out)?;
    writeln!(
        out,
        "{} selected training runs, per test position: mean ± population std over folds [{source}]",
        entry.train_runs
    )?;
    writeln!(
        out,
        "{:>3}  {:>7}  {:<33}  {:<33}  {:<15}",
        "#", "x0 [m]", "position error [m]", "orientation error [rad]", "actuator [m]"
    )?;
    for (i, p) in entry.blue.per_position.iter().enumerate() {
        let r = table.and_then(|t| t.get(i));
        writeln!(
            out,
            "{:>3}  {:>7.3}  {}  {}  {:<15}",
            i + 1,
            p.x0,
            cell(p.block_pos_err, r.map(|r| r.pos)),
            cell(p.block_ori_err, r.map(|r| r.ori)),
            ms(p.actuator_pos_err),
        )?;
    }
    summary_line(out, &entry.blue)
}

fn summary_line(out: &mut impl Write, blue: &BlockCurve) -> io::Result<()> {
    writeln!(
        out,
        "  over all positions: position {}, orientation {}, actuator {}",
        ms(blue.block_pos_err),
        ms(blue.block_ori_err),
        ms(blue.actuator_pos_err)
    )
}

fn two_objects(out: &mut impl Write, entry: &CurveEntry) -> io::Result<()> {
    let table = reference::two_objects(entry.train_runs);
    let source = match entry.train_runs {
        6 => "§6.1",
        7 => "§6.2",
        _ => "no thesis table for this N_train",
    };
    writeln!(out)?;
    writeln!(
        out,
        "Two objects, {} training runs, per test position: mean ± population std over folds [{source}]",
        entry.train_runs
    )?;
    writeln!(
        out,
        "{:>3}  {:>7}  {:<33}  {:<33}  {:<33}  {:<33}",
        "#",
        "x0 [m]",
        "red position [m]",
        "red orientation [rad]",
        "blue position [m]",
        "blue orientation [rad]"
    )?;
    let red = entry.red.as_ref();
    for (i, blue) in entry.blue.per_position.iter().enumerate() {
        let r = table.and_then(|t| t.get(i));
        let red_at = red.and_then(|c| c.per_position.get(i));
        let nan = MeanStd {
            mean: f64::NAN,
            std: f64::NAN,
        };
        writeln!(
            out,
            "{:>3}  {:>7.2}  {}  {}  {}  {}",
            i + 1,
            blue.x0,
            cell(
                red_at.map_or(nan, |p| p.block_pos_err),
                r.map(|r| r.red_pos)
            ),
            cell(
                red_at.map_or(nan, |p| p.block_ori_err),
                r.map(|r| r.red_ori)
            ),
            cell(blue.block_pos_err, r.map(|r| r.blue_pos)),
            cell(blue.block_ori_err, r.map(|r| r.blue_ori)),
        )?;
    }
    summary_line(out, &entry.blue)
}

fn nodes(out: &mut impl Write, results: &[CurveEntry], model: ModelKind) -> io::Result<()> {
    writeln!(out)?;
    let get = |n: &NodeSummary, name: &MapName, f: fn(&MapSummary) -> MeanStd| n.map(name).map(f);
    match model {
        ModelKind::Gate => {
            writeln!(
                out,
                "Node counts when training ended: mean (population std) over folds [§4.2; thesis: random training data]"
            )?;
            writeln!(
                out,
                "{:>7}  {:<34}  {:<34}  {:<34}  {:<34}  {:<16}",
                "N_train",
                "object updates",
                "object nodes",
                "gate updates",
                "gate nodes",
                "actuator nodes"
            )?;
            let predictor = MapName::Predictor(BLUE_ID);
            for e in results {
                let r = reference::GATE_NODES
                    .iter()
                    .find(|r| r.train_runs == e.train_runs);
                writeln!(
                    out,
                    "{:>7}  {}  {}  {}  {}  {:<16}",
                    e.train_runs,
                    count_cell(
                        get(&e.nodes, &predictor, |m| m.update_calls),
                        r.map(|r| r.object_updates)
                    ),
                    count_cell(
                        get(&e.nodes, &predictor, |m| m.nodes),
                        r.map(|r| r.object_nodes)
                    ),
                    count_cell(
                        get(&e.nodes, &MapName::Gate, |m| m.update_calls),
                        r.map(|r| Ms(r.gate_updates, 0.0))
                    ),
                    count_cell(
                        get(&e.nodes, &MapName::Gate, |m| m.nodes),
                        r.map(|r| r.gate_nodes)
                    ),
                    get(&e.nodes, &MapName::Actuator, |m| m.nodes)
                        .map_or_else(|| "–".to_owned(), count),
                )?;
            }
        }
        ModelKind::Interaction => {
            writeln!(
                out,
                "Node counts when training ended: mean (population std) over folds [§4.1; thesis: random \
                 training data; its AC columns are the script's values, docs/spec/experiments.md §7.5]"
            )?;
            writeln!(
                out,
                "{:>7}  {:<16}  {:<16}  {:<34}  {:<34}  {:<34}  {:<34}  {:<34}",
                "N_train",
                "largest AC upd.",
                "largest AC nodes",
                "AC updates (script)",
                "AC nodes (script)",
                "# ACs",
                "ACS updates",
                "ACS nodes"
            )?;
            for e in results {
                let r = reference::INTERACTION_NODES
                    .iter()
                    .find(|r| r.train_runs == e.train_runs);
                let acs = e.nodes.acs.as_ref();
                writeln!(
                    out,
                    "{:>7}  {:<16}  {:<16}  {}  {}  {}  {}  {}",
                    e.train_runs,
                    acs.map_or_else(|| "–".into(), |a| count(a.largest_update_calls)),
                    acs.map_or_else(|| "–".into(), |a| count(a.largest_nodes)),
                    count_cell(
                        acs.map(|a| a.script_quirk.update_calls),
                        r.map(|r| r.ac_updates)
                    ),
                    count_cell(acs.map(|a| a.script_quirk.nodes), r.map(|r| r.ac_nodes)),
                    count_cell(acs.map(|a| a.count), r.map(|r| r.ac_count)),
                    count_cell(
                        get(&e.nodes, &MapName::Acs, |m| m.update_calls),
                        r.map(|r| Ms(r.acs_updates, 0.0))
                    ),
                    count_cell(
                        get(&e.nodes, &MapName::Acs, |m| m.nodes),
                        r.map(|r| r.acs_nodes)
                    ),
                )?;
            }
        }
    }
    Ok(())
}

/// The footer every experiment prints: messages, the 2/f requirement,
/// corrections.
///
/// # Errors
/// Writing to `out`.
pub fn run_info(out: &mut impl Write, run: &RunInfo) -> io::Result<()> {
    writeln!(out)?;
    match &run.timing {
        Some(t) => writeln!(
            out,
            "{} messages in {:.1} s on {} worker(s); handling {:.3} ms mean, p50 {:.1} µs, \
             p99 {:.1} µs, {:.3} ms max; {} ({:.4} %) over the {:.0} ms budget \
             [thesis: well under 0.1 %]",
            run.messages,
            t.wall_seconds,
            t.workers,
            t.mean_handling_ms,
            t.p50_handling_us,
            t.p99_handling_us,
            t.max_handling_ms,
            t.too_slow,
            100.0 * t.too_slow_fraction,
            run.budget_seconds * 1e3
        )?,
        None => writeln!(
            out,
            "{} messages; handling times not in this document (it is kept free of \
             machine-dependent numbers; `pushlearn reproduce` writes them to docs/results/timing.md)",
            run.messages
        )?,
    }
    writeln!(
        out,
        "{} start-position corrections (SetPose), {} dropped messages after resets, {} unparseable states",
        run.reset_errors, run.ignored, run.parse_errors
    )
}

/// The constant-feedback report: per run, the error of each chained
/// prediction (qualitative, `docs/spec/experiments.md` §3.4).
///
/// # Errors
/// Writing to `out`.
pub fn feedback(out: &mut impl Write, report: &FeedbackReport, model: ModelKind) -> io::Result<()> {
    writeln!(
        out,
        "Push task with constant feedback, {}, {} Hz, mode {} (qualitative; the thesis shows images, §7)",
        learner_title(&report.setup, model),
        report.publish_rate_hz,
        report.setup.mode
    )?;
    for run in &report.runs {
        writeln!(out)?;
        writeln!(
            out,
            "run from x0 = {:.3}: error of the prediction for each message",
            run.x0
        )?;
        writeln!(
            out,
            "{:>7}  {:>12}  {:>12}  {:>12}",
            "message", "block [m]", "block [rad]", "actuator [m]"
        )?;
        for (k, e) in run.errors.iter().enumerate() {
            let block = e.blocks.get(&BLUE_ID);
            writeln!(
                out,
                "{:>7}  {:>12.4}  {:>12.4}  {:>12.4}",
                k + 2,
                block.map_or(f64::NAN, |b| b.pos),
                block.map_or(f64::NAN, |b| b.ori),
                e.actuator
            )?;
        }
    }
    run_info(out, &report.run)
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
    let source = match model {
        ModelKind::Gate => "§8.2",
        ModelKind::Interaction => "§8.1",
    };
    writeln!(
        out,
        "Move to Target, {}, {} repetitions, at most {} steps, mode {}, seed {}",
        learner_title(&report.setup, model),
        report.repetitions,
        report.max_steps,
        report.setup.mode,
        report.setup.seed
    )?;
    writeln!(
        out,
        "Pos/Ori: mean remaining error of the runs that failed; # steps: mean over all runs \
         (failures count {}), in brackets over the successful ones; [thesis {source}]",
        report.max_steps
    )?;
    writeln!(
        out,
        "{:<28}  {:<12}  {:<16}  {:<16}  {:<36}",
        "Target (x, y, θ)", "Reached", "Pos [m]", "Ori [rad]", "# steps"
    )?;
    let thesis_targets = TARGETS;
    for entry in &report.targets {
        let s = &entry.summary;
        let [x, y, theta] = entry.target;
        let r = thesis_targets
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
        writeln!(
            out,
            "{:<28}  {:<12}  {:<16}  {:<16}  {:<36}",
            format!("({x}, {y}, {theta:.4})"),
            format!("{}/{} {r_reached}", s.reached, s.runs),
            format!("{} {r_pos}", opt(s.pos_err_failed, 3)),
            format!("{} {r_ori}", opt(s.ori_err_failed, 3)),
            format!("{ours_steps} {r_steps}"),
        )?;
    }
    run_info(out, &report.run)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::test_support::{mtt_report, push_report};

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
