//! `pushlearn learner-check`: a learner author's conformance kit.
//!
//! Runs short scripted conversations against an external learner — every
//! message kind, a fold boundary, chained predictions, Move to Target if the
//! learner announces INVERSE — through the driver's own client
//! ([`ExternalModel`]) and its own run logic ([`RunStepper`]), so the
//! requests are the ones an experiment sends and every reply is checked by
//! the rules an experiment enforces (`docs/learner-protocol.md`). A rule
//! broken ends that conversation (as it would end a job); the next one
//! starts with a fresh connection, so one mistake does not hide the others.
//!
//! The states are a plausible push, not physics: the actuator drives straight
//! at the blue block and carries it along once it reaches it. A learner's
//! predictions are not judged for accuracy, only for the protocol.

use learner::eval::RunStepper;
use learner::features::ACTUATOR_SHAPE;
use learner::{
    Action, BodyShape, Frame, Model, ObjectState, Observation, Target, BLUE_ID, BLUE_NAME,
};
use learner::{ACTUATOR_ID, ACTUATOR_NAME};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::{ExternalModel, LearnerInfo, LearnerSpec};

/// The push of every scripted run, as the push task's.
const PUSH: Action = learner::eval::PUSH_ACTION;

/// The fold seed of the scripted folds.
pub const FOLD_SEED: u64 = 7;

/// What one check found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The learner kept the rule.
    Kept,
    /// The learner broke it: the driver's error, naming the message.
    Broken(String),
    /// Allowed by the driver, but a report would suffer from it.
    Warning(String),
    /// Not checked, and why.
    Skipped(String),
}

/// One rule (or group of rules) and what the learner did with it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Finding {
    /// What was checked, with the page's section.
    pub rule: String,
    pub outcome: Outcome,
}

/// Everything one `learner-check` found.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Findings {
    /// What the learner said in its hello, if it said one.
    pub learner: Option<LearnerInfo>,
    pub findings: Vec<Finding>,
}

impl Findings {
    /// The rules the learner broke.
    #[must_use]
    pub fn broken(&self) -> usize {
        self.findings
            .iter()
            .filter(|f| matches!(f.outcome, Outcome::Broken(_)))
            .count()
    }

    fn push(&mut self, rule: impl Into<String>, outcome: Outcome) {
        self.findings.push(Finding {
            rule: rule.into(),
            outcome,
        });
    }
}

/// A world message with the actuator at `actuator` and the blue block at
/// `block` (yaw 0, the heights the world publishes).
#[must_use]
pub fn scripted_state(actuator: (f64, f64), block: (f64, f64)) -> Frame {
    let body = |name: &str, id, (x, y): (f64, f64), z, shape| Observation {
        name: name.to_owned(),
        id,
        position: [x, y, z],
        orientation: [0.0, 0.0, 0.0, 1.0],
        shape: Some(shape),
    };
    // The thesis's bodies with the shapes an experiment's states carry.
    Frame {
        objects: vec![
            body(
                ACTUATOR_NAME,
                ACTUATOR_ID,
                actuator,
                0.03,
                BodyShape::Sphere {
                    radius: ACTUATOR_SHAPE.radius,
                },
            ),
            body(
                BLUE_NAME,
                BLUE_ID,
                block,
                0.05,
                BodyShape::Box {
                    size: [0.5, 0.1, 0.1],
                },
            ),
        ],
    }
}

/// `messages` states of a push from `(x0, 0)` at 0.5 m/s towards the blue
/// block at (0, 0.25): once the actuator reaches the block's near face it
/// carries the block along.
#[must_use]
pub fn scripted_push(x0: f64, messages: usize, publish_rate_hz: u32) -> Vec<Frame> {
    let per_message = PUSH.vy / f64::from(publish_rate_hz.max(1));
    // The blue block's half width plus the actuator's radius: where they touch.
    let contact = 0.05 + ACTUATOR_SHAPE.radius;
    (0..messages)
        .map(|k| {
            let y = per_message * k as f64;
            let block_y = if x0.abs() < 0.05 {
                0.25f64.max(y + contact)
            } else {
                0.25
            };
            scripted_state((x0, y), (0.0, block_y))
        })
        .collect()
}

/// One training run of the push task through the driver's stepper.
fn train(model: &mut ExternalModel, frames: &[Frame]) -> Option<String> {
    let mut stepper = RunStepper::new();
    for frame in frames {
        let world = match parse(model, frame) {
            Ok(world) => world,
            Err(failure) => return Some(failure),
        };
        stepper.train(model, &world, PUSH);
        if let Some(failure) = model.failure() {
            return Some(failure);
        }
    }
    None
}

/// One test run: the chain from the run's first state, as the push task's.
fn test(model: &mut ExternalModel, frames: &[Frame]) -> Result<Vec<ObjectState>, String> {
    let mut stepper = RunStepper::new();
    let mut predicted = Vec::new();
    for frame in frames {
        let world = parse(model, frame)?;
        stepper.test(model, &world, PUSH);
        if let Some(failure) = model.failure() {
            return Err(failure);
        }
        if let Some(p) = stepper.last_prediction() {
            let poses = ExternalModel::poses(p);
            predicted.push(poses.actuator);
            predicted.extend(poses.blocks.values().copied());
        }
    }
    Ok(predicted)
}

/// A scripted state as the driver parses it; it fails only if the script
/// itself is wrong, which every run must report rather than skip.
fn parse(model: &ExternalModel, frame: &Frame) -> Result<super::ExternalWorld, String> {
    model
        .parse(frame)
        .map_err(|e| format!("the driver could not parse its own scripted state: {e}"))
}

/// One fold as the push task runs it: NewFold, a training run (Reset and
/// Predict, then Update and Predict from the observed state), GetStats and
/// SetTraining(false) when training ends, a test run (Reset, Update and
/// Predict from the observed state, then from `LAST_PREDICTION`). The
/// chained predictions come back for the fold-boundary check.
///
/// `docs/learner-protocol.md`'s example conversation is this with two
/// training states and two test states ([`page_example`]).
///
/// # Errors
/// The driver's error, naming the message, at the first rule broken.
pub fn push_fold(
    base: &ExternalModel,
    training: &[Frame],
    testing: &[Frame],
) -> Result<Vec<ObjectState>, String> {
    let mut model = base.clone();
    model.start_fold(FOLD_SEED);
    if let Some(failure) = train(&mut model, training) {
        return Err(failure);
    }
    // As the push task: statistics first, then training off.
    let _ = model.stats();
    model.set_training(false);
    if let Some(failure) = model.failure() {
        return Err(failure);
    }
    test(&mut model, testing)
}

/// The conversation of `docs/learner-protocol.md` §3, "A whole
/// conversation": a fold of the push task with two training and two test
/// states at 100 Hz, then Bye. The suite replays the page's bytes through
/// this (`tests/e2e/docs.rs`).
///
/// # Errors
/// As [`push_fold`], or the learner's hello.
pub fn page_example(spec: &LearnerSpec) -> Result<(), String> {
    let base = ExternalModel::connect(spec, "push-task", 100).map_err(|e| e.to_string())?;
    let training = [
        scripted_state((0.1, 0.0), (0.0, 0.25)),
        scripted_state((0.1, 0.005), (0.0, 0.25)),
    ];
    let testing = [
        scripted_state((-0.1, 0.0), (0.0, 0.25)),
        scripted_state((-0.1, 0.005), (0.0, 0.25)),
    ];
    push_fold(&base, &training, &testing).map(|_| ())
}

/// Training messages of a scripted run, and test messages.
const TRAINING_MESSAGES: usize = 60;
const TEST_MESSAGES: usize = 40;
/// Test-run messages of the scripted Move to Target.
const TARGET_MESSAGES: usize = 30;

/// Runs every check against the learner `spec` names.
#[must_use]
pub fn check(spec: &LearnerSpec, publish_rate_hz: u32) -> Findings {
    let mut found = Findings::default();
    let hello_rule = "hello (§5): protocol version 1, a name, the FORWARD capability";
    let base = match ExternalModel::connect(spec, "push-task", publish_rate_hz) {
        Ok(base) => base,
        Err(err) => {
            found.push(hello_rule, Outcome::Broken(err.to_string()));
            return found;
        }
    };
    found.learner = Some(base.info().clone());
    found.push(hello_rule, Outcome::Kept);

    let training = scripted_push(0.0, TRAINING_MESSAGES, publish_rate_hz);
    let testing = scripted_push(0.02, TEST_MESSAGES, publish_rate_hz);
    let fold_rule = "a push-task fold (§3, §5): NewFold; Reset and Predict, then Update and \
                     Predict from the observed state; GetStats and SetTraining(false); a test \
                     run of predictions chained from LAST_PREDICTION; predictions hold the \
                     actuator and every block, finite (§4); statistics by the rule of §7";
    let first = push_fold(&base, &training, &testing);
    match &first {
        Ok(_) => found.push(fold_rule, Outcome::Kept),
        Err(failure) => found.push(fold_rule, Outcome::Broken(failure.clone())),
    }
    let boundary_rule = "a fold boundary (§5): NewFold forgets everything; the same seed and \
                         states give the same predictions";
    match first {
        Err(_) => found.push(
            boundary_rule,
            Outcome::Skipped("the first fold did not finish".into()),
        ),
        Ok(first) => match push_fold(&base, &training, &testing) {
            Err(failure) => found.push(boundary_rule, Outcome::Broken(failure)),
            Ok(second) if same_bits(&first, &second) => found.push(boundary_rule, Outcome::Kept),
            Ok(_) => found.push(
                boundary_rule,
                Outcome::Warning(
                    "the second fold, with the same seed and the same states, predicted \
                     differently from the first: the learner keeps something across NewFold or \
                     draws randomness not seeded by it, so its reports will not repeat"
                        .into(),
                ),
            ),
        },
    }
    drop(base);

    let target_rule = "Move to Target (§5, §6): SetTarget accepted; Reset, then Update and Act \
                       per message, actions finite; statistics (§7)";
    let inverse = found.learner.as_ref().is_some_and(|l| l.inverse);
    if !inverse {
        found.push(
            target_rule,
            Outcome::Skipped("the learner does not announce INVERSE".into()),
        );
        return found;
    }
    match move_to_target(spec, publish_rate_hz) {
        Ok(notes) => {
            found.push(target_rule, Outcome::Kept);
            for note in notes {
                found.push("the action's speed (§6)", Outcome::Warning(note));
            }
        }
        Err(failure) => found.push(target_rule, Outcome::Broken(failure)),
    }
    found
}

fn same_bits(a: &[ObjectState], b: &[ObjectState]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(a, b)| {
            a.x.to_bits() == b.x.to_bits()
                && a.y.to_bits() == b.y.to_bits()
                && a.theta.to_bits() == b.theta.to_bits()
        })
}

/// The world's speed limit in the built-in scenes (m/s).
const WORLD_MAX_SPEED: f64 = 0.5;

/// A Move to Target job in short: a fold, one training run, the target, a
/// test run of Update and Act, statistics. Returns notes about the actions.
fn move_to_target(spec: &LearnerSpec, publish_rate_hz: u32) -> Result<Vec<String>, String> {
    let base = ExternalModel::connect(spec, "move-to-target", publish_rate_hz)
        .map_err(|e| e.to_string())?;
    let mut model = base.clone();
    model.start_fold(FOLD_SEED);
    if let Some(failure) = train(
        &mut model,
        &scripted_push(0.0, TRAINING_MESSAGES, publish_rate_hz),
    ) {
        return Err(failure);
    }
    let _ = model.stats();
    if let Some(failure) = model.failure() {
        return Err(failure);
    }
    let goal = ObjectState::new(-0.6, -0.7, 0.0);
    if let Err(err) = model.set_target(Some(Target::new(BLUE_ID, goal))) {
        return Err(model
            .failure()
            .unwrap_or_else(|| format!("the target was refused: {err}")));
    }
    let mut notes = Vec::new();
    let mut last = None;
    // Not drawn from: an external learner explores with its own generator.
    let mut rng = ChaCha8Rng::seed_from_u64(FOLD_SEED);
    for frame in scripted_push(0.0, TARGET_MESSAGES, publish_rate_hz) {
        let world = parse(&model, &frame)?;
        match last {
            Some(action) => model.update(&world, action),
            None => model.reset_objects(&world),
        }
        let action = model.act(&mut rng);
        if let Some(failure) = model.failure() {
            return Err(failure);
        }
        let speed = action.vx.hypot(action.vy);
        if speed > WORLD_MAX_SPEED && notes.is_empty() {
            notes.push(format!(
                "it chose a speed of {speed:.3} m/s; the world drives at most \
                 {WORLD_MAX_SPEED} m/s and scales a longer velocity down, direction kept"
            ));
        }
        last = Some(action);
        if !model.has_target() {
            break;
        }
    }
    let _ = model.stats();
    match model.failure() {
        Some(failure) => Err(failure),
        None => Ok(notes),
    }
}
