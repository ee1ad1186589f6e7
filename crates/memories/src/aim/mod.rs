//! AIM — the Averaging Inverse Model, also called TIIM
//! (`docs/spec/inverse-model.md`).
//!
//! Answers "in which situation does feature i change in direction ±?" by
//! averaging, per (feature, sign) prototype, the preconditions that produced
//! such a change, and reduces a target difference greedily one feature at a
//! time.
//!
//! ```
//! use memories::aim::{AimConfig, InverseModel, PrototypeKey, Sign};
//!
//! let mut aim = InverseModel::new(AimConfig::hz100());
//! // Precondition p produced a change d: feature 1 grew by 0.1.
//! aim.train(&[0.25, -0.5], &[0.0, 0.1, 0.0]);
//! // To increase feature 1 (the largest component of the target difference):
//! let p = aim.preconditions_for(&[0.0, 0.4, -0.2]).expect("prototype (1, +)");
//! assert!((p[0] - 0.25).abs() < 1e-12 && (p[1] + 0.5).abs() < 1e-12);
//! assert_eq!(aim.current_key(), Some(PrototypeKey::new(1, Sign::Positive)));
//! ```

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
