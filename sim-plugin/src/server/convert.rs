//! Protobuf messages to world commands, and world states to protobuf.

use pushlearn::wire::pb::{
    self, actuator_command::Command as Actuator, client_message::Payload, sim_control::Action,
};
use pushlearn::wire::{BodyName, InvalidCommand, TimingMode};

use super::gate::{Op, Refusal};
use crate::scene::{BodySpec, Scene, ShapeSpec};
use crate::world::{check_command, ActuatorMode, BodyState, Command, Engine, Snapshot};

/// `ModelState.scale`: the original always sent (1, 1, 1).
const UNIT_SCALE: pb::Vector3d = pb::Vector3d {
    x: 1.0,
    y: 1.0,
    z: 1.0,
};

/// What `message` asks of the world of `scene`. `message` has passed
/// [`pushlearn::wire::validate`]; this adds the checks that need the scene.
pub(super) fn operation(message: &pb::ClientMessage, scene: &Scene) -> Result<Op, Refusal> {
    let commands = match &message.payload {
        None => return Err(InvalidCommand::MissingPayload.into()),
        Some(Payload::Actuator(actuator)) => vec![Command::Actuator {
            mode: match actuator.cmd() {
                Actuator::Nothing => ActuatorMode::Nothing,
                Actuator::Move => ActuatorMode::Move,
                Actuator::Grab => ActuatorMode::Grab,
                Actuator::Release => ActuatorMode::Release,
            },
            velocity: vector(actuator.direction),
        }],
        Some(Payload::Control(control)) => match control.action {
            None => return Err(InvalidCommand::MissingControlAction.into()),
            Some(Action::Pause(true)) => vec![Command::Pause],
            Some(Action::Pause(false)) => vec![Command::Unpause],
            Some(Action::Reset(_)) => vec![Command::Reset],
            Some(Action::PublishRateHz(hz)) => vec![Command::SetPublishRate(hz)],
            Some(Action::Advance(_)) => return Ok(Op::Advance),
            Some(Action::LatencySeed(seed)) => return Ok(Op::LatencySeed(seed)),
        },
        Some(Payload::SetPose(poses)) => poses
            .models
            .iter()
            .map(|model| set_pose(model, scene))
            .collect::<Result<_, _>>()?,
    };
    for command in &commands {
        check_command(scene, command).map_err(|error| Refusal::World {
            command: describe(command),
            error,
        })?;
    }
    Ok(Op::World(commands))
}

fn set_pose(model: &pb::ModelState, scene: &Scene) -> Result<Command, Refusal> {
    let name = BodyName::parse(&model.name);
    // Named in the wire's words (which list the scene's bodies) rather than
    // the world's, so every refusal of an unknown body reads the same.
    let known = || scene.bodies.iter().map(|b| b.name.clone()).collect();
    match &name {
        BodyName::Body(body) if scene.body_index(body).is_none() => {
            return Err(InvalidCommand::UnknownBody {
                name: body.clone(),
                known: known(),
            }
            .into());
        }
        BodyName::Ghost(ghost) if scene.body_index(&ghost.of).is_none() => {
            return Err(InvalidCommand::GhostOfUnknownBody {
                name: model.name.clone(),
                body: ghost.of.clone(),
                known: known(),
            }
            .into());
        }
        BodyName::Body(_) | BodyName::Ghost(_) => {}
    }
    let pose = model.pose.unwrap_or_default();
    let q = pose.orientation.unwrap_or_default();
    Ok(Command::SetPose {
        name,
        position: vector(pose.position),
        orientation: [q.x, q.y, q.z, q.w],
    })
}

fn describe(command: &Command) -> String {
    match command {
        Command::Actuator { .. } => "actuator".into(),
        Command::SetPose { name, .. } => {
            format!(
                "set_pose: body {}",
                pushlearn::wire::quoted(&name.to_string())
            )
        }
        Command::SetPublishRate(_) => "publish_rate_hz".into(),
        Command::Pause | Command::Unpause => "pause".into(),
        Command::Reset => "reset".into(),
    }
}

fn vector(v: Option<pb::Vector3d>) -> [f64; 3] {
    v.map_or([0.0; 3], |v| [v.x, v.y, v.z])
}

fn vector3d([x, y, z]: [f64; 3]) -> pb::Vector3d {
    pb::Vector3d { x, y, z }
}

fn pose(position: [f64; 3], [x, y, z, w]: [f64; 4]) -> pb::Pose {
    pb::Pose {
        position: Some(vector3d(position)),
        orientation: Some(pb::Quaternion { x, y, z, w }),
    }
}

/// Every connection's first message: the scene's bodies at their start poses.
/// `latency_max_steps` is the latency emulation's maximum, if it is on.
pub(super) fn hello(
    scene: &Scene,
    publish_rate: u32,
    timing: TimingMode,
    latency_max_steps: Option<u32>,
    engine: Engine,
) -> pb::Hello {
    pb::Hello {
        scene: scene.name.clone(),
        step_size: scene.physics.step_size,
        publish_rate,
        timing_mode: timing.as_str().into(),
        timing_kind: pb::hello::TimingKind::from(timing).into(),
        bodies: scene
            .bodies
            .iter()
            .map(|body| pb::ModelState {
                name: body.name.clone(),
                id: body.id,
                is_static: false,
                pose: Some(pose(body.start.position(), body.start.orientation())),
                scale: Some(UNIT_SCALE),
                ..Default::default()
            })
            .collect(),
        shapes: shapes(scene),
        latency_max_steps,
        max_speed: Some(scene.drive.max_speed),
        engine: engine.as_str().into(),
    }
}

/// Every body's size as the Hello gives it.
pub fn shapes(scene: &Scene) -> Vec<pb::Shape> {
    scene.bodies.iter().map(shape).collect()
}

/// The size of a body on the wire, so that viewers draw it at its real size.
fn shape(body: &BodySpec) -> pb::Shape {
    pb::Shape {
        name: body.name.clone(),
        geometry: Some(match body.shape {
            ShapeSpec::Sphere { radius } => pb::shape::Geometry::SphereRadius(radius),
            ShapeSpec::Box { size } => pb::shape::Geometry::BoxSize(vector3d(size)),
            ShapeSpec::Cylinder { radius, length } => {
                pb::shape::Geometry::Cylinder(pb::Cylinder { radius, length })
            }
        }),
    }
}

/// The published state: dynamic bodies in scene order, then the ghosts.
pub(super) fn world_state(
    snapshot: &Snapshot,
    publish_seq: u64,
    applied_seq: u64,
) -> pb::WorldState {
    pb::WorldState {
        model_v: Some(pb::ModelStateV {
            models: snapshot
                .bodies
                .iter()
                .chain(&snapshot.ghosts)
                .map(model)
                .collect(),
        }),
        step: snapshot.step,
        sim_time: snapshot.sim_time,
        publish_seq,
        applied_seq,
    }
}

fn model(body: &BodyState) -> pb::ModelState {
    pb::ModelState {
        name: body.name.clone(),
        id: body.id,
        is_static: body.is_static,
        pose: Some(pose(body.position, body.orientation)),
        scale: Some(UNIT_SCALE),
        lin_vel: Some(vector3d(body.lin_vel)),
        ang_vel: Some(vector3d(body.ang_vel)),
        r#type: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        Scene::builtin("one_block").expect("embedded scene")
    }

    fn refusal(message: &pb::ClientMessage) -> String {
        match operation(message, &scene()) {
            Err(refusal) => refusal.to_string(),
            Ok(op) => panic!("accepted {message:?} as {op:?}"),
        }
    }

    #[test]
    fn every_control_action_maps_to_its_command() {
        let scene = scene();
        let commands = |message| match operation(&message, &scene) {
            Ok(Op::World(commands)) => commands,
            other => panic!("{other:?}"),
        };
        assert_eq!(commands(pb::ClientMessage::pause(1)), [Command::Pause]);
        assert_eq!(commands(pb::ClientMessage::unpause(1)), [Command::Unpause]);
        assert_eq!(commands(pb::ClientMessage::reset(1)), [Command::Reset]);
        assert_eq!(
            commands(pb::ClientMessage::publish_rate(1, 10)),
            [Command::SetPublishRate(10)]
        );
        assert_eq!(
            commands(pb::ClientMessage::move_(1, 0.1, -0.2)),
            [Command::Actuator {
                mode: ActuatorMode::Move,
                velocity: [0.1, -0.2, 0.0]
            }]
        );
        assert!(matches!(
            operation(&pb::ClientMessage::advance(1), &scene),
            Ok(Op::Advance)
        ));
        assert!(matches!(
            operation(&pb::ClientMessage::latency_seed(1, 9), &scene),
            Ok(Op::LatencySeed(9))
        ));
    }

    #[test]
    fn hello_gives_every_body_its_size() {
        let scene = Scene::builtin("two_blocks").expect("embedded scene");
        let hello = hello(&scene, 100, TimingMode::Realtime, None, Engine::Ode);
        let shapes: Vec<_> = hello
            .shapes
            .iter()
            .map(|s| (s.name.as_str(), s.geometry))
            .collect();
        let size = |x, y, z| Some(pb::shape::Geometry::BoxSize(pb::Vector3d { x, y, z }));
        // docs/spec/world.md's body table.
        assert_eq!(
            shapes,
            [
                ("actuator", Some(pb::shape::Geometry::SphereRadius(0.025))),
                ("blockA", size(0.5, 0.1, 0.1)),
                ("blockB", size(0.3, 0.3, 0.1)),
            ]
        );
    }

    #[test]
    fn only_moves_are_moves() {
        let scene = scene();
        let is_move = |message| operation(&message, &scene).is_ok_and(|op| op.is_move());
        assert!(is_move(pb::ClientMessage::move_(1, 0.0, 0.5)));
        assert!(!is_move(pb::ClientMessage::reset(1)));
        assert!(!is_move(pb::ClientMessage::set_pose(
            1, "actuator", [0.0; 3], 0.0
        )));
        let mut nothing = pb::ClientMessage::move_(1, 0.0, 0.0);
        if let Some(Payload::Actuator(a)) = &mut nothing.payload {
            a.set_cmd(Actuator::Nothing);
        }
        assert!(!is_move(nothing));
    }

    #[test]
    fn unknown_bodies_are_named_with_the_scene_s_bodies() {
        assert_eq!(
            refusal(&pb::ClientMessage::set_pose(1, "blockB", [0.0; 3], 0.0)),
            "set_pose: unknown body 'blockB' (this world has: actuator, blockA)"
        );
        let ghost = operation(
            &pb::ClientMessage::set_pose(1, "blockAShadowTarget", [0.0; 3], 0.0),
            &scene(),
        );
        assert!(ghost.is_ok(), "{ghost:?}");
    }

    #[test]
    fn ghosts_of_absent_bodies_are_refused_naming_the_body() {
        assert_eq!(
            refusal(&pb::ClientMessage::set_pose(
                1,
                "blockBShadow",
                [0.0; 3],
                0.0
            )),
            "set_pose: ghost 'blockBShadow' is of body 'blockB', which this world lacks \
             (this world has: actuator, blockA)"
        );
        assert_eq!(
            refusal(&pb::ClientMessage::set_pose(1, "Shadow", [0.0; 3], 0.0)),
            "set_pose: ghost 'Shadow' is of body '', which this world lacks \
             (this world has: actuator, blockA)"
        );
    }

    #[test]
    fn far_positions_are_refused_by_the_world_s_check() {
        assert_eq!(
            refusal(&pb::ClientMessage::set_pose(
                1,
                "blockA",
                [0.0, 2e3, 0.05],
                0.0
            )),
            "set_pose: body 'blockA': position component 2000 is beyond ±1000 m"
        );
    }

    #[test]
    fn states_list_bodies_then_ghosts_with_unit_quaternions() {
        let body = BodyState {
            name: "blockA".into(),
            id: 15,
            is_static: false,
            position: [0.0, 0.25, 0.05],
            orientation: [0.0, 0.0, 0.0, 1.0],
            lin_vel: [0.1, 0.0, 0.0],
            ang_vel: [0.0, 0.0, 0.2],
        };
        let ghost = BodyState {
            name: "blockAShadow".into(),
            is_static: true,
            ..body.clone()
        };
        let snapshot = Snapshot {
            step: 20,
            sim_time: 0.02,
            bodies: vec![body],
            ghosts: vec![ghost],
        };
        let state = world_state(&snapshot, 7, 3);
        assert_eq!(
            (state.step, state.publish_seq, state.applied_seq),
            (20, 7, 3)
        );
        let names: Vec<_> = state.models().iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["blockA", "blockAShadow"]);
        let a = &state.models()[0];
        assert_eq!(a.id, 15);
        assert_eq!(a.lin_vel, Some(pb::Vector3d::new(0.1, 0.0, 0.0)));
        assert_eq!(a.ang_vel, Some(pb::Vector3d::new(0.0, 0.0, 0.2)));
        assert!(state.models()[1].is_static);
    }
}
