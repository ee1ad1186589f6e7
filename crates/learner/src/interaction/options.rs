//! The interaction model's own options: its selectors by name, and its
//! configuration from the command line's options, which the registry hands
//! it after refusing those of other models.

use pushlearn_core::Named;

use crate::interaction::{InteractionConfig, InteractionError, InteractionParams, SelectorKind};

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

impl InteractionConfig {
    /// The configuration of the original's configuration number `number`
    /// (the rate's bits included) with the Abstract Collections' learning
    /// rate `eta` and the selector `selector`.
    ///
    /// # Errors
    /// Bits that do not apply, or an invalid value.
    pub fn from_options(
        number: u32,
        eta: f64,
        selector: SelectorKind,
    ) -> Result<InteractionConfig, InteractionError> {
        let mut params = InteractionParams::from_config_number(number)?;
        params.ac_learning_rate = eta;
        params.selector = selector;
        params.check()
    }
}
