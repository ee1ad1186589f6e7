//! The Python example client: its generated module must match the schema,
//! and the script must work against the real daemon.

use std::path::PathBuf;
use std::process::Command;

use pushlearn::wire::pb;

use crate::daemon::{self, Daemon};
use crate::process::{run, text};

fn example_dir() -> PathBuf {
    crate::process::repo_root().join("examples").join("python")
}

/// The generated modules of the Python package: one per schema file.
struct Generated {
    /// File name in `python/pushlearn/_proto/`.
    file: &'static str,
    schema: &'static str,
    descriptor: &'static [u8],
    /// What the descriptor pool must hold first (the schema's imports).
    imports: &'static str,
}

const GENERATED: [Generated; 2] = [
    Generated {
        file: "pushlearn_pb2.py",
        schema: "proto/pushlearn.proto",
        descriptor: pb::FILE_DESCRIPTOR,
        imports: "",
    },
    Generated {
        file: "learner_pb2.py",
        schema: "proto/learner.proto",
        descriptor: pb::learner::FILE_DESCRIPTOR,
        imports: "from . import pushlearn_pb2 as _pushlearn_pb2  # noqa: F401  (imported schema)\n",
    },
];

fn proto_dir() -> PathBuf {
    crate::process::repo_root()
        .join("python")
        .join("pushlearn")
        .join("_proto")
}

/// A generated module as it must be for the current schema.
fn render_pb2(generated: &Generated) -> String {
    let mut literal = String::new();
    for chunk in generated.descriptor.chunks(48) {
        literal.push_str("    b\"");
        for &byte in chunk {
            match byte {
                b'"' | b'\\' => literal.push_str(&format!("\\{}", byte as char)),
                0x20..=0x7e => literal.push(byte as char),
                _ => literal.push_str(&format!("\\x{byte:02x}")),
            }
        }
        literal.push_str("\"\n");
    }
    let module = generated.file.trim_end_matches(".py");
    format!(
        r#"# Generated from {schema} by pushlearn's test suite. DO NOT EDIT.
#
# After changing the schema, regenerate with
#     PUSHLEARN_BLESS=1 cargo test --test e2e python::
# (the suite fails while this file and the schema disagree).
"""Message classes of {schema}.

The bytes below are the schema's ``FileDescriptorProto``, exactly as the Rust
crate embeds it. The classes are built from it at import time, as
protoc-generated modules do, so no protoc is needed: only the ``protobuf``
package (3.20 or newer).
"""

from google.protobuf import descriptor_pool as _descriptor_pool
from google.protobuf.internal import builder as _builder

{imports}
_SERIALIZED_FILE = (
{literal})

DESCRIPTOR = _descriptor_pool.Default().AddSerializedFile(_SERIALIZED_FILE)
_builder.BuildMessageAndEnumDescriptors(DESCRIPTOR, globals())
_builder.BuildTopDescriptorsAndMessages(DESCRIPTOR, "pushlearn._proto.{module}", globals())
"#,
        schema = generated.schema,
        imports = generated.imports,
    )
}

#[test]
fn generated_modules_match_the_schema() {
    for generated in &GENERATED {
        let path = proto_dir().join(generated.file);
        let expected = render_pb2(generated);
        if std::env::var_os("PUSHLEARN_BLESS").is_some() {
            std::fs::create_dir_all(proto_dir()).expect("create python/pushlearn/_proto");
            std::fs::write(&path, &expected).expect("write the generated module");
        }
        let actual = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            actual == expected,
            "{} does not match {}; regenerate it with\n    \
             PUSHLEARN_BLESS=1 cargo test --test e2e python::",
            path.display(),
            generated.schema
        );
    }
}

/// `python3` if it can be started, else `None` (the test is then skipped).
fn python3() -> Option<Command> {
    let probe = Command::new("python3").arg("--version").output();
    match probe {
        Ok(out) if out.status.success() => {
            let mut command = Command::new("python3");
            // Keep __pycache__ out of the source tree.
            command.env("PYTHONDONTWRITEBYTECODE", "1");
            Some(command)
        }
        _ => None,
    }
}

/// Runs `client.py` against a daemon started with `args`; returns the
/// blue block's final `(x, y, yaw)` as printed (4 decimals).
fn run_client_against(args: &[&str]) -> Option<[String; 3]> {
    let Some(mut python) = python3() else {
        eprintln!("SKIPPED: python3 is not installed, so examples/python/client.py was not run");
        return None;
    };
    let daemon = Daemon::start(args);
    python
        .arg(example_dir().join("client.py"))
        .arg("--port")
        .arg(daemon.addr.port().to_string());
    let output = run(python);
    let stderr = text(&output.stderr);
    assert!(
        !stderr.contains("No module named 'google'"),
        "the Python protobuf package is missing: run `python3 -m pip install -r examples/python/requirements.txt` \
         (scripts/ensure-deps.sh --test does)\n{stderr}"
    );
    let stdout = text(&output.stdout);
    assert!(
        output.status.success(),
        "client.py failed ({:?})\nstdout:\n{stdout}\nstderr:\n{stderr}",
        output.status
    );
    let last = stdout.lines().last().unwrap_or_default();
    let pose = last
        .strip_prefix("blockA (blue block) after 150 states: ")
        .unwrap_or_else(|| panic!("unexpected output:\n{stdout}"));
    let value = |key: &str| {
        pose.split_whitespace()
            .find_map(|field| field.strip_prefix(key))
            .unwrap_or_else(|| panic!("no {key} in {last}"))
            .to_owned()
    };
    Some([value("x="), value("y="), value("yaw=")])
}

#[test]
fn client_py_in_lockstep_reproduces_the_calibration_push() {
    let Some(printed) = run_client_against(&["--mode", "lockstep"]) else {
        return;
    };
    // The script's run (reset, actuator at x0 = 0, Move (0, 0.5), 150
    // states at 100 Hz) is the sweep's run from x0 = 0, bit for bit.
    let sweep = daemon::run(&["sweep", "--json"]);
    assert!(sweep.status.success(), "{}", text(&sweep.stderr));
    let rows: Vec<serde_json::Value> =
        serde_json::from_slice(&sweep.stdout).expect("the sweep's JSON");
    let centre = rows
        .iter()
        .find(|row| row["x0"] == 0.0)
        .expect("a run from x0 = 0");
    let expected = ["block_x", "block_y", "block_yaw"]
        .map(|key| format!("{:.4}", centre[key].as_f64().expect("a number")));
    assert_eq!(printed, expected);
}

#[test]
fn client_py_in_realtime_pushes_the_block() {
    let Some([x, y, _]) = run_client_against(&["--mode", "realtime", "--real-time-rate", "2000"])
    else {
        return;
    };
    let (x, y): (f64, f64) = (
        x.parse().expect("x is a number"),
        y.parse().expect("y is a number"),
    );
    // Where exactly depends on when the commands arrived, within an interval.
    assert!(
        x.abs() < 0.05 && y > 0.55,
        "pushed forward from (0, 0.25): ({x}, {y})"
    );
}
