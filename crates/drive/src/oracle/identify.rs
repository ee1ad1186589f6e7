//! The identification oracle (`docs/models.md`, "Reference rows"): the
//! engine itself with what a camera cannot see of an object — its friction
//! with the ground, its friction with the pusher and its centre of mass —
//! fitted to exactly the messages a learner was shown, then stepped as
//! [`Oracle`] steps its copy of the world. What is left of its error is what
//! those messages cannot tell; before any push it predicts with the middle
//! of the distributions objects are drawn from.
//!
//! The fit is argmin's Nelder–Mead over the four values, each held inside
//! its range of the distributions by `lo + (hi − lo)(1 + sin u)/2` and
//! started from the middle. It minimises the mean squared error of the runs
//! replayed open-loop: each run's chain of predictions from its first state
//! under the actions it saw, as the test chains predictions. Its budget is a
//! number of Nelder–Mead iterations ([`Budget`]); the report says how many
//! replays it took. The mass is not fitted: with the pusher's velocity
//! imposed, the frictions' forces and the object's inertia both scale with
//! it, so what a push does hardly depends on it (a test measures how
//! little).

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use learner::eval::wrapped_angle_error;
use learner::features::{ActuatorYaw, ParseError};
use learner::stats::ModelStats;
use learner::{Action, Frame, Model, Poses, Target, TargetError};
use rand::Rng;
use serde::{Deserialize, Serialize};
use sim_plugin::generate::{Distributions, Object as Drawn, Range};
use sim_plugin::scene::ShapeSpec;

use super::{Oracle, OracleLatency, OracleWorld};

/// What the identification fits: the values of an object no camera sees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Unknowns {
    pub ground_friction: f64,
    pub pusher_friction: f64,
    /// The centre of mass's horizontal offset from the shape's centre, in
    /// the object's frame, m.
    pub centre_of_mass: [f64; 2],
}

impl Unknowns {
    /// `object` with these values in place of its own.
    fn applied_to(self, object: &Drawn) -> Drawn {
        Drawn {
            ground_friction: self.ground_friction,
            pusher_friction: self.pusher_friction,
            centre_of_mass: [self.centre_of_mass[0], self.centre_of_mass[1], 0.0],
            ..object.clone()
        }
    }
}

/// How long a fit may search.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Budget {
    /// Nelder–Mead iterations (each replays the runs once or, when the
    /// simplex shrinks, once per unknown).
    pub iterations: u64,
}

impl Default for Budget {
    fn default() -> Self {
        Budget { iterations: 80 }
    }
}

/// What a fit found, and what it cost.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    pub unknowns: Unknowns,
    /// The mean squared error of the replayed runs at `unknowns`, m².
    pub error: f64,
    /// The runs' replays the fit took.
    pub replays: u64,
}

/// Why an identification cannot be set up or run.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    #[error("the object makes no valid scene: {0}")]
    Scene(#[from] sim_plugin::scene::SceneError),
    #[error("the fit failed: {0}")]
    Optimiser(String),
}

/// One run as the learner was shown it: its first state, then each later
/// state with the action that was in force on the way there and the delay
/// the harness told for it.
#[derive(Clone, Debug)]
pub struct SeenRun {
    start: OracleWorld,
    steps: Vec<Seen>,
}

#[derive(Clone, Debug)]
struct Seen {
    action: Action,
    delay: u32,
    world: OracleWorld,
}

/// The ranges the unknowns are drawn from, for one object's shape, and the
/// map from the optimiser's unbounded values into them.
#[derive(Clone, Copy, Debug)]
struct Bounds([Range; 4]);

impl Bounds {
    fn of(object: &Drawn, prior: &Distributions) -> Self {
        // The generator draws a box's offset along each side from the
        // fraction of its half-side, a cylinder's from the fraction of its
        // radius at any angle: the square around that disc holds it.
        let (half_x, half_y) = match object.shape {
            ShapeSpec::Box { size } => (size[0] / 2.0, size[1] / 2.0),
            ShapeSpec::Cylinder { radius, .. } | ShapeSpec::Sphere { radius } => (radius, radius),
        };
        let scaled = |half: f64| {
            let f = prior.com_fraction;
            Range::new(f.lo.min(-f.hi.abs()) * half, f.hi.max(f.lo.abs()) * half)
        };
        Bounds([
            prior.ground_friction,
            prior.pusher_friction,
            scaled(half_x),
            scaled(half_y),
        ])
    }

    fn unknowns(&self, u: &[f64]) -> Unknowns {
        let at = |i: usize| {
            let r = self.0[i];
            r.lo + (r.hi - r.lo) * (1.0 + u.get(i).copied().unwrap_or(0.0).sin()) / 2.0
        };
        Unknowns {
            ground_friction: at(0),
            pusher_friction: at(1),
            centre_of_mass: [at(2), at(3)],
        }
    }

    /// The middle of every range: what is assumed before any push.
    fn middle(&self) -> Unknowns {
        self.unknowns(&[0.0; 4])
    }
}

/// The error of a state no candidate can be scored on (a scene the values
/// make invalid, a body missing from a prediction): larger than any error
/// of a block that stays on the table.
const UNSCORABLE: f64 = 100.0;

/// The squared distance of two poses' blocks, the angle weighted by
/// `radius` so that it counts as the arc the object's rim moves.
fn squared_error(predicted: &Poses, seen: &Poses, radius: f64) -> f64 {
    seen.blocks
        .iter()
        .map(|(id, s)| match predicted.blocks.get(id) {
            Some(p) => {
                let turn = radius * wrapped_angle_error(p.theta, s.theta);
                (p.x - s.x).powi(2) + (p.y - s.y).powi(2) + turn * turn
            }
            None => UNSCORABLE,
        })
        .sum()
}

/// How many messages a replayed chain runs before its bodies are put back
/// where they were seen (keeping the velocities the chain gave them): a
/// whole run's chain turns on every contact's sticking or sliding, so its
/// error jumps with the values tried; chains of a tenth of a second are
/// smooth in them and still carry each contact's motion.
const SEGMENT: usize = 10;

/// The runs replayed on `oracle` in chains of [`SEGMENT`] messages, each
/// from a state seen: the mean squared error of the chained predictions
/// against what was seen.
fn replay_error(oracle: &mut Oracle, runs: &[SeenRun], radius: f64) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for run in runs {
        let mut world = run.start.clone();
        for (i, seen) in run.steps.iter().enumerate() {
            oracle.next_move_delay(seen.delay);
            world = oracle.predict(&world, seen.action);
            sum += squared_error(&Oracle::poses(&world), &Oracle::poses(&seen.world), radius);
            count += 1;
            if (i + 1) % SEGMENT == 0 {
                world = seen.world.resynced();
            }
        }
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

/// An object's footprint radius: its rim's distance from the centre.
fn rim_radius(shape: &ShapeSpec) -> f64 {
    match *shape {
        ShapeSpec::Box { size } => size[0].hypot(size[1]) / 2.0,
        ShapeSpec::Cylinder { radius, .. } | ShapeSpec::Sphere { radius } => radius,
    }
}

/// The problem Nelder–Mead solves: the replay error of candidate values.
struct Problem<'a> {
    object: &'a Drawn,
    bounds: Bounds,
    runs: &'a [SeenRun],
    publish_rate_hz: u32,
    latency_max: u32,
}

impl Problem<'_> {
    fn error_at(&self, unknowns: Unknowns) -> f64 {
        let Ok(scene) = unknowns.applied_to(self.object).scene() else {
            return UNSCORABLE;
        };
        let mut copy = Oracle::of_scene(
            scene,
            self.publish_rate_hz,
            OracleLatency::Known,
            self.latency_max,
        )
        .forgetting_chains();
        copy.start_fold(0);
        replay_error(&mut copy, self.runs, rim_radius(&self.object.shape))
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, u: &Self::Param) -> Result<f64, argmin::core::Error> {
        Ok(self.error_at(self.bounds.unknowns(u)))
    }
}

/// The first simplex's step from the middle, in the optimiser's values: a
/// quarter of each range's width either side.
const FIRST_STEP: f64 = 0.5;

/// Where Nelder–Mead starts: the best of the prior's middle and the 16
/// corners of the box at 20 % and 80 % of every range. A chain's error has
/// many local minima in the frictions (sticking against sliding at each
/// contact); starting from the best of a coarse design keeps the search
/// out of the ones far from the truth.
fn coarse_start(problem: &Problem<'_>) -> Vec<f64> {
    // (1 + sin u) / 2 = 0.2 and 0.8.
    let off = 0.6_f64.asin();
    let mut best = (problem.error_at(problem.bounds.middle()), vec![0.0; 4]);
    for corner in 0..16u32 {
        let u: Vec<f64> = (0..4)
            .map(|i| if corner >> i & 1 == 1 { off } else { -off })
            .collect();
        let error = problem.error_at(problem.bounds.unknowns(&u));
        if error < best.0 {
            best = (error, u);
        }
    }
    best.1
}

/// Fits `object`'s unknowns (its shape is known; its drawn frictions and
/// centre of mass are ignored) to `runs`, searching the ranges of `prior`.
///
/// # Errors
/// An object whose middle values make no valid scene; an optimiser failure.
pub fn fit(
    object: &Drawn,
    prior: &Distributions,
    runs: &[SeenRun],
    publish_rate_hz: u32,
    latency_max: u32,
    budget: Budget,
) -> Result<Fit, IdentifyError> {
    let bounds = Bounds::of(object, prior);
    bounds.middle().applied_to(object).scene()?;
    let problem = Problem {
        object,
        bounds,
        runs,
        publish_rate_hz,
        latency_max,
    };
    let start = coarse_start(&problem);
    let mut simplex = vec![start.clone()];
    for i in 0..start.len() {
        let mut vertex = start.clone();
        vertex[i] += FIRST_STEP;
        simplex.push(vertex);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-12)
        .map_err(|e| IdentifyError::Optimiser(e.to_string()))?;
    let result = Executor::new(problem, solver)
        .configure(|state| state.max_iters(budget.iterations))
        .run()
        .map_err(|e| IdentifyError::Optimiser(e.to_string()))?;
    let best = result
        .state()
        .get_best_param()
        .cloned()
        .unwrap_or_else(|| vec![0.0; 4]);
    let unknowns = bounds.unknowns(&best);
    let error = result.state().get_best_cost();
    let replays = result
        .problem
        .counts
        .get("cost_count")
        .copied()
        .unwrap_or(0);
    Ok(Fit {
        unknowns,
        error,
        replays,
    })
}

/// The identification oracle: records the runs it is trained on, fits the
/// object's unknowns to them when training ends, and predicts with a copy
/// of the world holding the fitted values. See the module documentation.
/// A model saved after its fit keeps it; the runs it was shown are not
/// saved.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct IdentificationOracle {
    /// The object with the middle of the prior for what is unknown.
    object: Drawn,
    prior: Distributions,
    publish_rate_hz: u32,
    latency_max: u32,
    budget: Budget,
    training: bool,
    #[serde(skip)]
    runs: Vec<SeenRun>,
    /// The delays told before the previous message and before this one: the
    /// action in force on the way to a state was sent after the previous.
    #[serde(skip)]
    told: [u32; 2],
    copy: Oracle,
    fit: Option<Fit>,
}

impl IdentificationOracle {
    /// The identification oracle of `object`'s shape, its unknowns drawn
    /// from `prior`, in a world publishing at `publish_rate_hz` whose
    /// latency emulation delays a Move by at most `latency_max` steps.
    ///
    /// # Errors
    /// An object the prior's middle values make no valid scene of.
    pub fn new(
        object: &Drawn,
        prior: &Distributions,
        publish_rate_hz: u32,
        latency_max: u32,
        budget: Budget,
    ) -> Result<Self, IdentifyError> {
        let masked = Bounds::of(object, prior).middle().applied_to(object);
        let copy = Oracle::of_scene(
            masked.scene()?,
            publish_rate_hz,
            OracleLatency::Known,
            latency_max,
        );
        Ok(Self {
            object: masked,
            prior: prior.clone(),
            publish_rate_hz,
            latency_max,
            budget,
            training: true,
            runs: Vec::new(),
            told: [0; 2],
            copy,
            fit: None,
        })
    }

    /// The last fit, once training has ended after at least one run.
    #[must_use]
    pub fn fit(&self) -> Option<&Fit> {
        self.fit.as_ref()
    }

    fn identify(&mut self) {
        if self.runs.iter().all(|r| r.steps.is_empty()) {
            return;
        }
        let fitted = fit(
            &self.object,
            &self.prior,
            &self.runs,
            self.publish_rate_hz,
            self.latency_max,
            self.budget,
        )
        .and_then(|fit| {
            let scene = fit.unknowns.applied_to(&self.object).scene()?;
            Ok((fit, scene))
        });
        match fitted {
            Ok((fit, scene)) => {
                self.copy = Oracle::of_scene(
                    scene,
                    self.publish_rate_hz,
                    OracleLatency::Known,
                    self.latency_max,
                );
                self.copy.next_move_delay(self.told[1]);
                self.fit = Some(fit);
            }
            // The copy keeps the prior's middle: a reference that could
            // not fit predicts as it did before any push.
            Err(err) => tracing::warn!(%err, "identification oracle: no fit"),
        }
    }
}

impl Model for IdentificationOracle {
    type World = OracleWorld;

    fn parse(&self, frame: &Frame) -> Result<OracleWorld, ParseError> {
        self.copy.parse(frame)
    }

    fn poses(world: &OracleWorld) -> Poses {
        Oracle::poses(world)
    }

    fn reset_objects(&mut self, world: &OracleWorld) {
        if self.training {
            self.runs.push(SeenRun {
                start: world.clone(),
                steps: Vec::new(),
            });
        }
    }

    fn update(&mut self, world: &OracleWorld, action: Action) {
        if !self.training {
            return;
        }
        if let Some(run) = self.runs.last_mut() {
            run.steps.push(Seen {
                action,
                delay: self.told[0],
                world: world.clone(),
            });
        }
    }

    fn predict(&self, world: &OracleWorld, action: Action) -> OracleWorld {
        self.copy.predict(world, action)
    }

    fn set_training(&mut self, on: bool) {
        if self.training && !on {
            self.identify();
        }
        self.training = on;
        self.copy.set_training(on);
    }

    fn is_training(&self) -> bool {
        self.training
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        self.copy.set_target(target)
    }

    fn has_target(&self) -> bool {
        false
    }

    fn act(&mut self, _rng: &mut dyn Rng) -> Action {
        Action::ZERO
    }

    fn stats(&self) -> ModelStats {
        self.copy.stats()
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::ForceZero
    }

    fn next_move_delay(&mut self, steps: u32) {
        self.told = [self.told[1], steps];
        self.copy.next_move_delay(steps);
    }

    fn start_fold(&mut self, seed: u64) {
        self.copy.start_fold(seed);
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::frame_of;
    use super::*;
    use sim_plugin::generate::{generate, Set};
    use sim_plugin::push_run::record_push_run;
    use sim_plugin::world::{Command, World};

    const RATE: u32 = 100;
    const PUSH: [f64; 2] = [0.0, 0.5];
    const MESSAGES: usize = 150;

    /// Push runs of the true object from actuator starts `xs`, as the
    /// driver hands them to a model in training.
    fn shown(model: &mut IdentificationOracle, truth: &Drawn, xs: &[f64]) {
        let mut world = World::new(&truth.scene().unwrap()).unwrap();
        world.apply(Command::SetPublishRate(RATE)).unwrap();
        for &x0 in xs {
            let run = record_push_run(&mut world, x0, PUSH, MESSAGES).unwrap();
            let first = model.parse(&frame_of(&run[0])).unwrap();
            model.reset_objects(&first);
            for snapshot in &run[1..] {
                let seen = model.parse(&frame_of(snapshot)).unwrap();
                model.update(&seen, Action::new(PUSH[0], PUSH[1]));
            }
        }
    }

    /// The chained prediction error, at the run's end, of a push from `x0`.
    fn test_error(model: &IdentificationOracle, truth: &Drawn, x0: f64) -> f64 {
        let mut world = World::new(&truth.scene().unwrap()).unwrap();
        world.apply(Command::SetPublishRate(RATE)).unwrap();
        let run = record_push_run(&mut world, x0, PUSH, MESSAGES).unwrap();
        let mut predicted = model.parse(&frame_of(&run[0])).unwrap();
        for _ in 1..run.len() {
            predicted = model.predict(&predicted, Action::new(PUSH[0], PUSH[1]));
        }
        let seen = model.parse(&frame_of(&run[run.len() - 1])).unwrap();
        let (p, s) = (
            IdentificationOracle::poses(&predicted),
            IdentificationOracle::poses(&seen),
        );
        let id = *s.blocks.keys().next().unwrap();
        p.blocks[&id].distance_to(&s.blocks[&id])
    }

    fn test_object(index: usize) -> Drawn {
        generate(Set::Test, index + 1, 1, &Distributions::default())
            .unwrap()
            .swap_remove(index)
            .object
    }

    /// Two off-centre pushes identify enough of an object that a third,
    /// from another contact, is predicted far better than by the prior's
    /// middle; and the fit stays within its budget (Nelder–Mead replays the
    /// runs at most once per unknown and iteration, after the 17 of the
    /// coarse start).
    #[test]
    fn pushes_identify_the_object_for_pushes_not_seen() {
        let prior = Distributions::default();
        let budget = Budget { iterations: 40 };
        for index in 0..3 {
            let truth = test_object(index);
            let untrained = IdentificationOracle::new(&truth, &prior, RATE, 0, budget).unwrap();
            let mut identified = untrained.clone();
            let half = match truth.shape {
                ShapeSpec::Box { size } => size[0] / 2.0,
                _ => unreachable!("the test set is boxes"),
            };
            shown(&mut identified, &truth, &[-0.6 * half, 0.6 * half]);
            identified.set_training(false);
            let fit = *identified.fit().expect("trained on two runs");
            assert!(fit.replays <= 17 + 5 + 4 * budget.iterations, "{fit:?}");
            let x0 = 0.3 * half;
            let before = test_error(&untrained, &truth, x0);
            let after = test_error(&identified, &truth, x0);
            assert!(
                after < 0.5 * before,
                "object {index}, error at the end of an unseen push: {after} identified, \
                 {before} from the prior ({fit:?} for {truth:?})"
            );
        }
    }

    /// Told the true values, the replay reproduces the runs (chains put
    /// back where the bodies were seen keep their motion): the error the fit
    /// minimises is zero at the truth, and not at the prior's middle.
    #[test]
    fn the_true_values_replay_the_runs_exactly() {
        let truth = test_object(1);
        let mut model = IdentificationOracle::new(
            &truth,
            &Distributions::default(),
            RATE,
            0,
            Budget::default(),
        )
        .unwrap();
        shown(&mut model, &truth, &[0.02]);
        let problem = Problem {
            object: &model.object,
            bounds: Bounds::of(&truth, &Distributions::default()),
            runs: &model.runs,
            publish_rate_hz: RATE,
            latency_max: 0,
        };
        let exact = Unknowns {
            ground_friction: truth.ground_friction,
            pusher_friction: truth.pusher_friction,
            centre_of_mass: [truth.centre_of_mass[0], truth.centre_of_mass[1]],
        };
        let at_truth = problem.error_at(exact);
        let at_middle = problem.error_at(Bounds::of(&truth, &Distributions::default()).middle());
        assert!(at_truth < 1e-12, "{at_truth}");
        assert!(at_middle > 1e-6, "{at_middle}");
    }

    /// What the module documentation claims of the mass: the same push of
    /// the same object at the prior's lightest and heaviest ends apart by
    /// less than 0.5 % of the way it moved the object.
    #[test]
    fn the_mass_hardly_changes_a_push() {
        let truth = test_object(2);
        let prior = Distributions::default();
        let end = |mass: f64| {
            let object = Drawn {
                mass,
                ..truth.clone()
            };
            let mut world = World::new(&object.scene().unwrap()).unwrap();
            world.apply(Command::SetPublishRate(RATE)).unwrap();
            let run = record_push_run(&mut world, 0.01, PUSH, MESSAGES).unwrap();
            let frame = frame_of(&run[run.len() - 1]);
            let poses = learner::features::parse_frame_at(
                &frame,
                ActuatorYaw::ForceZero,
                learner::features::Precision::Full,
            )
            .unwrap();
            *poses.blocks.values().next().unwrap()
        };
        let (light, heavy) = (end(prior.mass.lo), end(prior.mass.hi));
        let scene = truth.scene().unwrap();
        let start = scene.bodies[scene.body_index(learner::BLUE_NAME).unwrap()].start;
        let moved = (light.x - start.x).hypot(light.y - start.y);
        assert!(moved > 0.3, "the push moved the object {moved} m");
        assert!(
            light.distance_to(&heavy) < 0.005 * moved,
            "{light:?} against {heavy:?} after {moved} m"
        );
    }
}
