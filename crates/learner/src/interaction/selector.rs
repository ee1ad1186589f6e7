//! The Abstract Collection Selector as a pluggable choice: the final
//! thesis's AITM classifier (`docs/spec/interaction-model.md` §1, the default), the
//! draft's decision tree trained on every stored (interaction state, action)
//! → AC pair (thesis draft §3.2.2, §4.2.2), its incremental variant that
//! keeps no references (asked for in draft §4.2.2), and the naive
//! nearest-reference selection over all stored episodes (draft §4.2.3, the
//! baseline).

use serde::{Deserialize, Serialize};

use crate::aitm::{Aitm, AitmConfig, MapStats};
use crate::features::INTERACTION_INPUT_DIM;
use crate::tree::{Cart, HoeffdingParams, HoeffdingTree};

/// What every selector does: learn which AC an input `[ι, a_local]` led to
/// and name the AC expected for a new input.
pub trait AcSelector {
    /// Learn that input `x` was followed by a change of AC `ac`.
    fn learn(&mut self, x: &[f64], ac: usize);
    /// The AC expected to be responsible for the change after `x`; `None`
    /// before any training.
    fn select(&self, x: &[f64]) -> Option<usize>;
    /// Bring the selector up to date with everything learned (the batch tree
    /// rebuilds if references arrived since its last fit; the others are
    /// always current).
    fn refresh(&mut self) {}
    /// Node statistics in the AITM's terms: learn calls, inserts (stored
    /// references or tree nodes created), current nodes.
    fn stats(&self) -> MapStats;
}

/// Which selector a model uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SelectorKind {
    /// The final thesis's AITM classifier (WINNER, integer labels).
    #[default]
    Aitm,
    /// The draft's decision tree (CART), rebuilt from all stored references
    /// as experience grows.
    Tree,
    /// An incremental Hoeffding tree: no references kept.
    IncrementalTree,
    /// The nearest stored reference's AC (the draft's naive baseline).
    Nearest,
}

impl SelectorKind {
    /// Every kind, in the order reports list them.
    pub const ALL: [SelectorKind; 4] = [
        SelectorKind::Aitm,
        SelectorKind::Tree,
        SelectorKind::IncrementalTree,
        SelectorKind::Nearest,
    ];

    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            SelectorKind::Aitm => "aitm",
            SelectorKind::Tree => "tree",
            SelectorKind::IncrementalTree => "incremental-tree",
            SelectorKind::Nearest => "nearest",
        }
    }
}

impl std::fmt::Display for SelectorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Stored references `(x, AC)`: the draft's episodes as far as selection
/// needs them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct References {
    points: Vec<Vec<f64>>,
    labels: Vec<usize>,
}

impl References {
    fn push(&mut self, x: &[f64], ac: usize) {
        self.points.push(x.to_vec());
        self.labels.push(ac);
    }

    /// Number of references.
    #[must_use]
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Whether none is stored.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    fn consistent(&self, n_acs: usize) -> bool {
        self.points.len() == self.labels.len()
            && self
                .points
                .iter()
                .all(|p| p.len() == INTERACTION_INPUT_DIM && p.iter().all(|v| v.is_finite()))
            && self.labels.iter().all(|&l| l < n_acs)
    }
}

/// The draft's decision tree: every reference kept, the CART refitted on
/// all of them whenever their number has grown by a quarter since the last
/// fit (so the total fitting cost stays a small multiple of one fit) and
/// when training stops.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeSelector {
    references: References,
    tree: Cart,
    /// Number of references the tree was fitted on.
    fitted_on: usize,
}

impl TreeSelector {
    fn new() -> Self {
        Self {
            references: References::default(),
            tree: Cart::fit(INTERACTION_INPUT_DIM, &[], &[]),
            fitted_on: 0,
        }
    }

    fn refit(&mut self) {
        self.tree = Cart::fit(
            INTERACTION_INPUT_DIM,
            &self.references.points,
            &self.references.labels,
        );
        self.fitted_on = self.references.len();
    }

    /// The references kept.
    #[must_use]
    pub fn references(&self) -> &References {
        &self.references
    }

    /// Number of references the current tree was fitted on.
    #[must_use]
    pub fn fitted_on(&self) -> usize {
        self.fitted_on
    }
}

impl AcSelector for TreeSelector {
    fn learn(&mut self, x: &[f64], ac: usize) {
        self.references.push(x, ac);
        let n = self.references.len();
        if n >= self.fitted_on + (self.fitted_on / 4).max(1) {
            self.refit();
        }
    }

    fn select(&self, x: &[f64]) -> Option<usize> {
        self.tree.classify(x)
    }

    fn refresh(&mut self) {
        if self.fitted_on != self.references.len() {
            self.refit();
        }
    }

    fn stats(&self) -> MapStats {
        MapStats {
            update_calls: self.references.len() as u64,
            inserts: self.references.len() as u64,
            nodes: self.tree.node_count(),
        }
    }
}

/// The naive selection: the AC of the nearest stored reference (Euclidean
/// distance over the raw components, as the AITM measures; ties go to the
/// earliest reference).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NearestSelector {
    references: References,
}

impl AcSelector for NearestSelector {
    fn learn(&mut self, x: &[f64], ac: usize) {
        self.references.push(x, ac);
    }

    fn select(&self, x: &[f64]) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        for (p, &ac) in self.references.points.iter().zip(&self.references.labels) {
            let d: f64 = p.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, ac));
            }
        }
        best.map(|(_, ac)| ac)
    }

    fn stats(&self) -> MapStats {
        let n = self.references.len();
        MapStats {
            update_calls: n as u64,
            inserts: n as u64,
            nodes: n,
        }
    }
}

impl AcSelector for HoeffdingTree {
    fn learn(&mut self, x: &[f64], ac: usize) {
        HoeffdingTree::learn(self, x, ac);
    }

    fn select(&self, x: &[f64]) -> Option<usize> {
        self.classify(x)
    }

    fn stats(&self) -> MapStats {
        MapStats {
            update_calls: self.seen(),
            inserts: self.node_count() as u64,
            nodes: self.node_count(),
        }
    }
}

impl AcSelector for Aitm {
    fn learn(&mut self, x: &[f64], ac: usize) {
        // At most 64 ACs (S ⊆ {0, …, 7}): the id always fits.
        self.update_label(x, ac as i64);
    }

    /// The stored labels are AC ids (checked when deserialising).
    fn select(&self, x: &[f64]) -> Option<usize> {
        self.classify(x).and_then(|k| usize::try_from(k).ok())
    }

    fn stats(&self) -> MapStats {
        Aitm::stats(self)
    }
}

/// One selector of any kind. Serialised with its kind under `kind`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Selector {
    /// Boxed: the AITM with its spatial index is several times larger than
    /// the other selectors.
    Aitm(Box<Aitm>),
    Tree(TreeSelector),
    IncrementalTree(HoeffdingTree),
    Nearest(NearestSelector),
}

impl Selector {
    /// An untrained selector of `kind`.
    #[must_use]
    pub fn new(kind: SelectorKind) -> Self {
        match kind {
            SelectorKind::Aitm => Selector::Aitm(Box::new(Aitm::new(
                AitmConfig::classifier(),
                INTERACTION_INPUT_DIM,
                1,
            ))),
            SelectorKind::Tree => Selector::Tree(TreeSelector::new()),
            SelectorKind::IncrementalTree => Selector::IncrementalTree(HoeffdingTree::new(
                INTERACTION_INPUT_DIM,
                HoeffdingParams::default(),
            )),
            SelectorKind::Nearest => Selector::Nearest(NearestSelector::default()),
        }
    }

    /// Which kind this is.
    #[must_use]
    pub fn kind(&self) -> SelectorKind {
        match self {
            Selector::Aitm(_) => SelectorKind::Aitm,
            Selector::Tree(_) => SelectorKind::Tree,
            Selector::IncrementalTree(_) => SelectorKind::IncrementalTree,
            Selector::Nearest(_) => SelectorKind::Nearest,
        }
    }

    /// The AITM classifier, if this is one.
    #[must_use]
    pub fn aitm(&self) -> Option<&Aitm> {
        match self {
            Selector::Aitm(m) => Some(m.as_ref()),
            _ => None,
        }
    }

    fn inner(&self) -> &dyn AcSelector {
        match self {
            Selector::Aitm(s) => s.as_ref(),
            Selector::Tree(s) => s,
            Selector::IncrementalTree(s) => s,
            Selector::Nearest(s) => s,
        }
    }

    fn inner_mut(&mut self) -> &mut dyn AcSelector {
        match self {
            Selector::Aitm(s) => s.as_mut(),
            Selector::Tree(s) => s,
            Selector::IncrementalTree(s) => s,
            Selector::Nearest(s) => s,
        }
    }

    /// Why a deserialised selector cannot serve a model with `n_acs` ACs and
    /// the given trained flag, if it cannot.
    pub(super) fn inconsistency(&self, n_acs: usize, trained: bool) -> Option<&'static str> {
        let learned = self.stats().update_calls > 0;
        match self {
            Selector::Aitm(s) => {
                if s.input_dim() != INTERACTION_INPUT_DIM
                    || s.output_dim() != 1
                    || !s.config().is_classifier()
                {
                    return Some("selector dimensions or kind");
                }
                // The AITM never deletes its last two nodes: trained ⇔ non-empty.
                if trained == s.is_empty() {
                    return Some("selector trained flag contradicts its nodes");
                }
                let valid = |v: f64| v.fract() == 0.0 && v >= 0.0 && v < n_acs as f64;
                if !s.nodes().all(|n| n.w_out.iter().all(|&v| valid(v))) {
                    return Some("selector label names no AC");
                }
                return None;
            }
            Selector::Tree(s) => {
                if !s.references.consistent(n_acs)
                    || !s.tree.is_consistent(n_acs)
                    || s.fitted_on > s.references.len()
                {
                    return Some("selector label names no AC");
                }
            }
            Selector::IncrementalTree(s) => {
                if !s.is_consistent(n_acs) {
                    return Some("selector label names no AC");
                }
            }
            Selector::Nearest(s) => {
                if !s.references.consistent(n_acs) {
                    return Some("selector label names no AC");
                }
            }
        }
        (trained != learned).then_some("selector trained flag contradicts its nodes")
    }
}

impl AcSelector for Selector {
    fn learn(&mut self, x: &[f64], ac: usize) {
        self.inner_mut().learn(x, ac);
    }

    fn select(&self, x: &[f64]) -> Option<usize> {
        self.inner().select(x)
    }

    fn refresh(&mut self) {
        self.inner_mut().refresh();
    }

    fn stats(&self) -> MapStats {
        self.inner().stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// AC 1 when the first component is positive, else AC 0.
    fn sample(i: usize) -> (Vec<f64>, usize) {
        let v = (i as f64 * 0.37).sin();
        let mut x = vec![0.0; INTERACTION_INPUT_DIM];
        x[0] = (v * 1000.0).round() / 1000.0;
        x[9] = 0.5;
        (x, usize::from(v > 0.0))
    }

    #[test]
    fn every_kind_learns_a_separable_rule() {
        for kind in SelectorKind::ALL {
            let mut s = Selector::new(kind);
            assert_eq!(s.kind(), kind);
            assert_eq!(s.select(&[0.0; INTERACTION_INPUT_DIM]), None, "{kind}");
            for i in 0..400 {
                let (x, ac) = sample(i);
                s.learn(&x, ac);
            }
            s.refresh();
            assert_eq!(s.stats().update_calls, 400, "{kind}");
            let right = (400..600)
                .filter(|&i| {
                    let (x, ac) = sample(i);
                    s.select(&x) == Some(ac)
                })
                .count();
            assert!(right >= 190, "{kind}: {right} of 200");
            assert_eq!(s.inconsistency(2, true), None, "{kind}");
            assert!(s.inconsistency(1, true).is_some(), "{kind}");
            assert!(s.inconsistency(2, false).is_some(), "{kind}");
            let json = serde_json::to_string(&s).expect("serialise");
            assert!(json.contains(&format!("\"kind\":\"{kind}\"")), "{json:.80}");
            let back: Selector = serde_json::from_str(&json).expect("deserialise");
            assert_eq!(back, s);
        }
    }

    #[test]
    fn the_batch_tree_refits_as_references_grow() {
        let mut s = TreeSelector::new();
        let mut fits = Vec::new();
        for i in 0..100 {
            let (x, ac) = sample(i);
            s.learn(&x, ac);
            if fits.last() != Some(&s.fitted_on()) {
                fits.push(s.fitted_on());
            }
        }
        // 1, 2, … 8 one by one, then every quarter more.
        assert_eq!(
            fits,
            [1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 15, 18, 22, 27, 33, 41, 51, 63, 78, 97]
        );
        assert_eq!(s.references().len(), 100);
        s.refresh();
        assert_eq!(s.fitted_on(), 100);
    }

    #[test]
    fn nearest_returns_the_closest_references_ac() {
        let mut s = NearestSelector::default();
        let mut x = vec![0.0; INTERACTION_INPUT_DIM];
        s.learn(&x, 3);
        x[2] = 1.0;
        s.learn(&x, 5);
        x[2] = 0.6;
        assert_eq!(s.select(&x), Some(5));
        x[2] = 0.5;
        assert_eq!(s.select(&x), Some(3), "ties go to the earlier reference");
    }
}
