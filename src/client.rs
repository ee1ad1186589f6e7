//! An async client for the world daemon (`pushlearn-sim`).
//!
//! ```no_run
//! # async fn demo() -> Result<(), pushlearn::client::ClientError> {
//! use pushlearn::client::SimClient;
//! use pushlearn::wire::pb::client_message::Payload;
//!
//! let mut sim = SimClient::connect("127.0.0.1:11345").await?;
//! println!("scene {}", sim.hello().scene);
//! sim.command(Payload::reset()).await?;               // accepted by the world
//! let state = sim.command_and_wait_applied(Payload::move_(0.0, 0.5)).await?; // in force
//! println!("step {}", state.step);
//! # Ok(()) }
//! ```
//!
//! Three levels of waiting, from cheapest to strongest:
//!
//! * [`SimClient::send`] returns once the frame is written;
//! * [`SimClient::command`] returns once the world has *accepted* the command
//!   (validated it, queued it in order) or refused it, using a round-trip
//!   barrier ([`pb::ClientMessage::barrier`]); works in every world state;
//! * [`SimClient::command_and_wait_applied`] returns the first `WorldState`
//!   produced with the command in force (`applied_seq >= seq`). It needs the
//!   world to be stepping: while paused, or in lock-step mode before the next
//!   Advance, no such state is published and the call times out.
//!
//! Sequence numbers are assigned by the client, strictly increasing from
//! [`ClientOptions::first_seq`]. `applied_seq` is global to the world: with
//! several clients it only identifies a client's own commands if the clients
//! use disjoint, increasing seq ranges (docs/spec/protocol.md §3); otherwise a later
//! command of another client with a smaller seq can hide ours, and a wait for
//! "applied" can time out or return early.

use std::collections::BTreeSet;
use std::fmt;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::net::{TcpStream, ToSocketAddrs};
use tokio::time::Instant;

use crate::duration;
use crate::wire::pb::{self, client_message::Payload, server_message};
use crate::wire::{validate, ClientConnection, InvalidCommand, WireError};

/// The world daemon's default address.
pub const DEFAULT_ADDR: &str = "127.0.0.1:11345";

/// Default limit for every wait (connecting, answers, states).
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(10);

/// What can go wrong talking to the world.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// TCP connect failed.
    #[error(
        "cannot connect to the world at {addr}: {reason}{}",
        connect_hint(reason, addr)
    )]
    Connect {
        /// The address as given.
        addr: String,
        /// The cause (in the message, not a `source`, so it is printed once).
        reason: std::io::Error,
    },
    /// Something answers at the address, but it is no world daemon: no
    /// Hello came first.
    #[error("{addr} is not a pushlearn-sim: {why}")]
    NotAWorld {
        /// The address as given.
        addr: String,
        /// What it did instead.
        why: String,
    },
    /// Framing or transport failure.
    #[error(transparent)]
    Wire(#[from] WireError),
    /// The world closed the connection.
    #[error("the world closed the connection")]
    Closed,
    /// Nothing suitable arrived in time.
    #[error("timed out after {} waiting for {waiting_for}", duration::describe(*after))]
    Timeout {
        /// What was awaited.
        waiting_for: &'static str,
        /// The limit.
        after: Duration,
    },
    /// The world answered command `seq` with an `Error`.
    #[error("the world refused a command: {message}")]
    Refused {
        /// The refused command's seq.
        seq: u64,
        /// Why, for programs (`Unspecified` from a world older than the field).
        kind: pb::error::Kind,
        /// The world's explanation, for people.
        message: String,
    },
    /// The world sent an `Error` not tied to a command (`seq = 0`).
    #[error("the world reported an error: {message}")]
    World {
        /// What happened, for programs (`Unspecified` from a world older
        /// than the field).
        kind: pb::error::Kind,
        /// The world's explanation, for people.
        message: String,
    },
    /// The command failed local validation and was not sent.
    #[error("invalid command, not sent: {0}")]
    Invalid(InvalidCommand),
    /// The world broke the protocol (e.g. no `Hello` first).
    #[error("protocol violation by the world: {0}")]
    Protocol(String),
    /// All `u64` sequence numbers after the first one have been used.
    #[error("sequence numbers exhausted")]
    SeqExhausted,
}

impl ClientError {
    /// The `seq` of the command the world refused, if this is a refusal.
    pub fn refused_seq(&self) -> Option<u64> {
        match self {
            ClientError::Refused { seq, .. } => Some(*seq),
            _ => None,
        }
    }
}

impl From<InvalidCommand> for ClientError {
    fn from(err: InvalidCommand) -> Self {
        ClientError::Invalid(err)
    }
}

impl From<pb::Error> for ClientError {
    /// An `Error` from the world as a client reports it: a refusal of the
    /// command it answers, or a world error for `seq = 0`.
    fn from(error: pb::Error) -> Self {
        world_error(error)
    }
}

fn world_error(error: pb::Error) -> ClientError {
    let kind = error.kind();
    match error.seq {
        0 => ClientError::World {
            kind,
            message: error.message,
        },
        seq => ClientError::Refused {
            seq,
            kind,
            message: error.message,
        },
    }
}

/// Hands out strictly increasing sequence numbers.
#[derive(Debug, Clone)]
pub struct SeqCounter {
    next: Option<u64>,
    last: Option<u64>,
}

impl SeqCounter {
    /// Starts at `first`, or at 1 if `first` is 0: seq 0 means "no command"
    /// in `Error.seq` and `WorldState.applied_seq`.
    pub fn starting_at(first: u64) -> Self {
        Self {
            next: Some(first.max(1)),
            last: None,
        }
    }

    /// The next number, or `None` once `u64::MAX` has been handed out.
    pub fn next_seq(&mut self) -> Option<u64> {
        let seq = self.next?;
        self.next = seq.checked_add(1);
        self.last = Some(seq);
        Some(seq)
    }

    /// The number handed out last.
    pub fn last(&self) -> Option<u64> {
        self.last
    }
}

/// A seq base that grows with the wall clock (microseconds since 1970,
/// about 2^51 today): successive short-lived clients, such as `pushlearn ctl`
/// invocations, then use increasing, practically disjoint seq ranges without
/// coordinating, and a stale `applied_seq` left by an earlier client is always
/// below the new client's seqs.
pub fn seq_base_from_clock() -> u64 {
    let micros = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_micros());
    u64::try_from(micros).unwrap_or(u64::MAX / 2).max(1)
}

/// Connection settings.
#[derive(Debug, Clone)]
pub struct ClientOptions {
    /// Limit for every wait; `None` waits forever.
    pub timeout: Option<Duration>,
    /// The first seq this client uses (see the module docs about several clients).
    pub first_seq: u64,
}

impl Default for ClientOptions {
    fn default() -> Self {
        Self {
            timeout: Some(DEFAULT_TIMEOUT),
            first_seq: 1,
        }
    }
}

impl ClientOptions {
    /// The defaults, with seqs from [`seq_base_from_clock`]: for a
    /// long-running client beside others (a learner, a viewer), whose
    /// `applied_seq`s must stay apart from theirs (docs/protocol.md §5).
    pub fn clock_seqs() -> Self {
        Self {
            first_seq: seq_base_from_clock(),
            ..Self::default()
        }
    }
}

/// A connection to the world daemon.
#[derive(Debug)]
pub struct SimClient {
    connection: ClientConnection,
    hello: pb::Hello,
    seqs: SeqCounter,
    timeout: Option<Duration>,
    /// Barriers sent whose answer has not been read yet; their `Error`s are
    /// expected and never shown to callers.
    pending_barriers: BTreeSet<u64>,
    /// The `publish_seq` of the latest state received.
    last_publish_seq: Option<u64>,
    /// See [`SimClient::missed_states`].
    missed_states: u64,
}

impl SimClient {
    /// Connects with [`ClientOptions::default`] and reads the world's `Hello`.
    pub async fn connect<A: ToSocketAddrs + fmt::Display>(addr: A) -> Result<Self, ClientError> {
        Self::connect_with(addr, ClientOptions::default()).await
    }

    /// Connects and reads the world's `Hello`, both within `options.timeout`.
    pub async fn connect_with<A: ToSocketAddrs + fmt::Display>(
        addr: A,
        options: ClientOptions,
    ) -> Result<Self, ClientError> {
        let deadline = options.timeout.map(|t| Instant::now() + t);
        let addr_text = addr.to_string();
        let connect_error = |reason| ClientError::Connect {
            addr: addr_text.clone(),
            reason,
        };
        let stream = match within(
            deadline,
            options.timeout,
            "the TCP connection",
            TcpStream::connect(addr),
        )
        .await
        {
            Ok(connected) => connected.map_err(connect_error)?,
            Err(ClientError::Timeout { after, .. }) => {
                return Err(connect_error(std::io::Error::new(
                    std::io::ErrorKind::TimedOut,
                    format!("no answer within {}", duration::describe(after)),
                )))
            }
            Err(err) => return Err(err),
        };
        let mut connection = ClientConnection::new(stream);
        let not_a_world = |why: String| ClientError::NotAWorld {
            addr: addr_text.clone(),
            why,
        };
        let first = match within(
            deadline,
            options.timeout,
            "the Hello message",
            connection.read(),
        )
        .await
        {
            Ok(Ok(first)) => first,
            Ok(Err(wire)) => {
                return Err(not_a_world(format!(
                    "what it sent first is no pushlearn frame ({wire})"
                )))
            }
            Err(ClientError::Timeout { after, .. }) => {
                return Err(not_a_world(format!(
                    "it accepted the connection but sent no Hello within {}, and a world \
                     greets every client at once{NOT_THE_VIEWER}",
                    duration::describe(after)
                )))
            }
            Err(err) => return Err(err),
        };
        let hello = match first.map(|m| m.payload) {
            Some(Some(server_message::Payload::Hello(hello))) => hello,
            Some(Some(server_message::Payload::Error(error))) => return Err(world_error(error)),
            Some(_) => return Err(not_a_world("its first message was not a Hello".into())),
            None => {
                return Err(not_a_world(format!(
                    "it closed the connection without a Hello{NOT_THE_VIEWER}"
                )))
            }
        };
        tracing::debug!(addr = %addr_text, scene = %hello.scene, mode = %hello.timing_mode, "connected");
        Ok(Self {
            connection,
            hello,
            seqs: SeqCounter::starting_at(options.first_seq),
            timeout: options.timeout,
            pending_barriers: BTreeSet::new(),
            last_publish_seq: None,
            missed_states: 0,
        })
    }

    /// The world's `Hello`: scene, step size, publish rate at connect time,
    /// timing mode, bodies and their start poses.
    pub fn hello(&self) -> &pb::Hello {
        &self.hello
    }

    /// The limit for each wait.
    pub fn timeout(&self) -> Option<Duration> {
        self.timeout
    }

    /// Changes the limit for each wait; `None` waits forever.
    pub fn set_timeout(&mut self, timeout: Option<Duration>) {
        self.timeout = timeout;
    }

    /// States the world published after the first this client received
    /// but never delivered to it: the gaps in `publish_seq`, which the world
    /// leaves when a client's queue is full (`docs/protocol.md` §7). Every
    /// state received counts, also those a wait skipped.
    pub fn missed_states(&self) -> u64 {
        self.missed_states
    }

    /// The seq of the last frame sent (commands and barriers).
    pub fn last_seq(&self) -> Option<u64> {
        self.seqs.last()
    }

    /// Validates `payload`, tags it with the next seq and sends it; returns
    /// the seq. Does not wait for any answer.
    pub async fn send(&mut self, payload: Payload) -> Result<u64, ClientError> {
        let mut message = pb::ClientMessage::new(0, payload);
        validate(&message)?;
        message.seq = self.seqs.next_seq().ok_or(ClientError::SeqExhausted)?;
        tracing::debug!(
            seq = message.seq,
            kind = message.payload.as_ref().map_or("", Payload::kind),
            "send"
        );
        self.write(&message).await?;
        Ok(message.seq)
    }

    /// [`SimClient::send`] for each of `payloads`, in order, written to the
    /// socket at once; returns the last seq (`None` for no payloads). Every
    /// payload is validated before anything is sent.
    pub async fn send_all(&mut self, payloads: Vec<Payload>) -> Result<Option<u64>, ClientError> {
        let mut messages = Vec::with_capacity(payloads.len());
        for payload in payloads {
            let message = pb::ClientMessage::new(0, payload);
            validate(&message)?;
            messages.push(message);
        }
        for message in &mut messages {
            message.seq = self.seqs.next_seq().ok_or(ClientError::SeqExhausted)?;
            tracing::debug!(
                seq = message.seq,
                kind = message.payload.as_ref().map_or("", Payload::kind),
                "send"
            );
        }
        let deadline = self.deadline();
        within(
            deadline,
            self.timeout,
            "the world to read a command",
            self.connection.write_all(&messages),
        )
        .await??;
        Ok(messages.last().map(|m| m.seq))
    }

    /// The next message from the world, `Error`s included (answers to
    /// barriers excepted), within the timeout.
    pub async fn next_message(&mut self) -> Result<server_message::Payload, ClientError> {
        let deadline = self.deadline();
        self.receive(deadline, "a message from the world").await
    }

    /// The next `WorldState`. An `Error` from the world is returned as
    /// [`ClientError::Refused`] (or [`ClientError::World`] for `seq = 0`).
    pub async fn next_state(&mut self) -> Result<pb::WorldState, ClientError> {
        let deadline = self.deadline();
        match self.receive(deadline, "a WorldState").await? {
            server_message::Payload::WorldState(state) => Ok(state),
            server_message::Payload::Error(error) => Err(world_error(error)),
            server_message::Payload::Hello(_) => Err(second_hello()),
        }
    }

    /// Waits until the world has received and validated every frame sent so
    /// far: sends a barrier and waits for its answer. Fails with the first
    /// `Error` the world sends for an earlier command. `WorldState`s arriving
    /// meanwhile are discarded.
    pub async fn sync(&mut self) -> Result<(), ClientError> {
        let barrier = self.seqs.next_seq().ok_or(ClientError::SeqExhausted)?;
        self.write(&pb::ClientMessage::barrier(barrier)).await?;
        self.pending_barriers.insert(barrier);
        let deadline = self.deadline();
        loop {
            match self
                .read_payload(deadline, "the world's acknowledgement")
                .await?
            {
                server_message::Payload::Error(error) if error.seq == barrier => {
                    self.pending_barriers.remove(&barrier);
                    return Ok(());
                }
                server_message::Payload::Error(error)
                    if self.pending_barriers.remove(&error.seq) => {}
                server_message::Payload::Error(error) => return Err(world_error(error)),
                server_message::Payload::WorldState(_) => {}
                server_message::Payload::Hello(_) => return Err(second_hello()),
            }
        }
    }

    /// Sends `payload` and waits until the world has accepted it (see
    /// [`SimClient::sync`]); returns its seq. A refusal is
    /// [`ClientError::Refused`] with that seq.
    pub async fn command(&mut self, payload: Payload) -> Result<u64, ClientError> {
        let seq = self.send(payload).await?;
        self.sync().await?;
        Ok(seq)
    }

    /// Sends `payload` and returns the first `WorldState` whose `applied_seq`
    /// is at least its seq. See the module docs for when no such state comes
    /// (paused world, lock-step without Advance, other clients' seqs).
    pub async fn command_and_wait_applied(
        &mut self,
        payload: Payload,
    ) -> Result<pb::WorldState, ClientError> {
        let seq = self.send(payload).await?;
        self.wait_applied(seq).await
    }

    /// The first `WorldState` with `applied_seq >= seq`, skipping older
    /// states; any `Error` from the world ends the wait.
    pub async fn wait_applied(&mut self, seq: u64) -> Result<pb::WorldState, ClientError> {
        let deadline = self.deadline();
        loop {
            match self
                .receive(deadline, "a WorldState with the command applied")
                .await?
            {
                server_message::Payload::WorldState(state) if state.applied_seq >= seq => {
                    return Ok(state)
                }
                server_message::Payload::WorldState(_) => {}
                server_message::Payload::Error(error) => return Err(world_error(error)),
                server_message::Payload::Hello(_) => return Err(second_hello()),
            }
        }
    }

    /// Flushes and closes the connection.
    pub async fn close(mut self) -> Result<(), ClientError> {
        self.connection.close().await?;
        Ok(())
    }

    /// Writes within the timeout: a world that stops reading must not hang
    /// the client. A frame is buffered whole, so a timed-out write leaves the
    /// stream aligned.
    async fn write(&mut self, message: &pb::ClientMessage) -> Result<(), ClientError> {
        let deadline = self.deadline();
        within(
            deadline,
            self.timeout,
            "the world to read a command",
            self.connection.write(message),
        )
        .await??;
        Ok(())
    }

    fn deadline(&self) -> Option<Instant> {
        self.timeout.map(|t| Instant::now() + t)
    }

    /// The next message other than a barrier's answer.
    async fn receive(
        &mut self,
        deadline: Option<Instant>,
        waiting_for: &'static str,
    ) -> Result<server_message::Payload, ClientError> {
        loop {
            match self.read_payload(deadline, waiting_for).await? {
                server_message::Payload::Error(error)
                    if self.pending_barriers.remove(&error.seq) => {}
                payload => return Ok(payload),
            }
        }
    }

    /// The next message with a payload this client knows. A payload added by
    /// a newer world decodes as "none" and is skipped (docs/protocol.md §6).
    async fn read_payload(
        &mut self,
        deadline: Option<Instant>,
        waiting_for: &'static str,
    ) -> Result<server_message::Payload, ClientError> {
        loop {
            let message = within(deadline, self.timeout, waiting_for, self.connection.read())
                .await??
                .ok_or(ClientError::Closed)?;
            match message.payload {
                Some(payload) => {
                    if let server_message::Payload::WorldState(state) = &payload {
                        if let Some(last) = self.last_publish_seq {
                            self.missed_states += state.publish_seq.saturating_sub(last + 1);
                        }
                        self.last_publish_seq = Some(state.publish_seq);
                    }
                    return Ok(payload);
                }
                None => tracing::debug!("skipping a ServerMessage without a known payload"),
            }
        }
    }
}

fn second_hello() -> ClientError {
    ClientError::Protocol("a second Hello on the same connection".into())
}

/// Runs `future` until `deadline` (forever if `None`).
/// The likeliest wrong address: the viewer's page, an HTTP server that
/// waits for a request in silence.
const NOT_THE_VIEWER: &str =
    " (the viewer's HTTP port, 11346 by default, answers that way; the world's is 11345)";

/// What to try after a failed connect.
fn connect_hint(reason: &std::io::Error, addr: &str) -> String {
    match reason.kind() {
        std::io::ErrorKind::ConnectionRefused => {
            let default = if addr == DEFAULT_ADDR {
                ""
            } else {
                " (`pushlearn-sim serve --port P` listens on another port)"
            };
            format!(
                "; is pushlearn-sim running there? (`pushlearn-sim serve` starts one on {DEFAULT_ADDR}){default}"
            )
        }
        std::io::ErrorKind::TimedOut => "; is the host up and the address right?".to_owned(),
        _ => String::new(),
    }
}

async fn within<T>(
    deadline: Option<Instant>,
    limit: Option<Duration>,
    waiting_for: &'static str,
    future: impl std::future::Future<Output = T>,
) -> Result<T, ClientError> {
    match deadline {
        None => Ok(future.await),
        Some(deadline) => tokio::time::timeout_at(deadline, future)
            .await
            .map_err(|_| ClientError::Timeout {
                waiting_for,
                after: limit.unwrap_or_default(),
            }),
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn seq_zero_is_never_handed_out() {
        let mut seqs = SeqCounter::starting_at(0);
        assert_eq!(seqs.last(), None);
        assert_eq!(seqs.next_seq(), Some(1));
        assert_eq!(seqs.last(), Some(1));
    }

    #[test]
    fn seqs_stop_at_u64_max_instead_of_wrapping() {
        let mut seqs = SeqCounter::starting_at(u64::MAX - 1);
        assert_eq!(seqs.next_seq(), Some(u64::MAX - 1));
        assert_eq!(seqs.next_seq(), Some(u64::MAX));
        assert_eq!(seqs.next_seq(), None);
        assert_eq!(seqs.last(), Some(u64::MAX));
    }

    #[test]
    fn clock_seq_base_is_positive_and_leaves_room() {
        let base = seq_base_from_clock();
        assert!(base > 0 && base < u64::MAX / 2, "{base}");
    }

    proptest! {
        #[test]
        fn seqs_strictly_increase(first in any::<u64>(), count in 1usize..200) {
            let mut seqs = SeqCounter::starting_at(first);
            let mut previous = 0;
            for _ in 0..count {
                match seqs.next_seq() {
                    Some(seq) => {
                        prop_assert!(seq > previous, "{} after {}", seq, previous);
                        previous = seq;
                    }
                    None => {
                        prop_assert_eq!(previous, u64::MAX);
                        break;
                    }
                }
            }
        }
    }
}
