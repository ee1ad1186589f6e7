//! `pushlearn serve-learner`: a built-in model served over the learner
//! protocol (docs/learner-protocol.md), on stdin/stdout or as a daemon.

use std::io::{BufWriter, Write};
use std::net::{TcpListener, TcpStream};

use anyhow::{Context, Result};
use clap::Args;
use pushlearn_cli::external::server::{serve, stdout_file, Identity, Requests, ServeError};
use pushlearn_cli::models::{ModelKind, ModelOptions, WithModel};

/// Serve a built-in model over the learner protocol, so that any driver
/// that speaks it (another harness, or `pushlearn experiment --learner`)
/// can run it: on stdin and stdout by default, or as a daemon with --listen
/// (a fresh model per connection).
///
/// `pushlearn experiment push-task --learner "pushlearn serve-learner --model gate"`
/// gives the report of `--model gate`, bit for bit (the suite checks it).
#[derive(Debug, Args)]
pub struct ServeLearnerArgs {
    /// The model to serve.
    #[arg(long, value_enum, default_value_t = ModelKind::Gate)]
    model: ModelKind,

    #[command(flatten)]
    options: ModelOptions,

    /// Listen on HOST:PORT instead of serving stdin and stdout (port 0: any
    /// free port; the address is printed as "listening on HOST:PORT").
    #[arg(long, value_name = "HOST:PORT")]
    listen: Option<String>,
}

pub fn run(args: ServeLearnerArgs) -> Result<()> {
    match &args.listen {
        None => {
            let stdout = stdout_file().context("standard output")?;
            serve_one(&args, std::io::stdin().lock(), BufWriter::new(stdout))
                .context("serving the learner protocol on stdin/stdout")
        }
        Some(addr) => {
            let listener =
                TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))?;
            println!("listening on {}", listener.local_addr()?);
            std::io::stdout().flush()?;
            std::thread::scope(|scope| {
                for stream in listener.incoming() {
                    let stream = match stream {
                        Ok(stream) => stream,
                        Err(err) => {
                            tracing::warn!(%err, "accepting a connection failed");
                            continue;
                        }
                    };
                    let args = &args;
                    scope.spawn(move || {
                        let peer = stream
                            .peer_addr()
                            .map(|a| a.to_string())
                            .unwrap_or_default();
                        if let Err(err) = serve_stream(args, stream) {
                            tracing::warn!(%peer, "{err:#}");
                        }
                    });
                }
            });
            Ok(())
        }
    }
}

fn serve_stream(args: &ServeLearnerArgs, stream: TcpStream) -> Result<()> {
    let _ = stream.set_nodelay(true);
    let reader = stream.try_clone()?;
    serve_one(args, reader, BufWriter::new(stream))
}

/// One driver: its Start fixes the publish rate the model is configured for.
fn serve_one(args: &ServeLearnerArgs, input: impl std::io::Read, output: impl Write) -> Result<()> {
    let mut requests = Requests::new(input);
    let (seq, start) = requests.start()?;
    let job = Job {
        identity: Identity {
            name: args.options.report_name(args.model),
            version: env!("CARGO_PKG_VERSION").to_owned(),
            // `learner::features::ActuatorYaw`: the gate model's rule.
            ignores_actuator_yaw: args.model.family() == ModelKind::Gate,
        },
        seq,
        requests,
        output,
    };
    Ok(args
        .model
        .dispatch(&args.options, start.publish_rate_hz, job)??)
}

struct Job<R, W> {
    identity: Identity,
    seq: u64,
    requests: Requests<R>,
    output: W,
}

impl<R: std::io::Read, W: Write> WithModel for Job<R, W> {
    type Output = Result<(), ServeError>;
    fn run<M: learner::Model + 'static>(self, untrained: M) -> Self::Output {
        serve(
            untrained,
            &self.identity,
            self.seq,
            self.requests,
            self.output,
        )
    }
}
