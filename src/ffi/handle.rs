//! Handle validation: every runtime, arena and closure handle carries a tag that API
//! entry points compare (one load and one compare) and that destroy and reset poison.
//!
//! - Runtime, arena and material handles point to small shells. Destroy frees what
//!   they own, poisons the tag and parks the shell in a bounded global [quarantine],
//!   so a destroyed handle stays readable (and reads as destroyed) for a while instead
//!   of becoming freed memory at once. Runtimes and arenas share one queue, materials
//!   have their own, and destroyed arenas' closure slots leave by their own byte bound
//!   (their shells stay): destroys of one kind never free another kind's shell early.
//! - A closure handle is the address of its arena slot with the arena's generation in
//!   the 16 high bits, which x86-64 and AArch64 user-space addresses leave zero. The
//!   slot's tag holds the generation it was built in, `glint_arena_reset` poisons the
//!   live slots and bumps the generation, so a handle from before a reset never
//!   matches, even when its slot holds a newer closure. Each closure call also checks
//!   its runtime's tag.
//!
//! - Every handle type is `#[repr(C)]` with its tag first (asserted beside each), and
//!   every handle is masked to its address ([`shell`], [`decode`]), so a handle of one
//!   kind passed as another reads its tag in bounds and is refused; the header declares
//!   them opaque (cbindgen.toml).
//!
//! What stays undefined: pointers this library never returned; a destroyed runtime or
//! arena handle, or a material or closure of a destroyed runtime, used after
//! [`GLINT_QUARANTINE_SHELLS`] more runtimes and arenas were destroyed (material
//! destroys do not count; the shell is then freed); a destroyed material used after
//! [`GLINT_QUARANTINE_SHELLS`] more materials were destroyed; closures of a destroyed
//! arena whose slots exceeded [`GLINT_QUARANTINE_BYTES`] or left the quarantine (by
//! bytes, or with the arena's shell); a handle from exactly a multiple of 65536
//! resets ago whose slot was reused; and calls that race with the destroy or reset of
//! the handle they use.

use super::*;
use std::any::Any;
use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

pub(crate) const RUNTIME_LIVE: u64 = u64::from_be_bytes(*b"GLRTLIVE");
pub(crate) const RUNTIME_DEAD: u64 = u64::from_be_bytes(*b"GLRTDEAD");
pub(crate) const ARENA_LIVE: u64 = u64::from_be_bytes(*b"GLARLIVE");
pub(crate) const ARENA_DEAD: u64 = u64::from_be_bytes(*b"GLARDEAD");
/// A live closure slot: these 48 bits, then the 16-bit generation it was built in.
const CLOSURE_LIVE: u64 = u64::from_be_bytes(*b"GLCLLV\0\0");
/// A slot freed by `glint_arena_reset` (not yet reused).
pub(crate) const CLOSURE_RESET: u64 = u64::from_be_bytes(*b"GLCLRSET");
/// A slot of a destroyed arena.
pub(crate) const CLOSURE_DEAD: u64 = u64::from_be_bytes(*b"GLCLDEAD");

const GENERATION_SHIFT: u32 = 48;
const ADDRESS_MASK: usize = (1 << GENERATION_SHIFT) - 1;
const _: () = assert!(usize::BITS == 64, "closure handles need 64-bit pointers");

/// A handle's tag; atomic so that a checking thread never races a plain write.
pub(crate) struct Tag(AtomicU64);

impl Tag {
    pub(crate) const fn new(value: u64) -> Self {
        Tag(AtomicU64::new(value))
    }

    pub(crate) fn get(&self) -> u64 {
        self.0.load(Ordering::Relaxed)
    }

    pub(crate) fn set(&self, value: u64) {
        self.0.store(value, Ordering::Relaxed);
    }
}

pub(crate) fn invalid(message: String) -> Error {
    Error::new(Status::InvalidHandle, message)
}

/// Check a runtime or arena tag: one compare inline, the message out of line.
#[inline(always)]
pub(crate) fn check_tag(tag: &Tag, live: u64, dead: u64, what: &str) -> Result<(), Error> {
    let t = tag.get();
    if t == live {
        Ok(())
    } else {
        Err(tag_error(t, dead, what))
    }
}

/// Begin destroying a runtime or arena: unless its tag is live (the destroy is then
/// ignored with this error), poison it.
pub(crate) fn poison(tag: &Tag, live: u64, dead: u64, what: &str) -> Result<(), Error> {
    check_tag(tag, live, dead, what)
        .map_err(|e| invalid(format!("glint_{what}_destroy ignored: {}", e.message)))?;
    tag.set(dead);
    Ok(())
}

#[cold]
#[inline(never)]
fn tag_error(tag: u64, dead: u64, what: &str) -> Error {
    if tag == dead {
        invalid(format!("{what} was destroyed"))
    } else {
        invalid(format!(
            "{what} is not a {what} handle (another kind of handle, or freed memory)"
        ))
    }
}

/// The tag of a closure slot built in `generation`.
#[inline(always)]
pub(crate) fn closure_tag(generation: u16) -> u64 {
    CLOSURE_LIVE | u64::from(generation)
}

/// The handle of the closure in `slot`, built in `generation`.
pub(crate) fn encode<T>(slot: *mut T, generation: u16) -> Result<*mut T, Error> {
    if slot.addr() & !ADDRESS_MASK != 0 {
        return Err(Error::new(
            Status::Unsupported,
            format!(
                "closure slot address {:#x} does not fit in 48 bits",
                slot.addr()
            ),
        ));
    }
    Ok(slot.map_addr(|a| a | usize::from(generation) << GENERATION_SHIFT))
}

/// The slot a closure handle points to and the generation it carries.
#[inline(always)]
pub(crate) fn decode<T>(handle: *const T) -> (*const T, u16) {
    let generation = (handle.addr() >> GENERATION_SHIFT) as u16;
    (handle.map_addr(|a| a & ADDRESS_MASK), generation)
}

/// The shell a runtime, arena or material handle points to. Their addresses never have
/// the high 16 bits set; clearing them as for a closure handle makes a closure handle
/// passed in their place read its slot's tag (and be refused) instead of faulting.
#[inline(always)]
pub(crate) fn shell<T>(handle: *const T) -> *const T {
    decode(handle).0
}

/// [`shell`] for a mutable handle.
#[inline(always)]
pub(crate) fn shell_mut<T>(handle: *mut T) -> *mut T {
    shell(handle.cast_const()).cast_mut()
}

/// Check a closure slot's tag against the generation of the handle that led to it.
#[inline(always)]
pub(crate) fn check_closure_tag(tag: &Tag, generation: u16, what: &str) -> Result<(), Error> {
    let t = tag.get();
    if t == closure_tag(generation) {
        Ok(())
    } else {
        Err(closure_tag_error(t, what))
    }
}

#[cold]
#[inline(never)]
fn closure_tag_error(tag: u64, what: &str) -> Error {
    match tag {
        t if t & !0xffff == CLOSURE_LIVE => invalid(format!(
            "{what} is stale: its arena was reset and the slot now holds a newer closure"
        )),
        CLOSURE_RESET => invalid(format!("{what} is stale: its arena was reset")),
        CLOSURE_DEAD => invalid(format!("{what} belongs to a destroyed arena")),
        _ => invalid(format!(
            "{what} is not a closure handle (another kind of handle, or freed memory)"
        )),
    }
}

/// The quarantine queue a destroyed shell waits in. Each counts only destroys of its
/// own kinds, so that churning materials never frees a destroyed runtime's shell (its
/// materials and closures read it) before [`GLINT_QUARANTINE_SHELLS`] more runtimes
/// and arenas were destroyed, as `glint_runtime_destroy` documents.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Queue {
    /// Runtimes and arenas: the last [`GLINT_QUARANTINE_SHELLS`] of them.
    RuntimesAndArenas,
    /// Materials: the last [`GLINT_QUARANTINE_SHELLS`] of them.
    Materials,
}

/// A destroyed handle shell that the quarantine can park.
pub(crate) trait Quarantined: Any {
    /// The queue it waits in.
    fn queue(&self) -> Queue {
        Queue::RuntimesAndArenas
    }

    /// Free the closure slots it keeps (an arena's; the bytes it was parked with),
    /// keeping the shell itself readable.
    fn release_slots(&mut self) {}
}

/// A destroyed shell, kept readable while quarantined, with the bytes of closure
/// slots it still keeps.
struct Parked {
    shell: Box<dyn Quarantined>,
    bytes: usize,
}

struct Quarantine {
    /// Destroyed runtimes and arenas, oldest first.
    shells: VecDeque<Parked>,
    /// The closure slot bytes `shells` keep.
    bytes: usize,
    /// Destroyed materials, oldest first.
    materials: VecDeque<Box<dyn Quarantined>>,
}

// SAFETY: quarantined shells are dead: no thread uses them through the API (a use is
// a read of their poisoned tag), and the quarantine only frees their slots or drops them.
unsafe impl Send for Quarantine {}

impl Quarantine {
    const fn new() -> Self {
        Quarantine {
            shells: VecDeque::new(),
            bytes: 0,
            materials: VecDeque::new(),
        }
    }

    /// Park `shell`, keeping `bytes` of closure slots (at most
    /// [`GLINT_QUARANTINE_BYTES`]), and apply the bounds: beyond
    /// [`GLINT_QUARANTINE_BYTES`] the oldest shells' slots are freed (the shells
    /// stay), beyond [`GLINT_QUARANTINE_SHELLS`] in its queue the oldest shell of that
    /// queue is freed. Returns what leaves, for the caller to drop.
    fn park(&mut self, shell: Box<dyn Quarantined>, bytes: usize) -> Vec<Box<dyn Quarantined>> {
        let mut leaving = Vec::new();
        match shell.queue() {
            Queue::Materials => {
                self.materials.push_back(shell);
                while self.materials.len() > GLINT_QUARANTINE_SHELLS {
                    leaving.extend(self.materials.pop_front());
                }
            }
            Queue::RuntimesAndArenas => {
                self.bytes += bytes;
                self.shells.push_back(Parked { shell, bytes });
                for old in &mut self.shells {
                    if self.bytes <= GLINT_QUARANTINE_BYTES {
                        break;
                    }
                    if old.bytes > 0 {
                        old.shell.release_slots();
                        self.bytes -= old.bytes;
                        old.bytes = 0;
                    }
                }
                while self.shells.len() > GLINT_QUARANTINE_SHELLS {
                    let Some(old) = self.shells.pop_front() else {
                        break;
                    };
                    self.bytes -= old.bytes;
                    leaving.push(old.shell);
                }
            }
        }
        leaving
    }
}

/// Reachable from a global, so leak checkers count parked shells as still reachable.
static QUARANTINE: Mutex<Quarantine> = Mutex::new(Quarantine::new());

/// Park a destroyed shell that keeps `bytes` of closure slots (at most
/// [`GLINT_QUARANTINE_BYTES`]) in its [`Queue`]; the oldest of that queue leave (and
/// are freed) beyond [`GLINT_QUARANTINE_SHELLS`], the oldest slots beyond
/// [`GLINT_QUARANTINE_BYTES`].
pub(crate) fn quarantine(shell: Box<dyn Quarantined>, bytes: usize) {
    let leaving = QUARANTINE
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .park(shell, bytes);
    drop(leaving);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_handle_carries_its_generation_and_decodes_to_its_slot() {
        let mut slot = 0u64;
        let p: *mut u64 = &mut slot;
        for generation in [0, 1, 0x1234, u16::MAX] {
            let h = encode(p, generation).unwrap();
            assert_eq!(decode(h.cast_const()), (p.cast_const(), generation));
        }
        assert_ne!(encode(p, 1).unwrap(), encode(p, 2).unwrap());
    }

    #[test]
    fn a_slot_tag_accepts_only_its_own_generation() {
        let tag = Tag::new(closure_tag(7));
        assert!(check_closure_tag(&tag, 7, "c").is_ok());
        let stale = check_closure_tag(&tag, 6, "c").unwrap_err();
        assert_eq!(stale.status, Status::InvalidHandle);
        assert!(stale.message.contains("newer closure"), "{}", stale.message);
        for (poison, says) in [
            (CLOSURE_RESET, "was reset"),
            (CLOSURE_DEAD, "destroyed arena"),
            (RUNTIME_LIVE, "not a closure handle"),
        ] {
            tag.set(poison);
            let e = check_closure_tag(&tag, 7, "c").unwrap_err();
            assert!(e.message.contains(says), "{}", e.message);
        }
    }

    struct Shell {
        queue: Queue,
        released: bool,
    }

    impl Quarantined for Shell {
        fn queue(&self) -> Queue {
            self.queue
        }

        fn release_slots(&mut self) {
            self.released = true;
        }
    }

    fn shell(queue: Queue) -> Box<Shell> {
        Box::new(Shell {
            queue,
            released: false,
        })
    }

    fn released(p: &Parked) -> bool {
        (p.shell.as_ref() as &dyn Any)
            .downcast_ref::<Shell>()
            .unwrap()
            .released
    }

    #[test]
    fn the_quarantine_keeps_its_bounds() {
        let mut q = Quarantine::new();
        for _ in 0..GLINT_QUARANTINE_SHELLS + 10 {
            q.park(shell(Queue::RuntimesAndArenas), GLINT_QUARANTINE_BYTES / 4);
            q.park(shell(Queue::Materials), 0);
        }
        assert_eq!(q.shells.len(), GLINT_QUARANTINE_SHELLS);
        assert_eq!(q.materials.len(), GLINT_QUARANTINE_SHELLS);
        assert!(q.bytes <= GLINT_QUARANTINE_BYTES);
        assert_eq!(q.bytes, q.shells.iter().map(|p| p.bytes).sum::<usize>());
        assert!(q.shells.iter().all(|p| released(p) == (p.bytes == 0)));
    }

    #[test]
    fn only_runtime_and_arena_destroys_free_their_shells() {
        let mut q = Quarantine::new();
        q.park(shell(Queue::RuntimesAndArenas), 0);
        for _ in 0..GLINT_QUARANTINE_SHELLS * 2 {
            assert!(q.park(shell(Queue::Materials), 0).len() <= 1);
        }
        // Slots beyond the byte bound leave; the shells stay.
        for _ in 0..8 {
            q.park(shell(Queue::RuntimesAndArenas), GLINT_QUARANTINE_BYTES / 2);
        }
        assert_eq!(q.shells.len(), 9);
        assert_eq!(q.bytes, GLINT_QUARANTINE_BYTES);
        assert_eq!(q.shells.iter().filter(|p| released(p)).count(), 6);
        for k in 9..GLINT_QUARANTINE_SHELLS {
            assert!(q.park(shell(Queue::RuntimesAndArenas), 0).is_empty(), "{k}");
        }
        assert_eq!(q.park(shell(Queue::RuntimesAndArenas), 0).len(), 1);
        assert_eq!(q.shells.len(), GLINT_QUARANTINE_SHELLS);
    }
}
