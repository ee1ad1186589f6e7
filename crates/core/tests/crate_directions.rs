//! The workspace's crates depend on each other only in the directions
//! `docs/architecture.md` allows, so a dependency that runs upwards or closes
//! a cycle fails CI instead of waiting for a review.
//!
//! It lives beside the bottom crate because that crate builds in a second and
//! depends on no crate of ours: the check runs whatever state the rest is in.
//! It reads the real graph from `cargo metadata`, not from a copy of the
//! manifests.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each member and the members it may depend on (normal and build
/// dependencies), as `docs/architecture.md` draws them. A new member must be
/// added here and there.
const ALLOWED: &[(&str, &[&str])] = &[
    ("pushlearn-core", &[]),
    ("ode-sys", &[]),
    ("ode", &["ode-sys"]),
    ("mujoco-sys", &[]),
    ("mujoco", &["mujoco-sys"]),
    ("pushlearn", &["pushlearn-core"]),
    ("memories", &[]),
    ("learner", &["memories", "pushlearn-core"]),
    (
        "sim-plugin",
        &["mujoco", "ode", "pushlearn", "pushlearn-core"],
    ),
    (
        "pushlearn-python",
        &[
            "drive",
            "lab",
            "learner",
            "pushlearn",
            "pushlearn-core",
            "sim-plugin",
        ],
    ),
    (
        "drive",
        &["learner", "pushlearn", "pushlearn-core", "sim-plugin"],
    ),
    ("lab", &["drive", "learner"]),
    (
        "pushlearn-cli",
        &[
            "drive",
            "lab",
            "learner",
            "pushlearn",
            "pushlearn-core",
            "sim-plugin",
        ],
    ),
];

/// What tests and benchmarks may use beyond that: never a sink (the
/// application or the Python extension), so no test makes a cycle.
const DEV_ALLOWED: &[(&str, &[&str])] = &[
    ("sim-plugin", &["learner", "sim-plugin"]),
    ("drive", &["learner", "sim-plugin"]),
    ("lab", &["drive", "sim-plugin"]),
    ("pushlearn-cli", &["drive", "learner", "sim-plugin"]),
];

/// What `cargo ARGS --offline` prints, run in this crate; fails the test
/// if cargo fails.
fn cargo(args: &[&str]) -> Vec<u8> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let output = Command::new(cargo)
        .args(args)
        .arg("--offline")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        output.status.success(),
        "cargo {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output.stdout
}

/// Every workspace member and its dependencies on other members, by kind.
fn workspace_graph() -> BTreeMap<String, Vec<(String, String)>> {
    let output = cargo(&["metadata", "--format-version", "1", "--no-deps"]);
    let metadata: serde_json::Value =
        serde_json::from_slice(&output).expect("cargo metadata prints JSON");
    let packages = metadata["packages"].as_array().expect("a package list");
    let members: BTreeSet<&str> = packages.iter().filter_map(|p| p["name"].as_str()).collect();
    packages
        .iter()
        .map(|p| {
            let name = p["name"].as_str().expect("a package name").to_owned();
            let deps = p["dependencies"]
                .as_array()
                .expect("a dependency list")
                .iter()
                .filter_map(|d| {
                    let dep = d["name"].as_str()?;
                    let kind = d["kind"].as_str().unwrap_or("normal");
                    members
                        .contains(dep)
                        .then(|| (dep.to_owned(), kind.to_owned()))
                })
                .collect();
            (name, deps)
        })
        .collect()
}

fn table(
    rows: &[(&'static str, &'static [&'static str])],
) -> BTreeMap<&'static str, &'static [&'static str]> {
    rows.iter().copied().collect()
}

#[test]
fn every_member_depends_only_in_the_allowed_directions() {
    let allowed = table(ALLOWED);
    let dev_allowed = table(DEV_ALLOWED);
    let mut wrong = Vec::new();
    for (member, deps) in workspace_graph() {
        let Some(may) = allowed.get(member.as_str()) else {
            wrong.push(format!(
                "{member} is not in the table of crates/core/tests/crate_directions.rs \
                 (add it there and to docs/architecture.md)"
            ));
            continue;
        };
        let dev_may = dev_allowed.get(member.as_str()).copied().unwrap_or(&[]);
        for (dep, kind) in deps {
            let ok =
                may.contains(&dep.as_str()) || (kind == "dev" && dev_may.contains(&dep.as_str()));
            if !ok {
                wrong.push(format!("{member} depends on {dep} ({kind})"));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "dependencies against docs/architecture.md:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_allowed_directions_have_no_cycle() {
    // Depth-first over the table: a member met again on its own path is a cycle.
    let allowed = table(ALLOWED);
    fn visit<'a>(
        member: &'a str,
        allowed: &BTreeMap<&'a str, &'a [&'a str]>,
        path: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
    ) {
        if done.contains(member) {
            return;
        }
        assert!(
            !path.contains(&member),
            "cycle: {} -> {member}",
            path.join(" -> ")
        );
        path.push(member);
        for dep in allowed.get(member).copied().unwrap_or(&[]) {
            visit(dep, allowed, path, done);
        }
        path.pop();
        done.insert(member);
    }
    let mut done = BTreeSet::new();
    for member in allowed.keys() {
        visit(member, &allowed, &mut Vec::new(), &mut done);
    }
    // The sinks are sinks: nothing may depend on the application or the
    // Python extension.
    for (member, may) in ALLOWED.iter().chain(DEV_ALLOWED) {
        for sink in ["pushlearn-cli", "pushlearn-python"] {
            assert!(
                !may.contains(&sink),
                "{member} may depend on the sink {sink}"
            );
        }
    }
}

/// What `pushlearn` built without default features, the learner daemon and
/// the world tools, must not link: the experiments and their figures, and
/// the viewer's WebSocket and HTTP stack (`docs/architecture.md`).
const NOT_IN_THE_DAEMON: &[&str] = &["lab", "plotters", "tokio-tungstenite", "httparse"];

#[test]
fn the_daemon_build_links_neither_the_experiments_nor_the_viewer() {
    let tree = |features: &[&str]| {
        let mut args = vec!["tree", "-p", "pushlearn-cli", "--edges", "normal,build"];
        args.extend_from_slice(features);
        args.extend_from_slice(&["--prefix", "none", "--format", "{p}"]);
        String::from_utf8(cargo(&args))
            .expect("cargo tree prints UTF-8")
            .lines()
            .filter_map(|line| line.split_whitespace().next().map(str::to_owned))
            .collect::<BTreeSet<_>>()
    };
    let daemon = tree(&["--no-default-features"]);
    let linked: Vec<_> = NOT_IN_THE_DAEMON
        .iter()
        .filter(|name| daemon.contains(**name))
        .collect();
    assert!(
        linked.is_empty(),
        "pushlearn-cli without default features depends on {linked:?}"
    );
    // The check sees what it looks for: the default build has them all.
    let full = tree(&[]);
    for name in NOT_IN_THE_DAEMON {
        assert!(full.contains(*name), "the default build lacks {name}");
    }
}
