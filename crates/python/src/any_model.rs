//! `Model` / `ModelWorld`: any model of the registry by its name, with its
//! options by keyword (`Model(name, parts=…)`), so that a model
//! added to the registry is in Python with no binding of its own.
//!
//! The registry builds the model ([`ModelKind::dispatch`]); this module
//! hides its type behind [`Erased`], and a world behind `Any`, checked
//! back to the model's world type on every call that takes one.

use std::any::Any;
use std::sync::{Mutex, MutexGuard};

use learner::features::ActuatorYaw;
use learner::registry::{ModelKind, ModelOptions, Named, WithModel};
use learner::{Action, Frame, Model, ModelStats, ParseError, Poses, Target, TargetError};
use numpy::PyArray2;
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value};

use crate::args::{self, value_error, Body, Unsigned};
use crate::models::{pose_rows, poses_text};

/// A world of some model.
type AnyWorld = Box<dyn Any + Send>;

/// The poses of a world of one model type; `None` for another's world.
type PosesOf = fn(&AnyWorld) -> Option<Poses>;

/// A model of the registry with its type hidden: [`Model`]'s methods, the
/// worlds as [`AnyWorld`]. `None` where a world of another model was
/// given.
trait Erased: Send {
    fn parse(&self, frame: &Frame) -> Result<AnyWorld, ParseError>;
    fn poses_of(&self) -> PosesOf;
    fn reset_objects(&mut self, world: &AnyWorld) -> Option<()>;
    fn update(&mut self, world: &AnyWorld, action: Action) -> Option<()>;
    fn predict(&self, world: &AnyWorld, action: Action) -> Option<AnyWorld>;
    fn set_training(&mut self, on: bool);
    fn is_training(&self) -> bool;
    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError>;
    fn has_target(&self) -> bool;
    fn act(&mut self, rng: &mut ChaCha8Rng) -> Action;
    fn stats(&self) -> ModelStats;
    fn actuator_yaw(&self) -> ActuatorYaw;
    fn boxed_clone(&self) -> Box<dyn Erased>;
}

fn poses_of<M: Model + 'static>(world: &AnyWorld) -> Option<Poses> {
    world.downcast_ref::<M::World>().map(M::poses)
}

impl<M: Model + 'static> Erased for M {
    fn parse(&self, frame: &Frame) -> Result<AnyWorld, ParseError> {
        Ok(Box::new(Model::parse(self, frame)?))
    }
    fn poses_of(&self) -> PosesOf {
        poses_of::<M>
    }
    fn reset_objects(&mut self, world: &AnyWorld) -> Option<()> {
        Model::reset_objects(self, world.downcast_ref()?);
        Some(())
    }
    fn update(&mut self, world: &AnyWorld, action: Action) -> Option<()> {
        Model::update(self, world.downcast_ref()?, action);
        Some(())
    }
    fn predict(&self, world: &AnyWorld, action: Action) -> Option<AnyWorld> {
        Some(Box::new(Model::predict(
            self,
            world.downcast_ref()?,
            action,
        )))
    }
    fn set_training(&mut self, on: bool) {
        Model::set_training(self, on);
    }
    fn is_training(&self) -> bool {
        Model::is_training(self)
    }
    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        Model::set_target(self, target)
    }
    fn has_target(&self) -> bool {
        Model::has_target(self)
    }
    fn act(&mut self, rng: &mut ChaCha8Rng) -> Action {
        Model::act(self, rng)
    }
    fn stats(&self) -> ModelStats {
        Model::stats(self)
    }
    fn actuator_yaw(&self) -> ActuatorYaw {
        Model::actuator_yaw(self)
    }
    fn boxed_clone(&self) -> Box<dyn Erased> {
        Box::new(self.clone())
    }
}

/// The registry's job that hides the type of the model it builds.
struct Erase;

impl WithModel for Erase {
    type Output = Box<dyn Erased>;
    fn run<M: Model + 'static>(self, untrained: M) -> Box<dyn Erased> {
        Box::new(untrained)
    }
}

/// The options `Model` takes by keyword: the fields of the registry's
/// [`ModelOptions`], spelt with underscores, in the registry's order.
fn option_names() -> PyResult<Vec<String>> {
    match serde_json::to_value(ModelOptions::default()) {
        Ok(Value::Object(fields)) => Ok(fields.keys().map(|k| k.replace('-', "_")).collect()),
        _ => Err(PyRuntimeError::new_err(
            "the registry's options do not serialise as a map",
        )),
    }
}

/// `options` (Python keywords) as the registry's [`ModelOptions`]. The
/// lists (`flags`, `improve`) may also be given as one comma-separated
/// string, as on the command line.
fn model_options(py: Python<'_>, options: Option<&Bound<'_, PyDict>>) -> PyResult<ModelOptions> {
    let known = option_names()?;
    let mut fields = Map::new();
    if let Some(options) = options {
        let json = py.import("json")?;
        for (key, value) in options.iter() {
            let key: String = key.extract()?;
            if !known.contains(&key) {
                return Err(PyTypeError::new_err(format!(
                    "unknown model option '{key}'; the options are: {}",
                    known.join(", ")
                )));
            }
            let text: String = json.call_method1("dumps", (value,))?.extract()?;
            let mut value: Value = serde_json::from_str(&text).map_err(value_error)?;
            if let (Value::String(list), "flags" | "improve") = (&value, key.as_str()) {
                value = list.split(',').map(|n| Value::from(n.trim())).collect();
            }
            fields.insert(key.replace('_', "-"), value);
        }
    }
    serde_json::from_value(Value::Object(fields))
        .map_err(|e| PyValueError::new_err(format!("model options: {e}")))
}

/// The model kind called `name`, or ValueError listing the kinds there are.
fn kind(name: &str) -> PyResult<ModelKind> {
    ModelKind::from_name(name).ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown model '{name}'; one of: {}",
            ModelKind::names()
        ))
    })
}

/// The registry's models by name, in its order.
#[pyfunction]
pub fn model_names() -> Vec<&'static str> {
    ModelKind::ALL.iter().map(|k| k.name()).collect()
}

/// The keyword options `Model` takes (every model's; each model refuses
/// those that do not apply to it).
#[pyfunction]
pub fn model_options_names() -> PyResult<Vec<String>> {
    option_names()
}

/// A world state of a `Model`, parsed or predicted (returned by
/// Model.parse and Model.predict; not constructible). It belongs to the
/// model that made it: another model's methods refuse it.
#[pyclass(module = "pushlearn._native", name = "ModelWorld", frozen)]
pub struct PyModelWorld {
    world: Mutex<AnyWorld>,
    poses: PosesOf,
    model: String,
}

impl PyModelWorld {
    fn world(&self) -> PyResult<MutexGuard<'_, AnyWorld>> {
        self.world
            .lock()
            .map_err(|_| PyRuntimeError::new_err("a world was poisoned by a panic"))
    }

    /// The poses of the world; `None` never happens for a world of the
    /// model that made it.
    fn poses_now(&self) -> PyResult<Poses> {
        (self.poses)(&*self.world()?)
            .ok_or_else(|| PyRuntimeError::new_err("a world lost its model's type"))
    }
}

#[pymethods]
impl PyModelWorld {
    /// The world's bodies as a float64 array of shape (n, 4), one row
    /// `[id, x, y, theta]` per body: the actuator (id 8) first, then the
    /// blocks in ascending id order (`Model::poses`).
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        pose_rows(py, &self.poses_now()?)
    }

    /// The report name of the model that made this world.
    #[getter]
    fn model(&self) -> String {
        self.model.clone()
    }

    fn __repr__(&self) -> PyResult<String> {
        Ok(format!(
            "ModelWorld(model='{}', {})",
            self.model,
            poses_text(&self.poses_now()?)
        ))
    }
}

/// Any model of the registry by its name: Model(name, publish_rate_hz=100,
/// **options).
///
/// name is a model of `pushlearn experiment --model` (model_names() lists
/// them); the options are the command line's model options by keyword,
/// spelt with underscores (model_options_names() lists them: config,
/// flags, eta, selector, no_angular_velocity, improve, parts), with the
/// command line's names for their values; flags and improve take a list
/// or one comma-separated string. An unknown model or option raises
/// ValueError or TypeError naming it; an option the model does not take,
/// or a bad value, raises ValueError with the command line's reason.
///
/// The methods are those of the typed classes (one per model), with worlds
/// of type ModelWorld. Thread safety as theirs.
#[pyclass(module = "pushlearn._native", name = "Model")]
pub struct PyModel {
    model: Mutex<Box<dyn Erased>>,
    rng: ChaCha8Rng,
    kind: ModelKind,
    options: ModelOptions,
    publish_rate_hz: u32,
}

impl PyModel {
    fn model(&self) -> PyResult<MutexGuard<'_, Box<dyn Erased>>> {
        self.model
            .lock()
            .map_err(|_| PyRuntimeError::new_err("a model was poisoned by a panic"))
    }

    fn world_of(&self, world: AnyWorld, poses: PosesOf) -> PyModelWorld {
        PyModelWorld {
            world: Mutex::new(world),
            poses,
            model: self.name(),
        }
    }

    /// The error for a world another model made.
    fn foreign(&self, world: &PyModelWorld) -> PyErr {
        PyTypeError::new_err(format!(
            "a world of the {} model given to the {} model",
            world.model,
            self.name()
        ))
    }
}

#[pymethods]
impl PyModel {
    #[new]
    #[pyo3(signature = (name, publish_rate_hz = Unsigned(100), **options), text_signature = "(name, publish_rate_hz=100, **options)")]
    fn new(
        py: Python<'_>,
        name: &str,
        publish_rate_hz: Unsigned<u32>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let kind = kind(name)?;
        let options = model_options(py, options)?;
        let model = kind
            .dispatch(&options, publish_rate_hz.0, Erase)
            .map_err(value_error)?;
        Ok(Self {
            model: Mutex::new(model),
            rng: ChaCha8Rng::seed_from_u64(0),
            kind,
            options,
            publish_rate_hz: publish_rate_hz.0,
        })
    }

    /// The name reports give this model under its options, as `pushlearn
    /// experiment` names it (`ModelOptions::report_name`).
    #[getter]
    fn name(&self) -> String {
        self.options.report_name(self.kind)
    }

    /// The model's kind: the name it was built by.
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind.name()
    }

    /// The options in the canonical line of the memory the command line
    /// stores (`ModelOptions::canonical`).
    #[getter]
    fn options(&self) -> String {
        self.options.canonical()
    }

    /// Whether the driver reads the actuator's yaw as 0 for this model.
    #[getter]
    fn ignores_actuator_yaw(&self) -> PyResult<bool> {
        Ok(self.model()?.actuator_yaw() == ActuatorYaw::ForceZero)
    }

    /// Parse one world-state message into a world of this model
    /// (`Model::parse`): `bodies` as `(name, id, (x, y, z), (qx, qy, qz,
    /// qw))`, optionally a fifth element, the body's Shape. Learns nothing;
    /// ValueError with the parser's reason.
    fn parse(&self, bodies: Vec<Body>) -> PyResult<PyModelWorld> {
        let model = self.model()?;
        let world = model.parse(&args::frame(bodies)).map_err(value_error)?;
        Ok(self.world_of(world, model.poses_of()))
    }

    /// Re-synchronise with `world` at the first message of a run, without
    /// learning.
    fn reset_objects(&mut self, world: PyRef<'_, PyModelWorld>) -> PyResult<()> {
        let done = self.model()?.reset_objects(&*world.world()?);
        done.ok_or_else(|| self.foreign(&world))
    }

    /// Learn from the transition from the stored state into `world` under
    /// the action (vx, vy) in m/s, then store `world` (`Model::update`).
    fn update(&mut self, world: PyRef<'_, PyModelWorld>, vx: f64, vy: f64) -> PyResult<()> {
        let action = args::action(vx, vy)?;
        let done = self.model()?.update(&*world.world()?, action);
        done.ok_or_else(|| self.foreign(&world))
    }

    /// The predicted world one message after `world` if the action
    /// (vx, vy) is in force. Learns nothing.
    fn predict(&self, world: PyRef<'_, PyModelWorld>, vx: f64, vy: f64) -> PyResult<PyModelWorld> {
        let action = args::action(vx, vy)?;
        let model = self.model()?;
        let predicted = model.predict(&*world.world()?, action);
        let predicted = predicted.ok_or_else(|| self.foreign(&world))?;
        Ok(self.world_of(predicted, model.poses_of()))
    }

    /// Turn training on (a new model's default) or off.
    fn set_training(&mut self, on: bool) -> PyResult<()> {
        self.model()?.set_training(on);
        Ok(())
    }

    /// Whether `update` currently trains.
    #[getter]
    fn is_training(&self) -> PyResult<bool> {
        Ok(self.model()?.is_training())
    }

    /// Set the Move-to-Target goal: block `id` at (x, y) m with yaw
    /// `theta` rad; ValueError with the model's reason.
    fn set_target(&mut self, id: Unsigned<u32>, x: f64, y: f64, theta: f64) -> PyResult<()> {
        let target = Target::new(id.0, learner::ObjectState::new(x, y, theta));
        self.model()?.set_target(Some(target)).map_err(value_error)
    }

    /// Clear the Move-to-Target goal.
    fn clear_target(&mut self) -> PyResult<()> {
        self.model()?.set_target(None).map_err(value_error)
    }

    /// Whether a target is set.
    #[getter]
    fn has_target(&self) -> PyResult<bool> {
        Ok(self.model()?.has_target())
    }

    /// Seed the exploration generator that `act` draws from: ChaCha8 with
    /// `seed_from_u64(seed)`, as the experiment driver seeds each job's.
    fn seed(&mut self, seed: Unsigned<u64>) {
        self.rng = ChaCha8Rng::seed_from_u64(seed.0);
    }

    /// The next action (vx, vy) in m/s towards the target.
    fn act(&mut self) -> PyResult<(f64, f64)> {
        let model = self
            .model
            .get_mut()
            .map_err(|_| PyRuntimeError::new_err("a model was poisoned by a panic"))?;
        let a = model.act(&mut self.rng);
        Ok((a.vx, a.vy))
    }

    /// The model's statistics (`Model::stats`) in their serialised form:
    /// `{"maps": {…}, "extra": {…}, "labels": {…}}`.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::stats_to_python(py, &self.model()?.stats())
    }

    /// A deep copy, shared with nothing.
    fn copy(&self) -> PyResult<Self> {
        Ok(Self {
            model: Mutex::new(self.model()?.boxed_clone()),
            rng: self.rng.clone(),
            kind: self.kind,
            options: self.options.clone(),
            publish_rate_hz: self.publish_rate_hz,
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Model('{}', publish_rate_hz={}) [{}]",
            self.kind.name(),
            self.publish_rate_hz,
            self.options.canonical()
        )
    }
}
