//! The thesis's set-up, shared by the experiments, their documents and
//! figures, and the learner daemon: publish rates, the push task's start
//! poses, the z of a SetPose, and the objects of the new-object experiments.
//!
//! It sits below all of them so that a figure drawing a push task's start,
//! or a report naming the objects a job was trained on, need not reach into
//! the code that runs the experiments.

use std::collections::BTreeMap;

use learner::{ObjectState, BLUE_ID, BLUE_NAME, CYLINDER_ID, CYLINDER_NAME, RED_ID, RED_NAME};
use serde::{Deserialize, Serialize};

/// The thesis's model update rate (`docs/spec/experiments.md` §6).
pub const RATE_HZ: u32 = 100;

/// The constant-feedback images' rate (`docs/spec/experiments.md` §3.4,
/// configuration 2), at which a model takes the LOWFREQ thresholds: the
/// model registry's.
pub use learner::registry::LOW_RATE_HZ;

/// z of a SetPose for the actuator and for blocks (`docs/spec/protocol.md` §6).
pub const ACTUATOR_Z: f64 = 0.03;
/// See [`ACTUATOR_Z`].
pub const BLOCK_Z: f64 = 0.05;

/// The actuator's start y of every push-task run (its x is the run's x0).
pub const PUSH_TASK_START_Y: f64 = 0.0;

/// Expected start poses of the blocks in push-task runs (`docs/spec/experiments.md`
/// §2.1; the red block's entry only matters in the two-object scene).
#[must_use]
pub fn push_task_blocks() -> BTreeMap<u32, ObjectState> {
    BTreeMap::from([
        (learner::BLUE_ID, ObjectState::new(0.0, 0.25, 0.0)),
        (learner::RED_ID, ObjectState::new(-0.6, 0.35, 0.0)),
    ])
}

/// The scene of the new-object experiments.
pub const SCENE: &str = "objects";

/// An object of the `objects` scene a push-task run can be about, each
/// described in its [`Named`](pushlearn_core::Named) implementation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Object {
    Blue,
    Red,
    Cylinder,
}

impl pushlearn_core::Named for Object {
    const ALL: &'static [Self] = &Object::ALL;

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            Object::Blue => "The thesis's blue block, 0.5 × 0.1 × 0.1 m (`blockA`)",
            Object::Red => "The thesis's red block, 0.3 × 0.3 × 0.1 m (`blockB`)",
            Object::Cylinder => "A new shape: an upright cylinder, 0.2 m across, 0.1 m tall",
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
        let scene: SceneFile =
            toml::from_str(include_str!("../../../sim-plugin/scenes/objects.toml")).unwrap();
        for object in Object::ALL {
            let body = scene.body.iter().find(|b| b.name == object.body()).unwrap();
            assert_eq!(body.id, object.id());
            let start = ObjectState::new(body.start.x, body.start.y, body.start.yaw);
            match object.park() {
                Some(park) => assert_eq!(park, start, "{}", object.as_str()),
                // The blue block starts where the push task expects a block.
                None => assert_eq!(Some(&start), push_task_blocks().get(&BLUE_ID)),
            }
        }
    }
}
