//! Every learner sees the same (`docs/learner-protocol.md`): each built-in
//! model gives the same report run in process (`--model M`) and behind the
//! learner protocol (`--learner "pushlearn serve-learner --model M"`, or a
//! `serve-learner` daemon), number for number but for timing and the
//! learner's source, in every kind of experiment — the push task, two
//! objects, new objects (the object shown under the blue block's id with its
//! own shape), one object to another, and Move to Target. Reduced sizes;
//! what cannot be equal is a bug.

use std::process::Command;

use pushlearn_cli::models::{ModelKind, Named};

use crate::experiment::{experiment, read_json, succeeded, without_run_time, TempDir};
use crate::process::Background;

const PUSHLEARN: &str = env!("CARGO_BIN_EXE_pushlearn");

/// A report as JSON text without its run time and its learner's identity.
pub(crate) fn comparable(path: &str) -> String {
    let mut report = read_json(path);
    let setup = report.as_object_mut().expect("a report object");
    setup.remove("model");
    setup.remove("learner");
    without_run_time(report)
}

/// Equal texts, else the first difference in context.
pub(crate) fn assert_same(what: &str, inside: &str, outside: &str) {
    let at = inside
        .bytes()
        .zip(outside.bytes())
        .position(|(a, b)| a != b)
        .unwrap_or(inside.len().min(outside.len()));
    let context = |t: &str| {
        t.get(at.saturating_sub(160)..(at + 80).min(t.len()))
            .unwrap_or("")
            .to_owned()
    };
    assert!(
        inside == outside,
        "{what}: reports differ at byte {at}:\nin-process: …{}…\nprotocol:   …{}…",
        context(inside),
        context(outside)
    );
}

/// `experiment` (its arguments) with every built-in model, in process and
/// through `serve-learner` on stdin/stdout: the same reports.
fn every_model_alike(kind: &str, experiment_args: &[&str]) {
    let dir = TempDir::new(&format!("identity-{kind}"));
    for model in ModelKind::ALL {
        let model = model.name();
        let inside = dir.file(&format!("{model}-inside.json"));
        let outside = dir.file(&format!("{model}-outside.json"));
        let served = format!("{PUSHLEARN} serve-learner --model {model}");
        succeeded(&experiment(
            &[experiment_args, &["--model", model, "--json", &inside]].concat(),
        ));
        succeeded(&experiment(
            &[experiment_args, &["--learner", &served, "--json", &outside]].concat(),
        ));
        assert_same(
            &format!("{kind}, {model}"),
            &comparable(&inside),
            &comparable(&outside),
        );
        let report = read_json(&outside);
        assert_eq!(report["learner"]["source"], format!("`{served}`"));
    }
}

#[test]
fn every_model_gives_its_report_through_the_protocol_in_the_push_task() {
    every_model_alike(
        "push-task",
        &["push-task", "--train-runs", "1", "--folds", "1"],
    );
}

#[test]
fn every_model_gives_its_report_through_the_protocol_with_two_objects() {
    every_model_alike(
        "two-objects",
        &[
            "push-task",
            "--variant",
            "two-objects",
            "--train-runs",
            "6",
            "--folds",
            "1",
        ],
    );
}

/// The new-object experiment's hardest case: training alternates between
/// two objects, testing is on a third, each shown under the blue block's
/// id with its own shape.
#[test]
fn every_model_gives_its_report_through_the_protocol_on_new_objects() {
    every_model_alike(
        "new-objects",
        &[
            "push-task",
            "--train-on",
            "blue,red",
            "--test-on",
            "cylinder",
            "--train-runs",
            "2",
            "--folds",
            "1",
        ],
    );
}

#[test]
fn every_model_gives_its_report_through_the_protocol_from_one_object_to_another() {
    every_model_alike(
        "cross-object",
        &[
            "push-task",
            "--train-on",
            "red",
            "--test-on",
            "blue",
            "--train-runs",
            "1",
            "--folds",
            "1",
        ],
    );
}

#[test]
fn every_model_gives_its_report_through_the_protocol_in_move_to_target() {
    every_model_alike(
        "move-to-target",
        &[
            "move-to-target",
            "--target",
            "0.6,0.7,0.75",
            "--repetitions",
            "1",
            "--max-steps",
            "300",
        ],
    );
}

/// A learner daemon is the same path over TCP: the hybrid model (which
/// reads shapes) on a new object, and the gate model's inverse model and
/// its exploration (seeded by NewFold) in Move to Target.
#[test]
fn a_learner_daemon_gives_the_in_process_reports_too() {
    let dir = TempDir::new("identity-daemon");
    let inside = dir.file("inside.json");
    let outside = dir.file("outside.json");
    for (model, args) in [
        (
            "hybrid",
            &[
                "push-task",
                "--train-on",
                "blue",
                "--test-on",
                "red",
                "--train-runs",
                "1",
                "--folds",
                "2",
            ][..],
        ),
        (
            "gate",
            &[
                "move-to-target",
                "--target",
                "0.6,0.7,0.75",
                "--repetitions",
                "2",
                "--max-steps",
                "400",
            ][..],
        ),
    ] {
        let mut command = Command::new(PUSHLEARN);
        command.args(["serve-learner", "--model", model, "--listen", "127.0.0.1:0"]);
        let (mut daemon, line) = Background::start(command, "serve-learner");
        let addr = line
            .trim()
            .strip_prefix("listening on ")
            .unwrap_or_else(|| panic!("no address from serve-learner: {line:?}"))
            .to_owned();
        succeeded(&experiment(
            &[args, &["--model", model, "--json", &inside]].concat(),
        ));
        succeeded(&experiment(
            &[args, &["--learner-connect", &addr, "--json", &outside]].concat(),
        ));
        daemon.stop();
        assert_same(model, &comparable(&inside), &comparable(&outside));
    }
}
