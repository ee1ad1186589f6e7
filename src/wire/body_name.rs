//! A body's name as the wire carries it: the vocabulary's
//! ([`pushlearn_core::body`]), re-exported where the protocol's users have
//! always found it.

pub use pushlearn_core::body::{BodyName, Ghost, GhostKind, GHOST_MARKER, TARGET_GHOST_SUFFIX};
