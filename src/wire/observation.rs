//! The one conversion of a published body ([`pb::ModelState`], in a
//! `WorldState` or in the learner protocol's `State`) into the learner's
//! [`Observation`]: every driver of a learner, in process or behind
//! `pushlearn serve-learner`, goes through [`frame`], so both refuse the
//! same states. The rule for a missing pose is the vocabulary's
//! ([`Observation::published`]). A driver that knows the world's Hello
//! passes each body's outline on with it ([`Footprints`]).

use pushlearn_core::{Footprint, Frame, Observation};

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
    Footprints::default().frame(bodies)
}

impl pb::Shape {
    /// The outline seen from above: a box's rectangle, a sphere's or an
    /// upright cylinder's circle. `None` for a shape without geometry or
    /// with sizes that are not finite and positive (no outline rather
    /// than a wrong one).
    #[must_use]
    pub fn footprint(&self) -> Option<Footprint> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match self.geometry.as_ref()? {
            Geometry::SphereRadius(r) => positive(*r).then_some(Footprint::Disc { radius: *r }),
            Geometry::Cylinder(c) => {
                positive(c.radius).then_some(Footprint::Disc { radius: c.radius })
            }
            Geometry::BoxSize(v) => (positive(v.x) && positive(v.y)).then_some(Footprint::Box {
                half_extents: [v.x / 2.0, v.y / 2.0],
            }),
        }
    }
}

/// Each body's outline by name, from the world's Hello (`Hello.shapes`;
/// empty from a world older than them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Footprints(Vec<(String, Footprint)>);

impl Footprints {
    #[must_use]
    pub fn from_hello(hello: &pb::Hello) -> Self {
        Self(
            hello
                .shapes
                .iter()
                .filter_map(|shape| Some((shape.name.clone(), shape.footprint()?)))
                .collect(),
        )
    }

    /// The first body with this outline, if any.
    #[must_use]
    pub fn body_with(&self, footprint: Footprint) -> Option<&str> {
        self.0
            .iter()
            .find(|(_, f)| *f == footprint)
            .map(|(n, _)| n.as_str())
    }

    /// The outline of the body `name`, if the world gave one.
    #[must_use]
    pub fn of(&self, name: &str) -> Option<Footprint> {
        // A handful of bodies: a scan beats a map's hashing.
        self.0.iter().find(|(n, _)| n == name).map(|&(_, f)| f)
    }

    /// The learner's view of a world state's `bodies` (as [`frame`]), each
    /// with its outline.
    #[must_use]
    pub fn frame(&self, bodies: &[pb::ModelState]) -> Frame {
        Frame {
            objects: bodies
                .iter()
                .map(|body| Observation {
                    footprint: self.of(&body.name),
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
    fn outlines_come_from_the_hello_by_body_name() {
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
        let footprints = Footprints::from_hello(&hello);
        let seen = footprints.frame(&[
            body("cylinder", 3, None),
            body("blockA", 15, None),
            body("actuator", 8, None),
            body("broken", 9, None),
            body("wall", 4, None),
        ]);
        let outlines: Vec<_> = seen.objects.iter().map(|o| o.footprint).collect();
        assert_eq!(
            outlines,
            [
                Some(Footprint::Disc { radius: 0.1 }),
                Some(Footprint::Box {
                    half_extents: [0.25, 0.05]
                }),
                Some(Footprint::Disc { radius: 0.025 }),
                None,
                None,
            ]
        );
        assert!(frame(&[body("blockA", 15, None)]).objects[0]
            .footprint
            .is_none());
    }
}
