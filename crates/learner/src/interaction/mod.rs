//! The pairwise interaction-state model, "interaction model"
//! (`docs/spec/interaction-model.md`).
//!
//! The model sees one interaction state per ordered (block, actuator) pair in
//! the block's frame. Episodes are grouped into **Abstract Collections** by
//! the set of features that changed; each AC learns a local forward model
//! (WINNER AITM), the **AC Selector** (an AITM classifier) learns which AC
//! will be responsible for the next step, and one global Averaging Inverse
//! Model supplies preconditions for Move to Target (`docs/spec/planning.md` §3).
//!
//! | Spec | Here |
//! |---|---|
//! | §1 state, §3 update, §4 reset, §5 prediction | [`InteractionModel`] through [`crate::Model`] |
//! | §2 world state | [`InteractionWorld`] |
//! | §6 node statistics | [`crate::Model::stats`], [`crate::InteractionStats`] |
//! | `docs/spec/planning.md` §3, §4 | [`crate::Model::act`], [`circle_interaction`] |
//! | parameters (100 Hz / 10 Hz) | [`InteractionParams`], [`InteractionConfig`] |
//! | the draft's selectors (draft §3.2.2, §4.2.3) | [`AcSelector`], [`Selector`], [`SelectorKind`] |

mod algorithm;
mod errors;
mod hyperparams;
pub(crate) mod options;
mod planner;
mod selector;

#[cfg(test)]
mod tests;

pub use algorithm::{AbstractCollection, InteractionModel, InteractionWorld};
pub use errors::InteractionError;
pub use hyperparams::{InteractionConfig, InteractionParams};
pub use planner::circle_interaction;
pub use selector::{AcSelector, NearestSelector, References, Selector, SelectorKind, TreeSelector};
