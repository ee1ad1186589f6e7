//! Bad input: each is answered with an `Error` naming the problem, the world
//! is left as it was, and every other client keeps being served.

use pushlearn::client::SimClient;
use pushlearn::wire::pb::{self, client_message::Payload, sim_control::Action};
use pushlearn::wire::MAX_FRAME_SIZE;
use rand::rngs::ChaCha8Rng;
use rand::{RngExt, SeedableRng};
use sim_plugin::World;

use super::support::*;

/// A realtime bystander still gets states and has its commands accepted.
async fn still_served(bystander: &mut SimClient) {
    // Random frames may decode into any valid command, a pause included.
    bystander
        .command(Payload::unpause())
        .await
        .expect("a command");
    let first = bystander.next_state().await.expect("a state");
    let next = bystander.next_state().await.expect("another state");
    assert!(next.publish_seq > first.publish_seq);
    bystander
        .command(Payload::move_(0.0, 0.0))
        .await
        .expect("a command");
}

#[tokio::test]
async fn an_oversized_length_prefix_closes_only_that_connection() {
    let server = start(realtime(FAST)).await;
    let mut bystander = connect(&server).await;
    let mut raw = Raw::connect(&server).await;
    // Announces 4 GiB - 1: refused from the prefix alone, nothing allocated.
    raw.send_bytes(&u32::MAX.to_be_bytes()).await;
    let error = raw.next_error().await;
    assert_eq!(error.seq, 0);
    assert!(
        error.message.contains(&format!(
            "frame of {} bytes exceeds the maximum frame size of {MAX_FRAME_SIZE} bytes",
            u32::MAX
        )),
        "{}",
        error.message
    );
    raw.expect_closed().await;
    still_served(&mut bystander).await;
}

#[tokio::test]
async fn an_undecodable_frame_closes_only_that_connection() {
    let server = start(realtime(FAST)).await;
    let mut bystander = connect(&server).await;
    let mut raw = Raw::connect(&server).await;
    // A frame announcing a 200-byte field inside 3 bytes.
    raw.send_bytes(&[0, 0, 0, 3, 0x0a, 0xc8, 0x01]).await;
    let error = raw.next_error().await;
    assert_eq!(error.seq, 0);
    assert!(
        error.message.starts_with("undecodable frame"),
        "{}",
        error.message
    );
    raw.expect_closed().await;
    still_served(&mut bystander).await;
}

#[tokio::test]
async fn a_frame_cut_off_by_a_close_is_harmless() {
    let server = start(realtime(FAST)).await;
    let mut bystander = connect(&server).await;
    let mut raw = Raw::connect(&server).await;
    raw.send_bytes(&[0, 0, 0, 50, 8, 1]).await;
    drop(raw);
    still_served(&mut bystander).await;
}

fn with_action(seq: u64, action: Action) -> pb::ClientMessage {
    pb::ClientMessage::new(
        seq,
        Payload::Control(pb::SimControl {
            action: Some(action),
        }),
    )
}

#[tokio::test]
async fn invalid_commands_are_answered_with_their_seq_and_change_nothing() {
    let server = start(lockstep()).await;
    let mut raw = Raw::connect(&server).await;
    let mut watcher = connect(&server).await;
    let mut unknown_cmd = pb::ClientMessage::move_(9, 0.0, 0.5);
    if let Some(Payload::Actuator(a)) = &mut unknown_cmd.payload {
        a.cmd = 9;
    }
    let mut zero_quaternion = pb::ClientMessage::set_pose(7, "blockA", [0.0, 0.3, 0.05], 0.0);
    if let Some(Payload::SetPose(v)) = &mut zero_quaternion.payload {
        v.models[0]
            .pose
            .get_or_insert_default()
            .orientation
            .replace(pb::Quaternion::default());
    }
    let cases = [
        (
            pb::ClientMessage::move_(1, f64::NAN, 0.5),
            "actuator: direction.x is NaN",
        ),
        (
            pb::ClientMessage::set_pose(2, "blockA", [0.0, f64::INFINITY, 0.05], 0.0),
            "set_pose: body 'blockA' position.y is infinite (+inf)",
        ),
        (
            pb::ClientMessage::set_pose(3, "blockC", [0.0, 0.3, 0.05], 0.0),
            "set_pose: unknown body 'blockC' (this world has: actuator, blockA)",
        ),
        (
            pb::ClientMessage::publish_rate(4, 30),
            "publish_rate_hz: 30 Hz does not divide 1000",
        ),
        (
            pb::ClientMessage::set_pose(5, "blockA", [1e6, 0.25, 0.05], 0.0),
            "set_pose: body 'blockA': position component 1000000 is beyond ±1000 m",
        ),
        (with_action(6, Action::Reset(false)), "reset: must be true"),
        (
            zero_quaternion,
            "set_pose: body 'blockA' orientation has zero length",
        ),
        (
            pb::ClientMessage::latency_seed(8, 1),
            "latency_seed: this world does not emulate latency",
        ),
        (unknown_cmd, "actuator: cmd 9 is not a command"),
        (pb::ClientMessage::barrier(10), "missing payload"),
    ];
    for (message, problem) in cases {
        let seq = message.seq;
        raw.send(&message).await;
        let error = raw.next_error().await;
        assert_eq!(error.seq, seq, "{problem}");
        assert!(
            error.message.starts_with(problem),
            "expected `{problem}`, got `{}`",
            error.message
        );
    }
    // The world is exactly a fresh one: nothing was applied.
    let state = watcher
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    let mut fresh = World::new(&scene("one_block")).expect("world");
    assert_same(&state, &next_publish(&mut fresh));
    assert_eq!(server.stats().refused_commands, 10);
}

#[tokio::test]
async fn more_than_64_ghosts_are_refused_until_a_reset() {
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    for i in 0..64 {
        client
            .command(Payload::set_pose(format!("blockAShadow{i}"), [0.0; 3], 0.0))
            .await
            .expect("a ghost within the limit");
    }
    let err = client
        .command(Payload::set_pose("blockAShadowLast", [0.0; 3], 0.0))
        .await
        .expect_err("one ghost too many");
    assert!(err.to_string().contains("too many ghost poses"), "{err}");
    client
        .command(Payload::set_pose("blockAShadow0", [1.0, 0.0, 0.0], 0.0))
        .await
        .expect("moving a known ghost is fine");
    client.command(Payload::reset()).await.expect("reset");
    client
        .command(Payload::set_pose("blockAShadowLast", [0.0; 3], 0.0))
        .await
        .expect("room again after the reset");
    let state = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    assert_eq!(state.models().len(), 3, "two bodies and one ghost");
}

#[tokio::test]
async fn random_frames_never_take_the_daemon_down() {
    let server = start(realtime(FAST)).await;
    let mut bystander = connect(&server).await;
    let mut rng = ChaCha8Rng::seed_from_u64(2015);
    for _ in 0..20 {
        let mut raw = Raw::connect(&server).await;
        for _ in 0..20 {
            let len = rng.random_range(0..64usize);
            let mut frame = u32::try_from(len).expect("small").to_be_bytes().to_vec();
            frame.extend((0..len).map(|_| rng.random::<u8>()));
            raw.send_bytes(&frame).await;
        }
        // Whatever the bytes meant, a barrier is answered, or the
        // connection was closed after an Error.
        raw.send(&pb::ClientMessage::barrier(u64::MAX)).await;
        loop {
            match raw.next().await {
                Some(pb::server_message::Payload::Error(e)) if e.seq == u64::MAX => break,
                Some(_) => {}
                None => break,
            }
        }
    }
    still_served(&mut bystander).await;
}

#[tokio::test]
async fn a_physics_blow_up_resets_the_world_and_every_client_is_told() {
    let server = start(realtime(FAST)).await;
    let mut a = connect(&server).await;
    let mut b = connect(&server).await;
    a.command(Payload::move_(0.0, 0.5)).await.expect("move");
    // Some way into the push, so that the reset is visible.
    let mut before = a.next_state().await.expect("a state");
    while before.step < 200 {
        before = a.next_state().await.expect("a state");
    }
    server.provoke_blow_up("blockA");
    for client in [&mut a, &mut b] {
        let error = within("the blow-up's Error", async {
            loop {
                match client.next_state().await {
                    Ok(_) => continue,
                    Err(err) => break err,
                }
            }
        })
        .await;
        assert!(
            matches!(&error, pushlearn::client::ClientError::World { kind, message }
                if *kind == pushlearn::wire::pb::error::Kind::PhysicsBlewUp
                    && message.starts_with("physics blew up at step") && message.contains("blockA")),
            "{error}"
        );
        // The world went on from its start, every value finite.
        let after = client.next_state().await.expect("states go on");
        assert!(
            after.step < before.step,
            "{} then {}",
            before.step,
            after.step
        );
        assert!(after.publish_seq > before.publish_seq);
        for model in after.models() {
            let pose = model.pose.expect("a pose");
            let p = pose.position.expect("a position");
            assert!([p.x, p.y, p.z].iter().all(|v| v.is_finite()), "{model:?}");
        }
    }
    still_served(&mut a).await;
    assert!(server.shutdown().await.is_ok());
}
