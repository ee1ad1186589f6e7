//! Each client's bounded outgoing queue: the slow-client policy.
//!
//! The physics thread and the connection's reader put messages in; the
//! connection's writer takes them out and writes them to the socket. Putting
//! in never waits, so a client that reads slowly or not at all never stalls
//! the physics, the commanding client or anyone else:
//!
//! * the queue holds up to `capacity` messages (`--client-queue`); a state
//!   arriving at a full queue pushes out the **oldest state** in it, and the
//!   drop is counted (per connection, logged on disconnect, and in
//!   [`Stats::states_dropped`](super::Stats));
//! * replies (`Hello`, `Error`) are never dropped: a client waiting for a
//!   barrier's answer must get it. They may exceed `capacity`, up to twice it;
//! * a client whose queue has stayed full for longer than the slow-client
//!   limit (`--slow-client-timeout`), or whose replies would exceed twice the
//!   capacity, is disconnected ([`Stats::slow_disconnects`](super::Stats)).
//!
//! The queue counts as full from the first state that found it full until
//! the writer next takes a message out.

use std::collections::{BTreeMap, VecDeque};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use pushlearn::wire::pb::{self, server_message};
use tokio::sync::Notify;
use tokio_util::sync::CancellationToken;

use super::gate::ClientId;

/// What became of a message put in the queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Pushed {
    Queued,
    /// Queued, after dropping the oldest state.
    DroppedOldest,
    /// Not queued: the client is too slow and is being disconnected.
    TooSlow,
    /// Not queued: the connection is closing.
    Closed,
}

#[derive(Debug, Default)]
struct Queue {
    items: VecDeque<Arc<pb::ServerMessage>>,
    states_sent: u64,
    states_dropped: u64,
    full_since: Option<Instant>,
    closing: bool,
    too_slow: bool,
}

/// One client's outgoing queue.
#[derive(Debug)]
pub(super) struct Outbox {
    peer: SocketAddr,
    capacity: usize,
    slow_limit: Duration,
    queue: Mutex<Queue>,
    /// Wakes the writer: one waiter, and a wake-up before it waits is kept.
    ready: Notify,
    /// Cancelled to disconnect the client.
    disconnect: CancellationToken,
}

fn is_state(message: &pb::ServerMessage) -> bool {
    matches!(
        message.payload,
        Some(server_message::Payload::WorldState(_))
    )
}

impl Outbox {
    pub fn new(
        peer: SocketAddr,
        capacity: usize,
        slow_limit: Duration,
        disconnect: CancellationToken,
    ) -> Outbox {
        Outbox {
            peer,
            capacity,
            slow_limit,
            queue: Mutex::new(Queue::default()),
            ready: Notify::new(),
            disconnect,
        }
    }

    pub fn peer(&self) -> SocketAddr {
        self.peer
    }

    fn lock(&self) -> MutexGuard<'_, Queue> {
        self.queue.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Queues a published state (see the module docs for a full queue) and
    /// wakes the writer.
    pub fn push_state(&self, state: &Arc<pb::ServerMessage>, now: Instant) -> Pushed {
        let pushed = self.queue_state(state, now);
        self.wake();
        pushed
    }

    /// Wakes the writer for whatever is queued.
    pub fn wake(&self) {
        self.ready.notify_one();
    }

    /// Queues a published state without waking the writer: the caller wakes
    /// it soon after with [`Outbox::wake`] (the physics thread, to wake an
    /// idle writer once for several states).
    pub fn queue_state(&self, state: &Arc<pb::ServerMessage>, now: Instant) -> Pushed {
        let mut queue = self.lock();
        if queue.closing {
            return Pushed::Closed;
        }
        let mut pushed = Pushed::Queued;
        if queue.items.len() >= self.capacity {
            let since = *queue.full_since.get_or_insert(now);
            if now.saturating_duration_since(since) > self.slow_limit {
                return self.give_up(queue);
            }
            if let Some(oldest) = queue.items.iter().position(|m| is_state(m)) {
                queue.items.remove(oldest);
                queue.states_dropped += 1;
                pushed = Pushed::DroppedOldest;
            }
        }
        queue.items.push_back(state.clone());
        pushed
    }

    /// Queues a `Hello` or an `Error`; these are never dropped.
    pub fn push_reply(&self, reply: pb::ServerMessage) -> Pushed {
        let mut queue = self.lock();
        if queue.closing {
            return Pushed::Closed;
        }
        if queue.items.len() >= self.capacity.saturating_mul(2) {
            return self.give_up(queue);
        }
        queue.items.push_back(Arc::new(reply));
        drop(queue);
        self.ready.notify_one();
        Pushed::Queued
    }

    fn give_up(&self, mut queue: MutexGuard<'_, Queue>) -> Pushed {
        queue.closing = true;
        queue.too_slow = true;
        drop(queue);
        self.disconnect.cancel();
        Pushed::TooSlow
    }

    /// Accepts nothing more; the writer sends what is queued, then ends.
    pub fn close(&self) {
        self.lock().closing = true;
        self.ready.notify_one();
    }

    /// The next message to write, or `None` once the queue is closed and
    /// empty.
    pub async fn next(&self) -> Option<Arc<pb::ServerMessage>> {
        loop {
            {
                let mut queue = self.lock();
                if let Some(message) = queue.items.pop_front() {
                    if queue.items.len() < self.capacity {
                        queue.full_since = None;
                    }
                    if is_state(&message) {
                        queue.states_sent += 1;
                    }
                    return Some(message);
                }
                if queue.closing {
                    return None;
                }
            }
            self.ready.notified().await;
        }
    }

    /// Whether the client was disconnected for being too slow.
    pub fn was_too_slow(&self) -> bool {
        self.lock().too_slow
    }

    /// States taken for writing and states dropped so far.
    pub fn counts(&self) -> (u64, u64) {
        let queue = self.lock();
        (queue.states_sent, queue.states_dropped)
    }
}

/// The connected clients' queues, by connection.
#[derive(Debug, Default)]
pub(super) struct Clients {
    inner: Mutex<Registry>,
}

#[derive(Debug, Default)]
struct Registry {
    next_id: ClientId,
    outboxes: BTreeMap<ClientId, Arc<Outbox>>,
}

impl Clients {
    fn lock(&self) -> MutexGuard<'_, Registry> {
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Adds a client; it receives every state published from now on.
    pub fn register(&self, outbox: Arc<Outbox>) -> ClientId {
        let mut registry = self.lock();
        registry.next_id += 1;
        let id = registry.next_id;
        registry.outboxes.insert(id, outbox);
        id
    }

    pub fn unregister(&self, id: ClientId) {
        self.lock().outboxes.remove(&id);
    }

    pub fn get(&self, id: ClientId) -> Option<Arc<Outbox>> {
        self.lock().outboxes.get(&id).cloned()
    }

    /// Runs `f` on every client's queue (`f` must not block: it runs with
    /// the registry locked, on the physics thread).
    pub fn for_each(&self, mut f: impl FnMut(&Outbox)) {
        for outbox in self.lock().outboxes.values() {
            f(outbox);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outbox(capacity: usize, slow_limit: Duration) -> Outbox {
        Outbox::new(
            SocketAddr::from(([127, 0, 0, 1], 1)),
            capacity,
            slow_limit,
            CancellationToken::new(),
        )
    }

    fn state(step: u64) -> Arc<pb::ServerMessage> {
        Arc::new(
            pb::WorldState {
                step,
                ..Default::default()
            }
            .into(),
        )
    }

    fn step_of(message: &pb::ServerMessage) -> Option<u64> {
        match &message.payload {
            Some(server_message::Payload::WorldState(s)) => Some(s.step),
            _ => None,
        }
    }

    #[tokio::test]
    async fn a_full_queue_drops_its_oldest_states_but_never_replies() {
        let out = outbox(3, Duration::from_secs(60));
        let now = Instant::now();
        assert_eq!(
            out.push_reply(pb::ServerMessage::error(
                1,
                pb::error::Kind::Unspecified,
                "x"
            )),
            Pushed::Queued
        );
        assert_eq!(out.push_state(&state(10), now), Pushed::Queued);
        assert_eq!(out.push_state(&state(20), now), Pushed::Queued);
        assert_eq!(out.push_state(&state(30), now), Pushed::DroppedOldest);
        assert_eq!(out.push_state(&state(40), now), Pushed::DroppedOldest);
        assert_eq!(out.counts(), (0, 2));
        let first = out.next().await.expect("the reply");
        assert_eq!(step_of(&first), None, "the error is still first");
        let steps: Vec<_> = [out.next().await, out.next().await]
            .into_iter()
            .map(|m| m.as_deref().and_then(step_of))
            .collect();
        assert_eq!(steps, [Some(30), Some(40)]);
        assert_eq!(out.counts(), (2, 2));
    }

    #[tokio::test]
    async fn staying_full_past_the_limit_disconnects() {
        let limit = Duration::from_millis(100);
        let out = outbox(1, limit);
        let start = Instant::now();
        assert_eq!(out.push_state(&state(10), start), Pushed::Queued);
        assert_eq!(out.push_state(&state(20), start), Pushed::DroppedOldest);
        // Taking a message out ends the full period.
        assert!(out.next().await.is_some());
        let later = start + 2 * limit;
        assert_eq!(out.push_state(&state(30), later), Pushed::Queued);
        assert_eq!(out.push_state(&state(40), later), Pushed::DroppedOldest);
        assert_eq!(
            out.push_state(&state(50), later + limit),
            Pushed::DroppedOldest
        );
        assert!(!out.disconnect.is_cancelled());
        assert_eq!(
            out.push_state(&state(60), later + 2 * limit),
            Pushed::TooSlow
        );
        assert!(out.disconnect.is_cancelled() && out.was_too_slow());
        assert_eq!(
            out.push_reply(pb::ServerMessage::error(
                1,
                pb::error::Kind::Unspecified,
                "x"
            )),
            Pushed::Closed
        );
    }

    #[tokio::test]
    async fn unread_replies_are_bounded_too() {
        let out = outbox(2, Duration::from_secs(60));
        for seq in 1..=4 {
            assert_eq!(
                out.push_reply(pb::ServerMessage::error(
                    seq,
                    pb::error::Kind::Unspecified,
                    "x"
                )),
                Pushed::Queued
            );
        }
        assert_eq!(
            out.push_reply(pb::ServerMessage::error(
                5,
                pb::error::Kind::Unspecified,
                "x"
            )),
            Pushed::TooSlow
        );
    }

    #[tokio::test]
    async fn a_closed_queue_is_drained_then_ends() {
        let out = outbox(4, Duration::from_secs(60));
        assert_eq!(out.push_state(&state(10), Instant::now()), Pushed::Queued);
        out.close();
        assert_eq!(out.push_state(&state(20), Instant::now()), Pushed::Closed);
        assert!(out.next().await.is_some());
        assert!(out.next().await.is_none());
    }
}
