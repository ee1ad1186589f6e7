//! `GateModel` / `GateWorld` and `InteractionModel` / `InteractionWorld`:
//! the two learners through [`learner::Model`], one Python method per trait
//! method.
//!
//! Both classes come from one macro, so that their surfaces cannot drift
//! apart; only the constructors and `__repr__` differ. Both are configured
//! by the model registry (`learner::registry`), as the command line's
//! models are: the same options, checks and refusals.

use learner::registry::{self, Improvement, ModelKind, ModelOptions};
use learner::{Model, Poses, Target};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::args::{self, value_error, Body, Unsigned};

/// A constructor's arguments: the registry's options and the world's
/// publish rate (10 Hz selects the LOWFREQ thresholds, as bit 2 does).
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    model: ModelOptions,
    publish_rate_hz: u32,
    /// The improvements as the caller named them, for `__repr__`.
    improve: Vec<String>,
}

impl Options {
    /// The gate model's arguments, `improve` by the names of `--improve`.
    fn gate(
        config: u32,
        eta: f64,
        publish_rate_hz: u32,
        no_angular_velocity: bool,
        improve: Vec<String>,
    ) -> PyResult<Self> {
        let changes = improve
            .iter()
            .map(|name| Improvement::named(name))
            .collect::<Result<Vec<_>, _>>()
            .map_err(value_error)?;
        Ok(Self {
            model: ModelOptions {
                config,
                eta,
                no_angular_velocity,
                improve: changes,
                ..ModelOptions::default()
            },
            publish_rate_hz,
            improve,
        })
    }

    /// The interaction model's arguments.
    fn interaction(config: u32, eta: f64, publish_rate_hz: u32, selector: &str) -> PyResult<Self> {
        Ok(Self {
            model: ModelOptions {
                config,
                eta,
                selector: registry::selector(selector).map_err(value_error)?,
                ..ModelOptions::default()
            },
            publish_rate_hz,
            improve: Vec::new(),
        })
    }
}

impl Options {
    /// The hybrid model's arguments, `parts` by the names of `--parts`.
    fn hybrid(publish_rate_hz: u32, parts: &str) -> PyResult<Self> {
        let parts = <registry::Parts as registry::Named>::from_name(parts).ok_or_else(|| {
            value_error(format!(
                "unknown parts '{parts}'; one of: {}",
                <registry::Parts as registry::Named>::names()
            ))
        })?;
        Ok(Self {
            model: ModelOptions {
                parts,
                ..ModelOptions::default()
            },
            publish_rate_hz,
            improve: Vec::new(),
        })
    }
}

/// The rows `[id, x, y, theta]` of `poses`: the actuator first, then the
/// blocks in ascending id order.
pub(crate) fn pose_rows<'py>(
    py: Python<'py>,
    poses: &Poses,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let mut flat = Vec::with_capacity(4 * (1 + poses.blocks.len()));
    let actuator = (pushlearn_core::ACTUATOR_ID, poses.actuator);
    for (id, s) in std::iter::once(actuator).chain(poses.blocks.iter().map(|(&i, &s)| (i, s))) {
        flat.extend_from_slice(&[f64::from(id), s.x, s.y, s.theta]);
    }
    let rows = flat.len() / 4;
    PyArray1::from_vec(py, flat).reshape([rows, 4])
}

/// `poses` for a `__repr__`.
pub(crate) fn poses_text(poses: &Poses) -> String {
    let a = poses.actuator;
    let blocks: Vec<String> = poses
        .blocks
        .iter()
        .map(|(id, s)| format!("{id}: ({:?}, {:?}, {:?})", s.x, s.y, s.theta))
        .collect();
    format!(
        "actuator=({:?}, {:?}, {:?}), blocks={{{}}}",
        a.x,
        a.y,
        a.theta,
        blocks.join(", ")
    )
}

/// Python's spelling of a bool.
fn py_bool(b: bool) -> &'static str {
    if b {
        "True"
    } else {
        "False"
    }
}

macro_rules! model_class {
    (
        model: $Model:ty,
        world: $World:ty,
        py_model: $PyModel:ident,
        py_world: $PyWorld:ident,
        model_name: $model_name:tt,
        world_name: $world_name:tt,
        model_doc: $model_doc:tt,
        world_doc: $world_doc:tt,
        kind: $kind:expr,
        config: $config:ident,
        constructor: { $($constructor:tt)* }
    ) => {
        #[doc = $world_doc]
        #[pyclass(module = "pushlearn._native", name = $world_name, frozen)]
        pub struct $PyWorld {
            world: $World,
        }

        #[pymethods]
        impl $PyWorld {
            /// The world's bodies as a float64 array of shape (n, 4), one row
            /// `[id, x, y, theta]` per body: the actuator (id 8) first, then
            /// the blocks in ascending id order (`Model::poses`).
            fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
                pose_rows(py, &<$Model as Model>::poses(&self.world))
            }

            fn __repr__(&self) -> String {
                format!(
                    "{}({})",
                    $world_name,
                    poses_text(&<$Model as Model>::poses(&self.world))
                )
            }
        }

        #[doc = $model_doc]
        #[pyclass(module = "pushlearn._native", name = $model_name)]
        #[derive(Clone)]
        pub struct $PyModel {
            model: $Model,
            /// The exploration generator `act` draws from.
            rng: ChaCha8Rng,
            /// The constructor's arguments, for `__repr__` and `name`.
            options: Options,
        }

        impl $PyModel {
            fn with_options(options: Options) -> PyResult<Self> {
                let config = options
                    .model
                    .$config(options.publish_rate_hz)
                    .map_err(value_error)?;
                Ok(Self {
                    model: <$Model>::new(config),
                    rng: ChaCha8Rng::seed_from_u64(0),
                    options,
                })
            }
        }

        #[pymethods]
        impl $PyModel {
            $($constructor)*

            /// The name reports give this model under its arguments, as
            /// `pushlearn experiment` names it: "gate", "gate+" (every
            /// change), "gate+CHANGE+…" or "interaction".
            #[getter]
            fn name(&self) -> String {
                self.options.model.report_name($kind)
            }

            /// Whether the driver reads the actuator's yaw as 0 for this
            /// model (`Model::actuator_yaw`; the learner protocol's
            /// `Hello.ignores_actuator_yaw`).
            #[getter]
            fn ignores_actuator_yaw(&self) -> bool {
                self.model.actuator_yaw() == learner::features::ActuatorYaw::ForceZero
            }

            /// Parse one world-state message into a world of this model
            /// (`Model::parse`).
            ///
            /// `bodies` lists every body of the message as
            /// `(name, id, (x, y, z), (qx, qy, qz, qw))`: the model's name,
            /// its id, its position in metres and its orientation quaternion
            /// in the order x, y, z, w; a fifth element, the body's
            /// `pushlearn.Shape` (or None), shows the model the body's
            /// shape, as the learner protocol's states do. The actuator is
            /// the body named "actuator" (id 8); blocks need an id of the
            /// learner's shape table (15 "blockA", 27 "blockB"). Parsing
            /// learns nothing.
            ///
            /// Raises ValueError with the parser's reason when the message
            /// has no actuator, an unknown or duplicate id, a non-finite
            /// number or a shape no world can have.
            fn parse(&self, bodies: Vec<Body>) -> PyResult<$PyWorld> {
                self.model
                    .parse(&args::frame(bodies))
                    .map(|world| $PyWorld { world })
                    .map_err(value_error)
            }

            /// Re-synchronise with `world` at the first message of a run,
            /// without learning (`Model::reset_objects`).
            fn reset_objects(&mut self, world: PyRef<'_, $PyWorld>) {
                self.model.reset_objects(&world.world);
            }

            /// Learn from the transition from the model's stored state into
            /// `world` under the action (vx, vy) in m/s that was in force
            /// meanwhile, then store `world` (`Model::update`). With
            /// training off only the stored state moves on.
            ///
            /// Raises ValueError if vx or vy is not finite.
            fn update(&mut self, world: PyRef<'_, $PyWorld>, vx: f64, vy: f64) -> PyResult<()> {
                let action = args::action(vx, vy)?;
                self.model.update(&world.world, action);
                Ok(())
            }

            /// The predicted world one message after `world` (parsed or
            /// itself a prediction) if the action (vx, vy) is in force
            /// (`Model::predict`). Learns nothing.
            ///
            /// Raises ValueError if vx or vy is not finite.
            fn predict(&self, world: PyRef<'_, $PyWorld>, vx: f64, vy: f64) -> PyResult<$PyWorld> {
                let action = args::action(vx, vy)?;
                Ok($PyWorld {
                    world: self.model.predict(&world.world, action),
                })
            }

            /// Turn training on (a new model's default) or off
            /// (`Model::set_training`).
            fn set_training(&mut self, on: bool) {
                self.model.set_training(on);
            }

            /// Whether `update` currently trains (`Model::is_training`).
            #[getter]
            fn is_training(&self) -> bool {
                self.model.is_training()
            }

            /// Set the Move-to-Target goal: block `id` at (x, y) m with yaw
            /// `theta` rad (`Model::set_target`).
            ///
            /// Raises ValueError with the model's reason (the actuator, a
            /// non-finite pose, an object the model cannot plan for); the
            /// previous target then stays in place.
            fn set_target(
                &mut self,
                id: Unsigned<u32>,
                x: f64,
                y: f64,
                theta: f64,
            ) -> PyResult<()> {
                let target = Target::new(id.0, learner::ObjectState::new(x, y, theta));
                self.model.set_target(Some(target)).map_err(value_error)
            }

            /// Clear the Move-to-Target goal (`Model::set_target(None)`).
            fn clear_target(&mut self) -> PyResult<()> {
                self.model.set_target(None).map_err(value_error)
            }

            /// Whether a target is set; `act` clears it once it finds the
            /// target reached (`Model::has_target`).
            #[getter]
            fn has_target(&self) -> bool {
                self.model.has_target()
            }

            /// Seed the exploration generator that `act` draws from:
            /// ChaCha8 seeded with `seed_from_u64(seed)`, as the experiment
            /// driver seeds each job's generator, so that `act` draws the
            /// same stream as an in-process run with that seed. A model
            /// that was never seeded uses seed 0.
            fn seed(&mut self, seed: Unsigned<u64>) {
                self.rng = ChaCha8Rng::seed_from_u64(seed.0);
            }

            /// The next action (vx, vy) in m/s towards the target from the
            /// model's stored state (`Model::act`); (0.0, 0.0) without a
            /// target or once it is reached, when the target is cleared.
            /// Its exploration fallback draws from the generator of `seed`.
            fn act(&mut self) -> (f64, f64) {
                let a = self.model.act(&mut self.rng);
                (a.vx, a.vy)
            }

            /// The model's statistics (`Model::stats`) in their serialised
            /// form: `{"maps": {name: {"update_calls": int, "inserts": int,
            /// "nodes": int}}, "extra": {name: float}, "labels": {name:
            /// str}}`.
            fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
                crate::stats_to_python(py, &self.model.stats())
            }

            /// A deep copy: the learned memory, the stored state, the
            /// target and the generator's state, shared with nothing (e.g.
            /// a fresh model for each fold from an untrained template).
            fn copy(&self) -> Self {
                self.clone()
            }
        }
    };
}

model_class! {
    model: learner::GateModel,
    world: learner::GateWorld,
    py_model: PyGateModel,
    py_world: PyGateWorld,
    model_name: "GateModel",
    world_name: "GateWorld",
    model_doc: "The object-state model with gating function (docs/spec/gate-model.md).

GateModel(config=0, eta=0.0, publish_rate_hz=100, no_angular_velocity=False, improve=())

config is the original's configuration number, the sum of its bits (1
USE_DYNS, 2 LOWFREQ, 4 and 8 driver-only, 16 HARDCODEDACT, 32 HARDCODEDGATE,
64 USINGPREDICTIONBOOST); eta the forward models' learning rate (0 in the
final thesis); publish_rate_hz the world's rate (10 selects the LOWFREQ
thresholds, as bit 2 does); no_angular_velocity leaves the block's angular
velocity out of the USE_DYNS features; improve names changes beyond the
thesis as --improve does: \"unrounded\", \"interpolate\", \"adapt-actuator\",
\"average-outputs\", \"forward-check\", \"shared-blocks\", or \"all\", which
is the command line's gate+ model (docs/models.md, \"Beyond the thesis\").
The checks and the texts of the ValueError they raise are the command
line's (`pushlearn learn --model gate`), from the same model registry.

Thread safety: a GateModel may be used from any thread (it is Send and Sync
in Rust); every method holds the GIL throughout, so calls from several
threads on one model run one after another.",
    world_doc: "A world state of the gate model, parsed or predicted (returned by
GateModel.parse and GateModel.predict; not constructible).

It holds the model's own world unchanged, including the identity of its
block records (docs/spec/gate-model.md §4.1): a block the model adopted as
its record shows the model's current state whenever it is read, as in the
original. Never rebuild a world from its poses.",
    kind: ModelKind::Gate,
    config: gate,
    constructor: {
        #[new]
        #[pyo3(
            signature = (config = Unsigned(0), eta = 0.0, publish_rate_hz = Unsigned(100), no_angular_velocity = false, improve = Vec::new()),
            text_signature = "(config=0, eta=0.0, publish_rate_hz=100, no_angular_velocity=False, improve=())"
        )]
        fn new(
            config: Unsigned<u32>,
            eta: f64,
            publish_rate_hz: Unsigned<u32>,
            no_angular_velocity: bool,
            improve: Vec<String>,
        ) -> PyResult<Self> {
            Self::with_options(Options::gate(
                config.0,
                eta,
                publish_rate_hz.0,
                no_angular_velocity,
                improve,
            )?)
        }

        fn __repr__(&self) -> String {
            let o = &self.options;
            // `improve` only when given, as a model without changes was
            // shown before it existed. The names are known ones (the
            // constructor checked them): nothing to escape.
            let improve = if o.improve.is_empty() {
                String::new()
            } else {
                let names: Vec<String> = o.improve.iter().map(|n| format!("'{n}'")).collect();
                format!(", improve=[{}]", names.join(", "))
            };
            format!(
                "GateModel(config={}, eta={:?}, publish_rate_hz={}, no_angular_velocity={}{improve})",
                o.model.config,
                o.model.eta,
                o.publish_rate_hz,
                py_bool(o.model.no_angular_velocity)
            )
        }
    }
}

model_class! {
    model: learner::InteractionModel,
    world: learner::InteractionWorld,
    py_model: PyInteractionModel,
    py_world: PyInteractionWorld,
    model_name: "InteractionModel",
    world_name: "InteractionWorld",
    model_doc: "The pairwise interaction-state model with Abstract Collections
(docs/spec/interaction-model.md).

InteractionModel(config=0, eta=0.0, publish_rate_hz=100, selector=\"aitm\")

config is the original's configuration number (only bit 2, LOWFREQ, and the
driver-only bits 4 and 8 apply); eta the Abstract Collections' learning rate
(0 in the final thesis); publish_rate_hz the world's rate (10 selects the
LOWFREQ thresholds, as bit 2 does); selector the Abstract Collection
Selector: \"aitm\" (final thesis), \"tree\", \"incremental-tree\" or \"nearest\"
(the thesis draft's variants). The checks and the texts of the ValueError
they raise are the command line's (`pushlearn learn --model interaction`).

Thread safety: an InteractionModel may be used from any thread (it is Send
and Sync in Rust); every method holds the GIL throughout, so calls from
several threads on one model run one after another.",
    world_doc: "A world state of the interaction model, parsed or predicted (returned by
InteractionModel.parse and InteractionModel.predict; not constructible): the
object states and the interaction states computed from them.",
    kind: ModelKind::Interaction,
    config: interaction,
    constructor: {
        #[new]
        #[pyo3(
            signature = (config = Unsigned(0), eta = 0.0, publish_rate_hz = Unsigned(100), selector = "aitm"),
            text_signature = "(config=0, eta=0.0, publish_rate_hz=100, selector='aitm')"
        )]
        fn new(
            config: Unsigned<u32>,
            eta: f64,
            publish_rate_hz: Unsigned<u32>,
            selector: &str,
        ) -> PyResult<Self> {
            Self::with_options(Options::interaction(
                config.0,
                eta,
                publish_rate_hz.0,
                selector,
            )?)
        }

        fn __repr__(&self) -> String {
            let o = &self.options;
            format!(
                "InteractionModel(config={}, eta={:?}, publish_rate_hz={}, selector='{}')",
                o.model.config,
                o.model.eta,
                o.publish_rate_hz,
                o.model.selector.as_str()
            )
        }
    }
}

model_class! {
    model: learner::HybridModel,
    world: learner::HybridWorld,
    py_model: PyHybridModel,
    py_world: PyHybridWorld,
    model_name: "HybridModel",
    world_name: "HybridWorld",
    model_doc: "Pushing mechanics identified online plus a memory of their residual
(docs/models.md, \"The hybrid model\"); not a model of the thesis.

HybridModel(publish_rate_hz=100, parts=\"full\")

publish_rate_hz is the world's rate; parts chooses the model's parts for its
ablation, as --parts does: \"mechanics\" (the shape's mechanics alone,
learning nothing), \"identified\" (their parameters identified online) or
\"full\" (and the memory of their residual). The checks and the texts of the
ValueError they raise are the command line's (`pushlearn learn --model
hybrid`).

Thread safety: a HybridModel may be used from any thread (it is Send and
Sync in Rust); every method holds the GIL throughout, so calls from several
threads on one model run one after another.",
    world_doc: "A world state of the hybrid model, parsed or predicted (returned by
HybridModel.parse and HybridModel.predict; not constructible): the poses and
each block's motion over the message before.",
    kind: ModelKind::Hybrid,
    config: hybrid,
    constructor: {
        #[new]
        #[pyo3(
            signature = (publish_rate_hz = Unsigned(100), parts = "full"),
            text_signature = "(publish_rate_hz=100, parts='full')"
        )]
        fn new(publish_rate_hz: Unsigned<u32>, parts: &str) -> PyResult<Self> {
            Self::with_options(Options::hybrid(publish_rate_hz.0, parts)?)
        }

        fn __repr__(&self) -> String {
            let o = &self.options;
            format!(
                "HybridModel(publish_rate_hz={}, parts='{}')",
                o.publish_rate_hz,
                o.model.parts.as_str()
            )
        }
    }
}
