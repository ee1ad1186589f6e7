//! A spatial index for the winner and second winner (aitm.md §2, §7): a
//! dynamic k-d tree over the rows of `w_in`.
//!
//! The spec asks for exactly what the brute-force scan returns: the two
//! smallest ranking distances computed in the blocked summation order,
//! compared exactly, ties to the earlier node. The tree therefore only
//! *prunes*: a subtree is skipped when a conservative lower bound of every
//! distance in its bounding box is strictly larger than the current second
//! distance; every candidate that survives gets its distance from
//! [`pairwise_sq_sum`], and ties are decided by row (= node order).
//!
//! Leaves hold up to [`LEAF_CAP`] rows; a fuller leaf is split at the median
//! of its widest axis. Insertions that end too deep rebuild the subtree at
//! the highest unbalanced ancestor (scapegoat rule), so the depth stays
//! logarithmic whatever the insertion order. Removal takes a row out of its
//! leaf; bounding boxes only ever grow, so they stay conservative.

use super::distance::pairwise_sq_sum;

/// Rows per leaf before it is split.
const LEAF_CAP: usize = 16;

/// Scapegoat balance: a child holding more than this share of its parent's
/// rows marks the parent for rebuilding.
const ALPHA: f64 = 0.7;

/// Relative margin of the lower bounds. The bound and a candidate's distance
/// are sums of the same kind of non-negative rounded terms (each term of the
/// bound is at most the candidate's, as rounding is monotone) added in
/// different orders, which changes a sum by at most `(n − 1)·ε` relative;
/// 1e-9 covers that for any dimension up to millions.
const MARGIN: f64 = 1.0 - 1e-9;

const NONE: u32 = u32::MAX;

#[derive(Clone, Debug)]
enum KdNode {
    Leaf(Vec<u32>),
    Inner {
        axis: usize,
        split: f64,
        left: u32,
        right: u32,
    },
    /// A slot on the free list.
    Free,
}

/// A candidate: distance, sum of squares, row.
pub(crate) type Candidate = (f64, f64, usize);

/// Whether candidate `a` ranks before `b`: smaller distance, or equal
/// distance and earlier row (aitm.md §2).
#[inline]
pub(crate) fn ranks_before(a: Candidate, b: Candidate) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.2 < b.2)
}

/// The k-d tree; rows are identified by their index into the map's flat
/// `w_in` (which the caller passes to every operation).
#[derive(Clone, Debug)]
pub(crate) struct KdIndex {
    dim: usize,
    nodes: Vec<KdNode>,
    /// `2·dim` values per node: lower corner, then upper corner.
    bbox: Vec<f64>,
    free: Vec<u32>,
    root: u32,
    /// Leaf of each row, `NONE` if the row is not in the tree.
    leaf_of: Vec<u32>,
    len: usize,
}

impl KdIndex {
    /// A tree over `rows` of `w_in` (`dim` values per row).
    pub(crate) fn build(dim: usize, w_in: &[f64], rows: impl Iterator<Item = usize>) -> Self {
        let mut index = Self {
            dim,
            nodes: Vec::new(),
            bbox: Vec::new(),
            free: Vec::new(),
            root: NONE,
            leaf_of: Vec::new(),
            len: 0,
        };
        let mut all: Vec<u32> = rows.map(|r| r as u32).collect();
        index.len = all.len();
        let root = index.alloc();
        index.build_into(root, &mut all, w_in);
        index.root = root;
        index
    }

    /// Number of rows in the tree.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    fn alloc(&mut self) -> u32 {
        if let Some(slot) = self.free.pop() {
            return slot;
        }
        self.nodes.push(KdNode::Free);
        self.bbox.extend(std::iter::repeat_n(0.0, 2 * self.dim));
        (self.nodes.len() - 1) as u32
    }

    fn row<'a>(&self, w_in: &'a [f64], r: u32) -> &'a [f64] {
        let r = r as usize;
        &w_in[r * self.dim..(r + 1) * self.dim]
    }

    fn set_leaf(&mut self, node: u32, rows: &[u32]) {
        for &r in rows {
            let r = r as usize;
            if r >= self.leaf_of.len() {
                self.leaf_of.resize(r + 1, NONE);
            }
            self.leaf_of[r] = node;
        }
    }

    /// Builds a balanced subtree over `rows` into slot `node`.
    fn build_into(&mut self, node: u32, rows: &mut [u32], w_in: &[f64]) {
        let d = self.dim;
        let (mut lo, mut hi) = (vec![f64::INFINITY; d], vec![f64::NEG_INFINITY; d]);
        for &r in rows.iter() {
            for (j, v) in self.row(w_in, r).iter().enumerate() {
                lo[j] = lo[j].min(*v);
                hi[j] = hi[j].max(*v);
            }
        }
        let b = node as usize * 2 * d;
        self.bbox[b..b + d].copy_from_slice(&lo);
        self.bbox[b + d..b + 2 * d].copy_from_slice(&hi);
        let widest = (0..d)
            .map(|j| (j, hi[j] - lo[j]))
            .filter(|(_, w)| *w > 0.0)
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((axis, _)) = widest.filter(|_| rows.len() > LEAF_CAP) else {
            // Small, or all rows at one point: a leaf.
            self.set_leaf(node, rows);
            self.nodes[node as usize] = KdNode::Leaf(rows.to_vec());
            return;
        };
        let mid = rows.len() / 2;
        let key = |r: &u32| w_in[*r as usize * d + axis];
        rows.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        let split = key(&rows[mid]);
        let (left_rows, right_rows) = rows.split_at_mut(mid);
        let (left, right) = (self.alloc(), self.alloc());
        self.build_into(left, left_rows, w_in);
        self.build_into(right, right_rows, w_in);
        self.nodes[node as usize] = KdNode::Inner {
            axis,
            split,
            left,
            right,
        };
    }

    fn rows_below(&self, node: u32, out: &mut Vec<u32>) {
        match &self.nodes[node as usize] {
            KdNode::Leaf(rows) => out.extend_from_slice(rows),
            KdNode::Inner { left, right, .. } => {
                self.rows_below(*left, out);
                self.rows_below(*right, out);
            }
            KdNode::Free => {}
        }
    }

    fn count_below(&self, node: u32) -> usize {
        match &self.nodes[node as usize] {
            KdNode::Leaf(rows) => rows.len(),
            KdNode::Inner { left, right, .. } => self.count_below(*left) + self.count_below(*right),
            KdNode::Free => 0,
        }
    }

    fn release_below(&mut self, node: u32) {
        if let KdNode::Inner { left, right, .. } =
            std::mem::replace(&mut self.nodes[node as usize], KdNode::Free)
        {
            self.release_below(left);
            self.release_below(right);
            self.free.push(left);
            self.free.push(right);
        }
    }

    /// Rebuilds the subtree at `node` in place.
    fn rebuild(&mut self, node: u32, w_in: &[f64]) {
        let mut rows = Vec::new();
        self.rows_below(node, &mut rows);
        self.release_below(node);
        self.build_into(node, &mut rows, w_in);
    }

    /// Adds row `r` (its values already in `w_in`).
    pub(crate) fn insert(&mut self, r: usize, w_in: &[f64]) {
        let d = self.dim;
        let x = &w_in[r * d..(r + 1) * d];
        let mut path = Vec::new();
        let mut node = self.root;
        loop {
            path.push(node);
            let b = node as usize * 2 * d;
            let (lo, hi) = self.bbox[b..b + 2 * d].split_at_mut(d);
            for ((l, h), v) in lo.iter_mut().zip(hi.iter_mut()).zip(x) {
                *l = l.min(*v);
                *h = h.max(*v);
            }
            match &mut self.nodes[node as usize] {
                KdNode::Inner {
                    axis,
                    split,
                    left,
                    right,
                } => node = if x[*axis] < *split { *left } else { *right },
                KdNode::Leaf(rows) => {
                    rows.push(r as u32);
                    break;
                }
                KdNode::Free => unreachable!("the path only reaches live nodes"),
            }
        }
        self.set_leaf(node, &[r as u32]);
        self.len += 1;
        if matches!(&self.nodes[node as usize], KdNode::Leaf(rows) if rows.len() > LEAF_CAP) {
            self.rebuild(node, w_in);
        }
        // Scapegoat: too deep for the size means some ancestor is unbalanced.
        let limit = 2.0 * ((self.len / LEAF_CAP + 1) as f64).log2() + 4.0;
        if path.len() as f64 > limit {
            let mut size = self.count_below(*path.last().unwrap_or(&self.root));
            for pair in path.windows(2).rev() {
                let (parent, child) = (pair[0], pair[1]);
                let sibling = match &self.nodes[parent as usize] {
                    KdNode::Inner { left, right, .. } => {
                        if *left == child {
                            *right
                        } else {
                            *left
                        }
                    }
                    _ => break,
                };
                let parent_size = size + self.count_below(sibling);
                if size as f64 > ALPHA * parent_size as f64 {
                    self.rebuild(parent, w_in);
                    break;
                }
                size = parent_size;
            }
        }
    }

    /// Removes row `r`.
    pub(crate) fn remove(&mut self, r: usize) {
        let Some(&leaf) = self.leaf_of.get(r).filter(|&&l| l != NONE) else {
            return;
        };
        if let KdNode::Leaf(rows) = &mut self.nodes[leaf as usize] {
            if let Some(k) = rows.iter().position(|&x| x as usize == r) {
                rows.swap_remove(k);
                self.len -= 1;
            }
        }
        self.leaf_of[r] = NONE;
    }

    /// Lower bound of the squared distance from `x` to node's box.
    #[inline]
    fn lower_bound(&self, node: u32, x: &[f64]) -> f64 {
        let d = self.dim;
        let b = node as usize * 2 * d;
        let (lo, hi) = (&self.bbox[b..b + d], &self.bbox[b + d..b + 2 * d]);
        let mut sum = 0.0;
        for j in 0..d {
            let gap = if x[j] < lo[j] {
                lo[j] - x[j]
            } else if x[j] > hi[j] {
                x[j] - hi[j]
            } else {
                0.0
            };
            sum += gap * gap;
        }
        sum * MARGIN
    }

    /// The winner and second winner among the rows in the tree, exactly as
    /// the brute-force scan ranks them, for a finite `x` and finite rows.
    pub(crate) fn nearest_two(
        &self,
        x: &[f64],
        w_in: &[f64],
    ) -> (Option<Candidate>, Option<Candidate>) {
        let mut best: Option<Candidate> = None;
        let mut second: Option<Candidate> = None;
        let mut stack: Vec<(u32, f64)> = vec![(self.root, self.lower_bound(self.root, x))];
        while let Some((node, bound)) = stack.pop() {
            // Every distance in the box is ≥ √bound: strictly farther than
            // the second winner cannot rank, not even by a tie.
            if second.is_some_and(|s| bound.sqrt() > s.0) {
                continue;
            }
            match &self.nodes[node as usize] {
                KdNode::Leaf(rows) => {
                    for &r in rows {
                        let sum = pairwise_sq_sum(self.row(w_in, r), x);
                        let c = (sum.sqrt(), sum, r as usize);
                        if best.is_none_or(|b| ranks_before(c, b)) {
                            second = best;
                            best = Some(c);
                        } else if second.is_none_or(|s| ranks_before(c, s)) {
                            second = Some(c);
                        }
                    }
                }
                KdNode::Inner { left, right, .. } => {
                    let (bl, br) = (self.lower_bound(*left, x), self.lower_bound(*right, x));
                    // The nearer box is searched first (pushed last).
                    if bl <= br {
                        stack.push((*right, br));
                        stack.push((*left, bl));
                    } else {
                        stack.push((*left, bl));
                        stack.push((*right, br));
                    }
                }
                KdNode::Free => {}
            }
        }
        (best, second)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[derive(Debug, Clone)]
    enum Op {
        Insert(Vec<i32>),
        Remove(usize),
        Move(usize, Vec<i32>),
        Query(Vec<i32>),
    }

    fn point(dim: usize) -> impl Strategy<Value = Vec<i32>> {
        // Few distinct values: many exact ties and duplicates.
        prop::collection::vec(prop_oneof![3 => -3i32..=3, 1 => -2000i32..=2000], dim)
    }

    fn ops() -> impl Strategy<Value = (usize, Vec<Op>)> {
        prop_oneof![Just(1usize), Just(2), Just(3), Just(8), Just(10)].prop_flat_map(|dim| {
            let op = prop_oneof![
                4 => point(dim).prop_map(Op::Insert),
                2 => any::<usize>().prop_map(Op::Remove),
                1 => (any::<usize>(), point(dim)).prop_map(|(r, p)| Op::Move(r, p)),
                3 => point(dim).prop_map(Op::Query),
            ];
            (Just(dim), prop::collection::vec(op, 1..400))
        })
    }

    /// The scan's answer over the live rows in row order.
    fn brute(
        dim: usize,
        w_in: &[f64],
        alive: &[bool],
        x: &[f64],
    ) -> (Option<usize>, Option<usize>) {
        let mut all: Vec<Candidate> = (0..alive.len())
            .filter(|&r| alive[r])
            .map(|r| {
                let sum = pairwise_sq_sum(&w_in[r * dim..(r + 1) * dim], x);
                (sum.sqrt(), sum, r)
            })
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
        (all.first().map(|c| c.2), all.get(1).map(|c| c.2))
    }

    fn scale(p: &[i32]) -> Vec<f64> {
        p.iter().map(|&k| f64::from(k) / 1000.0).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn nearest_two_equals_the_scan((dim, ops) in ops()) {
            let mut w_in: Vec<f64> = Vec::new();
            let mut alive: Vec<bool> = Vec::new();
            let mut index = KdIndex::build(dim, &w_in, std::iter::empty());
            let live = |alive: &[bool]| -> Vec<usize> {
                (0..alive.len()).filter(|&r| alive[r]).collect()
            };
            for op in ops {
                match op {
                    Op::Insert(p) => {
                        w_in.extend(scale(&p));
                        alive.push(true);
                        index.insert(alive.len() - 1, &w_in);
                    }
                    Op::Remove(k) => {
                        let rows = live(&alive);
                        if let Some(&r) = rows.get(k % rows.len().max(1)) {
                            alive[r] = false;
                            index.remove(r);
                        }
                    }
                    Op::Move(k, p) => {
                        let rows = live(&alive);
                        if let Some(&r) = rows.get(k % rows.len().max(1)) {
                            index.remove(r);
                            w_in[r * dim..(r + 1) * dim].copy_from_slice(&scale(&p));
                            index.insert(r, &w_in);
                        }
                    }
                    Op::Query(p) => {
                        let x = scale(&p);
                        let (best, second) = index.nearest_two(&x, &w_in);
                        prop_assert_eq!(
                            (best.map(|c| c.2), second.map(|c| c.2)),
                            brute(dim, &w_in, &alive, &x)
                        );
                    }
                }
                prop_assert_eq!(index.len(), live(&alive).len());
            }
        }
    }

    #[test]
    fn sorted_insertions_keep_the_tree_shallow() {
        // Inputs arriving in order (as along a push) would make a chain of
        // one-sided splits without the scapegoat rebuilds.
        let n = 20_000;
        let w_in: Vec<f64> = (0..n).map(|i| f64::from(i) * 0.001).collect();
        let mut index = KdIndex::build(1, &[], std::iter::empty());
        for r in 0..n as usize {
            index.insert(r, &w_in);
        }
        fn depth(index: &KdIndex, node: u32) -> usize {
            match &index.nodes[node as usize] {
                KdNode::Inner { left, right, .. } => {
                    1 + depth(index, *left).max(depth(index, *right))
                }
                _ => 1,
            }
        }
        let limit = 2.0 * ((n as usize / LEAF_CAP + 1) as f64).log2() + 6.0;
        assert!(
            (depth(&index, index.root) as f64) <= limit,
            "{}",
            depth(&index, index.root)
        );
        let (best, second) = index.nearest_two(&[7.0005], &w_in);
        // The two rows nearest to 7.0005, nearer first.
        assert_eq!(
            (best.map(|c| c.2), second.map(|c| c.2)),
            (Some(7000), Some(7001))
        );
    }
}
