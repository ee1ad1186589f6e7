//! `still`: the reference that predicts that nothing moves (`docs/models.md`,
//! "Reference rows"). Every body of a prediction is where the state it was
//! made from had it, and as an inverse model it never pushes. It learns
//! nothing, so its error is what a task costs a learner that learned
//! nothing: the other end of the scale from the oracles, and the zero of
//! the results' normalised score.

use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::features::{parse_frame_at, ActuatorYaw, ParseError, Precision};
use crate::model::Model;
use crate::stats::{ModelStats, OtherStats};
use crate::types::{Action, Frame, Poses, Target, TargetError};

/// The model that predicts no motion; see the module documentation.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StillModel {
    training_off: bool,
    target: Option<Target>,
}

impl Model for StillModel {
    type World = Poses;

    /// The poses as published, unrounded: the prediction is exactly the
    /// state it was made from.
    fn parse(&self, frame: &Frame) -> Result<Poses, ParseError> {
        parse_frame_at(frame, ActuatorYaw::ForceZero, Precision::Full)
    }

    fn poses(world: &Poses) -> Poses {
        world.clone()
    }

    fn reset_objects(&mut self, _world: &Poses) {}

    fn update(&mut self, _world: &Poses, _action: Action) {}

    fn predict(&self, world: &Poses, _action: Action) -> Poses {
        world.clone()
    }

    fn set_training(&mut self, on: bool) {
        self.training_off = !on;
    }

    fn is_training(&self) -> bool {
        !self.training_off
    }

    /// Any valid target is accepted and kept: a model that never pushes
    /// never reaches it, which is the reference Move to Target needs.
    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        if let Some(t) = &target {
            t.check()?;
        }
        self.target = target;
        Ok(())
    }

    fn has_target(&self) -> bool {
        self.target.is_some()
    }

    fn act(&mut self, _rng: &mut dyn Rng) -> Action {
        Action::ZERO
    }

    fn stats(&self) -> ModelStats {
        ModelStats::Other(OtherStats::default())
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::ForceZero
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{ObjectState, Observation, BLUE_ID};

    fn frame(x: f64) -> Frame {
        let obs = |name: &str, id, x: f64, y| Observation {
            name: name.into(),
            id,
            position: [x, y, 0.05],
            orientation: [0.0, 0.0, 0.0, 1.0],
            shape: None,
        };
        Frame {
            objects: vec![
                obs("actuator", 8, x, 0.0),
                obs("blockA", BLUE_ID, 0.012_345_6, 0.25),
            ],
        }
    }

    #[test]
    fn it_predicts_every_body_where_it_was_and_never_pushes() {
        let mut model = StillModel::default();
        let seen = model.parse(&frame(0.1)).unwrap();
        model.update(&seen, Action::new(0.0, 0.5));
        let mut predicted = model.predict(&seen, Action::new(0.0, 0.5));
        for _ in 0..150 {
            predicted = model.predict(&predicted, Action::new(0.3, 0.5));
        }
        assert_eq!(predicted, seen);
        // Unrounded: what it predicts is what it was shown.
        assert_eq!(
            predicted.blocks[&BLUE_ID],
            ObjectState::new(0.012_345_6, 0.25, 0.0)
        );

        let target = Target::new(BLUE_ID, ObjectState::new(0.3, 0.3, 0.0));
        model.set_target(Some(target)).unwrap();
        assert_eq!(model.act(&mut NeverDrawn), Action::ZERO);
        assert!(model.has_target(), "it never finds a target reached");
        assert_eq!(model.stats(), ModelStats::default());
    }

    /// A generator the model must not draw from: it does not explore.
    struct NeverDrawn;

    impl rand::TryRng for NeverDrawn {
        type Error = std::convert::Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
            unreachable!("the still model drew a random number")
        }
        fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
            unreachable!("the still model drew a random number")
        }
        fn try_fill_bytes(&mut self, _: &mut [u8]) -> Result<(), Self::Error> {
            unreachable!("the still model drew a random number")
        }
    }
}
