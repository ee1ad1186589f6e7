//! Every command's checks on arrival, and the order in which accepted
//! commands reach the world.
//!
//! A command is checked completely before it is accepted, so that an invalid
//! one is answered at once and the world never sees it (`docs/spec/protocol.md` §3):
//! first the message-only checks of [`pushlearn::wire::validate`], then the
//! scene's (body names, positions), then those that depend on the commands
//! accepted before it (pause state, ghost count). The last kind is answered
//! from a mirror of exactly the state the world will be in once it has
//! applied everything accepted so far; the physics thread never changes
//! that state on its own (a divergence reset keeps pause and clears ghosts,
//! which only makes the mirror's ghost count err on the safe side).
//!
//! Checking against the mirror and handing the command to the physics
//! thread happen under one lock, so the order of acceptance is the order of
//! application, across all clients.

use std::collections::HashSet;
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Mutex, MutexGuard, PoisonError};

use pushlearn::wire::pb;
use pushlearn::wire::{validate, BodyName, Ghost, InvalidCommand};

use super::{convert, Config, Timing, MAX_QUEUED_COMMANDS};
use crate::scene::Scene;
use crate::world::{Command, CommandError, Engine, MAX_GHOSTS};

pub(crate) use crate::lockstep::{Accepted, ClientId, Op};

/// What the physics thread receives.
#[derive(Debug)]
pub(crate) enum ToPhysics {
    Command(Accepted),
    Stop,
    /// Test fault injection ([`super::ServerHandle::provoke_blow_up`]);
    /// no client message becomes one.
    #[cfg(feature = "testing")]
    BlowUp(String),
}

/// Why a command was not accepted. The text is what the `Error` carries.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum Refusal {
    /// The wire's checks, including the world-dependent ones it words.
    #[error(transparent)]
    Invalid(#[from] InvalidCommand),
    /// The world's own checks (e.g. a position beyond its bounds).
    #[error("{command}: {error}")]
    World {
        /// The command and body, e.g. `set_pose: body 'blockA'`.
        command: String,
        error: CommandError,
    },
    /// Too many accepted commands wait for the physics thread.
    #[error("busy: {MAX_QUEUED_COMMANDS} accepted commands are waiting to be applied; advance the world before sending more")]
    Busy,
    /// The physics thread has stopped.
    #[error("the world is shutting down")]
    Stopping,
}

impl Refusal {
    /// The `Error` answering command `seq`.
    pub fn reply(&self, seq: u64) -> pb::ServerMessage {
        let kind = match self {
            Refusal::Invalid(_) => pb::error::Kind::InvalidCommand,
            Refusal::World { .. } => pb::error::Kind::RefusedByWorld,
            Refusal::Busy => pb::error::Kind::Busy,
            Refusal::Stopping => pb::error::Kind::ShuttingDown,
        };
        pb::ServerMessage::error(seq, kind, self.to_string())
    }

    /// The refusal of an empty message, which clients send on purpose as a
    /// round-trip barrier: not worth more than a debug line.
    pub fn is_barrier(&self) -> bool {
        matches!(self, Refusal::Invalid(InvalidCommand::MissingPayload))
    }
}

/// The world's state as of every accepted command, where the checks on
/// arrival need it: what decides whether a well-formed command is accepted.
#[derive(Debug, Default)]
pub(crate) struct Admission {
    paused: bool,
    ghosts: HashSet<Ghost>,
}

/// The admission state and the channel behind it, under one lock.
#[derive(Debug)]
struct Mirror {
    admission: Admission,
    physics: Sender<ToPhysics>,
}

/// The arrival checks and the channel to the physics thread.
#[derive(Debug)]
pub(crate) struct Gate {
    scene: Scene,
    engine: Engine,
    timing: Timing,
    /// Current publish rate, for the Hello of new connections.
    publish_rate: AtomicU32,
    /// Accepted commands not yet taken by the physics thread.
    queued: AtomicUsize,
    mirror: Mutex<Mirror>,
}

impl Gate {
    pub fn new(config: &Config, physics: Sender<ToPhysics>) -> Gate {
        Gate {
            scene: config.scene.clone(),
            engine: config.engine,
            timing: config.timing,
            publish_rate: AtomicU32::new(
                config
                    .publish_rate_hz
                    .unwrap_or(config.scene.publish_rate_hz),
            ),
            queued: AtomicUsize::new(0),
            mirror: Mutex::new(Mirror {
                admission: Admission::default(),
                physics,
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Mirror> {
        // A panic elsewhere while holding the lock leaves plain data behind
        // that is still consistent (every update is a single assignment).
        self.mirror.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The first message of every connection.
    pub fn hello(&self) -> pb::Hello {
        convert::hello(
            &self.scene,
            self.publish_rate.load(Ordering::Relaxed),
            self.timing.mode(),
            self.timing.latency().map(|latency| latency.max_steps),
            self.engine,
        )
    }

    /// The physics thread applied a new publish rate.
    pub fn set_publish_rate(&self, hz: u32) {
        self.publish_rate.store(hz, Ordering::Relaxed);
    }

    /// Checks `message` from `client` and, if it passes, hands it to the
    /// physics thread behind everything accepted before it.
    pub fn admit(&self, client: ClientId, message: &pb::ClientMessage) -> Result<(), Refusal> {
        let op = operation(message, &self.scene)?;
        let mut mirror = self.lock();
        mirror.admission.check(&op, self.timing)?;
        // An Advance is what empties the queue, so it still passes a full
        // one, up to a second bound of its own.
        let limit = if matches!(op, Op::Advance) {
            2 * MAX_QUEUED_COMMANDS
        } else {
            MAX_QUEUED_COMMANDS
        };
        if self.queued.load(Ordering::Acquire) >= limit {
            return Err(Refusal::Busy);
        }
        mirror.admission.note(&op);
        // Counted before sending so the physics thread never takes more
        // than was counted.
        self.queued.fetch_add(1, Ordering::AcqRel);
        let accepted = Accepted {
            client,
            seq: message.seq,
            op,
        };
        if mirror.physics.send(ToPhysics::Command(accepted)).is_err() {
            self.queued.fetch_sub(1, Ordering::AcqRel);
            return Err(Refusal::Stopping);
        }
        Ok(())
    }

    /// The physics thread took `n` accepted commands off the channel.
    pub fn taken(&self, n: usize) {
        self.queued.fetch_sub(n, Ordering::AcqRel);
    }

    /// Hands the physics thread a test fault (never a client's command).
    #[cfg(feature = "testing")]
    pub fn inject(&self, fault: ToPhysics) {
        let _ = self.lock().physics.send(fault);
    }

    /// Asks the physics thread to stop after what it is doing.
    pub fn stop_physics(&self) {
        // Already gone is fine: it is stopping anyway.
        let _ = self.lock().physics.send(ToPhysics::Stop);
    }
}

impl Admission {
    /// Checks `op` against the world as it will be once everything
    /// accepted before it is applied, in `timing`.
    pub fn check(&self, op: &Op, timing: Timing) -> Result<(), Refusal> {
        match op {
            Op::Advance => match timing {
                Timing::Realtime { .. } => Err(InvalidCommand::AdvanceInRealtime.into()),
                Timing::Lockstep { .. } if self.paused => {
                    Err(InvalidCommand::AdvanceWhilePaused.into())
                }
                Timing::Lockstep { .. } => Ok(()),
            },
            Op::LatencySeed(_) if timing.latency().is_none() => {
                Err(InvalidCommand::LatencySeedWithoutLatency.into())
            }
            Op::LatencySeed(_) => Ok(()),
            Op::World(commands) => {
                let mut new_ghosts = HashSet::new();
                for ghost in commands.iter().filter_map(ghost) {
                    if !self.ghosts.contains(ghost)
                        && new_ghosts.insert(ghost)
                        && self.ghosts.len() + new_ghosts.len() > MAX_GHOSTS
                    {
                        return Err(Refusal::World {
                            command: format!(
                                "set_pose: body {}",
                                pushlearn::wire::quoted(&ghost.to_string())
                            ),
                            error: CommandError::TooManyGhosts,
                        });
                    }
                }
                Ok(())
            }
        }
    }

    /// Updates the state for an accepted `op`, as the world will change.
    pub fn note(&mut self, op: &Op) {
        let Op::World(commands) = op else { return };
        for command in commands {
            match command {
                Command::Pause => self.paused = true,
                Command::Unpause => self.paused = false,
                Command::Reset => self.ghosts.clear(),
                Command::SetPose {
                    name: BodyName::Ghost(ghost),
                    ..
                } => {
                    self.ghosts.insert(ghost.clone());
                }
                Command::Actuator { .. } | Command::SetPose { .. } | Command::SetPublishRate(_) => {
                }
            }
        }
    }
}

/// `message`'s checks that need no state beyond the scene: the wire's,
/// then the scene's; the operation it asks for.
pub(crate) fn operation(message: &pb::ClientMessage, scene: &Scene) -> Result<Op, Refusal> {
    validate(message)?;
    convert::operation(message, scene)
}

fn ghost(command: &Command) -> Option<&Ghost> {
    match command {
        Command::SetPose { name, .. } => name.ghost(),
        _ => None,
    }
}
