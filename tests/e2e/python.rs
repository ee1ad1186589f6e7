//! The Python example client: its generated module must match the schema,
//! and the script must work against a world.

use std::path::{Path, PathBuf};
use std::process::Command;

use pushlearn::wire::pb::{self, actuator_command::Command as Actuator, client_message::Payload};
use pushlearn::wire::TimingMode;

use crate::fake_world::BackgroundWorld;
use crate::process::{run, text};

fn example_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join("python")
}

/// `examples/python/pushlearn_pb2.py` as it must be for the current schema.
fn render_pb2(descriptor: &[u8]) -> String {
    let mut literal = String::new();
    for chunk in descriptor.chunks(48) {
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
    format!(
        r#"# Generated from proto/pushlearn.proto by pushlearn's test suite. DO NOT EDIT.
#
# After changing the schema, regenerate with
#     PUSHLEARN_BLESS=1 cargo test --test e2e python::
# (the suite fails while this file and the schema disagree).
"""Message classes of the pushlearn wire protocol (protobuf package ``pushlearn``).

The bytes below are the schema's ``FileDescriptorProto``, exactly as the Rust
crate embeds it (``pushlearn::wire::pb::FILE_DESCRIPTOR``). The classes are
built from it at import time, as protoc-generated modules do, so no protoc is
needed: only the ``protobuf`` package (3.20 or newer).
"""

from google.protobuf import descriptor_pool as _descriptor_pool
from google.protobuf.internal import builder as _builder

_SERIALIZED_FILE = (
{literal})

DESCRIPTOR = _descriptor_pool.Default().AddSerializedFile(_SERIALIZED_FILE)
_builder.BuildMessageAndEnumDescriptors(DESCRIPTOR, globals())
_builder.BuildTopDescriptorsAndMessages(DESCRIPTOR, "pushlearn_pb2", globals())
"#
    )
}

#[test]
fn generated_module_matches_the_schema() {
    let path = example_dir().join("pushlearn_pb2.py");
    let expected = render_pb2(pb::FILE_DESCRIPTOR);
    if std::env::var_os("PUSHLEARN_BLESS").is_some() {
        std::fs::write(&path, &expected).expect("write pushlearn_pb2.py");
    }
    let actual = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        actual == expected,
        "{} does not match proto/pushlearn.proto; regenerate it with\n    \
         PUSHLEARN_BLESS=1 cargo test --test e2e python::",
        path.display()
    );
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

fn run_client_against(timing: TimingMode) {
    let Some(mut python) = python3() else {
        eprintln!("SKIPPED: python3 is not installed, so examples/python/client.py was not run");
        return;
    };
    let world = BackgroundWorld::start(timing);
    python
        .arg(example_dir().join("client.py"))
        .arg("--port")
        .arg(world.addr.port().to_string());
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

    let applied = world.applied();
    let mut commands = applied
        .iter()
        .filter_map(|m| m.payload.as_ref())
        .filter(|p| p.kind() != "advance");
    assert_eq!(commands.next(), Some(&Payload::reset()));
    assert_eq!(
        commands.next(),
        Some(&Payload::set_pose("actuator", [0.0, 0.0, 0.03], 0.0))
    );
    match commands.next() {
        Some(Payload::Actuator(a)) => {
            assert_eq!(a.cmd(), Actuator::Move);
            assert_eq!(a.direction, Some(pb::Vector3d::new(0.0, 0.5, 0.0)));
        }
        other => panic!("expected the move command third, got {other:?}"),
    }
    assert_eq!(commands.next(), None);
    let seqs: Vec<u64> = applied.iter().map(|m| m.seq).collect();
    assert!(seqs.windows(2).all(|w| w[0] < w[1]), "{seqs:?}");

    let last = stdout.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("blockA (blue block) after 150 states:"),
        "{stdout}"
    );
    assert!(
        last.contains("x=0.0000 y=0.2500 z=0.0500 yaw=0.0000"),
        "{stdout}"
    );
    if timing == TimingMode::Lockstep {
        let advances = applied
            .iter()
            .filter(|m| m.payload.as_ref().is_some_and(|p| p.kind() == "advance"));
        assert_eq!(advances.count(), 150);
    }
}

#[test]
fn client_py_runs_against_a_realtime_world() {
    run_client_against(TimingMode::Realtime);
}

#[test]
fn client_py_runs_against_a_lockstep_world() {
    run_client_against(TimingMode::Lockstep);
}
