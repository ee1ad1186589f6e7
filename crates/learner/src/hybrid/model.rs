//! [`HybridModel`]: the [`Model`] built on pushing mechanics.

use std::collections::BTreeMap;

use nalgebra::{Rotation2, Vector2};
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::mechanics::{Outline, Parameters, Push, Slide, Stepped, Twist, SUBSTEPS};
use super::planner::PushPlan;
use super::residual::{self, Memory};
use crate::aitm::MapStats;
use crate::features::{is_skipped, parse_frame_at, ActuatorYaw, ParseError, Precision};
use crate::features::{Shape, ACTUATOR_SHAPE};
use crate::model::Model;
use crate::stats::{ModelStats, OtherStats};
use crate::types::{Action, Frame, ObjectState, Poses, Target, TargetError};

/// Which of the model's parts are on: the ablation of `docs/models.md`
/// "The hybrid model".
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Parts {
    /// The mechanics with the parameters a shape alone suggests: uniform
    /// pressure, a slider that stops when the push ends, the actuator
    /// moving exactly as commanded. Learns nothing.
    Mechanics,
    /// The mechanics with their parameters identified from the messages.
    Identified,
    /// The identified mechanics and the residual memory.
    #[default]
    Full,
}

impl Parts {
    pub const ALL: [Parts; 3] = [Parts::Mechanics, Parts::Identified, Parts::Full];

    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Parts::Mechanics => "mechanics",
            Parts::Identified => "identified",
            Parts::Full => "full",
        }
    }

    fn identifies(self) -> bool {
        self != Parts::Mechanics
    }

    fn remembers(self) -> bool {
        self == Parts::Full
    }
}

/// How the hybrid model is set up.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HybridConfig {
    pub parts: Parts,
    /// Messages per second: a slider faster than [`MAX_SPEED`] between
    /// two messages was moved by a reset, not by a push.
    pub publish_rate_hz: u32,
}

/// Metres per second no pushed block reaches (the actuator moves at
/// 0.5 m/s at most): a faster change between messages is a reset.
pub const MAX_SPEED: f64 = 2.0;

/// A pusher whose surface is within this of a slider is in contact for
/// the identification and near enough for the residual memory to matter.
const CONTACT_TOLERANCE: f64 = 0.002;
const NEAR: f64 = 0.03;

/// Below this motion per message a block is at rest.
const AT_REST: f64 = 1e-5;

/// The hybrid model's world: the poses, each block's motion over the
/// message before, which a free slide continues, and each block's outline
/// where the observation carried one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HybridWorld {
    pub poses: Poses,
    pub motion: BTreeMap<u32, Twist>,
    #[serde(default)]
    pub outlines: BTreeMap<u32, Outline>,
}

impl HybridWorld {
    /// The outline of block `id`: as observed, or else the shape table's
    /// for its id (a driver that passes no shapes on).
    #[must_use]
    pub fn outline(&self, id: u32) -> Outline {
        self.outlines
            .get(&id)
            .copied()
            .unwrap_or_else(|| HybridModel::outline(id))
    }
}

/// Least squares of the actuator's motion over a message on the action
/// in force and the one before it (whose last moments the world still
/// applies, `docs/spec/world.md` §8), shrunk towards moving exactly as
/// commanded.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct ActuatorFit {
    /// Σ x xᵀ and Σ x y over (action, previous action) → displacement,
    /// both axes pooled.
    xx: [[f64; 2]; 2],
    xy: [f64; 2],
    prior: [f64; 2],
}

/// Pseudo-observations of the prior: about one message at full speed.
const ACTUATOR_PRIOR_WEIGHT: f64 = 0.25;

impl ActuatorFit {
    fn new(publish_rate_hz: u32) -> Self {
        Self {
            xx: [[0.0; 2]; 2],
            xy: [0.0; 2],
            prior: [1.0 / f64::from(publish_rate_hz.max(1)), 0.0],
        }
    }

    fn learn(&mut self, action: Action, previous: Action, moved: Vector2<f64>) {
        for (x, y) in [
            ([action.vx, previous.vx], moved.x),
            ([action.vy, previous.vy], moved.y),
        ] {
            for i in 0..2 {
                for j in 0..2 {
                    self.xx[i][j] += x[i] * x[j];
                }
                self.xy[i] += x[i] * y;
            }
        }
    }

    fn weights(&self, identified: bool) -> [f64; 2] {
        if !identified {
            return self.prior;
        }
        let r = ACTUATOR_PRIOR_WEIGHT;
        let a = [
            [self.xx[0][0] + r, self.xx[0][1]],
            [self.xx[1][0], self.xx[1][1] + r],
        ];
        let b = [
            self.xy[0] + r * self.prior[0],
            self.xy[1] + r * self.prior[1],
        ];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        [
            (b[0] * a[1][1] - a[0][1] * b[1]) / det,
            (a[0][0] * b[1] - a[1][0] * b[0]) / det,
        ]
    }

    fn path(&self, action: Action, previous: Action, identified: bool) -> Vector2<f64> {
        let w = self.weights(identified);
        w[0] * action.to_vector() + w[1] * previous.to_vector()
    }
}

/// The tipping values the identification chooses among, metres (see
/// [`Parameters::tipping`]): from a level weight to far more than a push
/// at the world's actuator height (μ·h = 0.9 · 0.03 m) could tip.
pub const TIPPING_GRID: [f64; 11] = [
    0.0, 0.005, 0.01, 0.015, 0.02, 0.025, 0.03, 0.035, 0.04, 0.045, 0.05,
];

/// What the model knows of one block.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct BlockKnowledge {
    /// Per value of [`TIPPING_GRID`], the summed squared one-message error
    /// of the mechanics over the pushes seen (position, and turn times the
    /// outline's size).
    tipping_errors: [f64; TIPPING_GRID.len()],
    pushes: u64,
    weighing: std::collections::VecDeque<Weighing>,
    /// Decelerations seen while sliding freely: sums and counts.
    slide_linear: (f64, u32),
    slide_angular: (f64, u32),
    memory: Memory,
    /// What each residual was computed from, in the memory's order.
    remembered: Vec<Remembered>,
    /// The tipping the stored residuals are the residual of.
    residual_tipping: f64,
    updates: u64,
}

/// A remembered message: the mechanics' inputs and the block's motion seen
/// (its own frame at the start).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Remembered {
    outline: Outline,
    before: ObjectState,
    motion_before: Twist,
    from: Vector2<f64>,
    path: Vector2<f64>,
    seen: [f64; 3],
}

/// Without a free slide seen, a block stops the moment the push ends:
/// the quasi-static assumption.
const STOPS_AT_ONCE: f64 = 1.0;

impl BlockKnowledge {
    fn new() -> Self {
        Self {
            tipping_errors: [0.0; TIPPING_GRID.len()],
            pushes: 0,
            weighing: std::collections::VecDeque::new(),
            slide_linear: (0.0, 0),
            slide_angular: (0.0, 0),
            memory: Memory::default(),
            remembered: Vec::new(),
            residual_tipping: 0.0,
            updates: 0,
        }
    }

    /// The identified tipping: the grid value with the least error, the
    /// smallest on a tie (the data cannot tell them apart, and the least
    /// tipping is the plainest assumption); level weight before any push
    /// was weighed.
    fn tipping(&self) -> f64 {
        if self.pushes == 0 {
            return 0.0;
        }
        let mut best = (self.tipping_errors[0], TIPPING_GRID[0]);
        for (&e, &t) in self.tipping_errors.iter().zip(&TIPPING_GRID).skip(1) {
            // Rounding noise is no evidence: equal within it is a tie.
            if e < best.0 - (1e-9 * best.0 + 1e-24) {
                best = (e, t);
            }
        }
        best.1
    }

    fn parameters(&self, identified: bool) -> Parameters {
        if !identified {
            return Parameters {
                tipping: 0.0,
                slide: Slide {
                    linear: STOPS_AT_ONCE,
                    angular: STOPS_AT_ONCE,
                },
            };
        }
        let mean = |(sum, n): (f64, u32)| {
            if n == 0 {
                STOPS_AT_ONCE
            } else {
                sum / f64::from(n)
            }
        };
        Parameters {
            tipping: self.tipping(),
            slide: Slide {
                linear: mean(self.slide_linear),
                angular: mean(self.slide_angular),
            },
        }
    }

    /// Makes every stored residual the residual of the mechanics with
    /// `parameters`: a residual of mechanics the model no longer uses
    /// would correct an error it no longer makes. Only a new tipping
    /// calls for this (rarely, once the first pushes are weighed); the
    /// slide changes only the residuals of free slides, which are left.
    fn recompute_residuals(&mut self, parameters: &Parameters) {
        for (value, r) in self.memory.values_mut().iter_mut().zip(&self.remembered) {
            let push = Push {
                outline: &r.outline,
                parameters,
                pusher_radius: pusher_radius(),
            };
            let predicted = push
                .step(r.before, r.motion_before, r.from, r.path)
                .motion
                .in_frame(r.before.theta);
            *value = [
                r.seen[0] - predicted[0],
                r.seen[1] - predicted[1],
                r.seen[2] - predicted[2],
            ];
        }
        self.residual_tipping = parameters.tipping;
    }

    /// Keeps a message with the pusher at the block for weighing the
    /// tipping values, if the queue has room.
    fn keep_for_weighing(&mut self, sample: Weighing) {
        if self.weighing.len() < WEIGHING_QUEUE {
            self.weighing.push_back(sample);
        }
    }

    /// Weighs up to [`WEIGHINGS_PER_MESSAGE`] tipping values on the queued
    /// messages: how well the mechanics with each predict the message. A
    /// message counts once every value has been weighed on it, so that
    /// all values are compared on the same messages.
    fn weigh_tipping(&mut self, slide: Slide) {
        for _ in 0..WEIGHINGS_PER_MESSAGE {
            let Some(w) = self.weighing.front_mut() else {
                return;
            };
            let parameters = Parameters {
                tipping: TIPPING_GRID[w.next],
                slide,
            };
            let push = Push {
                outline: &w.outline,
                parameters: &parameters,
                pusher_radius: pusher_radius(),
            };
            // As finely as the model predicts: a coarser step biases the
            // choice. Each value starts its search where the last ended.
            let predicted = push
                .step_in(
                    w.before,
                    w.motion_before,
                    w.from,
                    w.path,
                    SUBSTEPS,
                    &mut w.hint,
                )
                .slider;
            let turn = w.outline.size() * (predicted.theta - w.after.theta);
            w.errors[w.next] =
                (predicted.x - w.after.x).powi(2) + (predicted.y - w.after.y).powi(2) + turn * turn;
            w.next += 1;
            if w.next == TIPPING_GRID.len() {
                for (sum, e) in self.tipping_errors.iter_mut().zip(w.errors) {
                    *sum += e;
                }
                self.pushes += 1;
                self.weighing.pop_front();
            }
        }
    }
}

/// Weighings of a tipping value per message: with the grid's eleven
/// values, one message in four is weighed, at a cost of three predictions
/// a message rather than eleven every fourth.
const WEIGHINGS_PER_MESSAGE: usize = 3;

/// Messages waiting to be weighed; later ones are not kept meanwhile.
const WEIGHING_QUEUE: usize = 1;

/// A message with the pusher at the block, being weighed.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Weighing {
    outline: Outline,
    before: ObjectState,
    motion_before: Twist,
    after: ObjectState,
    from: Vector2<f64>,
    path: Vector2<f64>,
    /// The next value of [`TIPPING_GRID`] to weigh, and the errors so far.
    next: usize,
    errors: [f64; TIPPING_GRID.len()],
    hint: Option<(usize, usize)>,
}

/// The hybrid model (`docs/models.md` "The hybrid model").
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HybridModel {
    config: HybridConfig,
    training: bool,
    /// The stored state: the latest world `update` or `reset_objects` saw.
    current: Option<HybridWorld>,
    /// The action in force while the world moved into `current`.
    last_action: Action,
    actuator: ActuatorFit,
    blocks: BTreeMap<u32, BlockKnowledge>,
    pub(super) target: Option<Target>,
    /// The push the planner is carrying out.
    #[serde(skip)]
    pub(super) push_plan: Option<PushPlan>,
}

/// The pusher's radius, from the shape table.
pub(super) fn pusher_radius() -> f64 {
    ACTUATOR_SHAPE.radius
}

/// How far the pusher's surface is from the outline of a block at `block`
/// (negative when they overlap).
pub(super) fn surface_gap(outline: &Outline, block: &ObjectState, pusher: Vector2<f64>) -> f64 {
    let local = Rotation2::new(-block.theta) * (pusher - block.position());
    outline.closest(local).distance - pusher_radius()
}

impl HybridModel {
    #[must_use]
    pub fn new(config: HybridConfig) -> Self {
        Self {
            config,
            training: true,
            current: None,
            last_action: Action::ZERO,
            actuator: ActuatorFit::new(config.publish_rate_hz),
            blocks: BTreeMap::new(),
            target: None,
            push_plan: None,
        }
    }

    #[must_use]
    pub fn config(&self) -> &HybridConfig {
        &self.config
    }

    pub(super) fn current(&self) -> Option<&HybridWorld> {
        self.current.as_ref()
    }

    pub(super) fn outline(id: u32) -> Outline {
        Shape::of(id).map_or(Outline::Disc { radius: 0.0 }, Outline::of_shape)
    }

    /// The actuator's path over the next message under `action`.
    pub(super) fn actuator_path(&self, action: Action) -> Vector2<f64> {
        self.actuator
            .path(action, self.last_action, self.config.parts.identifies())
    }

    /// Where the block `id` of `outline` at `pose`, having moved by
    /// `motion`, is after the pusher moved from `from` along `path`: the
    /// mechanics, and the residual memory if the pusher is near or the
    /// block moving.
    pub(super) fn block_after(
        &self,
        id: u32,
        outline: &Outline,
        pose: ObjectState,
        motion: Twist,
        from: Vector2<f64>,
        path: Vector2<f64>,
    ) -> (ObjectState, Twist) {
        let fallback;
        let knowledge = match self.blocks.get(&id) {
            Some(k) => k,
            None => {
                fallback = BlockKnowledge::new();
                &fallback
            }
        };
        let parameters = knowledge.parameters(self.config.parts.identifies());
        let push = Push {
            outline,
            parameters: &parameters,
            pusher_radius: pusher_radius(),
        };
        let stepped = push.step(pose, motion, from, path);
        if !self.config.parts.remembers() || knowledge.memory.is_empty() {
            return (stepped.slider, stepped.motion);
        }
        let Some(key) = residual_key(outline, &pose, &motion, from, path, &stepped) else {
            return (stepped.slider, stepped.motion);
        };
        let r = knowledge.memory.query(&key);
        let correction = Twist::from_frame(r, pose.theta);
        let slider = correction.applied_to(&stepped.slider);
        (slider, Twist::between(&pose, &slider))
    }

    fn learn(&mut self, from: &HybridWorld, to: &HybridWorld, action: Action) {
        let previous = self.last_action;
        let pusher_from = from.poses.actuator.position();
        let pusher_to = to.poses.actuator.position();
        let moved = pusher_to - pusher_from;
        self.actuator.learn(action, previous, moved);
        let identifies = self.config.parts.identifies();
        let remembers = self.config.parts.remembers();
        for (&id, before) in &from.poses.blocks {
            let Some(after) = to.poses.blocks.get(&id) else {
                continue;
            };
            let motion_before = from.motion.get(&id).copied().unwrap_or_default();
            let knowledge = self.blocks.entry(id).or_insert_with(BlockKnowledge::new);
            knowledge.updates += 1;
            let outline = from.outline(id);
            let motion = Twist::between(before, after);
            if surface_gap(&outline, before, pusher_from) > NEAR
                && surface_gap(&outline, after, pusher_to) > NEAR
            {
                let (v0, v1) = (motion_before.speed(), motion.speed());
                if v0 > AT_REST && v1 > AT_REST {
                    knowledge.slide_linear.0 += (v0 - v1).max(0.0);
                    knowledge.slide_linear.1 += 1;
                }
                let (w0, w1) = (motion_before.dtheta.abs(), motion.dtheta.abs());
                if w0 > AT_REST && w1 > AT_REST {
                    knowledge.slide_angular.0 += (w0 - w1).max(0.0);
                    knowledge.slide_angular.1 += 1;
                }
            }
            if identifies {
                if surface_gap(&outline, before, pusher_from) < CONTACT_TOLERANCE
                    || surface_gap(&outline, after, pusher_to) < CONTACT_TOLERANCE
                {
                    knowledge.keep_for_weighing(Weighing {
                        outline,
                        before: *before,
                        motion_before,
                        after: *after,
                        from: pusher_from,
                        path: moved,
                        next: 0,
                        errors: [0.0; TIPPING_GRID.len()],
                        hint: None,
                    });
                }
                let slide = knowledge.parameters(true).slide;
                knowledge.weigh_tipping(slide);
            }
            if !remembers {
                continue;
            }
            let parameters = knowledge.parameters(identifies);
            if parameters.tipping != knowledge.residual_tipping {
                knowledge.recompute_residuals(&parameters);
            }
            let push = Push {
                outline: &outline,
                parameters: &parameters,
                pusher_radius: pusher_radius(),
            };
            let stepped = push.step(*before, motion_before, pusher_from, moved);
            if let Some(key) = residual_key(
                &outline,
                before,
                &motion_before,
                pusher_from,
                moved,
                &stepped,
            ) {
                let seen = motion.in_frame(before.theta);
                let predicted = stepped.motion.in_frame(before.theta);
                knowledge.memory.insert(
                    key,
                    [
                        seen[0] - predicted[0],
                        seen[1] - predicted[1],
                        seen[2] - predicted[2],
                    ],
                );
                knowledge.remembered.push(Remembered {
                    outline,
                    before: *before,
                    motion_before,
                    from: pusher_from,
                    path: moved,
                    seen,
                });
            }
        }
    }

    fn parse_world(&self, frame: &Frame) -> Result<HybridWorld, ParseError> {
        let poses = parse_frame_at(frame, ActuatorYaw::ForceZero, Precision::Full)?;
        let limit = MAX_SPEED / f64::from(self.config.publish_rate_hz.max(1));
        let motion = poses
            .blocks
            .iter()
            .map(|(&id, pose)| {
                let before = self.current.as_ref().and_then(|c| c.poses.blocks.get(&id));
                let motion = before
                    .map(|b| Twist::between(b, pose))
                    .filter(|m| m.speed() < limit)
                    .unwrap_or_default();
                (id, motion)
            })
            .collect();
        let outlines = frame
            .objects
            .iter()
            .filter(|o| poses.blocks.contains_key(&o.id) && !is_skipped(&o.name))
            .filter_map(|o| Some((o.id, Outline::of_footprint(o.shape?.footprint()))))
            .collect();
        Ok(HybridWorld {
            poses,
            motion,
            outlines,
        })
    }
}

/// The residual memory's key for one message, if the pusher comes near
/// the block or the block moves: otherwise nothing happens that a memory
/// could add to.
fn residual_key(
    outline: &Outline,
    pose: &ObjectState,
    motion: &Twist,
    from: Vector2<f64>,
    path: Vector2<f64>,
    stepped: &Stepped,
) -> Option<[f64; residual::FEATURES]> {
    let near = surface_gap(outline, pose, from) < NEAR;
    let moving = motion.speed() > AT_REST || motion.dtheta.abs() > AT_REST;
    if !(near || moving || stepped.touched) {
        return None;
    }
    let to_frame = Rotation2::new(-pose.theta);
    let pusher = to_frame * (from - pose.position());
    let local_path = to_frame * path;
    Some(residual::features(
        [pusher.x, pusher.y],
        [local_path.x, local_path.y],
        motion.in_frame(pose.theta),
    ))
}

impl Model for HybridModel {
    type World = HybridWorld;

    fn parse(&self, frame: &Frame) -> Result<HybridWorld, ParseError> {
        self.parse_world(frame)
    }

    fn poses(world: &HybridWorld) -> Poses {
        world.poses.clone()
    }

    fn reset_objects(&mut self, world: &HybridWorld) {
        let mut world = world.clone();
        // A run starts from a reset world: nothing is sliding.
        for m in world.motion.values_mut() {
            *m = Twist::default();
        }
        self.current = Some(world);
        self.last_action = Action::ZERO;
    }

    fn update(&mut self, world: &HybridWorld, action: Action) {
        if self.training {
            if let Some(from) = self.current.take() {
                self.learn(&from, world, action);
            }
        }
        self.current = Some(world.clone());
        self.last_action = action;
    }

    fn predict(&self, world: &HybridWorld, action: Action) -> HybridWorld {
        let from = world.poses.actuator.position();
        let path = self.actuator_path(action);
        let mut next = world.clone();
        let to = from + path;
        next.poses.actuator = ObjectState::new(to.x, to.y, 0.0);
        for (&id, pose) in &world.poses.blocks {
            let motion = world.motion.get(&id).copied().unwrap_or_default();
            let (after, moved) =
                self.block_after(id, &world.outline(id), *pose, motion, from, path);
            next.poses.blocks.insert(id, after);
            next.motion.insert(id, moved);
        }
        next
    }

    fn set_training(&mut self, on: bool) {
        self.training = on;
    }

    fn is_training(&self) -> bool {
        self.training
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        if let Some(t) = &target {
            t.check()?;
            if Shape::of(t.id).is_none() {
                return Err(TargetError::UnknownObject { id: t.id });
            }
        }
        self.target = target;
        self.push_plan = None;
        Ok(())
    }

    fn has_target(&self) -> bool {
        self.target.is_some()
    }

    fn act(&mut self, rng: &mut dyn Rng) -> Action {
        self.plan(rng)
    }

    fn stats(&self) -> ModelStats {
        let mut stats = OtherStats::default();
        let w = self.actuator.weights(self.config.parts.identifies());
        stats.extra.insert("actuator_action_weight".into(), w[0]);
        stats.extra.insert("actuator_previous_weight".into(), w[1]);
        for (id, k) in &self.blocks {
            let p = k.parameters(self.config.parts.identifies());
            stats.extra.insert(format!("tipping/{id}"), p.tipping);
            stats
                .extra
                .insert(format!("slide_linear/{id}"), p.slide.linear);
            stats
                .extra
                .insert(format!("slide_angular/{id}"), p.slide.angular);
            let n = k.memory.len();
            stats.maps.insert(
                format!("residual/{id}"),
                MapStats {
                    update_calls: k.updates,
                    inserts: n as u64,
                    nodes: n,
                },
            );
        }
        stats
            .labels
            .insert("parts".into(), self.config.parts.as_str().into());
        ModelStats::Other(stats)
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::ForceZero
    }
}
