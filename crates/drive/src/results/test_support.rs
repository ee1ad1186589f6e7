//! Documents for the tests of the results and of their renderings.

use std::collections::BTreeMap;

use learner::eval::{test_positions, two_object_test_positions, BlockError, RunErrors};
use learner::{GateStats, MapStats, ModelStats, ObjectState, BLUE_ID, RED_ID};

use super::move_to_target::{MttRun, TargetSummary};
use super::push_task::{summarise, PushJobResult};
use super::run_info::{Counters, RunInfo, Timing};
use super::{MttReport, PushReport, Setup, TargetEntry};

/// Job `fold` of `n_train`: position i errs by 0.01 (i + fold) (the red
/// block, with `two_blocks`, by 0.02 everywhere); one gate map; 100 messages.
pub fn job(n_train: usize, fold: usize, two_blocks: bool) -> PushJobResult {
    let e = |x: f64| BlockError {
        pos: x,
        ori: 2.0 * x,
    };
    let errors = (0..21)
        .map(|i| {
            let mut blocks = BTreeMap::from([(BLUE_ID, e(0.01 * (i + fold) as f64))]);
            if two_blocks {
                blocks.insert(RED_ID, e(0.02));
            }
            RunErrors {
                actuator: 0.002,
                blocks,
            }
        })
        .collect();
    let nodes = ModelStats::Gate(GateStats {
        gate: MapStats {
            update_calls: 149 * n_train as u64,
            inserts: 4,
            nodes: 4,
        },
        ..GateStats::default()
    });
    PushJobResult {
        n_train,
        fold,
        training_starts: vec![0.0; n_train],
        errors,
        end_poses: Vec::new(),
        nodes,
        counters: Counters {
            messages: 100,
            ignored: 3,
            reset_errors: 1,
            parse_errors: 0,
        },
        timing: Timing {
            messages: 100,
            too_slow: 1,
            busy_seconds: 0.1,
            max_seconds: 0.03,
            ..Timing::default()
        },
        keypoints: Vec::new(),
        selection: Default::default(),
    }
}

/// Two folds of every N_train of `train_runs`, as the `variant` (by its
/// report name) would test them.
pub fn push_report(variant: &str, train_runs: &[usize]) -> PushReport {
    let two_blocks = variant == "two-objects";
    let (x0, blocks): (Vec<f64>, &[u32]) = if two_blocks {
        (two_object_test_positions().to_vec(), &[BLUE_ID, RED_ID])
    } else {
        (test_positions().to_vec(), &[BLUE_ID])
    };
    let jobs: Vec<PushJobResult> = train_runs
        .iter()
        .flat_map(|&n| (0..2).map(move |f| job(n, f, two_blocks)))
        .collect();
    PushReport {
        setup: Setup::for_tests("push-task", "gate"),
        variant: variant.into(),
        transfer: None,
        folds: 2,
        train_runs: train_runs.to_vec(),
        results: summarise(&x0, blocks, train_runs, &jobs).unwrap(),
        run: RunInfo::of(jobs.iter().map(|j| (j.counters, j.timing)), 100, 2, 1.5),
    }
}

/// One run of one repetition that did not reach the thesis's first target.
pub fn mtt_report() -> MttReport {
    let run = MttRun {
        reached: false,
        steps: 3000,
        pos_err: 0.5,
        ori_err: 0.1,
        final_block: ObjectState::new(0.1, 0.2, 0.3),
        trace: Default::default(),
    };
    MttReport {
        setup: Setup {
            experiment: "move-to-target".into(),
            model: "interaction".into(),
            mode: "lockstep-jitter".into(),
            latency_max_steps: Some(2),
            learner: None,
            seed: 1,
        },
        repetitions: 1,
        max_steps: 3000,
        targets: vec![TargetEntry {
            target: [0.6, 0.7, -2.1],
            runs: vec![run.clone()],
            summary: TargetSummary::of(&[run]),
            nodes_after_training: Default::default(),
        }],
        training_starts: Vec::new(),
        run: RunInfo::default(),
    }
}
