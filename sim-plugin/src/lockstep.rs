//! Lock-step timing and its latency emulation (`docs/spec/world.md` §8),
//! once for the daemon's physics thread and the world embedded in an
//! experiment's process ([`crate::server::EmbeddedWorld`]): what an accepted
//! command does to the world, when a delayed Move takes effect, and how an
//! Advance runs to the next publish. Both feed it the same accepted
//! commands in the same order, so both produce the same states.

use std::time::{Duration, Instant};

use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};

use crate::world::{ActuatorMode, Command, CommandError, Snapshot, StepError, World};

/// Identifies a connection for answers the world sends it.
pub(crate) type ClientId = u64;

/// A command that passed every check, on its way to the world.
#[derive(Debug)]
pub(crate) struct Accepted {
    pub client: ClientId,
    pub seq: u64,
    pub op: Op,
}

/// What an accepted `ClientMessage` asks of the world.
#[derive(Debug)]
pub(crate) enum Op {
    /// Commands of the world, applied together at one step boundary (a
    /// `set_pose` may name several bodies).
    World(Vec<Command>),
    /// Lock-step: run to the next publish.
    Advance,
    /// Lock-step with latency emulation: reseed the delay generator.
    LatencySeed(u64),
}

impl Op {
    /// A Move: what latency emulation delays.
    pub fn is_move(&self) -> bool {
        matches!(
            self,
            Op::World(commands) if matches!(
                commands.as_slice(),
                [Command::Actuator { mode: ActuatorMode::Move, .. }]
            )
        )
    }
}

/// Lock-step latency emulation: each Move received before an Advance takes
/// effect after `L` steps of the interval, `L` uniform in `0..=max_steps`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Latency {
    /// The largest delay in steps (the thesis observed up to about 5).
    pub max_steps: u32,
    /// Seed of the delay generator at start-up (`latency_seed` reseeds it).
    pub seed: u64,
}

/// When, within an interval, each command a lock-step world receives takes
/// effect under latency emulation: a Move draws its delay, uniform in
/// `0..=max_steps`, from a generator seeded by the latency seed; other
/// commands take none; and no command takes effect before one that arrived
/// earlier. Arrival order stays application order, as without latency: the
/// learner's Move(0, 0) before a Reset must not turn into a Reset followed
/// by a stale Move.
///
/// The world's stepper draws with it, and so can anyone who sends the world
/// its commands and wants to know their delays (the experiments' oracle
/// that knows the latency): the same seed and the same commands give the
/// same offsets.
#[derive(Debug)]
pub struct DelayDraws {
    max_steps: u32,
    rng: ChaCha8Rng,
    /// The next Move's own delay, drawn ahead so that it can be known
    /// before the Move is sent; Moves still take the draws in order.
    next_move: u32,
    /// The latest offset given in the current interval.
    floor: u32,
}

impl DelayDraws {
    /// The draws of `latency`'s generator from its seed on.
    #[must_use]
    pub fn new(latency: Latency) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(latency.seed);
        Self {
            max_steps: latency.max_steps,
            next_move: rng.random_range(0..=latency.max_steps),
            rng,
            floor: 0,
        }
    }

    /// Restarts the generator (`SimControl.latency_seed`); the commands
    /// after it in this interval still wait for those before it.
    pub fn reseed(&mut self, seed: u64) {
        let floor = self.floor;
        *self = Self::new(Latency {
            max_steps: self.max_steps,
            seed,
        });
        self.floor = floor;
    }

    /// The step offset, within the current interval, of the next command:
    /// a Move (`is_move`) takes its draw.
    pub fn offset(&mut self, is_move: bool) -> u32 {
        self.floor = self.peek(is_move);
        if is_move {
            self.next_move = self.rng.random_range(0..=self.max_steps);
        }
        self.floor
    }

    /// The offset [`DelayDraws::offset`] would give the next command, without
    /// drawing.
    #[must_use]
    pub fn peek(&self, is_move: bool) -> u32 {
        let own = if is_move { self.next_move } else { 0 };
        own.max(self.floor)
    }

    /// An Advance: the next command starts a new interval.
    pub fn next_interval(&mut self) {
        self.floor = 0;
    }
}

/// Moves waiting for their drawn step offset.
struct Delays {
    draws: DelayDraws,
    /// Commands received since the last Advance, with their step offsets
    /// within the next interval (never decreasing, see [`DelayDraws`]).
    pending: Vec<(u32, Accepted)>,
}

impl Delays {
    fn new(latency: Latency) -> Delays {
        Delays {
            draws: DelayDraws::new(latency),
            pending: Vec::new(),
        }
    }

    /// Gives `accepted` its offset ([`DelayDraws::offset`]).
    fn schedule(&mut self, accepted: Accepted) {
        if let Op::LatencySeed(seed) = accepted.op {
            self.draws.reseed(seed);
        }
        let offset = self.draws.offset(accepted.op.is_move());
        self.pending.push((offset, accepted));
    }

    /// The commands of the interval an Advance starts, with their offsets.
    fn take_interval(&mut self) -> Vec<(u32, Accepted)> {
        self.draws.next_interval();
        std::mem::take(&mut self.pending)
    }
}

/// What stepping the world produced besides its new state, for whoever
/// serves it to tell its clients.
#[derive(Debug)]
pub(crate) enum Event {
    /// A state was published (`publish_seq`, `applied_seq` as the wire's).
    Published {
        snapshot: Snapshot,
        publish_seq: u64,
        applied_seq: u64,
    },
    /// An accepted command was refused by the world after all: the
    /// arrival checks missed something, a bug; its client learns that
    /// nothing happened.
    Refused {
        client: ClientId,
        seq: u64,
        error: CommandError,
    },
    /// The publish rate changed to this many Hz.
    PublishRate(u32),
    /// The world blew up and reset itself (it has logged it).
    Diverged(StepError),
}

/// The world and what lock-step timing keeps beside it.
pub(crate) struct Stepper {
    world: World,
    publish_seq: u64,
    applied_seq: u64,
    delays: Option<Delays>,
    /// Wall time spent in the world's steps (collision, the solver, the
    /// snapshot), without the waits for other worlds of the process: the
    /// physics' own cost, measured where it is paid.
    physics: Duration,
}

impl Stepper {
    /// Steps `world`, delaying Moves as `latency` says in lock-step.
    pub fn new(world: World, latency: Option<Latency>) -> Stepper {
        Stepper {
            world,
            publish_seq: 0,
            applied_seq: 0,
            delays: latency.map(Delays::new),
            physics: Duration::ZERO,
        }
    }

    /// The wall time spent stepping the world so far, and the states it
    /// published in it.
    pub fn physics(&self) -> (Duration, u64) {
        (self.physics, self.publish_seq)
    }

    /// How long its steps waited for other worlds of the process.
    pub fn waited_for_ode(&self) -> Duration {
        self.world.waited_for_ode()
    }

    pub fn is_paused(&self) -> bool {
        self.world.is_paused()
    }

    /// Accepted commands the latency emulation holds for the next Advance:
    /// they count against the daemon's bound on waiting commands until they
    /// are applied, not merely until they left the channel.
    pub fn pending(&self) -> usize {
        self.delays
            .as_ref()
            .map_or(0, |delays| delays.pending.len())
    }

    #[cfg(feature = "testing")]
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// Lock-step: takes the next accepted command. An Advance runs the
    /// interval; with latency emulation other commands wait for it,
    /// without they are applied at once.
    ///
    /// # Errors
    /// A step failed in a way the world cannot recover from.
    pub fn take(
        &mut self,
        accepted: Accepted,
        events: &mut impl FnMut(Event),
    ) -> Result<(), StepError> {
        if matches!(accepted.op, Op::Advance) {
            self.run_interval(accepted.seq, events)
        } else {
            if let Some(delays) = &mut self.delays {
                delays.schedule(accepted);
            } else {
                self.apply(accepted, events);
            }
            Ok(())
        }
    }

    /// Runs to the next publish, applying delayed commands at their offsets
    /// (all of them before the interval's last step).
    fn run_interval(
        &mut self,
        advance: u64,
        events: &mut impl FnMut(Event),
    ) -> Result<(), StepError> {
        // Replaced, not emptied: after a flood the drained vector's
        // capacity would stay allocated for the world's life.
        let pending = self
            .delays
            .as_mut()
            .map(Delays::take_interval)
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
                    self.apply(accepted, events);
                }
            }
            if !advance_applied && pending.peek().is_none() {
                // The Advance is in force once everything before it is.
                self.applied_seq = advance;
                advance_applied = true;
            }
            if self.world.is_paused() {
                // The arrival checks accept an Advance only for a world that
                // will be unpaused by then; never step a paused world in a
                // loop.
                tracing::error!("an Advance reached a paused world; interval skipped");
                return Ok(());
            }
            if self.step(events)? {
                return Ok(());
            }
            offset += 1;
        }
    }

    fn next_step_publishes(&self) -> bool {
        (self.world.step_count() + 1).is_multiple_of(u64::from(self.world.publish_interval_steps()))
    }

    /// Applies an accepted command (an Advance only counts as applied).
    pub fn apply(&mut self, accepted: Accepted, events: &mut impl FnMut(Event)) {
        let Accepted { client, seq, op } = accepted;
        if let Op::World(commands) = op {
            for command in commands {
                let rate = matches!(command, Command::SetPublishRate(_));
                if let Err(error) = self.world.apply(command) {
                    tracing::error!(client, seq, "an accepted command was refused: {error}");
                    events(Event::Refused { client, seq, error });
                    return;
                }
                if rate {
                    events(Event::PublishRate(
                        1000 / self.world.publish_interval_steps(),
                    ));
                }
            }
        }
        self.applied_seq = seq;
    }

    /// One step, publishing if one is due. Returns whether it published.
    ///
    /// # Errors
    /// A step failed in a way the world cannot recover from (a divergence
    /// it recovers from is an [`Event::Diverged`]).
    pub fn step(&mut self, events: &mut impl FnMut(Event)) -> Result<bool, StepError> {
        let (started, waited) = (Instant::now(), self.world.waited_for_ode());
        let stepped = self.world.step();
        self.physics += started
            .elapsed()
            .saturating_sub(self.world.waited_for_ode() - waited);
        match stepped {
            Ok(Some(snapshot)) => {
                self.publish_seq += 1;
                events(Event::Published {
                    snapshot,
                    publish_seq: self.publish_seq,
                    applied_seq: self.applied_seq,
                });
                Ok(true)
            }
            Ok(None) => Ok(false),
            Err(err @ StepError::Diverged { .. }) => {
                events(Event::Diverged(err));
                Ok(false)
            }
            Err(err) => Err(err),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            delays.take_interval();
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

    /// A sender that mirrors the draws knows each Move's offset before it
    /// sends it: what the oracle that knows the latency relies on.
    #[test]
    fn a_mirror_of_the_draws_knows_each_offset_before_the_world_draws_it() {
        let latency = Latency {
            max_steps: 5,
            seed: 11,
        };
        let mut world = Delays::new(latency);
        let mut mirror = DelayDraws::new(latency);
        let mut seq = 0;
        for interval in 0..50 {
            for command in 0..(interval % 3) + 1 {
                seq += 1;
                let is_move = command != 1;
                let expected = mirror.peek(is_move);
                assert_eq!(mirror.offset(is_move), expected);
                world.schedule(accepted(
                    seq,
                    if is_move {
                        Command::Actuator {
                            mode: ActuatorMode::Move,
                            velocity: [0.0; 3],
                        }
                    } else {
                        Command::Reset
                    },
                ));
                assert_eq!(world.pending.last().map(|(o, _)| *o), Some(expected));
            }
            world.take_interval();
            mirror.next_interval();
        }
    }
}
