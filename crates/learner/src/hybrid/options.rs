//! The hybrid model's own options: its parts (`--parts`) by name.

use pushlearn_core::Named;

use crate::hybrid::Parts;

impl Named for Parts {
    const ALL: &'static [Self] = &Parts::ALL;

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            Parts::Mechanics => {
                "the mechanics alone, with the parameters the shape suggests; learns nothing"
            }
            Parts::Identified => "the mechanics with parameters identified from the messages",
            Parts::Full => "the identified mechanics and the memory of their residual",
        }
    }
}
