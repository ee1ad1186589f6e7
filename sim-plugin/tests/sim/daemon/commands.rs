//! Every command's effect, seen by a client over the socket.

use pushlearn::client::{ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb::{self, client_message::Payload};
use pushlearn::wire::TimingMode;
use sim_plugin::server::Config;
use sim_plugin::{ActuatorMode, Command, World};

use super::support::*;

#[tokio::test]
async fn hello_describes_scene_rate_mode_and_bodies() {
    let server = start(Config {
        publish_rate_hz: Some(10),
        ..Config {
            scene: scene("two_blocks"),
            ..lockstep()
        }
    })
    .await;
    let client = connect(&server).await;
    let hello = client.hello();
    assert_eq!(hello.scene, "two_blocks");
    assert_eq!(hello.step_size, 0.001);
    assert_eq!(hello.publish_rate, 10);
    assert_eq!(hello.timing(), Ok(TimingMode::Lockstep));
    let bodies: Vec<(&str, u32, [f64; 3])> = hello
        .bodies
        .iter()
        .map(|b| {
            let p = b.pose.and_then(|p| p.position).unwrap_or_default();
            (b.name.as_str(), b.id, [p.x, p.y, p.z])
        })
        .collect();
    assert_eq!(
        bodies,
        [
            ("actuator", 8, [0.0, 0.0, 0.03]),
            ("blockA", 15, [0.0, 0.25, 0.05]),
            ("blockB", 27, [-0.6, 0.35, 0.05]),
        ]
    );
}

#[tokio::test]
async fn move_and_set_pose_act_exactly_as_in_process() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    let mut world = World::new(&scene("one_block")).expect("world");

    // A push that reaches the block (first contact after about 35 messages).
    let x0 = 0.105;
    client
        .command(Payload::set_pose("actuator", [x0, 0.0, 0.03], 0.0))
        .await
        .expect("set_pose");
    client
        .command(Payload::move_(0.0, 0.5))
        .await
        .expect("move");
    world
        .apply(Command::SetPose {
            name: "actuator".into(),
            position: [x0, 0.0, 0.03],
            orientation: [0.0, 0.0, 0.0, 1.0],
        })
        .expect("in-process set_pose");
    world
        .apply(Command::Actuator {
            mode: ActuatorMode::Move,
            velocity: [0.0, 0.5, 0.0],
        })
        .expect("in-process move");
    for message in 1..=60u64 {
        let state = client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
        assert_same(&state, &next_publish(&mut world));
        assert_eq!(state.step, 10 * message);
        assert_eq!(state.publish_seq, message);
        assert_eq!(state.applied_seq, client.last_seq().expect("sent"));
    }
    let block = world.snapshot();
    assert!(
        block.body("blockA").expect("blockA").yaw().abs() > 0.1,
        "the push turned the block"
    );
}

#[tokio::test]
async fn reset_restores_the_start_and_restarts_the_step_count_not_publish_seq() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    let state = pushed_stopped_and_reset(&mut client).await;
    assert_eq!((state.step, state.publish_seq), (10, 4));
    assert_eq!(state.sim_time, 0.01);
    assert_eq!(position(&state, "actuator"), [0.0, 0.0, 0.03]);
    assert_near(position(&state, "blockA"), [0.0, 0.25, 0.05]);
}

#[tokio::test]
async fn publish_rate_changes_the_interval_and_later_hellos() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    client
        .command(Payload::publish_rate(10))
        .await
        .expect("rate");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    assert_eq!(state.step, 100);
    client
        .command(Payload::publish_rate(1000))
        .await
        .expect("rate");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    assert_eq!(state.step, 101);
    assert_eq!(connect(&server).await.hello().publish_rate, 1000);
}

#[tokio::test]
async fn lockstep_pause_refuses_advance_until_unpause() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    client.command(Payload::pause()).await.expect("pause");
    let err = client
        .command(Payload::advance())
        .await
        .expect_err("advance while paused");
    assert!(
        err.to_string()
            .contains("advance: the world is paused; unpause it first"),
        "{err}"
    );
    client.command(Payload::unpause()).await.expect("unpause");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance after unpause");
    assert_eq!(state.step, 10);
}

#[tokio::test]
async fn realtime_pause_stops_publishing_until_unpause() {
    let server = start(realtime(FAST)).await;
    let mut client = connect(&server).await;
    let running = client.next_state().await.expect("states flow");
    // `send`, not `command`: waiting for the acknowledgement would skip
    // states, and every state matters here.
    let pause = client.send(Payload::pause()).await.expect("pause");
    // Long enough for hundreds of publishes had the pause not worked.
    tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    let unpause = client.send(Payload::unpause()).await.expect("unpause");
    let mut last_before = running.step;
    loop {
        let state = client.next_state().await.expect("states after unpause");
        assert!(
            state.applied_seq < pause || state.applied_seq >= unpause,
            "published while paused: {state:?}"
        );
        if state.applied_seq >= unpause {
            // The world went on where it stopped: one interval later.
            assert_eq!(state.step, last_before + 10);
            break;
        }
        last_before = state.step;
    }
}

#[tokio::test]
async fn realtime_states_flow_and_commands_take_effect() {
    let server = start(realtime(FAST)).await;
    let mut client = connect(&server).await;
    let first = client.next_state().await.expect("a state");
    let second = client.next_state().await.expect("another state");
    assert_eq!(second.publish_seq, first.publish_seq + 1);
    assert_eq!(second.step, first.step + 10);
    let moving = client
        .command_and_wait_applied(Payload::move_(0.5, 0.0))
        .await
        .expect("move applied");
    let later = client.next_state().await.expect("a later state");
    assert!(
        position(&later, "actuator")[0] > position(&moving, "actuator")[0],
        "the actuator moves along +x"
    );
}

#[tokio::test]
async fn ghost_poses_are_published_static_and_cleared_by_reset() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    client
        .command(Payload::set_pose("blockAShadow", [0.1, 0.3, 0.05], 0.5))
        .await
        .expect("ghost");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    let ghost = state.model("blockAShadow").expect("the ghost is published");
    assert!(ghost.is_static);
    assert_eq!(ghost.id, 15, "a ghost carries its body's id");
    assert_eq!(position(&state, "blockAShadow"), [0.1, 0.3, 0.05]);
    // Never physical: the block only settles by a few nanometres.
    assert_near(position(&state, "blockA"), [0.0, 0.25, 0.05]);
    client.command(Payload::reset()).await.expect("reset");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    assert!(state.model("blockAShadow").is_none());
}

#[tokio::test]
async fn advance_and_latency_seed_are_refused_where_they_mean_nothing() {
    let realtime = start(realtime(FAST)).await;
    let mut client = connect(&realtime).await;
    let err = client
        .command(Payload::advance())
        .await
        .expect_err("advance in realtime");
    assert!(
        err.to_string()
            .contains("advance: only valid in lockstep mode"),
        "{err}"
    );
    let lockstep = start(lockstep()).await;
    let mut client = connect(&lockstep).await;
    let err = client
        .command(Payload::latency_seed(3))
        .await
        .expect_err("latency_seed without latency emulation");
    assert!(
        err.to_string()
            .contains("latency_seed: this world does not emulate latency"),
        "{err}"
    );
    let latency = start(with_latency(5, 0)).await;
    connect(&latency)
        .await
        .command(Payload::latency_seed(3))
        .await
        .expect("latency_seed with latency emulation");
}

#[tokio::test]
async fn a_refusal_answers_its_own_command_only() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    let err = client
        .command(Payload::set_pose("blockC", [0.0, 0.3, 0.05], 0.0))
        .await
        .expect_err("unknown body");
    let refused = err
        .refused_seq()
        .unwrap_or_else(|| panic!("not a refusal: {err:?}"));
    assert_eq!(Some(refused + 1), client.last_seq(), "then its barrier");
    assert!(
        err.to_string()
            .contains("set_pose: unknown body 'blockC' (this world has: actuator, blockA)"),
        "{err}"
    );
    // The refused command's barrier answer is still on its way; it must not
    // be taken for a refusal of the next command.
    client
        .command(Payload::reset())
        .await
        .expect("accepted after a refusal");
    let seq = client
        .send(Payload::set_pose("nobody", [0.0; 3], 0.0))
        .await
        .expect("sent");
    match client.next_state().await {
        Err(ClientError::Refused {
            seq: refused,
            kind,
            message,
        }) => {
            assert_eq!(refused, seq);
            assert_eq!(kind, pb::error::Kind::InvalidCommand, "{message}");
            assert!(message.contains("unknown body 'nobody'"), "{message}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[tokio::test]
async fn invalid_commands_are_refused_by_the_client_and_never_sent() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    let err = client
        .send(Payload::move_(f64::NAN, 0.0))
        .await
        .expect_err("NaN must be refused locally");
    assert!(matches!(err, ClientError::Invalid(_)), "{err:?}");
    assert!(
        err.to_string().contains("actuator: direction.x is NaN"),
        "{err}"
    );
    client.sync().await.expect("barrier");
    assert_eq!(
        server.stats().refused_commands,
        1,
        "only the barrier reached the daemon"
    );
}

#[tokio::test]
async fn waiting_for_a_state_from_a_paused_world_times_out() {
    let server = start(realtime(FAST)).await;
    let options = ClientOptions {
        timeout: Some(std::time::Duration::from_millis(300)),
        first_seq: 1,
    };
    let mut client = SimClient::connect_with(server.local_addr(), options)
        .await
        .expect("connect");
    client.command(Payload::pause()).await.expect("pause");
    // Drain what was published before the pause took effect.
    while client.next_state().await.is_ok() {}
    let err = client
        .next_state()
        .await
        .expect_err("a paused world publishes nothing");
    assert!(matches!(err, ClientError::Timeout { .. }), "{err:?}");
}
