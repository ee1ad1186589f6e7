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

pub use cart::Cart;
pub use hoeffding::{HoeffdingParams, HoeffdingTree};

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
mod tests {
    use super::majority;

    #[test]
    fn majority_prefers_the_lower_label_on_ties() {
        assert_eq!(majority(&[]), None);
        assert_eq!(majority(&[0.0, 0.0]), None);
        assert_eq!(majority(&[1.0, 3.0, 3.0]), Some(1));
        assert_eq!(majority(&[2.0, 0.0, 1.0]), Some(0));
    }
}
