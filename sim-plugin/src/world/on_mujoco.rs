//! The world's engine side on MuJoCo: the scene compiled from its MJCF
//! (`mjcf`), the actuator driven as on ODE, contacts as geom-tag pairs.

use mujoco::{FreeJoint, MujocoError, Simulation};

use super::{beyond_bound, mjcf, ActuatorMode, BodyState, MAX_POSITION};
use crate::scene::{Drive, Scene};

/// One scene body in the MuJoCo model.
struct MjBody {
    joint: FreeJoint,
    body: usize,
    start_position: [f64; 3],
    start_orientation: [f64; 4],
    /// The force that cancels gravity for a body without it (the actuator):
    /// MuJoCo 2.2 has no per-body gravity switch.
    antigravity: Option<[f64; 3]>,
}

pub(super) struct OnMujoco {
    sim: Simulation,
    bodies: Vec<MjBody>,
}

impl OnMujoco {
    /// The MuJoCo model of `scene` (validated).
    pub(super) fn new(scene: &Scene) -> Result<OnMujoco, MujocoError> {
        for name in mjcf::unphysical_inertia(scene) {
            tracing::warn!(
                "`{name}`: its inertia breaks A + B ≥ C, which no solid does; MuJoCo uses the \
                 mean of its diagonal instead (ODE takes it as given)"
            );
        }
        let sim = Simulation::from_mjcf(&mjcf::mjcf(scene))?;
        let mut bodies = Vec::with_capacity(scene.bodies.len());
        for (i, spec) in scene.bodies.iter().enumerate() {
            // Contacts are reported by geom id and read as ODE's geom tags.
            let geom = sim.geom(&spec.name)?;
            if geom != i + 1 {
                return Err(MujocoError::Unknown {
                    kind: "geom in scene order",
                    name: spec.name.clone(),
                });
            }
            let body = sim.body(&spec.name)?;
            let g = scene.physics.gravity;
            bodies.push(MjBody {
                joint: sim.free_joint(&spec.name)?,
                body,
                start_position: spec.start.position(),
                start_orientation: spec.start.orientation(),
                antigravity: (!spec.gravity).then(|| g.map(|a| -spec.mass * a)),
            });
        }
        Ok(OnMujoco { sim, bodies })
    }

    pub(super) fn reset(&mut self) -> Result<(), MujocoError> {
        // MuJoCo's reset clears time, velocities, applied forces and the
        // solver's warm start: a run after it repeats bit for bit.
        self.sim.reset();
        for b in &self.bodies {
            self.sim
                .set_pose(b.joint, b.start_position, b.start_orientation)?;
            if let (Some(force), Some(applied)) =
                (b.antigravity, self.sim.applied_force_mut(b.body))
            {
                applied[..3].copy_from_slice(&force);
            }
        }
        Ok(())
    }

    pub(super) fn set_pose(&mut self, i: usize, position: [f64; 3], orientation: [f64; 4]) {
        // Every value was checked by the world, so the engine cannot refuse it.
        if let Err(e) = self
            .sim
            .set_pose(self.bodies[i].joint, position, orientation)
        {
            tracing::error!("SetPose refused by MuJoCo: {e}");
        }
    }

    /// ODE's drive (`docs/spec/world.md` §5, steps 1–3) on the actuator's
    /// free joint: its velocity is imposed every step, it stays a dynamic
    /// body the contacts act on within the step, as on ODE.
    pub(super) fn drive_actuator(
        &mut self,
        actuator: usize,
        drive: &Drive,
        mode: ActuatorMode,
        direction: &mut [f64; 3],
    ) {
        let joint = self.bodies[actuator].joint;
        let (mut p, orientation) = self.sim.pose(joint);
        let (mut linear, _) = self.sim.velocity(joint);
        if beyond_bound(p, *direction, drive) {
            *direction = [0.0; 3];
            linear = [0.0; 3];
        }
        if mode == ActuatorMode::Move {
            linear = *direction;
            p[2] = drive.z_clamp;
        }
        // The values are the stored (finite) command, the state MuJoCo just
        // stepped (finite, or it would have reset) and the scene's clamp.
        let set = self
            .sim
            .set_velocity(joint, linear, [0.0; 3])
            .and_then(|()| self.sim.set_pose(joint, p, orientation));
        if let Err(e) = set {
            tracing::error!("the actuator drive was refused by MuJoCo: {e}");
        }
    }

    /// One step; `Err` names what MuJoCo found bad (it reset the data).
    pub(super) fn step(&mut self) -> Result<(), &'static str> {
        self.sim.step().map_err(|e| match e {
            MujocoError::Unstable(what) => what,
            _ => "an engine error",
        })
    }

    /// Whether the last step's contacts include the geom-tag pair `key`
    /// (smaller first).
    pub(super) fn touched(&self, key: (u32, u32)) -> bool {
        self.sim.contacts().any(|c| {
            let (a, b) = (c.geom1 as u32, c.geom2 as u32);
            (a.min(b), a.max(b)) == key
        })
    }

    #[cfg(feature = "testing")]
    pub(super) fn poison(&mut self, i: usize) {
        // Past the wrapper's finiteness check on purpose: this is the state
        // a diverging simulation leaves.
        let dof = self.bodies[i].joint.dof();
        if let Some(v) = self.sim.qvel_mut().get_mut(dof) {
            *v = f64::NAN;
        }
    }

    /// The first body whose state is lost, and how.
    pub(super) fn lost(&self) -> Option<(usize, &'static str)> {
        self.bodies.iter().enumerate().find_map(|(i, b)| {
            let (p, q) = self.sim.pose(b.joint);
            let (v, w) = self.sim.velocity(b.joint);
            let finite = p
                .iter()
                .chain(&q)
                .chain(&v)
                .chain(&w)
                .all(|x| x.is_finite());
            if !finite {
                Some((i, "a non-finite state"))
            } else if p.iter().any(|x| x.abs() > MAX_POSITION) {
                Some((i, "a position beyond ±1000 m"))
            } else {
                None
            }
        })
    }

    pub(super) fn states(&self, scene: &Scene) -> Vec<BodyState> {
        self.bodies
            .iter()
            .zip(&scene.bodies)
            .map(|(b, spec)| {
                let (position, orientation) = self.sim.pose(b.joint);
                let (lin_vel, ang_vel) = self.sim.velocity(b.joint);
                BodyState {
                    name: spec.name.clone(),
                    id: spec.id,
                    is_static: false,
                    position,
                    orientation,
                    lin_vel,
                    ang_vel,
                }
            })
            .collect()
    }
}
