//! A spatial index for the winner and second winner (docs/spec/aitm.md §2, §7): a
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
//! the lowest unbalanced ancestor (scapegoat rule, with the row count of
//! every subtree kept in its node), so the depth stays logarithmic whatever
//! the insertion order. Removal takes a row out of its leaf; bounding boxes
//! only ever grow, so they stay conservative.
//!
//! The layout is chosen for maps that outgrow the caches (docs/spec/aitm.md §7: the
//! thesis's named weakness is a memory that slows down as it grows). A
//! search touches a few dozen nodes and leaves wherever they lie, so each
//! touch should cost as few cache misses as possible:
//! * everything the search reads of a sibling pair lies in one block of
//!   whole, aligned cache lines: both boxes, as `f32` rounded outward (the
//!   lower corner down, the upper up, so a box still contains its rows and
//!   the bound stays a lower bound), and both nodes' kinds; the rest of a
//!   node (split, parent, row count), which only insertions and removals
//!   need, lies elsewhere. For 8 inputs a visit reads 3 lines instead of
//!   about 6 (`f64` boxes, unaligned, beside separately stored nodes);
//! * a leaf keeps its row numbers and its own copy of its rows' inputs in
//!   one aligned slot of a slab, so scanning a leaf streams one block
//!   instead of fetching every row from wherever `w_in` keeps it; a row
//!   farther than the second winner is rejected before its number is read;
//! * nodes are small plain values (no per-leaf heap allocation).
//!
//! The box bound is computed without branches (where a query lies against a
//! box is as good as random), with the dimension known at compile time for
//! the instances' input sizes; the pruning test compares the squared bound
//! with a threshold derived once per new second winner instead of taking a
//! root per box.
//!
//! The copies cost `dim` values per row on top of `w_in`; the map keeps
//! them in step by removing a row before its input changes and inserting it
//! again afterwards.

use super::distance::pairwise_sq_sum;

/// Rows per leaf before it is split. With a leaf's inputs contiguous, a
/// longer leaf costs little to scan and saves a tree level, which is a
/// cache miss in a large map: `cargo bench -p memories --bench aitm_scaling`
/// was fastest at 1 M nodes with 32 (of 16, 32, 64) and no slower at 1 k.
const LEAF_CAP: usize = 32;

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

/// The root's slot, paired with an unused node 1; every other node is one
/// of a pair of siblings at `(2k, 2k + 1)`.
const ROOT: u32 = 0;

/// Bytes in a cache line.
const LINE: usize = 64;

/// The search's copy of a node's kind, stored beside its box: `(a, b)` is
/// `(INNER, children)`, `(len, slot)` for a leaf or `(FREE, 0)`.
const INNER: u32 = u32::MAX;
const FREE: u32 = u32::MAX - 1;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Children at `children` and `children + 1`; inserted rows go left when
    /// their `axis` component is below `split`.
    Inner {
        axis: u32,
        split: f64,
        children: u32,
    },
    /// Rows and inputs in slab slot `slot`.
    Leaf { slot: u32, len: u32 },
    /// On the free list (with its sibling).
    Free,
}

impl Kind {
    /// What the search needs of the kind: the `(a, b)` of [`INNER`].
    fn link(self) -> (u32, u32) {
        match self {
            Kind::Inner { children, .. } => (INNER, children),
            Kind::Leaf { slot, len } => (len, slot),
            Kind::Free => (FREE, 0),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    kind: Kind,
    parent: u32,
    /// Rows in the subtree.
    count: u32,
}

/// A growable array whose first element starts a cache line, so that a
/// block of elements laid out to fill whole lines really occupies only
/// those lines (the allocator aligns large blocks to 16 bytes only).
#[derive(Debug)]
struct LineAligned<T> {
    data: Vec<T>,
    /// Padding elements before the first.
    base: usize,
}

impl<T: Copy + Default> LineAligned<T> {
    /// A copy of `items` starting a line, with room for `room` elements.
    fn with_room(items: &[T], room: usize) -> Self {
        let size = size_of::<T>().max(1);
        let mut data = Vec::with_capacity(room.max(items.len()) + LINE / size);
        let base = (LINE - data.as_ptr() as usize % LINE) % LINE / size;
        data.resize(base, T::default());
        data.extend_from_slice(items);
        Self { data, base }
    }

    fn len(&self) -> usize {
        self.data.len() - self.base
    }

    fn as_slice(&self) -> &[T] {
        &self.data[self.base..]
    }

    fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.data[self.base..]
    }

    /// Appends `n` default elements, moving everything to a new aligned
    /// block (of twice the size) when the current one is full.
    fn grow(&mut self, n: usize) {
        if self.data.len() + n > self.data.capacity() {
            *self = Self::with_room(self.as_slice(), 2 * (self.len() + n));
        }
        self.data.resize(self.data.len() + n, T::default());
    }
}

impl<T: Copy + Default> Clone for LineAligned<T> {
    fn clone(&self) -> Self {
        Self::with_room(self.as_slice(), self.len())
    }
}

/// `v` rounded to an `f32` not above it.
fn round_down(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) > v {
        -f32_next_up(-f)
    } else {
        f
    }
}

/// `v` rounded to an `f32` not below it.
fn round_up(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) < v {
        f32_next_up(f)
    } else {
        f
    }
}

/// The least `f32` above a finite or infinite `f` below +∞ (`f32::next_up`
/// is newer than the workspace's minimum Rust).
fn f32_next_up(f: f32) -> f32 {
    if f == 0.0 {
        return f32::from_bits(1);
    }
    let bits = f.to_bits();
    f32::from_bits(if f > 0.0 { bits + 1 } else { bits - 1 })
}

/// The least `f64` above `x`; +∞ stays +∞.
fn f64_next_up(x: f64) -> f64 {
    if x == f64::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f64::from_bits(1);
    }
    let bits = x.to_bits();
    f64::from_bits(if x > 0.0 { bits + 1 } else { bits - 1 })
}

/// A candidate: distance, sum of squares, row.
pub(crate) type Candidate = (f64, f64, usize);

/// Whether candidate `a` ranks before `b`: smaller distance, or equal
/// distance and earlier row (docs/spec/aitm.md §2).
#[inline]
pub(crate) fn ranks_before(a: Candidate, b: Candidate) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.2 < b.2)
}

/// The k-d tree; rows are identified by their index into the map's flat
/// `w_in` (which the caller passes whenever rows are added).
#[derive(Clone, Debug)]
pub(crate) struct KdIndex {
    dim: usize,
    /// Everything about a node that insertions and removals need.
    nodes: Vec<Node>,
    /// What the search reads, one block of `pair_stride` values (whole
    /// cache lines) per sibling pair: the two boxes (lower corner, upper
    /// corner, as `f32` rounded outward), then the two nodes' `(a, b)` of
    /// [`INNER`] as bits.
    pairs: LineAligned<f32>,
    pair_stride: usize,
    /// Free sibling pairs, by their first node.
    free_pairs: Vec<u32>,
    /// One block of `slot_stride` values per leaf slot: `LEAF_CAP` row
    /// numbers (exact in `f64`), then `LEAF_CAP · dim` inputs, the copies
    /// of those rows' inputs.
    slab: LineAligned<f64>,
    slot_stride: usize,
    free_slots: Vec<u32>,
    /// Leaf of each row, `NONE` if the row is not in the tree.
    leaf_of: Vec<u32>,
}

impl KdIndex {
    /// A tree over `rows` of `w_in` (`dim` values per row).
    pub(crate) fn build(dim: usize, w_in: &[f64], rows: impl Iterator<Item = usize>) -> Self {
        let per_line = LINE / size_of::<f32>();
        let mut index = Self {
            dim,
            nodes: Vec::new(),
            pairs: LineAligned::with_room(&[], 0),
            pair_stride: (4 * dim + 4).div_ceil(per_line) * per_line,
            free_pairs: Vec::new(),
            slab: LineAligned::with_room(&[], 0),
            slot_stride: LEAF_CAP * (1 + dim),
            free_slots: Vec::new(),
            leaf_of: Vec::new(),
        };
        let root = index.alloc_pair();
        debug_assert_eq!(root, ROOT);
        let mut all: Vec<u32> = rows.map(|r| r as u32).collect();
        index.build_into(ROOT, &mut all, w_in);
        index
    }

    /// Number of rows in the tree.
    pub(crate) fn len(&self) -> usize {
        self.nodes[ROOT as usize].count as usize
    }

    fn alloc_pair(&mut self) -> u32 {
        if let Some(first) = self.free_pairs.pop() {
            return first;
        }
        let first = self.nodes.len() as u32;
        let free = Node {
            kind: Kind::Free,
            parent: NONE,
            count: 0,
        };
        self.nodes.extend([free, free]);
        self.pairs.grow(self.pair_stride);
        for node in [first, first + 1] {
            self.set_kind(node, Kind::Free);
        }
        first
    }

    fn alloc_slot(&mut self) -> u32 {
        if let Some(slot) = self.free_slots.pop() {
            return slot;
        }
        let slot = (self.slab.len() / self.slot_stride) as u32;
        self.slab.grow(self.slot_stride);
        slot
    }

    fn row<'a>(&self, w_in: &'a [f64], r: u32) -> &'a [f64] {
        let r = r as usize;
        &w_in[r * self.dim..(r + 1) * self.dim]
    }

    /// Where node `node`'s box starts in `pairs`.
    fn box_at(&self, node: u32) -> usize {
        let node = node as usize;
        node / 2 * self.pair_stride + node % 2 * 2 * self.dim
    }

    /// Where node `node`'s `(a, b)` lies in `pairs`.
    fn link_at(&self, node: u32) -> usize {
        let node = node as usize;
        node / 2 * self.pair_stride + 4 * self.dim + node % 2 * 2
    }

    fn set_kind(&mut self, node: u32, kind: Kind) {
        self.nodes[node as usize].kind = kind;
        let at = self.link_at(node);
        let (a, b) = kind.link();
        // Stored as bits: copies keep them, whatever value they spell.
        self.pairs.as_mut_slice()[at..at + 2]
            .copy_from_slice(&[f32::from_bits(a), f32::from_bits(b)]);
    }

    /// The search's copy of node `node`'s kind.
    #[inline]
    fn link(&self, node: u32) -> (u32, u32) {
        let at = self.link_at(node);
        let pairs = self.pairs.as_slice();
        (pairs[at].to_bits(), pairs[at + 1].to_bits())
    }

    /// Where row `k` of slot `slot` has its number in `slab`; its inputs
    /// are at [`Self::input_at`].
    fn row_at(&self, slot: u32, k: usize) -> usize {
        slot as usize * self.slot_stride + k
    }

    fn input_at(&self, slot: u32, k: usize) -> usize {
        slot as usize * self.slot_stride + LEAF_CAP + k * self.dim
    }

    /// The inputs stored in `slot` at position `k`.
    #[cfg(test)]
    fn slab_input(&self, slot: u32, k: usize) -> &[f64] {
        let at = self.input_at(slot, k);
        &self.slab.as_slice()[at..at + self.dim]
    }

    /// The row stored in `slot` at position `k`.
    fn slab_row(&self, slot: u32, k: usize) -> u32 {
        self.slab.as_slice()[self.row_at(slot, k)] as u32
    }

    fn note_leaf(&mut self, r: u32, leaf: u32) {
        let r = r as usize;
        if r >= self.leaf_of.len() {
            self.leaf_of.resize(r + 1, NONE);
        }
        self.leaf_of[r] = leaf;
    }

    /// Appends row `r` to leaf `node` (which has room).
    fn push_to_leaf(&mut self, node: u32, r: u32, x: &[f64]) {
        let Kind::Leaf { slot, len } = self.nodes[node as usize].kind else {
            unreachable!("rows are only pushed to leaves");
        };
        let (row_at, input_at) = (
            self.row_at(slot, len as usize),
            self.input_at(slot, len as usize),
        );
        let slab = self.slab.as_mut_slice();
        slab[row_at] = f64::from(r);
        slab[input_at..input_at + x.len()].copy_from_slice(x);
        self.set_kind(node, Kind::Leaf { slot, len: len + 1 });
        self.note_leaf(r, node);
    }

    /// Sets node `node`'s box to the smallest `f32` box around `lo`..`hi`.
    fn set_box(&mut self, node: u32, lo: &[f64], hi: &[f64]) {
        let (at, d) = (self.box_at(node), self.dim);
        let b = &mut self.pairs.as_mut_slice()[at..at + 2 * d];
        for j in 0..d {
            b[j] = round_down(lo[j]);
            b[d + j] = round_up(hi[j]);
        }
    }

    /// Grows node `node`'s box to contain `x`.
    fn grow_box(&mut self, node: u32, x: &[f64]) {
        let (at, d) = (self.box_at(node), self.dim);
        let b = &mut self.pairs.as_mut_slice()[at..at + 2 * d];
        // Rounded only when the box grows (most insertions reach boxes
        // that hold them already).
        for (j, &v) in x.iter().enumerate() {
            if v < f64::from(b[j]) {
                b[j] = round_down(v);
            }
            if v > f64::from(b[d + j]) {
                b[d + j] = round_up(v);
            }
        }
    }

    /// Builds a balanced subtree over `rows` into node `node`, whose parent
    /// link is already set.
    fn build_into(&mut self, node: u32, rows: &mut [u32], w_in: &[f64]) {
        let d = self.dim;
        let (mut lo, mut hi) = (vec![f64::INFINITY; d], vec![f64::NEG_INFINITY; d]);
        for &r in rows.iter() {
            for (j, v) in self.row(w_in, r).iter().enumerate() {
                lo[j] = lo[j].min(*v);
                hi[j] = hi[j].max(*v);
            }
        }
        self.set_box(node, &lo, &hi);
        self.nodes[node as usize].count = rows.len() as u32;
        if rows.len() <= LEAF_CAP {
            let slot = self.alloc_slot();
            self.set_kind(node, Kind::Leaf { slot, len: 0 });
            for &r in rows.iter() {
                self.push_to_leaf(node, r, &w_in[r as usize * d..(r as usize + 1) * d]);
            }
            return;
        }
        // The widest axis; rows all at one point (a zero-width box) are
        // still split by count, as a leaf has a fixed capacity.
        let axis = (0..d)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        let mid = rows.len() / 2;
        let key = |r: &u32| w_in[*r as usize * d + axis];
        rows.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        let split = key(&rows[mid]);
        let (left_rows, right_rows) = rows.split_at_mut(mid);
        let children = self.alloc_pair();
        self.set_kind(
            node,
            Kind::Inner {
                axis: axis as u32,
                split,
                children,
            },
        );
        for child in [children, children + 1] {
            self.nodes[child as usize].parent = node;
        }
        self.build_into(children, left_rows, w_in);
        self.build_into(children + 1, right_rows, w_in);
    }

    fn rows_below(&self, node: u32, out: &mut Vec<u32>) {
        match self.nodes[node as usize].kind {
            Kind::Leaf { slot, len } => {
                out.extend((0..len as usize).map(|k| self.slab_row(slot, k)));
            }
            Kind::Inner { children, .. } => {
                self.rows_below(children, out);
                self.rows_below(children + 1, out);
            }
            Kind::Free => {}
        }
    }

    /// Frees every node and slot below `node` and `node`'s own slot.
    fn release_below(&mut self, node: u32) {
        match self.nodes[node as usize].kind {
            Kind::Leaf { slot, .. } => self.free_slots.push(slot),
            Kind::Inner { children, .. } => {
                self.release_below(children);
                self.release_below(children + 1);
                for child in [children, children + 1] {
                    self.set_kind(child, Kind::Free);
                }
                self.free_pairs.push(children);
            }
            Kind::Free => {}
        }
        self.set_kind(node, Kind::Free);
    }

    /// Rebuilds the subtree at `node` in place, with `extra` rows added.
    fn rebuild(&mut self, node: u32, extra: Option<u32>, w_in: &[f64]) {
        let mut rows = Vec::with_capacity(self.nodes[node as usize].count as usize + 1);
        self.rows_below(node, &mut rows);
        rows.extend(extra);
        self.release_below(node);
        self.build_into(node, &mut rows, w_in);
    }

    /// Adds row `r` (its values already in `w_in`).
    pub(crate) fn insert(&mut self, r: usize, w_in: &[f64]) {
        let d = self.dim;
        let x = &w_in[r * d..(r + 1) * d];
        let mut node = ROOT;
        let mut depth = 1;
        loop {
            self.grow_box(node, x);
            self.nodes[node as usize].count += 1;
            match self.nodes[node as usize].kind {
                Kind::Inner {
                    axis,
                    split,
                    children,
                } => {
                    node = children + u32::from(x[axis as usize] >= split);
                    depth += 1;
                }
                Kind::Leaf { len, .. } => {
                    if (len as usize) < LEAF_CAP {
                        self.push_to_leaf(node, r as u32, x);
                    } else {
                        // The count already includes `r`; the rebuild sets
                        // it again from the rows.
                        self.rebuild(node, Some(r as u32), w_in);
                        depth += 1;
                    }
                    break;
                }
                Kind::Free => unreachable!("the path only reaches live nodes"),
            }
        }
        // Scapegoat: too deep for the size means some ancestor is
        // unbalanced; rebuild the first one found walking up.
        let limit = 2.0 * ((self.len() / LEAF_CAP + 1) as f64).log2() + 4.0;
        if f64::from(depth) > limit {
            let mut child = node;
            while let Some(parent) = Some(self.nodes[child as usize].parent).filter(|&p| p != NONE)
            {
                let parent_count = f64::from(self.nodes[parent as usize].count);
                if f64::from(self.nodes[child as usize].count) > ALPHA * parent_count {
                    self.rebuild(parent, None, w_in);
                    break;
                }
                child = parent;
            }
        }
    }

    /// Removes row `r`.
    pub(crate) fn remove(&mut self, r: usize) {
        let Some(&leaf) = self.leaf_of.get(r).filter(|&&l| l != NONE) else {
            return;
        };
        self.leaf_of[r] = NONE;
        let Kind::Leaf { slot, len } = self.nodes[leaf as usize].kind else {
            return;
        };
        let Some(k) = (0..len as usize).find(|&k| self.slab_row(slot, k) as usize == r) else {
            return;
        };
        // Swap-remove: the last row and its inputs move into position `k`.
        let last = len as usize - 1;
        if k != last {
            let d = self.dim;
            let (from, to) = (self.input_at(slot, last), self.input_at(slot, k));
            let (last_row, k_row) = (self.row_at(slot, last), self.row_at(slot, k));
            let slab = self.slab.as_mut_slice();
            slab[k_row] = slab[last_row];
            slab.copy_within(from..from + d, to);
        }
        self.set_kind(leaf, Kind::Leaf { slot, len: len - 1 });
        let mut node = leaf;
        while node != NONE {
            self.nodes[node as usize].count -= 1;
            node = self.nodes[node as usize].parent;
        }
    }

    /// Lower bound of the squared distance from `x` to node's box; `N` is
    /// the dimension when known at compile time, 0 otherwise.
    #[inline(always)]
    fn lower_bound<const N: usize>(&self, node: u32, x: &[f64]) -> f64 {
        let d = if N == 0 { self.dim } else { N };
        let at = self.box_at(node);
        let (lo, hi) = self.pairs.as_slice()[at..at + 2 * d].split_at(d);
        let x = &x[..d];
        // Branch-free (where a query lies against a box is as good as
        // random, and a search compares hundreds of boxes), in four partial
        // sums. Each gap is the one positive difference, or 0: as the box
        // contains the rows (its bounds widen to `f64` exactly) and rounding
        // is monotone, at most the rounded difference of any row in it.
        let mut acc = [0.0; 4];
        for j in 0..d {
            let below = f64::from(lo[j]) - x[j];
            let above = x[j] - f64::from(hi[j]);
            let gap = if below > above { below } else { above };
            let gap = if gap > 0.0 { gap } else { 0.0 };
            acc[j % 4] += gap * gap;
        }
        ((acc[0] + acc[1]) + (acc[2] + acc[3])) * MARGIN
    }

    /// The winner and second winner among the rows in the tree, exactly as
    /// the brute-force scan ranks them, for a finite `x` and finite rows.
    pub(crate) fn nearest_two(&self, x: &[f64]) -> (Option<Candidate>, Option<Candidate>) {
        // The instances' input sizes get the dimension at compile time (the
        // same arithmetic, unrolled), as the scan does.
        match self.dim {
            2 => self.nearest_two_in::<2>(x),
            8 => self.nearest_two_in::<8>(x),
            10 => self.nearest_two_in::<10>(x),
            _ => self.nearest_two_in::<0>(x),
        }
    }

    fn nearest_two_in<const N: usize>(&self, x: &[f64]) -> (Option<Candidate>, Option<Candidate>) {
        let d = if N == 0 { self.dim } else { N };
        let x = &x[..d];
        let mut best: Option<Candidate> = None;
        let mut second: Option<Candidate> = None;
        // A box whose bound exceeds `prune` lies strictly farther than the
        // second winner (every distance in it is ≥ √bound > the second
        // distance): it cannot rank, not even by a tie. See
        // [`beyond_squared`]; no square root per box.
        let mut prune = f64::INFINITY;
        let slab = self.slab.as_slice();
        let mut stack: Vec<((u32, u32), f64)> = Vec::with_capacity(64);
        stack.push((self.link(ROOT), self.lower_bound::<N>(ROOT, x)));
        while let Some(((a, b), bound)) = stack.pop() {
            if bound > prune {
                continue;
            }
            if a == INNER {
                let (left, right) = (b, b + 1);
                let (bl, br) = (
                    self.lower_bound::<N>(left, x),
                    self.lower_bound::<N>(right, x),
                );
                // The nearer box is searched first (pushed last).
                let (near, far) = if bl <= br {
                    ((left, bl), (right, br))
                } else {
                    ((right, br), (left, bl))
                };
                if far.1 <= prune {
                    stack.push((self.link(far.0), far.1));
                }
                if near.1 <= prune {
                    stack.push((self.link(near.0), near.1));
                }
            } else if a != FREE {
                let (slot, len) = (b, a as usize);
                for k in 0..len {
                    let at = self.input_at(slot, k);
                    let sum = pairwise_sq_sum(&slab[at..at + d], x);
                    // Exact shortcuts: a strictly larger root cannot rank,
                    // not even by a tie, so its row number is not even read.
                    // An equal root can, when its row comes before the
                    // second winner's (the scan meets rows in order; the
                    // tree does not).
                    if sum > prune {
                        continue;
                    }
                    let root = sum.sqrt();
                    if second.is_some_and(|s| root > s.0) {
                        continue;
                    }
                    let row = slab[self.row_at(slot, k)] as usize;
                    if second.is_some_and(|s| sum > s.1 && row > s.2) {
                        continue;
                    }
                    let c = (root, sum, row);
                    if best.is_none_or(|b| ranks_before(c, b)) {
                        second = best;
                        best = Some(c);
                    } else if second.is_none_or(|s| ranks_before(c, s)) {
                        second = Some(c);
                    }
                    if let Some(s) = second {
                        prune = beyond_squared(s.0);
                    }
                }
            }
        }
        (best, second)
    }
}

/// A value `t` such that every `v > t` has `v.sqrt() > r` (for `r ≥ 0`),
/// so that bounds are compared without taking their roots: with `u` the
/// next value above `r`, `t ≥ u²` exactly (the rounded square plus one
/// step), so `√v > u` and its rounding, monotone, is at least `u > r`.
#[inline]
fn beyond_squared(r: f64) -> f64 {
    let u = f64_next_up(r);
    f64_next_up(u * u)
}

#[cfg(test)]
impl KdIndex {
    /// Checks every invariant the search relies on against `w_in` and the
    /// set of live rows, naming the first one broken.
    pub(crate) fn check(&self, w_in: &[f64], live: &[usize]) -> Result<(), String> {
        let mut seen = Vec::new();
        self.check_node(ROOT, NONE, w_in, &mut seen)?;
        seen.sort_unstable();
        let live: Vec<u32> = live.iter().map(|&r| r as u32).collect();
        if seen != live {
            return Err(format!("rows in the tree {seen:?}, live rows {live:?}"));
        }
        for (r, &leaf) in self.leaf_of.iter().enumerate() {
            let listed = leaf != NONE;
            if listed != live.binary_search(&(r as u32)).is_ok() {
                return Err(format!("row {r}: leaf_of {leaf} disagrees with liveness"));
            }
        }
        Ok(())
    }

    fn check_node(
        &self,
        node: u32,
        parent: u32,
        w_in: &[f64],
        seen: &mut Vec<u32>,
    ) -> Result<(), String> {
        let d = self.dim;
        let n = self.nodes[node as usize];
        if n.parent != parent {
            return Err(format!(
                "node {node}: parent {} instead of {parent}",
                n.parent
            ));
        }
        if self.link(node) != n.kind.link() {
            return Err(format!(
                "node {node}: the search's copy of its kind is stale"
            ));
        }
        let before = seen.len();
        let (at, pairs) = (self.box_at(node), self.pairs.as_slice());
        let (lo, hi) = pairs[at..at + 2 * d].split_at(d);
        match n.kind {
            Kind::Leaf { slot, len } => {
                if len as usize > LEAF_CAP {
                    return Err(format!("leaf {node} holds {len} rows"));
                }
                for k in 0..len as usize {
                    let r = self.slab_row(slot, k);
                    if self.slab_input(slot, k) != self.row(w_in, r) {
                        return Err(format!("leaf {node}: the copy of row {r} is stale"));
                    }
                    if self.leaf_of[r as usize] != node {
                        return Err(format!("row {r}: leaf_of is not leaf {node}"));
                    }
                    // The `f32` box, rounded outward, still holds the row.
                    let inside = self
                        .row(w_in, r)
                        .iter()
                        .enumerate()
                        .all(|(j, v)| f64::from(lo[j]) <= *v && *v <= f64::from(hi[j]));
                    if !inside {
                        return Err(format!("row {r} lies outside the box of leaf {node}"));
                    }
                    seen.push(r);
                }
            }
            Kind::Inner { children, .. } => {
                for child in [children, children + 1] {
                    self.check_node(child, node, w_in, seen)?;
                    let c = self.box_at(child);
                    let (clo, chi) = pairs[c..c + 2 * d].split_at(d);
                    let nested = (0..d).all(|j| lo[j] <= clo[j] && chi[j] <= hi[j]);
                    if !nested && self.nodes[child as usize].count > 0 {
                        return Err(format!("the box of {child} leaves its parent's"));
                    }
                }
            }
            Kind::Free => return Err(format!("free node {node} in the tree")),
        }
        if seen.len() - before != n.count as usize {
            return Err(format!(
                "node {node} counts {} rows, holds {}",
                n.count,
                seen.len() - before
            ));
        }
        Ok(())
    }

    /// Nodes on the longest path from the root to a leaf.
    pub(crate) fn depth(&self) -> usize {
        fn below(index: &KdIndex, node: u32) -> usize {
            match index.nodes[node as usize].kind {
                Kind::Inner { children, .. } => {
                    1 + below(index, children).max(below(index, children + 1))
                }
                _ => 1,
            }
        }
        below(self, ROOT)
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
                        let (best, second) = index.nearest_two(&x);
                        prop_assert_eq!(
                            (best.map(|c| c.2), second.map(|c| c.2)),
                            brute(dim, &w_in, &alive, &x)
                        );
                    }
                }
                prop_assert_eq!(index.len(), live(&alive).len());
                if let Err(broken) = index.check(&w_in, &live(&alive)) {
                    prop_assert!(false, "{}", broken);
                }
            }
        }
    }

    proptest! {
        #[test]
        fn f32_bounds_enclose_and_are_tight(v in prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO) {
            let (lo, hi) = (round_down(v), round_up(v));
            prop_assert!(f64::from(lo) <= v && v <= f64::from(hi));
            // One `f32` step apart at most (equal when `v` is an `f32`).
            prop_assert!(hi <= f32_next_up(lo));
        }

        #[test]
        fn beyond_the_squared_threshold_the_root_is_larger(r in 0.0..1e6f64, t in 0.0..1e-6f64) {
            let v = f64_next_up(beyond_squared(r)) * (1.0 + t);
            prop_assert!(v.sqrt() > r);
            prop_assert!(f64_next_up(r) > r && f64_next_up(f64::INFINITY) == f64::INFINITY);
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
        let limit = 2.0 * ((n as usize / LEAF_CAP + 1) as f64).log2() + 6.0;
        assert!(index.depth() as f64 <= limit, "{}", index.depth());
        assert_eq!(
            index.check(&w_in, &(0..n as usize).collect::<Vec<_>>()),
            Ok(())
        );
        let (best, second) = index.nearest_two(&[7.0005]);
        // The two rows nearest to 7.0005, nearer first.
        assert_eq!(
            (best.map(|c| c.2), second.map(|c| c.2)),
            (Some(7000), Some(7001))
        );
    }
}
