//! The one conversion of a published body ([`pb::ModelState`], in a
//! `WorldState` or in the learner protocol's `State`) into the learner's
//! [`Observation`]: every driver of a learner, in process or behind
//! `pushlearn serve-learner`, goes through [`frame`], so both refuse the
//! same states. The rule for a missing pose is the vocabulary's
//! ([`Observation::published`]).

use pushlearn_core::{Frame, Observation};

use super::pb;

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
    Frame {
        objects: bodies.iter().map(pb::ModelState::observation).collect(),
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
}
