//! `pushlearn ctl soak`: the command around [`pushlearn_cli::soak`].

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use pushlearn_cli::soak::{run_soak, SoakOptions};

use super::parse_seconds;

/// The options of `pushlearn ctl soak` (its help is the subcommand's).
#[derive(Debug, Args)]
pub struct Soak {
    /// Reading connections beside the learner.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=4096))]
    subscribers: u64,
    /// How long to run (after the learner's first state).
    #[arg(long, value_name = "SECONDS", default_value = "600", value_parser = parse_seconds)]
    seconds: Duration,
    /// Process id of the world daemon, to sample its memory (Linux /proc).
    #[arg(long)]
    pid: Option<u32>,
    /// Sample the memory and the state directory every SECONDS.
    #[arg(long, value_name = "SECONDS", default_value = "10", value_parser = parse_seconds)]
    sample_every: Duration,
    /// The learner's --snapshot-every: a minute at 100 Hz by default, so
    /// that ten minutes show ten compactions of the journal.
    #[arg(long, value_name = "N", default_value_t = 6000, value_parser = clap::value_parser!(u64).range(1..))]
    snapshot_every: u64,
    /// The learner's --state directory [default: a new one in a
    /// temporary directory, removed after a run that ends well].
    #[arg(long, value_name = "DIR")]
    state: Option<PathBuf>,
    /// Draw the memory, the journal and the state directory over time
    /// as DIR/soak.png and DIR/soak.svg.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
}

impl Soak {
    /// Runs the soak against the world at `sim` and prints its report (as
    /// one JSON object with `json`). The learner's log, report and, without
    /// --state, its state directory live in a temporary directory, removed
    /// when the soak ends well and named when it does not.
    pub async fn run(self, sim: &str, json: bool) -> Result<()> {
        // A typo in --plots must not cost a ten-minute run.
        if let Some(dir) = &self.plots {
            pushlearn_cli::output::check_writable_dir(dir)
                .with_context(|| format!("cannot write --plots {}", dir.display()))?;
        }
        let work_dir = std::env::temp_dir().join(format!("pushlearn-soak-{}", std::process::id()));
        std::fs::create_dir_all(&work_dir)
            .with_context(|| format!("cannot create {}", work_dir.display()))?;
        let state = self.state.clone().unwrap_or_else(|| work_dir.join("state"));
        std::fs::create_dir_all(&state)
            .with_context(|| format!("cannot create the --state directory {}", state.display()))?;
        let options = SoakOptions {
            sim: sim.to_owned(),
            world_pid: self.pid,
            subscribers: usize::try_from(self.subscribers).context("too many subscribers")?,
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
            for path in pushlearn_cli::soak::figure::soak(&report, dir)? {
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
