//! The vocabulary every pushlearn process shares, at the bottom of the
//! workspace (`docs/architecture.md`): it depends on no crate of ours, so the
//! wire, the world, the learner, the application and the Python extension
//! can all use it without depending on each other.
//!
//! * [`body`]: the scene's body ids and names, ghosts and the bodies a
//!   learner skips;
//! * [`orientation`]: a yaw as the wire's quaternion and back;
//! * [`limits`]: how far and how fast anything in a world can be;
//! * [`motion`]: an action and an object's planar state;
//! * [`observation`]: a published body as a learner sees it, with the rule
//!   for a body published without a pose.
//!
//! Everything here is arithmetic on plain values: no I/O, no protobuf.

pub mod body;
pub mod limits;
pub mod motion;
pub mod named;
pub mod observation;
pub mod orientation;

pub use body::{
    is_skipped, object_name, BodyName, Ghost, GhostKind, ACTUATOR_ID, ACTUATOR_NAME, BLUE_ID,
    BLUE_NAME, CYLINDER_ID, CYLINDER_NAME, GHOST_MARKER, GROUND_NAME, RED_ID, RED_NAME,
    TARGET_GHOST_SUFFIX,
};
pub use limits::{quoted, MAX_ACTION_SPEED, MAX_NAME_BYTES, MAX_POSITION};
pub use motion::{Action, ObjectState};
pub use named::Named;
pub use observation::{BodyShape, Footprint, Frame, Observation};
