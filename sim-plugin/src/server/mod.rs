//! The world daemon: the thesis world on its own physics thread, served to
//! any number of TCP clients (`docs/protocol.md`).
//!
//! The pieces, after mini-redis:
//!
//! * this module: [`Config`], [`Server::start`] and the listener (accept
//!   loop, connection cap, shutdown), kept apart from the per-connection
//!   handler;
//! * `connection`: one task per client that reads frames and writes the
//!   client's outgoing queue; it speaks envelopes, never bytes;
//! * `gate`: the checks every command passes on arrival, and the one lock
//!   that fixes the order in which commands reach the world;
//! * `physics`: the OS thread that owns the [`World`](crate::World), applies
//!   commands at step boundaries, paces or lock-steps the stepping and
//!   publishes states;
//! * `outbox`: a client's bounded outgoing queue (the slow-client policy);
//! * `convert`: protobuf messages to world commands and back;
//! * `embedded`: the same checks and lock-step world for one client in its
//!   own process, without sockets or threads ([`EmbeddedWorld`]).
//!
//! The physics thread and the tokio tasks only share plain data behind
//! `std::sync::Mutex`es (never held across an `.await`) and a channel of
//! accepted commands; neither side ever waits for the other, so no client can
//! stall the physics and the physics never stalls a connection.

pub(crate) mod connection;
mod convert;
mod embedded;
pub(crate) mod gate;
mod outbox;
mod physics;

use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use pushlearn::wire::pb;

use tokio::net::TcpListener;
use tokio::sync::{oneshot, Semaphore};
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use crate::scene::Scene;
use crate::world::{CommandError, Engine, WorldError};

/// The port of the original Gazebo world, kept as the default.
pub const DEFAULT_PORT: u16 = 11345;

/// Physics steps per wall-clock second in realtime mode: the thesis's
/// `real_time_update_rate` (real-time factor 0.5 with 1 ms steps).
pub const DEFAULT_REAL_TIME_RATE: u32 = 500;

/// Clients served at once by default. Each costs one task and a bounded
/// queue; the limit only stops a runaway script from exhausting the process.
pub const DEFAULT_MAX_CLIENTS: usize = 64;

/// Messages a client's outgoing queue holds by default: 10 s of states at
/// 100 Hz, on top of what the kernel's socket buffers hold.
pub const DEFAULT_CLIENT_QUEUE: usize = 1024;

/// How long a client's queue may stay full before the client is
/// disconnected, by default.
pub const DEFAULT_SLOW_CLIENT_LIMIT: Duration = Duration::from_secs(5);

/// How long nothing may pass over a connection, either way, before the
/// client is disconnected, by default.
pub const DEFAULT_IDLE_LIMIT: Duration = Duration::from_secs(60);

/// Accepted commands waiting to be applied, over all clients: on the
/// channel to the physics thread and held by the latency emulation for the
/// next Advance. In realtime mode the physics thread applies every waiting
/// command at each step boundary and in lock-step mode between intervals,
/// so this is only reached by a client flooding a lock-step world with
/// latency emulation without ever advancing it; commands beyond it are
/// refused (`busy:`), in the daemon and in an [`EmbeddedWorld`] alike.
pub const MAX_QUEUED_COMMANDS: usize = 65_536;

/// How the world paces its steps (`docs/spec/world.md` §8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timing {
    /// Step continuously at `steps_per_second` wall-clock steps per second
    /// (0: as fast as possible).
    Realtime { steps_per_second: u32 },
    /// After each publish, wait for an Advance; with `latency`, delay each
    /// Move by a seeded random number of steps.
    Lockstep { latency: Option<Latency> },
}

impl Timing {
    /// The wire's name of the mode.
    pub fn mode(self) -> pushlearn::wire::TimingMode {
        match self {
            Timing::Realtime { .. } => pushlearn::wire::TimingMode::Realtime,
            Timing::Lockstep { .. } => pushlearn::wire::TimingMode::Lockstep,
        }
    }

    /// The latency emulation, if any.
    pub fn latency(self) -> Option<Latency> {
        match self {
            Timing::Lockstep { latency } => latency,
            Timing::Realtime { .. } => None,
        }
    }
}

pub use crate::lockstep::Latency;
pub use convert::shapes;
pub use embedded::{hold_for_fork, EmbeddedWorld, ForkHold};

/// Everything the daemon needs to start.
#[derive(Debug, Clone)]
pub struct Config {
    pub scene: Scene,
    pub timing: Timing,
    /// Publish rate in Hz (must divide 1000); `None` keeps the scene's.
    pub publish_rate_hz: Option<u32>,
    /// Clients served at once; one more is told so and closed.
    pub max_clients: usize,
    /// Messages a client's outgoing queue holds; when it is full, the oldest
    /// state in it is dropped (`docs/protocol.md`, "Slow clients").
    pub client_queue: usize,
    /// A client whose queue stays full this long is disconnected.
    pub slow_client_limit: Duration,
    /// A client over which nothing passed this long, no frame read from it
    /// and none written to it, is disconnected.
    pub idle_limit: Duration,
    /// The physics engine (`--engine`).
    pub engine: Engine,
}

impl Config {
    /// Realtime at the thesis's rate with the default limits.
    pub fn new(scene: Scene) -> Config {
        Config {
            scene,
            timing: Timing::Realtime {
                steps_per_second: DEFAULT_REAL_TIME_RATE,
            },
            publish_rate_hz: None,
            max_clients: DEFAULT_MAX_CLIENTS,
            client_queue: DEFAULT_CLIENT_QUEUE,
            slow_client_limit: DEFAULT_SLOW_CLIENT_LIMIT,
            idle_limit: DEFAULT_IDLE_LIMIT,
            engine: Engine::Ode,
        }
    }

    fn check(&self) -> Result<(), ServerError> {
        let positive = |value: usize, what: &'static str| {
            if value == 0 {
                Err(ServerError::Config(format!("{what} must be at least 1")))
            } else {
                Ok(())
            }
        };
        positive(self.max_clients, "the maximum number of clients")?;
        if self.max_clients > Semaphore::MAX_PERMITS {
            return Err(ServerError::Config(format!(
                "at most {} clients are possible",
                Semaphore::MAX_PERMITS
            )));
        }
        positive(self.client_queue, "the client queue length")?;
        if self.slow_client_limit.is_zero() {
            return Err(ServerError::Config(
                "the slow-client limit must be positive".into(),
            ));
        }
        if self.idle_limit.is_zero() {
            return Err(ServerError::Config(
                "the idle timeout must be positive".into(),
            ));
        }
        Ok(())
    }
}

/// Why the daemon could not start or stopped on its own.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    #[error("invalid configuration: {0}")]
    Config(String),
    #[error("cannot build the world: {0}")]
    World(#[from] WorldError),
    #[error("invalid publish rate: {0}")]
    PublishRate(CommandError),
    #[error("cannot read the listening address: {0}")]
    Io(#[from] std::io::Error),
    #[error("the physics thread failed: {0}")]
    Physics(String),
}

/// Counters over the daemon's life, for logs and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Connections served (Hello sent).
    pub connections: u64,
    /// Connections turned away because `max_clients` were connected.
    pub refused_connections: u64,
    /// Commands answered with an `Error` (barriers included).
    pub refused_commands: u64,
    /// States dropped from full client queues, over all clients.
    pub states_dropped: u64,
    /// Clients disconnected because their queue stayed full too long.
    pub slow_disconnects: u64,
    /// States published by the world.
    pub published: u64,
}

#[derive(Debug, Default)]
struct Counters {
    connections: AtomicU64,
    refused_connections: AtomicU64,
    refused_commands: AtomicU64,
    states_dropped: AtomicU64,
    slow_disconnects: AtomicU64,
    published: AtomicU64,
}

impl Counters {
    fn add(counter: &AtomicU64, n: u64) {
        counter.fetch_add(n, Ordering::Relaxed);
    }

    fn snapshot(&self) -> Stats {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        Stats {
            connections: get(&self.connections),
            refused_connections: get(&self.refused_connections),
            refused_commands: get(&self.refused_commands),
            states_dropped: get(&self.states_dropped),
            slow_disconnects: get(&self.slow_disconnects),
            published: get(&self.published),
        }
    }
}

/// When a published state's writers are woken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wake {
    Now,
    /// By a later [`Shared::wake_writers`].
    Later,
}

/// What the connections, the gate and the physics thread share.
struct Shared {
    gate: gate::Gate,
    clients: outbox::Clients,
    counters: Counters,
    client_queue: usize,
    slow_client_limit: Duration,
    idle_limit: Duration,
}

impl Shared {
    /// Queues a published state for every client (never waits) and wakes
    /// their writers now, or leaves that to [`Shared::wake_writers`].
    fn broadcast_state(&self, state: &Arc<pb::ServerMessage>, wake: Wake) {
        Counters::add(&self.counters.published, 1);
        let now = Instant::now();
        self.clients.for_each(|outbox| {
            let pushed = match wake {
                Wake::Now => outbox.push_state(state, now),
                Wake::Later => outbox.queue_state(state, now),
            };
            self.count(outbox, pushed);
        });
    }

    /// Wakes every client's writer for what is queued.
    fn wake_writers(&self) {
        self.clients.for_each(outbox::Outbox::wake);
    }

    /// Queues an `Error` for every client.
    fn broadcast_reply(&self, reply: &pb::ServerMessage) {
        self.clients
            .for_each(|outbox| self.count(outbox, outbox.push_reply(reply.clone())));
    }

    /// Queues an `Error` for one client, if it is still connected.
    fn reply_to(&self, client: gate::ClientId, reply: pb::ServerMessage) {
        if let Some(outbox) = self.clients.get(client) {
            self.count(&outbox, outbox.push_reply(reply));
        }
    }

    /// Counts what became of a message queued for `outbox`.
    fn count(&self, outbox: &outbox::Outbox, pushed: outbox::Pushed) {
        match pushed {
            outbox::Pushed::DroppedOldest => Counters::add(&self.counters.states_dropped, 1),
            outbox::Pushed::TooSlow => {
                Counters::add(&self.counters.slow_disconnects, 1);
                tracing::warn!(
                    peer = %outbox.peer(),
                    "disconnecting a client that does not read: its queue stayed full for more \
                     than {:?}, or its unread answers exceed twice the queue",
                    self.slow_client_limit
                );
            }
            outbox::Pushed::Queued | outbox::Pushed::Closed => {}
        }
    }
}

/// The message the daemon publishes for `snapshot`: the per-publish work
/// beyond stepping (the writer then frames it). Public so that the overhead
/// bench (`sim-plugin/benches/round_trip.rs`) can charge the same work to the world
/// stepped in-process.
pub fn state_message(
    snapshot: &crate::world::Snapshot,
    publish_seq: u64,
    applied_seq: u64,
) -> pb::ServerMessage {
    convert::world_state(snapshot, publish_seq, applied_seq).into()
}

/// The daemon.
pub struct Server;

impl Server {
    /// Builds the world on a new physics thread and starts accepting
    /// clients on `listener`, on the current tokio runtime.
    pub async fn start(listener: TcpListener, config: Config) -> Result<ServerHandle, ServerError> {
        config.check()?;
        let addr = listener.local_addr()?;
        let shutdown = CancellationToken::new();
        let (commands, inbox) = std::sync::mpsc::channel();
        let shared = Arc::new(Shared {
            gate: gate::Gate::new(&config, commands),
            clients: outbox::Clients::default(),
            counters: Counters::default(),
            client_queue: config.client_queue,
            slow_client_limit: config.slow_client_limit,
            idle_limit: config.idle_limit,
        });
        let (ready_tx, ready_rx) = oneshot::channel();
        let physics = physics::spawn(
            config.clone(),
            inbox,
            shared.clone(),
            shutdown.clone(),
            ready_tx,
        )?;
        let built = ready_rx
            .await
            .map_err(|_| ServerError::Physics("it ended before the world was built".into()))?;
        if let Err(err) = built {
            // The thread ends right after reporting; it has nothing to add.
            let _ = tokio::task::spawn_blocking(move || physics.join()).await;
            return Err(err);
        }
        let tracker = TaskTracker::new();
        let listening = tokio::spawn(listen(
            listener,
            shared.clone(),
            config.max_clients,
            shutdown.clone(),
            tracker,
        ));
        tracing::info!(
            %addr,
            scene = %config.scene.name,
            mode = %config.timing.mode(),
            "serving the world"
        );
        Ok(ServerHandle {
            addr,
            shared,
            shutdown,
            listening: Some(listening),
            physics: Some(physics),
        })
    }
}

/// A running daemon. Dropping it stops the daemon without waiting;
/// [`ServerHandle::shutdown`] waits and reports how the physics thread ended.
pub struct ServerHandle {
    addr: SocketAddr,
    shared: Arc<Shared>,
    shutdown: CancellationToken,
    listening: Option<tokio::task::JoinHandle<()>>,
    physics: Option<std::thread::JoinHandle<Result<(), String>>>,
}

impl ServerHandle {
    /// The address the daemon listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The counters so far.
    pub fn stats(&self) -> Stats {
        self.shared.counters.snapshot()
    }

    /// Fault injection for tests, reachable from no client message or flag:
    /// after its next step the world finds `body` with a non-finite state,
    /// as when the physics blows up (`docs/protocol.md` §6).
    #[cfg(feature = "testing")]
    pub fn provoke_blow_up(&self, body: &str) {
        self.shared
            .gate
            .inject(gate::ToPhysics::BlowUp(body.to_owned()));
    }

    /// Resolves when the daemon stops by itself (the physics thread failed)
    /// or [`ServerHandle::shutdown`] began.
    pub async fn stopped(&self) {
        self.shutdown.cancelled().await;
    }

    /// Stops accepting, closes every connection, stops the physics thread
    /// and waits for all of it.
    pub async fn shutdown(mut self) -> Result<(), ServerError> {
        self.shutdown.cancel();
        if let Some(listening) = self.listening.take() {
            if let Err(err) = listening.await {
                tracing::error!("the listener task failed: {err}");
            }
        }
        self.shared.gate.stop_physics();
        let Some(physics) = self.physics.take() else {
            return Ok(());
        };
        let joined = tokio::task::spawn_blocking(move || physics.join())
            .await
            .map_err(|err| ServerError::Physics(err.to_string()))?;
        let stats = self.stats();
        tracing::info!(
            connections = stats.connections,
            refused_connections = stats.refused_connections,
            refused_commands = stats.refused_commands,
            states_dropped = stats.states_dropped,
            slow_disconnects = stats.slow_disconnects,
            published = stats.published,
            "stopped"
        );
        match joined {
            Ok(Ok(())) => Ok(()),
            Ok(Err(message)) => Err(ServerError::Physics(message)),
            Err(_) => Err(ServerError::Physics("it panicked".into())),
        }
    }
}

impl Drop for ServerHandle {
    fn drop(&mut self) {
        self.shutdown.cancel();
        self.shared.gate.stop_physics();
    }
}

/// The accept loop: hands each connection to its own task, turns away
/// connections beyond `max_clients`, and on shutdown waits for every
/// connection task to finish.
async fn listen(
    listener: TcpListener,
    shared: Arc<Shared>,
    max_clients: usize,
    shutdown: CancellationToken,
    tracker: TaskTracker,
) {
    let limit = Arc::new(Semaphore::new(max_clients));
    loop {
        let accepted = tokio::select! {
            () = shutdown.cancelled() => break,
            accepted = listener.accept() => accepted,
        };
        let (stream, peer) = match accepted {
            Ok(accepted) => accepted,
            Err(err) => {
                // Typically out of file descriptors: wait for some to be
                // released instead of spinning.
                tracing::warn!("accept failed: {err}");
                tokio::select! {
                    () = shutdown.cancelled() => break,
                    () = tokio::time::sleep(Duration::from_millis(100)) => continue,
                }
            }
        };
        match limit.clone().try_acquire_owned() {
            Ok(permit) => {
                tracker.spawn(connection::serve(
                    stream,
                    peer,
                    shared.clone(),
                    shutdown.child_token(),
                    permit,
                ));
            }
            Err(_) => {
                Counters::add(&shared.counters.refused_connections, 1);
                tracker.spawn(connection::turn_away(stream, peer, max_clients));
            }
        }
    }
    tracker.close();
    tracker.wait().await;
}
