//! The real `pushlearn-sim` binary.

use std::io::{BufRead, BufReader, Read};
use std::net::SocketAddr;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use pushlearn::client::SimClient;
use pushlearn::wire::pb::client_message::Payload;
use pushlearn::wire::TimingMode;

use super::support::LIMIT;

fn pushlearn_sim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pushlearn-sim"))
}

/// Starts the daemon with `args` and reads the address it printed.
fn spawn(args: &[&str]) -> (Child, SocketAddr) {
    let mut child = pushlearn_sim()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start pushlearn-sim");
    let stdout = child.stdout.take().expect("piped stdout");
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    let line = rx.recv_timeout(LIMIT).unwrap_or_else(|_| {
        let _ = child.kill();
        panic!("pushlearn-sim printed no address within {LIMIT:?}")
    });
    let addr = line
        .trim_end()
        .strip_prefix("listening on ")
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("unexpected first line: {line:?}"));
    (child, addr)
}

fn wait(child: &mut Child) -> std::process::ExitStatus {
    let deadline = Instant::now() + LIMIT;
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            return status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("pushlearn-sim did not stop within {LIMIT:?}");
        }
        thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn the_binary_serves_on_a_free_port_and_stops_cleanly_on_sigterm() {
    // A bare `pushlearn-sim` is `pushlearn-sim serve`.
    let (mut child, addr) = spawn(&["--port", "0", "--mode", "lockstep", "--rate", "10"]);
    assert!(
        addr.ip().is_loopback(),
        "binds 127.0.0.1 by default: {addr}"
    );
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async {
        let mut client = SimClient::connect(addr).await.expect("connect");
        assert_eq!(client.hello().timing(), Ok(TimingMode::Lockstep));
        client
            .command(Payload::move_(0.0, 0.5))
            .await
            .expect("move");
        let state = client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
        assert_eq!(state.step, 100);
    });
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill -TERM");
    assert!(status.success());
    let status = wait(&mut child);
    assert!(status.success(), "exit status after SIGTERM: {status:?}");
}

#[test]
fn with_stop_with_stdin_the_world_serves_while_its_stdin_is_open_and_stops_when_it_closes() {
    let mut child = pushlearn_sim()
        .args([
            "serve",
            "--port",
            "0",
            "--mode",
            "lockstep",
            "--stop-with-stdin",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pushlearn-sim");
    let stdin = child.stdin.take().expect("piped stdin");
    let mut stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
    let mut line = String::new();
    stdout.read_line(&mut line).expect("the listening line");
    let addr: SocketAddr = line
        .trim_end()
        .strip_prefix("listening on ")
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("unexpected first line: {line:?}"));
    // Still serving a while after start-up: the open pipe keeps it up.
    thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().expect("wait").is_none(), "stopped early");
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    runtime.block_on(async {
        let mut client = SimClient::connect(addr).await.expect("connect");
        let state = client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
        assert_eq!(state.step, 10);
    });
    drop(stdin);
    let status = wait(&mut child);
    assert!(
        status.success(),
        "exit status after stdin closed: {status:?}"
    );
    let mut log = String::new();
    child
        .stderr
        .take()
        .expect("piped stderr")
        .read_to_string(&mut log)
        .expect("stderr");
    assert!(log.contains("standard input closed"), "{log}");
}

fn refused(args: &[&str]) -> String {
    let mut child = pushlearn_sim()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pushlearn-sim");
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("piped stderr")
        .read_to_string(&mut stderr)
        .expect("stderr");
    let status = wait(&mut child);
    assert!(!status.success(), "{args:?} should fail");
    stderr
}

#[test]
fn bad_settings_are_refused_with_a_reason() {
    let stderr = refused(&["serve", "--port", "0", "--rate", "30"]);
    assert!(stderr.contains("30 Hz does not divide 1000"), "{stderr}");
    let stderr = refused(&["serve", "--port", "0", "--latency-max", "5"]);
    assert!(stderr.contains("add --mode lockstep"), "{stderr}");
    let stderr = refused(&["serve", "--port", "0", "--scene", "no_such_scene"]);
    assert!(stderr.contains("no_such_scene"), "{stderr}");
}
