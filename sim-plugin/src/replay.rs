//! `pushlearn-sim replay`: a recording (`pushlearn::recording`) served to
//! clients as if it were the world.
//!
//! Each connection gets the recorded Hello, then the recorded states: in a
//! lock-step recording one per Advance, otherwise at their recorded pace (or
//! at once with `fast`). Commands are answered as the world answered the
//! recorded ones (a barrier or an invalid command with the world's `Error`,
//! a command the world refused with the recorded refusal) and compared with
//! the recorded ones by position; a difference is counted and logged once
//! per kind, so a user sees where their learner left the recording.
//!
//! The states' `applied_seq` are the recorded client's seqs; they are
//! rewritten to the seq this client used for the command at the same
//! position, so that a client waiting for its command to be applied
//! (`SimClient::wait_applied`) behaves as the recorded one did.

use std::collections::{BTreeSet, HashMap};
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use pushlearn::recording::{Frame, Recording};
use pushlearn::wire::pb::{self, client_message::Payload, server_message, sim_control::Action};
use pushlearn::wire::{
    encode_frame, validate, InvalidCommand, ServerConnection, TimingMode, WireError,
};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::Semaphore;
use tokio::time::Instant;

/// How long a realtime replay goes on answering a client after the last
/// recorded state, while the client keeps sending.
const END_GRACE: Duration = Duration::from_secs(1);

/// What a replay serves and how.
#[derive(Debug)]
pub struct Replay {
    /// The file's name, for messages.
    name: String,
    hello: pb::Hello,
    lockstep: bool,
    /// Whether the recording holds the client's frames.
    commands: bool,
    /// The world's frames a client receives unasked: states, and errors
    /// not answering a command (`seq = 0`), with their recorded times.
    events: Vec<(Duration, pb::ServerMessage)>,
    /// The recorded client's frames, in order.
    client: Vec<pb::ClientMessage>,
    /// The world's answers to the recorded client's frames, by seq.
    answers: HashMap<u64, pb::Error>,
    fast: bool,
}

/// How one connection's replay ended, for the log and for tests.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Served {
    /// States sent.
    pub states: u64,
    /// Client frames received.
    pub received: u64,
    /// Of those, frames that differ from the recording's at their position
    /// (or go beyond it).
    pub differing: u64,
    /// The recording ran out (rather than the client leaving first).
    pub exhausted: bool,
}

impl Replay {
    /// Prepares `recording` (read from the file `name`); `fast` serves a
    /// realtime recording without its pauses.
    pub fn new(recording: Recording, name: impl Into<String>, fast: bool) -> Self {
        let lockstep = matches!(recording.header.hello.timing(), Ok(TimingMode::Lockstep));
        let mut events = Vec::new();
        let mut client = Vec::new();
        let mut answers = HashMap::new();
        for record in recording.records {
            match record.frame {
                Frame::Client(message) => client.push(message),
                Frame::World(message) => match message.payload {
                    Some(server_message::Payload::Error(error)) if error.seq != 0 => {
                        answers.insert(error.seq, error);
                    }
                    Some(
                        server_message::Payload::WorldState(_) | server_message::Payload::Error(_),
                    ) => {
                        events.push((record.at, message));
                    }
                    // A second Hello or an unknown payload: nothing a
                    // client of this world was given unasked.
                    Some(server_message::Payload::Hello(_)) | None => {}
                },
            }
        }
        Self {
            name: name.into(),
            hello: recording.header.hello,
            lockstep,
            commands: recording.header.commands,
            events,
            client,
            answers,
            fast,
        }
    }

    /// The number of states the recording holds.
    pub fn states(&self) -> usize {
        self.events
            .iter()
            .filter(|(_, m)| matches!(m.payload, Some(server_message::Payload::WorldState(_))))
            .count()
    }

    /// Serves every connection to `listener` with its own replay from the
    /// start, until the process ends; at most `max_clients` at once, one
    /// more is told so (an `Error` of kind `TOO_MANY_CLIENTS`, as the world
    /// does) and closed.
    pub async fn serve(
        self: Arc<Self>,
        listener: TcpListener,
        max_clients: usize,
    ) -> std::io::Result<()> {
        let max_clients = max_clients.clamp(1, Semaphore::MAX_PERMITS);
        let places = Arc::new(Semaphore::new(max_clients));
        loop {
            let (stream, peer) = listener.accept().await?;
            let Ok(place) = Arc::clone(&places).try_acquire_owned() else {
                tokio::spawn(crate::server::connection::turn_away(
                    stream,
                    peer,
                    max_clients,
                ));
                continue;
            };
            let replay = Arc::clone(&self);
            tokio::spawn(async move {
                let _place = place;
                match replay.serve_one(stream, peer).await {
                    Ok(served) => tracing::info!(
                        %peer,
                        states = served.states,
                        received = served.received,
                        differing = served.differing,
                        "replay of {} ended{}",
                        replay.name,
                        if served.exhausted { " at the end of the recording" } else { "" }
                    ),
                    Err(err) => tracing::warn!(%peer, "replay of {} failed: {err}", replay.name),
                }
            });
        }
    }

    /// One client's replay.
    pub async fn serve_one(
        &self,
        stream: TcpStream,
        peer: SocketAddr,
    ) -> Result<Served, WireError> {
        stream.set_nodelay(true)?;
        tracing::info!(%peer, "client connected; replaying {}", self.name);
        let mut connection = ServerConnection::new(stream);
        connection.write(&self.hello.clone().into()).await?;
        let mut session = Session::new(self);
        let start = Instant::now();
        loop {
            let due = (!self.lockstep)
                .then(|| self.events.get(session.next_event))
                .flatten()
                .map(|(at, _)| if self.fast { start } else { start + *at });
            if !self.lockstep && due.is_none() {
                session.end_of_recording();
                // The recorded client went on briefly after the last state
                // (a learner stops its actuator and waits for the answer):
                // answer this one until it closes or falls silent.
                while let Ok(message) = tokio::time::timeout(END_GRACE, connection.read()).await {
                    let Some(message) = message? else { break };
                    let (replies, _) = session.on_message(&message);
                    connection.write_all(&replies).await?;
                }
                break;
            }
            tokio::select! {
                message = connection.read() => match message? {
                    Some(message) => {
                        let (replies, end) = session.on_message(&message);
                        connection.write_all(&replies).await?;
                        if end {
                            break;
                        }
                    }
                    None => break,
                },
                () = sleep_until(due) => {
                    if let Some(message) = session.next_unasked() {
                        connection.write(&message).await?;
                    }
                }
            }
        }
        connection.close().await?;
        Ok(session.served)
    }
}

async fn sleep_until(due: Option<Instant>) {
    match due {
        Some(due) => tokio::time::sleep_until(due).await,
        None => std::future::pending().await,
    }
}

#[cfg(feature = "testing")]
impl Replay {
    /// The recorded client's own frames played back to one session of this
    /// replay, in order, as a client repeating the recorded session sends
    /// them; in realtime, every state then sent unasked. For the fuzz harness
    /// (`untrusted::load_untrusted_recording`).
    #[must_use]
    pub fn play_back(&self) -> Served {
        let mut session = Session::new(self);
        for message in &self.client {
            if session.on_message(message).1 {
                break;
            }
        }
        if !self.lockstep {
            while session.next_unasked().is_some() {}
        }
        session.served
    }

    /// Whether the recording holds the client's frames.
    #[must_use]
    pub fn commands(&self) -> bool {
        self.commands
    }
}

/// Whether two client frames carry the same command, whatever their seqs.
/// Compared as encoded, bit for bit: a recorded `Move(NaN, 0)` (which the
/// world refused) is the same command when a client sends it again, though
/// NaN is not equal to itself.
fn same_command(a: &pb::ClientMessage, b: &pb::ClientMessage) -> bool {
    let command = |m: &pb::ClientMessage| {
        encode_frame(&pb::ClientMessage {
            seq: 0,
            payload: m.payload.clone(),
        })
        .ok()
    };
    command(a).is_some_and(|a| Some(a) == command(b))
}

/// One connection's position in the recording.
struct Session<'a> {
    replay: &'a Replay,
    next_event: usize,
    /// This client's seqs, in the order received.
    seqs: Vec<u64>,
    /// Kinds of difference already logged.
    warned: BTreeSet<&'static str>,
    served: Served,
}

impl<'a> Session<'a> {
    fn new(replay: &'a Replay) -> Self {
        Self {
            replay,
            next_event: 0,
            seqs: Vec::new(),
            warned: BTreeSet::new(),
            served: Served::default(),
        }
    }

    /// The answers to `message` and whether the connection ends after them.
    fn on_message(&mut self, message: &pb::ClientMessage) -> (Vec<pb::ServerMessage>, bool) {
        let position = self.seqs.len();
        self.seqs.push(message.seq);
        self.served.received += 1;
        let recorded = self.replay.client.get(position);
        if self.replay.commands {
            self.compare(position, message, recorded);
        }
        if let Err(invalid) = validate(message) {
            return (vec![invalid.reply(message.seq)], false);
        }
        // The world refused the recorded frame at this position: so would it
        // this one, if it is the same.
        if let Some(error) = recorded
            .filter(|r| same_command(r, message))
            .and_then(|r| self.replay.answers.get(&r.seq))
        {
            let kind = error.kind();
            return (
                vec![pb::ServerMessage::error(
                    message.seq,
                    kind,
                    error.message.clone(),
                )],
                false,
            );
        }
        let advance = matches!(
            &message.payload,
            Some(Payload::Control(pb::SimControl {
                action: Some(Action::Advance(true))
            }))
        );
        if !advance {
            return (Vec::new(), false);
        }
        if !self.replay.lockstep {
            return (
                vec![InvalidCommand::AdvanceInRealtime.reply(message.seq)],
                false,
            );
        }
        let mut replies = Vec::new();
        while let Some(reply) = self.next_unasked() {
            let state = matches!(reply.payload, Some(server_message::Payload::WorldState(_)));
            replies.push(reply);
            if state {
                return (replies, false);
            }
        }
        self.end_of_recording();
        replies.push(pb::ServerMessage::error(
            message.seq,
            pb::error::Kind::ShuttingDown,
            format!(
                "advance: end of the recording {} ({} states replayed)",
                self.replay.name, self.served.states
            ),
        ));
        (replies, true)
    }

    /// The next recorded state (with `applied_seq` in this client's seqs)
    /// or world error.
    fn next_unasked(&mut self) -> Option<pb::ServerMessage> {
        let (_, message) = self.replay.events.get(self.next_event)?;
        self.next_event += 1;
        let mut message = message.clone();
        if let Some(server_message::Payload::WorldState(state)) = &mut message.payload {
            state.applied_seq = self.translate(state.applied_seq);
            self.served.states += 1;
        }
        Some(message)
    }

    /// A recorded `applied_seq` as this client's seq for the command at the
    /// same position: the latest recorded command at or below it, or this
    /// client's latest if it has not sent that many. Without recorded
    /// commands, every state counts as produced with this client's latest.
    fn translate(&self, recorded: u64) -> u64 {
        let latest = self.seqs.last().copied().unwrap_or(0);
        if !self.replay.commands {
            return latest;
        }
        if recorded == 0 {
            return 0;
        }
        let applied = self
            .replay
            .client
            .iter()
            .take_while(|m| m.seq <= recorded)
            .count();
        match applied.checked_sub(1) {
            Some(index) => self.seqs.get(index).copied().unwrap_or(latest),
            // Another client's command, before any of the recorded one's.
            None => 0,
        }
    }

    fn compare(
        &mut self,
        position: usize,
        message: &pb::ClientMessage,
        recorded: Option<&pb::ClientMessage>,
    ) {
        let kind = message.payload.as_ref().map_or("barrier", Payload::kind);
        let problem = match recorded {
            None => "comes after the recording's last command",
            Some(r) if !same_command(r, message) => "differs from the recording's",
            Some(_) => return,
        };
        self.served.differing += 1;
        if self.warned.insert(kind) {
            tracing::warn!(
                "the client's {kind} (its frame {}) {problem}: the client has diverged from the recording {} (logged once per kind; the replay goes on)",
                position + 1,
                self.replay.name
            );
        }
    }

    fn end_of_recording(&mut self) {
        if !self.served.exhausted {
            self.served.exhausted = true;
            tracing::info!(
                "end of the recording {}: {} states replayed; closing the connection",
                self.replay.name,
                self.served.states
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pushlearn::recording::{Header, Record};

    fn state(step: u64, applied_seq: u64) -> pb::ServerMessage {
        pb::WorldState {
            step,
            applied_seq,
            ..Default::default()
        }
        .into()
    }

    fn lockstep_recording() -> Recording {
        let at = Duration::ZERO;
        let client = |m| Record {
            at,
            frame: Frame::Client(m),
        };
        let world = |m| Record {
            at,
            frame: Frame::World(m),
        };
        Recording {
            header: Header {
                commands: true,
                hello: pb::Hello {
                    timing_mode: "lockstep".into(),
                    ..Default::default()
                },
            },
            records: vec![
                client(pb::ClientMessage::move_(100, 0.0, 0.5)),
                client(pb::ClientMessage::advance(101)),
                world(state(10, 101)),
                client(pb::ClientMessage::set_pose(102, "blockC", [0.0; 3], 0.0)),
                world(pb::ServerMessage::error(
                    102,
                    pb::error::Kind::InvalidCommand,
                    "set_pose: unknown body 'blockC'",
                )),
                client(pb::ClientMessage::advance(103)),
                world(state(20, 103)),
            ],
            truncated: None,
        }
    }

    fn applied(replies: &[pb::ServerMessage]) -> Vec<u64> {
        replies
            .iter()
            .filter_map(|m| match &m.payload {
                Some(server_message::Payload::WorldState(s)) => Some(s.applied_seq),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn advances_get_the_recorded_states_in_the_client_s_seqs() {
        let replay = Replay::new(lockstep_recording(), "r", false);
        assert_eq!(replay.states(), 2);
        let mut session = Session::new(&replay);
        assert_eq!(
            session.on_message(&pb::ClientMessage::move_(1, 0.0, 0.5)),
            (vec![], false)
        );
        let (replies, end) = session.on_message(&pb::ClientMessage::advance(2));
        assert_eq!((applied(&replies), end), (vec![2], false));
        let (replies, _) =
            session.on_message(&pb::ClientMessage::set_pose(3, "blockC", [0.0; 3], 0.0));
        assert_eq!(
            replies,
            vec![pb::ServerMessage::error(
                3,
                pb::error::Kind::InvalidCommand,
                "set_pose: unknown body 'blockC'"
            )],
            "refused as the world refused it"
        );
        let (replies, _) = session.on_message(&pb::ClientMessage::advance(4));
        assert_eq!(applied(&replies), vec![4]);
        assert_eq!(session.served.differing, 0);
        let (replies, end) = session.on_message(&pb::ClientMessage::advance(5));
        assert!(end, "the recording is over");
        assert!(
            matches!(&replies[..], [pb::ServerMessage { payload: Some(server_message::Payload::Error(e)) }]
                if e.seq == 5 && e.message.contains("end of the recording r")),
            "{replies:?}"
        );
        assert!(session.served.exhausted);
    }

    #[test]
    fn differing_commands_are_counted_and_still_accepted() {
        let replay = Replay::new(lockstep_recording(), "r", false);
        let mut session = Session::new(&replay);
        assert_eq!(
            session.on_message(&pb::ClientMessage::move_(1, 0.5, 0.0)),
            (vec![], false)
        );
        assert_eq!(session.served.differing, 1);
        let (replies, _) = session.on_message(&pb::ClientMessage::barrier(2));
        assert_eq!(replies, vec![InvalidCommand::MissingPayload.reply(2)]);
        assert_eq!(
            session.served.differing, 2,
            "a barrier where an advance was"
        );
    }

    /// Found by the `recording` fuzz target: NaN is not equal to itself,
    /// so a recorded command with a NaN in it was counted as differing when
    /// the same client sent it again.
    #[test]
    fn a_recorded_command_with_a_nan_is_the_same_when_sent_again() {
        let mut recording = lockstep_recording();
        recording.records[0].frame = Frame::Client(pb::ClientMessage::move_(100, f64::NAN, 0.5));
        let replay = Replay::new(recording, "r", false);
        let mut session = Session::new(&replay);
        session.on_message(&pb::ClientMessage::move_(1, f64::NAN, 0.5));
        assert_eq!(session.served.differing, 0);
        session.on_message(&pb::ClientMessage::move_(2, 0.0, 0.5));
        assert_eq!(session.served.differing, 1);
    }

    #[test]
    fn observer_recordings_count_states_as_the_client_s_latest() {
        let mut recording = lockstep_recording();
        recording.header.commands = false;
        recording
            .records
            .retain(|r| matches!(r.frame, Frame::World(_)));
        let replay = Replay::new(recording, "r", false);
        let mut session = Session::new(&replay);
        let (replies, _) = session.on_message(&pb::ClientMessage::advance(77));
        assert_eq!(applied(&replies), vec![77]);
        assert_eq!(session.served.differing, 0, "nothing to compare with");
    }
}
