use crate::{BodyHandle, GeomHandle};

/// Why the wrapper refused a call (before anything reached ODE) or why ODE
/// reported a failure.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OdeError {
    #[error("{what} must be a finite number, got {value}")]
    NotFinite { what: &'static str, value: f64 },
    #[error("{what} must be greater than zero, got {value}")]
    NotPositive { what: &'static str, value: f64 },
    #[error("{what} must lie in {range}, got {value}")]
    OutOfRange {
        what: &'static str,
        range: &'static str,
        value: f64,
    },
    #[error("{what} has zero length")]
    ZeroLength { what: &'static str },
    #[error("body handle {0:?} is stale or belongs to another world")]
    StaleBody(BodyHandle),
    #[error("geom handle {0:?} is stale or belongs to another world")]
    StaleGeom(GeomHandle),
    #[error("the inertia tensor must be positive definite")]
    NotPositiveDefinite,
    #[error("a geom offset needs a body to be offset from")]
    OffsetWithoutBody,
    #[error("a plane is not placeable and cannot be attached to a body")]
    PlaneOnBody,
    #[error("ODE could not {0}")]
    Ode(&'static str),
}
