//! The `pushlearn ctl` binary against the real daemon.

use std::path::PathBuf;
use std::process::Output;

use serde_json::Value;

use crate::daemon::Daemon;
use crate::process::{ctl, text};

const LOCKSTEP: &[&str] = &["--mode", "lockstep"];
/// Realtime at four times the thesis's pace, to keep the tests short.
const REALTIME: &[&str] = &["--mode", "realtime", "--real-time-rate", "2000"];

fn succeeded(output: &Output) -> String {
    assert!(
        output.status.success(),
        "ctl failed with {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status,
        text(&output.stdout),
        text(&output.stderr)
    );
    text(&output.stdout)
}

fn failed(output: &Output) -> String {
    assert!(
        !output.status.success(),
        "ctl should have failed; stdout:\n{}",
        text(&output.stdout)
    );
    text(&output.stderr)
}

/// A script file in a fresh temporary directory; removed on drop.
struct Script {
    dir: PathBuf,
    path: PathBuf,
}

impl Script {
    fn new(name: &str, content: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("pushlearn-e2e-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join(format!("{name}.ctl"));
        std::fs::write(&path, content).expect("write script");
        Self { dir, path }
    }

    fn arg(&self) -> &str {
        self.path.to_str().expect("temp paths are UTF-8 here")
    }
}

impl Drop for Script {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// The states printed by `ctl --json ...`, one JSON object per line.
fn json_states(output: &Output) -> Vec<Value> {
    succeeded(output)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect()
}

/// One more interval of a lock-step daemon, as `ctl --json advance` prints it.
fn advance(daemon: &Daemon) -> Value {
    let mut states = json_states(&ctl(daemon.addr, &["--json", "advance"]));
    assert_eq!(states.len(), 1);
    states.remove(0)
}

fn number(value: &Value) -> f64 {
    value
        .as_f64()
        .unwrap_or_else(|| panic!("not a number: {value}"))
}

/// `[x, y]` and `[vx, vy]` of the body named `name` in a JSON state.
fn planar(state: &Value, name: &str) -> ([f64; 2], [f64; 2]) {
    let bodies = state["bodies"].as_array().expect("bodies");
    let body = bodies
        .iter()
        .find(|b| b["name"] == name)
        .unwrap_or_else(|| panic!("no {name} in {state}"));
    (
        [number(&body["position"][0]), number(&body["position"][1])],
        [number(&body["lin_vel"][0]), number(&body["lin_vel"][1])],
    )
}

fn near(actual: f64, expected: f64) -> bool {
    (actual - expected).abs() < 1e-6
}

#[test]
fn single_commands_take_effect() {
    let daemon = Daemon::start(LOCKSTEP);
    for args in [
        &["reset"][..],
        &["set-pose", "actuator", "0.1", "0", "0.03", "0"],
        &["move", "0", "0.5"],
        &["rate", "10"],
    ] {
        succeeded(&ctl(daemon.addr, args));
    }
    let state = advance(&daemon);
    assert_eq!(state["step"], 100, "the rate applied: {state}");
    let ([x, y], [vx, vy]) = planar(&state, "actuator");
    assert!(near(x, 0.1), "set-pose applied: x = {x}");
    assert!((y - 0.05).abs() < 1e-4, "0.1 s at 0.5 m/s: y = {y}");
    assert!(
        near(vx, 0.0) && (vy - 0.5).abs() < 1e-3,
        "moving: {vx}, {vy}"
    );

    succeeded(&ctl(daemon.addr, &["pause"]));
    let stderr = failed(&ctl(daemon.addr, &["advance"]));
    assert!(stderr.contains("advance: the world is paused"), "{stderr}");
    succeeded(&ctl(daemon.addr, &["unpause"]));
    assert_eq!(advance(&daemon)["step"], 200);
}

#[test]
fn refusal_is_printed_and_fails() {
    let daemon = Daemon::start(REALTIME);
    let stderr = failed(&ctl(
        daemon.addr,
        &["set-pose", "blockC", "0", "0.3", "0.05", "0"],
    ));
    assert!(
        stderr.contains("the world refused command")
            && stderr
                .contains("set_pose: unknown body 'blockC' (this world has: actuator, blockA)"),
        "{stderr}"
    );
    let stderr = failed(&ctl(daemon.addr, &["advance"]));
    assert!(
        stderr.contains("advance: only valid in lockstep mode"),
        "{stderr}"
    );
}

#[test]
fn invalid_arguments_are_refused_before_sending() {
    let daemon = Daemon::start(REALTIME);
    let stderr = failed(&ctl(daemon.addr, &["rate", "30"]));
    assert!(
        stderr.contains("not sent: publish_rate_hz: 30 Hz does not divide 1000"),
        "{stderr}"
    );
    let stderr = failed(&ctl(daemon.addr, &["move", "NaN", "0"]));
    assert!(
        stderr.contains("not sent: actuator: direction.x is NaN"),
        "{stderr}"
    );
}

#[test]
fn advance_prints_each_resulting_state() {
    let daemon = Daemon::start(LOCKSTEP);
    let table = succeeded(&ctl(daemon.addr, &["advance", "3"]));
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(
        lines.len(),
        1 + 3 * 2,
        "header plus two bodies per state:\n{table}"
    );
    assert!(lines[0].split_whitespace().eq([
        "publish",
        "step",
        "sim_time",
        "applied_seq",
        "body",
        "x",
        "y",
        "z",
        "yaw",
        "vx",
        "vy"
    ]));
    let steps: Vec<&str> = lines[1..]
        .iter()
        .filter_map(|l| l.split_whitespace().nth(1))
        .collect();
    assert_eq!(steps, ["10", "10", "20", "20", "30", "30"]);

    let states = json_states(&ctl(daemon.addr, &["advance", "2", "--json"]));
    assert_eq!(states.len(), 2);
    assert_eq!(states[0]["step"], 40);
    assert_eq!(states[1]["step"], 50);
    assert_eq!(states[1]["bodies"][1]["name"], "blockA");
    let ([x, y], _) = planar(&states[1], "blockA");
    assert!(near(x, 0.0) && near(y, 0.25), "the block rests: {x}, {y}");
}

#[test]
fn watch_json_stops_after_count() {
    let daemon = Daemon::start(REALTIME);
    let states = json_states(&ctl(daemon.addr, &["watch", "--json", "--count", "5"]));
    let seqs: Vec<u64> = states
        .iter()
        .map(|v| v["publish_seq"].as_u64().expect("publish_seq"))
        .collect();
    assert_eq!(seqs.len(), 5, "{states:?}");
    assert!(seqs.windows(2).all(|w| w[0] < w[1]), "{seqs:?}");
}

#[test]
fn info_prints_the_hello() {
    let daemon = Daemon::start(&["--mode", "lockstep", "--scene", "two_blocks"]);
    let info = succeeded(&ctl(daemon.addr, &["info"]));
    assert!(info.contains("scene:        two_blocks"), "{info}");
    assert!(info.contains("timing mode:  lockstep"), "{info}");
    for (name, id) in [("blockA", 15), ("blockB", 27)] {
        assert!(
            info.lines()
                .any(|l| l.trim_start().starts_with(name) && l.contains(&format!("id  {id}"))),
            "{info}"
        );
    }
}

#[test]
fn script_runs_in_order_and_watch_starts_with_its_effect() {
    let daemon = Daemon::start(REALTIME);
    let script = Script::new(
        "push",
        "# push the blue block straight\n\
         move 0 0\n\
         reset\n\
         \n\
         set-pose actuator 0 0 0.03 0   # start line\n\
         move 0 0.5\n\
         watch --count 3\n",
    );
    let states = json_states(&ctl(daemon.addr, &["--json", "run", script.arg()]));
    assert_eq!(states.len(), 3);
    let mut last_y = f64::NEG_INFINITY;
    for state in &states {
        let ([x, y], [_, vy]) = planar(state, "actuator");
        assert!(near(x, 0.0), "on the start line: {state}");
        assert!(
            (vy - 0.5).abs() < 1e-3,
            "every state shown has the move in force: {state}"
        );
        assert!(y > last_y, "moving forward: {state}");
        last_y = y;
    }
}

#[test]
fn script_stops_at_the_failing_line_and_names_it() {
    let daemon = Daemon::start(LOCKSTEP);
    let script = Script::new(
        "fails",
        "reset\n\nset-pose blockC 0 0.3 0.05 0\nmove 0 0.5\n",
    );
    let stderr = failed(&ctl(daemon.addr, &["run", script.arg()]));
    let location = format!("{}:3: `set-pose blockC 0 0.3 0.05 0`", script.arg());
    assert!(stderr.contains(&location), "{stderr}");
    assert!(stderr.contains("unknown body 'blockC'"), "{stderr}");
    let (_, velocity) = planar(&advance(&daemon), "actuator");
    assert_eq!(velocity, [0.0, 0.0], "nothing after the failing line ran");
}

#[test]
fn script_with_a_syntax_error_sends_nothing() {
    let daemon = Daemon::start(LOCKSTEP);
    let script = Script::new("syntax", "reset\nmove 0 0.5\nrate ten\n");
    let stderr = failed(&ctl(daemon.addr, &["run", script.arg()]));
    let location = format!(
        "{}:3:6: rate: HZ must be a whole number of Hz, found 'ten'",
        script.arg()
    );
    assert!(stderr.contains(&location), "{stderr}");
    let (_, velocity) = planar(&advance(&daemon), "actuator");
    assert_eq!(velocity, [0.0, 0.0], "not even the move on line 2 was sent");
}

#[test]
fn lockstep_script_is_deterministic() {
    let script = Script::new(
        "lockstep",
        "reset\nset-pose actuator 0.105 0 0.03 0\nmove 0 0.5\nadvance 40\nmove 0 0\nadvance\n",
    );
    let run = || {
        let daemon = Daemon::start(LOCKSTEP);
        json_states(&ctl(daemon.addr, &["--json", "run", script.arg()]))
            .into_iter()
            .map(|mut v| {
                // Seqs are clock-based and differ between runs; the world must not.
                v["applied_seq"] = Value::Null;
                v
            })
            .collect::<Vec<_>>()
    };
    let first = run();
    assert_eq!(first.len(), 41);
    let ([_, y], _) = planar(&first[3], "actuator");
    assert!(
        (y - 0.02).abs() < 1e-4,
        "actuator y after 4 moving intervals: {y}"
    );
    let ([_, block_y], _) = planar(&first[40], "blockA");
    assert!(
        block_y > 0.25 + 1e-3,
        "the push reached the block: {block_y}"
    );
    assert_eq!(first, run());
}

#[test]
fn watch_on_a_quiet_world_explains_the_timeout() {
    let daemon = Daemon::start(LOCKSTEP);
    let stderr = failed(&ctl(
        daemon.addr,
        &["--timeout", "0.3", "watch", "--count", "1"],
    ));
    assert!(stderr.contains("no world state arrived"), "{stderr}");
    assert!(stderr.contains("timed out"), "{stderr}");
}
