//! The two learners, selectable by name wherever a model is used.

use learner::gate::VelocityFeatures;
use learner::interaction::SelectorKind;
use learner::{GateConfig, GateParams, InteractionConfig, InteractionParams};
use serde::{Deserialize, Serialize};

/// Which learner to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// Object-state model with a gating function (`docs/spec/gate-model.md`).
    Gate,
    /// Interaction-state model with Abstract Collections (`docs/spec/interaction-model.md`).
    Interaction,
}

impl ModelKind {
    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            ModelKind::Gate => "gate",
            ModelKind::Interaction => "interaction",
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The learner an experiment runs: a built-in model, in-process, or an
/// external one over the learner protocol (`crate::external`).
#[derive(Clone, Debug, PartialEq)]
pub enum LearnerChoice {
    Builtin(ModelKind),
    External(crate::external::LearnerSpec),
}

/// The choice as `pushlearn experiment` flags: `--model gate`,
/// `--learner 'CMD'` or `--learner-connect ADDR`.
impl std::fmt::Display for LearnerChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use crate::external::Source;
        match self {
            LearnerChoice::Builtin(kind) => write!(f, "--model {kind}"),
            LearnerChoice::External(spec) => {
                match &spec.source {
                    Source::Command(command) => write!(f, "--learner '{command}'")?,
                    Source::Connect(addr) => write!(f, "--learner-connect {addr}")?,
                }
                if spec.timeout != crate::external::DEFAULT_TIMEOUT {
                    write!(f, " --learner-timeout {}", spec.timeout.as_secs_f64())?;
                }
                Ok(())
            }
        }
    }
}

impl From<ModelKind> for LearnerChoice {
    fn from(kind: ModelKind) -> Self {
        LearnerChoice::Builtin(kind)
    }
}

/// Something to do with an untrained model of either kind: the one generic
/// entry point that [`ModelKind::dispatch`] instantiates for each learner.
pub trait WithModel {
    /// The result.
    type Output;
    /// Runs with `untrained`.
    fn run<M: learner::Model + 'static>(self, untrained: M) -> Self::Output;
}

/// A command-line name for each configuration bit of the original
/// (`docs/spec/experiments.md` §1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ConfigFlag {
    /// 1, USE_DYNS: the block predictors also see the block's velocity
    /// (gate model).
    UseDyns,
    /// 2, LOWFREQ: 10 Hz publish rate and thresholds.
    LowFreq,
    /// 4, ALLOWMISSPOSITIONS: random training starts in [−0.35, 0.35).
    AllowMissPositions,
    /// 8, FIXFIRSTTHREETRAININGRUNS: first training starts −0.18, 0.18, 0.
    FixFirstThree,
    /// 16, HARDCODEDACT: the actuator moves 0.01·a per message, untrained
    /// (gate model).
    HardCodedActuator,
    /// 32, HARDCODEDGATE: a geometric contact rule instead of the learned
    /// gate (gate model).
    HardCodedGate,
    /// 64, USINGPREDICTIONBOOST: predicted block changes × 1.5 (gate model).
    PredictionBoost,
}

impl ConfigFlag {
    /// The bit.
    #[must_use]
    pub fn bit(self) -> u32 {
        use learner::flags;
        match self {
            ConfigFlag::UseDyns => flags::USE_DYNS,
            ConfigFlag::LowFreq => flags::LOWFREQ,
            ConfigFlag::AllowMissPositions => flags::ALLOWMISSPOSITIONS,
            ConfigFlag::FixFirstThree => flags::FIXFIRSTTHREETRAININGRUNS,
            ConfigFlag::HardCodedActuator => flags::HARDCODEDACT,
            ConfigFlag::HardCodedGate => flags::HARDCODEDGATE,
            ConfigFlag::PredictionBoost => flags::USINGPREDICTIONBOOST,
        }
    }
}

/// The model variants of the original's configuration bits and of the
/// thesis draft: shared by `pushlearn experiment …` and `pushlearn learn`.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct ModelOptions {
    /// Configuration number of the original: the sum of its bits (1
    /// USE_DYNS, 2 LOWFREQ, 4 ALLOWMISSPOSITIONS, 8 FIXFIRSTTHREETRAININGRUNS,
    /// 16 HARDCODEDACT, 32 HARDCODEDGATE, 64 USINGPREDICTIONBOOST).
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=i64::from(learner::flags::ALL)))]
    pub config: u32,

    /// Configuration bits by name, comma-separated; added to --config.
    #[arg(
        long = "flag",
        value_name = "FLAG,…",
        value_enum,
        value_delimiter = ','
    )]
    pub flags: Vec<ConfigFlag>,

    /// Learning rate η (η_in = η_out = η_A) of the forward models: the gate
    /// model's actuator and block predictors, the interaction model's ACs.
    /// 0 in the final thesis; the draft's tables use 0.0, 0.1 and 0.2.
    #[arg(long, value_name = "ETA", default_value_t = 0.0, value_parser = parse_rate)]
    pub eta: f64,

    /// The interaction model's Abstract Collection Selector: aitm (final
    /// thesis), tree (the draft's decision tree, refitted on every stored
    /// reference), incremental-tree (Hoeffding tree, keeps no references) or
    /// nearest (the nearest stored reference: the draft's naive baseline).
    #[arg(long, value_name = "KIND", default_value = "aitm", value_parser = parse_selector)]
    pub selector: SelectorKind,

    /// With USE_DYNS, leave the block's angular velocity out (the draft's
    /// "NoAV" rows).
    #[arg(long)]
    pub no_angular_velocity: bool,
}

fn parse_rate(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| format!("'{text}' is not a finite, non-negative number"))
}

fn parse_selector(text: &str) -> Result<SelectorKind, String> {
    SelectorKind::ALL
        .into_iter()
        .find(|k| k.as_str() == text)
        .ok_or_else(|| {
            let names: Vec<&str> = SelectorKind::ALL.iter().map(|k| k.as_str()).collect();
            format!("unknown selector '{text}'; one of: {}", names.join(", "))
        })
}

/// Why a combination of [`ModelOptions`] cannot configure a model.
#[derive(Debug, thiserror::Error)]
pub enum ModelOptionsError {
    #[error("gate model: {0}")]
    Gate(#[from] learner::gate::GateError),
    #[error("interaction model: {0}")]
    Interaction(#[from] learner::interaction::InteractionError),
    #[error("{option} does not apply to the {model} model")]
    NotForModel {
        option: &'static str,
        model: ModelKind,
    },
    #[error(
        "--no-angular-velocity needs velocity features (--flag use-dyns or bit 1 of --config)"
    )]
    NoVelocities,
    #[error("{option} configures a built-in model; an external learner takes its options on its own command line")]
    NotForExternal { option: String },
}

impl ModelOptions {
    /// --config with every --flag added.
    #[must_use]
    pub fn config_number(&self) -> u32 {
        self.flags.iter().fold(self.config, |n, f| n | f.bit())
    }

    /// The options in one canonical line (the bits as one number, however
    /// they were given), e.g. stored with a learner's memory so that it is
    /// never resumed under other options.
    #[must_use]
    pub fn canonical(&self) -> String {
        format!(
            "config {}, eta {}, selector {}, no-angular-velocity {}",
            self.config_number(),
            self.eta,
            self.selector.as_str(),
            self.no_angular_velocity
        )
    }

    /// Refuses what only configures a built-in model: --eta, --selector,
    /// --no-angular-velocity and the model bits of --config (1, 16, 32, 64).
    /// The driver's bits (2, 4, 8: rate and training starts) apply to any
    /// learner.
    ///
    /// # Errors
    /// The first option that does not apply, named.
    pub fn check_external(&self) -> Result<(), ModelOptionsError> {
        use learner::flags;
        let refuse = |option: &str| {
            Err(ModelOptionsError::NotForExternal {
                option: option.to_owned(),
            })
        };
        if self.eta != 0.0 {
            return refuse("--eta");
        }
        if self.selector != SelectorKind::Aitm {
            return refuse("--selector");
        }
        if self.no_angular_velocity {
            return refuse("--no-angular-velocity");
        }
        let model_bits = flags::USE_DYNS
            | flags::HARDCODEDACT
            | flags::HARDCODEDGATE
            | flags::USINGPREDICTIONBOOST;
        let bits = self.config_number() & model_bits;
        if bits != 0 {
            return refuse(&format!("configuration bits {bits} (of --config/--flag)"));
        }
        Ok(())
    }

    /// Whether LOWFREQ is set.
    #[must_use]
    pub fn low_frequency(&self) -> bool {
        self.config_number() & learner::flags::LOWFREQ != 0
    }

    /// The gate model's parameters; a 10 Hz world selects the LOWFREQ
    /// thresholds as bit 2 does.
    ///
    /// # Errors
    /// Options that do not apply to the gate model or invalid values.
    pub fn gate(&self, publish_rate_hz: u32) -> Result<GateConfig, ModelOptionsError> {
        if self.selector != SelectorKind::Aitm {
            return Err(ModelOptionsError::NotForModel {
                option: "--selector",
                model: ModelKind::Gate,
            });
        }
        let mut params = GateParams::from_config_number(self.number_at(publish_rate_hz))?;
        params.forward_learning_rate = self.eta;
        if self.no_angular_velocity {
            if params.velocity_features != VelocityFeatures::LinearAngular {
                return Err(ModelOptionsError::NoVelocities);
            }
            params.velocity_features = VelocityFeatures::Linear;
        }
        Ok(params.check()?)
    }

    /// The interaction model's parameters (see [`ModelOptions::gate`]).
    ///
    /// # Errors
    /// Options that do not apply to the interaction model or invalid values.
    pub fn interaction(
        &self,
        publish_rate_hz: u32,
    ) -> Result<InteractionConfig, ModelOptionsError> {
        if self.no_angular_velocity {
            return Err(ModelOptionsError::NotForModel {
                option: "--no-angular-velocity",
                model: ModelKind::Interaction,
            });
        }
        let mut params = InteractionParams::from_config_number(self.number_at(publish_rate_hz))?;
        params.ac_learning_rate = self.eta;
        params.selector = self.selector;
        Ok(params.check()?)
    }

    fn number_at(&self, publish_rate_hz: u32) -> u32 {
        let low = publish_rate_hz == crate::experiment::LOW_RATE_HZ;
        self.config_number() | if low { learner::flags::LOWFREQ } else { 0 }
    }
}

impl ModelKind {
    /// Calls `job` with an untrained model of this kind configured by
    /// `options` for the world's publish rate (10 Hz: the LOWFREQ
    /// thresholds of `docs/spec/experiments.md` §1, as with bit 2).
    ///
    /// # Errors
    /// Options that do not apply to this model, or invalid values.
    pub fn dispatch<W: WithModel>(
        self,
        options: &ModelOptions,
        publish_rate_hz: u32,
        job: W,
    ) -> Result<W::Output, ModelOptionsError> {
        Ok(match self {
            ModelKind::Gate => job.run(learner::GateModel::new(options.gate(publish_rate_hz)?)),
            ModelKind::Interaction => job.run(learner::InteractionModel::new(
                options.interaction(publish_rate_hz)?,
            )),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(args: &[&str]) -> ModelOptions {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            options: ModelOptions,
        }
        let mut argv = vec!["test"];
        argv.extend_from_slice(args);
        <Cli as clap::Parser>::try_parse_from(argv)
            .expect("valid options")
            .options
    }

    #[test]
    fn defaults_are_the_final_thesis_models() {
        let o = options(&[]);
        assert_eq!(o, ModelOptions::default());
        assert_eq!(o.gate(100).unwrap(), GateConfig::hz100());
        assert_eq!(o.gate(10).unwrap(), GateConfig::hz10());
        assert_eq!(o.interaction(100).unwrap(), InteractionConfig::hz100());
        assert_eq!(o.interaction(10).unwrap(), InteractionConfig::hz10());
    }

    #[test]
    fn names_and_numbers_combine() {
        let o = options(&[
            "--config",
            "8",
            "--flag",
            "hard-coded-gate,hard-coded-actuator",
        ]);
        assert_eq!(o.config_number(), 8 | 16 | 32);
        let g = o.gate(100).unwrap();
        assert!(g.params().hard_coded_actuator && g.params().hard_coded_gate);
        let o = options(&[
            "--flag",
            "use-dyns",
            "--no-angular-velocity",
            "--eta",
            "0.1",
        ]);
        let g = *o.gate(100).unwrap().params();
        assert_eq!(g.velocity_features, VelocityFeatures::Linear);
        assert_eq!(g.forward_learning_rate, 0.1);
        let o = options(&["--flag", "low-freq", "--selector", "tree", "--eta", "0.2"]);
        assert!(o.low_frequency());
        let i = o.interaction(100).unwrap();
        assert_eq!(i.eps_noise(), InteractionConfig::hz10().eps_noise());
        assert_eq!(i.selector(), SelectorKind::Tree);
        assert_eq!(i.ac().params().eta_out, 0.2);
    }

    #[test]
    fn options_that_do_not_apply_are_refused() {
        let tree = options(&["--selector", "nearest"]);
        assert!(matches!(
            tree.gate(100),
            Err(ModelOptionsError::NotForModel { .. })
        ));
        let hg = options(&["--flag", "hard-coded-gate"]);
        assert!(matches!(
            hg.interaction(100),
            Err(ModelOptionsError::Interaction(_))
        ));
        let noav = options(&["--no-angular-velocity"]);
        assert!(matches!(
            noav.gate(100),
            Err(ModelOptionsError::NoVelocities)
        ));
        assert!(matches!(
            noav.interaction(100),
            Err(ModelOptionsError::NotForModel { .. })
        ));
        for bad in [
            &["--eta", "-1"][..],
            &["--eta", "nan"],
            &["--config", "128"],
            &["--selector", "forest"],
            &["--flag", "turbo"],
        ] {
            let mut argv = vec!["test"];
            argv.extend_from_slice(bad);
            #[derive(clap::Parser)]
            struct Cli {
                #[command(flatten)]
                _options: ModelOptions,
            }
            assert!(
                <Cli as clap::Parser>::try_parse_from(argv).is_err(),
                "{bad:?}"
            );
        }
    }
}
