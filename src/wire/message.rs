//! Constructors and small conveniences for the generated message types.
//!
//! The payload constructors ([`Payload::move_`], ...) are the one place where
//! commands are assembled; the `ClientMessage` constructors only attach a
//! `seq`.

use std::fmt;
use std::str::FromStr;

use super::orientation;
use super::pb::{
    self, actuator_command::Command, client_message::Payload, server_message, sim_control::Action,
};

impl pb::Vector3d {
    /// `(x, y, z)`.
    pub fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
}

impl pb::Quaternion {
    /// A rotation by `yaw` radians about the world z axis
    /// ([`orientation::from_yaw`]).
    pub fn from_yaw(yaw: f64) -> Self {
        let [x, y, z, w] = orientation::from_yaw(yaw);
        Self { x, y, z, w }
    }

    /// The yaw the learners read from this orientation
    /// ([`orientation::yaw`]).
    pub fn yaw(&self) -> f64 {
        orientation::yaw([self.x, self.y, self.z, self.w])
    }
}

impl pb::Pose {
    /// Position `[x, y, z]` with orientation `yaw` about the z axis.
    pub fn from_position_yaw(position: [f64; 3], yaw: f64) -> Self {
        let [x, y, z] = position;
        Self {
            position: Some(pb::Vector3d::new(x, y, z)),
            orientation: Some(pb::Quaternion::from_yaw(yaw)),
        }
    }
}

impl Payload {
    /// Move: actuator velocity `(vx, vy, 0)` in m/s, world frame.
    pub fn move_(vx: f64, vy: f64) -> Self {
        Payload::Actuator(pb::ActuatorCommand {
            cmd: Command::Move.into(),
            direction: Some(pb::Vector3d::new(vx, vy, 0.0)),
        })
    }

    /// Stop stepping.
    pub fn pause() -> Self {
        Self::control(Action::Pause(true))
    }

    /// Resume stepping.
    pub fn unpause() -> Self {
        Self::control(Action::Pause(false))
    }

    /// Reset every body, velocity, the time and the step counter.
    pub fn reset() -> Self {
        Self::control(Action::Reset(true))
    }

    /// Publish every `1000 / hz` steps; `hz` must divide 1000.
    pub fn publish_rate(hz: u32) -> Self {
        Self::control(Action::PublishRateHz(hz))
    }

    /// Lock-step mode: run the physics until the next publish.
    pub fn advance() -> Self {
        Self::control(Action::Advance(true))
    }

    /// Lock-step mode with latency emulation: reseed the generator that
    /// draws each Move's delay, so that a run's delays do not depend on what
    /// the world did before it.
    pub fn latency_seed(seed: u64) -> Self {
        Self::control(Action::LatencySeed(seed))
    }

    /// Set one body's pose: position `[x, y, z]` and `yaw` about the z axis.
    pub fn set_pose(name: impl Into<String>, position: [f64; 3], yaw: f64) -> Self {
        Self::set_poses([(name.into(), pb::Pose::from_position_yaw(position, yaw))])
    }

    /// Set several bodies' poses at one step boundary.
    pub fn set_poses(poses: impl IntoIterator<Item = (String, pb::Pose)>) -> Self {
        let models = poses
            .into_iter()
            .map(|(name, pose)| pb::ModelState {
                name,
                pose: Some(pose),
                ..Default::default()
            })
            .collect();
        Payload::SetPose(pb::ModelStateV { models })
    }

    fn control(action: Action) -> Self {
        Payload::Control(pb::SimControl {
            action: Some(action),
        })
    }

    /// A short name for logs and messages: `move`, `pause`, `set_pose`, ...
    pub fn kind(&self) -> &'static str {
        match self {
            Payload::Actuator(a) => match Command::try_from(a.cmd) {
                Ok(Command::Move) => "move",
                Ok(Command::Nothing) => "nothing",
                Ok(Command::Grab) => "grab",
                Ok(Command::Release) => "release",
                Err(_) => "actuator",
            },
            Payload::Control(c) => match c.action {
                Some(Action::Pause(true)) => "pause",
                Some(Action::Pause(false)) => "unpause",
                Some(Action::Reset(_)) => "reset",
                Some(Action::PublishRateHz(_)) => "publish_rate",
                Some(Action::Advance(_)) => "advance",
                Some(Action::LatencySeed(_)) => "latency_seed",
                None => "control",
            },
            Payload::SetPose(_) => "set_pose",
        }
    }
}

impl pb::ClientMessage {
    /// `payload` tagged with `seq`.
    pub fn new(seq: u64, payload: Payload) -> Self {
        Self {
            seq,
            payload: Some(payload),
        }
    }

    /// See [`Payload::move_`].
    pub fn move_(seq: u64, vx: f64, vy: f64) -> Self {
        Self::new(seq, Payload::move_(vx, vy))
    }

    /// See [`Payload::pause`].
    pub fn pause(seq: u64) -> Self {
        Self::new(seq, Payload::pause())
    }

    /// See [`Payload::unpause`].
    pub fn unpause(seq: u64) -> Self {
        Self::new(seq, Payload::unpause())
    }

    /// See [`Payload::reset`].
    pub fn reset(seq: u64) -> Self {
        Self::new(seq, Payload::reset())
    }

    /// See [`Payload::set_pose`].
    pub fn set_pose(seq: u64, name: impl Into<String>, position: [f64; 3], yaw: f64) -> Self {
        Self::new(seq, Payload::set_pose(name, position, yaw))
    }

    /// See [`Payload::publish_rate`].
    pub fn publish_rate(seq: u64, hz: u32) -> Self {
        Self::new(seq, Payload::publish_rate(hz))
    }

    /// See [`Payload::advance`].
    pub fn advance(seq: u64) -> Self {
        Self::new(seq, Payload::advance())
    }

    /// See [`Payload::latency_seed`].
    pub fn latency_seed(seq: u64, seed: u64) -> Self {
        Self::new(seq, Payload::latency_seed(seed))
    }

    /// A message without payload. The world refuses it at once with an
    /// `Error` carrying `seq` and changes nothing; because a world validates
    /// a client's frames in arrival order, that answer proves every earlier
    /// frame of this connection was received and validated. Clients use it as
    /// a round-trip barrier (`docs/protocol.md`, "Acknowledgement").
    pub fn barrier(seq: u64) -> Self {
        Self { seq, payload: None }
    }
}

impl pb::ServerMessage {
    /// An `Error` answering command `seq` (0: not about one command).
    pub fn error(seq: u64, kind: pb::error::Kind, message: impl Into<String>) -> Self {
        Self {
            payload: Some(server_message::Payload::Error(pb::Error {
                message: message.into(),
                seq,
                kind: kind.into(),
            })),
        }
    }
}

impl From<pb::Hello> for pb::ServerMessage {
    fn from(hello: pb::Hello) -> Self {
        Self {
            payload: Some(server_message::Payload::Hello(hello)),
        }
    }
}

impl From<pb::WorldState> for pb::ServerMessage {
    fn from(state: pb::WorldState) -> Self {
        Self {
            payload: Some(server_message::Payload::WorldState(state)),
        }
    }
}

impl pb::WorldState {
    /// The published bodies (empty if the message carries none).
    pub fn models(&self) -> &[pb::ModelState] {
        self.model_v.as_ref().map_or(&[], |v| &v.models)
    }

    /// The body called `name`, if published.
    pub fn model(&self, name: &str) -> Option<&pb::ModelState> {
        self.models().iter().find(|m| m.name == name)
    }
}

/// How the world paces its steps (`Hello.timing_mode`, docs/spec/world.md §8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimingMode {
    /// Steps continuously, paced against the wall clock.
    Realtime,
    /// Stops after every publish until a client sends Advance.
    Lockstep,
}

impl TimingMode {
    /// The name used in `Hello.timing_mode`.
    pub fn as_str(self) -> &'static str {
        match self {
            TimingMode::Realtime => "realtime",
            TimingMode::Lockstep => "lockstep",
        }
    }
}

impl From<TimingMode> for pb::hello::TimingKind {
    fn from(mode: TimingMode) -> Self {
        match mode {
            TimingMode::Realtime => Self::Realtime,
            TimingMode::Lockstep => Self::Lockstep,
        }
    }
}

impl fmt::Display for TimingMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A `timing_mode` string other than `realtime` or `lockstep`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown timing mode '{0}' (expected 'realtime' or 'lockstep')")]
pub struct UnknownTimingMode(pub String);

impl FromStr for TimingMode {
    type Err = UnknownTimingMode;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "realtime" => Ok(TimingMode::Realtime),
            "lockstep" => Ok(TimingMode::Lockstep),
            other => Err(UnknownTimingMode(other.to_owned())),
        }
    }
}

impl pb::Hello {
    /// The world's timing mode: `timing_kind`, or for a world that leaves it
    /// unspecified (one older than the field) the `timing_mode` string.
    pub fn timing(&self) -> Result<TimingMode, UnknownTimingMode> {
        match self.timing_kind() {
            pb::hello::TimingKind::Realtime => Ok(TimingMode::Realtime),
            pb::hello::TimingKind::Lockstep => Ok(TimingMode::Lockstep),
            pb::hello::TimingKind::Unspecified => self.timing_mode.parse(),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2, PI};

    use super::*;

    #[test]
    fn yaw_quaternion_is_half_angle_about_z() {
        let q = pb::Quaternion::from_yaw(FRAC_PI_2);
        let half = (FRAC_PI_2 / 2.0).sin();
        assert_eq!((q.x, q.y), (0.0, 0.0));
        assert!(
            (q.z - half).abs() < 1e-15 && (q.w - half).abs() < 1e-15,
            "{q:?}"
        );
        assert_eq!(
            pb::Quaternion::from_yaw(0.0),
            pb::Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0
            }
        );
    }

    #[test]
    fn yaw_survives_the_round_trip() {
        for yaw in [-3.0, -FRAC_PI_2, -0.1, 0.0, 0.25, 1.0, FRAC_PI_2, 3.0, PI] {
            let back = pb::Quaternion::from_yaw(yaw).yaw();
            assert!((back - yaw).abs() < 1e-12, "{yaw} -> {back}");
        }
    }

    #[test]
    fn move_sets_cmd_and_planar_direction() {
        let m = pb::ClientMessage::move_(4, 0.1, -0.5);
        assert_eq!(m.seq, 4);
        let Some(Payload::Actuator(a)) = m.payload else {
            panic!("not an actuator command: {m:?}")
        };
        assert_eq!(a.cmd(), Command::Move);
        assert_eq!(a.direction, Some(pb::Vector3d::new(0.1, -0.5, 0.0)));
    }

    #[test]
    fn control_constructors_pick_their_action() {
        let action = |m: pb::ClientMessage| match m.payload {
            Some(Payload::Control(c)) => c.action,
            other => panic!("not a control message: {other:?}"),
        };
        assert_eq!(
            action(pb::ClientMessage::pause(1)),
            Some(Action::Pause(true))
        );
        assert_eq!(
            action(pb::ClientMessage::unpause(1)),
            Some(Action::Pause(false))
        );
        assert_eq!(
            action(pb::ClientMessage::reset(1)),
            Some(Action::Reset(true))
        );
        assert_eq!(
            action(pb::ClientMessage::publish_rate(1, 10)),
            Some(Action::PublishRateHz(10))
        );
        assert_eq!(
            action(pb::ClientMessage::advance(1)),
            Some(Action::Advance(true))
        );
        assert_eq!(
            action(pb::ClientMessage::latency_seed(1, 42)),
            Some(Action::LatencySeed(42))
        );
    }

    #[test]
    fn set_pose_names_one_body_with_its_pose() {
        let m = pb::ClientMessage::set_pose(2, "actuator", [0.0, 0.0, 0.03], 0.0);
        let Some(Payload::SetPose(v)) = m.payload else {
            panic!("not set_pose: {m:?}")
        };
        assert_eq!(v.models.len(), 1);
        assert_eq!(v.models[0].name, "actuator");
        assert_eq!(
            v.models[0].pose,
            Some(pb::Pose::from_position_yaw([0.0, 0.0, 0.03], 0.0))
        );
    }

    #[test]
    fn kinds_name_the_command() {
        assert_eq!(Payload::move_(0.0, 0.0).kind(), "move");
        assert_eq!(Payload::unpause().kind(), "unpause");
        assert_eq!(Payload::latency_seed(7).kind(), "latency_seed");
        assert_eq!(
            Payload::set_pose("blockA", [0.0; 3], 0.0).kind(),
            "set_pose"
        );
    }

    #[test]
    fn a_hello_from_an_older_world_is_read_by_its_string() {
        use prost::Message;
        // Field 4 (timing_mode) = "lockstep", no field 7: what a world
        // older than `timing_kind` sends.
        let old = [&[0x22, 8][..], b"lockstep"].concat();
        let hello = pb::Hello::decode(&old[..]).unwrap();
        assert_eq!(hello.timing_kind(), pb::hello::TimingKind::Unspecified);
        assert_eq!(hello.timing(), Ok(TimingMode::Lockstep));
        let mut new = hello.clone();
        new.set_timing_kind(pb::hello::TimingKind::Realtime);
        // The enum wins over the string when both are there.
        assert_eq!(new.timing(), Ok(TimingMode::Realtime));
        let unknown = pb::Hello::decode(&[0x22, 1, b'x', 0x38, 9][..]).unwrap();
        assert_eq!(unknown.timing(), Err(UnknownTimingMode("x".into())));
    }

    #[test]
    fn an_error_from_an_older_world_decodes_to_its_message_and_seq() {
        use prost::Message;
        // message = "no", seq = 5, no kind (field 3).
        let old = [0x0a, 2, b'n', b'o', 0x10, 5];
        let error = pb::Error::decode(&old[..]).unwrap();
        assert_eq!(error.message, "no");
        assert_eq!(error.seq, 5);
        assert_eq!(error.kind(), pb::error::Kind::Unspecified);
        // A kind from a newer world than this reader reads as unspecified.
        let newer = pb::Error::decode(&[0x18, 99][..]).unwrap();
        assert_eq!(newer.kind(), pb::error::Kind::Unspecified);
        // And the new field is only appended: an older reader skips it.
        let sent = pb::ServerMessage::error(5, pb::error::Kind::Busy, "no");
        let Some(server_message::Payload::Error(e)) = sent.payload else {
            panic!("not an error: {sent:?}")
        };
        assert_eq!(e.encode_to_vec(), [&old[..], &[0x18, 3]].concat());
    }

    #[test]
    fn timing_mode_parses_its_own_names() {
        for mode in [TimingMode::Realtime, TimingMode::Lockstep] {
            assert_eq!(mode.as_str().parse::<TimingMode>(), Ok(mode));
        }
        assert!("Lockstep".parse::<TimingMode>().is_err());
    }
}
