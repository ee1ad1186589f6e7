//! Decision trees for the draft's Abstract Collection Selector
//! (thesis draft §3.2.2, §4.2.2, §4.2.3): a batch CART rebuilt from every
//! stored reference ([`Cart`]) and an incremental Hoeffding tree that keeps
//! only per-leaf statistics ([`HoeffdingTree`]).
//!
//! Written here rather than taken from a crate *(decision)*: the maintained
//! Rust tree crates (linfa-trees, smartcore) bring ndarray or their own
//! matrix types, offer no incremental tree, and their fitted models would
//! have to be serialised and re-validated for the bit-identical snapshots of
//! `Model`; a CART over at most a few thousand 10-dimensional references is
//! a hundred lines. Both trees are deterministic: ties go to the lower
//! feature index, the lower threshold and the lower label.

mod cart;
mod hoeffding;

use serde::{Deserialize, Serialize};

pub use cart::Cart;
pub use hoeffding::{HoeffdingParams, HoeffdingTree};

/// One node of a tree stored in an arena (children by index, always after
/// their parent); `L` is what a leaf keeps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
enum Node<L> {
    Leaf(L),
    Split {
        feature: usize,
        threshold: f64,
        left: usize,
        right: usize,
    },
}

/// Arena index of the leaf `x` falls into (`x[feature] ≤ threshold` goes
/// left); `None` for an empty arena or an `x` shorter than a split needs.
fn leaf_index<L>(nodes: &[Node<L>], x: &[f64]) -> Option<usize> {
    let mut at = 0;
    loop {
        match nodes.get(at)? {
            Node::Leaf(_) => return Some(at),
            Node::Split {
                feature,
                threshold,
                left,
                right,
            } => {
                at = if x.get(*feature)? <= threshold {
                    *left
                } else {
                    *right
                };
            }
        }
    }
}

/// Whether every split of a loaded arena names a feature below `dim`, has a
/// finite threshold and children that point forward inside the arena (so
/// that a descent cannot loop or leave it), and every leaf passes `leaf_ok`.
fn arena_is_consistent<L>(nodes: &[Node<L>], dim: usize, leaf_ok: impl Fn(&L) -> bool) -> bool {
    nodes.iter().enumerate().all(|(at, node)| match node {
        Node::Leaf(leaf) => leaf_ok(leaf),
        Node::Split {
            feature,
            threshold,
            left,
            right,
        } => {
            *feature < dim
                && threshold.is_finite()
                && *left > at
                && *right > at
                && *left < nodes.len()
                && *right < nodes.len()
        }
    })
}

/// The most frequent label of `counts` (index = label); ties go to the
/// lower label. `None` if every count is zero.
fn majority(counts: &[f64]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (label, &c) in counts.iter().enumerate() {
        if c > 0.0 && best.is_none_or(|(_, b)| c > b) {
            best = Some((label, c));
        }
    }
    best.map(|(label, _)| label)
}

#[cfg(test)]
mod tests;
