//! Push Task Simulation (`docs/spec/experiments.md` §3): the forward-model test.
//!
//! One job is one (N_train, fold): a fresh model, N_train training runs
//! pushing straight ahead from the job's training starts, then one chained
//! test run per test position. [`PushTask`] is the §3 handler for one job;
//! [`summarise`] turns the jobs' errors into the §7 tables.

use std::collections::BTreeMap;

use learner::eval::{
    draft_training_starts, test_positions, training_start_in, two_object_test_positions,
    CurveSummary, MeanStd, PositionErrors, RunErrors, FIXED_TRAINING_STARTS, PUSH_ACTION,
    TRAINING_START_RANGE, WIDE_TRAINING_START_RANGE,
};
use learner::flags;
use learner::keypoints::{KeyPointRun, KeyPointScore};
use learner::{Model, ModelStats, Poses, BLUE_ID, RED_ID};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::driver::{push_task_blocks, Core, Counters, Task};
use super::nodes::NodeSummary;
use super::ExperimentError;

/// Name used for seeds and reports.
pub const EXPERIMENT: &str = "push-task";

/// The thesis's learning-curve N_train values (`docs/spec/experiments.md` §3.1).
pub const DEFAULT_TRAIN_RUNS: [usize; 7] = [1, 2, 3, 5, 10, 20, 30];

/// Training starts of the two-object experiment (`docs/spec/experiments.md` §3.3); the
/// first variant uses the first six.
pub const TWO_OBJECT_TRAINING_STARTS: [f64; 7] = [-0.18, 0.18, 0.0, -0.73, -0.47, -0.6, -0.4];

/// The push-task variants of `docs/spec/experiments.md` §3.1–§3.4.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Variant {
    /// §3.1: every training start uniform in [−0.25, 0.25) (configuration 0).
    Random,
    /// §3.2: configuration 8, training starts −0.18, 0.18, 0.0.
    FixedThree,
    /// §3.4: no training, feedback from real states, 10 Hz (qualitative).
    ConstantFeedback,
    /// §3.3: both blocks; six (or, with `--train-runs 7`, seven) fixed starts.
    TwoObjects,
    /// The thesis draft's protocol (draft §6.1.1): training starts at the
    /// block's left end, right end and centre, then uniform in [−0.35,
    /// 0.35); 20 test starts drawn once from a fixed seed in the same range.
    Draft,
}

/// Seed of the draft protocol's test starts: the original reseeded its
/// generator with 4321 before every test phase (`docs/spec/experiments.md` §5), which
/// is what the draft's "another seed is set after the training is done, so
/// that all models are tested on the same starting positions" describes.
/// The original's generator cannot be reproduced, so the 20 starts differ
/// from the draft's; they are the same for every model, flag and --seed.
pub const DRAFT_TEST_SEED: u64 = 4321;

/// Number of test runs of the draft protocol (draft §6.1.2: "over 20 test
/// runs").
pub const DRAFT_TEST_RUNS: usize = 20;

/// The draft protocol's test starts: [`DRAFT_TEST_RUNS`] uniform draws in
/// [−0.35, 0.35) from [`DRAFT_TEST_SEED`], in draw order.
#[must_use]
pub fn draft_test_positions() -> Vec<f64> {
    use rand::SeedableRng;
    let mut rng = ChaCha8Rng::seed_from_u64(DRAFT_TEST_SEED);
    (0..DRAFT_TEST_RUNS)
        .map(|_| training_start_in(rng.random::<f64>(), WIDE_TRAINING_START_RANGE))
        .collect()
}

/// How a push-task experiment places its runs and how fast the world
/// publishes: the variant's protocol, changed by the driver's
/// configuration bits (`docs/spec/experiments.md` §1: 2 LOWFREQ, 4 ALLOWMISSPOSITIONS,
/// 8 FIXFIRSTTHREETRAININGRUNS).
#[derive(Clone, Debug, PartialEq)]
pub struct Protocol {
    pub variant: Variant,
    /// Training starts that replace the random ones, run by run.
    pub fixed_starts: Vec<f64>,
    /// Width of the random training start range, centred on 0.
    pub start_range: f64,
    pub test_positions: Vec<f64>,
    /// The world's publish rate and the learner's update rate.
    pub rate_hz: u32,
}

impl Protocol {
    /// The protocol of `variant` under configuration number `config`.
    #[must_use]
    pub fn new(variant: Variant, config: u32) -> Self {
        let mut fixed_starts = match variant {
            Variant::Draft => draft_training_starts().to_vec(),
            _ => variant.fixed_starts().to_vec(),
        };
        if config & flags::FIXFIRSTTHREETRAININGRUNS != 0 && fixed_starts.is_empty() {
            fixed_starts = FIXED_TRAINING_STARTS.to_vec();
        }
        let wide = variant == Variant::Draft || config & flags::ALLOWMISSPOSITIONS != 0;
        Self {
            variant,
            fixed_starts,
            start_range: if wide {
                WIDE_TRAINING_START_RANGE
            } else {
                TRAINING_START_RANGE
            },
            test_positions: variant.test_positions(),
            rate_hz: if config & flags::LOWFREQ != 0 {
                super::LOW_RATE_HZ
            } else {
                super::RATE_HZ
            },
        }
    }
}

impl From<Variant> for Protocol {
    fn from(variant: Variant) -> Self {
        Self::new(variant, 0)
    }
}

impl Variant {
    /// The name on the command line and in reports.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Variant::Random => "random",
            Variant::FixedThree => "fixed-three",
            Variant::ConstantFeedback => "constant-feedback",
            Variant::TwoObjects => "two-objects",
            Variant::Draft => "draft",
        }
    }

    /// The scene the world must load.
    #[must_use]
    pub fn scene(self) -> &'static str {
        match self {
            Variant::TwoObjects => "two_blocks",
            _ => "one_block",
        }
    }

    /// Fixed training starts that replace the random ones, run by run.
    #[must_use]
    pub fn fixed_starts(self) -> &'static [f64] {
        match self {
            Variant::Random | Variant::ConstantFeedback | Variant::Draft => &[],
            Variant::FixedThree => &FIXED_TRAINING_STARTS,
            Variant::TwoObjects => &TWO_OBJECT_TRAINING_STARTS,
        }
    }

    /// The N_train values the thesis used for this variant.
    #[must_use]
    pub fn default_train_runs(self) -> Vec<usize> {
        match self {
            Variant::Random => DEFAULT_TRAIN_RUNS.to_vec(),
            Variant::FixedThree => vec![3],
            Variant::TwoObjects => vec![6],
            Variant::ConstantFeedback => Vec::new(),
            // The draft's tables: 3 and 10 training runs.
            Variant::Draft => vec![3, 10],
        }
    }

    /// The test starts.
    #[must_use]
    pub fn test_positions(self) -> Vec<f64> {
        match self {
            Variant::TwoObjects => two_object_test_positions().to_vec(),
            // §3.4: the left corner, then the right one.
            Variant::ConstantFeedback => vec![-0.25, 0.25],
            Variant::Random | Variant::FixedThree => test_positions().to_vec(),
            Variant::Draft => draft_test_positions(),
        }
    }

    /// Blocks whose errors are reported: the blue one, and in the two-object
    /// scene the red one too.
    #[must_use]
    pub fn blocks(self) -> &'static [u32] {
        match self {
            Variant::TwoObjects => &[BLUE_ID, RED_ID],
            _ => &[BLUE_ID],
        }
    }
}

/// One (N_train, fold) of a push-task experiment.
#[derive(Clone, Debug, PartialEq)]
pub struct PushJob {
    pub n_train: usize,
    pub fold: usize,
    pub protocol: Protocol,
    /// Seed of the job's generator (training starts).
    pub seed: u64,
    /// Seed for the world's latency emulation.
    pub latency_seed: u64,
}

impl PushJob {
    /// The jobs of one experiment in report order: for each N_train, for each
    /// fold (`docs/spec/experiments.md` §3, outer loops).
    #[must_use]
    pub fn all(
        protocol: impl Into<Protocol>,
        train_runs: &[usize],
        folds: usize,
        seed: u64,
    ) -> Vec<PushJob> {
        let protocol = protocol.into();
        let mut jobs = Vec::with_capacity(train_runs.len() * folds);
        for &n_train in train_runs {
            for fold in 0..folds {
                let coords = [n_train as u64, fold as u64];
                jobs.push(PushJob {
                    n_train,
                    fold,
                    protocol: protocol.clone(),
                    seed: super::seed::derive(
                        seed,
                        EXPERIMENT,
                        &coords,
                        super::seed::Stream::Driver,
                    ),
                    latency_seed: super::seed::derive(
                        seed,
                        EXPERIMENT,
                        &coords,
                        super::seed::Stream::Latency,
                    ),
                });
            }
        }
        jobs
    }
}

/// The §3 handler for one job.
#[derive(Debug)]
pub struct PushTask {
    n_train: usize,
    fixed_starts: Vec<f64>,
    start_range: f64,
    test_positions: Vec<f64>,
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
    /// Selector samples of the test runs' real transitions.
    pub selection: SelectionCount,
    /// The actual and predicted end configurations of the test runs, for
    /// the snapshot figures; `None` where `errors` is `None`.
    pub end_poses: Vec<Option<EndPoses>>,
}

/// A test run's end: the real state of the message that ended it and the
/// chained prediction scored against it (`docs/spec/experiments.md` §7.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndPoses {
    /// The run's start x of the actuator.
    pub x0: f64,
    pub actual: Poses,
    pub predicted: Poses,
}

/// How often the model's AC selector chose, for the real state and action
/// of a test message, the AC that the model's own assignment gives to the
/// real transition that followed (models without a selector count nothing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SelectionCount {
    /// Transitions sampled.
    pub samples: u64,
    /// Of those, the selector chose the AC of the transition.
    pub agreed: u64,
    /// Of those, no AC has the transition's changed-feature set, so no
    /// selector could be right.
    pub unknown: u64,
}

impl SelectionCount {
    fn add(&mut self, other: SelectionCount) {
        self.samples += other.samples;
        self.agreed += other.agreed;
        self.unknown += other.unknown;
    }

    /// `agreed / samples`, `None` without samples.
    #[must_use]
    pub fn accuracy(&self) -> Option<f64> {
        (self.samples > 0).then(|| self.agreed as f64 / self.samples as f64)
    }
}

impl PushTask {
    /// The handler for `job`.
    #[must_use]
    pub fn new(job: &PushJob) -> Self {
        use rand::SeedableRng;
        Self {
            n_train: job.n_train,
            fixed_starts: job.protocol.fixed_starts.clone(),
            start_range: job.protocol.start_range,
            test_positions: job.protocol.test_positions.clone(),
            rng: ChaCha8Rng::seed_from_u64(job.seed),
            train_run: 0,
            test_run: 0,
            training_starts: Vec::new(),
            errors: Vec::new(),
            nodes: None,
            keypoints: Vec::new(),
            keypoints_run: KeyPointRun::default(),
            previous_real: None,
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
        if let Some(old) = &self.previous_real {
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

    /// `training_start(k)`: `u` is drawn for every run so that the random
    /// sequence does not depend on the variant.
    fn training_start(&mut self, k: usize) -> f64 {
        let random = training_start_in(self.rng.random::<f64>(), self.start_range);
        self.fixed_starts.get(k).copied().unwrap_or(random)
    }
}

impl<M: Model> Task<M> for PushTask {
    fn handle(&mut self, core: &mut Core<M>, model: &mut M, world: &M::World) {
        let n_test = self.test_positions.len();
        core.step_counter += 1;
        if core.run_started {
            if core.run_ended(&M::poses(world)) {
                let testing = self.train_run == self.n_train && self.test_run < n_test;
                if testing {
                    // Scored before `reset_world` forgets the prediction (§7.2).
                    let actual = M::poses(world);
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
                core.start_run((x0, 0.0), &push_task_blocks(), true);
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
                self.score_test_message(model, M::poses(world), predicted);
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

/// What one finished job contributes to the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PushJobResult {
    pub n_train: usize,
    pub fold: usize,
    pub training_starts: Vec<f64>,
    /// Per test position, in order.
    pub errors: Vec<RunErrors>,
    /// Per test position, in order.
    pub end_poses: Vec<EndPoses>,
    pub nodes: ModelStats,
    pub counters: Counters,
    pub timing: super::link::Timing,
    /// The draft's key-point scores per test run, in order.
    #[serde(default)]
    pub keypoints: Vec<KeyPointRun>,
    #[serde(default)]
    pub selection: SelectionCount,
}

impl PushJobResult {
    /// Collects a finished task's results.
    ///
    /// # Errors
    /// A test run without a prediction, or a job that did not finish.
    pub fn from_task(
        job: &PushJob,
        task: PushTask,
        counters: Counters,
        timing: super::link::Timing,
    ) -> Result<Self, ExperimentError> {
        let errors = task
            .errors
            .into_iter()
            .enumerate()
            .map(|(i, e)| {
                e.ok_or(ExperimentError::NoPrediction {
                    job: format!("N_train {} fold {}", job.n_train, job.fold),
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

/// Per-position mean and population std over folds (§7.3) of one block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PositionSummary {
    pub x0: f64,
    pub block_pos_err: MeanStd,
    pub block_ori_err: MeanStd,
    pub actuator_pos_err: MeanStd,
}

/// Learning-curve values of one block for one N_train (§7.4); "std" is the
/// mean of the per-position standard deviations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockCurve {
    pub block_pos_err: MeanStd,
    pub block_ori_err: MeanStd,
    pub actuator_pos_err: MeanStd,
    /// The same over the 15 interacting positions (single-block test
    /// positions only).
    pub interacting: InteractingCurve,
    pub per_position: Vec<PositionSummary>,
}

/// §7.4 over the interacting positions, with the original script's actuator
/// value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InteractingCurve {
    pub block_pos_err: MeanStd,
    pub block_ori_err: MeanStd,
    pub actuator_pos_err: MeanStd,
    /// Mean over the interacting positions of (mean + std) / 2: what the
    /// thesis's figure plotted for the actuator (§7.4 quirk).
    pub actuator_pos_err_script_quirk: f64,
}

/// Everything reported for one N_train.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveEntry {
    pub train_runs: usize,
    /// The blue block's values (flattened: `block_pos_err`, `per_position`, …).
    #[serde(flatten)]
    pub blue: BlockCurve,
    /// The red block's values in the two-object scene.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub red: Option<BlockCurve>,
    pub nodes: NodeSummary,
    pub folds: usize,
    /// The thesis draft's key-point scores (draft §6.1.2) per body id
    /// (actuator 8), each the mean over every test run of every fold.
    #[serde(default)]
    pub keypoints: BTreeMap<u32, KeyPointScore>,
    /// The AC selector's agreement on the test runs' real transitions
    /// (interaction model only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<SelectionCount>,
    /// Per fold (in fold order), the mean actuator error over its test
    /// runs: the actuator prediction of one trained model, whose spread
    /// over folds the learning-curve "std" hides.
    #[serde(default)]
    pub actuator_pos_err_by_fold: Vec<f64>,
    /// The first fold's test-run end configurations, for the snapshot
    /// figures.
    #[serde(default)]
    pub end_poses: Vec<EndPoses>,
}

/// Per body, the mean of each key-point score over `runs`.
#[must_use]
pub fn mean_keypoints<'a>(
    runs: impl IntoIterator<Item = &'a KeyPointRun>,
) -> BTreeMap<u32, KeyPointScore> {
    let mut sums: BTreeMap<u32, (KeyPointScore, usize)> = BTreeMap::new();
    for run in runs {
        for (&id, s) in &run.bodies {
            let (sum, n) = sums.entry(id).or_default();
            sum.final_dif += s.final_dif;
            sum.cum_dif += s.cum_dif;
            sum.mean_dif += s.mean_dif;
            sum.predictions += s.predictions;
            *n += 1;
        }
    }
    sums.into_iter()
        .map(|(id, (s, n))| {
            let k = n as f64;
            (
                id,
                KeyPointScore {
                    final_dif: s.final_dif / k,
                    cum_dif: s.cum_dif / k,
                    mean_dif: s.mean_dif / k,
                    predictions: s.predictions / n,
                },
            )
        })
        .collect()
}

fn mean_std(p: learner::eval::CurvePoint) -> MeanStd {
    MeanStd {
        mean: p.mean,
        std: p.error_bar,
    }
}

fn block_curve(
    positions: &[PositionErrors],
    x0: &[f64],
    id: u32,
) -> Result<BlockCurve, ExperimentError> {
    let summary = CurveSummary::of(positions, id).ok_or(ExperimentError::MissingBlock { id })?;
    let per_position = positions
        .iter()
        .zip(x0)
        .map(|(p, &x0)| {
            let get = |m: &BTreeMap<u32, Vec<f64>>| MeanStd::of(m.get(&id).map_or(&[][..], |v| v));
            PositionSummary {
                x0,
                block_pos_err: get(&p.block_pos),
                block_ori_err: get(&p.block_ori),
                actuator_pos_err: MeanStd::of(&p.actuator),
            }
        })
        .collect();
    Ok(BlockCurve {
        block_pos_err: mean_std(summary.block_pos),
        block_ori_err: mean_std(summary.block_ori),
        actuator_pos_err: mean_std(summary.actuator),
        interacting: InteractingCurve {
            block_pos_err: mean_std(summary.block_pos_interacting),
            block_ori_err: mean_std(summary.block_ori_interacting),
            actuator_pos_err: mean_std(summary.actuator_interacting),
            actuator_pos_err_script_quirk: summary.actuator_interacting_quirk,
        },
        per_position,
    })
}

/// The report entries, one per N_train in the order of `train_runs`, from
/// job results in any order.
///
/// # Errors
/// A block without errors at some position (e.g. the red block asked for in
/// a one-block scene), or an N_train without jobs.
pub fn summarise(
    protocol: &Protocol,
    train_runs: &[usize],
    results: &[PushJobResult],
) -> Result<Vec<CurveEntry>, ExperimentError> {
    let variant = protocol.variant;
    let x0 = &protocol.test_positions;
    train_runs
        .iter()
        .map(|&n| {
            let mut jobs: Vec<&PushJobResult> = results.iter().filter(|r| r.n_train == n).collect();
            jobs.sort_by_key(|r| r.fold);
            if jobs.is_empty() {
                return Err(ExperimentError::NoJobs { n_train: n });
            }
            let mut positions = vec![PositionErrors::default(); x0.len()];
            for job in &jobs {
                for (p, e) in positions.iter_mut().zip(&job.errors) {
                    p.push(e);
                }
            }
            let blue = block_curve(&positions, x0, BLUE_ID)?;
            let red = variant
                .blocks()
                .contains(&RED_ID)
                .then(|| block_curve(&positions, x0, RED_ID))
                .transpose()?;
            let stats: Vec<&ModelStats> = jobs.iter().map(|j| &j.nodes).collect();
            let actuator_pos_err_by_fold = jobs
                .iter()
                .map(|j| MeanStd::of(&j.errors.iter().map(|e| e.actuator).collect::<Vec<_>>()).mean)
                .collect();
            Ok(CurveEntry {
                train_runs: n,
                blue,
                red,
                nodes: NodeSummary::of(&stats),
                folds: jobs.len(),
                keypoints: mean_keypoints(jobs.iter().flat_map(|j| &j.keypoints)),
                selection: jobs
                    .iter()
                    .map(|j| j.selection)
                    .reduce(|mut a, b| {
                        a.add(b);
                        a
                    })
                    .filter(|c| c.samples > 0),
                actuator_pos_err_by_fold,
                end_poses: jobs[0].end_poses.clone(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use learner::eval::BlockError;

    use super::super::driver::test_support::{blue_home, describe, frame, Probe};
    use super::super::driver::Driver;
    use super::*;

    /// Feeds a driver the states a perfectly obedient world would publish:
    /// after SetPose the actuator is where it was put, after Move it advances
    /// by v · 0.01 per message, after Reset everything is home. Returns every
    /// command batch.
    fn simulate(driver: &mut Driver<Probe, PushTask>, limit: usize) -> Vec<Vec<String>> {
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
        let mut driver = Driver::new(Probe::default(), PushTask::new(&job), 100);
        let batches = simulate(&mut driver, 100_000);
        assert!(driver.is_done());
        let (task, model, counters) = driver.into_parts();
        // Two training runs from the fixed starts, in order.
        assert_eq!(task.training_starts, [-0.18, 0.18]);
        let nodes = task.nodes.as_ref().unwrap();
        assert_eq!(nodes.maps["probe"].update_calls, 2 * 149);
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
            let mut driver = Driver::new(untrained.clone(), PushTask::new(job), 100);
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
        let mut again = Driver::new(untrained, PushTask::new(&jobs[3]), 100);
        assert_eq!(simulate(&mut again, 100_000), runs[3].1);
    }

    #[test]
    fn random_starts_are_drawn_per_run_and_replaced_by_fixed_ones() {
        let random = PushJob {
            protocol: Variant::Random.into(),
            ..job(3, Variant::FixedThree)
        };
        let mut a = PushTask::new(&random);
        let mut b = PushTask::new(&job(3, Variant::FixedThree));
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
        let mut t = PushTask::new(&PushJob::all(wide, &[200], 1, 3).remove(0));
        let starts: Vec<f64> = (0..200).map(|k| t.training_start(k)).collect();
        assert!(starts.iter().all(|x| (-0.35..0.35).contains(x)));
        assert!(starts.iter().any(|x| x.abs() > 0.3));
    }

    #[test]
    fn the_draft_protocol_starts_at_the_blocks_ends_and_tests_on_a_fixed_seed() {
        let p = Protocol::from(Variant::Draft);
        assert_eq!(p.fixed_starts, [-0.25, 0.25, 0.0]);
        assert_eq!(p.start_range, 0.7);
        assert_eq!(p.rate_hz, 100);
        assert_eq!(p.test_positions.len(), DRAFT_TEST_RUNS);
        assert!(p.test_positions.iter().all(|x| (-0.35..0.35).contains(x)));
        // The same 20 starts whatever the seed, N_train or fold.
        let jobs = PushJob::all(Variant::Draft, &[3, 10], 2, 99);
        assert!(jobs
            .iter()
            .all(|j| j.protocol.test_positions == p.test_positions));
        assert_eq!(Variant::Draft.default_train_runs(), [3, 10]);
    }

    #[test]
    fn two_object_jobs_use_their_table_and_positions() {
        let j = job(7, Variant::TwoObjects);
        let mut t = PushTask::new(&j);
        let starts: Vec<f64> = (0..7).map(|k| t.training_start(k)).collect();
        assert_eq!(starts, TWO_OBJECT_TRAINING_STARTS);
        assert_eq!(Variant::TwoObjects.test_positions()[0], -0.8);
        assert_eq!(Variant::TwoObjects.scene(), "two_blocks");
    }

    #[test]
    fn jobs_are_ordered_by_n_train_then_fold_with_distinct_seeds() {
        let jobs = PushJob::all(Variant::Random, &[1, 3], 2, 5);
        let coords: Vec<(usize, usize)> = jobs.iter().map(|j| (j.n_train, j.fold)).collect();
        assert_eq!(coords, [(1, 0), (1, 1), (3, 0), (3, 1)]);
        let mut seeds: Vec<u64> = jobs.iter().flat_map(|j| [j.seed, j.latency_seed]).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), 8);
    }

    fn result(n_train: usize, fold: usize, pos: impl Fn(usize) -> f64) -> PushJobResult {
        let errors = (0..21)
            .map(|i| RunErrors {
                actuator: 0.001,
                blocks: BTreeMap::from([(
                    BLUE_ID,
                    BlockError {
                        pos: pos(i),
                        ori: 0.0,
                    },
                )]),
            })
            .collect();
        PushJobResult {
            n_train,
            fold,
            training_starts: vec![0.0; n_train],
            errors,
            end_poses: Vec::new(),
            nodes: ModelStats::default(),
            counters: Counters::default(),
            timing: Default::default(),
            keypoints: Vec::new(),
            selection: SelectionCount::default(),
        }
    }

    #[test]
    fn summaries_use_per_position_population_stds_in_the_given_order() {
        // Fold 0 errs by 0.1 everywhere, fold 1 by 0.3: per-position mean
        // 0.2, population std 0.1 (not the sample std 0.141).
        let results = vec![
            result(3, 1, |_| 0.3),
            result(1, 0, |_| 0.0),
            result(3, 0, |_| 0.1),
        ];
        let curve = summarise(&Variant::Random.into(), &[3, 1], &results).unwrap();
        assert_eq!(curve[0].train_runs, 3);
        assert_eq!(curve[0].folds, 2);
        let pos = curve[0].blue.block_pos_err;
        assert!((pos.mean - 0.2).abs() < 1e-12 && (pos.std - 0.1).abs() < 1e-12);
        assert_eq!(curve[0].blue.per_position.len(), 21);
        assert_eq!(curve[0].blue.per_position[0].x0, -0.35);
        assert_eq!(curve[1].blue.block_pos_err.mean, 0.0);
        assert!(curve[0].red.is_none());
        // The red block cannot be summarised without its errors.
        assert!(matches!(
            summarise(&Variant::TwoObjects.into(), &[1], &results),
            Err(ExperimentError::MissingBlock { id: RED_ID })
        ));
        assert!(matches!(
            summarise(&Variant::Random.into(), &[5], &results),
            Err(ExperimentError::NoJobs { n_train: 5 })
        ));
    }

    #[test]
    fn interacting_values_leave_out_the_misses() {
        let results = vec![result(
            1,
            0,
            |i| if (3..=17).contains(&i) { 0.0 } else { 1.0 },
        )];
        let curve = summarise(&Variant::Random.into(), &[1], &results).unwrap();
        assert_eq!(curve[0].blue.interacting.block_pos_err.mean, 0.0);
        assert!((curve[0].blue.block_pos_err.mean - 6.0 / 21.0).abs() < 1e-12);
        assert!((curve[0].blue.interacting.actuator_pos_err_script_quirk - 0.0005).abs() < 1e-12);
    }

    #[test]
    fn a_missed_prediction_is_an_error_not_a_zero() {
        let j = job(1, Variant::Random);
        let mut task = PushTask::new(&j);
        task.errors = vec![None];
        let err = PushJobResult::from_task(&j, task, Counters::default(), Default::default());
        assert!(matches!(
            err,
            Err(ExperimentError::NoPrediction { run: 0, .. })
        ));
    }
}
