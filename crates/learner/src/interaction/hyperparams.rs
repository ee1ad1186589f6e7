//! Parameters of the interaction model (`docs/spec/interaction-model.md` §3,
//! `docs/spec/README.md` §6): unchecked [`InteractionParams`], validated once into
//! [`InteractionConfig`].

use serde::{Deserialize, Serialize};

use super::errors::InteractionError;
use super::selector::SelectorKind;
use crate::aim::AimConfig;
use crate::aitm::{AitmConfig, AitmParams, QueryMode};
use crate::features::{EPS_NOISE_100HZ, EPS_NOISE_10HZ};
use crate::flags;

/// Unchecked parameters. The ACs are WINNER regressors and the ACS a WINNER
/// classifier with the evaluated values of `docs/spec/aitm.md` §6 unless the draft's
/// variants are chosen (`ac_learning_rate`, `selector`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InteractionParams {
    /// ε_noise: a feature belongs to an episode's changed-feature set if
    /// `|d_i| > eps_noise` (`docs/spec/interaction-model.md` §3, §8: 0.001 at 100 Hz,
    /// not the thesis table's 0.01).
    pub eps_noise: f64,
    /// The global inverse model's thresholds (`docs/spec/inverse-model.md` §1),
    /// validated on their own.
    pub aim: AimConfig,
    /// η_in = η_out = η_A of every AC's forward model (`docs/spec/aitm.md` §4); 0 in
    /// the evaluated configuration, varied in the thesis draft's tables.
    #[serde(default)]
    pub ac_learning_rate: f64,
    /// The Abstract Collection Selector: the final thesis's AITM classifier
    /// or one of the draft's variants (`selector.rs`).
    #[serde(default)]
    pub selector: SelectorKind,
}

impl InteractionParams {
    /// 100 Hz: ε_noise 0.001 and the 100 Hz AIM thresholds.
    #[must_use]
    pub fn hz100() -> Self {
        Self {
            eps_noise: EPS_NOISE_100HZ,
            aim: AimConfig::hz100(),
            ac_learning_rate: 0.0,
            selector: SelectorKind::Aitm,
        }
    }

    /// 10 Hz (configuration bit 2, `docs/spec/experiments.md` §1): ε_noise 0.01 and
    /// the 10 Hz AIM thresholds.
    #[must_use]
    pub fn hz10() -> Self {
        Self {
            eps_noise: EPS_NOISE_10HZ,
            aim: AimConfig::hz10(),
            ..Self::hz100()
        }
    }

    /// The parameters of one of the original's configuration numbers
    /// (`docs/spec/experiments.md` §1): bit 2 selects the 10 Hz thresholds, the
    /// driver's bits (4, 8) change nothing here; the gate model's bits (1,
    /// 16, 32, 64) and undefined ones are refused, since the interaction
    /// model has no such parts.
    pub fn from_config_number(number: u32) -> Result<Self, InteractionError> {
        let bad = number & !(flags::LOWFREQ | flags::DRIVER);
        if bad != 0 {
            return Err(InteractionError::UnsupportedFlags(number, bad));
        }
        Ok(if number & flags::LOWFREQ != 0 {
            Self::hz10()
        } else {
            Self::hz100()
        })
    }

    /// Validates the parameters once.
    pub fn check(self) -> Result<InteractionConfig, InteractionError> {
        if !(self.eps_noise.is_finite() && self.eps_noise >= 0.0) {
            return Err(InteractionError::InvalidEpsNoise(self.eps_noise));
        }
        let ac = AitmParams::regressor(QueryMode::Winner)
            .with_learning_rate(self.ac_learning_rate)
            .check()?;
        Ok(InteractionConfig { params: self, ac })
    }
}

/// Validated parameters. Deserialising re-validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "InteractionParams", into = "InteractionParams")]
pub struct InteractionConfig {
    params: InteractionParams,
    /// The ACs' forward-model configuration, checked.
    ac: AitmConfig,
}

impl TryFrom<InteractionParams> for InteractionConfig {
    type Error = InteractionError;

    fn try_from(params: InteractionParams) -> Result<Self, Self::Error> {
        params.check()
    }
}

impl From<InteractionConfig> for InteractionParams {
    fn from(config: InteractionConfig) -> Self {
        config.params
    }
}

impl Default for InteractionConfig {
    fn default() -> Self {
        Self::hz100()
    }
}

impl InteractionConfig {
    /// Checked [`InteractionParams::hz100`] (valid constants).
    #[must_use]
    pub fn hz100() -> Self {
        Self {
            params: InteractionParams::hz100(),
            ac: AitmConfig::regressor(QueryMode::Winner),
        }
    }

    /// Checked [`InteractionParams::hz10`].
    #[must_use]
    pub fn hz10() -> Self {
        Self {
            params: InteractionParams::hz10(),
            ..Self::hz100()
        }
    }

    /// The validated parameters.
    #[must_use]
    pub fn params(&self) -> &InteractionParams {
        &self.params
    }

    /// ε_noise.
    #[must_use]
    pub fn eps_noise(&self) -> f64 {
        self.params.eps_noise
    }

    /// The inverse model's parameters.
    #[must_use]
    pub fn aim(&self) -> AimConfig {
        self.params.aim
    }

    /// The configuration of every AC's forward model.
    #[must_use]
    pub fn ac(&self) -> AitmConfig {
        self.ac
    }

    /// The selector kind.
    #[must_use]
    pub fn selector(&self) -> SelectorKind {
        self.params.selector
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aim::AimParams;

    #[test]
    fn presets_match_the_parameter_table() {
        assert_eq!(InteractionConfig::hz100().eps_noise(), 0.001);
        assert_eq!(InteractionConfig::hz10().eps_noise(), 0.01);
        assert_eq!(
            *InteractionConfig::hz100().aim().params(),
            AimParams::hz100()
        );
        assert_eq!(*InteractionConfig::hz10().aim().params(), AimParams::hz10());
        assert_eq!(InteractionConfig::default(), InteractionConfig::hz100());
        assert_eq!(
            InteractionParams::hz10().check(),
            Ok(InteractionConfig::hz10())
        );
    }

    #[test]
    fn rejects_invalid_values() {
        for eps_noise in [-0.001, f64::NAN, f64::INFINITY] {
            let p = InteractionParams {
                eps_noise,
                ..InteractionParams::hz100()
            };
            assert!(matches!(
                p.check(),
                Err(InteractionError::InvalidEpsNoise(_))
            ));
        }
        let p = InteractionParams {
            ac_learning_rate: -0.1,
            ..InteractionParams::hz100()
        };
        assert!(matches!(p.check(), Err(InteractionError::Rate(_))));
        let json = serde_json::to_string(&InteractionConfig::hz100()).expect("serialise");
        assert!(json.starts_with(r#"{"eps_noise":0.001,"#), "{json}");
        let bad = json.replacen("0.001", "-1.0", 1);
        assert!(serde_json::from_str::<InteractionConfig>(&bad).is_err());
        let back: InteractionConfig = serde_json::from_str(&json).expect("valid");
        assert_eq!(back, InteractionConfig::hz100());
        // Snapshots written before the draft's variants existed still load.
        let mut v = serde_json::to_value(InteractionConfig::hz100()).expect("serialise");
        let fields = v.as_object_mut().expect("an object");
        assert!(fields.remove("ac_learning_rate").is_some() && fields.remove("selector").is_some());
        let old: InteractionConfig = serde_json::from_value(v).expect("an older snapshot");
        assert_eq!(old, InteractionConfig::hz100());
    }

    #[test]
    fn configuration_numbers() {
        assert_eq!(
            InteractionParams::from_config_number(0),
            Ok(InteractionParams::hz100())
        );
        assert_eq!(
            InteractionParams::from_config_number(4 | 8),
            Ok(InteractionParams::hz100())
        );
        assert_eq!(
            InteractionParams::from_config_number(2),
            Ok(InteractionParams::hz10())
        );
        for bit in [1, 16, 32, 64, 128] {
            assert_eq!(
                InteractionParams::from_config_number(bit | 8),
                Err(InteractionError::UnsupportedFlags(bit | 8, bit))
            );
        }
    }

    #[test]
    fn the_learning_rate_reaches_the_ac_models() {
        let config = InteractionParams {
            ac_learning_rate: 0.2,
            selector: SelectorKind::Tree,
            ..InteractionParams::hz100()
        }
        .check()
        .expect("valid");
        assert_eq!(config.ac().params().eta_out, 0.2);
        assert_eq!(config.ac().params().eta_in, 0.2);
        assert_eq!(config.ac().params().eta_a, 0.2);
        assert_eq!(config.selector(), SelectorKind::Tree);
        assert_eq!(InteractionConfig::hz100().ac().params().eta_out, 0.0);
    }
}
