//! `ctl record`: the world's frames to a file (`pushlearn::recording`), as a
//! recording proxy between one client and the world, or as an observer.
//!
//! Frames are passed on as bytes, never decoded and re-encoded: a proxy
//! must not drop fields a newer world or client added, and the file holds
//! exactly what crossed the sockets.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use bytes::{Bytes, BytesMut};
use futures::{SinkExt, StreamExt};
use prost::Message;
use pushlearn::recording::{Direction, RecordingWriter};
use pushlearn::wire::{pb, raw_frame_codec};
use tokio::net::{TcpListener, TcpStream};
use tokio::time::Instant;
use tokio_util::codec::{FramedRead, FramedWrite, LengthDelimitedCodec};

type Reader = FramedRead<tokio::net::tcp::OwnedReadHalf, LengthDelimitedCodec>;
type Writer = FramedWrite<tokio::net::tcp::OwnedWriteHalf, LengthDelimitedCodec>;

/// What was recorded, for the closing line.
#[derive(Debug, Default)]
struct Counts {
    from_world: u64,
    states: u64,
    from_client: u64,
}

/// Where and how to record.
pub struct RecordOptions<'a> {
    pub file: &'a Path,
    pub sim: &'a str,
    pub listen: Option<&'a str>,
    pub count: Option<u64>,
    pub timeout: Duration,
}

/// Runs `ctl record`.
pub async fn record(options: &RecordOptions<'_>) -> Result<()> {
    match options.listen {
        Some(listen) => proxy(options, listen).await,
        None => observe(options).await,
    }
}

async fn connect_world(options: &RecordOptions<'_>) -> Result<(Reader, Writer, BytesMut)> {
    let stream = tokio::time::timeout(options.timeout, TcpStream::connect(options.sim))
        .await
        .map_err(|_| anyhow::anyhow!("timed out connecting to the world at {}", options.sim))?
        .with_context(|| format!("cannot connect to the world at {}", options.sim))?;
    // Small frames, latency-sensitive (docs/protocol.md §8).
    stream.set_nodelay(true)?;
    let (read, write) = stream.into_split();
    let mut from_world = FramedRead::new(read, raw_frame_codec());
    let first = tokio::time::timeout(options.timeout, from_world.next())
        .await
        .map_err(|_| anyhow::anyhow!("the world at {} sent no Hello", options.sim))?;
    let hello = match first {
        Some(Ok(frame)) => frame,
        Some(Err(err)) => bail!("reading the world's Hello: {err}"),
        None => bail!("the world at {} closed before its Hello", options.sim),
    };
    match pb::ServerMessage::decode(hello.clone().freeze()).map(|m| m.payload) {
        Ok(Some(pb::server_message::Payload::Hello(_))) => {}
        Ok(Some(pb::server_message::Payload::Error(error))) => {
            bail!("the world refused the connection: {}", error.message)
        }
        _ => bail!("the world's first frame is not a Hello"),
    }
    Ok((
        from_world,
        FramedWrite::new(write, raw_frame_codec()),
        hello,
    ))
}

fn create(file: &Path, commands: bool, hello: &[u8]) -> Result<RecordingWriter<BufWriter<File>>> {
    let out = File::create(file).with_context(|| format!("cannot create {}", file.display()))?;
    RecordingWriter::new(BufWriter::new(out), commands, hello)
        .with_context(|| format!("cannot write {}", file.display()))
}

fn is_state(frame: &[u8]) -> bool {
    matches!(
        pb::ServerMessage::decode(frame).map(|m| m.payload),
        Ok(Some(pb::server_message::Payload::WorldState(_)))
    )
}

/// A proxy for one client: every frame both ways is recorded, then passed
/// on. Ends when the world closes (after the client has), or on Ctrl-C.
async fn proxy(options: &RecordOptions<'_>, listen: &str) -> Result<()> {
    // A bare port is on the loopback address: the proxy passes on commands
    // to the world from whoever connects.
    let listen = match listen.parse::<u16>() {
        Ok(port) => format!("127.0.0.1:{port}"),
        Err(_) => listen.to_owned(),
    };
    let listen = listen.as_str();
    let listener = TcpListener::bind(listen)
        .await
        .with_context(|| format!("cannot listen on {listen}"))?;
    let mut out = std::io::stdout().lock();
    // The one line a script or test waits for (as pushlearn-sim prints it).
    writeln!(out, "listening on {}", listener.local_addr()?)?;
    out.flush()?;
    drop(out);
    let (client, peer) = tokio::select! {
        accepted = listener.accept() => accepted.context("accepting the client")?,
        _ = tokio::signal::ctrl_c() => bail!("interrupted before a client connected; nothing recorded"),
    };
    // One session per recording: later clients are not served.
    drop(listener);
    client.set_nodelay(true)?;
    tracing::info!(%peer, "client connected; recording");
    let (mut from_world, mut to_world, hello) = connect_world(options).await?;
    let start = Instant::now();
    let mut file = create(options.file, true, &hello)?;
    let (client_read, client_write) = client.into_split();
    let mut from_client = FramedRead::new(client_read, raw_frame_codec());
    let mut to_client = FramedWrite::new(client_write, raw_frame_codec());
    let mut client_open = to_client.send(hello.freeze()).await.is_ok();
    let mut counts = Counts::default();
    let write_error = |file: &Path| format!("cannot write {}", file.display());
    loop {
        tokio::select! {
            frame = from_client.next(), if client_open => match frame {
                Some(Ok(frame)) => {
                    file.record(Direction::FromClient, start.elapsed(), &frame)
                        .with_context(|| write_error(options.file))?;
                    counts.from_client += 1;
                    if to_world.send(frame.freeze()).await.is_err() {
                        break;
                    }
                }
                end => {
                    if let Some(Err(err)) = end {
                        tracing::warn!("the client's stream ended badly: {err}");
                    }
                    // The world then sends what it has queued and closes.
                    client_open = false;
                    let _ = SinkExt::<Bytes>::close(&mut to_world).await;
                }
            },
            frame = from_world.next() => match frame {
                Some(Ok(frame)) => {
                    file.record(Direction::FromWorld, start.elapsed(), &frame)
                        .with_context(|| write_error(options.file))?;
                    counts.from_world += 1;
                    counts.states += u64::from(is_state(&frame));
                    if client_open && to_client.send(frame.freeze()).await.is_err() {
                        client_open = false;
                    }
                }
                Some(Err(err)) => {
                    tracing::warn!("the world's stream ended badly: {err}");
                    break;
                }
                None => break,
            },
            _ = tokio::signal::ctrl_c() => break,
        }
    }
    let _ = SinkExt::<Bytes>::close(&mut to_client).await;
    file.finish().with_context(|| write_error(options.file))?;
    eprintln!(
        "recorded {} frames from the world ({} states) and {} from the client to {}",
        counts.from_world,
        counts.states,
        counts.from_client,
        options.file.display()
    );
    Ok(())
}

/// An observer: the states the world publishes, until --count states, the
/// world closes, or Ctrl-C.
async fn observe(options: &RecordOptions<'_>) -> Result<()> {
    let (mut from_world, to_world, hello) = connect_world(options).await?;
    let start = Instant::now();
    let mut file = create(options.file, false, &hello)?;
    let mut counts = Counts::default();
    while options.count.is_none_or(|n| counts.states < n) {
        let frame = tokio::select! {
            frame = from_world.next() => frame,
            _ = tokio::signal::ctrl_c() => break,
        };
        match frame {
            Some(Ok(frame)) => {
                file.record(Direction::FromWorld, start.elapsed(), &frame)
                    .with_context(|| format!("cannot write {}", options.file.display()))?;
                counts.from_world += 1;
                counts.states += u64::from(is_state(&frame));
            }
            Some(Err(err)) => {
                tracing::warn!("the world's stream ended badly: {err}");
                break;
            }
            None => break,
        }
    }
    drop(to_world);
    file.finish()
        .with_context(|| format!("cannot write {}", options.file.display()))?;
    eprintln!(
        "recorded {} frames from the world ({} states) to {}",
        counts.from_world,
        counts.states,
        options.file.display()
    );
    Ok(())
}
