//! An incremental Hoeffding tree (VFDT, Domingos & Hulten 2000) for numeric
//! inputs: every leaf keeps class counts and, per class and feature, a
//! Gaussian estimate (count, mean, M2); no example is stored. Split points are
//! judged on those estimates (as MOA's Gaussian numeric observer does) and a
//! leaf splits when the Hoeffding bound says its best feature beats the second
//! best. Leaves answer with naive Bayes or the majority class, whichever has
//! been right more often at that leaf ("NB adaptive").

use serde::{Deserialize, Serialize};

use super::{arena_is_consistent, leaf_index, majority, Node};

/// Hyperparameters; [`Default`] gives MOA's defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HoeffdingParams {
    /// Examples a leaf sees between two split attempts.
    pub grace_period: u64,
    /// δ: allowed probability of choosing the wrong split feature.
    pub split_confidence: f64,
    /// τ: split anyway once the bound is below this (near ties).
    pub tie_threshold: f64,
    /// Candidate thresholds per feature, equally spaced over the leaf's range.
    pub split_points: usize,
    /// Smallest standard deviation of a Gaussian estimate: the inputs are
    /// rounded to 0.001 (`docs/spec/features.md` §1), so a class whose feature never
    /// varied is still spread over one rounding unit.
    pub min_std: f64,
}

impl Default for HoeffdingParams {
    fn default() -> Self {
        Self {
            grace_period: 200,
            split_confidence: 1e-7,
            tie_threshold: 0.05,
            split_points: 10,
            min_std: 1e-3,
        }
    }
}

/// Running mean and variance (Welford) of one feature for one class, with
/// the range seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
struct Gauss {
    n: f64,
    mean: f64,
    m2: f64,
    min: f64,
    max: f64,
}

impl Gauss {
    fn add(&mut self, v: f64) {
        if self.n == 0.0 {
            self.min = v;
            self.max = v;
        } else {
            self.min = self.min.min(v);
            self.max = self.max.max(v);
        }
        self.n += 1.0;
        let d = v - self.mean;
        self.mean += d / self.n;
        self.m2 += d * (v - self.mean);
    }

    fn std(&self, floor: f64) -> f64 {
        if self.n < 2.0 {
            floor
        } else {
            (self.m2 / (self.n - 1.0)).sqrt().max(floor)
        }
    }

    /// Estimated fraction of this class's values `≤ t`.
    fn fraction_below(&self, t: f64, floor: f64) -> f64 {
        if t < self.min {
            0.0
        } else if t >= self.max {
            1.0
        } else {
            normal_cdf((t - self.mean) / self.std(floor))
        }
    }

    fn log_density(&self, v: f64, floor: f64) -> f64 {
        let s = self.std(floor);
        let z = (v - self.mean) / s;
        -0.5 * z * z - s.ln()
    }
}

/// Φ(z) via erfc (Numerical Recipes' Chebyshev fit, |error| < 1.2e-7).
fn normal_cdf(z: f64) -> f64 {
    let x = -z / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * x.abs());
    let poly = -x * x - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * poly.exp();
    let erfc = if x >= 0.0 { erfc } else { 2.0 - erfc };
    0.5 * erfc
}

/// Entropy in bits of a class distribution.
fn entropy(counts: &[f64]) -> f64 {
    let n: f64 = counts.iter().sum();
    if n <= 0.0 {
        return 0.0;
    }
    counts
        .iter()
        .filter(|&&c| c > 0.0)
        .map(|&c| {
            let p = c / n;
            -p * p.log2()
        })
        .sum()
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Leaf {
    /// Class counts (observed, plus the share estimated at the split that
    /// created the leaf).
    counts: Vec<f64>,
    /// `[class][feature]`.
    stats: Vec<Vec<Gauss>>,
    seen_since_attempt: u64,
    nb_correct: u64,
    mc_correct: u64,
}

/// An incremental classification tree over inputs of one dimension, labels
/// `0, 1, …`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HoeffdingTree {
    dim: usize,
    params: HoeffdingParams,
    nodes: Vec<Node<Leaf>>,
    seen: u64,
}

impl HoeffdingTree {
    /// An empty tree (one leaf without data).
    #[must_use]
    pub fn new(dim: usize, params: HoeffdingParams) -> Self {
        Self {
            dim,
            params,
            nodes: vec![Node::Leaf(Leaf::new(Vec::new()))],
            seen: 0,
        }
    }

    /// Number of examples learned.
    #[must_use]
    pub fn seen(&self) -> u64 {
        self.seen
    }

    /// Number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The leaf's answer for `x`; `None` before any example.
    #[must_use]
    pub fn classify(&self, x: &[f64]) -> Option<usize> {
        match self.nodes.get(leaf_index(&self.nodes, x)?)? {
            Node::Leaf(leaf) => leaf.predict(x, self.params.min_std),
            Node::Split { .. } => None,
        }
    }

    /// Learns one example and splits its leaf if the bound allows.
    ///
    /// # Panics
    /// If `x` has another length than the tree's dimension (the caller's bug).
    pub fn learn(&mut self, x: &[f64], label: usize) {
        assert_eq!(x.len(), self.dim, "input dimension");
        self.seen += 1;
        let Some(at) = leaf_index(&self.nodes, x) else {
            return;
        };
        let params = self.params;
        let Some(Node::Leaf(leaf)) = self.nodes.get_mut(at) else {
            return;
        };
        leaf.learn(x, label, params.min_std);
        if leaf.seen_since_attempt >= params.grace_period {
            leaf.seen_since_attempt = 0;
            if let Some((feature, threshold, left, right)) = leaf.split_decision(&params) {
                let l = self.nodes.len();
                self.nodes.push(Node::Leaf(Leaf::new(left)));
                self.nodes.push(Node::Leaf(Leaf::new(right)));
                self.nodes[at] = Node::Split {
                    feature,
                    threshold,
                    left: l,
                    right: l + 1,
                };
            }
        }
    }

    /// Whether every split is well-formed (checked when a snapshot is
    /// loaded) and every class seen is below `n`.
    #[must_use]
    pub fn is_consistent(&self, n: usize) -> bool {
        arena_is_consistent(&self.nodes, self.dim, |leaf| {
            leaf.counts
                .iter()
                .enumerate()
                .all(|(c, &k)| c < n || k == 0.0)
                && leaf.stats.len() == leaf.counts.len()
                && leaf.stats.iter().all(|s| s.len() == self.dim)
        })
    }
}

impl Leaf {
    fn new(counts: Vec<f64>) -> Self {
        Self {
            stats: Vec::new(),
            counts,
            seen_since_attempt: 0,
            nb_correct: 0,
            mc_correct: 0,
        }
    }

    fn naive_bayes(&self, x: &[f64], floor: f64) -> Option<usize> {
        let n: f64 = self.counts.iter().sum();
        let mut best: Option<(usize, f64)> = None;
        for (c, (&count, stats)) in self.counts.iter().zip(&self.stats).enumerate() {
            if count <= 0.0 {
                continue;
            }
            let mut score = (count / n).ln();
            for (g, &v) in stats.iter().zip(x) {
                if g.n > 0.0 {
                    score += g.log_density(v, floor);
                }
            }
            if best.is_none_or(|(_, b)| score > b) {
                best = Some((c, score));
            }
        }
        best.map(|(c, _)| c)
    }

    fn predict(&self, x: &[f64], floor: f64) -> Option<usize> {
        if self.nb_correct > self.mc_correct {
            self.naive_bayes(x, floor)
                .or_else(|| majority(&self.counts))
        } else {
            majority(&self.counts)
        }
    }

    fn learn(&mut self, x: &[f64], label: usize, floor: f64) {
        if majority(&self.counts) == Some(label) {
            self.mc_correct += 1;
        }
        if self.naive_bayes(x, floor) == Some(label) {
            self.nb_correct += 1;
        }
        if self.counts.len() <= label {
            self.counts.resize(label + 1, 0.0);
        }
        if self.stats.len() < self.counts.len() {
            self.stats
                .resize(self.counts.len(), vec![Gauss::default(); x.len()]);
        }
        self.counts[label] += 1.0;
        for (g, &v) in self.stats[label].iter_mut().zip(x) {
            g.add(v);
        }
        self.seen_since_attempt += 1;
    }

    /// The best split if the Hoeffding bound separates it from the second
    /// best feature: (feature, threshold, class counts left, right).
    fn split_decision(&self, p: &HoeffdingParams) -> Option<(usize, f64, Vec<f64>, Vec<f64>)> {
        let classes = self.counts.iter().filter(|&&c| c > 0.0).count();
        if classes < 2 {
            return None;
        }
        let parent = entropy(&self.counts);
        let dim = self.stats.first()?.len();
        // Best (gain, threshold, left, right) per feature.
        let mut per_feature: Vec<(f64, f64, Vec<f64>, Vec<f64>)> = Vec::with_capacity(dim);
        for f in 0..dim {
            let observed = self.stats.iter().map(|s| s[f]).filter(|g| g.n > 0.0);
            let (lo, hi) = observed.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), g| {
                (lo.min(g.min), hi.max(g.max))
            });
            let mut best: Option<(f64, f64, Vec<f64>, Vec<f64>)> = None;
            if lo < hi {
                for k in 1..=p.split_points {
                    let t = lo + (hi - lo) * k as f64 / (p.split_points + 1) as f64;
                    let left: Vec<f64> = self
                        .stats
                        .iter()
                        .map(|s| s[f].n * s[f].fraction_below(t, p.min_std))
                        .collect();
                    let right: Vec<f64> = self
                        .stats
                        .iter()
                        .zip(&left)
                        .map(|(s, l)| s[f].n - l)
                        .collect();
                    let (nl, nr): (f64, f64) = (left.iter().sum(), right.iter().sum());
                    let n = nl + nr;
                    let gain = parent - (nl * entropy(&left) + nr * entropy(&right)) / n;
                    if best.as_ref().is_none_or(|b| gain > b.0) {
                        best = Some((gain, t, left, right));
                    }
                }
            }
            per_feature.push(best.unwrap_or((0.0, 0.0, Vec::new(), Vec::new())));
        }
        let mut order: Vec<usize> = (0..dim).collect();
        order.sort_by(|&a, &b| {
            per_feature[b]
                .0
                .total_cmp(&per_feature[a].0)
                .then(a.cmp(&b))
        });
        let g1 = per_feature[order[0]].0;
        let g2 = order.get(1).map_or(0.0, |&i| per_feature[i].0);
        let n: f64 = self.counts.iter().sum();
        let range = (classes as f64).log2();
        let bound = (range * range * (1.0 / p.split_confidence).ln() / (2.0 * n)).sqrt();
        if g1 > 0.0 && (g1 - g2 > bound || bound < p.tie_threshold) {
            let (_, t, left, right) = per_feature.swap_remove(order[0]);
            Some((order[0], t, left, right))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_matches_known_values() {
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-7);
        assert!((normal_cdf(1.0) - 0.841_344_746).abs() < 1e-6);
        assert!((normal_cdf(-1.96) - 0.024_997_895).abs() < 1e-6);
    }

    /// Label = which third of x[0] ∈ [0, 3) the point lies in; x[1] is noise.
    fn stream(n: usize) -> impl Iterator<Item = ([f64; 2], usize)> {
        (0..n).map(|i| {
            let x0 = ((i * 7919) % 3000) as f64 / 1000.0;
            let x1 = ((i * 104_729) % 1000) as f64 / 1000.0;
            ([x0, x1], x0 as usize)
        })
    }

    #[test]
    fn learns_without_storing_examples_and_splits_on_the_informative_feature() {
        let mut tree = HoeffdingTree::new(2, HoeffdingParams::default());
        assert_eq!(tree.classify(&[0.0, 0.0]), None);
        for (x, l) in stream(3000) {
            tree.learn(&x, l);
        }
        assert_eq!(tree.seen(), 3000);
        assert!(tree.node_count() > 1, "no split after 3000 examples");
        assert!(matches!(tree.nodes[0], Node::Split { feature: 0, .. }));
        let right = stream(600)
            .filter(|(x, l)| tree.classify(x) == Some(*l))
            .count();
        assert!(right > 540, "{right} of 600");
        assert!(tree.is_consistent(3));
        assert!(!tree.is_consistent(2));
    }

    #[test]
    fn a_single_class_never_splits() {
        let mut tree = HoeffdingTree::new(2, HoeffdingParams::default());
        for (x, _) in stream(1000) {
            tree.learn(&x, 4);
        }
        assert_eq!(tree.node_count(), 1);
        assert_eq!(tree.classify(&[9.0, 9.0]), Some(4));
    }
}
