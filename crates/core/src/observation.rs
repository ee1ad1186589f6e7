//! A published body as a learner sees it: the one conversion every driver of
//! a learner uses, in process or over the learner protocol, so that both
//! refuse the same states.

use serde::{Deserialize, Serialize};

/// One body of a world-state message, as the daemon hands it to the learner
/// (the protobuf `ModelState` minus what no learner reads: velocities, scale,
/// type, `is_static`; `docs/spec/protocol.md` §4).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    pub name: String,
    pub id: u32,
    /// World-frame position (x, y, z) in metres; z is not used by the learner.
    pub position: [f64; 3],
    /// Orientation quaternion in the order (x, y, z, w), as in the wire schema.
    pub orientation: [f64; 4],
    /// The body's shape as the world's Hello describes it (as a camera
    /// would see it): a learner that reasons about contact needs the shape
    /// of what it pushes, and the new-object experiments show another
    /// object under the blue block's id. Every driver passes it on, in
    /// process and over the learner protocol (`State.shapes`), so every
    /// learner sees the same; `None` only for a body the world gave no
    /// shape. The faithful models never read it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<BodyShape>,
}

/// A body's collision shape, centred on its pose, in its own frame: what a
/// world's Hello says of it (`Shape` in `proto/pushlearn.proto`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum BodyShape {
    /// A box with these full edge lengths along the body's x, y and z.
    Box { size: [f64; 3] },
    /// An upright cylinder (its axis the body's z).
    Cylinder { radius: f64, length: f64 },
    /// A sphere.
    Sphere { radius: f64 },
}

impl BodyShape {
    /// The shape's outline seen from above.
    #[must_use]
    pub fn footprint(self) -> Footprint {
        match self {
            BodyShape::Box { size } => Footprint::Box {
                half_extents: [size[0] / 2.0, size[1] / 2.0],
            },
            BodyShape::Cylinder { radius, .. } | BodyShape::Sphere { radius } => {
                Footprint::Disc { radius }
            }
        }
    }

    /// Whether every size is finite and positive: a shape a world can have.
    #[must_use]
    pub fn is_valid(self) -> bool {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match self {
            BodyShape::Box { size } => size.iter().all(|&v| positive(v)),
            BodyShape::Cylinder { radius, length } => positive(radius) && positive(length),
            BodyShape::Sphere { radius } => positive(radius),
        }
    }
}

/// A body's outline in its own frame, centred on its pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Footprint {
    /// A rectangle with these half-lengths along the body's x and y.
    Box { half_extents: [f64; 2] },
    /// A circle (a sphere's or an upright cylinder's outline).
    Disc { radius: f64 },
}

/// The raw content of one world-state message: every body it lists, in
/// message order, unfiltered (models parse it with `features::parse_frame`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    pub objects: Vec<Observation>,
}

impl Observation {
    /// A body as published: `position` and `orientation` are `None` where the
    /// message left them out.
    ///
    /// What is missing becomes NaN rather than a made-up pose (zeros would be
    /// a valid pose at the origin): the learner's parsing then refuses the
    /// frame with an error naming the body if, and only if, it is a body the
    /// learner uses, while a ghost or a wall without a pose stays harmless.
    #[must_use]
    pub fn published(
        name: impl Into<String>,
        id: u32,
        position: Option<[f64; 3]>,
        orientation: Option<[f64; 4]>,
    ) -> Self {
        Self {
            name: name.into(),
            id,
            position: position.unwrap_or([f64::NAN; 3]),
            orientation: orientation.unwrap_or([f64::NAN; 4]),
            shape: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_published_pose_is_kept_as_sent() {
        let obs = Observation::published(
            "blockA",
            15,
            Some([0.1, 0.2, 0.05]),
            Some([0.0, 0.0, 0.6, 0.8]),
        );
        assert_eq!(
            obs,
            Observation {
                name: "blockA".into(),
                id: 15,
                position: [0.1, 0.2, 0.05],
                orientation: [0.0, 0.0, 0.6, 0.8],
                shape: None,
            }
        );
    }

    #[test]
    fn what_was_not_published_is_nan_never_zero() {
        let obs = Observation::published("actuator", 8, None, None);
        assert!(obs.position.iter().all(|c| c.is_nan()));
        assert!(obs.orientation.iter().all(|c| c.is_nan()));

        let obs = Observation::published("actuator", 8, Some([0.0; 3]), None);
        assert_eq!(obs.position, [0.0; 3]);
        assert!(obs.orientation.iter().all(|c| c.is_nan()));

        let obs = Observation::published("actuator", 8, None, Some([0.0, 0.0, 0.0, 1.0]));
        assert!(obs.position.iter().all(|c| c.is_nan()));
        assert_eq!(obs.orientation, [0.0, 0.0, 0.0, 1.0]);
    }
}

#[cfg(test)]
mod shape_tests {
    use super::*;

    #[test]
    fn an_observation_without_a_shape_reads_and_writes_as_before() {
        let obs = Observation::published("blockA", 15, Some([0.0; 3]), Some([0.0, 0.0, 0.0, 1.0]));
        let json = serde_json::to_string(&obs).unwrap();
        assert!(!json.contains("shape"), "{json}");
        let old = r#"{"name":"blockA","id":15,"position":[0,0,0],"orientation":[0,0,0,1]}"#;
        assert_eq!(serde_json::from_str::<Observation>(old).unwrap(), obs);
        for shape in [
            BodyShape::Box {
                size: [0.5, 0.1, 0.1],
            },
            BodyShape::Cylinder {
                radius: 0.1,
                length: 0.1,
            },
            BodyShape::Sphere { radius: 0.025 },
        ] {
            let with = Observation {
                shape: Some(shape),
                ..obs.clone()
            };
            let back: Observation =
                serde_json::from_str(&serde_json::to_string(&with).unwrap()).unwrap();
            assert_eq!(back, with);
        }
    }

    #[test]
    fn a_shape_seen_from_above_is_its_outline() {
        let block = BodyShape::Box {
            size: [0.5, 0.1, 0.1],
        };
        assert_eq!(
            block.footprint(),
            Footprint::Box {
                half_extents: [0.25, 0.05]
            }
        );
        let cylinder = BodyShape::Cylinder {
            radius: 0.1,
            length: 0.1,
        };
        assert_eq!(cylinder.footprint(), Footprint::Disc { radius: 0.1 });
        assert!(block.is_valid() && cylinder.is_valid());
        assert!(!BodyShape::Sphere { radius: 0.0 }.is_valid());
        assert!(!BodyShape::Box {
            size: [0.5, f64::NAN, 0.1]
        }
        .is_valid());
    }
}
