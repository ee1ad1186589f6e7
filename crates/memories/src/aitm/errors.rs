//! Errors of the AITM: invalid hyperparameters and inconsistent stored state.

use thiserror::Error;

/// Why a set of [`AitmParams`](super::AitmParams) or a deserialised map was
/// rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AitmError {
    /// σ must be finite and positive, and σ² must neither underflow to 0 nor
    /// overflow (the BESTTWO weights divide by σ²).
    #[error("sigma must be finite and positive with a finite, non-zero square (got {0})")]
    InvalidSigma(f64),
    /// ε_max must be finite and non-negative, with a finite square.
    #[error("eps_max must be finite and non-negative (got {0})")]
    InvalidEpsMax(f64),
    /// A learning rate must be finite and non-negative.
    #[error("learning rate {name} must be finite and non-negative (got {value})")]
    InvalidRate {
        /// `eta_in`, `eta_out` or `eta_a`.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A deserialised map violates an invariant of the data structure.
    #[error("inconsistent AITM state: {0}")]
    InconsistentState(&'static str),
}
