//! `pushlearn experiment` and `pushlearn learn` as child processes over a
//! real socket, against the fake world (kinematic: only the actuator moves),
//! which records every command it applied.

use std::path::PathBuf;
use std::process::{Command, Output};

use pushlearn::wire::pb::client_message::Payload;
use pushlearn::wire::TimingMode;
use serde_json::Value;

use crate::fake_world::BackgroundWorld;
use crate::process::{run, text};

/// A temporary directory removed on drop.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("pushlearn-e2e-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        Self(dir)
    }

    pub fn file(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub fn pushlearn(args: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args(args);
    run(command)
}

pub fn succeeded(output: &Output) -> String {
    assert!(
        output.status.success(),
        "pushlearn failed with {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status,
        text(&output.stdout),
        text(&output.stderr)
    );
    text(&output.stdout)
}

pub fn read_json(path: &std::path::Path) -> Value {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_slice(&bytes).expect("valid JSON")
}

fn kinds(world: &BackgroundWorld) -> Vec<String> {
    world
        .applied()
        .iter()
        .filter_map(|m| m.payload.as_ref())
        .map(|p| match p {
            Payload::SetPose(v) => format!(
                "set_pose:{}",
                v.models
                    .iter()
                    .map(|m| m.name.as_str())
                    .collect::<Vec<_>>()
                    .join("+")
            ),
            other => other.kind().to_owned(),
        })
        .collect()
}

#[test]
fn push_task_drives_a_lockstep_world_and_scores_its_predictions() {
    let world = BackgroundWorld::start(TimingMode::Lockstep);
    let dir = TempDir::new("push-fake");
    let json = dir.file("push.json");
    let addr = world.addr.to_string();
    let stdout = succeeded(&pushlearn(&[
        "experiment",
        "push-task",
        "--connect",
        &addr,
        "--mode",
        "lockstep",
        "--train-runs",
        "1",
        "--folds",
        "2",
        "--json",
        json.to_str().expect("UTF-8 temp path"),
    ]));
    assert!(stdout.contains("Learning curve"), "{stdout}");
    let v = read_json(&json);
    assert_eq!(v["experiment"], "push-task");
    assert_eq!(v["mode"], "lockstep");
    let r = &v["results"][0];
    assert_eq!(r["train_runs"], 1);
    // Nothing but the actuator moves in this world, at exactly the
    // commanded speed: a chain of 150 predictions from a trained gate model
    // is exact (any off-by-one in the run protocol would show here).
    assert_eq!(r["block_pos_err"]["mean"], 0.0, "{r}");
    let act = r["actuator_pos_err"]["mean"].as_f64().expect("number");
    assert!(act < 1e-6, "{act}");
    assert_eq!(r["nodes"]["maps"]["gate"]["update_calls"]["mean"], 149.0);

    let kinds = kinds(&world);
    // Startup of the first job: rate, stop, reset; then the first run's start.
    let first: Vec<&str> = kinds.iter().take(5).map(String::as_str).collect();
    assert_eq!(
        first,
        ["advance", "publish_rate", "move", "reset", "advance"]
    );
    // 2 folds × (1 training + 21 test runs) start with the actuator's SetPose,
    // and this obedient world never needs a correction.
    let starts = kinds.iter().filter(|k| *k == "set_pose:actuator").count();
    assert_eq!(starts, 2 * 22);
    assert_eq!(v["run"]["reset_errors"], 0);
    // Lock-step: one Advance per handled message, each answered by one state.
    let advances = kinds.iter().filter(|k| *k == "advance").count() as u64;
    assert_eq!(Some(advances), v["run"]["messages"].as_u64());
}

#[test]
fn move_to_target_stops_at_the_step_limit_when_the_block_never_moves() {
    let world = BackgroundWorld::start(TimingMode::Lockstep);
    let dir = TempDir::new("mtt-fake");
    let json = dir.file("mtt.json");
    let addr = world.addr.to_string();
    let stdout = succeeded(&pushlearn(&[
        "experiment",
        "move-to-target",
        "--model",
        "gate",
        "--connect",
        &addr,
        "--mode",
        "lockstep",
        "--target",
        "-0.6,-0.7,0",
        "--repetitions",
        "1",
        "--max-steps",
        "40",
        "--json",
        json.to_str().expect("UTF-8 temp path"),
    ]));
    assert!(stdout.contains("Move to Target"), "{stdout}");
    let v = read_json(&json);
    let t = &v["targets"][0];
    assert_eq!(t["target"], serde_json::json!([-0.6, -0.7, 0.0]));
    let run = &t["runs"][0];
    assert_eq!(run["reached"], false);
    assert_eq!(run["steps"], 40);
    // The block stayed at (0, 0.25, 0).
    let pos = run["pos_err"].as_f64().expect("number");
    assert!((pos - 0.6f64.hypot(0.95)).abs() < 1e-9, "{pos}");
    assert_eq!(run["ori_err"], 0.0);
    // 8 training runs and the test run start with SetPose.
    let starts = kinds(&world)
        .iter()
        .filter(|k| *k == "set_pose:actuator")
        .count();
    assert_eq!(starts, 9);
}

#[test]
fn learn_advances_a_lockstep_world_and_sends_shadows() {
    let world = BackgroundWorld::start(TimingMode::Lockstep);
    let addr = world.addr.to_string();
    let stdout = succeeded(&pushlearn(&[
        "learn",
        "--connect",
        &addr,
        "--action",
        "0,0.5",
        "--shadows",
        "--messages",
        "30",
    ]));
    assert!(
        stdout.contains("stopped (message limit): 30 messages"),
        "{stdout}"
    );
    let kinds = kinds(&world);
    assert_eq!(kinds.iter().filter(|k| *k == "advance").count(), 30);
    assert_eq!(
        kinds
            .iter()
            .filter(|k| *k == "set_pose:actuatorShadow+blockAShadow")
            .count(),
        30
    );
    // Every state: Move, shadows, next Advance; at the end the actuator is stopped.
    assert_eq!(
        kinds[..4],
        [
            "advance",
            "move",
            "set_pose:actuatorShadow+blockAShadow",
            "advance"
        ]
    );
    let last = world.applied().pop().and_then(|m| m.payload);
    assert_eq!(last, Some(Payload::move_(0.0, 0.0)));
}

#[test]
fn a_world_in_the_wrong_mode_is_refused_with_a_clear_error() {
    let world = BackgroundWorld::start(TimingMode::Realtime);
    let addr = world.addr.to_string();
    let out = pushlearn(&[
        "experiment",
        "push-task",
        "--connect",
        &addr,
        "--mode",
        "lockstep",
        "--train-runs",
        "1",
        "--folds",
        "1",
    ]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("runs in realtime mode, this experiment needs lockstep"),
        "{stderr}"
    );
    assert!(world.applied().is_empty());
}
