//! Rigid bodies: handles, the builder, and read/write views.

use std::marker::PhantomData;

use ode_sys::dBodyID;

use crate::arena::GeomHandle;
use crate::check::{check_finite3, check_positive, quat_from_ode, quat_to_ode};
use crate::OdeError;

pub(crate) struct BodyEntry {
    pub(crate) raw: dBodyID,
    pub(crate) geoms: Vec<GeomHandle>,
}

/// Describes a body to create with [`World::insert_body`](crate::World::insert_body).
///
/// The centre of mass is the body origin (ODE requires it: `dBodySetMass`
/// refuses a mass whose centre is elsewhere; offset the geoms instead, with
/// [`GeomBuilder::offset`](crate::GeomBuilder::offset)). The inertia tensor is
/// diagonal in the body frame unless products of inertia are given.
#[derive(Debug, Clone, Copy, PartialEq)]
#[must_use = "a builder does nothing until passed to World::insert_body"]
pub struct BodyBuilder {
    pub(crate) mass: f64,
    pub(crate) inertia: [f64; 3],
    pub(crate) products: [f64; 3],
    pub(crate) position: [f64; 3],
    pub(crate) orientation: [f64; 4],
    pub(crate) linear_velocity: [f64; 3],
    pub(crate) angular_velocity: [f64; 3],
    pub(crate) gravity: bool,
}

impl BodyBuilder {
    /// A body of `mass` kg and diagonal inertia `inertia` kg·m², at the
    /// origin, unrotated, at rest, affected by gravity.
    pub fn new(mass: f64, inertia: [f64; 3]) -> Self {
        BodyBuilder {
            mass,
            inertia,
            products: [0.0; 3],
            position: [0.0; 3],
            orientation: [0.0, 0.0, 0.0, 1.0],
            linear_velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            gravity: true,
        }
    }

    /// The off-diagonal entries `[Ixy, Ixz, Iyz]` of the body-frame inertia
    /// tensor about the centre of mass, kg·m² (zero by default): tensor
    /// entries, `Ixy = −∫ x y dm`, as ODE's `dMassSetParameters` takes them.
    /// A centre of mass away from a shape's centre gives them (parallel-axis
    /// theorem).
    pub fn products_of_inertia(mut self, products: [f64; 3]) -> Self {
        self.products = products;
        self
    }

    pub fn position(mut self, position: [f64; 3]) -> Self {
        self.position = position;
        self
    }

    /// Unit quaternion `[x, y, z, w]` (normalised on insertion).
    pub fn orientation(mut self, orientation: [f64; 4]) -> Self {
        self.orientation = orientation;
        self
    }

    pub fn linear_velocity(mut self, v: [f64; 3]) -> Self {
        self.linear_velocity = v;
        self
    }

    pub fn angular_velocity(mut self, w: [f64; 3]) -> Self {
        self.angular_velocity = w;
        self
    }

    /// Whether the world's gravity acts on the body.
    pub fn gravity(mut self, on: bool) -> Self {
        self.gravity = on;
        self
    }

    /// Everything ODE's `dMassCheck` and setters would abort on. Positive
    /// diagonal moments make a diagonal tensor positive definite, which is
    /// all ODE requires; with products of inertia the whole tensor is
    /// checked. The triangle inequality is deliberately not enforced (the
    /// thesis's red block violates it and must be reproducible).
    pub(crate) fn validate(&self) -> Result<[f64; 4], OdeError> {
        check_positive("mass", self.mass)?;
        self.inertia
            .iter()
            .try_for_each(|&i| check_positive("inertia", i))?;
        check_finite3("products of inertia", self.products)?;
        if self.products != [0.0; 3] && !positive_definite(self.inertia, self.products) {
            return Err(OdeError::NotPositiveDefinite);
        }
        check_finite3("position", self.position)?;
        check_finite3("linear velocity", self.linear_velocity)?;
        check_finite3("angular velocity", self.angular_velocity)?;
        quat_to_ode(self.orientation)
    }
}

/// Whether the symmetric tensor with diagonal `d` and products
/// `[xy, xz, yz]` is positive definite, by a Cholesky factorisation as
/// ODE's `dMassCheck` does. Pivots must clear a small margin relative to the
/// largest moment, so that rounding inside ODE cannot tip a borderline
/// tensor (ODE aborts on one that fails).
pub fn positive_definite(d: [f64; 3], p: [f64; 3]) -> bool {
    let [xx, yy, zz] = d;
    let [xy, xz, yz] = p;
    let margin = 1e-12 * xx.abs().max(yy.abs()).max(zz.abs());
    // False for NaN too.
    let clears = |pivot: f64| pivot > margin;
    let p1 = xx;
    if !clears(p1) {
        return false;
    }
    let l21 = xy / p1.sqrt();
    let l31 = xz / p1.sqrt();
    let p2 = yy - l21 * l21;
    if !clears(p2) {
        return false;
    }
    let l32 = (yz - l31 * l21) / p2.sqrt();
    clears(zz - l31 * l31 - l32 * l32)
}

/// Read-only view of a body, borrowed from its world.
#[derive(Clone, Copy)]
pub struct Body<'w> {
    raw: dBodyID,
    _world: PhantomData<&'w ()>,
}

/// Read-write view of a body, borrowed mutably from its world.
pub struct BodyMut<'w> {
    raw: dBodyID,
    _world: PhantomData<&'w mut ()>,
}

fn read3(ptr: *const f64) -> [f64; 3] {
    // SAFETY: callers pass a pointer ODE returned for a live body's dVector3
    // (4 doubles, of which 3 are meaningful); it stays valid while the world
    // is borrowed, and nothing mutates it during this read.
    unsafe { [*ptr, *ptr.add(1), *ptr.add(2)] }
}

macro_rules! body_getters {
    () => {
        /// World-frame position of the centre of mass, m.
        pub fn position(&self) -> [f64; 3] {
            // SAFETY: `raw` is a live body (guaranteed by the world borrow).
            read3(unsafe { ode_sys::dBodyGetPosition(self.raw) })
        }

        /// Unit quaternion `[x, y, z, w]`.
        pub fn orientation(&self) -> [f64; 4] {
            // SAFETY: `raw` is a live body; dBodyGetQuaternion returns a
            // pointer to its 4-element quaternion.
            let q = unsafe {
                let p = ode_sys::dBodyGetQuaternion(self.raw);
                [*p, *p.add(1), *p.add(2), *p.add(3)]
            };
            quat_from_ode(q)
        }

        /// World-frame linear velocity, m/s.
        pub fn linear_velocity(&self) -> [f64; 3] {
            // SAFETY: `raw` is a live body.
            read3(unsafe { ode_sys::dBodyGetLinearVel(self.raw) })
        }

        /// World-frame angular velocity, rad/s.
        pub fn angular_velocity(&self) -> [f64; 3] {
            // SAFETY: `raw` is a live body.
            read3(unsafe { ode_sys::dBodyGetAngularVel(self.raw) })
        }

        /// World-frame position of the point at `rel` in the body frame
        /// (relative to the centre of mass), m.
        pub fn point_position(&self, rel: [f64; 3]) -> [f64; 3] {
            let mut out = [0.0; 4];
            // SAFETY: `raw` is a live body; `out` is a dVector3 (4 doubles)
            // that ODE writes the result into. Non-finite input gives a
            // non-finite result, nothing worse.
            unsafe {
                ode_sys::dBodyGetRelPointPos(self.raw, rel[0], rel[1], rel[2], out.as_mut_ptr())
            };
            [out[0], out[1], out[2]]
        }

        /// World-frame velocity of the point at `rel` in the body frame, m/s.
        pub fn point_velocity(&self, rel: [f64; 3]) -> [f64; 3] {
            let mut out = [0.0; 4];
            // SAFETY: as for `point_position`.
            unsafe {
                ode_sys::dBodyGetRelPointVel(self.raw, rel[0], rel[1], rel[2], out.as_mut_ptr())
            };
            [out[0], out[1], out[2]]
        }

        /// False while ODE's auto-disable has put the body to sleep.
        pub fn is_enabled(&self) -> bool {
            // SAFETY: `raw` is a live body.
            unsafe { ode_sys::dBodyIsEnabled(self.raw) != 0 }
        }
    };
}

impl<'w> Body<'w> {
    pub(crate) fn new(raw: dBodyID) -> Self {
        Body {
            raw,
            _world: PhantomData,
        }
    }

    body_getters!();
}

impl<'w> BodyMut<'w> {
    pub(crate) fn new(raw: dBodyID) -> Self {
        BodyMut {
            raw,
            _world: PhantomData,
        }
    }

    body_getters!();

    /// Moves the body (and its geoms) without touching its velocities.
    pub fn set_position(&mut self, p: [f64; 3]) -> Result<(), OdeError> {
        check_finite3("position", p)?;
        // SAFETY: `raw` is a live body; the values are finite.
        unsafe { ode_sys::dBodySetPosition(self.raw, p[0], p[1], p[2]) };
        Ok(())
    }

    /// Sets the orientation from a quaternion `[x, y, z, w]` (normalised).
    pub fn set_orientation(&mut self, q: [f64; 4]) -> Result<(), OdeError> {
        let q = quat_to_ode(q)?;
        // SAFETY: `raw` is a live body; `q` is a finite unit quaternion in
        // ODE's order, 4 doubles as dBodySetQuaternion reads.
        unsafe { ode_sys::dBodySetQuaternion(self.raw, q.as_ptr()) };
        Ok(())
    }

    pub fn set_linear_velocity(&mut self, v: [f64; 3]) -> Result<(), OdeError> {
        check_finite3("linear velocity", v)?;
        // SAFETY: `raw` is a live body; the values are finite.
        unsafe { ode_sys::dBodySetLinearVel(self.raw, v[0], v[1], v[2]) };
        Ok(())
    }

    /// Fault injection for tests: makes the linear velocity NaN, the state a
    /// diverged simulation leaves behind, so that a caller's divergence
    /// handling can be tested. Never step the world before repairing the body
    /// (e.g. by resetting it): ODE does not guard against NaN.
    #[cfg(feature = "testing")]
    pub fn poison_for_test(&mut self) {
        // SAFETY: `raw` is a live body; ODE stores the values as given and
        // reads them only when stepping, which the caller must not do first.
        unsafe { ode_sys::dBodySetLinearVel(self.raw, f64::NAN, f64::NAN, f64::NAN) };
    }

    pub fn set_angular_velocity(&mut self, w: [f64; 3]) -> Result<(), OdeError> {
        check_finite3("angular velocity", w)?;
        // SAFETY: `raw` is a live body; the values are finite.
        unsafe { ode_sys::dBodySetAngularVel(self.raw, w[0], w[1], w[2]) };
        Ok(())
    }

    /// Wakes the body and restarts its auto-disable idle countdown.
    pub fn enable(&mut self) {
        // SAFETY: `raw` is a live body.
        unsafe { ode_sys::dBodyEnable(self.raw) };
    }

    /// Puts the body's motion state back to what a freshly created body has:
    /// zero velocities, forces and torques, awake, with an empty
    /// auto-disable sample buffer. Pose is left alone. Needed for resets that
    /// must reproduce a fresh world bit for bit.
    pub fn reset_dynamics(&mut self) {
        // SAFETY: `raw` is a live body; re-setting the sample count to its
        // current (positive, validated at creation) value only reallocates
        // and clears the body's own sample buffers.
        unsafe {
            ode_sys::dBodySetLinearVel(self.raw, 0.0, 0.0, 0.0);
            ode_sys::dBodySetAngularVel(self.raw, 0.0, 0.0, 0.0);
            ode_sys::dBodySetForce(self.raw, 0.0, 0.0, 0.0);
            ode_sys::dBodySetTorque(self.raw, 0.0, 0.0, 0.0);
            let samples = ode_sys::dBodyGetAutoDisableAverageSamplesCount(self.raw);
            ode_sys::dBodySetAutoDisableAverageSamplesCount(self.raw, samples.max(0) as u32);
            ode_sys::dBodyEnable(self.raw);
        }
    }
}
