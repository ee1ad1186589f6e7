//! Orientations on the wire: the vocabulary's
//! ([`pushlearn_core::orientation`]), re-exported where the protocol's users
//! have always found them. The learner reads a yaw with the same function,
//! so the wire and the learner cannot drift apart.

pub use pushlearn_core::orientation::{from_yaw, normalise, yaw};
