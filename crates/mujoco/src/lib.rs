//! Safe wrapper over `mujoco-sys` (MuJoCo 2.2): a [`Simulation`] owns one
//! model, compiled from MJCF text held in memory, and its data.
//!
//! Model and data are created and freed together, so no data can be stepped
//! with another model's arrays. Everything the caller indexes (joints,
//! bodies, geoms) is checked against the model's sizes here.
//!
//! MuJoCo reports internal errors through a process-wide hook that must not
//! return; without one it writes `MUJOCO_LOG.TXT` into the working directory
//! and exits. This crate installs hooks once per process: warnings go to
//! `tracing`, errors are printed and abort (there is no state to return to).
//!
//! Conventions: positions and velocities are world-frame `[x, y, z]`;
//! quaternions are `[x, y, z, w]` in this API (MuJoCo stores `[w, x, y, z]`).

#![warn(clippy::undocumented_unsafe_blocks)]

use std::ffi::{c_char, c_int, CStr, CString};
use std::ptr::NonNull;
use std::sync::Once;

use mujoco_sys as sys;

/// Why MuJoCo refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MujocoError {
    #[error("the MuJoCo library is version {library}, but these bindings were built for {header}")]
    Version { library: i32, header: i32 },
    #[error("MJCF text contains a NUL byte or is larger than 2 GiB")]
    BadText,
    #[error("MuJoCo's virtual file system refused the model text (code {0})")]
    Vfs(c_int),
    #[error("MuJoCo cannot compile the model: {0}")]
    Compile(String),
    #[error("MuJoCo cannot allocate the model's data")]
    Data,
    #[error("the model has no {kind} named `{name}`")]
    Unknown { kind: &'static str, name: String },
    #[error("joint `{0}` is not a free joint")]
    NotFree(String),
    #[error("{field} must be finite")]
    NotFinite { field: &'static str },
    #[error("the simulation became unstable ({0}); MuJoCo reset its data")]
    Unstable(&'static str),
}

/// A MuJoCo error leaves no state to return to; the message is all there is.
unsafe extern "C" fn on_error(message: *const c_char) {
    let text = if message.is_null() {
        "(no message)".into()
    } else {
        // SAFETY: MuJoCo passes a NUL-terminated message that lives for the
        // duration of this call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy()
    };
    eprintln!("MuJoCo error: {text}");
    std::process::abort();
}

unsafe extern "C" fn on_warning(message: *const c_char) {
    if message.is_null() {
        return;
    }
    // SAFETY: as in `on_error`.
    let text = unsafe { CStr::from_ptr(message) }.to_string_lossy();
    tracing::warn!("MuJoCo: {text}");
}

static HOOKS: Once = Once::new();

fn install_hooks() -> Result<(), MujocoError> {
    HOOKS.call_once(|| {
        // SAFETY: the hooks are plain global function pointers MuJoCo reads
        // when it reports; `Once` makes this the only write, and it happens
        // before any model of this crate exists, so no MuJoCo call reads
        // them concurrently.
        unsafe {
            sys::mju_user_error = Some(on_error);
            sys::mju_user_warning = Some(on_warning);
        }
    });
    // SAFETY: mj_version takes nothing and returns a constant.
    let library = unsafe { sys::mj_version() };
    let header = sys::mjVERSION_HEADER as i32;
    if library != header {
        return Err(MujocoError::Version { library, header });
    }
    Ok(())
}

/// MuJoCo's version, e.g. `222` for 2.2.2.
pub fn version() -> i32 {
    // SAFETY: mj_version takes nothing and returns a constant.
    unsafe { sys::mj_version() }
}

/// The addresses of a free joint in `qpos` (7 numbers: position, then the
/// quaternion `[w, x, y, z]`) and `qvel` (6: the linear velocity in the world
/// frame, the angular velocity in the body frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FreeJoint {
    qpos: usize,
    dof: usize,
}

impl FreeJoint {
    /// Where the joint's 7 numbers start in [`Simulation::qpos`].
    pub fn qpos_index(self) -> usize {
        self.qpos
    }

    /// Where the joint's 6 numbers start in [`Simulation::qvel`].
    pub fn dof(self) -> usize {
        self.dof
    }
}

/// One contact of the last step, between two geoms by id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub geom1: usize,
    pub geom2: usize,
    /// Signed distance: negative when the geoms overlap, m.
    pub dist: f64,
}

/// A compiled model and its data.
pub struct Simulation {
    model: NonNull<sys::mjModel>,
    data: NonNull<sys::mjData>,
}

// SAFETY: model and data are plain heap memory owned by this value alone;
// MuJoCo keeps no thread-local or thread-bound state for them, so they may
// move to another thread. (Not Sync: `&self` methods only read, but nothing
// is gained by sharing.)
unsafe impl Send for Simulation {}

impl Drop for Simulation {
    fn drop(&mut self) {
        // SAFETY: both were allocated by MuJoCo in `from_mjcf`, are owned by
        // this value alone and are freed exactly once, data first.
        unsafe {
            sys::mj_deleteData(self.data.as_ptr());
            sys::mj_deleteModel(self.model.as_ptr());
        }
    }
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("nq", &self.model().nq)
            .field("nv", &self.model().nv)
            .field("time", &self.time())
            .finish()
    }
}

/// The model file's name inside the virtual file system.
const VFS_NAME: &CStr = c"model.xml";

impl Simulation {
    /// Compiles the MJCF document `xml` from memory (MuJoCo's virtual file
    /// system: no file is written) and allocates its data at `qpos0`.
    pub fn from_mjcf(xml: &str) -> Result<Simulation, MujocoError> {
        install_hooks()?;
        if xml.contains('\0') {
            return Err(MujocoError::BadText);
        }
        let size = c_int::try_from(xml.len()).map_err(|_| MujocoError::BadText)?;
        let mut vfs = zeroed_vfs();
        // SAFETY: `vfs` is a valid, exclusively borrowed mjVFS.
        unsafe { sys::mj_defaultVFS(&mut *vfs) };
        // SAFETY: `vfs` is valid and the name is NUL-terminated.
        let made = unsafe { sys::mj_makeEmptyFileVFS(&mut *vfs, VFS_NAME.as_ptr(), size) };
        if made != 0 {
            return Err(MujocoError::Vfs(made));
        }
        let model = {
            // SAFETY: `vfs` is valid and holds the file just made.
            let index = unsafe { sys::mj_findFileVFS(&*vfs, VFS_NAME.as_ptr()) };
            let slot = usize::try_from(index).map_err(|_| MujocoError::Vfs(index))?;
            let buffer = vfs.filedata[slot].cast::<u8>();
            if buffer.is_null() {
                // SAFETY: `vfs` is valid; this frees what it allocated.
                unsafe { sys::mj_deleteVFS(&mut *vfs) };
                return Err(MujocoError::Vfs(-1));
            }
            // SAFETY: mj_makeEmptyFileVFS allocated `size` bytes at `buffer`
            // for this file; the text is exactly `size` bytes and does not
            // overlap MuJoCo's buffer.
            unsafe { std::ptr::copy_nonoverlapping(xml.as_ptr(), buffer, xml.len()) };
            let mut error = [0 as c_char; 1000];
            // SAFETY: the name is NUL-terminated, `vfs` holds the file, and
            // `error` is a writable buffer of the length passed.
            let model = unsafe {
                sys::mj_loadXML(
                    VFS_NAME.as_ptr(),
                    &*vfs,
                    error.as_mut_ptr(),
                    error.len() as c_int,
                )
            };
            // SAFETY: `vfs` is valid; the model copied what it needs.
            unsafe { sys::mj_deleteVFS(&mut *vfs) };
            NonNull::new(model).ok_or_else(|| {
                // SAFETY: MuJoCo NUL-terminates the message within the buffer
                // (it was zeroed, and MuJoCo writes at most len − 1 bytes).
                let text = unsafe { CStr::from_ptr(error.as_ptr()) };
                MujocoError::Compile(text.to_string_lossy().trim().to_owned())
            })?
        };
        // SAFETY: `model` is a valid model just compiled.
        let data = unsafe { sys::mj_makeData(model.as_ptr()) };
        let Some(data) = NonNull::new(data) else {
            // SAFETY: `model` is valid and owned here alone.
            unsafe { sys::mj_deleteModel(model.as_ptr()) };
            return Err(MujocoError::Data);
        };
        Ok(Simulation { model, data })
    }

    fn model(&self) -> &sys::mjModel {
        // SAFETY: the model is valid for the life of `self` and MuJoCo never
        // changes it during a step.
        unsafe { self.model.as_ref() }
    }

    fn data(&self) -> &sys::mjData {
        // SAFETY: the data is valid for the life of `self`; `&self` excludes
        // a concurrent step.
        unsafe { self.data.as_ref() }
    }

    /// The model's time step, s.
    pub fn timestep(&self) -> f64 {
        self.model().opt.timestep
    }

    /// Simulated seconds since the data's last reset.
    pub fn time(&self) -> f64 {
        self.data().time
    }

    fn id(&self, kind: sys::mjtObj, what: &'static str, name: &str) -> Result<usize, MujocoError> {
        let unknown = || MujocoError::Unknown {
            kind: what,
            name: name.to_owned(),
        };
        let c_name = CString::new(name).map_err(|_| unknown())?;
        // SAFETY: the model is valid and the name NUL-terminated.
        let id = unsafe { sys::mj_name2id(self.model.as_ptr(), kind as c_int, c_name.as_ptr()) };
        usize::try_from(id).map_err(|_| unknown())
    }

    /// The body named `name`.
    pub fn body(&self, name: &str) -> Result<usize, MujocoError> {
        self.id(sys::mjtObj__mjOBJ_BODY, "body", name)
    }

    /// The geom named `name`.
    pub fn geom(&self, name: &str) -> Result<usize, MujocoError> {
        self.id(sys::mjtObj__mjOBJ_GEOM, "geom", name)
    }

    /// The free joint named `name`.
    pub fn free_joint(&self, name: &str) -> Result<FreeJoint, MujocoError> {
        let id = self.id(sys::mjtObj__mjOBJ_JOINT, "joint", name)?;
        let m = self.model();
        // SAFETY: `id` < njnt (mj_name2id found it), and the jnt_* arrays
        // have njnt entries.
        let (kind, qpos, dof) = unsafe {
            (
                *m.jnt_type.add(id),
                *m.jnt_qposadr.add(id),
                *m.jnt_dofadr.add(id),
            )
        };
        if kind != sys::mjtJoint__mjJNT_FREE as c_int {
            return Err(MujocoError::NotFree(name.to_owned()));
        }
        let (Ok(qpos), Ok(dof)) = (usize::try_from(qpos), usize::try_from(dof)) else {
            return Err(MujocoError::NotFree(name.to_owned()));
        };
        Ok(FreeJoint { qpos, dof })
    }

    /// The mass of body `body` (an id from [`Simulation::body`]), kg; `None`
    /// for an id the model lacks.
    pub fn body_mass(&self, body: usize) -> Option<f64> {
        let m = self.model();
        // SAFETY: checked against nbody, the length of body_mass.
        (body < m.nbody as usize).then(|| unsafe { *m.body_mass.add(body) })
    }

    fn slice(&self, ptr: *mut f64, len: c_int) -> &[f64] {
        // SAFETY: `ptr` is one of the data's arrays with `len` entries
        // (the callers pass the matching size from the model), valid for
        // the life of `self`, and `&self` excludes writers.
        unsafe { std::slice::from_raw_parts(ptr, len.max(0) as usize) }
    }

    fn slice_mut(&mut self, ptr: *mut f64, len: c_int) -> &mut [f64] {
        // SAFETY: as in `slice`; `&mut self` makes this the only borrow.
        unsafe { std::slice::from_raw_parts_mut(ptr, len.max(0) as usize) }
    }

    /// Generalised positions (nq).
    pub fn qpos(&self) -> &[f64] {
        self.slice(self.data().qpos, self.model().nq)
    }

    /// Generalised velocities (nv).
    pub fn qvel(&self) -> &[f64] {
        self.slice(self.data().qvel, self.model().nv)
    }

    /// Generalised positions, writable (nq). Non-finite values written here
    /// make the next step report [`MujocoError::Unstable`].
    pub fn qpos_mut(&mut self) -> &mut [f64] {
        let (ptr, len) = (self.data().qpos, self.model().nq);
        self.slice_mut(ptr, len)
    }

    /// Generalised velocities, writable (nv).
    pub fn qvel_mut(&mut self) -> &mut [f64] {
        let (ptr, len) = (self.data().qvel, self.model().nv);
        self.slice_mut(ptr, len)
    }

    /// The force and torque applied to body `body` at its centre of mass,
    /// world frame (`[fx, fy, fz, tx, ty, tz]`), kept until changed or reset;
    /// `None` for an id the model lacks.
    pub fn applied_force_mut(&mut self, body: usize) -> Option<&mut [f64]> {
        let (ptr, n) = (self.data().xfrc_applied, self.model().nbody);
        let all = self.slice_mut(ptr, n.saturating_mul(6));
        all.get_mut(6 * body..6 * body + 6)
    }

    /// Back to the model's initial state (`qpos0`, at rest, time 0, no
    /// applied forces, no warm start): what makes runs repeat bit for bit.
    pub fn reset(&mut self) {
        // SAFETY: model and data belong together and are valid.
        unsafe { sys::mj_resetData(self.model.as_ptr(), self.data.as_ptr()) };
    }

    /// One time step. MuJoCo itself resets the data when a position,
    /// velocity or acceleration is non-finite or beyond 1e10; that is
    /// reported as [`MujocoError::Unstable`].
    pub fn step(&mut self) -> Result<(), MujocoError> {
        let before = self.bad_state_counts();
        // SAFETY: model and data belong together and are valid; `&mut self`
        // makes this the only access during the step.
        unsafe { sys::mj_step(self.model.as_ptr(), self.data.as_ptr()) };
        let after = self.bad_state_counts();
        let names = ["a bad position", "a bad velocity", "a bad acceleration"];
        match (0..3).find(|&k| after[k] != before[k]) {
            Some(k) => Err(MujocoError::Unstable(names[k])),
            None => Ok(()),
        }
    }

    fn bad_state_counts(&self) -> [c_int; 3] {
        let w = &self.data().warning;
        [
            w[sys::mjtWarning__mjWARN_BADQPOS as usize].number,
            w[sys::mjtWarning__mjWARN_BADQVEL as usize].number,
            w[sys::mjtWarning__mjWARN_BADQACC as usize].number,
        ]
    }

    /// The contacts the last step's collision found.
    pub fn contacts(&self) -> impl Iterator<Item = Contact> + '_ {
        let d = self.data();
        let n = d.ncon.max(0) as usize;
        let all: &[sys::mjContact] = if n == 0 || d.contact.is_null() {
            &[]
        } else {
            // SAFETY: `contact` holds `ncon` initialised entries after a
            // step, valid for the life of `self`.
            unsafe { std::slice::from_raw_parts(d.contact, n) }
        };
        all.iter().map(|c| Contact {
            geom1: c.geom1.max(0) as usize,
            geom2: c.geom2.max(0) as usize,
            dist: c.dist,
        })
    }

    /// The free joint's position and orientation `[x, y, z, w]`.
    pub fn pose(&self, joint: FreeJoint) -> ([f64; 3], [f64; 4]) {
        let q = &self.qpos()[joint.qpos..joint.qpos + 7];
        ([q[0], q[1], q[2]], [q[4], q[5], q[6], q[3]])
    }

    /// Places the free joint's body; velocities are untouched.
    pub fn set_pose(
        &mut self,
        joint: FreeJoint,
        position: [f64; 3],
        orientation: [f64; 4],
    ) -> Result<(), MujocoError> {
        finite("position", &position)?;
        finite("orientation", &orientation)?;
        let [x, y, z, w] = orientation;
        self.qpos_mut()[joint.qpos..joint.qpos + 7].copy_from_slice(&[
            position[0],
            position[1],
            position[2],
            w,
            x,
            y,
            z,
        ]);
        Ok(())
    }

    /// The free joint's linear and angular velocity, both world frame.
    pub fn velocity(&self, joint: FreeJoint) -> ([f64; 3], [f64; 3]) {
        let v = &self.qvel()[joint.dof..joint.dof + 6];
        let (_, orientation) = self.pose(joint);
        ([v[0], v[1], v[2]], rotate(orientation, [v[3], v[4], v[5]]))
    }

    /// Sets the free joint's linear and angular velocity, both world frame.
    pub fn set_velocity(
        &mut self,
        joint: FreeJoint,
        linear: [f64; 3],
        angular: [f64; 3],
    ) -> Result<(), MujocoError> {
        finite("linear velocity", &linear)?;
        finite("angular velocity", &angular)?;
        let (_, [x, y, z, w]) = self.pose(joint);
        // The free joint's rotational dofs are in the body frame.
        let local = rotate([-x, -y, -z, w], angular);
        let v = &mut self.qvel_mut()[joint.dof..joint.dof + 6];
        v[..3].copy_from_slice(&linear);
        v[3..].copy_from_slice(&local);
        Ok(())
    }
}

/// An all-zero mjVFS on the heap: it is 2 MB, too much for a thread's stack.
fn zeroed_vfs() -> Box<sys::mjVFS> {
    let layout = std::alloc::Layout::new::<sys::mjVFS>();
    // SAFETY: the layout has a non-zero size (a 2 MB struct).
    let raw = unsafe { std::alloc::alloc_zeroed(layout) }.cast::<sys::mjVFS>();
    if raw.is_null() {
        std::alloc::handle_alloc_error(layout);
    }
    // SAFETY: `raw` was allocated by the global allocator with mjVFS's
    // layout, as Box requires, and mjVFS is integers, byte arrays and null
    // pointers, for which all-zero bytes are a valid value.
    unsafe { Box::from_raw(raw) }
}

fn finite(field: &'static str, values: &[f64]) -> Result<(), MujocoError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(MujocoError::NotFinite { field })
    }
}

/// `v` rotated by the unit quaternion `[x, y, z, w]`, with MuJoCo's own
/// routine so that the frames agree with the engine's to the last bit.
fn rotate([x, y, z, w]: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let quat = [w, x, y, z];
    let mut out = [0.0; 3];
    // SAFETY: mju_rotVecQuat reads 3 and 4 numbers and writes 3, all
    // pointing at the local arrays above.
    unsafe { sys::mju_rotVecQuat(out.as_mut_ptr(), v.as_ptr(), quat.as_ptr()) };
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const BALL: &str = r#"<mujoco>
      <option timestep="0.001" gravity="0 0 -9.81"/>
      <worldbody>
        <geom name="floor" type="plane" size="0 0 1"/>
        <body name="ball" pos="0 0 0.5">
          <freejoint name="ball"/>
          <geom name="ball" type="sphere" size="0.05" mass="1"/>
        </body>
      </worldbody>
    </mujoco>"#;

    #[test]
    fn a_ball_falls_and_lands_on_the_floor() {
        let mut sim = Simulation::from_mjcf(BALL).unwrap();
        let ball = sim.free_joint("ball").unwrap();
        assert_eq!(sim.timestep(), 0.001);
        for _ in 0..100 {
            sim.step().unwrap();
        }
        // Free fall for 0.1 s: about g t² / 2 = 4.9 cm.
        let (p, _) = sim.pose(ball);
        assert!((0.5 - p[2] - 0.049).abs() < 1e-3, "{p:?}");
        assert_eq!(sim.contacts().count(), 0);
        for _ in 0..2000 {
            sim.step().unwrap();
        }
        let (p, _) = sim.pose(ball);
        assert!((p[2] - 0.05).abs() < 2e-3, "resting at {p:?}");
        let floor = sim.geom("floor").unwrap();
        assert!(sim.contacts().any(|c| c.geom1 == floor || c.geom2 == floor));
    }

    #[test]
    fn reset_repeats_a_run_bit_for_bit() {
        let mut sim = Simulation::from_mjcf(BALL).unwrap();
        let ball = sim.free_joint("ball").unwrap();
        let run = |sim: &mut Simulation| {
            sim.reset();
            sim.set_velocity(ball, [0.3, 0.0, 0.0], [0.0, 0.0, 2.0])
                .unwrap();
            (0..700)
                .map(|_| {
                    sim.step().unwrap();
                    sim.qpos().to_vec()
                })
                .collect::<Vec<_>>()
        };
        let first = run(&mut sim);
        assert_eq!(first, run(&mut sim));
    }

    #[test]
    fn velocities_are_world_frame_both_ways() {
        let mut sim = Simulation::from_mjcf(BALL).unwrap();
        let ball = sim.free_joint("ball").unwrap();
        // A quarter turn about z: body x is world y.
        let h = std::f64::consts::FRAC_PI_4;
        sim.set_pose(ball, [0.0, 0.0, 0.5], [0.0, 0.0, h.sin(), h.cos()])
            .unwrap();
        sim.set_velocity(ball, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0])
            .unwrap();
        let local = &sim.qvel()[3..6];
        assert!((local[1] + 1.0).abs() < 1e-12, "{local:?}");
        let (linear, angular) = sim.velocity(ball);
        assert_eq!(linear, [1.0, 0.0, 0.0]);
        assert!((angular[0] - 1.0).abs() < 1e-12 && angular[1].abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_refused_with_its_reason() {
        let err = Simulation::from_mjcf("<mujoco><worldbody><geom type=\"box\"/>").unwrap_err();
        assert!(matches!(err, MujocoError::Compile(_)), "{err}");
        assert_eq!(
            Simulation::from_mjcf("a\0b").unwrap_err(),
            MujocoError::BadText
        );
        let mut sim = Simulation::from_mjcf(BALL).unwrap();
        assert!(matches!(
            sim.body("nobody"),
            Err(MujocoError::Unknown { .. })
        ));
        assert!(matches!(
            sim.free_joint("floor"),
            Err(MujocoError::Unknown { .. })
        ));
        let ball = sim.free_joint("ball").unwrap();
        assert!(sim
            .set_pose(ball, [f64::NAN, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
            .is_err());
    }

    #[test]
    fn a_non_finite_state_is_reported_and_reset() {
        let mut sim = Simulation::from_mjcf(BALL).unwrap();
        sim.qvel_mut()[0] = f64::NAN;
        assert!(matches!(sim.step(), Err(MujocoError::Unstable(_))));
        assert!(sim.qvel().iter().all(|v| v.is_finite()));
        assert_eq!(sim.body_mass(sim.body("ball").unwrap()), Some(1.0));
        assert!(sim.applied_force_mut(99).is_none());
    }
}
