//! The learner daemon (`pushlearn learn`): one model attached to a running
//! world, learning online from every state it publishes.
//!
//! For every world state: parse it, re-synchronise (first state) or update
//! the model with the action that was in force, choose the next action (a
//! fixed one, or the planner towards a target, `docs/spec/planning.md`), predict the
//! next state, and send Move — plus, optionally, the prediction as the
//! `*Shadow` ghost poses. In lock-step the daemon then sends Advance; in
//! realtime it measures each message's work against the 2/f budget
//! (`docs/spec/experiments.md` §6).

use std::future::Future;
use std::time::{Duration, Instant};

use learner::{object_name, Action, Frame, Model, ObjectState, ParseError, Target, TargetError};

use episodes::Step;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::frame::{frame_from_state, Shapes, StartHeights};
use crate::latency::{budget, Latencies, LatencySummary};
use pushlearn::client::{ClientError, SimClient};
use pushlearn::wire::pb::{self, client_message::Payload};
use pushlearn::wire::{Ghost, TimingMode};

pub mod episodes;
pub mod pretrain;
pub mod reconnect;
pub mod state;

pub use episodes::{EpisodeResult, Episodes};

/// How the daemon chooses its actions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Policy {
    /// Always the same velocity.
    Fixed(Action),
    /// The model's planner towards a pose of the blue block.
    Target(ObjectState),
}

/// What can stop the daemon.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    #[error(transparent)]
    Client(#[from] ClientError),
    #[error("the model refused the target: {0}")]
    Target(#[from] TargetError),
    #[error(transparent)]
    State(#[from] state::StateError),
}

/// What [`serve`] hands each world state to: a [`Learner`], or one that
/// also journals what it learns ([`state::Durable`]).
pub trait OnState {
    /// Handles one world state; returns the commands to send, ghosts at
    /// `heights` (the world's, [`StartHeights::from_hello`]).
    ///
    /// # Errors
    /// The model refuses its target, or the learner's memory cannot be kept.
    fn on_state(
        &mut self,
        frame: &Frame,
        heights: &StartHeights,
    ) -> Result<Vec<Payload>, LearnError>;

    /// [`Learner::resync`].
    ///
    /// # Errors
    /// The learner's memory cannot be kept.
    fn resync(&mut self) -> Result<(), LearnError>;

    /// The attempts at the target, for a target policy.
    fn episodes(&self) -> Option<&Episodes>;
}

impl<M: Model> OnState for Learner<M> {
    fn on_state(
        &mut self,
        frame: &Frame,
        heights: &StartHeights,
    ) -> Result<Vec<Payload>, LearnError> {
        Ok(Learner::on_state(self, frame, heights)?)
    }

    fn resync(&mut self) -> Result<(), LearnError> {
        Learner::resync(self);
        Ok(())
    }

    fn episodes(&self) -> Option<&Episodes> {
        Learner::episodes(self)
    }
}

/// One model's online loop, without I/O.
///
/// Everything here influences future predictions or actions, so all of it is
/// serialised into the daemon's persistent memory (`docs/reliability.md`):
/// the model (which keeps the previous world itself), the generator's
/// position, the action in force and the target bookkeeping.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Learner<M: Model> {
    model: M,
    policy: Policy,
    shadows: bool,
    rng: ChaCha8Rng,
    last_action: Option<Action>,
    target_set: bool,
    reached_reported: bool,
    /// States the model could not parse.
    pub parse_errors: u64,
    /// A target policy's attempts (a memory from before episodes existed
    /// is in its first and only one).
    #[serde(default)]
    episodes: Episodes,
}

impl<M: Model> Learner<M> {
    /// A learner for `model`; `seed` feeds the planner's exploration.
    pub fn new(model: M, policy: Policy, shadows: bool, seed: u64) -> Self {
        Self {
            model,
            policy,
            shadows,
            rng: ChaCha8Rng::seed_from_u64(seed),
            last_action: None,
            target_set: false,
            reached_reported: false,
            parse_errors: 0,
            episodes: Episodes::default(),
        }
    }

    /// With a target policy: makes `episodes` attempts of at most
    /// `max_steps` steps each, the world reset between them.
    #[must_use]
    pub fn with_episodes(mut self, episodes: u32, max_steps: u64) -> Self {
        self.episodes = Episodes::new(episodes, max_steps);
        self
    }

    /// Handles one world state; returns the commands to send (Move, then
    /// the shadows, at `heights`; a body without one gets no ghost). A state
    /// the model cannot parse sends nothing.
    ///
    /// # Errors
    /// The model refuses the target (set on the first state, once the model
    /// knows the block).
    pub fn on_state(
        &mut self,
        frame: &Frame,
        heights: &StartHeights,
    ) -> Result<Vec<Payload>, TargetError> {
        let world = match self.model.parse(frame) {
            Ok(world) => world,
            Err(err) => {
                self.parse_error(&err);
                return Ok(Vec::new());
            }
        };
        match self.last_action {
            Some(action) => self.model.update(&world, action),
            None => self.model.reset_objects(&world),
        }
        let action = match self.policy {
            Policy::Fixed(action) => action,
            Policy::Target(pose) => {
                if self.episodes.finished() {
                    return Ok(vec![Payload::move_(0.0, 0.0)]);
                }
                if !self.target_set {
                    self.model
                        .set_target(Some(Target::new(learner::BLUE_ID, pose)))?;
                    self.target_set = true;
                }
                let action = self.model.act(&mut self.rng);
                if !self.model.has_target() && !self.reached_reported {
                    self.reached_reported = true;
                    tracing::debug!(?pose, "target reached");
                }
                let block = M::poses(&world).blocks.get(&learner::BLUE_ID).copied();
                match self.episodes.step(block, pose, self.model.has_target()) {
                    Step::Running => action,
                    Step::Ended => return Ok(self.next_episode()),
                    Step::Finished => {
                        self.last_action = Some(Action::ZERO);
                        return Ok(vec![Payload::move_(0.0, 0.0)]);
                    }
                }
            }
        };
        self.last_action = Some(action);
        let mut commands = vec![Payload::move_(action.vx, action.vy)];
        if self.shadows {
            let predicted = M::poses(&self.model.predict(&world, action));
            let target = match self.policy {
                Policy::Target(pose) => Some(pose),
                Policy::Fixed(_) => None,
            };
            commands.push(shadows(&predicted, target, heights));
        }
        Ok(commands)
    }

    /// Ends an attempt: the actuator stopped and the world reset to the
    /// scene's start; the next state (the serving loop waits for one after
    /// the Reset) re-synchronises the model and the target is set again.
    fn next_episode(&mut self) -> Vec<Payload> {
        self.last_action = None;
        self.target_set = false;
        self.reached_reported = false;
        vec![Payload::move_(0.0, 0.0), Payload::reset()]
    }

    /// Forgets the action in force, so that the next state re-synchronises
    /// the model instead of training it on a transition across a gap (after
    /// a reconnect or a restart) whose action is unknown.
    pub fn resync(&mut self) {
        self.last_action = None;
    }

    fn parse_error(&mut self, err: &ParseError) {
        self.parse_errors += 1;
        tracing::warn!(%err, "skipping a world state the model cannot parse");
    }

    /// A target policy's attempts.
    #[must_use]
    pub fn episodes(&self) -> Option<&Episodes> {
        matches!(self.policy, Policy::Target(_)).then_some(&self.episodes)
    }

    /// The model.
    #[must_use]
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The model, for a learner that goes on elsewhere.
    #[must_use]
    pub fn into_model(self) -> M {
        self.model
    }
}

/// The predicted poses, and the blue block's target if there is one, as one
/// SetPose of the ghost bodies (`docs/spec/world.md` §3). The target is sent with every
/// prediction rather than once, because a Reset clears the ghosts.
fn shadows(
    predicted: &learner::Poses,
    target: Option<ObjectState>,
    heights: &StartHeights,
) -> Payload {
    let ghost = |id, s: ObjectState, kind: fn(&'static str) -> Ghost| {
        let name = object_name(id)?;
        let z = heights.z(id)?;
        Some((
            kind(name).to_string(),
            pb::Pose::from_position_yaw([s.x, s.y, z], s.theta),
        ))
    };
    let poses = predicted
        .objects()
        .filter_map(|(id, s)| ghost(id, s, Ghost::predicted))
        .chain(target.and_then(|pose| ghost(learner::BLUE_ID, pose, Ghost::target)));
    Payload::set_poses(poses)
}

/// Per-message work times and the too-slow count, in bounded memory: the
/// daemon runs for days.
#[derive(Clone, Debug, Default)]
pub struct WorkTimes {
    work: Latencies,
    too_slow: u64,
    /// The model's share (parse, update, act, predict): see [`crate::latency`].
    model: Latencies,
}

/// A summary of [`WorkTimes`]. The percentiles are nearest-rank ones from a
/// histogram ([`crate::latency`]): at most 1/16 above the true value; the
/// maximum is exact.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorkSummary {
    pub messages: u64,
    pub too_slow: u64,
    pub too_slow_fraction: f64,
    pub p50_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
    /// The model's work per message (parse, update, act, predict), without
    /// the socket writes.
    #[serde(default)]
    pub model: LatencySummary,
}

impl WorkTimes {
    /// Records the model's share of one message's work.
    pub fn record_model(&mut self, took: Duration) {
        self.model.record(took);
    }

    /// Records one message's work.
    pub fn record(&mut self, took: Duration, budget: Duration) {
        self.work.record(took);
        if took > budget {
            self.too_slow += 1;
        }
    }

    /// Messages recorded.
    #[must_use]
    pub fn messages(&self) -> u64 {
        self.work.count()
    }

    /// Count, too-slow count and fraction, and percentiles.
    #[must_use]
    pub fn summary(&self) -> WorkSummary {
        let n = self.work.count();
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        WorkSummary {
            messages: n,
            too_slow: self.too_slow,
            too_slow_fraction: if n == 0 {
                0.0
            } else {
                self.too_slow as f64 / n as f64
            },
            p50_ms: ms(self.work.quantile(0.5)),
            p99_ms: ms(self.work.quantile(0.99)),
            max_ms: ms(self.work.max()),
            model: self.model.summary(),
        }
    }
}

/// Several clients' or workers' times as one distribution.
impl std::ops::AddAssign for WorkTimes {
    fn add_assign(&mut self, other: Self) {
        self.work += other.work;
        self.too_slow += other.too_slow;
        self.model += other.model;
    }
}

impl std::fmt::Display for WorkSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} messages, {} ({:.4} %) over budget; work per message p50 {:.3} ms, p99 {:.3} ms \
             (each at most 1/16 high), max {:.3} ms; model alone {}",
            self.messages,
            self.too_slow,
            100.0 * self.too_slow_fraction,
            self.p50_ms,
            self.p99_ms,
            self.max_ms,
            self.model
        )
    }
}

/// When to stop and what to print on the way.
#[derive(Clone, Copy, Debug, Default)]
pub struct ServeOptions {
    /// Stop after this many states.
    pub max_messages: Option<u64>,
    /// Print the work-time summary this often.
    pub report_every: Option<Duration>,
    /// With a target policy: report the distance to the target every this
    /// many states.
    pub progress_every: Option<u64>,
}

/// What the serving loop tells its caller on the way.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// The periodic work-time summary (`report_every`).
    Work(&'a WorkSummary),
    /// The distance to the target (`progress_every`), in the current attempt.
    Progress(&'a Episodes),
    /// An attempt ended; its result is the last of [`Episodes::ended`].
    EpisodeEnded(&'a Episodes),
}

/// Why the loop ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Stop {
    Interrupted,
    MessageLimit,
    /// Every attempt at the target has ended.
    EpisodesDone,
}

/// What `pushlearn learn --json FILE` writes when the daemon has stopped
/// cleanly: for scripts and for `pushlearn ctl soak`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StopReport {
    pub stop: Stop,
    /// `SIGTERM` or `SIGINT` when a signal stopped the daemon.
    pub signal: Option<String>,
    /// States handled, over all connections.
    pub states: u64,
    /// States the world published that never reached the daemon (its queue
    /// at the world overflowed), over all connections.
    pub missed: u64,
    pub reconnects: u64,
    /// Physics blow-ups the world reported.
    pub world_errors: u64,
    /// Work per state since the last (re)connection.
    pub work: WorkSummary,
    /// With a target: attempts ended, and of them reached.
    pub attempts: Option<(usize, usize)>,
    /// With `--state`: the journal records on disk, every one covered by the
    /// final snapshot.
    pub records_on_disk: Option<u64>,
}

/// Runs `learner` against the world behind `client` until `shutdown`
/// completes, the message limit or the last attempt at the target. `report`
/// receives the periodic summaries and the attempts' progress.
///
/// `shutdown` is the caller's: the binary completes it on SIGTERM or SIGINT,
/// a test whenever it likes, so that a clean stop is tested without
/// signals. It is only waited on between states: a state being handled is
/// handled to the end (journalled, learnt, its commands sent) first.
///
/// # Errors
/// Socket errors, a refused command, a refused target, a learner memory
/// that cannot be kept. When the learner fails, the actuator is stopped
/// first (as far as the connection allows).
pub async fn serve(
    client: &mut SimClient,
    learner: &mut impl OnState,
    options: ServeOptions,
    shutdown: impl Future<Output = ()>,
    mut report: impl FnMut(Event<'_>),
) -> Result<(Stop, WorkSummary), LearnError> {
    let lockstep = client.hello().timing() == Ok(TimingMode::Lockstep);
    let budget = budget(client.hello().publish_rate);
    let heights = StartHeights::from_hello(client.hello());
    let shapes = Shapes::from_hello(client.hello());
    // A world can be quiet for long (paused, or waiting for another client).
    client.set_timeout(None);
    let mut times = WorkTimes::default();
    let mut last_report = Instant::now();
    tokio::pin!(shutdown);
    // After a Reset, the first state that shows it: in realtime, states
    // published before the world applied it may still be on their way.
    let mut reset_seq = None;
    let stop = loop {
        if options.max_messages.is_some_and(|n| times.messages() >= n) {
            break Stop::MessageLimit;
        }
        let next = async {
            if lockstep {
                let advance = client.send(Payload::advance()).await?;
                client.wait_applied(advance).await
            } else if let Some(seq) = reset_seq {
                client.wait_applied(seq).await
            } else {
                client.next_state().await
            }
        };
        let state = tokio::select! {
            // Biased: in lock-step the next state is always ready at once,
            // and a stop asked for must win over it.
            biased;
            () = &mut shutdown => break Stop::Interrupted,
            state = next => state?,
        };
        reset_seq = None;
        let received = Instant::now();
        let frame = frame_from_state(&state, &shapes);
        let modelled = Instant::now();
        let ended_before = learner.episodes().map_or(0, |e| e.ended.len());
        let commands = match learner.on_state(&frame, &heights) {
            Ok(commands) => commands,
            Err(err) => {
                // The daemon stops here: in a free-running world the last
                // Move would stay in force. Best effort — the error that
                // stops the daemon is the learner's, not this one.
                if client.send(Payload::move_(0.0, 0.0)).await.is_ok() {
                    let _ = client.sync().await;
                }
                return Err(err);
            }
        };
        times.record_model(modelled.elapsed());
        for command in commands {
            let reset = command.kind() == "reset";
            let seq = client.send(command).await?;
            if reset {
                reset_seq = Some(seq);
            }
        }
        times.record(received.elapsed(), budget);
        if let Some(every) = options.report_every {
            if last_report.elapsed() >= every {
                report(Event::Work(&times.summary()));
                last_report = Instant::now();
            }
        }
        if let Some(episodes) = learner.episodes() {
            if episodes.ended.len() > ended_before {
                report(Event::EpisodeEnded(episodes));
                if episodes.finished() {
                    break Stop::EpisodesDone;
                }
            } else if options.progress_every.is_some_and(|every| {
                // The first state of an attempt, then every `every`th.
                episodes
                    .handled
                    .checked_sub(1)
                    .is_some_and(|n| n % every.max(1) == 0)
            }) {
                report(Event::Progress(episodes));
            }
        }
    };
    // The last Move stays in force in a free-running world: stop the actuator.
    client.send(Payload::move_(0.0, 0.0)).await?;
    client.sync().await?;
    Ok((stop, times.summary()))
}

#[cfg(test)]
mod tests {
    use learner::BLUE_ID;

    use super::*;
    use crate::experiment::driver::test_support::{blue_home, describe, frame};
    use learner::testing::Probe;

    /// The shipped scenes' (`docs/spec/world.md` §3).
    pub(crate) fn heights() -> StartHeights {
        StartHeights::from_iter([
            (learner::ACTUATOR_ID, 0.03),
            (BLUE_ID, 0.05),
            (learner::RED_ID, 0.05),
        ])
    }

    #[test]
    fn shadows_skip_bodies_the_world_lacks() {
        // The world refuses a ghost of a body its scene lacks (blockBShadow
        // in one_block): a body without a start height gets none.
        let only_actuator: StartHeights = [(learner::ACTUATOR_ID, 0.03)].into_iter().collect();
        let mut l = Learner::new(
            Probe::default(),
            Policy::Fixed(Action::new(0.0, 0.5)),
            true,
            1,
        );
        let sent = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &only_actuator)
                .unwrap(),
        );
        assert_eq!(sent, ["move(0,0.5)", "pose(actuatorShadow,0,0.005)"]);
    }

    #[test]
    fn a_fixed_action_learns_from_every_state_and_sends_shadows() {
        let mut l = Learner::new(
            Probe::default(),
            Policy::Fixed(Action::new(0.0, 0.5)),
            true,
            1,
        );
        let first = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap(),
        );
        // Shadows predict the actuator 5 mm ahead (the probe's model).
        assert_eq!(
            first,
            [
                "move(0,0.5)",
                "pose(actuatorShadow,0,0.005);pose(blockAShadow,0,0.25)"
            ]
        );
        l.on_state(&frame((0.0, 0.005), &blue_home()), &heights())
            .unwrap();
        l.on_state(&frame((0.0, 0.01), &blue_home()), &heights())
            .unwrap();
        assert_eq!(l.model().resets, 1);
        assert_eq!(l.model().updates, 2);
        let mut broken = frame((0.0, 0.0), &blue_home());
        broken.objects.remove(0);
        assert!(l.on_state(&broken, &heights()).unwrap().is_empty());
        assert_eq!(l.parse_errors, 1);
        assert_eq!(l.model().updates, 2);
    }

    #[test]
    fn an_attempt_ends_when_the_worlds_block_is_at_the_goal() {
        // The block rests where the goal is; the probe never claims it.
        let goal = ObjectState::new(0.0, 0.25, 0.0);
        let mut l = Learner::new(Probe::default(), Policy::Target(goal), false, 1);
        let stop = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap(),
        );
        assert_eq!(stop, ["move(0,0)"]);
        let episodes = l.episodes().unwrap();
        assert!(episodes.finished());
        assert_eq!(episodes.reached(), 1);
        assert_eq!(episodes.ended[0].steps, 0);
    }

    #[test]
    fn a_target_policy_plans_until_the_model_stops_and_the_world_judges() {
        let probe = Probe {
            reach_after: Some(3),
            ..Probe::default()
        };
        let goal = ObjectState::new(0.6, 0.7, -2.1);
        let mut l = Learner::new(probe, Policy::Target(goal), false, 1);
        let a = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap(),
        );
        assert_eq!(a.len(), 1);
        assert_eq!(
            l.model().target.map(|t| (t.id, t.pose)),
            Some((BLUE_ID, goal))
        );
        assert!(l.episodes().unwrap().ended.is_empty());
        l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
            .unwrap();
        let stop = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap(),
        );
        assert_eq!(stop, ["move(0,0)"]);
        let episodes = l.episodes().unwrap();
        assert!(episodes.finished());
        // The probe claims the goal, but the block never moved.
        assert_eq!(episodes.reached(), 0);
        assert_eq!(episodes.ended[0].steps, 2);
        // The block at (0, 0.25) against the goal (0.6, 0.7, −2.1).
        assert!((episodes.ended[0].pos_err - 0.75).abs() < 1e-12);
        // Finished: the actuator is held still.
        let after = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap(),
        );
        assert_eq!(after, ["move(0,0)"]);
    }

    #[test]
    fn episodes_reset_the_world_between_attempts_and_keep_the_model() {
        let probe = Probe {
            reach_after: Some(2),
            ..Probe::default()
        };
        let goal = ObjectState::new(0.6, 0.7, -2.1);
        let mut l = Learner::new(probe, Policy::Target(goal), false, 1).with_episodes(2, 3000);
        let on = |l: &mut Learner<Probe>| {
            describe(
                &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                    .unwrap(),
            )
        };
        on(&mut l);
        assert_eq!(on(&mut l), ["move(0,0)", "reset"]);
        assert_eq!(l.episodes().unwrap().ended.len(), 1);
        assert!(l.model().target.is_none());
        // The state after the reset re-synchronises the model (no update
        // across the reset) and sets the target again; the probe, past its
        // reach count, finds it reached at once.
        let updates = l.model().updates;
        assert_eq!(on(&mut l), ["move(0,0)"]);
        assert_eq!(l.model().resets, 2);
        assert_eq!(l.model().updates, updates);
        let episodes = l.episodes().unwrap();
        assert!(episodes.finished());
        assert_eq!(
            episodes.ended.iter().map(|e| e.steps).collect::<Vec<_>>(),
            [1, 0]
        );
    }

    #[test]
    fn the_attempts_are_part_of_the_memory_and_an_old_memory_makes_one() {
        let goal = ObjectState::new(0.6, 0.7, -2.1);
        let mut l =
            Learner::new(Probe::default(), Policy::Target(goal), false, 1).with_episodes(3, 50);
        for _ in 0..5 {
            l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap();
        }
        let json = serde_json::to_value(&l).unwrap();
        let back: Learner<Probe> = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(back.episodes(), l.episodes());
        assert_eq!(back.episodes().unwrap().handled, 5);
        let mut old = json;
        old.as_object_mut().unwrap().remove("episodes");
        let old: Learner<Probe> = serde_json::from_value(old).unwrap();
        assert_eq!(old.episodes(), Some(&Episodes::default()));
    }

    #[test]
    fn shadows_of_a_target_policy_mark_the_target() {
        let goal = ObjectState::new(0.6, 0.7, -2.1);
        let mut l = Learner::new(Probe::default(), Policy::Target(goal), true, 1);
        let commands = describe(
            &l.on_state(&frame((0.0, 0.0), &blue_home()), &heights())
                .unwrap(),
        );
        assert_eq!(commands.len(), 2, "{commands:?}");
        assert!(
            commands[1].ends_with(";pose(blockAShadowTarget,0.6,0.7)"),
            "{commands:?}"
        );
    }

    #[test]
    fn a_refused_target_is_an_error() {
        let mut l = Learner::new(
            Probe::default(),
            Policy::Target(ObjectState::new(f64::NAN, 0.0, 0.0)),
            false,
            1,
        );
        assert!(matches!(
            l.on_state(&frame((0.0, 0.0), &blue_home()), &heights()),
            Err(TargetError::NonFinite { .. })
        ));
    }

    #[test]
    fn work_times_give_nearest_rank_percentiles_at_most_a_sixteenth_high() {
        let mut t = WorkTimes::default();
        let budget = Duration::from_millis(20);
        for ms in 1..=100 {
            t.record(Duration::from_micros(ms * 250), budget);
        }
        let s = t.summary();
        assert_eq!(s.messages, 100);
        // 0.25 ms … 25 ms: those above 20 ms are 20.25 … 25 (20 of them).
        assert_eq!(s.too_slow, 20);
        assert!((s.too_slow_fraction - 0.2).abs() < 1e-12);
        // The nearest ranks are 12.5 ms and 24.75 ms.
        assert!((12.5..=12.5 * 17.0 / 16.0).contains(&s.p50_ms), "{s:?}");
        assert!((24.75..=24.75 * 17.0 / 16.0).contains(&s.p99_ms), "{s:?}");
        assert_eq!(s.max_ms, 25.0);
        assert_eq!(WorkTimes::default().summary(), WorkSummary::default());
    }
}
