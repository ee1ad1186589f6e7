//! The physics thread: owns the world, applies accepted commands at step
//! boundaries, steps it in realtime or lock-step and publishes its states.
//!
//! It runs on its own OS thread because realtime pacing needs finer timing
//! than tokio's millisecond timers: it sleeps until each step's deadline
//! (waiting on the command channel, so that commands are applied as soon as
//! they arrive, which between two steps is the next step boundary). It never
//! waits for a client: states go into the clients' bounded queues.

use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use pushlearn::wire::pb;
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use tokio::sync::oneshot;
use tokio_util::sync::CancellationToken;

use super::gate::{Accepted, Op, ToPhysics};
use super::{Config, Latency, ServerError, Shared, Timing, Wake};
use crate::world::{Command, StepError, World};

/// In realtime mode, how far the world may fall behind its schedule (after
/// the machine stalled) before it gives up catching up: it then continues
/// at the normal pace from now instead of stepping a long burst.
const MAX_LAG: Duration = Duration::from_millis(100);

/// In lock-step, how many published states may wait for their writers'
/// wake-up while the physics runs on. Waking an idle writer thread costs the
/// waker ≈ 9 µs on a virtual machine whose idle vCPUs halt (docs/
/// docs/performance.md §4), a tenth of a 100 Hz interval's work; a client that
/// keeps Advances queued gets its states in pairs instead, each pair at
/// most one interval late. A client that waits for each state before it
/// advances is never kept waiting: the writers are woken whenever the
/// physics thread finds no Advance waiting.
const MAX_UNWOKEN_STATES: u32 = 2;

/// Starts the physics thread. It builds the world and reports the outcome on
/// `ready` before stepping; when it ends, for whatever reason, it cancels
/// `shutdown` so that the daemon stops with it.
pub(super) fn spawn(
    config: Config,
    inbox: Receiver<ToPhysics>,
    shared: Arc<Shared>,
    shutdown: CancellationToken,
    ready: oneshot::Sender<Result<(), ServerError>>,
) -> Result<JoinHandle<Result<(), String>>, ServerError> {
    let thread = std::thread::Builder::new()
        .name("physics".into())
        .spawn(move || {
            // Whatever ends the physics, a panic included, ends the daemon:
            // a server whose world is gone must not go on accepting clients.
            let _stop_daemon = CancelOnDrop(shutdown);
            // The world is built here: ODE's per-thread data then belongs to
            // the thread that steps it.
            let physics = match Physics::new(&config, inbox, shared) {
                Ok(physics) => physics,
                Err(err) => {
                    let _ = ready.send(Err(err));
                    return Ok(());
                }
            };
            // The receiver only disappears if start-up was abandoned.
            let _ = ready.send(Ok(()));
            let result = physics.run(config.timing);
            if let Err(err) = &result {
                tracing::error!("the physics stopped: {err}");
            }
            result.map_err(|err| err.to_string())
        })?;
    Ok(thread)
}

struct CancelOnDrop(CancellationToken);

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        self.0.cancel();
    }
}

/// Lock-step latency emulation: Moves wait for their drawn step offset.
struct Delays {
    max_steps: u32,
    rng: ChaCha8Rng,
    /// Commands received since the last Advance, with their step offsets
    /// within the next interval (never decreasing, see [`Delays::schedule`]).
    pending: Vec<(u32, Accepted)>,
}

impl Delays {
    fn new(latency: Latency) -> Delays {
        Delays {
            max_steps: latency.max_steps,
            rng: ChaCha8Rng::seed_from_u64(latency.seed),
            pending: Vec::new(),
        }
    }

    /// Gives `accepted` its offset: a Move draws one, other commands 0, but
    /// none is applied before a command that arrived earlier. Arrival order
    /// stays application order, as without latency: the learner's Move(0, 0)
    /// before a Reset must not turn into a Reset followed by a stale Move.
    fn schedule(&mut self, accepted: Accepted) {
        if let Op::LatencySeed(seed) = accepted.op {
            self.rng = ChaCha8Rng::seed_from_u64(seed);
        }
        let own = if accepted.op.is_move() {
            self.rng.random_range(0..=self.max_steps)
        } else {
            0
        };
        let earliest = self.pending.last().map_or(0, |(offset, _)| *offset);
        self.pending.push((own.max(earliest), accepted));
    }
}

struct Physics {
    world: World,
    inbox: Receiver<ToPhysics>,
    shared: Arc<Shared>,
    publish_seq: u64,
    applied_seq: u64,
    delays: Option<Delays>,
    /// When published states' writers are woken: at once in realtime; in
    /// lock-step by [`Physics::run_lockstep`] (see [`MAX_UNWOKEN_STATES`]).
    wake: Wake,
    /// States published since the writers were last woken.
    unwoken: u32,
}

/// Whether the thread should go on after a message.
#[derive(Debug, PartialEq, Eq)]
enum Flow {
    Continue,
    Stop,
}

impl Physics {
    fn new(
        config: &Config,
        inbox: Receiver<ToPhysics>,
        shared: Arc<Shared>,
    ) -> Result<Physics, ServerError> {
        let mut world = World::new(&config.scene)?;
        if let Some(hz) = config.publish_rate_hz {
            world
                .apply(Command::SetPublishRate(hz))
                .map_err(ServerError::PublishRate)?;
        }
        Ok(Physics {
            world,
            inbox,
            shared,
            publish_seq: 0,
            applied_seq: 0,
            delays: config.timing.latency().map(Delays::new),
            wake: match config.timing {
                Timing::Realtime { .. } => Wake::Now,
                Timing::Lockstep { .. } => Wake::Later,
            },
            unwoken: 0,
        })
    }

    fn run(mut self, timing: Timing) -> Result<(), StepError> {
        match timing {
            Timing::Realtime { steps_per_second } => self.run_realtime(steps_per_second),
            Timing::Lockstep { .. } => self.run_lockstep(),
        }
    }

    /// Steps continuously, `steps_per_second` per wall-clock second (0: as
    /// fast as possible), against deadlines so that sleep overshoot does not
    /// accumulate.
    fn run_realtime(&mut self, steps_per_second: u32) -> Result<(), StepError> {
        let period = (steps_per_second > 0).then(|| Duration::from_secs(1) / steps_per_second);
        let mut deadline = Instant::now();
        loop {
            loop {
                match self.inbox.try_recv() {
                    Ok(message) => {
                        if self.handle_now(message) == Flow::Stop {
                            return Ok(());
                        }
                    }
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => return Ok(()),
                }
            }
            if self.world.is_paused() {
                // Nothing to pace while paused: sleep until a command comes.
                let Ok(message) = self.inbox.recv() else {
                    return Ok(());
                };
                if self.handle_now(message) == Flow::Stop {
                    return Ok(());
                }
                deadline = Instant::now();
                continue;
            }
            self.step()?;
            let Some(period) = period else { continue };
            deadline += period;
            let now = Instant::now();
            if now > deadline + MAX_LAG {
                deadline = now;
            }
            while let Some(left) = deadline.checked_duration_since(Instant::now()) {
                if left.is_zero() {
                    break;
                }
                match self.inbox.recv_timeout(left) {
                    Ok(message) => {
                        if self.handle_now(message) == Flow::Stop {
                            return Ok(());
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => break,
                    Err(RecvTimeoutError::Disconnected) => return Ok(()),
                }
            }
        }
    }

    /// Realtime: the world is between two steps, so apply at once.
    fn handle_now(&mut self, message: ToPhysics) -> Flow {
        match message {
            ToPhysics::Stop => Flow::Stop,
            ToPhysics::Command(accepted) => {
                self.shared.gate.taken(1);
                self.apply(accepted);
                Flow::Continue
            }
            #[cfg(feature = "testing")]
            ToPhysics::BlowUp(body) => {
                self.blow_up(&body);
                Flow::Continue
            }
        }
    }

    /// Waits for commands between intervals and runs an interval per
    /// Advance. Commands that arrive during an interval wait in the channel
    /// until it has ended, so the states depend only on the order of the
    /// commands, never on when they arrived.
    fn run_lockstep(&mut self) -> Result<(), StepError> {
        loop {
            let message = match self.inbox.try_recv() {
                Ok(message) => message,
                Err(TryRecvError::Empty) => {
                    self.wake_writers();
                    match self.inbox.recv() {
                        Ok(message) => message,
                        Err(_) => return Ok(()),
                    }
                }
                Err(TryRecvError::Disconnected) => {
                    self.wake_writers();
                    return Ok(());
                }
            };
            let advance = matches!(&message, ToPhysics::Command(a) if matches!(a.op, Op::Advance));
            if !advance || self.unwoken >= MAX_UNWOKEN_STATES {
                self.wake_writers();
            }
            let accepted = match message {
                ToPhysics::Command(accepted) => accepted,
                #[cfg(feature = "testing")]
                ToPhysics::BlowUp(body) => {
                    self.blow_up(&body);
                    continue;
                }
                ToPhysics::Stop => return Ok(()),
            };
            self.shared.gate.taken(1);
            if matches!(accepted.op, Op::Advance) {
                self.run_interval(accepted.seq)?;
            } else if let Some(delays) = &mut self.delays {
                delays.schedule(accepted);
            } else {
                self.apply(accepted);
            }
        }
    }

    /// Runs to the next publish, applying delayed commands at their offsets
    /// (all of them before the interval's last step).
    fn run_interval(&mut self, advance: u64) -> Result<(), StepError> {
        let pending = self
            .delays
            .as_mut()
            .map(|delays| std::mem::take(&mut delays.pending))
            .unwrap_or_default();
        let mut pending = pending.into_iter().peekable();
        let mut offset = 0;
        let mut advance_applied = false;
        loop {
            while let Some((due, _)) = pending.peek() {
                let now = *due <= offset || self.world.is_paused() || self.next_step_publishes();
                if !now {
                    break;
                }
                if let Some((_, accepted)) = pending.next() {
                    self.apply(accepted);
                }
            }
            if !advance_applied && pending.peek().is_none() {
                // The Advance is in force once everything before it is.
                self.applied_seq = advance;
                advance_applied = true;
            }
            if self.world.is_paused() {
                // The gate accepts an Advance only for a world that will be
                // unpaused by then; never step a paused world in a loop.
                tracing::error!("an Advance reached a paused world; interval skipped");
                return Ok(());
            }
            if self.step()? {
                return Ok(());
            }
            offset += 1;
        }
    }

    fn wake_writers(&mut self) {
        if self.unwoken > 0 {
            self.shared.wake_writers();
            self.unwoken = 0;
        }
    }

    #[cfg(feature = "testing")]
    fn blow_up(&mut self, body: &str) {
        if let Err(err) = self.world.provoke_blow_up(body) {
            tracing::error!("cannot provoke a blow-up: {err}");
        }
    }

    fn next_step_publishes(&self) -> bool {
        (self.world.step_count() + 1).is_multiple_of(u64::from(self.world.publish_interval_steps()))
    }

    /// Applies an accepted command (an Advance only counts as applied).
    fn apply(&mut self, accepted: Accepted) {
        let Accepted { client, seq, op } = accepted;
        if let Op::World(commands) = op {
            for command in commands {
                let rate = matches!(command, Command::SetPublishRate(_));
                if let Err(err) = self.world.apply(command) {
                    // The gate ran the same checks on arrival, so this is a
                    // bug; the client still learns that nothing happened.
                    tracing::error!(client, seq, "an accepted command was refused: {err}");
                    self.shared.reply_to(
                        client,
                        pb::ServerMessage::error(
                            seq,
                            pb::error::Kind::RefusedByWorld,
                            err.to_string(),
                        ),
                    );
                    return;
                }
                if rate {
                    self.shared
                        .gate
                        .set_publish_rate(1000 / self.world.publish_interval_steps());
                }
            }
        }
        self.applied_seq = seq;
    }

    /// One step, publishing if one is due. Returns whether it published.
    fn step(&mut self) -> Result<bool, StepError> {
        match self.world.step() {
            Ok(Some(snapshot)) => {
                self.publish_seq += 1;
                let state = super::state_message(&snapshot, self.publish_seq, self.applied_seq);
                self.shared.broadcast_state(&Arc::new(state), self.wake);
                if self.wake == Wake::Later {
                    self.unwoken += 1;
                }
                Ok(true)
            }
            Ok(None) => Ok(false),
            Err(err @ StepError::Diverged { .. }) => {
                // The world has reset itself and logged it; tell everyone
                // and carry on.
                self.shared.broadcast_reply(&pb::ServerMessage::error(
                    0,
                    pb::error::Kind::PhysicsBlewUp,
                    err.to_string(),
                ));
                Ok(false)
            }
            Err(err) => Err(err),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ActuatorMode;

    fn accepted(seq: u64, command: Command) -> Accepted {
        Accepted {
            client: 1,
            seq,
            op: Op::World(vec![command]),
        }
    }

    #[test]
    fn moves_draw_delays_and_nothing_overtakes_an_earlier_command() {
        let mut delays = Delays::new(Latency {
            max_steps: 5,
            seed: 3,
        });
        for seq in 1..=60 {
            let command = if seq % 3 == 0 {
                Command::Reset
            } else {
                Command::Actuator {
                    mode: ActuatorMode::Move,
                    velocity: [0.0; 3],
                }
            };
            delays.schedule(accepted(seq, command));
        }
        let offsets: Vec<u32> = delays.pending.iter().map(|(offset, _)| *offset).collect();
        assert!(offsets.windows(2).all(|w| w[0] <= w[1]), "{offsets:?}");
        assert!(offsets.iter().all(|&o| o <= 5), "{offsets:?}");
        assert!(offsets.iter().any(|&o| o > 0), "{offsets:?}");
        for (i, (offset, scheduled)) in delays.pending.iter().enumerate().skip(1) {
            if !scheduled.op.is_move() {
                assert_eq!(
                    *offset,
                    offsets[i - 1],
                    "a Reset waits for the Move before it"
                );
            }
        }
    }

    #[test]
    fn reseeding_repeats_the_delays() {
        let draw = |delays: &mut Delays| -> Vec<u32> {
            delays.pending.clear();
            for seq in 1..=20 {
                delays.schedule(accepted(
                    seq,
                    Command::Actuator {
                        mode: ActuatorMode::Move,
                        velocity: [0.0; 3],
                    },
                ));
            }
            delays.pending.iter().map(|(offset, _)| *offset).collect()
        };
        let mut delays = Delays::new(Latency {
            max_steps: 1000,
            seed: 9,
        });
        let first = draw(&mut delays);
        delays.schedule(Accepted {
            client: 1,
            seq: 21,
            op: Op::LatencySeed(9),
        });
        assert_eq!(draw(&mut delays), first);
    }
}
