//! `pushlearn.bench`'s engine: the thesis's experiments run from Python on
//! the same worlds, seeds, driver and reports as `pushlearn experiment`,
//! from the same arguments: `pushlearn.bench` spells its keywords as the
//! command's options, and they go through the command's own parser and
//! lowering (`lab::args`) to the same validated spec and plan, run with
//! the options' learner or a Python `Learner` object called directly.
//!
//! A Python learner reaches the driver as [`PyLearner`], a
//! [`learner::Model`] whose calls go to `pushlearn.bench._Direct`, the
//! learner protocol's dispatch without the protocol: the same `State` and
//! `Prediction` objects, the same checks of what the learner returns
//! (`pushlearn.learner`'s own), in the order the driver makes its calls. So
//! its reports equal those of the same learner served to `pushlearn
//! experiment --learner`, bit for bit (`python/tests/test_bench.py`).
//!
//! The driver runs on a thread of its own; every learner call is made on
//! the thread that called `pushlearn.bench` (the main thread, normally),
//! which waits for the calls and polls for signals in between. So Ctrl-C
//! reaches learner code at once, a learner call can be given a deadline
//! (SIGALRM, set by `pushlearn.bench`), and the run stops within moments
//! when interrupted.
//!
//! The report is assembled here and handed to Python as a [`Report`] whose
//! data only Rust holds: learner code, which shares the interpreter, has no
//! reference to it and runs before it exists (`docs/learner-protocol.md` §1,
//! "In-process").

use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};
use std::time::{Duration, Instant};

use drive::experiment::run::Plan;
use drive::external::{predicted_poses, stats_of, LearnerChoice};
use drive::results::LearnerRecord;
use lab::args::{ArgsError, Lowered};
use lab::report::layout::Printout;
use lab::spec::{Document, SpecError, Valid};
use learner::features::{parse_frame, ActuatorYaw, ParseError};
use learner::{Action, BodyShape, Frame, Model, ModelStats, Poses, Target, TargetError};
use prost::Message;
use pushlearn::wire::pb::learner as lp;
use pyo3::exceptions::{
    PyException, PyKeyError, PyOSError, PyRuntimeError, PyTimeoutError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use serde::{Deserialize, Serialize};

/// What the learner's start said about it (as a Hello would).
#[derive(Debug)]
struct Info {
    name: String,
    version: String,
    ignores_actuator_yaw: bool,
}

/// A learner call the driver's thread asks the calling thread to make:
/// `_Direct.call(method, args, timeout)`.
struct CallRequest {
    method: &'static str,
    args: Py<PyTuple>,
    answer: mpsc::Sender<PyResult<Py<PyAny>>>,
}

/// What the driver's thread sends the thread that called `pushlearn.bench`.
enum ToCaller {
    Call(CallRequest),
    Done(Box<Result<Document, SpecError>>),
}

/// What every fold's handle on the one learner object shares.
#[derive(Debug)]
struct Shared {
    /// The `_Direct` adapter around the user's learner.
    direct: Py<PyAny>,
    info: Info,
    /// Where learner calls are made: the calling thread's loop in [`run`].
    caller: Mutex<mpsc::Sender<ToCaller>>,
    /// Set when the caller has gone (interrupted): from then on the
    /// driver's thread touches no Python object, not even to make a call's
    /// arguments (the interpreter may be exiting).
    stopped: Arc<AtomicBool>,
    /// The first exception a learner call raised: re-raised as the cause of
    /// the experiment's error, with its traceback.
    raised: Mutex<Option<PyErr>>,
}

/// A Python learner as a [`Model`]; see the module documentation. A clone
/// is a fresh handle on the same object, as a fold needs: the learner
/// forgets on `new_fold`.
#[derive(Debug)]
pub struct PyLearner {
    shared: Arc<Shared>,
    failure: RefCell<Option<String>>,
    training: bool,
    has_target: bool,
    /// Whether the driver has handed this handle a fold yet.
    in_fold: Cell<bool>,
}

impl Clone for PyLearner {
    fn clone(&self) -> Self {
        Self::handle(Arc::clone(&self.shared))
    }
}

/// The learner lives in Python: there is nothing to save or restore.
impl Serialize for PyLearner {
    fn serialize<S: serde::Serializer>(&self, _: S) -> Result<S::Ok, S::Error> {
        Err(serde::ser::Error::custom(format!(
            "learner '{}' is a Python object; it cannot be saved",
            self.shared.info.name
        )))
    }
}

impl<'de> Deserialize<'de> for PyLearner {
    fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom(
            "a Python learner object cannot be restored",
        ))
    }
}

/// A world as [`PyLearner`] sees it: the poses the driver checks and
/// scores, and the Python object the learner gets (`State` or its own
/// `Prediction`), made when the learner first needs it and the same object
/// every time after.
#[derive(Clone, Debug)]
pub struct PyWorldState {
    poses: Poses,
    frame: Option<Arc<Frame>>,
    object: Arc<OnceLock<Py<PyAny>>>,
}

impl PyLearner {
    /// Starts `direct` (a `pushlearn.bench._Direct`) for `task`, reading the
    /// learner's name, version and capabilities as its hello would give them.
    fn start(
        py: Python<'_>,
        direct: Py<PyAny>,
        task: &str,
        publish_rate_hz: u32,
        caller: mpsc::Sender<ToCaller>,
        stopped: Arc<AtomicBool>,
    ) -> PyResult<Self> {
        let (name, version, inverse, ignores_actuator_yaw): (String, String, bool, bool) = direct
            .call_method1(py, "start", (task, publish_rate_hz))?
            .extract(py)?;
        if task == "move-to-target" && !inverse {
            return Err(PyValueError::new_err(format!(
                "learner '{name}' cannot run move-to-target: it does not declare \
                 Capability.INVERSE (actions towards a target)"
            )));
        }
        Ok(Self::handle(Arc::new(Shared {
            direct,
            info: Info {
                name,
                version,
                ignores_actuator_yaw,
            },
            caller: Mutex::new(caller),
            stopped,
            raised: Mutex::new(None),
        })))
    }

    fn handle(shared: Arc<Shared>) -> Self {
        Self {
            shared,
            failure: RefCell::new(None),
            training: true,
            has_target: false,
            in_fold: Cell::new(false),
        }
    }

    fn failed(&self) -> bool {
        self.failure.borrow().is_some()
    }

    /// Keeps the first failure; the driver ends the job with it.
    fn fail(&self, what: String, err: Option<PyErr>) {
        let mut failure = self.failure.borrow_mut();
        if failure.is_some() {
            return;
        }
        *failure = Some(what);
        if let Some(err) = err {
            let mut raised = self
                .shared
                .raised
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            raised.get_or_insert(err);
        }
    }

    /// Calls `_Direct.method(args)`, reading its answer with `read`; `None`
    /// once failed, or when the call raised (then recorded as the failure).
    fn call<T>(
        &self,
        method: &'static str,
        args: impl FnOnce(Python<'_>) -> PyResult<Py<pyo3::types::PyTuple>>,
        read: impl FnOnce(Python<'_>, Bound<'_, PyAny>) -> PyResult<T>,
    ) -> Option<T> {
        if self.failed() {
            return None;
        }
        if !self.in_fold.get() {
            self.fail(
                "the driver called the learner outside a fold (no start_fold)".into(),
                None,
            );
            return None;
        }
        let outcome = (|| {
            let stopped = || PyRuntimeError::new_err("the run was stopped");
            if self.shared.stopped.load(Ordering::SeqCst) {
                return Err(stopped());
            }
            let args = Python::attach(args)?;
            let (answer, answered) = mpsc::channel();
            self.shared
                .caller
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .send(ToCaller::Call(CallRequest {
                    method,
                    args,
                    answer,
                }))
                .map_err(|_| stopped())?;
            let answer = answered.recv().map_err(|_| stopped())??;
            Python::attach(|py| read(py, answer.into_bound(py)))
        })();
        match outcome {
            Ok(value) => Some(value),
            Err(err) => {
                let text = Python::attach(|py| describe(py, &err));
                self.fail(format!("{method}() raised {text}"), Some(err));
                None
            }
        }
    }

    /// The Python object for `world`: an observed state made into a `State`
    /// once, a prediction the learner's own object.
    fn object(&self, py: Python<'_>, world: &PyWorldState) -> PyResult<Py<PyAny>> {
        if let Some(object) = world.object.get() {
            return Ok(object.clone_ref(py));
        }
        let frame = world
            .frame
            .as_ref()
            .ok_or_else(|| PyRuntimeError::new_err("a prediction without its object"))?;
        let bodies: Vec<_> = frame
            .objects
            .iter()
            .map(|o| {
                let shape = o.shape.map(|shape| match shape {
                    BodyShape::Sphere { radius } => ("sphere", vec![radius]),
                    BodyShape::Box { size } => ("box", size.to_vec()),
                    BodyShape::Cylinder { radius, length } => ("cylinder", vec![radius, length]),
                });
                (o.name.clone(), o.id, o.position, o.orientation, shape)
            })
            .collect();
        let state = self
            .shared
            .direct
            .bind(py)
            .call_method1("observed", (bodies,))?
            .unbind();
        Ok(world.object.get_or_init(|| state).clone_ref(py))
    }

    /// The learner's statistics from the protocol's form, which
    /// `_Direct.stats` makes with the SDK's own checks.
    fn read_stats(bytes: &[u8]) -> Result<ModelStats, String> {
        let stats = lp::Stats::decode(bytes).map_err(|e| format!("unreadable statistics: {e}"))?;
        stats_of(stats)
    }
}

/// One body of a prediction as `_Direct.predict` lists them: `(id, x, y, theta)`.
type PredictedBody = (u32, f64, f64, f64);

/// `TypeName: text` of an exception, as the learner protocol reports one.
fn describe(py: Python<'_>, err: &PyErr) -> String {
    let name = err
        .get_type(py)
        .name()
        .map_or_else(|_| "Exception".to_owned(), |n| n.to_string());
    format!("{name}: {}", err.value(py))
}

impl Model for PyLearner {
    type World = PyWorldState;

    fn parse(&self, frame: &Frame) -> Result<PyWorldState, ParseError> {
        Ok(PyWorldState {
            poses: parse_frame(frame, self.actuator_yaw())?,
            frame: Some(Arc::new(frame.clone())),
            object: Arc::new(OnceLock::new()),
        })
    }

    fn poses(world: &PyWorldState) -> Poses {
        world.poses.clone()
    }

    fn reset_objects(&mut self, world: &PyWorldState) {
        self.call(
            "reset",
            |py| {
                (self.object(py, world)?,)
                    .into_pyobject(py)
                    .map(Bound::unbind)
            },
            |_, _| Ok(()),
        );
    }

    fn update(&mut self, world: &PyWorldState, a: Action) {
        self.call(
            "update",
            |py| {
                (self.object(py, world)?, a.vx, a.vy)
                    .into_pyobject(py)
                    .map(Bound::unbind)
            },
            |_, _| Ok(()),
        );
    }

    fn predict(&self, world: &PyWorldState, a: Action) -> PyWorldState {
        let answer = self.call(
            "predict",
            |py| {
                (self.object(py, world)?, a.vx, a.vy)
                    .into_pyobject(py)
                    .map(Bound::unbind)
            },
            |_, answer| answer.extract::<(Py<PyAny>, Vec<PredictedBody>)>(),
        );
        let neutral = || PyWorldState {
            poses: world.poses.clone(),
            frame: None,
            object: world.object.clone(),
        };
        let Some((object, bodies)) = answer else {
            return neutral();
        };
        match predicted_poses(bodies, &world.poses) {
            Ok(poses) => PyWorldState {
                poses,
                frame: None,
                object: Arc::new(OnceLock::from(object)),
            },
            Err(what) => {
                self.fail(format!("predict(): the learner {what}"), None);
                neutral()
            }
        }
    }

    fn set_training(&mut self, on: bool) {
        self.training = on;
        self.call(
            "set_training",
            |py| (on,).into_pyobject(py).map(Bound::unbind),
            |_, _| Ok(()),
        );
    }

    fn is_training(&self) -> bool {
        self.training
    }

    fn set_target(&mut self, target: Option<Target>) -> Result<(), TargetError> {
        if let Some(t) = &target {
            t.check()?;
        }
        let goal = target.map(|t| (t.id, t.pose.x, t.pose.y, t.pose.theta));
        let refusal = self.call(
            "set_target",
            |py| (goal,).into_pyobject(py).map(Bound::unbind),
            |_, answer| answer.extract::<Option<String>>(),
        );
        match refusal {
            Some(None) => {
                self.has_target = target.is_some();
                Ok(())
            }
            Some(Some(reason)) => {
                self.fail(format!("the learner refused the target: {reason}"), None);
                Err(TargetError::UnknownObject {
                    id: target.map_or(0, |t| t.id),
                })
            }
            // Failed: the driver stops at the end of this message.
            None => Ok(()),
        }
    }

    fn has_target(&self) -> bool {
        self.has_target
    }

    /// The learner explores with its own generator (seeded by `new_fold`),
    /// so `rng` is not drawn from, as with any external learner.
    fn act(&mut self, _rng: &mut dyn rand::Rng) -> Action {
        let chosen = self.call(
            "act",
            |py| Ok(pyo3::types::PyTuple::empty(py).unbind()),
            |_, answer| answer.extract::<(f64, f64, bool)>(),
        );
        match chosen {
            Some((vx, vy, has_target)) => {
                self.has_target = has_target;
                Action::new(vx, vy)
            }
            None => Action::ZERO,
        }
    }

    fn stats(&self) -> ModelStats {
        let bytes = self.call(
            "stats",
            |py| Ok(pyo3::types::PyTuple::empty(py).unbind()),
            |_, answer| answer.extract::<Vec<u8>>(),
        );
        match bytes.map(|b| Self::read_stats(&b)) {
            Some(Ok(stats)) => stats,
            Some(Err(what)) => {
                self.fail(format!("stats(): the learner {what}"), None);
                ModelStats::default()
            }
            None => ModelStats::default(),
        }
    }

    fn actuator_yaw(&self) -> ActuatorYaw {
        if self.shared.info.ignores_actuator_yaw {
            ActuatorYaw::ForceZero
        } else {
            ActuatorYaw::Keep
        }
    }

    fn start_fold(&mut self, seed: u64) {
        self.training = true;
        self.has_target = false;
        self.in_fold.set(true);
        self.call(
            "new_fold",
            |py| (seed,).into_pyobject(py).map(Bound::unbind),
            |_, _| Ok(()),
        );
    }

    fn failure(&self) -> Option<String> {
        self.failure.borrow().as_ref().map(|what| {
            format!(
                "learner '{}' (a Python object): {what}",
                self.shared.info.name
            )
        })
    }
}

/// How often the calling thread looks for signals (Ctrl-C) while the
/// driver steps worlds: a run stops within this of the signal.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `spec` with `learner` (a `pushlearn.bench._Direct` of a learner
/// object) when given, else with the spec's own learner; `progress(done,
/// jobs)` is called after each job; each learner call may take `timeout`.
fn run(
    py: Python<'_>,
    spec: Valid,
    learner: Option<&Bound<'_, PyAny>>,
    mut plan: Plan,
    progress: Option<Py<PyAny>>,
    timeout: f64,
) -> PyResult<Document> {
    if !(timeout.is_finite() && timeout > 0.0) {
        return Err(PyValueError::new_err(format!(
            "timeout must be a positive number of seconds, not {timeout}"
        )));
    }
    let (to_caller, from_driver) = mpsc::channel::<ToCaller>();
    // Once set, the driver's thread calls no Python: the caller has gone.
    let stopped = Arc::new(AtomicBool::new(false));
    // Behind a lock only so that the wait can release the GIL.
    let from_driver = Mutex::new(from_driver);
    let direct = match learner {
        None => None,
        Some(learner) => {
            let model = PyLearner::start(
                py,
                learner.clone().unbind(),
                spec.task(),
                spec.publish_rate_hz().unwrap_or(drive::scene::RATE_HZ),
                to_caller.clone(),
                Arc::clone(&stopped),
            )?;
            model.shared.info.name.clone_into(&mut plan.model);
            plan.learner = Some(LearnerRecord {
                version: model.shared.info.version.clone(),
                source: "pushlearn.bench, in-process".to_owned(),
            });
            Some(model)
        }
    };
    // The first exception of the progress callback ends the run once the
    // job under way is done.
    let interrupted: Arc<Mutex<Option<PyErr>>> = Arc::new(Mutex::new(None));
    let jobs = spec.jobs();
    let report = {
        let (stopped, interrupted) = (Arc::clone(&stopped), Arc::clone(&interrupted));
        move |done: usize| {
            let Some(callback) = &progress else { return };
            if stopped.load(Ordering::SeqCst) {
                return;
            }
            Python::attach(|py| {
                if let Err(err) = callback.call1(py, (done, jobs)) {
                    interrupted
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner)
                        .get_or_insert(err);
                }
            });
        }
    };
    let shared = direct.as_ref().map(|d| Arc::clone(&d.shared));
    let driver = std::thread::Builder::new()
        .name("pushlearn-bench".into())
        .spawn(move || {
            let outcome = match direct {
                Some(model) => spec.run_with(&plan, model, report),
                None => spec.run(&plan, report),
            };
            // The caller may have gone (interrupted): nobody to tell.
            let _ = to_caller.send(ToCaller::Done(Box::new(outcome)));
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start the run: {e}")))?;
    let outcome = loop {
        let next = py.detach(|| {
            from_driver
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .recv_timeout(SIGNAL_POLL)
        });
        match next {
            Ok(ToCaller::Call(call)) => {
                let Some(shared) = &shared else { continue };
                let answer = learner_call(py, &shared.direct, &call, timeout);
                if let Err(err) = &answer {
                    if !err.is_instance_of::<PyException>(py) {
                        // KeyboardInterrupt, SystemExit: the run ends now,
                        // with the exception itself; the driver's thread
                        // finds the channel closed and winds down.
                        stopped.store(true, Ordering::SeqCst);
                        return Err(err.clone_ref(py));
                    }
                }
                // The driver waits for the answer unless it failed.
                let _ = call.answer.send(answer);
            }
            Ok(ToCaller::Done(outcome)) => break *outcome,
            Err(RecvTimeoutError::Timeout) => {
                if let Err(err) = py.check_signals() {
                    stopped.store(true, Ordering::SeqCst);
                    return Err(err);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                break Err(SpecError::Invalid(
                    "the run's thread ended without a result".into(),
                ))
            }
        }
    };
    // It has sent its result: what is left of it ends at once.
    let _ = py.detach(|| driver.join());
    if let Some(err) = interrupted
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .take()
    {
        return Err(err);
    }
    let document = match outcome {
        Ok(document) => document,
        Err(err) => {
            let cause = shared.and_then(|shared| {
                shared
                    .raised
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .take()
            });
            if let Some(cause) = &cause {
                if !cause.is_instance_of::<PyException>(py) {
                    return Err(cause.clone_ref(py));
                }
            }
            let error = PyRuntimeError::new_err(err.to_string());
            error.set_cause(py, cause);
            return Err(error);
        }
    };
    Ok(document)
}

/// Makes one learner call on this thread: `_Direct.call(method, args,
/// timeout)`, which sets the deadline where it can (SIGALRM, main thread
/// only). A call that returned but took longer fails all the same.
fn learner_call(
    py: Python<'_>,
    direct: &Py<PyAny>,
    call: &CallRequest,
    timeout: f64,
) -> PyResult<Py<PyAny>> {
    let started = Instant::now();
    let answer = direct
        .bind(py)
        .call_method1("call", (call.method, call.args.bind(py), timeout))?;
    if started.elapsed().as_secs_f64() > timeout {
        return Err(PyTimeoutError::new_err(format!(
            "no answer within {timeout} s (it returned after {:.1} s)",
            started.elapsed().as_secs_f64()
        )));
    }
    Ok(answer.unbind())
}

/// A cell of a report's table: a number, a text, or none.
#[derive(Clone, Debug)]
enum Entry {
    Int(i64),
    Float(f64),
    Text(String),
    Empty,
}

impl Entry {
    /// A CSV field read as `pushlearn experiment --csv`'s reader would:
    /// empty, an integer, a float, or text.
    fn of(field: &str) -> Entry {
        if field.is_empty() {
            Entry::Empty
        } else if let Ok(i) = field.parse::<i64>() {
            Entry::Int(i)
        } else if let Ok(f) = field.parse::<f64>() {
            Entry::Float(f)
        } else {
            Entry::Text(field.to_owned())
        }
    }

    fn to_python<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self {
            Entry::Int(i) => i.into_pyobject(py)?.into_any(),
            Entry::Float(f) => f.into_pyobject(py)?.into_any(),
            Entry::Text(t) => t.into_pyobject(py)?.into_any(),
            Entry::Empty => py.None().into_bound(py),
        })
    }
}

/// A JSON value as the Python objects `json.loads` gives, made here: learner
/// code may have replaced `json.loads` by the time a report is read.
fn json_to_python<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => pyo3::types::PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            (None, None) => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_python(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (key, item) in map {
                dict.set_item(key, json_to_python(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

/// One table of a report, as `pushlearn experiment --csv` writes it; see
/// `pushlearn.bench.Table`.
#[pyclass(frozen, module = "pushlearn._native", name = "Table")]
pub struct Table {
    name: String,
    title: String,
    columns: Vec<String>,
    rows: Vec<Vec<Entry>>,
}

#[pymethods]
impl Table {
    /// The table's name (the CSV file's: `learning-curve`, …).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The lines printed above it.
    #[getter]
    fn title(&self) -> &str {
        &self.title
    }

    /// The column names, in order.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.columns.clone()
    }

    /// The rows: dicts by column name, numbers as int or float, empty cells
    /// `None` (`pandas.DataFrame(table.rows)` takes them as they are); a new
    /// list every time.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let rows = PyList::empty(py);
        for row in &self.rows {
            let dict = PyDict::new(py);
            for (column, entry) in self.columns.iter().zip(row) {
                dict.set_item(column, entry.to_python(py)?)?;
            }
            rows.append(dict)?;
        }
        Ok(rows)
    }

    fn __repr__(&self) -> String {
        format!("Table({:?}, {} rows)", self.name, self.rows.len())
    }
}

/// What an experiment gave: its report document and its tables; see
/// `pushlearn.bench.Report`. Built here from the driver's results after the
/// run, and kept here: Python gets copies.
#[pyclass(frozen, module = "pushlearn._native", name = "Report")]
pub struct Report {
    json: String,
    printed: String,
    tables: Vec<Py<Table>>,
}

impl Report {
    fn of(document: &Document, printout: &Printout) -> PyResult<Report> {
        let json = document
            .to_json()
            .map_err(|e| PyRuntimeError::new_err(format!("cannot serialise the report: {e}")))?;
        let mut text = Vec::new();
        printout
            .write_text(&mut text)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let tables = Python::attach(|py| {
            printout
                .tables
                .iter()
                .map(|t| {
                    let (columns, rows) = t.csv_fields();
                    Py::new(
                        py,
                        Table {
                            name: t.name.clone(),
                            title: t.title.join("\n"),
                            columns,
                            rows: rows
                                .iter()
                                .map(|row| row.iter().map(|f| Entry::of(f)).collect())
                                .collect(),
                        },
                    )
                })
                .collect::<PyResult<Vec<_>>>()
        })?;
        Ok(Report {
            json,
            printed: String::from_utf8_lossy(&text).into_owned(),
            tables,
        })
    }
}

#[pymethods]
impl Report {
    /// The JSON document `pushlearn experiment --json` writes, as a dict (a
    /// new one every time).
    #[getter]
    fn document<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let value: serde_json::Value = serde_json::from_str(&self.json)
            .map_err(|e| PyRuntimeError::new_err(format!("the report's document: {e}")))?;
        json_to_python(py, &value)
    }

    /// The tables `pushlearn experiment` prints, beside the thesis's numbers.
    #[getter]
    fn tables(&self, py: Python<'_>) -> Vec<Py<Table>> {
        self.tables.iter().map(|t| t.clone_ref(py)).collect()
    }

    /// The text `pushlearn experiment` prints: every table, with the thesis's numbers.
    #[getter]
    fn printed(&self) -> &str {
        &self.printed
    }

    /// The table called `name`; `KeyError` naming the tables there are if none is.
    fn table(&self, py: Python<'_>, name: &str) -> PyResult<Py<Table>> {
        if let Some(table) = self.tables.iter().find(|t| t.get().name == name) {
            return Ok(table.clone_ref(py));
        }
        let names: Vec<&str> = self.tables.iter().map(|t| t.get().name.as_str()).collect();
        Err(PyKeyError::new_err(format!(
            "the report has no table '{name}' (it has: {})",
            names.join(", ")
        )))
    }

    /// The document as `pushlearn experiment --json` writes it.
    fn to_json(&self) -> &str {
        &self.json
    }

    /// What `pushlearn experiment` prints for the experiment.
    fn text(&self) -> &str {
        &self.printed
    }

    fn __repr__(&self) -> String {
        let names: Vec<&str> = self.tables.iter().map(|t| t.get().name.as_str()).collect();
        format!("Report(tables: {})", names.join(", "))
    }
}

/// `pushlearn experiment COMMAND WORDS…` run in this process (see
/// `pushlearn.bench`): `words` are the command's options, parsed and
/// lowered by the command's own parser (`lab::args`), so the bench takes
/// every option the command takes and refuses what it refuses, with its
/// messages. `learner` is a `pushlearn.bench._Direct` around a learner
/// object, run in place of the options' learner, or `None`.
#[pyfunction]
#[pyo3(signature = (command, words, *, learner, progress, timeout))]
pub fn run_experiment(
    py: Python<'_>,
    command: &str,
    words: Vec<String>,
    learner: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    timeout: f64,
) -> PyResult<Report> {
    let refused = |err: ArgsError| PyValueError::new_err(err.to_string());
    let args = lab::args::parse(command, &words).map_err(refused)?;
    let given = learner.map(|_| LearnerChoice::InProcess);
    let Lowered { spec, world } = args.lower_with(given.as_ref()).map_err(refused)?;
    world.check_outputs().map_err(refused)?;
    // No worker processes: they are the `pushlearn` program re-started,
    // which an interpreter is not.
    let mut plan = world.plan(spec.scene(), &|_| Ok(None)).map_err(refused)?;
    if learner.is_some() {
        // One learner object: its folds one after the other.
        plan.workers = 1;
    }
    let document = run(py, spec, learner, plan, progress, timeout)?;
    let printout = document
        .printout()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let report = Report::of(&document, &printout)?;
    world
        .write_outputs(&document, &printout)
        .map_err(|e| PyOSError::new_err(e.to_string()))?;
    Ok(report)
}

/// One option as `experiment_options` gives it: `(name, switch, values,
/// default)`, the name without `--`.
type OptionTuple = (String, bool, Vec<String>, Vec<String>);

/// The experiment options of `pushlearn experiment COMMAND`, from the
/// command's definition. For `pushlearn.bench`'s tests and documentation.
#[pyfunction]
pub fn experiment_options(command: &str) -> PyResult<Vec<OptionTuple>> {
    let options = lab::args::options(command).ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown experiment '{command}'; expected push-task or move-to-target"
        ))
    })?;
    Ok(options
        .into_iter()
        .map(|o| (o.long, o.switch, o.values, o.default))
        .collect())
}

/// A report document without its machine-dependent part (wall time,
/// handling times, workers), so that two runs compare equal; the JSON in,
/// the JSON out.
#[pyfunction]
pub fn without_timing(document: &str) -> PyResult<String> {
    let document = Document::read(document).map_err(|e| PyValueError::new_err(e.to_string()))?;
    document
        .without_timing()
        .to_json()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}
