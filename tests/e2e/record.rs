//! `pushlearn ctl record` and `pushlearn-sim replay` end to end: a learner
//! recorded through the proxy, then replayed, must learn the same model.

use std::net::SocketAddr;
use std::process::Command;

use crate::daemon::{binary, Daemon};
use crate::experiment::{succeeded, TempDir};
use crate::process::{run, text, Background};

/// A child that prints `listening on ADDR` first, and that address.
fn listening(command: Command, name: &'static str) -> (Background, SocketAddr) {
    let (mut process, line) = Background::start(command, name);
    match line
        .trim_end()
        .strip_prefix("listening on ")
        .and_then(|a| a.parse().ok())
    {
        Some(addr) => (process, addr),
        None => panic!(
            "{name} did not say where it listens (first line {line:?}); its log:\n{}",
            process.stop()
        ),
    }
}

fn recorder(world: SocketAddr, file: &str) -> (Background, SocketAddr) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args([
        "ctl",
        "--sim",
        &world.to_string(),
        "record",
        file,
        "--listen",
        "127.0.0.1:0",
    ]);
    listening(command, "ctl record")
}

fn replay(file: &str, extra: &[&str]) -> (Background, SocketAddr) {
    let mut command = Command::new(binary());
    command
        .args(["replay", file, "--listen", "127.0.0.1:0"])
        .args(extra)
        // Plain `key=value` fields in the log, to search it.
        .env("NO_COLOR", "1");
    listening(command, "pushlearn-sim replay")
}

/// `pushlearn learn --shadows` against `addr`; its `model: …` line.
///
/// The model line holds counts only (updates, inserts, nodes), which a
/// slightly different state need not change; the shadows are the model's
/// predictions, sent as SetPose, so a replay whose states differ from the
/// recorded ones makes them differ from the recorded SetPoses, and the
/// replay counts that (`differing=`).
fn learn(addr: SocketAddr, messages: &str) -> String {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args([
        "learn",
        "--connect",
        &addr.to_string(),
        "--action",
        "0,0.5",
        "--shadows",
        "--messages",
        messages,
        "--reconnect-for",
        "0",
    ]);
    let stdout = succeeded(&run(command));
    assert!(
        stdout.contains(&format!("stopped (message limit): {messages} messages")),
        "{stdout}"
    );
    stdout
        .lines()
        .find(|l| l.starts_with("model: "))
        .unwrap_or_else(|| panic!("no model line in\n{stdout}"))
        .to_owned()
}

#[test]
fn a_learner_replayed_from_a_recording_learns_the_same_model() {
    let dir = TempDir::new("record");
    let file = dir.file("push.plrec");
    let world = Daemon::start(&["--mode", "lockstep"]);
    let (mut proxy, proxy_addr) = recorder(world.addr, &file);
    let recorded = learn(proxy_addr, "200");
    let (status, log) = proxy.wait();
    assert!(status.success(), "the recorder failed: {log}");
    assert!(log.contains("states) and"), "{log}");

    let (mut server, replay_addr) = replay(&file, &[]);
    let replayed = learn(replay_addr, "200");
    assert_eq!(
        replayed, recorded,
        "the same states must teach the same model"
    );
    // A second client gets the recording from its start again.
    assert_eq!(learn(replay_addr, "200"), recorded);
    let log = server.stop();
    // The learner sent exactly the recorded commands, its predictions
    // (shadows) included: it saw exactly the recorded states.
    assert!(log.contains("differing=0"), "{log}");
    assert!(
        !log.contains("diverged"),
        "the learner did as recorded:\n{log}"
    );
    assert!(
        log.match_indices("differing=")
            .all(|(i, _)| log[i..].starts_with("differing=0\n")),
        "{log}"
    );

    // A learner that goes on longer than the recording is told it ended.
    let (mut server, replay_addr) = replay(&file, &[]);
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args([
        "learn",
        "--connect",
        &replay_addr.to_string(),
        "--action",
        "0.1,0.5",
        "--messages",
        "500",
        "--reconnect-for",
        "0",
    ]);
    let out = run(command);
    let log = server.stop();
    assert!(
        log.contains("end of the recording"),
        "stdout:\n{}\nstderr:\n{}\nreplay log:\n{log}",
        text(&out.stdout),
        text(&out.stderr)
    );
    assert!(
        log.contains("the client's move (its frame") && log.contains("has diverged"),
        "another action is a divergence:\n{log}"
    );
    assert_eq!(
        log.matches("the client's move").count(),
        1,
        "logged once per kind:\n{log}"
    );
}

#[test]
fn replay_refuses_garbage_and_wrong_versions_naming_the_file() {
    let dir = TempDir::new("replay-bad");
    let garbage = dir.file("garbage.plrec");
    std::fs::write(&garbage, b"not a recording at all").expect("write");
    let mut command = Command::new(binary());
    command.args(["replay", &garbage]);
    let out = run(command);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains(&format!("{garbage}: not a pushlearn recording")),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");

    let version = dir.file("version.plrec");
    std::fs::write(&version, b"PLRECORD\x00\x00\x00\x07\x00\x00\x00\x00").expect("write");
    let mut command = Command::new(binary());
    command.args(["replay", &version]);
    let stderr = text(&run(command).stderr);
    assert!(
        stderr.contains(&format!(
            "{version}: recording format version 7, but this build reads version 1 only"
        )),
        "{stderr}"
    );
}

#[test]
fn a_truncated_recording_replays_what_is_whole_and_warns_once() {
    let dir = TempDir::new("replay-cut");
    let file = dir.file("cut.plrec");
    let world = Daemon::start(&["--mode", "lockstep"]);
    let (mut proxy, proxy_addr) = recorder(world.addr, &file);
    learn(proxy_addr, "20");
    assert!(proxy.wait().0.success());
    let bytes = std::fs::read(&file).expect("the recording");
    std::fs::write(&file, &bytes[..bytes.len() - 7]).expect("cut it");

    let (mut server, replay_addr) = replay(&file, &[]);
    // Only the last record is lost: the first 10 states are whole.
    learn(replay_addr, "10");
    let log = server.stop();
    assert_eq!(log.matches("ends inside a record").count(), 1, "{log}");
}

#[test]
fn a_realtime_recording_replays_at_its_pace_or_fast() {
    let dir = TempDir::new("replay-realtime");
    let file = dir.file("realtime.plrec");
    let world = Daemon::start(&["--mode", "realtime", "--real-time-rate", "2000"]);
    let (mut proxy, proxy_addr) = recorder(world.addr, &file);
    // 50 states at 100 Hz: 500 steps, 0.25 s of wall-clock time at 2000 steps/s.
    let recorded = learn(proxy_addr, "50");
    assert!(proxy.wait().0.success());

    let (mut paced, addr) = replay(&file, &[]);
    let start = std::time::Instant::now();
    assert_eq!(learn(addr, "50"), recorded, "the same states, in order");
    let took = start.elapsed();
    assert!(
        took >= std::time::Duration::from_millis(200),
        "replayed at the recorded pace, not at once: {took:?}"
    );
    let log = paced.stop();
    assert!(log.contains("end of the recording"), "{log}");

    let (_fast, addr) = replay(&file, &["--fast"]);
    assert_eq!(learn(addr, "50"), recorded, "--fast changes the pace only");
}

#[test]
fn an_observer_recording_holds_the_published_states_and_replays_them() {
    let dir = TempDir::new("observer");
    let file = dir.file("observed.plrec");
    let world = Daemon::start(&["--mode", "realtime", "--real-time-rate", "2000"]);
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args([
        "ctl",
        "--sim",
        &world.addr.to_string(),
        "record",
        &file,
        "--count",
        "5",
    ]);
    let out = run(command);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let recording =
        pushlearn::recording::read_file(std::path::Path::new(&file)).expect("a recording");
    assert!(
        !recording.header.commands,
        "an observer records no commands"
    );
    assert_eq!(recording.header.hello.scene, "one_block");
    let recorded: Vec<u64> = recording
        .records
        .iter()
        .filter_map(|r| match &r.frame {
            pushlearn::recording::Frame::World(m) => match &m.payload {
                Some(pushlearn::wire::pb::server_message::Payload::WorldState(s)) => {
                    Some(s.publish_seq)
                }
                _ => None,
            },
            pushlearn::recording::Frame::Client(_) => None,
        })
        .collect();
    assert_eq!(recorded.len(), 5, "{recorded:?}");

    let (_server, addr) = replay(&file, &["--fast"]);
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args([
        "ctl",
        "--sim",
        &addr.to_string(),
        "--json",
        "watch",
        "--count",
        "5",
    ]);
    let watched: Vec<u64> = succeeded(&run(command))
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).expect("JSON")["publish_seq"]
                .as_u64()
                .expect("publish_seq")
        })
        .collect();
    assert_eq!(watched, recorded);
}
