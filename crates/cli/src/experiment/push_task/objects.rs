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
//! the object's parking place behind the start line ([`Object::park`]),
//! with two SetPose commands after the world's reset.

use learner::{
    Frame, ObjectState, BLUE_ID, BLUE_NAME, CYLINDER_ID, CYLINDER_NAME, RED_ID, RED_NAME,
};
use serde::{Deserialize, Serialize};

/// The scene of the new-object experiments.
pub const SCENE: &str = "objects";

/// An object of the `objects` scene a push-task run can be about.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Serialize,
    Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum Object {
    /// The thesis's blue block, 0.5 × 0.1 × 0.1 m (`blockA`).
    Blue,
    /// The thesis's red block, 0.3 × 0.3 × 0.1 m (`blockB`).
    Red,
    /// A new shape: an upright cylinder, 0.2 m across, 0.1 m tall.
    Cylinder,
}

impl Object {
    /// Every object, in this order in tables.
    pub const ALL: [Object; 3] = [Object::Blue, Object::Red, Object::Cylinder];

    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Object::Blue => "blue",
            Object::Red => "red",
            Object::Cylinder => "cylinder",
        }
    }

    /// The world's id of the object.
    #[must_use]
    pub fn id(self) -> u32 {
        match self {
            Object::Blue => BLUE_ID,
            Object::Red => RED_ID,
            Object::Cylinder => CYLINDER_ID,
        }
    }

    /// The world's body name of the object.
    #[must_use]
    pub fn body(self) -> &'static str {
        match self {
            Object::Blue => BLUE_NAME,
            Object::Red => RED_NAME,
            Object::Cylinder => CYLINDER_NAME,
        }
    }

    /// Where the object waits while another one is pushed: its start in the
    /// `objects` scene (the blue block's is the push task's block start, so
    /// the blue block waits in the place of the object that took it).
    #[must_use]
    pub fn park(self) -> Option<ObjectState> {
        match self {
            Object::Blue => None,
            Object::Red => Some(ObjectState::new(-1.0, -0.8, 0.0)),
            Object::Cylinder => Some(ObjectState::new(1.0, -0.8, 0.0)),
        }
    }
}

/// Which objects a push-task job trains and tests on.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Transfer {
    /// Training run k is about `train[k % train.len()]`.
    pub train: Vec<Object>,
    /// Every test run is about this one.
    pub test: Object,
}

/// Why a [`Transfer`] cannot be run.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TransferError {
    #[error("--train-on names no object")]
    NoTrainingObject,
    #[error("--train-on names {0} twice")]
    Repeated(&'static str),
}

impl Transfer {
    /// Checks the object lists.
    ///
    /// # Errors
    /// No training object, or one named twice.
    pub fn new(train: Vec<Object>, test: Object) -> Result<Self, TransferError> {
        if train.is_empty() {
            return Err(TransferError::NoTrainingObject);
        }
        for (i, object) in train.iter().enumerate() {
            if train[..i].contains(object) {
                return Err(TransferError::Repeated(object.as_str()));
            }
        }
        Ok(Self { train, test })
    }

    /// The object of training run `k` (0-based).
    #[must_use]
    pub fn training_object(&self, k: usize) -> Object {
        // `new` refuses an empty list; a deserialised one falls back to
        // the thesis's object rather than dividing by zero.
        self.train
            .get(k.checked_rem(self.train.len()).unwrap_or(0))
            .copied()
            .unwrap_or(Object::Blue)
    }

    /// The training objects' names joined by `separator`.
    #[must_use]
    pub fn train_names(&self, separator: &str) -> String {
        let names: Vec<&str> = self.train.iter().map(|o| o.as_str()).collect();
        names.join(separator)
    }

    /// `blue+red→cylinder`, for titles and names.
    #[must_use]
    pub fn label(&self) -> String {
        format!("{}→{}", self.train_names("+"), self.test.as_str())
    }

    /// `blue-red-to-cylinder`, for file names.
    #[must_use]
    pub fn slug(&self) -> String {
        format!("{}-to-{}", self.train_names("-"), self.test.as_str())
    }
}

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
    use learner::{Observation, ACTUATOR_ID, ACTUATOR_NAME};

    fn observation(name: &str, id: u32, x: f64) -> Observation {
        Observation {
            name: name.into(),
            id,
            position: [x, 0.25, 0.05],
            orientation: [0.0, 0.0, 0.0, 1.0],
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

    #[test]
    fn training_objects_alternate_and_bad_lists_are_refused() {
        let mix = Transfer::new(vec![Object::Blue, Object::Red], Object::Cylinder).unwrap();
        let runs: Vec<Object> = (0..5).map(|k| mix.training_object(k)).collect();
        assert_eq!(
            runs,
            [
                Object::Blue,
                Object::Red,
                Object::Blue,
                Object::Red,
                Object::Blue
            ]
        );
        assert_eq!(mix.label(), "blue+red→cylinder");
        assert_eq!(mix.slug(), "blue-red-to-cylinder");
        assert_eq!(
            Transfer::new(Vec::new(), Object::Red),
            Err(TransferError::NoTrainingObject)
        );
        assert_eq!(
            Transfer::new(vec![Object::Red, Object::Red], Object::Blue),
            Err(TransferError::Repeated("red"))
        );
    }

    #[derive(Deserialize)]
    struct SceneFile {
        body: Vec<BodyFile>,
    }

    #[derive(Deserialize)]
    struct BodyFile {
        name: String,
        id: u32,
        start: StartFile,
    }

    #[derive(Deserialize)]
    struct StartFile {
        x: f64,
        y: f64,
        yaw: f64,
    }

    #[test]
    fn ids_names_and_parking_places_are_the_scenes() {
        let scene: SceneFile = toml::from_str(include_str!(
            "../../../../../sim-plugin/scenes/objects.toml"
        ))
        .unwrap();
        for object in Object::ALL {
            let body = scene.body.iter().find(|b| b.name == object.body()).unwrap();
            assert_eq!(body.id, object.id());
            let start = ObjectState::new(body.start.x, body.start.y, body.start.yaw);
            match object.park() {
                Some(park) => assert_eq!(park, start, "{}", object.as_str()),
                // The blue block starts where the push task expects a block.
                None => assert_eq!(
                    Some(&start),
                    crate::experiment::driver::push_task_blocks().get(&BLUE_ID)
                ),
            }
        }
    }
}
