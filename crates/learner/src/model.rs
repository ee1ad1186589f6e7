//! The interface a daemon and the experiment driver use to drive a learner,
//! implemented by the gate model (`docs/spec/gate-model.md`) and the interaction model
//! (`docs/spec/interaction-model.md`).

use std::fmt::Debug;

use rand::Rng;
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::features::{ActuatorYaw, ParseError};
pub use crate::stats::ModelStats;
use crate::types::{Action, Frame, Poses, Target, TargetError};

/// A learner of forward and inverse models, driven one world-state message at
/// a time.
///
/// # How the driver calls it (`docs/spec/experiments.md` §2–§4)
///
/// For every message that is not dropped:
///
/// 1. `let ws = model.parse(&frame)?` — a frame that fails to parse is not a
///    model step (the daemon reports it and waits for the next one);
/// 2. [`Model::poses`] of `ws` for the start-position check and of `ws` and
///    the previous prediction for the recorded rows;
/// 3. on the first message of a run [`Model::reset_objects`]`(&ws)`, on every
///    later one [`Model::update`]`(&ws, last_action)` with the action that was
///    in force while the world moved to `ws`;
/// 4. [`Model::predict`] (the push-task test chains predictions:
///    `update(&p, a)` and `predict(&p, a)` are called with the previous
///    *prediction* `p` instead of a parsed world, training being off), and/or,
///    in Move to Target, [`Model::act`] for the next action.
///
/// Between phases: [`Model::set_training`]`(false)` when a push task's
/// training runs end; [`Model::set_target`] when Move to Target's training
/// runs end, [`Model::has_target`] after every `act` (false once the target
/// was reached); [`Model::stats`] when training ends and after a test run.
/// A fold starts with a *fresh* model: keep an untrained instance and clone
/// it (`Clone` is a supertrait for this).
///
/// # Why `update` takes only the new world
///
/// The issue that asked for this trait sketched
/// `update(previous world, action, current world)`. The spec's models keep
/// their previous state themselves (`docs/spec/gate-model.md` §2–§4,
/// `docs/spec/interaction-model.md` §3–§4) and the reference results depend on it: the
/// gate model's record of a block is what supplies `s_prev` (stale across a
/// reset, shared with prediction chains, `docs/spec/gate-model.md` §3, §4.1), and the
/// interaction model trains on its stored current interaction state. A
/// caller-supplied previous world would bypass exactly those quirks, so the
/// previous state is the model's and `update` sees only the new one.
///
/// # Determinism
///
/// Everything is deterministic given the inputs: the only randomness is the
/// exploration fallback of [`Model::act`], drawn from the caller's seeded
/// generator (`docs/spec/experiments.md` §5). No method does I/O.
pub trait Model: Clone + Debug + Send + Serialize + DeserializeOwned {
    /// The model's own parsed world state (`docs/spec/README.md` §4 "world state"): for
    /// the gate model the actuator and blocks as tracked objects with `s` and
    /// `s_prev`; for the interaction model the object states plus the
    /// interaction states computed from them. Predictions are values of the
    /// same type so that they can be chained.
    ///
    /// The gate model's shared block records (`docs/spec/gate-model.md` §4.1) need
    /// object identity across `parse`, `predict` and `reset_objects`/`update`
    /// even though they all take the world by shared reference: a parsed
    /// block can carry an identity token created at parse time (e.g. an
    /// `Arc<()>` compared with `Arc::ptr_eq`) that predictions of an
    /// unchanged block keep and that the model remembers when it adopts the
    /// block as its record.
    type World: Clone + Debug + Send;

    /// Parse one world-state message (`docs/spec/features.md` §1 with this model's
    /// actuator-yaw rule, `crate::features::ActuatorYaw`; `docs/spec/protocol.md` §4
    /// skip rules). Freshly parsed objects have `s_prev = s`.
    ///
    /// Errors instead of panics on anything the world may send: no actuator,
    /// non-finite numbers, unknown or duplicate ids (see [`ParseError`]).
    /// Parsing does not change what the model has learned.
    fn parse(&self, frame: &Frame) -> Result<Self::World, ParseError>;

    /// Model-agnostic object states of a world (parsed or predicted), for the
    /// start-position check (`docs/spec/experiments.md` §2), the recorded rows and the
    /// metrics (§7) and for shadows. For the interaction model's predictions
    /// these are the finalised objects (`docs/spec/interaction-model.md` §5), with the
    /// actuator's yaw 0.
    fn poses(world: &Self::World) -> Poses;

    /// Re-synchronise with `world` at the first message of a run, without
    /// training (`docs/spec/gate-model.md` §3, `docs/spec/interaction-model.md` §4). The gate
    /// model deliberately keeps the end of the previous run as its blocks'
    /// `s_prev` (quirk, `docs/spec/gate-model.md` §3).
    fn reset_objects(&mut self, world: &Self::World);

    /// Learn from the transition from the model's stored state into `world`
    /// under `action`, the action that was in force meanwhile; then make
    /// `world` the stored state (`docs/spec/gate-model.md` §2, `docs/spec/interaction-model.md`
    /// §3). With training off only the stored state moves forward.
    fn update(&mut self, world: &Self::World, action: Action);

    /// Predict the world one message after `world` if `action` is in force
    /// (`docs/spec/gate-model.md` §4, `docs/spec/interaction-model.md` §5). `world` may itself be
    /// a prediction. Never changes what the model has learned.
    fn predict(&self, world: &Self::World, action: Action) -> Self::World;

    /// Turn training on (the default for a new model) or off.
    fn set_training(&mut self, on: bool);

    /// Whether [`Model::update`] currently trains.
    fn is_training(&self) -> bool;

    /// Set (`Some`) or clear (`None`) the Move-to-Target goal
    /// (`docs/spec/planning.md`). Implementations start with [`Target::check`] and may
    /// refuse objects they cannot plan for ([`TargetError::UnknownObject`]);
    /// a refused target leaves the previous one in place. The interaction
    /// model builds its target interaction state here (`docs/spec/features.md` §6.5).
    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError>;

    /// Whether a target is set; `act` clears it when it finds the target
    /// reached (`docs/spec/planning.md` §2, §3).
    fn has_target(&self) -> bool;

    /// The next action from the model's current state (after the latest
    /// `update` or `reset_objects`) towards the target: `docs/spec/planning.md`
    /// `get_action()`. (0, 0) without a target or once it is reached (the
    /// target is then cleared).
    ///
    /// Takes no world: the gate model plans from its own actuator and block
    /// records (`docs/spec/planning.md` §2), the interaction model from its current
    /// interaction state (§3). `&mut self` because reaching the target clears
    /// it and the inverse model keeps its `current_key` between queries.
    /// `rng` feeds the exploration fallback (`docs/spec/planning.md` §5): two uniform
    /// samples in [−0.5, 0.5), x first, e.g. `rng.random::<f64>() - 0.5` with
    /// `rand::RngExt`; nothing else may draw from it.
    fn act(&mut self, rng: &mut dyn Rng) -> Action;

    /// Node statistics of every map (`docs/spec/experiments.md` §7.5).
    fn stats(&self) -> ModelStats;

    /// How the driver reads the actuator's yaw in the real states it checks
    /// and scores for this model (`docs/spec/experiments.md` §2: the gate
    /// model reads it as 0). The driver reads those states itself, at the
    /// thesis's precision, whatever the model's own parse does, so that a
    /// learner is scored alike in process and behind the learner protocol
    /// (whose Hello says the same: `ignores_actuator_yaw`).
    fn actuator_yaw(&self) -> ActuatorYaw {
        ActuatorYaw::Keep
    }

    /// What only the harness knows, told to the references that may know
    /// it and to no learner: after how many physics steps of the coming
    /// interval the world will apply the Move the driver sends next (the
    /// world's latency emulation, which the harness seeds). The driver
    /// calls it before every message it hands the model; the oracle that
    /// knows the latency reads it (`drive::oracle`), every other model
    /// ignores it, and the learner protocol has no such call.
    fn next_move_delay(&mut self, _steps: u32) {}

    /// Called once on a fresh clone before a fold's first message, with the
    /// fold's seed (the seed of the driver's own generator for the fold,
    /// `docs/spec/experiments.md` §5). In-process models need nothing here:
    /// the clone is the fresh model. A model that lives in another process
    /// (`pushlearn experiment --learner`) starts its fold there.
    fn start_fold(&mut self, _seed: u64) {}

    /// Why the model cannot answer any more, if it cannot. The methods above
    /// are infallible because an in-process model cannot fail; a model
    /// behind a pipe or a socket can (it crashed, hung, sent garbage). Such a
    /// model answers neutrally from then on and says why here; the driver
    /// asks after every message and ends the job with this. In-process
    /// models never fail.
    fn failure(&self) -> Option<String> {
        None
    }

    /// Selector diagnostics for the real transition `old` → `new` under
    /// `action`: per interaction pair, the AC the model's own assignment
    /// gives to the transition (`None` if no AC has its changed-feature set)
    /// and the AC its selector chooses from `old`. Empty for models without
    /// an AC selector. Changes nothing.
    fn selection(
        &self,
        _old: &Poses,
        _new: &Poses,
        _action: Action,
    ) -> Vec<(Option<usize>, Option<usize>)> {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Probe;
    use crate::types::{Observation, BLUE_ID};

    fn frame(actuator_y: f64) -> Frame {
        let obs = |name: &str, id, x, y| Observation {
            name: String::from(name),
            id,
            position: [x, y, 0.03],
            orientation: [0.0, 0.0, 0.0, 1.0],
            shape: None,
        };
        Frame {
            objects: vec![
                obs("actuator", 8, 0.0, actuator_y),
                obs("blockA", 15, 0.0, 0.25),
            ],
        }
    }

    /// A fixed-sequence generator keeps the test independent of rand's algorithms.
    struct Counter(u64);

    impl rand::TryRng for Counter {
        type Error = std::convert::Infallible;
        fn try_next_u32(&mut self) -> Result<u32, Self::Error> {
            self.0 += 1;
            Ok(self.0 as u32)
        }
        fn try_next_u64(&mut self) -> Result<u64, Self::Error> {
            self.0 += 1;
            Ok(self.0 << 62)
        }
        fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Self::Error> {
            dst.fill(0);
            Ok(())
        }
    }

    /// Drives a model through the trait only, the way the driver does.
    fn run_through_trait<M: Model>(mut model: M) -> (M, Poses) {
        model.set_training(true);
        let mut last = None;
        for step in 0..4 {
            let ws = model.parse(&frame(0.005 * f64::from(step))).unwrap();
            match last {
                None => model.reset_objects(&ws),
                Some(a) => model.update(&ws, a),
            }
            let a = Action::new(0.0, 0.5);
            let _ = model.predict(&ws, a);
            last = Some(a);
        }
        let ws = model.parse(&frame(0.02)).unwrap();
        // A zero action: the probe's prediction is then the parsed world.
        let p = model.predict(&ws, Action::ZERO);
        (model, M::poses(&p))
    }

    #[test]
    fn the_trait_supports_the_drivers_calling_pattern() {
        let (mut model, predicted) = run_through_trait(Probe::default());
        // Step 0 resynchronised, steps 1–3 were updates with training on.
        let probe = Probe::map(&model.stats()).unwrap();
        assert_eq!(probe.update_calls, 3);
        assert_eq!(probe.inserts, 1);
        assert!((predicted.actuator.y - 0.02).abs() < 1e-3);
        assert!(model.is_training());

        let mut rng = Counter(0);
        assert_eq!(model.act(&mut rng), Action::ZERO);
        assert_eq!(
            model.set_target(Some(Target::new(8, Default::default()))),
            Err(TargetError::Actuator)
        );
        assert!(!model.has_target());
        model
            .set_target(Some(Target::new(BLUE_ID, Default::default())))
            .unwrap();
        assert!(model.has_target());
        let a = model.act(&mut rng);
        assert!(a.vx >= -0.5 && a.vx < 0.5 && a.vy >= -0.5 && a.vy < 0.5);
        assert_ne!(a, Action::ZERO);

        let json = serde_json::to_string(&model).unwrap();
        let back: Probe = serde_json::from_str(&json).unwrap();
        assert_eq!(back.trained_updates, 3);
    }

    #[test]
    fn parse_errors_reach_the_driver() {
        let model = Probe::default();
        let mut f = frame(0.0);
        f.objects.remove(0);
        assert_eq!(model.parse(&f).err(), Some(ParseError::NoActuator));
    }
}
