//! `pushlearn._native`: the Rust models as a Python extension module (PyO3,
//! built by maturin from the root `pyproject.toml`; the Python package around
//! it lives in `python/pushlearn/`, its type stubs in
//! `python/pushlearn/_native.pyi`).
//!
//! * `GateModel` / `GateWorld`, `InteractionModel` / `InteractionWorld`,
//!   `HybridModel` / `HybridWorld`: the learners, one method per
//!   [`learner::Model`] method
//!   (`models.rs`), configured by the model registry
//!   (`learner::registry`) as the command line's models are;
//! * `Aitm`: the memory-based regressor and classifier (`aitm.rs`);
//! * `World`, `Worlds`, `step_messages`: the world of `pushlearn-sim` in
//!   the process (`world.rs`);
//! * `GoalTask`: the Gymnasium environments' step (`task.rs`);
//! * `run_experiment`, `experiment_options`, `without_timing`: the
//!   experiments of `pushlearn experiment`, their arguments parsed by the
//!   command's own parser (`lab::args`), with the options' learner or a
//!   Python learner object, for `pushlearn.bench` (`bench.rs`).
//!
//! Nothing here is `unsafe`: the crate inherits the workspace's
//! `unsafe_code = "forbid"` and needs no exception. The FFI stays inside pyo3
//! and numpy; the `unsafe` blocks PyO3's macros generate are spanned in the
//! macro's own code, which the lint does not flag (`docs/architecture.md`).
//!
//! Every class is `Send + Sync` (PyO3 requires it of a class that is not
//! `unsendable`), so Python may use an object from any thread. The models'
//! methods hold the GIL, so calls on one object from several threads run one
//! after another; the worlds release it while they step.

mod aitm;
mod any_model;
mod args;
mod bench;
mod models;
mod task;
mod world;

use learner::ModelStats;
use pyo3::prelude::*;
use serde_json::to_string;

/// `stats` in their serialised form (`{maps, extra, labels}`) through
/// `serde_json` and Python's `json.loads`: plain dicts, strings and numbers.
fn stats_to_python<'py>(py: Python<'py>, stats: &ModelStats) -> PyResult<Bound<'py, PyAny>> {
    let text = to_string(stats)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("cannot serialise: {e}")))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Raises ValueError, with the experiment driver's reason, unless `document`
/// (the JSON of `{maps, extra, labels}`) is statistics the driver accepts
/// from a learner: a built-in model's map names only in that model's
/// complete statistics (`docs/learner-protocol.md` §3, "Statistics").
#[pyfunction]
fn check_stats(document: &str) -> PyResult<()> {
    serde_json::from_str::<ModelStats>(document)
        .map(|_| ())
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
}

/// The norm of a block's `(Δx, Δy, wrap(Δθ))` to its target: the one
/// success criterion the harness judges every task with a goal by
/// (`learner::eval::goal_distance`; reached below `GOAL_TOLERANCE`).
#[pyfunction]
fn goal_distance(pose: (f64, f64, f64), target: (f64, f64, f64)) -> f64 {
    let state = |(x, y, theta)| learner::ObjectState::new(x, y, theta);
    learner::eval::goal_distance(&state(pose), &state(target))
}

/// [`goal_distance`] of every block of every row: `achieved` and `desired`
/// of shape `(n, 3k)` (x, y, θ per block), the result `(n, k)`. The native
/// vector environment judges all its worlds with one call.
#[pyfunction]
fn goal_distances<'py>(
    py: Python<'py>,
    achieved: numpy::PyReadonlyArray2<'py, f64>,
    desired: numpy::PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    use numpy::{PyArrayMethods, PyUntypedArrayMethods};
    let shape = achieved.shape();
    if shape != desired.shape() || shape[1] % 3 != 0 {
        return Err(args::value_error(format!(
            "goals must have one shape (n, 3k); got {} and {}",
            args::shape_text(shape),
            args::shape_text(desired.shape())
        )));
    }
    let (n, k) = (shape[0], shape[1] / 3);
    let (a, d) = (achieved.as_array(), desired.as_array());
    let state = |row: &numpy::ndarray::ArrayView2<'_, f64>, i: usize, j: usize| {
        learner::ObjectState::new(row[[i, 3 * j]], row[[i, 3 * j + 1]], row[[i, 3 * j + 2]])
    };
    let mut out = Vec::with_capacity(n * k);
    for i in 0..n {
        for j in 0..k {
            out.push(learner::eval::goal_distance(
                &state(&a, i, j),
                &state(&d, i, j),
            ));
        }
    }
    numpy::PyArray1::from_vec(py, out).reshape([n, k])
}

/// The yaw of the quaternion `(x, y, z, w)` as the learners read it
/// (`pushlearn_core::orientation::yaw`): the SDK's pure-Python
/// `quaternion_to_yaw` is tested against this one bit for bit.
#[pyfunction]
fn quaternion_to_yaw(x: f64, y: f64, z: f64, w: f64) -> f64 {
    pushlearn_core::orientation::yaw([x, y, z, w])
}

/// The quaternion `(x, y, z, w)` of a rotation by `theta` about z
/// (`pushlearn_core::orientation::from_yaw`).
#[pyfunction]
fn yaw_to_quaternion(theta: f64) -> (f64, f64, f64, f64) {
    let [x, y, z, w] = pushlearn_core::orientation::from_yaw(theta);
    (x, y, z, w)
}

/// Whether the learners skip a body of this name (`pushlearn_core::is_skipped`).
#[pyfunction]
fn is_skipped(name: &str) -> bool {
    pushlearn_core::is_skipped(name)
}

thread_local! {
    /// The worlds' locks, held by the forking thread from just before a
    /// fork until just after it, in the parent and in the child.
    static FORK_HOLD: std::cell::RefCell<Option<sim_plugin::server::ForkHold>> =
        const { std::cell::RefCell::new(None) };
}

/// `os.register_at_fork(before=…)`: waits until no world of this process is
/// being stepped and keeps it so until the fork is done, so that the child
/// inherits no lock held by a thread it does not have.
#[pyfunction]
fn _before_fork() {
    let hold = sim_plugin::server::hold_for_fork();
    FORK_HOLD.with(|held| *held.borrow_mut() = Some(hold));
}

/// `os.register_at_fork(after_in_parent=…, after_in_child=…)`.
#[pyfunction]
fn _after_fork() {
    FORK_HOLD.with(|held| held.borrow_mut().take());
}

/// The pushlearn models, implemented in Rust: GateModel, InteractionModel,
/// HybridModel (with their worlds GateWorld, InteractionWorld and
/// HybridWorld) and Aitm; and World, the world of pushlearn-sim in this
/// process.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_before_fork, m)?)?;
    m.add_function(wrap_pyfunction!(_after_fork, m)?)?;
    let hooks = pyo3::types::PyDict::new(m.py());
    hooks.set_item("before", m.getattr("_before_fork")?)?;
    hooks.set_item("after_in_parent", m.getattr("_after_fork")?)?;
    hooks.set_item("after_in_child", m.getattr("_after_fork")?)?;
    m.py()
        .import("os")?
        .call_method("register_at_fork", (), Some(&hooks))?;
    m.add_class::<models::PyGateModel>()?;
    m.add_class::<models::PyGateWorld>()?;
    m.add_class::<models::PyInteractionModel>()?;
    m.add_class::<models::PyHybridModel>()?;
    m.add_class::<models::PyInteractionWorld>()?;
    m.add_class::<models::PyHybridWorld>()?;
    m.add_class::<any_model::PyModel>()?;
    m.add_class::<any_model::PyModelWorld>()?;
    m.add_function(wrap_pyfunction!(any_model::model_names, m)?)?;
    m.add_function(wrap_pyfunction!(any_model::model_options_names, m)?)?;
    m.add_class::<aitm::PyAitm>()?;
    m.add_class::<world::PyWorld>()?;
    m.add_class::<world::PyWorlds>()?;
    m.add_class::<task::PyGoalTask>()?;
    m.add_function(wrap_pyfunction!(world::step_messages, m)?)?;
    m.add_function(wrap_pyfunction!(bench::run_experiment, m)?)?;
    m.add_function(wrap_pyfunction!(bench::experiment_options, m)?)?;
    m.add_function(wrap_pyfunction!(bench::without_timing, m)?)?;
    m.add_class::<bench::Report>()?;
    m.add_class::<bench::Table>()?;
    m.add_function(wrap_pyfunction!(check_stats, m)?)?;
    m.add_function(wrap_pyfunction!(goal_distance, m)?)?;
    m.add_function(wrap_pyfunction!(goal_distances, m)?)?;
    m.add("GOAL_TOLERANCE", learner::eval::GOAL_TOLERANCE)?;
    // The vocabulary the pure-Python SDK (`pushlearn.learner`) repeats so
    // that it works without the extension; its tests compare the two.
    m.add_function(wrap_pyfunction!(quaternion_to_yaw, m)?)?;
    m.add_function(wrap_pyfunction!(yaw_to_quaternion, m)?)?;
    m.add_function(wrap_pyfunction!(is_skipped, m)?)?;
    m.add("ACTUATOR_ID", pushlearn_core::ACTUATOR_ID)?;
    m.add("ACTUATOR_NAME", pushlearn_core::ACTUATOR_NAME)?;
    m.add("BLUE_ID", pushlearn_core::BLUE_ID)?;
    m.add("RED_ID", pushlearn_core::RED_ID)?;
    m.add("MAX_POSITION", pushlearn_core::MAX_POSITION)?;
    // Where the extension was built: the Gymnasium environments look for the
    // checkout's own `target/release/pushlearn-sim` after `PUSHLEARN_SIM_BIN`
    // and `PATH`, so that `pip install .` after `cargo build --release` needs
    // no further set-up.
    m.add(
        "SOURCE_CHECKOUT",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
    )?;
    Ok(())
}
