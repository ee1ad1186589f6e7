//! The `pushlearn ctl` binary against the fake world.

use std::path::PathBuf;
use std::process::Output;

use pushlearn::wire::pb::client_message::Payload;
use pushlearn::wire::TimingMode;

use crate::fake_world::BackgroundWorld;
use crate::process::{ctl, text};

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

#[test]
fn single_commands_reach_the_world_in_order() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    for args in [
        &["reset"][..],
        &["set-pose", "actuator", "0", "0", "0.03", "0"],
        &["move", "-0.25", "0.5"],
        &["rate", "10"],
        &["pause"],
        &["unpause"],
    ] {
        succeeded(&ctl(world.addr, args));
    }
    assert_eq!(
        world.applied_kinds(),
        [
            "reset",
            "set_pose",
            "move",
            "publish_rate",
            "pause",
            "unpause"
        ]
    );
    let applied = world.applied();
    assert_eq!(applied[2].payload, Some(Payload::move_(-0.25, 0.5)));
    assert_eq!(
        applied[1].payload,
        Some(Payload::set_pose("actuator", [0.0, 0.0, 0.03], 0.0))
    );
    // Each run starts from a clock-based seq, later runs above earlier ones.
    let seqs: Vec<u64> = applied.iter().map(|m| m.seq).collect();
    assert!(seqs.windows(2).all(|w| w[0] < w[1]), "{seqs:?}");
}

#[test]
fn refusal_is_printed_and_fails() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    let stderr = failed(&ctl(
        world.addr,
        &["set-pose", "blockC", "0", "0.3", "0.05", "0"],
    ));
    assert!(
        stderr.contains("set_pose: unknown body 'blockC' (this world has: actuator, blockA)"),
        "{stderr}"
    );
    let stderr = failed(&ctl(world.addr, &["advance"]));
    assert!(
        stderr.contains("advance: only valid in lockstep mode"),
        "{stderr}"
    );
    assert!(world.applied().is_empty());
}

#[test]
fn invalid_arguments_are_refused_before_sending() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    let stderr = failed(&ctl(world.addr, &["rate", "30"]));
    assert!(
        stderr.contains("publish_rate_hz: 30 Hz does not divide 1000"),
        "{stderr}"
    );
    let stderr = failed(&ctl(world.addr, &["move", "NaN", "0"]));
    assert!(stderr.contains("actuator: direction.x is NaN"), "{stderr}");
    assert!(world.frames().is_empty(), "{:?}", world.frames());
}

#[test]
fn advance_prints_each_resulting_state() {
    let world = BackgroundWorld::start(TimingMode::Lockstep);
    let table = succeeded(&ctl(world.addr, &["advance", "3"]));
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

    let json = succeeded(&ctl(world.addr, &["advance", "2", "--json"]));
    let states: Vec<serde_json::Value> = json
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(states.len(), 2);
    assert_eq!(states[0]["step"], 40);
    assert_eq!(states[1]["step"], 50);
    assert_eq!(states[1]["bodies"][1]["name"], "blockA");
    assert_eq!(states[1]["bodies"][1]["position"][1], 0.25);
}

#[test]
fn watch_json_stops_after_count() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    let json = succeeded(&ctl(world.addr, &["watch", "--json", "--count", "5"]));
    let seqs: Vec<u64> = json
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("JSON line"))
        .map(|v| v["publish_seq"].as_u64().expect("publish_seq"))
        .collect();
    assert_eq!(seqs.len(), 5, "{json}");
    assert!(seqs.windows(2).all(|w| w[0] < w[1]), "{seqs:?}");
}

#[test]
fn info_prints_the_hello() {
    let world = BackgroundWorld::start(TimingMode::Lockstep);
    let info = succeeded(&ctl(world.addr, &["info"]));
    assert!(info.contains("scene:        one_block"), "{info}");
    assert!(info.contains("timing mode:  lockstep"), "{info}");
    assert!(
        info.lines()
            .any(|l| l.trim_start().starts_with("blockA") && l.contains("id  15")),
        "{info}"
    );
}

#[test]
fn script_runs_in_order_and_watch_starts_with_its_effect() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
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
    let out = succeeded(&ctl(world.addr, &["--json", "run", script.arg()]));
    assert_eq!(world.applied_kinds(), ["move", "reset", "set_pose", "move"]);
    let last_move = world.applied().last().map(|m| m.seq).unwrap_or(u64::MAX);
    let states: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    assert_eq!(states.len(), 3);
    for state in &states {
        assert!(
            state["applied_seq"]
                .as_u64()
                .is_some_and(|s| s >= last_move),
            "{state}"
        );
    }
}

#[test]
fn script_stops_at_the_failing_line_and_names_it() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    let script = Script::new(
        "fails",
        "reset\n\nset-pose blockC 0 0.3 0.05 0\nmove 0 0.5\n",
    );
    let stderr = failed(&ctl(world.addr, &["run", script.arg()]));
    let location = format!("{}:3: `set-pose blockC 0 0.3 0.05 0`", script.arg());
    assert!(stderr.contains(&location), "{stderr}");
    assert!(stderr.contains("unknown body 'blockC'"), "{stderr}");
    assert_eq!(
        world.applied_kinds(),
        ["reset"],
        "nothing after the failing line"
    );
}

#[test]
fn script_with_a_syntax_error_sends_nothing() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    let script = Script::new("syntax", "reset\nmove 0 0.5\nrate ten\n");
    let stderr = failed(&ctl(world.addr, &["run", script.arg()]));
    let location = format!(
        "{}:3:6: rate: HZ must be a whole number of Hz, found 'ten'",
        script.arg()
    );
    assert!(stderr.contains(&location), "{stderr}");
    assert!(world.frames().is_empty(), "{:?}", world.frames());
}

#[test]
fn lockstep_script_is_deterministic() {
    let script = Script::new(
        "lockstep",
        "reset\nset-pose actuator 0 0 0.03 0\nmove 0 0.5\nadvance 4\nmove 0 0\nadvance\n",
    );
    let run = || {
        let world = BackgroundWorld::start(TimingMode::Lockstep);
        let out = succeeded(&ctl(world.addr, &["--json", "run", script.arg()]));
        out.lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("JSON line"))
            .map(|mut v| {
                // Seqs are clock-based and differ between runs; the world must not.
                v["applied_seq"] = serde_json::Value::Null;
                v
            })
            .collect::<Vec<_>>()
    };
    let first = run();
    assert_eq!(first.len(), 5);
    let y = first[4]["bodies"][0]["position"][1]
        .as_f64()
        .unwrap_or(f64::NAN);
    assert!(
        (y - 0.02).abs() < 1e-12,
        "actuator y after 4 moving intervals: {y}"
    );
    assert_eq!(first, run());
}

#[test]
fn watch_on_a_quiet_world_explains_the_timeout() {
    let world = BackgroundWorld::start(TimingMode::Lockstep);
    let stderr = failed(&ctl(
        world.addr,
        &["--timeout", "0.3", "watch", "--count", "1"],
    ));
    assert!(stderr.contains("no world state arrived"), "{stderr}");
    assert!(stderr.contains("timed out"), "{stderr}");
}
