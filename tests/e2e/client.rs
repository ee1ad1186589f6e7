//! `SimClient` against worlds that misbehave: a scripted listener plays
//! bytes no real daemon sends. Its behaviour against the real daemon is
//! tested with the daemon (`sim-plugin/tests/sim/daemon`).

use std::time::Duration;

use pushlearn::client::{ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb;
use pushlearn::wire::{encode_frame, WireError};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpListener;

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
        matches!(&err, ClientError::NotAWorld { why, .. }
            if why.starts_with("it accepted the connection but sent no Hello within 0.3 s")),
        "{err:?}"
    );
}

#[tokio::test]
async fn a_state_before_hello_is_a_protocol_violation() {
    let state: pb::ServerMessage = pb::WorldState::default().into();
    let addr = scripted_world(encode_frame(&state).expect("encode").to_vec()).await;
    let err = SimClient::connect(addr).await.expect_err("no Hello");
    assert_eq!(
        err.to_string(),
        format!("{addr} is not a pushlearn-sim: its first message was not a Hello")
    );
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

/// `send_all` writes its payloads in order with consecutive seqs, and a
/// batch with one invalid payload sends none of it.
#[tokio::test]
async fn a_batch_goes_out_in_order_and_an_invalid_one_not_at_all() {
    let listener = TcpListener::bind("127.0.0.1:0").await.expect("bind");
    let addr = listener.local_addr().expect("address");
    let received = tokio::spawn(async move {
        let (mut stream, _) = listener.accept().await.expect("accept");
        let hello: pb::ServerMessage = pb::Hello::default().into();
        stream
            .write_all(&encode_frame(&hello).expect("encode"))
            .await
            .expect("hello");
        let mut bytes = Vec::new();
        let _ = stream.read_to_end(&mut bytes).await;
        bytes
    });
    let options = ClientOptions {
        timeout: Some(Duration::from_secs(5)),
        first_seq: 1,
    };
    let mut client = SimClient::connect_with(addr, options)
        .await
        .expect("connect");
    let last = client
        .send_all(vec![
            pb::client_message::Payload::move_(0.0, 0.5),
            pb::client_message::Payload::advance(),
        ])
        .await
        .expect("a valid batch");
    assert_eq!(last, Some(2));
    let refused = client
        .send_all(vec![
            pb::client_message::Payload::advance(),
            pb::client_message::Payload::move_(f64::NAN, 0.0),
        ])
        .await;
    assert!(
        matches!(refused, Err(ClientError::Invalid(_))),
        "{refused:?}"
    );
    assert_eq!(client.send_all(Vec::new()).await.expect("nothing"), None);
    client.close().await.expect("close");
    let bytes = received.await.expect("the listener");
    let (messages, error) = pushlearn::wire::decode_stream::<pb::ClientMessage>(&bytes);
    assert!(error.is_none(), "{error:?}");
    assert_eq!(
        messages,
        [
            pb::ClientMessage::move_(1, 0.0, 0.5),
            pb::ClientMessage::advance(2)
        ]
    );
}
