//! The daemon on MuJoCo over a real socket: the Hello names the engine,
//! a run repeats bit for bit (on a second daemon and after a Reset, with
//! latency emulation on), and Reset and SetPose act as on ODE.

use pushlearn::client::SimClient;
use pushlearn::wire::pb::{self, client_message::Payload};
use sim_plugin::server::Config;
use sim_plugin::{ActuatorMode, Command, Engine, World};

use super::support::*;

fn on_mujoco(config: Config) -> Config {
    Config {
        engine: Engine::Mujoco,
        ..config
    }
}

/// Every number of every body of a state, for comparing runs bit for bit.
fn frame(state: &pb::WorldState) -> Vec<(String, Vec<u64>)> {
    state
        .models()
        .iter()
        .map(|m| {
            let pose = m.pose.unwrap_or_default();
            let p = pose.position.unwrap_or_default();
            let q = pose.orientation.unwrap_or_default();
            let v = m.lin_vel.unwrap_or_default();
            let w = m.ang_vel.unwrap_or_default();
            let numbers = [
                p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z,
            ];
            (m.name.clone(), numbers.map(f64::to_bits).to_vec())
        })
        .collect()
}

/// A push that reaches the block off-centre, so that it turns: the frames
/// of 60 Advances.
async fn push(client: &mut SimClient) -> Vec<Vec<(String, Vec<u64>)>> {
    client
        .command(Payload::set_pose("actuator", [0.105, 0.0, 0.03], 0.0))
        .await
        .expect("set_pose");
    client
        .command(Payload::move_(0.0, 0.5))
        .await
        .expect("move");
    let mut frames = Vec::new();
    for _ in 0..60 {
        let state = client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
        frames.push(frame(&state));
    }
    frames
}

#[tokio::test]
async fn the_hello_names_the_engine() {
    let mujoco = start(on_mujoco(lockstep())).await;
    assert_eq!(connect(&mujoco).await.hello().engine, "mujoco");
    let ode = start(lockstep()).await;
    assert_eq!(connect(&ode).await.hello().engine, "ode");
}

#[tokio::test]
async fn a_mujoco_run_repeats_bit_for_bit_on_another_daemon_and_after_a_reset() {
    let first = start(on_mujoco(with_latency(2, 7))).await;
    let second = start(on_mujoco(with_latency(2, 7))).await;
    let mut a = connect(&first).await;
    let mut b = connect(&second).await;
    let run = push(&mut a).await;
    assert_eq!(run, push(&mut b).await);
    // The block moved and turned: the runs compared are pushes, not rest.
    let last = run.last().expect("frames");
    let block = &last.iter().find(|(n, _)| n == "blockA").expect("blockA").1;
    assert!(f64::from_bits(block[1]) > 0.3, "the block was pushed");
    assert!(f64::from_bits(block[5]).abs() > 0.05, "the block turned");

    // Reset, with the latency stream reseeded as a new run would.
    a.command(Payload::move_(0.0, 0.0)).await.expect("stop");
    a.command(Payload::reset()).await.expect("reset");
    a.command(Payload::latency_seed(7)).await.expect("reseed");
    assert_eq!(run, push(&mut a).await);
}

#[tokio::test]
async fn reset_and_set_pose_act_as_in_process() {
    let server = start(on_mujoco(lockstep())).await;
    let mut client = connect(&server).await;
    let mut world = World::on(&scene("one_block"), Engine::Mujoco).expect("world");
    let state = pushed_stopped_and_reset(&mut client).await;
    assert_eq!((state.step, state.publish_seq), (10, 4));
    world
        .apply(Command::Actuator {
            mode: ActuatorMode::Move,
            velocity: [0.0; 3],
        })
        .expect("stop in process");
    // After a Reset the daemon's world is a fresh one, bit for bit.
    assert_same(&state, &next_publish(&mut world));
    assert_eq!(position(&state, "actuator"), [0.0, 0.0, 0.03]);

    // SetPose of a block: placed where asked (it settles into MuJoCo's
    // soft ground by micrometres), as the in-process world places it.
    let at = [0.3, 0.4, 0.05];
    client
        .command(Payload::set_pose("blockA", at, 0.5))
        .await
        .expect("set_pose");
    world
        .apply(Command::SetPose {
            name: "blockA".into(),
            position: at,
            orientation: pushlearn_core::orientation::from_yaw(0.5),
        })
        .expect("in-process set_pose");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    assert_same(&state, &next_publish(&mut world));
    let p = position(&state, "blockA");
    assert!(
        p.iter().zip(at).all(|(a, e)| (a - e).abs() < 1e-4),
        "{p:?} is not near {at:?}"
    );
}
