//! Safe RAII wrapper over `ode-sys` (the Open Dynamics Engine, double
//! precision).
//!
//! The shape follows rapier's handle-and-set design: a [`World`] owns every
//! raw ODE object (world, top-level space, bodies, geoms, the contact joint
//! group) and hands out copyable [`BodyHandle`]s and [`GeomHandle`]s. A handle
//! that outlived its object, or belongs to another world, is refused with
//! [`OdeError`] instead of reaching ODE.
//!
//! ODE's own argument checks `abort()` the process. Every value that could
//! trip one — non-finite numbers, non-positive masses or sizes, zero-length
//! quaternions or plane normals, stale handles — is rejected here first.
//!
//! Process set-up is automatic: `dInitODE2` runs once per process and
//! `dAllocateODEDataForThread` once in every thread that creates, changes or
//! steps a world, so a [`World`] can be built on one thread and stepped on a
//! dedicated physics thread.
//!
//! Conventions: positions and velocities are world-frame `[x, y, z]`;
//! quaternions are `[x, y, z, w]` in this API (ODE stores `[w, x, y, z]`; the
//! conversion lives in one private module).

#![warn(clippy::undocumented_unsafe_blocks)]

mod arena;
mod body;
mod check;
mod contact;
mod error;
mod geom;
mod init;
mod params;
mod world;

pub use arena::{BodyHandle, GeomHandle};
pub use body::{positive_definite, Body, BodyBuilder, BodyMut};
pub use contact::{ContactMode, ContactPair, ContactPoint, GeomInfo, Surface, SurfaceParams};
pub use error::OdeError;
pub use geom::{GeomBuilder, Shape};
pub use init::{hold_for_fork, rand_set_seed};
pub use params::{AutoDisable, StepParams};
pub use world::{SpaceKind, StepReport, World};
