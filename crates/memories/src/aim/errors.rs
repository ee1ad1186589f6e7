//! Errors of the Averaging Inverse Model.

use thiserror::Error;

/// Why a set of [`AimParams`](super::AimParams) or a deserialised model was
/// rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AimError {
    /// A threshold (`eps_dif`, `eps_node`, `eps_keep`) must be finite and
    /// non-negative.
    #[error("threshold {name} must be finite and non-negative (got {value})")]
    InvalidThreshold {
        /// The parameter's name.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// The alternative ratio must be finite and non-negative.
    #[error("ratio must be finite and non-negative (got {0})")]
    InvalidRatio(f64),
    /// A deserialised model violates an invariant.
    #[error("inconsistent inverse model state: {0}")]
    InconsistentState(&'static str),
}
