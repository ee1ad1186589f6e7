//! `pushlearn reproduce`: `--check` names the first value a stale document
//! differs in, and a regeneration writes the committed bytes again.

use std::path::Path;

use serde_json::Value;

use crate::daemon::binary;
use crate::experiment::TempDir;
use crate::process::{repo_root, run, text};

fn reproduce(root: &Path, extra: &[&str]) -> std::process::Output {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .args(["reproduce", "--quick", "--root"])
        .arg(root)
        .arg("--sim-bin")
        .arg(binary())
        .args(extra);
    run(command)
}

/// The committed quick documents, copied under `root`, with one value
/// changed: the check fails naming that value and both numbers, and a
/// regeneration restores every committed file byte for byte (the results
/// do not depend on the build profile or on where they are written).
#[test]
fn quick_check_names_a_changed_value_and_regeneration_restores_the_committed_bytes() {
    let root = TempDir::new("reproduce");
    let committed = repo_root().join("docs/results/quick");
    let copy = root.0.join("docs/results/quick");
    std::fs::create_dir_all(&copy).expect("docs/results/quick in the temp root");
    let mut names = Vec::new();
    for item in std::fs::read_dir(&committed).expect("committed quick results") {
        let path = item.expect("listing").path();
        if path.extension().is_some_and(|e| e == "json") {
            let name = path.file_name().expect("a file name").to_owned();
            std::fs::copy(&path, copy.join(&name)).expect("copy");
            names.push(name);
        }
    }
    assert!(names.len() >= 9, "{names:?}");
    // The reduced ablation's plan, which the reproduction runs as a sweep.
    let sweeps = root.0.join("sweeps");
    std::fs::create_dir_all(&sweeps).expect("sweeps/ in the temp root");
    std::fs::copy(
        repo_root().join("sweeps/ablation-ci.toml"),
        sweeps.join("ablation-ci.toml"),
    )
    .expect("copy the sweep file");

    let target = copy.join("push-task-gate.json");
    let mut document: Value =
        serde_json::from_str(&std::fs::read_to_string(&target).expect("read")).expect("JSON");
    let value = &mut document["results"][2]["block_pos_err"]["mean"];
    let original = value.as_f64().expect("a number");
    let changed = original + 0.001;
    *value = Value::from(changed);
    std::fs::write(
        &target,
        serde_json::to_string_pretty(&document).expect("JSON"),
    )
    .expect("write");

    let check = reproduce(&root.0, &["--check"]);
    let stderr = text(&check.stderr);
    assert!(!check.status.success(), "the check passed:\n{stderr}");
    let expected = format!(
        "push-task-gate.json: results[2].block_pos_err.mean: committed {changed}, now {original}"
    );
    assert!(stderr.contains(&expected), "{expected}\nnot in:\n{stderr}");
    assert!(stderr.contains("(1 stale)"), "{stderr}");

    let regenerated = reproduce(&root.0, &[]);
    assert!(
        regenerated.status.success(),
        "{}",
        text(&regenerated.stderr)
    );
    for name in &names {
        let a = std::fs::read(committed.join(name)).expect("committed");
        let b = std::fs::read(copy.join(name)).expect("regenerated");
        assert!(a == b, "{name:?} differs from the committed file");
    }
}
