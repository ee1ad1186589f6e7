//! Child processes that start children of their own (a learner under
//! `sh -c`, a browser with its renderers): started in a process group of
//! their own and stopped with it.

use std::process::{Child, Command, Stdio};

/// Kills `child`'s process group (its group id is its pid: start it with
/// `CommandExt::process_group(0)`), then reaps `child`. Without `unsafe`
/// there is no `killpg` here, so the system's `kill` sends the signal; the
/// child itself is killed directly in any case.
pub fn kill_group(child: &mut Child) {
    let _ = Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    let _ = child.kill();
    let _ = child.wait();
}

/// Sends `child` the signal `name` (as `kill -s` takes it: `TERM`, `INT`)
/// through the system's `kill`: without `unsafe` there is no `kill(2)` here.
///
/// # Errors
/// `kill` cannot be run or fails (the process has been reaped).
pub fn signal(child: &Child, name: &str) -> std::io::Result<()> {
    let status = Command::new("kill")
        .args(["-s", name, &child.id().to_string()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()?;
    if status.success() {
        Ok(())
    } else {
        Err(std::io::Error::other(format!(
            "kill -s {name} {} failed ({status})",
            child.id()
        )))
    }
}
