//! A model is its folder and one entry in the registry: outside them, only
//! the files listed here may name a model of the registry, each for a
//! reason given beside it. A new file that names a model fails this test
//! (ask the registry instead: `ModelKind::family`, `is_reference`,
//! `report_name`, …), and so does a listed file that no longer names it,
//! so the lists, and `docs/architecture.md` "How to add a model" which
//! quotes them, stay true.
//!
//! What counts: the non-test `.rs`, `.py` and `.pyi` files (not `tests/`,
//! `tests.rs`, `test_*.py`, `conftest.py`, a Rust file's `#[cfg(test)]`
//! module, `fuzz/` or `scripts/`) that name the model: its
//! `ModelKind::Variant`, its types (`VariantModel`, `VariantWorld`,
//! `VariantConfig`, `VariantLearner`), its name in quotes (`"gate"`, or
//! as a report name's head, `"hybrid-…"`), and for a model whose name is
//! no English word, the name anywhere, comments included.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use learner::registry::{ModelKind, Named};

/// Where each model lives: its folder (or file) in the learner crate.
fn home(kind: ModelKind) -> &'static str {
    match kind {
        ModelKind::Gate | ModelKind::GatePlus => "crates/learner/src/gate/",
        ModelKind::Interaction => "crates/learner/src/interaction/",
        ModelKind::Hybrid => "crates/learner/src/hybrid/",
        ModelKind::Still => "crates/learner/src/still.rs",
    }
}

/// The lists every model may be named in: the registry (the one list of
/// models), the learner crate's root (it declares the model's module), the
/// reproduction's manifest and the results page (which publish a row per
/// model), and the extension's stub (its typed classes). A folder ends in
/// `/`.
const LISTS: &[&str] = &[
    "crates/learner/src/registry.rs",
    "crates/learner/src/lib.rs",
    "crates/lab/src/reproduce/manifest.rs",
    "crates/lab/src/reproduce/page/",
    "python/pushlearn/_native.pyi",
];

/// Further files that name one model, and why. Each is a debt or a use the
/// registry cannot answer; a new model needs none of them.
fn further(kind: ModelKind) -> &'static [&'static str] {
    match kind {
        // The typed Python classes, written before `Model` built any model
        // by name.
        ModelKind::Hybrid => &[
            "crates/python/src/lib.rs",
            "crates/python/src/models.rs",
            "python/pushlearn/__init__.py",
            "python/pushlearn/models.py",
        ],
        // A learner written as an example is called `still` after it.
        ModelKind::Still => &[
            "crates/cli/benches/learner_protocol.rs",
            "python/pushlearn/bench.py",
            "python/pushlearn/learner.py",
        ],
        // The fuzz harness's pick of a model; the typed gate class's names.
        ModelKind::GatePlus => &[
            "crates/drive/src/external/untrusted.rs",
            "crates/python/src/models.rs",
            "python/pushlearn/models.py",
        ],
        // The thesis's two models: the families every model's tables,
        // figures and reference numbers follow (`ModelKind::family`), the
        // command line's default, their benchmarks and examples, the fuzz
        // harness's pick, the typed classes.
        ModelKind::Gate => &[
            "crates/cli/examples/cost_growth.rs",
            "crates/cli/src/cli/learn.rs",
            "crates/cli/src/cli/serve_learner.rs",
            "crates/cli/src/learn/state/testing.rs",
            "crates/drive/src/external/untrusted.rs",
            "crates/drive/src/results/mod.rs",
            "crates/lab/src/args.rs",
            "crates/lab/src/report/plot/cost.rs",
            "crates/learner/src/stats.rs",
            "crates/python/src/lib.rs",
            "crates/python/src/models.rs",
            "examples/python/gym_gate.py",
            "python/pushlearn/__init__.py",
            "python/pushlearn/bench.py",
            "python/pushlearn/envs/push.py",
            "python/pushlearn/learner.py",
            "python/pushlearn/models.py",
            "sim-plugin/benches/gate_model.rs",
        ],
        ModelKind::Interaction => &[
            "crates/cli/examples/cost_growth.rs",
            "crates/drive/src/external/untrusted.rs",
            "crates/lab/src/report/plot/cost.rs",
            "crates/python/src/lib.rs",
            "crates/python/src/models.rs",
            "python/pushlearn/__init__.py",
            "python/pushlearn/models.py",
            "sim-plugin/benches/interaction_model.rs",
        ],
    }
}

/// Whether `file` is in one of the [`LISTS`].
fn listed(file: &str) -> bool {
    LISTS
        .iter()
        .any(|l| file == *l || (l.ends_with('/') && file.starts_with(l)))
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The non-test sources under `dir`, relative to the repository.
fn sources(root: &Path, dir: &Path, found: &mut Vec<String>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            let skip = name.starts_with('.')
                || ["target", "tests", "test", "fuzz", "scripts", "build"].contains(&name)
                || name.ends_with(".egg-info")
                || name == "__pycache__";
            if !skip {
                sources(root, &path, found);
            }
            continue;
        }
        let code = name.ends_with(".rs") || name.ends_with(".py") || name.ends_with(".pyi");
        let test = name == "tests.rs" || name.starts_with("test_") || name == "conftest.py";
        if code && !test {
            let relative = path.strip_prefix(root).expect("under the repository");
            found.push(relative.to_string_lossy().replace('\\', "/"));
        }
    }
}

/// The text of `file` without its `#[cfg(test)]` modules.
fn code(root: &Path, file: &str) -> String {
    let text = std::fs::read_to_string(root.join(file)).unwrap_or_default();
    if !file.ends_with(".rs") {
        return text;
    }
    let lines: Vec<&str> = text.lines().collect();
    let end = lines
        .windows(2)
        .position(|w| w[0].trim() == "#[cfg(test)]" && w[1].trim_start().starts_with("mod "))
        .unwrap_or(lines.len());
    lines[..end].join("\n")
}

/// Whether `text` names `kind`.
fn names(text: &str, kind: ModelKind) -> bool {
    let variant = format!("{kind:?}");
    let name = kind.name();
    let word = |text: &str, needle: &str| {
        let identifier = |c: char| c.is_alphanumeric() || c == '_';
        text.match_indices(needle).any(|(i, _)| {
            let before = text[..i].chars().next_back();
            let after = text[i + needle.len()..].chars().next();
            !before.is_some_and(identifier) && !after.is_some_and(identifier)
        })
    };
    let typed = ["Model", "World", "Config", "Learner"]
        .iter()
        .any(|suffix| text.contains(&format!("{variant}{suffix}")));
    let english = ["gate", "interaction", "still"].contains(&name);
    word(text, &format!("ModelKind::{variant}"))
        || typed
        || text.contains(&format!("\"{name}\""))
        || text.contains(&format!("\"{name}-"))
        || (!english && !name.contains('+') && word(&text.to_lowercase(), name))
}

#[test]
fn only_the_lists_and_the_models_folder_name_a_model() {
    let root = repo();
    let mut files = Vec::new();
    for dir in ["crates", "python", "examples", "sim-plugin", "src"] {
        sources(&root, &root.join(dir), &mut files);
    }
    files.push("build.rs".to_owned());
    assert!(files.len() > 100, "found only {} sources", files.len());
    let texts: Vec<(String, String)> = files.iter().map(|f| (f.clone(), code(&root, f))).collect();
    let mut wrong = Vec::new();
    for &kind in ModelKind::ALL {
        let allowed: BTreeSet<&str> = further(kind).iter().copied().collect();
        let found: BTreeSet<&str> = texts
            .iter()
            .filter(|(file, text)| {
                !file.starts_with(home(kind)) && !listed(file) && names(text, kind)
            })
            .map(|(file, _)| file.as_str())
            .collect();
        for file in found.difference(&allowed) {
            wrong.push(format!("{file} names the {kind} model"));
        }
        for file in allowed.difference(&found) {
            wrong.push(format!(
                "{file} is listed for the {kind} model but no longer names it"
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "ask the registry instead, or list the file with its reason:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_name_rules_find_what_they_should() {
    assert!(names("let k = ModelKind::Hybrid;", ModelKind::Hybrid));
    assert!(names("// the hybrid model", ModelKind::Hybrid));
    assert!(names("x: StillModel", ModelKind::Still));
    assert!(names(r#"["gate", "x"]"#, ModelKind::Gate));
    assert!(names("ModelKind::GatePlus =>", ModelKind::GatePlus));
    assert!(!names("ModelKind::GatePlus =>", ModelKind::Gate));
    assert!(!names("a gate that is still open", ModelKind::Gate));
    assert!(!names("a gate that is still open", ModelKind::Still));
    assert!(!names("hybridisation", ModelKind::Hybrid));
    let registry = code(&repo(), "crates/learner/src/registry.rs");
    assert!(registry.contains("pub enum ModelKind") && !registry.contains("mod tests"));
}
