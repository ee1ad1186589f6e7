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
//! * [`orientation`]: a planar yaw as the wire's quaternion, and back;
//! * [`BodyName`]: a body's or a ghost's name, parsed;
//! * [`observation`]: a published body as a learner sees it;
//! * [`speed`]: the actuator's speed limit, as the world applies it.

pub mod body_name;
pub mod codec;
pub mod connection;
pub mod message;
pub mod observation;
pub mod orientation;
pub mod pb;
pub mod speed;
pub mod validate;

pub use body_name::{BodyName, Ghost, GhostKind, GHOST_MARKER, TARGET_GHOST_SUFFIX};
pub use codec::{
    decode_stream, encode_frame, raw_frame_codec, FrameDecoder, FrameEncoder, WireError,
    LENGTH_PREFIX_SIZE, MAX_FRAME_SIZE,
};
pub use connection::{ClientConnection, Connection, FrameReader, FrameWriter, ServerConnection};
pub use message::TimingMode;
pub use observation::{frame, Shapes};
pub use speed::clamp_speed;
pub use validate::{validate, InvalidCommand};

// The limits are the vocabulary's: the world and the learner daemon refuse
// beyond the same numbers.
pub use pushlearn_core::{quoted, MAX_ACTION_SPEED, MAX_NAME_BYTES, MAX_POSITION};
