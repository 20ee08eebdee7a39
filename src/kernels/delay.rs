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
//!
//! The ring releases each register onto the caller's lines: moved by the row's
//! [`line_shift`], so that a store is one whole line, not parts of two. Same C loop,
//! every row 16 bytes past a line (as NumPy's), medians of ten processes: eval 368 ->
//! 383 M lanes/s, sample 132 -> 154; with the written rows on lines already, 394 and
//! 156 before, 391 and 154 after. In `bench_vs_mitsuba.py`'s own arrays
//! (`bench_glint_pair.py`, 1M lanes): eval +10.3%, +5.5%, +4.6%, sample within 1.1%.
//! Rows that do not collide keep their direct stores even off lines (rows 12 KB apart,
//! 16 bytes past lines: eval 417 direct against 406 through the ring).
//!
//! All of the above was measured on an Intel Xeon with AVX-512. On an AMD EPYC (Zen 3,
//! AVX2) the ring lost in the colliding layout too, so the runtime's `stores=auto`
//! stores directly on AMD's CPUs ([`Stores`]).

use super::{FinishOutput, store};
use crate::math::Lane;
use crate::simd::Kernels;

/// Calls of at least this many lanes hold their outputs back: their ten rows, 4 bytes
/// a lane, outgrow the L2 cache and stream from memory. Smaller calls, whose rows a
/// host's loop keeps in cache, gain nothing from it and store directly.
pub const STREAMING_LANES: usize = 1 << 15;

/// Whether the fused kernels hold their outputs back, after later loads: the runtime's
/// `stores=` setting, carried by its [`Kernels`]. Held, a streaming call whose rows
/// [`collide`] stores through the ring, and the fused eval elsewhere stores each
/// register's sums two registers later (`kernels::fused`, against 4K aliasing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Stores {
    /// [`Stores::Held`], except on AMD's CPUs ([`crate::simd::is_amd`]), where
    /// [`Stores::Direct`]: holding was measured to gain on an Intel Xeon (the module
    /// doc) and to lose on an AMD EPYC (Zen 3, AVX2). There, in `bench_vs_mitsuba.py`'s
    /// arrays at 1M lanes (`bench_glint_pair.py`, one library under both settings, four
    /// runs of 11 rounds, both orders), the Disney closure's eval was 13-17% faster
    /// without the ring (median paired ratios 1.13-1.17), its sample 0-3%; the eval's
    /// direct stores in place of two registers later, 4-5% at 4096 lanes. Other CPUs
    /// of either vendor are unmeasured.
    #[default]
    Auto,
    /// After later loads: through the ring, or two registers later.
    Held,
    /// To the caller's rows as computed.
    Direct,
}

impl Stores {
    pub const ALL: [Stores; 3] = [Stores::Auto, Stores::Held, Stores::Direct];

    /// The name used in the runtime configuration (`stores=...`).
    pub fn name(self) -> &'static str {
        match self {
            Stores::Auto => "auto",
            Stores::Held => "held",
            Stores::Direct => "direct",
        }
    }

    /// Whether the kernels hold their outputs back.
    pub fn hold(self) -> bool {
        match self {
            Stores::Auto => !crate::simd::is_amd(),
            Stores::Held => true,
            Stores::Direct => false,
        }
    }
}

/// Whether a job of `lanes` lanes of a call of `count` on `kernels` may hold its
/// outputs back: it does where some row it writes also [`collide`]s with one it reads.
pub fn streams(kernels: Kernels, count: usize, lanes: usize) -> bool {
    streaming(count) && lanes > DELAY && kernels.stores().hold()
}

/// Whether a call of `count` lanes streams its rows from memory
/// ([`STREAMING_LANES`]): its fused kernels prefetch them (`fused::EVAL_AHEAD`).
pub fn streaming(count: usize) -> bool {
    count >= STREAMING_LANES
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

/// The lanes from `row`'s start to its first whole line (of a register's width, at
/// most 64 bytes), fewer than a register's: 0 where the row starts on one.
///
/// A release stores the register of lanes `at..` at `at + shift`, one whole line: a
/// store split over two lines costs a streaming call about half its bandwidth (an
/// AVX-512 loop reading six rows and writing four, 1M lanes: 850 M lanes/s with
/// every row on lines, 436 with only the written rows 16 bytes past them, 823 with
/// only the read rows so).
#[inline(always)]
pub fn line_shift<L: Lane>(row: &[f32]) -> usize {
    let bytes = 4 * L::LANES.min(16);
    (bytes - row.as_ptr() as usize % bytes) % bytes / 4
}

/// The register of lanes `at..` (a loop's, `DELAY` behind it) released from `from`'s
/// ring to `to`, moved by `to`'s [`line_shift`] `shift`: lanes `at + shift..`, the
/// ring's [`MIRROR`] holding those past its end. In a kernel's loop whole registers
/// only (no tail's code, nor its `memcpy`); `LAST` (the last `DELAY` lanes, after the
/// loop): only the lanes before `len`.
#[inline(always)]
fn release<L: Lane, const LAST: bool>(
    from: &[f32],
    to: &mut [f32],
    at: usize,
    shift: usize,
    len: usize,
) {
    let start = at + shift;
    let v = L::load(&from[at % DELAY + shift..]);
    if !LAST {
        v.store(&mut to[start..]);
    } else if start < len {
        store(v, to, start, L::LANES.min(len - start));
    }
}

/// After a register was stored to a ring's row at lane `at`: at the row's start (slot
/// 0) the register is copied to the [`MIRROR`], and the call's first register (no
/// release covers the lanes before a row's first line) goes to `to` as it is. A call
/// that holds its outputs has more than `DELAY` lanes: a whole register fits.
#[inline(always)]
pub fn wrap<L: Lane>(row: &mut [f32], to: &mut [f32], at: usize) {
    if at.is_multiple_of(DELAY) {
        let first = L::load(row);
        first.store(&mut row[DELAY..]);
        if at == 0 {
            first.store(to);
        }
    }
}

/// [`release`] of a row of integers (flags, components, lobes: only when asked for),
/// as it is.
#[inline(always)]
fn release_ints(from: &[u32], to: &mut [u32], at: usize, n: usize) {
    let slot = at % DELAY;
    to[at..at + n].copy_from_slice(&from[slot..slot + n]);
}

/// Lanes past a ring row's end that repeat its first register, so that a release
/// moved by a row's [`line_shift`] near the end loads one register, not two parts.
const MIRROR: usize = crate::math::lane::MAX_LANES;

// A release in a kernel's loop stores whole registers: the last lane it stores,
// `DELAY` behind the loop plus a shift, is one the call has.
const _: () = assert!(DELAY >= 2 * MIRROR);

/// A ring's row, on whole cache lines: a register stored to or loaded from a row at a
/// register's lane is then one line, not two (a split access).
#[derive(Clone, Copy)]
#[repr(align(64))]
pub struct Row<T>([T; DELAY + MIRROR]);

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

/// `R` rows of `DELAY` values and their mirror, made on the heap.
fn rows<T: Copy + Default, const R: usize>() -> Box<[Row<T>; R]> {
    let rows = vec![Row([T::default(); DELAY + MIRROR]); R].into_boxed_slice();
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

/// Each output row's [`line_shift`]: an eval's `value` (RGB) and `pdf`.
pub type EvalShifts = [usize; 4];

/// [`EvalShifts`] of the caller's rows.
#[inline(always)]
pub fn eval_shifts<L: Lane>(value: &Option<[&mut [f32]; 3]>, pdf: &[f32]) -> EvalShifts {
    let p = line_shift::<L>(pdf);
    match value {
        Some([r, g, b]) => [
            line_shift::<L>(r),
            line_shift::<L>(g),
            line_shift::<L>(b),
            p,
        ],
        None => [p; 4],
    }
}

/// An eval ring's sums of the register at `at` to the caller's rows of `len` lanes
/// ([`release`]).
#[inline(always)]
pub fn release_eval<L: Lane, const LAST: bool>(
    ring: &EvalRing,
    value: &mut Option<[&mut [f32]; 3]>,
    pdf: &mut [f32],
    at: usize,
    shifts: EvalShifts,
    len: usize,
) {
    if let Some([r, g, b]) = value {
        release::<L, LAST>(&ring[0], r, at, shifts[0], len);
        release::<L, LAST>(&ring[1], g, at, shifts[1], len);
        release::<L, LAST>(&ring[2], b, at, shifts[2], len);
    }
    release::<L, LAST>(&ring[3], pdf, at, shifts[3], len);
}

/// [`wrap`] of an eval ring's rows, the register at `at` just stored.
#[inline(always)]
pub fn wrap_eval<L: Lane>(
    ring: &mut EvalRing,
    value: &mut Option<[&mut [f32]; 3]>,
    pdf: &mut [f32],
    at: usize,
) {
    let [r, g, b, p] = ring;
    if let Some([vr, vg, vb]) = value {
        wrap::<L>(r, vr, at);
        wrap::<L>(g, vg, at);
        wrap::<L>(b, vb, at);
    }
    wrap::<L>(p, pdf, at);
}

/// Each float output row's [`line_shift`], in [`SampleRing`]'s order: `wi`, `pdf`,
/// `weight`, `value`, `eta`, `roughness` (0 for rows an output does not have).
pub type SampleShifts = [usize; 12];

/// [`SampleShifts`] of the caller's rows.
#[inline(always)]
pub fn sample_shifts<L: Lane>(o: &FinishOutput<'_>) -> SampleShifts {
    let shift = |row: Option<&[f32]>| row.map_or(0, line_shift::<L>);
    let [w0, w1, w2] = &o.wi;
    let [g0, g1, g2] = &o.weight;
    let v = o.value.as_ref();
    [
        line_shift::<L>(w0),
        line_shift::<L>(w1),
        line_shift::<L>(w2),
        line_shift::<L>(o.pdf),
        line_shift::<L>(g0),
        line_shift::<L>(g1),
        line_shift::<L>(g2),
        shift(v.map(|[r, _, _]| &**r)),
        shift(v.map(|[_, g, _]| &**g)),
        shift(v.map(|[_, _, b]| &**b)),
        shift(o.eta.as_deref()),
        shift(o.roughness.as_deref()),
    ]
}

/// Every row of `to` that `from` has, the register at `at` released to rows of `len`
/// lanes ([`release`]); the integer rows as they are.
#[inline(always)]
pub fn release_sample<L: Lane, const LAST: bool>(
    from: &FinishOutput<'_>,
    to: &mut FinishOutput<'_>,
    at: usize,
    shifts: &SampleShifts,
    len: usize,
) {
    for (k, (f, t)) in from.wi.iter().zip(to.wi.iter_mut()).enumerate() {
        release::<L, LAST>(f, t, at, shifts[k], len);
    }
    release::<L, LAST>(from.pdf, to.pdf, at, shifts[3], len);
    for (k, (f, t)) in from.weight.iter().zip(to.weight.iter_mut()).enumerate() {
        release::<L, LAST>(f, t, at, shifts[4 + k], len);
    }
    if let (Some(from), Some(to)) = (&from.value, &mut to.value) {
        for (k, (f, t)) in from.iter().zip(to.iter_mut()).enumerate() {
            release::<L, LAST>(f, t, at, shifts[7 + k], len);
        }
    }
    if let (Some(f), Some(t)) = (&from.eta, &mut to.eta) {
        release::<L, LAST>(f, t, at, shifts[10], len);
    }
    if let (Some(f), Some(t)) = (&from.roughness, &mut to.roughness) {
        release::<L, LAST>(f, t, at, shifts[11], len);
    }
    let n = if LAST {
        L::LANES.min(len - at)
    } else {
        L::LANES
    };
    for (f, t) in [
        (&from.flags, &mut to.flags),
        (&from.component, &mut to.component),
        (&from.lobe, &mut to.lobe),
    ] {
        if let (Some(f), Some(t)) = (f, t) {
            release_ints(f, t, at, n);
        }
    }
}

/// [`wrap`] of a sample ring's float rows, the register at `at` just stored.
#[inline(always)]
pub fn wrap_sample<L: Lane>(ring: &mut FinishOutput<'_>, to: &mut FinishOutput<'_>, at: usize) {
    if !at.is_multiple_of(DELAY) {
        return;
    }
    for (f, t) in ring.wi.iter_mut().zip(to.wi.iter_mut()) {
        wrap::<L>(f, t, at);
    }
    wrap::<L>(ring.pdf, to.pdf, at);
    for (f, t) in ring.weight.iter_mut().zip(to.weight.iter_mut()) {
        wrap::<L>(f, t, at);
    }
    if let (Some(f), Some(t)) = (&mut ring.value, &mut to.value) {
        for (f, t) in f.iter_mut().zip(t.iter_mut()) {
            wrap::<L>(f, t, at);
        }
    }
    if let (Some(f), Some(t)) = (&mut ring.eta, &mut to.eta) {
        wrap::<L>(f, t, at);
    }
    if let (Some(f), Some(t)) = (&mut ring.roughness, &mut to.roughness) {
        wrap::<L>(f, t, at);
    }
}
