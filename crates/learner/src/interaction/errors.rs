//! Errors of the interaction model: invalid parameters and inconsistent
//! stored state.

use thiserror::Error;

/// Why [`InteractionParams`](super::InteractionParams) or a deserialised
/// [`InteractionModel`](super::InteractionModel) was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InteractionError {
    /// ε_noise must be finite and non-negative.
    #[error("eps_noise must be finite and non-negative (got {0})")]
    InvalidEpsNoise(f64),
    /// A deserialised model violates an invariant.
    #[error("inconsistent interaction model state: {0}")]
    InconsistentState(&'static str),
}
