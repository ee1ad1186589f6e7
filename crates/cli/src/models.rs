//! The two learners, selectable by name wherever a model is used.

use learner::gate::{Improvements, VelocityFeatures};
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
    /// The gate model with every change beyond the thesis (`--improve`,
    /// `docs/models.md` "Beyond the thesis"); not the thesis's model.
    #[value(name = "gate+")]
    #[serde(rename = "gate+")]
    GatePlus,
}

impl ModelKind {
    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            ModelKind::Gate => "gate",
            ModelKind::Interaction => "interaction",
            ModelKind::GatePlus => "gate+",
        }
    }

    /// The thesis's model this one is, or is built on: the gate model for
    /// `gate+`. Tables, figures and the thesis's reference numbers follow it.
    #[must_use]
    pub fn family(self) -> ModelKind {
        match self {
            ModelKind::Gate | ModelKind::GatePlus => ModelKind::Gate,
            ModelKind::Interaction => ModelKind::Interaction,
        }
    }

    /// The model a report's `model` names: `gate`, `interaction`, `gate+`,
    /// or the gate model with some changes (`gate+unrounded+interpolate`,
    /// [`ModelOptions::report_name`]); `None` for other names (external
    /// learners).
    #[must_use]
    pub fn of_report_name(name: &str) -> Option<ModelKind> {
        <ModelKind as clap::ValueEnum>::from_str(name, false)
            .ok()
            .or_else(|| name.starts_with("gate+").then_some(ModelKind::GatePlus))
    }
}

/// One change of the improved gate model (`docs/models.md` "Beyond the
/// thesis"), by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Improvement {
    /// Features, changes and predictions at full precision, not rounded to
    /// 3 decimals.
    Unrounded,
    /// Forward models blend the winner with all its neighbours instead of
    /// the two nearest nodes.
    Interpolate,
    /// The planner ranks the inverse model's push and variants of it with
    /// the forward model.
    ForwardCheck,
    /// One forward and inverse model for every block, block ids left out of
    /// the features.
    SharedBlocks,
    /// The actuator's forward model averages its samples (η = 0.1).
    AdaptActuator,
    /// The block forward models' nodes average the changes they win
    /// (η_out = 0.1).
    AverageOutputs,
    /// Every change (what `--model gate+` has).
    All,
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

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
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

    /// Changes beyond the thesis for the gate model, comma-separated:
    /// unrounded, interpolate, adapt-actuator, average-outputs,
    /// forward-check, shared-blocks, or all (which
    /// is `--model gate+`). Not the thesis's model: reports name it
    /// `gate+CHANGE+…` (docs/models.md, "Beyond the thesis").
    #[arg(long, value_name = "CHANGE,…", value_enum, value_delimiter = ',')]
    pub improve: Vec<Improvement>,
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
    #[error("--improve adds changes to --model gate; gate+ already has every one")]
    ImproveOnGatePlus,
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
        let mut line = format!(
            "config {}, eta {}, selector {}, no-angular-velocity {}",
            self.config_number(),
            self.eta,
            self.selector.as_str(),
            self.no_angular_velocity
        );
        // Only when set, so that memory stored before --improve existed
        // still compares equal.
        let names = self.improvement_names();
        if !names.is_empty() {
            line.push_str(&format!(", improve {}", names.join("+")));
        }
        line
    }

    /// The names of the changes --improve turns on, in the order of
    /// [`Improvement::EACH`] (`all` spelt out), whatever the command line's.
    #[must_use]
    pub fn improvement_names(&self) -> Vec<&'static str> {
        let on = self.improvements();
        Improvement::EACH
            .into_iter()
            .filter(|i| i.is_in(on))
            .map(Improvement::as_str)
            .collect()
    }

    /// The changes of --improve.
    #[must_use]
    pub fn improvements(&self) -> Improvements {
        let mut on = Improvements::default();
        for i in &self.improve {
            i.set(&mut on);
        }
        on
    }

    /// The name reports give a built-in model under these options: the
    /// model's own, or for the gate model with changes `gate+` (all) or
    /// `gate+CHANGE+…` in the order of [`Improvement::EACH`].
    #[must_use]
    pub fn report_name(&self, kind: ModelKind) -> String {
        let on = self.improvements();
        if kind != ModelKind::Gate || !on.any() {
            return kind.as_str().to_owned();
        }
        if on == Improvements::ALL {
            return ModelKind::GatePlus.as_str().to_owned();
        }
        format!("gate+{}", self.improvement_names().join("+"))
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
        if !self.improve.is_empty() {
            return refuse("--improve");
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

    /// The interaction model's parameters (see [`ModelOptions::gate`]).
    ///
    /// # Errors
    /// Options that do not apply to the interaction model or invalid values.
    pub fn interaction(
        &self,
        publish_rate_hz: u32,
    ) -> Result<InteractionConfig, ModelOptionsError> {
        if self.no_angular_velocity || !self.improve.is_empty() {
            return Err(ModelOptionsError::NotForModel {
                option: if self.no_angular_velocity {
                    "--no-angular-velocity"
                } else {
                    "--improve"
                },
                model: ModelKind::Interaction,
            });
        }
        let mut params = InteractionParams::from_config_number(self.number_at(publish_rate_hz))?;
        params.ac_learning_rate = self.eta;
        params.selector = self.selector;
        Ok(params.check()?)
    }

    fn number_at(&self, publish_rate_hz: u32) -> u32 {
        let low = publish_rate_hz == crate::scene::LOW_RATE_HZ;
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
            ModelKind::GatePlus => {
                job.run(learner::GateModel::new(options.gate_plus(publish_rate_hz)?))
            }
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
    fn improvements_name_the_model_and_reach_the_gate_model() {
        let none = options(&[]);
        assert_eq!(none.report_name(ModelKind::Gate), "gate");
        assert_eq!(none.report_name(ModelKind::GatePlus), "gate+");
        assert!(!none.gate(100).unwrap().params().improvements.any());
        let two = options(&["--improve", "forward-check,unrounded"]);
        // The order of Improvement::EACH, whatever the command line's.
        assert_eq!(
            two.report_name(ModelKind::Gate),
            "gate+unrounded+forward-check"
        );
        let on = two.gate(100).unwrap().params().improvements;
        assert!(on.unrounded && on.forward_check && !on.interpolate);
        let all = options(&["--improve", "all"]);
        assert_eq!(all.report_name(ModelKind::Gate), "gate+");
        assert_eq!(
            options(&[]).gate_plus(100).unwrap().params().improvements,
            Improvements::ALL
        );
        assert_eq!(all.gate(100).unwrap(), options(&[]).gate_plus(100).unwrap());
        assert_eq!(
            ModelKind::of_report_name("gate+"),
            Some(ModelKind::GatePlus)
        );
        assert_eq!(
            ModelKind::of_report_name("gate+unrounded"),
            Some(ModelKind::GatePlus)
        );
        assert_eq!(ModelKind::of_report_name("gate"), Some(ModelKind::Gate));
        assert_eq!(ModelKind::of_report_name("knn"), None);
        assert_eq!(ModelKind::GatePlus.family(), ModelKind::Gate);
    }

    #[test]
    fn memory_stored_without_improvements_still_compares_equal() {
        let line = options(&[]).canonical();
        assert_eq!(
            line,
            "config 0, eta 0, selector aitm, no-angular-velocity false"
        );
        assert_eq!(
            options(&["--improve", "interpolate"]).canonical(),
            format!("{line}, improve interpolate")
        );
    }

    #[test]
    fn improve_is_refused_where_it_does_not_apply() {
        let o = options(&["--improve", "unrounded"]);
        assert!(matches!(
            o.gate_plus(100),
            Err(ModelOptionsError::ImproveOnGatePlus)
        ));
        assert!(matches!(
            o.interaction(100),
            Err(ModelOptionsError::NotForModel {
                option: "--improve",
                ..
            })
        ));
        assert!(matches!(
            o.check_external(),
            Err(ModelOptionsError::NotForExternal { .. })
        ));
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
