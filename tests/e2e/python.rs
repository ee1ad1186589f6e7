//! The Python package's generated message modules must match the schemas.
//! (The package itself, its `SimClient` against the real daemon included, is
//! tested by its own suite: `python/tests/`, run with pytest.)

use std::path::PathBuf;

use pushlearn::wire::pb;

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
#     PUSHLEARN_BLESS=1 cargo test -p pushlearn-cli --test e2e python::
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
             PUSHLEARN_BLESS=1 cargo test -p pushlearn-cli --test e2e python::",
            path.display(),
            generated.schema
        );
    }
}
