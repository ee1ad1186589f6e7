//! The object-state model with gating function, "gate model"
//! (`docs/spec/gate-model.md`), and its Move-to-Target planner (`docs/spec/planning.md` §2,
//! §4, §5).
//!
//! * [`GateModel`]: the [`Model`](crate::Model) implementation — actuator
//!   forward model, the gate classifier shared by all blocks, per-block
//!   forward and inverse models;
//! * [`GateWorld`]: its world state, whose blocks are records with identity
//!   (`docs/spec/gate-model.md` §4.1);
//! * [`GateParams`] / [`GateConfig`]: rate-dependent thresholds, prediction
//!   boost and the hard-coded variants of `docs/spec/gate-model.md` §5.

mod algorithm;
mod errors;
mod hyperparams;
pub(crate) mod options;
mod planner;
mod world;

#[cfg(test)]
mod tests;

pub use crate::planning::{
    APPROACH_SPEED, CIRCLE_FAR, CIRCLE_NEAR, CIRCLE_SPEED, EPS_CLOSE, EPS_CLOSE_ENOUGH, REACHED,
};
pub use crate::stats::HARD_CODED_LABEL;
pub use algorithm::{
    GateModel, Predictor, EPS_CHANGE, HARD_CODED_ACTUATOR_STEP, UNROUNDED_EPS_CHANGE,
};
pub use errors::GateError;
pub use hyperparams::{
    flags, GateConfig, GateParams, Improvements, VelocityFeatures, ADAPTED_ACTUATOR_RATE,
    AVERAGED_OUTPUT_RATE, FLAG_PREDICTION_BOOST,
};
pub use planner::{PASS_MAX, PASS_MIN};
pub use world::GateWorld;
