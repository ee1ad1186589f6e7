//! `GoalTask`: the step of the Gymnasium goal environments
//! (`pushlearn.envs`), done in Rust: the action's checks, the Move and the
//! Advance, the observation's arrays, the goal distance, the reward, the
//! flags and the info, in one call per step (one environment) or per step
//! of all (the native vector environment).
//!
//! The arithmetic is the harness's: the yaw is the learners'
//! ([`crate::world::planar`]), the distance `learner::eval::goal_distance`
//! and success its `GOAL_TOLERANCE`, so a step gives the same bits the
//! Python step gave (`python/tests/test_env_trajectories.py` replays
//! episodes recorded from it). Episode starts stay in Python (`reset`
//! draws targets and poses; it is rare), which tells the task each new
//! target with [`PyGoalTask::restart`].

use std::sync::{Mutex, MutexGuard, PoisonError};

use learner::eval::{goal_distance, GOAL_TOLERANCE};
use learner::ObjectState;
use numpy::ndarray::Array2;
use numpy::{
    AllowTypeChange, IntoPyArray, PyArray1, PyArrayDyn, PyArrayLikeDyn, PyArrayMethods,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyRuntimeError;
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::args::{elements, shape_text, value_error, Unsigned};
use crate::world::{planar, step_together, PyWorld, COLUMNS};

/// What changes from step to step.
struct Episodes {
    /// Each world's target, `3k` values (x, y, θ per block).
    desired: Vec<f64>,
    /// Steps since each world's episode began.
    elapsed: Vec<u64>,
    /// Whether each world's episode ended at the last step (the vector
    /// environment restarts it at the next, Gymnasium's `NEXT_STEP`).
    ended: Vec<bool>,
    /// Whether each world's first episode has begun.
    started: Vec<bool>,
}

/// One step's results for every world, in the layout the arrays take.
struct Results {
    observation: Vec<f64>,
    achieved: Vec<f64>,
    desired: Vec<f64>,
    reward: Vec<f64>,
    terminated: Vec<bool>,
    truncated: Vec<bool>,
    success: Vec<bool>,
    distance: Vec<f64>,
}

/// A step's world(s) and how its results are judged (see the module
/// documentation).
#[pyclass(name = "GoalTask", module = "pushlearn._native", frozen)]
pub struct PyGoalTask {
    worlds: Vec<Py<PyWorld>>,
    actuator: usize,
    blocks: Vec<usize>,
    speed: f64,
    dense: bool,
    terminate_on_success: bool,
    max_episode_steps: Option<u64>,
    episodes: Mutex<Episodes>,
}

/// The numbers of an action-like argument and its shape: float32 and
/// float64 arrays read as they are (the common case, and the cheap one),
/// anything else converted by numpy.
fn floats(value: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    if let Ok(array) = value.cast::<PyArrayDyn<f32>>() {
        let array = array.readonly();
        let values = array.as_array().iter().map(|&v| f64::from(v)).collect();
        return Ok((array.shape().to_vec(), values));
    }
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = value.extract()?;
    Ok((array.shape().to_vec(), elements(&array).into_owned()))
}

/// An action's velocity (m/s): each component clipped to [−1, 1] and
/// scaled by `speed`.
fn velocity(ax: f64, ay: f64, speed: f64) -> (f64, f64) {
    (ax.clamp(-1.0, 1.0) * speed, ay.clamp(-1.0, 1.0) * speed)
}

impl PyGoalTask {
    fn episodes(&self) -> MutexGuard<'_, Episodes> {
        // Nothing is left half-written by a panic: every field is set whole.
        self.episodes.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn goal_values(&self) -> usize {
        3 * self.blocks.len()
    }

    /// Appends world `i`'s results from its `rows` and `desired` target.
    fn judge(&self, rows: &[f64], desired: &[f64], out: &mut Results) {
        let row = |i: usize| &rows[i * COLUMNS..(i + 1) * COLUMNS];
        let actuator = row(self.actuator);
        out.observation
            .extend([actuator[0], actuator[1], actuator[7], actuator[8]]);
        let mut success = true;
        let mut distance = 0.0;
        for (j, &b) in self.blocks.iter().enumerate() {
            let block = planar(row(b));
            out.observation.extend(block);
            out.achieved.extend(&block[..3]);
            let target = &desired[3 * j..3 * j + 3];
            let d = goal_distance(
                &ObjectState::new(block[0], block[1], block[2]),
                &ObjectState::new(target[0], target[1], target[2]),
            );
            success &= d < GOAL_TOLERANCE;
            distance += d;
        }
        out.desired.extend(desired);
        out.reward.push(if self.dense {
            -distance
        } else {
            f64::from(success) - 1.0
        });
        out.terminated.push(success && self.terminate_on_success);
        out.success.push(success);
        out.distance.push(distance);
    }

    fn results(&self) -> Results {
        let n = self.worlds.len();
        let width = 4 + 6 * self.blocks.len();
        Results {
            observation: Vec::with_capacity(n * width),
            achieved: Vec::with_capacity(n * self.goal_values()),
            desired: Vec::with_capacity(n * self.goal_values()),
            reward: Vec::with_capacity(n),
            terminated: Vec::with_capacity(n),
            truncated: Vec::with_capacity(n),
            success: Vec::with_capacity(n),
            distance: Vec::with_capacity(n),
        }
    }

    fn not_started() -> PyErr {
        PyRuntimeError::new_err("call reset() before step()")
    }
}

/// The goal environments' observation dict of `observation`, `achieved` and
/// `desired` (each `(n, width)` when `n` is given, else one row).
fn observation_dict<'py>(
    py: Python<'py>,
    results: Results,
    n: Option<usize>,
) -> PyResult<(Bound<'py, PyDict>, Results)> {
    let array = |values: Vec<f64>| -> PyResult<Bound<'py, PyAny>> {
        let width = match n {
            Some(n) if n > 0 => values.len() / n,
            _ => 0,
        };
        match n {
            // One array object, not a flat one and a view of it.
            Some(n) => Ok(Array2::from_shape_vec((n, width), values)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
                .into_pyarray(py)
                .into_any()),
            None => Ok(PyArray1::from_vec(py, values).into_any()),
        }
    };
    let mut results = results;
    let dict = PyDict::new(py);
    dict.set_item(
        intern!(py, "observation"),
        array(std::mem::take(&mut results.observation))?,
    )?;
    dict.set_item(
        intern!(py, "achieved_goal"),
        array(std::mem::take(&mut results.achieved))?,
    )?;
    dict.set_item(
        intern!(py, "desired_goal"),
        array(std::mem::take(&mut results.desired))?,
    )?;
    Ok((dict, results))
}

#[pymethods]
impl PyGoalTask {
    /// The task of `worlds` (one for an environment, all of a vector
    /// environment's), each of one scene: the actuator's row and the
    /// blocks' rows with a target, in the goals' order; `speed` the m/s of
    /// an action of 1; `dense` the dense reward (else sparse);
    /// `max_episode_steps` the steps after which `step_all` truncates an
    /// episode (`None`: never; an environment's time limit is
    /// `gymnasium.make`'s wrapper).
    #[new]
    #[pyo3(signature = (worlds, actuator, blocks, *, speed, dense, terminate_on_success, max_episode_steps = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        worlds: Vec<Py<PyWorld>>,
        actuator: usize,
        blocks: Vec<usize>,
        speed: f64,
        dense: bool,
        terminate_on_success: bool,
        max_episode_steps: Option<Unsigned<u64>>,
    ) -> PyResult<Self> {
        let Some(first) = worlds.first() else {
            return Err(value_error("GoalTask needs at least one World"));
        };
        let bodies = first.get().body_count();
        if let Some(other) = worlds.iter().position(|w| w.get().body_count() != bodies) {
            return Err(value_error(format!(
                "every world must have the same bodies: world 0 has {bodies}, world {other} has {}",
                worlds[other].get().body_count()
            )));
        }
        if let Some(row) = blocks.iter().chain([&actuator]).find(|&&r| r >= bodies) {
            return Err(value_error(format!(
                "row {row} is not a body of the world (it has {bodies})"
            )));
        }
        if blocks.is_empty() {
            return Err(value_error("a goal task needs at least one block"));
        }
        if !(speed.is_finite() && speed > 0.0) {
            return Err(value_error(format!(
                "speed must be a finite speed > 0, got {speed}"
            )));
        }
        let max_episode_steps = match max_episode_steps {
            Some(Unsigned(0)) => {
                return Err(value_error("max_episode_steps must be ≥ 1 or None, got 0"))
            }
            other => other.map(|Unsigned(steps)| steps),
        };
        let n = worlds.len();
        let episodes = Episodes {
            desired: vec![0.0; n * 3 * blocks.len()],
            elapsed: vec![0; n],
            ended: vec![false; n],
            started: vec![false; n],
        };
        Ok(PyGoalTask {
            worlds,
            actuator,
            blocks,
            speed,
            dense,
            terminate_on_success,
            max_episode_steps,
            episodes: Mutex::new(episodes),
        })
    }

    /// World `i`'s episode began (its `reset` is done) with target `desired`
    /// (x, y, θ per block).
    fn restart(&self, i: usize, desired: PyArrayLikeDyn<'_, f64, AllowTypeChange>) -> PyResult<()> {
        let k = self.goal_values();
        if i >= self.worlds.len() {
            return Err(value_error(format!(
                "world {i} of {} does not exist",
                self.worlds.len()
            )));
        }
        if desired.shape() != [k] {
            return Err(value_error(format!(
                "desired must have {k} numbers (x, y, θ per block), got an array of shape {}",
                shape_text(desired.shape())
            )));
        }
        let mut episodes = self.episodes();
        episodes.desired[i * k..(i + 1) * k].copy_from_slice(&elements(&desired));
        episodes.elapsed[i] = 0;
        episodes.ended[i] = false;
        episodes.started[i] = true;
        Ok(())
    }

    /// One environment's step (the task of one world): `action` (2 numbers,
    /// clipped to [−1, 1]) as a Move of `speed · action` m/s with the
    /// Advance to the next state; returns `(observation, reward, terminated,
    /// False, info)` as `gymnasium.Env.step` does. Truncation is the time
    /// limit wrapper's.
    fn step<'py>(
        &self,
        py: Python<'py>,
        action: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
        if self.worlds.len() != 1 {
            return Err(value_error(format!(
                "step is the step of one world; this task has {}: use step_all",
                self.worlds.len()
            )));
        }
        let (shape, values) = floats(action)?;
        if shape != [2] {
            return Err(value_error(format!(
                "an action has shape (2,), got {}",
                shape_text(&shape)
            )));
        }
        let (ax, ay) = (values[0], values[1]);
        if !(ax.is_finite() && ay.is_finite()) {
            return Err(value_error(format!(
                "an action must be finite, got [{ax}, {ay}]"
            )));
        }
        let desired = {
            let episodes = self.episodes();
            if !episodes.started[0] {
                return Err(Self::not_started());
            }
            episodes.desired.clone()
        };
        let mv = velocity(ax, ay, self.speed);
        let mut results = self.results();
        py.detach(|| {
            step_together(&self.worlds, &[mv], &[true], |_, rows| {
                self.judge(rows, &desired, &mut results);
            })
        })?;
        let info = PyDict::new(py);
        info.set_item(intern!(py, "is_success"), results.success[0])?;
        info.set_item(intern!(py, "distance"), results.distance[0])?;
        let (reward, terminated) = (results.reward[0], results.terminated[0]);
        let (observation, _) = observation_dict(py, results, None)?;
        (observation, reward, terminated, false, info).into_pyobject(py)
    }

    /// A step of every world: `actions` of shape `(n, 2)`. A world whose
    /// episode ended at the last step is not stepped (its action ignored):
    /// Python restarts it. Returns `(observations, rewards, terminations,
    /// truncations, infos)` batched as a Gymnasium vector environment's
    /// step, and the list of the worlds to restart, whose entries are
    /// Python's to fill.
    fn step_all<'py>(
        &self,
        py: Python<'py>,
        actions: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, pyo3::types::PyTuple>, Bound<'py, PyList>)> {
        let n = self.worlds.len();
        let (shape, values) = floats(actions)?;
        if shape != [n, 2] {
            return Err(value_error(format!(
                "actions must have shape ({n}, 2), got {}",
                shape_text(&shape)
            )));
        }
        let bad: Vec<usize> = (0..n)
            .filter(|&i| !(values[2 * i].is_finite() && values[2 * i + 1].is_finite()))
            .collect();
        if !bad.is_empty() {
            return Err(value_error(format!(
                "the actions of environments {bad:?} are not finite"
            )));
        }
        let (desired, restarting) = {
            let episodes = self.episodes();
            if !episodes.started.iter().all(|&s| s) {
                return Err(Self::not_started());
            }
            (episodes.desired.clone(), episodes.ended.clone())
        };
        let moves: Vec<(f64, f64)> = (0..n)
            .map(|i| velocity(values[2 * i], values[2 * i + 1], self.speed))
            .collect();
        let stepped: Vec<bool> = restarting.iter().map(|&r| !r).collect();
        let k = self.goal_values();
        let mut results = self.results();
        py.detach(|| {
            step_together(&self.worlds, &moves, &stepped, |i, rows| {
                self.judge(rows, &desired[i * k..(i + 1) * k], &mut results);
            })
        })?;
        {
            let mut episodes = self.episodes();
            for (i, &restarted) in restarting.iter().enumerate() {
                let truncated = if restarted {
                    results.reward[i] = 0.0;
                    results.terminated[i] = false;
                    episodes.elapsed[i] = 0;
                    false
                } else {
                    episodes.elapsed[i] += 1;
                    !results.terminated[i]
                        && self
                            .max_episode_steps
                            .is_some_and(|max| episodes.elapsed[i] >= max)
                };
                results.truncated.push(truncated);
                episodes.ended[i] = results.terminated[i] || truncated;
            }
        }
        let every = || PyArray1::from_vec(py, vec![true; n]);
        let infos = PyDict::new(py);
        infos.set_item(
            intern!(py, "is_success"),
            PyArray1::from_slice(py, &results.success),
        )?;
        infos.set_item(intern!(py, "_is_success"), every())?;
        infos.set_item(
            intern!(py, "distance"),
            PyArray1::from_slice(py, &results.distance),
        )?;
        infos.set_item(intern!(py, "_distance"), every())?;
        let (observations, results) = observation_dict(py, results, Some(n))?;
        let step = (
            observations,
            PyArray1::from_vec(py, results.reward),
            PyArray1::from_vec(py, results.terminated),
            PyArray1::from_vec(py, results.truncated),
            infos,
        )
            .into_pyobject(py)?;
        let restart = (0..n).filter(|&i| restarting[i]).collect::<Vec<_>>();
        Ok((step, PyList::new(py, restart)?))
    }

    /// The number of worlds.
    fn __len__(&self) -> usize {
        self.worlds.len()
    }
}
