//! Generational slots, the backing store of the handle types, and the
//! handles themselves: bodies and geoms name each other (a body lists its
//! geoms, a geom its body), so their handles live below both.

use std::sync::atomic::{AtomicU32, Ordering};

/// Distinguishes the arenas of different worlds so that a handle from one
/// world is refused by another instead of silently naming a different object.
pub(crate) fn next_arena_id() -> u32 {
    static NEXT: AtomicU32 = AtomicU32::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct RawHandle {
    pub(crate) arena: u32,
    pub(crate) index: u32,
    pub(crate) generation: u32,
}

/// Names one body of one [`World`](crate::World). Copyable; refused once the
/// body is removed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyHandle(pub(crate) RawHandle);

/// Names one geom of one [`World`](crate::World).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GeomHandle(pub(crate) RawHandle);

struct Slot<T> {
    generation: u32,
    value: Option<T>,
}

pub(crate) struct Arena<T> {
    id: u32,
    slots: Vec<Slot<T>>,
    free: Vec<u32>,
}

impl<T> Arena<T> {
    pub(crate) fn new(id: u32) -> Self {
        Arena {
            id,
            slots: Vec::new(),
            free: Vec::new(),
        }
    }

    /// Reserves the slot `insert` will use, so the caller can record its
    /// index in the ODE object before the value exists.
    pub(crate) fn next_index(&self) -> u32 {
        self.free.last().copied().unwrap_or(self.slots.len() as u32)
    }

    pub(crate) fn insert(&mut self, value: T) -> RawHandle {
        let index = match self.free.pop() {
            Some(index) => {
                let slot = &mut self.slots[index as usize];
                slot.value = Some(value);
                index
            }
            None => {
                self.slots.push(Slot {
                    generation: 0,
                    value: Some(value),
                });
                (self.slots.len() - 1) as u32
            }
        };
        RawHandle {
            arena: self.id,
            index,
            generation: self.slots[index as usize].generation,
        }
    }

    pub(crate) fn get(&self, h: RawHandle) -> Option<&T> {
        if h.arena != self.id {
            return None;
        }
        let slot = self.slots.get(h.index as usize)?;
        if slot.generation != h.generation {
            return None;
        }
        slot.value.as_ref()
    }

    pub(crate) fn get_mut(&mut self, h: RawHandle) -> Option<&mut T> {
        if h.arena != self.id {
            return None;
        }
        let slot = self.slots.get_mut(h.index as usize)?;
        if slot.generation != h.generation {
            return None;
        }
        slot.value.as_mut()
    }

    /// The live value at `index` and its handle (used by the contact
    /// callback, which only gets the index back from ODE).
    pub(crate) fn by_index(&self, index: usize) -> Option<(RawHandle, &T)> {
        let slot = self.slots.get(index)?;
        let value = slot.value.as_ref()?;
        Some((
            RawHandle {
                arena: self.id,
                index: index as u32,
                generation: slot.generation,
            },
            value,
        ))
    }

    pub(crate) fn remove(&mut self, h: RawHandle) -> Option<T> {
        self.get(h)?;
        let slot = &mut self.slots[h.index as usize];
        let value = slot.value.take();
        slot.generation = slot.generation.wrapping_add(1);
        self.free.push(h.index);
        value
    }

    pub(crate) fn values(&self) -> impl Iterator<Item = &T> {
        self.slots.iter().filter_map(|s| s.value.as_ref())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn removed_slot_is_reused_with_a_new_generation() {
        let mut arena = Arena::new(7);
        let a = arena.insert("a");
        assert_eq!(arena.remove(a), Some("a"));
        let b = arena.insert("b");
        assert_eq!(a.index, b.index);
        assert!(arena.get(a).is_none());
        assert_eq!(arena.get(b), Some(&"b"));
        assert_eq!(arena.remove(a), None);
    }

    #[test]
    fn handles_of_another_arena_are_refused() {
        let mut one = Arena::new(1);
        let mut two = Arena::new(2);
        let h = one.insert(1);
        two.insert(2);
        assert!(two.get(h).is_none());
    }
}
