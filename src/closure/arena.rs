//! A caller-owned arena of closures: a fixed number of slots allocated once, so that
//! building and evaluating closures never touches the global allocator afterwards.
//! `reset` frees every closure at once (a host resets per shading point or bundle).
//! Generic over the slot type so the C API can keep its handle data beside each closure.

use super::Closure;
use crate::error::{Error, Status};

pub struct Arena<T = Closure> {
    slots: Vec<T>,
}

impl<T> Arena<T> {
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
        Ok(Arena { slots })
    }

    pub fn capacity(&self) -> usize {
        self.slots.capacity()
    }

    /// Closures currently allocated.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Place `closure` in the next slot. Slots never move: the arena never grows.
    pub fn alloc(&mut self, closure: T) -> Result<&mut T, Error> {
        if self.slots.len() == self.slots.capacity() {
            return Err(Error::new(
                Status::ArenaFull,
                format!(
                    "the arena is full ({} closures); reset it or create a larger one",
                    self.capacity()
                ),
            ));
        }
        self.slots.push(closure);
        Ok(self.slots.last_mut().expect("just pushed"))
    }

    /// The closures allocated since the last reset.
    pub fn iter(&self) -> impl Iterator<Item = &T> {
        self.slots.iter()
    }

    /// Free every closure; handles to them become invalid. The slots stay allocated.
    pub fn reset(&mut self) {
        self.slots.clear();
    }

    /// Free every closure and the slots themselves (the arena's end of life).
    pub fn release(&mut self) {
        self.slots = Vec::new();
    }
}
