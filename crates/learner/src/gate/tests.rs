//! Tests of the gate model (`docs/spec/gate-model.md`) and its planner (`docs/spec/planning.md`
//! §2, §4, §5): every rule and quirk pinned by a test that fails if it is
//! broken.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::Vector2;
use rand::RngExt;

use super::algorithm::hard_coded_gate;
use super::*;
use crate::aim::InverseModel;
use crate::aitm::{Aitm, AitmConfig, QueryMode};
use crate::features::{local_change, r3, relative_features};
use crate::model::Model;
use crate::planning::{circle, exploration};
use crate::stats::GateStats;
use crate::types::{
    Action, Frame, ObjectState, Observation, Poses, Target, TargetError, TrackedObject,
    ACTUATOR_ID, BLUE_ID, RED_ID,
};

const PUSH: Action = Action::new(0.0, 0.5);

fn st(x: f64, y: f64, theta: f64) -> ObjectState {
    ObjectState::new(x, y, theta)
}

fn tracked(id: u32, s: ObjectState, s_prev: ObjectState) -> TrackedObject {
    TrackedObject { id, s, s_prev }
}

/// A parsed-like world: actuator at `act`, blocks fresh (`s_prev = s`).
fn world(act: (f64, f64), blocks: &[(u32, ObjectState)]) -> GateWorld {
    let mut poses = Poses {
        actuator: st(act.0, act.1, 0.0),
        ..Poses::default()
    };
    poses.blocks.extend(blocks.iter().copied());
    GateWorld::from_poses(&poses)
}

fn blue(x: f64, y: f64, theta: f64) -> [(u32, ObjectState); 1] {
    [(BLUE_ID, st(x, y, theta))]
}

/// A gate classifier whose winner always carries `label`.
fn gate_always(label: i64) -> Aitm {
    let mut gate = Aitm::new(AitmConfig::classifier(), 8, 1);
    gate.update_label(&[0.0; 8], label);
    gate.update_label(&[1.0; 8], label);
    gate
}

/// A block predictor that answers `delta` near the usual features.
fn predictor_constant(delta: [f64; 3], inverse: InverseModel) -> Predictor {
    let mut forward = Aitm::new(AitmConfig::regressor(QueryMode::BestTwo), 8, 3);
    forward.update(&[15.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], &delta);
    forward.update(&[15.0, 8.0, 0.1, 0.0, 0.0, -0.1, 0.0, 0.0], &delta);
    Predictor { forward, inverse }
}

fn bits(p: &Poses) -> Vec<u64> {
    p.objects()
        .flat_map(|(id, s)| {
            [
                u64::from(id),
                s.x.to_bits(),
                s.y.to_bits(),
                s.theta.to_bits(),
            ]
        })
        .collect()
}

fn tracked_bits(o: &TrackedObject) -> [u64; 6] {
    [
        o.s.x.to_bits(),
        o.s.y.to_bits(),
        o.s.theta.to_bits(),
        o.s_prev.x.to_bits(),
        o.s_prev.y.to_bits(),
        o.s_prev.theta.to_bits(),
    ]
}

/// A kinematic stand-in for a push-task run (not the physics): the actuator
/// moves 5 mm per message from (x0, 0); once it reaches the blue block's
/// lower edge it carries the block along, which also turns by −0.02·x0 per
/// message. Rounded like parsed states.
fn synthetic_run(x0: f64, messages: usize) -> Vec<GateWorld> {
    let mut block = st(0.0, 0.25, 0.0);
    (0..messages)
        .map(|k| {
            let ay = r3(0.005 * k as f64);
            if x0.abs() < 0.25 && ay + 0.075 > block.y {
                block = st(block.x, r3(ay + 0.075), r3(block.theta - 0.02 * x0));
            }
            world((x0, ay), &[(BLUE_ID, block)])
        })
        .collect()
}

/// Trains the way the push-task driver does (`docs/spec/experiments.md` §2):
/// `reset_objects` on the first message of a run, `update` on the others.
fn train(model: &mut GateModel, starts: &[f64]) {
    for &x0 in starts {
        let run = synthetic_run(x0, 150);
        model.reset_objects(&run[0]);
        for w in &run[1..] {
            model.update(w, PUSH);
        }
    }
}

// ---------------------------------------------------------------- update

#[test]
fn gate_training_pairs_the_old_block_with_the_new_actuator() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.17), &blue(0.0, 0.25, 0.0)));
    m.update(&world((0.0, 0.175), &blue(0.0, 0.255, 0.01)), PUSH);

    let old_block = tracked(BLUE_ID, st(0.0, 0.25, 0.0), st(0.0, 0.25, 0.0));
    let new_block = tracked(BLUE_ID, st(0.0, 0.255, 0.01), st(0.0, 0.25, 0.0));
    let old_act = tracked(ACTUATOR_ID, st(0.0, 0.17, 0.0), st(0.0, 0.17, 0.0));
    let new_act = tracked(ACTUATOR_ID, st(0.0, 0.175, 0.0), st(0.0, 0.17, 0.0));
    let want = relative_features(&old_block, &new_act);
    // The alternatives differ, so the assertion below discriminates.
    assert_ne!(want, relative_features(&new_block, &new_act));
    assert_ne!(want, relative_features(&old_block, &old_act));

    let gate: Vec<_> = m.gate().nodes().collect();
    assert_eq!(gate.len(), 1);
    assert_eq!(gate[0].w_in, want);
    assert_eq!(gate[0].w_out, [1.0]);
    let p = m.predictor(BLUE_ID).expect("created on the first change");
    let node = p.forward().nodes().next().expect("one node");
    assert_eq!(node.w_in, want);
    assert_eq!(node.w_out, local_change(&old_block.s, &new_block.s));
    // (1, +) and (2, +): both changes exceed ε_dif = 0.002.
    assert_eq!(p.inverse().prototype_count(), 2);
}

#[test]
fn blocks_are_processed_in_descending_id_order() {
    let blocks = [(BLUE_ID, st(0.0, 0.25, 0.0)), (RED_ID, st(-0.6, 0.35, 0.0))];
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blocks));
    m.update(&world((0.0, 0.005), &blocks), PUSH);
    // The first two gate samples are always inserted, in training order.
    let ids: Vec<f64> = m.gate().nodes().map(|n| n.w_in[0]).collect();
    assert_eq!(ids, vec![27.0, 15.0]);
}

#[test]
fn the_actuator_model_learns_the_action_and_the_global_change() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.1, 0.0), &[]));
    m.update(&world((0.1, 0.005), &[]), PUSH);
    let node = m.actuator_model().nodes().next().expect("one node");
    assert_eq!(node.w_in, [0.0, 0.5]);
    assert_eq!(node.w_out, [0.0, 0.005, 0.0]);
    assert_eq!(
        m.actuator(),
        Some(tracked(ACTUATOR_ID, st(0.1, 0.005, 0.0), st(0.1, 0.0, 0.0)))
    );
}

#[test]
fn any_rounding_level_change_is_a_change() {
    // ε_change = 0: a 0.001 rad turn alone labels the sample "changed".
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    m.update(&world((0.0, 0.005), &blue(0.0, 0.25, 0.001)), PUSH);
    assert_eq!(m.gate().nodes().next().map(|n| n.w_out[0]), Some(1.0));
    assert!(m.predictor(BLUE_ID).is_some());
    // No change at all: label 0 and no predictor.
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    m.update(&world((0.0, 0.005), &blue(0.0, 0.25, 0.0)), PUSH);
    assert_eq!(m.gate().nodes().next().map(|n| n.w_out[0]), Some(0.0));
    assert!(m.predictor(BLUE_ID).is_none());
}

#[test]
fn the_first_sight_of_a_block_adopts_it_without_training() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &[]));
    let w = world((0.0, 0.005), &blue(0.0, 0.25, 0.0));
    m.update(&w, PUSH);
    assert_eq!(m.gate().stats().update_calls, 0);
    assert!(m.records[&BLUE_ID].0.same_record(&w.blocks[0]));
    assert_eq!(m.known_blocks().collect::<Vec<_>>(), vec![BLUE_ID]);
}

#[test]
fn known_blocks_missing_from_a_world_are_not_updated() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    m.update(&world((0.0, 0.005), &blue(0.0, 0.26, 0.0)), PUSH);
    let before = m.block(BLUE_ID);
    m.update(&world((0.0, 0.01), &[]), PUSH);
    assert_eq!(m.block(BLUE_ID), before);
    assert_eq!(m.gate().stats().update_calls, 1);
}

#[test]
fn training_off_only_moves_the_states() {
    let mut m = GateModel::default();
    train(&mut m, &[0.0]);
    let stats = m.stats();
    m.set_training(false);
    assert!(!m.is_training());
    let run = synthetic_run(0.1, 60);
    m.reset_objects(&run[0]);
    for w in &run[1..] {
        m.update(w, PUSH);
    }
    assert_eq!(m.stats(), stats);
    let last = run[59].poses();
    assert_eq!(
        m.block(BLUE_ID).map(|b| b.s),
        last.blocks.get(&BLUE_ID).copied()
    );
    assert_eq!(m.actuator().map(|a| a.s), Some(last.actuator));
    m.set_training(true);
    assert!(m.is_training());
}

// ------------------------------------------------------------- reset_objects

#[test]
fn reset_objects_keeps_the_previous_runs_end_as_s_prev() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    m.update(&world((0.0, 0.005), &blue(0.0, 0.8, 0.0)), PUSH);
    // The next run starts: the world was reset.
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    assert_eq!(
        m.block(BLUE_ID),
        Some(tracked(BLUE_ID, st(0.0, 0.25, 0.0), st(0.0, 0.8, 0.0)))
    );
    // reset_objects never trains.
    assert_eq!(m.gate().stats().update_calls, 1);
    assert_eq!(m.actuator_model().stats().update_calls, 1);
    assert_eq!(
        m.actuator(),
        Some(tracked(ACTUATOR_ID, st(0.0, 0.0, 0.0), st(0.0, 0.005, 0.0)))
    );

    // The first sample of the new run carries the bogus displacement
    // (0, −0.55) in its closing feature.
    m.update(&world((0.0, 0.005), &blue(0.0, 0.255, 0.0)), PUSH);
    let stale = tracked(BLUE_ID, st(0.0, 0.25, 0.0), st(0.0, 0.8, 0.0));
    let act = tracked(ACTUATOR_ID, st(0.0, 0.005, 0.0), st(0.0, 0.0, 0.0));
    let want = relative_features(&stale, &act);
    assert_eq!(want[3], -0.555);
    let clean = relative_features(&TrackedObject::fresh(BLUE_ID, stale.s), &act);
    assert_eq!(clean[3], -0.005);
    // The predictor's second sample is always inserted.
    let nodes: Vec<_> = m.predictor(BLUE_ID).unwrap().forward().nodes().collect();
    assert_eq!(nodes.len(), 2);
    assert_eq!(nodes[1].w_in, want);
}

#[test]
fn reset_objects_adopts_new_blocks_and_initialises_the_actuator() {
    let mut m = GateModel::default();
    let w = world((0.2, 0.0), &blue(0.0, 0.25, 0.0));
    m.reset_objects(&w);
    assert!(m.records[&BLUE_ID].0.same_record(&w.blocks[0]));
    assert_eq!(
        m.actuator(),
        Some(TrackedObject::fresh(ACTUATOR_ID, st(0.2, 0.0, 0.0)))
    );
}

// ----------------------------------------------------------------- predict

#[test]
fn an_untrained_model_predicts_no_change() {
    let m = GateModel::default();
    let w = GateWorld::new(
        tracked(ACTUATOR_ID, st(0.1, 0.2, 0.0), st(0.1, 0.19, 0.0)),
        [tracked(BLUE_ID, st(0.0, 0.25, 0.0), st(0.0, 0.24, 0.0))],
    );
    let p = m.predict(&w, PUSH);
    // Actuator model without nodes: zero change, s_prev = the world's s.
    assert_eq!(
        p.actuator(),
        tracked(ACTUATOR_ID, st(0.1, 0.2, 0.0), st(0.1, 0.2, 0.0))
    );
    // Gate never trained: the block is carried over as the same record.
    assert!(p.shares_block(&w, BLUE_ID));
    assert_eq!(p.block(BLUE_ID), w.block(BLUE_ID));
}

#[test]
fn a_trained_actuator_model_predicts_the_rounded_step() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &[]));
    m.update(&world((0.0, 0.005), &[]), PUSH);
    m.update(&world((0.0, 0.01), &[]), PUSH);
    let w = GateWorld::new(
        tracked(ACTUATOR_ID, st(0.1, 0.1, 0.0), st(0.0, 0.0, 0.0)),
        [],
    );
    let p = m.predict(&w, PUSH);
    assert_eq!(
        p.actuator(),
        tracked(ACTUATOR_ID, st(0.1, 0.105, 0.0), st(0.1, 0.1, 0.0))
    );
}

#[test]
fn the_predictor_is_used_only_when_the_gate_opens() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.17), &blue(0.0, 0.25, 0.0)));
    m.predictors.insert(
        BLUE_ID,
        predictor_constant([0.0, 0.01, 0.1], InverseModel::new(m.config.aim())),
    );
    let w = world((0.0, 0.17), &blue(0.1, 0.25, FRAC_PI_2));

    // Gate never trained: no change even though a predictor exists.
    assert!(m.predict(&w, PUSH).shares_block(&w, BLUE_ID));
    // Gate says 0: no change.
    m.gate = gate_always(0);
    assert!(m.predict(&w, PUSH).shares_block(&w, BLUE_ID));
    // Gate says 1: a new record, s from the local change, s_prev = o.s.
    m.gate = gate_always(1);
    let p = m.predict(&w, PUSH);
    assert!(!p.shares_block(&w, BLUE_ID));
    let b = p.block(BLUE_ID).unwrap();
    // R(π/2)·(0, 0.01) = (−0.01, 0) after rounding; θ + 0.1 unrounded.
    assert_eq!(b.s, st(0.1 - 0.01, 0.25, FRAC_PI_2 + 0.1));
    assert_eq!(b.s_prev, st(0.1, 0.25, FRAC_PI_2));
}

#[test]
fn without_a_predictor_an_open_gate_changes_nothing() {
    let mut m = GateModel::new(GateConfig::hz100());
    m.gate = gate_always(1);
    let w = world((0.0, 0.17), &blue(0.0, 0.25, 0.0));
    let p = m.predict(&w, PUSH);
    assert!(p.shares_block(&w, BLUE_ID));
}

#[test]
fn the_gate_sees_the_predicted_actuator_and_the_current_block() {
    // Two blocks; the gate opens only for features whose actuator position
    // is the *predicted* one: train the actuator model, then check which φ
    // the gate was asked about by giving it exactly one label-1 node there.
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &[]));
    m.update(&world((0.0, 0.005), &[]), PUSH);
    m.update(&world((0.0, 0.01), &[]), PUSH);
    let w = GateWorld::new(
        tracked(ACTUATOR_ID, st(0.0, 0.17, 0.0), st(0.0, 0.165, 0.0)),
        [tracked(BLUE_ID, st(0.0, 0.25, 0.0), st(0.0, 0.245, 0.0))],
    );
    let a_hat = tracked(ACTUATOR_ID, st(0.0, 0.175, 0.0), st(0.0, 0.17, 0.0));
    let o = w.block(BLUE_ID).unwrap();
    let asked = relative_features(&o, &a_hat);
    let mut gate = Aitm::new(AitmConfig::classifier(), 8, 1);
    gate.update_label(&asked, 1);
    // A label-0 node at the features of the unmoved actuator.
    gate.update_label(&relative_features(&o, &w.actuator()), 0);
    m.gate = gate;
    m.predictors.insert(
        BLUE_ID,
        predictor_constant([0.0, 0.005, 0.0], InverseModel::new(m.config.aim())),
    );
    let p = m.predict(&w, PUSH);
    assert_eq!(p.actuator(), a_hat);
    assert_eq!(p.block(BLUE_ID).map(|b| b.s), Some(st(0.0, 0.255, 0.0)));
}

#[test]
fn an_unchanged_predicted_block_keeps_its_own_s_prev() {
    let mut m = GateModel::new(GateConfig::hz100());
    m.gate = gate_always(0);
    let w = GateWorld::new(
        tracked(ACTUATOR_ID, st(0.0, 0.0, 0.0), st(0.0, 0.0, 0.0)),
        [tracked(BLUE_ID, st(0.0, 0.3, 0.0), st(0.0, 0.295, 0.0))],
    );
    let p1 = m.predict(&w, PUSH);
    let p2 = m.predict(&p1, PUSH);
    for p in [&p1, &p2] {
        assert_eq!(
            p.block(BLUE_ID),
            Some(tracked(BLUE_ID, st(0.0, 0.3, 0.0), st(0.0, 0.295, 0.0)))
        );
    }
    // So the displacement persists into the next step's features.
    let b = p2.block(BLUE_ID).unwrap();
    assert_eq!(b.velocity(), Vector2::new(0.0, 0.3 - 0.295));
}

#[test]
fn prediction_boost_scales_the_predicted_change() {
    let config = GateParams {
        prediction_boost: 1.5,
        ..GateParams::hz100()
    }
    .check()
    .unwrap();
    let mut m = GateModel::new(config);
    m.gate = gate_always(1);
    m.predictors.insert(
        BLUE_ID,
        predictor_constant([0.0, 0.004, 0.1], InverseModel::new(m.config.aim())),
    );
    let w = world((0.0, 0.17), &blue(0.0, 0.25, 0.0));
    let b = m.predict(&w, PUSH).block(BLUE_ID).unwrap();
    assert_eq!((b.s.x, b.s.y), (0.0, 0.25 + 0.006));
    assert!((b.s.theta - 0.15).abs() < 1e-15);
}

#[test]
fn predict_does_not_change_the_model() {
    let mut m = GateModel::default();
    train(&mut m, &[0.0, 0.1]);
    let before = serde_json::to_string(&m).unwrap();
    let run = synthetic_run(-0.1, 80);
    let mut p = run[0].clone();
    for _ in 0..80 {
        p = m.predict(&p, PUSH);
    }
    assert_eq!(serde_json::to_string(&m).unwrap(), before);
}

// ------------------------------------------------------------ §4.1 records

#[test]
fn a_chain_started_at_the_adopting_message_follows_the_real_block() {
    // The constant-feedback pattern (docs/spec/experiments.md §3.4) on a fresh model.
    let mut m = GateModel::default();
    let w1 = world((0.0, 0.17), &blue(0.0, 0.25, 0.0));
    let p1 = m.predict(&w1, PUSH);
    m.reset_objects(&w1);
    m.update(&w1, Action::ZERO);
    assert!(p1.shares_block(&w1, BLUE_ID));

    let w2 = world((0.0, 0.175), &blue(0.0, 0.26, 0.0));
    let p2 = m.predict(&p1, PUSH);
    m.update(&w2, PUSH);
    // The "prediction" shows the real block of the latest update.
    assert_eq!(
        p2.block(BLUE_ID),
        Some(tracked(BLUE_ID, st(0.0, 0.26, 0.0), st(0.0, 0.25, 0.0)))
    );
    assert_eq!(GateModel::poses(&p2).blocks[&BLUE_ID], st(0.0, 0.26, 0.0));
    assert_eq!(GateModel::poses(&p1).blocks[&BLUE_ID], st(0.0, 0.26, 0.0));
    assert!(p2.shares_block(&w1, BLUE_ID));

    // Reading the live record: the predicted change starts from the model's
    // current s, with its s_prev in the features.
    m.gate = gate_always(1);
    let p3 = m.predict(&p2, PUSH);
    assert!(!p3.shares_block(&p2, BLUE_ID));
    let b3 = p3.block(BLUE_ID).unwrap();
    assert_eq!(b3.s_prev, st(0.0, 0.26, 0.0));
    // From here on the chain is independent of the model's record.
    m.update(&world((0.0, 0.18), &blue(0.0, 0.3, 0.0)), PUSH);
    assert_eq!(p3.block(BLUE_ID), Some(b3));
    assert_eq!(p2.block(BLUE_ID).map(|b| b.s), Some(st(0.0, 0.3, 0.0)));
}

#[test]
fn a_chain_from_a_known_block_is_independent_of_the_model() {
    // The push-task test pattern (docs/spec/experiments.md §2 test_step): the block is
    // known, so reset_objects does not adopt the world's block.
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    m.set_training(false);
    let w = world((0.0, 0.0), &blue(0.0, 0.25, 0.0));
    m.reset_objects(&w);
    m.update(&w, PUSH);
    let p = m.predict(&w, PUSH);
    assert!(p.shares_block(&w, BLUE_ID));
    assert!(!m.records[&BLUE_ID].0.same_record(&w.blocks[0]));
    m.update(&world((0.0, 0.005), &blue(0.0, 0.3, 0.0)), PUSH);
    assert_eq!(p.block(BLUE_ID).map(|b| b.s), Some(st(0.0, 0.25, 0.0)));
}

#[test]
fn updating_with_the_models_own_record_moves_nothing() {
    // update(P) with P's block being the record: s_prev := s, no change.
    let mut m = GateModel::default();
    let w = world((0.0, 0.0), &blue(0.0, 0.25, 0.0));
    m.reset_objects(&w);
    m.update(&world((0.0, 0.005), &blue(0.0, 0.26, 0.0)), PUSH);
    // w's block is the record, now at 0.26 with s_prev 0.25.
    m.update(&w, PUSH);
    assert_eq!(
        m.block(BLUE_ID),
        Some(tracked(BLUE_ID, st(0.0, 0.26, 0.0), st(0.0, 0.26, 0.0)))
    );
    // The second gate sample: unchanged.
    let labels: Vec<f64> = m.gate().nodes().map(|n| n.w_out[0]).collect();
    assert_eq!(labels, vec![1.0, 0.0]);
}

#[test]
fn a_cloned_model_has_its_own_records() {
    let mut m = GateModel::default();
    let w = world((0.0, 0.0), &blue(0.0, 0.25, 0.0));
    m.reset_objects(&w);
    let copy = m.clone();
    m.update(&world((0.0, 0.005), &blue(0.0, 0.3, 0.0)), PUSH);
    assert_eq!(copy.block(BLUE_ID).map(|b| b.s), Some(st(0.0, 0.25, 0.0)));
    assert!(!copy.records[&BLUE_ID].0.same_record(&w.blocks[0]));
    assert_eq!(m.block(BLUE_ID).map(|b| b.s), Some(st(0.0, 0.3, 0.0)));
}

// ----------------------------------------------------------- §5 variants

#[test]
fn hard_coded_gate_rule() {
    let phi = |distance: f64, closing: f64, vx: f64, vy: f64| {
        [15.0, 8.0, distance, closing, 0.0, -0.1, vx, vy]
    };
    // Contact within the step: closing ≤ −distance (equality included).
    assert!(hard_coded_gate(&phi(0.005, -0.005, 0.0, 0.005)));
    assert!(hard_coded_gate(&phi(-0.001, 0.0, 0.0, 0.005)));
    assert!(!hard_coded_gate(&phi(0.006, -0.005, 0.0, 0.005)));
    // Resting contact: no closing, (almost) no own motion, close.
    assert!(hard_coded_gate(&phi(0.04, 0.0, 0.0, 0.0009)));
    assert!(!hard_coded_gate(&phi(0.04, 0.0, 0.0, 0.001)));
    assert!(!hard_coded_gate(&phi(0.05, 0.0, 0.0, 0.0)));
    assert!(!hard_coded_gate(&phi(0.04, 0.001, 0.0, 0.0)));
}

#[test]
fn hard_coded_variants_replace_and_do_not_train_their_maps() {
    let params = GateParams {
        hard_coded_actuator: true,
        hard_coded_gate: true,
        ..GateParams::hz100()
    };
    let mut m = GateModel::new(params.check().unwrap());
    train(&mut m, &[0.0]);
    let s = gate_stats(&m);
    assert_eq!(s.actuator.update_calls, 0);
    assert_eq!(s.gate.update_calls, 0);
    assert!(s.predictors[&15].update_calls > 0);
    assert!(s.hard_coded_actuator && s.hard_coded_gate);
    let labels = &serde_json::to_value(m.stats()).unwrap()["labels"];
    assert_eq!(labels["actuator"], HARD_CODED_LABEL);
    assert_eq!(labels["gate"], HARD_CODED_LABEL);

    // Actuator: r3(s + 0.01·a).
    let w = world((0.1, 0.1234), &blue(0.0, 0.25, 0.0));
    let p = m.predict(&w, Action::new(0.3, -0.25));
    assert_eq!(p.actuator().s, st(0.103, r3(0.1234 - 0.0025), 0.0));
    // Gate: the actuator touching the block opens it without any training.
    let touching = world((0.0, 0.177), &blue(0.0, 0.25, 0.0));
    assert!(!m.predict(&touching, PUSH).shares_block(&touching, BLUE_ID));
    let far = world((0.0, 0.0), &blue(0.0, 0.25, 0.0));
    assert!(m.predict(&far, PUSH).shares_block(&far, BLUE_ID));
}

// ------------------------------------------------------------------- misc

#[test]
fn stats_count_updates_inserts_and_nodes_per_map() {
    let mut m = GateModel::default();
    train(&mut m, &[0.0, 0.1]);
    let s = gate_stats(&m);
    // 149 updates per run, one known block.
    assert_eq!(s.actuator.update_calls, 298);
    assert_eq!(s.gate.update_calls, 298);
    // The actuator model sees one input only: its first two nodes (§8).
    assert_eq!(s.actuator.nodes, 2);
    let changed = s.predictors[&15].update_calls;
    assert!(changed > 100 && changed < 298, "{changed}");
    assert_eq!(
        s.predictors[&15].nodes,
        m.predictor(BLUE_ID).unwrap().forward().len()
    );
    assert!(!s.hard_coded_actuator && !s.hard_coded_gate);
    assert_eq!(s.predictors.len(), 1);
    let wire = serde_json::to_value(m.stats()).unwrap();
    assert!(wire["labels"].as_object().unwrap().is_empty());
    assert_eq!(wire["maps"].as_object().unwrap().len(), 3);
}

fn gate_stats(m: &GateModel) -> GateStats {
    m.stats()
        .as_gate()
        .cloned()
        .expect("the gate model reports GateStats")
}

#[test]
fn parse_forces_the_actuator_yaw_to_zero_and_starts_fresh() {
    let m = GateModel::default();
    let obs = |name: &str, id, x, y, yaw: f64| Observation {
        name: name.into(),
        id,
        position: [x, y, 0.03],
        orientation: crate::features::yaw_to_quaternion(yaw),
        shape: None,
    };
    let frame = Frame {
        objects: vec![
            obs("actuator", 8, 0.0004, 0.1, 0.7),
            obs("blockA", 15, 0.0, 0.25, 0.3),
        ],
    };
    let w = m.parse(&frame).unwrap();
    assert_eq!(w.actuator(), TrackedObject::fresh(8, st(0.0, 0.1, 0.0)));
    assert_eq!(
        w.block(BLUE_ID),
        Some(TrackedObject::fresh(15, st(0.0, 0.25, 0.3)))
    );
    assert!(m.parse(&Frame::default()).is_err());
}

#[test]
fn the_model_learns_a_synthetic_push() {
    // As with the fixed training runs (docs/spec/reference-results.md §5.1): after
    // pushes left, right and in the centre, a central push is predicted over
    // 150 chained steps. The gate's boundary on this perfectly regular data
    // is decided by exact distance ties, so the onset may be a few messages
    // early (4 here: 0.02 m); without the gate, predictor or chaining the
    // error would be the whole 0.575 m push.
    let mut m = GateModel::default();
    train(&mut m, &[-0.1, 0.1, 0.0]);
    m.set_training(false);
    let run = synthetic_run(0.0, 151);
    m.reset_objects(&run[0]);
    let mut p = run[0].clone();
    for _ in 0..150 {
        m.update(&p, PUSH);
        p = m.predict(&p, PUSH);
    }
    let (want, got) = (run[150].poses(), GateModel::poses(&p));
    assert!((want.actuator.y - got.actuator.y).abs() < 1e-9);
    let (b, bh) = (want.blocks[&BLUE_ID], got.blocks[&BLUE_ID]);
    assert!((b.y - bh.y).abs() < 0.03, "{b:?} vs {bh:?}");
    assert!((b.theta - bh.theta).abs() < 0.01, "{b:?} vs {bh:?}");
    assert!(b.x.abs() < 1e-9 && bh.x.abs() < 1e-9);
}

// ------------------------------------------------------------------ serde

#[test]
fn a_restored_model_predicts_and_plans_bit_identically() {
    let mut m = GateModel::default();
    train(&mut m, &[0.0, -0.12, 0.07, 0.2]);
    m.set_target(Some(Target::new(BLUE_ID, st(0.3, 0.9, 0.4))))
        .unwrap();
    let json = serde_json::to_string(&m).unwrap();
    let mut back: GateModel = serde_json::from_str(&json).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), json);
    assert_eq!(back.stats(), m.stats());
    assert_eq!(back.target(), m.target());
    assert_eq!(back.is_training(), m.is_training());

    for x0 in [-0.2, -0.03, 0.0, 0.11] {
        let run = synthetic_run(x0, 120);
        let (mut p, mut q) = (run[0].clone(), run[0].clone());
        for _ in 0..120 {
            p = m.predict(&p, PUSH);
            q = back.predict(&q, PUSH);
            assert_eq!(bits(&p.poses()), bits(&q.poses()));
            for (a, b) in p.blocks().zip(q.blocks()) {
                assert_eq!(tracked_bits(&a), tracked_bits(&b));
            }
        }
    }
    // Planning state (the AIM's keys) survives too.
    let (mut r1, mut r2) = (SplitMix(7), SplitMix(7));
    for _ in 0..5 {
        let (a, b) = (m.act(&mut r1), back.act(&mut r2));
        assert_eq!(
            (a.vx.to_bits(), a.vy.to_bits()),
            (b.vx.to_bits(), b.vy.to_bits())
        );
    }
    // And learning continues identically.
    train(&mut m, &[0.15]);
    train(&mut back, &[0.15]);
    assert_eq!(
        serde_json::to_string(&back).unwrap(),
        serde_json::to_string(&m).unwrap()
    );
}

#[test]
fn inconsistent_snapshots_are_rejected() {
    let mut m = GateModel::default();
    train(&mut m, &[0.0]);
    m.set_target(Some(Target::new(BLUE_ID, st(0.3, 0.9, 0.4))))
        .unwrap();
    let json = serde_json::to_string(&m).unwrap();
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let broken = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = value.clone();
        edit(&mut v);
        serde_json::from_value::<GateModel>(v)
    };
    assert!(broken(&|_| ()).is_ok());
    // A record filed under another id.
    assert!(broken(&|v| v["records"]["15"]["id"] = 27.into()).is_err());
    // Blocks but no actuator.
    assert!(broken(&|v| v["actuator"] = serde_json::Value::Null).is_err());
    // A target for an unknown block.
    assert!(broken(&|v| v["target"]["id"] = 27.into()).is_err());
    // Maps of the wrong shape.
    assert!(broken(&|v| v["gate"] = v["actuator_model"].clone()).is_err());
    assert!(broken(&|v| v["actuator_model"] = v["gate"].clone()).is_err());
    assert!(broken(&|v| v["predictors"]["15"]["forward"] = v["gate"].clone()).is_err());
    // An invalid configuration.
    assert!(broken(&|v| v["config"]["prediction_boost"] = (-1.0).into()).is_err());
}

// ----------------------------------------------------------------- targets

#[test]
fn set_target_accepts_known_blocks_only() {
    let mut m = GateModel::default();
    let t = Target::new(BLUE_ID, st(0.6, 0.7, -2.1));
    assert_eq!(
        m.set_target(Some(t)),
        Err(TargetError::UnknownObject { id: BLUE_ID })
    );
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    assert_eq!(m.set_target(Some(t)), Ok(()));
    assert!(m.has_target());
    assert_eq!(
        m.set_target(Some(Target::new(ACTUATOR_ID, st(0.0, 0.0, 0.0)))),
        Err(TargetError::Actuator)
    );
    assert_eq!(
        m.set_target(Some(Target::new(RED_ID, st(0.0, 0.0, 0.0)))),
        Err(TargetError::UnknownObject { id: RED_ID })
    );
    assert!(matches!(
        m.set_target(Some(Target::new(BLUE_ID, st(f64::NAN, 0.0, 0.0)))),
        Err(TargetError::NonFinite { .. })
    ));
    // Refusals keep the previous target.
    assert_eq!(m.target(), Some(t));
    assert_eq!(m.set_target(None), Ok(()));
    assert!(!m.has_target());
}

// ----------------------------------------------------------------- planner

/// SplitMix64 with a draw counter: a deterministic generator independent of
/// rand's algorithms.
#[derive(Clone)]
struct SplitMix {
    state: u64,
    draws: u64,
}

#[allow(non_snake_case)]
fn SplitMix(seed: u64) -> SplitMix {
    SplitMix {
        state: seed,
        draws: 0,
    }
}

impl rand::TryRng for SplitMix {
    type Error = std::convert::Infallible;
    fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
        self.try_next_u64().map(|v| (v >> 32) as u32)
    }
    fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
        self.draws += 1;
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        Ok(z ^ (z >> 31))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
        for chunk in dst.chunks_mut(8) {
            let v = self.try_next_u64()?.to_le_bytes();
            chunk.copy_from_slice(&v[..chunk.len()]);
        }
        Ok(())
    }
}

/// A block at (0, 0.25, 0) and a target straight above it; the AIM knows one
/// precondition for "+y": the actuator 0.08 m below the centre moving 5 mm
/// per step. Gate and predictor as given; actuator at `act`.
fn planning_model(act: (f64, f64), gate: Aitm, change: [f64; 3]) -> GateModel {
    let mut m = GateModel::default();
    m.reset_objects(&world(act, &blue(0.0, 0.25, 0.0)));
    let mut inverse = InverseModel::new(m.config.aim());
    inverse.train(&PRE, &[0.0, 0.005, 0.0]);
    m.predictors
        .insert(BLUE_ID, predictor_constant(change, inverse));
    m.gate = gate;
    m.set_target(Some(Target::new(BLUE_ID, st(0.0, 0.5, 0.0))))
        .unwrap();
    m
}

const PRE: [f64; 8] = [15.0, 8.0, 0.005, -0.005, 0.0, -0.08, 0.0, 0.005];

fn assert_action(got: Action, want: (f64, f64)) {
    assert!(
        (got.vx - want.0).abs() < 1e-12 && (got.vy - want.1).abs() < 1e-12,
        "got {got:?}, want {want:?}"
    );
}

#[test]
fn no_target_no_action_no_draws() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.0, 0.0), &blue(0.0, 0.25, 0.0)));
    let mut rng = SplitMix(1);
    assert_eq!(m.act(&mut rng), Action::ZERO);
    assert_eq!(rng.draws, 0);
}

#[test]
fn reaching_the_target_clears_it() {
    let mut m = planning_model((0.0, 0.0), gate_always(0), [0.0; 3]);
    // 0.0099 away: reached.
    m.set_target(Some(Target::new(BLUE_ID, st(0.0, 0.2599, 0.0))))
        .unwrap();
    let mut rng = SplitMix(1);
    assert_eq!(m.act(&mut rng), Action::ZERO);
    assert!(!m.has_target());
    assert_eq!(m.act(&mut rng), Action::ZERO);
    // Exactly 0.01 away (strict test) or an unwrapped 2π away: not reached.
    for goal in [st(0.0, 0.26, 0.0), st(0.0, 0.25, 2.0 * PI)] {
        let mut m = planning_model((0.0, 0.0), gate_always(0), [0.0; 3]);
        m.set_target(Some(Target::new(BLUE_ID, goal))).unwrap();
        m.act(&mut rng);
        assert!(m.has_target(), "{goal:?}");
    }
}

#[test]
fn exploration_without_an_inverse_model_draws_twice_x_first() {
    let mut m = GateModel::default();
    m.reset_objects(&world((0.3, -0.1), &blue(0.0, 0.25, 0.0)));
    m.set_target(Some(Target::new(BLUE_ID, st(0.0, 0.5, 0.0))))
        .unwrap();
    let start = SplitMix(42);
    let mut rng = start.clone();
    let got = m.act(&mut rng);
    assert_eq!(rng.draws, 2);
    let mut expect = start.clone();
    let (xi1, xi2) = (expect.random::<f64>() - 0.5, expect.random::<f64>() - 0.5);
    assert_eq!(rng.state, expect.state);
    let u = Vector2::new((0.0 - 0.3) + xi1, (0.25 - -0.1) + xi2);
    let n = (u.x * u.x + u.y * u.y).sqrt();
    assert_eq!(got, Action::new((0.3 * u.x) / n, (0.3 * u.y) / n));
    // The draws are x then y: swapping them gives another action.
    let swapped = Vector2::new(-0.3 + xi2, 0.35 + xi1);
    assert_ne!(got.vx, (0.3 * swapped.x) / swapped.norm());
}

#[test]
fn exploration_of_a_zero_vector_returns_it() {
    // The noise cancels the offset exactly: u = 0 is returned as it is.
    let mut probe = SplitMix(9);
    let (xi1, xi2) = (probe.random::<f64>() - 0.5, probe.random::<f64>() - 0.5);
    let a = exploration(Vector2::new(-xi1, -xi2), &mut SplitMix(9));
    assert_eq!(a, Action::ZERO);
}

#[test]
fn exploration_when_the_inverse_model_has_no_matching_prototype() {
    // Only "+y" is known; a target below needs "−y" and the angle key (0, +)
    // of a zero component has no prototype either.
    let mut m = planning_model((0.0, 0.0), gate_always(0), [0.0; 3]);
    m.set_target(Some(Target::new(BLUE_ID, st(0.0, -0.5, 0.0))))
        .unwrap();
    let start = SplitMix(3);
    let mut rng = start.clone();
    m.act(&mut rng);
    assert_eq!(rng.draws, 2);
}

#[test]
fn far_from_the_precondition_the_actuator_circles() {
    // p* = (0, 0.17); the actuator at (0.3, 0) is 0.34 away and 0.18 from
    // the block: move towards the block at 0.4 m/s, no draws.
    let mut m = planning_model((0.3, 0.0), gate_always(0), [0.0; 3]);
    let mut rng = SplitMix(5);
    let a = m.act(&mut rng);
    let r = Vector2::new(0.3, -0.25);
    let n = r.norm();
    assert_action(a, (-0.4 * r.x / n, -0.4 * r.y / n));
    assert_eq!(rng.draws, 0);
}

#[test]
fn approach_moves_straight_when_the_gate_predicts_no_contact() {
    // 0.05 below p*: |δ| between 0.01 and 0.1.
    let mut m = planning_model((0.0, 0.12), gate_always(0), [0.0, -0.005, 0.0]);
    assert_action(m.act(&mut SplitMix(0)), (0.0, 0.3));
}

#[test]
fn approach_moves_straight_when_the_predicted_contact_helps() {
    let mut m = planning_model((0.0, 0.12), gate_always(1), [0.0, 0.005, 0.0]);
    assert_action(m.act(&mut SplitMix(0)), (0.0, 0.3));
    // Equal distance (no predicted change) is not "farther" either.
    let mut m = planning_model((0.0, 0.12), gate_always(1), [0.0, 0.0, 0.0]);
    assert_action(m.act(&mut SplitMix(0)), (0.0, 0.3));
}

#[test]
fn approach_circles_when_the_predicted_contact_would_hurt() {
    // The block would move away from the target: circle instead. The
    // actuator is 0.055 from the block (tangential band) exactly below it,
    // at the angle of q: Δ = 0, so the clockwise tangent.
    let mut m = planning_model((0.0, 0.12), gate_always(1), [0.0, -0.005, 0.0]);
    assert_action(m.act(&mut SplitMix(0)), (-0.4, 0.0));
}

#[test]
fn at_the_precondition_the_motion_is_scaled_or_passed_through() {
    // |δ| ≤ 0.01: perform v* = R(θ)·P[6:8].
    let cases = [
        (0.005, (0.0, 0.3)),   // 100 Hz displacement: scaled to 0.3 m/s
        (0.01, (0.0, 0.3)),    // band is strict at 0.01
        (0.05, (0.0, 0.05)),   // 10 Hz displacement: passed through
        (0.199, (0.0, 0.199)), // inside the band
        (0.2, (0.0, 0.3)),     // band is strict at 0.2
        (0.0, (0.0, 0.0)),     // zero passes through
        (-0.3, (0.0, -0.3)),   // larger: scaled
    ];
    for (vy, want) in cases {
        let mut m = planning_model((0.0, 0.175), gate_always(0), [0.0; 3]);
        let mut inverse = InverseModel::new(m.config.aim());
        let mut pre = PRE;
        pre[7] = vy;
        inverse.train(&pre, &[0.0, 0.005, 0.0]);
        m.predictors.get_mut(&BLUE_ID).unwrap().inverse = inverse;
        assert_action(m.act(&mut SplitMix(0)), want);
    }
}

#[test]
fn the_precondition_is_placed_in_the_blocks_frame() {
    // Block turned by π/2 at (0.2, 0.3): q = (0, −0.08) is at (0.28, 0.3)
    // globally and P[6:8] = (0, 0.05) becomes (−0.05, 0) (passed through).
    let mut m = GateModel::default();
    m.reset_objects(&world((0.28, 0.305), &blue(0.2, 0.3, FRAC_PI_2)));
    let mut inverse = InverseModel::new(m.config.aim());
    let mut pre = PRE;
    pre[7] = 0.05;
    inverse.train(&pre, &[0.0, 0.005, 0.0]);
    m.predictors
        .insert(BLUE_ID, predictor_constant([0.0; 3], inverse));
    // Local +y of the turned block is global −x.
    m.set_target(Some(Target::new(BLUE_ID, st(-0.2, 0.3, FRAC_PI_2))))
        .unwrap();
    assert_action(m.act(&mut SplitMix(0)), (-0.05, 0.0));
}

#[test]
fn circling_keeps_the_distance_band() {
    let r = Vector2::new(0.3, 0.4);
    let q = Vector2::new(1.0, 0.0);
    assert_action(circle(0.039, r, 0.0, q), (0.4 * 0.6, 0.4 * 0.8));
    assert_action(circle(0.061, r, 0.0, q), (-0.4 * 0.6, -0.4 * 0.8));
    // 0.04 and 0.06 themselves are in the tangential band.
    for dist in [0.04, 0.06] {
        let a = circle(dist, r, 0.0, Vector2::new(0.0, 1.0));
        assert_action(a, (-0.4 * 0.8, 0.4 * 0.6));
    }
}

#[test]
fn circling_turns_the_shorter_way() {
    let r = Vector2::new(0.0, -0.1); // actuator below the block
    let ccw = (0.4, 0.0); // counter-clockwise tangent (−r_y, r_x) at 0.4 m/s
    let cw = (-0.4, 0.0);
    let at = |alpha_act: f64, qx: f64, qy: f64| circle(0.05, r, alpha_act, Vector2::new(qx, qy));
    // Δ > 0 and < π: counter-clockwise.
    assert_action(at(-FRAC_PI_2, 1.0, 0.0), ccw);
    // Δ > 0 and ≥ π: clockwise (the other way is shorter).
    assert_action(at(-FRAC_PI_2 - 0.1, 0.0, 1.0), cw);
    // Δ < 0 and |Δ| < π: clockwise.
    assert_action(at(-FRAC_PI_2, -1.0, 0.0), cw);
    // Δ < 0 and |Δ| ≥ π: counter-clockwise.
    assert_action(at(FRAC_PI_2 + 0.1, 0.0, -1.0), ccw);
    // Δ = 0 exactly: clockwise.
    assert_action(at(-FRAC_PI_2, 0.0, -0.08), cw);
    assert_action(at(0.0, 1.0, 0.0), cw);
}

#[test]
fn circling_on_the_blocks_centre_does_not_produce_nan() {
    let a = circle(-0.07, Vector2::zeros(), 0.0, Vector2::new(1.0, 0.0));
    assert_eq!(a, Action::ZERO);
}

// ------------------------------------------------- the thesis draft's variants

/// A model trained on two synthetic pushes under `params`.
fn trained_with(params: GateParams) -> GateModel {
    let mut m = GateModel::new(params.check().unwrap());
    train(&mut m, &[0.0, 0.1]);
    m
}

#[test]
fn velocity_features_extend_the_block_predictor_input() {
    let dims = |v: VelocityFeatures| {
        let m = trained_with(GateParams {
            velocity_features: v,
            ..GateParams::hz100()
        });
        let f = m.predictor(BLUE_ID).unwrap().forward();
        // The gate and the inverse model keep φ alone.
        assert_eq!(m.gate().input_dim(), 8);
        (
            f.input_dim(),
            f.nodes().map(|n| n.w_in.to_vec()).collect::<Vec<_>>(),
        )
    };
    let (n0, plain) = dims(VelocityFeatures::None);
    let (n2, linear) = dims(VelocityFeatures::Linear);
    let (n3, full) = dims(VelocityFeatures::LinearAngular);
    assert_eq!((n0, n2, n3), (8, 10, 11));
    // The synthetic block moves 5 mm per message once pushed: some stored
    // input carries that velocity in its block frame, and the turning push
    // (x0 = 0.1 turns the block by −0.002 per message) its yaw change.
    assert!(linear.iter().any(|w| w[9] == 0.005), "{linear:?}");
    assert!(full.iter().any(|w| w[10] == -0.002));
    assert!(plain.iter().all(|w| w.len() == 8));
    // GateParams from configuration number 1 selects all three.
    assert_eq!(
        GateParams::from_config_number(1).unwrap().velocity_features,
        VelocityFeatures::LinearAngular
    );
}

#[test]
fn a_velocity_model_round_trips_and_rejects_the_wrong_dimension() {
    let m = trained_with(GateParams {
        velocity_features: VelocityFeatures::Linear,
        ..GateParams::hz100()
    });
    let json = serde_json::to_value(&m).unwrap();
    let back: GateModel = serde_json::from_value(json.clone()).unwrap();
    assert_eq!(
        serde_json::to_string(&back).unwrap(),
        serde_json::to_string(&m).unwrap()
    );
    let mut v = json;
    v["config"]["velocity_features"] = serde_json::json!("none");
    let err = serde_json::from_value::<GateModel>(v).unwrap_err();
    assert!(err.to_string().contains("predictor dimensions"), "{err}");
}

#[test]
fn a_learning_rate_moves_the_forward_models_nodes() {
    let nodes = |eta: f64| {
        let m = trained_with(GateParams {
            forward_learning_rate: eta,
            ..GateParams::hz100()
        });
        let f = m.predictor(BLUE_ID).unwrap().forward();
        assert_eq!(f.config().params().eta_out, eta);
        f.nodes()
            .map(|n| (n.w_in.to_vec(), n.w_out.to_vec()))
            .collect::<Vec<_>>()
    };
    let still = nodes(0.0);
    let moved = nodes(0.2);
    assert_ne!(still, moved);
    // With η = 0 every stored input is one the model was shown: rounded.
    assert!(still.iter().all(|(w, _)| w.iter().all(|&v| v == r3(v))));
}

// ------------------------------------------------- beyond the thesis (gate+)

fn improved(on: Improvements) -> GateModel {
    GateModel::new(
        GateParams {
            improvements: on,
            ..GateParams::hz100()
        }
        .check()
        .unwrap(),
    )
}

fn frame_at(actuator: (f64, f64), block: (f64, f64)) -> Frame {
    let obs = |name: &str, id, (x, y): (f64, f64)| Observation {
        name: name.to_owned(),
        id,
        position: [x, y, 0.03],
        orientation: [0.0, 0.0, 0.0, 1.0],
        shape: None,
    };
    Frame {
        objects: vec![
            obs("actuator", ACTUATOR_ID, actuator),
            obs("blockA", BLUE_ID, block),
        ],
    }
}

#[test]
fn without_improvements_the_model_is_the_thesiss_bit_for_bit() {
    assert_eq!(GateParams::hz100().improvements, Improvements::default());
    assert!(!Improvements::default().any() && Improvements::ALL.any());
    let (mut faithful, mut default) = (GateModel::default(), improved(Improvements::default()));
    train(&mut faithful, &[0.0, -0.12, 0.07]);
    train(&mut default, &[0.0, -0.12, 0.07]);
    assert_eq!(
        serde_json::to_string(&faithful).unwrap(),
        serde_json::to_string(&default).unwrap()
    );
}

#[test]
fn an_older_model_file_without_improvements_still_loads_as_the_faithful_model() {
    let json = serde_json::to_string(&GateModel::default()).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let removed = value
        .pointer_mut("/config")
        .and_then(|c| c.as_object_mut())
        .and_then(|c| c.remove("improvements"));
    assert!(removed.is_some(), "the improvements are serialised: {json}");
    let back: GateModel = serde_json::from_value(value).unwrap();
    assert_eq!(back.config(), &GateConfig::hz100());
}

#[test]
fn unrounded_keeps_every_bit_of_the_world_and_of_the_features() {
    let frame = frame_at((0.123_456, -0.000_4), (0.0, 0.25));
    let rounded = GateModel::default().parse(&frame).unwrap();
    assert_eq!(rounded.actuator.s.x, 0.123);
    let on = Improvements {
        unrounded: true,
        ..Improvements::default()
    };
    let full = improved(on).parse(&frame).unwrap();
    assert_eq!(full.actuator.s.x, 0.123_456);
    assert_eq!(full.actuator.s.y, -0.000_4);
    let m = improved(on);
    let phi = m.phi(&full.blocks[0].get(), &full.actuator);
    // rel_x of the actuator in the block's frame, unrounded.
    assert!((phi[4] - 0.123_456).abs() < 1e-12, "{phi:?}");
}

#[test]
fn unrounded_does_not_take_sub_millimetre_jitter_for_a_push() {
    let on = Improvements {
        unrounded: true,
        ..Improvements::default()
    };
    let mut m = improved(on);
    m.reset_objects(&world((0.0, -0.3), &blue(0.0, 0.25, 0.0)));
    // The block creeps 0.2 mm: below UNROUNDED_EPS_CHANGE, no predictor.
    m.update(&world((0.0, -0.295), &blue(0.000_2, 0.25, 0.0)), PUSH);
    assert!(m.predictor(BLUE_ID).is_none());
    const { assert!(0.000_2 < UNROUNDED_EPS_CHANGE) };
    // A 2 mm push is a change.
    m.update(&world((0.0, -0.29), &blue(0.000_2, 0.252, 0.0)), PUSH);
    assert!(m.predictor(BLUE_ID).is_some());
}

#[test]
fn shared_blocks_carry_what_was_learned_on_one_block_to_another() {
    let shared = Improvements {
        shared_blocks: true,
        ..Improvements::default()
    };
    let delta = [0.0, 0.005, 0.001];
    let scene = world((0.0, 0.12), &[(RED_ID, st(0.0, 0.25, 0.0))]);
    for (on, moves) in [(Improvements::default(), false), (shared, true)] {
        let mut m = improved(on);
        m.reset_objects(&world((0.0, 0.1), &[(BLUE_ID, st(0.0, 0.25, 0.0))]));
        m.gate = gate_always(1);
        // As the model would have learned it: φ without ids when shared.
        let mut forward = Aitm::new(AitmConfig::regressor(QueryMode::BestTwo), 8, 3);
        let ids = if moves { [0.0, 0.0] } else { [15.0, 8.0] };
        for rel_y in [-0.1, -0.2] {
            forward.update(&[ids[0], ids[1], 0.0, 0.0, 0.0, rel_y, 0.0, 0.0], &delta);
        }
        let inverse = InverseModel::new(m.config().aim());
        m.predictors.insert(BLUE_ID, Predictor { forward, inverse });
        let p = m.predict(&scene, PUSH);
        let red = p.block(RED_ID).map(|b| b.s);
        if moves {
            // Only blue was ever learned; red moves as blue did.
            assert_eq!(red, Some(st(0.0, 0.255, 0.001)), "{on:?}");
            assert!(m.predictor(RED_ID).is_some());
        } else {
            assert_eq!(red, Some(st(0.0, 0.25, 0.0)), "{on:?}");
            assert!(m.predictor(RED_ID).is_none());
        }
    }
}

#[test]
fn a_shared_model_with_two_block_predictors_is_refused() {
    let mut m = improved(Improvements {
        shared_blocks: true,
        ..Improvements::default()
    });
    train(&mut m, &[0.0]);
    let aim = InverseModel::new(m.config().aim());
    m.predictors
        .insert(RED_ID, predictor_constant([0.0; 3], aim));
    let json = serde_json::to_string(&m).unwrap();
    assert!(serde_json::from_str::<GateModel>(&json).is_err());
}

#[test]
fn adapt_actuator_predicts_the_usual_step_after_a_latency_shortened_first_one() {
    let on = Improvements {
        adapt_actuator: true,
        ..Improvements::default()
    };
    let mut steps = vec![0.002];
    steps.extend([0.005; 60]);
    let predicted = |mut m: GateModel| {
        let mut y = 0.0;
        m.reset_objects(&world((0.0, y), &blue(0.0, 0.9, 0.0)));
        for s in &steps {
            y += s;
            m.update(&world((0.0, y), &blue(0.0, 0.9, 0.0)), PUSH);
        }
        let from = world((0.0, 0.0), &blue(0.0, 0.9, 0.0));
        m.predict(&from, PUSH).actuator.s.y
    };
    let faithful = predicted(GateModel::default());
    let adapted = predicted(improved(on));
    // The thesis's map keeps its first (short) sample in the blend.
    assert!((faithful - 0.005).abs() >= 0.001, "faithful {faithful}");
    assert!((adapted - 0.005).abs() < (faithful - 0.005).abs());
    assert!((adapted - 0.005).abs() <= 0.000_5, "adapted {adapted}");
}

#[test]
fn forward_check_takes_the_push_predicted_best_and_keeps_the_inverse_models_on_a_tie() {
    let on = Improvements {
        forward_check: true,
        ..Improvements::default()
    };
    let mut m = improved(on);
    train(&mut m, &[0.0, -0.12, 0.07, 0.2, -0.2, 0.1]);
    let goal = st(0.0, 0.6, 0.0);
    m.set_target(Some(Target::new(BLUE_ID, goal))).unwrap();
    let act = m.actuator().unwrap();
    let b = m.block(BLUE_ID).unwrap();
    for (vx, vy) in [
        (0.0, 0.3),
        (0.05, 0.3),
        (-0.1, 0.25),
        (0.2, 0.2),
        (0.0, 0.05),
    ] {
        let push = Action::new(vx, vy);
        let chosen = m.checked_push(&b, &act, push);
        let (d_push, d_chosen) = (
            m.predicted_block(&b, &act, push).distance_to(&goal),
            m.predicted_block(&b, &act, chosen).distance_to(&goal),
        );
        assert!(d_chosen <= d_push, "{push:?} → {chosen:?}");
        if chosen == push {
            continue;
        }
        assert!(d_chosen < d_push);
    }
    // Far from any contact every candidate predicts the block at rest: a tie.
    let far = tracked(ACTUATOR_ID, st(1.5, -1.5, 0.0), st(1.5, -1.5, 0.0));
    let push = Action::new(0.0, 0.3);
    assert_eq!(m.checked_push(&b, &far, push), push);
}
