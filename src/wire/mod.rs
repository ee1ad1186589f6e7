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
//! * [`speed`]: the actuator's speed limit, as the world applies it.

pub mod body_name;
pub mod codec;
pub mod connection;
pub mod message;
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
pub use speed::clamp_speed;
pub use validate::{validate, InvalidCommand};

/// No body of a world is farther than this from the origin, in metres, on
/// any axis: the world refuses a SetPose beyond it (nothing in a table-top
/// world lives there, and ODE's collision arithmetic is not meant for such
/// magnitudes), and a learner daemon refuses a state beyond it (a model
/// trained on a jump to 1e296 m predicts NaN).
pub const MAX_POSITION: f64 = 1000.0;

/// No action a learner is asked about is faster than this, in m/s, in
/// either component: a world drives its actuator at its scene's top speed
/// (0.5 m/s in the thesis's world) whatever a Move asks, and a learner
/// daemon refuses an action beyond this (gate+ trained on −7.4e283 m/s
/// predicts NaN).
pub const MAX_ACTION_SPEED: f64 = 1000.0;
