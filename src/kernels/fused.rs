//! Closures of built-in lobes evaluated in one pass. A batch over one shared closure
//! whose lobes share a frame (a material's) otherwise takes the directions into the
//! frame once and then runs each lobe's kernel over the chunk, each reading the local
//! directions and adding into the outputs. When the closure's lobe types, in order,
//! are one of the [`SHAPES`], one kernel instantiated for those models does it all per
//! register: the directions are normalized and taken into the frame in registers,
//! every lobe is evaluated on them (LLVM merges what the lobes compute alike, such as
//! the half vector) and the sums are stored once. Samples of such a closure, and of a
//! material batch whose kept slots are such a shape, are one pass per register too
//! ([`sample_register`]). The arithmetic is the unfused path's, operation for
//! operation, so the outputs are the same bits.

use super::delay::{self, DELAY, EvalRing};
use super::mixture::{self, clamp_random};
use super::{
    Directions, FinishOutput, MAX_LOBE_PARAMS, direction, load, load_frame, load3, pack_events,
    rgb_at, store, store_finished, unit_in_range,
};
use crate::closure::Closure;
use crate::lobes::disney_clearcoat::DisneyClearcoat;
use crate::lobes::disney_diffuse::DisneyDiffuse;
use crate::lobes::disney_sheen::DisneySheen;
use crate::lobes::disney_specular::DisneySpecular;
use crate::lobes::{
    Eval, InPlace, Model, Params, Sample, Settle, ToWorld, Transport, both_above, flags,
};
use crate::math::{Frame, Lane, LaneFrame, Mask, Rgb, Vec3};
use crate::simd::{Kernels, kernel};
use std::any::TypeId;

/// Most lobes of a fused shape.
pub const MAX_FUSED: usize = 4;

/// One lobe of a fused job: its decoded block, weight and selection probability.
#[derive(Clone, Copy)]
pub struct FusedLobe<'a> {
    pub params: &'a [f32],
    pub weight: Rgb<f32>,
    pub probability: f32,
}

/// A fused eval over the caller's raw direction rows (normalized as
/// [`Directions::Raw`] normalizes them).
pub struct FusedEvalJob<'a> {
    pub mode: Transport,
    pub frame: Frame,
    pub wo: [&'a [f32]; 3],
    pub wi: [&'a [f32]; 3],
    /// The closure's lobes in order (as many as the shape has; the rest unused).
    pub lobes: [FusedLobe<'a>; MAX_FUSED],
    /// `sum weight_k f_k cos` (when wanted) and `sum p_k pdf_k`, one per lane.
    pub value: Option<[&'a mut [f32]; 3]>,
    pub pdf: &'a mut [f32],
    /// A ring to hold the outputs back in ([`delay`]), for calls that stream.
    pub held: Option<&'a mut EvalRing>,
    /// Whether the call streams ([`delay::streaming`]): the input rows are then
    /// prefetched [`EVAL_AHEAD`] (or [`SAMPLE_AHEAD`]) lanes ahead.
    pub prefetch: bool,
}

impl<'a> FusedEvalJob<'a> {
    /// The job with its outputs held back in `ring`.
    pub fn with_ring(self, ring: &'a mut EvalRing) -> Self {
        FusedEvalJob {
            held: Some(ring),
            ..self
        }
    }

    /// Whether a row it writes [`delay::collide`]s with one it reads.
    pub fn rows_collide(&self) -> bool {
        let ([a, b, c], [d, e, f]) = (self.wo, self.wi);
        let pdf = &*self.pdf;
        let [red, green, blue] = match &self.value {
            Some([r, g, b]) => [&**r, &**g, &**b],
            None => [pdf; 3],
        };
        delay::collide(&[a, b, c, d, e, f], &[red, green, blue, pdf])
    }
}

/// A lobe's weight and selection probability over lanes.
#[derive(Clone, Copy)]
pub struct Term<L> {
    pub weight: Rgb<L>,
    pub probability: L,
}

impl<L: Lane> Term<L> {
    /// No weight (lobes a shape does not have).
    #[inline(always)]
    pub fn zero() -> Self {
        Term {
            weight: Rgb::zero(),
            probability: L::zero(),
        }
    }
}

/// A tuple of lobe models evaluated together.
pub trait Shape: 'static {
    /// Lobes in the shape.
    const LOBES: usize;
    /// No lobe of the shape has delta events (`flags::SPECULAR`).
    const SMOOTH: bool;
    type Prepared<L: Lane>;
    /// Whether `models` are this shape's models, in order.
    fn matches(models: &[Option<TypeId>]) -> bool;
    /// Each lobe's decoded block, in order.
    fn prepare<L: Lane>(params: &[Params<'_, L>; MAX_FUSED]) -> Self::Prepared<L>;
    /// `(sum weight_k f_k, sum p_k pdf_k)` in lobe order at `(wo, wi)`, the bits of
    /// [`sum_evals`] of [`Shape::evals`], each lobe added as it is evaluated (fewer
    /// live registers than every eval first: 330 instructions a register against 337).
    fn sum<L: Lane>(
        p: &Self::Prepared<L>,
        terms: &[Term<L>; MAX_FUSED],
        wo: Vec3<L>,
        wi: Vec3<L>,
        mode: Transport,
    ) -> (Rgb<L>, L);
    /// Each lane's sample of its chosen lobe (lobe `k` where `chosen` equals
    /// `labels[k]`), in the local frame and not yet settled: its `valid`, value and pdf
    /// are not read (each model is [`Model::VALID_ABOVE`]).
    fn sample<L: Lane>(
        p: &Self::Prepared<L>,
        chosen: (L, &[f32; MAX_FUSED]),
        wo: Vec3<L>,
        u: [L; 3],
        mode: Transport,
    ) -> Sample<L>;
    /// Each lobe's own `f |cos|` and pdf at `(wo, wi)`, in order.
    fn evals<L: Lane>(
        p: &Self::Prepared<L>,
        wo: Vec3<L>,
        wi: Vec3<L>,
        mode: Transport,
    ) -> [Eval<L>; MAX_FUSED];
}

/// `(sum weight_k f_k, sum p_k pdf_k)` of the first `lobes` evals, in order, from the
/// first lobe's terms, as lobe kernels store then add.
#[inline(always)]
pub fn sum_evals<L: Lane>(
    terms: &[Term<L>; MAX_FUSED],
    evals: &[Eval<L>; MAX_FUSED],
    lobes: usize,
) -> (Rgb<L>, L) {
    let mut sum = weighted(&terms[0], evals[0]);
    for k in 1..lobes {
        sum = add_weighted(sum, &terms[k], evals[k]);
    }
    sum
}

/// `(weight f, p pdf)` of a sum's first lobe.
#[inline(always)]
pub fn weighted<L: Lane>(term: &Term<L>, e: Eval<L>) -> (Rgb<L>, L) {
    (term.weight * e.value, term.probability * e.pdf)
}

/// `sum + (weight f, p pdf)` of one more lobe, each channel by one fused multiply-add:
/// how every eval path sums its lobes (`kernels::put_product` in rows), so that a
/// fused kernel and lobe-by-lobe rows hold the same bits.
#[inline(always)]
pub fn add_weighted<L: Lane>((value, pdf): (Rgb<L>, L), term: &Term<L>, e: Eval<L>) -> (Rgb<L>, L) {
    let w = term.weight;
    (
        Rgb::new(
            w.r.mul_add(e.value.r, value.r),
            w.g.mul_add(e.value.g, value.g),
            w.b.mul_add(e.value.b, value.b),
        ),
        term.probability.mul_add(e.pdf, pdf),
    )
}

/// The lobes' blocks and terms, the same for every lane.
#[inline(always)]
fn uniform<'a, L: Lane>(
    lobes: &[FusedLobe<'a>; MAX_FUSED],
) -> ([Params<'a, L>; MAX_FUSED], [Term<L>; MAX_FUSED]) {
    let mut params = [Params::shared(&[]); MAX_FUSED];
    let mut terms = [Term::zero(); MAX_FUSED];
    // A loop, not `array::map`: its closure would lose the kernel's target features.
    for k in 0..MAX_FUSED {
        let w = lobes[k].weight;
        params[k] = Params::shared(lobes[k].params);
        terms[k] = Term {
            weight: Rgb::new(L::splat(w.r), L::splat(w.g), L::splat(w.b)),
            probability: L::splat(lobes[k].probability),
        };
    }
    (params, terms)
}

macro_rules! shape {
    ($first:ident $(, $m:ident)*) => {
        impl<$first: Model $(, $m: Model)*> Shape for ($first, $($m,)*) {
            const LOBES: usize = [stringify!($first) $(, stringify!($m))*].len();
            const SMOOTH: bool = ($first::FLAGS $(| $m::FLAGS)*) & flags::SPECULAR == 0;
            type Prepared<L: Lane> = ($first::Prepared<L>, $($m::Prepared<L>,)*);
            fn matches(models: &[Option<TypeId>]) -> bool {
                let shape = [TypeId::of::<$first>() $(, TypeId::of::<$m>())*];
                models.len() == shape.len()
                    && models.iter().zip(shape).all(|(m, s)| *m == Some(s))
            }
            #[inline(always)]
            fn prepare<L: Lane>(params: &[Params<'_, L>; MAX_FUSED]) -> Self::Prepared<L> {
                let first = $first::prepare(params[0]);
                let mut k = 0;
                (first, $({
                    k += 1;
                    $m::prepare(params[k])
                },)*)
            }
            #[inline(always)]
            #[allow(non_snake_case)]
            fn sum<L: Lane>(
                p: &Self::Prepared<L>,
                terms: &[Term<L>; MAX_FUSED],
                wo: Vec3<L>,
                wi: Vec3<L>,
                mode: Transport,
            ) -> (Rgb<L>, L) {
                let ($first, $($m,)*) = p;
                let mut sum = weighted(&terms[0], $first::eval($first, wo, wi, mode));
                let mut k = 0;
                $(
                    k += 1;
                    sum = add_weighted(sum, &terms[k], $m::eval($m, wo, wi, mode));
                )*
                sum
            }
            #[inline(always)]
            #[allow(non_snake_case)]
            fn sample<L: Lane>(
                p: &Self::Prepared<L>,
                (chosen, labels): (L, &[f32; MAX_FUSED]),
                wo: Vec3<L>,
                [uc, u0, u1]: [L; 3],
                mode: Transport,
            ) -> Sample<L> {
                const { assert!($first::VALID_ABOVE $(&& $m::VALID_ABOVE)*) };
                let ($first, $($m,)*) = p;
                // Every lobe some lane chose samples every lane (LLVM shares what the
                // samplers compute alike); each lane keeps its chosen lobe's. A lobe
                // no lane chose is skipped: a rarely chosen one, such as a clearcoat,
                // in most registers.
                let mut s = $first::sample($first, wo, uc, u0, u1, mode, &mut InPlace);
                let mut k = 0;
                $(
                    k += 1;
                    let mine = chosen.eq(L::splat(labels[k]));
                    if mine.any() {
                        let t = $m::sample($m, wo, uc, u0, u1, mode, &mut InPlace);
                        s = Sample::select(mine, t, s);
                    }
                )*
                s
            }
            #[inline(always)]
            #[allow(non_snake_case)]
            fn evals<L: Lane>(
                p: &Self::Prepared<L>,
                wo: Vec3<L>,
                wi: Vec3<L>,
                mode: Transport,
            ) -> [Eval<L>; MAX_FUSED] {
                let ($first, $($m,)*) = p;
                let mut e = [Eval::zero(); MAX_FUSED];
                e[0] = $first::eval($first, wo, wi, mode);
                let mut k = 0;
                $(
                    k += 1;
                    e[k] = $m::eval($m, wo, wi, mode);
                )*
                e
            }
        }
    };
}

shape!(A, B);
shape!(A, B, C);
shape!(A, B, C, D);

/// Sums `(value, pdf)` stored to the `n` lanes at `i` (value only when wanted).
#[inline(always)]
fn store_sums<L: Lane>(
    (v, q): (Rgb<L>, L),
    value: &mut Option<[&mut [f32]; 3]>,
    pdf: &mut [f32],
    i: usize,
    n: usize,
) {
    if let Some(rows) = value {
        for (v, row) in v.to_array().into_iter().zip(rows.iter_mut()) {
            store(v, row, i, n);
        }
    }
    store(q, pdf, i, n);
}

/// One register at a time: two (`Lane::Interleaved`) measured slower on a Sapphire
/// Rapids Xeon (full Disney closure, AVX-512: 266 against 287 M lanes/s; AVX2 211, 209).
/// Each register's sums are stored as computed (`stores=direct`).
#[inline(always)]
fn eval_body<S: Shape, L: Lane>(job: &mut FusedEvalJob<'_>) -> bool {
    eval_lanes::<S, L, false, false>(job, None)
}

/// [`eval_body`] with each register's sums stored two registers later
/// (`stores=held`, see `eval_lanes`).
#[inline(always)]
fn eval_late_body<S: Shape, L: Lane>(job: &mut FusedEvalJob<'_>) -> bool {
    eval_lanes::<S, L, false, true>(job, None)
}

/// [`eval_body`] with the outputs held back in the job's ring ([`delay`]): a kernel
/// of its own, so that the other's loop keeps its code.
#[inline(always)]
fn eval_held_body<S: Shape, L: Lane>(job: &mut FusedEvalJob<'_>) -> bool {
    let ring = job.held.take();
    eval_lanes::<S, L, true, false>(job, ring)
}

/// [`eval_body`] with its outputs held back in `ring` (when given, see [`delay`]), or
/// (`LATE`) stored two registers later.
#[inline(always)]
fn eval_lanes<S: Shape, L: Lane, const HELD: bool, const LATE: bool>(
    job: &mut FusedEvalJob<'_>,
    mut ring: Option<&mut EvalRing>,
) -> bool {
    let len = job.pdf.len();
    let (params, terms) = uniform::<L>(&job.lobes);
    let p = S::prepare::<L>(&params);
    let frame = LaneFrame::<L>::splat(&job.frame);
    let mut out_of_range = false;
    // Every row cut to `len` once, so that the loop's loads and stores need no bounds
    // checks of their own (about 30 compares and branches a register otherwise).
    let (wo_rows, wi_rows) = (cut3(job.wo, len), cut3(job.wi, len));
    let mut value = job
        .value
        .as_mut()
        .map(|[r, g, b]| [&mut r[..len], &mut g[..len], &mut b[..len]]);
    // `LATE`: each register's sums stored two registers later, after the next loads:
    // a host's rows often lie within a few hundred bytes of each other modulo 4 KB
    // (the script's at 4096 lanes), and a load waits on an older store whose address
    // matches its bits 0-11 (4K aliasing). Intel Xeon, paired C loop, 4096 lanes:
    // +7.8% in the script's layout, +4% with the rows 16 KB apart (one register
    // later gained half as much, three lost 2-3%). On an AMD EPYC (Zen 3, AVX2) the
    // direct stores were faster, +4.3% and +5.2% at 4096 lanes and +1.4% at 1M in the
    // script's layout (the values carried cost stack spills), hence `stores=`
    // (`delay::Stores`). A held call instead loads each register's directions one
    // register ahead: more loads in flight over rows that stream (1M lanes, +2% to
    // +7%); without a ring that cost 8% at 4096 lanes.
    let (mut pending, mut later) = (None, None);
    let shifts = delay::eval_shifts::<L>(&value, job.pdf);
    let first = if HELD { 0 } else { len };
    let mut next = (ahead::<L>(wo_rows, first), ahead::<L>(wi_rows, first));
    for i in (0..len).step_by(L::LANES) {
        let n = L::LANES.min(len - i);
        if job.prefetch {
            prefetch_ahead::<L, EVAL_AHEAD>([wo_rows, wi_rows], i, len);
        }
        let (wo, wi) = if HELD {
            let d = next;
            let at = i + L::LANES;
            next = (ahead::<L>(wo_rows, at), ahead::<L>(wi_rows, at));
            d
        } else {
            (load3::<L>(wo_rows, i, n), load3::<L>(wi_rows, i, n))
        };
        if let Some((sums, k, m)) = pending.take() {
            store_sums(sums, &mut value, job.pdf, k, m);
        }
        pending = later.take();
        let (wo, ok_o) = unit_in_range(wo);
        let (wi, ok_i) = unit_in_range(wi);
        out_of_range |= !(ok_o & ok_i).all();
        if out_of_range {
            return false;
        }
        let (wo, wi) = frame.to_local_pair(wo, wi);
        let sums = S::sum(&p, &terms, wo, wi, job.mode);
        match ring.as_deref_mut() {
            Some(ring) => {
                if i >= DELAY {
                    let at = i - DELAY;
                    delay::release_eval::<L, false>(ring, &mut value, job.pdf, at, shifts, len);
                }
                let [r, g, b, pdf] = &mut *ring;
                let mut rgb = Some([&mut r[..], &mut g[..], &mut b[..]]);
                store_sums(sums, &mut rgb, pdf, i % DELAY, L::LANES);
                delay::wrap_eval::<L>(ring, &mut value, job.pdf, i);
            }
            None if LATE => later = Some((sums, i, n)),
            None => store_sums(sums, &mut value, job.pdf, i, n),
        }
    }
    if let Some((sums, k, m)) = pending {
        store_sums(sums, &mut value, job.pdf, k, m);
    }
    if let Some((sums, k, m)) = later {
        store_sums(sums, &mut value, job.pdf, k, m);
    }
    if let Some(ring) = ring {
        for k in delay::held(len, L::LANES) {
            delay::release_eval::<L, true>(ring, &mut value, job.pdf, k, shifts, len);
        }
    }
    true
}

/// Lanes ahead of its loads that a streaming fused eval prefetches its input rows
/// (512 bytes a row). AMD EPYC (Zen 5), the full Disney closure over
/// `bench_vs_mitsuba.py`'s arrays at 1M lanes (`bench_glint_pair.py`, 9 rounds each):
/// AVX-512 eval +20% to +31% at 128 lanes ahead (32: none, 64: +25%, 256: +16% to
/// +33%, 1024: +10%, 4096: +1%); AVX2 +27%. At 4096 lanes, whose rows the benchmark's
/// loop keeps in cache, it cost up to 7%: there it is off.
pub const EVAL_AHEAD: usize = 128;

/// [`EVAL_AHEAD`] of the fused sample, whose registers take about four times as
/// long: about as far ahead in time. Same machine and arrays, AVX-512: +10% and +11%
/// at 128 lanes, 64 another +7% (32: -11%, 256: +3% to +5%); AVX2 at 128 lanes +7%.
pub const SAMPLE_AHEAD: usize = 64;

/// The lines of `rows` (of `len` lanes) `AHEAD` lanes past the register of lanes `i..`
/// asked for: a line a row for each 16 lanes of the register.
#[inline(always)]
fn prefetch_ahead<L: Lane, const AHEAD: usize>(rows: [[&[f32]; 3]; 2], i: usize, len: usize) {
    let at = i + AHEAD;
    let [[a, b, c], [d, e, f]] = rows;
    if at < len {
        for k in 0..L::LANES.div_ceil(16) {
            for row in [a, b, c, d, e, f] {
                crate::simd::prefetch(row, at + 16 * k);
            }
        }
    }
}

/// The three rows cut to their first `len` lanes.
#[inline(always)]
fn cut3(rows: [&[f32]; 3], len: usize) -> [&[f32]; 3] {
    let [x, y, z] = rows;
    [&x[..len], &y[..len], &z[..len]]
}

/// [`load3`] of the register at lane `i`, which may lie past the rows' end (no lane
/// is read there).
#[inline(always)]
fn ahead<L: Lane>(rows: [&[f32]; 3], i: usize) -> Vec3<L> {
    let i = i.min(rows[0].len());
    load3(rows, i, L::LANES.min(rows[0].len() - i))
}

/// A closure's lobe indices as [`Shape::sample`]'s labels.
const LOBE_LABELS: [f32; MAX_FUSED] = [0.0, 1.0, 2.0, 3.0];

/// One register of a fused mixture sample ([`sample_register`]).
struct RegisterSample<L: Lane> {
    /// The chosen lobe's sample, `wi` in world space, not finished; its value and pdf
    /// are not read.
    sample: Sample<L>,
    /// Every lobe's eval at `wi`.
    evals: [Eval<L>; MAX_FUSED],
    /// The lanes that chose each lobe.
    mine: [L::Mask; MAX_FUSED],
}

impl<L: Lane> RegisterSample<L> {
    /// The mixture's value and `sum p_k pdf_k` at `wi`: the closure's eval there, to
    /// the bit, as the grouped paths sum it (every lobe evaluated on every lane).
    #[inline(always)]
    fn mixture(&self, terms: &[Term<L>; MAX_FUSED], lobes: usize) -> (Rgb<L>, L) {
        sum_evals(terms, &self.evals, lobes)
    }

    /// The chosen lobe's eval and its term, selected per lane.
    #[inline(always)]
    fn own(&self, terms: &[Term<L>; MAX_FUSED], lobes: usize) -> (Eval<L>, Term<L>) {
        let (mut value, mut term) = (self.evals[0].value, terms[0]);
        let lobe = self.evals.iter().zip(terms).zip(self.mine);
        for ((e, t), mine) in lobe.take(lobes).skip(1) {
            value = Rgb::select(mine, e.value, value);
            term = Term {
                weight: Rgb::select(mine, t.weight, term.weight),
                probability: L::select(mine, t.probability, term.probability),
            };
        }
        let pdf = self.own_pdf(lobes);
        (Eval { value, pdf }, term)
    }

    /// The chosen lobe's pdf, selected per lane. An index loop: with
    /// `iter().enumerate()` the material sample in the expansion's pass took 284
    /// instructions a lane instead of 242 (callgrind).
    #[inline(always)]
    fn own_pdf(&self, lobes: usize) -> L {
        let mut pdf = self.evals[0].pdf;
        for k in 1..lobes {
            pdf = L::select(self.mine[k], self.evals[k].pdf, pdf);
        }
        pdf
    }
}

/// Each lane samples its chosen lobe (`chosen` as [`Shape::sample`]) from the local
/// `wo` in `frame`; the direction is settled as the lobe's sampler settles it, which
/// is where an eval given the returned `wi` sees it (`Directions::Sampled`), and every
/// lobe is evaluated there: the chosen one's eval is the value and pdf its sampler
/// computes.
#[inline(always)]
fn sample_register<S: Shape, L: Lane>(
    p: &S::Prepared<L>,
    (chosen, labels): (L, &[f32; MAX_FUSED]),
    (frame, wo): (LaneFrame<L>, Vec3<L>),
    u: [L; 3],
    mode: Transport,
) -> RegisterSample<L> {
    const { assert!(S::SMOOTH, "a fused shape's samples are never delta events") };
    let s = S::sample(p, (chosen, labels), wo, u, mode);
    let mut settle = ToWorld::new(frame);
    let wi = settle.settle(s.wi);
    let sample = Sample {
        wi: settle.world,
        valid: both_above(wo, wi),
        ..s
    };
    let mut mine = [L::Mask::splat(false); MAX_FUSED];
    for (m, &label) in mine.iter_mut().zip(labels).take(S::LOBES) {
        *m = chosen.eq(L::splat(label));
    }
    RegisterSample {
        sample,
        evals: S::evals(p, wo, wi, mode),
        mine,
    }
}

/// A mixture sample over the caller's rows, each register sampled, evaluated and
/// finished in one pass (no grouping of lanes by lobe): every lobe samples each lane
/// and the lane keeps its chosen lobe's direction; every lobe is evaluated there (the
/// settled direction, where an eval given the returned `wi` evaluates) and the sums
/// are the closure's eval, so the outputs are those of the grouped path, bit for bit.
pub struct FusedSampleJob<'a> {
    pub mode: Transport,
    pub frame: Frame,
    /// The closure's lobes in order (as [`FusedEvalJob::lobes`]).
    pub lobes: [FusedLobe<'a>; MAX_FUSED],
    /// The caller's `wo` ([`Directions::Raw`]) and random numbers: the lobe choice,
    /// then the direction's two dimensions.
    pub wo: [&'a [f32]; 3],
    pub u: [&'a [f32]; 3],
    pub out: FinishOutput<'a>,
    /// The rows of a ring to hold the outputs back in ([`delay`]), as many as `out`
    /// has, for calls that stream.
    pub held: Option<FinishOutput<'a>>,
    /// As [`FusedEvalJob::prefetch`].
    pub prefetch: bool,
}

impl FusedSampleJob<'_> {
    /// Whether a row it writes [`delay::collide`]s with one it reads (of the rows
    /// every sample writes).
    pub fn rows_collide(&self) -> bool {
        let ([a, b, c], [d, e, f]) = (self.wo, self.u);
        let o = &self.out;
        let [w0, w1, w2] = &o.wi;
        let [g0, g1, g2] = &o.weight;
        let writes = [&**w0, &**w1, &**w2, &*o.pdf, &**g0, &**g1, &**g2];
        delay::collide(&[a, b, c, d, e, f], &writes)
    }
}

/// [`sample_lanes`] two registers at a time (`Lane::Interleaved`): a register's
/// sample waits on its chain of divisions and square roots, the other's fills the
/// gaps (full Disney closure: AVX-512 85.6 -> 114.5 M lanes/s, AVX2 58.3 -> 69.5).
#[inline(always)]
fn sample_body<S: Shape, L: Lane>(job: &mut FusedSampleJob<'_>) -> bool {
    sample_lanes::<S, L::Interleaved>(job, None)
}

/// [`sample_body`] with the outputs held back in the job's ring ([`delay`]).
#[inline(always)]
fn sample_held_body<S: Shape, L: Lane>(job: &mut FusedSampleJob<'_>) -> bool {
    let ring = job.held.take();
    sample_lanes::<S, L::Interleaved>(job, ring)
}

/// The lanes of a fused sample, their outputs held back in `ring` when given.
#[inline(always)]
fn sample_lanes<'a, S: Shape, L: Lane>(
    job: &mut FusedSampleJob<'a>,
    mut ring: Option<FinishOutput<'a>>,
) -> bool {
    let len = job.out.pdf.len();
    // Every row cut to `len` once, as in `eval_lanes` (AVX2 closure sample, paired
    // rounds in both orders: +1% and +4%).
    let (wo_rows, u_rows) = (cut3(job.wo, len), cut3(job.u, len));
    let mut direct = job.out.cut(len);
    // The ring whole, reborrowed for as long as `direct` (a `&mut` to either is a
    // register's output below, and `&mut` is invariant in its lifetime).
    let mut ring = ring.as_mut().map(|held| held.cut(held.pdf.len()));
    let (params, terms) = uniform::<L>(&job.lobes);
    let p = S::prepare::<L>(&params);
    let frame = LaneFrame::<L>::splat(&job.frame);
    let mut probabilities = [0.0f32; MAX_FUSED];
    for (q, l) in probabilities.iter_mut().zip(&job.lobes) {
        *q = l.probability;
    }
    let probabilities = &probabilities[..S::LOBES];
    let shifts = delay::sample_shifts::<L>(&direct);
    let mut out_of_range = false;
    for i in (0..len).step_by(L::LANES) {
        let n = L::LANES.min(len - i);
        if job.prefetch {
            prefetch_ahead::<L, SAMPLE_AHEAD>([wo_rows, u_rows], i, len);
        }
        let wo = direction(wo_rows, i, n, Directions::Raw, &mut out_of_range);
        let u_lobe = load::<L>(u_rows[0], i, n, 0.5);
        let u0 = load::<L>(u_rows[1], i, n, 0.5);
        let u1 = load::<L>(u_rows[2], i, n, 0.5);
        out_of_range |= !(u_lobe.is_finite() & u0.is_finite() & u1.is_finite()).all();
        if out_of_range {
            return false;
        }
        let Some((chosen, reused)) = mixture::choose(probabilities, u_lobe) else {
            return false;
        };
        let u = [reused, clamp_random(u0), clamp_random(u1)];
        let at = (frame, frame.to_local(wo));
        let (out, slot) = match ring.as_mut() {
            Some(held) => {
                if i >= DELAY {
                    let k = i - DELAY;
                    delay::release_sample::<L, false>(held, &mut direct, k, &shifts, len);
                }
                // A whole register: the ring's rows are long enough.
                (held, (i % DELAY, L::LANES))
            }
            None => (&mut direct, (i, n)),
        };
        sample_finished::<S, L>(&p, &terms, (chosen, at, u), job.mode, out, slot);
        if let Some(held) = ring.as_mut() {
            delay::wrap_sample::<L>(held, &mut direct, i);
        }
    }
    if let Some(held) = ring {
        for k in delay::held(len, L::LANES) {
            delay::release_sample::<L, true>(&held, &mut direct, k, &shifts, len);
        }
    }
    true
}

/// One register of a mixture sample: each lane samples lobe `chosen` (an index into
/// the shape's lobes) at `(frame, local wo)` with `u` (the rescaled lobe choice, then
/// the direction's two dimensions), every lobe is evaluated there
/// ([`sample_register`]), and the sample is finished (`mixture::finish`) into `out`'s
/// lanes `i..i + n`, the lobe output being `chosen`.
#[inline(always)]
pub fn sample_finished<S: Shape, L: Lane>(
    p: &S::Prepared<L>,
    terms: &[Term<L>; MAX_FUSED],
    (chosen, at, u): (L, (LaneFrame<L>, Vec3<L>), [L; 3]),
    mode: Transport,
    out: &mut FinishOutput<'_>,
    (i, n): (usize, usize),
) {
    let r = sample_register::<S, L>(p, (chosen, &LOBE_LABELS), at, u, mode);
    // Finished as the chosen lobe's sampler finishes it (`Sample::finish`) but for
    // the check of its value, which the mixture adds unclamped: a value not finite
    // makes the mixture's, and so the weight, not finite, and `mixture::finish` fails
    // the lane as the grouped path does. Only the own pdf is selected (a smooth shape
    // has no delta events, which would carry the own value).
    let sample = Sample {
        value: Rgb::zero(),
        pdf: r.own_pdf(S::LOBES),
        ..r.sample
    }
    .finish();
    let (value, pdf) = r.mixture(terms, S::LOBES);
    let c = mixture::finish(&sample, value, pdf);
    store_finished(&c, chosen, out, i, n);
}

/// One slot of a fused sample over a material batch's rows: its decoded blocks, weights
/// and selection probabilities per lane (value `p` of lane `j` at `p * len + j`).
#[derive(Clone, Copy)]
pub struct FusedRows<'a> {
    pub params: &'a [f32],
    pub param_count: usize,
    pub weight: &'a [f32],
    pub probability: &'a [f32],
}

/// A material batch's samples over its staged rows (`len` a multiple of
/// [`super::LANE_MULTIPLE`]), in one pass: each lane samples its chosen slot and every
/// slot is evaluated there ([`sample_register`]). The rows are what each slot's sample
/// kernel over its lanes and the mixture's evals write, the same bits.
pub struct FusedRowsJob<'a> {
    pub len: usize,
    pub mode: Transport,
    /// Each lane's frame: tangent, bitangent, normal, component `c` of axis `a` of lane
    /// `j` at `(3 a + c) len + j`.
    pub frame: &'a [f32],
    /// Unit `wo` (world space), and the random numbers: the lobe choice rescaled
    /// within the chosen slot's bin, then the direction's two dimensions.
    pub wo: [&'a [f32]; 3],
    pub u: [&'a [f32]; 3],
    /// The live slots in order (as many as the shape has), and their slot indices.
    pub slots: [FusedRows<'a>; MAX_FUSED],
    pub labels: [f32; MAX_FUSED],
    /// Each lane's chosen slot index.
    pub chosen: &'a [f32],
    pub out: RowsSample<'a>,
}

/// The rows a [`FusedRowsJob`] writes: the chosen slot's sample (`wi` in world space,
/// `weight * value`, `p * pdf`, eta, roughness, packed events) and the mixture's
/// value and pdf there.
pub struct RowsSample<'a> {
    pub wi: [&'a mut [f32]; 3],
    pub own_value: [&'a mut [f32]; 3],
    pub own_pdf: &'a mut [f32],
    pub eta: &'a mut [f32],
    pub roughness: &'a mut [f32],
    pub events: &'a mut [f32],
    pub value: [&'a mut [f32]; 3],
    pub pdf: &'a mut [f32],
}

#[inline(always)]
fn rows_body<S: Shape, L: Lane>(job: &mut FusedRowsJob<'_>) {
    rows_lanes::<S, L::Interleaved>(job);
}

/// [`rows_body`] over lanes of `L` (`len` is a multiple of [`super::LANE_MULTIPLE`],
/// which `MAX_LANES` makes a multiple of every lane count).
#[inline(always)]
fn rows_lanes<S: Shape, L: Lane>(job: &mut FusedRowsJob<'_>) {
    let len = job.len;
    let mut unused = false;
    for i in (0..len).step_by(L::LANES) {
        let mut terms = [Term::zero(); MAX_FUSED];
        let mut params = [Params::shared(&[]); MAX_FUSED];
        for k in 0..MAX_FUSED {
            let slot = &job.slots[k];
            if slot.weight.is_empty() {
                continue;
            }
            params[k] = Params::rows(slot.params, slot.param_count, len, i);
            terms[k] = Term {
                weight: rgb_at(slot.weight, 0, len, i),
                probability: L::load(&slot.probability[i..]),
            };
        }
        let p = S::prepare::<L>(&params);
        let frame = load_frame::<L>(job.frame, len, i);
        let wo = direction(job.wo, i, L::LANES, Directions::Unit, &mut unused);
        // No `map`: its closure would be a function without the kernel's target
        // features (tests/simd_inlining.rs).
        let u = [
            clamp_random(L::load(&job.u[0][i..])),
            clamp_random(L::load(&job.u[1][i..])),
            clamp_random(L::load(&job.u[2][i..])),
        ];
        let chosen = (L::load(&job.chosen[i..]), &job.labels);
        let at = (frame, frame.to_local(wo));
        let r = sample_register::<S, L>(&p, chosen, at, u, job.mode);
        // The chosen slot's sample, finished, weighted and its pdf times `p`, as its
        // sample kernel and `material_rows::chosen_pdf` leave them.
        let (own, term) = r.own(&terms, S::LOBES);
        let s = &Sample {
            value: own.value,
            pdf: own.pdf,
            ..r.sample
        }
        .finish();
        let (value, pdf) = r.mixture(&terms, S::LOBES);
        let out = &mut job.out;
        for (v, row) in [s.wi.x, s.wi.y, s.wi.z].into_iter().zip(out.wi.iter_mut()) {
            v.store(&mut row[i..]);
        }
        let own_value = term.weight * s.value;
        for (v, row) in own_value
            .to_array()
            .into_iter()
            .zip(out.own_value.iter_mut())
        {
            v.store(&mut row[i..]);
        }
        for (v, row) in value.to_array().into_iter().zip(out.value.iter_mut()) {
            v.store(&mut row[i..]);
        }
        (term.probability * s.pdf).store(&mut out.own_pdf[i..]);
        pdf.store(&mut out.pdf[i..]);
        s.eta.store(&mut out.eta[i..]);
        s.roughness.store(&mut out.roughness[i..]);
        pack_events(s).store(&mut out.events[i..]);
    }
}

kernel!(
    /// A fused shape's sample over a material batch's rows (`rows_body`).
    rows<S: Shape>(job: &mut FusedRowsJob<'_>) => rows_body
);
kernel!(
    /// A fused shape's eval over a job's lanes (`eval_body`); false when some
    /// direction is outside [`Directions::Raw`]'s range (outputs incomplete).
    eval<S: Shape>(job: &mut FusedEvalJob<'_>) -> bool => eval_body
);
kernel!(
    /// [`eval`] with each register's sums stored two registers later (`eval_late_body`).
    eval_late<S: Shape>(job: &mut FusedEvalJob<'_>) -> bool => eval_late_body
);
kernel!(
    /// [`eval`] with its outputs held back in the job's ring (`eval_held_body`).
    eval_held<S: Shape>(job: &mut FusedEvalJob<'_>) -> bool => eval_held_body
);
kernel!(
    /// A fused shape's mixture sample over a job's lanes (`sample_body`); false when
    /// some `wo` is outside [`Directions::Raw`]'s range or some random number is not
    /// finite (outputs incomplete).
    sample<S: Shape>(job: &mut FusedSampleJob<'_>) -> bool => sample_body
);
kernel!(
    /// [`sample`] with its outputs held back in the job's ring (`sample_held_body`).
    sample_held<S: Shape>(job: &mut FusedSampleJob<'_>) -> bool => sample_held_body
);

/// A fused eval kernel.
pub type FusedEval = fn(Kernels, &mut FusedEvalJob<'_>) -> bool;
/// A fused mixture sample kernel.
pub type FusedSample = fn(Kernels, &mut FusedSampleJob<'_>) -> bool;
/// A fused sample kernel over a material batch's rows.
pub type FusedRowsSample = fn(Kernels, &mut FusedRowsJob<'_>);
/// [`Shape::matches`] of a shape.
type Matches = fn(&[Option<TypeId>]) -> bool;

/// The fused shapes: those the `disney` material emits (its specular always, the
/// diffuse unless metallic 1, the sheen with the diffuse, the clearcoat unless 0).
type Diffuse = DisneyDiffuse;
type Sheen = DisneySheen;
type Specular = DisneySpecular;
type Clearcoat = DisneyClearcoat;
type Every = (Diffuse, Sheen, Specular, Clearcoat);
type NoClearcoat = (Diffuse, Sheen, Specular);
type NoSheen = (Diffuse, Specular, Clearcoat);
type Plastic = (Diffuse, Specular);
type Metal = (Specular, Clearcoat);
const SHAPES: [(
    Matches,
    FusedEval,
    FusedEval,
    FusedEval,
    FusedSample,
    FusedSample,
    FusedRowsSample,
); 5] = [
    (
        Every::matches,
        eval::<Every>,
        eval_late::<Every>,
        eval_held::<Every>,
        sample::<Every>,
        sample_held::<Every>,
        rows::<Every>,
    ),
    (
        NoClearcoat::matches,
        eval::<NoClearcoat>,
        eval_late::<NoClearcoat>,
        eval_held::<NoClearcoat>,
        sample::<NoClearcoat>,
        sample_held::<NoClearcoat>,
        rows::<NoClearcoat>,
    ),
    (
        NoSheen::matches,
        eval::<NoSheen>,
        eval_late::<NoSheen>,
        eval_held::<NoSheen>,
        sample::<NoSheen>,
        sample_held::<NoSheen>,
        rows::<NoSheen>,
    ),
    (
        Plastic::matches,
        eval::<Plastic>,
        eval_late::<Plastic>,
        eval_held::<Plastic>,
        sample::<Plastic>,
        sample_held::<Plastic>,
        rows::<Plastic>,
    ),
    (
        Metal::matches,
        eval::<Metal>,
        eval_late::<Metal>,
        eval_held::<Metal>,
        sample::<Metal>,
        sample_held::<Metal>,
        rows::<Metal>,
    ),
];

/// The fused sample over rows of the slots whose built-in models are `models`, in order,
/// when they are a shape.
pub fn for_rows(models: &[Option<TypeId>]) -> Option<FusedRowsSample> {
    if models.len() < 2 || models.len() > MAX_FUSED {
        return None;
    }
    let &(.., rows) = SHAPES.iter().find(|(matches, ..)| matches(models))?;
    Some(rows)
}

/// The fused kernels of a closure's shape, and its lobes as their jobs take them.
pub struct Fused<'a> {
    pub eval: FusedEval,
    /// `eval` storing each register's sums two registers later.
    pub eval_late: FusedEval,
    /// `eval` for a job with a ring ([`FusedEvalJob::held`]).
    pub eval_held: FusedEval,
    pub sample: FusedSample,
    /// `sample` for a job with a ring ([`FusedSampleJob::held`]).
    pub sample_held: FusedSample,
    pub lobes: [FusedLobe<'a>; MAX_FUSED],
}

/// The fused kernels of `closure`'s shape, when there are.
pub fn for_closure(closure: &Closure) -> Option<Fused<'_>> {
    let lobes = closure.lobes();
    if lobes.len() < 2 || lobes.len() > MAX_FUSED {
        return None;
    }
    let mut models = [None; MAX_FUSED];
    for (m, l) in models.iter_mut().zip(lobes) {
        *m = l.lobe.model();
    }
    let models = &models[..lobes.len()];
    let &(_, eval, eval_late, eval_held, sample, sample_held, _) =
        SHAPES.iter().find(|(matches, ..)| matches(models))?;
    let mut out = [FusedLobe {
        params: &[],
        weight: Rgb::new(0.0, 0.0, 0.0),
        probability: 0.0,
    }; MAX_FUSED];
    for (k, (o, l)) in out.iter_mut().zip(lobes).enumerate() {
        debug_assert!(closure.lobe_decoded(k).len() <= MAX_LOBE_PARAMS);
        *o = FusedLobe {
            params: closure.lobe_decoded(k),
            weight: l.weight,
            probability: l.probability,
        };
    }
    Some(Fused {
        eval,
        eval_late,
        eval_held,
        sample,
        sample_held,
        lobes: out,
    })
}
