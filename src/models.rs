//! The two learners, selectable by name wherever a model is used.

use serde::{Deserialize, Serialize};

/// Which learner to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// Object-state model with a gating function (`gate-model.md`).
    Gate,
    /// Interaction-state model with Abstract Collections (`interaction-model.md`).
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

/// Something to do with an untrained model of either kind: the one generic
/// entry point that [`ModelKind::dispatch`] instantiates for each learner.
pub trait WithModel {
    /// The result.
    type Output;
    /// Runs with `untrained`.
    fn run<M: learner::Model + 'static>(self, untrained: M) -> Self::Output;
}

impl ModelKind {
    /// Calls `job` with an untrained model of this kind, configured for the
    /// world's publish rate (10 Hz: the LOWFREQ thresholds of
    /// `experiments.md` §1; anything else: the 100 Hz ones).
    pub fn dispatch<W: WithModel>(self, publish_rate_hz: u32, job: W) -> W::Output {
        let low = publish_rate_hz == crate::experiment::LOW_RATE_HZ;
        match self {
            ModelKind::Gate => job.run(learner::GateModel::new(if low {
                learner::GateConfig::hz10()
            } else {
                learner::GateConfig::hz100()
            })),
            ModelKind::Interaction => job.run(learner::InteractionModel::new(if low {
                learner::InteractionConfig::hz10()
            } else {
                learner::InteractionConfig::hz100()
            })),
        }
    }
}
