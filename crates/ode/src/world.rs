//! The world: owner of every ODE object, and the collide-and-step loop.

use std::any::Any;
use std::ffi::c_void;
use std::os::raw::c_int;
use std::panic::{self, AssertUnwindSafe};
use std::ptr::NonNull;
use std::time::{Duration, Instant};

use ode_sys::{dContact, dContactGeom, dGeomID, dJointGroupID, dWorldID};

use crate::arena::{next_arena_id, Arena};
use crate::body::{Body, BodyEntry, BodyMut};
use crate::check::check_finite3;
use crate::contact::{ContactPair, GeomInfo, Surface};
use crate::geom::GeomEntry;
use crate::init::{ensure_thread, global_lock, rand_get_seed_locked, rand_set_seed_locked};
use crate::{BodyBuilder, BodyHandle, GeomBuilder, GeomHandle, OdeError, Shape, StepParams};

/// The broad-phase structure at the top level of a world.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpaceKind {
    /// Tests every pair (`dSimpleSpace`). Exact and, for a handful of
    /// bodies, as fast as anything else.
    #[default]
    Simple,
    /// Multi-resolution hash grid (`dHashSpace`). Kept for the regression
    /// test of libode 0.16's missed-contact bug; do not use for the thesis
    /// world.
    Hash,
}

/// What one [`World::step`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepReport {
    /// Contact joints created (one per accepted contact point).
    pub contact_joints: usize,
    /// How long the step waited for ODE's process-wide lock: the time
    /// other worlds of the process were stepping, not this one's cost.
    pub waited_for_lock: Duration,
}

/// An ODE world with its top-level space and contact joint group.
///
/// Owns all bodies and geoms; dropping it destroys them in the order ODE
/// requires (contacts, then geoms with the space, then bodies with the
/// world).
pub struct World {
    raw: NonNull<ode_sys::dxWorld>,
    space: NonNull<ode_sys::dxSpace>,
    contacts: NonNull<ode_sys::dxJointGroup>,
    space_kind: SpaceKind,
    params: StepParams,
    bodies: Arena<BodyEntry>,
    geoms: Arena<GeomEntry>,
    contact_buf: Vec<dContactGeom>,
    rand_seed: u64,
}

// SAFETY: ODE objects are plain heap data not tied to the creating thread.
// Every method that needs ODE's per-thread data calls `ensure_thread` first,
// and everything that touches ODE's process-wide state (collision, stepping,
// the random generator, geom creation) runs under the global lock. `World` is
// not `Sync`: all access goes through `&mut self` or views borrowed from it.
unsafe impl Send for World {}

impl World {
    /// Creates an empty world with `params` and a top-level space of `kind`.
    pub fn new(params: StepParams, kind: SpaceKind) -> Result<World, OdeError> {
        params.validate()?;
        ensure_thread()?;
        let _guard = global_lock();
        // SAFETY: the library is initialised; a null parent space means "top
        // level"; 0 as the joint group's size is ODE's "default" value.
        let (raw, space, contacts) = unsafe {
            let raw = ode_sys::dWorldCreate();
            let space = match kind {
                SpaceKind::Simple => ode_sys::dSimpleSpaceCreate(std::ptr::null_mut()),
                SpaceKind::Hash => ode_sys::dHashSpaceCreate(std::ptr::null_mut()),
            };
            let contacts = ode_sys::dJointGroupCreate(0);
            (raw, space, contacts)
        };
        let (Some(raw), Some(space), Some(contacts)) = (
            NonNull::new(raw),
            NonNull::new(space),
            NonNull::new(contacts),
        ) else {
            // SAFETY: each pointer is either null (skipped) or a freshly
            // created object nobody else refers to.
            unsafe {
                if !contacts.is_null() {
                    ode_sys::dJointGroupDestroy(contacts);
                }
                if !space.is_null() {
                    ode_sys::dSpaceDestroy(space);
                }
                if !raw.is_null() {
                    ode_sys::dWorldDestroy(raw);
                }
            }
            return Err(OdeError::Ode("create a world"));
        };
        let world = World {
            raw,
            space,
            contacts,
            space_kind: kind,
            params,
            bodies: Arena::new(next_arena_id()),
            geoms: Arena::new(next_arena_id()),
            contact_buf: vec![dContactGeom::default(); params.max_contacts_per_pair],
            rand_seed: 0,
        };
        world.apply_params();
        Ok(world)
    }

    fn apply_params(&self) {
        let p = &self.params;
        let w = self.raw.as_ptr();
        let ad = &p.auto_disable;
        // SAFETY: `w` is the live world; every value passed validation in
        // `StepParams::validate` (integers fit in c_int there).
        unsafe {
            ode_sys::dWorldSetGravity(w, p.gravity[0], p.gravity[1], p.gravity[2]);
            ode_sys::dWorldSetERP(w, p.erp);
            ode_sys::dWorldSetCFM(w, p.cfm);
            ode_sys::dWorldSetQuickStepNumIterations(w, p.quickstep_iterations as c_int);
            ode_sys::dWorldSetQuickStepW(w, p.sor_w);
            ode_sys::dWorldSetContactMaxCorrectingVel(w, p.contact_max_correcting_vel);
            ode_sys::dWorldSetContactSurfaceLayer(w, p.contact_surface_layer);
            ode_sys::dWorldSetDamping(w, p.linear_damping, p.angular_damping);
            ode_sys::dWorldSetAutoDisableFlag(w, c_int::from(ad.enabled));
            ode_sys::dWorldSetAutoDisableLinearThreshold(w, ad.linear_threshold);
            ode_sys::dWorldSetAutoDisableAngularThreshold(w, ad.angular_threshold);
            ode_sys::dWorldSetAutoDisableTime(w, ad.idle_time);
            ode_sys::dWorldSetAutoDisableSteps(w, ad.idle_steps as c_int);
            ode_sys::dWorldSetAutoDisableAverageSamplesCount(w, ad.average_samples);
        }
    }

    pub fn params(&self) -> &StepParams {
        &self.params
    }

    pub fn space_kind(&self) -> SpaceKind {
        self.space_kind
    }

    /// Creates a body. It takes the world's auto-disable settings.
    pub fn insert_body(&mut self, b: BodyBuilder) -> Result<BodyHandle, OdeError> {
        let q = b.validate()?;
        ensure_thread()?;
        // SAFETY: the world is live; all values were validated above (mass and
        // moments positive and finite, pose and velocities finite, `q` a unit
        // quaternion in ODE order); `mass` is a plain struct ODE fills in.
        let raw = unsafe {
            let raw = ode_sys::dBodyCreate(self.raw.as_ptr());
            if raw.is_null() {
                return Err(OdeError::Ode("create a body"));
            }
            let mut mass = ode_sys::dMass::default();
            ode_sys::dMassSetZero(&mut mass);
            let [ixx, iyy, izz] = b.inertia;
            let [ixy, ixz, iyz] = b.products;
            ode_sys::dMassSetParameters(
                &mut mass, b.mass, 0.0, 0.0, 0.0, ixx, iyy, izz, ixy, ixz, iyz,
            );
            ode_sys::dBodySetMass(raw, &mass);
            ode_sys::dBodySetGravityMode(raw, c_int::from(b.gravity));
            ode_sys::dBodySetPosition(raw, b.position[0], b.position[1], b.position[2]);
            ode_sys::dBodySetQuaternion(raw, q.as_ptr());
            let v = b.linear_velocity;
            ode_sys::dBodySetLinearVel(raw, v[0], v[1], v[2]);
            let w = b.angular_velocity;
            ode_sys::dBodySetAngularVel(raw, w[0], w[1], w[2]);
            raw
        };
        Ok(BodyHandle(self.bodies.insert(BodyEntry {
            raw,
            geoms: Vec::new(),
        })))
    }

    /// Creates a geom in the top-level space, optionally attached to a body.
    pub fn insert_geom(&mut self, g: GeomBuilder) -> Result<GeomHandle, OdeError> {
        let shape = g.shape.validated()?;
        let body_raw = match g.body {
            Some(h) => {
                if matches!(shape, Shape::Plane { .. }) {
                    return Err(OdeError::PlaneOnBody);
                }
                Some(self.bodies.get(h.0).ok_or(OdeError::StaleBody(h))?.raw)
            }
            None => None,
        };
        check_finite3("geom offset", g.offset)?;
        // ODE asserts (aborts) when a geom without a body is given an offset.
        let offset = (g.offset != [0.0; 3]).then_some(g.offset);
        if offset.is_some() && body_raw.is_none() {
            return Err(OdeError::OffsetWithoutBody);
        }
        ensure_thread()?;
        let _guard = global_lock();
        let index = self.geoms.next_index();
        let space = self.space.as_ptr();
        // SAFETY: the space is live; shapes were validated (positive finite
        // sizes, unit plane normal); `body_raw` is a live body of this world,
        // set before the (finite) offset, which ODE only accepts on a geom
        // with a body.
        // The geom's data pointer carries its arena index, read back only by
        // the near-callback of this world.
        let raw = unsafe {
            let raw = match shape {
                Shape::Sphere { radius } => ode_sys::dCreateSphere(space, radius),
                Shape::Cuboid { size } => ode_sys::dCreateBox(space, size[0], size[1], size[2]),
                Shape::Cylinder { radius, length } => {
                    ode_sys::dCreateCylinder(space, radius, length)
                }
                Shape::Plane { normal, offset } => {
                    ode_sys::dCreatePlane(space, normal[0], normal[1], normal[2], offset)
                }
            };
            if raw.is_null() {
                return Err(OdeError::Ode("create a geom"));
            }
            if let Some(b) = body_raw {
                ode_sys::dGeomSetBody(raw, b);
                if let Some([x, y, z]) = offset {
                    ode_sys::dGeomSetOffsetPosition(raw, x, y, z);
                }
            }
            ode_sys::dGeomSetData(raw, index as usize as *mut c_void);
            raw
        };
        let handle = GeomHandle(self.geoms.insert(GeomEntry {
            raw,
            body: g.body,
            tag: g.tag,
        }));
        debug_assert_eq!(handle.0.index, index);
        if let Some(b) = g.body.and_then(|h| self.bodies.get_mut(h.0)) {
            b.geoms.push(handle);
        }
        Ok(handle)
    }

    /// Destroys a geom.
    pub fn remove_geom(&mut self, h: GeomHandle) -> Result<(), OdeError> {
        let entry = self.geoms.remove(h.0).ok_or(OdeError::StaleGeom(h))?;
        if let Some(b) = entry.body.and_then(|b| self.bodies.get_mut(b.0)) {
            b.geoms.retain(|&g| g != h);
        }
        ensure_thread()?;
        let _guard = global_lock();
        // SAFETY: the geom was live and is now unreachable through the arena;
        // no contact joint refers to it (the group is emptied every step).
        unsafe { ode_sys::dGeomDestroy(entry.raw) };
        Ok(())
    }

    /// Destroys a body together with the geoms attached to it.
    pub fn remove_body(&mut self, h: BodyHandle) -> Result<(), OdeError> {
        let entry = self.bodies.remove(h.0).ok_or(OdeError::StaleBody(h))?;
        for g in entry.geoms {
            self.remove_geom(g)?;
        }
        // SAFETY: the body was live and is now unreachable through the arena;
        // its geoms are gone and no contact joint refers to it.
        unsafe { ode_sys::dBodyDestroy(entry.raw) };
        Ok(())
    }

    pub fn body(&self, h: BodyHandle) -> Result<Body<'_>, OdeError> {
        let entry = self.bodies.get(h.0).ok_or(OdeError::StaleBody(h))?;
        Ok(Body::new(entry.raw))
    }

    pub fn body_mut(&mut self, h: BodyHandle) -> Result<BodyMut<'_>, OdeError> {
        let entry = self.bodies.get(h.0).ok_or(OdeError::StaleBody(h))?;
        Ok(BodyMut::new(entry.raw))
    }

    pub fn body_count(&self) -> usize {
        self.bodies.values().count()
    }

    pub fn geom_count(&self) -> usize {
        self.geoms.values().count()
    }

    /// Seeds this world's random stream (QuickStep's constraint-row
    /// shuffling). Each world keeps its own stream and swaps it into ODE's
    /// single global generator around every step, so identical worlds
    /// stepped with identical inputs give bit-identical results even when
    /// other worlds are stepped in between or on other threads.
    pub fn set_rand_seed(&mut self, seed: u64) {
        self.rand_seed = seed;
    }

    pub fn rand_seed(&self) -> u64 {
        self.rand_seed
    }

    /// Collision detection, contact joints, one `dWorldQuickStep`, and
    /// emptying the contact group.
    ///
    /// `near` is called once per pair of geoms that touch; it returns the
    /// contact surface to use, or `None` to let them pass through each
    /// other. A contact joint is created for every contact point with
    /// non-negative depth (ODE's colliders occasionally report negative
    /// depths; a joint for one would pull the geoms together). If `near`
    /// panics, the step is abandoned (no integration happens) and the panic
    /// is resumed here, after the FFI boundary.
    pub fn step<F>(&mut self, mut near: F) -> Result<StepReport, OdeError>
    where
        F: FnMut(&ContactPair<'_>) -> Option<Surface>,
    {
        ensure_thread()?;
        let asked = Instant::now();
        let guard = global_lock();
        let waited_for_lock = asked.elapsed();
        rand_set_seed_locked(&guard, self.rand_seed);
        let mut ctx = Collide {
            world: self.raw.as_ptr(),
            group: self.contacts.as_ptr(),
            geoms: &self.geoms,
            buf: &mut self.contact_buf,
            near: &mut near,
            panic: None,
            joints: 0,
        };
        // SAFETY: `ctx` outlives the call and is only accessed through the
        // data pointer by `near_trampoline::<F>`, instantiated with the same
        // `F`; the space is live; the global lock is held.
        unsafe {
            ode_sys::dSpaceCollide(
                self.space.as_ptr(),
                (&raw mut ctx).cast::<c_void>(),
                Some(near_trampoline::<F>),
            );
        }
        let (panic, joints) = (ctx.panic.take(), ctx.joints);
        let ok = if panic.is_some() {
            true
        } else {
            // SAFETY: the world is live and the step size validated positive.
            unsafe { ode_sys::dWorldQuickStep(self.raw.as_ptr(), self.params.step_size) != 0 }
        };
        // SAFETY: the group is live; its joints are not referenced elsewhere.
        unsafe { ode_sys::dJointGroupEmpty(self.contacts.as_ptr()) };
        self.rand_seed = rand_get_seed_locked(&guard);
        drop(guard);
        if let Some(payload) = panic {
            panic::resume_unwind(payload);
        }
        if ok {
            Ok(StepReport {
                contact_joints: joints,
                waited_for_lock,
            })
        } else {
            Err(OdeError::Ode(
                "allocate memory for a step (dWorldQuickStep)",
            ))
        }
    }
}

impl Drop for World {
    fn drop(&mut self) {
        // Per-thread data is needed for destruction too; if it cannot be
        // allocated, leaking is the only safe option.
        if ensure_thread().is_err() {
            return;
        }
        let _guard = global_lock();
        // SAFETY: the three objects are live and owned by this world alone;
        // contacts go first (they reference bodies), the space destroys its
        // geoms (cleanup mode is on by default), the world its bodies.
        unsafe {
            ode_sys::dJointGroupDestroy(self.contacts.as_ptr());
            ode_sys::dSpaceDestroy(self.space.as_ptr());
            ode_sys::dWorldDestroy(self.raw.as_ptr());
        }
    }
}

struct Collide<'a, F> {
    world: dWorldID,
    group: dJointGroupID,
    geoms: &'a Arena<GeomEntry>,
    buf: &'a mut [dContactGeom],
    near: &'a mut F,
    panic: Option<Box<dyn Any + Send>>,
    joints: usize,
}

impl<F> Collide<'_, F>
where
    F: FnMut(&ContactPair<'_>) -> Option<Surface>,
{
    fn info(&self, g: dGeomID) -> Option<GeomInfo> {
        // SAFETY: `g` is a geom of this world's space (ODE passes only those),
        // whose data pointer holds its arena index.
        let index = unsafe { ode_sys::dGeomGetData(g) } as usize;
        let (handle, entry) = self.geoms.by_index(index)?;
        (entry.raw == g).then_some(GeomInfo {
            geom: GeomHandle(handle),
            body: entry.body,
            tag: entry.tag,
        })
    }

    fn near(&mut self, g1: dGeomID, g2: dGeomID) {
        let (Some(first), Some(second)) = (self.info(g1), self.info(g2)) else {
            return;
        };
        if first.body.is_none() && second.body.is_none() {
            return;
        }
        // SAFETY: both geoms are live; `buf` has room for `buf.len()` contact
        // geoms (validated ≤ 256 < 2^16, the count field of the flags) laid
        // out with the stride we pass.
        let n = unsafe {
            ode_sys::dCollide(
                g1,
                g2,
                self.buf.len() as c_int,
                self.buf.as_mut_ptr(),
                std::mem::size_of::<dContactGeom>() as c_int,
            )
        };
        let n = usize::try_from(n).unwrap_or(0).min(self.buf.len());
        if n == 0 {
            return;
        }
        let pair = ContactPair {
            first,
            second,
            raw: &self.buf[..n],
        };
        let Some(surface) = (self.near)(&pair) else {
            return;
        };
        let surface = surface.to_raw();
        // SAFETY: both geoms are live, so are their bodies (null for static
        // geoms, which dJointAttach accepts); world and group are live; the
        // contact struct is fully initialised and copied by ODE.
        unsafe {
            let b1 = ode_sys::dGeomGetBody(g1);
            let b2 = ode_sys::dGeomGetBody(g2);
            for geom in self.buf[..n].iter().filter(|c| c.depth >= 0.0) {
                let contact = dContact {
                    surface,
                    geom: *geom,
                    fdir1: [0.0; 4],
                };
                let joint = ode_sys::dJointCreateContact(self.world, self.group, &contact);
                ode_sys::dJointAttach(joint, b1, b2);
                self.joints += 1;
            }
        }
    }
}

/// Called by `dSpaceCollide` for every candidate pair.
unsafe extern "C" fn near_trampoline<F>(data: *mut c_void, g1: dGeomID, g2: dGeomID)
where
    F: FnMut(&ContactPair<'_>) -> Option<Surface>,
{
    // SAFETY: `data` is the `&mut Collide<F>` that `World::step` passed to
    // dSpaceCollide with this very instantiation; it is alive and not
    // otherwise borrowed until dSpaceCollide returns.
    let ctx = unsafe { &mut *data.cast::<Collide<'_, F>>() };
    if ctx.panic.is_some() {
        return;
    }
    // A panic must not unwind into C: keep it and resume after dSpaceCollide.
    if let Err(payload) = panic::catch_unwind(AssertUnwindSafe(|| ctx.near(g1, g2))) {
        ctx.panic = Some(payload);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ContactMode, SurfaceParams};

    fn ball_world() -> (World, BodyHandle) {
        let mut w = World::new(StepParams::gazebo(), SpaceKind::Simple).unwrap();
        w.insert_geom(GeomBuilder::plane([0.0, 0.0, 1.0], 0.0))
            .unwrap();
        let b = w
            .insert_body(BodyBuilder::new(1.0, [1e-3; 3]).position([0.0, 0.0, 0.5]))
            .unwrap();
        w.insert_geom(GeomBuilder::sphere(0.1).attached_to(b).tag(1))
            .unwrap();
        (w, b)
    }

    fn surface() -> Surface {
        SurfaceParams {
            mode: ContactMode::MU2 | ContactMode::APPROX1,
            mu: 0.5,
            mu2: 0.5,
            ..SurfaceParams::default()
        }
        .check()
        .unwrap()
    }

    #[test]
    fn ball_falls_and_rests_on_the_ground() {
        let (mut w, b) = ball_world();
        let s = surface();
        let mut touched = false;
        for _ in 0..2000 {
            let r = w.step(|_| Some(s)).unwrap();
            touched |= r.contact_joints > 0;
        }
        assert!(touched);
        let z = w.body(b).unwrap().position()[2];
        assert!((z - 0.1).abs() < 0.01, "z = {z}");
    }

    #[test]
    fn a_cylinder_stands_on_its_flat_end_along_the_body_z_axis() {
        let mut w = World::new(StepParams::gazebo(), SpaceKind::Simple).unwrap();
        w.insert_geom(GeomBuilder::plane([0.0, 0.0, 1.0], 0.0))
            .unwrap();
        let b = w
            .insert_body(BodyBuilder::new(1.0, [3.3e-3, 3.3e-3, 5e-3]).position([0.0, 0.0, 0.2]))
            .unwrap();
        w.insert_geom(GeomBuilder::cylinder(0.1, 0.1).attached_to(b))
            .unwrap();
        let s = surface();
        for _ in 0..2000 {
            w.step(|_| Some(s)).unwrap();
        }
        let body = w.body(b).unwrap();
        // On its end face the centre rests half the length (0.05) up; on its
        // side it would rest a radius (0.1) up.
        let z = body.position()[2];
        assert!((z - 0.05).abs() < 0.005, "z = {z}");
        let q = body.orientation();
        assert!(q[0].abs() < 1e-3 && q[1].abs() < 1e-3, "tilted: {q:?}");
    }

    #[test]
    fn an_offset_geom_rests_with_its_body_beside_it() {
        let mut w = World::new(StepParams::gazebo(), SpaceKind::Simple).unwrap();
        w.insert_geom(GeomBuilder::plane([0.0, 0.0, 1.0], 0.0))
            .unwrap();
        // A 0.2 m cube whose centre of mass sits 0.05 m to +x of its centre.
        let b = w
            .insert_body(
                BodyBuilder::new(1.0, [6e-3, 6e-3, 6e-3])
                    .products_of_inertia([0.0, 0.0, 0.0])
                    .position([0.05, 0.0, 0.1]),
            )
            .unwrap();
        w.insert_geom(
            GeomBuilder::cuboid([0.2; 3])
                .attached_to(b)
                .offset([-0.05, 0.0, 0.0]),
        )
        .unwrap();
        let s = surface();
        for _ in 0..1000 {
            w.step(|_| Some(s)).unwrap();
        }
        let body = w.body(b).unwrap();
        // The cube rests on its face: the centre of mass stays 0.05 m to +x
        // of the shape's centre, which is 0.1 m up.
        let p = body.position();
        assert!(
            (p[0] - 0.05).abs() < 1e-3 && (p[2] - 0.1).abs() < 2e-3,
            "{p:?}"
        );
        let centre = body.point_position([-0.05, 0.0, 0.0]);
        assert!(
            centre[0].abs() < 1e-3 && (centre[2] - 0.1).abs() < 2e-3,
            "{centre:?}"
        );
        let v = body.point_velocity([-0.05, 0.0, 0.0]);
        assert!(v.iter().all(|c| c.abs() < 1e-2), "{v:?}");
    }

    #[test]
    fn positive_definite_tensors() {
        use crate::positive_definite;
        assert!(positive_definite([1.0, 2.0, 3.0], [0.0; 3]));
        assert!(positive_definite([1.0, 1.0, 1.0], [0.5, 0.0, 0.0]));
        assert!(!positive_definite([1.0, 1.0, 1.0], [1.0, 0.0, 0.0]));
        assert!(!positive_definite([1.0, 1.0, 1.0], [0.9, -0.9, 0.9]));
        assert!(!positive_definite([1.0, -1.0, 1.0], [0.0; 3]));
        assert!(!positive_definite([f64::NAN, 1.0, 1.0], [0.0; 3]));
    }

    #[test]
    fn refusing_the_contact_lets_the_ball_fall_through() {
        let (mut w, b) = ball_world();
        for _ in 0..1000 {
            w.step(|_| None).unwrap();
        }
        assert!(w.body(b).unwrap().position()[2] < -1.0);
    }

    #[test]
    fn invalid_arguments_are_refused_before_ode() {
        let (mut w, b) = ball_world();
        assert!(matches!(
            w.insert_body(BodyBuilder::new(0.0, [1.0; 3])),
            Err(OdeError::NotPositive { what: "mass", .. })
        ));
        assert!(w
            .insert_body(BodyBuilder::new(1.0, [1.0, -1.0, 1.0]))
            .is_err());
        assert!(w
            .insert_body(BodyBuilder::new(1.0, [1.0; 3]).position([f64::NAN, 0.0, 0.0]))
            .is_err());
        assert!(w
            .insert_body(BodyBuilder::new(1.0, [1.0; 3]).orientation([0.0; 4]))
            .is_err());
        assert!(w.insert_geom(GeomBuilder::sphere(0.0)).is_err());
        assert!(w
            .insert_geom(GeomBuilder::cuboid([1.0, -1.0, 1.0]))
            .is_err());
        assert!(w.insert_geom(GeomBuilder::cylinder(0.1, 0.0)).is_err());
        assert!(w.insert_geom(GeomBuilder::cylinder(f64::NAN, 0.1)).is_err());
        assert!(w.insert_geom(GeomBuilder::plane([0.0; 3], 0.0)).is_err());
        assert_eq!(
            w.insert_geom(GeomBuilder::plane([0.0, 0.0, 1.0], 0.0).attached_to(b)),
            Err(OdeError::PlaneOnBody)
        );
        assert_eq!(
            w.insert_geom(GeomBuilder::sphere(0.1).offset([0.1, 0.0, 0.0])),
            Err(OdeError::OffsetWithoutBody)
        );
        assert!(w
            .insert_geom(
                GeomBuilder::sphere(0.1)
                    .attached_to(b)
                    .offset([f64::NAN; 3])
            )
            .is_err());
        // Products of inertia larger than the moments allow.
        assert_eq!(
            w.insert_body(BodyBuilder::new(1.0, [1.0; 3]).products_of_inertia([1.0, 0.0, 0.0])),
            Err(OdeError::NotPositiveDefinite)
        );
        assert!(w
            .insert_body(BodyBuilder::new(1.0, [1.0; 3]).products_of_inertia([0.0, f64::NAN, 0.0]))
            .is_err());
        let mut body = w.body_mut(b).unwrap();
        assert!(body.set_position([0.0, f64::INFINITY, 0.0]).is_err());
        assert!(body.set_orientation([0.0; 4]).is_err());
        assert!(body.set_linear_velocity([f64::NAN; 3]).is_err());
        assert!(body
            .set_angular_velocity([0.0, 0.0, f64::NEG_INFINITY])
            .is_err());
        assert_eq!(w.body_count(), 1);
        assert_eq!(w.geom_count(), 2);
    }

    #[test]
    fn stale_and_foreign_handles_are_refused() {
        let (mut w, b) = ball_world();
        let (other, foreign) = ball_world();
        w.remove_body(b).unwrap();
        assert_eq!(w.geom_count(), 1, "the body's sphere goes with it");
        assert!(matches!(w.body(b), Err(OdeError::StaleBody(_))));
        assert!(matches!(w.remove_body(b), Err(OdeError::StaleBody(_))));
        let fresh = w.insert_body(BodyBuilder::new(1.0, [1.0; 3])).unwrap();
        assert!(w.body(b).is_err(), "reused slot, new generation");
        assert!(w.body(fresh).is_ok());
        assert!(w.body(foreign).is_err() || foreign == fresh);
        assert!(matches!(
            w.insert_geom(GeomBuilder::sphere(1.0).attached_to(foreign)),
            Err(OdeError::StaleBody(_))
        ));
        drop(other);
    }

    #[test]
    fn pose_round_trips_in_public_quaternion_order() {
        let (mut w, b) = ball_world();
        let yaw = 0.3_f64;
        let q = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
        w.body_mut(b).unwrap().set_orientation(q).unwrap();
        let got = w.body(b).unwrap().orientation();
        for (a, e) in got.iter().zip(q) {
            assert!((a - e).abs() < 1e-15, "{got:?} vs {q:?}");
        }
    }

    #[test]
    fn a_panicking_callback_does_not_cross_ffi_and_the_world_stays_usable() {
        let (mut w, b) = ball_world();
        // Put the ball on the ground so the callback is called.
        w.body_mut(b)
            .unwrap()
            .set_position([0.0, 0.0, 0.09])
            .unwrap();
        let result = panic::catch_unwind(AssertUnwindSafe(|| {
            w.step(|_| panic!("boom")).ok();
        }));
        assert!(result.is_err());
        let s = surface();
        let r = w.step(|_| Some(s)).unwrap();
        assert!(r.contact_joints > 0);
    }

    #[test]
    fn identical_worlds_step_identically_despite_interleaving() {
        let run = |interleave: bool| {
            let (mut w, b) = ball_world();
            let (mut noise, _) = ball_world();
            let s = surface();
            w.body_mut(b)
                .unwrap()
                .set_linear_velocity([1.0, 0.3, 0.0])
                .unwrap();
            for _ in 0..600 {
                w.step(|_| Some(s)).unwrap();
                if interleave {
                    noise.step(|_| Some(s)).unwrap();
                }
            }
            let body = w.body(b).unwrap();
            (body.position(), body.orientation())
        };
        assert_eq!(run(false), run(true));
    }

    #[test]
    fn a_world_can_be_stepped_on_another_thread() {
        let (mut w, b) = ball_world();
        let s = surface();
        let z = std::thread::spawn(move || {
            for _ in 0..100 {
                w.step(|_| Some(s)).unwrap();
            }
            w.body(b).unwrap().position()[2]
        })
        .join()
        .unwrap();
        assert!(z < 0.5);
    }
}
