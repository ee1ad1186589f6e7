//! The real world daemon, `pushlearn-sim`, as a child process on a free port.

use std::io::{BufRead, BufReader, Read};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::thread::{self, JoinHandle};

use crate::process::CHILD_LIMIT;

/// `target/<profile>/pushlearn-sim`. A test of the root package cannot use
/// `CARGO_BIN_EXE_` of another package, but cargo builds every binary of the
/// workspace into the directory above this test binary's `deps/`.
pub fn binary() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let profile_dir = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("the test binary lives in target/<profile>/deps");
    let path = profile_dir.join(format!("pushlearn-sim{}", std::env::consts::EXE_SUFFIX));
    assert!(
        path.is_file(),
        "{} does not exist: build the daemon first with `cargo build -p sim-plugin` \
         (`cargo test --workspace` builds it)",
        path.display()
    );
    path
}

/// A running `pushlearn-sim`; killed when dropped.
pub struct Daemon {
    pub addr: SocketAddr,
    child: Child,
    logs: Option<JoinHandle<String>>,
}

impl Daemon {
    /// Starts `pushlearn-sim serve --port 0 ARGS...` and waits for its
    /// `listening on` line.
    pub fn start(args: &[&str]) -> Daemon {
        Daemon::start_on(0, args)
    }

    /// [`Daemon::start`] on `port` (e.g. a restarted world's).
    pub fn start_on(port: u16, args: &[&str]) -> Daemon {
        let mut child = Command::new(binary())
            .args(["serve", "--port", &port.to_string()])
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start pushlearn-sim");
        // Drained all the time: a daemon blocked on a full log pipe would
        // stall the test.
        let logs = child.stderr.take().map(|mut stderr| {
            thread::spawn(move || {
                let mut text = String::new();
                let _ = stderr.read_to_string(&mut text);
                text
            })
        });
        let stdout = child.stdout.take().expect("piped stdout");
        let (tx, rx) = mpsc::channel();
        thread::spawn(move || {
            let mut line = String::new();
            let _ = BufReader::new(stdout).read_line(&mut line);
            let _ = tx.send(line);
        });
        let mut daemon = Daemon {
            addr: SocketAddr::from(([127, 0, 0, 1], 0)),
            child,
            logs,
        };
        let line = rx.recv_timeout(CHILD_LIMIT).unwrap_or_default();
        match line
            .trim_end()
            .strip_prefix("listening on ")
            .and_then(|a| a.parse().ok())
        {
            Some(addr) => daemon.addr = addr,
            None => panic!(
                "pushlearn-sim {args:?} did not say where it listens (first line {line:?}); \
                 its log:\n{}",
                daemon.stop()
            ),
        }
        daemon
    }

    /// Kills the daemon (SIGKILL) and returns its log.
    pub fn stop(&mut self) -> String {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.logs
            .take()
            .and_then(|logs| logs.join().ok())
            .unwrap_or_default()
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let logs = self.stop();
        if thread::panicking() {
            eprintln!("pushlearn-sim's log:\n{logs}");
        }
    }
}

/// `pushlearn-sim ARGS...` to completion.
pub fn run(args: &[&str]) -> std::process::Output {
    let mut command = Command::new(binary());
    command.args(args);
    crate::process::run(command)
}
