//! `pushlearn learn`: the learner daemon.

use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use learner::{Action, Model, ObjectState};
use pushlearn::client::{ClientOptions, SimClient, DEFAULT_ADDR};
use pushlearn::learn::{serve, Learner, Policy, ServeOptions, Stop, WorkSummary};
use pushlearn::models::{ModelKind, ModelOptions, WithModel};

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
#[derive(Debug, Args)]
#[command(
    group = clap::ArgGroup::new("policy").required(true).args(["action", "target"]),
    after_help = "Examples:\n  \
        pushlearn learn --action 0,0.5 --shadows\n  \
        pushlearn learn --model interaction --target 0.6,0.7,-2.1 --report-every 5"
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
}

fn parse_action(text: &str) -> Result<Action, String> {
    let v = parse_numbers(text, 2)?;
    Ok(Action::new(v[0], v[1]))
}

fn parse_seconds(text: &str) -> Result<Duration, String> {
    text.parse::<f64>()
        .ok()
        .and_then(|s| Duration::try_from_secs_f64(s).ok())
        .filter(|d| !d.is_zero())
        .ok_or_else(|| format!("'{text}' is not a positive number of seconds"))
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
        if args.options.low_frequency() && rate != pushlearn::experiment::LOW_RATE_HZ {
            anyhow::bail!(
                "LOWFREQ (bit 2, --flag low-freq) needs a world publishing at {} Hz; this one publishes at {rate} Hz (set it with `pushlearn ctl` or start pushlearn-sim at that rate)",
                pushlearn::experiment::LOW_RATE_HZ
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
            mut client,
            policy,
            args,
        } = self;
        Box::pin(async move {
            let hello = client.hello();
            eprintln!(
                "pushlearn learn: {} model on scene {} ({} Hz, {}); Ctrl-C to stop",
                args.model, hello.scene, hello.publish_rate, hello.timing_mode
            );
            let mut learner = Learner::new(untrained, policy, args.shadows, args.seed);
            let options = ServeOptions {
                max_messages: args.messages,
                report_every: args.report_every,
            };
            let (stop, summary) = serve(&mut client, &mut learner, options, |s: &WorkSummary| {
                eprintln!("{s}");
            })
            .await?;
            println!(
                "stopped ({}): {summary}",
                match stop {
                    Stop::Interrupted => "interrupted",
                    Stop::MessageLimit => "message limit",
                }
            );
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
            client.close().await?;
            Ok(())
        })
    }
}
