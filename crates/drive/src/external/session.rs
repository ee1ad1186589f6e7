//! One connection to an external learner (`docs/learner-protocol.md`): a
//! child process spoken to on its stdin and stdout, or a learner daemon's
//! TCP socket. Requests go out in the protocol's framing; one-way calls are
//! buffered and leave with the next call that is answered, so a world
//! message costs one round trip.
//!
//! The child's stdin and stdout are the two directions of one Unix socket
//! pair rather than two pipes: a socket has a read timeout, so the driver
//! waits for a reply on its own thread with a deadline. (A reader thread
//! would give pipes a deadline too, at the price of a second wake-up per
//! reply, which on an idle machine doubled the protocol's cost.)
//!
//! Before it sleeps on the socket, the driver polls it without blocking for
//! at most [`SPIN`]: a driver asleep when the reply comes is woken on an
//! idle vCPU, which on the 2-vCPU VM the benchmark runs on (guest halt
//! polling off) costs about 7 µs of a 23 µs round trip
//! (`docs/performance.md` §7). A learner slower than that gains nothing from
//! the spin and would only burn the driver's core, so the driver spins only
//! while the previous reply came within [`SPIN`] of the request.

use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::net::{Shutdown, TcpStream};
use std::os::fd::OwnedFd;
use std::os::unix::net::UnixStream;
use std::os::unix::process::CommandExt;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use bytes::BytesMut;
use tokio_util::codec::Decoder;

use pushlearn::wire::pb::learner::{reply::Answer, request::Call, Reply, Request};
use pushlearn::wire::{encode_frame, FrameDecoder, WireError};

use super::LearnerError;
use crate::process::kill_group;

/// How long the driver polls for a reply before it blocks: a fast learner's
/// reply (its wake-up and a built-in model's work) comes within it; the
/// figures behind the choice are in `docs/performance.md` §7.
pub const SPIN: Duration = Duration::from_micros(50);

/// A read timeout for `left` that stays the same from one read to the
/// next: `left` rounded down to whole milliseconds (exact below one). A
/// read that times out early finds its deadline not passed and reads
/// again; in return, the socket's timeout is set once, not before every
/// read (a `setsockopt` each).
pub fn steady_timeout(left: Duration) -> Duration {
    let ms = Duration::from_millis(1);
    if left < ms {
        left
    } else {
        ms * u32::try_from(left.as_millis()).unwrap_or(u32::MAX)
    }
}

/// Where a learner runs.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Source {
    /// A command line, run by `sh -c`: one child process per connection,
    /// spoken to on its stdin and stdout (its stderr is ours).
    Command(String),
    /// A learner daemon's address: one connection per session.
    Connect(String),
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Source::Command(command) => write!(f, "`{command}`"),
            Source::Connect(addr) => write!(f, "the learner daemon at {addr}"),
        }
    }
}

/// What the reader thread saw.
enum Event {
    Reply(Reply),
    Garbage(WireError),
    Closed,
}

/// The connection and what must be cleaned up.
enum Transport {
    /// `stream` is the driver's end of the child's stdin and stdout.
    Child {
        child: Child,
        stream: UnixStream,
    },
    Socket(TcpStream),
}

impl Transport {
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        match self {
            Transport::Child { stream, .. } => stream.write_all(bytes),
            Transport::Socket(stream) => stream.write_all(bytes),
        }
    }

    /// Reads what is there without waiting; `None`: nothing yet.
    fn try_read(&mut self, chunk: &mut [u8]) -> std::io::Result<Option<usize>> {
        let flags = rustix::net::RecvFlags::DONTWAIT;
        let read = match self {
            Transport::Child { stream, .. } => rustix::net::recv(&*stream, chunk, flags),
            Transport::Socket(stream) => rustix::net::recv(&*stream, chunk, flags),
        };
        match read {
            Ok((n, _)) => Ok(Some(n)),
            Err(e) if e == rustix::io::Errno::AGAIN || e == rustix::io::Errno::INTR => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    /// Reads what is there, waiting at most `timeout` (not zero), which
    /// is set on the socket unless `set` says it is already.
    fn read(
        &mut self,
        chunk: &mut [u8],
        timeout: Duration,
        set: &mut Option<Duration>,
    ) -> std::io::Result<usize> {
        if *set != Some(timeout) {
            match self {
                Transport::Child { stream, .. } => stream.set_read_timeout(Some(timeout))?,
                Transport::Socket(stream) => stream.set_read_timeout(Some(timeout))?,
            }
            *set = Some(timeout);
        }
        match self {
            Transport::Child { stream, .. } => stream.read(chunk),
            Transport::Socket(stream) => stream.read(chunk),
        }
    }
}

/// One learner instance.
pub struct Session {
    transport: Transport,
    decoder: FrameDecoder<Reply>,
    /// Bytes read but not yet decoded.
    buffer: BytesMut,
    next_seq: u64,
    /// Encoded one-way requests not yet written.
    pending: Vec<u8>,
    /// One-way requests since the last answered one: (seq, call name), to
    /// name the call a late Error reply is about.
    unanswered: VecDeque<(u64, &'static str)>,
    timeout: Duration,
    /// A call failed: the learner is not to be trusted with another.
    failed: bool,
    /// The previous reply came within [`SPIN`]: poll for the next one.
    spin: bool,
    /// The socket's read timeout as last set.
    timeout_set: Option<Duration>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("next_seq", &self.next_seq)
            .finish_non_exhaustive()
    }
}

/// The protocol's name of a call, for messages.
pub fn call_name(call: &Call) -> &'static str {
    match call {
        Call::Start(_) => "start",
        Call::NewFold(_) => "new_fold",
        Call::Reset(_) => "reset",
        Call::Update(_) => "update",
        Call::Predict(_) => "predict",
        Call::SetTraining(_) => "set_training",
        Call::SetTarget(_) => "set_target",
        Call::Act(_) => "act",
        Call::GetStats(_) => "get_stats",
        Call::Bye(_) => "bye",
    }
}

/// The protocol's name of an answer, for messages.
fn answer_name(answer: &Answer) -> &'static str {
    match answer {
        Answer::Hello(_) => "hello",
        Answer::Prediction(_) => "prediction",
        Answer::Action(_) => "action",
        Answer::Target(_) => "target",
        Answer::Stats(_) => "stats",
        Answer::Error(_) => "error",
    }
}

/// The answer each answered call expects; `None` for one-way calls.
fn expected_answer(call: &Call) -> Option<&'static str> {
    match call {
        Call::Start(_) => Some("hello"),
        Call::Predict(_) => Some("prediction"),
        Call::SetTarget(_) => Some("target"),
        Call::Act(_) => Some("action"),
        Call::GetStats(_) => Some("stats"),
        Call::NewFold(_)
        | Call::Reset(_)
        | Call::Update(_)
        | Call::SetTraining(_)
        | Call::Bye(_) => None,
    }
}

impl Session {
    /// Starts the learner (a child, or a connection to a daemon).
    ///
    /// # Errors
    /// The command cannot be started or the daemon cannot be reached.
    pub fn open(source: &Source, timeout: Duration) -> Result<Self, LearnerError> {
        let start_error =
            |e: std::io::Error| LearnerError::Start(format!("cannot run {source}: {e}"));
        let transport = match source {
            Source::Command(command) => {
                let (ours, theirs) = UnixStream::pair().map_err(start_error)?;
                let theirs_out = theirs.try_clone().map_err(start_error)?;
                let child = Command::new("sh")
                    .arg("-c")
                    .arg(command)
                    // Its own process group, so that a learner the shell
                    // started as its child is stopped with it (`kill_group`).
                    .process_group(0)
                    .stdin(Stdio::from(OwnedFd::from(theirs)))
                    .stdout(Stdio::from(OwnedFd::from(theirs_out)))
                    .stderr(Stdio::inherit())
                    .spawn()
                    .map_err(start_error)?;
                Transport::Child {
                    child,
                    stream: ours,
                }
            }
            Source::Connect(addr) => {
                let stream = TcpStream::connect(addr).map_err(|e| {
                    LearnerError::Start(format!(
                        "cannot connect to {source}: {e} (is the learner daemon running?)"
                    ))
                })?;
                // Requests are small and each waits for its answer.
                let _ = stream.set_nodelay(true);
                Transport::Socket(stream)
            }
        };
        Ok(Self {
            transport,
            decoder: FrameDecoder::new(),
            buffer: BytesMut::with_capacity(4096),
            next_seq: 1,
            pending: Vec::new(),
            unanswered: VecDeque::new(),
            timeout,
            failed: false,
            spin: true,
            timeout_set: None,
        })
    }

    /// The learner's next reply, or why there is none by `deadline`
    /// (`None`: the deadline passed).
    fn next_event(&mut self, deadline: Instant) -> Option<Event> {
        let mut chunk = [0_u8; 4096];
        let sent = Instant::now();
        let mut spinning = self.spin;
        loop {
            match self.decoder.decode(&mut self.buffer) {
                Ok(Some(reply)) => return Some(Event::Reply(reply)),
                Ok(None) => {}
                Err(err) => return Some(Event::Garbage(err)),
            }
            let now = Instant::now();
            let left = deadline.saturating_duration_since(now);
            if left.is_zero() {
                return None;
            }
            if spinning && now.duration_since(sent) >= SPIN {
                spinning = false;
            }
            let read = if spinning {
                match self.transport.try_read(&mut chunk) {
                    Ok(None) => {
                        // Lets a learner waiting for this core run.
                        std::thread::yield_now();
                        continue;
                    }
                    Ok(Some(n)) => Ok(n),
                    Err(e) => Err(e),
                }
            } else {
                self.transport
                    .read(&mut chunk, steady_timeout(left), &mut self.timeout_set)
            };
            if matches!(read, Ok(n) if n > 0) {
                self.spin = sent.elapsed() < SPIN;
            }
            match read {
                Ok(0) if self.buffer.is_empty() => return Some(Event::Closed),
                Ok(0) => {
                    return Some(Event::Garbage(WireError::Truncated {
                        buffered: self.buffer.len(),
                    }))
                }
                Ok(n) => self.buffer.extend_from_slice(&chunk[..n]),
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return Some(Event::Closed),
            }
        }
    }

    /// Sends `call`. A one-way call is only queued (`Ok(None)`); an answered
    /// one is sent with everything queued and its answer awaited.
    ///
    /// # Errors
    /// The learner failed, hung, exited, answered garbage or the wrong kind,
    /// or reported an error on this or an earlier one-way call.
    pub fn call(&mut self, call: Call) -> Result<Option<Answer>, LearnerError> {
        let result = self.exchange(call);
        self.failed |= result.is_err();
        result
    }

    /// The seq of the latest request.
    pub fn last_seq(&self) -> u64 {
        self.next_seq - 1
    }

    /// Whether a call failed.
    pub fn has_failed(&self) -> bool {
        self.failed
    }

    fn exchange(&mut self, call: Call) -> Result<Option<Answer>, LearnerError> {
        let seq = self.next_seq;
        self.next_seq += 1;
        let name = call_name(&call);
        let expected = expected_answer(&call);
        let frame = encode_frame(&Request {
            seq,
            call: Some(call),
        })
        .map_err(|e| LearnerError::Protocol {
            seq,
            call: name,
            what: format!("cannot encode the request: {e}"),
        })?;
        self.pending.extend_from_slice(&frame);
        let Some(expected) = expected else {
            // An Error the learner sends about it is read with the next
            // answer.
            self.unanswered.push_back((seq, name));
            return Ok(None);
        };
        self.flush(seq, name)?;
        let event =
            self.next_event(Instant::now() + self.timeout)
                .ok_or(LearnerError::Timeout {
                    seq,
                    call: name,
                    after: self.timeout,
                })?;
        let Event::Reply(reply) = event else {
            return Err(self.unexpected(event, seq, name));
        };
        match reply.answer {
            Some(Answer::Error(error)) => Err(self.reported(reply.seq, seq, name, error.message)),
            Some(answer) if reply.seq == seq && answer_name(&answer) == expected => {
                self.unanswered.clear();
                Ok(Some(answer))
            }
            Some(answer) => {
                let one_way = self
                    .unanswered
                    .iter()
                    .find(|(sent, _)| *sent == reply.seq)
                    .map(|(_, call)| *call);
                let what = match one_way {
                    Some(call) => format!(
                        "answered message {} ({call}) with a {} reply, but {call} is one-way and \
                         gets no reply (§3); the driver waited for a {expected} reply to message {seq}",
                        reply.seq,
                        answer_name(&answer),
                    ),
                    None => format!(
                        "answered with a {} reply for message {} (expected a {expected} reply for message {seq})",
                        answer_name(&answer),
                        reply.seq
                    ),
                };
                Err(LearnerError::Protocol {
                    seq,
                    call: name,
                    what,
                })
            }
            None => Err(LearnerError::Protocol {
                seq,
                call: name,
                what: format!("sent a reply without an answer for message {}", reply.seq),
            }),
        }
    }

    /// Writes what is queued.
    fn flush(&mut self, seq: u64, name: &'static str) -> Result<(), LearnerError> {
        let bytes = std::mem::take(&mut self.pending);
        if self.transport.write_all(&bytes).is_err() {
            // A broken pipe: the learner is gone. Why is for the reader to
            // tell (it may have sent an Error first).
            let event = self
                .next_event(Instant::now() + Duration::from_millis(500))
                .unwrap_or(Event::Closed);
            return Err(self.unexpected(event, seq, name));
        }
        Ok(())
    }

    /// The error for an event that is not the awaited answer.
    fn unexpected(&mut self, event: Event, seq: u64, name: &'static str) -> LearnerError {
        match event {
            Event::Reply(Reply {
                seq: failed,
                answer: Some(Answer::Error(error)),
            }) => self.reported(failed, seq, name, error.message),
            Event::Reply(reply) => LearnerError::Protocol {
                seq,
                call: name,
                what: format!(
                    "sent a {} reply for message {}, which needs no answer",
                    reply.answer.as_ref().map_or("empty", answer_name),
                    reply.seq
                ),
            },
            Event::Garbage(err) => LearnerError::Garbage {
                seq,
                call: name,
                what: describe_garbage(&err),
            },
            Event::Closed => LearnerError::Exited {
                seq,
                call: name,
                status: self.exit_status(),
            },
        }
    }

    /// The error for the learner's own Error reply about message `failed`.
    fn reported(&self, failed: u64, seq: u64, name: &'static str, message: String) -> LearnerError {
        let call = if failed == seq {
            name
        } else {
            self.unanswered
                .iter()
                .find(|(s, _)| *s == failed)
                .map_or("an earlier message", |(_, n)| *n)
        };
        LearnerError::Reported {
            seq: failed,
            call,
            message,
        }
    }

    /// How the child ended, once it has (waits briefly).
    fn exit_status(&mut self) -> String {
        let Transport::Child { child, .. } = &mut self.transport else {
            return "the daemon closed the connection".to_owned();
        };
        let deadline = Instant::now() + Duration::from_secs(1);
        loop {
            match child.try_wait() {
                Ok(Some(status)) => return format!("it exited ({status})"),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(10));
                }
                _ => return "it closed its output".to_owned(),
            }
        }
    }
}

/// What a stream that stopped being frames looked like.
fn describe_garbage(err: &WireError) -> String {
    match err {
        WireError::FrameTooLarge { len, .. } => {
            let prefix = u32::try_from(*len).unwrap_or(u32::MAX).to_be_bytes();
            let text: String = prefix
                .iter()
                .map(|&b| {
                    if b.is_ascii_graphic() || b == b' ' {
                        char::from(b)
                    } else {
                        '.'
                    }
                })
                .collect();
            format!(
                "wrote something that is not a frame (a length prefix of {len} bytes, \"{text}\" as text): \
                 does it print to stdout? Its output must be protocol frames only; logs go to stderr"
            )
        }
        other => format!("wrote something that is not a frame: {other}"),
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // A healthy learner is told to go and given a second; one that
        // failed (it may hang) is killed at once.
        if !self.failed {
            let bye = Call::Bye(pushlearn::wire::pb::learner::Bye {});
            if let Ok(frame) = encode_frame(&Request {
                seq: self.next_seq,
                call: Some(bye),
            }) {
                self.pending.extend_from_slice(&frame);
            }
            let bytes = std::mem::take(&mut self.pending);
            let _ = self.transport.write_all(&bytes);
        }
        match &mut self.transport {
            Transport::Child { child, stream } => {
                // The child reads the end of its input.
                let _ = stream.shutdown(Shutdown::Write);
                let deadline = Instant::now() + Duration::from_secs(1);
                loop {
                    match child.try_wait() {
                        Ok(None) if !self.failed && Instant::now() < deadline => {
                            std::thread::sleep(Duration::from_millis(5));
                        }
                        Ok(Some(_)) => break,
                        _ => {
                            kill_group(child);
                            break;
                        }
                    }
                }
            }
            Transport::Socket(stream) => {
                let _ = stream.shutdown(Shutdown::Both);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_timeout_is_whole_milliseconds_never_more_than_what_is_left() {
        let ms = Duration::from_millis;
        assert_eq!(steady_timeout(Duration::from_micros(9_999_990)), ms(9_999));
        assert_eq!(steady_timeout(Duration::from_micros(9_999_001)), ms(9_999));
        assert_eq!(steady_timeout(ms(2)), ms(2));
        assert_eq!(
            steady_timeout(Duration::from_micros(1_999)),
            Duration::from_millis(1)
        );
        // Below a millisecond it is exact, so a deadline is still met.
        assert_eq!(
            steady_timeout(Duration::from_micros(400)),
            Duration::from_micros(400)
        );
        for left in [1_u64, 999, 1_000, 1_001, 123_456_789] {
            let left = Duration::from_micros(left);
            assert!(steady_timeout(left) <= left && !steady_timeout(left).is_zero());
        }
    }
}
