//! `pushlearn ctl`: one-shot and scripted commands for a running world, and a
//! state watcher.
//!
//! Every command waits until the world has answered it before the next one is
//! sent (see [`Session::perform`]), so a script has the same effect on every
//! run, and an error names the script line that caused it.

mod output;
mod record;
mod script;
#[cfg(feature = "lab")]
mod soak;

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use pushlearn::client::{seq_base_from_clock, ClientError, ClientOptions, SimClient, DEFAULT_ADDR};
use pushlearn::duration::{self, SecondsError};
use pushlearn::wire::pb::{self, client_message::Payload};
use pushlearn::wire::{clamp_speed, BodyName};

use output::Output;
#[cfg(feature = "lab")]
use soak::Soak;

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
    pushlearn ctl --sim 127.0.0.1:12000 run push.ctl")]
pub struct CtlArgs {
    /// Address of the world daemon to connect to.
    // `--addr` was this flag's name before the project settled on `--sim`;
    // kept, hidden, for one release so that existing scripts keep working.
    #[arg(long, alias = "addr", global = true, value_name = "HOST:PORT", default_value = DEFAULT_ADDR)]
    sim: String,

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

    /// Record the world's frames to FILE, for `pushlearn-sim replay FILE`.
    ///
    /// With --listen ADDR, a recording proxy: a client (a learner, a script)
    /// connects to ADDR instead of the world, and every frame both ways is
    /// passed on to the world at --sim and written to FILE with its
    /// direction and time; prints `listening on ADDR` and ends when that
    /// client has gone and the world has sent its last frame. Without
    /// --listen, an observer: records what the world publishes (states, no
    /// commands) until --count states or Ctrl-C. The format is in
    /// docs/protocol.md §9.
    Record {
        /// The recording to write (replaced if it exists).
        file: PathBuf,
        /// Be a proxy for one client connecting to this HOST:PORT (port 0
        /// picks a free one; a bare PORT listens on 127.0.0.1). Later
        /// clients are refused: the listening socket is closed once the
        /// first has connected.
        #[arg(long, value_name = "[HOST:]PORT")]
        listen: Option<String>,
        /// Observer mode: stop after N states.
        #[arg(long, value_name = "N", conflicts_with = "listen")]
        count: Option<u64>,
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

    /// Soak a realtime world: a learning, acting `pushlearn learn --state`
    /// beside SUBSCRIBERS reading connections for SECONDS.
    ///
    /// Starts the learner (this program's `learn`, planning towards the
    /// blue block's pose -0.6,-0.7,0, the world reset after every attempt),
    /// waits until it journals its first state, then runs the subscribers
    /// and samples, every --sample-every, the learner's resident memory and
    /// its state directory (journal records and bytes, snapshots) and, with
    /// --pid, the world's memory. At the end the learner is stopped with
    /// SIGTERM and its --json report read. Prints how many states the
    /// learner handled and missed (gaps in publish_seq), the subscribers'
    /// states, misses and intervals between states against the 2/f budget,
    /// the memory and the journal against its bound (2 × --snapshot-every
    /// records). Start the world with enough clients for all:
    /// `pushlearn-sim serve --mode realtime --real-time-rate 1000
    /// --max-clients 80`. docs/reliability.md, "Soak".
    #[cfg(feature = "lab")]
    Soak(Soak),
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
    ///
    /// The world refuses a position beyond ±1000 m on any axis and a body
    /// its scene lacks; a `<body>Shadow` name sets a ghost of that body. A
    /// YAW beyond ±1000 rad is refused before sending (the wire carries a
    /// quaternion, so a yaw is only known modulo 2π). Prints what was set.
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
        /// Rotation about the z axis in radians, |YAW| ≤ 1000.
        #[arg(value_parser = parse_yaw)]
        yaw: f64,
    },
    /// Drive the actuator with velocity (VX, VY) in m/s.
    ///
    /// The world caps the speed at its limit (0.5 m/s in the built-in
    /// scenes; `ctl info` shows a world's), scaling the velocity down with
    /// its direction kept. Prints the velocity the world applies, and says
    /// when it was capped.
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
    // Negative numbers are values here too, so that `rate -10` is refused
    // as a rate rather than as the unknown flag `-1`.
    #[command(allow_negative_numbers = true)]
    Rate {
        /// States per simulated second.
        #[arg(value_parser = parse_rate)]
        hz: u32,
    },
    /// Lock-step mode: run the world to its next publish, N times.
    ///
    /// Prints each resulting state. Refused by a world in realtime mode or
    /// paused.
    #[command(allow_negative_numbers = true)]
    Advance {
        /// How many intervals to run.
        #[arg(default_value_t = 1, value_parser = parse_count)]
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
        /// Show only this body (repeat for several; ghosts such as
        /// blockAShadow too). Without it, every body.
        #[arg(long = "body", value_name = "NAME")]
        bodies: Vec<String>,
    },
    /// Print the world's Hello: scene, timing mode, rates, limits and bodies.
    Info,
}

/// The largest |yaw| `set-pose` sends. A quaternion keeps a yaw only modulo
/// 2π, and far out the f64 spacing makes even that meaningless (at 1e300 it
/// is larger than 2π): a yaw this large is a mistake, not a rotation.
pub const MAX_YAW: f64 = 1000.0;

/// Refuses a yaw beyond [`MAX_YAW`] or not finite, naming it.
pub fn check_yaw(yaw: f64) -> Result<f64, String> {
    if yaw.is_finite() && yaw.abs() <= MAX_YAW {
        Ok(yaw)
    } else {
        Err(format!(
            "yaw {yaw:e} rad is out of range: |yaw| must be at most {MAX_YAW} rad"
        ))
    }
}

fn parse_yaw(text: &str) -> Result<f64, String> {
    let yaw: f64 = text
        .parse()
        .map_err(|_| format!("'{text}' is not a number of radians"))?;
    check_yaw(yaw)
        .map_err(|_| format!("yaw '{text}' is out of range: |yaw| must be at most {MAX_YAW} rad"))
}

fn parse_rate(text: &str) -> Result<u32, String> {
    text.parse().map_err(|_| {
        format!("'{text}' is not a publish rate: HZ must be a positive whole number dividing 1000 (e.g. 100 or 10)")
    })
}

fn parse_count(text: &str) -> Result<u32, String> {
    text.parse()
        .map_err(|_| format!("'{text}' is not a count: N must be a whole number ≥ 0"))
}

impl Action {
    /// The command as a user types it.
    fn name(&self) -> &'static str {
        match self {
            Action::Pause => "pause",
            Action::Unpause => "unpause",
            Action::Reset => "reset",
            Action::SetPose { .. } => "set-pose",
            Action::Move { .. } => "move",
            Action::Rate { .. } => "rate",
            Action::Advance { .. } => "advance",
            Action::Watch { .. } => "watch",
            Action::Info => "info",
        }
    }

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
        CtlCommand::Record {
            file,
            listen,
            count,
        } => {
            let options = record::RecordOptions {
                file: &file,
                sim: &args.sim,
                listen: listen.as_deref(),
                count,
                timeout: args.timeout,
            };
            return record::record(&options).await;
        }
        CtlCommand::Load {
            clients,
            seconds,
            pid,
        } => {
            let options = pushlearn_cli::load::LoadOptions {
                clients: usize::try_from(clients).context("too many clients")?,
                duration: seconds,
                control: true,
                pid,
                sample_every: Duration::from_secs(1),
            };
            let report = pushlearn_cli::load::run_load(&args.sim, &options).await?;
            if args.json {
                println!("{}", serde_json::to_string(&report)?);
            } else {
                println!("{report}");
            }
            return Ok(());
        }
        #[cfg(feature = "lab")]
        CtlCommand::Soak(soak) => return soak.run(&args.sim, args.json).await,
    };
    // Clock-based seqs keep `applied_seq` left over from earlier ctl runs
    // below this run's seqs (pushlearn::client docs).
    let options = ClientOptions {
        timeout: Some(args.timeout),
        first_seq: seq_base_from_clock(),
    };
    let sim = SimClient::connect_with(args.sim.as_str(), options).await?;
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
        let name = action.name();
        if let Some(payload) = action.command_payload() {
            let kind = payload.kind();
            let seq = self
                .sim
                .command(payload)
                .await
                .map_err(|err| refused(name, err))?;
            tracing::info!(seq, kind, "accepted");
            self.last_command = Some(seq);
            if let Some(line) = confirmation(action, self.sim.hello()) {
                self.output.note(&line)?;
            }
            return Ok(());
        }
        match action {
            Action::Advance { n } => {
                for _ in 0..*n {
                    let state = self
                        .sim
                        .command_and_wait_applied(Payload::advance())
                        .await
                        .map_err(|err| refused(name, err))?;
                    self.output.state(&state)?;
                }
                // The state with every command in force has just been shown.
                self.last_command = None;
                Ok(())
            }
            Action::Watch { count, bodies } => {
                check_bodies(bodies, self.sim.hello())?;
                self.output.only(bodies);
                let watched = self.watch(*count).await;
                self.output.only(&[]);
                watched
            }
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

/// A refusal as a user reads it: the command as they typed it and the
/// world's reason, without the seq (an internal number they never chose).
/// The world's reason starts with the wire's name of the command
/// (`set_pose: …`), which would only repeat `what`.
fn refused(what: &str, err: ClientError) -> anyhow::Error {
    match err {
        ClientError::Refused { message, .. } => {
            let reason = match message.split_once(": ") {
                Some((word, rest)) if is_wire_name(word) => rest,
                _ => message.as_str(),
            };
            anyhow::anyhow!("world refused {what}: {reason}")
        }
        other => anyhow::Error::from(other),
    }
}

fn is_wire_name(word: &str) -> bool {
    !word.is_empty() && word.chars().all(|c| c.is_ascii_lowercase() || c == '_')
}

/// `watch --body` names must be bodies of this world or ghosts of them: a
/// typo would otherwise show an empty table forever.
fn check_bodies(bodies: &[String], hello: &pb::Hello) -> Result<()> {
    let known: Vec<&str> = hello.bodies.iter().map(|b| b.name.as_str()).collect();
    for name in bodies {
        let body = BodyName::parse(name);
        if !known.contains(&body.body()) {
            anyhow::bail!(
                "watch: no body '{name}' in this world (it has: {}, and their ghosts such as {}Shadow)",
                known.join(", "),
                known.first().copied().unwrap_or("actuator")
            );
        }
    }
    Ok(())
}

/// What the world applied for a single command, as one line for people;
/// `None` for actions that print states instead. A Move is capped exactly
/// as the world caps it ([`clamp_speed`], with the limit from its Hello).
fn confirmation(action: &Action, hello: &pb::Hello) -> Option<String> {
    Some(match action {
        Action::Pause => "pause: the world has stopped stepping".to_owned(),
        Action::Unpause => "unpause: the world steps again".to_owned(),
        Action::Reset => {
            "reset: every body at its start pose, at rest; time 0 (the actuator's velocity command is kept)".to_owned()
        }
        Action::SetPose { name, x, y, z, yaw } => {
            let wrapped = yaw.sin().atan2(yaw.cos());
            let shown = if (wrapped - yaw).abs() > 1e-12 {
                format!(
                    "yaw {} rad (= {} rad)",
                    output::number(*yaw),
                    output::number(wrapped)
                )
            } else {
                format!("yaw {} rad", output::number(*yaw))
            };
            format!(
                "set-pose: {name} at ({}, {}, {}) m, {shown}",
                output::number(*x),
                output::number(*y),
                output::number(*z)
            )
        }
        Action::Move { vx, vy } => {
            let velocity =
                |[x, y]: [f64; 2]| format!("({}, {}) m/s", output::number(x), output::number(y));
            match hello.max_speed {
                Some(limit) => {
                    let [ax, ay, _] = clamp_speed([*vx, *vy, 0.0], limit);
                    if [ax, ay] == [*vx, *vy] {
                        format!("move: actuator velocity {}", velocity([ax, ay]))
                    } else {
                        format!(
                            "move: actuator velocity {}, clamped from {} to the world's speed limit {} m/s",
                            velocity([ax, ay]),
                            velocity([*vx, *vy]),
                            output::number(limit)
                        )
                    }
                }
                None => format!(
                    "move: actuator velocity {} requested (this world does not say its speed limit)",
                    velocity([*vx, *vy])
                ),
            }
        }
        Action::Rate { hz } => {
            let steps = if hello.step_size > 0.0 {
                format!(
                    " (a state every {} steps of {} s)",
                    output::number((1.0 / (f64::from(*hz) * hello.step_size)).round()),
                    output::number(hello.step_size)
                )
            } else {
                String::new()
            };
            format!("rate: {hz} Hz{steps}")
        }
        Action::Advance { .. } | Action::Watch { .. } | Action::Info => return None,
    })
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
