//! The hybrid model: pushing mechanics whose parameters are identified
//! online, and a memory for the residual the mechanics miss
//! (`docs/models.md` "The hybrid model"). Not a model of the thesis.
//!
//! * [`mechanics`]: contact geometry and quasi-static pushing with friction
//!   at the block's supports (the twist of least dissipation, a linear
//!   programme), free sliding after contact;
//! * [`residual`]: the k-nearest-neighbour memory of residuals;
//! * [`HybridModel`]: the [`Model`](crate::Model) implementation: the
//!   actuator by least squares on the commanded velocities, every block by
//!   the mechanics plus the residual; Move to Target by pushing where the
//!   mechanics say the block goes towards its target.

pub mod mechanics;
mod model;
pub(crate) mod options;
mod planner;
pub mod residual;
#[cfg(test)]
mod tests;

pub use model::{HybridConfig, HybridModel, HybridWorld, Parts};
