//! Trace-driven test of the gate model: the Push Task Simulation
//! (`docs/spec/experiments.md` §3.1) with 10 random training runs, on pushes simulated
//! by our own world in-process, scored with `learner::eval`.
//!
//! The thesis reports, over 20 folds, 0.049 m / 0.15 rad / 0.0022 m after 10
//! runs (`docs/spec/reference-results.md` §3.4); the original learner re-run on a
//! reconstructed world gives 0.05 m / 0.15 rad / 0.0005 m (§10, no command
//! latency, as here). The bounds below leave room for 5 folds instead of 20
//! and for the knife-edge noise §10 describes (up to 0.01 m / 0.03 rad on the
//! 21-position means); a model that is wrong in substance misses them by far
//! (an untrained model scores ≈ 0.22 m / 0.5 rad).

use learner::eval::{
    self, CurveSummary, PositionErrors, MESSAGES_PER_RUN, PUSH_ACTION, TEST_POSITION_COUNT,
};
use learner::{Frame, GateModel, Model, ObjectState, BLUE_ID};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sim_plugin::{Command, Scene, World};

use crate::push_frames::record_run;

const FOLDS: u64 = 5;
const TRAINING_RUNS: usize = 10;

/// `check_start_positions` of `docs/spec/experiments.md` §2 as an assertion: in
/// lock-step nothing can be stale, so a failure is a bug here.
fn assert_start(model: &GateModel, frames: &[Frame], x0: f64) {
    let poses = GateModel::poses(&model.parse(&frames[0]).expect("world frames parse"));
    assert!(poses.actuator.distance_to(&ObjectState::new(x0, 0.0, 0.0)) <= 0.01);
    assert!(poses.blocks[&BLUE_ID].distance_to(&ObjectState::new(0.0, 0.25, 0.0)) <= 0.01);
}

#[test]
fn gate_model_push_task_after_ten_random_training_runs() {
    let scene = Scene::builtin("one_block").expect("embedded scene");
    let mut world = World::new(&scene).expect("world");
    world.apply(Command::SetPublishRate(100)).expect("100 Hz");

    let starts = eval::test_positions();
    let tests: Vec<Vec<Frame>> = starts
        .iter()
        .map(|&x0| record_run(&mut world, x0))
        .collect();
    let mut positions = vec![PositionErrors::default(); TEST_POSITION_COUNT];
    let mut node_counts = Vec::new();

    for fold in 0..FOLDS {
        // docs/spec/experiments.md §5: one seeded generator per (N_train, fold).
        let mut rng = ChaCha8Rng::seed_from_u64(fold);
        let mut model = GateModel::default();
        for _ in 0..TRAINING_RUNS {
            let x0 = eval::random_training_start(rng.random::<f64>());
            let frames = record_run(&mut world, x0);
            assert_start(&model, &frames, x0);
            let handled = eval::train_on_run(&mut model, &frames, PUSH_ACTION).expect("parses");
            assert_eq!(handled, MESSAGES_PER_RUN);
        }
        let stats = model.stats();
        let stats = stats.as_gate().expect("gate statistics");
        // 149 updates per training run (docs/spec/experiments.md §8); the actuator
        // model sees one input only and keeps its first two nodes
        // (docs/spec/gate-model.md §8, docs/spec/reference-results.md §4.2).
        assert_eq!(stats.gate.update_calls, 149 * TRAINING_RUNS as u64);
        assert_eq!(stats.actuator.nodes, 2);
        let predictor = stats.predictors[&BLUE_ID];
        node_counts.push((stats.gate.nodes, predictor.update_calls, predictor.nodes));
        model.set_training(false);
        for (i, frames) in tests.iter().enumerate() {
            assert_start(&model, frames, starts[i]);
            let errors = eval::test_on_run(&mut model, frames, PUSH_ACTION)
                .expect("parses")
                .expect("151 messages");
            positions[i].push(&errors);
        }
    }

    let s = CurveSummary::of(&positions, BLUE_ID).expect("every position scored");
    println!(
        "gate model, {TRAINING_RUNS} training runs, {FOLDS} folds, 21 positions: \
         block position {:.4} ± {:.4} m, orientation {:.4} ± {:.4} rad, actuator {:.5} ± {:.5} m",
        s.block_pos.mean,
        s.block_pos.error_bar,
        s.block_ori.mean,
        s.block_ori.error_bar,
        s.actuator.mean,
        s.actuator.error_bar,
    );
    println!(
        "15 interacting positions: block position {:.4} ± {:.4} m, orientation {:.4} ± {:.4} rad",
        s.block_pos_interacting.mean,
        s.block_pos_interacting.error_bar,
        s.block_ori_interacting.mean,
        s.block_ori_interacting.error_bar,
    );
    for (fold, (gate, updates, nodes)) in node_counts.iter().enumerate() {
        println!("fold {fold}: gate nodes {gate}, predictor updates {updates}, nodes {nodes}");
    }
    for (x0, p) in starts.iter().zip(&positions) {
        let m = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        println!(
            "x0 {x0:+.3}: pos {:.4} ori {:.4} act {:.5}",
            m(&p.block_pos[&BLUE_ID]),
            m(&p.block_ori[&BLUE_ID]),
            m(&p.actuator)
        );
    }

    assert!(
        s.block_pos.mean <= 0.08,
        "block position {}",
        s.block_pos.mean
    );
    assert!(
        s.block_ori.mean <= 0.25,
        "block orientation {}",
        s.block_ori.mean
    );
    assert!(s.actuator.mean <= 0.005, "actuator {}", s.actuator.mean);
}
