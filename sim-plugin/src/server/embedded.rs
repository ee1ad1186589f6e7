//! The daemon's lock-step world for a single client in the client's own
//! process: every command passes the daemon's checks on arrival (the
//! [`Admission`] and the wire's and scene's checks) and reaches the same
//! lock-step [`Stepper`], latency emulation included, so a client that sends
//! the same messages gets the same states and errors as over a socket,
//! without a round trip per state. The experiments step their worlds this
//! way (`docs/performance.md`).

use std::collections::VecDeque;

use pushlearn::wire::pb;

use super::gate::{operation, Admission, Refusal};
use super::{convert, state_message, Latency, ServerError, Timing, MAX_QUEUED_COMMANDS};
use crate::lockstep::{Accepted, Event, Op, Stepper};
use crate::scene::Scene;
use crate::world::{Command, Engine, StepError, World};

/// The client id of the one client.
const CLIENT: u64 = 1;

/// Held by an embedded world while it runs an interval. ODE steps one world
/// at a time per process anyway (`ode::World::step` takes a process-wide
/// lock for each 1 ms step); taking turns per interval instead of per step
/// spares the workers a lock hand-over at every step while their learners
/// still run in parallel (`docs/performance.md` §1, "Embedded worlds").
static INTERVAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// What [`hold_for_fork`] holds: no embedded world is in an interval, and
/// no thread inside ODE, until it is dropped.
pub struct ForkHold {
    _ode: std::sync::MutexGuard<'static, ()>,
    _interval: std::sync::MutexGuard<'static, ()>,
}

/// Waits until no embedded world steps and holds them all, for a fork: a
/// lock held by another thread at the fork stays held in the child, which
/// then waits for ever (16 of 20 children of a process stepping a world on
/// another thread did). Taken in the stepping order, interval then ODE.
pub fn hold_for_fork() -> ForkHold {
    let interval = INTERVAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    ForkHold {
        _ode: ode::hold_for_fork(),
        _interval: interval,
    }
}

/// A lock-step world served to one in-process client.
pub struct EmbeddedWorld {
    stepper: Stepper,
    scene: Scene,
    engine: Engine,
    timing: Timing,
    publish_rate_hz: u32,
    admission: Admission,
    /// What the daemon would have written to the client, oldest first.
    outbox: VecDeque<pb::ServerMessage>,
    /// How long its Advances waited for other embedded worlds' intervals.
    waited_for_turn: std::time::Duration,
}

impl std::fmt::Debug for EmbeddedWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmbeddedWorld")
            .field("scene", &self.scene.name)
            .field("timing", &self.timing)
            .field("publish_rate_hz", &self.publish_rate_hz)
            .field("queued", &self.outbox.len())
            .finish_non_exhaustive()
    }
}

impl EmbeddedWorld {
    /// The world of `scene` in lock-step, with `latency` emulation, at
    /// `publish_rate_hz` (`None`: the scene's), as `pushlearn-sim serve
    /// --mode lockstep` would start it.
    ///
    /// # Errors
    /// The world cannot be built, or the rate does not divide 1000.
    pub fn new(
        scene: Scene,
        publish_rate_hz: Option<u32>,
        latency: Option<Latency>,
    ) -> Result<EmbeddedWorld, ServerError> {
        EmbeddedWorld::on(scene, Engine::Ode, publish_rate_hz, latency)
    }

    /// Like [`EmbeddedWorld::new`] on `engine`, as `pushlearn-sim serve
    /// --mode lockstep --engine ENGINE` would start it.
    ///
    /// # Errors
    /// The world cannot be built (or this build lacks the engine), or the
    /// rate does not divide 1000.
    pub fn on(
        scene: Scene,
        engine: Engine,
        publish_rate_hz: Option<u32>,
        latency: Option<Latency>,
    ) -> Result<EmbeddedWorld, ServerError> {
        let mut world = World::on(&scene, engine)?;
        if let Some(hz) = publish_rate_hz {
            world
                .apply(Command::SetPublishRate(hz))
                .map_err(ServerError::PublishRate)?;
        }
        Ok(EmbeddedWorld {
            stepper: Stepper::new(world, latency),
            publish_rate_hz: publish_rate_hz.unwrap_or(scene.publish_rate_hz),
            scene,
            engine,
            timing: Timing::Lockstep { latency },
            admission: Admission::default(),
            outbox: VecDeque::new(),
            waited_for_turn: std::time::Duration::ZERO,
        })
    }

    /// The Hello the daemon greets a connection with.
    #[must_use]
    pub fn hello(&self) -> pb::Hello {
        convert::hello(
            &self.scene,
            self.publish_rate_hz,
            self.timing.mode(),
            self.timing.latency().map(|latency| latency.max_steps),
            self.engine,
        )
    }

    /// Takes `message` as the daemon takes a message from its client: a
    /// refusal becomes an `Error` answering its seq, an Advance runs the
    /// world to its next publish. What the daemon would send back waits in
    /// [`EmbeddedWorld::next_message`].
    ///
    /// # Errors
    /// A step failed in a way the world cannot recover from (the daemon
    /// stops then).
    pub fn send(&mut self, message: &pb::ClientMessage) -> Result<(), StepError> {
        let op = match operation(message, &self.scene)
            .and_then(|op| self.admission.check(&op, self.timing).map(|()| op))
        {
            Ok(op) => op,
            Err(refusal) => {
                self.outbox.push_back(refusal.reply(message.seq));
                return Ok(());
            }
        };
        if !matches!(op, Op::Advance) && self.stepper.pending() >= MAX_QUEUED_COMMANDS {
            self.outbox.push_back(Refusal::Busy.reply(message.seq));
            return Ok(());
        }
        self.admission.note(&op);
        let asked = std::time::Instant::now();
        // A poisoned lock guards nothing but the turn: take it over.
        let _turn = matches!(op, Op::Advance).then(|| {
            INTERVAL
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        });
        self.waited_for_turn += asked.elapsed();
        let Self {
            stepper,
            outbox,
            publish_rate_hz,
            ..
        } = self;
        let accepted = Accepted {
            client: CLIENT,
            seq: message.seq,
            op,
        };
        stepper.take(accepted, &mut |event| match event {
            Event::Published {
                snapshot,
                publish_seq,
                applied_seq,
            } => outbox.push_back(state_message(&snapshot, publish_seq, applied_seq)),
            Event::Refused { seq, error, .. } => outbox.push_back(pb::ServerMessage::error(
                seq,
                pb::error::Kind::RefusedByWorld,
                error.to_string(),
            )),
            Event::PublishRate(hz) => *publish_rate_hz = hz,
            Event::Diverged(err) => outbox.push_back(pb::ServerMessage::error(
                0,
                pb::error::Kind::PhysicsBlewUp,
                err.to_string(),
            )),
        })
    }

    /// Whether [`EmbeddedWorld::send`] would accept `message` now, without
    /// sending it: `Err` is the refusal's `Error` text. For a caller that
    /// must check several commands (or worlds) before any takes effect.
    ///
    /// # Errors
    /// The daemon's refusal of `message`.
    pub fn check(&self, message: &pb::ClientMessage) -> Result<(), String> {
        let op = operation(message, &self.scene)
            .and_then(|op| self.admission.check(&op, self.timing).map(|()| op))
            .map_err(|refusal| refusal.to_string())?;
        if !matches!(op, Op::Advance) && self.stepper.pending() >= MAX_QUEUED_COMMANDS {
            return Err(Refusal::Busy.to_string());
        }
        Ok(())
    }

    /// The wall time this world has spent stepping its physics, and the
    /// states it published in it: what a state costs, measured.
    #[must_use]
    pub fn physics(&self) -> (std::time::Duration, u64) {
        self.stepper.physics()
    }

    /// How long this world's steps waited for other worlds of the process
    /// to finish theirs: ODE steps one world at a time per process.
    #[must_use]
    pub fn waited_for_ode(&self) -> std::time::Duration {
        self.waited_for_turn + self.stepper.waited_for_ode()
    }

    /// The next message the daemon would have written to the client.
    pub fn next_message(&mut self) -> Option<pb::ServerMessage> {
        self.outbox.pop_front()
    }
}
