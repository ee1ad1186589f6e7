//! Inside each crate, the top-level modules use each other only in the
//! directions `docs/architecture.md` allows: no cycles, no import that runs
//! up. The crate-level twin of `crate_directions.rs`, for the walls cargo
//! does not draw.
//!
//! The graph is read from the sources: every path that starts at the crate's
//! root (`crate::x`, `crate::{x, y}`, `$crate::x`, or a `super::` chain that
//! climbs out of its top-level module) is an edge from the module of the file
//! it is written in to `x`. Comments and string literals are skipped, so a
//! doc link or a message naming a module is not an edge. The crate roots
//! (`lib.rs`, `main.rs`) assemble the modules and may name any of them.
//! Code compiled for tests alone is left out. `MODULE_GRAPH=1 cargo test -p
//! pushlearn-core --test module_directions -- --nocapture` prints every edge
//! it finds.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Each crate's source folder and, for each of its top-level modules, the
/// modules it may use. A module missing from its crate's table fails the
/// test, so a new module is placed on purpose.
/// A crate's top-level modules, each with the modules it may use.
type Table = &'static [(&'static str, &'static [&'static str])];

const CRATES: &[(&str, Table)] = &[
    // The ODE wrapper: the generational handles at the bottom, the world on
    // top.
    (
        "crates/ode/src",
        &[
            ("arena", &[]),
            ("check", &[]),
            ("error", &[]),
            ("init", &[]),
            ("params", &["check"]),
            ("body", &["arena", "check"]),
            ("geom", &["arena", "check"]),
            ("contact", &["check"]),
            (
                "world",
                &["arena", "body", "check", "contact", "geom", "init"],
            ),
        ],
    ),
    // The world: the scene as data, the world on it, what runs it (the
    // calibration sweep, push runs, the daemon), the playback of a
    // recording on the daemon's connection handling, the fuzzing harness
    // over all of them.
    (
        "sim-plugin/src",
        &[
            ("scene", &[]),
            // Objects drawn from distributions, written as scenes.
            ("generate", &["scene"]),
            ("world", &["scene"]),
            ("calibration", &["scene", "world"]),
            ("push_run", &["calibration", "scene", "world"]),
            // Lock-step timing and latency emulation, for the daemon and
            // the embedded world alike.
            ("lockstep", &["world"]),
            ("server", &["lockstep", "scene", "world"]),
            ("replay", &["server"]),
            (
                "untrusted",
                &["lockstep", "replay", "scene", "server", "world"],
            ),
            ("bin", &[]),
        ],
    ),
    // The protocol crate.
    (
        "src",
        &[
            ("duration", &[]),
            ("errors", &[]),
            ("wire", &[]),
            ("recording", &["wire"]),
            ("client", &["duration", "wire"]),
        ],
    ),
    // The memory-based learners.
    (
        "crates/memories/src",
        &[("aitm", &[]), ("tree", &[]), ("aim", &["aitm"])],
    ),
    // The models (on the memories, which are a crate of their own), the
    // evaluation and the test double above them.
    (
        "crates/learner/src",
        &[
            ("types", &[]),
            ("flags", &[]),
            ("features", &["types"]),
            ("keypoints", &["features", "types"]),
            ("planning", &["types"]),
            ("stats", &[]),
            ("model", &["features", "stats", "types"]),
            (
                "gate",
                &["features", "flags", "model", "planning", "stats", "types"],
            ),
            (
                "interaction",
                &["features", "flags", "model", "planning", "stats", "types"],
            ),
            // Not a thesis model: no configuration bits. Its planner stops
            // by the harness's own success criterion (`eval::goal_distance`).
            (
                "hybrid",
                &["eval", "features", "model", "planning", "stats", "types"],
            ),
            // The reference that predicts nothing moves.
            ("still", &["features", "model", "stats", "types"]),
            // The models by name, their options and building them.
            (
                "registry",
                &["flags", "gate", "hybrid", "interaction", "still"],
            ),
            ("eval", &["features", "keypoints", "model", "types"]),
            ("testing", &["features", "model", "stats", "types"]),
        ],
    ),
    (
        "crates/python/src",
        &[
            ("args", &[]),
            ("aitm", &["args"]),
            ("models", &["args"]),
            // Any model of the registry by name, on the typed classes'
            // helpers.
            ("any_model", &["args", "models"]),
            // The world of the daemon in the process (the sim-plugin
            // crate's, so no edges beyond the argument helpers).
            ("world", &["args"]),
            // The Gymnasium environments' step over those worlds.
            ("task", &["args", "world"]),
            // The experiments of `lab` with a Python learner object: the
            // engine's, so no edges inside the crate.
            ("bench", &[]),
        ],
    ),
    // The experiment engine.
    (
        "crates/drive/src",
        &[
            ("process", &[]),
            ("output", &[]),
            // Argument values several command lines share (clap's side of
            // the model registry).
            ("cli_args", &[]),
            ("frame", &[]),
            ("latency", &[]),
            ("scene", &[]),
            // The world predicting itself, a model on the world library
            // (the new-object scene's parking places).
            ("oracle", &["scene"]),
            // The learner protocol's client and server, and which learner
            // an experiment runs.
            ("external", &["frame", "oracle", "process"]),
            // What the experiments measured, as plain data.
            ("results", &["latency", "oracle", "scene"]),
            // The driver, the tasks, the links and workers, and whole
            // experiments into documents.
            (
                "experiment",
                &["external", "frame", "latency", "oracle", "results", "scene"],
            ),
        ],
    ),
    // The experiments, on the engine (whose modules are another crate's,
    // so no edges here).
    (
        "crates/lab/src",
        &[
            // Tables and figures of the documents, and the drawing toolkit.
            ("report", &[]),
            // One folder per experiment: its tables and figures, made with
            // the report's pieces.
            ("experiments", &["report"]),
            ("spec", &["experiments", "report"]),
            // The experiments' arguments, lowered onto a spec: the command
            // line's, a sweep's and `pushlearn.bench`'s.
            ("args", &["report", "spec"]),
            ("sweep", &["report"]),
            (
                "reproduce",
                &["args", "experiments", "report", "spec", "sweep"],
            ),
        ],
    ),
    // The application, on the engine and the experiments (whose modules it
    // re-exports under their old paths; those are other crates', so no
    // edges here).
    (
        "crates/cli/src",
        &[
            // clap's side of the model registry.
            ("models", &[]),
            // The learner daemon runs the engine's driver and Move to
            // Target task (its pretraining and attempts), never reports.
            ("learn", &["models"]),
            ("load", &["learn"]),
            // Tools with figures of their own draw them with the
            // experiments' toolkit.
            ("soak", &["learn", "load"]),
            ("view", &[]),
            // The binary's own module (main.rs): it reaches the library as
            // `pushlearn_cli::…`, never through `crate::`.
            ("cli", &[]),
        ],
    ),
];

/// The workspace's root folder (this crate is `crates/core`).
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, found: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, found);
        } else if path.extension().is_some_and(|x| x == "rs") {
            found.push(path);
        }
    }
}

/// The module path of a file relative to its crate's `src`:
/// `experiment/run.rs` → `[experiment, run]`, `experiment/mod.rs` →
/// `[experiment]`, `lib.rs` → `[]`.
fn module_path(relative: &Path) -> Vec<String> {
    let mut parts: Vec<String> = relative
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if let Some(last) = parts.pop() {
        let stem = last.trim_end_matches(".rs");
        let is_root = parts.is_empty() && (stem == "lib" || stem == "main");
        if stem != "mod" && !is_root {
            parts.push(stem.to_owned());
        }
    }
    parts
}

/// The source with comments and the contents of string and character
/// literals blanked out (lengths kept, so positions stay meaningful).
fn code_only(source: &str) -> Vec<char> {
    let text: Vec<char> = source.chars().collect();
    let mut out = text.clone();
    let mut i = 0;
    let blank = |out: &mut Vec<char>, from: usize, to: usize| {
        for c in &mut out[from..to.min(text.len())] {
            if *c != '\n' {
                *c = ' ';
            }
        }
    };
    while i < text.len() {
        let rest = |k: usize| text.get(i + k).copied();
        match text[i] {
            '/' if rest(1) == Some('/') => {
                let end = (i..text.len())
                    .find(|&j| text[j] == '\n')
                    .unwrap_or(text.len());
                blank(&mut out, i, end);
                i = end;
            }
            '/' if rest(1) == Some('*') => {
                let (mut depth, mut j) = (1, i + 2);
                while j < text.len() && depth > 0 {
                    if text[j] == '/' && text.get(j + 1) == Some(&'*') {
                        depth += 1;
                        j += 1;
                    } else if text[j] == '*' && text.get(j + 1) == Some(&'/') {
                        depth -= 1;
                        j += 1;
                    }
                    j += 1;
                }
                blank(&mut out, i, j);
                i = j;
            }
            'r' if (rest(1) == Some('"') || rest(1) == Some('#'))
                && !text
                    .get(i.wrapping_sub(1))
                    .is_some_and(|c| c.is_alphanumeric() || *c == '_') =>
            {
                let hashes = (i + 1..text.len()).take_while(|&j| text[j] == '#').count();
                if text.get(i + 1 + hashes) != Some(&'"') {
                    i += 1;
                    continue;
                }
                let open = i + 2 + hashes;
                let close: Vec<char> = std::iter::once('"')
                    .chain(std::iter::repeat_n('#', hashes))
                    .collect();
                let end = (open..text.len())
                    .find(|&j| text[j..].starts_with(&close))
                    .map_or(text.len(), |j| j + close.len());
                blank(&mut out, open, end - 1);
                i = end;
            }
            '"' => {
                let mut j = i + 1;
                while j < text.len() && text[j] != '"' {
                    j += if text[j] == '\\' { 2 } else { 1 };
                }
                blank(&mut out, i + 1, j);
                i = j + 1;
            }
            // A character literal ('x', '\n', '\u{..}'), not a lifetime.
            '\'' if rest(2) == Some('\'') || rest(1) == Some('\\') => {
                let end = (i + 2..text.len())
                    .find(|&j| text[j] == '\'')
                    .unwrap_or(text.len());
                blank(&mut out, i + 1, end);
                i = end + 1;
            }
            _ => i += 1,
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The identifier starting at `i` after whitespace, and the index after it.
fn ident_at(code: &[char], mut i: usize) -> (String, usize) {
    while code.get(i).is_some_and(|c| c.is_whitespace()) {
        i += 1;
    }
    let start = i;
    while code.get(i).is_some_and(|&c| is_ident(c)) {
        i += 1;
    }
    (code[start..i].iter().collect(), i)
}

/// The top-level modules a path from the crate's root names, reading from
/// just after `crate::`: one module, or each first name of a `{…}` group.
fn root_names(code: &[char], mut i: usize) -> Vec<String> {
    while code.get(i).is_some_and(|c| c.is_whitespace()) {
        i += 1;
    }
    if code.get(i) != Some(&'{') {
        return vec![ident_at(code, i).0];
    }
    let mut names = Vec::new();
    let (mut depth, mut expect_name) = (0, true);
    while i < code.len() {
        match code[i] {
            '{' => {
                depth += 1;
                expect_name = depth == 1;
            }
            '}' => {
                depth -= 1;
                if depth == 0 {
                    break;
                }
            }
            ',' if depth == 1 => expect_name = true,
            c if expect_name && depth == 1 && is_ident(c) => {
                let (name, end) = ident_at(code, i);
                names.push(name);
                expect_name = false;
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    names
}

/// Whether the `mod` at `i` is compiled for tests alone (`#[cfg(test)]`
/// before it, a visibility between).
fn is_test_only(code: &[char], i: usize) -> bool {
    let before: String = code[..i].iter().collect();
    let before = before.trim_end();
    let before = ["pub(crate)", "pub(super)", "pub"]
        .iter()
        .find_map(|v| before.strip_suffix(v))
        .unwrap_or(before);
    before.trim_end().ends_with("#[cfg(test)]")
}

/// A file's source with comments and literals blanked, and its module path.
struct Source {
    relative: PathBuf,
    path: Vec<String>,
    code: Vec<char>,
}

/// One crate's top-level modules, and the edges `(from, to)` between them,
/// each with the places that make it.
struct CrateGraph {
    modules: BTreeSet<String>,
    edges: BTreeMap<(String, String), Vec<String>>,
}

/// The graph of one crate's top-level modules. Code compiled for tests alone (a `#[cfg(test)]` module,
/// inline or in a file of its own) is left out: a test may use what it
/// needs, and its edges make no cycle in what ships.
fn module_graph(src: &Path) -> CrateGraph {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let sources: Vec<Source> = files
        .iter()
        .map(|file| {
            let relative = file.strip_prefix(src).expect("a file under src").to_owned();
            let text = std::fs::read_to_string(file).expect("a readable source file");
            Source {
                path: module_path(&relative),
                relative,
                code: code_only(&text),
            }
        })
        .collect();
    let modules: BTreeSet<String> = sources
        .iter()
        .filter_map(|s| s.path.first())
        .cloned()
        .collect();
    // Files that hold a module declared `#[cfg(test)] mod name;`.
    let mut test_files: Vec<Vec<String>> = Vec::new();
    for source in &sources {
        let code = &source.code;
        for i in 0..code.len() {
            if (i == 0 || !is_ident(code[i - 1]))
                && code[i..].starts_with(&['m', 'o', 'd', ' '])
                && is_test_only(code, i)
            {
                let (name, after) = ident_at(code, i + 3);
                if code[after..].iter().find(|c| !c.is_whitespace()) == Some(&';') {
                    let mut path = source.path.clone();
                    path.push(name);
                    test_files.push(path);
                }
            }
        }
    }
    let mut edges: BTreeMap<(String, String), Vec<String>> = BTreeMap::new();
    for Source {
        relative,
        path,
        code,
    } in &sources
    {
        let Some(top) = path.first() else {
            continue; // the crate root
        };
        if test_files.iter().any(|t| path.starts_with(t)) {
            continue;
        }
        let line_of = |i: usize| 1 + code[..i].iter().filter(|&&c| c == '\n').count();
        // Inline modules (`mod tests { … }`) deepen the path a `super::`
        // chain climbs: the brace depth at which each one closes, and
        // whether it is compiled for tests alone.
        let mut inline: Vec<(usize, bool)> = Vec::new();
        let mut depth = 0usize;
        let mut i = 0;
        while i < code.len() {
            let c = code[i];
            let word_start = i == 0 || !is_ident(code[i - 1]);
            if c == '{' {
                depth += 1;
            } else if c == '}' {
                depth = depth.saturating_sub(1);
                if inline.last().is_some_and(|&(at, _)| at == depth) {
                    inline.pop();
                }
            } else if word_start
                && code[i..].starts_with(&['m', 'o', 'd'])
                && code.get(i + 3).is_some_and(|c| c.is_whitespace())
            {
                let (name, after) = ident_at(code, i + 3);
                let brace = (after..code.len()).find(|&j| !code[j].is_whitespace());
                if !name.is_empty() && brace.is_some_and(|j| code[j] == '{') {
                    inline.push((depth, is_test_only(code, i)));
                }
            }
            let mut targets = Vec::new();
            if word_start && code[i..].starts_with(&['c', 'r', 'a', 't', 'e', ':', ':']) {
                targets = root_names(code, i + 7);
            } else if word_start && code[i..].starts_with(&['s', 'u', 'p', 'e', 'r', ':', ':']) {
                let mut supers = 0;
                let mut j = i;
                while code[j..].starts_with(&['s', 'u', 'p', 'e', 'r', ':', ':']) {
                    supers += 1;
                    j += 7;
                }
                if supers >= path.len() + inline.len() {
                    targets = root_names(code, j);
                }
                i = j;
            }
            let in_tests = inline.iter().any(|&(_, test)| test);
            // Names at the root that are not modules are re-exports; the
            // module behind one is not named, so it is not an edge.
            for to in targets.into_iter().filter(|to| modules.contains(to)) {
                if &to != top && !in_tests {
                    edges.entry((top.clone(), to)).or_default().push(format!(
                        "{}:{}",
                        relative.display(),
                        line_of(i)
                    ));
                }
            }
            i += 1;
        }
    }
    CrateGraph { modules, edges }
}

/// A cycle among `edges`, as a path that comes back to its start.
fn find_cycle(edges: &BTreeSet<(String, String)>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        edges: &BTreeSet<(String, String)>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == node) {
            let mut cycle = path[at..].to_vec();
            cycle.push(node.to_owned());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_owned());
        for (_, to) in edges.iter().filter(|(from, _)| from == node) {
            if let Some(cycle) = visit(to, edges, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(node.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    edges
        .iter()
        .find_map(|(from, _)| visit(from, edges, &mut Vec::new(), &mut done))
}

#[test]
fn modules_use_each_other_only_in_the_allowed_directions() {
    let mut wrong = Vec::new();
    for (dir, table) in CRATES {
        let allowed: BTreeMap<&str, &[&str]> = table.iter().copied().collect();
        let CrateGraph { modules, edges } = module_graph(&workspace_root().join(dir));
        for module in modules.iter().filter(|m| !allowed.contains_key(m.as_str())) {
            wrong.push(format!(
                "{dir}: module {module} is not in the table of \
                 crates/core/tests/module_directions.rs (add it there and to \
                 docs/architecture.md)"
            ));
        }
        for ((from, to), places) in edges {
            // Modules outside the table are reported above.
            if let Some(may) = allowed.get(from.as_str()) {
                if !may.contains(&to.as_str()) {
                    wrong.push(format!("{dir}: {from} uses {to} at {}", places.join(", ")));
                }
            }
            if std::env::var_os("MODULE_GRAPH").is_some() {
                eprintln!("{dir}: {from} -> {to}");
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "module imports against docs/architecture.md:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_allowed_module_directions_have_no_cycle() {
    for (dir, table) in CRATES {
        let edges: BTreeSet<(String, String)> = table
            .iter()
            .flat_map(|(from, may)| may.iter().map(|to| ((*from).to_owned(), (*to).to_owned())))
            .collect();
        if let Some(cycle) = find_cycle(&edges) {
            panic!("{dir}: the table allows a cycle: {}", cycle.join(" -> "));
        }
        let modules: BTreeSet<&str> = table.iter().map(|(m, _)| *m).collect();
        for (from, to) in &edges {
            assert!(
                modules.contains(to.as_str()),
                "{dir}: {from} may use {to}, which is not in the table"
            );
        }
    }
}

#[test]
fn the_scanner_sees_groups_and_super_chains_and_skips_comments_strings_and_tests() {
    let dir = std::env::temp_dir().join(format!("module-directions-{}", std::process::id()));
    let write = |path: &str, text: &str| {
        let path = dir.join(path);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("a scratch folder");
        std::fs::write(path, text).expect("a scratch file");
    };
    write("lib.rs", "use crate::z;\n");
    write(
        "a/mod.rs",
        "use crate::{b::X, c::{self, Y}, a::Z};\n// use crate::d;\n/* crate::e */\n\
         const S: &str = \"crate::f\";\nconst R: &str = r#\"crate::g\"#;\nconst C: char = '\"';\n\
         fn h() { crate::h2::run(); }\nfn model() {}\nmod tests { use super::super::i; }\n\
         #[cfg(test)]\nmod checks { use crate::t1; }\n#[cfg(test)]\npub(crate) mod helpers;\n",
    );
    write(
        "a/inner.rs",
        "use super::super::j;\nuse super::k;\nuse crate::NotAModule;\n",
    );
    write("a/helpers.rs", "use crate::t2;\n");
    for module in [
        "b", "c", "d", "e", "f", "g", "h2", "i", "j", "t1", "t2", "k",
    ] {
        write(&format!("{module}.rs"), "");
    }
    let edges: BTreeSet<String> = module_graph(&dir)
        .edges
        .into_keys()
        .map(|(from, to)| format!("{from}->{to}"))
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    let expected: BTreeSet<String> = ["a->b", "a->c", "a->h2", "a->i", "a->j"]
        .into_iter()
        .map(str::to_owned)
        .collect();
    assert_eq!(edges, expected);
}
