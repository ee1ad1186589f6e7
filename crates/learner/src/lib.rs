//! pushlearn models: the learner side of the system (`docs/spec/README.md` §1).
//!
//! Pure and deterministic: no I/O, no protobuf, no global state.
//!
//! * [`types`]: what the daemon and the experiment driver exchange with a
//!   model (frames, object states, actions, poses, targets);
//! * [`features`]: parsing and every feature computation of `docs/spec/features.md`;
//! * [`aitm`], [`aim`], [`tree`]: the memory-based learners the models are
//!   built from (the Adapted Instantaneous Topological Map, the Averaging
//!   Inverse Model, the draft's decision trees), re-exported from the
//!   `memories` crate;
//! * [`gate`]: the object-state model with gating function
//!   (`docs/spec/gate-model.md`) and its planner (`docs/spec/planning.md` §2);
//! * [`model`]: the [`Model`] trait both learners implement;
//! * [`stats`]: their statistics, typed per model;
//! * [`eval`]: the push-task protocol on the learner's side and its metrics;
//! * [`interaction`]: the pairwise interaction-state model
//!   (`docs/spec/interaction-model.md`);
//! * [`planning`]: the model-independent parts of Move to Target
//!   (`docs/spec/planning.md` §1, §4, §5);
//! * [`registry`]: the models by name, their options as plain data with
//!   their checks, and building an untrained model from them (what the
//!   command line and the Python extension both use);
//! * [`keypoints`]: the thesis draft's key-point score (draft §6.1.2);
//! * [`still`]: the reference that predicts nothing moves;
//! * `testing` (feature `testing`): the [`Model`] test double of every
//!   crate's tests.

pub mod eval;
pub mod features;
pub mod flags;
pub mod gate;
pub mod hybrid;
pub mod interaction;
pub mod keypoints;
pub mod model;
pub mod planning;
pub mod registry;
pub mod stats;
pub mod still;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod types;

pub use memories::{aim, aitm, tree};

pub use aitm::MapStats;
pub use features::ParseError;
pub use gate::{GateConfig, GateModel, GateParams, GateWorld};
pub use hybrid::{HybridConfig, HybridModel, HybridWorld};
pub use interaction::{InteractionConfig, InteractionModel, InteractionParams, InteractionWorld};
pub use model::Model;
pub use stats::{
    AcStats, GateStats, InteractionStats, LargestAc, MapName, ModelStats, OtherStats, ScriptAc,
    StatsError,
};
pub use still::StillModel;
pub use types::{
    object_name, Action, BodyShape, Footprint, Frame, ObjectState, Observation, Poses, Target,
    TargetError, TrackedObject, ACTUATOR_ID, ACTUATOR_NAME, BLUE_ID, BLUE_NAME, CYLINDER_ID,
    CYLINDER_NAME, RED_ID, RED_NAME,
};
