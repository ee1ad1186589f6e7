//! The chains the oracles have stepped in this process, kept so that a
//! chain asked for again is not stepped again.
//!
//! An oracle's chain from a shown state is a pure function of the oracle's
//! world (scene, publish rate, latency hypotheses), the state shown and the
//! actions since: a copy is reset before it is shown a state (its bodies,
//! counters and ODE's generator), and the world is deterministic. The push
//! task asks for the same chains over and over — its 21 test runs start from
//! the same states in every fold and for every number of training runs, and
//! an oracle learns nothing — so the chains are a tree: a root per
//! (oracle, shown state), a child per action. A prediction found in the tree
//! is the one the copies would have produced, bit for bit; a test keeps it so.
//!
//! Oracles whose chains depend on more than their actions (the oracle told
//! each Move's delay by the harness, when the world has latency emulation)
//! do not use it: their chains repeat too rarely to be worth the memory.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, MutexGuard, PoisonError};

use learner::features::is_skipped;
use learner::{Action, Frame};

use super::OracleWorld;

/// How many predictions the tree holds at most; past it, chains are stepped
/// and not kept (what is kept stays valid). About 1 KiB each.
const CAPACITY: usize = 200_000;

/// One step of a chain: the action's bits and the delay the copy was told
/// (0 for the oracle that ignores it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct StepKey {
    action: [u64; 2],
    delay: u32,
}

impl StepKey {
    pub(super) fn of(action: Action, delay: u32) -> Self {
        StepKey {
            action: [action.vx.to_bits(), action.vy.to_bits()],
            delay,
        }
    }

    pub(super) fn action(self) -> Action {
        Action::new(
            f64::from_bits(self.action[0]),
            f64::from_bits(self.action[1]),
        )
    }

    pub(super) fn delay(self) -> u32 {
        self.delay
    }
}

/// A node of the tree: a chain's root (a shown state) or one step from
/// its parent.
enum Node {
    Root(Frame),
    Step {
        parent: u64,
        step: StepKey,
        world: OracleWorld,
    },
}

#[derive(Default)]
struct Tree {
    /// By (oracle, the shown state written out exactly).
    roots: HashMap<(Arc<str>, String), u64>,
    children: HashMap<(u64, StepKey), u64>,
    nodes: HashMap<u64, Node>,
}

static TREE: LazyLock<Mutex<Tree>> = LazyLock::new(Mutex::default);
/// Node ids: never 0 (a copy that holds no node).
static NEXT: AtomicU64 = AtomicU64::new(1);

fn tree() -> MutexGuard<'static, Tree> {
    TREE.lock().unwrap_or_else(PoisonError::into_inner)
}

fn next_id() -> u64 {
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// The root of the chains of `oracle` (its key) from the shown `frame`.
pub(super) fn root(oracle: &Arc<str>, frame: &Frame) -> u64 {
    // What the copies are shown: the bodies a learner does not skip (not
    // the ground, nor the ghosts of earlier predictions). Debug prints every
    // f64 in its shortest exact form: equal strings are equal states.
    let shown: Vec<_> = frame
        .objects
        .iter()
        .filter(|o| !is_skipped(&o.name))
        .collect();
    let key = (Arc::clone(oracle), format!("{shown:?}"));
    let mut tree = tree();
    if let Some(&id) = tree.roots.get(&key) {
        return id;
    }
    let id = next_id();
    if tree.nodes.len() < CAPACITY {
        tree.nodes.insert(id, Node::Root(frame.clone()));
        tree.roots.insert(key, id);
    }
    id
}

/// The prediction one `step` after node `parent`, if it was stepped before.
pub(super) fn stepped(parent: u64, step: StepKey) -> Option<(u64, OracleWorld)> {
    let tree = tree();
    let id = *tree.children.get(&(parent, step))?;
    match tree.nodes.get(&id)? {
        Node::Step { world, .. } => Some((
            id,
            OracleWorld {
                node: id,
                ..world.clone()
            },
        )),
        Node::Root(_) => None,
    }
}

/// Keeps `world` as the prediction one `step` after `parent`; its node.
pub(super) fn keep(parent: u64, step: StepKey, world: &OracleWorld) -> u64 {
    let id = next_id();
    let mut tree = tree();
    if tree.nodes.len() < CAPACITY && tree.nodes.contains_key(&parent) {
        tree.nodes.insert(
            id,
            Node::Step {
                parent,
                step,
                world: world.clone(),
            },
        );
        tree.children.insert((parent, step), id);
    }
    id
}

/// The shown state node `id`'s chain starts from and the steps from it to
/// `id`; `None` for a node not kept.
pub(super) fn history(id: u64) -> Option<(Frame, Vec<StepKey>)> {
    let tree = tree();
    let mut actions = Vec::new();
    let mut at = id;
    loop {
        match tree.nodes.get(&at)? {
            Node::Root(frame) => {
                actions.reverse();
                return Some((frame.clone(), actions));
            }
            Node::Step { parent, step, .. } => {
                actions.push(*step);
                at = *parent;
            }
        }
    }
}
