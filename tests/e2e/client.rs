//! `SimClient` against the fake world, and the world-side wire API against
//! raw sockets.

use std::time::Duration;

use pushlearn::client::{ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb::{self, client_message::Payload, server_message};
use pushlearn::wire::{encode_frame, FrameReader, TimingMode, WireError, MAX_FRAME_SIZE};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream};

use crate::fake_world::FakeWorld;

async fn connect(world: &FakeWorld) -> SimClient {
    SimClient::connect(world.addr)
        .await
        .expect("connect to the fake world")
}

fn error_of(message: Option<pb::ServerMessage>) -> pb::Error {
    match message.and_then(|m| m.payload) {
        Some(server_message::Payload::Error(error)) => error,
        other => panic!("expected an Error, got {other:?}"),
    }
}

#[tokio::test]
async fn connect_exposes_the_hello() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let client = connect(&world).await;
    let hello = client.hello();
    assert_eq!(hello.scene, "one_block");
    assert_eq!(hello.timing(), Ok(TimingMode::Lockstep));
    assert_eq!(hello.publish_rate, 100);
    let names: Vec<&str> = hello.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["actuator", "blockA"]);
}

#[tokio::test]
async fn commands_arrive_in_order_with_strictly_increasing_seqs() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let mut client = connect(&world).await;
    let mut seqs = Vec::new();
    for payload in [
        Payload::move_(0.0, 0.0),
        Payload::reset(),
        Payload::set_pose("actuator", [0.0, 0.0, 0.03], 0.0),
        Payload::publish_rate(10),
        Payload::move_(0.0, 0.5),
    ] {
        seqs.push(client.command(payload).await.expect("accepted"));
    }
    assert_eq!(
        world.applied_kinds(),
        ["move", "reset", "set_pose", "publish_rate", "move"]
    );
    let applied: Vec<u64> = world.applied().iter().map(|m| m.seq).collect();
    assert_eq!(applied, seqs);
    let on_the_wire: Vec<u64> = world.frames().iter().map(|m| m.seq).collect();
    assert!(
        on_the_wire.windows(2).all(|w| w[0] < w[1]),
        "{on_the_wire:?}"
    );
    assert_eq!(client.last_seq(), on_the_wire.last().copied());
}

#[tokio::test]
async fn lockstep_advance_returns_the_state_with_the_command_applied() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let mut client = connect(&world).await;
    client
        .command(Payload::move_(0.0, 0.5))
        .await
        .expect("move accepted");
    let first = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    let advance_seq = client.last_seq().expect("a seq was used");
    assert!(first.applied_seq >= advance_seq);
    assert_eq!(first.step, 10);
    let second = client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance");
    assert_eq!(second.step, 20);
    let y = second
        .model("actuator")
        .and_then(|m| m.pose)
        .and_then(|p| p.position)
        .map(|p| p.y);
    assert!(
        y.is_some_and(|y| (y - 0.01).abs() < 1e-12),
        "actuator y {y:?}"
    );
}

#[tokio::test]
async fn realtime_states_flow_and_show_applied_commands() {
    let world = FakeWorld::start(TimingMode::Realtime).await;
    let mut client = connect(&world).await;
    let first = client.next_state().await.expect("a state");
    let second = client.next_state().await.expect("another state");
    assert!(second.publish_seq > first.publish_seq);
    let state = client
        .command_and_wait_applied(Payload::reset())
        .await
        .expect("reset applied");
    assert!(state.applied_seq >= client.last_seq().unwrap_or(u64::MAX));
}

#[tokio::test]
async fn refusal_carries_the_seq_and_the_connection_stays_usable() {
    let world = FakeWorld::start(TimingMode::Realtime).await;
    let mut client = connect(&world).await;
    let err = client
        .command(Payload::set_pose("blockC", [0.0, 0.3, 0.05], 0.0))
        .await
        .expect_err("unknown body must be refused");
    let refused = err
        .refused_seq()
        .unwrap_or_else(|| panic!("not a refusal: {err:?}"));
    assert_eq!(world.frames().first().map(|m| m.seq), Some(refused));
    assert!(
        err.to_string().contains("set_pose: unknown body 'blockC'"),
        "{err}"
    );

    // The refused command's barrier answer is still on its way; it must not
    // be mistaken for a refusal of the next command.
    client
        .command(Payload::reset())
        .await
        .expect("reset accepted after a refusal");
    let advance = client
        .command(Payload::advance())
        .await
        .expect_err("advance in realtime");
    assert!(advance.to_string().contains("realtime"), "{advance}");
    assert_eq!(world.applied_kinds(), ["reset"]);
}

#[tokio::test]
async fn next_state_reports_errors_as_typed_refusals() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let mut client = connect(&world).await;
    let seq = client
        .send(Payload::set_pose("nobody", [0.0; 3], 0.0))
        .await
        .expect("sent");
    match client.next_state().await {
        Err(ClientError::Refused {
            seq: refused,
            message,
        }) => {
            assert_eq!(refused, seq);
            assert!(message.contains("unknown body 'nobody'"), "{message}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[tokio::test]
async fn invalid_commands_are_not_sent() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let mut client = connect(&world).await;
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
        world.frames().len(),
        1,
        "only the barrier reached the world"
    );
}

#[tokio::test]
async fn waiting_on_a_paused_world_times_out() {
    let world = FakeWorld::start(TimingMode::Realtime).await;
    let options = ClientOptions {
        timeout: Some(Duration::from_millis(300)),
        first_seq: 1,
    };
    let mut client = SimClient::connect_with(world.addr, options)
        .await
        .expect("connect");
    client
        .command(Payload::pause())
        .await
        .expect("pause accepted");
    // Drain what was published before the pause took effect.
    while client.next_state().await.is_ok() {}
    let err = client
        .next_state()
        .await
        .expect_err("a paused world publishes nothing");
    assert!(matches!(err, ClientError::Timeout { .. }), "{err:?}");
}

/// A raw connection to `world`: the Hello is read, then bytes go out as given.
async fn raw_connection(
    world: &FakeWorld,
) -> (
    FrameReader<pb::ServerMessage, OwnedReadHalf>,
    OwnedWriteHalf,
) {
    let stream = TcpStream::connect(world.addr).await.expect("connect");
    let (read_half, write_half) = stream.into_split();
    let mut reader = FrameReader::<pb::ServerMessage, _>::new(read_half);
    let hello = reader
        .read()
        .await
        .expect("readable")
        .and_then(|m| m.payload);
    assert!(
        matches!(hello, Some(server_message::Payload::Hello(_))),
        "Hello first, got {hello:?}"
    );
    (reader, write_half)
}

async fn refused_and_closed(world: &FakeWorld, bytes: &[u8]) -> pb::Error {
    let (mut reader, mut writer) = raw_connection(world).await;
    writer.write_all(bytes).await.expect("write");
    let error = error_of(reader.read().await.expect("an answer"));
    assert_eq!(
        reader.read().await.expect("clean close"),
        None,
        "the world closes the connection"
    );
    error
}

#[tokio::test]
async fn undecodable_frame_gets_an_error_and_only_that_connection_closes() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let mut bystander = connect(&world).await;
    // A frame announcing a 200-byte field inside 3 bytes.
    let error = refused_and_closed(&world, &[0, 0, 0, 3, 0x0a, 0xc8, 0x01]).await;
    assert_eq!(error.seq, 0);
    assert!(
        error.message.starts_with("undecodable frame"),
        "{}",
        error.message
    );
    bystander
        .command(Payload::reset())
        .await
        .expect("the other client is still served");
}

#[tokio::test]
async fn oversized_prefix_gets_an_error_and_the_connection_closes() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let announced = MAX_FRAME_SIZE as u32 + 1;
    let error = refused_and_closed(&world, &announced.to_be_bytes()).await;
    assert!(
        error
            .message
            .contains(&format!("frame of {announced} bytes exceeds")),
        "{}",
        error.message
    );
    connect(&world)
        .await
        .command(Payload::reset())
        .await
        .expect("new clients are served");
}

#[tokio::test]
async fn invalid_command_from_a_raw_client_is_answered_with_its_seq() {
    let world = FakeWorld::start(TimingMode::Lockstep).await;
    let (mut reader, mut writer) = raw_connection(&world).await;
    let frame = encode_frame(&pb::ClientMessage::set_pose(
        77,
        "blockA",
        [f64::NAN, 0.25, 0.05],
        0.0,
    ))
    .expect("encode");
    writer.write_all(&frame).await.expect("write");
    let error = error_of(reader.read().await.expect("an answer"));
    assert_eq!(error.seq, 77);
    assert_eq!(error.message, "set_pose: body 'blockA' position.x is NaN");
    assert!(world.applied().is_empty(), "the world is unchanged");
}

/// A listener that plays `script` to the first client instead of a world.
async fn scripted_world(script: Vec<u8>) -> std::net::SocketAddr {
    let listener = TcpListener::bind("127.0.0.1:0").await.expect("bind");
    let addr = listener.local_addr().expect("address");
    tokio::spawn(async move {
        if let Ok((mut stream, _)) = listener.accept().await {
            let _ = stream.write_all(&script).await;
            // Hold the connection open until the client gives up.
            let mut sink = Vec::new();
            let _ = stream.read_to_end(&mut sink).await;
        }
    });
    addr
}

#[tokio::test]
async fn a_world_that_never_says_hello_times_out() {
    let addr = scripted_world(Vec::new()).await;
    let options = ClientOptions {
        timeout: Some(Duration::from_millis(300)),
        first_seq: 1,
    };
    let err = SimClient::connect_with(addr, options)
        .await
        .expect_err("no Hello");
    assert!(
        matches!(
            err,
            ClientError::Timeout {
                waiting_for: "the Hello message",
                ..
            }
        ),
        "{err:?}"
    );
}

#[tokio::test]
async fn a_state_before_hello_is_a_protocol_violation() {
    let state: pb::ServerMessage = pb::WorldState::default().into();
    let addr = scripted_world(encode_frame(&state).expect("encode").to_vec()).await;
    let err = SimClient::connect(addr).await.expect_err("no Hello");
    assert!(matches!(err, ClientError::Protocol(_)), "{err:?}");
}

#[tokio::test]
async fn garbage_from_the_world_is_a_decode_error() {
    let hello: pb::ServerMessage = pb::Hello {
        scene: "one_block".into(),
        ..Default::default()
    }
    .into();
    let mut script = encode_frame(&hello).expect("encode").to_vec();
    script.extend_from_slice(&[0, 0, 0, 2, 0xff, 0xff]);
    let addr = scripted_world(script).await;
    let mut client = SimClient::connect(addr).await.expect("Hello is fine");
    let err = client.next_message().await.expect_err("garbage");
    assert!(
        matches!(err, ClientError::Wire(WireError::Decode(_))),
        "{err:?}"
    );
}

#[tokio::test]
async fn unknown_server_payloads_are_skipped() {
    let hello: pb::ServerMessage = pb::Hello {
        scene: "one_block".into(),
        ..Default::default()
    }
    .into();
    let state: pb::ServerMessage = pb::WorldState {
        step: 10,
        ..Default::default()
    }
    .into();
    let mut script = encode_frame(&hello).expect("encode").to_vec();
    // What a newer world's new payload looks like to this client: no payload.
    script.extend_from_slice(&encode_frame(&pb::ServerMessage::default()).expect("encode"));
    script.extend_from_slice(&encode_frame(&state).expect("encode"));
    let addr = scripted_world(script).await;
    let mut client = SimClient::connect(addr).await.expect("connect");
    assert_eq!(
        client
            .next_state()
            .await
            .expect("the state after the unknown message")
            .step,
        10
    );
}
