//! `pushlearn ctl`: one-shot and scripted commands for a running world, and a
//! state watcher.
//!
//! Every command waits until the world has answered it before the next one is
//! sent (see [`Session::perform`]), so a script has the same effect on every
//! run, and an error names the script line that caused it.

mod output;
mod script;

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use pushlearn::client::{seq_base_from_clock, ClientError, ClientOptions, SimClient, DEFAULT_ADDR};
use pushlearn::duration::{self, SecondsError};
use pushlearn::wire::pb::client_message::Payload;

use output::Output;

/// Send commands to a running world daemon (pushlearn-sim) and watch its states.
///
/// Each command waits until the world has accepted it (or refused it: the
/// world's error is printed and the exit status is non-zero), so commands run
/// strictly in order. Numbers are SI units: metres, m/s, radians, Hz.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  \
    pushlearn ctl reset\n  \
    pushlearn ctl set-pose actuator 0 0 0.03 0\n  \
    pushlearn ctl move 0 0.5\n  \
    pushlearn ctl watch --count 10\n  \
    pushlearn ctl --addr 127.0.0.1:12000 run push.ctl")]
pub struct CtlArgs {
    /// Address of the world daemon.
    #[arg(long, global = true, value_name = "HOST:PORT", default_value = DEFAULT_ADDR)]
    addr: String,

    /// Seconds to wait for the world to connect, answer a command or publish
    /// an awaited state before giving up.
    #[arg(long, global = true, value_name = "SECONDS", default_value = "10", value_parser = parse_seconds)]
    timeout: Duration,

    /// Print world states (watch, advance) and `info` as JSON lines instead of a table.
    #[arg(long, global = true)]
    json: bool,

    #[command(subcommand)]
    command: CtlCommand,
}

#[derive(Debug, Subcommand)]
enum CtlCommand {
    #[command(flatten)]
    Action(Action),

    /// Run a script of the commands above, one per line.
    ///
    /// Lines are written as on this command line without `pushlearn ctl`
    /// (e.g. `set-pose blockA 0 0.25 0.05 0`). `#` starts a comment; blank
    /// lines are ignored; `watch` needs `--count N`. The whole file is checked
    /// before anything is sent; the first failing command stops the script and
    /// is reported with its file and line. All commands use one connection.
    Run {
        /// The script file.
        file: PathBuf,
    },

    /// Load-test a realtime world: CLIENTS connections at once for SECONDS.
    ///
    /// The first connection sends a Move for every state, as a learner does;
    /// the others only read. Prints the states each saw and missed, the
    /// intervals between the controlling client's states against the 2/f
    /// budget, and (with --pid) the daemon's resident memory over time.
    /// For 100 states per wall-clock second start the world with
    /// `pushlearn-sim serve --real-time-rate 1000`.
    Load {
        /// Connections in all, the controlling one included.
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=4096))]
        clients: u64,
        /// How long to run.
        #[arg(long, value_name = "SECONDS", default_value = "60", value_parser = parse_seconds)]
        seconds: Duration,
        /// Process id of the world daemon, to sample its memory (Linux /proc).
        #[arg(long)]
        pid: Option<u32>,
    },
}

/// A command for the world; the same set is accepted in `ctl run` scripts.
#[derive(Debug, Clone, PartialEq, Subcommand)]
pub enum Action {
    /// Stop stepping (the world keeps accepting commands).
    Pause,
    /// Resume stepping.
    Unpause,
    /// Put every body back to its start pose, at rest; time restarts at 0.
    ///
    /// The actuator's velocity command is kept: send `move 0 0` first to stop it.
    Reset,
    /// Set one body's position and yaw (its velocities are kept).
    #[command(allow_negative_numbers = true)]
    SetPose {
        /// Body name, e.g. actuator, blockA, blockB.
        name: String,
        /// Position x in metres.
        x: f64,
        /// Position y in metres.
        y: f64,
        /// Position z in metres (0.03 for the actuator, 0.05 for blocks).
        z: f64,
        /// Rotation about the z axis in radians.
        yaw: f64,
    },
    /// Drive the actuator with velocity (VX, VY) in m/s.
    #[command(name = "move", allow_negative_numbers = true)]
    Move {
        /// Velocity along x in m/s.
        vx: f64,
        /// Velocity along y in m/s.
        vy: f64,
    },
    /// Set the publishing rate in Hz.
    ///
    /// HZ must divide 1000: the world publishes every 1000/HZ steps of 1 ms.
    /// The thesis used 100 and 10.
    Rate {
        /// States per simulated second.
        hz: u32,
    },
    /// Lock-step mode: run the world to its next publish, N times.
    ///
    /// Prints each resulting state. Refused by a world in realtime mode or
    /// paused.
    Advance {
        /// How many intervals to run.
        #[arg(default_value_t = 1)]
        n: u32,
    },
    /// Print published world states, one row per body per state.
    ///
    /// After earlier commands of the same script, the first state shown is the
    /// first one produced with all of them in force.
    Watch {
        /// Stop after N states (without it, watch until interrupted).
        #[arg(long, value_name = "N")]
        count: Option<u64>,
    },
    /// Print the world's Hello: scene, timing mode, rates and bodies.
    Info,
}

impl Action {
    /// The message for actions that are a single command to acknowledge.
    fn command_payload(&self) -> Option<Payload> {
        match self {
            Action::Pause => Some(Payload::pause()),
            Action::Unpause => Some(Payload::unpause()),
            Action::Reset => Some(Payload::reset()),
            Action::SetPose { name, x, y, z, yaw } => {
                Some(Payload::set_pose(name.clone(), [*x, *y, *z], *yaw))
            }
            Action::Move { vx, vy } => Some(Payload::move_(*vx, *vy)),
            Action::Rate { hz } => Some(Payload::publish_rate(*hz)),
            Action::Advance { .. } | Action::Watch { .. } | Action::Info => None,
        }
    }
}

fn parse_seconds(text: &str) -> Result<Duration, String> {
    duration::parse_positive_seconds(text).map_err(|err| match err {
        SecondsError::NotANumber => format!("'{text}' is not a number of seconds"),
        SecondsError::OutOfRange | SecondsError::Zero => {
            format!("the timeout must be a positive number of seconds, not '{text}'")
        }
    })
}

/// Runs `pushlearn ctl`.
pub fn run(args: CtlArgs) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(execute(args))
}

async fn execute(args: CtlArgs) -> Result<()> {
    // A script is checked completely before the world is touched.
    let steps = match args.command {
        CtlCommand::Action(action) => vec![script::Step {
            origin: None,
            action,
        }],
        CtlCommand::Run { file } => script::load(&file)?,
        CtlCommand::Load {
            clients,
            seconds,
            pid,
        } => {
            let options = pushlearn_cli::load::LoadOptions {
                clients: usize::try_from(clients).context("too many clients")?,
                duration: seconds,
                pid,
                sample_every: Duration::from_secs(1),
            };
            let report = pushlearn_cli::load::run_load(&args.addr, &options).await?;
            if args.json {
                println!("{}", serde_json::to_string(&report)?);
            } else {
                println!("{report}");
            }
            return Ok(());
        }
    };
    // Clock-based seqs keep `applied_seq` left over from earlier ctl runs
    // below this run's seqs (pushlearn::client docs).
    let options = ClientOptions {
        timeout: Some(args.timeout),
        first_seq: seq_base_from_clock(),
    };
    let sim = SimClient::connect_with(args.addr.as_str(), options).await?;
    let mut session = Session {
        sim,
        last_command: None,
        output: Output::new(args.json),
    };
    for step in &steps {
        let result = session.perform(&step.action).await;
        match &step.origin {
            Some(origin) => result.with_context(|| origin.to_string())?,
            None => result?,
        }
    }
    session.sim.close().await?;
    Ok(())
}

/// One connection's worth of commands.
struct Session {
    sim: SimClient,
    /// Seq of the last command sent, so that `watch` starts with its effect.
    last_command: Option<u64>,
    output: Output,
}

impl Session {
    async fn perform(&mut self, action: &Action) -> Result<()> {
        if let Some(payload) = action.command_payload() {
            let kind = payload.kind();
            let seq = self.sim.command(payload).await?;
            tracing::info!(seq, kind, "accepted");
            self.last_command = Some(seq);
            return Ok(());
        }
        match action {
            Action::Advance { n } => {
                for _ in 0..*n {
                    let state = self
                        .sim
                        .command_and_wait_applied(Payload::advance())
                        .await?;
                    self.output.state(&state)?;
                }
                // The state with every command in force has just been shown.
                self.last_command = None;
                Ok(())
            }
            Action::Watch { count } => self.watch(*count).await,
            Action::Info => Ok(self.output.hello(self.sim.hello())?),
            // The single commands were sent above.
            Action::Pause
            | Action::Unpause
            | Action::Reset
            | Action::SetPose { .. }
            | Action::Move { .. }
            | Action::Rate { .. } => Ok(()),
        }
    }

    async fn watch(&mut self, count: Option<u64>) -> Result<()> {
        let limit = self.sim.timeout();
        if count.is_none() {
            // An open-ended watch is a monitor: a quiet world is not an error.
            self.sim.set_timeout(None);
        }
        let mut shown = 0;
        if let Some(seq) = self.last_command.take() {
            if count != Some(0) {
                let state = self
                    .sim
                    .wait_applied(seq)
                    .await
                    .map_err(explain_quiet_world)?;
                self.output.state(&state)?;
                shown += 1;
            }
        }
        while count.is_none_or(|n| shown < n) {
            let state = self.sim.next_state().await.map_err(explain_quiet_world)?;
            self.output.state(&state)?;
            shown += 1;
        }
        self.sim.set_timeout(limit);
        Ok(())
    }
}

/// A timeout while watching usually means the world is not publishing; say
/// why that happens rather than just "timed out".
fn explain_quiet_world(err: ClientError) -> anyhow::Error {
    let quiet = matches!(err, ClientError::Timeout { .. });
    let err = anyhow::Error::from(err);
    if quiet {
        err.context("no world state arrived (a paused world, or a lock-step world without `advance`, publishes none)")
    } else {
        err
    }
}
