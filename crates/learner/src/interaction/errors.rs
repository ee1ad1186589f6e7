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
    /// The ACs' learning rate is invalid.
    #[error("AC learning rate: {0}")]
    Rate(#[from] crate::aitm::AitmError),
    /// Configuration bits that concern only the gate model, or undefined ones.
    #[error("configuration number {0}: bits {1:#x} do not apply to the interaction model (gate-model bits 1, 16, 32, 64 or undefined)")]
    UnsupportedFlags(u32, u32),
    /// A deserialised model violates an invariant.
    #[error("inconsistent interaction model state: {0}")]
    InconsistentState(&'static str),
}
