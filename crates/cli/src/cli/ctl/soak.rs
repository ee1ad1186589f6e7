//! `pushlearn ctl soak`: the command around [`pushlearn_cli::soak`].

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use pushlearn_cli::soak::{run_soak, SoakOptions};

/// The command's options.
pub struct Soak {
    pub subscribers: usize,
    pub seconds: Duration,
    pub pid: Option<u32>,
    pub sample_every: Duration,
    pub snapshot_every: u64,
    pub state: Option<PathBuf>,
    pub plots: Option<PathBuf>,
}

impl Soak {
    /// Runs the soak against the world at `sim` and prints its report (as
    /// one JSON object with `json`). The learner's log, report and, without
    /// --state, its state directory live in a temporary directory, removed
    /// when the soak ends well and named when it does not.
    pub async fn run(self, sim: &str, json: bool) -> Result<()> {
        let work_dir = std::env::temp_dir().join(format!("pushlearn-soak-{}", std::process::id()));
        std::fs::create_dir_all(&work_dir)
            .with_context(|| format!("cannot create {}", work_dir.display()))?;
        let state = self.state.clone().unwrap_or_else(|| work_dir.join("state"));
        std::fs::create_dir_all(&state)
            .with_context(|| format!("cannot create the --state directory {}", state.display()))?;
        let options = SoakOptions {
            sim: sim.to_owned(),
            world_pid: self.pid,
            subscribers: self.subscribers,
            duration: self.seconds,
            sample_every: self.sample_every,
            state,
            snapshot_every: self.snapshot_every,
            learner_bin: std::env::current_exe().context("cannot find this program")?,
            work_dir: work_dir.clone(),
        };
        eprintln!(
            "soak: a learner and {} subscribers on the world at {sim} for {:.0} s; the \
             learner's log is {}",
            self.subscribers,
            self.seconds.as_secs_f64(),
            work_dir.join("learner.log").display()
        );
        let report = run_soak(&options).await.with_context(|| {
            format!("the soak failed (its files are in {})", work_dir.display())
        })?;
        if let Some(dir) = &self.plots {
            for path in pushlearn_cli::report::plot::soak(&report, dir)? {
                eprintln!("wrote {}", path.display());
            }
        }
        if json {
            println!("{}", serde_json::to_string(&report)?);
        } else {
            println!("{report}");
        }
        // The files are only worth keeping when something went wrong.
        let _ = std::fs::remove_dir_all(&work_dir);
        Ok(())
    }
}
