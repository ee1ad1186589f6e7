//! Lock-step determinism and latency emulation.

use pushlearn::wire::pb::{self, client_message::Payload};
use sim_plugin::server::{Config, EmbeddedWorld};

use super::support::*;

enum Step {
    Command(Payload),
    Advance(u32),
}

/// Every kind of command, with a push that reaches the block.
fn script() -> Vec<Step> {
    use Step::{Advance, Command};
    vec![
        Command(Payload::set_pose("actuator", [0.105, 0.0, 0.03], 0.0)),
        Command(Payload::move_(0.0, 0.5)),
        Advance(45),
        Command(Payload::set_pose("blockA", [0.1, 0.5, 0.05], 0.3)),
        Command(Payload::set_pose("blockAShadow", [0.1, 0.5, 0.05], 0.3)),
        Command(Payload::move_(0.2, -0.3)),
        Advance(10),
        Command(Payload::publish_rate(10)),
        Advance(2),
        Command(Payload::publish_rate(100)),
        Command(Payload::pause()),
        Command(Payload::unpause()),
        Command(Payload::move_(0.0, 0.0)),
        Command(Payload::reset()),
        Command(Payload::move_(-0.4, 0.1)),
        Advance(5),
    ]
}

/// The states `script` produces on a fresh daemon with `config`, preceded
/// by `first` commands.
async fn states(config: Config, first: Vec<Payload>) -> Vec<pb::WorldState> {
    let server = start(config).await;
    let mut client = connect(&server).await;
    let mut states = Vec::new();
    for payload in first {
        client.command(payload).await.expect("accepted");
    }
    for step in script() {
        match step {
            Step::Command(payload) => {
                client.command(payload).await.expect("accepted");
            }
            Step::Advance(n) => {
                for _ in 0..n {
                    states.push(
                        client
                            .command_and_wait_applied(Payload::advance())
                            .await
                            .expect("advance"),
                    );
                }
            }
        }
    }
    states
}

#[tokio::test]
async fn identical_command_streams_give_identical_state_streams() {
    // Two worlds stepping at the same time in one process.
    let (a, b) = tokio::join!(
        states(lockstep(), Vec::new()),
        states(lockstep(), Vec::new())
    );
    assert_eq!(a.len(), 62);
    assert_eq!(a, b);
}

#[tokio::test]
async fn with_latency_the_seed_decides_the_state_stream() {
    let (a, b, other) = tokio::join!(
        states(with_latency(5, 11), Vec::new()),
        states(with_latency(5, 11), Vec::new()),
        states(with_latency(5, 12), Vec::new()),
    );
    assert_eq!(a, b);
    assert_ne!(a, other);
    assert_ne!(a, states(lockstep(), Vec::new()).await);
}

#[tokio::test]
async fn latency_seed_makes_the_stream_independent_of_the_start_seed() {
    let reseed = || vec![Payload::latency_seed(42)];
    let (a, b) = tokio::join!(
        states(with_latency(5, 1), reseed()),
        states(with_latency(5, 2), reseed()),
    );
    assert_eq!(a, b);
    // The same as starting with that seed (unpause: a command that changes
    // nothing, so that the seqs match).
    assert_eq!(
        a,
        states(with_latency(5, 42), vec![Payload::unpause()]).await
    );
}

/// The delay of each Move, read off the actuator's travel: in each interval
/// of 10 steps the actuator moves L steps at the old velocity, then 10 − L
/// at the new one. Velocities alternate so that every delay shows.
async fn move_delays(config: Config) -> Vec<u32> {
    const STEP: f64 = 0.001;
    let server = start(config).await;
    let mut client = connect(&server).await;
    let (mut y, mut old) = (0.0, 0.0);
    let mut delays = Vec::new();
    for i in 0..16 {
        let new = if i % 2 == 0 { 0.5 } else { -0.5 };
        client.send(Payload::move_(0.0, new)).await.expect("move");
        let state = client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
        let end = position(&state, "actuator")[1];
        let delay = (end - y - 10.0 * new * STEP) / ((old - new) * STEP);
        assert!(
            (delay - delay.round()).abs() < 0.01,
            "not a whole number of steps: {delay}"
        );
        delays.push(delay.round() as u32);
        (y, old) = (end, new);
    }
    delays
}

#[tokio::test]
async fn latency_delays_each_move_by_zero_to_l_steps() {
    let delays = move_delays(with_latency(5, 7)).await;
    assert!(delays.iter().all(|&d| d <= 5), "{delays:?}");
    let mut distinct = delays.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() > 2, "delays vary: {delays:?}");
    let undelayed = move_delays(lockstep()).await;
    assert!(undelayed.iter().all(|&d| d == 0), "{undelayed:?}");
}

#[tokio::test]
async fn commands_keep_their_order_behind_a_delayed_move() {
    // Move(0, 0) then Reset, as the learner sends at a run boundary: the
    // Reset must not overtake the delayed Move, or the actuator would leave
    // its start pose with the old velocity.
    let server = start(with_latency(5, 7)).await;
    let mut client = connect(&server).await;
    client
        .command(Payload::move_(0.0, 0.5))
        .await
        .expect("move");
    for _ in 0..3 {
        client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
    }
    for _ in 0..8 {
        client
            .command(Payload::move_(0.0, 0.0))
            .await
            .expect("stop");
        client.command(Payload::reset()).await.expect("reset");
        let state = client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
        assert_eq!(position(&state, "actuator")[..2], [0.0, 0.0]);
        client
            .command(Payload::move_(0.0, 0.5))
            .await
            .expect("move");
        client
            .command_and_wait_applied(Payload::advance())
            .await
            .expect("advance");
    }
}

/// The push's states with its Advances sent one at a time (each after the
/// previous state) or queued all at once, a Move between the two halves.
async fn push_states(queued: bool) -> Vec<pb::WorldState> {
    const HALF: usize = 20;
    let server = start(lockstep()).await;
    let mut client = connect(&server).await;
    let mut states = Vec::new();
    for payload in [
        Payload::set_pose("actuator", [0.105, 0.0, 0.03], 0.0),
        Payload::move_(0.0, 0.5),
    ] {
        client.send(payload).await.expect("command");
    }
    for half in 0..2 {
        if half == 1 {
            client.send(Payload::move_(0.2, -0.3)).await.expect("move");
        }
        for _ in 0..HALF {
            if queued {
                client.send(Payload::advance()).await.expect("advance");
            } else {
                states.push(
                    client
                        .command_and_wait_applied(Payload::advance())
                        .await
                        .expect("advance"),
                );
            }
        }
    }
    if queued {
        for _ in 0..2 * HALF {
            states.push(client.next_state().await.expect("state"));
        }
    }
    states
}

#[tokio::test]
async fn queued_advances_give_the_states_of_advances_one_at_a_time() {
    // docs/protocol.md §5: several Advances in a row run as many intervals,
    // and a command sent between them applies at its place in the stream,
    // even though it reaches the world while earlier intervals still wait to
    // run.
    let (queued, one_at_a_time) = tokio::join!(push_states(true), push_states(false));
    assert_eq!(queued.len(), 40);
    assert!(
        queued.windows(2).all(|w| w[1].step == w[0].step + 10),
        "one interval per Advance"
    );
    assert_eq!(queued, one_at_a_time);
}

/// An [`EmbeddedWorld`] sent what a `SimClient` sends: numbered messages,
/// each command followed by its barrier.
struct OneClient {
    world: EmbeddedWorld,
    seq: u64,
}

impl OneClient {
    fn new(config: &Config) -> OneClient {
        let world = EmbeddedWorld::new(
            config.scene.clone(),
            config.publish_rate_hz,
            config.timing.latency(),
        )
        .expect("a world");
        OneClient { world, seq: 0 }
    }

    /// Sends `payload` (`None`: a barrier); what the world answered.
    fn send(&mut self, payload: Option<Payload>) -> Vec<pb::ServerMessage> {
        self.seq += 1;
        let message = match payload {
            Some(payload) => pb::ClientMessage::new(self.seq, payload),
            None => pb::ClientMessage::barrier(self.seq),
        };
        self.world.send(&message).expect("the world steps");
        std::iter::from_fn(|| self.world.next_message()).collect()
    }

    /// As `SimClient::command`: the command, then a barrier.
    fn command(&mut self, payload: Payload) {
        assert_eq!(self.send(Some(payload)), Vec::new(), "accepted");
        let barrier = self.send(None);
        let answered = matches!(
            barrier.as_slice(),
            [pb::ServerMessage { payload: Some(pb::server_message::Payload::Error(e)) }] if e.seq == self.seq
        );
        assert!(answered, "the barrier's answer: {barrier:?}");
    }

    fn advance(&mut self) -> pb::WorldState {
        match self.send(Some(Payload::advance())).as_slice() {
            [pb::ServerMessage {
                payload: Some(pb::server_message::Payload::WorldState(state)),
            }] => state.clone(),
            other => panic!("an Advance gave {other:?}"),
        }
    }
}

/// The states `script` produces on an [`EmbeddedWorld`] with `config`'s
/// scene and timing, sent exactly the messages `states` sends over the
/// socket.
fn embedded_states(config: &Config, first: Vec<Payload>) -> Vec<pb::WorldState> {
    let mut client = OneClient::new(config);
    for payload in first {
        client.command(payload);
    }
    let mut states = Vec::new();
    for step in script() {
        match step {
            Step::Command(payload) => client.command(payload),
            Step::Advance(n) => states.extend((0..n).map(|_| client.advance())),
        }
    }
    states
}

#[tokio::test]
async fn the_embedded_world_gives_the_daemons_states() {
    for (config, first) in [
        (lockstep(), Vec::new()),
        (with_latency(5, 11), Vec::new()),
        (with_latency(2, 3), vec![Payload::latency_seed(42)]),
    ] {
        let embedded = embedded_states(&config, first.clone());
        let served = states(config, first).await;
        assert_eq!(served.len(), 62);
        assert_eq!(embedded, served);
    }
}

#[tokio::test]
async fn the_embedded_world_greets_and_refuses_as_the_daemon_does() {
    let config = with_latency(2, 1);
    let server = start(config.clone()).await;
    let mut client = connect(&server).await;
    let mut world = EmbeddedWorld::new(
        config.scene.clone(),
        config.publish_rate_hz,
        config.timing.latency(),
    )
    .expect("a world");
    assert_eq!(&world.hello(), client.hello());
    for (payload, refused) in [
        (
            Payload::set_pose("no-such-body", [0.0, 0.0, 0.05], 0.0),
            true,
        ),
        (Payload::set_pose("blockA", [1.0e4, 0.0, 0.05], 0.0), true),
        (Payload::latency_seed(0), false),
    ] {
        let served = client.command(payload.clone()).await;
        let seq = client.last_seq().expect("sent") - 1;
        world
            .send(&pb::ClientMessage::new(seq, payload))
            .expect("the world steps");
        let embedded = world.next_message();
        match (served, embedded) {
            (
                Err(pushlearn::client::ClientError::Refused { message, kind, .. }),
                Some(pb::ServerMessage {
                    payload: Some(pb::server_message::Payload::Error(error)),
                }),
            ) if refused => {
                assert_eq!(error.seq, seq);
                assert_eq!((error.kind(), error.message), (kind, message));
            }
            (Ok(_), None) if !refused => {}
            other => panic!("the daemon and the embedded world differ: {other:?}"),
        }
    }
    // A paused world refuses an Advance in both.
    client.command(Payload::pause()).await.expect("accepted");
    world
        .send(&pb::ClientMessage::new(100, Payload::pause()))
        .expect("the world steps");
    let served = client.command(Payload::advance()).await;
    world
        .send(&pb::ClientMessage::new(101, Payload::advance()))
        .expect("the world steps");
    let Some(pb::ServerMessage {
        payload: Some(pb::server_message::Payload::Error(error)),
    }) = world.next_message()
    else {
        panic!("the embedded world advanced a paused world");
    };
    let Err(pushlearn::client::ClientError::Refused { message, .. }) = served else {
        panic!("the daemon advanced a paused world: {served:?}");
    };
    assert_eq!(error.message, message);
}

/// Issue 49, item 1: the bound on waiting commands counted only those still
/// on the channel, and the physics thread moves each Move into the latency
/// emulation's pending list at once, so a flood without an Advance never
/// met it (2 000 000 Moves: 7 → 322 MB, no `busy:`). Now the held Moves
/// count until an Advance applies them: the flood is refused past the
/// bound, an Advance still passes and empties it, and Moves are accepted
/// again.
#[tokio::test]
async fn a_flood_of_moves_without_an_advance_is_refused_busy_and_an_advance_drains_it() {
    use pushlearn::wire::encode_frame;
    use sim_plugin::server::MAX_QUEUED_COMMANDS;

    let server = start(with_latency(2, 1)).await;
    let mut raw = Raw::connect(&server).await;
    let over = 5;
    let flood = MAX_QUEUED_COMMANDS as u64 + over;
    let mut batch = Vec::new();
    for seq in 1..=flood {
        batch.extend(
            encode_frame(&pb::ClientMessage::new(seq, Payload::move_(0.1, 0.0))).expect("frame"),
        );
        if batch.len() > 1 << 16 {
            raw.send_bytes(&batch).await;
            batch.clear();
        }
    }
    raw.send_bytes(&batch).await;
    for expected in (flood - over + 1)..=flood {
        let error = raw.next_error().await;
        assert_eq!(error.kind(), pb::error::Kind::Busy, "{error:?}");
        assert_eq!(error.seq, expected);
        assert!(error.message.starts_with("busy:"), "{}", error.message);
    }
    raw.send(&pb::ClientMessage::new(flood + 1, Payload::advance()))
        .await;
    match raw.next().await {
        Some(pb::server_message::Payload::WorldState(state)) => {
            assert_eq!(state.applied_seq, flood + 1);
        }
        other => panic!("expected the Advance's state, got {other:?}"),
    }
    raw.send(&pb::ClientMessage::new(flood + 2, Payload::move_(0.1, 0.0)))
        .await;
    // A barrier: its answer, and no busy before it, shows the Move passed.
    raw.send(&pb::ClientMessage {
        seq: flood + 3,
        payload: None,
    })
    .await;
    let error = raw.next_error().await;
    assert_eq!(error.seq, flood + 3, "{error:?}");
}
