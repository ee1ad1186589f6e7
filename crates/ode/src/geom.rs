//! Collision geometry: handles, shapes and the builder.

use ode_sys::dGeomID;

use crate::arena::BodyHandle;
use crate::check::{check_finite, check_positive, unit_direction};
use crate::OdeError;

pub(crate) struct GeomEntry {
    pub(crate) raw: dGeomID,
    pub(crate) body: Option<BodyHandle>,
    pub(crate) tag: u32,
}

/// A collision shape. Sizes are full side lengths / radii in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    Sphere {
        radius: f64,
    },
    /// Full edge lengths along the body's x, y and z axes.
    Cuboid {
        size: [f64; 3],
    },
    /// A flat-ended cylinder whose axis is the body's z axis; `length` is
    /// its full extent along that axis.
    Cylinder {
        radius: f64,
        length: f64,
    },
    /// The half-space `normal · p <= offset` (static only).
    Plane {
        normal: [f64; 3],
        offset: f64,
    },
}

impl Shape {
    /// Checks the shape and returns it with a plane's normal made unit length.
    pub(crate) fn validated(self) -> Result<Shape, OdeError> {
        match self {
            Shape::Sphere { radius } => {
                check_positive("sphere radius", radius)?;
            }
            Shape::Cuboid { size } => {
                size.iter()
                    .try_for_each(|&s| check_positive("box size", s))?;
            }
            Shape::Cylinder { radius, length } => {
                check_positive("cylinder radius", radius)?;
                check_positive("cylinder length", length)?;
            }
            Shape::Plane { normal, offset } => {
                check_finite("plane offset", offset)?;
                return Ok(Shape::Plane {
                    normal: unit_direction("plane normal", normal)?,
                    offset,
                });
            }
        }
        Ok(self)
    }
}

/// Describes a geom to create with [`World::insert_geom`](crate::World::insert_geom).
#[derive(Debug, Clone, Copy, PartialEq)]
#[must_use = "a builder does nothing until passed to World::insert_geom"]
pub struct GeomBuilder {
    pub(crate) shape: Shape,
    pub(crate) body: Option<BodyHandle>,
    pub(crate) offset: [f64; 3],
    pub(crate) tag: u32,
}

impl GeomBuilder {
    pub fn new(shape: Shape) -> Self {
        GeomBuilder {
            shape,
            body: None,
            offset: [0.0; 3],
            tag: 0,
        }
    }

    pub fn sphere(radius: f64) -> Self {
        GeomBuilder::new(Shape::Sphere { radius })
    }

    pub fn cuboid(size: [f64; 3]) -> Self {
        GeomBuilder::new(Shape::Cuboid { size })
    }

    pub fn cylinder(radius: f64, length: f64) -> Self {
        GeomBuilder::new(Shape::Cylinder { radius, length })
    }

    pub fn plane(normal: [f64; 3], offset: f64) -> Self {
        GeomBuilder::new(Shape::Plane { normal, offset })
    }

    /// Makes the geom follow `body` (centred on it). Without a body the geom
    /// is static.
    pub fn attached_to(mut self, body: BodyHandle) -> Self {
        self.body = Some(body);
        self
    }

    /// Places the geom's centre at `offset` in its body's frame (from the
    /// body's origin, its centre of mass) instead of on it: how a body's
    /// centre of mass comes to lie away from its shape's centre. Needs
    /// [`GeomBuilder::attached_to`]. A zero offset leaves the geom exactly as
    /// without this call (ODE is never told of it).
    pub fn offset(mut self, offset: [f64; 3]) -> Self {
        self.offset = offset;
        self
    }

    /// A number handed back to the contact callback in [`GeomInfo`](crate::GeomInfo),
    /// e.g. an index into the caller's material table.
    pub fn tag(mut self, tag: u32) -> Self {
        self.tag = tag;
        self
    }
}
