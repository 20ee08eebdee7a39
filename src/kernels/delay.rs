//! Outputs of a streaming fused eval or sample stored [`DELAY`] lanes after their
//! inputs are read, where the host's rows collide.
//!
//! A host's rows often sit at nearly the same offset within their pages: the rows of
//! one allocation, or consecutive `malloc`s (NumPy's arrays in
//! `scripts/bench_vs_mitsuba.py`), whose 4 MB blocks differ by their 16-byte
//! headers. The lines a lane reads and the lines it writes then fall in the same sets
//! of the L2 cache (address bits 6-16: moving the output rows 64 KB removed the loss,
//! 128 KB did not), and ten or more rows streaming at once evict each other before
//! use. A full Disney closure's eval over 1M lanes, one thread, AVX-512, 2 MB pages,
//! in an ad hoc C loop: 270-302 M lanes/s with the rows 16 bytes apart and 267-313
//! with them all at one offset, against 405-452 with the rows 4 KB apart. Where some
//! row written [`collide`]s with a row read, the fused eval and sample of a call that
//! streams therefore keep each register's results in a ring (a thread's, on the heap:
//! [`Rings`]) and store them to the caller's rows `DELAY` lanes later, 2 KB from the
//! lines being read: the eval 19-24% and 22-35% faster in those two layouts. Where the
//! ring lies against the host's rows moves these figures by up to 10% from one
//! process to the next (its address, like theirs, varies). Elsewhere the kernels store
//! directly: with the rows 4 KB apart the ring cost an eval 3-7% and a sample up to
//! 14%.

use super::{FinishOutput, store};
use crate::math::Lane;

/// Calls of at least this many lanes hold their outputs back: their ten rows, 4 bytes
/// a lane, outgrow the L2 cache and stream from memory. Smaller calls, whose rows a
/// host's loop keeps in cache, gain nothing from it and store directly.
pub const STREAMING_LANES: usize = 1 << 15;

/// Whether a job of `lanes` lanes of a call of `count` may hold its outputs back: it
/// does where some row it writes also [`collide`]s with one it reads.
pub fn streams(count: usize, lanes: usize) -> bool {
    count >= STREAMING_LANES && lanes > DELAY
}

/// Whether a row of `writes` starts within 2 KB of a row of `reads` in the L2
/// cache's 128 KB cycle of sets (address bits 6-16). Rows further apart do not
/// evict each other, and there the ring's loads and stores are only a cost (rows
/// 4 KB apart: an eval 3-7% slower with the ring).
pub fn collide(reads: &[&[f32]], writes: &[&[f32]]) -> bool {
    const CYCLE: usize = 128 << 10;
    const NEAR: usize = 2 << 10;
    reads.iter().any(|r| {
        writes.iter().any(|w| {
            let d = (w.as_ptr() as usize).wrapping_sub(r.as_ptr() as usize) % CYCLE;
            d.min(CYCLE - d) < NEAR
        })
    })
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

/// [`release`] of a row of integers (flags, components, lobes: only when asked for).
#[inline(always)]
fn release_ints(from: &[u32], to: &mut [u32], slot: usize, at: usize, n: usize) {
    to[at..at + n].copy_from_slice(&from[slot..slot + n]);
}

/// A ring's row, on whole cache lines: a register stored to or loaded from a row at a
/// register's lane is then one line, not two (a split access).
#[derive(Clone, Copy)]
#[repr(align(64))]
pub struct Row<T>([T; DELAY]);

impl<T> std::ops::Deref for Row<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.0
    }
}

impl<T> std::ops::DerefMut for Row<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        &mut self.0
    }
}

/// An eval's ring: `value` (RGB) and `pdf`.
pub type EvalRing = [Row<f32>; 4];

/// A sample's ring, with a row for each output a [`FinishOutput`] may have.
pub struct SampleRing {
    /// `wi`, `pdf`, `weight`, `value`, `eta`, `roughness`.
    floats: Box<[Row<f32>; 12]>,
    /// `flags`, `component`, `lobe`.
    ints: Box<[Row<u32>; 3]>,
}

/// A thread's rings, on the heap and made once: a host may call from a thread with a
/// small stack (a fiber), and a sample's ring takes 30 KB. Every slot a call releases
/// it has written first, so a ring needs no clearing between calls.
#[derive(Default)]
pub struct Rings {
    eval: Option<Box<EvalRing>>,
    sample: Option<SampleRing>,
}

impl Rings {
    pub fn eval(&mut self) -> &mut EvalRing {
        self.eval.get_or_insert_with(rows)
    }

    pub fn sample(&mut self) -> &mut SampleRing {
        self.sample.get_or_insert_with(|| SampleRing {
            floats: rows(),
            ints: rows(),
        })
    }
}

/// `R` rows of `DELAY` values, made on the heap.
fn rows<T: Copy + Default, const R: usize>() -> Box<[Row<T>; R]> {
    let rows = vec![Row([T::default(); DELAY]); R].into_boxed_slice();
    rows.try_into().unwrap_or_else(|_| unreachable!("R rows"))
}

impl SampleRing {
    /// The ring as an output with the rows `like` has.
    pub fn rows_like(&mut self, like: &FinishOutput<'_>) -> FinishOutput<'_> {
        let [w0, w1, w2, pdf, g0, g1, g2, v0, v1, v2, eta, roughness] = &mut *self.floats;
        let [flags, component, lobe] = &mut *self.ints;
        FinishOutput {
            wi: [w0, w1, w2],
            pdf,
            weight: [g0, g1, g2],
            value: like.value.is_some().then_some([v0, v1, v2]),
            flags: like.flags.is_some().then_some(flags),
            lobe: like.lobe.is_some().then_some(lobe),
            component: like.component.is_some().then_some(component),
            eta: like.eta.is_some().then_some(eta),
            roughness: like.roughness.is_some().then_some(roughness),
        }
    }
}

/// An eval ring's sums of lanes `at..at + n` to the caller's rows.
#[inline(always)]
pub fn release_eval<L: Lane>(
    ring: &EvalRing,
    value: &mut Option<[&mut [f32]; 3]>,
    pdf: &mut [f32],
    at: usize,
    n: usize,
) {
    let slot = at % DELAY;
    if let Some(rows) = value {
        for (from, to) in ring.iter().zip(rows.iter_mut()) {
            release::<L>(from, to, slot, at, n);
        }
    }
    release::<L>(&ring[3], pdf, slot, at, n);
}

/// Every row of `to` that `from` has: lanes `slot..slot + n` of `from` to `at..`.
#[inline(always)]
pub fn release_sample<L: Lane>(
    from: &FinishOutput<'_>,
    to: &mut FinishOutput<'_>,
    slot: usize,
    at: usize,
    n: usize,
) {
    for (f, t) in from.wi.iter().zip(to.wi.iter_mut()) {
        release::<L>(f, t, slot, at, n);
    }
    release::<L>(from.pdf, to.pdf, slot, at, n);
    for (f, t) in from.weight.iter().zip(to.weight.iter_mut()) {
        release::<L>(f, t, slot, at, n);
    }
    if let (Some(from), Some(to)) = (&from.value, &mut to.value) {
        for (f, t) in from.iter().zip(to.iter_mut()) {
            release::<L>(f, t, slot, at, n);
        }
    }
    for (f, t) in [
        (&from.eta, &mut to.eta),
        (&from.roughness, &mut to.roughness),
    ] {
        if let (Some(f), Some(t)) = (f, t) {
            release::<L>(f, t, slot, at, n);
        }
    }
    for (f, t) in [
        (&from.flags, &mut to.flags),
        (&from.component, &mut to.component),
        (&from.lobe, &mut to.lobe),
    ] {
        if let (Some(f), Some(t)) = (f, t) {
            release_ints(f, t, slot, at, n);
        }
    }
}
