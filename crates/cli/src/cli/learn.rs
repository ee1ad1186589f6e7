//! `pushlearn learn`: the learner daemon.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use learner::{Action, Model, ObjectState};
use pushlearn::client::{ClientOptions, SimClient, DEFAULT_ADDR};
use pushlearn::duration;
use pushlearn_cli::learn::reconnect::{serve_resilient, Reconnect};
use pushlearn_cli::learn::state::{Durable, Opened, Settings, DEFAULT_SNAPSHOT_EVERY};
use pushlearn_cli::learn::{Learner, OnState, Policy, ServeOptions, Stop, WorkSummary};
use pushlearn_cli::models::{ModelKind, ModelOptions, WithModel};

use super::experiment::{parse_numbers, parse_pose};

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
/// (20 ms at 100 Hz). Stop with Ctrl-C: a summary follows.
///
/// With --state DIR the learner's memory is kept on disk (snapshots plus a
/// checksummed journal of every state, docs/reliability.md): a daemon
/// killed at any moment resumes where it left off. If the world goes away
/// the daemon reconnects with backoff for up to --reconnect-for seconds.
#[derive(Debug, Args)]
#[command(
    group = clap::ArgGroup::new("policy").required(true).args(["action", "target"]),
    after_help = "Examples:\n  \
        pushlearn learn --action 0,0.5 --shadows\n  \
        pushlearn learn --model interaction --target 0.6,0.7,-2.1 --report-every 5\n  \
        pushlearn learn --action 0,0.5 --state ~/.pushlearn/gate-memory"
)]
pub struct LearnArgs {
    /// Address of the world daemon.
    #[arg(long, value_name = "HOST:PORT", default_value = DEFAULT_ADDR)]
    connect: String,

    /// The learner.
    #[arg(long, value_enum, default_value_t = ModelKind::Gate)]
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

    /// Seed of the planner's exploration.
    #[arg(long, default_value_t = 1)]
    seed: u64,

    #[command(flatten)]
    options: ModelOptions,

    /// Keep the learner's memory in DIR (created if missing) and resume from
    /// it: a snapshot plus a journal of every state since.
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

fn parse_seconds_or_zero(text: &str) -> Result<Duration, String> {
    duration::parse_seconds(text).map_err(|_| format!("'{text}' is not a number of seconds"))
}

fn parse_action(text: &str) -> Result<Action, String> {
    let v = parse_numbers(text, 2)?;
    Ok(Action::new(v[0], v[1]))
}

fn parse_seconds(text: &str) -> Result<Duration, String> {
    duration::parse_positive_seconds(text)
        .map_err(|_| format!("'{text}' is not a positive number of seconds"))
}

/// Runs `pushlearn learn`.
pub fn run(args: LearnArgs) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(async {
        let client =
            SimClient::connect_with(args.connect.as_str(), ClientOptions::clock_seqs()).await?;
        let rate = client.hello().publish_rate;
        if args.options.low_frequency() && rate != pushlearn_cli::experiment::LOW_RATE_HZ {
            anyhow::bail!(
                "LOWFREQ (bit 2, --flag low-freq) needs a world publishing at {} Hz; this one publishes at {rate} Hz (set it with `pushlearn ctl` or start pushlearn-sim at that rate)",
                pushlearn_cli::experiment::LOW_RATE_HZ
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
        };
        args.model.dispatch(&args.options, rate, job)?.await
    })
}

struct Daemon<'a> {
    client: SimClient,
    policy: Policy,
    args: &'a LearnArgs,
}

impl<'a> WithModel for Daemon<'a> {
    type Output = std::pin::Pin<Box<dyn std::future::Future<Output = Result<()>> + 'a>>;

    fn run<M: Model + 'static>(self, untrained: M) -> Self::Output {
        let Daemon {
            client,
            policy,
            args,
        } = self;
        Box::pin(async move {
            let hello = client.hello();
            eprintln!(
                "pushlearn learn: {} model on scene {} ({} Hz, {}); Ctrl-C to stop",
                args.model, hello.scene, hello.publish_rate, hello.timing_mode
            );
            let fresh = || Learner::new(untrained, policy, args.shadows, args.seed);
            let Some(dir) = &args.state else {
                let mut learner = fresh();
                attached(client, &mut learner, args).await?;
                return finish(&learner, policy);
            };
            let settings = Settings {
                model: args.model.to_string(),
                publish_rate_hz: hello.publish_rate,
                policy,
                shadows: args.shadows,
                seed: args.seed,
                model_options: args.options.canonical(),
            };
            let (mut durable, opened) = Durable::open(dir, &settings, fresh, args.snapshot_every)
                .with_context(|| {
                format!("cannot use the learner memory in {}", dir.display())
            })?;
            match &opened {
                Opened::Fresh => eprintln!("memory: new, in {}", dir.display()),
                Opened::Resumed(recovery) => {
                    eprintln!("memory: resumed from {}: {recovery}", dir.display());
                }
            }
            attached(client, &mut durable, args).await?;
            finish(durable.learner(), policy)?;
            let stored = durable.close()?;
            println!("memory: {stored} records on disk in {}", dir.display());
            Ok(())
        })
    }
}

/// Serves until stopped, reconnecting as --reconnect-for allows.
async fn attached(client: SimClient, learner: &mut impl OnState, args: &LearnArgs) -> Result<()> {
    let options = ServeOptions {
        max_messages: args.messages,
        report_every: args.report_every,
    };
    let reconnect = Reconnect::new(
        args.connect.clone(),
        (!args.reconnect_for.is_zero()).then_some(args.reconnect_for),
    );
    let served = serve_resilient(client, learner, options, &reconnect, |s: &WorkSummary| {
        eprintln!("{s}");
    })
    .await?;
    println!(
        "stopped ({}): {}",
        match served.stop {
            Stop::Interrupted => "interrupted",
            Stop::MessageLimit => "message limit",
        },
        served.summary
    );
    if served.reconnects > 0 || served.world_errors > 0 {
        println!(
            "{} states over {} reconnection(s); {} physics blow-up(s) reported by the world",
            served.states, served.reconnects, served.world_errors
        );
    }
    if let Some(client) = served.client {
        client.close().await?;
    }
    Ok(())
}

/// The end-of-run report.
fn finish<M: Model>(learner: &Learner<M>, policy: Policy) -> Result<()> {
    if learner.parse_errors > 0 {
        println!("{} world states could not be parsed", learner.parse_errors);
    }
    if matches!(policy, Policy::Target(_)) {
        println!(
            "target {}",
            if learner.reached() {
                "reached"
            } else {
                "not reached"
            }
        );
    }
    println!(
        "model: {}",
        serde_json::to_string(&learner.model().stats())?
    );
    Ok(())
}
