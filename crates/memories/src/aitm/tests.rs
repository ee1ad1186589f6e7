//! Hand-built scenarios pinning each rule of docs/spec/aitm.md. Each test names the
//! rule it pins; breaking that rule makes the test fail.

use std::collections::BTreeSet;

use serde_json::json;

use super::algorithm::insertion_threshold;
use super::distance::{lr_sq_distance, pairwise_sq_sum};
use super::*;

fn regressor(mode: QueryMode, n: usize, m: usize) -> Aitm {
    Aitm::new(AitmConfig::regressor(mode), n, m)
}

/// A map in an arbitrary state (ids 0, 1, … in the given order), built
/// through the validated deserialisation path.
fn build(
    config: AitmConfig,
    nodes: &[(Vec<f64>, Vec<f64>)],
    edges: &[(u64, u64)],
    a: Option<Vec<f64>>,
) -> Aitm {
    let n = nodes[0].0.len();
    let m = nodes[0].1.len();
    let mut neighbours = vec![BTreeSet::new(); nodes.len()];
    for &(p, q) in edges {
        neighbours[p as usize].insert(q);
        neighbours[q as usize].insert(p);
    }
    let a = a.unwrap_or_else(|| vec![0.0; nodes.len() * n * m]);
    let state = json!({
        "config": config,
        "input_dim": n,
        "output_dim": m,
        "update_calls": nodes.len(),
        "inserts": nodes.len(),
        "ids": (0..nodes.len() as u64).collect::<Vec<_>>(),
        "w_in": nodes.iter().flat_map(|(x, _)| x.clone()).collect::<Vec<_>>(),
        "w_out": nodes.iter().flat_map(|(_, y)| y.clone()).collect::<Vec<_>>(),
        "a": a,
        "neighbours": neighbours,
    });
    serde_json::from_value(state).expect("hand-built state is consistent")
}

fn node(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>) {
    (x.to_vec(), y.to_vec())
}

fn ids(map: &Aitm) -> Vec<NodeId> {
    map.nodes().map(|v| v.id).collect()
}

fn edges(map: &Aitm) -> Vec<(NodeId, NodeId)> {
    let mut out = Vec::new();
    for v in map.nodes() {
        for &c in v.neighbours {
            if v.id < c {
                out.push((v.id, c));
            }
        }
    }
    out
}

fn w_out(map: &Aitm, id: NodeId) -> Vec<f64> {
    map.node(id).expect("node exists").w_out.to_vec()
}

// ---------------------------------------------------------------- §4 update

#[test]
fn first_two_updates_always_insert_even_identical_samples() {
    let mut map = regressor(QueryMode::Winner, 2, 1);
    map.update(&[0.1, 0.2], &[0.0]);
    map.update(&[0.1, 0.2], &[0.0]);
    assert_eq!(
        map.stats(),
        MapStats {
            update_calls: 2,
            inserts: 2,
            nodes: 2
        }
    );
    // Inserted without edges.
    assert!(edges(&map).is_empty());
    // The third identical sample is predicted correctly: no insertion, and
    // the too-close second winner survives because only two nodes exist.
    map.update(&[0.1, 0.2], &[0.0]);
    assert_eq!(map.stats().nodes, 2);
    assert_eq!(map.stats().inserts, 2);
    assert_eq!(edges(&map), vec![(0, 1)]);
}

/// Two nodes at 0 and 1 with output `y0`; one update at 0.01 (farther than
/// ε_max from the winner) with `target`. Returns whether a node was inserted.
fn inserts(y0: &[f64], target: &[f64]) -> bool {
    let mut map = regressor(QueryMode::Winner, 1, y0.len());
    map.update(&[0.0], y0);
    map.update(&[1.0], y0);
    map.update(&[0.01], target);
    match map.len() {
        2 => false,
        3 => true,
        n => panic!("unexpected node count {n}"),
    }
}

#[test]
fn insertion_threshold_follows_target_magnitude() {
    // Block changes of ≈ 0.005 → 0.001.
    assert!(inserts(&[0.0039], &[0.005]));
    assert!(!inserts(&[0.0041], &[0.005]));
    // Class label 1 → 0.1 (not 1: norms in [1, 10) give 0.1).
    assert!(inserts(&[0.89], &[1.0]));
    assert!(!inserts(&[0.91], &[1.0]));
    // Class label 0 → 0.001.
    assert!(inserts(&[0.0011], &[0.0]));
    assert!(!inserts(&[0.0009], &[0.0]));
    // Class label 12 → 10.
    assert!(inserts(&[1.9], &[12.0]));
    assert!(!inserts(&[2.1], &[12.0]));
    // Norm in [1, 10) → 0.1, for a multi-component output of norm 5.
    assert!(inserts(&[3.0, 3.89], &[3.0, 4.0]));
    assert!(!inserts(&[3.0, 3.91], &[3.0, 4.0]));
    // Norm 0.05 → 0.01.
    assert!(inserts(&[0.039], &[0.05]));
    assert!(!inserts(&[0.041], &[0.05]));
}

#[test]
fn insertion_threshold_values() {
    let cases = [
        (0.0, 0.001),
        (0.001, 0.001),
        (0.0011, 0.001),
        (0.005, 0.001),
        (0.0099, 0.001),
        (0.01, 0.01),
        (0.05, 0.01),
        (0.1, 0.1),
        (0.999, 0.1),
        (1.0, 0.1),
        (5.0, 0.1),
        (9.99, 0.1),
        (10.0, 10.0),
        (12.0, 10.0),
        (99.0, 10.0),
        (100.0, 100.0),
    ];
    for (nu, expected) in cases {
        assert_eq!(insertion_threshold(nu), expected, "ν = {nu}");
    }
}

#[test]
fn output_error_comparison_is_strict() {
    // |ŷ − y| = |0.001 − 0| is exactly the threshold 10⁻³: no insertion.
    assert!(!inserts(&[0.001], &[0.0]));
    // |2 − 12| is exactly the threshold 10 of label 12.
    assert!(!inserts(&[2.0], &[12.0]));
    // One unit of 0.001 off a 3-decimal target: the last bit decides.
    assert!(std::hint::black_box(0.01f64) - 0.009 > 0.001);
    assert!(inserts(&[0.01], &[0.009]));
    assert!(std::hint::black_box(0.009f64) - 0.008 < 0.001);
    assert!(!inserts(&[0.008], &[0.009]));
}

#[test]
fn input_distance_comparison_is_strict() {
    // The winner at 0 is exactly ε_max = 0.001 from the sample: the halfway
    // rule applies instead of an insertion.
    let mut map = regressor(QueryMode::Winner, 1, 1);
    map.update(&[0.0], &[0.2]);
    map.update(&[1.0], &[0.2]);
    map.update(&[0.001], &[0.0]);
    assert_eq!(map.len(), 2);
    assert_eq!(w_out(&map, 0), vec![0.2 + 0.5 * (0.0 - 0.2)]);
    // Slightly farther: inserted.
    map.update(&[0.0011], &[0.0]);
    assert_eq!(map.len(), 3);
    assert_eq!(edges(&map), vec![(0, 1), (0, 2)]);
}

#[test]
fn halfway_rule_for_regressors_keeps_fractions() {
    let cases = [
        (1.0, 0.0, 0.5),
        (5.0, 2.0, 3.5),
        (2.0, 5.0, 3.5),
        (0.2, 0.0, 0.1),
    ];
    for (stored, target, expected) in cases {
        let mut map = regressor(QueryMode::Winner, 1, 1);
        map.update(&[0.0], &[stored]);
        map.update(&[1.0], &[stored]);
        map.update(&[0.0], &[target]);
        assert_eq!(map.len(), 2);
        assert_eq!(w_out(&map, 0), vec![expected], "{stored} hit by {target}");
    }
}

#[test]
fn classifier_halfway_rule_truncates_toward_zero() {
    // docs/spec/aitm.md §6, plus a negative case where floor would differ.
    let cases = [
        (1, 0, 0),
        (0, 1, 0),
        (5, 2, 3),
        (2, 5, 3),
        (3, 4, 3),
        (-5, -2, -3),
    ];
    for (stored, target, expected) in cases {
        let mut map = Aitm::new(AitmConfig::classifier(), 1, 1);
        map.update_label(&[0.0], stored);
        map.update_label(&[1.0], stored);
        map.update_label(&[0.0], target);
        assert_eq!(map.len(), 2, "{stored} hit by {target}");
        assert_eq!(w_out(&map, 0), vec![expected as f64]);
        assert_eq!(map.classify(&[0.0]), Some(expected));
    }
}

#[test]
fn classifier_zero_label_never_climbs_back() {
    // The stored (truncated) value enters the following insertion tests.
    let mut map = Aitm::new(AitmConfig::classifier(), 1, 1);
    map.update_label(&[0.0], 0);
    map.update_label(&[1.0], 0);
    for _ in 0..5 {
        map.update_label(&[0.0], 1);
        assert_eq!(map.classify(&[0.0]), Some(0));
    }
    assert_eq!(map.len(), 2);
}

#[test]
fn classifier_stores_integer_labels_on_insertion() {
    let mut map = Aitm::new(AitmConfig::classifier(), 1, 1);
    assert_eq!(map.classify(&[0.0]), None);
    map.update(&[0.0], &[2.7]);
    map.update(&[1.0], &[-1.5]);
    assert_eq!(w_out(&map, 0), vec![2.0]);
    assert_eq!(w_out(&map, 1), vec![-1.0]);
    assert_eq!(map.classify(&[0.1]), Some(2));
    assert_eq!(map.classify(&[0.9]), Some(-1));
}

#[test]
fn update_uses_the_configured_mode_for_its_estimate() {
    // Equidistant sample: BESTTWO predicts 0.01, WINNER predicts 0.
    // Target 0.012 has threshold 0.01.
    let mut counts = Vec::new();
    for mode in [QueryMode::BestTwo, QueryMode::Winner] {
        let mut map = regressor(mode, 1, 1);
        map.update(&[0.0], &[0.0]);
        map.update(&[0.01], &[0.02]);
        map.update(&[0.005], &[0.012]);
        counts.push(map.len());
    }
    assert_eq!(counts, vec![2, 3]);
}

// ------------------------------------------------- too-close second winner

#[test]
fn too_close_second_winner_is_deleted_once_more_than_two_nodes() {
    // Nodes 0 and 1 share an input (first-two rule). The next sample is far
    // and wrong: node 2 is inserted next to the winner (node 0, the earlier
    // of the tie) and node 1 is deleted for being closer than ε_max.
    let mut map = regressor(QueryMode::Winner, 1, 1);
    map.update(&[0.0], &[0.0]);
    map.update(&[0.0], &[0.0]);
    map.update(&[0.5], &[5.0]);
    assert_eq!(ids(&map), vec![0, 2]);
    assert_eq!(edges(&map), vec![(0, 2)]);
    assert_eq!(
        map.stats(),
        MapStats {
            update_calls: 3,
            inserts: 3,
            nodes: 2
        }
    );
}

#[test]
fn too_close_second_winner_survives_with_two_nodes() {
    let mut map = regressor(QueryMode::Winner, 1, 1);
    map.update(&[0.0], &[0.0]);
    map.update(&[0.0], &[0.0]);
    map.update(&[0.5], &[0.0]);
    assert_eq!(ids(&map), vec![0, 1]);
}

#[test]
fn second_winner_exactly_at_eps_max_is_kept() {
    // |δ_ws|² must be strictly below ε_max²: a second winner exactly 0.001
    // away (0.001² == ε_max² in floating point) is kept, one 0.0005 away is
    // deleted, and its neighbour 2, isolated by that, goes with it (§5).
    for (offset, expected) in [(0.001, vec![0, 1, 2, 3]), (0.0005, vec![0, 3])] {
        let mut map = build(
            AitmConfig::regressor(QueryMode::Winner),
            &[
                node(&[0.0], &[0.0]),
                node(&[offset], &[0.0]),
                node(&[1.0], &[0.0]),
            ],
            &[(0, 1), (1, 2)],
            None,
        );
        // Winner node 0, second node 1; the wrong output inserts node 3, so
        // the node count is above two.
        map.update(&[-0.5], &[5.0]);
        assert_eq!(ids(&map), expected, "offset {offset}");
    }
}

#[test]
fn deletion_cascade_can_delete_the_winner() {
    // docs/spec/aitm.md §5: the winner's only edge is to a too-close second winner.
    let mut map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0], &[0.0]),
            node(&[0.0005], &[0.0]),
            node(&[1.0], &[0.0]),
            node(&[2.0], &[0.0]),
        ],
        &[(0, 1), (2, 3)],
        None,
    );
    map.update(&[0.0], &[0.0]);
    assert_eq!(ids(&map), vec![2, 3]);
    assert_eq!(edges(&map), vec![(2, 3)]);
    assert_eq!(map.stats().update_calls, 5);
}

#[test]
fn deletion_cascade_counts_the_node_being_deleted() {
    // Three nodes: while deleting node 1 the count is still 3 > 2, so the
    // isolated winner goes too and one node is left.
    let mut map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0], &[0.0]),
            node(&[0.0005], &[0.0]),
            node(&[1.0], &[0.0]),
        ],
        &[(0, 1)],
        None,
    );
    map.update(&[0.0], &[0.0]);
    assert_eq!(ids(&map), vec![2]);
    // With one node left, the next sample is inserted unconditionally.
    map.update(&[1.0], &[0.0]);
    assert_eq!(ids(&map), vec![2, 3]);
}

#[test]
fn deletion_cascade_visits_neighbours_in_ascending_id_order() {
    // Deleting node 1 isolates 0, 2 and 3 in turn; the count reaches 2 after
    // 0 and 2 are gone, so 3 (visited last) survives.
    let mut map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0], &[0.0]),
            node(&[0.0005], &[0.0]),
            node(&[1.0], &[0.0]),
            node(&[2.0], &[0.0]),
        ],
        &[(0, 1), (1, 2), (1, 3)],
        None,
    );
    map.update(&[0.0], &[0.0]);
    assert_eq!(ids(&map), vec![3]);
}

// ------------------------------------------------------------ edge pruning

#[test]
fn thales_pruning_removes_edges_and_isolated_nodes() {
    // Winner 0 at the origin, second 1 at (0.1, 0): δ_ws = (−0.1, 0), so
    // neighbours c with c_x > 0.1 lose their edge to the winner.
    let mut map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0, 0.0], &[0.0]),
            node(&[0.1, 0.0], &[0.0]),
            node(&[0.2, 0.5], &[0.0]),  // pruned, then isolated → deleted
            node(&[-0.3, 0.1], &[0.0]), // kept (c_x < 0.1)
            node(&[0.3, -0.2], &[0.0]), // pruned, survives through 4–3
            node(&[0.1, 0.3], &[0.0]),  // dot product exactly 0: kept (strict)
        ],
        &[(0, 2), (0, 3), (0, 4), (3, 4), (0, 5)],
        None,
    );
    map.update(&[0.0, 0.0], &[0.0]);
    assert_eq!(ids(&map), vec![0, 1, 3, 4, 5]);
    assert_eq!(edges(&map), vec![(0, 1), (0, 3), (0, 5), (3, 4)]);
}

#[test]
fn pruning_never_touches_the_second_winner() {
    // The second winner is itself "behind" nothing (its dot product is 0)
    // and must stay connected to the winner it was just connected to.
    let mut map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0, 0.0], &[0.0]),
            node(&[0.1, 0.0], &[0.0]),
            node(&[1.0, 1.0], &[0.0]),
        ],
        &[(0, 1), (1, 2)],
        None,
    );
    map.update(&[0.0, 0.0], &[0.0]);
    assert_eq!(edges(&map), vec![(0, 1), (1, 2)]);
}

// ----------------------------------------------------------------- ranking

#[test]
fn ties_go_to_the_earlier_node() {
    for (first, second, expected) in [(0.5, -0.5, 1.0), (-0.5, 0.5, 1.0)] {
        let mut map = regressor(QueryMode::Winner, 1, 1);
        map.update(&[first], &[1.0]);
        map.update(&[second], &[2.0]);
        assert_eq!(map.query(&[0.0]), vec![expected]);
        assert_eq!(
            map.rank_two(&[0.0]).map(|r| (r.winner, r.second)),
            Some((0, Some(1)))
        );
    }
    // Among three tied nodes the second winner is the second-earliest.
    let map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[2.0], &[0.0]),
            node(&[1.0], &[0.0]),
            node(&[-1.0], &[0.0]),
            node(&[1.0], &[0.0]),
        ],
        &[],
        None,
    );
    let r = map.rank_two(&[0.0]).expect("non-empty");
    assert_eq!((r.winner, r.second), (1, Some(2)));
}

/// Inputs found by search: the two candidate nodes are at mathematically
/// equal distance from `x`, but the blocked sum (docs/spec/aitm.md §2) puts `a` a last
/// bit closer while a left-to-right sum puts `b` closer.
fn summation_order_case(dim: usize) -> ([f64; 10], [f64; 10], [f64; 10]) {
    if dim == 8 {
        (
            [
                0.076, 0.088, -0.186, -0.157, 0.21, 0.296, -0.011, 0.038, 0.0, 0.0,
            ],
            [
                0.094, 0.291, 0.26, -0.118, 0.021, -0.271, 0.025, -0.091, 0.0, 0.0,
            ],
            [
                0.112, 0.291, -0.375, -0.724, 0.249, 0.742, 0.007, -0.091, 0.0, 0.0,
            ],
        )
    } else {
        (
            [
                -0.102, 0.202, -0.191, 0.225, 0.046, -0.047, -0.272, -0.039, 0.225, 0.18,
            ],
            [
                -0.148, 0.028, 0.02, -0.124, 0.049, -0.108, 0.128, -0.243, -0.3, -0.063,
            ],
            [
                -0.627, 0.028, -0.54, 0.021, 0.049, 0.164, 0.128, -0.085, 0.164, -0.063,
            ],
        )
    }
}

#[test]
fn blocked_summation_order_decides_the_winner() {
    for dim in [8, 10] {
        let (x, a, b) = summation_order_case(dim);
        let (x, a, b) = (&x[..dim], &a[..dim], &b[..dim]);
        // The case really separates the two orders.
        assert!(pairwise_sq_sum(a, x).sqrt() < pairwise_sq_sum(b, x).sqrt());
        assert!(lr_sq_distance(a, x).sqrt() > lr_sq_distance(b, x).sqrt());
        // `b` is inserted first, so neither a tie nor the left-to-right
        // order would make `a` win.
        let mut map = regressor(QueryMode::Winner, dim, 1);
        map.update(b, &[1.0]);
        map.update(a, &[2.0]);
        assert_eq!(map.query(x), vec![2.0], "dim {dim}");
    }
}

// ------------------------------------------------------------ §3 queries

#[test]
fn empty_map_answers_zero_vector() {
    for mode in [QueryMode::Winner, QueryMode::BestTwo, QueryMode::Neighbour] {
        let map = regressor(mode, 2, 3);
        assert_eq!(map.query(&[0.3, 0.4]), vec![0.0; 3]);
        assert!(map.is_empty());
    }
}

#[test]
fn besttwo_blends_with_gaussian_weights() {
    let mut map = regressor(QueryMode::BestTwo, 1, 1);
    map.update(&[0.0], &[1.0]);
    map.update(&[0.1], &[3.0]);
    let x = 0.02_f64;
    let (dn, ds) = (x, 0.1 - x);
    let sq = 0.05_f64 * 0.05;
    let (kn, ks) = ((-(dn * dn) / sq).exp(), (-(ds * ds) / sq).exp());
    let expected = (kn * 1.0 + ks * 3.0) / (kn + ks);
    let got = map.query(&[x])[0];
    assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
    // Not the thesis's printed formula exp(d/σ²) (docs/spec/aitm.md §8), which would
    // favour the farther node.
    let (tn, ts) = ((dn / sq).exp(), (ds / sq).exp());
    assert!((got - (tn + ts * 3.0) / (tn + ts)).abs() > 0.1);
    assert_eq!(map.query_mode(&[x], QueryMode::Winner), vec![1.0]);
}

#[test]
fn besttwo_far_away_weights_underflow_to_zero_vector() {
    let mut map = regressor(QueryMode::BestTwo, 1, 2);
    map.update(&[0.0], &[1.0, -2.0]);
    map.update(&[0.1], &[3.0, 4.0]);
    assert_eq!(map.query(&[5.0]), vec![0.0, 0.0]);
    assert_eq!(map.query_mode(&[5.0], QueryMode::Winner), vec![3.0, 4.0]);
}

#[test]
fn one_node_besttwo_returns_stored_output_without_linear_term() {
    let config = AitmConfig::regressor(QueryMode::BestTwo);
    let map = build(
        config,
        &[node(&[0.0, 0.0], &[1.0])],
        &[],
        Some(vec![2.0, 3.0]),
    );
    assert_eq!(map.query(&[0.5, 0.5]), vec![1.0]);
    assert_eq!(map.query_mode(&[0.5, 0.5], QueryMode::Neighbour), vec![1.0]);
    // WINNER includes A·(x − w_in) = 2·0.5 + 3·0.5.
    assert_eq!(map.query_mode(&[0.5, 0.5], QueryMode::Winner), vec![3.5]);
    // A fresh vector: modifying it leaves the node alone.
    let mut y = map.query(&[0.5, 0.5]);
    y[0] = 7.0;
    assert_eq!(w_out(&map, 0), vec![1.0]);
}

#[test]
fn neighbour_mode_blends_winner_and_its_neighbours_only() {
    let map = build(
        AitmConfig::regressor(QueryMode::Neighbour),
        &[
            node(&[0.0], &[1.0]),
            node(&[0.1], &[2.0]),
            node(&[-0.05], &[4.0]),
            node(&[0.02], &[100.0]), // nearer, but not a neighbour of the winner
        ],
        &[(0, 1), (0, 2), (1, 3)],
        None,
    );
    let sq = 0.05 * 0.05;
    let k = |d: f64| (-(d * d) / sq).exp();
    let (k0, k1, k2) = (k(0.0), k(0.1), k(0.05));
    let expected = (k0 * 1.0 + k1 * 2.0 + k2 * 4.0) / (k0 + k1 + k2);
    let got = map.query(&[0.0])[0];
    assert!((got - expected).abs() < 1e-12, "{got} vs {expected}");
    // BESTTWO uses the nearest other node instead.
    let bt = map.query_mode(&[0.0], QueryMode::BestTwo)[0];
    assert!((bt - (k0 + k(0.02) * 100.0) / (k0 + k(0.02))).abs() < 1e-12);
}

#[test]
fn winner_mode_includes_the_local_linear_map() {
    let map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0, 0.0], &[1.0, 2.0]),
            node(&[1.0, 1.0], &[0.0, 0.0]),
        ],
        &[],
        Some(vec![1.0, 2.0, 3.0, 4.0, 0.0, 0.0, 0.0, 0.0]),
    );
    // y = w_out + A·(x − w_in) with A = [[1, 2], [3, 4]].
    assert_eq!(
        map.query(&[0.1, 0.2]),
        vec![1.0 + (0.1 + 2.0 * 0.2), 2.0 + (3.0 * 0.1 + 4.0 * 0.2)]
    );
}

// ------------------------------------------------------ dimension-0 output

#[test]
fn zero_dimensional_outputs_stop_inserting_after_two_nodes() {
    for mode in [QueryMode::Winner, QueryMode::BestTwo, QueryMode::Neighbour] {
        let mut map = regressor(mode, 3, 0);
        for k in 0..20 {
            let v = k as f64 * 0.37;
            map.update(&[v, -v, 1.0], &[]);
        }
        assert_eq!(
            map.stats(),
            MapStats {
                update_calls: 20,
                inserts: 2,
                nodes: 2
            }
        );
        assert_eq!(map.query(&[0.0, 0.0, 0.0]), Vec::<f64>::new());
        assert_eq!(map.classify(&[0.0, 0.0, 0.0]), None);
    }
}

// ------------------------------------------------------ learning rates ≠ 0

#[test]
fn nonzero_rates_adapt_the_winner_with_the_textbook_rule() {
    let params = AitmParams {
        eta_in: 0.5,
        eta_out: 0.25,
        eta_a: 0.5,
        ..AitmParams::regressor(QueryMode::Winner)
    };
    let config = params.check().expect("valid");
    let mut map = build(
        config,
        &[node(&[0.0], &[1.0]), node(&[2.0], &[0.0])],
        &[],
        Some(vec![0.5, 0.0]),
    );
    // Winner 0: e = 0.4, y_n = 1 + 0.5·0.4 = 1.2, error = 3 − 1.2 = 1.8.
    map.update(&[0.4], &[3.0]);
    let n0 = map.node(0).expect("winner kept");
    let dw = 0.5 * 0.4;
    assert_eq!(n0.w_in, &[dw]);
    // w_out += η_out·(y − y_n) + A·Δw_in (A before adaptation).
    assert_eq!(n0.w_out[0], 1.0 + (0.25 * (3.0 - 1.2) + 0.5 * dw));
    // A += η_A·(y − y_n)·e / |e|².
    assert_eq!(n0.a, &[0.5 + 0.5 * (3.0 - 1.2) * 0.4 / (0.4 * 0.4)]);
}

// ------------------------------------------------------------- serde

#[test]
fn deserialisation_rejects_inconsistent_state() {
    let map = build(
        AitmConfig::regressor(QueryMode::Winner),
        &[
            node(&[0.0], &[0.0]),
            node(&[1.0], &[0.0]),
            node(&[2.0], &[0.0]),
        ],
        &[(0, 1), (1, 2)],
        None,
    );
    let good = serde_json::to_value(&map).expect("serialise");
    let mutate = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        f(&mut v);
        serde_json::from_value::<Aitm>(v)
    };
    assert!(mutate(&|_| {}).is_ok());
    assert!(mutate(&|v| v["w_in"] = json!([0.0, 1.0])).is_err());
    assert!(mutate(&|v| v["w_out"] = json!([0.0])).is_err());
    assert!(mutate(&|v| v["a"] = json!([])).is_err());
    assert!(mutate(&|v| v["ids"] = json!([0, 2, 1])).is_err());
    assert!(mutate(&|v| v["inserts"] = json!(2)).is_err());
    assert!(mutate(&|v| v["update_calls"] = json!(1)).is_err());
    assert!(mutate(&|v| v["neighbours"][0] = json!([1, 7])).is_err());
    assert!(mutate(&|v| v["neighbours"][0] = json!([1, 2])).is_err());
    assert!(mutate(&|v| v["neighbours"][0] = json!([0, 1])).is_err());
    assert!(mutate(&|v| v["neighbours"] = json!([[1], [0, 2]])).is_err());
    assert!(mutate(&|v| v["config"]["sigma"] = json!(0.0)).is_err());
}

#[test]
fn serde_round_trip_is_bit_identical() {
    let mut map = regressor(QueryMode::BestTwo, 2, 3);
    let mut s = 1u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 33) % 1000) as f64 / 1000.0 - 0.5
    };
    for _ in 0..300 {
        let x = [next(), next()];
        let y = [next() / 7.0, next() * 1e-3, next() / 3.0];
        map.update(&x, &y);
    }
    let json = serde_json::to_string(&map).expect("serialise");
    let back: Aitm = serde_json::from_str(&json).expect("deserialise");
    assert_eq!(serde_json::to_string(&back).expect("serialise"), json);
    for (a, b) in map.nodes().zip(back.nodes()) {
        assert_eq!(a.id, b.id);
        for (u, v) in a.w_out.iter().zip(b.w_out) {
            assert_eq!(u.to_bits(), v.to_bits());
        }
    }
}
