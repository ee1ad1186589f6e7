//! The §3 handler of one push-task job (`docs/spec/experiments.md` §3): N_train
//! training runs pushing straight ahead from the job's training starts,
//! then one chained test run per test position, scored as it ends (§7.2).

use learner::eval::{training_start_in, RunErrors, PUSH_ACTION};
use learner::keypoints::KeyPointRun;
use learner::{Model, ModelStats, ObjectState, Poses};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::objects::View;
use super::protocol::{PushJob, Variant};
use crate::experiment::driver::{Core, Task};
use crate::experiment::ExperimentError;
use crate::results::push_task::{EndPoses, PushJobResult, SelectionCount};
use crate::results::run_info::{Counters, Timing};
use crate::scene::{push_task_blocks, Object, Transfer, BLOCK_Z, PUSH_TASK_START_Y};

/// The §3 handler for one job: the driver's [`Task`] for a [`PushJob`].
/// Named for the job, not the experiment: `PushTask` is the push-task
/// experiment (the lab's `experiments::push_task::PushTask`, `Spec::PushTask`
/// and the `push-task` command), of which this runs one (N_train, fold).
#[derive(Debug)]
pub struct PushJobTask {
    n_train: usize,
    fixed_starts: Vec<f64>,
    start_range: f64,
    test_positions: Vec<f64>,
    transfer: Option<Transfer>,
    rng: ChaCha8Rng,
    train_run: usize,
    test_run: usize,
    /// Training starts actually used, in order.
    pub training_starts: Vec<f64>,
    /// One entry per finished test run; `None` if a run ended before any
    /// prediction was made.
    pub errors: Vec<Option<RunErrors>>,
    /// Node statistics when training ended (§7.5).
    pub nodes: Option<ModelStats>,
    /// The thesis draft's key-point scores, one per finished test run.
    pub keypoints: Vec<KeyPointRun>,
    /// The current test run's scores so far.
    keypoints_run: KeyPointRun,
    /// The real state of the previous message of the current test run, for
    /// the selector samples.
    previous_real: Option<Poses>,
    /// Whether to sample the model's selector on the test runs' real
    /// transitions: the thesis draft's protocol, whose tables show the
    /// agreement. It asks the model about real states the test chain never
    /// shows it, which the learner protocol cannot do without showing a
    /// learner its test runs; so it is a diagnostic of the draft's tables
    /// alone, and every other report is the same in process and behind
    /// the protocol.
    samples_selector: bool,
    /// Selector samples of the test runs' real transitions.
    pub selection: SelectionCount,
    /// The actual and predicted end configurations of the test runs, for
    /// the snapshot figures; `None` where `errors` is `None`.
    pub end_poses: Vec<Option<EndPoses>>,
}

impl PushJobTask {
    /// The handler for `job`.
    #[must_use]
    pub fn new(job: &PushJob) -> Self {
        use rand::SeedableRng;
        Self {
            n_train: job.n_train,
            fixed_starts: job.protocol.fixed_starts.clone(),
            start_range: job.protocol.start_range,
            test_positions: job.protocol.test_positions.clone(),
            transfer: job.protocol.transfer.clone(),
            rng: ChaCha8Rng::seed_from_u64(job.seed),
            train_run: 0,
            test_run: 0,
            training_starts: Vec::new(),
            errors: Vec::new(),
            nodes: None,
            keypoints: Vec::new(),
            keypoints_run: KeyPointRun::default(),
            previous_real: None,
            samples_selector: job.protocol.variant == Variant::Draft,
            selection: SelectionCount::default(),
            end_poses: Vec::new(),
        }
    }

    /// The draft's per-message scores (draft §6.1.2) and the selector
    /// sample of one message of a test run: `actual` against the prediction
    /// made for it, and the real transition from the previous message.
    fn score_test_message<M: Model>(&mut self, model: &M, actual: Poses, predicted: Option<Poses>) {
        if let Some(p) = predicted {
            self.keypoints_run.add(&actual, &p);
        }
        if let Some(old) = self
            .previous_real
            .as_ref()
            .filter(|_| self.samples_selector)
        {
            for (truth, chosen) in model.selection(old, &actual, PUSH_ACTION) {
                self.selection.samples += 1;
                match truth {
                    None => self.selection.unknown += 1,
                    Some(k) if chosen == Some(k) => self.selection.agreed += 1,
                    Some(_) => {}
                }
            }
        }
        self.previous_real = Some(actual);
    }

    /// Puts the run's object in the blue block's start and the blue block
    /// in the object's parking place (the world was just reset, so every
    /// body is at its scene start), and shows the learner only that object.
    fn place(core: &mut Core<impl Model>, object: Object) {
        use pushlearn::wire::pb::{client_message::Payload, Pose};
        let start = push_task_blocks().get(&learner::BLUE_ID).copied();
        if let (Some(park), Some(start)) = (object.park(), start) {
            let pose = |s: ObjectState| Pose::from_position_yaw([s.x, s.y, BLOCK_Z], s.theta);
            core.send(Payload::set_poses([
                (learner::BLUE_NAME.to_owned(), pose(park)),
                (object.body().to_owned(), pose(start)),
            ]));
        }
        core.set_view(Some(View { object }));
    }

    /// `training_start(k)`: `u` is drawn for every run so that the random
    /// sequence does not depend on the variant.
    fn training_start(&mut self, k: usize) -> f64 {
        let random = training_start_in(self.rng.random::<f64>(), self.start_range);
        self.fixed_starts.get(k).copied().unwrap_or(random)
    }
}

impl<M: Model> Task<M> for PushJobTask {
    fn initial_view(&self) -> Option<View> {
        self.transfer.as_ref().map(|_| View {
            object: Object::Blue,
        })
    }

    fn run_name(&self) -> String {
        if self.train_run < self.n_train {
            format!("training run {} of {}", self.train_run + 1, self.n_train)
        } else {
            let n_test = self.test_positions.len();
            format!("test run {} of {n_test}", (self.test_run + 1).min(n_test))
        }
    }

    fn handle(&mut self, core: &mut Core<M>, model: &mut M, world: &M::World, actual: &Poses) {
        let n_test = self.test_positions.len();
        core.step_counter += 1;
        if core.run_started {
            if core.run_ended(actual) {
                let testing = self.train_run == self.n_train && self.test_run < n_test;
                if testing {
                    // Scored before `reset_world` forgets the prediction (§7.2).
                    let actual = actual.clone();
                    let predicted = core.stepper.last_prediction().map(M::poses);
                    self.errors
                        .push(predicted.as_ref().map(|p| RunErrors::score(&actual, p)));
                    self.score_test_message(model, actual.clone(), predicted.clone());
                    self.keypoints.push(std::mem::take(&mut self.keypoints_run));
                    self.previous_real = None;
                    let x0 = self.test_positions.get(self.test_run).copied();
                    self.end_poses
                        .push(predicted.zip(x0).map(|(predicted, x0)| EndPoses {
                            x0,
                            actual,
                            predicted,
                        }));
                }
                core.reset_world();
                core.run_started = false;
            }
        } else {
            let x0 = if self.train_run == self.n_train {
                self.test_positions.get(self.test_run).copied()
            } else {
                let x0 = self.training_start(self.train_run);
                self.training_starts.push(x0);
                Some(x0)
            };
            if let Some(x0) = x0 {
                if let Some(transfer) = &self.transfer {
                    let object = if self.train_run == self.n_train {
                        transfer.test
                    } else {
                        transfer.training_object(self.train_run)
                    };
                    Self::place(core, object);
                }
                core.start_run((x0, PUSH_TASK_START_Y), &push_task_blocks(), true);
            }
            return;
        }
        if self.train_run < self.n_train {
            if core.run_started {
                let action = core.stepper.train(model, world, PUSH_ACTION);
                core.send_move(action);
            } else {
                self.train_run += 1;
                if self.train_run == self.n_train {
                    self.nodes = Some(model.stats());
                    model.set_training(false);
                }
            }
        } else if self.test_run < n_test {
            if core.run_started {
                let predicted = core.stepper.last_prediction().map(M::poses);
                self.score_test_message(model, actual.clone(), predicted);
                let action = core.stepper.test(model, world, PUSH_ACTION);
                core.send_move(action);
            } else {
                self.test_run += 1;
                if self.test_run == n_test {
                    core.finish();
                }
            }
        }
    }
}

impl PushJobResult {
    /// Collects a finished task's results.
    ///
    /// # Errors
    /// A test run without a prediction, or a job that did not finish.
    pub fn from_task(
        job: &PushJob,
        task: PushJobTask,
        counters: Counters,
        timing: Timing,
    ) -> Result<Self, ExperimentError> {
        let errors = task
            .errors
            .into_iter()
            .enumerate()
            .map(|(i, e)| {
                e.ok_or(ExperimentError::NoPrediction {
                    job: job.name(),
                    run: i,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        // Present wherever an error is (both come from the same prediction).
        let end_poses = task.end_poses.into_iter().flatten().collect();
        Ok(Self {
            n_train: job.n_train,
            fold: job.fold,
            training_starts: task.training_starts,
            errors,
            end_poses,
            nodes: task.nodes.unwrap_or_default(),
            counters,
            timing,
            keypoints: task.keypoints,
            selection: task.selection,
        })
    }
}

#[cfg(test)]
mod tests {
    use learner::eval::FIXED_TRAINING_STARTS;
    use learner::flags;

    use super::super::protocol::{Protocol, Variant, TWO_OBJECT_TRAINING_STARTS};
    use super::*;
    use crate::experiment::driver::test_support::{blue_home, describe, frame};
    use crate::experiment::driver::Driver;
    use learner::testing::Probe;

    /// Feeds a driver the states a perfectly obedient world would publish:
    /// after SetPose the actuator is where it was put, after Move it advances
    /// by v · 0.01 per message, after Reset everything is home. Returns every
    /// command batch.
    fn simulate(driver: &mut Driver<Probe, PushJobTask>, limit: usize) -> Vec<Vec<String>> {
        let mut actuator = (0.0, 0.0);
        let mut velocity = (0.0, 0.0);
        let mut batches = Vec::new();
        for _ in 0..limit {
            if driver.is_done() {
                break;
            }
            actuator.0 += velocity.0 * 0.01;
            actuator.1 += velocity.1 * 0.01;
            let commands = driver.on_state(&frame(actuator, &blue_home()));
            for c in describe(&commands) {
                if let Some(v) = c.strip_prefix("move(") {
                    let v: Vec<f64> = v
                        .trim_end_matches(')')
                        .split(',')
                        .filter_map(|s| s.parse().ok())
                        .collect();
                    velocity = (v[0], v[1]);
                } else if c == "reset" {
                    actuator = (0.0, 0.0);
                } else if let Some(p) = c.strip_prefix("pose(actuator,") {
                    let p: Vec<f64> = p
                        .trim_end_matches(')')
                        .split(',')
                        .filter_map(|s| s.parse().ok())
                        .collect();
                    actuator = (p[0], p[1]);
                }
            }
            batches.push(describe(&commands));
        }
        batches
    }

    fn job(n_train: usize, variant: Variant) -> PushJob {
        PushJob::all(variant, &[n_train], 1, 42).remove(0)
    }

    #[test]
    fn one_job_trains_149_updates_per_run_then_tests_every_position() {
        let job = job(2, Variant::FixedThree);
        let mut driver = Driver::new(Probe::default(), PushJobTask::new(&job), 100);
        let batches = simulate(&mut driver, 100_000);
        assert!(driver.is_done());
        let (task, model, counters) = driver.into_parts();
        // Two training runs from the fixed starts, in order.
        assert_eq!(task.training_starts, [-0.18, 0.18]);
        let nodes = task.nodes.as_ref().unwrap();
        assert_eq!(Probe::map(nodes).unwrap().update_calls, 2 * 149);
        // 21 test runs, each scored once; the probe's chain is exact.
        assert_eq!(task.errors.len(), 21);
        assert!(task
            .errors
            .iter()
            .all(|e| e.as_ref().unwrap().actuator < 1e-9));
        // The draft's key-point score: one per test run, 150 predictions
        // each (messages 2 … 151), exact for the probe.
        assert_eq!(task.keypoints.len(), 21);
        for run in &task.keypoints {
            let a = run.actuator().unwrap();
            assert_eq!(a.predictions, 150);
            assert!(a.cum_dif < 1e-9 && a.final_dif < 1e-9);
        }
        // The probe has no AC selector: nothing sampled.
        assert_eq!(task.selection, SelectionCount::default());
        // Each scored run keeps its end: the real state and the prediction.
        assert_eq!(task.end_poses.len(), 21);
        let last = task.end_poses[20].as_ref().unwrap();
        assert!((last.x0 - 0.35).abs() < 1e-12);
        assert!((last.actual.actuator.y - last.predicted.actuator.y).abs() < 1e-9);
        assert!(last.actual.actuator.y > 0.7, "{last:?}");
        // Every run: one resync. A test run also "updates" on its first
        // message (with training off that only moves the chain forward).
        assert_eq!(model.resets, 2 + 21);
        assert_eq!(model.trained_updates, 2 * 149);
        assert_eq!(model.updates, 2 * 149 + 21 * 150);
        // A perfectly obedient world never fails the start check.
        assert_eq!(counters.reset_errors, 0);
        // Runs start with the actuator's SetPose at the test positions.
        let starts: Vec<&String> = batches
            .iter()
            .flatten()
            .filter(|c| c.starts_with("pose(actuator"))
            .collect();
        assert_eq!(starts.len(), 23);
        assert_eq!(starts[2], "pose(actuator,-0.35,0)");
        // Each run: the message on which step_counter becomes 151 stops
        // the actuator and resets the world.
        let run_end = batches
            .iter()
            .position(|b| b == &["move(0,0)", "reset"])
            .unwrap();
        let first_move = batches.iter().position(|b| b == &["move(0,0.5)"]).unwrap();
        assert_eq!(run_end - first_move, 150);
    }

    /// Folds and N_train values are separate jobs: each starts like the
    /// spec's `new_fold` (a fresh clone of the untrained model, rate and
    /// world reset, its own seed), so consecutive jobs on one world do not
    /// see each other, and a job replayed gives the same commands.
    #[test]
    fn every_job_starts_like_a_new_fold() {
        let untrained = Probe::default();
        let jobs = PushJob::all(Variant::Random, &[1, 2], 2, 7);
        let mut runs = Vec::new();
        for job in &jobs {
            let mut driver = Driver::new(untrained.clone(), PushJobTask::new(job), 100);
            let batches = simulate(&mut driver, 100_000);
            assert_eq!(batches[0], ["rate(100)", "move(0,0)", "reset"]);
            let (task, model, _) = driver.into_parts();
            assert_eq!(task.training_starts.len(), job.n_train);
            assert_eq!(model.trained_updates, 149 * job.n_train as u64);
            runs.push((task.training_starts, batches));
        }
        // Folds of one N_train draw different starts; N_train = 2 does not
        // continue the sequence of N_train = 1.
        assert_ne!(runs[0].0, runs[1].0);
        assert_ne!(runs[0].0[0], runs[2].0[0]);
        // Replaying job 3 alone gives exactly the same command sequence.
        let mut again = Driver::new(untrained, PushJobTask::new(&jobs[3]), 100);
        assert_eq!(simulate(&mut again, 100_000), runs[3].1);
    }

    #[test]
    fn random_starts_are_drawn_per_run_and_replaced_by_fixed_ones() {
        let random = PushJob {
            protocol: Variant::Random.into(),
            ..job(3, Variant::FixedThree)
        };
        let mut a = PushJobTask::new(&random);
        let mut b = PushJobTask::new(&job(3, Variant::FixedThree));
        let drawn: Vec<f64> = (0..3).map(|k| a.training_start(k)).collect();
        assert!(drawn.iter().all(|x| (-0.25..0.25).contains(x)));
        let fixed: Vec<f64> = (0..4).map(|k| b.training_start(k)).collect();
        assert_eq!(&fixed[..3], &FIXED_TRAINING_STARTS);
        // The fourth draw continues the same random sequence.
        assert_eq!(fixed[3], a.training_start(3));
    }

    #[test]
    fn driver_bits_change_the_protocol() {
        let base = Protocol::from(Variant::Random);
        assert_eq!(base, Protocol::new(Variant::Random, 16 | 32 | 64 | 1));
        assert_eq!((base.rate_hz, base.start_range), (100, 0.5));
        assert!(base.fixed_starts.is_empty());
        // LOWFREQ: 10 Hz.
        assert_eq!(Protocol::new(Variant::Random, flags::LOWFREQ).rate_hz, 10);
        // FIXFIRSTTHREETRAININGRUNS: the §3.2 starts, not replacing a
        // variant's own table.
        assert_eq!(
            Protocol::new(Variant::Random, flags::FIXFIRSTTHREETRAININGRUNS).fixed_starts,
            Protocol::from(Variant::FixedThree).fixed_starts
        );
        assert_eq!(
            Protocol::new(Variant::TwoObjects, 8).fixed_starts,
            TWO_OBJECT_TRAINING_STARTS
        );
        // ALLOWMISSPOSITIONS: starts in [−0.35, 0.35), some beyond ±0.25.
        let wide = Protocol::new(Variant::Random, flags::ALLOWMISSPOSITIONS);
        let mut t = PushJobTask::new(&PushJob::all(wide, &[200], 1, 3).remove(0));
        let starts: Vec<f64> = (0..200).map(|k| t.training_start(k)).collect();
        assert!(starts.iter().all(|x| (-0.35..0.35).contains(x)));
        assert!(starts.iter().any(|x| x.abs() > 0.3));
    }

    #[test]
    fn two_object_jobs_use_their_table_and_positions() {
        let j = job(7, Variant::TwoObjects);
        let mut t = PushJobTask::new(&j);
        let starts: Vec<f64> = (0..7).map(|k| t.training_start(k)).collect();
        assert_eq!(starts, TWO_OBJECT_TRAINING_STARTS);
        assert_eq!(Variant::TwoObjects.test_positions()[0], -0.8);
        assert_eq!(Variant::TwoObjects.scene(), "two_blocks");
    }

    #[test]
    fn a_missed_prediction_is_an_error_not_a_zero() {
        let j = job(1, Variant::Random);
        let mut task = PushJobTask::new(&j);
        task.errors = vec![None];
        let err = PushJobResult::from_task(&j, task, Counters::default(), Default::default());
        assert!(matches!(
            err,
            Err(ExperimentError::NoPrediction { run: 0, .. })
        ));
    }
}
