//! The new-object experiments (`docs/experiments.md` "New objects"): push
//! tasks in the `objects` scene whose runs are about other objects than
//! the blue block, to see what a model learned about one object is worth
//! for another.
//!
//! Every learner keys what it knows by object id, so a learner told that
//! an object is new starts from nothing: that measures nothing. Instead the
//! learner is shown, in every run, only the actuator and the run's object,
//! under the blue block's id and name ([`View`]). Trained on the blue block
//! and tested on the cylinder, it predicts the cylinder with what it knows
//! of the blue block, which is exactly the carry-over in question.
//!
//! The run's object takes the blue block's start, and the blue block takes
//! the object's parking place behind the start line ([`Object::park`](crate::scene::Object::park)),
//! with two SetPose commands after the world's reset.

use learner::{Frame, BLUE_ID, BLUE_NAME};

use crate::scene::Object;

/// What the learner is shown of a world state during a run about `object`:
/// the actuator, and the object as the blue block; nothing else.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct View {
    pub object: Object,
}

impl View {
    /// The frame the learner sees.
    #[must_use]
    pub fn apply(&self, frame: &Frame) -> Frame {
        let id = self.object.id();
        Frame {
            objects: frame
                .objects
                .iter()
                .filter(|o| o.id == learner::ACTUATOR_ID || o.id == id)
                .map(|o| {
                    let mut o = o.clone();
                    if o.id == id {
                        o.id = BLUE_ID;
                        BLUE_NAME.clone_into(&mut o.name);
                    }
                    o
                })
                .collect(),
        }
    }

    /// The world's body name of what the learner knows as `id`.
    #[must_use]
    pub fn body(&self, id: u32) -> Option<&'static str> {
        if id == BLUE_ID {
            Some(self.object.body())
        } else {
            learner::object_name(id)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use learner::{
        Observation, ACTUATOR_ID, ACTUATOR_NAME, CYLINDER_ID, CYLINDER_NAME, RED_ID, RED_NAME,
    };

    fn observation(name: &str, id: u32, x: f64) -> Observation {
        Observation {
            name: name.into(),
            id,
            position: [x, 0.25, 0.05],
            orientation: [0.0, 0.0, 0.0, 1.0],
            shape: None,
        }
    }

    #[test]
    fn the_learner_sees_the_runs_object_as_the_blue_block_and_nothing_else() {
        let frame = Frame {
            objects: vec![
                observation(ACTUATOR_NAME, ACTUATOR_ID, 0.0),
                observation(BLUE_NAME, BLUE_ID, 1.0),
                observation(RED_NAME, RED_ID, -1.0),
                observation(CYLINDER_NAME, CYLINDER_ID, 0.1),
            ],
        };
        let seen = View {
            object: Object::Cylinder,
        }
        .apply(&frame);
        assert_eq!(
            seen.objects,
            [
                observation(ACTUATOR_NAME, ACTUATOR_ID, 0.0),
                observation(BLUE_NAME, BLUE_ID, 0.1),
            ]
        );
        let blue = View {
            object: Object::Blue,
        };
        assert_eq!(blue.apply(&frame).objects.len(), 2);
        assert_eq!(blue.apply(&frame).objects[1].position[0], 1.0);
        assert_eq!(
            View {
                object: Object::Red
            }
            .body(BLUE_ID),
            Some(RED_NAME)
        );
    }
}
