//! Compiles `proto/pushlearn.proto` and `proto/learner.proto` into the root library without a system
//! `protoc`: protox parses the schema, prost-build generates the Rust types.

use std::error::Error;
use std::path::PathBuf;

use protox::prost::Message;

const PROTO_DIR: &str = "proto";
/// The world protocol, and the learner protocol that imports it.
const PROTO_FILES: [&str; 2] = ["pushlearn.proto", "learner.proto"];

fn main() -> Result<(), Box<dyn Error>> {
    for file in PROTO_FILES {
        println!("cargo:rerun-if-changed={PROTO_DIR}/{file}");
    }

    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").ok_or("OUT_DIR is not set")?);
    let fds = protox::compile(PROTO_FILES, [PROTO_DIR])?;

    // The descriptor without source positions is what protoc embeds in the code
    // it generates; exported so that clients in other languages (the Python
    // example) can build their message classes from exactly this schema.
    for name in PROTO_FILES {
        let file = fds
            .file
            .iter()
            .find(|f| f.name.as_deref() == Some(name))
            .ok_or_else(|| format!("protox returned no descriptor for {name}"))?;
        let mut bare = file.clone();
        bare.source_code_info = None;
        let stem = name.trim_end_matches(".proto");
        std::fs::write(
            out_dir.join(format!("{stem}.descriptor.bin")),
            bare.encode_to_vec(),
        )?;
    }

    // Source info stays in for prost-build: it turns the .proto comments into
    // rustdoc on the generated types.
    prost_build::Config::new().compile_fds(fds)?;
    Ok(())
}
