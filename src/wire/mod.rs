//! The wire protocol between the world daemon and its clients.
//!
//! Every message is one frame: a 4-byte big-endian length followed by that
//! many bytes of one protobuf envelope, [`pb::ClientMessage`] from client to
//! world and [`pb::ServerMessage`] from world to client. `docs/protocol.md`
//! describes the bytes and the semantics; this module is the Rust side of it:
//!
//! * [`pb`]: the generated message types;
//! * [`codec`]: framing with a hard [`MAX_FRAME_SIZE`];
//! * [`connection`]: typed reader/writer halves over any byte stream;
//! * [`validate()`]: the state-independent checks a world runs on every
//!   command on arrival (a client runs them before sending);
//! * [`message`]: constructors such as [`pb::ClientMessage::move_`];
//! * [`orientation`]: a planar yaw as the wire's quaternion, and back.

pub mod codec;
pub mod connection;
pub mod message;
pub mod orientation;
pub mod pb;
pub mod validate;

pub use codec::{
    decode_stream, encode_frame, FrameDecoder, FrameEncoder, WireError, LENGTH_PREFIX_SIZE,
    MAX_FRAME_SIZE,
};
pub use connection::{ClientConnection, Connection, FrameReader, FrameWriter, ServerConnection};
pub use message::TimingMode;
pub use validate::{validate, InvalidCommand};

/// Substring that marks a non-physical ghost pose (`docs/spec/protocol.md` §3): the
/// world never simulates such a body and learners skip it.
pub const GHOST_MARKER: &str = "Shadow";

/// Suffix after [`GHOST_MARKER`] of the ghost that marks a Move-to-Target
/// goal: `blockAShadowTarget` is the target pose of `blockA`, and the world
/// gives it blockA's id (docs/protocol.md §3, docs/viewer.md). A ghost
/// without suffix (`blockAShadow`) is a predicted pose.
pub const TARGET_GHOST_SUFFIX: &str = "Target";
