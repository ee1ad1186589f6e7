//! A soak of the whole system (`pushlearn ctl soak`): a learning, acting
//! `pushlearn learn --state DIR` against a realtime world while many
//! subscribers read every state, for as long as asked. It samples the
//! learner's resident memory and its state directory (journal and
//! snapshots) every few seconds, and the world's memory through the load
//! run beside it ([`crate::load`]); at the end it stops the learner with
//! SIGTERM, as an operator would, and reads its `--json` report: how many
//! states it handled and how many it missed (`docs/reliability.md`, "Soak").
//! Its figure is [`figure`].

pub mod figure;

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::learn::state::{on_disk, OnDisk};
use crate::learn::StopReport;
use crate::load::{rss_kib, run_load, sample_until, LoadOptions, LoadReport};
use crate::process::{kill_group, signal};

/// The learner's target: the README's first-hour pose of the blue block.
/// Each attempt ends reached or after the thesis's 3000 steps, the world is
/// reset and the next begins, so a long soak exercises resets too.
const TARGET: &str = "-0.6,-0.7,0";

/// How long the learner may take to journal its first state, and to stop
/// after SIGTERM (its final snapshot included).
const LEARNER_LIMIT: Duration = Duration::from_secs(60);

/// What to run.
#[derive(Clone, Debug)]
pub struct SoakOptions {
    /// The world daemon (realtime).
    pub sim: String,
    /// Its process id, for its memory (Linux /proc).
    pub world_pid: Option<u32>,
    /// Connections that only read, beside the learner.
    pub subscribers: usize,
    pub duration: Duration,
    pub sample_every: Duration,
    /// The learner's `--state` directory.
    pub state: PathBuf,
    /// The learner's `--snapshot-every`.
    pub snapshot_every: u64,
    /// The `pushlearn` binary the learner runs as.
    pub learner_bin: PathBuf,
    /// Where the learner's output (`learner.log`) and report
    /// (`learner.json`) go.
    pub work_dir: PathBuf,
}

/// One sample of the learner's side.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Since the measurement started.
    pub seconds: f64,
    pub learner_rss_kib: u64,
    pub on_disk: OnDisk,
}

/// The outcome.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SoakReport {
    /// The subscribers' view and the world's memory.
    pub load: LoadReport,
    /// What the learner said when it stopped.
    pub learner: StopReport,
    pub samples: Vec<Sample>,
    pub snapshot_every: u64,
}

/// Why a soak could not be run to its end.
#[derive(Debug, thiserror::Error)]
pub enum SoakError {
    #[error("cannot run the learner: {0}")]
    Learner(String),
    #[error("the load run failed: {0}")]
    Load(#[from] pushlearn::client::ClientError),
}

impl SoakReport {
    /// The most journal records the directory may hold: the records since
    /// the previous snapshot, at most two snapshot intervals (the records
    /// queued while a snapshot is written come on top, a handful).
    #[must_use]
    pub fn journal_bound(&self) -> u64 {
        2 * self.snapshot_every
    }

    /// The most journal records sampled.
    #[must_use]
    pub fn journal_max(&self) -> u64 {
        self.samples
            .iter()
            .map(|s| s.on_disk.journal_records)
            .max()
            .unwrap_or(0)
    }
}

/// A `pushlearn learn` child, its output in a file.
struct Learner {
    child: Child,
    log: PathBuf,
}

impl Learner {
    fn start(options: &SoakOptions, report: &Path) -> Result<Learner, SoakError> {
        let log = options.work_dir.join("learner.log");
        let output = File::create(&log)
            .and_then(|out| Ok((out.try_clone()?, out)))
            .map_err(|e| SoakError::Learner(format!("{}: {e}", log.display())))?;
        let child = Command::new(&options.learner_bin)
            .arg("learn")
            .args(["--sim", &options.sim, "--target", TARGET])
            .args(["--episodes", &u32::MAX.to_string(), "--progress-every", "0"])
            // A lost world fails the soak rather than being waited for.
            .args(["--reconnect-for", "0"])
            .arg("--state")
            .arg(&options.state)
            .args(["--snapshot-every", &options.snapshot_every.to_string()])
            .arg("--json")
            .arg(report)
            .stdin(Stdio::null())
            .stdout(Stdio::from(output.0))
            .stderr(Stdio::from(output.1))
            .spawn()
            .map_err(|e| SoakError::Learner(format!("{}: {e}", options.learner_bin.display())))?;
        Ok(Learner { child, log })
    }

    /// `what`, with the end of the learner's log.
    fn failed(&self, what: &str) -> SoakError {
        let log = std::fs::read_to_string(&self.log).unwrap_or_default();
        let lines: Vec<&str> = log.lines().collect();
        let tail = &lines[lines.len().saturating_sub(12)..];
        SoakError::Learner(format!(
            "{what}; the end of its log ({}):\n{}",
            self.log.display(),
            tail.join("\n")
        ))
    }

    /// Waits until the learner has journalled a state: it is connected,
    /// learning and keeping its memory.
    async fn wait_until_learning(&mut self, state: &Path) -> Result<(), SoakError> {
        let deadline = Instant::now() + LEARNER_LIMIT;
        loop {
            if on_disk(state).is_ok_and(|d| d.journal_records > 0) {
                return Ok(());
            }
            if let Ok(Some(status)) = self.child.try_wait() {
                return Err(self.failed(&format!("it exited ({status}) before learning")));
            }
            if Instant::now() > deadline {
                return Err(
                    self.failed(&format!("it journalled no state within {LEARNER_LIMIT:?}"))
                );
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// Stops the learner as an operator does (SIGTERM) and waits for its
    /// clean end.
    async fn stop(mut self) -> Result<(), SoakError> {
        signal(&self.child, "TERM").map_err(|e| SoakError::Learner(format!("kill: {e}")))?;
        let deadline = Instant::now() + LEARNER_LIMIT;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) if status.success() => return Ok(()),
                Ok(Some(status)) => {
                    return Err(self.failed(&format!("it ended with {status} after SIGTERM")))
                }
                Ok(None) if Instant::now() < deadline => {
                    tokio::time::sleep(Duration::from_millis(20)).await;
                }
                _ => {
                    let err = self.failed(&format!(
                        "it did not stop within {LEARNER_LIMIT:?} of SIGTERM"
                    ));
                    kill_group(&mut self.child);
                    return Err(err);
                }
            }
        }
    }
}

impl Drop for Learner {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            kill_group(&mut self.child);
        }
    }
}

/// Runs the soak: starts the learner, waits until it learns, runs
/// `options.subscribers` reading clients for `options.duration` while
/// sampling, then stops the learner and reads its report.
///
/// # Errors
/// The learner cannot be started, does not learn, does not stop cleanly or
/// writes no report; the load run fails.
pub async fn run_soak(options: &SoakOptions) -> Result<SoakReport, SoakError> {
    let report_file = options.work_dir.join("learner.json");
    let _ = std::fs::remove_file(&report_file);
    let mut learner = Learner::start(options, &report_file)?;
    learner.wait_until_learning(&options.state).await?;
    let load = LoadOptions {
        clients: options.subscribers,
        duration: options.duration,
        control: false,
        pid: options.world_pid,
        sample_every: options.sample_every,
    };
    let start = Instant::now();
    let learner_pid = learner.child.id();
    let state = options.state.clone();
    let sampler = sample_until(
        start,
        start + options.duration,
        options.sample_every,
        move || {
            Some((
                rss_kib(Some(learner_pid))?,
                on_disk(&state).unwrap_or_default(),
            ))
        },
    );
    let (load, samples) = tokio::join!(run_load(&options.sim, &load), sampler);
    if let Ok(Some(status)) = learner.child.try_wait() {
        return Err(learner.failed(&format!("it exited ({status}) during the soak")));
    }
    let load = load?;
    learner.stop().await?;
    let text = std::fs::read_to_string(&report_file)
        .map_err(|e| SoakError::Learner(format!("its report {}: {e}", report_file.display())))?;
    let stopped: StopReport = serde_json::from_str(&text).map_err(|e| {
        SoakError::Learner(format!(
            "its report {} is not one: {e}",
            report_file.display()
        ))
    })?;
    Ok(SoakReport {
        load,
        learner: stopped,
        samples: samples
            .into_iter()
            .map(|(seconds, (learner_rss_kib, on_disk))| Sample {
                seconds,
                learner_rss_kib,
                on_disk,
            })
            .collect(),
        snapshot_every: options.snapshot_every,
    })
}

/// `first → max → last` of a series, for the summary.
fn span(values: impl Iterator<Item = u64> + Clone) -> String {
    let first = values.clone().next().unwrap_or(0);
    let max = values.clone().max().unwrap_or(0);
    let last = values.last().unwrap_or(0);
    format!("{first} at the start, {max} at most, {last} at the end")
}

impl std::fmt::Display for SoakReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let l = &self.learner;
        writeln!(
            f,
            "learner: {} states handled, {} missed, {} reconnections; stopped by {} with {} \
             records on disk; attempts at the target: {}",
            l.states,
            l.missed,
            l.reconnects,
            l.signal.as_deref().unwrap_or("itself"),
            l.records_on_disk.unwrap_or(0),
            l.attempts
                .map_or("none".to_owned(), |(ended, reached)| format!(
                    "{ended} ended, {reached} reached"
                ))
        )?;
        writeln!(f, "learner work per state: {}", l.work)?;
        writeln!(f, "{}", self.load)?;
        writeln!(
            f,
            "learner RSS [KiB]: {} ({} samples)",
            span(self.samples.iter().map(|s| s.learner_rss_kib)),
            self.samples.len()
        )?;
        writeln!(
            f,
            "journal [records]: {} (bound 2 × --snapshot-every = {})",
            span(self.samples.iter().map(|s| s.on_disk.journal_records)),
            self.journal_bound()
        )?;
        write!(
            f,
            "journal [bytes]: {}; snapshots [bytes]: {}",
            span(self.samples.iter().map(|s| s.on_disk.journal_bytes)),
            span(self.samples.iter().map(|s| s.on_disk.snapshot_bytes))
        )
    }
}
