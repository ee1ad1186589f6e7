//! `World` and `Worlds`: the pushing world of `pushlearn-sim` inside the
//! Python process.
//!
//! A `World` is the daemon's lock-step world for one client
//! ([`sim_plugin::server::EmbeddedWorld`]): every command is the protocol
//! message a `SimClient` would send, checked on arrival by the daemon's own
//! checks (the wire's, the scene's, the admission's) and applied by the same
//! lock-step stepper with the same latency emulation, so the same commands
//! give the same states bit for bit as over a socket. Anything the daemon
//! would refuse with an `Error` raises `ValueError` with the daemon's text,
//! and nothing reaches ODE unchecked (its assertions abort the process).
//!
//! The state comes back as one float64 array, a row per dynamic body in
//! scene order ([`COLUMNS`]), or as the daemon's `WorldState` message bytes,
//! ghosts included.
//!
//! Stepping releases the GIL. ODE steps one world at a time per process
//! (`ode::World::step` takes a process-wide lock and swaps in each world's
//! own random generator state), so worlds stepped from several Python threads
//! take turns and each stays bit-identical to a world stepped alone.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError, TryLockError};
use std::time::Instant;

use numpy::{
    AllowTypeChange, PyArray2, PyArray3, PyArrayLikeDyn, PyArrayMethods, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use prost::Message;
use pushlearn::wire::pb::{self, client_message::Payload, server_message};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use sim_plugin::server::{EmbeddedWorld, Latency};
use sim_plugin::Scene;

use crate::args::{elements, shape_text, value_error, Unsigned};

/// The values of a body's row in a state array: position (x, y, z),
/// orientation quaternion (x, y, z, w), linear velocity (x, y, z) and
/// angular velocity (x, y, z), world frame.
pub const COLUMNS: usize = 13;

/// The values of a body's row in a planar state array: x, y, yaw (as the
/// learners read it, `pushlearn_core::orientation::yaw`), vx, vy and the
/// spin about z: what a pushing task on the table sees.
pub const PLANAR_COLUMNS: usize = 6;

/// A body's row ([`COLUMNS`] values) as its planar row ([`PLANAR_COLUMNS`]).
pub fn planar(r: &[f64]) -> [f64; PLANAR_COLUMNS] {
    let yaw = pushlearn_core::orientation::yaw([r[3], r[4], r[5], r[6]]);
    [r[0], r[1], yaw, r[7], r[8], r[12]]
}

/// `rows` ([`COLUMNS`] each) as the caller asked for them, and the number
/// of columns.
fn view(rows: &[f64], planar: bool) -> (Vec<f64>, usize) {
    if !planar {
        return (rows.to_vec(), COLUMNS);
    }
    let mut out = Vec::with_capacity(rows.len() / COLUMNS * PLANAR_COLUMNS);
    for r in rows.chunks_exact(COLUMNS) {
        out.extend(self::planar(r));
    }
    (out, PLANAR_COLUMNS)
}

/// The `N` numbers of a 1-D array argument called `name` (`what` names
/// them); the world's own checks judge their values.
fn numbers<const N: usize>(
    name: &str,
    what: &str,
    array: &PyArrayLikeDyn<'_, f64, AllowTypeChange>,
) -> PyResult<[f64; N]> {
    let shape = array.shape();
    let wrong = || {
        value_error(format!(
            "{name} must be {N} numbers ({what}), got an array of shape {}",
            shape_text(shape)
        ))
    };
    if shape != [N] {
        return Err(wrong());
    }
    <[f64; N]>::try_from(&elements(array)[..]).map_err(|_| wrong())
}

/// The latest published state, as the daemon would have sent it.
struct Published {
    message: pb::WorldState,
    /// The dynamic bodies' rows ([`COLUMNS`] values each), scene order.
    rows: Vec<f64>,
}

impl Published {
    fn new(message: pb::WorldState, bodies: usize) -> Published {
        let mut rows = Vec::with_capacity(bodies * COLUMNS);
        let models = message.model_v.as_ref().map_or(&[][..], |v| &v.models[..]);
        // Dynamic bodies come first, in scene order; the ghosts after them
        // are static.
        for model in models.iter().filter(|m| !m.is_static).take(bodies) {
            let pose = model.pose.unwrap_or_default();
            let p = pose.position.unwrap_or_default();
            let q = pose.orientation.unwrap_or_default();
            let v = model.lin_vel.unwrap_or_default();
            let w = model.ang_vel.unwrap_or_default();
            rows.extend([
                p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z,
            ]);
        }
        Published { message, rows }
    }
}

/// Why a command did not do what it was asked; becomes a Python exception.
#[derive(Debug, thiserror::Error)]
pub enum Failure {
    /// The daemon's checks refused it (its `Error` text): `ValueError`.
    #[error("{0}")]
    Refused(String),
    /// The physics diverged (the world reset itself) or failed: `RuntimeError`.
    #[error("{0}")]
    Physics(String),
}

impl Failure {
    /// The failure as world `i` of a `Worlds` had it.
    fn in_world(self, i: usize) -> Failure {
        match self {
            Failure::Refused(text) => Failure::Refused(format!("world {i}: {text}")),
            Failure::Physics(text) => Failure::Physics(format!("world {i}: {text}")),
        }
    }
}

impl From<Failure> for PyErr {
    fn from(failure: Failure) -> PyErr {
        match failure {
            Failure::Refused(text) => PyValueError::new_err(text),
            Failure::Physics(text) => PyRuntimeError::new_err(text),
        }
    }
}

/// The world and its client's side of the conversation.
pub struct Session {
    world: EmbeddedWorld,
    /// The last seq sent (the commands are numbered as a `SimClient` does).
    seq: u64,
    bodies: usize,
    last: Option<Published>,
}

impl Session {
    /// Sends `payload` as the next message and takes what the daemon would
    /// answer: the first `Error` becomes the failure, states are kept.
    fn send(&mut self, payload: Payload) -> Result<u64, Failure> {
        self.seq += 1;
        let seq = self.seq;
        let message = pb::ClientMessage::new(seq, payload);
        self.world
            .send(&message)
            .map_err(|e| Failure::Physics(e.to_string()))?;
        let mut failure = None;
        while let Some(answer) = self.world.next_message() {
            match answer.payload {
                Some(server_message::Payload::WorldState(state)) => {
                    self.last = Some(Published::new(state, self.bodies));
                }
                Some(server_message::Payload::Error(error)) if failure.is_none() => {
                    failure = Some(if error.kind() == pb::error::Kind::PhysicsBlewUp {
                        Failure::Physics(error.message)
                    } else {
                        Failure::Refused(error.message)
                    });
                }
                Some(_) | None => {}
            }
        }
        failure.map_or(Ok(seq), Err)
    }

    fn published(&self) -> Result<&Published, Failure> {
        self.last
            .as_ref()
            .ok_or_else(|| Failure::Refused("no state yet: advance the world first".to_owned()))
    }

    /// The last published state's rows ([`COLUMNS`] each, scene order).
    pub fn rows(&self) -> Result<&[f64], Failure> {
        self.published().map(|p| &p.rows[..])
    }

    pub fn move_and_advance(&mut self, vx: f64, vy: f64) -> Result<(), Failure> {
        self.send(Payload::move_(vx, vy))?;
        self.send(Payload::advance())?;
        Ok(())
    }

    /// Whether [`Session::move_and_advance`] would be accepted: the Move and
    /// the Advance as the world would check them now (a Move changes
    /// nothing the Advance's check reads).
    fn check_move_and_advance(&self, vx: f64, vy: f64) -> Result<(), Failure> {
        for (offset, payload) in [(1, Payload::move_(vx, vy)), (2, Payload::advance())] {
            let message = pb::ClientMessage::new(self.seq + offset, payload);
            self.world.check(&message).map_err(Failure::Refused)?;
        }
        Ok(())
    }
}

/// The lock-step world of `pushlearn-sim serve --mode lockstep` in this
/// process (see the module documentation).
#[pyclass(name = "World", module = "pushlearn._native", frozen)]
pub struct PyWorld {
    session: Mutex<Session>,
    /// The process that last used the world: after a fork, the child's
    /// first use finds out whether the lock was held at the fork.
    pid: AtomicU32,
    scene: String,
    names: Vec<String>,
    latency_max: Option<u32>,
    hello: Vec<u8>,
}

impl PyWorld {
    /// The number of dynamic bodies: the rows of a state.
    pub fn body_count(&self) -> usize {
        self.names.len()
    }

    pub fn lock(&self) -> Result<MutexGuard<'_, Session>, Failure> {
        // A panic while stepping leaves a world whose next command is
        // checked like any other; nothing half-written to guard.
        let pid = std::process::id();
        if self.pid.load(Ordering::Acquire) == pid {
            return Ok(self.session.lock().unwrap_or_else(PoisonError::into_inner));
        }
        // The first use in a forked child: a lock another thread of the
        // parent held at the fork stays held for ever, since that thread
        // does not exist here. Say so instead of waiting.
        match self.session.try_lock() {
            Ok(session) => {
                self.pid.store(pid, Ordering::Release);
                Ok(session)
            }
            Err(TryLockError::Poisoned(poisoned)) => {
                self.pid.store(pid, Ordering::Release);
                Ok(poisoned.into_inner())
            }
            Err(TryLockError::WouldBlock) => Err(Failure::Physics(
                "this World was in use by another thread when the process forked, and that \
                 thread does not exist in the child: make a new World here"
                    .to_owned(),
            )),
        }
    }

    /// Sends `payload` with the GIL released (it may step the world).
    fn send(&self, py: Python<'_>, payload: Payload) -> PyResult<u64> {
        Ok(py.detach(|| self.lock()?.send(payload))?)
    }

    fn state_array<'py>(
        &self,
        py: Python<'py>,
        (values, columns): (Vec<f64>, usize),
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        numpy::PyArray1::from_vec(py, values).reshape([self.names.len(), columns])
    }
}

#[pymethods]
impl PyWorld {
    /// The world of `scene` (a built-in scene name or a scene file, as
    /// `pushlearn-sim serve --scene` takes it), in lock-step; `latency_max`
    /// and `latency_seed` as `--latency-max` and `--latency-seed`,
    /// `publish_rate` as `--rate`.
    #[new]
    #[pyo3(signature = (scene = "one_block", *, latency_max = None, latency_seed = Unsigned(0), publish_rate = None))]
    fn new(
        scene: &str,
        latency_max: Option<Unsigned<u32>>,
        latency_seed: Unsigned<u64>,
        publish_rate: Option<Unsigned<u32>>,
    ) -> PyResult<Self> {
        let loaded =
            Scene::load(scene).map_err(|e| value_error(format!("scene `{scene}`: {e}")))?;
        let names = loaded
            .bodies
            .iter()
            .map(|b| b.name.clone())
            .collect::<Vec<_>>();
        let latency = latency_max.map(|Unsigned(max_steps)| Latency {
            max_steps,
            seed: latency_seed.0,
        });
        let world = EmbeddedWorld::new(loaded, publish_rate.map(|r| r.0), latency)
            .map_err(|e| value_error(format!("scene `{scene}`: {e}")))?;
        let hello = world.hello().encode_to_vec();
        Ok(PyWorld {
            pid: AtomicU32::new(std::process::id()),
            session: Mutex::new(Session {
                world,
                seq: 0,
                bodies: names.len(),
                last: None,
            }),
            scene: scene.to_owned(),
            names,
            latency_max: latency.map(|l| l.max_steps),
            hello,
        })
    }

    /// The scene as given.
    #[getter]
    fn scene(&self) -> &str {
        &self.scene
    }

    /// The dynamic bodies' names: the rows of [`PyWorld::state`], in order.
    #[getter]
    fn body_names(&self) -> Vec<String> {
        self.names.clone()
    }

    /// The latency emulation's largest delay of a Move in steps (`None`: none).
    #[getter]
    fn latency_max(&self) -> Option<u32> {
        self.latency_max
    }

    /// The daemon's Hello for this world, as `pushlearn.Hello` message bytes.
    fn hello_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.hello)
    }

    /// Every body to its start pose at rest, step and time to 0 (the stored
    /// actuator command is kept). Returns the command's seq.
    fn reset(&self, py: Python<'_>) -> PyResult<u64> {
        self.send(py, Payload::reset())
    }

    /// Pauses the world (an Advance is refused while it is paused).
    fn pause(&self, py: Python<'_>) -> PyResult<u64> {
        self.send(py, Payload::pause())
    }

    /// Resumes stepping.
    fn unpause(&self, py: Python<'_>) -> PyResult<u64> {
        self.send(py, Payload::unpause())
    }

    /// The actuator's velocity `(vx, vy)` in m/s, world frame, until the
    /// next Move (the world scales it down to its top speed). Returns the seq.
    #[pyo3(name = "move")]
    fn move_(&self, py: Python<'_>, vx: f64, vy: f64) -> PyResult<u64> {
        self.send(py, Payload::move_(vx, vy))
    }

    /// Puts body `name` at `position` (x, y, z) with `orientation`, the
    /// quaternion (x, y, z, w) (normalised by the world; default upright).
    /// Names ending in `Shadow…` set the viewer's ghosts. Returns the seq.
    #[pyo3(signature = (name, position, orientation = None))]
    fn set_pose(
        &self,
        py: Python<'_>,
        name: String,
        position: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        orientation: Option<PyArrayLikeDyn<'_, f64, AllowTypeChange>>,
    ) -> PyResult<u64> {
        let [x, y, z] = numbers("position", "x, y, z", &position)?;
        let [qx, qy, qz, qw] = match &orientation {
            Some(orientation) => numbers("orientation", "x, y, z, w", orientation)?,
            None => [0.0, 0.0, 0.0, 1.0],
        };
        let pose = pb::Pose {
            position: Some(pb::Vector3d::new(x, y, z)),
            orientation: Some(pb::Quaternion {
                x: qx,
                y: qy,
                z: qz,
                w: qw,
            }),
        };
        self.send(py, Payload::set_poses([(name, pose)]))
    }

    /// Reseeds the latency emulation's generator (refused without latency
    /// emulation). Returns the seq.
    fn latency_seed(&self, py: Python<'_>, seed: Unsigned<u64>) -> PyResult<u64> {
        self.send(py, Payload::latency_seed(seed.0))
    }

    /// Publishes every `1000 / hz` steps (`hz` must divide 1000).
    fn set_publish_rate(&self, py: Python<'_>, hz: Unsigned<u32>) -> PyResult<u64> {
        self.send(py, Payload::publish_rate(hz.0))
    }

    /// Runs the world to its next publish (every command sent before is in
    /// force by then) and returns the state, as [`PyWorld::state`].
    #[pyo3(signature = (*, planar = false))]
    fn advance<'py>(&self, py: Python<'py>, planar: bool) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let values = py.detach(|| {
            let mut session = self.lock()?;
            session.send(Payload::advance())?;
            session.rows().map(|rows| view(rows, planar))
        })?;
        self.state_array(py, values)
    }

    /// `move(vx, vy)` and `advance()` in one call: one environment step.
    #[pyo3(signature = (vx, vy, *, planar = false))]
    fn move_and_advance<'py>(
        &self,
        py: Python<'py>,
        vx: f64,
        vy: f64,
        planar: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let values = py.detach(|| {
            let mut session = self.lock()?;
            session.move_and_advance(vx, vy)?;
            session.rows().map(|rows| view(rows, planar))
        })?;
        self.state_array(py, values)
    }

    /// The last published state: a row per dynamic body (`body_names`), 13
    /// columns: position x, y, z; orientation quaternion x, y, z, w; linear
    /// velocity x, y, z; angular velocity x, y, z (world frame, m, m/s,
    /// rad/s). With `planar`, 6 columns: x, y, yaw, vx, vy and the spin
    /// about z. `ValueError` before the first `advance`.
    #[pyo3(signature = (*, planar = false))]
    fn state<'py>(&self, py: Python<'py>, planar: bool) -> PyResult<Bound<'py, PyArray2<f64>>> {
        // Without the GIL: another thread may be stepping this world.
        let values = py.detach(|| self.lock()?.rows().map(|rows| view(rows, planar)))?;
        self.state_array(py, values)
    }

    /// The last published state as the daemon sent it: `pushlearn.WorldState`
    /// message bytes (ghosts and counters included).
    fn state_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = py.detach(|| self.lock()?.published().map(|p| p.message.encode_to_vec()))?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// `(step, applied_seq)` of the last published state: physics steps
    /// since the last reset, and the last command in force.
    fn counters(&self, py: Python<'_>) -> PyResult<(u64, u64)> {
        Ok(py.detach(|| {
            self.lock()?
                .published()
                .map(|p| (p.message.step, p.message.applied_seq))
        })?)
    }

    fn __repr__(&self) -> String {
        match self.latency_max {
            Some(max) => format!("World({:?}, latency_max={max})", self.scene),
            None => format!("World({:?})", self.scene),
        }
    }
}

/// Several worlds stepped together in one call, the GIL released: the
/// native vector environment's step.
#[pyclass(name = "Worlds", module = "pushlearn._native", frozen)]
pub struct PyWorlds {
    worlds: Vec<Py<PyWorld>>,
    bodies: usize,
}

#[pymethods]
impl PyWorlds {
    /// The worlds to step together; all of one scene's body count.
    #[new]
    fn new(py: Python<'_>, worlds: Vec<Py<PyWorld>>) -> PyResult<Self> {
        let Some(first) = worlds.first() else {
            return Err(value_error("Worlds needs at least one World"));
        };
        let bodies = first.get().names.len();
        // One lock per world is taken for a whole step of them all: a world
        // listed twice would wait for itself.
        for (i, world) in worlds.iter().enumerate() {
            if let Some(j) = worlds[..i].iter().position(|w| w.is(world)) {
                return Err(value_error(format!(
                    "worlds[{j}] and worlds[{i}] are the same World; each may be listed once"
                )));
            }
        }
        if let Some(other) = worlds.iter().find(|w| w.get().names.len() != bodies) {
            return Err(value_error(format!(
                "every world must have the same bodies: {} has {:?}, {} has {:?}",
                first.bind(py).repr()?,
                first.get().names,
                other.bind(py).repr()?,
                other.get().names
            )));
        }
        Ok(PyWorlds { worlds, bodies })
    }

    /// The number of worlds.
    fn __len__(&self) -> usize {
        self.worlds.len()
    }

    /// Moves world i at `velocities[i]` (m/s) and advances it, for every i,
    /// and returns their states stacked, shape `(len, bodies, 13)` (rows as
    /// `World.state`; `(len, bodies, 6)` with `planar`). With `stepped`, a
    /// flag per world, only the worlds flagged move and advance; the others
    /// give their last state. Every argument is checked before any world
    /// steps.
    #[pyo3(signature = (velocities, *, planar = false, stepped = None))]
    fn move_and_advance<'py>(
        &self,
        py: Python<'py>,
        velocities: PyReadonlyArray2<'py, f64>,
        planar: bool,
        stepped: Option<Vec<bool>>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let n = self.worlds.len();
        if velocities.shape() != [n, 2] {
            return Err(value_error(format!(
                "velocities must have shape ({n}, 2), got {}",
                shape_text(velocities.shape())
            )));
        }
        let stepped = stepped.unwrap_or_else(|| vec![true; n]);
        if stepped.len() != n {
            return Err(value_error(format!(
                "stepped must have {n} flags, got {}",
                stepped.len()
            )));
        }
        let array = velocities.as_array();
        let moves: Vec<(f64, f64)> = array.rows().into_iter().map(|r| (r[0], r[1])).collect();
        if let Some(i) = moves
            .iter()
            .position(|(vx, vy)| !(vx.is_finite() && vy.is_finite()))
        {
            return Err(value_error(format!(
                "velocities[{i}] is not finite ({}, {})",
                moves[i].0, moves[i].1
            )));
        }
        let columns = if planar { PLANAR_COLUMNS } else { COLUMNS };
        let mut values = Vec::with_capacity(n * self.bodies * columns);
        py.detach(|| {
            step_together(&self.worlds, &moves, &stepped, |_, rows| {
                values.extend(view(rows, planar).0);
            })
        })?;
        numpy::PyArray1::from_vec(py, values).reshape([n, self.bodies, columns])
    }
}

/// Moves world i at `moves[i]` and advances it where `stepped[i]`, and
/// hands `each` every world's rows in order (the last state of a world not
/// stepped). Every world is locked, in one global order so that two calls
/// on overlapping lists cannot deadlock, and checked before any steps: all
/// or nothing. Call it without the GIL.
pub fn step_together(
    worlds: &[Py<PyWorld>],
    moves: &[(f64, f64)],
    stepped: &[bool],
    mut each: impl FnMut(usize, &[f64]),
) -> Result<(), Failure> {
    let n = worlds.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| worlds[i].as_ptr() as usize);
    let mut locked: Vec<Option<MutexGuard<'_, Session>>> = (0..n).map(|_| None).collect();
    for i in order {
        locked[i] = Some(worlds[i].get().lock()?);
    }
    let mut sessions: Vec<MutexGuard<'_, Session>> = locked.into_iter().flatten().collect();
    for (i, (session, (&(vx, vy), &step))) in
        sessions.iter().zip(moves.iter().zip(stepped)).enumerate()
    {
        let checked = if step {
            session.check_move_and_advance(vx, vy)
        } else {
            session.rows().map(|_| ())
        };
        checked.map_err(|failure| failure.in_world(i))?;
    }
    for (i, (session, (&(vx, vy), &step))) in sessions
        .iter_mut()
        .zip(moves.iter().zip(stepped))
        .enumerate()
    {
        if step {
            session.move_and_advance(vx, vy)?;
        }
        each(i, session.rows()?);
    }
    Ok(())
}

/// Seconds the world library takes to step `velocities` (shape `(n, 2)`,
/// m/s) as Moves, each followed by an Advance, on a fresh world of `scene`
/// (latency emulation as `World`'s), with nothing between them: the physics
/// floor of `python -m pushlearn.envs.throughput`. With `episode_steps`,
/// the world is reset after every `episode_steps` messages (a stop, the
/// Reset, a latency seed counting the episodes, an Advance: an
/// environment's reset), so that the floor steps the states an environment
/// with that time limit steps: a push near the block's start costs several
/// times one of an actuator that has wandered off.
#[pyfunction]
#[pyo3(signature = (velocities, scene = "one_block", *, latency_max = None, episode_steps = None))]
pub fn step_messages(
    py: Python<'_>,
    velocities: PyReadonlyArray2<'_, f64>,
    scene: &str,
    latency_max: Option<Unsigned<u32>>,
    episode_steps: Option<Unsigned<usize>>,
) -> PyResult<f64> {
    let episode = match episode_steps {
        Some(Unsigned(0)) => return Err(value_error("episode_steps must be at least 1")),
        Some(Unsigned(steps)) => steps,
        None => usize::MAX,
    };
    let shape = velocities.shape();
    if shape.len() != 2 || shape[1] != 2 {
        return Err(value_error(format!(
            "velocities must have shape (n, 2), got {}",
            shape_text(shape)
        )));
    }
    let moves: Vec<(f64, f64)> = velocities
        .as_array()
        .rows()
        .into_iter()
        .map(|r| (r[0], r[1]))
        .collect();
    let world = PyWorld::new(scene, latency_max, Unsigned(0), None)?;
    let latency = world.latency_max.is_some();
    let seconds = py.detach(|| -> Result<f64, Failure> {
        let mut session = world.lock()?;
        if latency {
            session.send(Payload::latency_seed(0))?;
        }
        session.send(Payload::advance())?;
        let start = Instant::now();
        for (episode, chunk) in moves.chunks(episode).enumerate() {
            if episode > 0 {
                session.send(Payload::move_(0.0, 0.0))?;
                session.send(Payload::reset())?;
                if latency {
                    session.send(Payload::latency_seed(
                        u64::try_from(episode).unwrap_or(u64::MAX),
                    ))?;
                }
                session.send(Payload::advance())?;
            }
            for &(vx, vy) in chunk {
                session.move_and_advance(vx, vy)?;
            }
        }
        Ok(start.elapsed().as_secs_f64())
    })?;
    Ok(seconds)
}
