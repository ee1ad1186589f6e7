//! Reuse of simulated runs in lock-step mode, with or without latency
//! emulation.
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
//! With latency emulation a reset does not restart the stream: the world's
//! delay generator keeps drawing across resets, so a reset batch alone is no
//! root. `SimControl.latency_seed` restarts the generator, and the driver
//! sends one at the end of every job's first batch (`super::link`), before
//! the reset of its start-up; from the seed on the world is again a function
//! of the batches. A root is then a batch that holds a latency seed and a
//! reset preceded by an actuator command, so that neither the bodies nor the
//! generator remember anything from before it: the job's first batch when
//! it also carries the previous job's closing reset, or else the seed
//! joined to the start-up's reset batch that follows it (sending the two in
//! one interval gives the same frame, since the reset wipes what the first
//! batch did to the bodies; re-sending such a root reseeds a world brought
//! back by replay). Everything after the root, resets included, is a path
//! of batches.
//!
//! [`RunCache`] stores these streams as a tree (a trie over command batches,
//! shared by all workers of an experiment, and by experiments given the
//! same cache). A link that follows a branch
//! already in the tree hands the stored frames to its driver without
//! touching the socket; at the first batch the tree does not know, it brings
//! its world to that point (the root batch and the branch's batches are sent
//! again, and every frame the world produces on the way must equal the stored
//! one bit for bit, else the experiment stops with
//! [`RunCacheError::Diverged`]), and from there simulates and records.
//!
//! In the push task the actuator's action during a run does not depend on
//! the model, so a run is determined by its start (and, with latency
//! emulation, by its job's seed): without latency the 21 test runs are
//! simulated once per experiment, and a training run once however many
//! models replay it; with latency, where every job has its own seed, a job
//! is simulated once however many models run it. Anything else that would
//! make the stream depend on more than the batches — pausing, or a latency
//! seed sent to a world without latency emulation — switches the link back
//! to plain live operation for the rest of its life.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use learner::Frame;

use pushlearn::wire::pb::client_message::Payload;
use pushlearn::wire::pb::sim_control::Action;

/// Why replaying stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunCacheError {
    /// A world produced a different frame for the same commands since a
    /// root (a reset; with latency emulation a latency seed and a reset)
    /// than the one recorded: the world is not deterministic, and the
    /// experiment must run without reuse (`--no-reuse`).
    #[error(
        "the world produced a different state for the same commands since its reset \
         ({step} states after the reset batch): it is not deterministic; run with --no-reuse"
    )]
    Diverged { step: usize },
}

/// How a node was reached: a root (rate in force and the reset batch, see
/// the module docs) or a batch sent after its parent's frame.
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
    /// for the same edge meanwhile; the node, and whether it is new.
    fn insert(&mut self, edge: Edge, frame: Arc<Frame>) -> Result<(usize, bool), RunCacheError> {
        let existing = match &edge {
            Edge::Root { rate, batch } => self.root(*rate, batch),
            Edge::Child { parent, batch } => self.child(*parent, batch),
        };
        if let Some(n) = existing {
            return if *self.nodes[n].frame == *frame {
                Ok((n, false))
            } else {
                Err(RunCacheError::Diverged {
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
        Ok((n, true))
    }

    /// Makes `nodes` (and so everything recorded after them) unreachable:
    /// no lookup finds them again, and their edges are simulated afresh.
    /// They stay in the arena, so that a link standing on one of them (or
    /// below) can still walk its path back to the root.
    fn withdraw(&mut self, nodes: &[usize]) {
        for &n in nodes {
            match self.nodes[n].edge {
                Edge::Root { .. } => self.roots.retain(|&r| r != n),
                Edge::Child { parent, .. } => self.nodes[parent].children.retain(|&c| c != n),
            }
        }
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
#[derive(Debug)]
pub struct RunCache {
    tree: Mutex<Tree>,
    replayed: AtomicU64,
    simulated: AtomicU64,
    /// Unique in this process: worker processes keep one cache of their
    /// own per cache of the experiment's ([`crate::experiment::processes`]).
    id: u64,
}

impl Default for RunCache {
    fn default() -> Self {
        static NEXT_ID: AtomicU64 = AtomicU64::new(0);
        Self {
            tree: Mutex::default(),
            replayed: AtomicU64::new(0),
            simulated: AtomicU64::new(0),
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        }
    }
}

/// How many world states a cache served from memory and how many the worlds
/// simulated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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

    /// Which cache this is, among this process's.
    #[must_use]
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Counts what a worker process's copy of this cache did for a job
    /// ([`crate::experiment::processes`]), so that [`Self::counts`] covers
    /// the experiment's states wherever they were simulated.
    pub fn count_elsewhere(&self, counts: CacheCounts) {
        self.replayed.fetch_add(counts.replayed, Ordering::Relaxed);
        self.simulated
            .fetch_add(counts.simulated, Ordering::Relaxed);
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
    /// batches since a root.
    live_only: bool,
    /// The world emulates latency: roots need a latency seed.
    latency: bool,
    /// The latency seed the driver's last batch ended with, which the next
    /// reset batch joins to make a root.
    seed: Option<Payload>,
    /// The nodes this link added since its job started
    /// ([`Cursor::withdraw_job`]).
    recorded: Vec<usize>,
}

/// A batch that makes the following stream independent of what came before:
/// it resets the world after setting the actuator command (the only body
/// state a reset keeps), and neither pauses nor touches latency emulation.
fn is_root(batch: &[Payload]) -> bool {
    let reset = batch.iter().position(is_reset);
    let actuator = batch.iter().position(|p| matches!(p, Payload::Actuator(_)));
    matches!((actuator, reset), (Some(a), Some(r)) if a < r)
}

/// [`is_root`] for a world with latency emulation: the batch also restarts
/// the delay generator, and after its last reset it holds nothing whose
/// delay the commands before the seed could shift (only seeds and rates).
fn is_seeded_root(batch: &[Payload]) -> bool {
    let after_reset = batch
        .iter()
        .rposition(is_reset)
        .map_or(&[][..], |r| &batch[r + 1..]);
    is_root(batch)
        && batch.iter().any(is_seed)
        && after_reset.iter().all(|p| is_seed(p) || is_rate(p))
}

fn is_reset(p: &Payload) -> bool {
    matches!(p, Payload::Control(c) if matches!(c.action, Some(Action::Reset(true))))
}

fn is_rate(p: &Payload) -> bool {
    matches!(p, Payload::Control(c) if matches!(c.action, Some(Action::PublishRateHz(_))))
}

fn is_seed(p: &Payload) -> bool {
    matches!(p, Payload::Control(c) if matches!(c.action, Some(Action::LatencySeed(_))))
}

/// A batch whose effect outlives a root in a way the tree does not track:
/// a pause, or a latency seed where there is no latency emulation (the
/// world refuses it, and the stream no longer follows the batches).
fn leaves_the_tree(batch: &[Payload], latency: bool) -> bool {
    batch.iter().any(|p| {
        matches!(p, Payload::Control(c) if matches!(c.action, Some(Action::Pause(_))))
            || (!latency && is_seed(p))
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
    /// Hello's), with latency emulation if `latency`.
    pub(crate) fn new(cache: Arc<RunCache>, rate: u32, latency: bool) -> Self {
        Self {
            cache,
            at: None,
            recording: None,
            rate,
            real_rate: rate,
            real_at: None,
            live_only: false,
            latency,
            seed: None,
            recorded: Vec::new(),
        }
    }

    /// A job starts: what it records from now on is withdrawn if it fails.
    pub(crate) fn start_job(&mut self) {
        self.recorded.clear();
    }

    /// The job failed: the states it recorded are taken out of the cache
    /// (a later job simulates them again), and this link no longer assumes
    /// its world is anywhere in the tree.
    pub(crate) fn withdraw_job(&mut self) {
        let recorded = std::mem::take(&mut self.recorded);
        if !recorded.is_empty() {
            tracing::debug!(
                states = recorded.len(),
                "withdrawing a failed job's recording"
            );
            self.cache.tree().withdraw(&recorded);
        }
        self.at = None;
        self.real_at = None;
        self.recording = None;
    }

    /// The root `batch` starts, if any: the batch itself, or with latency
    /// emulation also the seed the last batch ended with joined to it.
    fn root_of(&self, seed: Option<Payload>, batch: &[Payload]) -> Option<Vec<Payload>> {
        if !self.latency {
            return is_root(batch).then(|| batch.to_vec());
        }
        if is_seeded_root(batch) {
            return Some(batch.to_vec());
        }
        let joined: Vec<Payload> = seed.into_iter().chain(batch.iter().cloned()).collect();
        is_seeded_root(&joined).then_some(joined)
    }

    /// The next state of the driver's stream after it sent `batch`.
    pub(crate) fn next(&mut self, batch: Vec<Payload>) -> Next {
        let rate = self.rate;
        self.rate = rate_after(rate, &batch);
        let last_seed = batch.last().filter(|p| self.latency && is_seed(p)).cloned();
        let seed = std::mem::replace(&mut self.seed, last_seed);
        if self.live_only || leaves_the_tree(&batch, self.latency) {
            self.live_only = true;
            let resync = self.resync_to(self.at);
            self.at = None;
            self.recording = None;
            return Next::Simulate { resync, batch };
        }
        if let Some(root) = self.root_of(seed, &batch) {
            let found = self.cache.tree().root(rate, &root);
            if let Some(n) = found {
                return self.stored(n);
            }
            // A root needs no resynchronisation, only the same rate; the world
            // gets the root batch, so a joined seed reseeds a world whose
            // last batches were replayed.
            let resync = (self.real_rate != rate).then(|| Path {
                rate: Some(rate),
                first_step: 0,
                steps: Vec::new(),
            });
            self.recording = Some(Edge::Root {
                rate,
                batch: root.clone(),
            });
            return Next::Simulate {
                resync,
                batch: root,
            };
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
    pub(crate) fn simulated(&mut self, frame: Frame) -> Result<Arc<Frame>, RunCacheError> {
        self.cache.simulated.fetch_add(1, Ordering::Relaxed);
        let frame = Arc::new(frame);
        match self.recording.take() {
            Some(edge) => {
                let (n, new) = self.cache.tree().insert(edge, Arc::clone(&frame))?;
                if new {
                    self.recorded.push(n);
                }
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
            shape: None,
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
        assert!(leaves_the_tree(&[Payload::latency_seed(3)], false));
        assert!(!leaves_the_tree(&[Payload::latency_seed(3)], true));
        assert!(leaves_the_tree(&[Payload::pause()], true));
        assert!(!leaves_the_tree(&reset_batch(), false));
    }

    #[test]
    fn a_second_link_replays_what_the_first_recorded_and_resyncs_to_branch() {
        let cache = Arc::new(RunCache::new());
        let mut first = Cursor::new(Arc::clone(&cache), 100, false);
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

        let mut second = Cursor::new(Arc::clone(&cache), 100, false);
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
        let mut leader = Cursor::new(Arc::clone(&cache), 100, false);
        let mut follower = Cursor::new(Arc::clone(&cache), 100, false);
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
        let mut a = Cursor::new(Arc::clone(&cache), 100, false);
        let mut b = Cursor::new(Arc::clone(&cache), 100, false);
        // Both miss the same root at once (two workers), then report.
        for c in [&mut a, &mut b] {
            assert!(matches!(c.next(reset_batch()), Next::Simulate { .. }));
        }
        a.simulated(frame(0.0)).expect("first record");
        assert_eq!(
            b.simulated(frame(0.001)),
            Err(RunCacheError::Diverged { step: 0 })
        );
    }

    /// The start-up batch every driver sends after its first state.
    fn startup() -> Vec<Payload> {
        vec![
            Payload::publish_rate(100),
            Payload::move_(0.0, 0.0),
            Payload::reset(),
        ]
    }

    fn joined(seed: u64) -> Vec<Payload> {
        let mut batch = vec![Payload::latency_seed(seed)];
        batch.extend(startup());
        batch
    }

    #[test]
    fn seeded_roots_restart_both_the_bodies_and_the_delays() {
        assert!(is_seeded_root(&joined(7)));
        // The previous job's closing reset, then the next job's seed.
        let mut closing = reset_batch();
        closing.push(Payload::latency_seed(7));
        assert!(is_seeded_root(&closing));
        assert!(!is_seeded_root(&reset_batch()));
        assert!(!is_seeded_root(&[Payload::latency_seed(7)]));
        // A Move after the reset would be applied at an offset that the
        // commands before the seed drew.
        closing.push(Payload::move_(1.0, 0.0));
        assert!(!is_seeded_root(&closing));
    }

    /// A job's first batch is the seed alone on a fresh link: live, and the
    /// start-up's reset batch joined to it is the root. Later resets are
    /// batches on the path, since the delays keep drawing across them.
    #[test]
    fn a_jitter_root_is_the_seed_and_its_path_runs_through_resets() {
        let cache = Arc::new(RunCache::new());
        let mut first = Cursor::new(Arc::clone(&cache), 100, true);
        // Before any seed even a reset batch is no root: the delays are unknown.
        assert!(simulate(&mut first, reset_batch(), 9.0).is_none());
        assert!(simulate(&mut first, vec![Payload::latency_seed(7)], 8.0).is_none());
        assert!(cache.tree().roots.is_empty());
        let Next::Simulate {
            resync: None,
            batch,
        } = first.next(startup())
        else {
            panic!("expected a simulation of a new root");
        };
        // The world gets the seed again with the reset.
        assert_eq!(batch, joined(7));
        first.sent(&batch);
        first.simulated(frame(0.0)).expect("record");
        let run = [
            vec![Payload::move_(1.0, 0.0)],
            reset_batch(),
            vec![Payload::set_pose("actuator", [0.1, 0.0, 0.03], 0.0)],
            vec![Payload::move_(1.0, 0.0)],
        ];
        for (i, b) in run.iter().enumerate() {
            simulate(&mut first, b.clone(), 0.1 * (i + 1) as f64);
        }
        {
            let tree = cache.tree();
            assert_eq!(tree.roots.len(), 1);
            assert_eq!(tree.depth(tree.nodes.len() - 1), run.len());
        }

        // The same job on a link that ran another job before: its first
        // batch also carries the previous job's closing reset, a root of
        // its own; then the joined root and the whole path are replayed.
        let mut second = Cursor::new(Arc::clone(&cache), 100, true);
        let mut closing = reset_batch();
        closing.push(Payload::latency_seed(7));
        assert!(simulate(&mut second, closing, 5.0).is_none());
        assert_eq!(stored(&mut second, startup()), frame(0.0));
        for (i, b) in run.iter().enumerate() {
            assert_eq!(stored(&mut second, b.clone()), frame(0.1 * (i + 1) as f64));
        }
        // A new branch: the world is brought there from the joined root,
        // which reseeds it.
        let Next::Simulate {
            resync: Some(path), ..
        } = second.next(vec![Payload::move_(0.5, 0.0)])
        else {
            panic!("expected a resynchronised simulation");
        };
        assert_eq!((path.rate, path.first_step), (Some(100), 0));
        assert_eq!(path.steps.len(), 1 + run.len());
        assert_eq!(path.steps[0].0, joined(7));
        assert_eq!(
            cache.counts(),
            CacheCounts {
                replayed: 1 + run.len() as u64,
                simulated: 3 + run.len() as u64 + 1
            }
        );
    }

    #[test]
    fn a_different_seed_is_a_different_root_and_divergence_is_still_checked() {
        let cache = Arc::new(RunCache::new());
        let mut a = Cursor::new(Arc::clone(&cache), 100, true);
        simulate(&mut a, vec![Payload::latency_seed(7)], 8.0);
        simulate(&mut a, startup(), 0.0);
        simulate(&mut a, vec![Payload::move_(1.0, 0.0)], 0.1);

        let mut b = Cursor::new(Arc::clone(&cache), 100, true);
        simulate(&mut b, vec![Payload::latency_seed(8)], 8.0);
        assert!(simulate(&mut b, startup(), 0.0).is_none());
        assert_eq!(cache.tree().roots.len(), 2);
        assert_eq!(cache.counts().replayed, 0);

        // Seed 7 again on two links at once, and one world moves
        // differently: divergence.
        let mut c = Cursor::new(Arc::clone(&cache), 100, true);
        simulate(&mut c, vec![Payload::latency_seed(7)], 8.0);
        assert_eq!(stored(&mut c, startup()), frame(0.0));
        assert_eq!(stored(&mut c, vec![Payload::move_(1.0, 0.0)]), frame(0.1));
        for cursor in [&mut a, &mut c] {
            assert!(matches!(
                cursor.next(vec![Payload::move_(2.0, 0.0)]),
                Next::Simulate { .. }
            ));
        }
        a.simulated(frame(0.2)).expect("first record");
        assert_eq!(
            c.simulated(frame(0.25)),
            Err(RunCacheError::Diverged { step: 2 })
        );
    }

    /// A job whose world died half-way: what it recorded is withdrawn, so
    /// the next link simulates those states again instead of replaying them;
    /// what other jobs recorded before stays.
    #[test]
    fn a_failed_jobs_recording_is_withdrawn() {
        let cache = Arc::new(RunCache::new());
        let push = |x: f64| vec![Payload::move_(x, 0.0)];
        let mut done = Cursor::new(Arc::clone(&cache), 100, false);
        done.start_job();
        simulate(&mut done, reset_batch(), 0.0);
        simulate(&mut done, push(1.0), 0.1);

        let mut dying = Cursor::new(Arc::clone(&cache), 100, false);
        dying.start_job();
        assert_eq!(stored(&mut dying, reset_batch()), frame(0.0));
        assert_eq!(stored(&mut dying, push(1.0)), frame(0.1));
        simulate(&mut dying, push(2.0), 0.2);
        simulate(&mut dying, push(3.0), 0.3);
        // Its world dies before the next state arrives.
        assert!(matches!(dying.next(push(4.0)), Next::Simulate { .. }));
        dying.withdraw_job();

        let mut retry = Cursor::new(Arc::clone(&cache), 100, false);
        retry.start_job();
        assert_eq!(stored(&mut retry, reset_batch()), frame(0.0));
        assert_eq!(stored(&mut retry, push(1.0)), frame(0.1));
        // The dead world's states are not served: the world is brought to
        // the last kept state and simulates on from there.
        let resync = simulate(&mut retry, push(2.0), 0.2).expect("a resync to the kept state");
        assert_eq!(resync.steps.len(), 2);
        assert!(simulate(&mut retry, push(3.0), 0.3).is_none());
        assert_eq!(cache.counts().replayed, 4);
    }

    #[test]
    fn pausing_or_latency_seeds_switch_to_live_for_good() {
        let cache = Arc::new(RunCache::new());
        let mut c = Cursor::new(Arc::clone(&cache), 100, false);
        simulate(&mut c, reset_batch(), 0.0);
        simulate(&mut c, vec![Payload::latency_seed(1)], 0.1);
        // Even a known root is simulated now.
        simulate(&mut c, reset_batch(), 0.0);
        assert_eq!(cache.counts().replayed, 0);
    }
}
