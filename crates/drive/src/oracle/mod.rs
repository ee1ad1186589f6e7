//! The oracles (`docs/models.md`, "Reference rows"): predictors that are a
//! copy of the experiment's world — the same scene, so the true masses,
//! frictions and shapes — stepped under the observed actions one message at
//! a time, chaining their own states as a model chains its predictions.
//! Not learners: they learn nothing, plan nothing (Move to Target is
//! refused) and report no maps. They are the references at the other end
//! of the scale from `still`.
//!
//! What separates them is the world's latency emulation, the one thing a
//! copy of the world does not know by itself: after how many physics steps
//! of its interval each Move takes effect.
//!
//! * [`OracleLatency::Known`] is told each delay by the harness, which seeds
//!   the emulation and follows its draws
//!   ([`learner::Model::next_move_delay`]); what is left of its error is
//!   what a copy started from a shown state cannot know (the bodies' motion
//!   and contacts before it) and the scoring's precision.
//! * [`OracleLatency::Unknown`] predicts what can be known: the median
//!   outcome over the delays the harness may draw. It keeps one copy per
//!   delay `0..=L_max`, each applying every Move after that delay, and
//!   predicts the median of their states, coordinate by coordinate. In the
//!   push task, whose action is constant, only a run's first Move's delay
//!   matters, so these are exactly the outcomes the draws can give.
//!
//! Without latency emulation both are the same copy with no delay.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use learner::features::{is_skipped, parse_frame_at, ActuatorYaw, ParseError, Precision};
use learner::stats::ModelStats;
use learner::{
    Action, BodyShape, Frame, Model, ObjectState, Observation, Poses, Target, TargetError,
};
use pushlearn::wire::{pb, Shapes};
use pushlearn_core::Named;
use rand::Rng;
use serde::{Deserialize, Serialize};
use sim_plugin::world::{ActuatorMode, Command, Snapshot, World};
use sim_plugin::Scene;

use crate::scene::Object;

mod chains;
pub mod identify;
pub use identify::IdentificationOracle;

/// What an oracle knows of the world's latency emulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OracleLatency {
    /// Told each Move's delay by the harness.
    Known,
    /// The median outcome over every delay the harness may draw.
    Unknown,
}

impl Named for OracleLatency {
    const ALL: &'static [Self] = &[OracleLatency::Known, OracleLatency::Unknown];

    fn name(self) -> &'static str {
        match self {
            OracleLatency::Known => "known",
            OracleLatency::Unknown => "unknown",
        }
    }

    fn description(self) -> &'static str {
        match self {
            OracleLatency::Known => {
                "A copy of the world told, by the harness, when each Move takes effect"
            }
            OracleLatency::Unknown => {
                "The median outcome of copies of the world over every delay the harness may draw"
            }
        }
    }
}

impl OracleLatency {
    /// The name reports give this oracle.
    #[must_use]
    pub fn report_name(self) -> &'static str {
        match self {
            OracleLatency::Known => "oracle-known",
            OracleLatency::Unknown => "oracle-unknown",
        }
    }

    /// The oracle a report's model names, if it names one.
    #[must_use]
    pub fn of_report_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|o| o.report_name() == name)
    }

    /// How tables and figures label it.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            OracleLatency::Known => "oracle: true parameters, latency known",
            OracleLatency::Unknown => "oracle: true parameters, latency unknown",
        }
    }
}

/// An oracle's world: the state shown or predicted, and which step of its
/// copies it is (0: a state the copies did not produce).
#[derive(Clone, Debug)]
pub struct OracleWorld {
    frame: Frame,
    poses: Poses,
    token: u64,
    /// What the world's bodies were shown as (empty until the copies
    /// stepped it).
    shown: Vec<Shown>,
    /// A state shown to copies that are mid-chain: they take its poses and
    /// keep their own velocities instead of starting it at rest
    /// ([`OracleWorld::resynced`]).
    keep_motion: bool,
    /// Its node in the tree of chains already stepped ([`chains`]; 0: not
    /// in it).
    node: u64,
}

impl OracleWorld {
    /// This state, to be taken up by copies still moving from the chain
    /// before it: the bodies are put where it shows them and keep the
    /// velocities the copies gave them. A shown state carries no
    /// velocities; this is how a fit restarts chains mid-run
    /// ([`identify`]) without starting a moving object at rest.
    #[must_use]
    pub fn resynced(&self) -> OracleWorld {
        OracleWorld {
            token: 0,
            keep_motion: true,
            ..self.clone()
        }
    }
}

/// The world copies, one per latency hypothesis, and the token of the
/// state they hold.
#[derive(Default)]
struct Copies {
    worlds: Vec<World>,
    /// The scene's bodies' shapes.
    shapes: Shapes,
    token: u64,
    /// What the tree of chains knows the oracle by: everything its chains
    /// depend on but the states and actions.
    key: Arc<str>,
    /// The chain node the copies hold, and the one they would hold had
    /// they stepped every prediction handed out from the tree.
    held: u64,
    handed_out: u64,
}

impl std::fmt::Debug for Copies {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Copies")
            .field("worlds", &self.worlds.len())
            .field("token", &self.token)
            .finish()
    }
}

/// The world as a predictor of itself; see the module documentation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Oracle {
    scene: Scene,
    publish_rate_hz: u32,
    latency: OracleLatency,
    /// The largest delay of the world's latency emulation (0: none).
    latency_max: u32,
    training: bool,
    /// Whether its chains are kept in the tree ([`chains`]).
    #[serde(skip, default = "remembering")]
    remember_chains: bool,
    /// The delay of the next Move, as the harness said it.
    #[serde(skip)]
    next_delay: u32,
    /// Built at the first prediction of a fold; shared by clones, which
    /// take turns (a fold's predictions are sequential).
    #[serde(skip)]
    copies: Arc<Mutex<Copies>>,
}

/// Why an oracle cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum OracleError {
    #[error("the oracles need a built-in scene: {0}")]
    Scene(String),
    #[error(
        "the oracles need a lock-step world (--mode lockstep or lockstep-jitter): a realtime \
         world's delays are the machine's, which no copy of it knows"
    )]
    Realtime,
}

impl Oracle {
    /// The oracle `latency` of the built-in scene `scene` at
    /// `publish_rate_hz`, for a world whose latency emulation delays a Move
    /// by at most `latency_max` steps (0: none).
    ///
    /// # Errors
    /// An unknown scene.
    pub fn new(
        scene: &str,
        publish_rate_hz: u32,
        latency: OracleLatency,
        latency_max: u32,
    ) -> Result<Self, OracleError> {
        let scene = Scene::builtin(scene).map_err(|err| OracleError::Scene(err.to_string()))?;
        Ok(Self::of_scene(scene, publish_rate_hz, latency, latency_max))
    }

    /// The oracle `latency` of `scene` (its bodies, masses and frictions
    /// are what the copies step), as [`Oracle::new`] for a built-in one.
    #[must_use]
    pub fn of_scene(
        scene: Scene,
        publish_rate_hz: u32,
        latency: OracleLatency,
        latency_max: u32,
    ) -> Self {
        Self {
            scene,
            publish_rate_hz,
            latency,
            latency_max,
            training: true,
            remember_chains: true,
            next_delay: 0,
            copies: Arc::default(),
        }
    }

    /// This oracle, stepping every chain it is asked for even if it was
    /// stepped before: for copies whose chains never repeat (an
    /// identification's candidates), which would only fill the tree.
    #[must_use]
    pub fn forgetting_chains(self) -> Self {
        Self {
            remember_chains: false,
            ..self
        }
    }

    /// Whether its chains are worth keeping: in testing (training predicts
    /// from each real state, once), and only when a chain is the same
    /// whatever the harness tells the copies — the oracle that ignores the
    /// delays, or a world without latency emulation.
    fn chains_repeat(&self) -> bool {
        self.remember_chains
            && !self.training
            && (self.latency == OracleLatency::Unknown || self.latency_max == 0)
    }

    fn lock(&self) -> MutexGuard<'_, Copies> {
        self.copies.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The delay each copy applies the next Move after, the harness having
    /// told `told`.
    fn delays_for(&self, told: u32) -> Vec<u32> {
        match self.latency {
            OracleLatency::Known => vec![told],
            OracleLatency::Unknown => (0..=self.latency_max).collect(),
        }
    }

    /// One message of the copies from `from` under `action`: their next
    /// states if they hold `from`, else from `from`'s poses at rest (what is
    /// shown carries no velocities). `None` if the copies refused the state
    /// (a body the scene does not have) or could not step. A chain stepped
    /// before is taken from the tree of chains instead ([`chains`]).
    fn step(&self, from: &OracleWorld, action: Action) -> Option<OracleWorld> {
        let mut copies = self.lock();
        let copies = &mut *copies;
        self.build(copies)?;
        if from.keep_motion || !self.chains_repeat() {
            let show = from.token == 0 || from.token != copies.token;
            return self.advance(copies, from, show, action);
        }
        // The delay told matters only to the copy that is told it.
        let told = match self.latency {
            OracleLatency::Known => self.next_delay,
            OracleLatency::Unknown => 0,
        };
        let step = chains::StepKey::of(action, told);
        // In turn: the copies hold `from`, or would had they stepped every
        // prediction handed out since.
        let in_turn = from.node != 0 && from.node == copies.handed_out;
        let parent = if in_turn {
            from.node
        } else {
            chains::root(&copies.key, &from.frame)
        };
        if let Some((id, world)) = chains::stepped(parent, step) {
            copies.handed_out = id;
            return Some(world);
        }
        let mut next = if !in_turn {
            self.advance(copies, from, true, action)?
        } else if copies.held == from.node {
            self.advance(copies, from, false, action)?
        } else {
            // Behind the chain handed out: step through it from its shown
            // state, as the copies would have.
            let (frame, steps) = chains::history(from.node)?;
            let mut world = self.parse_shown(frame).ok()?;
            let mut show = true;
            for past in steps {
                world = self.advance_by(copies, &world, show, past.action(), past.delay())?;
                show = false;
            }
            self.advance(copies, &world, show, action)?
        };
        let id = chains::keep(parent, step, &next);
        next.node = id;
        copies.held = id;
        copies.handed_out = id;
        Some(next)
    }

    /// The copies, one per latency hypothesis, built at a fold's first
    /// prediction.
    fn build(&self, copies: &mut Copies) -> Option<()> {
        let count = self.delays_for(0).len();
        if copies.worlds.len() == count {
            return Some(());
        }
        let scene = &self.scene;
        copies.shapes = Shapes::from_hello(&pb::Hello {
            shapes: sim_plugin::server::shapes(scene),
            ..pb::Hello::default()
        });
        copies.worlds = (0..count)
            .map(|_| World::new(scene).ok())
            .collect::<Option<_>>()?;
        copies.token = 0;
        copies.key = format!(
            "{}|{}|{}|{}",
            serde_json::to_string(scene).ok()?,
            self.publish_rate_hz,
            self.latency.name(),
            self.latency_max
        )
        .into();
        copies.held = 0;
        copies.handed_out = 0;
        Some(())
    }

    /// `frame` as a state shown to the oracle.
    fn parse_shown(&self, frame: Frame) -> Result<OracleWorld, ParseError> {
        Ok(OracleWorld {
            poses: parse_frame_at(&frame, ActuatorYaw::ForceZero, Precision::Full)?,
            frame,
            token: 0,
            shown: Vec::new(),
            keep_motion: false,
            node: 0,
        })
    }

    fn advance(
        &self,
        copies: &mut Copies,
        from: &OracleWorld,
        show: bool,
        action: Action,
    ) -> Option<OracleWorld> {
        self.advance_by(copies, from, show, action, self.next_delay)
    }

    /// Steps the copies one message under `action`, the told delay being
    /// `told`: from `from` shown to them first if `show`, else from the
    /// state they hold (which is `from`).
    fn advance_by(
        &self,
        copies: &mut Copies,
        from: &OracleWorld,
        show: bool,
        action: Action,
        told: u32,
    ) -> Option<OracleWorld> {
        let delays = self.delays_for(told);
        let shown = if show {
            let shown = shown_bodies(&from.frame, &copies.shapes)?;
            // Copies that never stepped have no motion to keep.
            let keep_motion = from.keep_motion && copies.token != 0;
            for world in &mut copies.worlds {
                if !keep_motion {
                    self.stop(world)?;
                }
                place(world, &from.frame, &shown)?;
            }
            shown
        } else {
            from.shown.clone()
        };
        let mut frames = Vec::with_capacity(delays.len());
        for (world, &delay) in copies.worlds.iter_mut().zip(&delays) {
            let snapshot = interval(world, action, delay)?;
            frames.push(view_of(&snapshot, &shown)?);
        }
        let poses: Vec<Poses> = frames
            .iter()
            .map(|frame| parse_frame_at(frame, ActuatorYaw::ForceZero, Precision::Full).ok())
            .collect::<Option<_>>()?;
        let poses = median(&poses)?;
        copies.token = copies.token.wrapping_add(1).max(1);
        // The frame a chain would restart from if it were ever handed back
        // out of turn: the middle hypothesis's.
        let frame = frames.swap_remove(frames.len() / 2);
        Some(OracleWorld {
            frame,
            poses,
            token: copies.token,
            shown,
            keep_motion: false,
            node: 0,
        })
    }

    /// Brings `world` to rest, the actuator stopped: as the driver's
    /// `reset_world` leaves the world before a run (Move(0, 0), then
    /// Reset), so that a Move that comes late is late from a standstill,
    /// not from the previous run's push.
    fn stop(&self, world: &mut World) -> Option<()> {
        world
            .apply(Command::Actuator {
                mode: ActuatorMode::Move,
                velocity: [0.0; 3],
            })
            .ok()?;
        world.apply(Command::Reset).ok()?;
        world.apply(Command::Unpause).ok()?;
        world
            .apply(Command::SetPublishRate(self.publish_rate_hz))
            .ok()
    }
}

fn remembering() -> bool {
    true
}

/// Puts `world`'s bodies where `frame` shows them (their velocities as they
/// are).
fn place(world: &mut World, frame: &Frame, shown: &[Shown]) -> Option<()> {
    for (body, seen) in shown
        .iter()
        .zip(frame.objects.iter().filter(|o| !is_skipped(&o.name)))
    {
        if body.body != body.name {
            // The new-object view: the object shown under another
            // body's name took that body's start, and that body its
            // parking place (`experiment::push_task::objects`).
            let object = Object::ALL.into_iter().find(|o| o.body() == body.body)?;
            let park = object.park()?;
            let z = world.scene().bodies[world.scene().body_index(&body.name)?]
                .start
                .position()[2];
            world
                .apply(Command::SetPose {
                    name: body.name.as_str().into(),
                    position: [park.x, park.y, z],
                    orientation: pushlearn_core::orientation::from_yaw(park.theta),
                })
                .ok()?;
        }
        world
            .apply(Command::SetPose {
                name: body.body.as_str().into(),
                position: seen.position,
                orientation: seen.orientation,
            })
            .ok()?;
    }
    Some(())
}

/// Steps `world` to its next publish with `action` in force from step
/// `delay` of the interval on (or from its last step, whichever comes
/// first), as the lock-step world applies a delayed Move.
fn interval(world: &mut World, action: Action, delay: u32) -> Option<Snapshot> {
    let command = Command::Actuator {
        mode: ActuatorMode::Move,
        velocity: [action.vx, action.vy, 0.0],
    };
    let mut pending = Some(command);
    let mut offset = 0;
    loop {
        let publishes_next =
            (world.step_count() + 1).is_multiple_of(u64::from(world.publish_interval_steps()));
        if offset >= delay || publishes_next {
            if let Some(command) = pending.take() {
                world.apply(command).ok()?;
            }
        }
        if let Some(snapshot) = world.step().ok()? {
            return Some(snapshot);
        }
        offset += 1;
    }
}

/// The coordinate-wise median of `poses` (all of the same bodies): the
/// middle value, or the mean of the two middle ones for an even count.
fn median(poses: &[Poses]) -> Option<Poses> {
    let first = poses.first()?;
    if poses.len() == 1 {
        return Some(first.clone());
    }
    let of = |get: &dyn Fn(&Poses) -> Option<ObjectState>| -> Option<ObjectState> {
        let states: Vec<ObjectState> = poses.iter().map(get).collect::<Option<_>>()?;
        let middle = |value: fn(&ObjectState) -> f64| {
            let mut values: Vec<f64> = states.iter().map(value).collect();
            values.sort_by(f64::total_cmp);
            let n = values.len();
            if n % 2 == 1 {
                values[n / 2]
            } else {
                (values[n / 2 - 1] + values[n / 2]) / 2.0
            }
        };
        Some(ObjectState::new(
            middle(|s| s.x),
            middle(|s| s.y),
            middle(|s| s.theta),
        ))
    };
    let actuator = of(&|p: &Poses| Some(p.actuator))?;
    let blocks = first
        .blocks
        .keys()
        .map(|&id| Some((id, of(&|p: &Poses| p.blocks.get(&id).copied())?)))
        .collect::<Option<_>>()?;
    Some(Poses { actuator, blocks })
}

/// A body as the oracle was shown it, and the world's body it is.
#[derive(Clone, Debug, PartialEq)]
struct Shown {
    name: String,
    id: u32,
    shape: Option<BodyShape>,
    body: String,
}

/// Which of the world's bodies each body shown is: the one of its name,
/// unless its observed shape is another body's (the new-object view shows
/// an object under the blue block's name). `None` if a shape matches no
/// body.
fn shown_bodies(frame: &Frame, shapes: &Shapes) -> Option<Vec<Shown>> {
    frame
        .objects
        .iter()
        .filter(|o| !is_skipped(&o.name))
        .map(|o| {
            let body = match o.shape {
                Some(shape) if shapes.of(&o.name) != Some(shape) => shapes.body_with(shape)?,
                _ => o.name.as_str(),
            };
            Some(Shown {
                name: o.name.clone(),
                id: o.id,
                shape: o.shape,
                body: body.to_owned(),
            })
        })
        .collect()
}

/// A copy's state as the oracle was shown the world: the bodies shown,
/// under the names they were shown with.
fn view_of(snapshot: &Snapshot, shown: &[Shown]) -> Option<Frame> {
    let objects = shown
        .iter()
        .map(|s| {
            let body = snapshot.bodies.iter().find(|b| b.name == s.body)?;
            Some(Observation {
                name: s.name.clone(),
                id: s.id,
                shape: s.shape,
                ..body.observation()
            })
        })
        .collect::<Option<Vec<_>>>()?;
    Some(Frame { objects })
}

impl Model for Oracle {
    type World = OracleWorld;

    fn parse(&self, frame: &Frame) -> Result<OracleWorld, ParseError> {
        self.parse_shown(frame.clone())
    }

    fn poses(world: &OracleWorld) -> Poses {
        world.poses.clone()
    }

    fn reset_objects(&mut self, _world: &OracleWorld) {}

    fn update(&mut self, _world: &OracleWorld, _action: Action) {}

    /// A state the copies refuse (a body the scene lacks) is predicted to
    /// stay as it is.
    fn predict(&self, world: &OracleWorld, action: Action) -> OracleWorld {
        self.step(world, action).unwrap_or_else(|| OracleWorld {
            token: 0,
            node: 0,
            ..world.clone()
        })
    }

    fn set_training(&mut self, on: bool) {
        self.training = on;
    }

    fn is_training(&self) -> bool {
        self.training
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        match target {
            None => Ok(()),
            Some(t) => Err(TargetError::UnknownObject { id: t.id }),
        }
    }

    fn has_target(&self) -> bool {
        false
    }

    fn act(&mut self, _rng: &mut dyn Rng) -> Action {
        Action::ZERO
    }

    fn stats(&self) -> ModelStats {
        ModelStats::Other(learner::stats::OtherStats::default())
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::ForceZero
    }

    fn next_move_delay(&mut self, steps: u32) {
        self.next_delay = steps;
    }

    /// Every fold gets copies of its own, so that folds run side by side
    /// never step each other's.
    fn start_fold(&mut self, _seed: u64) {
        self.copies = Arc::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_plugin::push_run::record_push_run;

    /// What the world publishes, as a model is handed it.
    pub(super) fn frame_of(snapshot: &Snapshot) -> Frame {
        Frame {
            objects: snapshot
                .bodies
                .iter()
                .map(sim_plugin::BodyState::observation)
                .collect(),
        }
    }

    #[test]
    fn an_oracle_chains_a_copy_of_the_world() {
        let scene = Scene::builtin("one_block").unwrap();
        let mut world = World::new(&scene).unwrap();
        world.apply(Command::SetPublishRate(100)).unwrap();
        let push = Action::new(0.0, 0.5);
        let run = record_push_run(&mut world, 0.1, [push.vx, push.vy], 120).unwrap();
        for latency in OracleLatency::ALL {
            let mut oracle = Oracle::new("one_block", 100, *latency, 0).unwrap();
            oracle.start_fold(1);
            // Sent after the first message, the push moves the world into
            // the second.
            let mut predicted = oracle.parse(&frame_of(&run[0])).unwrap();
            for _ in 1..run.len() {
                predicted = oracle.predict(&predicted, push);
            }
            let blue = |w: &OracleWorld| Oracle::poses(w).blocks[&learner::BLUE_ID];
            let seen = blue(&oracle.parse(&frame_of(&run[run.len() - 1])).unwrap());
            let start = blue(&oracle.parse(&frame_of(&run[0])).unwrap());
            assert!(seen.distance_to(&start) > 0.1, "the block was pushed");
            assert!(
                blue(&predicted).distance_to(&seen) < 1e-3,
                "{latency:?}: {:?} against {seen:?}",
                blue(&predicted)
            );

            // A state it did not produce (token 0) is taken as shown, at
            // rest: from the last message the block, released, hardly moves.
            let shown = oracle.parse(&frame_of(&run[run.len() - 1])).unwrap();
            let next = oracle.predict(&shown, Action::ZERO);
            assert!(blue(&next).distance_to(&blue(&shown)) < 1e-3);
            assert_ne!(next.token, 0);
        }
    }

    /// The oracle that knows the latency steps the delay it is told; the
    /// one that does not predicts the middle of the delays it may be: the
    /// actuator, moving at 0.5 m/s, is 0.5 mm further for each step less.
    #[test]
    fn the_latency_known_is_applied_and_the_unknown_one_is_the_median() {
        let frame = frame_of(
            &World::new(&Scene::builtin("one_block").unwrap())
                .unwrap()
                .snapshot(),
        );
        let push = Action::new(0.0, 0.5);
        let first = |oracle: &mut Oracle| {
            let shown = oracle.parse(&frame).unwrap();
            Oracle::poses(&oracle.predict(&shown, push)).actuator.y
        };
        let mut known = Oracle::new("one_block", 100, OracleLatency::Known, 4).unwrap();
        let by_delay: Vec<f64> = (0..=4)
            .map(|d| {
                known.next_move_delay(d);
                // A run before, which left the copy pushing: the next run
                // starts from a standstill all the same.
                let shown = known.parse(&frame).unwrap();
                let _ = known.predict(&known.predict(&shown, push), push);
                first(&mut known)
            })
            .collect();
        for pair in by_delay.windows(2) {
            assert!(
                (pair[0] - pair[1] - 0.0005).abs() < 1e-9,
                "one step later, 0.5 mm shorter: {by_delay:?}"
            );
        }
        let mut unknown = Oracle::new("one_block", 100, OracleLatency::Unknown, 4).unwrap();
        assert!((first(&mut unknown) - by_delay[2]).abs() < 1e-12);
        let mut even = Oracle::new("one_block", 100, OracleLatency::Unknown, 3).unwrap();
        let middle = (by_delay[1] + by_delay[2]) / 2.0;
        assert!((first(&mut even) - middle).abs() < 1e-12);
    }

    #[test]
    fn an_object_shown_under_the_blue_blocks_name_is_found_by_its_shape() {
        let scene = Scene::builtin(crate::scene::SCENE).unwrap();
        let shapes = Shapes::from_hello(&pb::Hello {
            shapes: sim_plugin::server::shapes(&scene),
            ..pb::Hello::default()
        });
        let cylinder = shapes.of(Object::Cylinder.body()).unwrap();
        let shown = |shape| Observation {
            name: learner::BLUE_NAME.into(),
            id: learner::BLUE_ID,
            position: [0.0, 0.3, 0.05],
            orientation: [0.0, 0.0, 0.0, 1.0],
            shape,
        };
        let frame = |shape| Frame {
            objects: vec![shown(shape)],
        };
        let body = |shape| shown_bodies(&frame(shape), &shapes).map(|s| s[0].body.clone());
        assert_eq!(
            body(Some(cylinder)).as_deref(),
            Some(Object::Cylinder.body())
        );
        assert_eq!(body(None).as_deref(), Some(learner::BLUE_NAME));
        let blue = shapes.of(learner::BLUE_NAME);
        assert_eq!(body(blue).as_deref(), Some(learner::BLUE_NAME));
        assert_eq!(body(Some(BodyShape::Sphere { radius: 7.0 })), None);
    }

    /// Chains taken from the tree, or stepped through it to catch up, are
    /// the chains the copies step, bit for bit: folds that repeat a chain,
    /// one that leaves it half way, one handed a state out of turn.
    #[test]
    fn chains_from_the_tree_are_the_copies_chains() {
        let scene = Scene::builtin("one_block").unwrap();
        let mut world = World::new(&scene).unwrap();
        world.apply(Command::SetPublishRate(100)).unwrap();
        let run = record_push_run(&mut world, 0.05, [0.0, 0.5], 2).unwrap();
        let push = Action::new(0.0, 0.5);
        let turn = Action::new(0.2, 0.4);
        // Distinct from every other test's chains: the tree is the process's.
        let start = frame_of(&run[1]);
        let chain = |oracle: &Oracle, actions: &[Action], out_of_turn: Option<usize>| {
            let mut at = oracle.parse(&start).unwrap();
            let mut seen = Vec::new();
            for (i, &a) in actions.iter().enumerate() {
                let next = oracle.predict(&at, a);
                seen.push((Oracle::poses(&next), next.frame.clone()));
                at = if out_of_turn == Some(i) {
                    // Handed back a state from before: shown at rest.
                    oracle.parse(&next.frame).unwrap()
                } else {
                    next
                };
            }
            seen
        };
        let straight = [push; 30];
        let mut bent = [push; 30];
        bent[15..].fill(turn);
        for latency in OracleLatency::ALL {
            for latency_max in [0, 3] {
                let fresh = || {
                    let mut o = Oracle::new("one_block", 100, *latency, latency_max).unwrap();
                    o.start_fold(1);
                    // Testing: an oracle keeps no chain in training.
                    o.set_training(false);
                    o
                };
                let truth = |actions: &[Action], out: Option<usize>| {
                    chain(&fresh().forgetting_chains(), actions, out)
                };
                for (actions, out) in [
                    (&straight, None),
                    (&straight, None),
                    (&bent, None),
                    (&bent, Some(20)),
                    (&straight, Some(5)),
                ] {
                    // Twice: the second time every step is in the tree.
                    for _ in 0..2 {
                        let remembered = fresh();
                        let (l, r) = (chain(&remembered, actions, out), truth(actions, out));
                        assert_eq!(
                            l, r,
                            "{latency:?}, latency up to {latency_max}, out of turn at {out:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn it_refuses_unknown_scenes_and_targets() {
        assert!(Oracle::new("no_such_scene", 100, OracleLatency::Known, 0).is_err());
        let mut oracle = Oracle::new("one_block", 100, OracleLatency::Unknown, 2).unwrap();
        assert!(oracle
            .set_target(Some(Target::new(
                learner::BLUE_ID,
                ObjectState::new(0.0, 0.0, 0.0)
            )))
            .is_err());
        assert!(oracle.set_target(None).is_ok());
        assert_eq!(
            OracleLatency::of_report_name("oracle-unknown"),
            Some(OracleLatency::Unknown)
        );
        assert_eq!(OracleLatency::of_report_name("oracle"), None);
    }
}
