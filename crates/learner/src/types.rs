//! Types shared by every model, the daemon and the experiment driver.
//!
//! Nothing here knows about protobuf: the daemon converts wire messages into a
//! [`Frame`] of [`Observation`]s, the models parse those (`docs/spec/features.md` §1) into
//! object states, and everything a model hands back for scoring or display is a
//! model-agnostic [`Poses`].

use std::collections::BTreeMap;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

// The bodies' ids and names are the vocabulary's, shared with the wire, the
// world and the Python extension; re-exported where the learner's users find
// them.
pub use pushlearn_core::body::{
    object_name, ACTUATOR_ID, ACTUATOR_NAME, BLUE_ID, BLUE_NAME, CYLINDER_ID, CYLINDER_NAME,
    RED_ID, RED_NAME,
};
// What a driver hands a model: converted from a published body in one place
// (`pushlearn_core::Observation::published`).
pub use pushlearn_core::{BodyShape, Footprint, Frame, Observation};

// Actions and object states are the vocabulary's, shared with everyone
// who drives or scores a model; re-exported where the learner's users find
// them.
pub use pushlearn_core::motion::{Action, ObjectState};

/// Model-agnostic object states of a world state, real or predicted: what the
/// experiment driver checks start positions against, records and scores
/// (`docs/spec/experiments.md` §2, §7) and what shadows display.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Poses {
    /// The actuator (id [`ACTUATOR_ID`]).
    pub actuator: ObjectState,
    /// Every block, keyed by id (ascending; the gate model processes blocks
    /// in descending id order, `docs/spec/gate-model.md` §1: iterate with `.rev()`).
    pub blocks: BTreeMap<u32, ObjectState>,
}

impl Poses {
    /// State of the object with this id, the actuator included.
    #[must_use]
    pub fn get(&self, id: u32) -> Option<ObjectState> {
        if id == ACTUATOR_ID {
            Some(self.actuator)
        } else {
            self.blocks.get(&id).copied()
        }
    }

    /// All objects, the actuator included, in ascending id order.
    pub fn objects(&self) -> impl Iterator<Item = (u32, ObjectState)> + '_ {
        // The actuator's id (8) is below every block id, but the merge must
        // not rely on that for hand-built values.
        let mut all: Vec<(u32, ObjectState)> = self.blocks.iter().map(|(&i, &s)| (i, s)).collect();
        let at = all.partition_point(|(i, _)| *i < ACTUATOR_ID);
        all.insert(at, (ACTUATOR_ID, self.actuator));
        all.into_iter()
    }
}

/// A Move-to-Target goal: a global pose for a block (`docs/spec/planning.md`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    pub id: u32,
    pub pose: ObjectState,
}

/// Why a [`Target`] cannot be pursued.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum TargetError {
    /// `docs/spec/planning.md` §6: the original raised an error for actuator targets.
    #[error("targets for the actuator (id {ACTUATOR_ID}) are not supported")]
    Actuator,
    #[error("target pose for object {id} is not finite: {pose:?}")]
    NonFinite { id: u32, pose: ObjectState },
    /// The model does not know (or cannot plan for) this object.
    #[error("the model cannot plan for object {id}")]
    UnknownObject { id: u32 },
}

impl Target {
    #[must_use]
    pub const fn new(id: u32, pose: ObjectState) -> Self {
        Self { id, pose }
    }

    /// The model-independent validity checks every `Model::set_target`
    /// implementation should run first.
    pub fn check(&self) -> Result<(), TargetError> {
        if self.id == ACTUATOR_ID {
            return Err(TargetError::Actuator);
        }
        if !self.pose.is_finite() {
            return Err(TargetError::NonFinite {
                id: self.id,
                pose: self.pose,
            });
        }
        Ok(())
    }
}

/// An object as the gate model tracks it: current state `s` and previous state
/// `s_prev`, whose difference is the "velocity" feature (`docs/spec/features.md` §1 step 5,
/// §3.1). How `s_prev` is maintained (including the stale-after-reset quirk) is
/// the gate model's business (`docs/spec/gate-model.md` §2–§4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackedObject {
    pub id: u32,
    pub s: ObjectState,
    pub s_prev: ObjectState,
}

impl TrackedObject {
    /// A freshly parsed object: `s_prev` is a copy of `s` (zero displacement,
    /// `docs/spec/features.md` §1 step 5).
    #[must_use]
    pub const fn fresh(id: u32, s: ObjectState) -> Self {
        Self { id, s, s_prev: s }
    }

    /// `v(o) = o.s[0:2] − o.s_prev[0:2]` (`docs/spec/features.md` §3.1), metres per update.
    #[must_use]
    pub fn velocity(&self) -> Vector2<f64> {
        Vector2::new(self.s.x - self.s_prev.x, self.s.y - self.s_prev.y)
    }

    /// `s_prev := s; s := new` — the in-place move of a record to a newly
    /// observed state (`docs/spec/gate-model.md` §2, §3).
    pub fn advance(&mut self, new: ObjectState) {
        self.s_prev = self.s;
        self.s = new;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_the_world() {
        assert_eq!(object_name(ACTUATOR_ID), Some("actuator"));
        assert_eq!(object_name(BLUE_ID), Some("blockA"));
        assert_eq!(object_name(RED_ID), Some("blockB"));
        assert_eq!(object_name(9), None);
        assert_eq!((ACTUATOR_ID, BLUE_ID, RED_ID), (8, 15, 27));
    }

    #[test]
    // The literals are docs/spec/planning.md §6's example, not approximations of π.
    #[allow(clippy::approx_constant)]
    fn distance_to_does_not_wrap_angles() {
        let a = ObjectState::new(0.0, 0.0, -3.14);
        let b = ObjectState::new(0.0, 0.0, 3.1415);
        assert!((a.distance_to(&b) - 6.2815).abs() < 1e-12);
        let c = ObjectState::new(0.3, 0.4, 0.0);
        assert!((c.distance_to(&ObjectState::default()) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn poses_objects_are_in_id_order_and_get_finds_the_actuator() {
        let mut blocks = BTreeMap::new();
        blocks.insert(RED_ID, ObjectState::new(-0.6, 0.35, 0.0));
        blocks.insert(BLUE_ID, ObjectState::new(0.0, 0.25, 0.0));
        blocks.insert(3, ObjectState::new(1.0, 1.0, 1.0));
        let poses = Poses {
            actuator: ObjectState::new(0.1, 0.0, 0.0),
            blocks,
        };
        let ids: Vec<u32> = poses.objects().map(|(i, _)| i).collect();
        assert_eq!(ids, vec![3, 8, 15, 27]);
        assert_eq!(poses.get(8), Some(ObjectState::new(0.1, 0.0, 0.0)));
        assert_eq!(poses.get(15), Some(ObjectState::new(0.0, 0.25, 0.0)));
        assert_eq!(poses.get(99), None);
    }

    #[test]
    fn tracked_object_velocity_and_advance() {
        let mut o = TrackedObject::fresh(BLUE_ID, ObjectState::new(0.0, 0.25, 0.0));
        assert_eq!(o.velocity(), Vector2::zeros());
        o.advance(ObjectState::new(0.001, 0.255, 0.01));
        assert_eq!(o.s_prev, ObjectState::new(0.0, 0.25, 0.0));
        let v = o.velocity();
        assert!((v.x - 0.001).abs() < 1e-12 && (v.y - 0.005).abs() < 1e-12);
    }

    #[test]
    fn target_check_rejects_actuator_and_non_finite() {
        let ok = Target::new(BLUE_ID, ObjectState::new(0.6, 0.7, -2.1));
        assert_eq!(ok.check(), Ok(()));
        let act = Target::new(ACTUATOR_ID, ObjectState::default());
        assert_eq!(act.check(), Err(TargetError::Actuator));
        let nan = Target::new(BLUE_ID, ObjectState::new(f64::NAN, 0.0, 0.0));
        assert!(matches!(
            nan.check(),
            Err(TargetError::NonFinite { id: 15, .. })
        ));
    }

    #[test]
    fn poses_round_trip_through_json() {
        let mut blocks = BTreeMap::new();
        blocks.insert(BLUE_ID, ObjectState::new(0.0, 0.25, 0.5));
        let poses = Poses {
            actuator: ObjectState::new(0.1, 0.0, 0.0),
            blocks,
        };
        let json = serde_json::to_string(&poses).unwrap();
        let back: Poses = serde_json::from_str(&json).unwrap();
        assert_eq!(back, poses);
    }
}
