//! The learner's view of the world's `WorldState` (`docs/spec/protocol.md` §4),
//! and the start heights of its Hello.
//!
//! The conversion of each body is the wire's [`pushlearn::wire::frame`], the
//! one that `pushlearn serve-learner` uses as well, so that the in-process
//! driver and the learner protocol refuse the same states.

use std::collections::BTreeMap;

use learner::Frame;

use pushlearn::wire::pb;
pub use pushlearn::wire::Shapes;

/// The learner's view of one world state: every body in message order, a
/// body published without a pose given NaN (refused by the models' parsing
/// if, and only if, it is a body the learner uses), each with its shape
/// from the world's Hello ([`Shapes::from_hello`]).
#[must_use]
pub fn frame_from_state(state: &pb::WorldState, shapes: &Shapes) -> Frame {
    shapes.frame(state.models())
}

/// The z to give a SetPose of each body (or of its ghost): the z of its start
/// pose in the world's Hello — the actuator's clamp height and the blocks'
/// resting height (`docs/spec/protocol.md` §6). Read from the world rather
/// than copied, so that a scene with other sizes gets its own.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StartHeights(BTreeMap<u32, f64>);

impl StartHeights {
    /// The bodies of `hello` by id (a body without a position is left out).
    #[must_use]
    pub fn from_hello(hello: &pb::Hello) -> Self {
        hello
            .bodies
            .iter()
            .filter_map(|body| Some((body.id, body.pose.as_ref()?.position.as_ref()?.z)))
            .collect()
    }

    /// `None` for a body the world does not have.
    #[must_use]
    pub fn z(&self, id: u32) -> Option<f64> {
        self.0.get(&id).copied()
    }
}

impl FromIterator<(u32, f64)> for StartHeights {
    fn from_iter<I: IntoIterator<Item = (u32, f64)>>(iter: I) -> Self {
        Self(iter.into_iter().collect())
    }
}

#[cfg(test)]
mod tests {
    use learner::features::{parse_frame, ActuatorYaw};
    use learner::ParseError;

    use super::*;

    fn body(name: &str, id: u32, position: [f64; 3], yaw: f64) -> pb::ModelState {
        pb::ModelState {
            name: name.into(),
            id,
            pose: Some(pb::Pose::from_position_yaw(position, yaw)),
            ..Default::default()
        }
    }

    fn state(models: Vec<pb::ModelState>) -> pb::WorldState {
        pb::WorldState {
            model_v: Some(pb::ModelStateV { models }),
            ..Default::default()
        }
    }

    #[test]
    fn keeps_every_body_in_order_with_xyzw_quaternions() {
        let s = state(vec![
            body("blockA", 15, [0.1, 0.25, 0.05], 0.5),
            body("actuator", 8, [0.0, 0.0, 0.03], 0.0),
            body("blockAShadow", 15, [9.0, 9.0, 0.05], 0.0),
        ]);
        let frame = frame_from_state(&s, &Shapes::default());
        let names: Vec<&str> = frame.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["blockA", "actuator", "blockAShadow"]);
        let block = &frame.objects[0];
        assert_eq!(block.id, 15);
        assert_eq!(block.position, [0.1, 0.25, 0.05]);
        let q = pb::Quaternion::from_yaw(0.5);
        assert_eq!(block.orientation, [q.x, q.y, q.z, q.w]);

        // The learner reads the same yaw back (and skips the shadow).
        let poses = parse_frame(&frame, ActuatorYaw::Keep).unwrap();
        assert_eq!(poses.blocks.len(), 1);
        assert_eq!(poses.blocks[&15].theta, 0.5);
        assert_eq!(poses.blocks[&15].x, 0.1);
    }

    #[test]
    fn a_missing_pose_is_refused_by_parsing_only_where_it_matters() {
        let mut actuator = body("actuator", 8, [0.0, 0.0, 0.03], 0.0);
        actuator.pose = None;
        let frame = frame_from_state(&state(vec![actuator]), &Shapes::default());
        assert!(matches!(
            parse_frame(&frame, ActuatorYaw::Keep),
            Err(ParseError::NonFinite { ref name, .. }) if name == "actuator"
        ));

        let mut shadow = body("actuatorShadow", 8, [0.0; 3], 0.0);
        shadow.pose = None;
        let frame = frame_from_state(
            &state(vec![body("actuator", 8, [0.2, 0.0, 0.03], 0.0), shadow]),
            &Shapes::default(),
        );
        assert_eq!(
            parse_frame(&frame, ActuatorYaw::Keep).unwrap().actuator.x,
            0.2
        );
    }

    #[test]
    fn an_empty_state_is_an_empty_frame() {
        assert!(
            frame_from_state(&pb::WorldState::default(), &Shapes::default())
                .objects
                .is_empty()
        );
    }

    #[test]
    fn start_heights_are_the_z_of_the_hello_start_poses() {
        let hello = pb::Hello {
            bodies: vec![
                body("actuator", 8, [0.0, 0.0, 0.03], 0.0),
                body("blockA", 15, [0.0, 0.25, 0.05], 0.0),
                pb::ModelState {
                    name: "blockB".into(),
                    id: 27,
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        let heights = StartHeights::from_hello(&hello);
        assert_eq!(heights.z(8), Some(0.03));
        assert_eq!(heights.z(15), Some(0.05));
        assert_eq!(heights.z(27), None);
    }
}
