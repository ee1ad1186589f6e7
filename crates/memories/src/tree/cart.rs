//! A batch CART classifier (Gini impurity, binary splits `x[f] ≤ t`).

use serde::{Deserialize, Serialize};

use super::{arena_is_consistent, leaf_index, majority, Node};

/// A classification tree fitted to labelled points of one dimension.
///
/// Grown until every leaf is pure or no split separates its points
/// (identical inputs with different labels): the draft's selector is a
/// memory-based lookup, so no pruning *(decision)*.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cart {
    dim: usize,
    /// Leaves keep their label.
    nodes: Vec<Node<usize>>,
}

impl Cart {
    /// Fits a tree to `points` (each of length `dim`) and their `labels`.
    /// An empty training set gives a tree that classifies nothing.
    ///
    /// # Panics
    /// If the two slices differ in length or a point has another length
    /// than `dim` (the caller's bug).
    #[must_use]
    pub fn fit(dim: usize, points: &[Vec<f64>], labels: &[usize]) -> Self {
        assert_eq!(points.len(), labels.len(), "one label per point");
        assert!(points.iter().all(|p| p.len() == dim), "point dimension");
        let mut tree = Self {
            dim,
            nodes: Vec::new(),
        };
        if !points.is_empty() {
            let n_labels = labels.iter().max().map_or(0, |&m| m + 1);
            tree.grow(points, labels, n_labels, (0..points.len()).collect());
        }
        tree
    }

    /// Grows the tree of the points `all`, depth first with the left
    /// subtree before the right one (the arena order of a recursive
    /// pre-order walk), on an explicit stack: an unpruned tree over
    /// thousands of references can be thousands of levels deep.
    fn grow(&mut self, points: &[Vec<f64>], labels: &[usize], n_labels: usize, all: Vec<usize>) {
        let mut pending = vec![Pending {
            idx: all,
            parent: None,
        }];
        while let Some(Pending { idx, parent }) = pending.pop() {
            let mut counts = vec![0.0; n_labels];
            for &i in &idx {
                counts[labels[i]] += 1.0;
            }
            let at = self.nodes.len();
            let label = majority(&counts).unwrap_or(0);
            self.nodes.push(Node::Leaf(label));
            if let Some((split, side)) = parent {
                if let Node::Split { left, right, .. } = &mut self.nodes[split] {
                    match side {
                        Side::Left => *left = at,
                        Side::Right => *right = at,
                    }
                }
            }
            let Some((feature, threshold)) = best_split(points, labels, &counts, &idx, self.dim)
            else {
                continue;
            };
            // Partition keeping the original order on each side, so that
            // the result never depends on an unstable sort.
            let (left, right): (Vec<usize>, Vec<usize>) =
                idx.iter().partition(|&&i| points[i][feature] <= threshold);
            self.nodes[at] = Node::Split {
                feature,
                threshold,
                left: at,
                right: at,
            };
            // Last in, first out: the left subtree is grown first.
            pending.push(Pending {
                idx: right,
                parent: Some((at, Side::Right)),
            });
            pending.push(Pending {
                idx: left,
                parent: Some((at, Side::Left)),
            });
        }
    }

    /// The label of the leaf `x` falls into; `None` for an empty tree.
    #[must_use]
    pub fn classify(&self, x: &[f64]) -> Option<usize> {
        match self.nodes.get(leaf_index(&self.nodes, x)?)? {
            Node::Leaf(label) => Some(*label),
            Node::Split { .. } => None,
        }
    }

    /// Number of nodes (leaves and splits).
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Whether every stored label is below `n` and every child index points
    /// forward inside the arena (checked when a snapshot is loaded, so that
    /// `classify` cannot loop or name an unknown class).
    #[must_use]
    pub fn is_consistent(&self, n: usize) -> bool {
        arena_is_consistent(&self.nodes, self.dim, |&label| label < n)
    }
}

/// A subtree still to grow: its points, and the split whose child it is.
struct Pending {
    idx: Vec<usize>,
    parent: Option<(usize, Side)>,
}

/// Which child of a split a pending subtree becomes.
#[derive(Clone, Copy)]
enum Side {
    Left,
    Right,
}

/// Gini impurity times the count: `n − Σ c² / n`.
fn weighted_gini(counts: &[f64], n: f64) -> f64 {
    if n == 0.0 {
        return 0.0;
    }
    n - counts.iter().map(|c| c * c).sum::<f64>() / n
}

/// The split of an impure `idx` with the lowest weighted Gini impurity, even
/// one that does not lower it (XOR-like layouts need such a first split):
/// threshold halfway between two consecutive distinct values. `None` for a
/// pure set or one whose inputs are all identical.
// `f` indexes the features inside each point, not `points` itself.
#[allow(clippy::needless_range_loop)]
fn best_split(
    points: &[Vec<f64>],
    labels: &[usize],
    counts: &[f64],
    idx: &[usize],
    dim: usize,
) -> Option<(usize, f64)> {
    let n = idx.len() as f64;
    let parent = weighted_gini(counts, n);
    if parent <= 0.0 {
        return None;
    }
    let mut best: Option<(f64, usize, f64)> = None;
    let mut order = idx.to_vec();
    for f in 0..dim {
        order.sort_by(|&a, &b| points[a][f].total_cmp(&points[b][f]).then(a.cmp(&b)));
        let mut left = vec![0.0; counts.len()];
        for k in 0..order.len() - 1 {
            left[labels[order[k]]] += 1.0;
            let (v, next) = (points[order[k]][f], points[order[k + 1]][f]);
            if v == next {
                continue;
            }
            let nl = (k + 1) as f64;
            let right: Vec<f64> = counts.iter().zip(&left).map(|(c, l)| c - l).collect();
            let impurity = weighted_gini(&left, nl) + weighted_gini(&right, n - nl);
            if best.is_none_or(|(b, _, _)| impurity < b) {
                // Halfway, unless `v` and `next` are neighbouring doubles
                // whose midpoint rounds up to `next`: then `v` itself, so
                // that the split still separates them.
                let half = v + (next - v) / 2.0;
                best = Some((impurity, f, if half < next { half } else { v }));
            }
        }
    }
    best.map(|(_, f, t)| (f, t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separates_classes_along_the_informative_feature() {
        // Label 1 iff x[1] > 0.5; x[0] is noise.
        let points: Vec<Vec<f64>> = (0..40)
            .map(|i| vec![(i * 7 % 11) as f64, f64::from(i) / 40.0])
            .collect();
        let labels: Vec<usize> = points.iter().map(|p| usize::from(p[1] > 0.5)).collect();
        let tree = Cart::fit(2, &points, &labels);
        assert_eq!(tree.node_count(), 3, "one split suffices");
        assert_eq!(tree.classify(&[3.0, 0.9]), Some(1));
        assert_eq!(tree.classify(&[3.0, 0.1]), Some(0));
        assert!(tree.is_consistent(2));
        assert!(!tree.is_consistent(1));
        for (p, &l) in points.iter().zip(&labels) {
            assert_eq!(tree.classify(p), Some(l));
        }
    }

    #[test]
    fn empty_and_contradictory_data() {
        let tree = Cart::fit(2, &[], &[]);
        assert_eq!(tree.classify(&[0.0, 0.0]), None);
        // Identical inputs with different labels: one leaf, the majority
        // (ties to the lower label).
        let p = vec![vec![1.0, 1.0]; 4];
        let tree = Cart::fit(2, &p, &[2, 1, 2, 1]);
        assert_eq!(tree.node_count(), 1);
        assert_eq!(tree.classify(&[5.0, 5.0]), Some(1));
        let tree = Cart::fit(2, &p, &[2, 1, 2, 0]);
        assert_eq!(tree.classify(&[1.0, 1.0]), Some(2));
    }

    #[test]
    fn neighbouring_doubles_are_still_separated() {
        // The midpoint of these two rounds to the larger one, which would
        // put both points on the left and never stop splitting.
        let v = f64::from_bits(1.0f64.to_bits() + 1);
        let next = f64::from_bits(v.to_bits() + 1);
        assert_eq!(v + (next - v) / 2.0, next);
        let tree = Cart::fit(1, &[vec![v], vec![next]], &[0, 1]);
        assert_eq!(tree.node_count(), 3);
        assert_eq!(
            (tree.classify(&[v]), tree.classify(&[next])),
            (Some(0), Some(1))
        );
    }

    #[test]
    fn a_tree_thousands_of_levels_deep_grows_without_recursion() {
        // Alternating labels along one axis: every split peels off one
        // point, so the tree is as deep as the data is long.
        let n = 3_000;
        let points: Vec<Vec<f64>> = (0..n).map(|i| vec![f64::from(i)]).collect();
        let labels: Vec<usize> = (0..n).map(|i| usize::from(i % 2 == 1)).collect();
        let tree = std::thread::Builder::new()
            .stack_size(64 * 1024)
            .spawn(move || Cart::fit(1, &points, &labels))
            .expect("thread")
            .join()
            .expect("no stack overflow");
        assert!(tree.is_consistent(2));
        assert_eq!(tree.classify(&[4.0]), Some(0));
        assert_eq!(tree.classify(&[2_999.0]), Some(1));
    }

    #[test]
    fn fits_xor_with_two_levels() {
        let points = vec![
            vec![0.0, 0.0],
            vec![0.0, 1.0],
            vec![1.0, 0.0],
            vec![1.0, 1.0],
        ];
        let labels = [0, 1, 1, 0];
        let tree = Cart::fit(2, &points, &labels);
        for (p, &l) in points.iter().zip(&labels) {
            assert_eq!(tree.classify(p), Some(l), "{p:?}");
        }
    }
}
