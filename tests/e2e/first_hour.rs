//! What a new user meets first: the README's demo, the learner daemon's
//! experience and attempts, output paths checked before work, and errors
//! that say what is wrong once.

use std::net::TcpListener;
use std::process::{Command, Output};

use crate::daemon::{binary, Daemon};
use crate::experiment::{pushlearn, succeeded, TempDir};
use crate::process::{repo_root, run, text};

/// The `pushlearn learn` command of the README's "Watch a push", as words.
pub(crate) fn readme_learn_command() -> Vec<String> {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).expect("README.md");
    let section = readme
        .split("## Watch a push")
        .nth(1)
        .expect("a \"Watch a push\" section");
    let line = section
        .lines()
        .find(|l| l.starts_with("target/release/pushlearn learn "))
        .expect("a `pushlearn learn` command in \"Watch a push\"");
    let words: Vec<String> = line
        .trim_end_matches('&')
        .split_whitespace()
        .map(str::to_owned)
        .collect();
    assert!(
        !words.iter().any(|w| w.contains(['"', '\'', '$', '\\'])),
        "the test splits the command on spaces: {line}"
    );
    words
}

fn learn(args: &[&str]) -> Output {
    let mut all = vec!["learn"];
    all.extend_from_slice(args);
    pushlearn(&all)
}

#[test]
fn the_readme_demo_reaches_the_target() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let words = readme_learn_command();
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .args(&words[1..])
        .args(["--sim", &world.addr.to_string()]);
    let out = run(command);
    let stdout = succeeded(&out);
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("pretrained on"),
        "{words:?}\n{stdout}\n{stderr}"
    );
    assert!(
        stderr.contains("attempt 1, step 100: the block is"),
        "{stderr}"
    );
    assert!(
        stdout.contains("attempt 1 of 1: target reached after"),
        "{words:?}\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains("target reached: 1 of 1 attempts"),
        "{stdout}"
    );
}

#[test]
fn episodes_reset_the_world_and_keep_learning() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr.to_string();
    let out = learn(&[
        "--sim",
        &addr,
        "--pretrain",
        "thesis",
        "--target=-0.6,-0.7,0",
        "--episodes",
        "2",
        "--max-steps",
        "300",
        "--progress-every",
        "1000",
    ]);
    let stdout = succeeded(&out);
    // Each attempt starts from the scene's start: the block 1.124 m from
    // the target, whatever the first attempt did with it.
    let stderr = text(&out.stderr);
    for attempt in [1, 2] {
        assert!(
            stderr.contains(&format!(
                "attempt {attempt}, step 0: the block is 1.124 m and 0.000 rad from the target"
            )),
            "{stderr}"
        );
    }
    let ended: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("attempt "))
        .collect();
    assert_eq!(ended.len(), 2, "{stdout}");
    assert!(ended[0].starts_with("attempt 1 of 2: target not reached after 300 steps"));
    assert!(ended[1].starts_with("attempt 2 of 2: target not reached after 300 steps"));
    assert!(
        stdout.contains("target not reached: 0 of 2 attempts"),
        "{stdout}"
    );
    assert!(stdout.contains("stopped (every attempt ended)"), "{stdout}");
}

/// The `model: {…}` statistics line a daemon prints when it stops.
fn model_line(stdout: &str) -> String {
    stdout
        .lines()
        .find(|l| l.starts_with("model: "))
        .unwrap_or_else(|| panic!("no model line in {stdout}"))
        .to_owned()
}

#[test]
fn a_kept_model_is_where_the_next_daemon_starts() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr.to_string();
    let dir = TempDir::new("memory");
    let saved = dir.file("gate.model");
    let state = dir.file("state");
    let first = succeeded(&learn(&[
        "--sim",
        &addr,
        "--pretrain",
        "thesis",
        "--action",
        "0,0.5",
        "--messages",
        "20",
        "--save-model",
        &saved,
        "--state",
        &state,
    ]));
    assert!(
        first.contains(&format!("model saved to {saved}")),
        "{first}"
    );
    // One state only re-synchronises the model: nothing is learned, so the
    // statistics are the stored model's own.
    for memory in [&saved, &state] {
        let next = learn(&[
            "--sim",
            &addr,
            "--memory",
            memory,
            "--action",
            "0,0",
            "--messages",
            "1",
        ]);
        assert!(
            text(&next.stderr).contains(&format!("memory: starting from {memory}")),
            "{}",
            text(&next.stderr)
        );
        assert_eq!(
            model_line(&succeeded(&next)),
            model_line(&first),
            "{memory}"
        );
    }
    let other = learn(&[
        "--sim",
        &addr,
        "--model",
        "interaction",
        "--memory",
        &saved,
        "--action",
        "0,0",
    ]);
    assert!(!other.status.success());
    let stderr = text(&other.stderr);
    assert!(
        stderr.contains("holds a model made otherwise (model: stored gate, now interaction)"),
        "{stderr}"
    );
}

#[test]
fn output_paths_are_checked_before_any_work() {
    // No world at all: the path is refused before the daemon connects.
    let out = learn(&[
        "--sim",
        "127.0.0.1:9",
        "--action",
        "0,0",
        "--save-model",
        "/nonexistent-pushlearn/gate.model",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr).trim(),
        "error: cannot write --save-model /nonexistent-pushlearn/gate.model: the directory /nonexistent-pushlearn does not exist"
    );
    let out = pushlearn(&[
        "experiment",
        "push-task",
        "--sim",
        "127.0.0.1:9",
        "--json",
        "/nonexistent-pushlearn/curve.json",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr)
            .starts_with("error: cannot write --json /nonexistent-pushlearn/curve.json"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn errors_say_each_cause_once_and_usage_errors_exit_with_2() {
    let mut command = Command::new(binary());
    command.args(["serve", "--scene", "/nonexistent-pushlearn/scene.toml"]);
    let out = run(command);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert_eq!(
        stderr.matches("No such file or directory").count(),
        1,
        "{stderr}"
    );
    let dir = TempDir::new("not-a-report");
    let file = dir.file("other.json");
    std::fs::write(&file, r#"{"experiment": "push-task"}"#).expect("write");
    let out = pushlearn(&["report", "plot", &file]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(lines[0].starts_with("error: "), "{stderr}");
    for (i, line) in lines.iter().enumerate() {
        for later in &lines[i + 1..] {
            let cause = later.trim_start().trim_start_matches("caused by: ");
            assert!(!line.ends_with(cause), "repeated cause:\n{stderr}");
        }
    }
    let out = pushlearn(&["learn", "--no-such-flag"]);
    assert_eq!(out.status.code(), Some(2));
    let out = learn(&["--action", "0,0", "--episodes", "3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).starts_with("error: --episodes counts attempts at a target"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn a_port_that_is_no_world_is_named_as_such() {
    // Accepts and hangs up at once, as a server of another protocol might.
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
    let addr = listener.local_addr().expect("addr").to_string();
    let server = std::thread::spawn(move || drop(listener.accept()));
    let out = learn(&["--sim", &addr, "--action", "0,0"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.starts_with(&format!("error: {addr} is not a pushlearn-sim: ")),
        "{stderr}"
    );
    let _ = server.join();
    // Nothing listens: the hint says what to start.
    let out = learn(&["--sim", "127.0.0.1:9", "--action", "0,0"]);
    assert!(
        text(&out.stderr).contains(
            "127.0.0.1:9: Connection refused (os error 111); is pushlearn-sim running there?"
        ),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn logs_written_to_a_file_carry_no_colour_codes() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .args(["learn", "--sim", &world.addr.to_string()])
        .args(["--action", "0,0", "--messages", "2"])
        .env("RUST_LOG", "debug");
    let out = run(command);
    let stderr = text(&out.stderr);
    assert!(stderr.contains("DEBUG"), "{stderr}");
    assert!(!stderr.contains('\u{1b}'), "{stderr}");
}
