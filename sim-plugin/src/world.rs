//! The thesis world (`docs/spec/world.md` §2–§7) on one of two engines: ODE
//! (the `ode` wrapper, the thesis's engine) or MuJoCo (the `mujoco` wrapper,
//! cargo feature `mujoco`; `docs/world.md`, "Two engines"). Commands,
//! ghosts, publishing and the divergence check are the world's own; the
//! engines only build the scene, drive the actuator, step and report.

#[cfg(feature = "mujoco")]
mod mjcf;
#[cfg(feature = "mujoco")]
mod on_mujoco;

use ode::{
    BodyBuilder, BodyHandle, ContactMode, GeomBuilder, OdeError, SpaceKind, Surface, SurfaceParams,
};
use pushlearn::wire::orientation::normalise;
use pushlearn_core::orientation::unit_yaw;
use pushlearn_core::GROUND_NAME;
use serde::{Deserialize, Serialize};

use pushlearn::wire::{clamp_speed, BodyName, Ghost};

use crate::scene::{Scene, ShapeSpec, ACTUATOR};

/// Steps per simulated second; publish rates must divide it.
const STEPS_PER_SECOND: u32 = 1000;

/// Positions farther than this from the origin are refused.
pub use pushlearn::wire::MAX_POSITION;

/// Distinct ghost names kept at once; a client cannot grow the world's
/// memory without bound.
pub const MAX_GHOSTS: usize = 64;

/// The physics engine a world runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Engine {
    /// The Open Dynamics Engine, as the thesis's Gazebo 2.x ran it: every
    /// published number.
    #[default]
    Ode,
    /// MuJoCo 2.2, the held-out engine (`docs/world.md`, "Two engines").
    Mujoco,
}

impl Engine {
    /// Both, ODE first.
    pub const ALL: [Engine; 2] = [Engine::Ode, Engine::Mujoco];

    /// The name flags and the Hello use: `ode` or `mujoco`.
    pub fn as_str(self) -> &'static str {
        match self {
            Engine::Ode => "ode",
            Engine::Mujoco => "mujoco",
        }
    }

    /// Whether this build carries the engine (MuJoCo is the `mujoco` cargo
    /// feature, on by default).
    pub fn is_available(self) -> bool {
        match self {
            Engine::Ode => true,
            Engine::Mujoco => cfg!(feature = "mujoco"),
        }
    }
}

impl std::fmt::Display for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Engine {
    type Err = String;

    fn from_str(s: &str) -> Result<Engine, String> {
        Engine::ALL
            .into_iter()
            .find(|e| e.as_str() == s)
            .ok_or_else(|| format!("unknown engine `{s}` (engines: ode, mujoco)"))
    }
}

/// The actuator's stored command (`ActuatorCommand.cmd` of the protocol).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ActuatorMode {
    #[default]
    Nothing,
    Move,
    Grab,
    Release,
}

/// A client command, applied between steps.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Stores the actuator command; with `Move`, `velocity` (m/s, world
    /// frame) is re-imposed every step until the next command.
    Actuator {
        mode: ActuatorMode,
        velocity: [f64; 3],
    },
    Pause,
    Unpause,
    /// Every body to its start pose at rest, step counter and time to 0.
    /// The stored actuator command is kept (`docs/spec/world.md` §6).
    Reset,
    /// Sets a body's pose (velocities untouched), or stores a ghost pose.
    SetPose {
        name: BodyName,
        position: [f64; 3],
        /// `[x, y, z, w]`, normalised on application.
        orientation: [f64; 4],
    },
    /// Publish every `1000 / hz` steps.
    SetPublishRate(u32),
}

/// Why a command was refused. The world is unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    #[error("{field} must be finite, got {value}")]
    NotFinite { field: &'static str, value: f64 },
    #[error("{field} component {value} is beyond ±{limit} m")]
    TooFar {
        field: &'static str,
        value: f64,
        limit: f64,
    },
    #[error(
        "the actuator at ({:.3}, {:.3}, {:.3}) would be outside its drive bound ({bound_radius} m \
         around ({:.3}, {:.3}, {:.3})), where it can never move again",
        position[0], position[1], position[2], centre[0], centre[1], centre[2]
    )]
    OutsideDriveBound {
        position: [f64; 3],
        centre: [f64; 3],
        bound_radius: f64,
    },
    #[error("unknown body `{0}`")]
    UnknownBody(String),
    #[error("orientation of `{0}` is a quaternion of zero length")]
    ZeroQuaternion(String),
    #[error("publish rate {0} Hz does not divide 1000")]
    BadPublishRate(u32),
    #[error("too many ghost poses (at most {MAX_GHOSTS} names)")]
    TooManyGhosts,
}

#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("scene: {0}")]
    Scene(#[from] crate::scene::SceneError),
    #[error("physics engine: {0}")]
    Ode(#[from] OdeError),
    #[cfg(feature = "mujoco")]
    #[error("MuJoCo: {0}")]
    Mujoco(#[from] mujoco::MujocoError),
    #[error("this build has no {0} engine (sim-plugin was built without its `{0}` cargo feature)")]
    EngineMissing(Engine),
}

#[derive(Debug, thiserror::Error)]
pub enum StepError {
    #[error("physics blew up at step {step}: `{body}` reached {what}; the world was reset")]
    Diverged {
        step: u64,
        body: String,
        /// `a non-finite state`, or a position beyond the world's bounds.
        what: &'static str,
    },
    #[error("physics engine: {0}")]
    Ode(#[from] OdeError),
}

/// One body as published (`docs/spec/protocol.md` ModelState).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    pub name: String,
    pub id: u32,
    pub is_static: bool,
    pub position: [f64; 3],
    /// Unit quaternion `[x, y, z, w]`.
    pub orientation: [f64; 4],
    /// World frame, m/s.
    pub lin_vel: [f64; 3],
    /// World frame, rad/s.
    pub ang_vel: [f64; 3],
}

impl BodyState {
    /// Rotation about +z in (−π, π], from the orientation quaternion.
    ///
    /// Not the learners' [`orientation::yaw`](pushlearn_core::orientation::yaw)
    /// but the calibration sweep's [`unit_yaw`] (`docs/results.md` §2), whose
    /// published numbers it must keep reproducing bit for bit.
    pub fn yaw(&self) -> f64 {
        unit_yaw(self.orientation)
    }

    /// The body as a learner sees it published (no shape: that comes
    /// from the Hello).
    #[must_use]
    pub fn observation(&self) -> pushlearn_core::Observation {
        pushlearn_core::Observation {
            name: self.name.clone(),
            id: self.id,
            position: self.position,
            orientation: self.orientation,
            shape: None,
        }
    }
}

/// The world's state at a step boundary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Steps since the last reset.
    pub step: u64,
    /// Seconds since the last reset.
    pub sim_time: f64,
    /// Dynamic bodies in scene order.
    pub bodies: Vec<BodyState>,
    /// `*Shadow` poses set by SetPose, in the order first set; never physical.
    pub ghosts: Vec<BodyState>,
}

impl Snapshot {
    pub fn body(&self, name: &str) -> Option<&BodyState> {
        self.bodies.iter().find(|b| b.name == name)
    }
}

struct SimBody {
    handle: BodyHandle,
    name: String,
    id: u32,
    /// The shape's centre (the published frame) at the start.
    start_position: [f64; 3],
    start_orientation: [f64; 4],
    /// The centre of mass from the shape's centre, body frame; `None` when
    /// they coincide, so that such a body is read and written exactly as
    /// before centres of mass could move.
    centre_of_mass: Option<[f64; 3]>,
}

impl SimBody {
    /// Puts the shape's centre at `position` with `orientation`. The ODE
    /// body sits at the centre of mass, `R c` further on, computed by ODE's
    /// own body transform (the one it places the offset geom with).
    fn place(
        &self,
        body: &mut ode::BodyMut<'_>,
        position: [f64; 3],
        orientation: [f64; 4],
    ) -> Result<(), OdeError> {
        // In this order for bodies without an offset, as before offsets.
        body.set_position(position)?;
        body.set_orientation(orientation)?;
        if let Some(c) = self.centre_of_mass {
            let centre_of_mass = body.point_position(c);
            body.set_position(centre_of_mass)?;
        }
        Ok(())
    }

    /// The published state: the pose and velocity of the shape's centre.
    fn state(&self, body: &ode::Body<'_>) -> BodyState {
        let (position, lin_vel) = match self.centre_of_mass {
            None => (body.position(), body.linear_velocity()),
            Some([x, y, z]) => (
                body.point_position([-x, -y, -z]),
                body.point_velocity([-x, -y, -z]),
            ),
        };
        BodyState {
            name: self.name.clone(),
            id: self.id,
            is_static: false,
            position,
            orientation: body.orientation(),
            lin_vel,
            ang_vel: body.angular_velocity(),
        }
    }
}

/// Contact surfaces for every pair of materials, indexed by geom tag
/// (tag 0 is the ground, tag i + 1 the scene's body i).
struct SurfaceTable {
    materials: usize,
    surfaces: Vec<Surface>,
}

impl SurfaceTable {
    fn new(scene: &Scene) -> Result<SurfaceTable, OdeError> {
        // (mu1, mu2, kp, kd) per tag.
        let mut mats = vec![(
            scene.ground.mu1,
            scene.ground.mu2,
            scene.ground.kp,
            scene.ground.kd,
        )];
        mats.extend(scene.bodies.iter().map(|b| (b.mu1, b.mu2, b.kp, b.kd)));
        let h = scene.physics.step_size;
        let n = mats.len();
        let mut surfaces = Vec::with_capacity(n * n);
        for a in &mats {
            for b in &mats {
                surfaces.push(combine(*a, *b, h, None)?);
            }
        }
        // `[[friction]]` pairs replace the minimum rule for themselves only.
        let tag = |name: &str| {
            if name == GROUND_NAME {
                Some(0)
            } else {
                scene.body_index(name).map(|i| i + 1)
            }
        };
        for pair in &scene.frictions {
            let [a, b] = &pair.between;
            // Validated: both name the ground or a body.
            let (Some(a), Some(b)) = (tag(a), tag(b)) else {
                continue;
            };
            let mu = pair.coefficients();
            surfaces[a * n + b] = combine(mats[a], mats[b], h, Some(mu))?;
            surfaces[b * n + a] = combine(mats[b], mats[a], h, Some(mu))?;
        }
        Ok(SurfaceTable {
            materials: n,
            surfaces,
        })
    }

    fn get(&self, a: u32, b: u32) -> Option<Surface> {
        let (a, b) = (a as usize, b as usize);
        (a < self.materials && b < self.materials).then(|| self.surfaces[a * self.materials + b])
    }
}

/// Gazebo 2.x's contact surface for two materials (`docs/spec/world.md` §4): friction
/// by the minimum rule unless the scene gives the pair's own `(mu1, mu2)`,
/// softness from springs in series and dampers in parallel.
fn combine(
    a: (f64, f64, f64, f64),
    b: (f64, f64, f64, f64),
    h: f64,
    pair_friction: Option<(f64, f64)>,
) -> Result<Surface, OdeError> {
    let kp = 1.0 / (1.0 / a.2 + 1.0 / b.2);
    let kd = a.3 + b.3;
    let (mu, mu2) = pair_friction.unwrap_or((a.0.min(b.0), a.1.min(b.1)));
    SurfaceParams {
        mode: ContactMode::APPROX1
            | ContactMode::MU2
            | ContactMode::SOFT_ERP
            | ContactMode::SOFT_CFM
            | ContactMode::BOUNCE
            | ContactMode::SLIP1
            | ContactMode::SLIP2,
        mu,
        mu2,
        bounce: 0.0,
        bounce_vel: 0.0,
        soft_erp: h * kp / (h * kp + kd),
        soft_cfm: 1.0 / (h * kp + kd),
        slip1: 0.0,
        slip2: 0.0,
    }
    .check()
}

/// The ODE side of a world: its bodies, contact surfaces and the pairs the
/// collider reported.
struct OnOde {
    ode: ode::World,
    bodies: Vec<SimBody>,
    surfaces: SurfaceTable,
    /// Tag pairs (smaller first) the collider reported touching in the last
    /// step.
    touching: Vec<(u32, u32)>,
}

impl OnOde {
    fn new(scene: &Scene, space: SpaceKind) -> Result<OnOde, WorldError> {
        let mut ode = ode::World::new(scene.step_params(), space)?;
        ode.insert_geom(GeomBuilder::plane([0.0, 0.0, 1.0], 0.0).tag(0))?;
        let mut bodies = Vec::with_capacity(scene.bodies.len());
        for (i, spec) in scene.bodies.iter().enumerate() {
            // ODE wants the body at its centre of mass (`dBodySetMass`
            // refuses a mass centred elsewhere), so a centre of mass away
            // from the shape's centre puts the geom at −c from the body.
            // The published pose is converted back to the shape's centre
            // (`SimBody::state`) rather than read from the geom, because
            // the same body transform also gives that point's velocity,
            // and SetPose and Reset write through its inverse.
            let centre_of_mass = Some(spec.centre_of_mass()).filter(|c| *c != [0.0; 3]);
            let (inertia, products) = spec.inertia_about_centre_of_mass();
            let handle = ode.insert_body(
                BodyBuilder::new(spec.mass, inertia)
                    .products_of_inertia(products)
                    .position(spec.start.position())
                    .orientation(spec.start.orientation())
                    .gravity(spec.gravity),
            )?;
            let geom = match spec.shape {
                ShapeSpec::Sphere { radius } => GeomBuilder::sphere(radius),
                ShapeSpec::Box { size } => GeomBuilder::cuboid(size),
                ShapeSpec::Cylinder { radius, length } => GeomBuilder::cylinder(radius, length),
            };
            let geom = match centre_of_mass {
                Some([x, y, z]) => geom.offset([-x, -y, -z]),
                None => geom,
            };
            ode.insert_geom(geom.attached_to(handle).tag(i as u32 + 1))?;
            bodies.push(SimBody {
                handle,
                name: spec.name.clone(),
                id: spec.id,
                start_position: spec.start.position(),
                start_orientation: spec.start.orientation(),
                centre_of_mass,
            });
        }
        Ok(OnOde {
            surfaces: SurfaceTable::new(scene)?,
            ode,
            bodies,
            touching: Vec::new(),
        })
    }

    fn reset(&mut self) -> Result<(), OdeError> {
        for b in &self.bodies {
            let mut body = self.ode.body_mut(b.handle)?;
            b.place(&mut body, b.start_position, b.start_orientation)?;
            body.reset_dynamics();
        }
        // QuickStep's row shuffling draws from this stream: seeding it at
        // every reset makes runs reproducible (`docs/spec/world.md` §12).
        self.ode.set_rand_seed(0);
        self.touching.clear();
        Ok(())
    }

    fn set_pose(&mut self, i: usize, position: [f64; 3], orientation: [f64; 4]) {
        let sim = &self.bodies[i];
        let set = self.ode.body_mut(sim.handle).and_then(|mut b| {
            sim.place(&mut b, position, orientation)?;
            // A sleeping body moved into the air would otherwise hang there.
            b.enable();
            Ok(())
        });
        // Every value was checked by the world, so the engine cannot refuse it.
        if let Err(e) = set {
            tracing::error!("SetPose `{}` refused by the engine: {e}", sim.name);
        }
    }

    /// `docs/spec/world.md` §5, steps 1–3, in that order.
    fn drive_actuator(
        &mut self,
        actuator: usize,
        drive: &crate::scene::Drive,
        mode: ActuatorMode,
        direction: &mut [f64; 3],
    ) -> Result<(), OdeError> {
        let mut body = self.ode.body_mut(self.bodies[actuator].handle)?;
        // The explicit wake-up keeps auto-disable from freezing the actuator.
        body.enable();
        let p = body.position();
        if beyond_bound(p, *direction, drive) {
            *direction = [0.0; 3];
            body.set_linear_velocity([0.0; 3])?;
        }
        body.set_angular_velocity([0.0; 3])?;
        if mode == ActuatorMode::Move {
            body.set_linear_velocity(*direction)?;
            body.set_position([p[0], p[1], drive.z_clamp])?;
        }
        Ok(())
    }

    /// One step; how long it waited for other worlds of the process.
    fn step(&mut self) -> Result<std::time::Duration, OdeError> {
        let surfaces = &self.surfaces;
        let touching = &mut self.touching;
        touching.clear();
        let report = self.ode.step(|pair| {
            let (a, b) = (pair.first.tag, pair.second.tag);
            let key = (a.min(b), a.max(b));
            if !touching.contains(&key) {
                touching.push(key);
            }
            surfaces.get(a, b)
        })?;
        Ok(report.waited_for_lock)
    }

    #[cfg(feature = "testing")]
    fn poison(&mut self, i: usize) {
        if let Ok(mut body) = self.ode.body_mut(self.bodies[i].handle) {
            body.poison_for_test();
        }
    }

    /// The first body whose state is lost, and how.
    fn lost(&self) -> Option<(usize, &'static str)> {
        self.bodies.iter().enumerate().find_map(|(i, b)| {
            let Ok(body) = self.ode.body(b.handle) else {
                return Some((i, "a non-finite state"));
            };
            let finite = (body.position().iter())
                .chain(&body.orientation())
                .chain(&body.linear_velocity())
                .chain(&body.angular_velocity())
                .all(|v| v.is_finite());
            if !finite {
                Some((i, "a non-finite state"))
            } else if body.position().iter().any(|v| v.abs() > MAX_POSITION) {
                Some((i, "a position beyond ±1000 m"))
            } else {
                None
            }
        })
    }

    fn states(&self) -> Vec<BodyState> {
        self.bodies
            .iter()
            .filter_map(|b| Some(b.state(&self.ode.body(b.handle).ok()?)))
            .collect()
    }
}

/// Whether the actuator's next position, `p + direction` (the velocity read
/// as one second's travel, as the thesis's plugin did), leaves the bound.
fn beyond_bound(p: [f64; 3], direction: [f64; 3], drive: &crate::scene::Drive) -> bool {
    let ahead: f64 = (0..3)
        .map(|k| (p[k] + direction[k] - drive.bound_centre[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    ahead > drive.bound_radius
}

/// The engine a world runs on, with everything that engine keeps.
enum Physics {
    Ode(Box<OnOde>),
    #[cfg(feature = "mujoco")]
    Mujoco(Box<on_mujoco::OnMujoco>),
}

/// The simulated thesis world: bodies from a [`Scene`], the actuator drive,
/// commands, ghosts and publishing.
pub struct World {
    scene: Scene,
    physics: Physics,
    actuator: usize,
    mode: ActuatorMode,
    direction: [f64; 3],
    paused: bool,
    step_count: u64,
    publish_every: u32,
    ghosts: Vec<BodyState>,
    /// [`World::provoke_blow_up`]'s body, poisoned after the next step.
    #[cfg(feature = "testing")]
    blow_up: Option<usize>,
    /// How long the steps so far waited for other worlds of this process
    /// to finish theirs (ODE's process-wide lock).
    waited_for_ode: std::time::Duration,
}

impl World {
    /// Builds the world of `scene` on ODE with the top-level simple space the
    /// thesis world needs.
    pub fn new(scene: &Scene) -> Result<World, WorldError> {
        World::with_space(scene, SpaceKind::Simple)
    }

    /// Builds the world of `scene` on `engine`.
    pub fn on(scene: &Scene, engine: Engine) -> Result<World, WorldError> {
        match engine {
            Engine::Ode => World::new(scene),
            #[cfg(feature = "mujoco")]
            Engine::Mujoco => {
                scene.validate()?;
                let physics = Physics::Mujoco(Box::new(on_mujoco::OnMujoco::new(scene)?));
                World::around(scene, physics)
            }
            #[cfg(not(feature = "mujoco"))]
            Engine::Mujoco => Err(WorldError::EngineMissing(engine)),
        }
    }

    /// Like [`World::new`] with a chosen top-level space. Only the libode 0.16
    /// hash-space regression test wants anything but [`SpaceKind::Simple`].
    pub fn with_space(scene: &Scene, space: SpaceKind) -> Result<World, WorldError> {
        scene.validate()?;
        let physics = Physics::Ode(Box::new(OnOde::new(scene, space)?));
        World::around(scene, physics)
    }

    fn around(scene: &Scene, physics: Physics) -> Result<World, WorldError> {
        let actuator =
            scene
                .body_index(ACTUATOR)
                .ok_or_else(|| crate::scene::SceneError::Invalid {
                    field: "body".into(),
                    problem: format!("no body named `{ACTUATOR}`"),
                })?;
        let mut world = World {
            scene: scene.clone(),
            physics,
            actuator,
            mode: ActuatorMode::Nothing,
            direction: [0.0; 3],
            paused: false,
            step_count: 0,
            publish_every: STEPS_PER_SECOND / scene.publish_rate_hz,
            ghosts: Vec::new(),
            #[cfg(feature = "testing")]
            blow_up: None,
            waited_for_ode: std::time::Duration::ZERO,
        };
        // The same routine as every Reset, so that a fresh world and a reset
        // one agree bit for bit (including ODE's internal geom order).
        world.reset()?;
        Ok(world)
    }

    /// The engine this world runs on.
    pub fn engine(&self) -> Engine {
        match self.physics {
            Physics::Ode(_) => Engine::Ode,
            #[cfg(feature = "mujoco")]
            Physics::Mujoco(_) => Engine::Mujoco,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn is_paused(&self) -> bool {
        self.paused
    }

    /// How long this world's steps have waited for other worlds of the
    /// process to finish theirs: ODE steps one world at a time per process.
    /// Always zero on MuJoCo, whose worlds share nothing.
    pub fn waited_for_ode(&self) -> std::time::Duration {
        self.waited_for_ode
    }

    /// Physics steps since the last reset.
    pub fn step_count(&self) -> u64 {
        self.step_count
    }

    /// Simulated seconds since the last reset.
    pub fn sim_time(&self) -> f64 {
        self.step_count as f64 * self.scene.physics.step_size
    }

    /// Steps between two published states (1000 / rate).
    pub fn publish_interval_steps(&self) -> u32 {
        self.publish_every
    }

    /// The stored actuator command and velocity (after the speed clamp).
    pub fn actuator_command(&self) -> (ActuatorMode, [f64; 3]) {
        (self.mode, self.direction)
    }

    /// Whether the collider reported the bodies named `a` and `b` touching
    /// in the last step ([`GROUND_NAME`] names the ground).
    pub fn touched_last_step(&self, a: &str, b: &str) -> bool {
        let (Some(ta), Some(tb)) = (self.tag_of(a), self.tag_of(b)) else {
            return false;
        };
        let key = (ta.min(tb), ta.max(tb));
        match &self.physics {
            Physics::Ode(on) => on.touching.contains(&key),
            #[cfg(feature = "mujoco")]
            Physics::Mujoco(on) => on.touched(key),
        }
    }

    fn tag_of(&self, name: &str) -> Option<u32> {
        if name == GROUND_NAME {
            return Some(0);
        }
        self.scene.body_index(name).map(|i| i as u32 + 1)
    }

    /// Validates `cmd` completely, then applies it. On error nothing changed.
    pub fn apply(&mut self, cmd: Command) -> Result<(), CommandError> {
        check_command(&self.scene, &cmd)?;
        match cmd {
            Command::Actuator { mode, velocity } => {
                self.mode = mode;
                self.direction = clamp_speed(velocity, self.scene.drive.max_speed);
            }
            Command::Pause => self.paused = true,
            Command::Unpause => self.paused = false,
            Command::Reset => {
                // Only fails if the engine cannot set up a thread, which
                // World::new already proved it can on this thread.
                if let Err(e) = self.reset() {
                    tracing::error!("reset failed: {e}");
                }
            }
            Command::SetPose {
                name,
                position,
                orientation,
            } => self.set_pose(name, position, orientation)?,
            Command::SetPublishRate(hz) => self.publish_every = STEPS_PER_SECOND / hz,
        }
        Ok(())
    }

    /// `name`, `position` and `orientation` passed [`check_command`].
    fn set_pose(
        &mut self,
        name: BodyName,
        position: [f64; 3],
        orientation: [f64; 4],
    ) -> Result<(), CommandError> {
        let Some(unit) = normalise(orientation) else {
            return Err(CommandError::ZeroQuaternion(name.to_string()));
        };
        let name = match name {
            BodyName::Ghost(ghost) => return self.set_ghost(&ghost, position, unit),
            BodyName::Body(name) => name,
        };
        let Some(i) = self.scene.body_index(&name) else {
            return Err(CommandError::UnknownBody(name));
        };
        match &mut self.physics {
            Physics::Ode(on) => on.set_pose(i, position, unit),
            #[cfg(feature = "mujoco")]
            Physics::Mujoco(on) => on.set_pose(i, position, unit),
        }
        Ok(())
    }

    /// Fault injection for tests, reachable from no command, flag or
    /// message: the next step leaves `name` with a non-finite velocity, as
    /// a diverging simulation would, to exercise the divergence reset of
    /// [`World::step`]. (Driving ODE itself there is no option: values large
    /// enough to overflow make it abort the process, hence the scene limits.)
    #[cfg(feature = "testing")]
    pub fn provoke_blow_up(&mut self, name: &str) -> Result<(), CommandError> {
        let i = self
            .scene
            .body_index(name)
            .ok_or_else(|| CommandError::UnknownBody(name.to_owned()))?;
        self.blow_up = Some(i);
        Ok(())
    }

    fn set_ghost(
        &mut self,
        ghost: &Ghost,
        position: [f64; 3],
        orientation: [f64; 4],
    ) -> Result<(), CommandError> {
        let id = self
            .scene
            .bodies
            .iter()
            .find(|b| b.name == ghost.of)
            .map_or(0, |b| b.id);
        let state = BodyState {
            name: ghost.to_string(),
            id,
            is_static: true,
            position,
            orientation,
            lin_vel: [0.0; 3],
            ang_vel: [0.0; 3],
        };
        if let Some(g) = self.ghosts.iter_mut().find(|g| g.name == state.name) {
            *g = state;
        } else if self.ghosts.len() >= MAX_GHOSTS {
            return Err(CommandError::TooManyGhosts);
        } else {
            self.ghosts.push(state);
        }
        Ok(())
    }

    fn reset(&mut self) -> Result<(), WorldError> {
        match &mut self.physics {
            Physics::Ode(on) => on.reset()?,
            #[cfg(feature = "mujoco")]
            Physics::Mujoco(on) => on.reset()?,
        }
        self.step_count = 0;
        self.ghosts.clear();
        Ok(())
    }

    /// One 1 ms physics step (nothing while paused). Returns the snapshot
    /// when a publish is due: after every N-th step since the last reset.
    pub fn step(&mut self) -> Result<Option<Snapshot>, StepError> {
        if self.paused {
            return Ok(None);
        }
        let drive = &self.scene.drive;
        let lost = match &mut self.physics {
            Physics::Ode(on) => {
                on.drive_actuator(self.actuator, drive, self.mode, &mut self.direction)?;
                self.waited_for_ode += on.step()?;
                None
            }
            #[cfg(feature = "mujoco")]
            Physics::Mujoco(on) => {
                on.drive_actuator(self.actuator, drive, self.mode, &mut self.direction);
                // MuJoCo resets its data itself when a state goes bad, so
                // which body it was is no longer known.
                on.step()
                    .err()
                    .map(|reason| ("the MuJoCo model".to_owned(), reason))
            }
        };
        self.step_count += 1;
        #[cfg(feature = "testing")]
        if let Some(i) = self.blow_up.take() {
            match &mut self.physics {
                Physics::Ode(on) => on.poison(i),
                #[cfg(feature = "mujoco")]
                Physics::Mujoco(on) => on.poison(i),
            }
        }
        // A body beyond the bounds a SetPose may reach (bodies placed
        // overlapping are shot apart, and reached 1130 m) is as lost as a
        // non-finite one: the world resets rather than publish it.
        let lost = lost.or_else(|| {
            let found = match &self.physics {
                Physics::Ode(on) => on.lost(),
                #[cfg(feature = "mujoco")]
                Physics::Mujoco(on) => on.lost(),
            };
            found.map(|(i, what)| (self.scene.bodies[i].name.clone(), what))
        });
        if let Some((body, what)) = lost {
            let err = StepError::Diverged {
                step: self.step_count,
                body,
                what,
            };
            tracing::error!("{err}");
            if let Err(e) = self.reset() {
                tracing::error!("reset after the blow-up failed: {e}");
            }
            return Err(err);
        }
        if self
            .step_count
            .is_multiple_of(u64::from(self.publish_every))
        {
            Ok(Some(self.snapshot()))
        } else {
            Ok(None)
        }
    }

    /// The current state of every dynamic body and ghost.
    pub fn snapshot(&self) -> Snapshot {
        let bodies = match &self.physics {
            Physics::Ode(on) => on.states(),
            #[cfg(feature = "mujoco")]
            Physics::Mujoco(on) => on.states(&self.scene),
        };
        Snapshot {
            step: self.step_count,
            sim_time: self.sim_time(),
            bodies,
            ghosts: self.ghosts.clone(),
        }
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// The checks of [`World::apply`] that need only the scene, not the world's
/// state (everything but the ghost limit): a daemon runs them when a command
/// arrives, long before the physics thread applies it.
pub fn check_command(scene: &Scene, cmd: &Command) -> Result<(), CommandError> {
    match cmd {
        Command::Actuator { velocity, .. } => check_finite("velocity", velocity),
        Command::Pause | Command::Unpause | Command::Reset => Ok(()),
        Command::SetPose {
            name,
            position,
            orientation,
        } => {
            check_finite("position", position)?;
            check_finite("orientation", orientation)?;
            if let Some(&value) = position.iter().find(|v| v.abs() > MAX_POSITION) {
                return Err(CommandError::TooFar {
                    field: "position",
                    value,
                    limit: MAX_POSITION,
                });
            }
            if normalise(*orientation).is_none() {
                return Err(CommandError::ZeroQuaternion(name.to_string()));
            }
            // A ghost is published with its body's id, so one of a body
            // the scene lacks would be anonymous (id 0).
            let body = match name {
                BodyName::Body(name) => name,
                BodyName::Ghost(ghost) => &ghost.of,
            };
            if scene.body_index(body).is_none() {
                return Err(CommandError::UnknownBody(body.clone()));
            }
            // The drive stops an actuator whose next position leaves its
            // bound, so one placed outside it would never move again.
            let drive = &scene.drive;
            if matches!(name, BodyName::Body(n) if n == ACTUATOR)
                && distance(*position, drive.bound_centre) > drive.bound_radius
            {
                return Err(CommandError::OutsideDriveBound {
                    position: *position,
                    centre: drive.bound_centre,
                    bound_radius: drive.bound_radius,
                });
            }
            Ok(())
        }
        Command::SetPublishRate(hz) => {
            if *hz == 0 || !STEPS_PER_SECOND.is_multiple_of(*hz) {
                Err(CommandError::BadPublishRate(*hz))
            } else {
                Ok(())
            }
        }
    }
}

fn check_finite(field: &'static str, values: &[f64]) -> Result<(), CommandError> {
    match values.iter().find(|v| !v.is_finite()) {
        Some(&value) => Err(CommandError::NotFinite { field, value }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blow_up_resets_the_world_and_names_the_body() {
        let mut world = World::new(&Scene::builtin("one_block").unwrap()).unwrap();
        world
            .apply(Command::Actuator {
                mode: ActuatorMode::Move,
                velocity: [0.0, 0.5, 0.0],
            })
            .unwrap();
        for _ in 0..25 {
            world.step().unwrap();
        }
        world.provoke_blow_up("blockA").unwrap();
        let err = world.step().unwrap_err();
        assert!(
            matches!(&err, StepError::Diverged { step: 26, body, .. } if body == "blockA"),
            "{err}"
        );
        // Reset: back at the start, every value finite, stepping on.
        assert_eq!(world.step_count(), 0);
        let start = World::new(&Scene::builtin("one_block").unwrap())
            .unwrap()
            .snapshot();
        assert_eq!(world.snapshot().bodies, start.bodies);
        for _ in 0..10 {
            world.step().unwrap();
        }
        assert_eq!(world.step_count(), 10);
    }

    /// Every built-in scene builds on both engines and steps a push with
    /// the same command handling; a blow-up resets on MuJoCo as on ODE.
    #[cfg(feature = "mujoco")]
    #[test]
    fn every_built_in_scene_runs_on_both_engines() {
        for name in Scene::builtin_names() {
            let scene = Scene::builtin(name).unwrap();
            for engine in Engine::ALL {
                let mut world = World::on(&scene, engine).unwrap();
                assert_eq!(world.engine(), engine);
                let start = world.snapshot();
                world
                    .apply(Command::Actuator {
                        mode: ActuatorMode::Move,
                        velocity: [0.0, 0.5, 0.0],
                    })
                    .unwrap();
                for _ in 0..100 {
                    world.step().unwrap();
                }
                let after = world.snapshot();
                let actuator = |s: &Snapshot| s.body(ACTUATOR).unwrap().position;
                // 0.1 s at 0.5 m/s, held at the z clamp.
                let moved = actuator(&after)[1] - actuator(&start)[1];
                assert!((moved - 0.05).abs() < 1e-6, "{name} on {engine}: {moved}");
                assert_eq!(actuator(&after)[2], scene.drive.z_clamp);
                world.provoke_blow_up("blockA").unwrap();
                assert!(matches!(
                    world.step(),
                    Err(StepError::Diverged { body, .. }) if body == "blockA"
                ));
                assert_eq!(world.snapshot().bodies, start.bodies, "{name} on {engine}");
            }
        }
    }

    #[test]
    fn engines_are_named_as_the_flag_and_the_hello_say() {
        for engine in Engine::ALL {
            assert_eq!(engine.as_str().parse::<Engine>(), Ok(engine));
        }
        assert!("bullet"
            .parse::<Engine>()
            .unwrap_err()
            .contains("ode, mujoco"));
        assert_eq!(Engine::default(), Engine::Ode);
    }

    #[test]
    fn gazebo_softness_for_two_default_surfaces() {
        let s = combine((0.9, 0.9, 1e12, 1.0), (0.01, 0.02, 1e12, 1.0), 0.001, None).unwrap();
        let p = s.params();
        assert_eq!((p.mu, p.mu2), (0.01, 0.02));
        let (kp, kd) = (5e11, 2.0);
        assert_eq!(p.soft_erp, 0.001 * kp / (0.001 * kp + kd));
        assert_eq!(p.soft_cfm, 1.0 / (0.001 * kp + kd));
        assert_eq!(
            p.mode.bits(),
            0x7000 | 0x1 | 0x4 | 0x8 | 0x10 | 0x100 | 0x200
        );
    }
}
