//! `pushlearn serve-learner`: a built-in model served over the learner
//! protocol (docs/learner-protocol.md), on stdin/stdout or as a daemon.

use std::io::{BufWriter, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use prost::Message;
use pushlearn::wire::pb::learner::Request;
use pushlearn_cli::external::server::{error_frame, serve_driver, stdout_file, Requests};
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

    /// With --listen, close a connection whose next request has not arrived
    /// complete within SECONDS of the previous one (or of connecting): a
    /// silent or stalled driver holds its place, and the bytes of a frame it
    /// began, no longer than this.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_IDLE_TIMEOUT,
          value_parser = parse_idle_timeout)]
    idle_timeout: f64,
}

/// Seconds a connection may go without a complete request: far above a
/// driver's pause between requests (a world message at most) and above the
/// driver's own 30 s wait for a learner.
const DEFAULT_IDLE_TIMEOUT: f64 = 60.0;

/// Drivers beyond --max-connections being answered at once; more are closed
/// unanswered. Each is a task holding a socket and a Start's bytes.
const MAX_REFUSALS: usize = 256;

/// The largest first request read from a driver turned away: a Start is
/// tens of bytes.
const REFUSAL_REQUEST_BYTES: usize = 4096;

fn parse_idle_timeout(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s.is_finite() && (0.001..=86_400.0).contains(&s) => Ok(s),
        _ => Err(format!(
            "expected seconds between 0.001 and 86400, got '{text}'"
        )),
    }
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
struct Place(Arc<AtomicUsize>);

impl Place {
    fn take(open: &Arc<AtomicUsize>, max: usize) -> Option<Self> {
        open.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n < max).then_some(n + 1)
        })
        .ok()
        .map(|_| Place(Arc::clone(open)))
    }
}

impl Drop for Place {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

pub fn run(args: ServeLearnerArgs) -> Result<()> {
    let Some(addr) = args.listen else {
        let stdout = stdout_file().context("standard output")?;
        return serve_one(
            &args,
            Requests::new(std::io::stdin().lock()),
            BufWriter::new(stdout),
        )
        .context("serving the learner protocol on stdin/stdout");
    };
    // The accept loop and the refusals run on one tokio thread: a driver
    // turned away costs a task, not an OS thread (800 refused connections
    // once held 801 threads). The drivers served are plain blocking
    // threads, at most --max-connections of them.
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the accept loop")?;
    runtime.block_on(listen(args, addr))
}

async fn listen(args: ServeLearnerArgs, addr: SocketAddr) -> Result<()> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("cannot listen on {addr}"))?;
    println!("listening on {}", listener.local_addr()?);
    std::io::stdout().flush()?;
    let max = args.max_connections as usize;
    let idle = Duration::from_secs_f64(args.idle_timeout);
    let args = Arc::new(args);
    let open = Arc::new(AtomicUsize::new(0));
    let refusing = Arc::new(tokio::sync::Semaphore::new(MAX_REFUSALS));
    loop {
        let (stream, peer) = match listener.accept().await {
            Ok(accepted) => accepted,
            Err(err) => {
                // Typically out of descriptors: wait instead of spinning.
                tracing::warn!(%err, "accepting a connection failed");
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        let Some(place) = Place::take(&open, max) else {
            tracing::warn!(%peer, "turning a driver away: {max} are connected");
            match refusing.clone().try_acquire_owned() {
                Ok(permit) => {
                    tokio::spawn(async move {
                        let _permit = permit;
                        if let Err(err) = turn_away(stream, max).await {
                            tracing::debug!(%peer, "turning a driver away: {err:#}");
                        }
                    });
                }
                // Dropping the stream closes it unanswered.
                Err(_) => tracing::debug!(%peer, "closed at once: {MAX_REFUSALS} refusals pending"),
            }
            continue;
        };
        let stream = stream.into_std().and_then(|s| {
            s.set_nonblocking(false)?;
            Ok(s)
        });
        let stream = match stream {
            Ok(stream) => stream,
            Err(err) => {
                tracing::warn!(%peer, %err, "cannot serve a connection");
                continue;
            }
        };
        let args = Arc::clone(&args);
        let spawned = std::thread::Builder::new()
            .name("driver".into())
            .spawn(move || {
                let _place = place;
                if let Err(err) = serve_stream(&args, stream, idle) {
                    tracing::warn!(%peer, "{err:#}");
                }
            });
        if let Err(err) = spawned {
            tracing::warn!(%peer, %err, "cannot start a thread for a connection");
        }
    }
}

fn serve_stream(args: &ServeLearnerArgs, stream: TcpStream, idle: Duration) -> Result<()> {
    let _ = stream.set_nodelay(true);
    // A driver that stops reading its replies holds the thread no longer
    // than one that stops writing.
    stream.set_write_timeout(Some(idle))?;
    let reader = stream.try_clone()?;
    let timeouts = stream.try_clone()?;
    let requests = Requests::new(reader)
        .with_idle_limit(idle, Box::new(move |t| timeouts.set_read_timeout(t)));
    serve_one(args, requests, BufWriter::new(stream))
}

/// Answers a driver beyond --max-connections: reads its first request (a
/// Start, at most [`REFUSAL_REQUEST_BYTES`]) and replies with an `Error`
/// naming the limit, all within [`REFUSAL_LIMIT`].
async fn turn_away(stream: tokio::net::TcpStream, max: usize) -> Result<()> {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let why = format!("too many connections: this learner daemon serves at most {max} at once");
    tokio::time::timeout(REFUSAL_LIMIT, async move {
        let (mut read, mut write) = stream.into_split();
        let mut prefix = [0_u8; 4];
        read.read_exact(&mut prefix).await?;
        let len = u32::from_be_bytes(prefix) as usize;
        anyhow::ensure!(
            len <= REFUSAL_REQUEST_BYTES,
            "a first request of {len} bytes is no Start"
        );
        let mut body = vec![0_u8; len];
        read.read_exact(&mut body).await?;
        let seq = Request::decode(&body[..]).map(|r| r.seq).unwrap_or(0);
        write.write_all(&error_frame(seq, &why)?).await?;
        // Read the driver's close before closing: closing a socket with
        // unread data resets it, and the reset may overtake the reply.
        write.shutdown().await?;
        tokio::io::copy(&mut read, &mut tokio::io::sink()).await?;
        Ok(())
    })
    .await
    .context("the driver neither sent its Start nor closed in time")?
}

/// One driver: its Start fixes the publish rate the model is configured for.
fn serve_one(
    args: &ServeLearnerArgs,
    requests: Requests<impl std::io::Read>,
    output: impl Write,
) -> Result<()> {
    Ok(serve_driver(
        args.model,
        &args.options.options(),
        requests,
        output,
    )?)
}
