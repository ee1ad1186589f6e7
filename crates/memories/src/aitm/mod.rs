//! AITM — the Adapted Instantaneous Topological Map (`docs/spec/aitm.md`).
//!
//! A growing graph of nodes in input space, each with an output vector and a
//! local linear map, used as every forward model and classifier of both
//! concepts. Nodes are inserted when the map's own output is wrong for a
//! training sample (output-driven insertion).
//!
//! ```
//! use memories::aitm::{Aitm, AitmConfig, QueryMode};
//!
//! // An object predictor of the gate model: 8 inputs, 3 outputs, BESTTWO.
//! let mut map = Aitm::new(AitmConfig::regressor(QueryMode::BestTwo), 8, 3);
//! map.update(&[15.0, 0.1, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0], &[0.0, 0.005, 0.0]);
//! let prediction = map.query(&[15.0, 0.1, 0.21, 0.0, 0.0, 0.0, 0.0, 0.0]);
//! assert_eq!(prediction, vec![0.0, 0.005, 0.0]); // one node: its output
//!
//! // A classifier (gate, ACS): integer labels, WINNER.
//! let mut gate = Aitm::new(AitmConfig::classifier(), 2, 1);
//! assert_eq!(gate.classify(&[0.0, 0.0]), None); // never trained
//! gate.update_label(&[0.0, 0.0], 1);
//! assert_eq!(gate.classify(&[0.1, 0.0]), Some(1));
//! assert_eq!(gate.stats().nodes, 1);
//! ```

mod algorithm;
pub(crate) mod distance;
mod errors;
mod hyperparams;
mod index;

#[cfg(test)]
mod proptests;
#[cfg(test)]
mod tests;

pub use algorithm::{Aitm, MapStats, NodeId, NodeView, INDEX_MIN_NODES};
pub use errors::AitmError;
pub use hyperparams::{AitmConfig, AitmParams, QueryMode, EPS_MAX, SIGMA};
