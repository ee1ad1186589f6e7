//! AIM — the Averaging Inverse Model, also called TIIM
//! (`spec/inverse-model.md`).
//!
//! Answers "in which situation does feature i change in direction ±?" by
//! averaging, per (feature, sign) prototype, the preconditions that produced
//! such a change, and reduces a target difference greedily one feature at a
//! time.

mod algorithm;
mod errors;
mod hyperparams;
mod prototype;

#[cfg(test)]
mod tests;

pub use algorithm::{InverseModel, PrototypeKey, Sign};
pub use errors::AimError;
pub use hyperparams::{AimConfig, AimParams};
pub use prototype::{sign_combination, Combination, MergedGroup, Preconditions, Prototype};
