//! Keeping the learner daemon attached to its world: when the connection
//! breaks (the world restarted, the network failed) it reconnects with
//! exponential backoff, logging every attempt, and re-synchronises the model
//! on the first state after the gap; when the world reports a physics
//! blow-up (it has reset itself, `docs/protocol.md` §6) it re-synchronises too.
//! In neither case does the model train on a transition across the gap.

use std::future::Future;
use std::time::{Duration, Instant};

use futures::FutureExt;

use super::{serve, Episodes, Event, LearnError, OnState, ServeOptions, Stop, WorkSummary};
use crate::frame::StartHeights;
use learner::Frame;
use pushlearn::client::{seq_base_from_clock, ClientError, ClientOptions, SimClient};
use pushlearn::wire::pb::client_message::Payload;

/// How to reconnect.
#[derive(Clone, Debug)]
pub struct Reconnect {
    /// The world's address.
    pub addr: String,
    /// The first wait after a failed attempt; it doubles up to `max_delay`.
    pub first_delay: Duration,
    /// The longest wait between attempts.
    pub max_delay: Duration,
    /// Give up when the world has been unreachable this long (`None`: never
    /// reconnect, the first break ends the daemon).
    pub give_up_after: Option<Duration>,
}

/// Defaults of [`Reconnect`].
pub const FIRST_DELAY: Duration = Duration::from_millis(100);
/// Defaults of [`Reconnect`].
pub const MAX_DELAY: Duration = Duration::from_secs(5);

impl Reconnect {
    /// Reconnects to `addr` for up to `give_up_after` with the default delays.
    #[must_use]
    pub fn new(addr: impl Into<String>, give_up_after: Option<Duration>) -> Self {
        Reconnect {
            addr: addr.into(),
            first_delay: FIRST_DELAY,
            max_delay: MAX_DELAY,
            give_up_after,
        }
    }
}

/// Whether `err` means the connection is gone (rather than the world
/// refusing a command): worth reconnecting.
#[must_use]
pub fn connection_lost(err: &ClientError) -> bool {
    matches!(err, ClientError::Closed | ClientError::Wire(_))
}

/// What [`serve_resilient`] did.
#[derive(Debug)]
pub struct Served {
    /// The connection at the end (`None` if interrupted while reconnecting).
    pub client: Option<SimClient>,
    pub stop: Stop,
    /// Work times since the last (re)connection.
    pub summary: WorkSummary,
    /// States handled over all connections.
    pub states: u64,
    /// Successful reconnections.
    pub reconnects: u64,
    /// Physics blow-ups the world reported.
    pub world_errors: u64,
    /// States the world published that never reached the learner, over all
    /// connections ([`SimClient::missed_states`]).
    pub missed: u64,
}

/// Counts the states handed to the learner, across connections.
struct Counting<'a, H> {
    inner: &'a mut H,
    states: u64,
}

impl<H: OnState> OnState for Counting<'_, H> {
    fn on_state(
        &mut self,
        frame: &Frame,
        heights: &StartHeights,
    ) -> Result<Vec<Payload>, LearnError> {
        self.states += 1;
        self.inner.on_state(frame, heights)
    }

    fn resync(&mut self) -> Result<(), LearnError> {
        self.inner.resync()
    }

    fn episodes(&self) -> Option<&Episodes> {
        self.inner.episodes()
    }
}

/// [`serve`], surviving a lost world: reconnects as `reconnect` says and
/// re-synchronises `learner`; `options.max_messages` counts over all
/// connections. `shutdown` stops it as it stops [`serve`], also while
/// reconnecting.
///
/// # Errors
/// As [`serve`], and the world staying unreachable for longer than allowed
/// or coming back as a different world (scene, mode or rate).
pub async fn serve_resilient(
    mut client: SimClient,
    learner: &mut impl OnState,
    options: ServeOptions,
    reconnect: &Reconnect,
    shutdown: impl Future<Output = ()>,
    mut report: impl FnMut(Event<'_>),
) -> Result<Served, LearnError> {
    // Shared: every connection's serving loop and the reconnection wait on
    // the same stop, and one that has come stays come.
    let shutdown = shutdown.shared();
    let mut counting = Counting {
        inner: learner,
        states: 0,
    };
    let mut reconnects = 0;
    let mut world_errors = 0;
    // Missed by the connections before the current one.
    let mut missed_before = 0;
    loop {
        let left = ServeOptions {
            max_messages: options
                .max_messages
                .map(|n| n.saturating_sub(counting.states)),
            ..options
        };
        let err = match serve(
            &mut client,
            &mut counting,
            left,
            shutdown.clone(),
            &mut report,
        )
        .await
        {
            Ok((stop, summary)) => {
                return Ok(Served {
                    missed: missed_before + client.missed_states(),
                    client: Some(client),
                    stop,
                    summary,
                    states: counting.states,
                    reconnects,
                    world_errors,
                })
            }
            Err(err) => err,
        };
        match err {
            LearnError::Client(ClientError::World { message, .. }) => {
                // A blow-up: the world has reset itself.
                world_errors += 1;
                tracing::warn!("the world reported: {message}; re-synchronising the model");
                counting.resync()?;
            }
            LearnError::Client(lost) if connection_lost(&lost) => {
                let Some(limit) = reconnect.give_up_after else {
                    return Err(lost.into());
                };
                tracing::warn!("lost the world at {}: {lost}; reconnecting", reconnect.addr);
                counting.resync()?;
                let expected = client.hello().clone();
                let connected = tokio::select! {
                    connected = connect_with_backoff(reconnect, limit) => connected?,
                    () = shutdown.clone() => {
                        return Ok(Served {
                            client: None,
                            stop: Stop::Interrupted,
                            summary: WorkSummary::default(),
                            states: counting.states,
                            reconnects,
                            world_errors,
                            missed: missed_before + client.missed_states(),
                        });
                    }
                };
                same_world(&expected, connected.hello())?;
                missed_before += client.missed_states();
                client = connected;
                reconnects += 1;
            }
            err => return Err(err),
        }
    }
}

/// Connects to `reconnect.addr`, waiting `first_delay`, then twice that, …
/// up to `max_delay` between attempts, for at most `limit`.
///
/// # Errors
/// The last connection error once `limit` has passed.
pub async fn connect_with_backoff(
    reconnect: &Reconnect,
    limit: Duration,
) -> Result<SimClient, ClientError> {
    let started = Instant::now();
    let mut delay = reconnect.first_delay;
    let mut attempt = 0u32;
    loop {
        attempt += 1;
        let options = ClientOptions {
            // A fresh range: the world may still show the old connection's
            // applied_seq (`client.rs`, several clients).
            first_seq: seq_base_from_clock(),
            ..ClientOptions::default()
        };
        match SimClient::connect_with(reconnect.addr.as_str(), options).await {
            Ok(client) => {
                tracing::warn!(
                    attempt,
                    after = %pushlearn::duration::describe(started.elapsed()),
                    "reconnected to the world at {}; the next state re-synchronises the model",
                    reconnect.addr
                );
                return Ok(client);
            }
            Err(err) if started.elapsed() + delay > limit => {
                tracing::error!(attempt, "giving up reconnecting: {err}");
                return Err(err);
            }
            Err(err) => {
                tracing::warn!(
                    attempt,
                    retry_in = %pushlearn::duration::describe(delay),
                    "reconnecting failed: {err}"
                );
                tokio::time::sleep(delay).await;
                delay = (delay * 2).min(reconnect.max_delay);
            }
        }
    }
}

/// The learner's model and thresholds were made for one world.
fn same_world(
    expected: &pushlearn::wire::pb::Hello,
    now: &pushlearn::wire::pb::Hello,
) -> Result<(), ClientError> {
    let describe = |h: &pushlearn::wire::pb::Hello| {
        format!("{} at {} Hz, {}", h.scene, h.publish_rate, h.timing_mode)
    };
    if describe(expected) == describe(now) {
        Ok(())
    } else {
        Err(ClientError::Protocol(format!(
            "the world came back as {} instead of {}",
            describe(now),
            describe(expected)
        )))
    }
}
