//! Lock-step determinism and latency emulation.

use pushlearn::wire::pb::{self, client_message::Payload};
use sim_plugin::server::Config;

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
