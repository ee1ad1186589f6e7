//! AITM — the Adapted Instantaneous Topological Map (`spec/aitm.md`).
//!
//! A growing graph of nodes in input space, each with an output vector and a
//! local linear map, used as every forward model and classifier of both
//! concepts. Nodes are inserted when the map's own output is wrong for a
//! training sample (output-driven insertion).

mod algorithm;
pub(crate) mod distance;
mod errors;
mod hyperparams;

#[cfg(test)]
mod proptests;
#[cfg(test)]
mod tests;

pub use algorithm::{Aitm, MapStats, NodeId, NodeView};
pub use errors::AitmError;
pub use hyperparams::{AitmConfig, AitmParams, QueryMode, EPS_MAX, SIGMA};
