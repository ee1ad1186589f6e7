//! The model registry: which models there are, their options as plain
//! data with their checks, and building an untrained model from them.
//!
//! Every front end builds its models here — the command line
//! (`crates/cli`, whose clap arguments map onto [`ModelOptions`]), the
//! Python extension (`crates/python`) — so that a model and its refusals
//! are the same wherever it is made. The names here are the command line's
//! and the documents': a report names its model by
//! [`ModelOptions::report_name`], read back by [`ModelKind::of_report_name`].
//!
//! The refusals name options by their command-line flags (`--eta`,
//! `--improve`): those are the options' names in the documentation, and the
//! Python extension's arguments are spelt after them.

use serde::{Deserialize, Serialize};

use crate::gate::Improvements;
use crate::interaction::{InteractionError, SelectorKind};
use crate::{flags, GateConfig, HybridConfig, InteractionConfig};

pub use crate::gate::options::{GateOptionsError, Improvement};
pub use crate::hybrid::Parts;

/// The publish rate that selects the LOWFREQ thresholds, as bit 2 does
/// (`docs/spec/experiments.md` §3.4: the constant-feedback images' rate).
pub const LOW_RATE_HZ: u32 = 10;

pub use pushlearn_core::Named;

/// Which learner to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    Gate,
    Interaction,
    #[serde(rename = "gate+")]
    GatePlus,
    Hybrid,
    Still,
}

impl Named for ModelKind {
    const ALL: &'static [Self] = &[
        ModelKind::Gate,
        ModelKind::Interaction,
        ModelKind::GatePlus,
        ModelKind::Hybrid,
        ModelKind::Still,
    ];

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            ModelKind::Gate => "Object-state model with a gating function (`docs/spec/gate-model.md`)",
            ModelKind::Interaction => {
                "Interaction-state model with Abstract Collections (`docs/spec/interaction-model.md`)"
            }
            ModelKind::GatePlus => {
                "The gate model with every change beyond the thesis (`--improve`, \
                 `docs/models.md` \"Beyond the thesis\"); not the thesis's model"
            }
            ModelKind::Hybrid => {
                "Pushing mechanics identified online plus a memory of their residual \
                 (`docs/models.md` \"The hybrid model\"); not the thesis's model"
            }
            ModelKind::Still => {
                "The reference that predicts nothing moves and never pushes; learns nothing \
                 (`docs/models.md` \"Reference rows\")"
            }
        }
    }
}

impl ModelKind {
    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            ModelKind::Gate => "gate",
            ModelKind::Interaction => "interaction",
            ModelKind::GatePlus => "gate+",
            ModelKind::Hybrid => "hybrid",
            ModelKind::Still => "still",
        }
    }

    /// The thesis's model this one is, or is built on: the gate model for
    /// `gate+`. Tables, figures and the thesis's reference numbers follow it.
    /// The hybrid model and the `still` reference, built on neither, stand
    /// beside the gate model, the thesis's forward model of choice.
    #[must_use]
    pub fn family(self) -> ThesisModel {
        match self {
            ModelKind::Gate | ModelKind::GatePlus | ModelKind::Hybrid | ModelKind::Still => {
                ThesisModel::Gate
            }
            ModelKind::Interaction => ThesisModel::Interaction,
        }
    }

    /// Whether this is a reference row rather than a learner: it learns
    /// nothing (the `still` reference, the zero of the normalised score).
    /// Figures of what learners learn leave it out; tables keep it.
    #[must_use]
    pub fn is_reference(self) -> bool {
        match self {
            ModelKind::Still => true,
            ModelKind::Gate | ModelKind::Interaction | ModelKind::GatePlus | ModelKind::Hybrid => {
                false
            }
        }
    }

    /// The model a report's `model` names, if it is a name
    /// [`ModelOptions::report_name`] gives: `gate`, `interaction`, `gate+`,
    /// or the gate model with some changes (`gate+unrounded+interpolate`,
    /// in the order of [`Improvement::EACH`]) as [`ModelKind::GatePlus`].
    /// `None` for any other name (an external learner's, a typo).
    #[must_use]
    pub fn of_report_name(name: &str) -> Option<ModelKind> {
        if let Some(kind) = ModelKind::from_name(name) {
            return Some(kind);
        }
        if let Some(parts) = name.strip_prefix("hybrid-") {
            return crate::hybrid::Parts::ALL
                .iter()
                .any(|p| *p != crate::hybrid::Parts::Full && p.as_str() == parts)
                .then_some(ModelKind::Hybrid);
        }
        let improve = name
            .strip_prefix("gate+")?
            .split('+')
            .map(Improvement::from_name)
            .collect::<Option<Vec<_>>>()?;
        let options = ModelOptions {
            improve,
            ..ModelOptions::default()
        };
        // Only the spelling reports use: no repeats, no other order, no
        // `all` or every change spelt out (that is `gate+`).
        (options.report_name(ModelKind::Gate) == name).then_some(ModelKind::GatePlus)
    }

    /// Whether `options` configure a model of this kind at this publish
    /// rate, without building one.
    ///
    /// # Errors
    /// As [`ModelKind::dispatch`].
    pub fn check(
        self,
        options: &ModelOptions,
        publish_rate_hz: u32,
    ) -> Result<(), ModelOptionsError> {
        match self {
            ModelKind::Gate => options.gate(publish_rate_hz).map(drop),
            ModelKind::Interaction => options.interaction(publish_rate_hz).map(drop),
            ModelKind::GatePlus => options.gate_plus(publish_rate_hz).map(drop),
            ModelKind::Hybrid => options.hybrid(publish_rate_hz).map(drop),
            ModelKind::Still => options.still(),
        }
    }

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
            ModelKind::Gate => job.run(crate::GateModel::new(options.gate(publish_rate_hz)?)),
            ModelKind::Interaction => job.run(crate::InteractionModel::new(
                options.interaction(publish_rate_hz)?,
            )),
            ModelKind::GatePlus => {
                job.run(crate::GateModel::new(options.gate_plus(publish_rate_hz)?))
            }
            ModelKind::Hybrid => job.run(crate::HybridModel::new(options.hybrid(publish_rate_hz)?)),
            ModelKind::Still => {
                options.still()?;
                job.run(crate::StillModel::default())
            }
        })
    }
}

/// The thesis's two models: what a model's tables, figures and reference
/// numbers follow ([`ModelKind::family`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThesisModel {
    Gate,
    Interaction,
}

impl ThesisModel {
    /// The built-in model that is this thesis model.
    #[must_use]
    pub fn kind(self) -> ModelKind {
        match self {
            ThesisModel::Gate => ModelKind::Gate,
            ThesisModel::Interaction => ModelKind::Interaction,
        }
    }
}

impl std::fmt::Display for ThesisModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.kind().fmt(f)
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Something to do with an untrained model of any kind: the one generic
/// entry point that [`ModelKind::dispatch`] instantiates for each learner.
pub trait WithModel {
    /// The result.
    type Output;
    /// Runs with `untrained`.
    fn run<M: crate::Model + 'static>(self, untrained: M) -> Self::Output;
}

impl Improvement {
    /// The change called `name`.
    ///
    /// # Errors
    /// An unknown name, with the names there are.
    pub fn named(name: &str) -> Result<Improvement, ModelOptionsError> {
        Improvement::from_name(name).ok_or_else(|| ModelOptionsError::UnknownImprovement {
            name: name.to_owned(),
        })
    }
}

/// A name for each configuration bit of the original
/// (`docs/spec/experiments.md` §1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConfigFlag {
    UseDyns,
    LowFreq,
    AllowMissPositions,
    FixFirstThree,
    HardCodedActuator,
    HardCodedGate,
    PredictionBoost,
}

impl Named for ConfigFlag {
    const ALL: &'static [Self] = &[
        ConfigFlag::UseDyns,
        ConfigFlag::LowFreq,
        ConfigFlag::AllowMissPositions,
        ConfigFlag::FixFirstThree,
        ConfigFlag::HardCodedActuator,
        ConfigFlag::HardCodedGate,
        ConfigFlag::PredictionBoost,
    ];

    fn name(self) -> &'static str {
        match self {
            ConfigFlag::UseDyns => "use-dyns",
            ConfigFlag::LowFreq => "low-freq",
            ConfigFlag::AllowMissPositions => "allow-miss-positions",
            ConfigFlag::FixFirstThree => "fix-first-three",
            ConfigFlag::HardCodedActuator => "hard-coded-actuator",
            ConfigFlag::HardCodedGate => "hard-coded-gate",
            ConfigFlag::PredictionBoost => "prediction-boost",
        }
    }

    fn description(self) -> &'static str {
        match self {
            ConfigFlag::UseDyns => {
                "1, USE_DYNS: the block predictors also see the block's velocity (gate model)"
            }
            ConfigFlag::LowFreq => "2, LOWFREQ: 10 Hz publish rate and thresholds",
            ConfigFlag::AllowMissPositions => {
                "4, ALLOWMISSPOSITIONS: random training starts in [−0.35, 0.35)"
            }
            ConfigFlag::FixFirstThree => {
                "8, FIXFIRSTTHREETRAININGRUNS: first training starts −0.18, 0.18, 0"
            }
            ConfigFlag::HardCodedActuator => {
                "16, HARDCODEDACT: the actuator moves 0.01·a per message, untrained (gate model)"
            }
            ConfigFlag::HardCodedGate => {
                "32, HARDCODEDGATE: a geometric contact rule instead of the learned gate \
                 (gate model)"
            }
            ConfigFlag::PredictionBoost => {
                "64, USINGPREDICTIONBOOST: predicted block changes × 1.5 (gate model)"
            }
        }
    }
}

impl ConfigFlag {
    /// The bit.
    #[must_use]
    pub fn bit(self) -> u32 {
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

/// The interaction model's selector called `name`.
///
/// # Errors
/// An unknown name, with the names there are.
pub fn selector(name: &str) -> Result<SelectorKind, ModelOptionsError> {
    SelectorKind::from_name(name).ok_or_else(|| ModelOptionsError::UnknownSelector {
        name: name.to_owned(),
    })
}

/// Whether `eta` can be a learning rate: finite and not negative.
#[must_use]
pub fn is_learning_rate(eta: f64) -> bool {
    eta.is_finite() && eta >= 0.0
}

/// The model variants of the original's configuration bits and of the
/// thesis draft, and the changes beyond the thesis: what configures a
/// built-in model besides its kind. The default is the final thesis's
/// models.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields, rename_all = "kebab-case")]
pub struct ModelOptions {
    /// Configuration number of the original: the sum of its bits.
    pub config: u32,
    /// Configuration bits by name, added to `config`.
    pub flags: Vec<ConfigFlag>,
    /// Learning rate η (η_in = η_out = η_A) of the forward models: the
    /// gate model's actuator and block predictors, the interaction model's
    /// ACs. 0 in the final thesis.
    pub eta: f64,
    /// The interaction model's Abstract Collection Selector.
    pub selector: SelectorKind,
    /// With USE_DYNS, leave the block's angular velocity out (the draft's
    /// "NoAV" rows).
    pub no_angular_velocity: bool,
    /// Changes beyond the thesis for the gate model.
    pub improve: Vec<Improvement>,
    /// The hybrid model's parts (its ablation); all of them by default.
    pub parts: Parts,
}

/// Why a combination of [`ModelOptions`] cannot configure a model.
#[derive(Debug, thiserror::Error)]
pub enum ModelOptionsError {
    #[error(transparent)]
    Gate(#[from] GateOptionsError),
    #[error("interaction model: {0}")]
    Interaction(#[from] InteractionError),
    #[error("{option} does not apply to the {model} model")]
    NotForModel {
        option: &'static str,
        model: ModelKind,
    },
    #[error("{option} configures a built-in model; an external learner takes its options on its own command line")]
    NotForExternal { option: String },
    #[error("{option} configures the thesis's models; the {model} model has none of it")]
    ThesisOptionOnModel { option: String, model: ModelKind },
    #[error("--parts chooses the hybrid model's parts; it does not apply to the {0} model")]
    PartsNotForModel(ModelKind),
    #[error("--improve adds changes to --model gate; gate+ already has every one")]
    ImproveOnGatePlus,
    #[error("eta {0} is not a finite, non-negative number")]
    Eta(f64),
    #[error("unknown selector '{name}'; one of: {}", SelectorKind::names())]
    UnknownSelector { name: String },
    #[error("unknown change '{name}' to improve; one of: {}", Improvement::names())]
    UnknownImprovement { name: String },
}

impl ModelOptions {
    /// `config` with every flag added.
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
        if self.parts != Parts::Full {
            line.push_str(&format!(", parts {}", self.parts.as_str()));
        }
        line
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

    /// The changes of `improve`.
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
        if kind == ModelKind::Hybrid && self.parts != Parts::Full {
            return format!("hybrid-{}", self.parts.as_str());
        }
        let on = self.improvements();
        if kind != ModelKind::Gate || !on.any() {
            return kind.as_str().to_owned();
        }
        if on == Improvements::ALL {
            return ModelKind::GatePlus.as_str().to_owned();
        }
        format!("gate+{}", self.improvement_names().join("+"))
    }

    /// Refuses what only configures a built-in model: the options of the
    /// thesis's models (see `thesis_model_option`) and --parts.
    ///
    /// # Errors
    /// The first option that does not apply, named.
    pub fn check_external(&self) -> Result<(), ModelOptionsError> {
        if let Some(option) = self.thesis_model_option() {
            return Err(ModelOptionsError::NotForExternal { option });
        }
        if self.parts != Parts::Full {
            return Err(ModelOptionsError::NotForExternal {
                option: "--parts".to_owned(),
            });
        }
        Ok(())
    }

    /// Whether LOWFREQ is set.
    #[must_use]
    pub fn low_frequency(&self) -> bool {
        self.config_number() & flags::LOWFREQ != 0
    }

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
        Ok(GateConfig::from_options(
            self.number_at(publish_rate_hz),
            self.eta,
            self.no_angular_velocity,
            self.improvements(),
        )?)
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
        params
            .check()
            .map_err(|e| ModelOptionsError::Gate(e.into()))
    }

    /// The interaction model's parameters (see [`ModelOptions::gate`]).
    ///
    /// # Errors
    /// Options that do not apply to the interaction model or invalid values.
    pub fn interaction(
        &self,
        publish_rate_hz: u32,
    ) -> Result<InteractionConfig, ModelOptionsError> {
        self.check_eta()?;
        self.check_no_parts(ModelKind::Interaction)?;
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
        Ok(InteractionConfig::from_options(
            self.number_at(publish_rate_hz),
            self.eta,
            self.selector,
        )?)
    }

    /// The hybrid model's configuration. It has no thesis variants: the
    /// configuration bits of the model (1, 16, 32, 64), --eta, --selector,
    /// --no-angular-velocity and --improve are refused.
    ///
    /// # Errors
    /// The first option that does not apply, named.
    pub fn hybrid(&self, publish_rate_hz: u32) -> Result<HybridConfig, ModelOptionsError> {
        if let Some(option) = self.thesis_model_option() {
            return Err(ModelOptionsError::ThesisOptionOnModel {
                option,
                model: ModelKind::Hybrid,
            });
        }
        Ok(HybridConfig {
            parts: self.parts,
            publish_rate_hz,
        })
    }

    /// Checks that nothing configures the `still` reference: it has no
    /// options.
    ///
    /// # Errors
    /// The first option set, named.
    pub fn still(&self) -> Result<(), ModelOptionsError> {
        if let Some(option) = self.thesis_model_option() {
            return Err(ModelOptionsError::ThesisOptionOnModel {
                option,
                model: ModelKind::Still,
            });
        }
        self.check_no_parts(ModelKind::Still)
    }

    /// The first option set that configures only the thesis's models
    /// (--eta, --selector, --no-angular-velocity, --improve, the model bits
    /// of --config/--flag: 1, 16, 32, 64), named as the refusals name it.
    /// The driver's bits (2, 4, 8: rate and training starts) apply to any
    /// learner.
    fn thesis_model_option(&self) -> Option<String> {
        if self.eta != 0.0 {
            return Some("--eta".to_owned());
        }
        if self.selector != SelectorKind::Aitm {
            return Some("--selector".to_owned());
        }
        if self.no_angular_velocity {
            return Some("--no-angular-velocity".to_owned());
        }
        if !self.improve.is_empty() {
            return Some("--improve".to_owned());
        }
        let model_bits = flags::USE_DYNS
            | flags::HARDCODEDACT
            | flags::HARDCODEDGATE
            | flags::USINGPREDICTIONBOOST;
        let bits = self.config_number() & model_bits;
        (bits != 0).then(|| format!("configuration bits {bits} (of --config/--flag)"))
    }

    fn check_no_parts(&self, model: ModelKind) -> Result<(), ModelOptionsError> {
        if self.parts == Parts::Full {
            Ok(())
        } else {
            Err(ModelOptionsError::PartsNotForModel(model))
        }
    }

    /// The command line refuses a bad --eta as it parses it; options built
    /// as data (the Python arguments, a document) are checked here.
    fn check_eta(&self) -> Result<(), ModelOptionsError> {
        if is_learning_rate(self.eta) {
            Ok(())
        } else {
            Err(ModelOptionsError::Eta(self.eta))
        }
    }

    fn number_at(&self, publish_rate_hz: u32) -> u32 {
        let low = publish_rate_hz == LOW_RATE_HZ;
        self.config_number() | if low { flags::LOWFREQ } else { 0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gate::VelocityFeatures;

    fn improve(changes: &[Improvement]) -> ModelOptions {
        ModelOptions {
            improve: changes.to_vec(),
            ..ModelOptions::default()
        }
    }

    #[test]
    fn defaults_are_the_final_thesis_models() {
        let o = ModelOptions::default();
        assert_eq!(o.gate(100).unwrap(), GateConfig::hz100());
        assert_eq!(o.gate(10).unwrap(), GateConfig::hz10());
        assert_eq!(o.interaction(100).unwrap(), InteractionConfig::hz100());
        assert_eq!(o.interaction(10).unwrap(), InteractionConfig::hz10());
    }

    #[test]
    fn names_and_numbers_combine() {
        let o = ModelOptions {
            config: 8,
            flags: vec![ConfigFlag::HardCodedGate, ConfigFlag::HardCodedActuator],
            ..ModelOptions::default()
        };
        assert_eq!(o.config_number(), 8 | 16 | 32);
        let g = o.gate(100).unwrap();
        assert!(g.params().hard_coded_actuator && g.params().hard_coded_gate);
        let o = ModelOptions {
            flags: vec![ConfigFlag::UseDyns],
            no_angular_velocity: true,
            eta: 0.1,
            ..ModelOptions::default()
        };
        let g = *o.gate(100).unwrap().params();
        assert_eq!(g.velocity_features, VelocityFeatures::Linear);
        assert_eq!(g.forward_learning_rate, 0.1);
        let o = ModelOptions {
            flags: vec![ConfigFlag::LowFreq],
            selector: SelectorKind::Tree,
            eta: 0.2,
            ..ModelOptions::default()
        };
        assert!(o.low_frequency());
        let i = o.interaction(100).unwrap();
        assert_eq!(i.eps_noise(), InteractionConfig::hz10().eps_noise());
        assert_eq!(i.selector(), SelectorKind::Tree);
        assert_eq!(i.ac().params().eta_out, 0.2);
    }

    #[test]
    fn improvements_name_the_model_and_reach_the_gate_model() {
        use Improvement::{All, ForwardCheck, Unrounded};
        let none = ModelOptions::default();
        assert_eq!(none.report_name(ModelKind::Gate), "gate");
        assert_eq!(none.report_name(ModelKind::GatePlus), "gate+");
        assert!(!none.gate(100).unwrap().params().improvements.any());
        let two = improve(&[ForwardCheck, Unrounded]);
        // The order of Improvement::EACH, whatever the given order.
        assert_eq!(
            two.report_name(ModelKind::Gate),
            "gate+unrounded+forward-check"
        );
        let on = two.gate(100).unwrap().params().improvements;
        assert!(on.unrounded && on.forward_check && !on.interpolate);
        let all = improve(&[All]);
        assert_eq!(all.report_name(ModelKind::Gate), "gate+");
        assert_eq!(
            none.gate_plus(100).unwrap().params().improvements,
            Improvements::ALL
        );
        assert_eq!(all.gate(100).unwrap(), none.gate_plus(100).unwrap());
        assert_eq!(ModelKind::GatePlus.family(), ThesisModel::Gate);
    }

    #[test]
    fn report_names_read_back_only_as_reports_spell_them() {
        assert_eq!(ModelKind::of_report_name("gate"), Some(ModelKind::Gate));
        assert_eq!(
            ModelKind::of_report_name("interaction"),
            Some(ModelKind::Interaction)
        );
        assert_eq!(
            ModelKind::of_report_name("gate+"),
            Some(ModelKind::GatePlus)
        );
        assert_eq!(
            ModelKind::of_report_name("gate+unrounded"),
            Some(ModelKind::GatePlus)
        );
        assert_eq!(
            ModelKind::of_report_name("gate+unrounded+adapt-actuator"),
            Some(ModelKind::GatePlus)
        );
        // Every name report_name gives reads back.
        for i in Improvement::EACH {
            let name = improve(&[i]).report_name(ModelKind::Gate);
            assert_eq!(ModelKind::of_report_name(&name), Some(ModelKind::GatePlus));
        }
        for other in [
            "knn",
            "",
            "Gate",
            "gate+turbo",
            "gate+all",
            "gate+unrounded+",
            "gate++unrounded",
            "gate+unrounded+unrounded",
            "gate+adapt-actuator+unrounded",
            "gate+unrounded+interpolate+adapt-actuator+average-outputs+forward-check+shared-blocks",
            "interaction+unrounded",
        ] {
            assert_eq!(ModelKind::of_report_name(other), None, "{other:?}");
        }
    }

    #[test]
    fn memory_stored_without_improvements_still_compares_equal() {
        let line = ModelOptions::default().canonical();
        assert_eq!(
            line,
            "config 0, eta 0, selector aitm, no-angular-velocity false"
        );
        assert_eq!(
            improve(&[Improvement::Interpolate]).canonical(),
            format!("{line}, improve interpolate")
        );
    }

    #[test]
    fn improve_is_refused_where_it_does_not_apply() {
        let o = improve(&[Improvement::Unrounded]);
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
        let nearest = ModelOptions {
            selector: SelectorKind::Nearest,
            ..ModelOptions::default()
        };
        assert!(matches!(
            nearest.gate(100),
            Err(ModelOptionsError::NotForModel { .. })
        ));
        let hg = ModelOptions {
            flags: vec![ConfigFlag::HardCodedGate],
            ..ModelOptions::default()
        };
        assert!(matches!(
            hg.interaction(100),
            Err(ModelOptionsError::Interaction(_))
        ));
        let noav = ModelOptions {
            no_angular_velocity: true,
            ..ModelOptions::default()
        };
        assert!(matches!(
            noav.gate(100),
            Err(ModelOptionsError::Gate(GateOptionsError::NoVelocities))
        ));
        assert!(matches!(
            noav.interaction(100),
            Err(ModelOptionsError::NotForModel { .. })
        ));
        let unknown_bits = ModelOptions {
            config: 128,
            ..ModelOptions::default()
        };
        assert!(matches!(
            unknown_bits.gate(100),
            Err(ModelOptionsError::Gate(GateOptionsError::Gate(_)))
        ));
        for eta in [-1.0, f64::NAN, f64::INFINITY] {
            let o = ModelOptions {
                eta,
                ..ModelOptions::default()
            };
            assert!(matches!(o.gate(100), Err(ModelOptionsError::Eta(_))));
            assert!(matches!(o.interaction(100), Err(ModelOptionsError::Eta(_))));
        }
    }

    #[test]
    fn names_are_looked_up_exactly_and_refusals_list_them() {
        assert_eq!(
            Improvement::named("average-outputs").unwrap(),
            Improvement::AverageOutputs
        );
        assert_eq!(
            Improvement::named("turbo").unwrap_err().to_string(),
            "unknown change 'turbo' to improve; one of: unrounded, interpolate, \
             forward-check, shared-blocks, adapt-actuator, average-outputs, all"
        );
        assert_eq!(selector("tree").unwrap(), SelectorKind::Tree);
        assert_eq!(
            selector("forest").unwrap_err().to_string(),
            "unknown selector 'forest'; one of: aitm, tree, incremental-tree, nearest"
        );
        assert_eq!(ModelKind::from_name("GATE"), None);
        for flag in ConfigFlag::ALL {
            assert_eq!(ConfigFlag::from_name(flag.name()), Some(*flag));
        }
        // The names are the serialised forms.
        for kind in ModelKind::ALL {
            let json = serde_json::to_string(kind).unwrap();
            assert_eq!(json, format!("\"{}\"", kind.name()));
        }
        for i in Improvement::ALL {
            assert_eq!(
                serde_json::to_string(i).unwrap(),
                format!("\"{}\"", i.name())
            );
        }
        for f in ConfigFlag::ALL {
            assert_eq!(
                serde_json::to_string(f).unwrap(),
                format!("\"{}\"", f.name())
            );
        }
    }

    #[test]
    fn the_hybrid_model_refuses_the_thesis_models_options_and_only_it_takes_parts() {
        let parts = ModelOptions {
            parts: Parts::Mechanics,
            ..ModelOptions::default()
        };
        assert_eq!(parts.hybrid(100).unwrap().parts, Parts::Mechanics);
        assert_eq!(parts.report_name(ModelKind::Hybrid), "hybrid-mechanics");
        assert_eq!(
            ModelKind::of_report_name("hybrid-mechanics"),
            Some(ModelKind::Hybrid)
        );
        assert_eq!(ModelKind::of_report_name("hybrid-full"), None);
        assert!(matches!(
            parts.gate(100),
            Err(ModelOptionsError::PartsNotForModel(ModelKind::Gate))
        ));
        assert!(parts.check_external().is_err());
        let eta = ModelOptions {
            eta: 0.1,
            ..ModelOptions::default()
        };
        let bits = ModelOptions {
            config: 16 | 8,
            ..ModelOptions::default()
        };
        for (options, named) in [
            (eta, "--eta"),
            (bits, "configuration bits 16 (of --config/--flag)"),
        ] {
            match options.hybrid(100) {
                Err(ModelOptionsError::ThesisOptionOnModel {
                    option,
                    model: ModelKind::Hybrid,
                }) => {
                    assert_eq!(option, named);
                }
                other => panic!("{other:?}"),
            }
        }
        // The driver's bits apply to any learner.
        let driver = ModelOptions {
            config: 2 | 4 | 8,
            ..ModelOptions::default()
        };
        assert!(driver.hybrid(10).is_ok() && driver.check_external().is_ok());
    }

    #[test]
    fn options_are_plain_data() {
        let o = ModelOptions {
            config: 8,
            flags: vec![ConfigFlag::UseDyns],
            eta: 0.1,
            selector: SelectorKind::Tree,
            no_angular_velocity: true,
            improve: vec![Improvement::AverageOutputs],
            parts: Parts::Identified,
        };
        let json = serde_json::to_string(&o).unwrap();
        assert_eq!(
            json,
            r#"{"config":8,"flags":["use-dyns"],"eta":0.1,"selector":"tree","no-angular-velocity":true,"improve":["average-outputs"],"parts":"identified"}"#
        );
        assert_eq!(serde_json::from_str::<ModelOptions>(&json).unwrap(), o);
        assert_eq!(
            serde_json::from_str::<ModelOptions>("{}").unwrap(),
            ModelOptions::default()
        );
        assert!(serde_json::from_str::<ModelOptions>(r#"{"improve":["turbo"]}"#).is_err());
        assert!(serde_json::from_str::<ModelOptions>(r#"{"etta":0.1}"#).is_err());
    }

    #[test]
    fn dispatch_builds_the_kind() {
        struct Stats;
        impl WithModel for Stats {
            type Output = crate::ModelStats;
            fn run<M: crate::Model + 'static>(self, untrained: M) -> crate::ModelStats {
                untrained.stats()
            }
        }
        use crate::ModelStats::{Gate, Interaction};
        let o = ModelOptions::default();
        for (kind, gate) in [
            (ModelKind::Gate, true),
            (ModelKind::GatePlus, true),
            (ModelKind::Interaction, false),
        ] {
            let stats = kind.dispatch(&o, 100, Stats).unwrap();
            assert_eq!(matches!(stats, Gate(_)), gate, "{kind}");
            assert_eq!(matches!(stats, Interaction(_)), !gate, "{kind}");
        }
        assert!(ModelKind::GatePlus
            .dispatch(&improve(&[Improvement::Unrounded]), 100, Stats)
            .is_err());
    }
}
