//! An eval's outputs stored [`DELAY`] lanes after its inputs are read.
//!
//! A host's rows often sit at nearly the same offset within their pages: the rows of
//! one allocation, or consecutive `malloc`s (NumPy's arrays in
//! `scripts/bench_vs_mitsuba.py`), whose 4 MB blocks differ by their 16-byte
//! headers. The lines a lane reads and the lines it writes then fall in the same sets
//! of the L2 cache (address bits 6-16: moving the output rows 64 KB removed the loss,
//! 128 KB did not), and ten rows streaming at once evict each other before use. A
//! full Disney closure's eval over 1M lanes, one thread, AVX-512, 2 MB pages, in an
//! ad hoc C loop: 270-302 M lanes/s with the rows 16 bytes apart and 267-313 with
//! them all at one offset, against 405-452 with the rows 4 KB apart. The fused eval
//! of a call that streams therefore keeps each register's results in a ring on the
//! stack and stores them to the caller's rows `DELAY` lanes later, 2 KB from the
//! lines being read: 19-24% and 22-35% faster in those two layouts, 3-7% slower with
//! the rows 4 KB apart (the ring's loads and stores), unchanged below
//! [`STREAMING_LANES`]. The same ring in the fused sample lost as much as it won
//! (-14% to +24% over the three layouts), so a sample stores directly.

use super::store;
use crate::math::Lane;

/// Calls of at least this many lanes hold their outputs back: their ten rows, 4 bytes
/// a lane, outgrow the L2 cache and stream from memory. Smaller calls, whose rows a
/// host's loop keeps in cache, gain nothing from it and store directly.
pub const STREAMING_LANES: usize = 1 << 15;

/// Whether a job of `lanes` lanes of a call of `count` holds its outputs back.
pub fn holds_back(count: usize, lanes: usize) -> bool {
    count >= STREAMING_LANES && lanes > DELAY
}

/// Lanes the stores trail the loads by: 2 KB a row. Against 512, a ring of 256 lanes
/// was 6% and 18% slower in the colliding layouts, one of 1024 (16 KB) 6-8% slower
/// in all three.
pub const DELAY: usize = 512;

/// The first lanes of the registers still held once a loop over `len` lanes, in
/// steps of `lanes`, has released those `DELAY` behind it.
#[inline(always)]
pub fn held(len: usize, lanes: usize) -> impl Iterator<Item = usize> {
    (len.saturating_sub(DELAY).next_multiple_of(lanes)..len).step_by(lanes)
}

/// `to[at..at + n] = from[slot..slot + n]` by one register's load and store (a slot
/// is a whole register of the ring).
#[inline(always)]
pub fn release<L: Lane>(from: &[f32], to: &mut [f32], slot: usize, at: usize, n: usize) {
    store(L::load(&from[slot..]), to, at, n);
}

/// An eval's ring: `value` (RGB) and `pdf`.
pub type EvalRing = [[f32; DELAY]; 4];
