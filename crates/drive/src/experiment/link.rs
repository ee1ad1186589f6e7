//! A driver's connection to one world: the socket side of
//! `docs/spec/experiments.md` §2 and the pacing of `docs/spec/world.md` §8.
//! The world is a daemon behind a socket, or embedded in this process
//! ([`sim_plugin::server::EmbeddedWorld`], lock-step only): both are sent
//! the same messages and answer with the same states, the embedded one
//! without a round trip per state.
//!
//! * **lock-step**: the world waits for Advance after every publish. The
//!   link sends Advance, takes the first state produced after it (its
//!   `applied_seq` covers the Advance, so a stale or unsolicited state is
//!   skipped), lets the driver handle it and sends the driver's commands;
//!   then the next Advance. Exactly one Advance is ever outstanding, so the
//!   driver's commands are always in force from the next interval on.
//! * **realtime**: the world does not wait. The link handles every state as
//!   it comes and counts the messages whose handling took longer than the
//!   original's budget of 2/f seconds (`docs/spec/experiments.md` §6).

use std::sync::Arc;
use std::time::Instant;

use learner::Model;
use serde::{Deserialize, Serialize};

use super::driver::{Driver, Task};
use super::run_cache::{Cursor, Next, Path, RunCache, RunCacheError};
use super::ExperimentError;
use crate::frame::{frame_from_state, Shapes};
use crate::latency::budget;
use crate::results::run_info::Timing;
use pushlearn::client::{ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb::{self, client_message::Payload, server_message};
use pushlearn::wire::{validate, TimingMode};
use sim_plugin::server::{EmbeddedWorld, Latency};
use sim_plugin::Scene;

/// How a link paces the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Pacing {
    /// Send Advance after handling each state.
    Lockstep,
    /// React to a free-running world.
    Realtime,
}

impl Pacing {
    /// How to pace a world in `mode`.
    #[must_use]
    pub fn of(mode: TimingMode) -> Self {
        match mode {
            TimingMode::Lockstep => Pacing::Lockstep,
            TimingMode::Realtime => Pacing::Realtime,
        }
    }

    fn timing_mode(self) -> TimingMode {
        match self {
            Pacing::Lockstep => TimingMode::Lockstep,
            Pacing::Realtime => TimingMode::Realtime,
        }
    }
}

/// What a driver asks of a world, the same of a daemon behind a socket
/// ([`SimClient`]) and of a world embedded in this process
/// ([`Embedded`]).
pub(crate) trait Wire {
    /// The world's Hello.
    fn hello(&self) -> &pb::Hello;

    /// Sends `batch` in order; the last seq (`None` for an empty batch).
    async fn send_all(&mut self, batch: Vec<Payload>) -> Result<Option<u64>, ExperimentError>;

    /// The first state with `applied_seq >= seq`; any `Error` from the world
    /// ends the wait.
    async fn wait_applied(&mut self, seq: u64) -> Result<pb::WorldState, ExperimentError>;

    /// The next state of a free-running world.
    async fn next_state(&mut self) -> Result<pb::WorldState, ExperimentError>;

    /// Fails with the first `Error` the world sent for a command so far.
    async fn sync(&mut self) -> Result<(), ExperimentError>;
}

impl Wire for SimClient {
    fn hello(&self) -> &pb::Hello {
        SimClient::hello(self)
    }

    async fn send_all(&mut self, batch: Vec<Payload>) -> Result<Option<u64>, ExperimentError> {
        Ok(SimClient::send_all(self, batch).await?)
    }

    async fn wait_applied(&mut self, seq: u64) -> Result<pb::WorldState, ExperimentError> {
        Ok(SimClient::wait_applied(self, seq).await?)
    }

    async fn next_state(&mut self) -> Result<pb::WorldState, ExperimentError> {
        Ok(SimClient::next_state(self).await?)
    }

    async fn sync(&mut self) -> Result<(), ExperimentError> {
        Ok(SimClient::sync(self).await?)
    }
}

/// A lock-step world in this process, sent numbered messages as a
/// [`SimClient`] sends them; what it answers is read as the client reads
/// the socket.
#[derive(Debug)]
pub(crate) struct Embedded {
    world: EmbeddedWorld,
    hello: pb::Hello,
    last_seq: u64,
}

impl Embedded {
    /// The world of the built-in scene `scene` with latency emulation up
    /// to `latency_max` steps (`None`: none), as `pushlearn-sim serve
    /// --scene SCENE --mode lockstep [--latency-max L]` starts it.
    ///
    /// # Errors
    /// An unknown scene, or a world that cannot be built.
    pub fn new(scene: &str, latency_max: Option<u32>) -> Result<Self, ExperimentError> {
        let embedded = |why: String| ExperimentError::Embedded(why);
        let scene = Scene::builtin(scene).map_err(|err| embedded(err.to_string()))?;
        // The daemon's default seed; every job reseeds it anyway.
        let latency = latency_max.map(|max_steps| Latency { max_steps, seed: 0 });
        let world =
            EmbeddedWorld::new(scene, None, latency).map_err(|err| embedded(err.to_string()))?;
        Ok(Self {
            hello: world.hello(),
            world,
            last_seq: 0,
        })
    }

    /// The wall time the world has spent on physics, and its states.
    fn physics(&self) -> (std::time::Duration, u64) {
        self.world.physics()
    }

    /// The next answer; none left means the world has said all it will.
    fn next(&mut self, waiting_for: &str) -> Result<server_message::Payload, ExperimentError> {
        loop {
            let Some(message) = self.world.next_message() else {
                return Err(ExperimentError::Incomplete(format!(
                    "the embedded world sent no {waiting_for}"
                )));
            };
            if let Some(payload) = message.payload {
                return Ok(payload);
            }
        }
    }
}

impl Wire for Embedded {
    fn hello(&self) -> &pb::Hello {
        &self.hello
    }

    async fn send_all(&mut self, batch: Vec<Payload>) -> Result<Option<u64>, ExperimentError> {
        let mut messages = Vec::with_capacity(batch.len());
        for payload in batch {
            let message = pb::ClientMessage::new(0, payload);
            validate(&message).map_err(ClientError::from)?;
            messages.push(message);
        }
        let mut last = None;
        for mut message in messages {
            self.last_seq += 1;
            message.seq = self.last_seq;
            self.world
                .send(&message)
                .map_err(|err| ExperimentError::Embedded(err.to_string()))?;
            last = Some(message.seq);
        }
        Ok(last)
    }

    async fn wait_applied(&mut self, seq: u64) -> Result<pb::WorldState, ExperimentError> {
        loop {
            match self.next("state with the command applied")? {
                server_message::Payload::WorldState(state) if state.applied_seq >= seq => {
                    return Ok(state)
                }
                server_message::Payload::WorldState(_) | server_message::Payload::Hello(_) => {}
                server_message::Payload::Error(error) => {
                    return Err(ClientError::from(error).into())
                }
            }
        }
    }

    async fn next_state(&mut self) -> Result<pb::WorldState, ExperimentError> {
        Err(ExperimentError::Embedded(
            "an embedded world runs in lock-step only".into(),
        ))
    }

    async fn sync(&mut self) -> Result<(), ExperimentError> {
        while let Some(message) = self.world.next_message() {
            if let Some(server_message::Payload::Error(error)) = message.payload {
                return Err(ClientError::from(error).into());
            }
        }
        Ok(())
    }
}

/// A link's world.
#[derive(Debug)]
enum Conn {
    Socket(Box<SimClient>),
    Embedded(Box<Embedded>),
}

/// One connection to a world, with its own single-threaded runtime so that a
/// worker thread can drive it with plain blocking calls.
#[derive(Debug)]
pub struct WorldLink {
    runtime: tokio::runtime::Runtime,
    conn: Conn,
    pacing: Pacing,
    /// Set when recorded runs are reused (lock-step only; see
    /// [`super::run_cache`]), with the batch the last driver left unsent.
    replay: Option<(Cursor, Vec<Payload>)>,
    /// The last batch written to the world, for the message when the world
    /// dies.
    last_sent: Vec<Payload>,
}

impl WorldLink {
    /// Connects and checks that the world's timing mode matches `pacing`.
    ///
    /// # Errors
    /// Connection failures, or a world in the other timing mode.
    pub fn connect(addr: &str, pacing: Pacing) -> Result<Self, ExperimentError> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(ExperimentError::Runtime)?;
        let client = runtime.block_on(SimClient::connect_with(addr, ClientOptions::default()))?;
        let found = client.hello().timing();
        if found != Ok(pacing.timing_mode()) {
            return Err(ExperimentError::WrongMode {
                addr: addr.to_owned(),
                found: found.map_or_else(|unknown| unknown.0, |mode| mode.to_string()),
                wanted: pacing.timing_mode().as_str(),
            });
        }
        Ok(Self::new(runtime, Conn::Socket(Box::new(client)), pacing))
    }

    /// A lock-step world of `scene` embedded in this process, with latency
    /// emulation up to `latency_max` steps (`None`: none).
    ///
    /// # Errors
    /// An unknown scene, or a world that cannot be built.
    pub fn embedded(scene: &str, latency_max: Option<u32>) -> Result<Self, ExperimentError> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .build()
            .map_err(ExperimentError::Runtime)?;
        let world = Embedded::new(scene, latency_max)?;
        Ok(Self::new(
            runtime,
            Conn::Embedded(Box::new(world)),
            Pacing::Lockstep,
        ))
    }

    fn new(runtime: tokio::runtime::Runtime, conn: Conn, pacing: Pacing) -> Self {
        Self {
            runtime,
            conn,
            pacing,
            replay: None,
            last_sent: Vec::new(),
        }
    }

    fn hello(&self) -> &pb::Hello {
        match &self.conn {
            Conn::Socket(client) => client.hello(),
            Conn::Embedded(world) => world.hello(),
        }
    }

    /// Serves states from `cache` where it has them and records the others
    /// there (see [`super::run_cache`]); `latency` tells whether the world
    /// emulates command latency (its Hello does not say). Only for a
    /// lock-step world: in realtime the stream depends on more than the
    /// commands, so nothing is reused there.
    pub fn reuse_runs(&mut self, cache: Arc<RunCache>, latency: bool) {
        if self.pacing == Pacing::Lockstep {
            let rate = self.hello().publish_rate;
            self.replay = Some((Cursor::new(cache, rate, latency), Vec::new()));
        }
    }

    /// The scene the world reported in its Hello.
    #[must_use]
    pub fn scene(&self) -> &str {
        &self.hello().scene
    }

    /// Checks that the world runs `scene`.
    ///
    /// # Errors
    /// [`ExperimentError::WrongScene`].
    pub fn require_scene(&self, scene: &str) -> Result<(), ExperimentError> {
        if self.scene() == scene {
            Ok(())
        } else {
            Err(ExperimentError::WrongScene {
                found: self.scene().to_owned(),
                wanted: scene.to_owned(),
            })
        }
    }

    /// Checks that the world emulates command latency up to `latency_max`
    /// steps (`None`: not at all), as its Hello says; the report records
    /// the experiment's value, which must be the world's.
    ///
    /// # Errors
    /// The world's latency emulation differs.
    pub fn require_latency(&self, latency_max: Option<u32>) -> Result<(), ExperimentError> {
        let found = self.hello().latency_max_steps;
        if found == latency_max {
            return Ok(());
        }
        let describe = |l: Option<u32>| {
            l.map_or_else(
                || "no latency emulation".to_owned(),
                |l| format!("latency emulation up to {l} steps"),
            )
        };
        Err(ExperimentError::WrongLatency {
            found: describe(found),
            wanted: describe(latency_max),
        })
    }

    /// Runs `driver` until its job is done. `setup` is sent first (e.g. the
    /// job's latency seed).
    ///
    /// # Errors
    /// Socket errors, and any command the world refuses.
    pub fn run_driver<M: Model, T: Task<M>>(
        &mut self,
        driver: &mut Driver<M, T>,
        setup: Vec<Payload>,
    ) -> Result<Timing, ExperimentError> {
        match &mut self.conn {
            Conn::Socket(client) => run_on_link(
                &self.runtime,
                client.as_mut(),
                self.pacing,
                &mut self.replay,
                &mut self.last_sent,
                driver,
                setup,
            ),
            Conn::Embedded(world) => {
                let (seconds, states) = world.physics();
                let waited = world.world.waited_for_ode();
                let mut timing = run_on_link(
                    &self.runtime,
                    world.as_mut(),
                    self.pacing,
                    &mut self.replay,
                    &mut self.last_sent,
                    driver,
                    setup,
                )?;
                let (seconds_after, states_after) = world.physics();
                timing.physics_seconds = (seconds_after - seconds).as_secs_f64();
                timing.physics_states = states_after - states;
                timing.physics_wait_seconds = (world.world.waited_for_ode() - waited).as_secs_f64();
                Ok(timing)
            }
        }
    }

    /// The last batch of commands written to the world, as `move(0, 0.5) +
    /// advance`.
    #[must_use]
    pub fn last_sent(&self) -> String {
        describe(&self.last_sent)
    }

    /// Closes the connection (an embedded world just ends).
    pub fn close(self) {
        let Self { runtime, conn, .. } = self;
        if let Conn::Socket(client) = conn {
            if let Err(err) = runtime.block_on(client.close()) {
                tracing::debug!(%err, "closing the world connection");
            }
        }
    }
}

/// [`WorldLink::run_driver`] on the link's world `wire`.
fn run_on_link<M: Model, T: Task<M>, W: Wire>(
    runtime: &tokio::runtime::Runtime,
    wire: &mut W,
    pacing: Pacing,
    replay: &mut Option<(Cursor, Vec<Payload>)>,
    last_sent: &mut Vec<Payload>,
    driver: &mut Driver<M, T>,
    setup: Vec<Payload>,
) -> Result<Timing, ExperimentError> {
    let mut sent = Sent(last_sent);
    match replay {
        Some((cursor, pending)) => {
            // After the last driver's commands, as on the socket: a latency
            // seed must end the job's first batch to start a root there.
            pending.extend(setup);
            cursor.start_job();
            let driven = runtime.block_on(run_replaying(wire, cursor, pending, driver, &mut sent));
            if driven.is_err() {
                // What this job recorded is not kept: a world that failed
                // mid-job may have been wrong before it failed (ODE aborts
                // on an internal assertion), and stored states reach later
                // jobs unchecked.
                cursor.withdraw_job();
            }
            driven
        }
        None => runtime.block_on(run_tracked(wire, pacing, driver, setup, &mut sent)),
    }
}

/// Runs `driver` against the world behind `client` until its job is done;
/// `setup` goes first.
///
/// # Errors
/// Socket errors, and any command the world refuses.
pub async fn run_driver<M: Model, T: Task<M>>(
    client: &mut SimClient,
    pacing: Pacing,
    driver: &mut Driver<M, T>,
    setup: Vec<Payload>,
) -> Result<Timing, ExperimentError> {
    let mut last = Vec::new();
    run_tracked(client, pacing, driver, setup, &mut Sent(&mut last)).await
}

/// The last batch written to a world.
struct Sent<'a>(&'a mut Vec<Payload>);

impl Sent<'_> {
    /// Sends `batch` in one write, remembering it.
    async fn send_all<W: Wire>(
        &mut self,
        wire: &mut W,
        batch: Vec<Payload>,
    ) -> Result<Option<u64>, ExperimentError> {
        if !batch.is_empty() {
            self.0.clone_from(&batch);
        }
        wire.send_all(batch).await
    }

    /// Sends `batch` and an Advance in one write; the Advance's seq.
    async fn send_with_advance<W: Wire>(
        &mut self,
        wire: &mut W,
        mut batch: Vec<Payload>,
    ) -> Result<u64, ExperimentError> {
        batch.push(Payload::advance());
        self.send_all(wire, batch)
            .await?
            .ok_or_else(|| ExperimentError::Incomplete("an Advance was not sent".into()))
    }
}

/// `move(0, 0.5) + advance`: a batch of commands for messages.
fn describe(batch: &[Payload]) -> String {
    use pushlearn::wire::pb::sim_control::Action;
    if batch.is_empty() {
        return "none".to_owned();
    }
    batch
        .iter()
        .map(|p| match p {
            Payload::Actuator(a) => {
                let d = a.direction.unwrap_or_default();
                format!("{}({}, {})", p.kind(), d.x, d.y)
            }
            Payload::SetPose(poses) => {
                let names: Vec<&str> = poses.models.iter().map(|m| m.name.as_str()).collect();
                format!("set_pose({})", names.join(", "))
            }
            Payload::Control(c) => match c.action {
                Some(Action::PublishRateHz(hz)) => format!("publish_rate({hz})"),
                Some(Action::LatencySeed(seed)) => format!("latency_seed({seed})"),
                _ => p.kind().to_owned(),
            },
        })
        .collect::<Vec<_>>()
        .join(" + ")
}

/// [`run_driver`], remembering the last batch sent in `sent`.
async fn run_tracked<M: Model, T: Task<M>, W: Wire>(
    client: &mut W,
    pacing: Pacing,
    driver: &mut Driver<M, T>,
    setup: Vec<Payload>,
    sent: &mut Sent<'_>,
) -> Result<Timing, ExperimentError> {
    // In lock-step the driver's commands take effect at the next Advance
    // whenever they arrive, so they go out with it in one write; in realtime
    // they go out at once.
    let mut pending = setup;
    if pacing == Pacing::Realtime {
        sent.send_all(client, std::mem::take(&mut pending)).await?;
    }
    let budget = budget(driver.publish_rate_hz());
    let shapes = Shapes::from_hello(client.hello());
    let mut timing = Timing::default();
    while !driver.is_done() {
        let state = match pacing {
            Pacing::Lockstep => {
                let advance = sent
                    .send_with_advance(client, std::mem::take(&mut pending))
                    .await?;
                client.wait_applied(advance).await?
            }
            Pacing::Realtime => client.next_state().await?,
        };
        let received = Instant::now();
        let commands = driver.on_state(&frame_from_state(&state, &shapes));
        match pacing {
            Pacing::Lockstep => pending = commands,
            Pacing::Realtime => {
                sent.send_all(client, commands).await?;
            }
        }
        timing.record(received.elapsed(), budget);
    }
    sent.send_all(client, pending).await?;
    // Surfaces a refusal of the last commands here rather than in the next job.
    client.sync().await?;
    Ok(timing)
}

/// [`run_driver`] in lock-step through a [`RunCache`]: states the cache holds
/// are handed to the driver without touching the world. The driver's last
/// commands stay in `pending` for the next job on this link, whose first
/// state follows them as it would on the socket.
async fn run_replaying<M: Model, T: Task<M>, W: Wire>(
    client: &mut W,
    cursor: &mut Cursor,
    pending: &mut Vec<Payload>,
    driver: &mut Driver<M, T>,
    sent: &mut Sent<'_>,
) -> Result<Timing, ExperimentError> {
    let budget = budget(driver.publish_rate_hz());
    let shapes = Shapes::from_hello(client.hello());
    let mut timing = Timing::default();
    while !driver.is_done() {
        let frame = match cursor.next(std::mem::take(pending)) {
            Next::Stored(frame) => frame,
            Next::Simulate { resync, batch } => {
                if let Some(path) = resync {
                    resync_world(client, cursor, path, sent).await?;
                }
                let state = send_and_advance(client, cursor, batch, sent).await?;
                cursor.simulated(frame_from_state(&state, &shapes))?
            }
        };
        let received = Instant::now();
        *pending = driver.on_state(&frame);
        timing.record(received.elapsed(), budget);
    }
    Ok(timing)
}

/// Sends `batch`, then Advance; the state that covers the Advance.
async fn send_and_advance<W: Wire>(
    client: &mut W,
    cursor: &mut Cursor,
    batch: Vec<Payload>,
    sent: &mut Sent<'_>,
) -> Result<pushlearn::wire::pb::WorldState, ExperimentError> {
    cursor.sent(&batch);
    let advance = sent.send_with_advance(client, batch).await?;
    client.wait_applied(advance).await
}

/// Brings the world to the end of a recorded path (from its rate and reset
/// batch, or from the frame the world produced last), each state checked
/// against the record.
async fn resync_world<W: Wire>(
    client: &mut W,
    cursor: &mut Cursor,
    path: Path,
    sent: &mut Sent<'_>,
) -> Result<(), ExperimentError> {
    let shapes = Shapes::from_hello(client.hello());
    if let Some(rate) = path.rate.filter(|&rate| cursor.needs_rate(rate)) {
        let set_rate = Payload::publish_rate(rate);
        cursor.sent(std::slice::from_ref(&set_rate));
        sent.send_all(client, vec![set_rate]).await?;
    }
    for (step, (batch, expected)) in (path.first_step..).zip(path.steps) {
        let state = send_and_advance(client, cursor, batch, sent).await?;
        cursor.resimulated();
        if frame_from_state(&state, &shapes) != *expected {
            return Err(RunCacheError::Diverged { step }.into());
        }
    }
    Ok(())
}
