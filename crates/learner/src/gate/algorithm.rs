//! The gate model's state, update, re-synchronisation and prediction
//! (`docs/spec/gate-model.md` §1–§4, §7).

use std::collections::BTreeMap;

use rand::Rng;
use serde::{Deserialize, Serialize};

use super::errors::GateError;
use super::hyperparams::{GateConfig, VelocityFeatures};
use super::world::{GateWorld, Record, SharedBlock};
use crate::aim::InverseModel;
use crate::aitm::{Aitm, AitmConfig};
use crate::features::{
    actuator_change, apply_actuator_change_at, apply_local_change_at, local_change_at, local_vec,
    parse_frame_at, relative_features_at, ActuatorYaw, ParseError, LOCAL_CHANGE_DIM,
    RELATIVE_FEATURES_DIM,
};
use crate::model::Model;
use crate::stats::{GateStats, ModelStats};
use crate::types::{Action, Frame, ObjectState, Poses, Target, TargetError, TrackedObject};

/// ε_change (`docs/spec/gate-model.md` §2, `docs/spec/README.md` §6): a block "changed" when its
/// local change has a norm above this, i.e. any rounding-level change.
pub const EPS_CHANGE: f64 = 0.0;

/// ε_change of the `unrounded` improvement: half a rounding unit, the
/// smallest change that rounding to 3 decimals let through, so that the
/// physics' sub-millimetre jitter of a resting block is not taken for a push.
pub const UNROUNDED_EPS_CHANGE: f64 = 0.0005;

/// The hard-coded actuator's displacement per unit of action: the 100 Hz step
/// length (`docs/spec/gate-model.md` §5, flag 16).
pub const HARD_CODED_ACTUATOR_STEP: f64 = 0.01;

/// Input dimension of the actuator forward model: the action (vx, vy).
const ACTION_DIM: usize = 2;

/// Label of a gate sample whose block changed (`docs/spec/gate-model.md` §1).
const CHANGED: i64 = 1;

/// Longest block-predictor input: φ and the three velocities of USE_DYNS.
const MAX_PREDICTOR_INPUT: usize = RELATIVE_FEATURES_DIM + 3;

/// The block predictors' input dimension under `config`.
fn predictor_input_dim(config: &GateConfig) -> usize {
    RELATIVE_FEATURES_DIM + config.params().velocity_features.dim()
}

/// The block predictor's input for block `o` with features `phi`: φ itself
/// in the evaluated configuration; with USE_DYNS followed by `o`'s own
/// velocity ([`VelocityFeatures`]). Returns the buffer and its used length.
fn predictor_input(
    config: &GateConfig,
    o: &TrackedObject,
    phi: &[f64; RELATIVE_FEATURES_DIM],
) -> ([f64; MAX_PREDICTOR_INPUT], usize) {
    let mut x = [0.0; MAX_PREDICTOR_INPUT];
    x[..RELATIVE_FEATURES_DIM].copy_from_slice(phi);
    let extra = config.params().velocity_features;
    let precision = config.params().improvements.precision();
    if extra != VelocityFeatures::None {
        let v = precision.round_vec(local_vec(
            o.s_prev.theta,
            o.s.position() - o.s_prev.position(),
        ));
        x[RELATIVE_FEATURES_DIM] = v.x;
        x[RELATIVE_FEATURES_DIM + 1] = v.y;
        if extra == VelocityFeatures::LinearAngular {
            x[RELATIVE_FEATURES_DIM + 2] = precision.round(o.s.theta - o.s_prev.theta);
        }
    }
    (x, RELATIVE_FEATURES_DIM + extra.dim())
}

/// The models of one block id (`docs/spec/gate-model.md` §1): forward model φ → Δ and
/// the inverse model, created together on the block's first observed change.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Predictor {
    pub(super) forward: Aitm,
    pub(super) inverse: InverseModel,
}

impl Predictor {
    fn new(config: &GateConfig) -> Self {
        Self {
            forward: Aitm::new(
                config.forward(),
                predictor_input_dim(config),
                LOCAL_CHANGE_DIM,
            ),
            inverse: InverseModel::new(config.aim()),
        }
    }

    /// The forward model (AITM, BESTTWO, φ → Δ).
    pub fn forward(&self) -> &Aitm {
        &self.forward
    }

    /// The Averaging Inverse Model of this block.
    pub fn inverse(&self) -> &InverseModel {
        &self.inverse
    }
}

/// The object-state model with gating function (`docs/spec/gate-model.md`).
///
/// An actuator forward model (action → actuator change), one gate classifier
/// shared by all blocks ("does the actuator change this block in the next
/// step?") and per block id a forward model and an inverse model of the
/// block's change; plus the planner of `docs/spec/planning.md` §2 ([`Model::act`]).
///
/// ```
/// use learner::gate::{GateConfig, GateModel, GateWorld};
/// use learner::{Action, Model, ObjectState, Poses};
///
/// let mut model = GateModel::new(GateConfig::hz100());
/// let world = |y: f64| {
///     let mut poses = Poses::default();
///     poses.actuator = ObjectState::new(0.0, y, 0.0);
///     poses.blocks.insert(15, ObjectState::new(0.0, 0.25, 0.0));
///     GateWorld::from_poses(&poses)
/// };
/// let push = Action::new(0.0, 0.5);
/// model.reset_objects(&world(0.0));
/// model.update(&world(0.005), push);
/// model.update(&world(0.01), push);
/// // The actuator model has learned the step of this action.
/// let p = model.predict(&world(0.01), push);
/// assert_eq!(p.actuator().s, ObjectState::new(0.0, 0.015, 0.0));
/// // The untrained-for-change block stays where it is.
/// assert_eq!(p.block(15).map(|b| b.s), Some(ObjectState::new(0.0, 0.25, 0.0)));
/// ```
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "GateModelState")]
pub struct GateModel {
    pub(super) config: GateConfig,
    pub(super) actuator_model: Aitm,
    pub(super) gate: Aitm,
    pub(super) predictors: BTreeMap<u32, Predictor>,
    /// The model's copy of the actuator; unset before the first message.
    pub(super) actuator: Option<TrackedObject>,
    /// Known blocks: the records first seen, advanced in place (§4.1).
    pub(super) records: BTreeMap<u32, Record>,
    pub(super) training: bool,
    pub(super) target: Option<Target>,
}

impl Default for GateModel {
    fn default() -> Self {
        Self::new(GateConfig::default())
    }
}

impl GateModel {
    /// An untrained model: training on, no target, nothing known.
    #[must_use]
    pub fn new(config: GateConfig) -> Self {
        Self {
            config,
            actuator_model: Aitm::new(config.actuator(), ACTION_DIM, LOCAL_CHANGE_DIM),
            gate: Aitm::new(AitmConfig::classifier(), RELATIVE_FEATURES_DIM, 1),
            predictors: BTreeMap::new(),
            actuator: None,
            records: BTreeMap::new(),
            training: true,
            target: None,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &GateConfig {
        &self.config
    }

    /// The actuator forward model (AITM, BESTTWO, action → actuator change);
    /// never trained with the hard-coded actuator.
    pub fn actuator_model(&self) -> &Aitm {
        &self.actuator_model
    }

    /// The gate classifier (AITM, WINNER, φ → changed); never trained with
    /// the hard-coded gate.
    pub fn gate(&self) -> &Aitm {
        &self.gate
    }

    /// The forward and inverse model of a block id, once it has changed
    /// (with the `shared-blocks` improvement: the one model of every block,
    /// kept under the id of the block that first changed).
    pub fn predictor(&self, id: u32) -> Option<&Predictor> {
        self.predictors.get(&self.predictor_key(id))
    }

    /// [`GateModel::predictor`], to train or to query the inverse model.
    pub(super) fn predictor_mut(&mut self, id: u32) -> Option<&mut Predictor> {
        let key = self.predictor_key(id);
        self.predictors.get_mut(&key)
    }

    /// Where block `id`'s predictor is kept: under its id, or with
    /// `shared-blocks` under the id of the block that first changed (the
    /// one entry there is), `id` itself before any did.
    fn predictor_key(&self, id: u32) -> u32 {
        if self.config.params().improvements.shared_blocks {
            self.predictors.keys().next().copied().unwrap_or(id)
        } else {
            id
        }
    }

    /// φ(reference, other) as this model computes it: at its precision, and
    /// without the two ids when the blocks share one model.
    pub(super) fn phi(
        &self,
        reference: &TrackedObject,
        other: &TrackedObject,
    ) -> [f64; RELATIVE_FEATURES_DIM] {
        let improvements = self.config.params().improvements;
        let mut phi = relative_features_at(reference, other, improvements.precision());
        if improvements.shared_blocks {
            phi[0] = 0.0;
            phi[1] = 0.0;
        }
        phi
    }

    /// Δ(pre, post) at this model's precision.
    pub(super) fn local_change(
        &self,
        pre: &ObjectState,
        post: &ObjectState,
    ) -> [f64; LOCAL_CHANGE_DIM] {
        local_change_at(pre, post, self.precision())
    }

    fn precision(&self) -> crate::features::Precision {
        self.config.params().improvements.precision()
    }

    /// The model's actuator (state after the latest update).
    pub fn actuator(&self) -> Option<TrackedObject> {
        self.actuator
    }

    /// The model's current record of a known block.
    pub fn block(&self, id: u32) -> Option<TrackedObject> {
        self.records.get(&id).map(|r| r.0.get())
    }

    /// Ids of the known blocks, ascending.
    pub fn known_blocks(&self) -> impl ExactSizeIterator<Item = u32> + '_ {
        self.records.keys().copied()
    }

    /// The current Move-to-Target goal.
    pub fn target(&self) -> Option<Target> {
        self.target
    }

    /// Whether the gate predicts that the actuator changes the block described
    /// by `phi` in the next step (`docs/spec/gate-model.md` §4: 0 if never trained).
    pub(super) fn influences(&self, phi: &[f64; RELATIVE_FEATURES_DIM]) -> bool {
        if self.config.params().hard_coded_gate {
            hard_coded_gate(phi)
        } else {
            self.gate.classify(phi) == Some(CHANGED)
        }
    }

    /// The predicted actuator for action `a` from `from` (`docs/spec/gate-model.md` §4):
    /// `s = r3(from.s + Δ̂a)`, `s_prev = from.s`. Always the model's own
    /// actuator forward model; zero change while it has no nodes.
    pub(super) fn predict_actuator(&self, from: &TrackedObject, a: Action) -> TrackedObject {
        let delta = if self.config.params().hard_coded_actuator {
            [
                HARD_CODED_ACTUATOR_STEP * a.vx,
                HARD_CODED_ACTUATOR_STEP * a.vy,
                0.0,
            ]
        } else {
            let d = self.actuator_model.query(&[a.vx, a.vy]);
            [d[0], d[1], d[2]]
        };
        TrackedObject {
            id: from.id,
            s: apply_actuator_change_at(&from.s, delta, self.precision()),
            s_prev: from.s,
        }
    }

    /// The predictor's next state of block `o` with features `phi`
    /// (`docs/spec/features.md` §3.4, times the prediction boost), `None` without a
    /// predictor for its id.
    pub(super) fn predictor_state(
        &self,
        o: &TrackedObject,
        phi: &[f64; RELATIVE_FEATURES_DIM],
    ) -> Option<ObjectState> {
        let p = self.predictor(o.id)?;
        let (x, n) = predictor_input(&self.config, o, phi);
        let d = p.forward.query(&x[..n]);
        Some(apply_local_change_at(
            &o.s,
            [d[0], d[1], d[2]],
            self.config.params().prediction_boost,
            self.precision(),
        ))
    }

    /// `docs/spec/gate-model.md` §2 for one known block `k` newly observed as `o`,
    /// with the model's actuator already moved to the new state.
    fn train_block(&mut self, k: &TrackedObject, o: &TrackedObject, act: &TrackedObject) {
        // docs/spec/gate-model.md §2: OLD block state with NEW actuator state, the
        // pairing predict() presents (predicted actuator, current block).
        let phi = self.phi(k, act);
        let delta = self.local_change(&k.s, &o.s);
        let eps_change = if self.config.params().improvements.unrounded {
            UNROUNDED_EPS_CHANGE
        } else {
            EPS_CHANGE
        };
        let changed = norm(&delta) > eps_change;
        if !self.config.params().hard_coded_gate {
            self.gate.update_label(&phi, i64::from(changed));
        }
        if changed {
            let config = &self.config;
            let (x, n) = predictor_input(config, k, &phi);
            let key = self.predictor_key(o.id);
            let p = self
                .predictors
                .entry(key)
                .or_insert_with(|| Predictor::new(config));
            p.forward.update(&x[..n], &delta);
            p.inverse.train(&phi, &delta);
        }
    }

    /// The model's record for `block`'s id, adopting `block` itself if the id
    /// is new (`docs/spec/gate-model.md` §4.1); `None` after an adoption.
    fn known_or_adopt(&mut self, block: &SharedBlock) -> Option<SharedBlock> {
        match self.records.get(&block.id()) {
            Some(r) => Some(r.0.clone()),
            None => {
                self.records.insert(block.id(), Record(block.clone()));
                None
            }
        }
    }
}

/// The hard-coded gate (`docs/spec/gate-model.md` §5, flag 32): contact within this
/// step (`closing ≤ −distance`), or resting contact.
pub(super) fn hard_coded_gate(phi: &[f64; RELATIVE_FEATURES_DIM]) -> bool {
    let (distance, closing) = (phi[2], phi[3]);
    if closing <= -distance {
        return true;
    }
    closing == 0.0 && norm(&phi[6..8]) < 0.001 && distance < 0.05
}

/// Euclidean norm, summed left to right.
pub(super) fn norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |acc, x| acc + x * x).sqrt()
}

impl Model for GateModel {
    type World = GateWorld;

    fn parse(&self, frame: &Frame) -> Result<GateWorld, ParseError> {
        // docs/spec/features.md §1 step 4: the gate model zeroes the actuator's yaw.
        Ok(GateWorld::from_poses(&parse_frame_at(
            frame,
            ActuatorYaw::ForceZero,
            self.precision(),
        )?))
    }

    fn poses(world: &GateWorld) -> Poses {
        world.poses()
    }

    fn reset_objects(&mut self, world: &GateWorld) {
        for block in world.blocks.iter().rev() {
            let o = block.get();
            if let Some(k) = self.known_or_adopt(block) {
                // docs/spec/gate-model.md §3 quirk: s_prev becomes the previous run's
                // last state.
                k.advance(o.s);
            }
        }
        let act = self.actuator.get_or_insert(world.actuator);
        act.advance(world.actuator.s);
    }

    fn update(&mut self, world: &GateWorld, action: Action) {
        let new = world.actuator;
        let act = self.actuator.get_or_insert(new);
        if self.training && !self.config.params().hard_coded_actuator {
            self.actuator_model
                .update(&[action.vx, action.vy], &actuator_change(&act.s, &new.s));
        }
        act.advance(new.s);
        let act = *act;
        // docs/spec/gate-model.md §1: descending id; it orders the shared gate's samples.
        for block in world.blocks.iter().rev() {
            // Read before any write: `block` may be the model's record itself.
            let o = block.get();
            let Some(k) = self.known_or_adopt(block) else {
                continue;
            };
            if self.training {
                self.train_block(&k.get(), &o, &act);
            }
            k.advance(o.s);
        }
    }

    fn predict(&self, world: &GateWorld, action: Action) -> GateWorld {
        let act = self.predict_actuator(&world.actuator, action);
        let blocks = world
            .blocks
            .iter()
            .map(|block| {
                let o = block.get();
                let phi = self.phi(&o, &act);
                match self
                    .influences(&phi)
                    .then(|| self.predictor_state(&o, &phi))
                    .flatten()
                {
                    Some(s) => SharedBlock::new(TrackedObject {
                        id: o.id,
                        s,
                        s_prev: o.s,
                    }),
                    // docs/spec/gate-model.md §4 quirk: the same record, own s_prev included.
                    None => block.clone(),
                }
            })
            .collect();
        GateWorld {
            actuator: act,
            blocks,
        }
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
            // The original looked the block up among its known objects.
            if !self.records.contains_key(&t.id) {
                return Err(TargetError::UnknownObject { id: t.id });
            }
        }
        self.target = target;
        Ok(())
    }

    fn has_target(&self) -> bool {
        self.target.is_some()
    }

    fn act(&mut self, rng: &mut dyn Rng) -> Action {
        self.get_action(rng)
    }

    fn stats(&self) -> ModelStats {
        let params = self.config.params();
        ModelStats::Gate(GateStats {
            actuator: self.actuator_model.stats(),
            gate: self.gate.stats(),
            predictors: self
                .predictors
                .iter()
                .map(|(&id, p)| (id, p.forward.stats()))
                .collect(),
            hard_coded_actuator: params.hard_coded_actuator,
            hard_coded_gate: params.hard_coded_gate,
        })
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::ForceZero
    }
}

/// The serialised form, validated before it becomes a [`GateModel`] so that
/// no later call can trip over inconsistent dimensions.
#[derive(Deserialize)]
struct GateModelState {
    config: GateConfig,
    actuator_model: Aitm,
    gate: Aitm,
    predictors: BTreeMap<u32, Predictor>,
    actuator: Option<TrackedObject>,
    records: BTreeMap<u32, Record>,
    training: bool,
    target: Option<Target>,
}

impl TryFrom<GateModelState> for GateModel {
    type Error = GateError;

    fn try_from(s: GateModelState) -> Result<Self, Self::Error> {
        use GateError::InconsistentState as Bad;
        let dims = |m: &Aitm| (m.input_dim(), m.output_dim());
        if dims(&s.actuator_model) != (ACTION_DIM, LOCAL_CHANGE_DIM) {
            return Err(Bad("actuator model dimensions"));
        }
        if dims(&s.gate) != (RELATIVE_FEATURES_DIM, 1) || !s.gate.config().is_classifier() {
            return Err(Bad("gate dimensions or kind"));
        }
        if s.config.params().improvements.shared_blocks && s.predictors.len() > 1 {
            return Err(Bad(
                "several block predictors in a model whose blocks share one",
            ));
        }
        for p in s.predictors.values() {
            if dims(&p.forward) != (predictor_input_dim(&s.config), LOCAL_CHANGE_DIM) {
                return Err(Bad("predictor dimensions"));
            }
            if p.inverse
                .precondition_dim()
                .is_some_and(|d| d != RELATIVE_FEATURES_DIM)
            {
                return Err(Bad("inverse model dimensions"));
            }
        }
        if s.records.iter().any(|(&id, r)| r.0.id() != id) {
            return Err(Bad("block record under another id"));
        }
        if !s.records.is_empty() && s.actuator.is_none() {
            return Err(Bad("known blocks without an actuator"));
        }
        if let Some(t) = &s.target {
            if t.check().is_err() || !s.records.contains_key(&t.id) {
                return Err(Bad("target"));
            }
        }
        Ok(Self {
            config: s.config,
            actuator_model: s.actuator_model,
            gate: s.gate,
            predictors: s.predictors,
            actuator: s.actuator,
            records: s.records,
            training: s.training,
            target: s.target,
        })
    }
}
