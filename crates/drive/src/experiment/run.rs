//! Whole experiments: jobs built, spread over workers, gathered in job order
//! and summarised into the report documents.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use learner::{Model, ObjectState};

use super::constant_feedback::FeedbackTask;
use super::driver::{Driver, Task};
use super::move_to_target::{MttJob, MttTask};
use super::processes::{Processes, Recipe};
use super::push_task::protocol::{Protocol, PushJob, Variant};
use super::push_task::task::PushJobTask;
use super::run_cache::{CacheCounts, RunCache};
use super::workers::{retry_if_the_world_dies, run_jobs, Worker, WorldDeath, WorldSource};
use super::{ExperimentError, Mode};
use crate::results::move_to_target::{MttJobResult, TargetSummary};
use crate::results::nodes::NodeSummary;
use crate::results::push_task::{summarise, PushJobResult};
use crate::results::run_info::{Counters, RunInfo, Timing};
use crate::results::{FeedbackReport, MttReport, PushReport, Setup, TargetEntry};
use crate::scene::{LOW_RATE_HZ, RATE_HZ};
use pushlearn::wire::pb::client_message::Payload;
use sim_plugin::lockstep::Latency;

/// When an experiment began, for [`Plan::run_info`].
struct Started {
    at: Instant,
    counts: CacheCounts,
}

/// Where and how an experiment runs.
#[derive(Clone, Debug)]
pub struct Plan {
    pub mode: Mode,
    /// With latency emulation, the largest delay of a Move in steps (the
    /// world's `--latency-max`); recorded in the report's setup.
    pub latency_max: u32,
    pub workers: usize,
    pub source: WorldSource,
    pub seed: u64,
    /// Name of the model, for the report.
    pub model: String,
    /// An external learner's record, for the report.
    pub learner: Option<crate::results::LearnerRecord>,
    /// Recorded runs to reuse, shared by the workers, and by experiments run
    /// one after the other with plans that hold the same cache (a clone of
    /// this plan with another `model`, say: both models' curves then
    /// simulate each job once). The cache does not know the world, so share
    /// it only between experiments on the same scene, mode and latency
    /// maximum. Only used
    /// where [`Mode::reuses_runs`], where
    /// a world's states are a function of the commands since a reset or
    /// latency seed (see [`super::run_cache`]); ignored in the other modes.
    pub runs: Option<Arc<RunCache>>,
    /// Worker processes for embedded worlds ([`super::processes`]): with
    /// them, a built-in model's push-task jobs run on up to `workers` of
    /// them, each stepping its own world; without, embedded worlds run in
    /// this process, one at a time.
    pub processes: Option<Arc<Processes>>,
    /// How a worker process rebuilds the model: set for built-in models.
    pub recipe: Option<Recipe>,
}

impl Plan {
    /// The setup its reports record for `experiment`.
    #[must_use]
    pub fn setup(&self, experiment: &str) -> Setup {
        Setup {
            experiment: experiment.to_owned(),
            model: self.model.clone(),
            mode: self.mode.as_str().to_owned(),
            latency_max_steps: self.mode.jitter().then_some(self.latency_max),
            seed: self.seed,
            learner: self.learner.clone(),
        }
    }

    /// The cache in use, if runs are reused.
    pub(crate) fn cache(&self) -> Option<&Arc<RunCache>> {
        self.runs.as_ref().filter(|_| self.mode.reuses_runs())
    }

    /// Which cache is in use, for worker processes to keep theirs apart.
    pub(crate) fn cache_id(&self) -> Option<u64> {
        self.cache().map(|c| c.id())
    }

    /// The cache's counts so far, taken when an experiment starts: a shared
    /// cache counts the states of every experiment that used it.
    fn counts(&self) -> CacheCounts {
        self.cache().map(|c| c.counts()).unwrap_or_default()
    }

    /// Marks the start of an experiment: its wall clock, and the cache's
    /// counts so far (a shared cache counts every experiment that used it).
    fn started(&self) -> Started {
        Started {
            at: Instant::now(),
            counts: self.counts(),
        }
    }

    /// How the experiment begun at `started` went: the jobs' counters and
    /// timings summed, and the states the worlds simulated since, if runs
    /// were reused.
    fn run_info(
        &self,
        started: &Started,
        jobs: impl IntoIterator<Item = (Counters, Timing)>,
        publish_rate_hz: u32,
        workers: usize,
    ) -> RunInfo {
        let mut run = RunInfo::of(
            jobs,
            publish_rate_hz,
            workers,
            started.at.elapsed().as_secs_f64(),
        );
        if let (Some(cache), Some(timing)) = (self.cache(), run.timing.as_mut()) {
            timing.simulated_states = cache.counts().simulated - started.counts.simulated;
        }
        run
    }

    /// Workers in this process.
    fn workers(&self) -> usize {
        if matches!(self.source, WorldSource::Embedded { .. }) && self.learner.is_none() {
            // Embedded worlds step one at a time per process, and a built-in
            // model's work per message is too small to overlap with a second
            // worker's physics: a second worker only adds hand-overs
            // (`docs/performance.md` §1, "Embedded worlds"). Worker processes
            // are the way to more cores.
            return 1;
        }
        self.source.max_workers(self.workers)
    }

    /// The worker processes jobs run on, the learner's recipe and how many
    /// to use: with embedded worlds, when the plan has processes, a recipe
    /// and more than one worker. An external learner is then started beside
    /// each worker's world.
    fn worker_processes(&self) -> Option<(&Processes, &Recipe, usize)> {
        let (WorldSource::Embedded { .. }, Some(processes), Some(recipe)) =
            (&self.source, &self.processes, &self.recipe)
        else {
            return None;
        };
        let workers = self.workers.min(processes.size());
        (workers > 1).then_some((processes.as_ref(), recipe, workers))
    }

    /// [`worker_processes`](Self::worker_processes) when its recipe's
    /// learner runs at `rate_hz`.
    fn worker_processes_for(&self, rate_hz: u32) -> Option<(&Processes, &Recipe, usize)> {
        self.worker_processes()
            .filter(|(_, recipe, _)| recipe.publish_rate_hz() == rate_hz)
    }

    /// Whether a built-in model's jobs at `rate_hz` run in worker
    /// processes, which build the model from the recipe (so this process
    /// need not build one).
    #[must_use]
    pub fn runs_in_workers(&self, rate_hz: u32) -> bool {
        self.worker_processes_for(rate_hz).is_some()
    }

    /// Workers for jobs of a model at `rate_hz`: processes or threads.
    fn job_workers(&self, rate_hz: u32) -> usize {
        match self.worker_processes_for(rate_hz) {
            Some((_, _, n)) => n,
            None => self.workers(),
        }
    }

    /// Runs `job` on `worker`, retried once on a new world if the world
    /// process dies ([`retry_if_the_world_dies`]).
    fn retrying<R>(
        &self,
        worker: &mut Worker,
        scene: &str,
        job: impl FnMut(&mut Worker) -> Result<R, ExperimentError>,
    ) -> Result<R, ExperimentError> {
        retry_if_the_world_dies(worker, || self.start(scene), job)
    }

    pub(crate) fn start(&self, scene: &str) -> Result<Worker, ExperimentError> {
        let mut worker = Worker::start(&self.source, self.mode.pacing())?;
        worker.link.require_scene(scene)?;
        if self.mode.pacing() == super::link::Pacing::Lockstep {
            worker
                .link
                .require_latency(self.mode.jitter().then_some(self.latency_max))?;
        }
        if let Some(cache) = self.cache() {
            worker
                .link
                .reuse_runs(Arc::clone(cache), self.mode.jitter());
        }
        Ok(worker)
    }

    /// Commands sent before a job's first Advance: with latency emulation
    /// the job's latency seed, so that the world's jitter does not depend on
    /// earlier jobs or on which worker runs the job (`docs/spec/experiments.md` §5).
    fn job_setup(&self, latency_seed: u64) -> JobSetup {
        if self.mode.jitter() {
            JobSetup {
                commands: vec![Payload::latency_seed(latency_seed)],
                latency: Some(Latency {
                    max_steps: self.latency_max,
                    seed: latency_seed,
                }),
            }
        } else {
            JobSetup::default()
        }
    }
}

/// What a job sends its world before its driver's first command, and the
/// latency emulation that seeds (the driver follows its draws).
#[derive(Debug, Default)]
struct JobSetup {
    commands: Vec<Payload>,
    latency: Option<Latency>,
}

/// Which job a driver runs, for [`run_job`]: its seed and its name in errors.
struct Fold {
    seed: u64,
    name: String,
}

/// Runs one job's driver to its end on `worker`'s world; a world process
/// that died meanwhile is [`ExperimentError::WorldDied`].
fn run_job<M: Model, T: Task<M>>(
    worker: &mut Worker,
    untrained: &Mutex<M>,
    task: T,
    rate_hz: u32,
    setup: JobSetup,
    fold: Fold,
) -> Result<(T, Timing, Counters), ExperimentError> {
    // A fold starts from an untrained instance (`docs/spec/experiments.md` §2 new_fold).
    let mut model = untrained
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .clone();
    model.start_fold(fold.seed);
    let mut driver = Driver::new(model, task, rate_hz).knowing_latency(setup.latency);
    let timing = match worker.link.run_driver(&mut driver, setup.commands) {
        Ok(timing) => timing,
        Err(err) => {
            return Err(match worker.world_death() {
                Some(status) => ExperimentError::WorldDied(Box::new(WorldDeath {
                    job: fold.name,
                    at: driver.position(),
                    last_sent: worker.link.last_sent(),
                    status,
                    retried: false,
                })),
                None => err,
            })
        }
    };
    if let Some(why) = driver.failure() {
        return Err(ExperimentError::Learner {
            job: fold.name,
            why: why.to_owned(),
        });
    }
    let (task, _, counters) = driver.into_parts();
    Ok((task, timing, counters))
}

/// Push Task Simulation (`docs/spec/experiments.md` §3.1–§3.3).
///
/// # Errors
/// The first failing job, or a summary that cannot be formed.
pub fn push_task<M: Model>(
    untrained: M,
    protocol: &Protocol,
    train_runs: &[usize],
    folds: usize,
    plan: &Plan,
    progress: impl FnMut(usize),
) -> Result<PushReport, ExperimentError> {
    push_task_of(protocol, train_runs, folds, plan, |jobs| {
        push_jobs(
            untrained,
            protocol.rate_hz,
            jobs,
            plan,
            |_| Ok(()),
            progress,
        )
    })
}

/// [`push_task`] when the plan runs its jobs in worker processes, each
/// building the model from the plan's recipe: no model is built in this
/// process. `None` when the plan runs jobs of the protocol's rate here.
///
/// # Errors
/// As [`push_task`].
pub fn push_task_in_workers(
    protocol: &Protocol,
    train_runs: &[usize],
    folds: usize,
    plan: &Plan,
    progress: impl FnMut(usize),
) -> Option<Result<PushReport, ExperimentError>> {
    let (processes, recipe, workers) = plan.worker_processes_for(protocol.rate_hz)?;
    Some(push_task_of(protocol, train_runs, folds, plan, |jobs| {
        processes.push_jobs(recipe, jobs, plan, workers, |_| Ok(()), progress)
    }))
}

/// The push task's report, its jobs' results given by `run`.
fn push_task_of(
    protocol: &Protocol,
    train_runs: &[usize],
    folds: usize,
    plan: &Plan,
    run: impl FnOnce(&[PushJob]) -> Result<Vec<PushJobResult>, ExperimentError>,
) -> Result<PushReport, ExperimentError> {
    let started = plan.started();
    let jobs = PushJob::all(protocol.clone(), train_runs, folds, plan.seed);
    let results = run(&jobs)?;
    let mut report = push_report(
        plan.setup(crate::results::push_task::EXPERIMENT),
        protocol,
        train_runs,
        folds,
        &results,
    )?;
    report.run = plan.run_info(
        &started,
        results.iter().map(|r| (r.counters, r.timing)),
        RATE_HZ,
        plan.job_workers(protocol.rate_hz).min(jobs.len()),
    );
    Ok(report)
}

/// Runs some push-task jobs (of [`PushJob::all`], any subset: each job's
/// seeds depend only on its own coordinates) and returns their results in
/// job order, calling `done` with each as it finishes — `pushlearn sweep`
/// writes it there, so that an interrupted run keeps what it finished.
///
/// # Errors
/// The first failing job, or the first error of `done`.
pub fn push_jobs<M: Model>(
    untrained: M,
    rate_hz: u32,
    jobs: &[PushJob],
    plan: &Plan,
    done: impl Fn(&PushJobResult) -> Result<(), ExperimentError> + Sync,
    progress: impl FnMut(usize),
) -> Result<Vec<PushJobResult>, ExperimentError> {
    let Some(first) = jobs.first() else {
        return Ok(Vec::new());
    };
    let mut progress = progress;
    if let Some(results) = push_jobs_in_workers(rate_hz, jobs, plan, &done, &mut progress) {
        return results;
    }
    let scene = first.protocol.scene();
    let untrained = Mutex::new(untrained);
    run_jobs(
        jobs,
        plan.workers(),
        || plan.start(scene),
        |job, worker| {
            let result = push_job(worker, &untrained, job, rate_hz, plan)?;
            done(&result)?;
            Ok(result)
        },
        progress,
    )
}

/// [`push_jobs`] in the plan's worker processes, each building the model
/// from the plan's recipe: no model is built in this process. `None` when
/// the plan runs jobs of `rate_hz` here.
///
/// # Errors
/// As [`push_jobs`].
pub fn push_jobs_in_workers(
    rate_hz: u32,
    jobs: &[PushJob],
    plan: &Plan,
    done: impl Fn(&PushJobResult) -> Result<(), ExperimentError> + Sync,
    progress: impl FnMut(usize),
) -> Option<Result<Vec<PushJobResult>, ExperimentError>> {
    let (processes, recipe, workers) = plan.worker_processes_for(rate_hz)?;
    if jobs.is_empty() {
        return Some(Ok(Vec::new()));
    }
    Some(processes.push_jobs(recipe, jobs, plan, workers, done, progress))
}

/// Runs one push-task job on `worker`'s world (retried once on a new world
/// if the world process dies).
pub(crate) fn push_job<M: Model>(
    worker: &mut Worker,
    untrained: &Mutex<M>,
    job: &PushJob,
    rate_hz: u32,
    plan: &Plan,
) -> Result<PushJobResult, ExperimentError> {
    let scene = job.protocol.scene();
    let (task, timing, counters) = plan.retrying(worker, scene, |worker| {
        run_job(
            worker,
            untrained,
            PushJobTask::new(job),
            rate_hz,
            plan.job_setup(job.latency_seed),
            Fold {
                seed: job.seed,
                name: job.name(),
            },
        )
    })?;
    PushJobResult::from_task(job, task, counters, timing)
}

/// The push task's report from its jobs' results (in any order): the
/// learning curve of every N_train of `train_runs`, and a [`RunInfo`]
/// without timing (the caller that timed the run replaces it).
///
/// # Errors
/// An N_train without results, or a block without errors.
pub fn push_report(
    setup: Setup,
    protocol: &Protocol,
    train_runs: &[usize],
    folds: usize,
    results: &[PushJobResult],
) -> Result<PushReport, ExperimentError> {
    let variant = protocol.variant;
    Ok(PushReport {
        setup,
        variant: variant.as_str().to_owned(),
        transfer: protocol.transfer.clone(),
        folds,
        train_runs: train_runs.to_vec(),
        results: summarise(
            &protocol.test_positions,
            variant.blocks(),
            train_runs,
            results,
        )?,
        run: RunInfo::of(
            results.iter().map(|r| (r.counters, r.timing)),
            RATE_HZ,
            1,
            0.0,
        )
        .without_timing(),
    })
}

/// Generalisation with constant feedback (`docs/spec/experiments.md` §3.4): one job
/// with both test runs, at 10 Hz. `untrained` must use the 10 Hz thresholds.
///
/// # Errors
/// The job failed.
pub fn constant_feedback<M: Model>(
    untrained: M,
    plan: &Plan,
) -> Result<FeedbackReport, ExperimentError> {
    let started = plan.started();
    let seed_of =
        |stream| super::seed::derive(plan.seed, super::constant_feedback::EXPERIMENT, &[], stream);
    let jobs = [seed_of(super::seed::Stream::Latency)];
    let driver_seed = seed_of(super::seed::Stream::Driver);
    let untrained = Mutex::new(untrained);
    let mut results = run_jobs(
        &jobs,
        1,
        || plan.start(Variant::ConstantFeedback.scene()),
        |&latency_seed, worker| {
            plan.retrying(worker, Variant::ConstantFeedback.scene(), |worker| {
                run_job(
                    worker,
                    &untrained,
                    FeedbackTask::new(Variant::ConstantFeedback.test_positions()),
                    LOW_RATE_HZ,
                    plan.job_setup(latency_seed),
                    Fold {
                        seed: driver_seed,
                        name: "the constant-feedback job".to_owned(),
                    },
                )
            })
        },
        |_| {},
    )?;
    let (task, timing, counters) = results.pop().ok_or(ExperimentError::JobLost { index: 0 })?;
    Ok(FeedbackReport {
        setup: plan.setup(crate::results::push_task::EXPERIMENT),
        variant: Variant::ConstantFeedback.as_str().to_owned(),
        publish_rate_hz: LOW_RATE_HZ,
        runs: task.runs,
        run: plan.run_info(&started, [(counters, timing)], LOW_RATE_HZ, 1),
    })
}

/// Move to Target (`docs/spec/experiments.md` §4).
///
/// # Errors
/// The first failing job.
pub fn move_to_target<M: Model>(
    untrained: M,
    targets: &[ObjectState],
    repetitions: usize,
    max_steps: u64,
    plan: &Plan,
    progress: impl FnMut(usize),
) -> Result<MttReport, ExperimentError> {
    let started = plan.started();
    let jobs = MttJob::all(targets, repetitions, max_steps, plan.seed);
    let results = match plan.worker_processes() {
        Some((processes, recipe, workers)) if recipe.publish_rate_hz() == RATE_HZ => {
            processes.mtt_jobs(recipe, &jobs, plan, workers, progress)?
        }
        _ => {
            let untrained = Mutex::new(untrained);
            run_jobs(
                &jobs,
                plan.workers(),
                || plan.start("one_block"),
                |job, worker| mtt_job(worker, &untrained, job, plan),
                progress,
            )?
        }
    };
    let entries = targets
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mine: Vec<&MttJobResult> = results.iter().filter(|r| r.target_index == i).collect();
            let runs: Vec<_> = mine.iter().map(|r| r.run.clone()).collect();
            let nodes: Vec<&learner::ModelStats> =
                mine.iter().map(|r| &r.nodes_after_training).collect();
            TargetEntry {
                target: t.to_array(),
                summary: TargetSummary::of(&runs),
                runs,
                nodes_after_training: NodeSummary::of(&nodes),
            }
        })
        .collect();
    Ok(MttReport {
        setup: plan.setup(crate::results::move_to_target::EXPERIMENT),
        repetitions,
        max_steps,
        targets: entries,
        training_starts: crate::experiment::move_to_target::TRAINING_RUNS
            .iter()
            .map(|&((x, y), _)| [x, y])
            .collect(),
        run: plan.run_info(
            &started,
            results.iter().map(|r| (r.counters, r.timing)),
            RATE_HZ,
            plan.job_workers(RATE_HZ).min(jobs.len()),
        ),
    })
}

/// Runs one Move to Target job on `worker`'s world (retried once on a new
/// world if the world process dies).
pub(crate) fn mtt_job<M: Model>(
    worker: &mut Worker,
    untrained: &Mutex<M>,
    job: &MttJob,
    plan: &Plan,
) -> Result<MttJobResult, ExperimentError> {
    let (task, timing, counters) = plan.retrying(worker, "one_block", |worker| {
        run_job(
            worker,
            untrained,
            MttTask::new(job),
            RATE_HZ,
            plan.job_setup(job.latency_seed),
            Fold {
                seed: job.seed,
                name: job.name(),
            },
        )
    })?;
    MttJobResult::from_task(job, task, counters, timing)
}
