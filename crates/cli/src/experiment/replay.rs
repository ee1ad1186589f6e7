//! Reuse of simulated runs in `lockstep` mode.
//!
//! In lock-step without latency emulation the world is a deterministic
//! function of the commands it received since its last reset: `Reset`
//! restores every body, clears the contacts and reseeds QuickStep's random
//! stream (`docs/spec/world.md` §12), and the state that survives a reset — the
//! actuator command and the publish rate — is set by the reset batch itself
//! or tracked here. So the frames a driver sees after a reset batch depend
//! only on
//!
//! * the publish rate in force and the reset batch (a *root*), and
//! * the command batch sent after each frame since.
//!
//! [`RunCache`] stores these streams as a tree (a trie over command batches,
//! shared by all workers of an experiment). A link that follows a branch
//! already in the tree hands the stored frames to its driver without
//! touching the socket; at the first batch the tree does not know, it brings
//! its world to that point (the root batch and the branch's batches are sent
//! again, and every frame the world produces on the way must equal the stored
//! one bit for bit, else the experiment stops with
//! [`ReplayError::Diverged`]), and from there simulates and records.
//!
//! In the push task the actuator's action during a run does not depend on
//! the model, so a run is determined by its start: the 21 test runs are
//! simulated once per experiment, and a training run once however many
//! models replay it. Anything else that would make the stream depend on more
//! than the batches — pausing, latency emulation — switches the link back to
//! plain live operation for the rest of its life.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use learner::Frame;

use pushlearn::wire::pb::client_message::Payload;
use pushlearn::wire::pb::sim_control::Action;

/// Why replaying stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReplayError {
    /// A world produced a different frame for the same commands since a
    /// reset than the one recorded: the world is not deterministic, and the
    /// experiment must run without reuse (`--no-reuse`).
    #[error(
        "the world produced a different state for the same commands since its reset \
         ({step} states after the reset): it is not deterministic; run with --no-reuse"
    )]
    Diverged { step: usize },
}

/// How a node was reached: a root (rate in force and the reset batch) or a
/// batch sent after its parent's frame.
#[derive(Debug)]
enum Edge {
    Root { rate: u32, batch: Vec<Payload> },
    Child { parent: usize, batch: Vec<Payload> },
}

/// One frame of a recorded stream.
#[derive(Debug)]
struct Node {
    edge: Edge,
    frame: Arc<Frame>,
    children: Vec<usize>,
}

#[derive(Debug, Default)]
struct Tree {
    nodes: Vec<Node>,
    roots: Vec<usize>,
}

impl Tree {
    fn root(&self, rate: u32, batch: &[Payload]) -> Option<usize> {
        self.roots.iter().copied().find(|&n| {
            matches!(&self.nodes[n].edge, Edge::Root { rate: r, batch: b } if *r == rate && b == batch)
        })
    }

    fn child(&self, parent: usize, batch: &[Payload]) -> Option<usize> {
        self.nodes[parent]
            .children
            .iter()
            .copied()
            .find(|&n| matches!(&self.nodes[n].edge, Edge::Child { batch: b, .. } if b == batch))
    }

    /// Adds a frame, or checks it against the one another worker recorded
    /// for the same edge meanwhile.
    fn insert(&mut self, edge: Edge, frame: Arc<Frame>) -> Result<usize, ReplayError> {
        let existing = match &edge {
            Edge::Root { rate, batch } => self.root(*rate, batch),
            Edge::Child { parent, batch } => self.child(*parent, batch),
        };
        if let Some(n) = existing {
            return if *self.nodes[n].frame == *frame {
                Ok(n)
            } else {
                Err(ReplayError::Diverged {
                    step: self.depth(n),
                })
            };
        }
        let n = self.nodes.len();
        match &edge {
            Edge::Root { .. } => self.roots.push(n),
            Edge::Child { parent, .. } => self.nodes[*parent].children.push(n),
        }
        self.nodes.push(Node {
            edge,
            frame,
            children: Vec::new(),
        });
        Ok(n)
    }

    fn depth(&self, mut n: usize) -> usize {
        let mut depth = 0;
        while let Edge::Child { parent, .. } = &self.nodes[n].edge {
            n = *parent;
            depth += 1;
        }
        depth
    }

    /// The way to bring a world that produced the frame of `from` (or any
    /// other) to node `to`. When `from` is an ancestor of `to` only the
    /// batches after it are needed: a link that replays what another link is
    /// recording meets the recording's end again and again, and sending the
    /// whole run from its reset each time would cost the square of the run's
    /// length. Otherwise the way starts at the root: its rate and reset batch.
    fn path(&self, from: Option<usize>, to: usize) -> Path {
        let mut steps = Vec::new();
        let mut n = to;
        loop {
            if Some(n) == from {
                steps.reverse();
                return Path {
                    rate: None,
                    first_step: self.depth(n) + 1,
                    steps,
                };
            }
            let node = &self.nodes[n];
            steps.push((node.edge.batch().to_vec(), Arc::clone(&node.frame)));
            match &node.edge {
                Edge::Child { parent, .. } => n = *parent,
                Edge::Root { rate, .. } => {
                    steps.reverse();
                    return Path {
                        rate: Some(*rate),
                        first_step: 0,
                        steps,
                    };
                }
            }
        }
    }
}

impl Edge {
    fn batch(&self) -> &[Payload] {
        match self {
            Edge::Root { batch, .. } | Edge::Child { batch, .. } => batch,
        }
    }
}

/// See [`Tree::path`].
pub(crate) struct Path {
    /// The publish rate to set first; `None` when the path continues from
    /// the frame the world produced last, whose rate is still in force.
    pub(crate) rate: Option<u32>,
    /// How many states after the reset the first step's frame is.
    pub(crate) first_step: usize,
    /// Batch to send, frame it must produce; from the root's when `rate` is
    /// given.
    pub(crate) steps: Vec<(Vec<Payload>, Arc<Frame>)>,
}

/// Recorded world streams shared by the workers of one experiment (see the
/// module docs).
#[derive(Debug, Default)]
pub struct RunCache {
    tree: Mutex<Tree>,
    replayed: AtomicU64,
    simulated: AtomicU64,
}

/// How many world states a cache served from memory and how many the worlds
/// simulated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheCounts {
    pub replayed: u64,
    pub simulated: u64,
}

impl RunCache {
    /// An empty cache.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// States served from memory and states simulated so far.
    #[must_use]
    pub fn counts(&self) -> CacheCounts {
        CacheCounts {
            replayed: self.replayed.load(Ordering::Relaxed),
            simulated: self.simulated.load(Ordering::Relaxed),
        }
    }

    fn tree(&self) -> std::sync::MutexGuard<'_, Tree> {
        self.tree.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// What a link must do for the next state (see [`Cursor::next`]).
pub(crate) enum Next {
    /// Hand this stored frame to the driver; send nothing.
    Stored(Arc<Frame>),
    /// Bring the world to a recorded point first (when `resync` is given),
    /// then send `batch`, advance, and report the state with
    /// [`Cursor::simulated`].
    Simulate {
        resync: Option<Path>,
        batch: Vec<Payload>,
    },
}

/// One link's place in a [`RunCache`]: where the stream its driver sees is,
/// and where its real world is.
#[derive(Debug)]
pub(crate) struct Cursor {
    cache: Arc<RunCache>,
    /// The node of the last frame handed to the driver; `None` outside the
    /// tree (then the real world has received every batch).
    at: Option<usize>,
    /// The edge the next simulated frame is recorded under.
    recording: Option<Edge>,
    /// Publish rate in force in the driver's stream.
    rate: u32,
    /// Publish rate in force on the real world.
    real_rate: u32,
    /// The node whose frame the real world produced last, nothing sent since.
    real_at: Option<usize>,
    /// Set for good once a batch made the stream depend on more than the
    /// batches since a reset.
    live_only: bool,
}

/// A batch that makes the following stream independent of what came before:
/// it resets the world after setting the actuator command (the only body
/// state a reset keeps), and neither pauses nor touches latency emulation.
fn is_root(batch: &[Payload]) -> bool {
    let reset = batch.iter().position(
        |p| matches!(p, Payload::Control(c) if matches!(c.action, Some(Action::Reset(true)))),
    );
    let actuator = batch.iter().position(|p| matches!(p, Payload::Actuator(_)));
    matches!((actuator, reset), (Some(a), Some(r)) if a < r)
}

/// A batch whose effect outlives a reset in a way the tree does not track.
fn leaves_the_tree(batch: &[Payload]) -> bool {
    batch.iter().any(|p| {
        matches!(p, Payload::Control(c)
            if matches!(c.action, Some(Action::Pause(_) | Action::LatencySeed(_))))
    })
}

/// The publish rate after `batch`, starting from `rate`.
fn rate_after(rate: u32, batch: &[Payload]) -> u32 {
    batch.iter().fold(rate, |rate, p| match p {
        Payload::Control(c) => match c.action {
            Some(Action::PublishRateHz(hz)) => hz,
            _ => rate,
        },
        _ => rate,
    })
}

impl Cursor {
    /// A cursor for a connection to a world publishing at `rate` (its
    /// Hello's).
    pub(crate) fn new(cache: Arc<RunCache>, rate: u32) -> Self {
        Self {
            cache,
            at: None,
            recording: None,
            rate,
            real_rate: rate,
            real_at: None,
            live_only: false,
        }
    }

    /// The next state of the driver's stream after it sent `batch`.
    pub(crate) fn next(&mut self, batch: Vec<Payload>) -> Next {
        let rate = self.rate;
        self.rate = rate_after(rate, &batch);
        if self.live_only || leaves_the_tree(&batch) {
            self.live_only = true;
            let resync = self.resync_to(self.at);
            self.at = None;
            self.recording = None;
            return Next::Simulate { resync, batch };
        }
        if is_root(&batch) {
            let found = self.cache.tree().root(rate, &batch);
            if let Some(n) = found {
                return self.stored(n);
            }
            // A reset needs no resynchronisation, only the same rate.
            let resync = (self.real_rate != rate).then(|| Path {
                rate: Some(rate),
                first_step: 0,
                steps: Vec::new(),
            });
            self.recording = Some(Edge::Root {
                rate,
                batch: batch.clone(),
            });
            return Next::Simulate { resync, batch };
        }
        let Some(at) = self.at else {
            self.recording = None;
            return Next::Simulate {
                resync: None,
                batch,
            };
        };
        let found = self.cache.tree().child(at, &batch);
        if let Some(n) = found {
            return self.stored(n);
        }
        let resync = self.resync_to(Some(at));
        self.recording = Some(Edge::Child {
            parent: at,
            batch: batch.clone(),
        });
        Next::Simulate { resync, batch }
    }

    fn stored(&mut self, n: usize) -> Next {
        self.at = Some(n);
        self.cache.replayed.fetch_add(1, Ordering::Relaxed);
        Next::Stored(Arc::clone(&self.cache.tree().nodes[n].frame))
    }

    /// The way to bring the real world to node `to`, if it is not there.
    fn resync_to(&self, to: Option<usize>) -> Option<Path> {
        let to = to?;
        (self.real_at != Some(to)).then(|| self.cache.tree().path(self.real_at, to))
    }

    /// Whether the real world must be told `rate` before a resync path.
    pub(crate) fn needs_rate(&self, rate: u32) -> bool {
        self.real_rate != rate
    }

    /// Records that the real world received `batch` (resynchronisation
    /// included) — for its publish rate.
    pub(crate) fn sent(&mut self, batch: &[Payload]) {
        self.real_rate = rate_after(self.real_rate, batch);
    }

    /// Counts a state the real world produced again to resynchronise.
    pub(crate) fn resimulated(&self) {
        self.cache.simulated.fetch_add(1, Ordering::Relaxed);
    }

    /// The frame the real world produced for the batch of the last
    /// [`Next::Simulate`]; recorded if the stream is inside the tree.
    pub(crate) fn simulated(&mut self, frame: Frame) -> Result<Arc<Frame>, ReplayError> {
        self.cache.simulated.fetch_add(1, Ordering::Relaxed);
        let frame = Arc::new(frame);
        match self.recording.take() {
            Some(edge) => {
                let n = self.cache.tree().insert(edge, Arc::clone(&frame))?;
                self.at = Some(n);
                self.real_at = Some(n);
            }
            None => {
                self.at = None;
                self.real_at = None;
            }
        }
        Ok(frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(x: f64) -> Frame {
        let mut f = Frame::default();
        f.objects.push(learner::Observation {
            name: "actuator".into(),
            id: 8,
            position: [x, 0.0, 0.03],
            orientation: [0.0, 0.0, 0.0, 1.0],
        });
        f
    }

    fn reset_batch() -> Vec<Payload> {
        vec![Payload::move_(0.0, 0.0), Payload::reset()]
    }

    fn simulate(cursor: &mut Cursor, batch: Vec<Payload>, x: f64) -> Option<Path> {
        match cursor.next(batch) {
            Next::Simulate { resync, batch } => {
                cursor.sent(&batch);
                cursor.simulated(frame(x)).expect("record");
                resync
            }
            Next::Stored(_) => panic!("expected a simulation"),
        }
    }

    fn stored(cursor: &mut Cursor, batch: Vec<Payload>) -> Frame {
        match cursor.next(batch) {
            Next::Stored(f) => (*f).clone(),
            Next::Simulate { .. } => panic!("expected a stored frame"),
        }
    }

    #[test]
    fn roots_need_an_actuator_command_before_the_reset() {
        assert!(is_root(&reset_batch()));
        assert!(is_root(&[
            Payload::publish_rate(100),
            Payload::move_(0.0, 0.0),
            Payload::reset()
        ]));
        assert!(!is_root(&[Payload::reset()]));
        assert!(!is_root(&[Payload::reset(), Payload::move_(0.0, 0.0)]));
        assert!(!is_root(&[Payload::move_(0.1, 0.0)]));
        assert!(leaves_the_tree(&[Payload::latency_seed(3)]));
        assert!(!leaves_the_tree(&reset_batch()));
    }

    #[test]
    fn a_second_link_replays_what_the_first_recorded_and_resyncs_to_branch() {
        let cache = Arc::new(RunCache::new());
        let mut first = Cursor::new(Arc::clone(&cache), 100);
        // Start of a job: outside the tree, live.
        assert!(simulate(&mut first, Vec::new(), 9.0).is_none());
        let startup = vec![
            Payload::publish_rate(100),
            Payload::move_(0.0, 0.0),
            Payload::reset(),
        ];
        assert!(simulate(&mut first, startup.clone(), 0.0).is_none());
        assert!(simulate(&mut first, vec![Payload::move_(1.0, 0.0)], 0.1).is_none());
        assert!(simulate(&mut first, vec![Payload::move_(1.0, 0.0)], 0.2).is_none());

        let mut second = Cursor::new(Arc::clone(&cache), 100);
        assert!(simulate(&mut second, Vec::new(), 5.0).is_none());
        assert_eq!(stored(&mut second, startup), frame(0.0));
        assert_eq!(
            stored(&mut second, vec![Payload::move_(1.0, 0.0)]),
            frame(0.1)
        );
        // A new branch: the world must first replay the root and one batch.
        let Next::Simulate {
            resync: Some(path),
            batch,
        } = second.next(vec![Payload::move_(0.5, 0.0)])
        else {
            panic!("expected a resynchronised simulation");
        };
        assert_eq!(path.rate, Some(100));
        assert_eq!(path.first_step, 0);
        assert_eq!(path.steps.len(), 2);
        assert_eq!(*path.steps[1].1, frame(0.1));
        second.sent(&batch);
        second.simulated(frame(0.15)).expect("record");
        assert_eq!(
            cache.counts(),
            CacheCounts {
                replayed: 2,
                simulated: 6
            }
        );
        // A later reset batch without a rate command is a root of its own.
        assert!(simulate(&mut first, reset_batch(), 0.0).is_none());
        assert_eq!(stored(&mut second, reset_batch()), frame(0.0));
    }

    /// Two workers on the same run at once: the follower keeps meeting the
    /// end of the leader's recording, and the leader the follower's. Each
    /// resynchronisation must send only the batches that link's world has
    /// not seen, so each link simulates every state of the run at most once
    /// (whole-run resynchronisations made a CI run simulate 61 % of all
    /// states where the e2e reuse test allows 60 %).
    #[test]
    fn links_overtaking_each_other_resync_only_the_gap() {
        let cache = Arc::new(RunCache::new());
        let mut leader = Cursor::new(Arc::clone(&cache), 100);
        let mut follower = Cursor::new(Arc::clone(&cache), 100);
        let push = |i: u32| vec![Payload::move_(f64::from(i), 0.0)];
        let x = |i: u32| f64::from(i) / 10.0;
        // Sends the resync path and the batch; the path's (rate, first
        // step, length).
        let catch_up = |cursor: &mut Cursor, i: u32| {
            let Next::Simulate {
                resync: Some(path),
                batch,
            } = cursor.next(push(i))
            else {
                panic!("expected a resynchronised simulation at {i}");
            };
            for (batch, _) in &path.steps {
                cursor.sent(batch);
                cursor.resimulated();
            }
            cursor.sent(&batch);
            cursor.simulated(frame(x(i))).expect("record");
            (path.rate, path.first_step, path.steps.len())
        };

        simulate(&mut leader, reset_batch(), 0.0);
        for i in 1..=3 {
            simulate(&mut leader, push(i), x(i));
        }
        // The follower's world has produced nothing of this run: from the
        // reset.
        assert_eq!(stored(&mut follower, reset_batch()), frame(0.0));
        for i in 1..=3 {
            assert_eq!(stored(&mut follower, push(i)), frame(x(i)));
        }
        assert_eq!(catch_up(&mut follower, 4), (Some(100), 0, 4));
        // The leader replays the follower's state 4 and needs only it.
        assert_eq!(stored(&mut leader, push(4)), frame(x(4)));
        assert_eq!(catch_up(&mut leader, 5), (None, 4, 1));
        for i in 6..=7 {
            simulate(&mut leader, push(i), x(i));
        }
        for i in 5..=7 {
            assert_eq!(stored(&mut follower, push(i)), frame(x(i)));
        }
        assert_eq!(catch_up(&mut follower, 8), (None, 5, 3));
        // States 0–7 by the leader, 0–8 by the follower; each once.
        assert_eq!(
            cache.counts(),
            CacheCounts {
                replayed: 1 + 3 + 1 + 3,
                simulated: 8 + 9
            }
        );
    }

    #[test]
    fn a_different_frame_for_a_recorded_edge_is_divergence() {
        let cache = Arc::new(RunCache::new());
        let mut a = Cursor::new(Arc::clone(&cache), 100);
        let mut b = Cursor::new(Arc::clone(&cache), 100);
        // Both miss the same root at once (two workers), then report.
        for c in [&mut a, &mut b] {
            assert!(matches!(c.next(reset_batch()), Next::Simulate { .. }));
        }
        a.simulated(frame(0.0)).expect("first record");
        assert_eq!(
            b.simulated(frame(0.001)),
            Err(ReplayError::Diverged { step: 0 })
        );
    }

    #[test]
    fn pausing_or_latency_seeds_switch_to_live_for_good() {
        let cache = Arc::new(RunCache::new());
        let mut c = Cursor::new(Arc::clone(&cache), 100);
        simulate(&mut c, reset_batch(), 0.0);
        simulate(&mut c, vec![Payload::latency_seed(1)], 0.1);
        // Even a known root is simulated now.
        simulate(&mut c, reset_batch(), 0.0);
        assert_eq!(cache.counts().replayed, 0);
    }
}
