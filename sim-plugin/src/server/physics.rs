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
use tokio::sync::oneshot;
use tokio_util::sync::CancellationToken;

use super::gate::ToPhysics;
use super::{Config, ServerError, Shared, Timing, Wake};
use crate::lockstep::{Accepted, Event, Op, Stepper};
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

struct Physics {
    stepper: Stepper,
    inbox: Receiver<ToPhysics>,
    shared: Arc<Shared>,
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
        let mut world = World::on(&config.scene, config.engine)?;
        if let Some(hz) = config.publish_rate_hz {
            world
                .apply(Command::SetPublishRate(hz))
                .map_err(ServerError::PublishRate)?;
        }
        Ok(Physics {
            stepper: Stepper::new(world, config.timing.latency()),
            inbox,
            shared,
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
            if self.stepper.is_paused() {
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
            // A command the latency emulation holds still waits: it leaves
            // the count when the Advance after it applies it.
            let held = self.stepper.pending();
            self.stepping(|stepper, mut events| stepper.take(accepted, &mut events))?;
            self.shared.gate.taken(1 + held - self.stepper.pending());
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
        if let Err(err) = self.stepper.world_mut().provoke_blow_up(body) {
            tracing::error!("cannot provoke a blow-up: {err}");
        }
    }

    /// Runs `f` on the stepper, the clients told of everything it does.
    fn stepping<R>(&mut self, f: impl FnOnce(&mut Stepper, &mut dyn FnMut(Event)) -> R) -> R {
        let Physics {
            stepper,
            shared,
            wake,
            unwoken,
            ..
        } = self;
        f(stepper, &mut |event| serve(shared, *wake, unwoken, event))
    }

    /// Realtime: applies an accepted command at once.
    fn apply(&mut self, accepted: Accepted) {
        self.stepping(|stepper, mut events| stepper.apply(accepted, &mut events));
    }

    /// Realtime: one step, publishing if one is due.
    fn step(&mut self) -> Result<bool, StepError> {
        self.stepping(|stepper, mut events| stepper.step(&mut events))
    }
}

/// Tells the clients what stepping the world produced.
fn serve(shared: &Shared, wake: Wake, unwoken: &mut u32, event: Event) {
    match event {
        Event::Published {
            snapshot,
            publish_seq,
            applied_seq,
        } => {
            let state = super::state_message(&snapshot, publish_seq, applied_seq);
            shared.broadcast_state(&Arc::new(state), wake);
            if wake == Wake::Later {
                *unwoken += 1;
            }
        }
        Event::Refused { client, seq, error } => shared.reply_to(
            client,
            pb::ServerMessage::error(seq, pb::error::Kind::RefusedByWorld, error.to_string()),
        ),
        Event::PublishRate(hz) => shared.gate.set_publish_rate(hz),
        // The world has reset itself and logged it; tell everyone and
        // carry on.
        Event::Diverged(err) => shared.broadcast_reply(&pb::ServerMessage::error(
            0,
            pb::error::Kind::PhysicsBlewUp,
            err.to_string(),
        )),
    }
}
