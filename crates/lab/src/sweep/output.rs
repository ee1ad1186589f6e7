//! A sweep's output directory:
//!
//! ```text
//! DIR/sweep.toml           the plan last run or submitted into DIR (merge reads it)
//! DIR/jobs/ID.json         one finished job: its parameters, setup and result
//! DIR/timing/ID.json       its handling times (machine-dependent; not merged)
//! DIR/slurm/submit-N.*     each submission's script, job list, plan and logs
//! DIR/merged/              what `pushlearn sweep merge` writes
//! ```
//!
//! A job file is written whole under a temporary name and renamed
//! ([`drive::output::write_atomically`]): a preempted or killed task leaves
//! no half file, only a `*.partial` one that nothing reads. A job is done
//! when its file exists, which is what resuming skips.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{Job, Sweep};
use drive::results::push_task::PushJobResult;
use drive::results::run_info::Timing;
use drive::results::Setup;

/// The plan's copy in an output directory.
pub const PLAN: &str = "sweep.toml";
/// Finished jobs.
pub const JOBS: &str = "jobs";
/// Their timing.
pub const TIMING: &str = "timing";
/// Slurm submissions.
pub const SLURM: &str = "slurm";
/// Merged reports.
pub const MERGED: &str = "merged";

/// What a finished job leaves in `DIR/jobs/ID.json`. Everything in it is a
/// function of the job's parameters (its timing is in `DIR/timing/`), so a
/// job run twice, anywhere, writes the same bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JobOutput {
    pub id: String,
    /// The configuration's options ([`super::Configuration::canonical`]).
    pub configuration: String,
    pub seed: u64,
    pub n_train: usize,
    pub fold: usize,
    /// The report's setup as the job ran it (the model's name, mode, seed).
    pub setup: Setup,
    /// The job's result, its timing zeroed but for the message count (a
    /// function of the job, which the report's `run` counts).
    pub result: PushJobResult,
}

/// Why a job's output cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum JobFileError {
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{} is not a job output: {why}", path.display())]
    Parse { path: PathBuf, why: String },
    #[error("{} belongs to another plan: it holds {found}, the plan's job {id} is {wanted}", path.display())]
    Mismatch {
        path: PathBuf,
        id: String,
        found: String,
        wanted: String,
    },
    #[error("cannot write {}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The path of job `id`'s output under `dir`.
#[must_use]
pub fn job_path(dir: &Path, id: &str) -> PathBuf {
    dir.join(JOBS).join(format!("{id}.json"))
}

impl JobOutput {
    /// The output of `job` of `sweep`.
    #[must_use]
    pub fn new(sweep: &Sweep, job: &Job, setup: Setup, result: &PushJobResult) -> Self {
        let mut result = result.clone();
        result.timing = Timing {
            messages: result.timing.messages,
            ..Timing::default()
        };
        Self {
            id: job.id.clone(),
            configuration: sweep.configurations[job.configuration].canonical(),
            seed: job.seed,
            n_train: job.n_train,
            fold: job.fold,
            setup,
            result,
        }
    }

    /// What identifies the job, for [`JobFileError::Mismatch`].
    fn parameters(&self) -> String {
        format!(
            "`{}` seed {} N_train {} fold {}",
            self.configuration, self.seed, self.n_train, self.fold
        )
    }

    /// Writes the output (and `timing` beside it) into `dir`, atomically.
    ///
    /// # Errors
    /// A file cannot be written.
    pub fn write(&self, dir: &Path, timing: &Timing) -> Result<(), JobFileError> {
        let write = |path: PathBuf, text: Result<String, serde_json::Error>| {
            let text = text.map_err(|e| JobFileError::Write {
                path: path.clone(),
                source: std::io::Error::other(e),
            })?;
            drive::output::write_atomically(&path, text.as_bytes())
                .map_err(|source| JobFileError::Write { path, source })
        };
        // The timing first: a job counts as done once its output exists.
        write(
            dir.join(TIMING).join(format!("{}.json", self.id)),
            serde_json::to_string(timing),
        )?;
        write(
            job_path(dir, &self.id),
            serde_json::to_string(self).map(|t| t + "\n"),
        )
    }

    /// Reads job `job` of `sweep` back from `dir`, checking that the file
    /// is that job's.
    ///
    /// # Errors
    /// Unreadable, not a job output, or another job's.
    pub fn read(dir: &Path, sweep: &Sweep, job: &Job) -> Result<Self, JobFileError> {
        let path = job_path(dir, &job.id);
        let text = std::fs::read_to_string(&path).map_err(|source| JobFileError::Read {
            path: path.clone(),
            source,
        })?;
        let output: Self = serde_json::from_str(&text).map_err(|e| JobFileError::Parse {
            path: path.clone(),
            why: e.to_string(),
        })?;
        let wanted = Self {
            id: job.id.clone(),
            configuration: sweep.configurations[job.configuration].canonical(),
            seed: job.seed,
            n_train: job.n_train,
            fold: job.fold,
            ..output.clone()
        };
        if output != wanted {
            return Err(JobFileError::Mismatch {
                path,
                id: job.id.clone(),
                found: output.parameters(),
                wanted: wanted.parameters(),
            });
        }
        Ok(output)
    }
}

/// The jobs of `jobs` whose output is not in `dir` yet, in order.
#[must_use]
pub fn pending<'a>(dir: &Path, jobs: &'a [Job]) -> Vec<&'a Job> {
    jobs.iter()
        .filter(|job| !job_path(dir, &job.id).is_file())
        .collect()
}

/// Why a sweep cannot be merged yet.
#[derive(Debug, thiserror::Error)]
#[error("{} of the plan's {total} jobs have no output in {}: {}{}\nrun only those with `{resume}` (both skip the jobs already done), or `pushlearn sweep slurm {} --out {} --only ID,…`",
    missing.len(), dir.display(), shown(missing), more(missing), plan.display(), dir.display())]
pub struct Incomplete {
    pub dir: PathBuf,
    pub plan: PathBuf,
    pub total: usize,
    pub missing: Vec<String>,
    /// The commands that finish the set.
    pub resume: String,
}

const SHOWN: usize = 20;

fn shown(missing: &[String]) -> String {
    missing
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ")
}

fn more(missing: &[String]) -> String {
    if missing.len() > SHOWN {
        format!(
            " and {} more (all in {}/missing.txt)",
            missing.len() - SHOWN,
            MERGED
        )
    } else {
        String::new()
    }
}

/// Checks that every job of `sweep` has its output in `dir`.
///
/// # Errors
/// [`Incomplete`], naming the missing jobs and how to run only them.
pub fn complete(dir: &Path, sweep: &Sweep) -> Result<(), Incomplete> {
    let jobs = sweep.jobs();
    let missing: Vec<String> = pending(dir, &jobs)
        .into_iter()
        .map(|j| j.id.clone())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let plan = dir.join(PLAN);
    Err(Incomplete {
        dir: dir.to_owned(),
        resume: format!(
            "pushlearn sweep run {p} --out {d}` or `pushlearn sweep slurm {p} --out {d}",
            p = plan.display(),
            d = dir.display()
        ),
        plan,
        total: jobs.len(),
        missing,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use drive::results::run_info::Counters;

    fn sweep() -> Sweep {
        let known = ["model".to_owned()];
        Sweep::parse(
            "folds = 2\ntrain-runs = [1]\n[[grid]]\nmodel = [\"gate\", \"interaction\"]",
            &known,
        )
        .unwrap()
    }

    fn result(job: &Job) -> PushJobResult {
        PushJobResult {
            n_train: job.n_train,
            fold: job.fold,
            training_starts: vec![0.1],
            errors: Vec::new(),
            end_poses: Vec::new(),
            nodes: learner::ModelStats::default(),
            counters: Counters::default(),
            timing: Timing::default(),
            keypoints: Vec::new(),
            selection: Default::default(),
        }
    }

    fn temp(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("pushlearn-sweep-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join(JOBS)).unwrap();
        std::fs::create_dir_all(dir.join(TIMING)).unwrap();
        dir
    }

    #[test]
    fn outputs_are_written_whole_read_back_and_checked_against_the_plan() {
        let dir = temp("roundtrip");
        let sweep = sweep();
        let jobs = sweep.jobs();
        let setup = Setup::for_tests("push-task", "gate");
        let timed = Timing {
            busy_seconds: 1.5,
            messages: 7,
            ..Timing::default()
        };
        let mut with_timing = result(&jobs[0]);
        with_timing.timing = timed;
        let output = JobOutput::new(&sweep, &jobs[0], setup.clone(), &with_timing);
        output.write(&dir, &timed).unwrap();
        let back = JobOutput::read(&dir, &sweep, &jobs[0]).unwrap();
        assert_eq!(back, output);
        assert_eq!(back.result.timing.messages, 7, "the message count is kept");
        assert_eq!(
            back.result.timing,
            Timing {
                messages: 7,
                ..Timing::default()
            },
            "no timing in the job file"
        );
        let names: Vec<String> = std::fs::read_dir(dir.join(JOBS))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            names,
            [format!("{}.json", jobs[0].id)],
            "no temporary file is left"
        );
        // Another job's file under this job's name is refused.
        let other = JobOutput::new(&sweep, &jobs[1], setup, &result(&jobs[1]));
        std::fs::write(
            job_path(&dir, &jobs[0].id),
            serde_json::to_string(&other).unwrap(),
        )
        .unwrap();
        let err = JobOutput::read(&dir, &sweep, &jobs[0])
            .unwrap_err()
            .to_string();
        assert!(err.contains("belongs to another plan"), "{err}");
        std::fs::write(job_path(&dir, &jobs[0].id), "{\"id\": ").unwrap();
        let err = JobOutput::read(&dir, &sweep, &jobs[0])
            .unwrap_err()
            .to_string();
        assert!(err.contains("is not a job output"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_incomplete_set_is_refused_naming_the_missing_jobs_and_the_resume_command() {
        let dir = temp("incomplete");
        let sweep = sweep();
        let jobs = sweep.jobs();
        assert_eq!(pending(&dir, &jobs).len(), 4);
        for job in &jobs[..3] {
            JobOutput::new(
                &sweep,
                job,
                Setup::for_tests("push-task", "gate"),
                &result(job),
            )
            .write(&dir, &Timing::default())
            .unwrap();
        }
        // A half-written file under the temporary name is not an output.
        std::fs::write(
            dir.join(JOBS)
                .join(format!("{}.json.1.partial", jobs[3].id)),
            "{",
        )
        .unwrap();
        let pending: Vec<&str> = pending(&dir, &jobs).iter().map(|j| j.id.as_str()).collect();
        assert_eq!(pending, [jobs[3].id.as_str()]);
        let err = complete(&dir, &sweep).unwrap_err();
        assert_eq!(err.missing, [jobs[3].id.clone()]);
        let text = err.to_string();
        assert!(
            text.starts_with(&format!(
                "1 of the plan's 4 jobs have no output in {}: {}",
                dir.display(),
                jobs[3].id
            )),
            "{text}"
        );
        assert!(text.contains("pushlearn sweep slurm"), "{text}");
        JobOutput::new(
            &sweep,
            &jobs[3],
            Setup::for_tests("push-task", "gate"),
            &result(&jobs[3]),
        )
        .write(&dir, &Timing::default())
        .unwrap();
        complete(&dir, &sweep).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
