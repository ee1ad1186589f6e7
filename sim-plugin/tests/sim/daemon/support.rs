//! Starting daemons on 127.0.0.1:0 and talking to them.

use std::future::Future;
use std::time::Duration;

use pushlearn::client::SimClient;
use pushlearn::wire::pb::{self, client_message::Payload, server_message};
use pushlearn::wire::{encode_frame, FrameReader};
use sim_plugin::server::{Config, Latency, Server, ServerHandle, Timing};
use sim_plugin::{Scene, Snapshot, World};
use tokio::io::AsyncWriteExt;
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream};

/// Only there to turn a hang into a failure.
pub const LIMIT: Duration = Duration::from_secs(30);

/// Realtime pace for tests: 20 times the thesis's, so states come quickly
/// without one daemon taking a whole core.
pub const FAST: u32 = 20_000;

pub fn scene(name: &str) -> Scene {
    Scene::builtin(name).expect("embedded scene")
}

pub fn lockstep() -> Config {
    Config {
        timing: Timing::Lockstep { latency: None },
        ..Config::new(scene("one_block"))
    }
}

pub fn with_latency(max_steps: u32, seed: u64) -> Config {
    Config {
        timing: Timing::Lockstep {
            latency: Some(Latency { max_steps, seed }),
        },
        ..Config::new(scene("one_block"))
    }
}

pub fn realtime(steps_per_second: u32) -> Config {
    Config {
        timing: Timing::Realtime { steps_per_second },
        ..Config::new(scene("one_block"))
    }
}

pub async fn start(config: Config) -> ServerHandle {
    let listener = TcpListener::bind("127.0.0.1:0").await.expect("bind");
    Server::start(listener, config)
        .await
        .expect("server starts")
}

pub async fn connect(server: &ServerHandle) -> SimClient {
    SimClient::connect(server.local_addr())
        .await
        .expect("connect to the daemon")
}

/// `future`, or a panic naming `what` if it takes longer than [`LIMIT`].
pub async fn within<T>(what: &str, future: impl Future<Output = T>) -> T {
    tokio::time::timeout(LIMIT, future)
        .await
        .unwrap_or_else(|_| panic!("timed out waiting for {what}"))
}

/// A connection that sends raw bytes; its Hello has been read.
pub struct Raw {
    pub reader: FrameReader<pb::ServerMessage, OwnedReadHalf>,
    pub writer: OwnedWriteHalf,
}

impl Raw {
    pub async fn connect(server: &ServerHandle) -> Raw {
        let stream = TcpStream::connect(server.local_addr())
            .await
            .expect("connect");
        let (read_half, writer) = stream.into_split();
        let mut raw = Raw {
            reader: FrameReader::new(read_half),
            writer,
        };
        match raw.next().await {
            Some(server_message::Payload::Hello(_)) => raw,
            other => panic!("expected Hello first, got {other:?}"),
        }
    }

    pub async fn send_bytes(&mut self, bytes: &[u8]) {
        self.writer.write_all(bytes).await.expect("write");
    }

    pub async fn send(&mut self, message: &pb::ClientMessage) {
        let frame = encode_frame(message).expect("encodable");
        self.send_bytes(&frame).await;
    }

    /// The next message's payload; `None` at the end of the stream.
    pub async fn next(&mut self) -> Option<server_message::Payload> {
        within("a message from the daemon", self.reader.read())
            .await
            .expect("a readable frame")
            .map(|m| m.payload.expect("a known payload"))
    }

    /// The next `Error`, skipping states.
    pub async fn next_error(&mut self) -> pb::Error {
        loop {
            match self.next().await {
                Some(server_message::Payload::Error(error)) => return error,
                Some(server_message::Payload::WorldState(_)) => {}
                other => panic!("expected an Error, got {other:?}"),
            }
        }
    }

    /// Reads until the daemon closes the connection, skipping states.
    pub async fn expect_closed(&mut self) {
        while let Some(payload) = self.next().await {
            assert!(
                matches!(payload, server_message::Payload::WorldState(_)),
                "unexpected {payload:?} before the close"
            );
        }
    }
}

/// A body's pose and velocities as `[x, y, z, qx, qy, qz, qw, vx, vy, vz, wx, wy, wz]`.
fn numbers(model: &pb::ModelState) -> Vec<f64> {
    let pose = model.pose.unwrap_or_default();
    let p = pose.position.unwrap_or_default();
    let q = pose.orientation.unwrap_or_default();
    let v = model.lin_vel.unwrap_or_default();
    let w = model.ang_vel.unwrap_or_default();
    vec![
        p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z,
    ]
}

/// Asserts that a published state is exactly (bit for bit) `snapshot`.
pub fn assert_same(state: &pb::WorldState, snapshot: &Snapshot) {
    assert_eq!(state.step, snapshot.step);
    assert_eq!(state.sim_time, snapshot.sim_time);
    let published: Vec<(&str, u32, bool, Vec<f64>)> = state
        .models()
        .iter()
        .map(|m| (m.name.as_str(), m.id, m.is_static, numbers(m)))
        .collect();
    let expected: Vec<(&str, u32, bool, Vec<f64>)> = snapshot
        .bodies
        .iter()
        .chain(&snapshot.ghosts)
        .map(|b| {
            let mut n = b.position.to_vec();
            n.extend(b.orientation);
            n.extend(b.lin_vel);
            n.extend(b.ang_vel);
            (b.name.as_str(), b.id, b.is_static, n)
        })
        .collect();
    assert_eq!(published, expected, "at step {}", state.step);
}

/// Steps an in-process world to its next publish.
pub fn next_publish(world: &mut World) -> Snapshot {
    loop {
        if let Some(snapshot) = world.step().expect("step") {
            return snapshot;
        }
    }
}

/// The position of `name` in `state`.
pub fn position(state: &pb::WorldState, name: &str) -> [f64; 3] {
    let p = state
        .model(name)
        .and_then(|m| m.pose)
        .and_then(|p| p.position)
        .unwrap_or_else(|| panic!("no {name} in the state"));
    [p.x, p.y, p.z]
}

/// Asserts that two positions agree within a micrometre: a resting block
/// still settles into the ground by tiny amounts.
pub fn assert_near(actual: [f64; 3], expected: [f64; 3]) {
    assert!(
        actual
            .iter()
            .zip(&expected)
            .all(|(a, e)| (a - e).abs() < 1e-6),
        "{actual:?} is not {expected:?}"
    );
}

/// Pushes the actuator along x for three messages, stops it and resets the
/// world, as a run boundary does: the first state after the Reset.
pub async fn pushed_stopped_and_reset(client: &mut SimClient) -> pb::WorldState {
    client
        .command(Payload::move_(0.5, 0.0))
        .await
        .expect("move");
    for _ in 0..3 {
        client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
    }
    client
        .command(Payload::move_(0.0, 0.0))
        .await
        .expect("stop");
    client.command(Payload::reset()).await.expect("reset");
    client
        .command_and_wait_applied(Payload::advance())
        .await
        .expect("advance")
}
