//! The gate model's own options: the changes beyond the thesis
//! (`--improve`) by name, and its configuration from the command line's
//! options, which the registry hands it after refusing those of other
//! models.

use pushlearn_core::Named;
use serde::{Deserialize, Serialize};

use crate::gate::{GateConfig, GateError, GateParams, Improvements, VelocityFeatures};

/// One change of the improved gate model (`docs/models.md` "Beyond the
/// thesis"), by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Improvement {
    Unrounded,
    Interpolate,
    ForwardCheck,
    SharedBlocks,
    AdaptActuator,
    AverageOutputs,
    /// Every change (what `gate+` has).
    All,
}

impl Named for Improvement {
    const ALL: &'static [Self] = &[
        Improvement::Unrounded,
        Improvement::Interpolate,
        Improvement::ForwardCheck,
        Improvement::SharedBlocks,
        Improvement::AdaptActuator,
        Improvement::AverageOutputs,
        Improvement::All,
    ];

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            Improvement::Unrounded => {
                "Features, changes and predictions at full precision, not rounded to 3 decimals"
            }
            Improvement::Interpolate => {
                "Forward models blend the winner with all its neighbours instead of the two \
                 nearest nodes"
            }
            Improvement::ForwardCheck => {
                "The planner ranks the inverse model's push and variants of it with the \
                 forward model"
            }
            Improvement::SharedBlocks => {
                "One forward and inverse model for every block, block ids left out of the \
                 features"
            }
            Improvement::AdaptActuator => {
                "The actuator's forward model averages its samples (η = 0.1)"
            }
            Improvement::AverageOutputs => {
                "The block forward models' nodes average the changes they win (η_out = 0.1)"
            }
            Improvement::All => "Every change (what `--model gate+` has)",
        }
    }
}

impl Improvement {
    /// Every single change, in the order of reports and tables.
    pub const EACH: [Improvement; 6] = [
        Improvement::Unrounded,
        Improvement::Interpolate,
        Improvement::AdaptActuator,
        Improvement::AverageOutputs,
        Improvement::ForwardCheck,
        Improvement::SharedBlocks,
    ];

    /// The name on the command line.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Improvement::Unrounded => "unrounded",
            Improvement::Interpolate => "interpolate",
            Improvement::ForwardCheck => "forward-check",
            Improvement::SharedBlocks => "shared-blocks",
            Improvement::AdaptActuator => "adapt-actuator",
            Improvement::AverageOutputs => "average-outputs",
            Improvement::All => "all",
        }
    }

    pub(crate) fn set(self, on: &mut Improvements) {
        match self {
            Improvement::Unrounded => on.unrounded = true,
            Improvement::Interpolate => on.interpolate = true,
            Improvement::ForwardCheck => on.forward_check = true,
            Improvement::SharedBlocks => on.shared_blocks = true,
            Improvement::AdaptActuator => on.adapt_actuator = true,
            Improvement::AverageOutputs => on.average_outputs = true,
            Improvement::All => *on = Improvements::ALL,
        }
    }

    pub(crate) fn is_in(self, on: Improvements) -> bool {
        match self {
            Improvement::Unrounded => on.unrounded,
            Improvement::Interpolate => on.interpolate,
            Improvement::ForwardCheck => on.forward_check,
            Improvement::SharedBlocks => on.shared_blocks,
            Improvement::AdaptActuator => on.adapt_actuator,
            Improvement::AverageOutputs => on.average_outputs,
            Improvement::All => on == Improvements::ALL,
        }
    }
}

/// Why the command line's options cannot configure the gate model.
#[derive(Debug, thiserror::Error)]
pub enum GateOptionsError {
    #[error("gate model: {0}")]
    Gate(#[from] GateError),
    #[error(
        "--no-angular-velocity needs velocity features (--flag use-dyns or bit 1 of --config)"
    )]
    NoVelocities,
}

impl GateConfig {
    /// The configuration of the original's configuration number `number`
    /// (the rate's bits included) with the forward models' learning rate
    /// `eta`, the block's angular velocity left out of the USE_DYNS
    /// features if `no_angular_velocity`, and the changes `improvements`.
    ///
    /// # Errors
    /// Unknown bits, an invalid value, or `no_angular_velocity` without
    /// velocity features.
    pub fn from_options(
        number: u32,
        eta: f64,
        no_angular_velocity: bool,
        improvements: Improvements,
    ) -> Result<GateConfig, GateOptionsError> {
        let mut params = GateParams::from_config_number(number)?;
        params.forward_learning_rate = eta;
        params.improvements = improvements;
        if no_angular_velocity {
            if params.velocity_features != VelocityFeatures::LinearAngular {
                return Err(GateOptionsError::NoVelocities);
            }
            params.velocity_features = VelocityFeatures::Linear;
        }
        Ok(params.check()?)
    }
}
