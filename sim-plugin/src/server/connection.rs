//! One client: read its frames and admit its commands, and write its
//! outgoing queue, concurrently, until either side ends.

use std::fmt;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use pushlearn::wire::pb;
use pushlearn::wire::{FrameReader, FrameWriter, ServerConnection, WireError};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::TcpStream;
use tokio::sync::OwnedSemaphorePermit;
use tokio_util::sync::CancellationToken;

use super::gate::ClientId;
use super::outbox::Outbox;
use super::{Counters, Shared};

/// How long a turned-away client gets to take its `Error`.
const TURN_AWAY_LIMIT: Duration = Duration::from_secs(1);

/// Why a connection ended, for the log.
#[derive(Debug)]
enum Ending {
    /// The client closed the connection.
    ClientClosed,
    /// An oversized or undecodable frame (answered with an `Error`).
    BadFrame(WireError),
    /// The transport failed, in either direction.
    Broken(WireError),
    /// Its queue stayed full too long.
    TooSlow,
    /// Nothing passed either way for the idle limit.
    Idle(Duration),
    /// The daemon is shutting down.
    Shutdown,
}

impl fmt::Display for Ending {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Ending::ClientClosed => f.write_str("closed by the client"),
            Ending::BadFrame(err) => write!(f, "bad frame: {err}"),
            Ending::Broken(err) => write!(f, "connection broken: {err}"),
            Ending::TooSlow => f.write_str("too slow: its queue stayed full"),
            Ending::Idle(limit) => write!(f, "idle: nothing passed either way for {limit:?}"),
            Ending::Shutdown => f.write_str("shutting down"),
        }
    }
}

/// Serves one client until it leaves, breaks the protocol, falls too far
/// behind or the daemon stops. `_permit` holds its place among the
/// `max_clients`.
pub(super) async fn serve(
    stream: TcpStream,
    peer: SocketAddr,
    shared: Arc<Shared>,
    disconnect: CancellationToken,
    _permit: OwnedSemaphorePermit,
) {
    Counters::add(&shared.counters.connections, 1);
    let outbox = Arc::new(Outbox::new(
        peer,
        shared.client_queue,
        shared.slow_client_limit,
        disconnect.clone(),
    ));
    // Queued before the client is registered for states: Hello comes first.
    outbox.push_reply(shared.gate.hello().into());
    let client = shared.clients.register(outbox.clone());
    tracing::info!(%peer, client, "client connected");
    let (reader, writer) = ServerConnection::new(stream).split();
    let ending = exchange(reader, writer, client, &shared, &outbox, &disconnect).await;
    shared.clients.unregister(client);
    let (states_sent, states_dropped) = outbox.counts();
    tracing::info!(
        %peer,
        client,
        states_sent,
        states_dropped,
        "client disconnected: {ending}"
    );
}

async fn exchange(
    reader: FrameReader<pb::ClientMessage, OwnedReadHalf>,
    writer: FrameWriter<pb::ServerMessage, OwnedWriteHalf>,
    client: ClientId,
    shared: &Shared,
    outbox: &Outbox,
    disconnect: &CancellationToken,
) -> Ending {
    let activity = Activity::new();
    let writing = write_queue(writer, outbox, &activity);
    tokio::pin!(writing);
    let reading = read_commands(reader, client, shared, outbox, &activity);
    tokio::pin!(reading);
    let ending = tokio::select! {
        () = disconnect.cancelled() => return cancelled(outbox),
        // Dropping the reader frees a frame the client began and stalled.
        () = activity.idle(shared.idle_limit) => return Ending::Idle(shared.idle_limit),
        written = &mut writing => return match written {
            Ok(()) => Ending::ClientClosed,
            Err(err) => Ending::Broken(err),
        },
        ending = &mut reading => ending,
    };
    // The client stopped sending, or sent a bad frame: write what is queued
    // (e.g. the Error naming the bad frame), then close. A client that does
    // not read it is not waited for longer than the slow-client limit.
    outbox.close();
    tokio::select! {
        () = disconnect.cancelled() => return cancelled(outbox),
        _ = tokio::time::timeout(shared.slow_client_limit, &mut writing) => {}
    }
    ending
}

/// When a frame last passed over a connection, either way.
struct Activity {
    started: Instant,
    /// Milliseconds after `started`.
    last: AtomicU64,
}

impl Activity {
    fn new() -> Activity {
        Activity {
            started: Instant::now(),
            last: AtomicU64::new(0),
        }
    }

    fn touch(&self) {
        let now = u64::try_from(self.started.elapsed().as_millis()).unwrap_or(u64::MAX);
        self.last.store(now, Ordering::Relaxed);
    }

    /// Resolves once nothing has passed for `limit`. A frame counts when it
    /// is whole: a client trickling one, or stalled inside one, is idle.
    async fn idle(&self, limit: Duration) {
        loop {
            let last = Duration::from_millis(self.last.load(Ordering::Relaxed));
            let quiet = self.started.elapsed().saturating_sub(last);
            match limit.checked_sub(quiet) {
                Some(left) if !left.is_zero() => tokio::time::sleep(left).await,
                _ => return,
            }
        }
    }
}

fn cancelled(outbox: &Outbox) -> Ending {
    if outbox.was_too_slow() {
        Ending::TooSlow
    } else {
        Ending::Shutdown
    }
}

/// Reads frames and admits their commands, answering refusals at once.
/// Returns when the client closed its side or broke the framing.
async fn read_commands(
    mut reader: FrameReader<pb::ClientMessage, OwnedReadHalf>,
    client: ClientId,
    shared: &Shared,
    outbox: &Outbox,
    activity: &Activity,
) -> Ending {
    loop {
        let message = match reader.read().await {
            Ok(Some(message)) => {
                activity.touch();
                message
            }
            Ok(None) => return Ending::ClientClosed,
            Err(err) => {
                return match err.error_reply() {
                    Some(reply) => {
                        tracing::warn!(peer = %outbox.peer(), "{err}; closing the connection");
                        outbox.push_reply(reply);
                        Ending::BadFrame(err)
                    }
                    None => Ending::Broken(err),
                };
            }
        };
        let Err(refusal) = shared.gate.admit(client, &message) else {
            continue;
        };
        Counters::add(&shared.counters.refused_commands, 1);
        if refusal.is_barrier() {
            tracing::debug!(peer = %outbox.peer(), seq = message.seq, "barrier answered");
        } else {
            tracing::info!(peer = %outbox.peer(), seq = message.seq, "refused: {refusal}");
        }
        shared.count(outbox, outbox.push_reply(refusal.reply(message.seq)));
    }
}

/// Writes the queue to the socket; ends when the queue is closed and empty.
async fn write_queue(
    mut writer: FrameWriter<pb::ServerMessage, OwnedWriteHalf>,
    outbox: &Outbox,
    activity: &Activity,
) -> Result<(), WireError> {
    while let Some(message) = outbox.next().await {
        writer.write(&message).await?;
        activity.touch();
    }
    writer.close().await
}

/// Tells a client beyond `max_clients` so, and closes.
pub(crate) async fn turn_away(stream: TcpStream, peer: SocketAddr, max_clients: usize) {
    tracing::warn!(%peer, "turning a client away: {max_clients} clients are connected");
    let (_reader, mut writer) = ServerConnection::new(stream).split();
    let refusal = pb::ServerMessage::error(
        0,
        pb::error::Kind::TooManyClients,
        format!("too many clients: this world serves at most {max_clients} at once"),
    );
    let told = tokio::time::timeout(TURN_AWAY_LIMIT, async {
        writer.write(&refusal).await?;
        writer.close().await
    })
    .await;
    if let Ok(Err(err)) = told {
        tracing::debug!(%peer, "could not tell the client: {err}");
    }
}
