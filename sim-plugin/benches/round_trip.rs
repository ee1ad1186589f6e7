//! Lock-step runs over a localhost socket against the same runs in-process.
//!
//! One iteration is one calibration run of the push task from x0 = 0.105:
//! Move(0, 0), Reset, place the actuator, Move(0, 0.5), then 150 messages at
//! 100 Hz (1500 steps of 1 ms).
//!
//! * `socket`: a lock-step `pushlearn-sim` server in this process, driven by
//!   a `SimClient` over 127.0.0.1: 150 round trips of state → Advance → next
//!   state, each through the client's socket, the server's tasks and the
//!   physics thread;
//! * `in_process`: the same world stepped directly (`sweep::run`).
//!
//! Criterion's throughput is in runs, so "elem/s" is runs of 150 messages
//! per second; time / 150 is the cost of one message.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use pushlearn::client::{ClientError, SimClient};
use pushlearn::wire::pb::{self, client_message::Payload};
use sim_plugin::server::{Config, Server, ServerHandle, Timing};
use sim_plugin::sweep::run;
use sim_plugin::{Scene, SweepOptions, World};
use tokio::net::TcpListener;

const MESSAGES: u32 = 150;
const X0: f64 = 0.105;

async fn socket_run(client: &mut SimClient, x0: f64) -> Result<pb::WorldState, ClientError> {
    for payload in [
        Payload::move_(0.0, 0.0),
        Payload::reset(),
        Payload::set_pose("actuator", [x0, 0.0, 0.03], 0.0),
        Payload::move_(0.0, 0.5),
    ] {
        client.send(payload).await?;
    }
    let mut last = client.command_and_wait_applied(Payload::advance()).await?;
    for _ in 1..MESSAGES {
        last = client.command_and_wait_applied(Payload::advance()).await?;
    }
    Ok(last)
}

async fn lockstep_server(scene: Scene) -> (ServerHandle, SimClient) {
    let Ok(listener) = TcpListener::bind("127.0.0.1:0").await else {
        panic!("cannot bind 127.0.0.1:0");
    };
    let config = Config {
        timing: Timing::Lockstep { latency: None },
        ..Config::new(scene)
    };
    let server = match Server::start(listener, config).await {
        Ok(server) => server,
        Err(err) => panic!("server: {err}"),
    };
    let client = match SimClient::connect(server.local_addr()).await {
        Ok(client) => client,
        Err(err) => panic!("client: {err}"),
    };
    (server, client)
}

fn runs(c: &mut Criterion) {
    let Ok(scene) = Scene::builtin("one_block") else {
        panic!("the embedded scene does not parse");
    };
    let mut group = c.benchmark_group("lockstep_run");
    group.throughput(Throughput::Elements(1));
    group.sample_size(20);

    let Ok(mut world) = World::new(&scene) else {
        panic!("the world does not build");
    };
    let options = SweepOptions::default();
    group.bench_function("in_process", |b| {
        b.iter(|| run(&mut world, &options, std::hint::black_box(X0)).is_ok())
    });

    // One thread for the client and the server's tasks, one for the physics.
    let Ok(runtime) = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    else {
        panic!("cannot build a tokio runtime");
    };
    let (server, mut client) = runtime.block_on(lockstep_server(scene));
    group.bench_function("socket", |b| {
        b.iter(|| runtime.block_on(socket_run(&mut client, std::hint::black_box(X0))))
    });
    group.finish();
    if let Err(err) = runtime.block_on(server.shutdown()) {
        panic!("server shutdown: {err}");
    }
}

criterion_group!(benches, runs);
criterion_main!(benches);
