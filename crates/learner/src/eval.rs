//! The push-task protocol on the learner's side and its metrics
//! (`docs/spec/experiments.md` §2, §3, §7), independent of where the frames come from:
//! the experiment driver feeds it messages from the simulator's socket, the
//! trace-driven tests feed it runs of an in-process world.
//!
//! One [`RunStepper`] handles the messages of one run: `train` is the spec's
//! `train_step`, `test` its `test_step` (chained predictions without
//! feedback). [`RunErrors`] scores the last message of a test run against the
//! prediction made on the message before, and [`MeanStd`] / [`CurvePoint`]
//! aggregate them as the thesis's tables and figures do.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::features::ParseError;
use crate::model::Model;
use crate::types::{Action, Frame, ObjectState, Poses};

/// The push action of every push-task run, in training and in testing
/// (`docs/spec/experiments.md` §3): straight towards the block at 0.5 m/s.
pub const PUSH_ACTION: Action = Action::new(0.0, 0.5);

/// Messages processed per run; the next one (the 151st) ends the run and is
/// the one scored (`docs/spec/experiments.md` §2: "the message on which `step_counter`
/// becomes 151 ends the run").
pub const MESSAGES_PER_RUN: usize = 150;

/// A run also ends once the actuator is farther than this from the origin
/// (`docs/spec/experiments.md` §2.1 `run_ended`).
pub const RUN_END_DISTANCE: f64 = 1.0;

/// Number of push-task test positions.
pub const TEST_POSITION_COUNT: usize = 21;

/// Indices of the 15 test positions whose push meets the block
/// (`docs/spec/experiments.md` §3: ±0.28, ±0.315, ±0.35 miss it).
pub const INTERACTING_POSITIONS: std::ops::RangeInclusive<usize> = 3..=17;

/// The first training starts of configuration 8 (`docs/spec/experiments.md` §3.2, §8:
/// −0.18 / 0.18, not the −0.14 / 0.14 of the original's last commit).
pub const FIXED_TRAINING_STARTS: [f64; 3] = [-0.18, 0.18, 0.0];

/// The single-block test starts `−0.35 + 0.035·i`, i = 0 … 20.
#[must_use]
pub fn test_positions() -> [f64; TEST_POSITION_COUNT] {
    std::array::from_fn(|i| -0.35 + 0.035 * i as f64)
}

/// The two-object test starts `−0.8 + 0.06·i`, i = 0 … 20 (`docs/spec/experiments.md`
/// §3.3).
#[must_use]
pub fn two_object_test_positions() -> [f64; TEST_POSITION_COUNT] {
    std::array::from_fn(|i| -0.8 + 0.06 * i as f64)
}

/// Width of the random training start range of `docs/spec/experiments.md` §3:
/// [−0.25, 0.25), the block's length.
pub const TRAINING_START_RANGE: f64 = 0.5;

/// The range with configuration bit 4, ALLOWMISSPOSITIONS (`docs/spec/experiments.md`
/// §1): [−0.35, 0.35), so that some pushes miss the block (thesis draft
/// §6.1.1 samples "between −0.35 and 0.35").
pub const WIDE_TRAINING_START_RANGE: f64 = 0.7;

/// A random training start from a uniform sample `u` in [0, 1):
/// `(u − 0.5) · 0.5`, i.e. [−0.25, 0.25) (`docs/spec/experiments.md` §3). The caller
/// draws `u` for every run, also when a fixed start replaces it, so that the
/// random sequence does not depend on the variant.
#[must_use]
pub fn random_training_start(u: f64) -> f64 {
    training_start_in(u, TRAINING_START_RANGE)
}

/// A start uniform in a range of `width` centred on 0, from `u` in [0, 1).
#[must_use]
pub fn training_start_in(u: f64, width: f64) -> f64 {
    (u - 0.5) * width
}

/// The thesis draft's first three training starts (§6.1.1): "the outer
/// left, the outer right side and directly at the center" of the blue
/// block, i.e. the actuator's centre under the block's ends (± its half
/// length from the shape table) and under its centre.
#[must_use]
pub fn draft_training_starts() -> [f64; 3] {
    let (w, _) = crate::keypoints::half_extents(crate::types::BLUE_ID);
    [-w, w, 0.0]
}

/// `run_ended(WS)` of `docs/spec/experiments.md` §2.1, for the distance part; the step
/// count part is the caller's (it counts messages).
#[must_use]
pub fn actuator_left_area(poses: &Poses) -> bool {
    let a = &poses.actuator;
    a.x.hypot(a.y) > RUN_END_DISTANCE
}

/// How close a block must come to its target for a Move-to-Target run to
/// count as reached: the thesis's threshold (`docs/spec/planning.md` §1) on
/// [`goal_distance`], metres and radians together.
pub const GOAL_TOLERANCE: f64 = 0.01;

/// `|wrap(θ − θ_t)|` with the single wrap of `docs/spec/experiments.md` §7.6:
/// a difference beyond π is taken the other way round once.
#[must_use]
pub fn wrapped_angle_error(theta: f64, target: f64) -> f64 {
    use std::f64::consts::PI;
    let mut d = theta - target;
    if d > PI {
        d -= 2.0 * PI;
    } else if d < -PI {
        d += 2.0 * PI;
    }
    d.abs()
}

/// The norm of a block's `(Δx, Δy, wrap(Δθ))` to its target: the one
/// success criterion of every task with a goal (Move to Target, `pushlearn
/// learn --target`, the Gymnasium environments), judged by the harness on
/// the world's own state, never taken from a learner.
///
/// The thesis's models test the same norm on their own records without
/// wrapping the angle (`docs/spec/planning.md` §6): where the two disagree
/// (a block at −3.14 rad and a target at π) the world's wrapped difference
/// is the true one. The sum runs in the order of
/// [`ObjectState::distance_to`], so that the two agree bit for bit whenever
/// the angle needs no wrap.
#[must_use]
pub fn goal_distance(pose: &ObjectState, target: &ObjectState) -> f64 {
    let dx = pose.x - target.x;
    let dy = pose.y - target.y;
    let dt = wrapped_angle_error(pose.theta, target.theta);
    (dx * dx + dy * dy + dt * dt).sqrt()
}

/// Whether a block at `pose` has reached `target` ([`goal_distance`] below
/// [`GOAL_TOLERANCE`]).
#[must_use]
pub fn goal_reached(pose: &ObjectState, target: &ObjectState) -> bool {
    goal_distance(pose, target) < GOAL_TOLERANCE
}

/// The per-message learner side of one run (`docs/spec/experiments.md` §2
/// `train_step` / `test_step`).
///
/// `last_prediction` doubles, as in the original, as the marker that the
/// first message of the run has been handled; start every run with a new
/// stepper (the driver's `reset_world` clears both fields).
#[derive(Debug, Clone)]
pub struct RunStepper<M: Model> {
    last_action: Option<Action>,
    last_prediction: Option<M::World>,
    messages: usize,
}

impl<M: Model> Default for RunStepper<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: Model> RunStepper<M> {
    /// A stepper for a new run.
    #[must_use]
    pub fn new() -> Self {
        Self {
            last_action: None,
            last_prediction: None,
            messages: 0,
        }
    }

    /// `train_step`: re-synchronise on the first message, learn the
    /// transition into `world` on every later one, then predict the next
    /// message under `direction` (for display and for the recorded rows; it
    /// never changes the model). Returns the action to send.
    pub fn train(&mut self, model: &mut M, world: &M::World, direction: Action) -> Action {
        match self.last_action {
            Some(action) if self.last_prediction.is_some() => model.update(world, action),
            _ => model.reset_objects(world),
        }
        self.last_action = Some(direction);
        self.last_prediction = Some(model.predict(world, direction));
        self.messages += 1;
        direction
    }

    /// `test_step`: the chain starts from the real state of the run's first
    /// message and from then on predicts from its own previous prediction;
    /// later real states are never shown to the model. `update` is called on
    /// the prediction, as in the original: with training off it only moves
    /// the model's stored states forward. Returns the action to send.
    pub fn test(&mut self, model: &mut M, world: &M::World, direction: Action) -> Action {
        self.last_action = Some(direction);
        let from = match self.last_prediction.take() {
            Some(previous) => previous,
            None => {
                model.reset_objects(world);
                world.clone()
            }
        };
        model.update(&from, direction);
        self.last_prediction = Some(model.predict(&from, direction));
        self.messages += 1;
        direction
    }

    /// The prediction made on the latest message (of the state at the next
    /// one), if any.
    #[must_use]
    pub fn last_prediction(&self) -> Option<&M::World> {
        self.last_prediction.as_ref()
    }

    /// Messages handled so far in this run.
    #[must_use]
    pub fn messages(&self) -> usize {
        self.messages
    }
}

/// Errors of one scored test run (`docs/spec/experiments.md` §7.2): the actual state
/// of the message that ended the run against the prediction made on the
/// message before.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BlockError {
    /// Centre distance `|(x, y) − (x̂, ŷ)|` in metres.
    pub pos: f64,
    /// `|θ − θ̂|` in radians, deliberately **not** wrapped.
    pub ori: f64,
}

/// All errors of one scored run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunErrors {
    /// Actuator centre distance in metres.
    pub actuator: f64,
    /// Per block id; see [`RunErrors::score`] for blocks missing on one side.
    pub blocks: BTreeMap<u32, BlockError>,
}

impl RunErrors {
    /// Scores `predicted` against `actual`. Blocks present in only one of
    /// them are left out (a model never drops a block it was given, so a
    /// missing block is the caller's bug and shows up as a missing entry).
    #[must_use]
    pub fn score(actual: &Poses, predicted: &Poses) -> Self {
        let actuator = (actual.actuator.x - predicted.actuator.x)
            .hypot(actual.actuator.y - predicted.actuator.y);
        let blocks = actual
            .blocks
            .iter()
            .filter_map(|(&id, a)| {
                let p = predicted.blocks.get(&id)?;
                Some((
                    id,
                    BlockError {
                        pos: (a.x - p.x).hypot(a.y - p.y),
                        ori: (a.theta - p.theta).abs(),
                    },
                ))
            })
            .collect();
        Self { actuator, blocks }
    }
}

/// Trains `model` on one recorded run: `frames[0..150]` are the processed
/// messages (fewer if the actuator left the area first); later frames are
/// ignored. Returns the number of messages processed.
///
/// # Errors
/// A frame that does not parse.
pub fn train_on_run<M: Model>(
    model: &mut M,
    frames: &[Frame],
    direction: Action,
) -> Result<usize, ParseError> {
    let mut stepper = RunStepper::<M>::new();
    for frame in frames.iter().take(MESSAGES_PER_RUN) {
        let world = model.parse(frame)?;
        if actuator_left_area(&M::poses(&world)) {
            break;
        }
        stepper.train(model, &world, direction);
    }
    Ok(stepper.messages())
}

/// Runs one push-task test run on a recorded run of at least 151 frames and
/// scores the run's end (`docs/spec/experiments.md` §2, §7.2): 150 chained predictions,
/// the last of which is compared with frame 151. `None` if there are too few
/// frames or the run ended early before any prediction was made.
///
/// # Errors
/// A frame that does not parse.
pub fn test_on_run<M: Model>(
    model: &mut M,
    frames: &[Frame],
    direction: Action,
) -> Result<Option<RunErrors>, ParseError> {
    let mut stepper = RunStepper::<M>::new();
    for frame in frames.iter().take(MESSAGES_PER_RUN + 1) {
        let world = model.parse(frame)?;
        let ended = stepper.messages() == MESSAGES_PER_RUN || actuator_left_area(&M::poses(&world));
        if ended {
            return Ok(stepper
                .last_prediction()
                .map(|p| RunErrors::score(&M::poses(&world), &M::poses(p))));
        }
        stepper.test(model, &world, direction);
    }
    Ok(None)
}

/// Mean and **population** standard deviation (divide by n), as the thesis's
/// per-position tables use them (`docs/spec/experiments.md` §7.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanStd {
    pub mean: f64,
    pub std: f64,
}

impl MeanStd {
    /// NaN for an empty slice, so that a missing value cannot pass for 0.
    #[must_use]
    pub fn of(values: &[f64]) -> Self {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
        Self {
            mean,
            std: var.sqrt(),
        }
    }
}

/// One point of a learning curve (`docs/spec/experiments.md` §7.4): the mean over test
/// positions of the per-position means, with the mean of the per-position
/// standard deviations as its error bar (not the spread over all runs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    pub mean: f64,
    pub error_bar: f64,
}

impl CurvePoint {
    #[must_use]
    pub fn of(per_position: &[MeanStd]) -> Self {
        let n = per_position.len() as f64;
        Self {
            mean: per_position.iter().map(|p| p.mean).sum::<f64>() / n,
            error_bar: per_position.iter().map(|p| p.std).sum::<f64>() / n,
        }
    }

    /// The value the original analysis plotted for the actuator over the
    /// interacting positions: the mean of `(mean + std) / 2` per position
    /// (`docs/spec/experiments.md` §7.4 quirk). Only for comparison with the thesis's
    /// figures; [`CurvePoint::of`] is the correct value.
    #[must_use]
    pub fn original_script_quirk(per_position: &[MeanStd]) -> f64 {
        per_position
            .iter()
            .map(|p| (p.mean + p.std) / 2.0)
            .sum::<f64>()
            / per_position.len() as f64
    }
}

/// Per test position, the errors of every fold, and their summaries.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PositionErrors {
    pub actuator: Vec<f64>,
    pub block_pos: BTreeMap<u32, Vec<f64>>,
    pub block_ori: BTreeMap<u32, Vec<f64>>,
}

impl PositionErrors {
    /// Adds one fold's errors at this position.
    pub fn push(&mut self, errors: &RunErrors) {
        self.actuator.push(errors.actuator);
        for (&id, e) in &errors.blocks {
            self.block_pos.entry(id).or_default().push(e.pos);
            self.block_ori.entry(id).or_default().push(e.ori);
        }
    }
}

/// Learning-curve summary of one `N_train` over all positions and over the
/// interacting ones (`docs/spec/experiments.md` §7.4), for one block.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurveSummary {
    pub block_pos: CurvePoint,
    pub block_ori: CurvePoint,
    pub actuator: CurvePoint,
    pub block_pos_interacting: CurvePoint,
    pub block_ori_interacting: CurvePoint,
    pub actuator_interacting: CurvePoint,
    /// [`CurvePoint::original_script_quirk`] of the actuator over the
    /// interacting positions.
    pub actuator_interacting_quirk: f64,
}

impl CurveSummary {
    /// Summarises `positions` (one entry per test position, in order) for
    /// block `id`. `None` if some position has no error for that block.
    #[must_use]
    pub fn of(positions: &[PositionErrors], id: u32) -> Option<Self> {
        let summarise = |f: &dyn Fn(&PositionErrors) -> Option<&Vec<f64>>| {
            positions
                .iter()
                .map(|p| f(p).map(|v| MeanStd::of(v)))
                .collect::<Option<Vec<MeanStd>>>()
        };
        let pos = summarise(&|p| p.block_pos.get(&id))?;
        let ori = summarise(&|p| p.block_ori.get(&id))?;
        let act = summarise(&|p| Some(&p.actuator))?;
        let interacting = |v: &[MeanStd]| -> Vec<MeanStd> {
            v.iter()
                .enumerate()
                .filter(|(i, _)| INTERACTING_POSITIONS.contains(i))
                .map(|(_, m)| *m)
                .collect()
        };
        Some(Self {
            block_pos: CurvePoint::of(&pos),
            block_ori: CurvePoint::of(&ori),
            actuator: CurvePoint::of(&act),
            block_pos_interacting: CurvePoint::of(&interacting(&pos)),
            block_ori_interacting: CurvePoint::of(&interacting(&ori)),
            actuator_interacting: CurvePoint::of(&interacting(&act)),
            actuator_interacting_quirk: CurvePoint::original_script_quirk(&interacting(&act)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{parse_frame, ActuatorYaw};
    use crate::testing::Probe;
    use crate::types::{Observation, ACTUATOR_NAME, BLUE_ID, BLUE_NAME};

    /// A run in which the actuator moves 5 mm per message and the block
    /// stays put.
    fn frames(n: usize) -> Vec<Frame> {
        (0..n)
            .map(|k| Frame {
                objects: vec![
                    Observation {
                        name: ACTUATOR_NAME.into(),
                        id: 8,
                        position: [0.0, 0.005 * k as f64, 0.03],
                        orientation: [0.0, 0.0, 0.0, 1.0],
                        shape: None,
                    },
                    Observation {
                        name: BLUE_NAME.into(),
                        id: BLUE_ID,
                        position: [0.0, 0.25, 0.05],
                        orientation: [0.0, 0.0, 0.0, 1.0],
                        shape: None,
                    },
                ],
            })
            .collect()
    }

    #[test]
    fn the_orientation_error_wraps_once() {
        use std::f64::consts::PI;
        assert!((wrapped_angle_error(-3.1, PI) - (2.0 * PI - 3.1 - PI)).abs() < 1e-12);
        assert!((wrapped_angle_error(0.5, -2.1) - 2.6).abs() < 1e-12);
        assert!((wrapped_angle_error(3.0, -3.0) - (2.0 * PI - 6.0)).abs() < 1e-12);
        // Once only: a difference beyond 3π stays above π.
        assert!(wrapped_angle_error(10.0, 0.0) > PI);
    }

    #[test]
    fn the_goal_needs_position_and_orientation_and_wraps_the_angle() {
        use std::f64::consts::PI;
        let target = ObjectState::new(0.6, -0.7, PI);
        // Within 1 cm and 1 mrad of it, across the ±π seam: reached.
        let seam = ObjectState::new(0.605, -0.702, -PI + 0.001);
        assert!(goal_reached(&seam, &target));
        // The thesis's models' own test does not wrap: 2π away.
        assert!(seam.distance_to(&target) > 6.0);
        // Right place, wrong orientation: not reached.
        let blind = ObjectState::new(0.6, -0.7, PI - 1.4);
        assert!(!goal_reached(&blind, &target));
        assert!((goal_distance(&blind, &target) - 1.4).abs() < 1e-12);
        // The norm is of all three components together.
        let edge = ObjectState::new(0.6 + 0.006, -0.7 + 0.006, PI - 0.006);
        assert!(!goal_reached(&edge, &target));
        // Without a wrap the two norms are the same bits.
        let a = ObjectState::new(0.123, 0.456, 0.789);
        let b = ObjectState::new(-0.3, 0.2, -2.1);
        assert_eq!(goal_distance(&a, &b).to_bits(), a.distance_to(&b).to_bits());
    }

    #[test]
    fn test_positions_match_the_spec() {
        let x = test_positions();
        assert!((x[0] + 0.35).abs() < 1e-12);
        assert!((x[10]).abs() < 1e-12);
        assert!((x[20] - 0.35).abs() < 1e-12);
        assert!((x[3] + 0.245).abs() < 1e-12, "first interacting position");
        let two = two_object_test_positions();
        assert!((two[0] + 0.8).abs() < 1e-12 && (two[20] - 0.4).abs() < 1e-12);
        assert_eq!(random_training_start(0.0), -0.25);
        assert_eq!(random_training_start(0.5), 0.0);
        assert_eq!(training_start_in(0.0, WIDE_TRAINING_START_RANGE), -0.35);
        assert_eq!(draft_training_starts(), [-0.25, 0.25, 0.0]);
    }

    #[test]
    fn training_run_resyncs_once_then_makes_149_updates() {
        let mut model = Probe::default();
        let n = train_on_run(&mut model, &frames(151), PUSH_ACTION).unwrap();
        assert_eq!(n, MESSAGES_PER_RUN);
        assert_eq!(model.calls.len(), 150);
        assert_eq!(model.calls[0], "reset y=0.000");
        assert_eq!(model.calls[1], "update y=0.005 a=0.5");
        let updates = model
            .calls
            .iter()
            .filter(|c| c.starts_with("update"))
            .count();
        assert_eq!(
            updates, 149,
            "docs/spec/experiments.md §8: 149 updates per run"
        );
        assert_eq!(model.calls[149], "update y=0.745 a=0.5", "frame 151 unused");
    }

    #[test]
    fn test_run_chains_predictions_and_scores_the_151st_message() {
        let mut model = Probe::default();
        let errors = test_on_run(&mut model, &frames(151), PUSH_ACTION)
            .unwrap()
            .unwrap();
        // The chain is fed its own predictions: after the first message the
        // model is updated with y = 0.005, 0.010, … (the probe predicts 5 mm
        // per step), never with a real frame.
        assert_eq!(model.calls[0], "reset y=0.000");
        assert_eq!(model.calls[1], "update y=0.000 a=0.5");
        assert_eq!(model.calls[2], "update y=0.005 a=0.5");
        assert_eq!(model.calls.len(), 151);
        // P150 = 150 · 5 mm = 0.75, exactly the actual 151st state.
        assert!(errors.actuator < 1e-9, "{errors:?}");
        assert_eq!(errors.blocks[&BLUE_ID].pos, 0.0);
    }

    #[test]
    fn test_run_error_compares_prediction_150_with_message_151() {
        let mut model = Probe::default();
        let mut run = frames(151);
        // Only the scored message moves: a chain that looked at real states
        // or scored another message would not see this.
        run[150].objects[0].position[0] = 0.3;
        let errors = test_on_run(&mut model, &run, PUSH_ACTION).unwrap().unwrap();
        assert!((errors.actuator - 0.3).abs() < 1e-9, "{errors:?}");
        assert_eq!(
            test_on_run(&mut Probe::default(), &run[..150], PUSH_ACTION).unwrap(),
            None
        );
    }

    #[test]
    fn orientation_error_is_not_wrapped() {
        let mut actual = parse_frame(&frames(1)[0], ActuatorYaw::ForceZero).unwrap();
        let mut predicted = actual.clone();
        actual.blocks.get_mut(&BLUE_ID).unwrap().theta = 3.1;
        predicted.blocks.get_mut(&BLUE_ID).unwrap().theta = -3.1;
        let e = RunErrors::score(&actual, &predicted);
        assert!((e.blocks[&BLUE_ID].ori - 6.2).abs() < 1e-12);
    }

    #[test]
    fn statistics_use_population_std_and_mean_of_position_stds() {
        let m = MeanStd::of(&[1.0, 3.0]);
        assert_eq!(
            m,
            MeanStd {
                mean: 2.0,
                std: 1.0
            }
        );
        assert!(MeanStd::of(&[]).mean.is_nan());
        let per = [
            MeanStd {
                mean: 1.0,
                std: 0.5,
            },
            MeanStd {
                mean: 3.0,
                std: 1.5,
            },
        ];
        assert_eq!(
            CurvePoint::of(&per),
            CurvePoint {
                mean: 2.0,
                error_bar: 1.0
            }
        );
        assert_eq!(CurvePoint::original_script_quirk(&per), 1.5);
    }

    #[test]
    fn curve_summary_restricts_to_the_interacting_positions() {
        let positions: Vec<PositionErrors> = (0..TEST_POSITION_COUNT)
            .map(|i| {
                let mut p = PositionErrors::default();
                let miss = !INTERACTING_POSITIONS.contains(&i);
                let e = RunErrors {
                    actuator: 0.0,
                    blocks: [(
                        BLUE_ID,
                        BlockError {
                            pos: if miss { 1.0 } else { 0.0 },
                            ori: 0.0,
                        },
                    )]
                    .into(),
                };
                p.push(&e);
                p
            })
            .collect();
        let s = CurveSummary::of(&positions, BLUE_ID).unwrap();
        assert!((s.block_pos.mean - 6.0 / 21.0).abs() < 1e-12);
        assert_eq!(s.block_pos_interacting.mean, 0.0);
        assert!(CurveSummary::of(&positions, 27).is_none());
    }
}
