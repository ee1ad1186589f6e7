//! AIM parameters (docs/spec/inverse-model.md §1): unchecked [`AimParams`], validated
//! once into [`AimConfig`].

use serde::{Deserialize, Serialize};

use super::errors::AimError;

/// Unchecked parameters of the Averaging Inverse Model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AimParams {
    /// A change component trains a prototype only if `|d_i| > eps_dif`.
    pub eps_dif: f64,
    /// A precondition component counts as 0 if `|p_j| ≤ eps_node`.
    pub eps_node: f64,
    /// The current feature is kept while `|D_i| > eps_keep` (and same sign).
    pub eps_keep: f64,
    /// A second alternative is offered if its average contribution is
    /// `> ratio ×` the best one's.
    pub ratio: f64,
    /// Combinations merge only if they differ in "zero vs non-zero" in at
    /// most this many components.
    pub max_zero_mismatch: usize,
}

impl AimParams {
    /// The 100 Hz parameters: ε_dif 0.002, ε_node 0.001, ε_keep 0.01.
    pub fn hz100() -> Self {
        Self {
            eps_dif: 0.002,
            eps_node: 0.001,
            eps_keep: 0.01,
            ratio: 0.5,
            max_zero_mismatch: 1,
        }
    }

    /// The 10 Hz parameters: ε_dif 0.02, ε_node 0.01, ε_keep 0.01.
    pub fn hz10() -> Self {
        Self {
            eps_dif: 0.02,
            eps_node: 0.01,
            ..Self::hz100()
        }
    }

    /// Validates the parameters once.
    pub fn check(self) -> Result<AimConfig, AimError> {
        for (name, value) in [
            ("eps_dif", self.eps_dif),
            ("eps_node", self.eps_node),
            ("eps_keep", self.eps_keep),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(AimError::InvalidThreshold { name, value });
            }
        }
        if !(self.ratio.is_finite() && self.ratio >= 0.0) {
            return Err(AimError::InvalidRatio(self.ratio));
        }
        Ok(AimConfig(self))
    }
}

/// Validated AIM parameters. Deserialising re-validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "AimParams", into = "AimParams")]
pub struct AimConfig(AimParams);

impl TryFrom<AimParams> for AimConfig {
    type Error = AimError;

    fn try_from(params: AimParams) -> Result<Self, Self::Error> {
        params.check()
    }
}

impl From<AimConfig> for AimParams {
    fn from(config: AimConfig) -> Self {
        config.0
    }
}

impl AimConfig {
    /// Checked [`AimParams::hz100`].
    pub fn hz100() -> Self {
        Self(AimParams::hz100())
    }

    /// Checked [`AimParams::hz10`].
    pub fn hz10() -> Self {
        Self(AimParams::hz10())
    }

    /// The validated parameters.
    pub fn params(&self) -> &AimParams {
        &self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_the_parameter_table() {
        let p = *AimConfig::hz100().params();
        assert_eq!(
            (
                p.eps_dif,
                p.eps_node,
                p.eps_keep,
                p.ratio,
                p.max_zero_mismatch
            ),
            (0.002, 0.001, 0.01, 0.5, 1)
        );
        let p = *AimConfig::hz10().params();
        assert_eq!(
            (
                p.eps_dif,
                p.eps_node,
                p.eps_keep,
                p.ratio,
                p.max_zero_mismatch
            ),
            (0.02, 0.01, 0.01, 0.5, 1)
        );
        assert_eq!(AimParams::hz100().check(), Ok(AimConfig::hz100()));
        assert_eq!(AimParams::hz10().check(), Ok(AimConfig::hz10()));
    }

    #[test]
    fn rejects_invalid_values() {
        let base = AimParams::hz100();
        let bad = [
            (
                AimParams {
                    eps_dif: -1e-3,
                    ..base
                },
                "eps_dif",
            ),
            (
                AimParams {
                    eps_node: f64::NAN,
                    ..base
                },
                "eps_node",
            ),
            (
                AimParams {
                    eps_keep: f64::INFINITY,
                    ..base
                },
                "eps_keep",
            ),
        ];
        for (p, expected) in bad {
            match p.check() {
                Err(AimError::InvalidThreshold { name, .. }) => assert_eq!(name, expected),
                other => panic!("{expected}: {other:?}"),
            }
        }
        assert_eq!(
            AimParams {
                ratio: -0.5,
                ..base
            }
            .check(),
            Err(AimError::InvalidRatio(-0.5))
        );
        let json = serde_json::to_string(&AimConfig::hz10()).expect("serialise");
        assert!(serde_json::from_str::<AimConfig>(&json.replace("0.5", "NaN")).is_err());
    }
}
