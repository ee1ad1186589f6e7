//! The models' constructor arguments, checked exactly as the command line's
//! `ModelOptions` checks them.
//!
//! KEEP IN STEP with `crates/cli/src/models.rs` (`ModelOptions::gate`,
//! `ModelOptions::interaction`, `number_at`, `parse_rate`,
//! `parse_selector`): this crate does not depend on the application, so
//! those few lines are reproduced here, and a change to one must be made to
//! the other. The refusals' texts are the application's (`ModelOptionsError`,
//! with the Python argument names where it names a flag).

use learner::gate::VelocityFeatures;
use learner::interaction::SelectorKind;
use learner::{flags, GateConfig, GateParams, InteractionConfig, InteractionParams};
use pyo3::PyResult;

use crate::args::value_error;

/// The publish rate that selects the LOWFREQ thresholds
/// (`crates/cli/src/experiment/mod.rs`, `LOW_RATE_HZ`).
pub const LOW_RATE_HZ: u32 = 10;

/// The gate model's constructor arguments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GateOptions {
    pub config: u32,
    pub eta: f64,
    pub publish_rate_hz: u32,
    pub no_angular_velocity: bool,
}

/// The interaction model's constructor arguments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InteractionOptions {
    pub config: u32,
    pub eta: f64,
    pub publish_rate_hz: u32,
    pub selector: SelectorKind,
}

/// `ModelOptions::number_at`: the configuration number with LOWFREQ added
/// for a 10 Hz world.
fn number_at(config: u32, publish_rate_hz: u32) -> u32 {
    let low = publish_rate_hz == LOW_RATE_HZ;
    config | if low { flags::LOWFREQ } else { 0 }
}

/// `parse_rate`: a finite, non-negative learning rate.
fn check_eta(eta: f64) -> PyResult<f64> {
    if eta.is_finite() && eta >= 0.0 {
        Ok(eta)
    } else {
        Err(value_error(format!(
            "eta {eta} is not a finite, non-negative number"
        )))
    }
}

/// `parse_selector`: a selector by its `SelectorKind::as_str` name.
pub fn selector(name: &str) -> PyResult<SelectorKind> {
    SelectorKind::ALL
        .into_iter()
        .find(|k| k.as_str() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = SelectorKind::ALL.iter().map(|k| k.as_str()).collect();
            value_error(format!(
                "unknown selector '{name}'; one of: {}",
                names.join(", ")
            ))
        })
}

impl GateOptions {
    /// `ModelOptions::gate` (without its `--selector` check: the gate model
    /// takes no selector argument here).
    pub fn config(&self) -> PyResult<GateConfig> {
        let eta = check_eta(self.eta)?;
        let gate_error = |e| value_error(format!("gate model: {e}"));
        let mut params =
            GateParams::from_config_number(number_at(self.config, self.publish_rate_hz))
                .map_err(gate_error)?;
        params.forward_learning_rate = eta;
        if self.no_angular_velocity {
            if params.velocity_features != VelocityFeatures::LinearAngular {
                return Err(value_error(
                    "no_angular_velocity needs velocity features (bit 1, USE_DYNS, of config)",
                ));
            }
            params.velocity_features = VelocityFeatures::Linear;
        }
        params.check().map_err(gate_error)
    }
}

impl InteractionOptions {
    /// `ModelOptions::interaction` (without its `--no-angular-velocity`
    /// check: the interaction model takes no such argument here).
    pub fn config(&self) -> PyResult<InteractionConfig> {
        let eta = check_eta(self.eta)?;
        let interaction_error = |e| value_error(format!("interaction model: {e}"));
        let mut params =
            InteractionParams::from_config_number(number_at(self.config, self.publish_rate_hz))
                .map_err(interaction_error)?;
        params.ac_learning_rate = eta;
        params.selector = self.selector;
        params.check().map_err(interaction_error)
    }
}
