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
    assert!(
        stderr.contains("world refused advance: the world is paused"),
        "{stderr}"
    );
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
    // The command as typed and the world's reason, once; no seq.
    assert_eq!(
        stderr,
        "error: world refused set-pose: unknown body 'blockC' (this world has: actuator, blockA)\n"
    );
    let stderr = failed(&ctl(daemon.addr, &["advance"]));
    assert_eq!(
        stderr,
        "error: world refused advance: only valid in lockstep mode, but this world runs in realtime mode\n"
    );
}

#[test]
fn the_old_addr_flag_still_works_but_is_not_advertised() {
    let daemon = Daemon::start(LOCKSTEP);
    let addr = daemon.addr.to_string();
    for flag in ["--sim", "--addr"] {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_pushlearn"));
        command.args(["ctl", flag, &addr, "info"]);
        let out = crate::process::run(command);
        assert!(
            succeeded(&out).contains("scene:        one_block"),
            "{flag}"
        );
    }
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args(["ctl", "--help"]);
    let help = succeeded(&crate::process::run(command));
    assert!(help.contains("--sim <HOST:PORT>"), "{help}");
    assert!(!help.contains("--addr"), "{help}");
}

#[test]
fn negative_numbers_are_values_and_a_negative_rate_is_named() {
    let daemon = Daemon::start(LOCKSTEP);
    let stderr = failed(&ctl(daemon.addr, &["rate", "-10"]));
    assert!(stderr.contains("'-10' is not a publish rate"), "{stderr}");
    assert!(!stderr.contains("'-1'"), "{stderr}");
    let stderr = failed(&ctl(daemon.addr, &["advance", "-3"]));
    assert!(stderr.contains("'-3' is not a count"), "{stderr}");
    let out = succeeded(&ctl(
        daemon.addr,
        &["set-pose", "blockA", "-0.1", "0.25", "0.05", "-0.5"],
    ));
    assert_eq!(
        out,
        "set-pose: blockA at (-0.1, 0.25, 0.05) m, yaw -0.5 rad\n"
    );
    let out = succeeded(&ctl(daemon.addr, &["move", "-0.3", "-0.1"]));
    assert_eq!(out, "move: actuator velocity (-0.3, -0.1) m/s\n");
    let (_, [vx, vy]) = planar(&advance(&daemon), "actuator");
    assert!(
        (vx + 0.3).abs() < 1e-3 && (vy + 0.1).abs() < 1e-3,
        "{vx}, {vy}"
    );
}

#[test]
fn commands_confirm_what_the_world_applied_and_say_when_it_clamped() {
    let daemon = Daemon::start(LOCKSTEP);
    assert_eq!(
        succeeded(&ctl(daemon.addr, &["move", "0.3", "0"])),
        "move: actuator velocity (0.3, 0) m/s\n"
    );
    assert_eq!(
        succeeded(&ctl(daemon.addr, &["move", "1e300", "0"])),
        "move: actuator velocity (0.5, 0) m/s, clamped from (1e300, 0) m/s to the world's speed limit 0.5 m/s\n"
    );
    let (_, [vx, _]) = planar(&advance(&daemon), "actuator");
    assert!((vx - 0.5).abs() < 1e-3, "the world applied the limit: {vx}");
    assert_eq!(
        succeeded(&ctl(daemon.addr, &["rate", "10"])),
        "rate: 10 Hz (a state every 100 steps of 0.001 s)\n"
    );
    assert_eq!(
        succeeded(&ctl(
            daemon.addr,
            &["set-pose", "actuator", "0", "0", "0.03", "7"]
        )),
        "set-pose: actuator at (0, 0, 0.03) m, yaw 7 rad (= 0.716815 rad)\n"
    );
    let stderr = failed(&ctl(
        daemon.addr,
        &["set-pose", "blockA", "0", "0.25", "0.05", "1e300"],
    ));
    assert!(stderr.contains("yaw '1e300' is out of range"), "{stderr}");
    assert!(
        succeeded(&ctl(daemon.addr, &["info"])).contains("speed limit:  0.5 m/s"),
        "info shows the limit"
    );
    for (command, limit) in [("move", "0.5 m/s"), ("set-pose", "1000 m")] {
        let mut help = std::process::Command::new(env!("CARGO_BIN_EXE_pushlearn"));
        help.args(["ctl", command, "--help"]);
        let help = succeeded(&crate::process::run(help));
        assert!(help.contains(limit), "{command} --help:\n{help}");
    }
    // JSON output stays one state per line: no confirmations in it.
    assert_eq!(
        succeeded(&ctl(daemon.addr, &["--json", "move", "0", "0"])),
        ""
    );
}

#[test]
fn a_ghost_of_a_body_the_scene_lacks_is_refused() {
    let daemon = Daemon::start(LOCKSTEP);
    let stderr = failed(&ctl(
        daemon.addr,
        &["set-pose", "blockBShadow", "0", "0.5", "0.05", "0"],
    ));
    assert_eq!(
        stderr,
        "error: world refused set-pose: ghost 'blockBShadow' is of body 'blockB', which this world lacks (this world has: actuator, blockA)\n"
    );
    succeeded(&ctl(
        daemon.addr,
        &["set-pose", "blockAShadow", "0", "0.5", "0.05", "0"],
    ));
    let state = advance(&daemon);
    let ghost = state["bodies"]
        .as_array()
        .and_then(|b| b.iter().find(|b| b["name"] == "blockAShadow"))
        .unwrap_or_else(|| panic!("no ghost in {state}"));
    assert_eq!(ghost["id"], 15, "a ghost carries its body's id");
    let two = Daemon::start(&["--mode", "lockstep", "--scene", "two_blocks"]);
    succeeded(&ctl(
        two.addr,
        &["set-pose", "blockBShadow", "0", "0.5", "0.05", "0"],
    ));
}

#[test]
fn watch_filters_bodies_and_keeps_its_columns() {
    let daemon = Daemon::start(REALTIME);
    let script = Script::new(
        "columns",
        "set-pose blockA -999.123456 0.25 0.05 3\n\
         set-pose blockAShadowTarget 0.1 0.2 0.05 0\n\
         watch --count 3 --body blockA --body blockAShadowTarget\n",
    );
    let out = succeeded(&ctl(daemon.addr, &["run", script.arg()]));
    let table: Vec<&str> = out.lines().skip(2).collect();
    assert_eq!(
        table.len(),
        1 + 3 * 2,
        "header and two bodies per state:\n{out}"
    );
    let width = table[0].chars().count();
    assert!(
        table.iter().all(|l| l.chars().count() == width),
        "every line as wide as the header:\n{out}"
    );
    assert!(table[1..].iter().all(|l| !l.contains("actuator")), "{out}");
    assert!(table[1].contains("-999.12346"), "{out}");

    let states = json_states(&ctl(
        daemon.addr,
        &["--json", "watch", "--count", "2", "--body", "actuator"],
    ));
    for state in &states {
        let names: Vec<&Value> = state["bodies"]
            .as_array()
            .expect("bodies")
            .iter()
            .map(|b| &b["name"])
            .collect();
        assert_eq!(names, ["actuator"], "{state}");
    }
    let stderr = failed(&ctl(
        daemon.addr,
        &["watch", "--count", "1", "--body", "blockZ"],
    ));
    assert!(
        stderr.contains("watch: no body 'blockZ' in this world (it has: actuator, blockA"),
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
