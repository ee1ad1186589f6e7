//! The worked examples of docs/spec/inverse-model.md §5 and scenarios pinning the
//! merge and query rules.

use super::*;

fn cfg() -> AimConfig {
    AimConfig::hz100()
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

fn key(feature: usize, sign: Sign) -> PrototypeKey {
    PrototypeKey::new(feature, sign)
}

const P_A: [f64; 10] = [15.0, 8.0, 0.5, -0.02, -0.25, -0.05, 0.1, 0.0, 0.5, 0.0];
const P_B: [f64; 10] = [15.0, 8.0, 0.5, -0.02, -0.2, -0.05, 0.0, 0.0, 0.5, 0.0];
const P_C: [f64; 10] = [15.0, 8.0, 0.5, -0.01, 0.25, -0.05, 0.0, 0.5, 0.0, 0.0];

// ------------------------------------------------- §5 prototype examples

#[test]
fn example_1_sign_combinations_and_accumulators() {
    let mut proto = Prototype::new(10);
    let p1 = [15.0, 8.0, 0.5, -0.02, -0.25, -0.05, 0.0, 0.0, 0.5, 0.0];
    let p2 = P_B;
    let p3 = [15.0, 8.0, 0.5, -0.001, 0.25, -0.05, 0.0, 0.5, 0.0, 0.0];
    proto.train(&p1, 0.1, &cfg());
    assert_eq!(proto.combinations().len(), 1);
    assert_eq!(
        proto.combinations()[0].signs,
        vec![1, 1, 1, -1, -1, -1, 0, 0, 1, 0]
    );
    assert_eq!(proto.combinations()[0].w, 0.1);
    proto.train(&p2, 0.2, &cfg());
    assert_eq!(proto.combinations().len(), 1);
    assert_eq!(proto.combinations()[0].w, 0.1 + 0.2);
    assert_eq!(proto.combinations()[0].n, 2);
    let expected_i: Vec<f64> = p1.iter().zip(&p2).map(|(a, b)| 0.1 * a + 0.2 * b).collect();
    assert_eq!(proto.combinations()[0].i, expected_i);
    // −0.001 lies inside the zero band (|p_j| ≤ ε_node).
    proto.train(&p3, 0.3, &cfg());
    assert_eq!(proto.combinations().len(), 2);
    assert_eq!(
        proto.combinations()[1].signs,
        vec![1, 1, 1, 0, 1, -1, 0, 1, 0, 0]
    );
    assert_eq!(proto.combinations()[1].w, 0.3);
    assert_eq!(proto.combinations()[1].n, 1);
}

#[test]
fn example_2_merging_and_two_alternatives() {
    let mut proto = Prototype::new(10);
    assert_eq!(proto.preconditions(&cfg()), None);
    proto.train(&P_A, 0.105, &cfg());
    let pre = proto.preconditions(&cfg()).expect("trained");
    assert!(close(&pre.primary, &P_A, 1e-12));
    assert_eq!(pre.alternative, None);

    // p_b differs from p_a only in component 6 (zero vs non-zero): merged.
    proto.train(&P_B, 0.2, &cfg());
    let pre = proto.preconditions(&cfg()).expect("trained");
    let w_ab = 0.2 + 0.105;
    let avg_ab: Vec<f64> = P_B
        .iter()
        .zip(&P_A)
        .map(|(b, a)| (0.2 * b + 0.105 * a) / w_ab)
        .collect();
    assert_eq!(pre.primary, avg_ab);
    assert_eq!(pre.alternative, None);

    // p_c opposes them in component 4: its own group, with the larger
    // average contribution (0.3 against 0.1525, ratio 0.508 > 0.5).
    proto.train(&P_C, 0.3, &cfg());
    let pre = proto.preconditions(&cfg()).expect("trained");
    let pooled_3 = (0.305 * avg_ab[3] + 0.3 * -0.01) / 0.605;
    assert!((pooled_3 - -0.015041).abs() < 1e-6);
    let mut p1 = P_C.to_vec();
    p1[3] = pooled_3;
    assert!(close(&pre.primary, &p1, 1e-12), "{:?}", pre.primary);
    // Not exactly −0.015 (the original test used a 1e-4 tolerance).
    assert!((pre.primary[3] - -0.015).abs() > 1e-5);
    let mut p2 = avg_ab.clone();
    p2[3] = pooled_3;
    let alternative = pre.alternative.expect("ratio above 0.5");
    assert!(close(&alternative, &p2, 1e-12), "{alternative:?}");
    // The pooled components are bitwise identical in both alternatives.
    for j in [0, 1, 2, 3, 5, 9] {
        assert_eq!(
            pre.primary[j].to_bits(),
            alternative[j].to_bits(),
            "component {j}"
        );
    }
}

// ------------------------------------------------ §3.2 merging details

#[test]
fn rare_combinations_are_dropped_by_the_mean_count_filter() {
    let mut proto = Prototype::new(2);
    for _ in 0..3 {
        proto.train(&[0.5, 0.5], 0.1, &cfg());
    }
    // Larger contribution but N = 1 < mean 2: ignored.
    proto.train(&[-0.5, 0.5], 1.0, &cfg());
    let merged = proto.merge(&cfg());
    assert_eq!(merged.len(), 1);
    assert_eq!(merged[0].n, 3);
    let pre = proto.preconditions(&cfg()).expect("trained");
    assert!(close(&pre.primary, &[0.5, 0.5], 1e-12));
    assert_eq!(pre.alternative, None);
}

#[test]
fn equivalence_is_tested_against_the_group_s_first_member() {
    // Inserted (1,0,1), (0,1,1), (0,0,1). Sorted by zero count, (0,0,1)
    // leads and absorbs both others, although they differ from each other
    // in two zero positions. Without the sort, or testing against the
    // growing group, two groups would result.
    let mut proto = Prototype::new(3);
    proto.train(&[0.5, 0.0, 0.5], 0.1, &cfg());
    proto.train(&[0.0, 0.5, 0.5], 0.1, &cfg());
    proto.train(&[0.0, 0.0, 0.5], 0.1, &cfg());
    let merged = proto.merge(&cfg());
    assert_eq!(merged.len(), 1);
    assert_eq!(merged[0].n, 3);
    assert_eq!(merged[0].key, vec![1, 1, 1]);
    // The stored accumulators are untouched by merging.
    assert_eq!(proto.combinations().len(), 3);
    // With no zero mismatch allowed nothing merges.
    let strict = AimParams {
        max_zero_mismatch: 0,
        ..AimParams::hz100()
    }
    .check()
    .expect("valid");
    assert_eq!(proto.merge(&strict).len(), 3);
}

#[test]
fn colliding_recomputed_key_overwrites_in_the_original_position() {
    // Zero-count order: b (2 zeros), a, e, d (1), c (0).
    // Group 1 = b + a + d, recomputed key (1,−1,1); group 2 = e, key
    // (−1,1,0); group 3 = c, key (1,−1,1) again: it replaces group 1 in
    // slot 0 (original behaviour, docs/spec/inverse-model.md §6).
    let mut proto = Prototype::new(3);
    proto.train(&[0.0, -1.0, 0.002], 0.01, &cfg()); // a (0,−1,1)
    proto.train(&[0.0, 0.0, 0.002], 1.0, &cfg()); // b (0,0,1)
    proto.train(&[-1.0, 1.0, 0.0], 0.01, &cfg()); // e (−1,1,0)
    proto.train(&[1.0, -1.0, 1.0], 0.01, &cfg()); // c (1,−1,1)
    proto.train(&[1.0, 0.0, 1.0], 0.01, &cfg()); // d (1,0,1)
    let merged = proto.merge(&cfg());
    assert_eq!(merged.len(), 2);
    assert_eq!(merged[0].key, vec![1, -1, 1]);
    assert_eq!((merged[0].w, merged[0].n), (0.01, 1));
    assert_eq!(merged[1].key, vec![-1, 1, 0]);
    // Equal averages: the stable sort keeps slot order, so c's vector is P1.
    let pre = proto.preconditions(&cfg()).expect("trained");
    assert!(close(&pre.primary, &[1.0, -1.0, 1.0], 1e-12));
    let alt = pre.alternative.expect("ratio 1");
    assert!(close(&alt, &[-1.0, 1.0, 0.0], 1e-12));
}

#[test]
fn alternative_requires_ratio_strictly_above_one_half() {
    // Averages 0.2 and 0.1: ratio exactly 0.5, no alternative.
    let mut proto = Prototype::new(2);
    proto.train(&[0.5, 0.5], 0.2, &cfg());
    proto.train(&[-0.5, 0.5], 0.1, &cfg());
    assert_eq!(
        proto.preconditions(&cfg()).expect("trained").alternative,
        None
    );
    // Slightly more: offered.
    let mut proto = Prototype::new(2);
    proto.train(&[0.5, 0.5], 0.2, &cfg());
    proto.train(&[-0.5, 0.5], 0.1001, &cfg());
    let pre = proto.preconditions(&cfg()).expect("trained");
    assert!(close(
        &pre.primary,
        &[0.5, 0.5 * (0.2 + 0.1001) / 0.3001],
        1e-12
    ));
    assert!(close(
        &pre.alternative.expect("offered"),
        &[-0.5, 0.5 * (0.2 + 0.1001) / 0.3001],
        1e-12
    ));
}

// --------------------------------------------------- §5 network examples

fn example_3_model() -> InverseModel {
    let mut p = P_B;
    p[4] = -0.25;
    let mut model = InverseModel::new(cfg());
    model.train(&p, &[0.0, 0.1, 0.0, 0.1]);
    assert_eq!(model.prototype_count(), 2);
    assert!(model.prototype(key(1, Sign::Positive)).is_some());
    assert!(model.prototype(key(3, Sign::Positive)).is_some());
    model.train(&P_B, &[0.0, 0.1, -0.1, 0.1]);
    assert_eq!(model.prototype_count(), 3);
    assert!(model.prototype(key(2, Sign::Negative)).is_some());
    model
}

#[test]
fn example_3_and_4_network_training_and_queries() {
    let mut p = P_B;
    p[4] = -0.25;
    let mut model = example_3_model();
    let got = model
        .preconditions_for(&[0.0, 0.5, -0.2, 0.3])
        .expect("feature 1 has a prototype");
    let mean: Vec<f64> = p.iter().zip(&P_B).map(|(a, b)| 0.5 * (a + b)).collect();
    assert!(close(&got, &mean, 1e-12), "{got:?}");
    assert_eq!(model.current_key(), Some(key(1, Sign::Positive)));
    assert_eq!(model.second_key(), Some(key(3, Sign::Positive)));

    model.clear_current();
    let got = model
        .preconditions_for(&[0.0, 0.5, -0.6, 0.3])
        .expect("feature 2 has a prototype");
    assert!(close(&got, &P_B, 1e-12), "{got:?}");
    assert_eq!(model.current_key(), Some(key(2, Sign::Negative)));
}

#[test]
fn training_threshold_is_strict_and_weights_are_magnitudes() {
    let mut model = InverseModel::new(cfg());
    model.train(&[1.0, 2.0], &[0.002, -0.0021, 0.0]);
    assert_eq!(model.prototype_count(), 1);
    let proto = model.prototype(key(1, Sign::Negative)).expect("trained");
    assert_eq!(proto.combinations()[0].w, 0.0021);
    assert_eq!(model.preconditions_for(&[0.5, 0.0, 0.0]), None);
}

#[test]
fn current_feature_is_kept_while_large_and_same_sign() {
    let mut p = P_B;
    p[4] = -0.25;
    let mean: Vec<f64> = p.iter().zip(&P_B).map(|(a, b)| 0.5 * (a + b)).collect();
    let mut model = example_3_model();
    model.preconditions_for(&[0.0, 0.5, -0.2, 0.3]);
    assert_eq!(model.current_key(), Some(key(1, Sign::Positive)));
    // Feature 2 is now the largest, but feature 1 is still > ε_keep: kept,
    // and second_key is not recomputed (it would become (1, +)).
    let got = model
        .preconditions_for(&[0.0, 0.4, -0.6, 0.05])
        .expect("kept");
    assert!(close(&got, &mean, 1e-12));
    assert_eq!(model.current_key(), Some(key(1, Sign::Positive)));
    assert_eq!(model.second_key(), Some(key(3, Sign::Positive)));
    // |D_1| = ε_keep exactly: not kept (strict), feature 2 selected.
    let got = model
        .preconditions_for(&[0.0, 0.01, -0.6, 0.05])
        .expect("switch");
    assert!(close(&got, &P_B, 1e-12));
    assert_eq!(model.current_key(), Some(key(2, Sign::Negative)));
    assert_eq!(model.second_key(), Some(key(3, Sign::Positive)));
    // Sign flip of the current feature: reselected.
    model.preconditions_for(&[0.0, 0.5, 0.6, 0.05]);
    assert_eq!(model.current_key(), Some(key(1, Sign::Positive)));
    assert_eq!(model.second_key(), Some(key(3, Sign::Positive)));
}

#[test]
fn ties_in_magnitude_go_to_the_higher_index() {
    let mut model = example_3_model();
    model.preconditions_for(&[0.0, 0.3, 0.0, 0.3]);
    assert_eq!(model.current_key(), Some(key(3, Sign::Positive)));
    assert_eq!(model.second_key(), Some(key(1, Sign::Positive)));
}

#[test]
fn second_key_stays_at_the_last_index_when_only_it_matches() {
    let mut model = InverseModel::new(cfg());
    model.train(&[1.0], &[0.0, 0.0, -0.1]);
    model
        .preconditions_for(&[0.5, 0.4, -0.1])
        .expect("feature 2");
    assert_eq!(model.current_key(), Some(key(2, Sign::Negative)));
    assert_eq!(model.second_key(), Some(key(2, Sign::Negative)));
}

#[test]
fn no_matching_prototype_answers_none_but_sets_second_key() {
    let mut model = example_3_model();
    assert_eq!(model.preconditions_for(&[0.5, -0.5, 0.5, -0.1]), None);
    assert_eq!(model.current_key(), None);
    // The last assignment is key_of(order[len − 1]) = key_of(3).
    assert_eq!(model.second_key(), Some(key(3, Sign::Negative)));
}

#[test]
fn zero_components_map_onto_feature_0_positive() {
    // Gate-like model: prototype (0, +) exists.
    let mut model = InverseModel::new(cfg());
    model.train(&[0.25, 0.75], &[0.1, 0.0, 0.0]);
    // D_0 < 0 has no prototype; the zero components (also −0.0) look up
    // (0, +). Ties between them: higher index (2) first.
    let got = model.preconditions_for(&[-0.5, 0.0, -0.0]).expect("(0, +)");
    assert!(close(&got, &[0.25, 0.75], 1e-12));
    assert_eq!(model.current_key(), Some(key(0, Sign::Positive)));
    assert_eq!(model.second_key(), Some(key(0, Sign::Positive)));

    // Interaction-like model: no (0, +), so zero components never match.
    let mut model = InverseModel::new(cfg());
    model.train(&[0.25, 0.75], &[0.0, 0.1, 0.0]);
    assert_eq!(model.preconditions_for(&[0.0, -0.5, 0.0]), None);
}

/// Prototype (1, +) offers P1 = (0.5, 0.5) and P2 = (−0.5, 0.5).
fn two_way_model() -> InverseModel {
    let mut model = InverseModel::new(cfg());
    model.train(&[0.5, 0.5], &[0.0, 0.1, 0.0]);
    model.train(&[-0.5, 0.5], &[0.0, 0.1, 0.0]);
    let pre = model
        .prototype(key(1, Sign::Positive))
        .and_then(|p| p.preconditions(&cfg()))
        .expect("trained");
    assert!(close(&pre.primary, &[0.5, 0.5], 1e-12));
    assert!(close(
        &pre.alternative.expect("two ways"),
        &[-0.5, 0.5],
        1e-12
    ));
    model
}

#[test]
fn alternative_is_chosen_by_distance_to_the_second_key() {
    // No second prototype: P1.
    let mut model = two_way_model();
    assert_eq!(
        model.preconditions_for(&[0.0, 0.5, 0.3]),
        Some(vec![0.5, 0.5])
    );

    // (2, +) with one precondition near P2: P2.
    let mut model = two_way_model();
    model.train(&[-0.4, 0.3], &[0.0, 0.0, 0.1]);
    let got = model.preconditions_for(&[0.0, 0.5, 0.3]).expect("answer");
    assert!(close(&got, &[-0.5, 0.5], 1e-12));
    // Near P1: P1.
    let mut model = two_way_model();
    model.train(&[0.4, 0.3], &[0.0, 0.0, 0.1]);
    let got = model.preconditions_for(&[0.0, 0.5, 0.3]).expect("answer");
    assert!(close(&got, &[0.5, 0.5], 1e-12));
}

#[test]
fn second_key_alternatives_both_count() {
    // (2, +) offers S1 = (0.1, −0.9) and S2 = (−0.45, 0.45). S1 alone would
    // pick P1 (o1 ≈ 1.456 ≤ o2 ≈ 1.523), but S2 is very near P2.
    let mut model = two_way_model();
    model.train(&[0.1, -0.9], &[0.0, 0.0, 0.1]);
    model.train(&[-0.45, 0.45], &[0.0, 0.0, 0.1]);
    let got = model.preconditions_for(&[0.0, 0.5, 0.3]).expect("answer");
    assert!(close(&got, &[-0.5, 0.5], 1e-12));
}

// ---------------------------------------------------------------- serde

#[test]
fn serde_round_trip_and_validation() {
    let mut model = two_way_model();
    model.train(&[0.1, -0.9], &[0.0, 0.0, 0.1]);
    model.preconditions_for(&[0.0, 0.5, 0.3]);
    let json = serde_json::to_string(&model).expect("serialise");
    let mut back: InverseModel = serde_json::from_str(&json).expect("deserialise");
    assert_eq!(serde_json::to_string(&back).expect("serialise"), json);
    assert_eq!(back, model);
    assert_eq!(
        back.preconditions_for(&[0.0, 0.4, 0.3]),
        model.preconditions_for(&[0.0, 0.4, 0.3])
    );

    let value = serde_json::to_value(&model).expect("serialise");
    let bad = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = value.clone();
        f(&mut v);
        serde_json::from_value::<InverseModel>(v).is_err()
    };
    assert!(!bad(&|_| {}));
    assert!(bad(&|v| v["precondition_dim"] = serde_json::json!(3)));
    assert!(bad(
        &|v| v["prototypes"][0][1]["combinations"] = serde_json::json!([])
    ));
    assert!(bad(
        &|v| v["prototypes"][1][0] = v["prototypes"][0][0].clone()
    ));
    assert!(bad(&|v| {
        v["current_key"] = serde_json::json!({"feature": 7, "sign": "Positive"})
    }));
    assert!(bad(&|v| v["config"]["eps_dif"] = serde_json::json!(-1.0)));
}

// ------------------------------------------------------------ properties

mod properties {
    use proptest::prelude::*;

    use super::super::*;

    fn grid() -> impl Strategy<Value = f64> {
        (-30i32..=30).prop_map(|k| f64::from(k) / 1000.0)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn queries_are_finite_and_round_trips_exact(
            samples in prop::collection::vec(
                (prop::collection::vec(grid(), 4), prop::collection::vec(grid(), 3)),
                0..40,
            ),
            queries in prop::collection::vec(prop::collection::vec(grid(), 3), 1..8),
        ) {
            let mut model = InverseModel::new(AimConfig::hz100());
            for (p, d) in &samples {
                model.train(p, d);
            }
            prop_assert!(model.prototype_count() <= 6);
            let text = serde_json::to_string(&model).expect("serialise");
            let mut copy: InverseModel = serde_json::from_str(&text).expect("deserialise");
            prop_assert_eq!(serde_json::to_string(&copy).expect("serialise"), text);
            for d in &queries {
                let answer = model.preconditions_for(d);
                if let Some(p) = &answer {
                    prop_assert_eq!(p.len(), 4);
                    prop_assert!(p.iter().all(|v| v.is_finite()));
                    prop_assert!(model.current_key().is_some());
                }
                let again = copy.preconditions_for(d);
                prop_assert_eq!(
                    answer.map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>()),
                    again.map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                );
                prop_assert_eq!(model.current_key(), copy.current_key());
                prop_assert_eq!(model.second_key(), copy.second_key());
            }
        }
    }
}
