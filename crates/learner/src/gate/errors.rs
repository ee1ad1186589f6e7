//! Errors of the gate model: invalid parameters and inconsistent stored
//! state.

use thiserror::Error;

use crate::aim::AimError;
use crate::aitm::AitmError;

/// Why a gate model configuration or a deserialised gate model was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum GateError {
    /// The prediction boost must be finite and positive.
    #[error("prediction boost must be finite and positive (got {0})")]
    InvalidBoost(f64),
    /// The inverse models' thresholds are invalid.
    #[error("inverse model parameters: {0}")]
    Aim(#[from] AimError),
    /// The forward models' learning rate is invalid.
    #[error("forward model learning rate: {0}")]
    Rate(#[from] AitmError),
    /// Bits the original never defined.
    #[error("configuration number {0}: unknown bits {1:#x}")]
    UnsupportedFlags(u32, u32),
    /// A deserialised model violates an invariant.
    #[error("inconsistent gate model state: {0}")]
    InconsistentState(&'static str),
}
