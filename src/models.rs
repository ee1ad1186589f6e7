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
