//! Compiles `proto/pushlearn.proto` into the root library without a system
//! `protoc`: protox parses the schema, prost-build generates the Rust types.

use std::error::Error;
use std::path::PathBuf;

use protox::prost::Message;

const PROTO_DIR: &str = "proto";
const PROTO_FILE: &str = "pushlearn.proto";

fn main() -> Result<(), Box<dyn Error>> {
    println!("cargo:rerun-if-changed={PROTO_DIR}/{PROTO_FILE}");

    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").ok_or("OUT_DIR is not set")?);
    let fds = protox::compile([PROTO_FILE], [PROTO_DIR])?;

    // The descriptor without source positions is what protoc embeds in the code
    // it generates; exported so that clients in other languages (the Python
    // example) can build their message classes from exactly this schema.
    let file = fds
        .file
        .iter()
        .find(|f| f.name.as_deref() == Some(PROTO_FILE))
        .ok_or("protox returned no descriptor for pushlearn.proto")?;
    let mut bare = file.clone();
    bare.source_code_info = None;
    std::fs::write(
        out_dir.join("pushlearn.descriptor.bin"),
        bare.encode_to_vec(),
    )?;

    // Source info stays in for prost-build: it turns the .proto comments into
    // rustdoc on the generated types.
    prost_build::Config::new().compile_fds(fds)?;
    Ok(())
}
