//! pushlearn models: the learner side of the system (`spec/README.md` §1).
//!
//! Pure and deterministic: no I/O, no protobuf, no global state.
//!
//! * [`types`]: what the daemon and the experiment driver exchange with a
//!   model (frames, object states, actions, poses, targets);
//! * [`features`]: parsing and every feature computation of `features.md`;
//! * [`model`]: the [`Model`] trait both learners implement.

pub mod features;
pub mod model;
pub mod types;

pub use features::ParseError;
pub use model::{stat_keys, MapCounts, Model, ModelStats};
pub use types::{
    object_name, Action, Frame, ObjectState, Observation, Poses, Target, TargetError,
    TrackedObject, ACTUATOR_ID, ACTUATOR_NAME, BLUE_ID, BLUE_NAME, RED_ID, RED_NAME,
};
