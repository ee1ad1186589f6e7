//! Property tests: structural invariants of the graph under random training
//! sequences on a 3-decimal grid (dense enough for ties, near-duplicates and
//! deletions), and bit-identical serde round trips.

use std::collections::BTreeSet;

use proptest::prelude::*;

use super::distance::ranking_distance;
use super::*;

#[derive(Debug, Clone)]
struct Scenario {
    params: AitmParams,
    input_dim: usize,
    output_dim: usize,
    samples: Vec<(Vec<f64>, Vec<f64>)>,
    probes: Vec<Vec<f64>>,
    split: usize,
}

/// A grid coordinate: k/1000 for small k (many exact ties and one-unit
/// neighbours) or, sometimes, a coarser value.
fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => (-6i32..=6).prop_map(|k| f64::from(k) / 1000.0),
        1 => (-300i32..=300).prop_map(|k| f64::from(k) / 1000.0),
    ]
}

fn scenario() -> impl Strategy<Value = Scenario> {
    let dims = prop_oneof![Just(1usize), Just(2), Just(3), Just(8), Just(10)];
    let mode = prop_oneof![
        Just(QueryMode::Winner),
        Just(QueryMode::BestTwo),
        Just(QueryMode::Neighbour)
    ];
    (dims, 0usize..=3, mode, any::<bool>(), 1usize..60).prop_flat_map(
        |(input_dim, output_dim, mode, classifier, count)| {
            let output_dim = if classifier { 1 } else { output_dim };
            let params = if classifier {
                AitmParams::classifier()
            } else {
                AitmParams::regressor(mode)
            };
            let output = if classifier {
                (0i32..=12).prop_map(|k| vec![f64::from(k)]).boxed()
            } else {
                prop::collection::vec(
                    (-40i32..=40).prop_map(|k| f64::from(k) / 1000.0),
                    output_dim,
                )
                .boxed()
            };
            let sample = (prop::collection::vec(coord(), input_dim), output);
            (
                prop::collection::vec(sample, count),
                prop::collection::vec(prop::collection::vec(coord(), input_dim), 1..4),
                0..=count,
            )
                .prop_map(move |(samples, probes, split)| Scenario {
                    params,
                    input_dim,
                    output_dim,
                    samples,
                    probes,
                    split,
                })
        },
    )
}

fn check_invariants(map: &Aitm) -> Result<(), TestCaseError> {
    let ids: Vec<NodeId> = map.nodes().map(|v| v.id).collect();
    let id_set: BTreeSet<NodeId> = ids.iter().copied().collect();
    prop_assert!(
        ids.windows(2).all(|w| w[0] < w[1]),
        "ids in insertion order"
    );
    for v in map.nodes() {
        prop_assert_eq!(v.w_in.len(), map.input_dim());
        prop_assert_eq!(v.w_out.len(), map.output_dim());
        for &c in v.neighbours {
            prop_assert!(c != v.id, "self loop at {}", c);
            prop_assert!(id_set.contains(&c), "dangling neighbour id {}", c);
            let other = map.node(c).expect("checked above");
            prop_assert!(other.neighbours.contains(&v.id), "asymmetric edge");
        }
        if map.config().is_classifier() {
            prop_assert!(v.w_out.iter().all(|y| y.fract() == 0.0), "integer labels");
        }
    }
    let s = map.stats();
    prop_assert_eq!(s.nodes, map.len());
    prop_assert!(s.nodes as u64 <= s.update_calls);
    prop_assert!(s.inserts >= s.nodes as u64);
    prop_assert!(s.inserts <= s.update_calls);
    prop_assert!(s.update_calls == 0 || s.nodes >= 1);
    Ok(())
}

/// Reference ranking: a stable sort of the ranking distances.
fn reference_ranking(map: &Aitm, x: &[f64]) -> Option<(NodeId, Option<NodeId>)> {
    let mut order: Vec<(NodeId, f64)> = map
        .nodes()
        .map(|v| (v.id, ranking_distance(v.w_in, x)))
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let first = order.first()?.0;
    Some((first, order.get(1).map(|s| s.0)))
}

fn json(map: &Aitm) -> String {
    serde_json::to_string(map).expect("finite state serialises")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn invariants_hold_after_every_update(sc in scenario()) {
        let config = sc.params.check().expect("valid presets");
        let mut map = Aitm::new(config, sc.input_dim, sc.output_dim);
        check_invariants(&map)?;
        for (x, y) in &sc.samples {
            map.update(x, y);
            check_invariants(&map)?;
            for probe in sc.probes.iter().chain(std::iter::once(x)) {
                let answer = map.query(probe);
                prop_assert_eq!(answer.len(), sc.output_dim);
                prop_assert!(answer.iter().all(|v| v.is_finite()));
                for mode in [QueryMode::Winner, QueryMode::BestTwo, QueryMode::Neighbour] {
                    prop_assert!(map.query_mode(probe, mode).iter().all(|v| v.is_finite()));
                }
                prop_assert_eq!(map.ranked_ids(probe, true), reference_ranking(&map, probe));
            }
        }
    }

    /// docs/spec/aitm.md §7: the spatial index returns exactly the scan's winner and
    /// second winner, and a map searching through it evolves bit for bit
    /// like one that scans, through insertions, deletions (gaps and their
    /// compaction) and, with η > 0, moving nodes.
    #[test]
    fn the_index_ranks_exactly_like_the_scan(sc in scenario(), eta in prop_oneof![Just(0.0), Just(0.5)]) {
        let mut params = sc.params;
        params.eta_in = eta;
        params.eta_out = eta;
        let config = params.check().expect("valid rates");
        let mut scan = Aitm::new(config, sc.input_dim, sc.output_dim);
        let mut indexed = scan.clone();
        indexed.set_index_min(0);
        scan.set_index_min(usize::MAX);
        for (x, y) in &sc.samples {
            scan.update(x, y);
            indexed.update(x, y);
            prop_assert_eq!(json(&indexed), json(&scan));
            prop_assert_eq!(indexed.is_indexed(), sc.input_dim > 0);
            for probe in sc.probes.iter().chain(std::iter::once(x)) {
                prop_assert_eq!(indexed.ranked_ids(probe, false), scan.ranked_ids(probe, true));
            }
        }
    }

    #[test]
    fn serde_round_trip_is_bit_identical_and_behaves_identically(sc in scenario()) {
        let config = sc.params.check().expect("valid presets");
        let mut map = Aitm::new(config, sc.input_dim, sc.output_dim);
        let (before, after) = sc.samples.split_at(sc.split);
        for (x, y) in before {
            map.update(x, y);
        }
        let text = json(&map);
        let mut copy: Aitm = serde_json::from_str(&text).expect("own output deserialises");
        prop_assert_eq!(json(&copy), text);
        for probe in &sc.probes {
            let (a, b) = (map.query(probe), copy.query(probe));
            prop_assert_eq!(
                a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                b.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
            prop_assert_eq!(map.classify(probe), copy.classify(probe));
        }
        for (x, y) in after {
            map.update(x, y);
            copy.update(x, y);
        }
        prop_assert_eq!(json(&copy), json(&map));
        prop_assert_eq!(copy.stats(), map.stats());
    }
}
