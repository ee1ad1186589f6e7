//! AITM hyperparameters (docs/spec/aitm.md §1, §6): unchecked [`AitmParams`], validated
//! once into [`AitmConfig`].

use serde::{Deserialize, Serialize};

use super::errors::AitmError;

/// How a map answers queries and computes its own estimate ŷ during
/// `update` (docs/spec/aitm.md §3; the same mode is used for both, §6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum QueryMode {
    /// The winner's local linear output.
    Winner,
    /// Gaussian-weighted blend of winner and second winner.
    BestTwo,
    /// Gaussian-weighted blend of the winner and all its neighbours.
    Neighbour,
}

/// Unchecked AITM hyperparameters. Turn them into an [`AitmConfig`] with
/// [`AitmParams::check`] (or `AitmConfig::try_from`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AitmParams {
    /// Width σ of the Gaussian interpolation weights (docs/spec/aitm.md §3).
    pub sigma: f64,
    /// ε_max: inputs closer than this to the winner do not get a new node, and
    /// second winners closer than this to the winner are deleted (docs/spec/aitm.md §4).
    pub eps_max: f64,
    /// Learning rate of the winner's input vector.
    pub eta_in: f64,
    /// Learning rate of the winner's output vector.
    pub eta_out: f64,
    /// Learning rate of the winner's local linear map `A`.
    pub eta_a: f64,
    /// Query mode, used for queries and for ŷ inside `update`.
    pub mode: QueryMode,
    /// Whether outputs are class labels stored as integers (docs/spec/aitm.md §6).
    pub classifier: bool,
}

/// σ of every instance in the specification (docs/spec/aitm.md §6).
pub const SIGMA: f64 = 0.05;
/// ε_max of every instance in the specification (docs/spec/aitm.md §6).
pub const EPS_MAX: f64 = 0.001;

impl AitmParams {
    /// The evaluated regressor parameters (docs/spec/aitm.md §6): σ 0.05, ε_max 0.001,
    /// all learning rates 0, real-valued outputs.
    pub fn regressor(mode: QueryMode) -> Self {
        Self {
            sigma: SIGMA,
            eps_max: EPS_MAX,
            eta_in: 0.0,
            eta_out: 0.0,
            eta_a: 0.0,
            mode,
            classifier: false,
        }
    }

    /// The evaluated classifier parameters (gate, ACS; docs/spec/aitm.md §6): as
    /// [`AitmParams::regressor`] with WINNER and integer labels.
    pub fn classifier() -> Self {
        Self {
            classifier: true,
            ..Self::regressor(QueryMode::Winner)
        }
    }

    /// These parameters with all three learning rates set to `eta` (the
    /// draft's "ITM η" rows vary them together, thesis draft Tables 6.1/6.2).
    #[must_use]
    pub fn with_learning_rate(self, eta: f64) -> Self {
        Self {
            eta_in: eta,
            eta_out: eta,
            eta_a: eta,
            ..self
        }
    }

    /// Validates the parameters once.
    pub fn check(self) -> Result<AitmConfig, AitmError> {
        let sq = self.sigma * self.sigma;
        if !(self.sigma.is_finite() && self.sigma > 0.0 && sq.is_finite() && sq > 0.0) {
            return Err(AitmError::InvalidSigma(self.sigma));
        }
        if !(self.eps_max.is_finite()
            && self.eps_max >= 0.0
            && (self.eps_max * self.eps_max).is_finite())
        {
            return Err(AitmError::InvalidEpsMax(self.eps_max));
        }
        for (name, value) in [
            ("eta_in", self.eta_in),
            ("eta_out", self.eta_out),
            ("eta_a", self.eta_a),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(AitmError::InvalidRate { name, value });
            }
        }
        Ok(AitmConfig(self))
    }
}

/// Validated AITM hyperparameters. Deserialising re-validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "AitmParams", into = "AitmParams")]
pub struct AitmConfig(AitmParams);

impl TryFrom<AitmParams> for AitmConfig {
    type Error = AitmError;

    fn try_from(params: AitmParams) -> Result<Self, Self::Error> {
        params.check()
    }
}

impl From<AitmConfig> for AitmParams {
    fn from(config: AitmConfig) -> Self {
        config.0
    }
}

impl AitmConfig {
    /// Checked form of [`AitmParams::regressor`] (the parameters are valid
    /// constants, so no check is needed).
    pub fn regressor(mode: QueryMode) -> Self {
        Self(AitmParams::regressor(mode))
    }

    /// Checked form of [`AitmParams::classifier`].
    pub fn classifier() -> Self {
        Self(AitmParams::classifier())
    }

    /// The validated parameters.
    pub fn params(&self) -> &AitmParams {
        &self.0
    }

    /// σ.
    pub fn sigma(&self) -> f64 {
        self.0.sigma
    }

    /// ε_max.
    pub fn eps_max(&self) -> f64 {
        self.0.eps_max
    }

    /// The query mode.
    pub fn mode(&self) -> QueryMode {
        self.0.mode
    }

    /// Whether the map stores integer class labels.
    pub fn is_classifier(&self) -> bool {
        self.0.classifier
    }

    /// Whether any learning rate is non-zero (the winner adaptation of
    /// docs/spec/aitm.md §4 then has an effect).
    pub(crate) fn adapts(&self) -> bool {
        self.0.eta_in != 0.0 || self.0.eta_out != 0.0 || self.0.eta_a != 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluated_instances_are_valid() {
        for mode in [QueryMode::Winner, QueryMode::BestTwo, QueryMode::Neighbour] {
            assert_eq!(
                AitmParams::regressor(mode).check(),
                Ok(AitmConfig::regressor(mode))
            );
        }
        assert_eq!(
            AitmParams::classifier().check(),
            Ok(AitmConfig::classifier())
        );
        let c = AitmConfig::classifier();
        assert!(c.is_classifier());
        assert_eq!(c.mode(), QueryMode::Winner);
        assert_eq!((c.sigma(), c.eps_max()), (0.05, 0.001));
        assert!(!c.adapts());
    }

    #[test]
    fn rejects_bad_sigma() {
        for sigma in [0.0, -0.05, f64::NAN, f64::INFINITY, 1e-200, 1e200] {
            let p = AitmParams {
                sigma,
                ..AitmParams::regressor(QueryMode::BestTwo)
            };
            assert!(
                matches!(p.check(), Err(AitmError::InvalidSigma(_))),
                "{sigma}"
            );
        }
    }

    #[test]
    fn rejects_bad_eps_max_and_accepts_zero() {
        for eps_max in [-0.001, f64::NAN, f64::INFINITY, 1e200] {
            let p = AitmParams {
                eps_max,
                ..AitmParams::classifier()
            };
            assert!(matches!(p.check(), Err(AitmError::InvalidEpsMax(_))));
        }
        let p = AitmParams {
            eps_max: 0.0,
            ..AitmParams::classifier()
        };
        assert!(p.check().is_ok());
    }

    #[test]
    fn rejects_bad_rates() {
        let base = AitmParams::regressor(QueryMode::Winner);
        let cases = [
            (
                AitmParams {
                    eta_in: -0.1,
                    ..base
                },
                "eta_in",
            ),
            (
                AitmParams {
                    eta_out: f64::NAN,
                    ..base
                },
                "eta_out",
            ),
            (
                AitmParams {
                    eta_a: f64::INFINITY,
                    ..base
                },
                "eta_a",
            ),
        ];
        for (p, expected) in cases {
            match p.check() {
                Err(AitmError::InvalidRate { name, .. }) => assert_eq!(name, expected),
                other => panic!("{expected}: {other:?}"),
            }
        }
        let p = AitmParams { eta_a: 0.3, ..base };
        assert!(p.check().expect("valid").adapts());
    }

    #[test]
    fn config_deserialisation_validates() {
        let ok = serde_json::to_string(&AitmConfig::classifier()).expect("serialise");
        let back: AitmConfig = serde_json::from_str(&ok).expect("valid config");
        assert_eq!(back, AitmConfig::classifier());
        let bad = ok.replace("0.05", "-0.05");
        assert!(serde_json::from_str::<AitmConfig>(&bad).is_err());
    }
}
