//! The AITM data structure, query and update (docs/spec/aitm.md §1–§5).

use std::borrow::Cow;
use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use super::distance::{lr_distance, lr_sq_norm, pairwise_sq_sum, ranking_distance};
use super::errors::AitmError;
use super::hyperparams::{AitmConfig, QueryMode};
use super::index::KdIndex;

/// Node count from which the winner search goes through the spatial index
/// ([`KdIndex`]); below it the contiguous scan is as fast (docs/spec/aitm.md §7: the
/// thesis's maps stay near 1100 nodes).
pub const INDEX_MIN_NODES: usize = 512;

/// Removed rows are kept as gaps until they outnumber the live ones (and
/// this many), so that a removal does not move every later row.
const COMPACT_MIN_GAPS: usize = 64;

/// Identifier of a node, unique within one map (docs/spec/aitm.md §1: a per-map counter
/// starting at 0, incremented per insertion). Ids are never reused.
pub type NodeId = u64;

/// Counters reported by the experiments (`docs/spec/experiments.md`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MapStats {
    /// Number of `update` invocations.
    pub update_calls: u64,
    /// Number of nodes ever inserted.
    pub inserts: u64,
    /// Current number of nodes.
    pub nodes: usize,
}

/// Read-only view of one node.
#[derive(Debug, Clone, Copy)]
pub struct NodeView<'a> {
    /// The node's id.
    pub id: NodeId,
    /// Input vector `w_in` (length `input_dim`).
    pub w_in: &'a [f64],
    /// Output vector `w_out` (length `output_dim`).
    pub w_out: &'a [f64],
    /// Local linear map `A`, row-major `output_dim × input_dim`.
    pub a: &'a [f64],
    /// Ids of the nodes connected to this one.
    pub neighbours: &'a BTreeSet<NodeId>,
}

/// Winner and second winner of a ranking (positions in the node order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Ranking {
    pub(crate) winner: usize,
    pub(crate) second: Option<usize>,
}

/// Adapted Instantaneous Topological Map (docs/spec/aitm.md).
///
/// Nodes are kept in insertion order (removals preserve the order of the
/// others). Their inputs, outputs and linear maps live in flat row-major
/// vectors, one row per node, so that the nearest-node scan walks contiguous
/// memory.
///
/// Removed nodes leave gaps (rows marked dead) until compaction, and maps of
/// [`INDEX_MIN_NODES`] nodes or more keep a spatial index of their inputs;
/// neither is visible: equality, views and the serialised form only see the
/// live nodes in order.
///
/// Serialising and deserialising (e.g. through `serde_json` with its
/// `float_roundtrip` feature) reproduces the map bit for bit; deserialisation
/// checks the structural invariants and rejects inconsistent data.
#[derive(Debug, Clone, Deserialize)]
#[serde(try_from = "AitmState")]
pub struct Aitm {
    config: AitmConfig,
    input_dim: usize,
    output_dim: usize,
    update_calls: u64,
    /// Number of nodes ever inserted; also the id of the next node.
    inserts: u64,
    /// Node ids in node order; strictly increasing because ids follow
    /// insertion order and removals keep the order, so positions are found
    /// by binary search.
    ids: Vec<NodeId>,
    w_in: Vec<f64>,
    w_out: Vec<f64>,
    a: Vec<f64>,
    neighbours: Vec<BTreeSet<NodeId>>,
    /// Whether each row holds a node (false: a removed node's gap).
    alive: Vec<bool>,
    /// Number of live rows.
    live: usize,
    /// Live rows with a non-finite input (the index handles finite ones).
    nonfinite: usize,
    /// Node count from which the index is used.
    index_min: usize,
    index: Option<KdIndex>,
}

impl PartialEq for Aitm {
    fn eq(&self, other: &Self) -> bool {
        self.config == other.config
            && self.input_dim == other.input_dim
            && self.output_dim == other.output_dim
            && self.update_calls == other.update_calls
            && self.inserts == other.inserts
            && self.len() == other.len()
            && self.nodes().zip(other.nodes()).all(|(a, b)| {
                a.id == b.id
                    && a.w_in == b.w_in
                    && a.w_out == b.w_out
                    && a.a == b.a
                    && a.neighbours == b.neighbours
            })
    }
}

impl Aitm {
    /// An empty map for `input_dim`-dimensional inputs and
    /// `output_dim`-dimensional outputs (either may be 0).
    pub fn new(config: AitmConfig, input_dim: usize, output_dim: usize) -> Self {
        Self {
            config,
            input_dim,
            output_dim,
            update_calls: 0,
            inserts: 0,
            ids: Vec::new(),
            w_in: Vec::new(),
            w_out: Vec::new(),
            a: Vec::new(),
            neighbours: Vec::new(),
            alive: Vec::new(),
            live: 0,
            nonfinite: 0,
            index_min: INDEX_MIN_NODES,
            index: None,
        }
    }

    /// Searches winners through the spatial index once the map holds
    /// `nodes` nodes (default [`INDEX_MIN_NODES`]; `usize::MAX`: always scan).
    /// The answers are the same either way (docs/spec/aitm.md §7); only the time
    /// differs.
    pub fn set_index_min(&mut self, nodes: usize) {
        self.index_min = nodes;
        self.index = None;
        self.update_index_use();
    }

    /// Builds the index once the map is large enough.
    fn update_index_use(&mut self) {
        if self.index.is_none() && self.input_dim > 0 && self.live >= self.index_min {
            let alive = &self.alive;
            self.index = Some(KdIndex::build(
                self.input_dim,
                &self.w_in,
                (0..alive.len()).filter(|&i| alive[i]),
            ));
        }
    }

    /// The validated parameters.
    pub fn config(&self) -> &AitmConfig {
        &self.config
    }

    /// Input dimension n.
    pub fn input_dim(&self) -> usize {
        self.input_dim
    }

    /// Output dimension m.
    pub fn output_dim(&self) -> usize {
        self.output_dim
    }

    /// Current number of nodes.
    pub fn len(&self) -> usize {
        self.live
    }

    /// Whether the map has no nodes (it was never trained: training never
    /// removes the last two nodes).
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Update calls, inserts and current node count.
    pub fn stats(&self) -> MapStats {
        MapStats {
            update_calls: self.update_calls,
            inserts: self.inserts,
            nodes: self.len(),
        }
    }

    /// The nodes in node order.
    pub fn nodes(&self) -> impl Iterator<Item = NodeView<'_>> + '_ {
        (0..self.ids.len())
            .filter(move |&i| self.alive[i])
            .map(move |i| self.view(i))
    }

    /// The node with this id, if it exists.
    pub fn node(&self, id: NodeId) -> Option<NodeView<'_>> {
        self.position(id).map(|i| self.view(i))
    }

    /// `f(x, mode)` of docs/spec/aitm.md §3 in the configured mode: a fresh vector of
    /// length `output_dim`, the zero vector for an empty map.
    ///
    /// # Panics
    /// If `x.len() != input_dim` (a programming error).
    pub fn query(&self, x: &[f64]) -> Vec<f64> {
        self.query_mode(x, self.config.mode())
    }

    /// `f(x, mode)` in an explicitly given mode.
    ///
    /// # Panics
    /// If `x.len() != input_dim`.
    pub fn query_mode(&self, x: &[f64], mode: QueryMode) -> Vec<f64> {
        self.check_input(x);
        match self.rank_two(x) {
            None => vec![0.0; self.output_dim],
            Some(ranking) => self.estimate(x, ranking, mode),
        }
    }

    /// Classifier answer (docs/spec/aitm.md §6): `None` if the map has no nodes (never
    /// trained) or no output component, otherwise the first component of the
    /// winner's local output truncated toward zero. With integer storage and
    /// `A = 0` this is the winner's stored label.
    ///
    /// # Panics
    /// If `x.len() != input_dim`.
    pub fn classify(&self, x: &[f64]) -> Option<i64> {
        self.check_input(x);
        if self.output_dim == 0 {
            return None;
        }
        let ranking = self.rank_two(x)?;
        let mut y = vec![0.0; self.output_dim];
        self.local_output(ranking.winner, x, &mut y);
        // Saturating float-to-int conversion; labels are small integers.
        Some(y[0].trunc() as i64)
    }

    /// Trains a one-output map with an integer class label (`update(x, [label])`).
    ///
    /// # Panics
    /// If `output_dim != 1` or `x.len() != input_dim`.
    pub fn update_label(&mut self, x: &[f64], label: i64) {
        assert_eq!(self.output_dim, 1, "update_label needs a one-output map");
        // Class labels are small integers, exactly representable.
        self.update(x, &[label as f64]);
    }

    /// One training step `update(x, y)` of docs/spec/aitm.md §4.
    ///
    /// # Panics
    /// If `x.len() != input_dim` or `y.len() != output_dim` (programming
    /// errors: every instance has fixed dimensions).
    pub fn update(&mut self, x: &[f64], y: &[f64]) {
        self.check_input(x);
        assert_eq!(
            y.len(),
            self.output_dim,
            "AITM output has {} components, the map expects {}",
            y.len(),
            self.output_dim
        );
        self.update_calls += 1;

        // docs/spec/aitm.md §4: while the map holds at most one node, every sample is
        // inserted without edges, whatever its input (even a duplicate).
        let Some(Ranking {
            winner,
            second: Some(second),
        }) = self.rank_two(x)
        else {
            self.insert(x, y, None);
            return;
        };
        let n_id = self.ids[winner];
        let s_id = self.ids[second];
        // Taken before any adaptation (docs/spec/aitm.md §4).
        let delta_ws: Vec<f64> = self
            .w_in_row(winner)
            .iter()
            .zip(self.w_in_row(second))
            .map(|(n, s)| n - s)
            .collect();

        if self.config.adapts() {
            self.adapt_winner(winner, x, y);
        }

        self.connect(winner, second);

        // ŷ with the winner and second winner just found (positions are still
        // valid: nothing was removed yet).
        let y_hat = self.estimate(
            x,
            Ranking {
                winner,
                second: Some(second),
            },
            self.config.mode(),
        );

        self.prune_edges(n_id, s_id, &delta_ws);

        // Output-driven insertion (docs/spec/aitm.md §4). Both comparisons are strict
        // and exact, with left-to-right norms.
        let eps_out = insertion_threshold(lr_sq_norm(y).sqrt());
        if lr_distance(&y_hat, y) > eps_out {
            let n = self
                .position(n_id)
                .expect("edge pruning deletes only isolated neighbours, never the winner");
            if lr_distance(self.w_in_row(n), x) > self.config.eps_max() {
                self.insert(x, y, Some(n_id));
            } else {
                let classifier = self.config.is_classifier();
                for (w, t) in self.w_out_row_mut(n).iter_mut().zip(y) {
                    *w += 0.5 * (t - *w);
                    if classifier {
                        // docs/spec/aitm.md §6: the original's integer label array
                        // truncated the halfway value toward zero in place.
                        *w = w.trunc();
                    }
                }
            }
        }

        // Too-close second winner (docs/spec/aitm.md §4, following the code: deleted
        // when *closer* than ε_max, §8). The squared norm is the
        // left-to-right sum of squares, compared without a square root.
        let eps_max = self.config.eps_max();
        if lr_sq_norm(&delta_ws) < eps_max * eps_max && self.len() > 2 {
            self.delete(s_id);
        }
    }

    /// The nearest and second-nearest node (docs/spec/aitm.md §2): brute-force scan with
    /// the blocked ranking distance; exact comparisons, ties to the earlier
    /// node. A NaN distance ranks after every number. `None` for an empty map.
    ///
    /// Any faster search (spatial index) must return exactly this.
    pub(crate) fn rank_two(&self, x: &[f64]) -> Option<Ranking> {
        if let Some(index) = &self.index {
            if self.nonfinite == 0 && x.iter().all(|v| v.is_finite()) {
                return self.rank_two_indexed(index, x);
            }
        }
        self.rank_two_scan(x)
    }

    /// The ids of the winner and second winner (tests: positions are rows,
    /// which include the gaps of removed nodes).
    #[cfg(test)]
    pub(crate) fn ranked_ids(&self, x: &[f64], scan: bool) -> Option<(NodeId, Option<NodeId>)> {
        let r = if scan {
            self.rank_two_scan(x)
        } else {
            self.rank_two(x)
        }?;
        Some((self.ids[r.winner], r.second.map(|s| self.ids[s])))
    }

    /// Whether the winner search currently goes through the index.
    #[cfg(test)]
    pub(crate) fn is_indexed(&self) -> bool {
        self.index.is_some()
    }

    /// [`Aitm::rank_two`] by the brute-force scan of docs/spec/aitm.md §2.
    pub(crate) fn rank_two_scan(&self, x: &[f64]) -> Option<Ranking> {
        // The instances' input sizes get a loop with the dimension known at
        // compile time (same arithmetic, unrolled).
        match self.input_dim {
            2 => self.rank_two_fixed::<2>(x),
            8 => self.rank_two_fixed::<8>(x),
            10 => self.rank_two_fixed::<10>(x),
            n => rank_rows(
                (0..self.ids.len())
                    .filter(|&i| self.alive[i])
                    .map(|i| (i, pairwise_sq_sum(&self.w_in[i * n..(i + 1) * n], x))),
            ),
        }
    }

    fn rank_two_fixed<const N: usize>(&self, x: &[f64]) -> Option<Ranking> {
        let x = &x[..N];
        let rows = self.w_in.chunks_exact(N).enumerate();
        if self.live == self.ids.len() {
            rank_rows(rows.map(|(i, row)| (i, pairwise_sq_sum(row, x))))
        } else {
            rank_rows(
                rows.filter(|(i, _)| self.alive[*i])
                    .map(|(i, row)| (i, pairwise_sq_sum(row, x))),
            )
        }
    }

    /// [`Aitm::rank_two`] through the index (finite inputs only; the scan
    /// ranks NaN distances).
    fn rank_two_indexed(&self, index: &KdIndex, x: &[f64]) -> Option<Ranking> {
        debug_assert_eq!(index.len(), self.live);
        let (best, second) = index.nearest_two(x);
        best.map(|(_, _, winner)| Ranking {
            winner,
            second: second.map(|(_, _, s)| s),
        })
    }

    fn check_input(&self, x: &[f64]) {
        assert_eq!(
            x.len(),
            self.input_dim,
            "AITM input has {} components, the map expects {}",
            x.len(),
            self.input_dim
        );
    }

    fn view(&self, i: usize) -> NodeView<'_> {
        NodeView {
            id: self.ids[i],
            w_in: self.w_in_row(i),
            w_out: self.w_out_row(i),
            a: self.a_block(i),
            neighbours: &self.neighbours[i],
        }
    }

    fn position(&self, id: NodeId) -> Option<usize> {
        self.ids.binary_search(&id).ok().filter(|&i| self.alive[i])
    }

    fn w_in_row(&self, i: usize) -> &[f64] {
        let n = self.input_dim;
        &self.w_in[i * n..(i + 1) * n]
    }

    fn w_out_row(&self, i: usize) -> &[f64] {
        let m = self.output_dim;
        &self.w_out[i * m..(i + 1) * m]
    }

    fn w_out_row_mut(&mut self, i: usize) -> &mut [f64] {
        let m = self.output_dim;
        &mut self.w_out[i * m..(i + 1) * m]
    }

    fn a_block(&self, i: usize) -> &[f64] {
        let k = self.input_dim * self.output_dim;
        &self.a[i * k..(i + 1) * k]
    }

    /// `y_c(x) = w_out(c) + A_c · (x − w_in(c))` into `out`. Each row of the
    /// product is summed left to right from 0.0 (as a BLAS dot product), so
    /// with `A = 0` a stored −0.0 comes out as +0.0; no caller depends on the
    /// sign of a zero output.
    fn local_output(&self, c: usize, x: &[f64], out: &mut [f64]) {
        let n = self.input_dim;
        let w_in = self.w_in_row(c);
        let a = self.a_block(c);
        for (i, (o, w)) in out.iter_mut().zip(self.w_out_row(c)).enumerate() {
            let mut acc = 0.0;
            for j in 0..n {
                acc += a[i * n + j] * (x[j] - w_in[j]);
            }
            *o = w + acc;
        }
    }

    /// `exp(−|x − w_in(c)|² / σ²)` with the ranking distance (docs/spec/aitm.md §2, §3).
    /// Follows the code, not the thesis, which prints `exp(‖x − w‖ / σ²)`
    /// (§8).
    fn weight(&self, c: usize, x: &[f64]) -> f64 {
        let d = ranking_distance(self.w_in_row(c), x);
        let sigma = self.config.sigma();
        (-(d * d) / (sigma * sigma)).exp()
    }

    /// `f(x, mode)` given the ranking (docs/spec/aitm.md §3).
    fn estimate(&self, x: &[f64], ranking: Ranking, mode: QueryMode) -> Vec<f64> {
        let m = self.output_dim;
        let n = ranking.winner;
        let mut out = vec![0.0; m];
        match mode {
            QueryMode::Winner => self.local_output(n, x, &mut out),
            QueryMode::BestTwo => {
                let Some(s) = ranking.second else {
                    // One node: its stored output, without the linear term; a
                    // copy (the original returned the stored array itself,
                    // which a caller then modified in place; §8).
                    out.copy_from_slice(self.w_out_row(n));
                    return out;
                };
                let (k_n, k_s) = (self.weight(n, x), self.weight(s, x));
                let mut y_s = vec![0.0; m];
                self.local_output(n, x, &mut out);
                self.local_output(s, x, &mut y_s);
                let k = k_n + k_s;
                for (o, ys) in out.iter_mut().zip(&y_s) {
                    let sum = k_n * *o + k_s * ys;
                    // Both weights underflow to 0 farther than ≈ σ·√745 from
                    // x; the unnormalised sum (zero) is returned then.
                    *o = if k != 0.0 { sum / k } else { sum };
                }
            }
            QueryMode::Neighbour => {
                if ranking.second.is_none() {
                    out.copy_from_slice(self.w_out_row(n));
                    return out;
                }
                // Winner first, then its neighbours in ascending id order
                // (decision: the original iterated a hash set).
                let k_n = self.weight(n, x);
                self.local_output(n, x, &mut out);
                for o in out.iter_mut() {
                    *o *= k_n;
                }
                let mut k = k_n;
                let mut y_c = vec![0.0; m];
                for &c_id in &self.neighbours[n] {
                    let c = self
                        .position(c_id)
                        .expect("neighbour ids always name existing nodes");
                    let k_c = self.weight(c, x);
                    self.local_output(c, x, &mut y_c);
                    for (o, yc) in out.iter_mut().zip(&y_c) {
                        *o += k_c * yc;
                    }
                    k += k_c;
                }
                if k != 0.0 {
                    for o in out.iter_mut() {
                        *o /= k;
                    }
                }
            }
        }
        out
    }

    /// Local Linear Map adaptation of the winner (docs/spec/aitm.md §4), only called
    /// when a learning rate is non-zero. This is the textbook rule: the
    /// original used `y − w_out + A·e` where the rule has `y − w_out − A·e`
    /// (= `y − y_n(x)`), and updated `A` with the already adapted `w_out`
    /// (§8); irrelevant for the evaluated rates, which are all 0.
    fn adapt_winner(&mut self, c: usize, x: &[f64], y: &[f64]) {
        let (n, m) = (self.input_dim, self.output_dim);
        let p = *self.config.params();
        let e: Vec<f64> = x.iter().zip(self.w_in_row(c)).map(|(x, w)| x - w).collect();
        let mut y_c = vec![0.0; m];
        self.local_output(c, x, &mut y_c);
        let err: Vec<f64> = y.iter().zip(&y_c).map(|(t, o)| t - o).collect();
        let dw: Vec<f64> = e.iter().map(|e| p.eta_in * e).collect();
        // A_n · Δw_in with the A before adaptation.
        let a_dw: Vec<f64> = {
            let a = self.a_block(c);
            (0..m)
                .map(|i| {
                    let mut acc = 0.0;
                    for j in 0..n {
                        acc += a[i * n + j] * dw[j];
                    }
                    acc
                })
                .collect()
        };
        let was_finite = self.w_in_row(c).iter().all(|v| v.is_finite());
        if let Some(index) = &mut self.index {
            index.remove(c);
        }
        for (w, d) in self.w_in[c * n..(c + 1) * n].iter_mut().zip(&dw) {
            *w += d;
        }
        self.track_finite(c, was_finite);
        if let Some(index) = &mut self.index {
            index.insert(c, &self.w_in);
        }
        for ((w, er), ad) in self.w_out_row_mut(c).iter_mut().zip(&err).zip(&a_dw) {
            *w += p.eta_out * er + ad;
        }
        let e_sq = lr_sq_norm(&e);
        if e_sq > 0.0 {
            let k = n * m;
            let a = &mut self.a[c * k..(c + 1) * k];
            for i in 0..m {
                for j in 0..n {
                    a[i * n + j] += p.eta_a * err[i] * e[j] / e_sq;
                }
            }
        }
    }

    /// Thales-sphere edge pruning of the ITM (docs/spec/aitm.md §4), over a snapshot
    /// of the winner's neighbours in ascending id order.
    fn prune_edges(&mut self, n_id: NodeId, s_id: NodeId, delta_ws: &[f64]) {
        let n = self
            .position(n_id)
            .expect("the winner exists during its own update");
        let snapshot: Vec<NodeId> = self.neighbours[n].iter().copied().collect();
        for c_id in snapshot {
            if c_id == s_id {
                continue;
            }
            // Positions are looked up again: a deletion in an earlier
            // iteration may have shifted them.
            let (Some(c), Some(s)) = (self.position(c_id), self.position(s_id)) else {
                continue;
            };
            let mut dot = 0.0;
            for ((d, wc), ws) in delta_ws.iter().zip(self.w_in_row(c)).zip(self.w_in_row(s)) {
                dot += d * (wc - ws);
            }
            if dot < 0.0 {
                self.disconnect(n_id, c_id);
                let c = self.position(c_id).expect("c was found above");
                if self.neighbours[c].is_empty() {
                    // An isolated node: its deletion cascades no further (§5).
                    self.delete(c_id);
                }
            }
        }
    }

    /// docs/spec/aitm.md §5: detach the node from every neighbour (ascending id order);
    /// a neighbour left without edges is deleted too while more than two
    /// nodes (counting this one) remain. This can delete the winner of the
    /// current update; original behaviour, kept.
    fn delete(&mut self, id: NodeId) {
        let Some(i) = self.position(id) else {
            return;
        };
        let neighbours = std::mem::take(&mut self.neighbours[i]);
        for c_id in neighbours {
            let Some(c) = self.position(c_id) else {
                continue;
            };
            self.neighbours[c].remove(&id);
            if self.neighbours[c].is_empty() && self.len() > 2 {
                self.delete(c_id);
            }
        }
        let i = self
            .position(id)
            .expect("only isolated neighbours were removed, not the node itself");
        self.remove_row(i);
    }

    /// Counts row `c`'s input as finite or not after it changed.
    fn track_finite(&mut self, c: usize, was_finite: bool) {
        let finite = self.w_in_row(c).iter().all(|v| v.is_finite());
        match (was_finite, finite) {
            (true, false) => self.nonfinite += 1,
            (false, true) => self.nonfinite -= 1,
            _ => {}
        }
    }

    /// Removes node `i`, keeping the order of the others: its row becomes a
    /// gap, and the gaps are squeezed out once they outnumber the nodes.
    fn remove_row(&mut self, i: usize) {
        self.alive[i] = false;
        self.neighbours[i].clear();
        self.live -= 1;
        if !self.w_in_row(i).iter().all(|v| v.is_finite()) {
            self.nonfinite -= 1;
        }
        if let Some(index) = &mut self.index {
            index.remove(i);
        }
        let gaps = self.ids.len() - self.live;
        if gaps > self.live && gaps >= COMPACT_MIN_GAPS {
            self.compact();
        }
    }

    /// Drops the gaps of removed nodes (row positions change; callers look
    /// positions up again after any removal) and rebuilds the index.
    fn compact(&mut self) {
        let (n, m) = (self.input_dim, self.output_dim);
        let alive = std::mem::take(&mut self.alive);
        let keep = |v: &mut Vec<f64>, width: usize| {
            let mut row = 0;
            v.retain(|_| {
                let k = alive[row / width.max(1)];
                row += 1;
                k
            });
        };
        if n > 0 {
            keep(&mut self.w_in, n);
        }
        if m > 0 {
            keep(&mut self.w_out, m);
        }
        if n * m > 0 {
            keep(&mut self.a, n * m);
        }
        let mut k = alive.iter();
        self.ids.retain(|_| *k.next().unwrap_or(&false));
        let mut k = alive.iter();
        self.neighbours.retain(|_| *k.next().unwrap_or(&false));
        self.alive = vec![true; self.live];
        if self.index.is_some() {
            self.index = None;
            self.update_index_use();
        }
    }

    /// Appends a node for (x, y), optionally connected to `edge_to`.
    /// Classifiers store the label truncated toward zero (docs/spec/aitm.md §6).
    fn insert(&mut self, x: &[f64], y: &[f64], edge_to: Option<NodeId>) {
        let id = self.inserts;
        self.inserts += 1;
        self.ids.push(id);
        self.w_in.extend_from_slice(x);
        if self.config.is_classifier() {
            self.w_out.extend(y.iter().map(|v| v.trunc()));
        } else {
            self.w_out.extend_from_slice(y);
        }
        self.a
            .extend(std::iter::repeat_n(0.0, self.input_dim * self.output_dim));
        self.neighbours.push(BTreeSet::new());
        self.alive.push(true);
        self.live += 1;
        let row = self.ids.len() - 1;
        if !x.iter().all(|v| v.is_finite()) {
            self.nonfinite += 1;
        }
        match &mut self.index {
            Some(index) => index.insert(row, &self.w_in),
            None => self.update_index_use(),
        }
        if let Some(other) = edge_to.and_then(|o| self.position(o)) {
            self.connect(row, other);
        }
    }

    fn connect(&mut self, a: usize, b: usize) {
        let (id_a, id_b) = (self.ids[a], self.ids[b]);
        self.neighbours[a].insert(id_b);
        self.neighbours[b].insert(id_a);
    }

    fn disconnect(&mut self, id_a: NodeId, id_b: NodeId) {
        if let Some(a) = self.position(id_a) {
            self.neighbours[a].remove(&id_b);
        }
        if let Some(b) = self.position(id_b) {
            self.neighbours[b].remove(&id_a);
        }
    }
}

/// The winner and second winner among rows given by their sums of squared
/// differences in row order (docs/spec/aitm.md §2): distances are the square roots,
/// compared exactly, ties to the earlier row, NaN after every number.
#[inline(always)]
fn rank_rows(sq_sums: impl Iterator<Item = (usize, f64)>) -> Option<Ranking> {
    /// Position, squared-distance sum and distance of a candidate.
    type Candidate = (usize, f64, f64);
    fn closer(d: f64, current: Option<Candidate>) -> bool {
        match current {
            None => true,
            Some((_, _, c)) => d < c || (c.is_nan() && !d.is_nan()),
        }
    }
    let mut best: Option<Candidate> = None;
    let mut second: Option<Candidate> = None;
    for (i, sum) in sq_sums {
        // Exact shortcut: the square root is monotone, so a sum above the
        // second winner's gives a distance at least as large, and an equal
        // distance loses the tie to the earlier second winner. Only the
        // remaining candidates need their square root.
        if second.is_some_and(|(_, s, _)| sum > s) {
            continue;
        }
        let d = sum.sqrt();
        if closer(d, best) {
            second = best;
            best = Some((i, sum, d));
        } else if closer(d, second) {
            second = Some((i, sum, d));
        }
    }
    best.map(|(winner, _, _)| Ranking {
        winner,
        second: second.map(|(s, _, _)| s),
    })
}

/// ε_out of docs/spec/aitm.md §4 for a target output of norm `nu`: `10^floor(log10 ν)`,
/// except 0.1 for norms in [1, 10) and 10⁻³ for a zero output. Follows the
/// code, which applies the 0.1 case whenever `floor(log10 ν) = 0`; the thesis
/// writes it for `log10 ν = 0` only (§8).
pub(crate) fn insertion_threshold(nu: f64) -> f64 {
    let e10 = if nu != 0.0 {
        let e = nu.log10().floor();
        if e == 0.0 {
            -1.0
        } else {
            e
        }
    } else {
        -3.0
    };
    pow10(e10)
}

/// `10^e` for an integral `e`, correctly rounded in the range of exactly
/// representable powers (|e| ≤ 22; negative powers as one division).
fn pow10(e: f64) -> f64 {
    const EXACT: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    if e.fract() == 0.0 && e.abs() <= 22.0 {
        let k = e.abs() as usize;
        if e >= 0.0 {
            EXACT[k]
        } else {
            1.0 / EXACT[k]
        }
    } else {
        10f64.powf(e)
    }
}

/// The serialised form, validated before it becomes an [`Aitm`]: the live
/// nodes in order, without gaps or index.
#[derive(Serialize, Deserialize)]
struct AitmState<'a> {
    config: Cow<'a, AitmConfig>,
    input_dim: usize,
    output_dim: usize,
    update_calls: u64,
    inserts: u64,
    ids: Cow<'a, [NodeId]>,
    w_in: Cow<'a, [f64]>,
    w_out: Cow<'a, [f64]>,
    a: Cow<'a, [f64]>,
    neighbours: Cow<'a, [BTreeSet<NodeId>]>,
}

impl Serialize for Aitm {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        if self.live == self.ids.len() {
            AitmState {
                config: Cow::Borrowed(&self.config),
                input_dim: self.input_dim,
                output_dim: self.output_dim,
                update_calls: self.update_calls,
                inserts: self.inserts,
                ids: Cow::Borrowed(&self.ids),
                w_in: Cow::Borrowed(&self.w_in),
                w_out: Cow::Borrowed(&self.w_out),
                a: Cow::Borrowed(&self.a),
                neighbours: Cow::Borrowed(&self.neighbours),
            }
            .serialize(serializer)
        } else {
            let mut compact = self.clone();
            compact.compact();
            compact.serialize(serializer)
        }
    }
}

impl TryFrom<AitmState<'_>> for Aitm {
    type Error = AitmError;

    fn try_from(s: AitmState<'_>) -> Result<Self, Self::Error> {
        use AitmError::InconsistentState as Bad;
        let count = s.ids.len();
        let rows = |dim: usize| count.checked_mul(dim);
        if rows(s.input_dim) != Some(s.w_in.len()) {
            return Err(Bad("w_in length"));
        }
        if rows(s.output_dim) != Some(s.w_out.len()) {
            return Err(Bad("w_out length"));
        }
        if s.input_dim.checked_mul(s.output_dim).and_then(rows) != Some(s.a.len()) {
            return Err(Bad("A length"));
        }
        if s.neighbours.len() != count {
            return Err(Bad("neighbour list length"));
        }
        if !s.ids.windows(2).all(|w| w[0] < w[1]) {
            return Err(Bad("node ids not strictly increasing"));
        }
        if s.ids.last().is_some_and(|&last| last >= s.inserts) || count as u64 > s.inserts {
            return Err(Bad("node ids or count exceed the insert counter"));
        }
        if s.inserts > s.update_calls {
            return Err(Bad("more inserts than update calls"));
        }
        for (i, set) in s.neighbours.iter().enumerate() {
            for c in set {
                let Ok(j) = s.ids.binary_search(c) else {
                    return Err(Bad("neighbour id names no node"));
                };
                if j == i {
                    return Err(Bad("node connected to itself"));
                }
                if !s.neighbours[j].contains(&s.ids[i]) {
                    return Err(Bad("edge not symmetric"));
                }
            }
        }
        let nonfinite = s
            .w_in
            .chunks(s.input_dim.max(1))
            .take(count)
            .filter(|row| !row.iter().all(|v| v.is_finite()))
            .count();
        let mut map = Self {
            config: s.config.into_owned(),
            input_dim: s.input_dim,
            output_dim: s.output_dim,
            update_calls: s.update_calls,
            inserts: s.inserts,
            ids: s.ids.into_owned(),
            w_in: s.w_in.into_owned(),
            w_out: s.w_out.into_owned(),
            a: s.a.into_owned(),
            neighbours: s.neighbours.into_owned(),
            alive: vec![true; count],
            live: count,
            nonfinite: if s.input_dim == 0 { 0 } else { nonfinite },
            index_min: INDEX_MIN_NODES,
            index: None,
        };
        // The index is not serialised: rebuilt here, it returns the same
        // rankings as the scan (and as the index of the saved map).
        map.update_index_use();
        Ok(map)
    }
}

#[cfg(test)]
mod gap_tests {
    use super::*;
    use crate::aitm::{AitmConfig, QueryMode};

    /// Removals leave gaps, compaction squeezes them out, and neither changes
    /// what the map answers or how it serialises.
    #[test]
    fn gaps_and_compaction_are_invisible() {
        let mut map = Aitm::new(AitmConfig::regressor(QueryMode::Winner), 2, 1);
        map.set_index_min(100);
        for k in 0..300u32 {
            let x = [f64::from(k % 17) * 0.01, f64::from(k / 17) * 0.01];
            map.insert(&x, &[f64::from(k)], None);
        }
        map.update_calls = 300;
        assert!(map.is_indexed());
        let mut fresh = Aitm::new(AitmConfig::regressor(QueryMode::Winner), 2, 1);
        let mut deleted_rows = 0;
        for id in 0..300u64 {
            if id % 5 != 0 {
                map.delete(id);
                deleted_rows += 1;
            }
            if deleted_rows == 100 {
                // Gaps still in place: 100 of 300 rows.
                assert_eq!(map.ids.len(), 300);
            }
        }
        // 240 removed of 300: compacted on the way.
        assert!(
            map.ids.len() < 300 && map.ids.len() >= map.len(),
            "{}",
            map.ids.len()
        );
        assert_eq!(map.len(), 60);
        for v in map.nodes() {
            fresh.ids.push(v.id);
            fresh.w_in.extend_from_slice(v.w_in);
            fresh.w_out.extend_from_slice(v.w_out);
            fresh.a.extend_from_slice(v.a);
            fresh.neighbours.push(v.neighbours.clone());
            fresh.alive.push(true);
            fresh.live += 1;
        }
        fresh.inserts = map.inserts;
        fresh.update_calls = map.update_calls;
        assert_eq!(fresh, map);
        let text = serde_json::to_string(&map).expect("serialises");
        assert_eq!(text, serde_json::to_string(&fresh).expect("serialises"));
        let restored: Aitm = serde_json::from_str(&text).expect("deserialises");
        assert_eq!(restored, map);
        for probe in [[0.0, 0.0], [0.05, 0.051], [0.16, 0.17], [0.3, -0.2]] {
            let expected = fresh.ranked_ids(&probe, true);
            assert!(expected.is_some_and(|(_, s)| s.is_some()));
            assert_eq!(map.ranked_ids(&probe, false), expected);
            assert_eq!(map.ranked_ids(&probe, true), expected);
            assert_eq!(restored.ranked_ids(&probe, true), expected);
        }
    }
}
