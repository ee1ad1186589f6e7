//! `pushlearn learn`: the learner daemon.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use learner::{Action, Model, ObjectState};
use pushlearn::client::{ClientOptions, SimClient, DEFAULT_ADDR};
use pushlearn::duration;
use pushlearn_cli::learn::pretrain::{pretrain, Pretrain};
use pushlearn_cli::learn::reconnect::{serve_resilient, Reconnect};
use pushlearn_cli::learn::state::{
    holds_memory, load_model, write_snapshot_file, Durable, EpisodeSettings, Opened, Settings,
    StateLock, DEFAULT_SNAPSHOT_EVERY,
};
use pushlearn_cli::learn::{
    EpisodeResult, Episodes, Event, Learner, OnState, Policy, ServeOptions, Stop, StopReport,
};
use pushlearn_cli::models::{named, ModelArgs, ModelKind, WithModel};

use drive::cli_args::{parse_action, parse_pose};

/// Attach a learner to a running world (pushlearn-sim): learn from every
/// state it publishes and drive the actuator.
///
/// For every world state the model is updated with the action that was in
/// force, chooses the next action (a fixed --action, or its planner towards
/// --target), predicts the next state and sends Move (and with --shadows the
/// prediction as the ghost bodies actuatorShadow, blockAShadow,
/// blockBShadow, and a --target as blockAShadowTarget, for `pushlearn
/// view`). A lock-step world is advanced after every state; in a
/// realtime world the work per message is measured against the 2/f budget
/// (20 ms at 100 Hz). Stop with Ctrl-C (SIGINT) or SIGTERM: the state being
/// handled is finished, the actuator stopped, a summary printed and, with
/// --state, the journal flushed and a final snapshot written; the daemon
/// then exits with status 0.
///
/// An untrained model does not know yet what pushing does: with --pretrain
/// thesis it first makes the thesis's eight fixed training pushes against
/// the world (as Move to Target does before its test run), or it starts
/// from a model kept earlier (--memory). With --target the daemon makes
/// --episodes attempts (the world reset between them, the model learning
/// across all), each ending when the model finds the target reached or
/// after --max-steps, prints the distance to the target on the way and how
/// each attempt ended, then stops.
///
/// With --state DIR the learner's memory is kept on disk (snapshots plus a
/// checksummed journal of every state, docs/reliability.md): a daemon
/// killed at any moment resumes where it left off, a damaged newest
/// snapshot is replaced by the previous one and the journal after it, and a
/// write that fails (a full or read-only disk) stops the daemon with status
/// 1 and the file and OS error named; restarted, it has lost no
/// acknowledged state. If the world goes away the daemon reconnects with
/// backoff for up to --reconnect-for seconds.
#[derive(Debug, Args)]
#[command(
    group = clap::ArgGroup::new("policy").required(true).args(["action", "target"]),
    after_help = "Examples:\n  \
        pushlearn learn --pretrain thesis --target=-0.6,-0.7,0 --shadows\n  \
        pushlearn learn --pretrain thesis --target=-0.6,-0.7,0 --episodes 5 --save-model gate.model\n  \
        pushlearn learn --memory gate.model --target 0.6,-0.7,3.1416\n  \
        pushlearn learn --action 0,0.5 --state ~/.pushlearn/gate-memory"
)]
pub struct LearnArgs {
    /// Address of the world daemon (pushlearn-sim).
    #[arg(long, value_name = "HOST:PORT", default_value = DEFAULT_ADDR,
          alias = "connect")]
    sim: String,

    /// The learner.
    #[arg(long, value_parser = named::<ModelKind>(), default_value_t = ModelKind::Gate)]
    model: ModelKind,

    /// Always send this velocity VX,VY (m/s).
    #[arg(long, value_name = "VX,VY", allow_hyphen_values = true, value_parser = parse_action)]
    action: Option<Action>,

    /// Plan towards this pose X,Y,ORI of the blue block (metres, radians).
    #[arg(long, value_name = "X,Y,ORI", allow_hyphen_values = true, value_parser = parse_pose)]
    target: Option<ObjectState>,

    /// Send the predicted poses (and the --target) as *Shadow ghost bodies,
    /// which `pushlearn view` draws.
    #[arg(long)]
    shadows: bool,

    /// Print the work-time summary every SECONDS.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    report_every: Option<Duration>,

    /// Stop after N world states.
    #[arg(long, value_name = "N")]
    messages: Option<u64>,

    /// With --target: attempts to make; the world is reset between them and
    /// the model keeps learning across all.
    /// [default: 1]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    episodes: Option<u32>,

    /// With --target: the step limit of one attempt [default: the thesis's
    /// 3000].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    max_steps: Option<u64>,

    /// With --target: print the distance to the target every N world states
    /// (0: never) [default: 100].
    #[arg(long, value_name = "N")]
    progress_every: Option<u64>,

    /// Train before pursuing the policy: `thesis` makes the thesis's eight
    /// fixed training pushes of Move to Target against the world first.
    #[arg(long, value_enum, value_name = "PROGRAMME")]
    pretrain: Option<Pretrain>,

    /// Start from the model kept in PATH: an earlier daemon's --state
    /// directory or a --save-model file (read, never changed). It must have
    /// been made with the same --model, model options and publish rate.
    #[arg(long, value_name = "PATH")]
    memory: Option<PathBuf>,

    /// When the daemon stops, write its model to FILE (atomically), for a
    /// later --memory FILE.
    #[arg(long, value_name = "FILE")]
    save_model: Option<PathBuf>,

    /// When the daemon stops cleanly, write its summary to FILE as JSON:
    /// why it stopped, states handled and missed (gaps in the world's
    /// publish_seq), reconnections, work per state, attempts and, with
    /// --state, the records on disk.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,

    /// Seed of the planner's exploration.
    #[arg(long, default_value_t = 1)]
    seed: u64,

    #[command(flatten)]
    options: ModelArgs,

    /// Keep the learner's memory in DIR (created if missing) and resume from
    /// it: a snapshot plus a journal of every state since. One daemon at a
    /// time: a second one on DIR is refused (DIR/lock, an OS lock released
    /// when its holder ends, however it ends).
    #[arg(long, value_name = "DIR")]
    state: Option<PathBuf>,

    /// With --state: write a snapshot every N journal records.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SNAPSHOT_EVERY,
          value_parser = clap::value_parser!(u64).range(1..))]
    snapshot_every: u64,

    /// Reconnect to a lost world for up to SECONDS (0: stop instead).
    #[arg(long, value_name = "SECONDS", default_value = "60", value_parser = parse_seconds_or_zero)]
    reconnect_for: Duration,
}

/// See [`LearnArgs::progress_every`].
const DEFAULT_PROGRESS_EVERY: u64 = 100;

impl LearnArgs {
    fn episode_settings(&self) -> EpisodeSettings {
        let default = EpisodeSettings::default();
        EpisodeSettings {
            episodes: self.episodes.unwrap_or(default.episodes),
            max_steps: self.max_steps.unwrap_or(default.max_steps),
        }
    }
}

fn parse_seconds_or_zero(text: &str) -> Result<Duration, String> {
    duration::parse_seconds(text).map_err(|_| format!("'{text}' is not a number of seconds"))
}

fn parse_seconds(text: &str) -> Result<Duration, String> {
    duration::parse_positive_seconds(text)
        .map_err(|_| format!("'{text}' is not a positive number of seconds"))
}

/// Runs `pushlearn learn`.
pub fn run(args: LearnArgs) -> Result<()> {
    // clap's `requires` is not enforced for these (the policy group), so
    // the usage error is raised here, as clap would.
    if args.target.is_none() {
        let given = [
            ("--episodes", args.episodes.is_some()),
            ("--max-steps", args.max_steps.is_some()),
            ("--progress-every", args.progress_every.is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, given)| *given) {
            clap::Error::raw(
                clap::error::ErrorKind::MissingRequiredArgument,
                format!("{flag} counts attempts at a target: it needs --target X,Y,ORI\n"),
            )
            .exit();
        }
    }
    let lock = check_outputs(&args)?;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(async {
        let client =
            SimClient::connect_with(args.sim.as_str(), ClientOptions::clock_seqs()).await?;
        let rate = client.hello().publish_rate;
        if args.options.options().low_frequency() && rate != pushlearn_cli::scene::LOW_RATE_HZ {
            anyhow::bail!(
                "LOWFREQ (bit 2, --flag low-freq) needs a world publishing at {} Hz; this one publishes at {rate} Hz (set it with `pushlearn ctl` or start pushlearn-sim at that rate)",
                pushlearn_cli::scene::LOW_RATE_HZ
            );
        }
        let policy = match (args.action, args.target) {
            (_, Some(pose)) => Policy::Target(pose),
            (Some(action), None) => Policy::Fixed(action),
            (None, None) => anyhow::bail!("give --action or --target"),
        };
        let job = Daemon {
            client,
            policy,
            args: &args,
            lock,
        };
        args.model.dispatch(&args.options.options(), rate, job)?.await
    })
}

/// The files the daemon writes, checked before it connects: a typo must
/// not cost a long run's model. Takes the --state directory's lock: a second
/// daemon on it is refused before it touches the world.
fn check_outputs(args: &LearnArgs) -> Result<Option<StateLock>> {
    if let Some(file) = &args.save_model {
        pushlearn_cli::output::check_file(file, "--save-model")?;
    }
    if let Some(file) = &args.json {
        pushlearn_cli::output::check_file(file, "--json")?;
    }
    if let Some(dir) = &args.state {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the --state directory {}", dir.display()))?;
    }
    let lock = args.state.as_deref().map(StateLock::acquire).transpose()?;
    if let Some(path) = &args.memory {
        if !path.exists() {
            anyhow::bail!("--memory {}: no such file or directory", path.display());
        }
    }
    Ok(lock)
}

struct Daemon<'a> {
    client: SimClient,
    policy: Policy,
    args: &'a LearnArgs,
    /// The --state directory's, taken by [`check_outputs`].
    lock: Option<StateLock>,
}

impl<'a> WithModel for Daemon<'a> {
    type Output = std::pin::Pin<Box<dyn std::future::Future<Output = Result<()>> + 'a>>;

    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        let Daemon {
            mut client,
            policy,
            args,
            lock,
        } = self;
        Box::pin(async move {
            let hello = client.hello();
            eprintln!(
                "pushlearn learn: {} model on scene {} ({} Hz, {}); Ctrl-C or SIGTERM to stop",
                args.model, hello.scene, hello.publish_rate, hello.timing_mode
            );
            let settings = Settings {
                model: args.model.to_string(),
                publish_rate_hz: hello.publish_rate,
                policy,
                shadows: args.shadows,
                seed: args.seed,
                model_options: args.options.options().canonical(),
                episodes: args.episode_settings(),
            };
            let resuming = args.state.as_ref().filter(|dir| holds_memory(dir));
            let model = match resuming {
                Some(dir) => {
                    if args.pretrain.is_some() || args.memory.is_some() {
                        eprintln!(
                            "memory: {} already holds this learner's memory; resuming it instead of --pretrain/--memory",
                            dir.display()
                        );
                    }
                    untrained
                }
                None => experienced(&mut client, untrained, &settings, args).await?,
            };
            let fresh = || {
                let episodes = args.episode_settings();
                Learner::new(model, policy, args.shadows, args.seed)
                    .with_episodes(episodes.episodes, episodes.max_steps)
            };
            let (Some(dir), Some(lock)) = (&args.state, lock) else {
                let mut learner = fresh();
                let mut report = attached(client, &mut learner, args).await?;
                finish(&learner)?;
                save(&learner, &settings, args)?;
                report.attempts = attempts(&learner);
                write_report(&report, args)?;
                return Ok(());
            };
            let (mut durable, opened) =
                Durable::open_locked(lock, &settings, fresh, args.snapshot_every).with_context(
                    || format!("cannot use the learner memory in {}", dir.display()),
                )?;
            match &opened {
                Opened::Fresh => eprintln!("memory: new, in {}", dir.display()),
                Opened::Resumed(recovery) => {
                    eprintln!("memory: resumed from {}: {recovery}", dir.display());
                }
            }
            let mut report = attached(client, &mut durable, args).await?;
            finish(durable.learner())?;
            save(durable.learner(), &settings, args)?;
            report.attempts = attempts(durable.learner());
            let stored = durable.close()?;
            println!("memory: {stored} records on disk in {}", dir.display());
            report.records_on_disk = Some(stored);
            write_report(&report, args)?;
            Ok(())
        })
    }
}

/// The model to start from: the one kept in --memory, then trained by
/// --pretrain.
async fn experienced<M: Model + 'static>(
    client: &mut SimClient,
    untrained: M,
    settings: &Settings,
    args: &LearnArgs,
) -> Result<M> {
    let mut model = untrained;
    if let Some(path) = &args.memory {
        let (kept, records) = load_model::<M>(path, settings)
            .with_context(|| format!("cannot start from --memory {}", path.display()))?;
        eprintln!(
            "memory: starting from {} ({records} world states learned)",
            path.display()
        );
        model = kept;
    }
    if let Some(programme) = args.pretrain {
        eprintln!(
            "pretraining: the thesis's {} fixed training pushes",
            programme.pushes()
        );
        let (trained, done) = pretrain(client, model, programme)
            .await
            .context("pretraining failed")?;
        eprintln!(
            "pretrained on {} world states ({} start corrections)",
            done.messages, done.corrections
        );
        model = trained;
    }
    Ok(model)
}

/// Installs the SIGTERM and SIGINT handlers now and returns the future that
/// completes on the first of them, naming it. From here on neither signal
/// kills the daemon: the serving loop stops, the journal is flushed and a
/// final snapshot written. Installed only once serving starts, so that
/// Ctrl-C still ends pretraining at once (nothing is kept from it anyway).
#[cfg(unix)]
fn stop_signal() -> Result<impl std::future::Future<Output = &'static str>> {
    use tokio::signal::unix::{signal, SignalKind};
    let mut interrupt = signal(SignalKind::interrupt()).context("cannot listen for SIGINT")?;
    let mut terminate = signal(SignalKind::terminate()).context("cannot listen for SIGTERM")?;
    Ok(async move {
        tokio::select! {
            _ = terminate.recv() => "SIGTERM",
            _ = interrupt.recv() => "SIGINT",
        }
    })
}

/// Ctrl-C only, where there are no Unix signals.
#[cfg(not(unix))]
fn stop_signal() -> Result<impl std::future::Future<Output = &'static str>> {
    Ok(async {
        if let Err(err) = tokio::signal::ctrl_c().await {
            tracing::error!("cannot listen for Ctrl-C: {err}");
            std::future::pending::<()>().await;
        }
        "Ctrl-C"
    })
}

/// Serves until stopped, reconnecting as --reconnect-for allows. Returns how
/// it ended (for --json; the attempts and the records on disk are the
/// caller's to add).
async fn attached(
    client: SimClient,
    learner: &mut impl OnState,
    args: &LearnArgs,
) -> Result<StopReport> {
    let signal = stop_signal()?;
    let caught = std::cell::Cell::new(None);
    let shutdown = async {
        caught.set(Some(signal.await));
    };
    let options = ServeOptions {
        max_messages: args.messages,
        report_every: args.report_every,
        progress_every: Some(args.progress_every.unwrap_or(DEFAULT_PROGRESS_EVERY))
            .filter(|&every| every > 0),
    };
    let reconnect = Reconnect::new(
        args.sim.clone(),
        (!args.reconnect_for.is_zero()).then_some(args.reconnect_for),
    );
    let served = serve_resilient(
        client,
        learner,
        options,
        &reconnect,
        shutdown,
        |event| match event {
            Event::Work(summary) => eprintln!("{summary}"),
            Event::Progress(episodes) => eprintln!("{}", describe_progress(episodes)),
            Event::EpisodeEnded(episodes) => {
                if let Some(ended) = episodes.ended.last() {
                    println!(
                        "{}",
                        describe_episode(episodes.ended.len(), episodes.total, ended)
                    );
                }
            }
        },
    )
    .await?;
    println!(
        "stopped ({}): {}",
        match served.stop {
            Stop::Interrupted => "interrupted",
            Stop::MessageLimit => "message limit",
            Stop::EpisodesDone => "every attempt ended",
        },
        served.summary
    );
    if served.reconnects > 0 || served.world_errors > 0 {
        println!(
            "{} states over {} reconnection(s); {} physics blow-up(s) reported by the world",
            served.states, served.reconnects, served.world_errors
        );
    }
    if served.missed > 0 {
        println!(
            "{} states the world published never reached the learner (it fell behind)",
            served.missed
        );
    }
    if let Some(client) = served.client {
        client.close().await?;
    }
    Ok(StopReport {
        stop: served.stop,
        signal: caught.get().map(str::to_owned),
        states: served.states,
        missed: served.missed,
        reconnects: served.reconnects,
        world_errors: served.world_errors,
        work: served.summary,
        attempts: None,
        records_on_disk: None,
    })
}

/// With a target: the attempts ended, and of them reached.
fn attempts<M: Model>(learner: &Learner<M>) -> Option<(usize, usize)> {
    learner
        .episodes()
        .map(|episodes| (episodes.ended.len(), episodes.reached()))
}

/// Says how a clean stop went and writes --json: the last words of a
/// daemon that ends well.
fn write_report(report: &StopReport, args: &LearnArgs) -> Result<()> {
    if let Some(file) = &args.json {
        let json = serde_json::to_vec_pretty(report)?;
        pushlearn_cli::output::write_atomically(file, &json)
            .with_context(|| format!("cannot write --json {}", file.display()))?;
    }
    if let Some(signal) = &report.signal {
        match (report.records_on_disk, &args.state) {
            (Some(stored), Some(dir)) => eprintln!(
                "pushlearn learn: {signal}: stopped cleanly; journal flushed and final \
                 snapshot written ({stored} records in {})",
                dir.display()
            ),
            _ => eprintln!("pushlearn learn: {signal}: stopped cleanly"),
        }
    }
    Ok(())
}

fn describe_progress(episodes: &Episodes) -> String {
    let (pos, ori) = episodes.errors.unwrap_or((f64::NAN, f64::NAN));
    format!(
        "attempt {}, step {}: the block is {pos:.3} m and {ori:.3} rad from the target",
        episodes.current(),
        episodes.handled.saturating_sub(1)
    )
}

fn describe_episode(number: usize, total: u32, ended: &EpisodeResult) -> String {
    format!(
        "attempt {number} of {total}: {} after {} steps, {:.3} m and {:.3} rad from the target",
        if ended.reached {
            "target reached"
        } else {
            "target not reached"
        },
        ended.steps,
        ended.pos_err,
        ended.ori_err
    )
}

/// The end-of-run report.
fn finish<M: Model>(learner: &Learner<M>) -> Result<()> {
    if learner.parse_errors > 0 {
        println!("{} world states could not be parsed", learner.parse_errors);
    }
    if let Some(episodes) = learner.episodes() {
        let ended = episodes.ended.len();
        if ended < episodes.total as usize {
            let (pos, ori) = episodes.errors.unwrap_or((f64::NAN, f64::NAN));
            println!(
                "attempt {} stopped after {} steps, {pos:.3} m and {ori:.3} rad from the target",
                ended + 1,
                episodes.handled.saturating_sub(1)
            );
        }
        println!(
            "target {}: {} of {} attempts{}",
            if episodes.reached() > 0 {
                "reached"
            } else {
                "not reached"
            },
            episodes.reached(),
            episodes.total,
            if ended < episodes.total as usize {
                format!(", {} of them ended", ended)
            } else {
                String::new()
            }
        );
    }
    println!(
        "model: {}",
        serde_json::to_string(&learner.model().stats())?
    );
    Ok(())
}

/// --save-model: the learner as a snapshot file that --memory reads.
fn save<M: Model>(learner: &Learner<M>, settings: &Settings, args: &LearnArgs) -> Result<()> {
    if let Some(file) = &args.save_model {
        write_snapshot_file(file, 0, settings, learner)
            .with_context(|| format!("cannot write --save-model {}", file.display()))?;
        println!("model saved to {}", file.display());
    }
    Ok(())
}
