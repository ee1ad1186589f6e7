//! The real world daemon, `pushlearn-sim`, as a child process on a free port.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::Command;

use crate::process::Background;

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
    process: Background,
}

impl Daemon {
    /// Starts `pushlearn-sim serve --port 0 ARGS...` and waits for its
    /// `listening on` line.
    pub fn start(args: &[&str]) -> Daemon {
        Daemon::start_on(0, args)
    }

    /// [`Daemon::start`] on `port` (e.g. a restarted world's).
    pub fn start_on(port: u16, args: &[&str]) -> Daemon {
        let mut command = Command::new(binary());
        command
            .args(["serve", "--port", &port.to_string()])
            .args(args);
        let (mut process, line) = Background::start(command, "pushlearn-sim");
        match line
            .trim_end()
            .strip_prefix("listening on ")
            .and_then(|a| a.parse().ok())
        {
            Some(addr) => Daemon { addr, process },
            None => panic!(
                "pushlearn-sim {args:?} did not say where it listens (first line {line:?}); \
                 its log:\n{}",
                process.stop()
            ),
        }
    }

    /// The daemon's process id.
    pub fn pid(&self) -> u32 {
        self.process.pid()
    }

    /// Kills the daemon (SIGKILL) and returns its log.
    pub fn stop(&mut self) -> String {
        self.process.stop()
    }
}
