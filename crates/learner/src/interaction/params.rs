//! Parameters of the interaction model (`interaction-model.md` §3,
//! `README.md` §6): unchecked [`InteractionParams`], validated once into
//! [`InteractionConfig`].

use serde::{Deserialize, Serialize};

use super::errors::InteractionError;
use crate::aim::AimConfig;
use crate::features::{EPS_NOISE_100HZ, EPS_NOISE_10HZ};

/// Unchecked parameters. The AITM instances have no free parameters: the
/// ACs are WINNER regressors and the ACS a WINNER classifier with the
/// evaluated values of `aitm.md` §6.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InteractionParams {
    /// ε_noise: a feature belongs to an episode's changed-feature set if
    /// `|d_i| > eps_noise` (`interaction-model.md` §3, §8: 0.001 at 100 Hz,
    /// not the thesis table's 0.01).
    pub eps_noise: f64,
    /// The global inverse model's thresholds (`inverse-model.md` §1),
    /// validated on their own.
    pub aim: AimConfig,
}

impl InteractionParams {
    /// 100 Hz: ε_noise 0.001 and the 100 Hz AIM thresholds.
    #[must_use]
    pub fn hz100() -> Self {
        Self {
            eps_noise: EPS_NOISE_100HZ,
            aim: AimConfig::hz100(),
        }
    }

    /// 10 Hz (configuration bit 2, `experiments.md` §1): ε_noise 0.01 and
    /// the 10 Hz AIM thresholds.
    #[must_use]
    pub fn hz10() -> Self {
        Self {
            eps_noise: EPS_NOISE_10HZ,
            aim: AimConfig::hz10(),
        }
    }

    /// Validates the parameters once.
    pub fn check(self) -> Result<InteractionConfig, InteractionError> {
        if !(self.eps_noise.is_finite() && self.eps_noise >= 0.0) {
            return Err(InteractionError::InvalidEpsNoise(self.eps_noise));
        }
        Ok(InteractionConfig(self))
    }
}

/// Validated parameters. Deserialising re-validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "InteractionParams", into = "InteractionParams")]
pub struct InteractionConfig(InteractionParams);

impl TryFrom<InteractionParams> for InteractionConfig {
    type Error = InteractionError;

    fn try_from(params: InteractionParams) -> Result<Self, Self::Error> {
        params.check()
    }
}

impl From<InteractionConfig> for InteractionParams {
    fn from(config: InteractionConfig) -> Self {
        config.0
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
        Self(InteractionParams::hz100())
    }

    /// Checked [`InteractionParams::hz10`].
    #[must_use]
    pub fn hz10() -> Self {
        Self(InteractionParams::hz10())
    }

    /// The validated parameters.
    #[must_use]
    pub fn params(&self) -> &InteractionParams {
        &self.0
    }

    /// ε_noise.
    #[must_use]
    pub fn eps_noise(&self) -> f64 {
        self.0.eps_noise
    }

    /// The inverse model's parameters.
    #[must_use]
    pub fn aim(&self) -> AimConfig {
        self.0.aim
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
        let json = serde_json::to_string(&InteractionConfig::hz100()).expect("serialise");
        assert!(json.starts_with(r#"{"eps_noise":0.001,"#), "{json}");
        let bad = json.replacen("0.001", "-1.0", 1);
        assert!(serde_json::from_str::<InteractionConfig>(&bad).is_err());
        let back: InteractionConfig = serde_json::from_str(&json).expect("valid");
        assert_eq!(back, InteractionConfig::hz100());
    }
}
