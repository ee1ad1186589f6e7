//! Worker processes for embedded worlds: one per core, each stepping its own
//! worlds with the model beside it.
//!
//! ODE steps one world at a time per process (`ode::World::step` holds a
//! process-wide lock, because QuickStep shuffles constraint rows with ODE's
//! single random generator), so embedded worlds in threads of one process
//! take turns, and a second thread only adds hand-overs. Work on several
//! cores therefore needs several processes. The experiment's process starts
//! copies of its own program (the `pushlearn` binary's hidden
//! `experiment-worker` command, which calls [`serve`]), sends each one job at
//! a time as a JSON line ([`JobRequest`]) and gathers the results in job
//! order. The worker rebuilds the untrained model from its [`Recipe`] and the
//! job carries its seeds, so a job's result is the one it has in-process.
//!
//! A worker keeps its worlds between jobs, and a run cache of its own for
//! each run cache of the experiment's process. A job that ran in a worker
//! before (the other model of a pair: the same seeds, so the same pushes)
//! goes back to that worker, where its recorded runs replay.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex, PoisonError};

use learner::registry::{ModelKind, ModelOptions, WithModel};
use learner::Model;
use serde::{Deserialize, Serialize};

use super::move_to_target::MttJob;
use super::push_task::protocol::PushJob;
use super::run::{mtt_job, push_job, Plan};
use super::run_cache::{CacheCounts, RunCache};
use super::workers::{in_job_order, Worker, WorldSource};
use super::{ExperimentError, Mode};
use crate::external::{ExternalModel, LearnerSpec};
use crate::latency::Latencies;
use crate::oracle::{Oracle, OracleLatency};
use crate::results::move_to_target::MttJobResult;
use crate::results::push_task::PushJobResult;
use crate::results::run_info::Timing;

/// The learner as a worker process makes it: a built-in model from its
/// kind and options, or an external learner started beside the worker.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Recipe {
    Builtin {
        kind: ModelKind,
        options: ModelOptions,
        /// The rate its thresholds are for.
        publish_rate_hz: u32,
    },
    External {
        spec: LearnerSpec,
        /// The task it must be able to run (the protocol's Start).
        task: String,
        publish_rate_hz: u32,
    },
    /// An oracle ([`crate::oracle::Oracle`]) of `scene`, its world's
    /// latency emulation delaying a Move by at most `latency_max` steps.
    Oracle {
        scene: String,
        publish_rate_hz: u32,
        latency: OracleLatency,
        latency_max: u32,
    },
}

impl Recipe {
    /// The publish rate the learner is made for.
    #[must_use]
    pub fn publish_rate_hz(&self) -> u32 {
        match self {
            Recipe::Builtin {
                publish_rate_hz, ..
            }
            | Recipe::External {
                publish_rate_hz, ..
            }
            | Recipe::Oracle {
                publish_rate_hz, ..
            } => *publish_rate_hz,
        }
    }
}

/// The world a job runs on, and which of the experiment process's run
/// caches it may reuse runs of (`None`: no reuse).
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
struct WorldRequest {
    scene: String,
    mode: Mode,
    latency_max: u32,
    cache: Option<u64>,
}

/// A job a worker process can run.
#[derive(Clone, Debug, Serialize, Deserialize)]
enum Job {
    Push(PushJob),
    MoveToTarget(MttJob),
}

impl Job {
    fn name(&self) -> String {
        match self {
            Job::Push(job) => job.name(),
            Job::MoveToTarget(job) => job.name(),
        }
    }

    /// What makes its runs: with the world, which worker may replay them.
    fn seeds(&self) -> (u64, u64) {
        match self {
            Job::Push(job) => (job.seed, job.latency_seed),
            Job::MoveToTarget(job) => (job.seed, job.latency_seed),
        }
    }
}

/// A finished [`Job`].
#[derive(Clone, Debug, Serialize, Deserialize)]
enum Finished {
    Push(PushJobResult),
    MoveToTarget(MttJobResult),
}

impl Finished {
    fn timing(&mut self) -> &mut Timing {
        match self {
            Finished::Push(result) => &mut result.timing,
            Finished::MoveToTarget(result) => &mut result.timing,
        }
    }
}

/// One job for a worker process.
#[derive(Debug, Serialize, Deserialize)]
pub struct JobRequest {
    recipe: Recipe,
    world: WorldRequest,
    job: Job,
}

/// A worker process's answer to a [`JobRequest`].
#[derive(Debug, Serialize, Deserialize)]
enum JobResponse {
    Done {
        result: Box<Finished>,
        /// The result's handling times, which its own serialisation leaves out.
        histogram: Box<Latencies>,
        /// What the worker's run cache did for the job.
        cache: CacheCounts,
    },
    Failed {
        error: String,
    },
}

/// The worker processes of an experiment program, started when first
/// needed and kept for its life (with their worlds and recorded runs).
#[derive(Debug)]
pub struct Processes {
    program: PathBuf,
    args: Vec<String>,
    slots: Vec<Mutex<Option<WorkerProcess>>>,
    /// Which worker ran a job before, by the job's world and seeds.
    affinity: Mutex<HashMap<(WorldRequest, u64, u64), usize>>,
}

impl Processes {
    /// Up to `size` workers, each `program args…` (a program whose command
    /// calls [`serve`] on its stdin and stdout).
    #[must_use]
    pub fn new(program: PathBuf, args: Vec<String>, size: usize) -> Self {
        Self {
            program,
            args,
            slots: (0..size.max(1)).map(|_| Mutex::new(None)).collect(),
            affinity: Mutex::default(),
        }
    }

    /// How many workers there can be.
    #[must_use]
    pub fn size(&self) -> usize {
        self.slots.len()
    }

    /// Runs push-task `jobs` of `recipe`'s model on up to `workers` worker
    /// processes and returns their results in job order; `done` and
    /// `progress` as in [`super::run::push_jobs`], `done` with each result
    /// as it arrives, `progress` on the calling thread.
    pub(crate) fn push_jobs(
        &self,
        recipe: &Recipe,
        jobs: &[PushJob],
        plan: &Plan,
        workers: usize,
        done: impl Fn(&PushJobResult) -> Result<(), ExperimentError> + Sync,
        progress: impl FnMut(usize),
    ) -> Result<Vec<PushJobResult>, ExperimentError> {
        let scene = jobs.first().map_or("", |j| j.protocol.scene());
        let jobs: Vec<Job> = jobs.iter().cloned().map(Job::Push).collect();
        let finished = self.run(
            recipe,
            scene,
            &jobs,
            plan,
            workers,
            |finished| match finished {
                Finished::Push(result) => done(result),
                Finished::MoveToTarget(_) => Ok(()),
            },
            progress,
        )?;
        finished
            .into_iter()
            .zip(&jobs)
            .map(|(finished, job)| match finished {
                Finished::Push(result) => Ok(result),
                Finished::MoveToTarget(_) => Err(mixed_up(job)),
            })
            .collect()
    }

    /// Runs Move to Target `jobs` like [`Self::push_jobs`].
    pub(crate) fn mtt_jobs(
        &self,
        recipe: &Recipe,
        jobs: &[MttJob],
        plan: &Plan,
        workers: usize,
        progress: impl FnMut(usize),
    ) -> Result<Vec<MttJobResult>, ExperimentError> {
        let jobs: Vec<Job> = jobs.iter().cloned().map(Job::MoveToTarget).collect();
        let finished = self.run(
            recipe,
            "one_block",
            &jobs,
            plan,
            workers,
            |_| Ok(()),
            progress,
        )?;
        finished
            .into_iter()
            .zip(&jobs)
            .map(|(finished, job)| match finished {
                Finished::MoveToTarget(result) => Ok(result),
                Finished::Push(_) => Err(mixed_up(job)),
            })
            .collect()
    }

    #[allow(clippy::too_many_arguments)] // `push_jobs`' and `mtt_jobs`' one body
    fn run(
        &self,
        recipe: &Recipe,
        scene: &str,
        jobs: &[Job],
        plan: &Plan,
        workers: usize,
        done: impl Fn(&Finished) -> Result<(), ExperimentError> + Sync,
        progress: impl FnMut(usize),
    ) -> Result<Vec<Finished>, ExperimentError> {
        let workers = workers.clamp(1, self.size()).min(jobs.len().max(1));
        let world = WorldRequest {
            scene: scene.to_owned(),
            mode: plan.mode,
            latency_max: plan.latency_max,
            cache: plan.cache_id(),
        };
        let key = |job: &Job| {
            let (seed, latency_seed) = job.seeds();
            (world.clone(), seed, latency_seed)
        };
        let claimed = Mutex::new(vec![false; jobs.len()]);
        let stop = AtomicBool::new(false);
        let (sender, results) = mpsc::channel::<Result<(usize, Finished), ExperimentError>>();
        std::thread::scope(|scope| {
            for id in 0..workers {
                let sender = sender.clone();
                let (claimed, stop, done, key, world) = (&claimed, &stop, &done, &key, &world);
                scope.spawn(move || {
                    let mut slot = self.slots[id]
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner);
                    while !stop.load(Ordering::SeqCst) {
                        let Some(index) = self.next_job(id, workers, jobs, claimed, key) else {
                            break;
                        };
                        let request = JobRequest {
                            recipe: recipe.clone(),
                            world: world.clone(),
                            job: jobs[index].clone(),
                        };
                        let result = self.ask(&mut slot, &request).and_then(|(result, counts)| {
                            if let Some(cache) = plan.cache() {
                                cache.count_elsewhere(counts);
                            }
                            done(&result)?;
                            Ok(result)
                        });
                        if result.is_err() {
                            stop.store(true, Ordering::SeqCst);
                        }
                        if sender.send(result.map(|r| (index, r))).is_err() {
                            break;
                        }
                    }
                });
            }
            drop(sender);
            in_job_order(jobs.len(), results, progress)
        })
    }

    /// The next job for worker `id` of `workers`: one it ran before, else
    /// one no worker in use ran before (which becomes its own). Jobs another
    /// worker ran before wait for that worker, whose recorded runs replay
    /// them.
    fn next_job(
        &self,
        id: usize,
        workers: usize,
        jobs: &[Job],
        claimed: &Mutex<Vec<bool>>,
        key: impl Fn(&Job) -> (WorldRequest, u64, u64),
    ) -> Option<usize> {
        let mut claimed = claimed.lock().unwrap_or_else(PoisonError::into_inner);
        let mut affinity = self.affinity.lock().unwrap_or_else(PoisonError::into_inner);
        let open = || (0..jobs.len()).filter(|&i| !claimed[i]);
        let index = open()
            .find(|&i| affinity.get(&key(&jobs[i])) == Some(&id))
            .or_else(|| {
                open().find(|&i| {
                    affinity
                        .get(&key(&jobs[i]))
                        .is_none_or(|&other| other >= workers)
                })
            })?;
        claimed[index] = true;
        affinity.insert(key(&jobs[index]), id);
        Some(index)
    }

    /// Sends `request` to the worker in `slot` (started if there is none)
    /// and waits for its answer. A worker that dies is forgotten, so that
    /// the next experiment starts a new one.
    fn ask(
        &self,
        slot: &mut Option<WorkerProcess>,
        request: &JobRequest,
    ) -> Result<(Finished, CacheCounts), ExperimentError> {
        let job = request.job.name();
        let worker = match slot {
            Some(worker) => worker,
            None => slot.insert(WorkerProcess::start(&self.program, &self.args)?),
        };
        match worker.ask(request) {
            Ok(JobResponse::Done {
                result,
                histogram,
                cache,
            }) => {
                let mut result = *result;
                result.timing().histogram = *histogram;
                Ok((result, cache))
            }
            Ok(JobResponse::Failed { error }) => Err(ExperimentError::InWorker(error)),
            Err(why) => {
                let status = worker.end();
                *slot = None;
                Err(ExperimentError::WorkerDied {
                    job,
                    why: format!("{why} ({status})"),
                })
            }
        }
    }
}

/// A worker that answered `job` with the other kind's result.
fn mixed_up(job: &Job) -> ExperimentError {
    ExperimentError::InWorker(format!(
        "{}: the worker process answered with another kind of job's result",
        job.name()
    ))
}

/// One running worker process.
#[derive(Debug)]
struct WorkerProcess {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl WorkerProcess {
    fn start(program: &PathBuf, args: &[String]) -> Result<Self, ExperimentError> {
        let command = || format!("{} {}", program.display(), args.join(" "));
        let spawn_error = |reason: String| ExperimentError::Spawn {
            command: command(),
            reason,
        };
        let mut child = Command::new(program)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|err| spawn_error(err.to_string()))?;
        let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(spawn_error("its stdin and stdout were not piped".into()));
        };
        tracing::debug!(pid = child.id(), "worker process started");
        Ok(Self {
            child,
            stdin,
            stdout: BufReader::new(stdout),
        })
    }

    fn ask(&mut self, request: &JobRequest) -> Result<JobResponse, String> {
        let mut line = serde_json::to_vec(request).map_err(|e| e.to_string())?;
        line.push(b'\n');
        self.stdin
            .write_all(&line)
            .and_then(|()| self.stdin.flush())
            .map_err(|err| format!("did not take the job: {err}"))?;
        let mut answer = String::new();
        match self.stdout.read_line(&mut answer) {
            Ok(0) => Err("ended without answering".into()),
            Ok(_) => serde_json::from_str(&answer)
                .map_err(|err| format!("answered something unreadable: {err}")),
            Err(err) => Err(format!("could not be read: {err}")),
        }
    }

    /// How the process ended, after the conversation broke: its exit
    /// status if it ends within a second, else it is killed.
    fn end(&mut self) -> String {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(1);
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return status.to_string(),
                Ok(None) if std::time::Instant::now() < deadline => {
                    std::thread::sleep(std::time::Duration::from_millis(10));
                }
                Ok(None) => {
                    let _ = self.child.kill();
                    let _ = self.child.wait();
                    return "it was still running and was killed".into();
                }
                Err(err) => return format!("exit status unknown: {err}"),
            }
        }
    }
}

impl Drop for WorkerProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A worker process's loop: reads [`JobRequest`]s, one JSON line each, from
/// `input`, runs each on an embedded world and answers on `output`, until
/// `input` ends. A job that fails is answered with its error, and the
/// worker goes on.
///
/// # Errors
/// Reading `input` or writing `output` failed.
pub fn serve(input: impl BufRead, mut output: impl Write) -> std::io::Result<()> {
    let mut kept = Kept::default();
    for line in input.lines() {
        let line = line?;
        let response = match serde_json::from_str::<JobRequest>(&line) {
            Ok(request) => kept.run(request).unwrap_or_else(|err| JobResponse::Failed {
                error: err.to_string(),
            }),
            Err(err) => JobResponse::Failed {
                error: format!("a job the worker process cannot read: {err}"),
            },
        };
        serde_json::to_writer(&mut output, &response)?;
        output.write_all(b"\n")?;
        output.flush()?;
    }
    Ok(())
}

/// What a worker process keeps between jobs: its worlds (with their run
/// caches) and the external learners it started.
#[derive(Default)]
struct Kept {
    worlds: HashMap<WorldRequest, (Plan, Worker)>,
    /// By their recipe's JSON; each job gets a fresh handle (a clone).
    learners: HashMap<String, ExternalModel>,
}

impl Kept {
    fn run(&mut self, request: JobRequest) -> Result<JobResponse, ExperimentError> {
        let (plan, worker) = match self.worlds.entry(request.world.clone()) {
            std::collections::hash_map::Entry::Occupied(entry) => entry.into_mut(),
            std::collections::hash_map::Entry::Vacant(entry) => {
                let world = entry.key();
                let plan = Plan {
                    mode: world.mode,
                    latency_max: world.latency_max,
                    workers: 1,
                    source: WorldSource::embedded(world.mode, &world.scene, world.latency_max)?,
                    seed: 0,
                    model: String::new(),
                    learner: None,
                    runs: world.cache.map(|_| Arc::new(RunCache::new())),
                    processes: None,
                    recipe: None,
                };
                let worker = plan.start(&world.scene)?;
                entry.insert((plan, worker))
            }
        };
        let before = plan.cache().map(|c| c.counts()).unwrap_or_default();
        let rate_hz = request.recipe.publish_rate_hz();
        let job = OneJob {
            job: &request.job,
            rate_hz,
            plan,
            worker,
        };
        let mut result = match &request.recipe {
            Recipe::Builtin { kind, options, .. } => kind
                .dispatch(options, rate_hz, job)
                .map_err(|err| ExperimentError::InWorker(err.to_string()))??,
            Recipe::Oracle {
                scene,
                latency,
                latency_max,
                ..
            } => job.run(
                Oracle::new(scene, rate_hz, *latency, *latency_max)
                    .map_err(|err| ExperimentError::InWorker(err.to_string()))?,
            )?,
            Recipe::External { spec, task, .. } => {
                let key = serde_json::to_string(&request.recipe)
                    .map_err(|err| ExperimentError::InWorker(err.to_string()))?;
                let learner = match self.learners.entry(key) {
                    std::collections::hash_map::Entry::Occupied(entry) => entry.into_mut(),
                    std::collections::hash_map::Entry::Vacant(entry) => entry.insert(
                        ExternalModel::connect(spec, task, rate_hz)
                            .map_err(|err| ExperimentError::InWorker(err.to_string()))?,
                    ),
                };
                job.run(learner.clone())?
            }
        };
        let after = plan.cache().map(|c| c.counts()).unwrap_or_default();
        let histogram = std::mem::take(&mut result.timing().histogram);
        Ok(JobResponse::Done {
            result: Box::new(result),
            histogram: Box::new(histogram),
            cache: CacheCounts {
                replayed: after.replayed - before.replayed,
                simulated: after.simulated - before.simulated,
            },
        })
    }
}

/// One job with the model a [`Recipe`] built.
struct OneJob<'a> {
    job: &'a Job,
    rate_hz: u32,
    plan: &'a Plan,
    worker: &'a mut Worker,
}

impl WithModel for OneJob<'_> {
    type Output = Result<Finished, ExperimentError>;
    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        let untrained = Mutex::new(untrained);
        Ok(match self.job {
            Job::Push(job) => Finished::Push(push_job(
                self.worker,
                &untrained,
                job,
                self.rate_hz,
                self.plan,
            )?),
            Job::MoveToTarget(job) => {
                Finished::MoveToTarget(mtt_job(self.worker, &untrained, job, self.plan)?)
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::push_task::protocol::{Protocol, Variant};

    fn plan() -> Plan {
        let scene = Variant::Random.scene();
        Plan {
            mode: Mode::Lockstep,
            latency_max: 0,
            workers: 2,
            source: WorldSource::embedded(Mode::Lockstep, scene, 0).expect("lock-step"),
            seed: 1,
            model: "gate".into(),
            learner: None,
            runs: None,
            processes: None,
            recipe: None,
        }
    }

    /// Runs two jobs on two "workers" that are shell scripts.
    fn run_on(script: &str) -> ExperimentError {
        let processes = Processes::new("sh".into(), vec!["-c".into(), script.into()], 2);
        let jobs = PushJob::all(Protocol::from(Variant::Random), &[1], 2, 1);
        let recipe = Recipe::Builtin {
            kind: ModelKind::Gate,
            options: ModelOptions::default(),
            publish_rate_hz: 100,
        };
        processes
            .push_jobs(&recipe, &jobs, &plan(), 2, |_| Ok(()), |_| {})
            .expect_err("the workers fail")
    }

    #[test]
    fn a_worker_that_dies_is_named_with_its_job_and_exit_status() {
        let err = run_on("read job; exit 3").to_string();
        assert!(err.starts_with("N_train 1 fold "), "{err}");
        assert!(
            err.contains("the worker process ended without answering"),
            "{err}"
        );
        assert!(err.contains("exit status: 3"), "{err}");
    }

    #[test]
    fn a_worker_that_answers_nonsense_is_refused() {
        let err = run_on("read job; echo nonsense; sleep 30").to_string();
        assert!(err.contains("answered something unreadable"), "{err}");
        assert!(err.contains("it was still running and was killed"), "{err}");
    }

    #[test]
    fn a_worker_answers_an_unreadable_job_and_waits_for_the_next() {
        let mut out = Vec::new();
        serve("not a job\n{\"also\": \"not\"}\n".as_bytes(), &mut out).expect("serve");
        let answers: Vec<JobResponse> = String::from_utf8(out)
            .expect("UTF-8")
            .lines()
            .map(|line| serde_json::from_str(line).expect("an answer"))
            .collect();
        assert_eq!(answers.len(), 2);
        for answer in answers {
            let JobResponse::Failed { error } = answer else {
                panic!("a failure, not {answer:?}");
            };
            assert!(
                error.starts_with("a job the worker process cannot read"),
                "{error}"
            );
        }
    }
}
