//! Move to Target (`docs/spec/experiments.md` §4): the inverse-model test.
//!
//! One job is one (target, repetition): a fresh model, the eight fixed
//! training runs of §4.1, then one test run in which the model plans every
//! action towards the target (`docs/spec/planning.md`) while it keeps learning.
//!
//! The harness, not the learner, judges the run: it ends on the first
//! message on which the world's block meets the goal
//! ([`learner::eval::goal_reached`]), when the learner clears its target
//! (it believes it arrived, or gives up), or after the step limit; it counts
//! as reached only if the world's block meets the goal on the message that
//! ended it. A learner's word alone never makes a run a success.

use std::collections::BTreeMap;

use learner::eval::{goal_reached, wrapped_angle_error};
use learner::{Action, Model, ModelStats, ObjectState, Poses, Target, BLUE_ID, RED_ID};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::driver::{Core, Task};
use super::seed::{derive, Stream};
use super::ExperimentError;
use crate::results::move_to_target::{ErrorTrace, MttJobResult, MttRun, EXPERIMENT, TRACE_EVERY};
use crate::results::run_info::{Counters, Timing};

/// The thesis's step limit of a test run.
pub const MAX_STEPS: u64 = 3000;

/// §4.1: actuator start and action of each training run, then the test
/// run's start (the action of that entry is never used).
pub const TRAINING_RUNS: [((f64, f64), Action); 8] = [
    ((0.24, 0.0), Action::new(0.0, 0.5)),
    ((0.3, 0.25), Action::new(-0.5, 0.0)),
    ((0.24, 0.5), Action::new(0.0, -0.5)),
    ((0.0, 0.5), Action::new(0.0, -0.5)),
    ((-0.24, 0.5), Action::new(0.0, -0.5)),
    ((-0.3, 0.25), Action::new(0.5, 0.0)),
    ((-0.24, 0.0), Action::new(0.0, 0.5)),
    ((0.0, 0.0), Action::new(0.0, 0.5)),
];

/// Where the test run starts.
pub const TEST_START: (f64, f64) = (0.0, 0.0);

/// The blue block's start in every run.
const TEST_BLOCK_START: ObjectState = ObjectState::new(0.0, 0.25, 0.0);

/// `--sample-targets n` with `--seed seed`: `n` targets of the sampled
/// region, away from the blue block's start.
#[must_use]
pub fn sampled_targets(n: usize, seed: u64) -> Vec<ObjectState> {
    crate::results::move_to_target::sampled_targets(
        n,
        seed,
        (TEST_BLOCK_START.x, TEST_BLOCK_START.y),
    )
}

/// Expected block starts of every run (§4.3; the red block's entry, which
/// differs from the push task's, only matters in a two-block scene).
fn expected_blocks() -> BTreeMap<u32, ObjectState> {
    BTreeMap::from([
        (BLUE_ID, TEST_BLOCK_START),
        (RED_ID, ObjectState::new(-0.3, 0.35, 0.0)),
    ])
}

/// One (target, repetition).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MttJob {
    /// Index into the experiment's target list.
    pub target_index: usize,
    pub target: ObjectState,
    pub repetition: usize,
    pub seed: u64,
    pub latency_seed: u64,
    pub max_steps: u64,
}

impl MttJob {
    /// The job in messages, e.g. `target 2 repetition 0`.
    #[must_use]
    pub fn name(&self) -> String {
        format!(
            "target {} repetition {}",
            self.target_index + 1,
            self.repetition
        )
    }

    /// All jobs in report order: for each target, for each repetition.
    #[must_use]
    pub fn all(
        targets: &[ObjectState],
        repetitions: usize,
        max_steps: u64,
        seed: u64,
    ) -> Vec<Self> {
        let mut jobs = Vec::new();
        for (target_index, target) in targets.iter().enumerate() {
            for repetition in 0..repetitions {
                // Seeds follow the target's value, not its position in the
                // list, so a target gives the same runs in any list.
                let coords = [
                    target.x.to_bits(),
                    target.y.to_bits(),
                    target.theta.to_bits(),
                    repetition as u64,
                ];
                jobs.push(MttJob {
                    target_index,
                    target: *target,
                    repetition,
                    seed: derive(seed, EXPERIMENT, &coords, Stream::Driver),
                    latency_seed: derive(seed, EXPERIMENT, &coords, Stream::Latency),
                    max_steps,
                });
            }
        }
        jobs
    }
}

/// The block's distance to the target and `|wrap(θ − θ_t)|` (§7.6), NaN
/// without a block.
#[must_use]
pub fn target_errors(block: Option<ObjectState>, target: ObjectState) -> (f64, f64) {
    block.map_or((f64::NAN, f64::NAN), |b| {
        (
            (b.x - target.x).hypot(b.y - target.y),
            wrapped_angle_error(b.theta, target.theta),
        )
    })
}

/// The §4.3 handler for one job.
#[derive(Debug)]
pub struct MttTask {
    target: ObjectState,
    max_steps: u64,
    rng: ChaCha8Rng,
    train_run: usize,
    /// The test run's result once it ended.
    pub run: Option<MttRun>,
    /// Node statistics when training ended and after the test run.
    pub nodes_after_training: Option<ModelStats>,
    pub nodes_after_test: Option<ModelStats>,
    /// Why the job could not go on (a refused target).
    pub error: Option<learner::TargetError>,
    trace: ErrorTrace,
    /// End after the training runs (`pushlearn learn --pretrain thesis`).
    training_only: bool,
}

impl MttTask {
    #[must_use]
    pub fn new(job: &MttJob) -> Self {
        Self {
            target: job.target,
            max_steps: job.max_steps,
            rng: ChaCha8Rng::seed_from_u64(job.seed),
            train_run: 0,
            run: None,
            nodes_after_training: None,
            nodes_after_test: None,
            error: None,
            trace: ErrorTrace::default(),
            training_only: false,
        }
    }

    /// Only the eight training runs: the job ends with the world reset and
    /// the actuator at the test run's start, the model trained.
    #[must_use]
    pub fn training_only() -> Self {
        Self {
            training_only: true,
            ..Self::new(&MttJob {
                target_index: 0,
                target: TEST_BLOCK_START,
                repetition: 0,
                seed: 0,
                latency_seed: 0,
                max_steps: 0,
            })
        }
    }

    /// Whether the training runs are over.
    #[must_use]
    pub fn trained(&self) -> bool {
        self.train_run >= TRAINING_RUN_COUNT
    }
}

const TRAINING_RUN_COUNT: usize = TRAINING_RUNS.len();

impl<M: Model> Task<M> for MttTask {
    fn run_name(&self) -> String {
        if self.train_run < TRAINING_RUN_COUNT {
            format!(
                "training run {} of {TRAINING_RUN_COUNT}",
                self.train_run + 1
            )
        } else {
            "the test run".to_owned()
        }
    }

    fn handle(&mut self, core: &mut Core<M>, model: &mut M, world: &M::World, actual: &Poses) {
        core.step_counter += 1;
        if core.run_started {
            if self.train_run < TRAINING_RUN_COUNT && core.run_ended(actual) {
                core.reset_world();
                core.run_started = false;
            }
        } else {
            let start = TRAINING_RUNS
                .get(self.train_run)
                .map_or(TEST_START, |(start, _)| *start);
            core.start_run(start, &expected_blocks(), false);
            return;
        }
        if let Some(&(_, direction)) = TRAINING_RUNS.get(self.train_run) {
            if core.run_started {
                let action = core.stepper.train(model, world, direction);
                core.send_move(action);
            } else {
                self.train_run += 1;
                if self.train_run == TRAINING_RUN_COUNT {
                    self.nodes_after_training = Some(model.stats());
                    if self.training_only {
                        core.finish();
                    } else if let Err(err) =
                        model.set_target(Some(Target::new(BLUE_ID, self.target)))
                    {
                        self.error = Some(err);
                        core.finish();
                    }
                }
            }
            return;
        }
        // The test run; training stays on.
        match core.last_action {
            Some(action) => model.update(world, action),
            None => model.reset_objects(world),
        }
        let action = model.act(&mut self.rng);
        core.last_action = Some(action);
        core.send_move(action);
        let steps = core.step_counter - 1;
        let block = actual.blocks.get(&BLUE_ID).copied();
        let errors = target_errors(block, self.target);
        let reached = block.is_some_and(|b| goal_reached(&b, &self.target));
        let running = !reached && model.has_target() && core.step_counter <= self.max_steps;
        if !running || steps.is_multiple_of(TRACE_EVERY) {
            self.trace.push(steps, errors);
        }
        if running {
            return;
        }
        core.run_started = false;
        self.nodes_after_test = Some(model.stats());
        let (pos_err, ori_err) = errors;
        self.run = Some(MttRun {
            reached,
            steps,
            pos_err,
            ori_err,
            final_block: block.unwrap_or(ObjectState::new(f64::NAN, f64::NAN, f64::NAN)),
            trace: std::mem::take(&mut self.trace),
        });
        core.finish();
    }
}

impl MttJobResult {
    /// Collects a finished task's results.
    ///
    /// # Errors
    /// A refused target, or a task that ended without a result.
    pub fn from_task(
        job: &MttJob,
        task: MttTask,
        counters: Counters,
        timing: Timing,
    ) -> Result<Self, ExperimentError> {
        if let Some(err) = task.error {
            return Err(err.into());
        }
        let run = task.run.ok_or_else(|| {
            ExperimentError::Incomplete(format!(
                "target {:?}, repetition {}: the test run did not end",
                job.target, job.repetition
            ))
        })?;
        Ok(Self {
            target_index: job.target_index,
            repetition: job.repetition,
            run,
            nodes_after_training: task.nodes_after_training.unwrap_or_default(),
            nodes_after_test: task.nodes_after_test.unwrap_or_default(),
            counters,
            timing,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::driver::test_support::{blue_home, describe, frame};
    use super::super::driver::Driver;
    use super::*;
    use crate::results::move_to_target::TARGETS;
    use learner::testing::Probe;

    /// An obedient world (see `push_task` tests) driven until the job ends.
    fn simulate(driver: &mut Driver<Probe, MttTask>) -> Vec<Vec<String>> {
        let (mut x, mut y, mut vx, mut vy) = (0.0, 0.0, 0.0, 0.0);
        let mut batches = Vec::new();
        for _ in 0..20_000 {
            if driver.is_done() {
                break;
            }
            x += vx * 0.01;
            y += vy * 0.01;
            let b = describe(&driver.on_state(&frame((x, y), &blue_home())));
            for c in &b {
                let nums = |s: &str| -> Vec<f64> {
                    s.trim_end_matches(')')
                        .split(',')
                        .filter_map(|n| n.parse().ok())
                        .collect()
                };
                if let Some(v) = c.strip_prefix("move(") {
                    let v = nums(v);
                    (vx, vy) = (v[0], v[1]);
                } else if c == "reset" {
                    (x, y) = (0.0, 0.0);
                } else if let Some(p) = c.strip_prefix("pose(actuator,") {
                    let p = nums(p);
                    (x, y) = (p[0], p[1]);
                }
            }
            batches.push(b);
        }
        batches
    }

    fn job(max_steps: u64) -> MttJob {
        MttJob::all(&TARGETS[..1], 1, max_steps, 3).remove(0)
    }

    #[test]
    fn eight_training_runs_then_a_test_run_that_a_learner_ends_but_the_world_judges() {
        let model = Probe {
            // Claims the target reached on the 40th test message (39
            // actions were sent before), with the block never moved.
            reach_after: Some(40),
            ..Probe::default()
        };
        let mut d = Driver::new(model, MttTask::new(&job(MAX_STEPS)), 100);
        let batches = simulate(&mut d);
        assert!(d.is_done());
        let (task, model, counters) = d.into_parts();
        let run = task.run.unwrap();
        // The learner may end the run; only the world makes it a success.
        assert_eq!(run.steps, 39);
        assert!(!run.reached);
        assert_eq!(model.acts, 40);
        // Training: 8 runs × 149 updates; the test run trains too.
        assert_eq!(
            Probe::map(&task.nodes_after_training.unwrap())
                .unwrap()
                .update_calls,
            8 * 149
        );
        assert_eq!(model.trained_updates, 8 * 149 + 39);
        assert!(model.target.is_none());
        assert_eq!(counters.reset_errors, 0);
        let starts: Vec<&String> = batches
            .iter()
            .flatten()
            .filter(|c| c.starts_with("pose("))
            .collect();
        assert_eq!(starts.len(), 9);
        assert_eq!(starts[1], "pose(actuator,0.3,0.25)");
        assert_eq!(starts[8], "pose(actuator,0,0)");
        // The block never moved in this world: the final error is the
        // distance from its start to target 1.
        assert!((run.pos_err - (0.6f64).hypot(0.45)).abs() < 1e-9);
        assert!((run.ori_err - 2.1).abs() < 1e-9);
        // Steps 0, 10, 20, 30 and the last one, 39.
        assert_eq!(run.trace.steps, [0, 10, 20, 30, 39]);
        assert_eq!(run.trace.pos_err.len(), 5);
        assert!(run.trace.pos_err.iter().all(|&e| (e - 0.75).abs() < 1e-12));
        assert!(run.trace.ori_err.iter().all(|&e| (e - 2.1).abs() < 1e-12));
    }

    /// A job whose target is `target` instead of one of the thesis's.
    fn job_for(target: ObjectState, max_steps: u64) -> MttJob {
        MttJob::all(&[target], 1, max_steps, 3).remove(0)
    }

    #[test]
    fn a_lying_learner_is_not_scored_reached() {
        // Claims success at once: its first Act clears the target.
        let liar = Probe {
            reach_after: Some(1),
            ..Probe::default()
        };
        let mut d = Driver::new(liar, MttTask::new(&job(MAX_STEPS)), 100);
        simulate(&mut d);
        let run = d.into_parts().0.run.unwrap();
        assert_eq!(run.steps, 0);
        assert!(!run.reached);
        assert!((run.pos_err - (0.6f64).hypot(0.45)).abs() < 1e-9);
    }

    #[test]
    fn the_world_ends_a_run_whose_block_is_at_the_target_whatever_the_learner_says() {
        // The block rests at the target from the first test message; the
        // learner never claims anything.
        let mut d = Driver::new(
            Probe::default(),
            MttTask::new(&job_for(TEST_BLOCK_START, MAX_STEPS)),
            100,
        );
        simulate(&mut d);
        let (task, model, _) = d.into_parts();
        let run = task.run.unwrap();
        assert!(run.reached);
        assert_eq!(run.steps, 0);
        assert!(model.target.is_some(), "the learner still holds its target");
    }

    #[test]
    fn a_block_in_place_but_turned_away_is_not_reached() {
        // An orientation-blind learner's best: the right place, 1.4 rad off.
        let target = ObjectState::new(TEST_BLOCK_START.x, TEST_BLOCK_START.y, 1.4);
        let blind = Probe {
            reach_after: Some(5),
            ..Probe::default()
        };
        let mut d = Driver::new(blind, MttTask::new(&job_for(target, MAX_STEPS)), 100);
        simulate(&mut d);
        let run = d.into_parts().0.run.unwrap();
        assert!(!run.reached);
        assert!(run.pos_err < 1e-12);
        assert!((run.ori_err - 1.4).abs() < 1e-12);
    }

    #[test]
    fn a_run_that_never_arrives_stops_after_the_limit() {
        let mut d = Driver::new(Probe::default(), MttTask::new(&job(25)), 100);
        simulate(&mut d);
        let (task, model, _) = d.into_parts();
        let run = task.run.unwrap();
        // Ends on the 26th test message with steps = 25 = the limit.
        assert_eq!(run.steps, 25);
        assert!(!run.reached);
        assert_eq!(model.acts, 26);
        assert!(model.target.is_some());
    }

    #[test]
    fn jobs_are_by_target_then_repetition_and_seeded_by_target_value() {
        let jobs = MttJob::all(&TARGETS, 2, MAX_STEPS, 1);
        let coords: Vec<(usize, usize)> = jobs
            .iter()
            .map(|j| (j.target_index, j.repetition))
            .collect();
        assert_eq!(coords[..3], [(0, 0), (0, 1), (1, 0)]);
        let alone = MttJob::all(&TARGETS[2..3], 2, MAX_STEPS, 1);
        assert_eq!(alone[1].seed, jobs[5].seed);
        assert_ne!(jobs[0].seed, jobs[1].seed);
    }
}
