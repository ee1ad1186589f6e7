//! External learners (`docs/learner-protocol.md`): `pushlearn experiment
//! --learner` against learners that behave and learners that do not.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use pushlearn::wire::encode_frame;
use pushlearn::wire::pb::learner::{self as lp, reply::Answer, Reply};

use crate::experiment::{experiment, TempDir};
use crate::process::text;

const PUSHLEARN: &str = env!("CARGO_BIN_EXE_pushlearn");

/// A learner that says hello and then does what `after` says; `$DIR` is
/// where its canned frames are. It waits for the driver's first requests
/// after the hello (NewFold, Reset and Predict, sent in one write) before
/// it misbehaves, so the misbehaviour meets the Predict (message 4).
fn canned(dir: &TempDir, after: &str, capabilities: &[lp::Capability]) -> String {
    let hello = encode_frame(&Reply {
        seq: 1,
        answer: Some(Answer::Hello(lp::Hello {
            protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
            name: "canned".into(),
            version: "1".into(),
            capabilities: capabilities.iter().map(|&c| c as i32).collect(),
            ignores_actuator_yaw: false,
        })),
    })
    .expect("encodes");
    std::fs::write(dir.0.join("hello.bin"), hello).expect("write hello");
    // The push task's Start, as the driver sends it, is read first.
    let start = encode_frame(&lp::Request {
        seq: 1,
        call: Some(lp::request::Call::Start(lp::Start {
            protocol_version: lp::ProtocolVersion::ProtocolVersion as i32,
            task: "push-task".into(),
            publish_rate_hz: 100,
        })),
    })
    .expect("encodes");
    format!(
        "cat '{d}/hello.bin'; head -c {n} > /dev/null; head -c 1 > /dev/null; echo $$ > '{d}/pid'; {after}",
        d = dir.0.display(),
        n = start.len()
    )
}

/// Writes `reply` where a canned learner can `cat` it.
fn write_reply(dir: &TempDir, name: &str, reply: Reply) {
    let frame = encode_frame(&reply).expect("encodes");
    std::fs::write(dir.0.join(name), frame).expect("write reply");
}

/// Runs a short push task with `learner`; it must fail.
fn failing_push_task(dir: &TempDir, learner: &str, extra: &[&str]) -> (String, Duration) {
    let json = dir.file("report.json");
    let args = [
        &[
            "push-task",
            "--train-runs",
            "1",
            "--folds",
            "1",
            "--workers",
            "1",
            "--learner",
            learner,
            "--json",
            &json,
        ][..],
        extra,
    ]
    .concat();
    let started = Instant::now();
    let output: Output = experiment(&args);
    let took = started.elapsed();
    let stderr = text(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        !Path::new(&json).exists(),
        "a report was written although the learner failed"
    );
    assert_eq!(
        stderr.matches("error:").count(),
        1,
        "the error is printed once:\n{stderr}"
    );
    (stderr, took)
}

/// The learner's process (and the shell that ran it) is gone.
fn assert_stopped(dir: &TempDir) {
    let pid = std::fs::read_to_string(dir.0.join("pid")).expect("the learner wrote its pid");
    let pid = pid.trim();
    let deadline = Instant::now() + Duration::from_secs(5);
    while Path::new(&format!("/proc/{pid}")).exists() {
        assert!(Instant::now() < deadline, "learner {pid} still runs");
        std::thread::sleep(Duration::from_millis(20));
    }
}

const FORWARD: &[lp::Capability] = &[lp::Capability::Forward];

#[test]
fn a_learner_that_crashes_is_named_with_the_fold_and_the_message() {
    let dir = TempDir::new("learner-crash");
    let (stderr, _) = failing_push_task(&dir, &canned(&dir, "exit 3", FORWARD), &[]);
    for part in [
        "N_train 1 fold 0",
        "learner 'canned'",
        "message 4 (predict)",
        "exit status: 3",
    ] {
        assert!(stderr.contains(part), "no {part:?} in:\n{stderr}");
    }
    assert_stopped(&dir);
}

#[test]
fn a_learner_that_hangs_times_out_and_is_stopped() {
    let dir = TempDir::new("learner-hang");
    let (stderr, took) = failing_push_task(
        &dir,
        &canned(&dir, "exec sleep 60", FORWARD),
        &["--learner-timeout", "1"],
    );
    assert!(
        stderr.contains("no answer to message 4 (predict) within 1s"),
        "{stderr}"
    );
    assert!(stderr.contains("--learner-timeout"), "{stderr}");
    assert!(took < Duration::from_secs(30), "took {took:?}");
    assert_stopped(&dir);
}

#[test]
fn a_learner_that_prints_to_stdout_is_told_so() {
    let dir = TempDir::new("learner-garbage");
    let (stderr, _) = failing_push_task(
        &dir,
        &canned(
            &dir,
            "echo 'Traceback (most recent call last):'; exec sleep 60",
            FORWARD,
        ),
        &[],
    );
    assert!(stderr.contains("not a frame"), "{stderr}");
    assert!(stderr.contains("\"Trac\""), "{stderr}");
    assert!(stderr.contains("does it print to stdout?"), "{stderr}");
    assert_stopped(&dir);
}

/// Two wrong answers to the first Predict (message 4), as files a canned
/// learner `cat`s: `stats.bin` (the wrong kind of reply) and `nan.bin` (a
/// prediction with a non-finite pose).
fn write_wrong_answers(dir: &TempDir) {
    write_reply(
        dir,
        "stats.bin",
        Reply {
            seq: 4,
            answer: Some(Answer::Stats(lp::Stats::default())),
        },
    );
    let nan = lp::BodyPose {
        id: 8,
        x: Some(f64::NAN),
        y: Some(0.0),
        theta: Some(0.0),
    };
    write_reply(
        dir,
        "nan.bin",
        Reply {
            seq: 4,
            answer: Some(Answer::Prediction(lp::Prediction { bodies: vec![nan] })),
        },
    );
}

#[test]
fn a_learner_that_answers_the_wrong_kind_or_nan_is_refused() {
    let dir = TempDir::new("learner-wrong");
    write_wrong_answers(&dir);
    let learner = canned(
        &dir,
        &format!("cat '{}/stats.bin'; exec sleep 60", dir.0.display()),
        FORWARD,
    );
    let (stderr, _) = failing_push_task(&dir, &learner, &[]);
    assert!(
        stderr.contains("answered with a stats reply for message 4 (expected a prediction reply"),
        "{stderr}"
    );
    assert_stopped(&dir);

    let learner = canned(
        &dir,
        &format!("cat '{}/nan.bin'; exec sleep 60", dir.0.display()),
        FORWARD,
    );
    let (stderr, _) = failing_push_task(&dir, &learner, &[]);
    assert!(
        stderr.contains("message 4 (predict)") && stderr.contains("non-finite pose for body 8"),
        "{stderr}"
    );
    assert_stopped(&dir);
}

/// `pushlearn learner-check CMD` with a one-second answer limit.
fn learner_check(learner: &str) -> Output {
    Command::new(PUSHLEARN)
        .args(["learner-check", "--timeout", "1", learner])
        .output()
        .expect("run pushlearn learner-check")
}

#[test]
fn learner_check_catches_each_broken_learner_of_these_tests() {
    let dir = TempDir::new("learner-check");
    write_wrong_answers(&dir);
    let d = dir.0.display();
    for (after, rule) in [
        ("exit 3".to_owned(), "exit status: 3"),
        (
            "exec sleep 60".to_owned(),
            "no answer to message 4 (predict) within 1s",
        ),
        (
            "echo 'Traceback (most recent call last):'; exec sleep 60".to_owned(),
            "does it print to stdout?",
        ),
        (
            format!("cat '{d}/stats.bin'; exec sleep 60"),
            "answered with a stats reply for message 4 (expected a prediction reply",
        ),
        (
            format!("cat '{d}/nan.bin'; exec sleep 60"),
            "non-finite pose for body 8",
        ),
    ] {
        let output = learner_check(&canned(&dir, &after, FORWARD));
        let stdout = text(&output.stdout);
        assert_eq!(output.status.code(), Some(1), "{after}:\n{stdout}");
        assert!(stdout.contains(rule), "{after}: no {rule:?} in\n{stdout}");
        assert!(stdout.contains("BROKEN"), "{stdout}");
        // The hello went well: the learner is named, the first fold broke.
        assert!(stdout.contains("learner 'canned' 1"), "{stdout}");
        assert_stopped(&dir);
    }
    // A forward-only learner is told that Move to Target was not checked.
    let output = learner_check(&canned(&dir, "exec sleep 60", FORWARD));
    let stdout = text(&output.stdout);
    assert!(
        stdout.contains("the learner does not announce INVERSE"),
        "{stdout}"
    );
    // One that never says hello.
    let output = learner_check("exit 0");
    let stdout = text(&output.stdout);
    assert_eq!(output.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("did not say hello"), "{stdout}");
}

#[test]
fn learner_check_passes_a_built_in_model_served_over_the_protocol() {
    let served = format!("{PUSHLEARN} serve-learner --model gate");
    let output = learner_check(&served);
    let stdout = text(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}{}",
        text(&output.stderr)
    );
    assert!(
        !stdout.contains("BROKEN") && !stdout.contains("warning"),
        "{stdout}"
    );
    assert_eq!(stdout.matches("  ok ").count(), 4, "{stdout}");
}

#[test]
fn a_forward_only_learner_is_refused_for_move_to_target_before_any_world_starts() {
    let dir = TempDir::new("learner-forward");
    let learner = canned(&dir, "exec sleep 60", FORWARD);
    let json = dir.file("mtt.json");
    let output = experiment(&["move-to-target", "--learner", &learner, "--json", &json]);
    let stderr = text(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("learner 'canned' cannot run move-to-target: it announces FORWARD only"),
        "{stderr}"
    );
    assert!(!Path::new(&json).exists());

    // A learner that never says hello, and options it cannot take.
    let output = experiment(&["push-task", "--learner", "exit 0", "--json", &json]);
    let stderr = text(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("did not say hello"), "{stderr}");
    let output = experiment(&["push-task", "--learner", "exit 0", "--eta", "0.1"]);
    let stderr = text(&output.stderr);
    assert!(
        stderr.contains("--eta configures a built-in model"),
        "{stderr}"
    );
}
