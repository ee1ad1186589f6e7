//! The message handler common to every experiment (`docs/spec/experiments.md` §2): the
//! state machine that drops the message after a reset, verifies start
//! positions (correcting them with SetPose), and hands every other message
//! to the current experiment's [`Task`].
//!
//! It is synchronous and does no I/O: [`Driver::on_state`] takes one frame
//! and returns the commands to send in order. The socket side
//! (`super::link`) adds pacing (Advance in lock-step, the 2/f budget in
//! realtime), so the state machine can be tested with scripted frames.

use std::collections::BTreeMap;

use learner::eval::{actuator_left_area, RunStepper, MESSAGES_PER_RUN};
use learner::features::{parse_frame, ActuatorYaw, ParseError};
use learner::{object_name, Action, Frame, Model, ObjectState, Poses, ACTUATOR_ID, ACTUATOR_NAME};

use super::push_task::objects::View;
use crate::results::run_info::Counters;
use crate::scene::{ACTUATOR_Z, BLOCK_Z};
use pushlearn::wire::pb::{self, client_message::Payload};
use sim_plugin::lockstep::{DelayDraws, Latency};

/// `docs/spec/experiments.md` §2: a start pose farther than this (norm over x, y, θ,
/// unwrapped) from the expected one is corrected.
pub const START_TOLERANCE: f64 = 0.01;

/// The driver variables of `docs/spec/experiments.md` §2 and the run primitives of
/// §2.1; the tasks change them only through these methods and fields.
#[derive(Debug)]
pub struct Core<M: Model> {
    publish_rate_hz: u32,
    startup: bool,
    ignore: bool,
    /// A start position still needs checking.
    started_run: bool,
    /// Whether a run is in progress (`run_started` of the spec).
    pub run_started: bool,
    done: bool,
    /// Messages handled in the current run; each task increments it itself
    /// (the constant-feedback task deliberately never does, §3.4).
    pub step_counter: u64,
    expected_start: BTreeMap<u32, ObjectState>,
    /// `train_step` / `test_step` with the run's `last_action` and
    /// `last_prediction`; replaced by a fresh one on every `reset_world`.
    pub stepper: RunStepper<M>,
    /// `last_action` and `last_prediction` for handlers that step the model
    /// themselves (Move to Target's test run, constant feedback); cleared
    /// with the stepper.
    pub last_action: Option<Action>,
    /// See [`Core::last_action`].
    pub last_prediction: Option<M::World>,
    counters: Counters,
    out: Vec<Payload>,
    /// What the learner is shown of each world state; `None`: all of it.
    view: Option<View>,
    /// The world's latency draws, followed command by command, where the
    /// harness seeded them ([`Driver::knowing_latency`]).
    delays: Option<DelayDraws>,
}

impl<M: Model> Core<M> {
    fn new(publish_rate_hz: u32) -> Self {
        Self {
            publish_rate_hz,
            startup: true,
            ignore: false,
            started_run: false,
            run_started: false,
            done: false,
            step_counter: 0,
            expected_start: BTreeMap::new(),
            stepper: RunStepper::new(),
            last_action: None,
            last_prediction: None,
            counters: Counters::default(),
            out: Vec::new(),
            view: None,
            delays: None,
        }
    }

    /// Shows the learner only what `view` keeps of the following world
    /// states (the new-object experiments), or everything.
    pub fn set_view(&mut self, view: Option<View>) {
        self.view = view;
    }

    /// Queues a command for the world.
    pub fn send(&mut self, payload: Payload) {
        if let Some(delays) = &mut self.delays {
            let is_move = matches!(
                &payload,
                Payload::Actuator(a) if a.cmd == pb::actuator_command::Command::Move as i32
            );
            delays.offset(is_move);
        }
        self.out.push(payload);
    }

    /// Queues Move(action).
    pub fn send_move(&mut self, action: Action) {
        self.send(Payload::move_(action.vx, action.vy));
    }

    /// `reset_world()`: stop, reset, forget the run, drop one message.
    pub fn reset_world(&mut self) {
        self.send_move(Action::ZERO);
        self.send(Payload::reset());
        self.stepper = RunStepper::new();
        self.last_action = None;
        self.last_prediction = None;
        self.step_counter = 0;
        self.ignore = true;
    }

    /// `start_run` / `start_target_run`: place the actuator at `actuator`
    /// (yaw 0) and expect the blocks at `blocks`. `ignore_next` is false for
    /// Move to Target, whose original did not drop a message there
    /// (`docs/spec/experiments.md` §8; the position check covers it).
    pub fn start_run(
        &mut self,
        actuator: (f64, f64),
        blocks: &BTreeMap<u32, ObjectState>,
        ignore_next: bool,
    ) {
        let (x, y) = actuator;
        self.expected_start = blocks.clone();
        self.expected_start
            .insert(ACTUATOR_ID, ObjectState::new(x, y, 0.0));
        self.send(Payload::set_pose(ACTUATOR_NAME, [x, y, ACTUATOR_Z], 0.0));
        self.step_counter = 0;
        self.ignore |= ignore_next;
        self.started_run = true;
        self.run_started = true;
    }

    /// `run_ended(WS)` of §2.1.
    #[must_use]
    pub fn run_ended(&self, poses: &Poses) -> bool {
        actuator_left_area(poses) || self.step_counter > MESSAGES_PER_RUN as u64
    }

    /// Ends the job: later messages are not handled.
    pub fn finish(&mut self) {
        self.done = true;
    }

    /// `check_start_positions(WS)`: the actuator first, then each block the
    /// run expects; the first misplaced body is put back and the message is
    /// not handled.
    fn check_start_positions(&mut self, poses: &Poses) -> bool {
        let misplaced = poses
            .objects()
            .filter_map(|(id, s)| Some((id, s, *self.expected_start.get(&id)?)))
            .find(|(_, s, expected)| s.distance_to(expected) > START_TOLERANCE);
        let Some((id, found, expected)) = misplaced else {
            return true;
        };
        self.counters.reset_errors += 1;
        tracing::debug!(id, ?found, ?expected, "start position off; SetPose");
        let z = if id == ACTUATOR_ID {
            ACTUATOR_Z
        } else {
            BLOCK_Z
        };
        // `expected_start` only holds ids of the world's bodies.
        let name = match &self.view {
            Some(view) => view.body(id),
            None => object_name(id),
        };
        if let Some(name) = name {
            self.send(Payload::set_pose(
                name,
                [expected.x, expected.y, z],
                expected.theta,
            ));
        }
        self.started_run = true;
        false
    }
}

/// One experiment's handler (`docs/spec/experiments.md` §3–§4): called for every
/// message that passed the common checks, with the model's parse of it and
/// the driver's own reading of it.
pub trait Task<M: Model> {
    /// Handles one message: `world` is the model's parse, for the model;
    /// `actual` the driver's reading of the same state ([`read_state`]), for
    /// everything the task decides or scores by the real state. Commands go
    /// through `core`; the job ends with [`Core::finish`].
    fn handle(&mut self, core: &mut Core<M>, model: &mut M, world: &M::World, actual: &Poses);

    /// What the learner is shown of the world states before the task
    /// first changes it ([`Core::set_view`]); `None`: everything.
    fn initial_view(&self) -> Option<View> {
        None
    }

    /// Which run of the job is in progress or next, for messages (e.g.
    /// `training run 2 of 3`); empty if the task has no runs to name.
    fn run_name(&self) -> String {
        String::new()
    }
}

/// The driver's reading of a real world state: the poses it checks start
/// positions, ends runs and scores predictions by (`docs/spec/experiments.md`
/// §2, §7), read at the thesis's precision (3 decimals, as the thesis's
/// driver read them through its model) with the learner's rule for the
/// actuator's yaw. It is the driver's, not the model's, so that a learner is
/// judged alike however it runs — in process, behind the learner protocol,
/// from Python — and whatever its own parse keeps.
///
/// # Errors
/// A state without an actuator, with an unknown or duplicate id, or a
/// non-finite number.
pub fn read_state(frame: &Frame, actuator_yaw: ActuatorYaw) -> Result<Poses, ParseError> {
    parse_frame(frame, actuator_yaw)
}

/// The state machine of `docs/spec/experiments.md` §2 for one job: a fresh model and
/// the task that drives it.
#[derive(Debug)]
pub struct Driver<M: Model, T: Task<M>> {
    core: Core<M>,
    model: M,
    task: T,
    /// Why the model stopped answering ([`Model::failure`]); ends the job.
    failure: Option<String>,
}

impl<M: Model, T: Task<M>> Driver<M, T> {
    /// A driver that starts, on its first message, with SetPublishRate and a
    /// world reset (`startup`).
    pub fn new(model: M, task: T, publish_rate_hz: u32) -> Self {
        let mut core = Core::new(publish_rate_hz);
        core.set_view(task.initial_view());
        Self {
            core,
            model,
            task,
            failure: None,
        }
    }

    /// A driver whose world emulates `latency`, seeded just before the
    /// driver's first command: it follows the world's draws for every
    /// command it sends, and tells the model the delay of its next Move
    /// ([`Model::next_move_delay`]) before each message.
    #[must_use]
    pub fn knowing_latency(mut self, latency: Option<Latency>) -> Self {
        self.core.delays = latency.map(DelayDraws::new);
        self
    }

    /// `on_world_state(msg)`: returns the commands to send, in order.
    pub fn on_state(&mut self, frame: &Frame) -> Vec<Payload> {
        let core = &mut self.core;
        if core.done {
            return Vec::new();
        }
        core.counters.messages += 1;
        // Everything sent now goes out with one Advance: one interval.
        if let Some(delays) = &mut core.delays {
            delays.next_interval();
        }
        if core.startup {
            core.send(Payload::publish_rate(core.publish_rate_hz));
            core.reset_world();
            core.startup = false;
        } else if core.ignore {
            core.ignore = false;
            core.counters.ignored += 1;
        } else {
            let shown = core.view.map(|view| view.apply(frame));
            let shown = shown.as_ref().unwrap_or(frame);
            let parsed = read_state(shown, self.model.actuator_yaw())
                .and_then(|actual| Ok((self.model.parse(shown)?, actual)));
            match parsed {
                Err(err) => {
                    core.counters.parse_errors += 1;
                    tracing::warn!(%err, "a world state the model cannot parse was skipped");
                }
                Ok((world, actual)) => {
                    let checked = !std::mem::take(&mut core.started_run)
                        || core.check_start_positions(&actual);
                    if checked {
                        if let Some(delays) = &core.delays {
                            self.model.next_move_delay(delays.peek(true));
                        }
                        self.task.handle(core, &mut self.model, &world, &actual);
                    }
                }
            }
        }
        if let Some(why) = self.model.failure() {
            // What the model answered after it failed is not a result.
            self.failure = Some(why);
            core.done = true;
            core.out.clear();
        }
        std::mem::take(&mut core.out)
    }

    /// Why the model stopped answering, if it did: the job then ended
    /// without a result.
    #[must_use]
    pub fn failure(&self) -> Option<&str> {
        self.failure.as_deref()
    }

    /// Whether the job has ended.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.core.done
    }

    /// Where in its job the driver is, for messages: the task's run and the
    /// message of the run (e.g. `test run 4 of 21, message 37`).
    #[must_use]
    pub fn position(&self) -> String {
        let run = self.task.run_name();
        let message = format!("message {} of the run", self.core.step_counter);
        if run.is_empty() {
            message
        } else {
            format!("{run}, {message}")
        }
    }

    /// The publish rate this driver sets, for the 2/f budget.
    #[must_use]
    pub fn publish_rate_hz(&self) -> u32 {
        self.core.publish_rate_hz
    }

    /// The counters so far.
    #[must_use]
    pub fn counters(&self) -> Counters {
        self.core.counters
    }

    /// The task (its results) and the model, once done.
    pub fn into_parts(self) -> (T, M, Counters) {
        (self.task, self.model, self.core.counters)
    }

    /// The model.
    #[must_use]
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The task.
    #[must_use]
    pub fn task(&self) -> &T {
        &self.task
    }
}

#[cfg(any(test, feature = "testing"))]
pub mod test_support {
    //! A scripted world for driver tests: frames built from poses, the
    //! learner's test model (its predictions are visible), and a decoder for
    //! the commands.

    use learner::{Frame, ObjectState, Observation};

    use pushlearn::wire::pb::{client_message::Payload, sim_control};

    /// A frame with the actuator at (x, y) and the given blocks.
    pub fn frame(actuator: (f64, f64), blocks: &[(u32, ObjectState)]) -> Frame {
        let obs = |name: &str, id, x, y, yaw: f64, z| Observation {
            name: name.into(),
            id,
            position: [x, y, z],
            orientation: learner::features::yaw_to_quaternion(yaw),
            shape: None,
        };
        let mut objects = vec![obs("actuator", 8, actuator.0, actuator.1, 0.0, 0.03)];
        for (id, s) in blocks {
            let name = learner::object_name(*id).unwrap_or("block");
            objects.push(obs(name, *id, s.x, s.y, s.theta, 0.05));
        }
        Frame { objects }
    }

    /// The blue block at its start pose.
    pub fn blue_home() -> Vec<(u32, ObjectState)> {
        vec![(learner::BLUE_ID, ObjectState::new(0.0, 0.25, 0.0))]
    }

    /// Short names of commands, e.g. `move(0,0.5)`, `reset`, `pose(actuator,0.1,0)`.
    pub fn describe(commands: &[Payload]) -> Vec<String> {
        commands
            .iter()
            .map(|c| match c {
                Payload::Actuator(a) => {
                    let d = a.direction.unwrap_or_default();
                    format!("move({},{})", d.x, d.y)
                }
                Payload::Control(c) => match c.action {
                    Some(sim_control::Action::PublishRateHz(hz)) => format!("rate({hz})"),
                    _ => c_kind(c),
                },
                Payload::SetPose(v) => v
                    .models
                    .iter()
                    .map(|m| {
                        let p = m.pose.and_then(|p| p.position).unwrap_or_default();
                        format!("pose({},{},{})", m.name, p.x, p.y)
                    })
                    .collect::<Vec<_>>()
                    .join(";"),
            })
            .collect()
    }

    fn c_kind(c: &pushlearn::wire::pb::SimControl) -> String {
        Payload::Control(*c).kind().to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::{blue_home, describe, frame};
    use super::*;
    use crate::scene::push_task_blocks;
    use learner::testing::Probe;

    /// A task that starts one run at x = 0.1 and records what reaches it.
    #[derive(Debug, Default)]
    struct Recorder {
        handled: Vec<(u64, f64)>,
    }

    impl Task<Probe> for Recorder {
        fn handle(
            &mut self,
            core: &mut Core<Probe>,
            _model: &mut Probe,
            world: &Poses,
            _actual: &Poses,
        ) {
            core.step_counter += 1;
            if !core.run_started {
                core.start_run((0.1, 0.0), &push_task_blocks(), true);
                return;
            }
            self.handled.push((core.step_counter, world.actuator.x));
            if core.step_counter == 2 {
                core.finish();
            }
        }
    }

    #[test]
    fn startup_sets_the_rate_resets_and_drops_the_next_message() {
        let mut d = Driver::new(Probe::default(), Recorder::default(), 100);
        let home = frame((0.0, 0.0), &blue_home());
        assert_eq!(
            describe(&d.on_state(&home)),
            ["rate(100)", "move(0,0)", "reset"]
        );
        // The next message may predate the reset: dropped unseen.
        assert!(d.on_state(&home).is_empty());
        assert_eq!(d.counters().ignored, 1);
        // Then the task starts its run: SetPose, and one more dropped message.
        assert_eq!(describe(&d.on_state(&home)), ["pose(actuator,0.1,0)"]);
        assert!(d.on_state(&home).is_empty());
        assert_eq!(d.counters().ignored, 2);
        assert!(d.task().handled.is_empty());
    }

    #[test]
    fn a_failed_start_check_sets_the_pose_again_and_is_not_handled() {
        let mut d = Driver::new(Probe::default(), Recorder::default(), 100);
        let home = frame((0.0, 0.0), &blue_home());
        for _ in 0..4 {
            d.on_state(&home);
        }
        // Still at the old place: corrected, not counted.
        assert_eq!(describe(&d.on_state(&home)), ["pose(actuator,0.1,0)"]);
        assert_eq!(d.counters().reset_errors, 1);
        // A pushed block is put back at z = 0.05 with its start yaw.
        let moved_block = [(learner::BLUE_ID, ObjectState::new(0.0, 0.3, 0.0))];
        assert_eq!(
            describe(&d.on_state(&frame((0.1, 0.0), &moved_block))),
            ["pose(blockA,0,0.25)"]
        );
        assert_eq!(d.counters().reset_errors, 2);
        assert!(d.task().handled.is_empty());
        // Within 0.01 everywhere: the check passes, and no message is dropped
        // after a correction (the original had no `ignore` there).
        let close = frame(
            (0.105, 0.004),
            &[(learner::BLUE_ID, ObjectState::new(0.003, 0.25, 0.0))],
        );
        assert!(d.on_state(&close).is_empty());
        assert_eq!(d.task().handled, [(1, 0.105)]);
        // Later messages are not checked.
        d.on_state(&frame((0.5, 0.5), &blue_home()));
        assert_eq!(d.task().handled.len(), 2);
        assert!(d.is_done());
        assert!(d.on_state(&home).is_empty(), "a done driver sends nothing");
        assert_eq!(d.counters().reset_errors, 2);
    }

    #[test]
    fn the_check_uses_the_norm_over_x_y_and_theta() {
        let mut d = Driver::new(Probe::default(), Recorder::default(), 100);
        let home = frame((0.1, 0.0), &blue_home());
        for _ in 0..4 {
            d.on_state(&home);
        }
        let turned = [(learner::BLUE_ID, ObjectState::new(0.0, 0.25, 0.02))];
        assert_eq!(
            describe(&d.on_state(&frame((0.1, 0.0), &turned))),
            ["pose(blockA,0,0.25)"]
        );
    }

    #[test]
    fn unparseable_frames_are_counted_and_skipped() {
        let mut d = Driver::new(Probe::default(), Recorder::default(), 100);
        let home = frame((0.1, 0.0), &blue_home());
        d.on_state(&home);
        d.on_state(&home);
        let mut broken = home.clone();
        broken.objects[0].position[0] = f64::NAN;
        assert!(d.on_state(&broken).is_empty());
        assert_eq!(d.counters().parse_errors, 1);
        assert_eq!(describe(&d.on_state(&home)), ["pose(actuator,0.1,0)"]);
    }

    #[test]
    fn run_ended_by_count_or_distance() {
        let mut core = Core::<Probe>::new(100);
        let mut poses = Poses::default();
        core.step_counter = 150;
        assert!(!core.run_ended(&poses));
        core.step_counter = 151;
        assert!(core.run_ended(&poses));
        core.step_counter = 1;
        poses.actuator = ObjectState::new(0.6, 0.81, 0.0);
        assert!(core.run_ended(&poses));
    }
}
