//! A caller-owned arena of closures: a fixed number of slots, each closure's lobes and
//! parameter blocks in storage sized to what it holds. `reset` frees every closure at
//! once (a host resets per shading point or bundle) but keeps the slots and their
//! storage, so after the first use of a slot building closures in it allocates
//! nothing. Generic over the slot type so the C API can keep its handle data beside
//! each closure.

use super::Closure;
use crate::error::{Error, Status};

/// A slot's contents that a reset drops while keeping their storage for the next
/// closure placed there.
pub trait Recycle {
    /// Drop the contents (lobe references included), keep the storage.
    fn recycle(&mut self);
    /// Drop the contents and the storage (the arena's end of life).
    fn free_storage(&mut self);
}

pub struct Arena<T = Closure> {
    /// Every slot used since creation: `slots[..live]` hold closures, the rest are
    /// recycled storage for the next ones.
    slots: Vec<T>,
    live: usize,
}

impl<T: Recycle> Arena<T> {
    /// An arena with room for `capacity` closures.
    pub fn new(capacity: usize) -> Result<Self, Error> {
        if capacity == 0 {
            return Err(Error::new(
                Status::InvalidArgument,
                "arena capacity must be at least 1 closure",
            ));
        }
        let mut slots = Vec::new();
        slots.try_reserve_exact(capacity).map_err(|_| {
            Error::new(
                Status::OutOfRange,
                format!("cannot allocate an arena of {capacity} closures"),
            )
        })?;
        Ok(Arena { slots, live: 0 })
    }

    pub fn capacity(&self) -> usize {
        self.slots.capacity()
    }

    /// Closures currently allocated.
    pub fn len(&self) -> usize {
        self.live
    }

    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Place `closure` in the next slot (its recycled storage is dropped).
    pub fn alloc(&mut self, closure: T) -> Result<&mut T, Error> {
        let closure = std::cell::Cell::new(Some(closure));
        self.alloc_with(
            || closure.take().expect("one of the two is called"),
            |slot| *slot = closure.take().expect("one of the two is called"),
        )
    }

    /// Place a closure in the next slot: `reuse` reinitializes a recycled slot (its
    /// storage kept), `make` builds the first closure of a slot never used. Slots
    /// never move: the arena never grows.
    pub fn alloc_with(
        &mut self,
        make: impl FnOnce() -> T,
        reuse: impl FnOnce(&mut T),
    ) -> Result<&mut T, Error> {
        if self.live == self.slots.capacity() {
            return Err(Error::new(
                Status::ArenaFull,
                format!(
                    "the arena is full ({} closures); reset it or create a larger one",
                    self.capacity()
                ),
            ));
        }
        if self.live < self.slots.len() {
            reuse(&mut self.slots[self.live]);
        } else {
            self.slots.push(make());
        }
        self.live += 1;
        Ok(&mut self.slots[self.live - 1])
    }

    /// The closures allocated since the last reset.
    pub fn iter(&self) -> impl Iterator<Item = &T> {
        self.slots[..self.live].iter()
    }

    /// Free every closure; handles to them become invalid. The slots and their storage
    /// stay allocated.
    pub fn reset(&mut self) {
        for slot in &mut self.slots[..self.live] {
            slot.recycle();
        }
        self.live = 0;
    }

    /// Free every closure and every slot's storage, keeping the slots themselves
    /// (their headers stay readable: see `glint_arena_destroy`).
    pub fn free_storage(&mut self) {
        for slot in &mut self.slots {
            slot.free_storage();
        }
        self.live = 0;
    }

    /// Free every closure and the slots themselves (the arena's end of life).
    pub fn release(&mut self) {
        self.slots = Vec::new();
        self.live = 0;
    }
}
