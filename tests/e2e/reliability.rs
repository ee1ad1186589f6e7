//! Faults around `pushlearn learn`: killed with SIGKILL mid-training and
//! restarted from its `--state` directory, stopped by SIGTERM/SIGINT, two of
//! them on one directory, and its world restarted under it.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use learner::{Action, GateConfig, GateModel, Model};
use pushlearn::client::SimClient;
use pushlearn_cli::learn::reconnect::{serve_resilient, Reconnect};
use pushlearn_cli::learn::state::{recover, Durable, Settings};
use pushlearn_cli::learn::{serve, LearnError, Learner, OnState, Policy, ServeOptions, Stop};
use serde_json::Value;

use crate::daemon::Daemon;
use crate::experiment::{read_json, TempDir};
use crate::process::{run, text, CHILD_LIMIT};

const ACTION: Action = Action { vx: 0.0, vy: 0.5 };

/// `pushlearn learn` in the background, its stderr read line by line.
struct Learn {
    child: Child,
    lines: mpsc::Receiver<String>,
    log: Vec<String>,
    output: Option<thread::JoinHandle<String>>,
}

impl Learn {
    fn start(args: &[&str], log_filter: &str) -> Learn {
        let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
        command.arg("learn").args(args);
        Learn::spawn(command, log_filter)
    }

    /// `command` (a `pushlearn learn`, perhaps behind a wrapper) in the
    /// background.
    fn spawn(mut command: Command, log_filter: &str) -> Learn {
        let mut child = command
            .env("RUST_LOG", log_filter)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start pushlearn learn");
        let mut stdout = child.stdout.take().expect("piped stdout");
        let output = thread::spawn(move || {
            let mut text = String::new();
            let _ = std::io::Read::read_to_string(&mut stdout, &mut text);
            text
        });
        let stderr = child.stderr.take().expect("piped stderr");
        let (tx, lines) = mpsc::channel();
        thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Learn {
            child,
            lines,
            log: Vec::new(),
            output: Some(output),
        }
    }

    /// Waits for a successful end; returns stdout (stderr is in `log`).
    fn finish(&mut self) -> String {
        let (status, stdout) = self.end();
        assert!(
            status.success(),
            "pushlearn learn failed ({status}):\n{stdout}\n{}",
            self.log.join("\n")
        );
        stdout
    }

    /// Waits for the daemon to end by itself; its status and stdout (stderr
    /// is in `log`).
    fn end(&mut self) -> (std::process::ExitStatus, String) {
        let deadline = Instant::now() + CHILD_LIMIT;
        let status = loop {
            while let Ok(line) = self.lines.try_recv() {
                self.log.push(line);
            }
            match self.child.try_wait() {
                Ok(Some(status)) => break status,
                Ok(None) if Instant::now() < deadline => thread::sleep(Duration::from_millis(20)),
                _ => panic!(
                    "pushlearn learn did not end; its log:\n{}",
                    self.log.join("\n")
                ),
            }
        };
        let stdout = self
            .output
            .take()
            .and_then(|o| o.join().ok())
            .unwrap_or_default();
        // The rest of stderr: the reader ends when the pipe closes.
        while let Ok(line) = self.lines.recv_timeout(CHILD_LIMIT) {
            self.log.push(plain(&line));
        }
        (status, stdout)
    }

    /// Waits for the journal's trace line (`pushlearn_cli::learn::state=trace`)
    /// acknowledging at least `n` records; returns the count it gave.
    fn acknowledged(&mut self, n: u64) -> u64 {
        self.wait_for(&format!("{n} acknowledged records"), |line| {
            let got: u64 = line
                .split("acknowledged=")
                .nth(1)?
                .split_whitespace()
                .next()?
                .parse()
                .ok()?;
            (got >= n).then_some(got)
        })
    }

    /// Sends `signal` (a name `kill -s` takes) to the daemon.
    fn signal(&self, signal: &str) {
        let status = Command::new("kill")
            .args(["-s", signal, &self.child.id().to_string()])
            .status()
            .expect("run kill");
        assert!(status.success(), "kill -s {signal} failed");
    }

    /// Reads the log until `found` returns something.
    fn wait_for<T>(&mut self, what: &str, mut found: impl FnMut(&str) -> Option<T>) -> T {
        let deadline = Instant::now() + CHILD_LIMIT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    let line = plain(&line);
                    let hit = found(&line);
                    self.log.push(line);
                    if let Some(hit) = hit {
                        return hit;
                    }
                }
                Err(_) => {
                    let _ = self.child.kill();
                    panic!(
                        "pushlearn learn never logged {what}; its log:\n{}",
                        self.log.join("\n")
                    );
                }
            }
        }
    }
}

impl Drop for Learn {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `line` without terminal colour sequences (`ESC [ … m`).
fn plain(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            for c in chars.by_ref() {
                if c == 'm' {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// The learner `pushlearn learn --action 0,0.5` builds at 100 Hz.
fn fresh() -> Learner<GateModel> {
    Learner::new(
        GateModel::new(GateConfig::hz100()),
        Policy::Fixed(ACTION),
        false,
        1,
    )
}

fn settings() -> Settings {
    Settings {
        model: "gate".into(),
        publish_rate_hz: 100,
        policy: Policy::Fixed(ACTION),
        shadows: false,
        seed: 1,
        model_options: pushlearn_cli::models::ModelOptions::default().canonical(),
        episodes: pushlearn_cli::learn::state::EpisodeSettings::default(),
    }
}

/// An uninterrupted learner over the first `n` states of a fresh lock-step
/// world driven with the same Move: the states the killed daemon saw.
fn uninterrupted(n: u64) -> Learner<GateModel> {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let mut learner = fresh();
    runtime.block_on(async {
        let mut client = SimClient::connect(world.addr).await.expect("connect");
        let options = ServeOptions {
            max_messages: Some(n),
            ..ServeOptions::default()
        };
        serve(
            &mut client,
            &mut learner,
            options,
            std::future::pending(),
            |_| {},
        )
        .await
        .expect("reference run");
    });
    learner
}

fn segment(dir: &Path) -> std::path::PathBuf {
    let mut logs: Vec<_> = std::fs::read_dir(dir)
        .expect("state dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("log-"))
        })
        .collect();
    logs.sort();
    logs.pop().expect("a journal segment")
}

#[test]
fn a_learner_killed_mid_training_resumes_bit_identically_and_cuts_a_torn_tail() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr.to_string();
    let dir = TempDir::new("learn-state");
    let state = dir.0.join("memory");
    let state_arg = state.to_string_lossy().into_owned();
    let args = [
        // The old name of --sim, kept as a hidden alias.
        "--connect",
        &addr,
        "--action",
        "0,0.5",
        "--state",
        &state_arg,
        "--snapshot-every",
        "150",
    ];
    let mut learn = Learn::start(&args, "pushlearn_cli::learn::state=trace");
    // Acknowledged records, as the journal reports them after each fsync.
    let acknowledged = learn.acknowledged(400);
    learn.child.kill().expect("SIGKILL");
    let _ = learn.child.wait();

    let (recovered, recovery) = recover::<GateModel>(&state, &settings())
        .expect("recoverable")
        .expect("a stored learner");
    assert!(
        recovery.records() >= acknowledged,
        "{recovery} but {acknowledged} were acknowledged"
    );
    let reference = uninterrupted(recovery.records());
    assert!(
        fingerprint(&recovered) == fingerprint(&reference),
        "the recovered learner ({recovery}) differs from an uninterrupted one"
    );
    let probe = recovered
        .model()
        .parse(&learner::Frame {
            objects: vec![
                observation("actuator", 8, [0.0, 0.1, 0.03]),
                observation("blockA", 15, [0.0, 0.25, 0.05]),
            ],
        })
        .expect("probe frame");
    let predict = |l: &Learner<GateModel>| {
        let p = GateModel::poses(&l.model().predict(&probe, ACTION));
        p.objects()
            .map(|(id, s)| (id, s.x.to_bits(), s.y.to_bits(), s.theta.to_bits()))
            .collect::<Vec<_>>()
    };
    assert_eq!(predict(&recovered), predict(&reference));

    // A write torn by a crash: ten bytes of a record header.
    let mut journal = std::fs::OpenOptions::new()
        .append(true)
        .open(segment(&state))
        .expect("open the journal");
    journal.write_all(&[0xAB; 10]).expect("tear the tail");
    drop(journal);

    let mut resumed = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    resumed.arg("learn").args(args).args(["--messages", "50"]);
    let out = run(resumed);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let records = recovery.records();
    assert!(
        stderr.contains(&format!(
            "memory: resumed from {state_arg}: {records} records"
        )) && stderr.contains("damaged journal tail cut")
            && stderr.contains("a record header cut off after 10 of 16 bytes"),
        "{stderr}"
    );
    // The resync the restart journalled, then 50 states.
    let total = records + 1 + 50;
    assert!(
        stdout.contains(&format!("memory: {total} records on disk")),
        "{stdout}"
    );
    let (_, again) = recover::<GateModel>(&state, &settings())
        .expect("recoverable")
        .expect("a stored learner");
    assert_eq!((again.records(), again.cut), (total, None));
}

fn observation(name: &str, id: u32, position: [f64; 3]) -> learner::Observation {
    learner::Observation {
        name: name.into(),
        id,
        position,
        orientation: [0.0, 0.0, 0.0, 1.0],
        shape: None,
    }
}

fn fingerprint(l: &Learner<GateModel>) -> String {
    serde_json::to_string(l).expect("serialise")
}

/// `pushlearn learn --state` stopped by SIGTERM, restarted, stopped by
/// SIGINT: each time it exits 0 with its one-line message, and the
/// directory holds a final snapshot of every record with nothing left to
/// replay after it.
#[test]
fn a_learner_stopped_by_sigterm_or_sigint_flushes_its_journal_and_writes_a_final_snapshot() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr.to_string();
    let dir = TempDir::new("learn-sigterm");
    let state = dir.0.join("memory");
    let state_arg = state.to_string_lossy().into_owned();
    let args = [
        "--sim",
        &addr,
        "--action",
        "0,0.5",
        "--state",
        &state_arg,
        "--snapshot-every",
        "150",
    ];
    let mut at_least = 300;
    let mut records = 0;
    for signal in ["TERM", "INT"] {
        let mut learn = Learn::start(&args, "pushlearn_cli::learn::state=trace");
        let acknowledged = learn.acknowledged(at_least);
        learn.signal(signal);
        let stdout = learn.finish();
        let stderr = learn.log.join("\n");
        let (recovered, recovery) = recover::<GateModel>(&state, &settings())
            .expect("recoverable")
            .expect("a stored learner");
        assert!(
            recovery.records() >= acknowledged,
            "{recovery} but {acknowledged} were acknowledged"
        );
        // The final snapshot covers every record: an empty journal tail.
        assert_eq!((recovery.replayed, &recovery.cut), (0, &None), "{recovery}");
        records = recovery.records();
        assert!(
            stdout.contains("stopped (interrupted)")
                && stdout.contains(&format!("memory: {records} records on disk in {state_arg}")),
            "{stdout}"
        );
        let line = format!(
            "pushlearn learn: SIG{signal}: stopped cleanly; journal flushed and final snapshot \
             written ({records} records in {state_arg})"
        );
        assert!(
            stderr.lines().any(|l| l == line),
            "no `{line}` in\n{stderr}"
        );
        if signal == "TERM" {
            // The snapshot is the learner after exactly those records (the
            // second run's has a resync in it, which a fresh world's
            // learner does not).
            assert!(
                fingerprint(&recovered) == fingerprint(&uninterrupted(records)),
                "the final snapshot ({recovery}) differs from an uninterrupted learner"
            );
        }
        at_least = records + 300;
    }
    // The second run resumed the first's memory: its resync and more.
    assert!(records > 600, "{records}");
}

/// Two learners on one state directory: the second is refused before it
/// does anything, naming the directory and the holder; once the holder is
/// gone, even by SIGKILL, the directory is free.
#[test]
fn a_second_learner_on_a_state_directory_in_use_is_refused_until_the_first_dies() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr.to_string();
    let dir = TempDir::new("learn-lock");
    let state = dir.0.join("memory");
    let state_arg = state.to_string_lossy().into_owned();
    let args = ["--sim", &addr, "--action", "0,0.5", "--state", &state_arg];
    let mut first = Learn::start(&args, "pushlearn_cli::learn::state=trace");
    first.acknowledged(50);
    let second = || {
        let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
        command.arg("learn").args(args).args(["--messages", "20"]);
        run(command)
    };
    let refused = second();
    let stderr = text(&refused.stderr);
    assert!(!refused.status.success(), "{stderr}");
    let expected = format!(
        "{state_arg} is in use by another learner (pid {}); only one `pushlearn learn` may use \
         a --state directory at a time",
        first.child.id()
    );
    assert!(stderr.contains(&expected), "{stderr}");
    // Refused before connecting: the world never saw a second learner.
    assert!(!stderr.contains("model on scene"), "{stderr}");

    first.child.kill().expect("SIGKILL");
    let _ = first.child.wait();
    let after = second();
    let stderr = text(&after.stderr);
    assert!(after.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("memory: resumed from {state_arg}")),
        "{stderr}"
    );
}

/// The journal's file reaching a size limit (RLIMIT_FSIZE, with SIGXFSZ
/// ignored so that the write fails with EFBIG instead of killing the
/// process) mid-run, as a full disk would: the daemon stops with one error
/// naming the file and the OS error and a non-zero status; restarted
/// without the limit it has every acknowledged record, bit-identical to an
/// uninterrupted learner over them.
#[cfg(target_os = "linux")]
#[test]
fn a_journal_that_cannot_grow_stops_the_learner_and_a_restart_loses_no_acknowledged_update() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr.to_string();
    let dir = TempDir::new("learn-fsize");
    let state = dir.0.join("memory");
    let state_arg = state.to_string_lossy().into_owned();
    let args = ["--sim", &addr, "--action", "0,0.5", "--state", &state_arg];
    assert!(
        Command::new("prlimit")
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success()),
        "this test needs prlimit (util-linux)"
    );
    // 16 KiB: the first snapshot (about 1.6 KiB) fits, the journal (147
    // bytes a state of this scene) reaches it after about a hundred states.
    let mut limited = Command::new("sh");
    limited
        .args([
            "-c",
            r#"trap '' XFSZ; exec prlimit --fsize=16384 "$0" "$@""#,
            env!("CARGO_BIN_EXE_pushlearn"),
            "learn",
        ])
        .args(args);
    let mut learn = Learn::spawn(limited, "pushlearn_cli::learn::state=trace");
    let (status, _) = learn.end();
    let log = learn.log.join("\n");
    assert_eq!(status.code(), Some(1), "{log}");
    let segment = format!("{state_arg}/log-00000000000000000000");
    let errors: Vec<_> = learn
        .log
        .iter()
        .filter(|l| l.starts_with("error: "))
        .collect();
    assert!(
        errors.len() == 1
            && errors[0].starts_with(&format!(
                "error: cannot keep the learner's memory: {segment}: File too large (os error 27)"
            )),
        "{log}"
    );
    assert!(
        learn
            .log
            .iter()
            .any(|l| l.contains("ERROR") && l.contains(&format!("the journal stopped: {segment}"))),
        "{log}"
    );
    let acknowledged = learn
        .log
        .iter()
        .filter_map(|l| l.split("acknowledged=").nth(1)?.trim().parse::<u64>().ok())
        .max()
        .unwrap_or(0);

    let (recovered, recovery) = recover::<GateModel>(&state, &settings())
        .expect("recoverable")
        .expect("a stored learner");
    assert!(
        recovery.records() >= acknowledged && recovery.records() > 0,
        "{recovery} but {acknowledged} were acknowledged"
    );
    assert!(
        fingerprint(&recovered) == fingerprint(&uninterrupted(recovery.records())),
        "the recovered learner ({recovery}) differs from an uninterrupted one"
    );
    let mut resumed = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    resumed.arg("learn").args(args).args(["--messages", "20"]);
    let out = run(resumed);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "memory: resumed from {state_arg}: {} records",
            recovery.records()
        )),
        "{stderr}"
    );
}

/// Hands states to a learner and completes a shutdown future after `after`
/// of them, or at the first resync (the world lost), as a test's stand-in
/// for SIGTERM; with a world to kill, it kills it at state `after`.
struct StopAfter<'a, H> {
    inner: &'a mut H,
    after: u64,
    states: u64,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    kill_world: Option<Daemon>,
}

impl<'a, H> StopAfter<'a, H> {
    fn new(inner: &'a mut H, after: u64) -> (Self, impl std::future::Future<Output = ()>) {
        let (tx, rx) = tokio::sync::oneshot::channel();
        let wrapper = StopAfter {
            inner,
            after,
            states: 0,
            stop: Some(tx),
            kill_world: None,
        };
        // A sender dropped unfired must not stop anything.
        let shutdown = async move {
            if rx.await.is_err() {
                std::future::pending::<()>().await;
            }
        };
        (wrapper, shutdown)
    }

    fn fire(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
    }
}

impl<H: OnState> OnState for StopAfter<'_, H> {
    fn on_state(
        &mut self,
        frame: &learner::Frame,
        heights: &pushlearn_cli::frame::StartHeights,
    ) -> Result<Vec<pushlearn::wire::pb::client_message::Payload>, LearnError> {
        self.states += 1;
        let commands = self.inner.on_state(frame, heights);
        if self.states == self.after {
            match self.kill_world.as_mut() {
                Some(world) => {
                    world.stop();
                }
                None => self.fire(),
            }
        }
        commands
    }

    fn resync(&mut self) -> Result<(), LearnError> {
        if self.kill_world.is_some() {
            self.fire();
        }
        self.inner.resync()
    }

    fn episodes(&self) -> Option<&pushlearn_cli::learn::Episodes> {
        self.inner.episodes()
    }
}

/// The shutdown future without signals: the serving loop stops between two
/// states, and closing the memory leaves a final snapshot of exactly the
/// states handled.
#[test]
fn a_shutdown_future_stops_the_serving_loop_and_close_snapshots_every_state() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let dir = TempDir::new("learn-shutdown");
    let (mut durable, _) =
        Durable::open(&dir.0, &settings(), fresh, 1000).expect("open the memory");
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let (stop, summary) = runtime.block_on(async {
        let mut client = SimClient::connect(world.addr).await.expect("connect");
        let (mut stopping, shutdown) = StopAfter::new(&mut durable, 120);
        serve(
            &mut client,
            &mut stopping,
            ServeOptions::default(),
            shutdown,
            |_| {},
        )
        .await
        .expect("serve")
    });
    assert_eq!((stop, summary.messages), (Stop::Interrupted, 120));
    assert_eq!(durable.close().expect("close"), 120);
    let (recovered, recovery) = recover::<GateModel>(&dir.0, &settings())
        .expect("recoverable")
        .expect("a stored learner");
    assert_eq!(
        (recovery.snapshot_records, recovery.replayed, recovery.cut),
        (120, 0, None)
    );
    assert!(fingerprint(&recovered) == fingerprint(&uninterrupted(120)));
}

/// A stop that comes while the world is gone ends the reconnection at once
/// instead of waiting out --reconnect-for.
#[test]
fn a_shutdown_while_reconnecting_stops_at_once() {
    let world = Daemon::start(&["--mode", "lockstep"]);
    let addr = world.addr;
    let mut learner = fresh();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let served = runtime.block_on(async {
        let client = SimClient::connect(addr).await.expect("connect");
        let (mut stopping, shutdown) = StopAfter::new(&mut learner, 30);
        stopping.kill_world = Some(world);
        // Without the stop this would retry for ten minutes, far beyond
        // the test's limit.
        let reconnect = Reconnect::new(addr.to_string(), Some(Duration::from_secs(600)));
        tokio::time::timeout(
            CHILD_LIMIT,
            serve_resilient(
                client,
                &mut stopping,
                ServeOptions::default(),
                &reconnect,
                shutdown,
                |_| {},
            ),
        )
        .await
        .expect("stopped before the test's limit")
        .expect("serve")
    });
    assert_eq!(served.stop, Stop::Interrupted);
    assert!(served.client.is_none());
    assert_eq!((served.states, served.reconnects), (30, 0));
}

#[test]
fn a_restarted_world_is_reconnected_with_backoff_and_the_model_resynchronised() {
    let mut world = Daemon::start(&["--mode", "lockstep"]);
    let port = world.addr.port();
    let addr = world.addr.to_string();
    let mut learn = Learn::start(
        &[
            "--sim",
            &addr,
            "--action",
            "0,0.5",
            "--messages",
            "2000",
            "--reconnect-for",
            "30",
        ],
        "warn,pushlearn::client=debug",
    );
    // Some states into the run (a Move and an Advance per state), take the
    // world away.
    let mut sent = 0;
    learn.wait_for("commands", |l| {
        sent += usize::from(l.contains("send"));
        (sent >= 40).then_some(())
    });
    world.stop();
    learn.wait_for("the lost world", |l| {
        l.contains("lost the world").then_some(())
    });
    learn.wait_for("a failed attempt with its backoff", |l| {
        l.contains("reconnecting failed").then_some(())
    });
    let _world = Daemon::start_on(port, &["--mode", "lockstep"]);
    learn.wait_for("the reconnection", |l| {
        l.contains("reconnected to the world").then_some(())
    });
    let stdout = learn.finish();
    assert!(
        stdout.contains("2000 states over 1 reconnection(s)"),
        "{stdout}"
    );
    // The model did not train on the transition across the gap: two of the
    // states re-synchronised it, all others updated it.
    let stats: Value = stdout
        .lines()
        .find_map(|l| l.strip_prefix("model: "))
        .and_then(|json| serde_json::from_str(json).ok())
        .unwrap_or_else(|| panic!("no model statistics in {stdout}"));
    assert_eq!(
        stats["maps"]["actuator"]["update_calls"].as_u64(),
        Some(2000 - 2),
        "{stdout}"
    );
}

/// The reduced version of the documented 64-client, 60 s load run
/// (`docs/reliability.md`): the same code as `pushlearn ctl load`, 2 s
/// against a real realtime daemon.
#[test]
fn sixty_four_clients_at_100_hz_miss_nothing_and_the_daemons_memory_stays_bounded() {
    let daemon = Daemon::start(&["--real-time-rate", "1000"]);
    let options = pushlearn_cli::load::LoadOptions {
        clients: 64,
        duration: Duration::from_secs(2),
        control: true,
        pid: Some(daemon.pid()),
        sample_every: Duration::from_millis(250),
    };
    let runtime = tokio::runtime::Runtime::new().expect("a tokio runtime");
    let report = runtime
        .block_on(async {
            tokio::time::timeout(
                CHILD_LIMIT,
                pushlearn_cli::load::run_load(&daemon.addr.to_string(), &options),
            )
            .await
        })
        .expect("the load run finishes in time")
        .expect("load run");
    let controller = report.controller.as_ref().expect("a controlling client");
    assert!(controller.counts.states > 0, "{report}");
    assert_eq!(controller.counts.missed, 0, "{report}");
    assert_eq!(report.subscribers_lost, 0, "{report}");
    assert!(report.subscriber_min_states > 0, "{report}");
    // Every subscriber's intervals are in the one distribution.
    assert_eq!(
        report.subscriber_intervals.messages,
        report.subscribers.states - 63,
        "{report}"
    );
    // Bounded: whatever happens, 64 queues of 1024 states (about 0.3 KiB
    // each) are all the daemon may hold on to.
    let rss: Vec<u64> = report.rss_kib.iter().map(|s| s.1).collect();
    assert!(rss.len() >= 2, "{report}");
    let growth = rss.iter().max().unwrap_or(&0) - rss[0];
    assert!(growth < 64 * 1024, "RSS grew by {growth} KiB: {report}");
}

/// The reduced version of the documented ten-minute soak
/// (`docs/reliability.md`, "Soak"): `pushlearn ctl soak` for 5 s, a real
/// learning, acting `pushlearn learn --state` beside 64 subscribers of a
/// realtime world at 100 states a second, its journal compacted every 100
/// records.
#[test]
fn a_soak_of_a_learner_beside_64_subscribers_misses_nothing_and_keeps_its_journal_bounded() {
    let daemon = Daemon::start(&["--real-time-rate", "1000", "--max-clients", "80"]);
    let plots = TempDir::new("soak-plots");
    let pid = daemon.pid().to_string();
    let out = crate::process::ctl(
        daemon.addr,
        &[
            "--json",
            "soak",
            "--subscribers",
            "64",
            "--seconds",
            "5",
            "--sample-every",
            "0.5",
            "--snapshot-every",
            "100",
            "--pid",
            &pid,
            "--plots",
            &plots.file(""),
        ],
    );
    assert!(
        out.status.success(),
        "ctl soak failed:\n{}",
        text(&out.stderr)
    );
    let report: pushlearn_cli::soak::SoakReport =
        serde_json::from_slice(&out.stdout).expect("the soak's JSON report");
    let learner = &report.learner;
    // The controlling client, the learner, misses no state and stops
    // cleanly on SIGTERM with every record it handled on disk.
    assert!(learner.states >= 400, "{report}");
    assert_eq!(learner.missed, 0, "{report}");
    assert_eq!(learner.signal.as_deref(), Some("SIGTERM"), "{report}");
    assert!(
        learner.records_on_disk.is_some_and(|n| n >= learner.states),
        "{report}"
    );
    let load = &report.load;
    assert!(load.controller.is_none(), "{report}");
    assert_eq!(load.subscribers.missed, 0, "{report}");
    assert_eq!(load.subscribers_lost, 0, "{report}");
    assert!(load.subscriber_min_states >= 400, "{report}");
    assert!((5.0..10.0).contains(&load.seconds), "{report}");
    assert!((90.0..110.0).contains(&load.publish_rate_wall), "{report}");
    // Sampled throughout; the journal compacted: never more than two
    // snapshot intervals (and what queues while a snapshot is written), far
    // fewer than the records written.
    assert!(report.samples.len() >= 8, "{report}");
    assert!(load.rss_kib.len() >= 8, "{report}");
    assert!(
        report.journal_max() <= report.journal_bound() + 50,
        "{report}"
    );
    assert!(report.journal_max() < learner.states / 2, "{report}");
    // Bounded memory: the learner's model grows by a few nodes a second,
    // far below this; the world's queues hold at most 64 × 1024 states.
    let growth = |series: Vec<u64>| series.iter().max().unwrap_or(&0) - series[0];
    let learner_growth = growth(report.samples.iter().map(|s| s.learner_rss_kib).collect());
    assert!(
        learner_growth < 16 * 1024,
        "learner RSS grew by {learner_growth} KiB: {report}"
    );
    let world_growth = growth(load.rss_kib.iter().map(|s| s.1).collect());
    assert!(
        world_growth < 64 * 1024,
        "world RSS grew by {world_growth} KiB: {report}"
    );
    let png = std::fs::read(plots.0.join("soak.png")).expect("the soak's figure");
    assert!(png.starts_with(b"\x89PNG"), "soak.png is no PNG");
}

/// The `pushlearn-sim` children of process `parent` (from `/proc`).
fn world_children(parent: u32) -> Vec<u32> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .filter_map(|entry| entry.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|&pid| {
            let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
                return false;
            };
            // `pid (comm) state ppid …`; comm may hold spaces, so split
            // after its closing parenthesis.
            let Some((head, tail)) = stat.rsplit_once(')') else {
                return false;
            };
            let ppid = tail.split_whitespace().nth(1).and_then(|p| p.parse().ok());
            head.ends_with("(pushlearn-sim") && ppid == Some(parent)
        })
        .collect()
}

/// CPU time (user + system, in clock ticks) process `pid` has used.
fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let (_, tail) = stat.rsplit_once(')')?;
    let fields: Vec<&str> = tail.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of stat, 12 and 13 after comm.
    Some(fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?)
}

/// Issue 22 item 5: ODE aborts its process on internal assertions, so a
/// world may die in the middle of an experiment. A worker's world is killed
/// (SIGKILL) while it steps a job: the experiment names the job, the run
/// and the last command, restarts the world, retries the job once, and its
/// report is bit-identical to an undisturbed run's (jobs are seeded; the run
/// cache keeps nothing of the dead world's half-recorded job).
#[test]
fn a_world_killed_mid_experiment_is_restarted_and_its_job_retried_bit_identically() {
    let dir = TempDir::new("world-death");
    let sim = crate::daemon::binary();
    let sim = sim.to_str().expect("UTF-8 target path");
    let args = |json: &str| -> Vec<String> {
        [
            "experiment",
            "push-task",
            "--model",
            "gate",
            "--mode",
            "lockstep",
            "--train-runs",
            "1,2",
            "--folds",
            "2",
            "--workers",
            "2",
            "--sim-bin",
            sim,
            "--json",
            json,
        ]
        .iter()
        .map(|s| (*s).to_owned())
        .collect()
    };
    let (calm, disturbed) = (dir.file("calm.json"), dir.file("disturbed.json"));
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command.args(args(&calm));
    let out = run(command);
    assert!(out.status.success(), "{}", text(&out.stderr));

    let (stdout, stderr) = (dir.file("stdout"), dir.file("stderr"));
    let mut experiment = Command::new(env!("CARGO_BIN_EXE_pushlearn"))
        .args(args(&disturbed))
        .env_remove("RUST_LOG")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout).expect("stdout file"))
        .stderr(std::fs::File::create(&stderr).expect("stderr file"))
        .spawn()
        .expect("pushlearn starts");
    let deadline = Instant::now() + CHILD_LIMIT * 3;
    // A world that has used 0.2 s of CPU is stepping a job (starting and
    // waiting cost next to nothing): kill it then.
    let victim = loop {
        assert!(
            experiment.try_wait().expect("waiting").is_none(),
            "the experiment ended before a world could be killed:\n{}",
            std::fs::read_to_string(&stderr).unwrap_or_default()
        );
        assert!(Instant::now() < deadline, "no busy world to kill");
        let busy = world_children(experiment.id())
            .into_iter()
            .find(|&pid| cpu_ticks(pid).is_some_and(|ticks| ticks >= 20));
        if let Some(pid) = busy {
            break pid;
        }
        thread::sleep(Duration::from_millis(10));
    };
    let killed = Command::new("kill")
        .args(["-KILL", &victim.to_string()])
        .status()
        .expect("kill runs");
    assert!(killed.success());
    let status = loop {
        if let Some(status) = experiment.try_wait().expect("waiting") {
            break status;
        }
        if Instant::now() > deadline {
            let _ = experiment.kill();
            panic!("the disturbed experiment did not finish");
        }
        thread::sleep(Duration::from_millis(10));
    };
    let log = std::fs::read_to_string(&stderr).unwrap_or_default();
    assert!(status.success(), "{status}:\n{log}");

    // Said once, with the job, the run, the signal and the last command.
    let said: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("the world process died"))
        .collect();
    assert_eq!(said.len(), 1, "{log}");
    let line = said[0];
    for part in [
        "N_train ",
        " fold ",
        " run ",
        " of the run: the world process died (signal: 9 (SIGKILL)); the last command sent was ",
        "; restarting the world and retrying the job once",
    ] {
        assert!(line.contains(part), "{part:?} not in {line}");
    }

    let (a, b) = (read_json(&calm), read_json(&disturbed));
    let exact = |v: &Value| serde_json::to_string(&v["results"]).expect("serialises");
    assert_eq!(exact(&a), exact(&b));
    assert_eq!(a["run"]["messages"], b["run"]["messages"]);
}

/// The gate model, sleeping [`SLEEP`] in every [`SLEEP_EVERY`]-th
/// prediction: a learner too slow for the 2/f budget on some states. Clones
/// (each fold's untrained copy) share the counters.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Sleepy {
    inner: GateModel,
    #[serde(skip)]
    predictions: std::sync::Arc<std::sync::atomic::AtomicU64>,
    #[serde(skip)]
    slept: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

/// 30 ms against the 20 ms budget at 100 Hz. The predictions a state
/// triggers are fewer than [`SLEEP_EVERY`], so no state sleeps twice.
const SLEEP: Duration = Duration::from_millis(30);
const SLEEP_EVERY: u64 = 97;

impl Model for Sleepy {
    type World = <GateModel as Model>::World;
    fn parse(&self, frame: &learner::Frame) -> Result<Self::World, learner::ParseError> {
        self.inner.parse(frame)
    }
    fn poses(world: &Self::World) -> learner::Poses {
        GateModel::poses(world)
    }
    fn reset_objects(&mut self, world: &Self::World) {
        self.inner.reset_objects(world);
    }
    fn update(&mut self, world: &Self::World, action: Action) {
        self.inner.update(world, action);
    }
    fn predict(&self, world: &Self::World, action: Action) -> Self::World {
        use std::sync::atomic::Ordering;
        if self.predictions.fetch_add(1, Ordering::SeqCst) % SLEEP_EVERY == SLEEP_EVERY - 1 {
            self.slept.fetch_add(1, Ordering::SeqCst);
            thread::sleep(SLEEP);
        }
        self.inner.predict(world, action)
    }
    fn set_training(&mut self, on: bool) {
        self.inner.set_training(on);
    }
    fn is_training(&self) -> bool {
        self.inner.is_training()
    }
    fn set_target(&mut self, target: Option<learner::Target>) -> Result<(), learner::TargetError> {
        self.inner.set_target(target)
    }
    fn has_target(&self) -> bool {
        self.inner.has_target()
    }
    fn act(&mut self, rng: &mut dyn rand::Rng) -> Action {
        self.inner.act(rng)
    }
    fn stats(&self) -> learner::ModelStats {
        self.inner.stats()
    }
    fn start_fold(&mut self, seed: u64) {
        self.inner.start_fold(seed);
    }
}

/// Issue 22 item 6: in realtime the world does not wait for a slow learner.
/// A learner that sleeps 30 ms (over the 20 ms budget at 100 Hz) on some
/// states runs a push-task fold against a free-running world: the report
/// counts exactly the states it slept on as over budget, and a second
/// client of the world saw it publish every state, 10 physics steps apart,
/// throughout (a world waiting for its learner would have stalled).
#[test]
fn a_learner_over_budget_in_realtime_is_counted_and_the_world_never_waits() {
    use pushlearn_cli::experiment::push_task::protocol::{Protocol, Variant};
    use pushlearn_cli::experiment::run::{push_task, Plan};
    use pushlearn_cli::experiment::workers::WorldSource;
    use pushlearn_cli::experiment::{Mode, LATENCY_MAX_STEPS};
    use std::sync::atomic::{AtomicBool, Ordering};

    // 2000 steps per wall-clock second: 200 states a second, so that the
    // fold takes a quarter of the thesis's 500-step pace.
    let world = Daemon::start(&["--mode", "realtime", "--real-time-rate", "2000"]);
    let done = std::sync::Arc::new(AtomicBool::new(false));
    let addr = world.addr;
    let observer = {
        let done = std::sync::Arc::clone(&done);
        thread::spawn(move || {
            let runtime = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
                .expect("a runtime");
            runtime.block_on(async {
                let mut client = SimClient::connect(addr).await.expect("observer connects");
                let mut seen = Vec::new();
                while !done.load(Ordering::SeqCst) {
                    let state = client.next_state().await.expect("a state");
                    seen.push((state.publish_seq, state.step));
                }
                seen
            })
        })
    };
    let model = Sleepy {
        inner: GateModel::new(GateConfig::hz100()),
        predictions: Default::default(),
        slept: Default::default(),
    };
    let slept = std::sync::Arc::clone(&model.slept);
    let plan = Plan {
        mode: Mode::Realtime,
        latency_max: LATENCY_MAX_STEPS,
        workers: 1,
        source: WorldSource::Connect(addr.to_string()),
        seed: 1,
        model: "sleepy gate".into(),
        learner: None,
        runs: None,
        processes: None,
        recipe: None,
    };
    let report = push_task(
        model,
        &Protocol::new(Variant::Random, 0),
        &[1],
        1,
        &plan,
        |_| {},
    )
    .expect("the realtime push task runs");
    done.store(true, Ordering::SeqCst);
    let seen = observer.join().expect("the observer");

    let slept = slept.load(Ordering::SeqCst);
    let timing = report.run.timing.as_ref().expect("timing");
    assert!(slept >= 20, "only {slept} sleeps");
    assert_eq!(timing.too_slow, slept, "{timing:?}");
    assert_eq!(report.run.budget_seconds, 0.02);

    // Every state the world published, at its rate: consecutive
    // publish_seq, 10 steps (1000 / 100 Hz) apart except across a reset
    // (which restarts the step counter).
    assert!(
        seen.len() as u64 >= report.run.messages,
        "{} < {}",
        seen.len(),
        report.run.messages
    );
    for pair in seen.windows(2) {
        let ((seq0, step0), (seq1, step1)) = (pair[0], pair[1]);
        assert_eq!(seq1, seq0 + 1, "{pair:?}");
        assert!(step1 == step0 + 10 || step1 <= 10, "{pair:?}");
    }
}
