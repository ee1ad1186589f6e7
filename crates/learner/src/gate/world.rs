//! The gate model's world state (`docs/spec/gate-model.md` §1) and its shared block
//! records (§4.1).
//!
//! The original kept objects with identity: the model adopts a world state's
//! own block object as its record the first time it sees the block id, later
//! updates overwrite that object in place, and a prediction passes a block it
//! does not change on as the same object. A prediction chain that starts at
//! the adopting message therefore follows the real block. Rather than
//! emulating this with "live" marks, blocks here *are* shared records
//! ([`Arc`]), so every reader — `predict`, `update`, `poses` for recorded
//! rows and shadows — sees what the original's readers saw, whenever it
//! reads.

use std::fmt;
use std::sync::{Arc, Mutex, PoisonError};

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::types::{ObjectState, Poses, TrackedObject};

/// One block record with identity. Cloning shares the record (as copying a
/// reference did in the original).
#[derive(Clone)]
pub(super) struct SharedBlock {
    /// Never changes: records are keyed by id.
    id: u32,
    /// `(s, s_prev)`.
    cell: Arc<Mutex<(ObjectState, ObjectState)>>,
}

impl SharedBlock {
    pub(super) fn new(o: TrackedObject) -> Self {
        Self {
            id: o.id,
            cell: Arc::new(Mutex::new((o.s, o.s_prev))),
        }
    }

    pub(super) fn id(&self) -> u32 {
        self.id
    }

    /// The record's current values.
    pub(super) fn get(&self) -> TrackedObject {
        // A poisoned lock still holds a valid value: every writer stores a
        // complete pair in one assignment.
        let (s, s_prev) = *self.cell.lock().unwrap_or_else(PoisonError::into_inner);
        TrackedObject {
            id: self.id,
            s,
            s_prev,
        }
    }

    /// `s_prev := s; s := new`, in place (`docs/spec/gate-model.md` §2, §3).
    pub(super) fn advance(&self, new: ObjectState) {
        let mut cell = self.cell.lock().unwrap_or_else(PoisonError::into_inner);
        *cell = (new, cell.0);
    }

    pub(super) fn same_record(&self, other: &SharedBlock) -> bool {
        Arc::ptr_eq(&self.cell, &other.cell)
    }
}

impl fmt::Debug for SharedBlock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.get().fmt(f)
    }
}

/// The model's record of a known block: a [`SharedBlock`] that world states
/// may share, but that is never shared between two models. Cloning a model
/// copies its records (a copied model is a different object, whose records
/// no existing world state holds), and a deserialised model starts with
/// unshared records.
pub(super) struct Record(pub(super) SharedBlock);

impl Clone for Record {
    fn clone(&self) -> Self {
        Self(SharedBlock::new(self.0.get()))
    }
}

impl fmt::Debug for Record {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl Serialize for Record {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.0.get().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Record {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        TrackedObject::deserialize(deserializer).map(|o| Self(SharedBlock::new(o)))
    }
}

/// A world state of the gate model: the actuator and the blocks, each with
/// `s` and `s_prev` (`docs/spec/gate-model.md` §1), parsed or predicted.
///
/// Blocks are records with identity (`docs/spec/gate-model.md` §4.1): cloning a world
/// shares them, and a block the model has adopted as its record keeps
/// showing the model's current state. The actuator is a plain value (the
/// model keeps a copy, `docs/spec/gate-model.md` §2).
#[derive(Clone, Debug)]
pub struct GateWorld {
    pub(super) actuator: TrackedObject,
    /// Ascending id, unique.
    pub(super) blocks: Vec<SharedBlock>,
}

impl GateWorld {
    /// A world of freshly observed objects (`s_prev = s`, `docs/spec/features.md` §1
    /// step 5). The actuator's state is taken as it is: parsing for the gate
    /// model has already set its yaw to 0.
    #[must_use]
    pub fn from_poses(poses: &Poses) -> Self {
        Self::new(
            TrackedObject::fresh(crate::types::ACTUATOR_ID, poses.actuator),
            poses
                .blocks
                .iter()
                .map(|(&id, &s)| TrackedObject::fresh(id, s)),
        )
    }

    /// A world from tracked objects with arbitrary previous states. Every
    /// block becomes a new record; of several blocks with the same id the
    /// last one is kept.
    #[must_use]
    pub fn new(actuator: TrackedObject, blocks: impl IntoIterator<Item = TrackedObject>) -> Self {
        let mut list: Vec<TrackedObject> = Vec::new();
        for b in blocks {
            match list.binary_search_by_key(&b.id, |o| o.id) {
                Ok(i) => list[i] = b,
                Err(i) => list.insert(i, b),
            }
        }
        Self {
            actuator,
            blocks: list.into_iter().map(SharedBlock::new).collect(),
        }
    }

    /// The actuator.
    #[must_use]
    pub fn actuator(&self) -> TrackedObject {
        self.actuator
    }

    /// The current values of the block with this id.
    #[must_use]
    pub fn block(&self, id: u32) -> Option<TrackedObject> {
        self.find(id).map(SharedBlock::get)
    }

    /// The current values of every block, ascending id.
    pub fn blocks(&self) -> impl ExactSizeIterator<Item = TrackedObject> + '_ {
        self.blocks.iter().map(SharedBlock::get)
    }

    /// Whether both worlds hold the very same record for block `id`
    /// (`docs/spec/gate-model.md` §4.1): then every in-place update of one is seen by
    /// the other.
    #[must_use]
    pub fn shares_block(&self, other: &GateWorld, id: u32) -> bool {
        match (self.find(id), other.find(id)) {
            (Some(a), Some(b)) => a.same_record(b),
            _ => false,
        }
    }

    /// Object states for scoring and display, read now.
    #[must_use]
    pub fn poses(&self) -> Poses {
        Poses {
            actuator: self.actuator.s,
            blocks: self.blocks().map(|o| (o.id, o.s)).collect(),
        }
    }

    pub(super) fn find(&self, id: u32) -> Option<&SharedBlock> {
        self.blocks
            .binary_search_by_key(&id, SharedBlock::id)
            .ok()
            .map(|i| &self.blocks[i])
    }
}
