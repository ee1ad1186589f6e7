//! The interaction model's options: its checks and its constructor from
//! the registry's [`ModelOptions`], and the selectors by name.

use crate::interaction::{InteractionConfig, InteractionParams, SelectorKind};
use crate::registry::{ModelKind, ModelOptions, ModelOptionsError, Named};

impl Named for SelectorKind {
    const ALL: &'static [Self] = &SelectorKind::ALL;

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            SelectorKind::Aitm => "the final thesis's AITM classifier",
            SelectorKind::Tree => "the draft's decision tree, refitted on every stored reference",
            SelectorKind::IncrementalTree => "Hoeffding tree, keeps no references",
            SelectorKind::Nearest => "the nearest stored reference: the draft's naive baseline",
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

impl ModelOptions {
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
        let mut params = InteractionParams::from_config_number(self.number_at(publish_rate_hz))?;
        params.ac_learning_rate = self.eta;
        params.selector = self.selector;
        Ok(params.check()?)
    }
}
