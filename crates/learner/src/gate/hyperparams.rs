//! Gate model configuration (`docs/spec/gate-model.md` §1, §5; `docs/spec/experiments.md` §1):
//! unchecked [`GateParams`], validated once into [`GateConfig`].

use serde::{Deserialize, Serialize};

use super::errors::GateError;
use crate::aim::{AimConfig, AimParams};
use crate::aitm::{AitmConfig, AitmParams, QueryMode};
use crate::features::{Precision, DEFAULT_PREDICTION_BOOST};

/// The boost of configuration flag 64 (`docs/spec/gate-model.md` §5).
pub const FLAG_PREDICTION_BOOST: f64 = 1.5;

pub use crate::flags;

/// Which of the block's own velocities the block predictors see besides φ
/// (configuration bit 1, USE_DYNS; thesis draft §4.3.1 lists linVelX,
/// linVelY and angVel among an object's features).
///
/// *(decision)* The learner's frames carry no message velocities
/// (`docs/spec/protocol.md` §4: no evaluated learner reads them), so the velocities
/// are the block's displacement since its previous state, in that previous
/// state's frame and rounded to 3 decimals, and its yaw change: the
/// message's velocities times the message period up to the world's
/// integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VelocityFeatures {
    /// φ only: the evaluated configuration (the draft's "NoDyns").
    #[default]
    None,
    /// φ and the block's linear velocity (the draft's "NoAV": no angular
    /// velocity).
    Linear,
    /// φ, the linear and the angular velocity (USE_DYNS).
    LinearAngular,
}

impl VelocityFeatures {
    /// Number of components added to φ.
    #[must_use]
    pub fn dim(self) -> usize {
        match self {
            VelocityFeatures::None => 0,
            VelocityFeatures::Linear => 2,
            VelocityFeatures::LinearAngular => 3,
        }
    }
}

/// The improved gate model's changes (`docs/models.md` "Beyond the
/// thesis"), each one switchable so that an ablation has one row per change.
/// All off is the thesis's model, bit for bit; all on is `gate+`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, rename_all = "kebab-case")]
pub struct Improvements {
    /// Features, changes and predictions at full precision instead of
    /// rounded to 3 decimals; a block then counts as changed above a noise
    /// threshold ([`UNROUNDED_EPS_CHANGE`](super::UNROUNDED_EPS_CHANGE))
    /// instead of at any rounding unit.
    pub unrounded: bool,
    /// The forward models blend the winner with all its topological
    /// neighbours (AITM `NEIGHBOUR`) instead of the winner and the second
    /// winner only.
    pub interpolate: bool,
    /// The planner checks the inverse model's push and variants of it with
    /// the forward model and takes the one predicted to bring the block
    /// closest to the target.
    pub forward_check: bool,
    /// One forward and inverse model shared by every block, with the block
    /// ids left out of φ, so that what was learned on one object applies to
    /// another.
    pub shared_blocks: bool,
    /// The actuator's forward model adapts its winner towards every sample
    /// ([`ADAPTED_ACTUATOR_RATE`]) instead of replacing half of it only when
    /// the error exceeds the insertion threshold: its one input, the
    /// commanded action, then predicts the mean step rather than whichever
    /// (possibly latency-shortened) step it stored first.
    pub adapt_actuator: bool,
    /// The block forward models move their winner's output towards every
    /// sample it wins (η_out = [`AVERAGED_OUTPUT_RATE`], inputs and local
    /// linear maps fixed), so that a node holds a running mean of the
    /// changes it stands for, not the single sample that created it.
    pub average_outputs: bool,
}

/// η_out of the block forward models with `average-outputs` (the draft's
/// smaller rate, as [`ADAPTED_ACTUATOR_RATE`]).
pub const AVERAGED_OUTPUT_RATE: f64 = 0.1;

/// η of the actuator's forward model with `adapt-actuator`: the smaller of
/// the two non-zero rates of the thesis draft's tables (0.1 and 0.2).
pub const ADAPTED_ACTUATOR_RATE: f64 = 0.1;

impl Improvements {
    /// Every change: the `gate+` model.
    pub const ALL: Self = Self {
        unrounded: true,
        interpolate: true,
        forward_check: true,
        shared_blocks: true,
        adapt_actuator: true,
        average_outputs: true,
    };

    /// Whether any change is on.
    #[must_use]
    pub fn any(self) -> bool {
        self != Self::default()
    }

    /// The precision of features and predictions.
    #[must_use]
    pub fn precision(self) -> Precision {
        if self.unrounded {
            Precision::Full
        } else {
            Precision::Thesis
        }
    }
}

/// Unchecked gate model parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GateParams {
    /// Thresholds of the per-block inverse models (`docs/spec/inverse-model.md` §1);
    /// the only rate-dependent part of the gate model.
    pub aim: AimParams,
    /// Factor on predicted block changes (`docs/spec/gate-model.md` §5): 1.0 in every
    /// reported result, 1.5 with flag 64.
    pub prediction_boost: f64,
    /// Flag 16: the actuator moves `0.01 · a` per message and its forward
    /// model is never trained (`docs/spec/gate-model.md` §5).
    pub hard_coded_actuator: bool,
    /// Flag 32: a geometric rule replaces the learned gate, which is then
    /// never trained (`docs/spec/gate-model.md` §5).
    pub hard_coded_gate: bool,
    /// η_in = η_out = η_A of the actuator and block forward models
    /// (`docs/spec/aitm.md` §4): 0 in every final result, varied in the thesis
    /// draft's tables ("ITM η").
    #[serde(default)]
    pub forward_learning_rate: f64,
    /// The block predictors' velocity inputs (flag 1).
    #[serde(default)]
    pub velocity_features: VelocityFeatures,
    /// Changes beyond the thesis; none in the faithful model.
    #[serde(default)]
    pub improvements: Improvements,
}

impl GateParams {
    /// The evaluated configuration (0): 100 Hz, learned actuator and gate,
    /// boost 1.0.
    pub fn hz100() -> Self {
        Self {
            aim: AimParams::hz100(),
            prediction_boost: DEFAULT_PREDICTION_BOOST,
            hard_coded_actuator: false,
            hard_coded_gate: false,
            forward_learning_rate: 0.0,
            velocity_features: VelocityFeatures::None,
            improvements: Improvements::default(),
        }
    }

    /// As [`GateParams::hz100`] with the 10 Hz inverse-model thresholds
    /// (configuration 2).
    pub fn hz10() -> Self {
        Self {
            aim: AimParams::hz10(),
            ..Self::hz100()
        }
    }

    /// The parameters of one of the original's configuration numbers
    /// (`docs/spec/experiments.md` §1). Driver-only bits (4, 8) are accepted and have
    /// no effect here; undefined bits are refused.
    pub fn from_config_number(number: u32) -> Result<Self, GateError> {
        let bad = number & !flags::ALL;
        if bad != 0 {
            return Err(GateError::UnsupportedFlags(number, bad));
        }
        let base = if number & flags::LOWFREQ != 0 {
            Self::hz10()
        } else {
            Self::hz100()
        };
        Ok(Self {
            prediction_boost: if number & flags::USINGPREDICTIONBOOST != 0 {
                FLAG_PREDICTION_BOOST
            } else {
                DEFAULT_PREDICTION_BOOST
            },
            hard_coded_actuator: number & flags::HARDCODEDACT != 0,
            hard_coded_gate: number & flags::HARDCODEDGATE != 0,
            velocity_features: if number & flags::USE_DYNS != 0 {
                VelocityFeatures::LinearAngular
            } else {
                VelocityFeatures::None
            },
            ..base
        })
    }

    /// Validates the parameters once.
    pub fn check(self) -> Result<GateConfig, GateError> {
        let aim = self.aim.check()?;
        if !(self.prediction_boost.is_finite() && self.prediction_boost > 0.0) {
            return Err(GateError::InvalidBoost(self.prediction_boost));
        }
        let mode = if self.improvements.interpolate {
            QueryMode::Neighbour
        } else {
            QueryMode::BestTwo
        };
        let mut forward =
            AitmParams::regressor(mode).with_learning_rate(self.forward_learning_rate);
        if self.improvements.average_outputs {
            forward.eta_out = AVERAGED_OUTPUT_RATE;
        }
        let forward = forward.check()?;
        let actuator = if self.improvements.adapt_actuator {
            AitmParams::regressor(mode)
                .with_learning_rate(ADAPTED_ACTUATOR_RATE)
                .check()?
        } else {
            forward
        };
        Ok(GateConfig {
            params: self,
            aim,
            forward,
            actuator,
        })
    }
}

impl Default for GateParams {
    fn default() -> Self {
        Self::hz100()
    }
}

/// Validated gate model parameters. Deserialising re-validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GateParams", into = "GateParams")]
pub struct GateConfig {
    params: GateParams,
    /// `params.aim`, checked.
    aim: AimConfig,
    /// The block forward models' configuration (BESTTWO,
    /// `docs/spec/aitm.md` §6, with `params.forward_learning_rate`), checked.
    forward: AitmConfig,
    /// The actuator forward model's: `forward`, but for `adapt-actuator`.
    actuator: AitmConfig,
}

impl TryFrom<GateParams> for GateConfig {
    type Error = GateError;

    fn try_from(params: GateParams) -> Result<Self, Self::Error> {
        params.check()
    }
}

impl From<GateConfig> for GateParams {
    fn from(config: GateConfig) -> Self {
        config.params
    }
}

impl Default for GateConfig {
    fn default() -> Self {
        Self::hz100()
    }
}

impl GateConfig {
    /// Checked [`GateParams::hz100`] (valid constants, no check needed).
    pub fn hz100() -> Self {
        Self {
            params: GateParams::hz100(),
            aim: AimConfig::hz100(),
            forward: AitmConfig::regressor(QueryMode::BestTwo),
            actuator: AitmConfig::regressor(QueryMode::BestTwo),
        }
    }

    /// Checked [`GateParams::hz10`].
    pub fn hz10() -> Self {
        Self {
            params: GateParams::hz10(),
            aim: AimConfig::hz10(),
            ..Self::hz100()
        }
    }

    /// The validated parameters.
    pub fn params(&self) -> &GateParams {
        &self.params
    }

    /// The per-block inverse models' configuration.
    pub fn aim(&self) -> AimConfig {
        self.aim
    }

    /// The block forward models' configuration.
    pub fn forward(&self) -> AitmConfig {
        self.forward
    }

    /// The actuator forward model's configuration.
    pub fn actuator(&self) -> AitmConfig {
        self.actuator
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets() {
        let p = *GateConfig::hz100().params();
        assert_eq!(p.aim, AimParams::hz100());
        assert_eq!(p.prediction_boost, 1.0);
        assert!(!p.hard_coded_actuator && !p.hard_coded_gate);
        assert_eq!(GateConfig::hz10().params().aim, AimParams::hz10());
        assert_eq!(GateParams::hz100().check(), Ok(GateConfig::hz100()));
        assert_eq!(GateConfig::default(), GateConfig::hz100());
        assert_eq!(GateConfig::hz10().aim(), AimConfig::hz10());
        assert_eq!(GateParams::hz10().check(), Ok(GateConfig::hz10()));
    }

    #[test]
    fn configuration_numbers() {
        assert_eq!(GateParams::from_config_number(0), Ok(GateParams::hz100()));
        // Driver-only bits change nothing in the model.
        assert_eq!(GateParams::from_config_number(8), Ok(GateParams::hz100()));
        assert_eq!(GateParams::from_config_number(4), Ok(GateParams::hz100()));
        assert_eq!(GateParams::from_config_number(2), Ok(GateParams::hz10()));
        let p = GateParams::from_config_number(2 | 16 | 32 | 64).unwrap();
        assert_eq!(p.aim, AimParams::hz10());
        assert_eq!(p.prediction_boost, 1.5);
        assert!(p.hard_coded_actuator && p.hard_coded_gate);
        assert_eq!(
            GateParams::from_config_number(1 | 8).map(|p| p.velocity_features),
            Ok(VelocityFeatures::LinearAngular)
        );
        assert_eq!(p.velocity_features, VelocityFeatures::None);
        assert_eq!(
            GateParams::from_config_number(128),
            Err(GateError::UnsupportedFlags(128, 128))
        );
    }

    #[test]
    fn rejects_invalid_values() {
        for boost in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let p = GateParams {
                prediction_boost: boost,
                ..GateParams::hz100()
            };
            assert!(
                matches!(p.check(), Err(GateError::InvalidBoost(_))),
                "{boost}"
            );
        }
        let p = GateParams {
            aim: AimParams {
                eps_dif: -1.0,
                ..AimParams::hz100()
            },
            ..GateParams::hz100()
        };
        assert!(matches!(p.check(), Err(GateError::Aim(_))));
        let p = GateParams {
            forward_learning_rate: f64::NAN,
            ..GateParams::hz100()
        };
        assert!(matches!(p.check(), Err(GateError::Rate(_))));
        let c = GateParams {
            forward_learning_rate: 0.1,
            ..GateParams::hz100()
        }
        .check()
        .unwrap();
        assert_eq!(c.forward().params().eta_out, 0.1);
        assert_eq!(GateConfig::hz100().forward().params().eta_out, 0.0);
        let json = serde_json::to_string(&GateConfig::hz100()).unwrap();
        let back: GateConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, GateConfig::hz100());
        let bad = json.replace("\"prediction_boost\":1.0", "\"prediction_boost\":-1.0");
        assert_ne!(bad, json);
        assert!(serde_json::from_str::<GateConfig>(&bad).is_err());
    }
}
