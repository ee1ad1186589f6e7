//! Command validation (docs/spec/protocol.md §3: "every command is validated on
//! arrival").
//!
//! [`validate`] holds the checks that need nothing but the message; a world
//! runs it on every `ClientMessage` as it arrives and answers a failure with
//! [`InvalidCommand::reply`]. Checks that depend on the
//! world (body names, timing mode, pause state) are the world's, but their
//! wording lives here too ([`InvalidCommand::UnknownBody`], ...) so that every
//! refusal reads the same.

use super::pb::{self, actuator_command::Command, client_message::Payload, sim_control::Action};
use pushlearn_core::{quoted, MAX_NAME_BYTES};

/// Why a command is refused. The `Display` text is what the `Error` message
/// carries; it always names the command and, where there is one, the field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InvalidCommand {
    /// No `actuator`, `control` or `set_pose`. (Also the round-trip barrier,
    /// see [`pb::ClientMessage::barrier`].)
    #[error("missing payload: a ClientMessage must carry actuator, control or set_pose")]
    MissingPayload,
    /// `control` without an action.
    #[error(
        "control: no action (expected pause, reset, publish_rate_hz, advance or latency_seed)"
    )]
    MissingControlAction,
    /// `reset = false` or `advance = false`: a flag whose only meaning is true.
    #[error("{action}: must be true (false has no meaning)")]
    FalseFlag {
        /// `reset` or `advance`.
        action: &'static str,
    },
    /// A NaN or infinite number.
    #[error("{location} is {}", non_finite_word(*value))]
    NonFinite {
        /// The command and field, e.g. `set_pose: body 'blockA' position.x`.
        location: String,
        /// The offending value.
        value: f64,
    },
    /// An `ActuatorCommand.cmd` outside the enum.
    #[error("actuator: cmd {0} is not a command (expected NOTHING = 0, MOVE = 1, GRAB = 2 or RELEASE = 3)")]
    UnknownActuatorCommand(i32),
    /// A publish rate that is 0 or does not divide 1000.
    #[error("publish_rate_hz: {0} Hz does not divide 1000 (the world publishes every 1000/rate steps; use e.g. 100 or 10)")]
    BadPublishRate(u32),
    /// `set_pose` without any body.
    #[error("set_pose: no bodies given")]
    EmptySetPose,
    /// A `set_pose` entry without a name.
    #[error("set_pose: entry {index} has an empty name")]
    EmptyBodyName {
        /// Position of the entry in `models`.
        index: usize,
    },
    /// A `set_pose` entry whose name is longer than [`MAX_NAME_BYTES`].
    #[error("set_pose: entry {index} has a name of {bytes} bytes (at most {MAX_NAME_BYTES})")]
    LongBodyName {
        /// Position of the entry in `models`.
        index: usize,
        /// The name's length.
        bytes: usize,
    },
    /// A `set_pose` entry lacking `pose`, `pose.position` or `pose.orientation`.
    #[error("set_pose: body {} has no {field}", quoted(body))]
    MissingPoseField {
        /// The body's name.
        body: String,
        /// `pose`, `position` or `orientation`.
        field: &'static str,
    },
    /// An orientation that cannot be normalised to a unit quaternion.
    #[error("set_pose: body {} orientation {problem}", quoted(body))]
    DegenerateQuaternion {
        /// The body's name.
        body: String,
        /// `has zero length` or `is too long to normalise`.
        problem: &'static str,
    },
    /// World-dependent: `set_pose` names a body the scene does not have
    /// (`*Shadow` names are not unknown: the world keeps them as ghosts).
    #[error("set_pose: unknown body {} (this world has: {})", quoted(name), known.join(", "))]
    UnknownBody {
        /// The name as sent.
        name: String,
        /// The scene's bodies, for the message.
        known: Vec<String>,
    },
    /// World-dependent: a ghost (`<body>Shadow…`) of a body the scene does
    /// not have. Refused rather than published, since a ghost is drawn and
    /// identified as its body (with that body's id).
    #[error("set_pose: ghost {} is of body {}, which this world lacks (this world has: {})", quoted(name), quoted(body), known.join(", "))]
    GhostOfUnknownBody {
        /// The ghost's name as sent.
        name: String,
        /// The body it names, the part before `Shadow`.
        body: String,
        /// The scene's bodies, for the message.
        known: Vec<String>,
    },
    /// World-dependent: Advance sent to a world in realtime mode.
    #[error("advance: only valid in lockstep mode, but this world runs in realtime mode")]
    AdvanceInRealtime,
    /// World-dependent: Advance sent while the world is paused.
    #[error("advance: the world is paused; unpause it first")]
    AdvanceWhilePaused,
    /// World-dependent: `latency_seed` sent to a world without latency
    /// emulation (which only exists in lock-step mode).
    #[error("latency_seed: this world does not emulate latency (it needs lockstep mode with a latency maximum)")]
    LatencySeedWithoutLatency,
}

impl InvalidCommand {
    /// The `Error` answering command `seq`.
    pub fn reply(&self, seq: u64) -> pb::ServerMessage {
        pb::ServerMessage::error(seq, pb::error::Kind::InvalidCommand, self.to_string())
    }
}

fn non_finite_word(value: f64) -> &'static str {
    if value.is_nan() {
        "NaN"
    } else if value > 0.0 {
        "infinite (+inf)"
    } else {
        "infinite (-inf)"
    }
}

/// The checks that need only the message: every number finite, payload and
/// control action present, a known actuator command, a publish rate dividing
/// 1000, `set_pose` entries named and with a normalisable orientation.
pub fn validate(message: &pb::ClientMessage) -> Result<(), InvalidCommand> {
    match &message.payload {
        None => Err(InvalidCommand::MissingPayload),
        Some(Payload::Actuator(command)) => validate_actuator(command),
        Some(Payload::Control(control)) => validate_control(control),
        Some(Payload::SetPose(poses)) => validate_set_pose(poses),
    }
}

fn validate_actuator(command: &pb::ActuatorCommand) -> Result<(), InvalidCommand> {
    if Command::try_from(command.cmd).is_err() {
        return Err(InvalidCommand::UnknownActuatorCommand(command.cmd));
    }
    check_vector(command.direction.as_ref(), || {
        "actuator: direction".to_owned()
    })
}

fn validate_control(control: &pb::SimControl) -> Result<(), InvalidCommand> {
    match control.action {
        None => Err(InvalidCommand::MissingControlAction),
        Some(Action::Pause(_)) => Ok(()),
        Some(Action::Reset(false)) => Err(InvalidCommand::FalseFlag { action: "reset" }),
        Some(Action::Advance(false)) => Err(InvalidCommand::FalseFlag { action: "advance" }),
        Some(Action::Reset(true) | Action::Advance(true)) => Ok(()),
        Some(Action::PublishRateHz(hz)) if hz == 0 || 1000 % hz != 0 => {
            Err(InvalidCommand::BadPublishRate(hz))
        }
        Some(Action::PublishRateHz(_) | Action::LatencySeed(_)) => Ok(()),
    }
}

fn validate_set_pose(poses: &pb::ModelStateV) -> Result<(), InvalidCommand> {
    if poses.models.is_empty() {
        return Err(InvalidCommand::EmptySetPose);
    }
    for (index, model) in poses.models.iter().enumerate() {
        validate_model(index, model)?;
    }
    Ok(())
}

fn validate_model(index: usize, model: &pb::ModelState) -> Result<(), InvalidCommand> {
    let body = &model.name;
    if body.is_empty() {
        return Err(InvalidCommand::EmptyBodyName { index });
    }
    if body.len() > MAX_NAME_BYTES {
        return Err(InvalidCommand::LongBodyName {
            index,
            bytes: body.len(),
        });
    }
    let missing = |field| InvalidCommand::MissingPoseField {
        body: body.clone(),
        field,
    };
    let pose = model.pose.as_ref().ok_or_else(|| missing("pose"))?;
    let position = pose.position.as_ref().ok_or_else(|| missing("position"))?;
    let orientation = pose
        .orientation
        .as_ref()
        .ok_or_else(|| missing("orientation"))?;
    let at = |field: &str| format!("set_pose: body {} {field}", quoted(body));

    check_vector(Some(position), || at("position"))?;
    let pb::Quaternion { x, y, z, w } = *orientation;
    for (axis, value) in [("x", x), ("y", y), ("z", z), ("w", w)] {
        check_finite(value, || at(&format!("orientation.{axis}")))?;
    }
    // The protocol's rule (docs/protocol.md): a length whose square neither
    // underflows to zero nor overflows. The world's `orientation::normalise`
    // would cope with more (it refuses only zero); the wire's rule is the
    // published one and stays.
    let norm_squared = x * x + y * y + z * z + w * w;
    if norm_squared < f64::MIN_POSITIVE || norm_squared.is_infinite() {
        let problem = if norm_squared.is_infinite() {
            "is too long to normalise"
        } else {
            "has zero length"
        };
        return Err(InvalidCommand::DegenerateQuaternion {
            body: body.clone(),
            problem,
        });
    }
    check_vector(model.scale.as_ref(), || at("scale"))?;
    check_vector(model.lin_vel.as_ref(), || at("lin_vel"))?;
    check_vector(model.ang_vel.as_ref(), || at("ang_vel"))
}

fn check_vector(
    vector: Option<&pb::Vector3d>,
    location: impl Fn() -> String,
) -> Result<(), InvalidCommand> {
    let Some(v) = vector else { return Ok(()) };
    for (axis, value) in [("x", v.x), ("y", v.y), ("z", v.z)] {
        check_finite(value, || format!("{}.{axis}", location()))?;
    }
    Ok(())
}

fn check_finite(value: f64, location: impl FnOnce() -> String) -> Result<(), InvalidCommand> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(InvalidCommand::NonFinite {
            location: location(),
            value,
        })
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;
    use crate::wire::pb::ClientMessage;

    fn refusal(message: &ClientMessage) -> String {
        match validate(message) {
            Err(err) => err.to_string(),
            Ok(()) => panic!("accepted an invalid command: {message:?}"),
        }
    }

    fn set_pose_with(edit: impl FnOnce(&mut pb::ModelState)) -> ClientMessage {
        let mut message = ClientMessage::set_pose(1, "blockA", [0.0, 0.25, 0.05], 0.0);
        if let Some(Payload::SetPose(v)) = &mut message.payload {
            edit(&mut v.models[0]);
        }
        message
    }

    fn position(m: &mut pb::ModelState) -> &mut pb::Vector3d {
        m.pose
            .get_or_insert_default()
            .position
            .get_or_insert_default()
    }

    fn orientation(m: &mut pb::ModelState) -> &mut pb::Quaternion {
        m.pose
            .get_or_insert_default()
            .orientation
            .get_or_insert_default()
    }

    #[test]
    fn every_constructor_makes_a_valid_command() {
        for message in [
            ClientMessage::move_(1, 0.0, 0.5),
            ClientMessage::move_(1, -0.5, 0.0),
            ClientMessage::pause(1),
            ClientMessage::unpause(1),
            ClientMessage::reset(1),
            ClientMessage::set_pose(1, "actuator", [0.0, 0.0, 0.03], 0.0),
            ClientMessage::set_pose(1, "blockAShadow", [0.1, 0.3, 0.05], -2.0),
            ClientMessage::publish_rate(1, 100),
            ClientMessage::publish_rate(1, 10),
            ClientMessage::publish_rate(1, 1000),
            ClientMessage::publish_rate(1, 1),
            ClientMessage::advance(1),
            ClientMessage::latency_seed(1, 0),
            ClientMessage::latency_seed(1, u64::MAX),
        ] {
            assert_eq!(validate(&message), Ok(()), "{message:?}");
        }
    }

    #[test]
    fn nan_position_names_body_and_axis() {
        let message = set_pose_with(|m| position(m).x = f64::NAN);
        assert_eq!(
            refusal(&message),
            "set_pose: body 'blockA' position.x is NaN"
        );
    }

    #[test]
    fn infinite_numbers_anywhere_are_named() {
        let cases: Vec<(ClientMessage, &str)> = vec![
            (
                ClientMessage::move_(1, f64::INFINITY, 0.0),
                "actuator: direction.x is infinite (+inf)",
            ),
            (
                ClientMessage::move_(1, 0.0, f64::NAN),
                "actuator: direction.y is NaN",
            ),
            (
                set_pose_with(|m| orientation(m).w = f64::NEG_INFINITY),
                "set_pose: body 'blockA' orientation.w is infinite (-inf)",
            ),
            (
                set_pose_with(|m| m.lin_vel = Some(pb::Vector3d::new(0.0, 0.0, f64::NAN))),
                "set_pose: body 'blockA' lin_vel.z is NaN",
            ),
            (
                set_pose_with(|m| m.ang_vel = Some(pb::Vector3d::new(0.0, f64::INFINITY, 0.0))),
                "set_pose: body 'blockA' ang_vel.y is infinite (+inf)",
            ),
            (
                set_pose_with(|m| m.scale = Some(pb::Vector3d::new(f64::NAN, 1.0, 1.0))),
                "set_pose: body 'blockA' scale.x is NaN",
            ),
        ];
        for (message, expected) in cases {
            assert_eq!(refusal(&message), expected);
        }
    }

    #[test]
    fn direction_z_is_checked_too() {
        let mut message = ClientMessage::move_(1, 0.0, 0.0);
        if let Some(Payload::Actuator(a)) = &mut message.payload {
            a.direction = Some(pb::Vector3d::new(0.0, 0.0, f64::NAN));
        }
        assert_eq!(refusal(&message), "actuator: direction.z is NaN");
    }

    #[test]
    fn zero_and_overflowing_quaternions_are_refused() {
        let zero = set_pose_with(|m| *orientation(m) = pb::Quaternion::default());
        assert_eq!(
            refusal(&zero),
            "set_pose: body 'blockA' orientation has zero length"
        );
        let tiny = set_pose_with(|m| {
            *orientation(m) = pb::Quaternion {
                x: 0.0,
                y: 0.0,
                z: 1e-200,
                w: 0.0,
            }
        });
        assert_eq!(
            refusal(&tiny),
            "set_pose: body 'blockA' orientation has zero length"
        );
        let huge = set_pose_with(|m| {
            *orientation(m) = pb::Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1e200,
            }
        });
        assert_eq!(
            refusal(&huge),
            "set_pose: body 'blockA' orientation is too long to normalise"
        );
    }

    #[test]
    fn non_unit_quaternions_are_left_to_normalisation() {
        let scaled = set_pose_with(|m| {
            *orientation(m) = pb::Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 2.0,
            }
        });
        assert_eq!(validate(&scaled), Ok(()));
    }

    #[test]
    fn missing_pose_parts_are_named() {
        assert_eq!(
            refusal(&set_pose_with(|m| m.pose = None)),
            "set_pose: body 'blockA' has no pose"
        );
        let no_position = set_pose_with(|m| m.pose.get_or_insert_default().position = None);
        assert_eq!(
            refusal(&no_position),
            "set_pose: body 'blockA' has no position"
        );
        let no_orientation = set_pose_with(|m| m.pose.get_or_insert_default().orientation = None);
        assert_eq!(
            refusal(&no_orientation),
            "set_pose: body 'blockA' has no orientation"
        );
    }

    #[test]
    fn set_pose_needs_named_bodies() {
        let empty = ClientMessage::new(1, Payload::SetPose(pb::ModelStateV::default()));
        assert_eq!(refusal(&empty), "set_pose: no bodies given");
        let unnamed = set_pose_with(|m| m.name.clear());
        assert_eq!(refusal(&unnamed), "set_pose: entry 0 has an empty name");
    }

    #[test]
    fn later_entries_are_checked() {
        let mut message = ClientMessage::new(
            1,
            Payload::set_poses([
                (
                    "actuator".to_owned(),
                    pb::Pose::from_position_yaw([0.0, 0.0, 0.03], 0.0),
                ),
                (
                    "blockB".to_owned(),
                    pb::Pose::from_position_yaw([-0.6, 0.35, 0.05], 0.0),
                ),
            ]),
        );
        if let Some(Payload::SetPose(v)) = &mut message.payload {
            position(&mut v.models[1]).y = f64::NAN;
        }
        assert_eq!(
            refusal(&message),
            "set_pose: body 'blockB' position.y is NaN"
        );
    }

    #[test]
    fn publish_rates_must_divide_1000() {
        for hz in [0, 3, 7, 30, 999, 1001, 2000] {
            let text = refusal(&ClientMessage::publish_rate(1, hz));
            assert!(
                text.starts_with(&format!("publish_rate_hz: {hz} Hz does not divide 1000")),
                "{text}"
            );
        }
    }

    #[test]
    fn missing_payload_and_action_are_refused() {
        assert!(refusal(&ClientMessage::barrier(5)).starts_with("missing payload"));
        let no_action = ClientMessage::new(1, Payload::Control(pb::SimControl { action: None }));
        assert!(refusal(&no_action).starts_with("control: no action"));
    }

    #[test]
    fn false_flags_are_refused() {
        let flag = |action| {
            ClientMessage::new(
                1,
                Payload::Control(pb::SimControl {
                    action: Some(action),
                }),
            )
        };
        assert_eq!(
            refusal(&flag(Action::Reset(false))),
            "reset: must be true (false has no meaning)"
        );
        assert_eq!(
            refusal(&flag(Action::Advance(false))),
            "advance: must be true (false has no meaning)"
        );
    }

    #[test]
    fn unknown_actuator_command_is_refused_known_ones_pass() {
        let with_cmd = |cmd| {
            ClientMessage::new(
                1,
                Payload::Actuator(pb::ActuatorCommand {
                    cmd,
                    direction: None,
                }),
            )
        };
        assert!(refusal(&with_cmd(9)).starts_with("actuator: cmd 9 is not a command"));
        for cmd in 0..=3 {
            assert_eq!(validate(&with_cmd(cmd)), Ok(()));
        }
    }

    #[test]
    fn world_dependent_texts_name_the_problem() {
        let unknown = InvalidCommand::UnknownBody {
            name: "blockC".into(),
            known: vec!["actuator".into(), "blockA".into()],
        };
        assert_eq!(
            unknown.to_string(),
            "set_pose: unknown body 'blockC' (this world has: actuator, blockA)"
        );
        let reply = InvalidCommand::AdvanceInRealtime.reply(42);
        match reply.payload {
            Some(pb::server_message::Payload::Error(e)) => {
                assert_eq!(e.seq, 42);
                assert!(e.message.contains("realtime"), "{}", e.message);
            }
            other => panic!("expected an Error, got {other:?}"),
        }
    }

    proptest! {
        #[test]
        fn finite_set_poses_pass(x in -10.0f64..10.0, y in -10.0f64..10.0, z in 0.0f64..1.0, yaw in -7.0f64..7.0) {
            prop_assert_eq!(validate(&ClientMessage::set_pose(1, "blockA", [x, y, z], yaw)), Ok(()));
        }

        #[test]
        fn any_non_finite_coordinate_is_refused(index in 0usize..3, bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)]) {
            let mut p = [0.0, 0.25, 0.05];
            p[index] = bad;
            let text = refusal(&ClientMessage::set_pose(1, "blockA", p, 0.0));
            let expected = format!("set_pose: body 'blockA' position.{} is ", ["x", "y", "z"][index]);
            prop_assert!(text.starts_with(&expected), "{}", text);
        }
    }

    /// Issue 49, item 10: a body name with a newline wrote a forged log
    /// line (the refusal is logged), and a 100 KB name was echoed whole.
    #[test]
    fn body_names_are_capped_and_shown_escaped() {
        let long = set_pose_with(|m| m.name = "x".repeat(100_000));
        assert_eq!(
            refusal(&long),
            "set_pose: entry 0 has a name of 100000 bytes (at most 256)"
        );
        let forged = set_pose_with(|m| {
            m.name = "blockA\nINFO forged".into();
            if let Some(p) = m.pose.as_mut().and_then(|p| p.position.as_mut()) {
                p.x = f64::NAN;
            }
        });
        let text = refusal(&forged);
        assert!(!text.contains('\n'), "{text}");
        assert!(text.contains("'blockA\\nINFO forged'"), "{text}");
        let unknown = InvalidCommand::UnknownBody {
            name: "a\rb".into(),
            known: vec!["actuator".into()],
        };
        assert!(!unknown.to_string().contains('\r'), "{unknown}");
    }
}
