//! The gate model's options: its checks and its constructor from the
//! registry's [`ModelOptions`], and the changes beyond the thesis
//! (`--improve`) with the names reports give them.

use serde::{Deserialize, Serialize};

use crate::gate::{GateConfig, GateParams, Improvements, VelocityFeatures};
use crate::interaction::SelectorKind;
use crate::registry::{ModelKind, ModelOptions, ModelOptionsError, Named};

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

    /// The change called `name`.
    ///
    /// # Errors
    /// An unknown name, with the names there are.
    pub fn named(name: &str) -> Result<Improvement, ModelOptionsError> {
        Improvement::from_name(name).ok_or_else(|| ModelOptionsError::UnknownImprovement {
            name: name.to_owned(),
        })
    }

    fn set(self, on: &mut Improvements) {
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

    fn is_in(self, on: Improvements) -> bool {
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

impl ModelOptions {
    /// The gate model's parameters; a 10 Hz world selects the LOWFREQ
    /// thresholds as bit 2 does.
    ///
    /// # Errors
    /// Options that do not apply to the gate model or invalid values.
    pub fn gate(&self, publish_rate_hz: u32) -> Result<GateConfig, ModelOptionsError> {
        self.check_eta()?;
        self.check_no_parts(ModelKind::Gate)?;
        if self.selector != SelectorKind::Aitm {
            return Err(ModelOptionsError::NotForModel {
                option: "--selector",
                model: ModelKind::Gate,
            });
        }
        let mut params = GateParams::from_config_number(self.number_at(publish_rate_hz))?;
        params.forward_learning_rate = self.eta;
        params.improvements = self.improvements();
        if self.no_angular_velocity {
            if params.velocity_features != VelocityFeatures::LinearAngular {
                return Err(ModelOptionsError::NoVelocities);
            }
            params.velocity_features = VelocityFeatures::Linear;
        }
        Ok(params.check()?)
    }

    /// The parameters of `gate+`: [`ModelOptions::gate`] with every change.
    ///
    /// # Errors
    /// As [`ModelOptions::gate`], and --improve, which gate+ does not take.
    pub fn gate_plus(&self, publish_rate_hz: u32) -> Result<GateConfig, ModelOptionsError> {
        if !self.improve.is_empty() {
            return Err(ModelOptionsError::ImproveOnGatePlus);
        }
        let mut params = *self.gate(publish_rate_hz)?.params();
        params.improvements = Improvements::ALL;
        Ok(params.check()?)
    }

    /// The changes of `improve`.
    #[must_use]
    pub fn improvements(&self) -> Improvements {
        let mut on = Improvements::default();
        for i in &self.improve {
            i.set(&mut on);
        }
        on
    }

    /// The names of the changes `improve` turns on, in the order of
    /// [`Improvement::EACH`] (`all` spelt out), whatever the given order.
    #[must_use]
    pub fn improvement_names(&self) -> Vec<&'static str> {
        let on = self.improvements();
        Improvement::EACH
            .into_iter()
            .filter(|i| i.is_in(on))
            .map(Improvement::as_str)
            .collect()
    }

    /// The name reports give the gate model under these options: `gate`,
    /// `gate+` (every change) or `gate+CHANGE+…` in the order of
    /// [`Improvement::EACH`].
    pub(crate) fn gate_report_name(&self) -> String {
        let on = self.improvements();
        if !on.any() {
            return ModelKind::Gate.as_str().to_owned();
        }
        if on == Improvements::ALL {
            return ModelKind::GatePlus.as_str().to_owned();
        }
        format!("gate+{}", self.improvement_names().join("+"))
    }
}

/// Whether `name` is a name [`ModelOptions::gate_report_name`] gives the
/// gate model with some changes (spelt as reports spell them: no repeats,
/// no other order, no `all` or every change spelt out, which is `gate+`).
pub(crate) fn is_improved_report_name(name: &str) -> bool {
    let Some(changes) = name.strip_prefix("gate+") else {
        return false;
    };
    let Some(improve) = changes
        .split('+')
        .map(Improvement::from_name)
        .collect::<Option<Vec<_>>>()
    else {
        return false;
    };
    let options = ModelOptions {
        improve,
        ..ModelOptions::default()
    };
    options.gate_report_name() == name
}
