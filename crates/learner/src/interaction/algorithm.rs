//! State, update, reset, prediction and statistics of the interaction model
//! (`docs/spec/interaction-model.md` §1–§6). Planning is in `planner.rs`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::errors::InteractionError;
use super::hyperparams::InteractionConfig;
use super::selector::{AcSelector, Selector};
use crate::aim::InverseModel;
use crate::aitm::Aitm;
use crate::features::{
    changed_features, episode_difference, interaction_states, parse_frame, poses_from_states,
    target_interaction_state, ActuatorYaw, InteractionState, PairKey, ParseError, Shape,
    INTERACTION_DIM, INTERACTION_INPUT_DIM,
};
use crate::model::Model;
use crate::stats::{AcStats, InteractionStats, ModelStats};
use crate::types::{Action, Frame, Poses, Target, TargetError};

/// The interaction model's world state (`docs/spec/interaction-model.md` §2): the
/// object states (parsed with the actuator's reported yaw, or finalised from
/// a prediction with actuator yaw 0) and every interaction state computed
/// from them, by pair key (with one block only "15,8").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InteractionWorld {
    /// Kept for recording, scoring and finalisation; the model itself reads
    /// only `states`.
    pub poses: Poses,
    /// ι(n1, n2) for every block n1 and every other object n2 (`docs/spec/features.md` §6.1).
    pub states: BTreeMap<PairKey, InteractionState>,
}

impl InteractionWorld {
    /// The world of these object states, with freshly computed interaction
    /// states (`docs/spec/features.md` §6.1, which rounds the relative positions).
    #[must_use]
    pub fn from_poses(poses: Poses) -> Self {
        let states = interaction_states(&poses);
        Self { poses, states }
    }
}

/// One Abstract Collection: the episodes whose changed-feature set is
/// `features` (`docs/spec/interaction-model.md` §1). Its episodes and local inverse
/// model, never used by the original, are not kept.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbstractCollection {
    features: Vec<usize>,
    forward: Aitm,
}

impl AbstractCollection {
    fn new(features: Vec<usize>, config: &InteractionConfig) -> Self {
        let forward = Aitm::new(config.ac(), INTERACTION_INPUT_DIM, features.len());
        Self { features, forward }
    }

    /// The changed-feature list `S_k`, ascending.
    #[must_use]
    pub fn features(&self) -> &[usize] {
        &self.features
    }

    /// The local forward model `[ι, a_local] → d[S_k]` (WINNER).
    #[must_use]
    pub fn forward(&self) -> &Aitm {
        &self.forward
    }

    /// `S_k` written as the AC index key, e.g. "2,3,5" ("" for the empty set).
    #[must_use]
    pub fn label(&self) -> String {
        crate::stats::changed_label(&self.features)
    }
}

/// A Move-to-Target goal and its target interaction state (`docs/spec/features.md`
/// §6.5). Serialised as the target alone: the state is recomputed, which is
/// deterministic, so a restored model plans bit-identically.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "Target", into = "Target")]
pub(super) struct Goal {
    pub(super) target: Target,
    pub(super) state: InteractionState,
}

impl From<Target> for Goal {
    fn from(target: Target) -> Self {
        Self {
            target,
            state: target_interaction_state(&target),
        }
    }
}

impl From<Goal> for Target {
    fn from(goal: Goal) -> Self {
        goal.target
    }
}

/// The pairwise interaction-state model (`docs/spec/interaction-model.md`).
///
/// ```
/// use learner::interaction::InteractionModel;
/// use learner::{Action, Model, ObjectState, Poses};
/// use learner::interaction::InteractionWorld;
///
/// let mut model = InteractionModel::default();
/// let world = |y: f64| {
///     let mut poses = Poses { actuator: ObjectState::new(0.0, y, 0.0), ..Poses::default() };
///     poses.blocks.insert(15, ObjectState::new(0.0, 0.25, 0.0));
///     InteractionWorld::from_poses(poses)
/// };
/// model.reset_objects(&world(0.0));
/// model.update(&world(0.005), Action::new(0.0, 0.5)); // the actuator moved: S = {6}
/// assert_eq!(model.collections()[0].features(), &[6]);
/// let p = model.predict(&world(0.005), Action::new(0.0, 0.5));
/// assert!((p.poses.actuator.y - 0.01).abs() < 1e-9);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "InteractionModelState")]
pub struct InteractionModel {
    pub(super) config: InteractionConfig,
    /// AC `k` is `acs[k]` (ids in creation order).
    pub(super) acs: Vec<AbstractCollection>,
    /// AC index: changed-feature list → AC id. Rebuilt from `acs` when
    /// deserialising.
    #[serde(skip)]
    pub(super) index: BTreeMap<Vec<usize>, usize>,
    /// The ACS: `[ι, a_local]` → AC id; by default the AITM classifier with
    /// integer labels (`docs/spec/aitm.md` §6), else one of the draft's selectors.
    pub(super) selector: Selector,
    pub(super) selector_trained: bool,
    /// The single global AIM (`docs/spec/interaction-model.md` §8).
    pub(super) inverse: InverseModel,
    /// Current interaction states by pair key.
    pub(super) current: BTreeMap<PairKey, InteractionState>,
    pub(super) training: bool,
    pub(super) goal: Option<Goal>,
}

impl Default for InteractionModel {
    fn default() -> Self {
        Self::new(InteractionConfig::default())
    }
}

impl InteractionModel {
    /// An untrained model: no ACs, untrained ACS and AIM, no current states,
    /// training on, no target.
    #[must_use]
    pub fn new(config: InteractionConfig) -> Self {
        Self {
            config,
            acs: Vec::new(),
            index: BTreeMap::new(),
            selector: Selector::new(config.selector()),
            selector_trained: false,
            inverse: InverseModel::new(config.aim()),
            current: BTreeMap::new(),
            training: true,
            goal: None,
        }
    }

    /// The validated parameters.
    #[must_use]
    pub fn config(&self) -> &InteractionConfig {
        &self.config
    }

    /// The Abstract Collections; AC `k` is element `k`.
    #[must_use]
    pub fn collections(&self) -> &[AbstractCollection] {
        &self.acs
    }

    /// The id of the AC for a changed-feature list, if it exists.
    #[must_use]
    pub fn collection_id(&self, features: &[usize]) -> Option<usize> {
        self.index.get(features).copied()
    }

    /// The Abstract Collection Selector.
    #[must_use]
    pub fn selector(&self) -> &Selector {
        &self.selector
    }

    /// The ACS as the final thesis's AITM classifier, if it is one.
    #[must_use]
    pub fn aitm_selector(&self) -> Option<&Aitm> {
        self.selector.aitm()
    }

    /// One pair's sample of [`Model::selection`]: the AC the model's own
    /// assignment gives to the transition `old` → `new` (the AC of its changed-feature set, `docs/spec/interaction-model.md` §3),
    /// `None` if no AC has that set, together with the AC the selector
    /// chooses for `old` under `action`: one sample of the selector's
    /// accuracy on real transitions. Changes nothing.
    #[must_use]
    pub fn pair_selection(
        &self,
        old: &InteractionState,
        new: &InteractionState,
        action: Action,
    ) -> (Option<usize>, Option<usize>) {
        let d = episode_difference(old, new);
        let truth = self.collection_id(&changed_features(&d, self.config.eps_noise()));
        let chosen = if self.selector_trained {
            self.selector.select(&old.input(action))
        } else {
            None
        };
        (truth, chosen)
    }

    /// Whether the ACS was ever trained (before that, predictions change nothing).
    #[must_use]
    pub fn selector_trained(&self) -> bool {
        self.selector_trained
    }

    /// The global inverse model.
    #[must_use]
    pub fn inverse_model(&self) -> &InverseModel {
        &self.inverse
    }

    /// The current interaction states by pair key.
    #[must_use]
    pub fn current_states(&self) -> &BTreeMap<PairKey, InteractionState> {
        &self.current
    }

    /// The current target, if any.
    #[must_use]
    pub fn target(&self) -> Option<Target> {
        self.goal.map(|g| g.target)
    }

    /// The AC for `features`, created with the next id if new (§3).
    fn collection_for(&mut self, features: Vec<usize>) -> usize {
        if let Some(&k) = self.index.get(&features) {
            return k;
        }
        let k = self.acs.len();
        self.index.insert(features.clone(), k);
        self.acs
            .push(AbstractCollection::new(features, &self.config));
        k
    }

    /// One training episode (`docs/spec/interaction-model.md` §3) from `old` to `new`
    /// under `action`.
    fn learn(&mut self, old: &InteractionState, new: &InteractionState, action: Action) {
        let d = episode_difference(old, new);
        let k = self.collection_for(changed_features(&d, self.config.eps_noise()));
        // x = ι_old ‖ R(θ_ref,old)ᵀ·a: the action in the *old* frame.
        let x = old.input(action);
        let ac = &mut self.acs[k];
        let y: Vec<f64> = ac.features.iter().map(|&i| d[i]).collect();
        ac.forward.update(&x, &y);
        self.selector.learn(&x, k);
        self.selector_trained = true;
        self.inverse.train(&x, &d);
    }

    /// The predicted interaction state for one pair (`docs/spec/interaction-model.md`
    /// §5, before finalisation): same `T`, `T⁻¹`, `θ_ref`; the selected AC's
    /// output added to the components `S_k`.
    #[must_use]
    pub fn predict_state(&self, state: &InteractionState, action: Action) -> InteractionState {
        let mut out = *state;
        if !self.selector_trained {
            return out;
        }
        let x = state.input(action);
        // The stored labels are AC ids (checked when deserialising); a label
        // without an AC, which only a hand-edited snapshot could produce,
        // predicts no change rather than panicking.
        let Some(ac) = self.selector.select(&x).and_then(|k| self.acs.get(k)) else {
            return out;
        };
        let change = ac.forward.query(&x);
        for (&i, v) in ac.features.iter().zip(&change) {
            out.components[i] += v;
        }
        out
    }
}

impl Model for InteractionModel {
    type World = InteractionWorld;

    fn parse(&self, frame: &Frame) -> Result<InteractionWorld, ParseError> {
        Ok(InteractionWorld::from_poses(parse_frame(
            frame,
            ActuatorYaw::Keep,
        )?))
    }

    fn poses(world: &InteractionWorld) -> Poses {
        world.poses.clone()
    }

    /// §4: the whole map is replaced, so no state of an earlier run remains.
    fn reset_objects(&mut self, world: &InteractionWorld) {
        self.current = world.states.clone();
    }

    fn update(&mut self, world: &InteractionWorld, action: Action) {
        for (key, new) in &world.states {
            if let Some(old) = self.current.get(key).copied() {
                if self.training {
                    self.learn(&old, new, action);
                }
            }
            self.current.insert(*key, *new);
        }
    }

    /// §5. The finalised objects are extracted through each predicted
    /// state's *old* frame, in pair-key order (later pairs overwrite earlier
    /// ones), and the interaction states recomputed from them. A world
    /// without blocks has no interaction state, so nothing is predicted and
    /// its objects are returned unchanged.
    fn predict(&self, world: &InteractionWorld, action: Action) -> InteractionWorld {
        let predicted: BTreeMap<PairKey, InteractionState> = world
            .states
            .iter()
            .map(|(key, state)| (*key, self.predict_state(state, action)))
            .collect();
        InteractionWorld::from_poses(
            poses_from_states(&predicted).unwrap_or_else(|| world.poses.clone()),
        )
    }

    /// Turning training off also brings the selector up to date (the
    /// draft's batch tree refits on every reference stored so far).
    fn set_training(&mut self, on: bool) {
        if !on {
            self.selector.refresh();
        }
        self.training = on;
    }

    fn is_training(&self) -> bool {
        self.training
    }

    /// Any block of the shape table can be a target; the plan then follows
    /// the pair (block, actuator).
    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        let Some(target) = target else {
            self.goal = None;
            return Ok(());
        };
        target.check()?;
        if Shape::of(target.id).is_none() {
            return Err(TargetError::UnknownObject { id: target.id });
        }
        self.goal = Some(Goal::from(target));
        Ok(())
    }

    fn has_target(&self) -> bool {
        self.goal.is_some()
    }

    fn act(&mut self, rng: &mut dyn rand::Rng) -> Action {
        self.get_action(rng)
    }

    /// §6 and `docs/spec/experiments.md` §7.5: the ACS and every AC with its
    /// changed-feature set; the AC columns are derived from these.
    fn stats(&self) -> ModelStats {
        ModelStats::Interaction(InteractionStats {
            acs: self.selector.stats(),
            collections: self
                .acs
                .iter()
                .map(|ac| AcStats {
                    changed: ac.features.clone(),
                    map: ac.forward.stats(),
                })
                .collect(),
        })
    }

    fn selection(
        &self,
        old: &Poses,
        new: &Poses,
        action: Action,
    ) -> Vec<(Option<usize>, Option<usize>)> {
        let (old, new) = (interaction_states(old), interaction_states(new));
        old.iter()
            .filter_map(|(key, o)| Some(self.pair_selection(o, new.get(key)?, action)))
            .collect()
    }
}

/// The serialised form, validated before it becomes an [`InteractionModel`]
/// so that no stored value can make a later call panic.
#[derive(Deserialize)]
struct InteractionModelState {
    config: InteractionConfig,
    acs: Vec<AbstractCollection>,
    selector: Selector,
    selector_trained: bool,
    inverse: InverseModel,
    current: BTreeMap<PairKey, InteractionState>,
    training: bool,
    goal: Option<Goal>,
}

impl TryFrom<InteractionModelState> for InteractionModel {
    type Error = InteractionError;

    fn try_from(s: InteractionModelState) -> Result<Self, Self::Error> {
        use InteractionError::InconsistentState as Bad;
        let mut index = BTreeMap::new();
        for (k, ac) in s.acs.iter().enumerate() {
            if !ac.features.windows(2).all(|w| w[0] < w[1])
                || ac.features.iter().any(|&i| i >= INTERACTION_DIM)
            {
                return Err(Bad("AC feature list not ascending within 0..8"));
            }
            if ac.forward.input_dim() != INTERACTION_INPUT_DIM
                || ac.forward.output_dim() != ac.features.len()
            {
                return Err(Bad("AC forward model dimensions"));
            }
            if index.insert(ac.features.clone(), k).is_some() {
                return Err(Bad("two ACs with the same feature list"));
            }
        }
        if let Some(why) = s.selector.inconsistency(s.acs.len(), s.selector_trained) {
            return Err(Bad(why));
        }
        if s.selector.kind() != s.config.selector() {
            return Err(Bad("selector kind differs from the configuration"));
        }
        if s.inverse
            .precondition_dim()
            .is_some_and(|n| n != INTERACTION_INPUT_DIM)
        {
            return Err(Bad("inverse model precondition dimension"));
        }
        if s.current.iter().any(|(k, st)| *k != st.key()) {
            return Err(Bad("interaction state stored under another pair key"));
        }
        if s.goal
            .is_some_and(|g| g.target.check().is_err() || Shape::of(g.target.id).is_none())
        {
            return Err(Bad("target the model cannot plan for"));
        }
        Ok(Self {
            config: s.config,
            acs: s.acs,
            index,
            selector: s.selector,
            selector_trained: s.selector_trained,
            inverse: s.inverse,
            current: s.current,
            training: s.training,
            goal: s.goal,
        })
    }
}
