//! The one conversion of a published body ([`pb::ModelState`], in a
//! `WorldState` or in the learner protocol's `State`) into the learner's
//! [`Observation`]: every driver of a learner, in process or behind
//! `pushlearn serve-learner`, goes through [`frame`], so both refuse the
//! same states. The rule for a missing pose is the vocabulary's
//! ([`Observation::published`]). A driver that knows the world's Hello
//! passes each body's shape on with it ([`Shapes`]), and the learner
//! protocol carries the same shapes in its `State` (`State.shapes`), read
//! back by [`Shapes::from_shapes`].

use pushlearn_core::{BodyShape, Frame, Observation};

use super::pb::{self, shape::Geometry};

impl pb::ModelState {
    /// The learner's view of this body: NaN where the pose was not published.
    #[must_use]
    pub fn observation(&self) -> Observation {
        let pose = self.pose.as_ref();
        Observation::published(
            self.name.clone(),
            self.id,
            pose.and_then(|p| p.position.as_ref())
                .map(|v| [v.x, v.y, v.z]),
            pose.and_then(|p| p.orientation.as_ref())
                .map(|q| [q.x, q.y, q.z, q.w]),
        )
    }
}

/// The learner's view of a world state's `bodies`: every one in message
/// order, unfiltered (skipping and rounding are the models' parsing,
/// `docs/spec/features.md` §1).
#[must_use]
pub fn frame(bodies: &[pb::ModelState]) -> Frame {
    Shapes::default().frame(bodies)
}

impl pb::Shape {
    /// The shape as the vocabulary's [`BodyShape`]. `None` for a shape
    /// without geometry or with sizes that are not finite and positive (no
    /// shape rather than a wrong one).
    #[must_use]
    pub fn body_shape(&self) -> Option<BodyShape> {
        let shape = match self.geometry.as_ref()? {
            Geometry::SphereRadius(radius) => BodyShape::Sphere { radius: *radius },
            Geometry::Cylinder(c) => BodyShape::Cylinder {
                radius: c.radius,
                length: c.length,
            },
            Geometry::BoxSize(v) => BodyShape::Box {
                size: [v.x, v.y, v.z],
            },
        };
        shape.is_valid().then_some(shape)
    }

    /// `shape` of the body `name`, as the Hello and the learner protocol
    /// send it.
    #[must_use]
    pub fn of_body(name: &str, shape: BodyShape) -> Self {
        let geometry = match shape {
            BodyShape::Box { size: [x, y, z] } => Geometry::BoxSize(pb::Vector3d::new(x, y, z)),
            BodyShape::Cylinder { radius, length } => {
                Geometry::Cylinder(pb::Cylinder { radius, length })
            }
            BodyShape::Sphere { radius } => Geometry::SphereRadius(radius),
        };
        Self {
            name: name.to_owned(),
            geometry: Some(geometry),
        }
    }
}

/// Each body's shape by name: from the world's Hello (`Hello.shapes`; empty
/// from a world older than them), or from the learner protocol's
/// `State.shapes`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shapes(Vec<(String, BodyShape)>);

impl Shapes {
    /// The shapes a world's Hello describes.
    #[must_use]
    pub fn from_hello(hello: &pb::Hello) -> Self {
        Self::from_shapes(&hello.shapes)
    }

    /// Shapes as the protocols send them; one without a valid geometry is
    /// left out, and of a name given twice the first counts.
    #[must_use]
    pub fn from_shapes(shapes: &[pb::Shape]) -> Self {
        let mut out: Vec<(String, BodyShape)> = Vec::with_capacity(shapes.len());
        for shape in shapes {
            if let Some(body) = shape.body_shape() {
                if !out.iter().any(|(n, _)| *n == shape.name) {
                    out.push((shape.name.clone(), body));
                }
            }
        }
        Self(out)
    }

    /// The first body with this shape, if any.
    #[must_use]
    pub fn body_with(&self, shape: BodyShape) -> Option<&str> {
        self.0
            .iter()
            .find(|(_, s)| *s == shape)
            .map(|(n, _)| n.as_str())
    }

    /// The shape of the body `name`, if the world gave one.
    #[must_use]
    pub fn of(&self, name: &str) -> Option<BodyShape> {
        // A handful of bodies: a scan beats a map's hashing.
        self.0.iter().find(|(n, _)| n == name).map(|&(_, s)| s)
    }

    /// The learner's view of a world state's `bodies` (as [`frame`]), each
    /// with its shape.
    #[must_use]
    pub fn frame(&self, bodies: &[pb::ModelState]) -> Frame {
        Frame {
            objects: bodies
                .iter()
                .map(|body| Observation {
                    shape: self.of(&body.name),
                    ..body.observation()
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(name: &str, id: u32, pose: Option<pb::Pose>) -> pb::ModelState {
        pb::ModelState {
            name: name.into(),
            id,
            pose,
            ..Default::default()
        }
    }

    #[test]
    fn a_published_pose_is_carried_over_in_xyzw_order() {
        let obs = body(
            "blockA",
            15,
            Some(pb::Pose::from_position_yaw([0.1, 0.2, 0.05], 0.5)),
        )
        .observation();
        let q = pb::Quaternion::from_yaw(0.5);
        assert_eq!(obs.name, "blockA");
        assert_eq!(obs.id, 15);
        assert_eq!(obs.position, [0.1, 0.2, 0.05]);
        assert_eq!(obs.orientation, [q.x, q.y, q.z, q.w]);
    }

    #[test]
    fn a_missing_pose_or_half_of_one_is_nan() {
        let none = body("actuator", 8, None).observation();
        assert!(none
            .position
            .iter()
            .chain(&none.orientation)
            .all(|c| c.is_nan()));
        let half = body(
            "actuator",
            8,
            Some(pb::Pose {
                position: Some(pb::Vector3d::new(0.0, 0.0, 0.03)),
                orientation: None,
            }),
        )
        .observation();
        assert_eq!(half.position, [0.0, 0.0, 0.03]);
        assert!(half.orientation.iter().all(|c| c.is_nan()));
    }

    #[test]
    fn a_frame_keeps_every_body_in_order() {
        let names: Vec<String> = frame(&[
            body("b", 1, None),
            body("aShadow", 2, None),
            body("a", 3, None),
        ])
        .objects
        .into_iter()
        .map(|o| o.name)
        .collect();
        assert_eq!(names, ["b", "aShadow", "a"]);
    }

    #[test]
    fn shapes_come_from_the_hello_by_body_name() {
        let shape = |name: &str, geometry| pb::Shape {
            name: name.into(),
            geometry: Some(geometry),
        };
        let hello = pb::Hello {
            shapes: vec![
                shape(
                    "blockA",
                    Geometry::BoxSize(pb::Vector3d::new(0.5, 0.1, 0.1)),
                ),
                shape(
                    "cylinder",
                    Geometry::Cylinder(pb::Cylinder {
                        radius: 0.1,
                        length: 0.1,
                    }),
                ),
                shape("actuator", Geometry::SphereRadius(0.025)),
                shape("broken", Geometry::SphereRadius(f64::NAN)),
            ],
            ..Default::default()
        };
        let shapes = Shapes::from_hello(&hello);
        let seen = shapes.frame(&[
            body("cylinder", 3, None),
            body("blockA", 15, None),
            body("actuator", 8, None),
            body("broken", 9, None),
            body("wall", 4, None),
        ]);
        let found: Vec<_> = seen.objects.iter().map(|o| o.shape).collect();
        let expected = [
            Some(BodyShape::Cylinder {
                radius: 0.1,
                length: 0.1,
            }),
            Some(BodyShape::Box {
                size: [0.5, 0.1, 0.1],
            }),
            Some(BodyShape::Sphere { radius: 0.025 }),
            None,
            None,
        ];
        assert_eq!(found, expected);
        assert!(frame(&[body("blockA", 15, None)]).objects[0]
            .shape
            .is_none());

        // What the learner protocol sends back reads as the Hello did.
        let sent: Vec<pb::Shape> = seen
            .objects
            .iter()
            .filter_map(|o| Some(pb::Shape::of_body(&o.name, o.shape?)))
            .collect();
        let by_body_order = [&hello.shapes[1], &hello.shapes[0], &hello.shapes[2]];
        assert_eq!(sent.iter().collect::<Vec<_>>(), by_body_order);
        assert_eq!(
            Shapes::from_shapes(&sent)
                .frame(&[body("blockA", 15, None)])
                .objects[0]
                .shape,
            expected[1]
        );
    }
}
