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
