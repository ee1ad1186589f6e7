//! `pushlearn serve-learner`: a built-in model served over the learner
//! protocol (docs/learner-protocol.md), on stdin/stdout or as a daemon.

use std::io::{BufWriter, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use pushlearn_cli::external::server::{refuse, serve_driver, stdout_file, Requests};
use pushlearn_cli::models::{named, ModelArgs, ModelKind};

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
    #[arg(long, value_parser = named::<ModelKind>(), default_value_t = ModelKind::Gate)]
    model: ModelKind,

    #[command(flatten)]
    options: ModelArgs,

    /// Listen on HOST:PORT instead of serving stdin and stdout (port 0: any
    /// free port; the address is printed as "listening on HOST:PORT"). A
    /// bare PORT listens on 127.0.0.1: the protocol has no authentication,
    /// so anything but a loopback address lets everyone who reaches it run
    /// the model.
    #[arg(long, value_name = "[HOST:]PORT", value_parser = parse_listen)]
    listen: Option<SocketAddr>,

    /// With --listen, the most drivers served at once; one more is answered
    /// with an Error naming the limit and closed.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_CONNECTIONS,
          value_parser = clap::value_parser!(u32).range(1..))]
    max_connections: u32,
}

/// As many as the world daemon's clients (`pushlearn-sim serve --max-clients`):
/// an experiment opens one connection per worker.
const DEFAULT_MAX_CONNECTIONS: u32 = 64;

/// How long a driver turned away may take to send its Start, so that the
/// refusal can answer it; a silent one is closed after this.
const REFUSAL_LIMIT: Duration = Duration::from_secs(2);

fn parse_listen(text: &str) -> Result<SocketAddr, String> {
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::from((Ipv4Addr::LOCALHOST, port)));
    }
    std::net::ToSocketAddrs::to_socket_addrs(text)
        .ok()
        .and_then(|mut addrs| addrs.next())
        .ok_or_else(|| format!("expected PORT or HOST:PORT, got '{text}'"))
}

/// One place of `--max-connections`, given back when dropped.
struct Place<'a>(&'a AtomicUsize);

impl<'a> Place<'a> {
    fn take(open: &'a AtomicUsize, max: usize) -> Option<Self> {
        open.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n < max).then_some(n + 1)
        })
        .ok()
        .map(|_| Place(open))
    }
}

impl Drop for Place<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
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
            let max = args.max_connections as usize;
            let open = AtomicUsize::new(0);
            std::thread::scope(|scope| {
                for stream in listener.incoming() {
                    let stream = match stream {
                        Ok(stream) => stream,
                        Err(err) => {
                            tracing::warn!(%err, "accepting a connection failed");
                            continue;
                        }
                    };
                    let peer = stream
                        .peer_addr()
                        .map(|a| a.to_string())
                        .unwrap_or_default();
                    let Some(place) = Place::take(&open, max) else {
                        tracing::warn!(%peer, "turning a driver away: {max} are connected");
                        std::thread::spawn(move || {
                            if let Err(err) = refuse_stream(stream, max) {
                                tracing::debug!(%peer, "turning a driver away: {err:#}");
                            }
                        });
                        continue;
                    };
                    let args = &args;
                    scope.spawn(move || {
                        let _place = place;
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

fn refuse_stream(stream: TcpStream, max: usize) -> Result<()> {
    stream.set_read_timeout(Some(REFUSAL_LIMIT))?;
    stream.set_write_timeout(Some(REFUSAL_LIMIT))?;
    let reader = stream.try_clone()?;
    let why = format!("too many connections: this learner daemon serves at most {max} at once");
    refuse(Requests::new(reader), BufWriter::new(&stream), &why)?;
    // Read the driver's close before closing: closing a socket with unread
    // data resets it, and the reset may overtake the reply.
    stream.shutdown(std::net::Shutdown::Write)?;
    let _ = std::io::copy(&mut &stream, &mut std::io::sink());
    Ok(())
}

/// One driver: its Start fixes the publish rate the model is configured for.
fn serve_one(args: &ServeLearnerArgs, input: impl std::io::Read, output: impl Write) -> Result<()> {
    Ok(serve_driver(
        args.model,
        &args.options.options(),
        Requests::new(input),
        output,
    )?)
}
