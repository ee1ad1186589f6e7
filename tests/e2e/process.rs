//! Running child processes (the `pushlearn` binary, python3) with a limit so
//! that a hung child fails its test instead of hanging the suite.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// Generous: only there to turn a hang into a failure.
pub const CHILD_LIMIT: Duration = Duration::from_secs(60);

/// The repository's top level: these tests belong to `crates/cli`, but read
/// the docs, the schema and the examples of the whole repository.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn run(mut command: Command) -> Output {
    command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let description = format!("{command:?}");
    let mut child = command
        .spawn()
        .unwrap_or_else(|err| panic!("cannot start {description}: {err}"));
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            bytes
        })
    };
    let stdout = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let stderr = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let deadline = Instant::now() + CHILD_LIMIT;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if Instant::now() < deadline => thread::sleep(Duration::from_millis(10)),
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                panic!("{description} did not finish within {CHILD_LIMIT:?}");
            }
            Err(err) => panic!("waiting for {description}: {err}"),
        }
    };
    Output {
        status,
        stdout: stdout.join().unwrap_or_default(),
        stderr: stderr.join().unwrap_or_default(),
    }
}

/// `pushlearn ctl --sim ADDR ARGS...`
pub fn ctl(addr: std::net::SocketAddr, args: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .arg("ctl")
        .arg("--sim")
        .arg(addr.to_string())
        .args(args);
    run(command)
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A long-running child (a daemon, the viewer): killed when dropped, its
/// stderr kept to show when a test fails.
pub struct Background {
    name: &'static str,
    child: Child,
    logs: Option<JoinHandle<String>>,
}

impl Background {
    /// Starts `command` and returns it with the first line it prints to
    /// stdout (empty if none comes within [`CHILD_LIMIT`]).
    pub fn start(mut command: Command, name: &'static str) -> (Background, String) {
        let mut child = command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|err| panic!("cannot start {name}: {err}"));
        // Drained all the time: a child blocked on a full log pipe would
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
            let mut stdout = BufReader::new(stdout);
            let _ = stdout.read_line(&mut line);
            let _ = tx.send(line);
            // Keep reading so that later output never blocks the child.
            let _ = std::io::copy(&mut stdout, &mut std::io::sink());
        });
        let line = rx.recv_timeout(CHILD_LIMIT).unwrap_or_default();
        (Background { name, child, logs }, line)
    }

    /// The child's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Waits up to [`CHILD_LIMIT`] for the child to end by itself; its exit
    /// status and log. Panics if it does not end.
    pub fn wait(&mut self) -> (std::process::ExitStatus, String) {
        let deadline = Instant::now() + CHILD_LIMIT;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return (status, self.stop()),
                Ok(None) if Instant::now() < deadline => thread::sleep(Duration::from_millis(10)),
                Ok(None) => {
                    let log = self.stop();
                    panic!(
                        "{} did not end within {CHILD_LIMIT:?}; its log:\n{log}",
                        self.name
                    )
                }
                Err(err) => panic!("waiting for {}: {err}", self.name),
            }
        }
    }

    /// Kills the child and returns its log.
    pub fn stop(&mut self) -> String {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.logs
            .take()
            .and_then(|logs| logs.join().ok())
            .unwrap_or_default()
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let logs = self.stop();
        if thread::panicking() {
            eprintln!("{}'s log:\n{logs}", self.name);
        }
    }
}
