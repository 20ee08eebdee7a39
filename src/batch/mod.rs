//! Batch evaluation over SoA arrays.
//!
//! A call is cut into blocks of [`BLOCK`] lanes (run on rayon workers when the
//! batch is large and the runtime allows threads). Within a block, active lanes are
//! grouped by closure shape (`Closure::same_shape`; for sampling, also by the lobe
//! each lane chose); each group's inputs are staged into padded SoA arrays, every
//! lobe of the shape runs its kernel once over the group (`crate::simd::kernels`),
//! and the results are scattered back in the caller's order. Inactive lanes are not
//! read, computed or written. Every lane's result depends only on its own inputs,
//! so results are identical whatever the thread count or the grouping.
//!
//! Lanes whose inputs are invalid (NaN, infinite or zero-length directions,
//! unfinished closures) get zeroed outputs, the other lanes are still computed, and
//! the call reports the first bad lane.

pub mod material;
mod stage;

use crate::closure::{Closure, MAX_LOBES, SampleResult};
use crate::error::{Error, Status};
use crate::kernels::{
    AlbedoJob, ClosureRows, Directions, EvalJob, LANE_MULTIPLE, LobeLanes, SampleJob, delay, fused,
    fused::{FusedEvalJob, FusedSampleJob},
    mixture,
};
use crate::kernels::{
    FinishJob, FinishLobe, FinishOutput, choose_lobes, finish_mixture, normalize, sort_rows,
    to_local, unpack_events, unsort_rows,
};
use crate::lobes::{LobeType, Sample};
use crate::math::lane::MAX_LANES;
use crate::math::{Frame, Rgb, Vec3};
use crate::simd::Kernels;
use stage::{Randoms, Scratch, grow, padded, rows3, stage_directions, view3, with_scratch};
use std::fmt;
use std::ops::Range;

/// Lanes per work item: a group's staged arrays stay in the L2 cache.
pub const BLOCK: usize = 4096;

/// Where each lane's closure comes from.
pub trait ClosureSource<'a>: Sync {
    fn closure(&self, lane: usize) -> Result<&'a Closure, Error>;
    /// Whether every lane has the same closure.
    fn is_shared(&self) -> bool {
        false
    }
    /// How many lanes have a closure, when known.
    fn lane_count(&self) -> Option<usize> {
        None
    }
}

/// One closure shared by every lane.
impl<'a> ClosureSource<'a> for &'a Closure {
    fn closure(&self, _lane: usize) -> Result<&'a Closure, Error> {
        Ok(self)
    }
    fn is_shared(&self) -> bool {
        true
    }
}

/// One closure per lane.
impl<'a> ClosureSource<'a> for &'a [&'a Closure] {
    fn closure(&self, lane: usize) -> Result<&'a Closure, Error> {
        Ok(self[lane])
    }
    fn lane_count(&self) -> Option<usize> {
        Some(<[&Closure]>::len(self))
    }
}

/// Which threads a batch call may use.
#[derive(Clone, Copy)]
pub enum Threads<'a> {
    /// Only the calling thread.
    Caller,
    /// Rayon's global pool.
    Global,
    /// A runtime's own pool (`threads=N`).
    Pool(&'a rayon::ThreadPool),
}

/// How a batch call runs: its kernel set and its threads.
#[derive(Clone, Copy)]
pub struct Exec<'a> {
    pub kernels: Kernels,
    pub threads: Threads<'a>,
}

impl Exec<'static> {
    /// Scalar kernels on the calling thread.
    pub fn scalar() -> Self {
        Exec {
            kernels: Kernels::scalar(),
            threads: Threads::Caller,
        }
    }
}

/// Three SoA component arrays.
#[derive(Clone, Copy)]
pub struct Soa3<'a> {
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
}

/// Mutable SoA component arrays.
pub struct Soa3Mut<'a> {
    pub x: &'a mut [f32],
    pub y: &'a mut [f32],
    pub z: &'a mut [f32],
}

impl Soa3Mut<'_> {
    fn set(&mut self, lane: usize, v: [f32; 3]) {
        self.x[lane] = v[0];
        self.y[lane] = v[1];
        self.z[lane] = v[2];
    }
}

/// Most lanes one batch call takes (`GLINT_MAX_BATCH_COUNT`): lanes are indexed by
/// 32-bit integers, and every array of that many pointers fits in `isize::MAX` bytes.
pub const MAX_COUNT: usize = u32::MAX as usize;

/// A count beyond [`MAX_COUNT`] is refused before any array is touched.
pub fn check_count(count: usize) -> Result<(), Error> {
    if count > MAX_COUNT {
        return Err(Error::new(
            Status::OutOfRange,
            format!("count = {count} exceeds the largest batch, {MAX_COUNT} lanes"),
        ));
    }
    Ok(())
}

/// An array the call reads or writes must hold `count` lanes. `what` is formatted only
/// for the error: a valid call allocates nothing but its staging, which may fail.
fn check_len(len: usize, count: usize, what: impl fmt::Display) -> Result<(), Error> {
    if len < count {
        return Err(Error::new(
            Status::InvalidArgument,
            format!("{what} has {len} lanes but count is {count}"),
        ));
    }
    Ok(())
}

/// Outputs cut at a lane, so that blocks are handed out without a list of them.
trait SplitLanes: Sized + Send {
    /// `(lanes ..lanes, lanes lanes..)`.
    fn split_lanes(self, lanes: usize) -> (Self, Self);
}

impl<T: Send> SplitLanes for &mut [T] {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        self.split_at_mut(lanes)
    }
}

impl<S: SplitLanes> SplitLanes for Option<S> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        match self {
            Some(s) => {
                let (a, b) = s.split_lanes(lanes);
                (Some(a), Some(b))
            }
            None => (None, None),
        }
    }
}

impl SplitLanes for Soa3Mut<'_> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        let (x, x2) = self.x.split_lanes(lanes);
        let (y, y2) = self.y.split_lanes(lanes);
        let (z, z2) = self.z.split_lanes(lanes);
        (
            Soa3Mut { x, y, z },
            Soa3Mut {
                x: x2,
                y: y2,
                z: z2,
            },
        )
    }
}

impl Soa3<'_> {
    #[inline]
    fn check(&self, count: usize, what: &str) -> Result<(), Error> {
        if self.x.len() >= count && self.y.len() >= count && self.z.len() >= count {
            return Ok(());
        }
        for (len, axis) in [
            (self.x.len(), "x"),
            (self.y.len(), "y"),
            (self.z.len(), "z"),
        ] {
            check_len(len, count, format_args!("{what}.{axis}"))?;
        }
        Ok(())
    }
}

impl Soa3Mut<'_> {
    fn check(&self, count: usize, what: &str) -> Result<(), Error> {
        Soa3 {
            x: self.x,
            y: self.y,
            z: self.z,
        }
        .check(count, what)
    }
}

/// Shared inputs of every batch call.
pub struct BatchInput<'a, C> {
    pub count: usize,
    pub closures: C,
    /// Nonzero = active; `None` = all lanes active.
    pub active: Option<&'a [u8]>,
    pub wo: Soa3<'a>,
}

impl<'a, C: ClosureSource<'a>> BatchInput<'a, C> {
    fn is_active(&self, lane: usize) -> bool {
        self.active.is_none_or(|a| a[lane] != 0)
    }

    /// The count is within [`MAX_COUNT`] and every input array holds `count` lanes.
    fn check(&self) -> Result<(), Error> {
        check_count(self.count)?;
        if let Some(len) = self.closures.lane_count() {
            check_len(len, self.count, "closures")?;
        }
        if let Some(a) = self.active {
            check_len(a.len(), self.count, "active")?;
        }
        self.wo.check(self.count, "wo")
    }
}

/// Run `block(start, out)` for every block of `count` lanes, in parallel when the
/// batch is large enough and `exec` allows; the error of the lowest failing lane wins.
fn run_blocks<O: SplitLanes>(
    exec: &Exec<'_>,
    count: usize,
    out: O,
    block: impl Fn(usize, O) -> Result<(), Error> + Sync,
) -> Result<(), Error> {
    match exec.threads {
        _ if count == 0 => Ok(()),
        _ if count <= BLOCK => block(0, out),
        Threads::Caller => split_blocks(0, count, out, false, &block),
        Threads::Global => split_blocks(0, count, out, true, &block),
        Threads::Pool(pool) => pool.install(|| split_blocks(0, count, out, true, &block)),
    }
}

/// The blocks of lanes `start .. start + count`, halved at a block boundary until one
/// is left (on two rayon workers when `parallel`); the lower half's error wins.
fn split_blocks<O: SplitLanes>(
    start: usize,
    count: usize,
    out: O,
    parallel: bool,
    block: &(impl Fn(usize, O) -> Result<(), Error> + Sync),
) -> Result<(), Error> {
    if count <= BLOCK {
        return block(start, out);
    }
    let half = count.div_ceil(BLOCK) / 2 * BLOCK;
    let (low, high) = out.split_lanes(half);
    let low = || split_blocks(start, half, low, parallel, block);
    let high = || split_blocks(start + half, count - half, high, parallel, block);
    let (a, b) = if parallel {
        rayon::join(low, high)
    } else {
        (low(), high())
    };
    a.and(b)
}

/// Outputs of [`eval`].
pub struct EvalOutput<'a> {
    pub value: Soa3Mut<'a>,
    pub pdf: &'a mut [f32],
    pub pdf_reverse: Option<&'a mut [f32]>,
}

/// `eval` on every active lane.
pub fn eval<'a, C: ClosureSource<'a>>(
    exec: &Exec<'_>,
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    out: EvalOutput<'_>,
) -> Result<(), Error> {
    let n = input.count;
    input.check()?;
    wi.check(n, "wi")?;
    out.value.check(n, "value")?;
    check_len(out.pdf.len(), n, "pdf")?;
    if let Some(rev) = &out.pdf_reverse {
        check_len(rev.len(), n, "pdf_reverse")?;
    }
    let out = EvalBlockOutput {
        value: Some(out.value),
        pdf: out.pdf,
        pdf_reverse: out.pdf_reverse,
    };
    run_blocks(exec, n, out, |start, mut out| {
        eval_block(exec.kernels, input, wi, start, &mut out)
    })
}

/// `pdf` on every active lane.
pub fn pdf<'a, C: ClosureSource<'a>>(
    exec: &Exec<'_>,
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    out: &mut [f32],
) -> Result<(), Error> {
    input.check()?;
    wi.check(input.count, "wi")?;
    check_len(out.len(), input.count, "pdf")?;
    let out = EvalBlockOutput {
        value: None,
        pdf: out,
        pdf_reverse: None,
    };
    run_blocks(exec, input.count, out, |start, mut out| {
        eval_block(exec.kernels, input, wi, start, &mut out)
    })
}

/// One block's eval or pdf outputs; `None` = not wanted.
struct EvalBlockOutput<'o> {
    value: Option<Soa3Mut<'o>>,
    pdf: &'o mut [f32],
    pdf_reverse: Option<&'o mut [f32]>,
}

impl SplitLanes for EvalBlockOutput<'_> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        let (value, value2) = self.value.split_lanes(lanes);
        let (pdf, pdf2) = self.pdf.split_lanes(lanes);
        let (rev, rev2) = self.pdf_reverse.split_lanes(lanes);
        (
            EvalBlockOutput {
                value,
                pdf,
                pdf_reverse: rev,
            },
            EvalBlockOutput {
                value: value2,
                pdf: pdf2,
                pdf_reverse: rev2,
            },
        )
    }
}

/// Eval the block starting at lane `start`: in place, chunk by chunk, when every
/// lane shares one closure that runs in place, else through staging.
fn eval_block<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    start: usize,
    out: &mut EvalBlockOutput<'_>,
) -> Result<(), Error> {
    let end = (start + BLOCK).min(input.count);
    let staged = |range: Range<usize>, out: &mut EvalBlockOutput<'_>| {
        with_scratch(|s| eval_staged(kernels, input, wi, range, start, s, out))
    };
    let Some(closure) = in_place(input) else {
        return staged(start..end, out);
    };
    // A fused shape runs over the whole block in one call (per chunk, finding the
    // shape and preparing its lobes took 7% of a Disney closure's eval); when some
    // lane's direction needs staging, the chunks below redo the block.
    if fused_eval(kernels, closure, input.wo, wi, start..end, start, out) == Some(true) {
        return Ok(());
    }
    // In place needs no scratch buffers: a chunk takes them only to be staged. Its
    // directions in a frame all its lobes share go on the stack.
    let mut local = [[0.0f32; CHUNK]; 6];
    in_chunks(start..end, CHUNK, |chunk| {
        let (wo, range) = (input.wo, chunk.clone());
        if eval_in_place(kernels, closure, wo, wi, range, start, &mut local, out) {
            Ok(())
        } else {
            staged(chunk, out)
        }
    })
}

/// Lanes of an in-place chunk: each lobe of the closure passes over the chunk while
/// its outputs are in the L1 cache.
const CHUNK: usize = 256;

/// The closure every lane shares, when the block can run in place: no active mask,
/// a finished closure whose lobes all have SIMD kernels.
fn in_place<'a, C: ClosureSource<'a>>(input: &BatchInput<'a, C>) -> Option<&'a Closure> {
    if input.active.is_some() || !input.closures.is_shared() {
        return None;
    }
    let c = input.closures.closure(0).ok()?;
    (c.is_finished() && c.lobes().iter().all(|l| l.lobe.has_kernels())).then_some(c)
}

/// Lanes of a chunk of an in-place mixture sample: its many jobs (a sample, evals on
/// the other lobes' runs and a finish per lobe) read their lobe's parameters once
/// per job, and its rows stay in the L2 cache.
const MIXTURE_CHUNK: usize = 1024;

/// Rows of a mixture chunk sorted by lobe, each lobe's run in whole registers, and
/// one register past the last run (`kernels::sort_rows` stores whole registers).
const MIXTURE_ROWS: usize = MIXTURE_CHUNK + MAX_LOBES * LANE_MULTIPLE + MAX_LANES;

/// Run `chunk` on every chunk of `size` lanes of `range`; every chunk runs, the
/// first error wins.
fn in_chunks(
    range: Range<usize>,
    size: usize,
    mut chunk: impl FnMut(Range<usize>) -> Result<(), Error>,
) -> Result<(), Error> {
    let mut result = Ok(());
    for lo in range.clone().step_by(size) {
        let r = chunk(lo..(lo + size).min(range.end));
        if result.is_ok() {
            result = r;
        }
    }
    result
}

/// Lanes `lanes` of the caller's rows.
fn rows<'r>(v: Soa3<'r>, lanes: &Range<usize>) -> [&'r [f32]; 3] {
    [v.x, v.y, v.z].map(|row| &row[lanes.clone()])
}

/// Lanes `run` of scratch rows.
fn view_run<'r>(v: &'r [Vec<f32>; 3], run: &Range<usize>) -> [&'r [f32]; 3] {
    [&v[0][run.clone()], &v[1][run.clone()], &v[2][run.clone()]]
}

/// Lanes `run` of mutable scratch rows.
fn run_mut<'r>(v: &'r mut [Vec<f32>; 3], run: &Range<usize>) -> [&'r mut [f32]; 3] {
    let [a, b, c] = v;
    [
        &mut a[run.clone()],
        &mut b[run.clone()],
        &mut c[run.clone()],
    ]
}

/// Lanes `lanes` of mutable output rows.
fn rows_mut<'r>(v: &'r mut Soa3Mut<'_>, lanes: &Range<usize>) -> [&'r mut [f32]; 3] {
    [
        &mut v.x[lanes.clone()],
        &mut v.y[lanes.clone()],
        &mut v.z[lanes.clone()],
    ]
}

/// Lobe `k` of a closure shared by every lane.
fn uniform_lobe(closure: &Closure, k: usize) -> LobeLanes<'_> {
    let l = &closure.lobes()[k];
    LobeLanes::Uniform {
        params: closure.lobe_decoded(k),
        frame: l.frame,
        weight: l.weight,
        probability: l.probability,
    }
}

/// Eval lanes `lanes` of a fused shape in one pass, as [`eval_in_place`]; `None` when
/// the closure is not one (or a reverse pdf is wanted).
fn fused_eval(
    kernels: Kernels,
    closure: &Closure,
    wo: Soa3<'_>,
    wi: Soa3<'_>,
    lanes: Range<usize>,
    base: usize,
    out: &mut EvalBlockOutput<'_>,
) -> Option<bool> {
    let frame = shared_frame(closure)?;
    if out.pdf_reverse.is_some() {
        return None;
    }
    let fused = fused::for_closure(closure)?;
    let local = lanes.start - base..lanes.end - base;
    let mut job = FusedEvalJob {
        mode: closure.transport(),
        frame,
        wo: rows(wo, &lanes),
        wi: rows(wi, &lanes),
        lobes: fused.lobes,
        value: out.value.as_mut().map(|v| rows_mut(v, &local)),
        pdf: &mut out.pdf[local],
        held: None,
        prefetch: delay::streaming(wo.x.len()),
    };
    if delay::streams(kernels, wo.x.len(), lanes.len()) && job.rows_collide() {
        return Some(with_scratch(|s| {
            (fused.eval_held)(kernels, &mut job.with_ring(s.rings.eval()))
        }));
    }
    let eval = if kernels.stores().hold() {
        fused.eval_late
    } else {
        fused.eval
    };
    Some(eval(kernels, &mut job))
}

/// Eval lanes `lanes` in place: the kernels read the caller's directions and write
/// `out` (whose lane 0 is lane `base`). False when some direction needs the staged
/// path's exact normalization or error (the outputs are then incomplete).
#[allow(clippy::too_many_arguments)]
fn eval_in_place(
    kernels: Kernels,
    closure: &Closure,
    wo: Soa3<'_>,
    wi: Soa3<'_>,
    lanes: Range<usize>,
    base: usize,
    local_rows: &mut [[f32; CHUNK]; 6],
    out: &mut EvalBlockOutput<'_>,
) -> bool {
    let local = lanes.start - base..lanes.end - base;
    if closure.lobes().is_empty() {
        if let Some(v) = out.value.as_mut() {
            for row in rows_mut(v, &local) {
                row.fill(0.0);
            }
        }
        out.pdf[local.clone()].fill(0.0);
        if let Some(rev) = out.pdf_reverse.as_deref_mut() {
            rev[local].fill(0.0);
        }
        return true;
    }
    // Lobes that share one frame (a material's) take the directions into it once:
    // normalized as `Directions::Raw` would, the same bits; a fused shape evaluates
    // them all in one pass, with the same bits.
    let n = lanes.len();
    if let Some(done) = fused_eval(kernels, closure, wo, wi, lanes.clone(), base, out) {
        return done;
    }
    let frame = shared_frame(closure);
    let (wo, wi, directions) = if let Some(frame) = frame {
        let [a, b, c, d, e, f] = local_rows;
        let (mut wo_local, mut wi_local) = (
            [&mut a[..n], &mut b[..n], &mut c[..n]],
            [&mut d[..n], &mut e[..n], &mut f[..n]],
        );
        let raw = Directions::Raw;
        if !to_local(kernels, &frame, raw, rows(wo, &lanes), &mut wo_local)
            || !to_local(kernels, &frame, raw, rows(wi, &lanes), &mut wi_local)
        {
            return false;
        }
        let [a, b, c, d, e, f] = &*local_rows;
        (
            [&a[..n], &b[..n], &c[..n]],
            [&d[..n], &e[..n], &f[..n]],
            Directions::Local,
        )
    } else {
        (rows(wo, &lanes), rows(wi, &lanes), Directions::Raw)
    };
    for (k, l) in closure.lobes().iter().enumerate() {
        let mut job = EvalJob {
            len: n,
            mode: closure.transport(),
            directions,
            wo,
            wi,
            lobe: uniform_lobe(closure, k),
            store: k == 0,
            value: out.value.as_mut().map(|v| rows_mut(v, &local)),
            pdf: &mut out.pdf[local.clone()],
            out_of_range: false,
        };
        l.lobe.eval_lanes(kernels, &mut job);
        if job.out_of_range {
            return false;
        }
        if let Some(rev) = out.pdf_reverse.as_deref_mut() {
            let mut job = EvalJob {
                wo: wi,
                wi: wo,
                value: None,
                pdf: &mut rev[local.clone()],
                ..job
            };
            l.lobe.eval_lanes(kernels, &mut job);
        }
    }
    true
}

/// The frame every lobe of `closure` has, when it has more than one lobe and they
/// share it (a material's): in-place evals take their directions into it once
/// ([`Directions::Local`]).
fn shared_frame(closure: &Closure) -> Option<Frame> {
    let (first, rest) = closure.lobes().split_first()?;
    (!rest.is_empty() && rest.iter().all(|l| l.frame == first.frame)).then_some(first.frame)
}

/// Eval lanes `range` through grouping and staging; `out`'s lane 0 is lane `base`.
fn eval_staged<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    range: Range<usize>,
    base: usize,
    s: &mut Scratch,
    out: &mut EvalBlockOutput<'_>,
) -> Result<(), Error> {
    s.groups.build(input, range, None)?;
    for g in 0..s.groups.groups().len() {
        let (len, closure) = begin_group(input, s, g)?;
        stage_input(kernels, input, s, g, len, Some(wi));
        let (value, reverse) = (out.value.is_some(), out.pdf_reverse.is_some());
        eval_lobes(kernels, input, s, g, closure, false, value, reverse);
        let group = &s.groups.groups()[g];
        let scatter = Scatter::new(&group.lanes, base, &s.failed, s.any_failed);
        if let Some(v) = out.value.as_mut() {
            scatter.rows(&s.value, [&mut *v.x, &mut *v.y, &mut *v.z]);
        }
        scatter.row(&s.pdf, out.pdf);
        if let Some(rev) = out.pdf_reverse.as_deref_mut() {
            scatter.row(&s.pdf_reverse, rev);
        }
    }
    finish_block(s, base, |lane| {
        if let Some(v) = out.value.as_mut() {
            v.set(lane, [0.0; 3]);
        }
        out.pdf[lane] = 0.0;
        if let Some(rev) = out.pdf_reverse.as_deref_mut() {
            rev[lane] = 0.0;
        }
    })
}

/// Accumulate every lobe of group `g`'s `closure` at the staged `wo` and `wi`, in
/// lobe order: the pdf into `s.pdf`, with `want_value` the value into `s.value`, with
/// `want_reverse` the pdf of `wi` to `wo` into `s.pdf_reverse`. `sampled`: `wi` is a
/// sample's, returned as it is (`Directions::Sampled`).
#[allow(clippy::too_many_arguments)]
fn eval_lobes<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    s: &mut Scratch,
    g: usize,
    closure: &Closure,
    sampled: bool,
    want_value: bool,
    want_reverse: bool,
) {
    let Scratch {
        groups,
        lobe,
        wo,
        wi,
        value,
        pdf,
        pdf_reverse,
        ..
    } = s;
    let group = &groups.groups()[g];
    let len = padded(group.lanes.len());
    for (k, l) in closure.lobes().iter().enumerate() {
        let lanes = lobe.lanes(input, group, k, len, false);
        let [vr, vg, vb] = &mut *value;
        let mut job = EvalJob {
            len,
            mode: closure.transport(),
            directions: if sampled {
                Directions::Sampled
            } else {
                Directions::Unit
            },
            wo: view3(wo, len),
            wi: view3(wi, len),
            lobe: lanes,
            store: false,
            value: want_value.then(|| [&mut vr[..len], &mut vg[..len], &mut vb[..len]]),
            pdf: &mut pdf[..len],
            out_of_range: false,
        };
        l.lobe.eval_lanes(kernels, &mut job);
        if want_reverse {
            eval_reverse(kernels, &*l.lobe, job, pdf_reverse);
        }
    }
}

/// Group `g`'s length padded to whole registers and its representative closure, with
/// the scratch buffers reserved for it.
fn begin_group<'a, C: ClosureSource<'a>>(
    input: &BatchInput<'a, C>,
    s: &mut Scratch,
    g: usize,
) -> Result<(usize, &'a Closure), Error> {
    let group = &s.groups.groups()[g];
    let len = padded(group.lanes.len());
    let closure = input.closures.closure(group.rep).expect("resolved before");
    s.reset(len, closure)?;
    Ok((len, closure))
}

/// Stage group `g`'s `wo` (and `wi`) into the scratch rows.
fn stage_input<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    s: &mut Scratch,
    g: usize,
    len: usize,
    wi: Option<Soa3<'_>>,
) {
    let Scratch {
        groups,
        wo: wo_rows,
        wi: wi_rows,
        failed,
        any_failed,
        ..
    } = s;
    let lanes = std::mem::take(&mut groups.list_mut()[g].lanes);
    let mut stage = |src: Soa3<'_>, what: &str, rows: &mut [Vec<f32>; 3]| {
        *any_failed |= stage_directions(
            kernels,
            src,
            what,
            &lanes,
            rows3(rows, len),
            failed,
            &mut groups.error,
        );
    };
    stage(input.wo, "wo", wo_rows);
    if let Some(wi) = wi {
        stage(wi, "wi", wi_rows);
    }
    groups.list_mut()[g].lanes = lanes;
}

/// Writes a group's staged results back to the caller's lanes.
struct Scatter<'g> {
    lanes: &'g [u32],
    start: usize,
    /// The group's lanes are `first .. first + len` (block-local).
    contiguous: Option<usize>,
    failed: Option<&'g [u8]>,
}

impl<'g> Scatter<'g> {
    fn new(lanes: &'g [u32], start: usize, failed: &'g [u8], any_failed: bool) -> Self {
        let contiguous = match (lanes.first(), lanes.last()) {
            (Some(&a), Some(&b)) if (b - a) as usize + 1 == lanes.len() => Some(a as usize - start),
            _ => None,
        };
        Scatter {
            lanes,
            start,
            contiguous,
            failed: any_failed.then_some(failed),
        }
    }

    /// `out[lane] = staged[j]` for the group's `j`-th lane; failed lanes get 0.
    fn row<T: Copy + Default>(&self, staged: &[T], out: &mut [T]) {
        let n = self.lanes.len();
        match self.contiguous {
            Some(first) => out[first..first + n].copy_from_slice(&staged[..n]),
            None => {
                for (j, &lane) in self.lanes.iter().enumerate() {
                    out[lane as usize - self.start] = staged[j];
                }
            }
        }
        if let Some(failed) = self.failed {
            for (j, &lane) in self.lanes.iter().enumerate() {
                if failed[j] != 0 {
                    out[lane as usize - self.start] = T::default();
                }
            }
        }
    }

    fn rows(&self, staged: &[Vec<f32>; 3], out: [&mut [f32]; 3]) {
        for (row, out) in staged.iter().zip(out) {
            self.row(row, out);
        }
    }
}

/// Zero-output the lanes that failed before grouping; the block's first error.
fn finish_block(s: &mut Scratch, start: usize, mut zero: impl FnMut(usize)) -> Result<(), Error> {
    for &lane in &s.groups.failed {
        zero(lane as usize - start);
    }
    s.groups.take_error().map_or(Ok(()), Err)
}

/// Directional albedo of every active lane's closure.
pub fn albedo<'a, C: ClosureSource<'a>>(
    exec: &Exec<'_>,
    input: &BatchInput<'a, C>,
    out: Soa3Mut<'_>,
) -> Result<(), Error> {
    input.check()?;
    out.check(input.count, "albedo")?;
    let kernels = exec.kernels;
    run_blocks(exec, input.count, out, |start, mut out| {
        let end = (start + BLOCK).min(input.count);
        let staged = |range: Range<usize>, out: &mut Soa3Mut<'_>| {
            with_scratch(|s| albedo_staged(kernels, input, range, start, s, out))
        };
        let Some(closure) = in_place(input) else {
            return staged(start..end, &mut out);
        };
        in_chunks(start..end, CHUNK, |chunk| {
            if albedo_in_place(kernels, closure, input.wo, chunk.clone(), start, &mut out) {
                Ok(())
            } else {
                staged(chunk, &mut out)
            }
        })
    })
}

/// [`eval_in_place`] for albedo.
fn albedo_in_place(
    kernels: Kernels,
    closure: &Closure,
    wo: Soa3<'_>,
    lanes: Range<usize>,
    base: usize,
    out: &mut Soa3Mut<'_>,
) -> bool {
    let local = lanes.start - base..lanes.end - base;
    if closure.lobes().is_empty() {
        for row in rows_mut(out, &local) {
            row.fill(0.0);
        }
        return true;
    }
    for (k, l) in closure.lobes().iter().enumerate() {
        let mut job = AlbedoJob {
            len: lanes.len(),
            mode: closure.transport(),
            directions: Directions::Raw,
            wo: rows(wo, &lanes),
            lobe: uniform_lobe(closure, k),
            store: k == 0,
            estimate: false,
            value: rows_mut(out, &local),
            out_of_range: false,
        };
        l.lobe.albedo_lanes(kernels, &mut job);
        if job.out_of_range {
            return false;
        }
    }
    true
}

/// [`eval_staged`] for albedo.
fn albedo_staged<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    range: Range<usize>,
    base: usize,
    s: &mut Scratch,
    out: &mut Soa3Mut<'_>,
) -> Result<(), Error> {
    s.groups.build(input, range, None)?;
    for g in 0..s.groups.groups().len() {
        let (len, closure) = begin_group(input, s, g)?;
        stage_input(kernels, input, s, g, len, None);
        let group = &s.groups.groups()[g];
        for (k, l) in closure.lobes().iter().enumerate() {
            let lanes = s.lobe.lanes(input, group, k, len, true);
            let mut job = AlbedoJob {
                len,
                mode: closure.transport(),
                directions: Directions::Unit,
                wo: view3(&s.wo, len),
                lobe: lanes,
                store: false,
                estimate: false,
                value: rows3(&mut s.value, len),
                out_of_range: false,
            };
            l.lobe.albedo_lanes(kernels, &mut job);
        }
        Scatter::new(&group.lanes, base, &s.failed, s.any_failed)
            .rows(&s.value, [&mut *out.x, &mut *out.y, &mut *out.z]);
    }
    finish_block(s, base, |lane| out.set(lane, [0.0; 3]))
}

/// Random numbers of [`sample`], one array per dimension.
#[derive(Clone, Copy)]
pub struct SampleRandoms<'a> {
    pub u_lobe: &'a [f32],
    pub u0: &'a [f32],
    pub u1: &'a [f32],
}

/// Outputs of [`sample`]; the optional ones are skipped when `None`.
pub struct SampleOutput<'a> {
    pub wi: Soa3Mut<'a>,
    pub pdf: &'a mut [f32],
    pub weight: Soa3Mut<'a>,
    pub value: Option<Soa3Mut<'a>>,
    pub flags: Option<&'a mut [u32]>,
    pub lobe: Option<&'a mut [u32]>,
    pub component: Option<&'a mut [u32]>,
    pub eta: Option<&'a mut [f32]>,
    pub roughness: Option<&'a mut [f32]>,
}

impl SplitLanes for SampleOutput<'_> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        let (wi, wi2) = self.wi.split_lanes(lanes);
        let (pdf, pdf2) = self.pdf.split_lanes(lanes);
        let (weight, weight2) = self.weight.split_lanes(lanes);
        let (value, value2) = self.value.split_lanes(lanes);
        let (flags, flags2) = self.flags.split_lanes(lanes);
        let (lobe, lobe2) = self.lobe.split_lanes(lanes);
        let (component, component2) = self.component.split_lanes(lanes);
        let (eta, eta2) = self.eta.split_lanes(lanes);
        let (roughness, roughness2) = self.roughness.split_lanes(lanes);
        (
            SampleOutput {
                wi,
                pdf,
                weight,
                value,
                flags,
                lobe,
                component,
                eta,
                roughness,
            },
            SampleOutput {
                wi: wi2,
                pdf: pdf2,
                weight: weight2,
                value: value2,
                flags: flags2,
                lobe: lobe2,
                component: component2,
                eta: eta2,
                roughness: roughness2,
            },
        )
    }
}

impl SampleOutput<'_> {
    /// Every output array holds `count` lanes.
    fn check(&self, count: usize) -> Result<(), Error> {
        self.wi.check(count, "wi")?;
        check_len(self.pdf.len(), count, "pdf")?;
        self.weight.check(count, "weight")?;
        if let Some(v) = &self.value {
            v.check(count, "value")?;
        }
        for (len, what) in [
            (self.flags.as_ref().map(|f| f.len()), "flags"),
            (self.lobe.as_ref().map(|l| l.len()), "lobe"),
            (self.component.as_ref().map(|k| k.len()), "component"),
            (self.eta.as_ref().map(|e| e.len()), "eta"),
            (self.roughness.as_ref().map(|r| r.len()), "roughness"),
        ] {
            if let Some(len) = len {
                check_len(len, count, what)?;
            }
        }
        Ok(())
    }

    /// The outputs of lanes `local`, as a finish kernel writes them.
    fn finish_rows(&mut self, local: &Range<usize>) -> FinishOutput<'_> {
        FinishOutput {
            wi: rows_mut(&mut self.wi, local),
            pdf: &mut self.pdf[local.clone()],
            weight: rows_mut(&mut self.weight, local),
            value: self.value.as_mut().map(|v| rows_mut(v, local)),
            flags: self.flags.as_deref_mut().map(|f| &mut f[local.clone()]),
            lobe: self.lobe.as_deref_mut().map(|l| &mut l[local.clone()]),
            component: self.component.as_deref_mut().map(|k| &mut k[local.clone()]),
            eta: self.eta.as_deref_mut().map(|e| &mut e[local.clone()]),
            roughness: self.roughness.as_deref_mut().map(|r| &mut r[local.clone()]),
        }
    }

    fn write(&mut self, i: usize, s: &SampleResult) {
        self.wi.set(i, [s.wi.x, s.wi.y, s.wi.z]);
        self.pdf[i] = s.pdf;
        self.weight.set(i, s.weight.to_array());
        if let Some(v) = self.value.as_mut() {
            v.set(i, s.value.to_array());
        }
        if let Some(f) = self.flags.as_deref_mut() {
            f[i] = s.flags;
        }
        if let Some(l) = self.lobe.as_deref_mut() {
            l[i] = s.lobe;
        }
        if let Some(k) = self.component.as_deref_mut() {
            k[i] = s.component;
        }
        if let Some(e) = self.eta.as_deref_mut() {
            e[i] = s.eta;
        }
        if let Some(r) = self.roughness.as_deref_mut() {
            r[i] = s.roughness;
        }
    }
}

/// `sample` on every active lane. A lane that cannot scatter is not an error: it
/// gets `pdf = 0` and zero weight, as `glint_sample` returns `GLINT_NO_SAMPLE`.
pub fn sample<'a, C: ClosureSource<'a>>(
    exec: &Exec<'_>,
    input: &BatchInput<'a, C>,
    u: SampleRandoms<'_>,
    out: SampleOutput<'_>,
) -> Result<(), Error> {
    let n = input.count;
    input.check()?;
    for (row, what) in [(u.u_lobe, "u_lobe"), (u.u0, "u0"), (u.u1, "u1")] {
        check_len(row.len(), n, what)?;
    }
    out.check(n)?;
    run_blocks(exec, n, out, |start, mut out| {
        with_scratch(|s| sample_block(exec.kernels, input, u, start, s, &mut out))
    })
}

fn sample_block<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    u: SampleRandoms<'_>,
    start: usize,
    s: &mut Scratch,
    out: &mut SampleOutput<'_>,
) -> Result<(), Error> {
    let end = (start + BLOCK).min(input.count);
    let Some(closure) = in_place(input).filter(|c| !c.lobes().is_empty()) else {
        return sample_staged(kernels, input, u, start..end, start, s, out);
    };
    // A fused shape samples the block in one pass over the caller's rows.
    if let Some(frame) = shared_frame(closure)
        && let Some(fused) = fused::for_closure(closure)
    {
        let mut job = FusedSampleJob {
            mode: closure.transport(),
            frame,
            lobes: fused.lobes,
            wo: rows(input.wo, &(start..end)),
            u: [u.u_lobe, u.u0, u.u1].map(|row| &row[start..end]),
            out: out.finish_rows(&(0..end - start)),
            held: None,
            prefetch: delay::streaming(input.count),
        };
        let sample = if delay::streams(kernels, input.count, end - start) && job.rows_collide() {
            job.held = Some(s.rings.sample().rows_like(&job.out));
            fused.sample_held
        } else {
            fused.sample
        };
        if sample(kernels, &mut job) {
            return Ok(());
        }
        return sample_staged(kernels, input, u, start..end, start, s, out);
    }
    // One lobe, which every lane chooses: finished in the kernel.
    let one_lobe = closure.lobes().len() == 1 && closure.lobes()[0].probability == 1.0;
    let (size, rows) = if one_lobe {
        (CHUNK, padded(CHUNK))
    } else {
        (MIXTURE_CHUNK, MIXTURE_ROWS)
    };
    s.reserve_rows(rows)?;
    in_chunks(start..end, size, |chunk| {
        let done = if one_lobe {
            sample_in_place(kernels, closure, input.wo, u, chunk.clone(), start, s, out)
        } else {
            mixture_in_place(kernels, closure, input.wo, u, chunk.clone(), start, s, out)
        };
        if done {
            Ok(())
        } else {
            sample_staged(kernels, input, u, chunk, start, s, out)
        }
    })
}

/// Most rows a mixture sample unsorts: `wi`, pdf, weight, value, eta, roughness,
/// flags, lobe and component.
const UNSORT_ROWS: usize = 15;

/// Rows unsorted by one call, each with its destination.
#[derive(Default)]
struct RowPairs<'a> {
    src: [&'a [f32]; UNSORT_ROWS],
    dst: [&'a mut [f32]; UNSORT_ROWS],
    len: usize,
}

impl<'a> RowPairs<'a> {
    fn push(&mut self, src: &'a [f32], dst: &'a mut [f32]) {
        self.src[self.len] = src;
        self.dst[self.len] = dst;
        self.len += 1;
    }
}

/// Sample lanes `lanes` of a shared closure of several lobes. The lanes are grouped
/// by the lobe they chose (lobe choice in a kernel, runs counted, then each lobe's
/// lanes packed into its run by `compress`) and their inputs moved once in that order, so each lobe samples its own run of rows and
/// is evaluated on the other lobes' runs, with no mask and no lane computed twice;
/// the finish writes each lane back to the caller's order. False as [`eval_in_place`].
#[allow(clippy::too_many_arguments)]
fn mixture_in_place(
    kernels: Kernels,
    closure: &Closure,
    wo: Soa3<'_>,
    u: SampleRandoms<'_>,
    lanes: Range<usize>,
    base: usize,
    s: &mut Scratch,
    out: &mut SampleOutput<'_>,
) -> bool {
    let n = lanes.len();
    let count = closure.lobes().len();
    let mut probabilities = [0.0f32; MAX_LOBES];
    for (p, l) in probabilities.iter_mut().zip(closure.lobes()) {
        *p = l.probability;
    }
    let probabilities = &probabilities[..count];
    let chosen = grow(&mut s.chosen, n);
    let [reused, ..] = rows3(&mut s.u, n);
    let mut starts = [0usize; MAX_LOBES + 1];
    if !choose_lobes(
        kernels,
        probabilities,
        &u.u_lobe[lanes.clone()],
        chosen,
        reused,
        &mut starts[..=count],
    ) {
        return false;
    }
    // Rows in lobe order: every run in whole registers, its pads copying its first
    // lane; sorted rows have room for a whole register past the last run.
    let len = starts[count];
    let c = &mut s.compact;
    // Inputs in that order, `wo` normalized as staging does (the other lobes are
    // evaluated at the sampled `wi` as it is returned, so their jobs take unit
    // directions).
    let [wo_x, wo_y, wo_z] = rows(wo, &lanes);
    let [c_wo, c_u] = [&mut c.wo, &mut c.u].map(|r| rows3(r, len + MAX_LANES));
    let [a, b, c3] = c_wo;
    let [d, e, f] = c_u;
    sort_rows(
        kernels,
        &s.chosen[..n],
        &starts[..=count],
        &[
            wo_x,
            wo_y,
            wo_z,
            &s.u[0][..n],
            &u.u0[lanes.clone()],
            &u.u1[lanes.clone()],
        ],
        &mut [a, b, c3, d, e, f],
    );
    if normalize(kernels, &mut rows3(&mut c.wo, len), len) {
        return false;
    }
    // Each lobe samples its run.
    let (mut wi, mut own_value) = (rows3(&mut s.wi, len), rows3(&mut s.sample_value, len));
    let (own_pdf, eta) = (grow(&mut s.sample_pdf, len), grow(&mut s.eta, len));
    let (roughness, events) = (grow(&mut s.roughness, len), grow(&mut s.events, len));
    for (k, l) in closure.lobes().iter().enumerate() {
        let run = starts[k]..starts[k + 1];
        if run.is_empty() {
            continue;
        }
        let mut job = SampleJob {
            len: run.len(),
            mode: closure.transport(),
            directions: Directions::Unit,
            wo: view_run(&c.wo, &run),
            u: view_run(&c.u, &run),
            lobe: uniform_lobe(closure, k),
            wi: wi.each_mut().map(|row| &mut row[run.clone()]),
            value: own_value.each_mut().map(|row| &mut row[run.clone()]),
            pdf: &mut own_pdf[run.clone()],
            eta: &mut eta[run.clone()],
            roughness: &mut roughness[run.clone()],
            events: Some(&mut events[run.clone()]),
            closure: None,
            only: None,
            out_of_range: false,
        };
        l.lobe.sample_lanes(kernels, &mut job);
        if job.out_of_range {
            return false;
        }
    }
    mixture_lobe_by_lobe(kernels, closure, shared_frame(closure), len, s);
    let c = &mut s.compact;
    // The closure's samples in sorted order, then gathered into the caller's.
    let (want_value, want_eta) = (out.value.is_some(), out.eta.is_some());
    let want_roughness = out.roughness.is_some();
    for rows in [&mut c.wi, &mut c.weight, &mut c.value] {
        rows3(rows, len + MAX_LANES);
    }
    for row in [&mut c.pdf, &mut c.eta, &mut c.roughness] {
        grow(row, len + MAX_LANES);
    }
    for row in [&mut s.flags, &mut s.lobe_index, &mut s.component] {
        grow(row, len);
    }
    for (k, &probability) in probabilities.iter().enumerate() {
        let run = starts[k]..starts[k + 1];
        if run.is_empty() {
            continue;
        }
        let [wr, wg, wb] = &mut c.weight;
        let [vr, vg, vb] = &mut c.value;
        let mut job = FinishJob {
            len: run.len(),
            lobe: FinishLobe::One(k as u32),
            probability,
            wi: view_run(&s.wi, &run),
            own_value: view_run(&s.sample_value, &run),
            own_pdf: &s.sample_pdf[run.clone()],
            events: &s.events[run.clone()],
            eta: &s.eta[run.clone()],
            roughness: &s.roughness[run.clone()],
            value: view_run(&s.value, &run),
            pdf: &s.pdf[run.clone()],
            out: FinishOutput {
                wi: run_mut(&mut c.wi, &run),
                pdf: &mut c.pdf[run.clone()],
                weight: [
                    &mut wr[run.clone()],
                    &mut wg[run.clone()],
                    &mut wb[run.clone()],
                ],
                value: want_value.then(|| {
                    [
                        &mut vr[run.clone()],
                        &mut vg[run.clone()],
                        &mut vb[run.clone()],
                    ]
                }),
                flags: out.flags.is_some().then(|| &mut s.flags[run.clone()]),
                lobe: out.lobe.is_some().then(|| &mut s.lobe_index[run.clone()]),
                component: out
                    .component
                    .is_some()
                    .then(|| &mut s.component[run.clone()]),
                eta: want_eta.then(|| &mut c.eta[run.clone()]),
                roughness: want_roughness.then(|| &mut c.roughness[run.clone()]),
            },
        };
        finish_mixture(kernels, &mut job);
    }
    let local = lanes.start - base..lanes.end - base;
    let (chosen, starts) = (&s.chosen[..n], &starts[..=count]);
    let sorted = len + MAX_LANES;
    // Integer rows go back as the bits of float rows (moves and blends keep any
    // bits), and every requested row in one unsort: each call finds each register's
    // lanes' lobes again.
    let words = [
        (&s.flags, out.flags.as_deref_mut()),
        (&s.lobe_index, out.lobe.as_deref_mut()),
        (&s.component, out.component.as_deref_mut()),
    ];
    let mut words_out: [Option<&mut [u32]>; 3] = Default::default();
    for (((src, dst), bits), o) in words.into_iter().zip(&mut c.bits).zip(&mut words_out) {
        if let Some(dst) = dst {
            for (b, &w) in grow(bits, sorted).iter_mut().zip(&src[..len]) {
                *b = f32::from_bits(w);
            }
            *o = Some(&mut dst[local.clone()]);
        }
    }
    {
        let mut rows = RowPairs::default();
        for (src, dst) in view3(&c.wi, sorted)
            .into_iter()
            .zip(rows_mut(&mut out.wi, &local))
        {
            rows.push(src, dst);
        }
        rows.push(&c.pdf[..sorted], &mut out.pdf[local.clone()]);
        let weight = rows_mut(&mut out.weight, &local);
        for (src, dst) in view3(&c.weight, sorted).into_iter().zip(weight) {
            rows.push(src, dst);
        }
        if let Some(v) = out.value.as_mut() {
            for (src, dst) in view3(&c.value, sorted).into_iter().zip(rows_mut(v, &local)) {
                rows.push(src, dst);
            }
        }
        for (src, dst) in [
            (&c.eta, out.eta.as_deref_mut()),
            (&c.roughness, out.roughness.as_deref_mut()),
        ] {
            if let Some(dst) = dst {
                rows.push(&src[..sorted], &mut dst[local.clone()]);
            }
        }
        let unsorted = rows3(&mut c.unsorted, n);
        for ((bits, o), dst) in c.bits.iter().zip(&words_out).zip(unsorted) {
            if o.is_some() {
                rows.push(&bits[..sorted], dst);
            }
        }
        unsort_rows(
            kernels,
            chosen,
            starts,
            &rows.src[..rows.len],
            &mut rows.dst[..rows.len],
        );
    }
    for (o, unsorted) in words_out.iter_mut().zip(&c.unsorted) {
        if let Some(o) = o {
            for (d, &b) in o.iter_mut().zip(unsorted) {
                *d = b.to_bits();
            }
        }
    }
    true
}

/// The mixture sums of the `len` rows of a sorted sample chunk in `s`, lobe by lobe.
fn mixture_lobe_by_lobe(
    kernels: Kernels,
    closure: &Closure,
    frame: Option<Frame>,
    len: usize,
    s: &mut Scratch,
) {
    let c = &mut s.compact;
    // Lobes that share one frame take `wo` and the sampled `wi` into it once, as
    // their jobs would (`Directions::Sampled`).
    let (wo_rows, wi_rows, directions) = match frame {
        Some(frame) => {
            let unit = to_local(
                kernels,
                &frame,
                Directions::Unit,
                view3(&c.wo, len),
                &mut rows3(&mut c.wo_local, len),
            );
            let sampled = to_local(
                kernels,
                &frame,
                Directions::Sampled,
                view3(&s.wi, len),
                &mut rows3(&mut c.wi_local, len),
            );
            debug_assert!(unit && sampled, "only raw directions can be out of range");
            (
                view3(&c.wo_local, len),
                view3(&c.wi_local, len),
                Directions::Local,
            )
        }
        None => (view3(&c.wo, len), view3(&s.wi, len), Directions::Sampled),
    };
    // The mixture: the closure's eval at the sampled directions, summed in lobe order
    // as an eval's rows are (the chosen lobe's eval there is its sample's value and
    // pdf), so that a sample's value and pdf are the eval's at its `wi`, to the bit.
    let (mut value, pdf) = (rows3(&mut s.value, len), grow(&mut s.pdf, len));
    for (k, l) in closure.lobes().iter().enumerate() {
        let [r, g, b] = &mut value;
        let mut job = EvalJob {
            len,
            mode: closure.transport(),
            directions,
            wo: wo_rows,
            wi: wi_rows,
            lobe: uniform_lobe(closure, k),
            store: k == 0,
            value: Some([&mut r[..], &mut g[..], &mut b[..]]),
            pdf: &mut pdf[..],
            out_of_range: false,
        };
        l.lobe.eval_lanes(kernels, &mut job);
    }
}

/// The closure's sample of scratch lane `j`, from the chosen lobe `k`'s sample rows
/// (`sample_value`, `sample_pdf`, `wi`, `eta`, `roughness`, `events`) and the
/// mixture's rows (`value`, `pdf`); `probability` is lobe `k`'s, `computed` false for
/// a lane that failed before sampling ([`mixture::finish`]).
fn finish_lane(s: &Scratch, j: usize, k: usize, probability: f32, computed: bool) -> SampleResult {
    let (valid, transmitted, delta, class, component) = unpack_events(s.events[j]);
    let sampled = Sample {
        wi: Vec3::new(s.wi[0][j], s.wi[1][j], s.wi[2][j]),
        value: Rgb::zero(),
        pdf: 0.0,
        valid: computed && valid,
        transmitted,
        delta,
        eta: s.eta[j],
        roughness: s.roughness[j],
        class,
        component,
    };
    let row = |rows: &[Vec<f32>; 3]| Rgb::new(rows[0][j], rows[1][j], rows[2][j]);
    let own = (row(&s.sample_value), s.sample_pdf[j]);
    let (value, pdf) = mixture::sampled(delta, own, probability, || (row(&s.value), s.pdf[j]));
    let c = mixture::finish(&sampled, value, pdf);
    SampleResult {
        wi: c.wi,
        value: c.value,
        pdf: c.pdf,
        weight: c.weight,
        flags: mixture::flags(&c)[0],
        lobe: if c.ok { k as u32 } else { 0 },
        component: mixture::components(&c)[0],
        eta: c.eta,
        roughness: c.roughness,
    }
}

/// Sample lanes `lanes` of a one-lobe closure in place: the kernel reads the caller's
/// directions and random numbers and writes every output, the closure's sample
/// finished in the kernel (`kernels::mixture::finish`). Outputs the caller did not
/// ask for go to scratch rows. False as [`eval_in_place`].
#[allow(clippy::too_many_arguments)]
fn sample_in_place(
    kernels: Kernels,
    closure: &Closure,
    wo: Soa3<'_>,
    u: SampleRandoms<'_>,
    lanes: Range<usize>,
    base: usize,
    s: &mut Scratch,
    out: &mut SampleOutput<'_>,
) -> bool {
    let local = lanes.start - base..lanes.end - base;
    let n = lanes.len();
    let lobe = &closure.lobes()[0].lobe;
    let [sv_r, sv_g, sv_b] = &mut s.sample_value;
    let value = match out.value.as_mut() {
        Some(v) => rows_mut(v, &local),
        None => [grow(sv_r, n), grow(sv_g, n), grow(sv_b, n)],
    };
    let mut job = SampleJob {
        len: n,
        mode: closure.transport(),
        directions: Directions::Raw,
        wo: rows(wo, &lanes),
        u: [u.u_lobe, u.u0, u.u1].map(|row| &row[lanes.clone()]),
        lobe: uniform_lobe(closure, 0),
        wi: rows_mut(&mut out.wi, &local),
        value,
        pdf: &mut out.pdf[local.clone()],
        eta: match out.eta.as_deref_mut() {
            Some(e) => &mut e[local.clone()],
            None => grow(&mut s.eta, n),
        },
        roughness: match out.roughness.as_deref_mut() {
            Some(r) => &mut r[local.clone()],
            None => grow(&mut s.roughness, n),
        },
        events: None,
        closure: Some(ClosureRows {
            weight: rows_mut(&mut out.weight, &local),
            flags: out.flags.as_deref_mut().map(|f| &mut f[local.clone()]),
            lobe: out.lobe.as_deref_mut().map(|l| &mut l[local.clone()]),
            component: out.component.as_deref_mut().map(|k| &mut k[local.clone()]),
        }),
        only: None,
        out_of_range: false,
    };
    lobe.sample_lanes(kernels, &mut job);
    !job.out_of_range
}

/// Sample lanes `range` through grouping (by closure shape and chosen lobe) and
/// staging; `out`'s lane 0 is lane `base`.
fn sample_staged<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    u: SampleRandoms<'_>,
    range: Range<usize>,
    base: usize,
    s: &mut Scratch,
    out: &mut SampleOutput<'_>,
) -> Result<(), Error> {
    let start = range.start;
    let randoms = Randoms {
        u: [u.u_lobe, u.u0, u.u1],
    };
    s.groups.build(input, range, Some(randoms))?;
    for g in 0..s.groups.groups().len() {
        let (len, closure) = begin_group(input, s, g)?;
        stage_input(kernels, input, s, g, len, None);
        let group = &s.groups.groups()[g];
        let k = group.lobe;
        let lobe = &closure.lobes()[k].lobe;
        // The chosen lobe's random numbers: the rescaled lobe choice, then u0 and u1
        // (the kernel clamps them into [0, 1)).
        let [uc, u0, u1] = rows3(&mut s.u, len);
        let n = group.lanes.len();
        for (j, &lane) in group.lanes.iter().enumerate() {
            let lane = lane as usize;
            (uc[j], u0[j], u1[j]) = (s.groups.u_reused[lane - start], u.u0[lane], u.u1[lane]);
        }
        for row in [uc, u0, u1] {
            row[n..].fill(0.5);
        }
        let lanes = s.lobe.lanes(input, group, k, len, false);
        let [sv_r, sv_g, sv_b] = &mut s.sample_value;
        let mut job = SampleJob {
            len,
            mode: closure.transport(),
            directions: Directions::Unit,
            wo: view3(&s.wo, len),
            u: view3(&s.u, len),
            lobe: lanes,
            wi: rows3(&mut s.wi, len),
            value: [grow(sv_r, len), grow(sv_g, len), grow(sv_b, len)],
            pdf: grow(&mut s.sample_pdf, len),
            eta: grow(&mut s.eta, len),
            roughness: grow(&mut s.roughness, len),
            events: Some(grow(&mut s.events, len)),
            closure: None,
            only: None,
            out_of_range: false,
        };
        lobe.sample_lanes(kernels, &mut job);
        // The mixture at the sampled direction: the closure's eval there (the chosen
        // lobe's eval is its sample's value and pdf), to the bit.
        eval_lobes(kernels, input, s, g, closure, true, true, false);
        let group = &s.groups.groups()[g];
        grow(&mut s.flags, len);
        grow(&mut s.lobe_index, len);
        grow(&mut s.component, len);
        for (j, &lane) in group.lanes.iter().enumerate() {
            let c = input
                .closures
                .closure(lane as usize)
                .expect("resolved before");
            let p = c.lobes()[k].probability;
            let r = finish_lane(s, j, k, p, s.failed[j] == 0);
            for (c, v) in [r.wi.x, r.wi.y, r.wi.z].into_iter().enumerate() {
                s.wi[c][j] = v;
            }
            for (c, (w, v)) in r
                .weight
                .to_array()
                .into_iter()
                .zip(r.value.to_array())
                .enumerate()
            {
                s.u[c][j] = w;
                s.value[c][j] = v;
            }
            (s.pdf[j], s.eta[j], s.roughness[j]) = (r.pdf, r.eta, r.roughness);
            s.flags[j] = r.flags;
            s.lobe_index[j] = r.lobe;
            s.component[j] = r.component;
        }
        let (sample_flags, lobe_index, component) = (&s.flags, &s.lobe_index, &s.component);
        let scatter = Scatter::new(&group.lanes, base, &s.failed, false);
        scatter.rows(&s.wi, [&mut *out.wi.x, &mut *out.wi.y, &mut *out.wi.z]);
        scatter.row(&s.pdf, out.pdf);
        scatter.rows(
            &s.u,
            [&mut *out.weight.x, &mut *out.weight.y, &mut *out.weight.z],
        );
        if let Some(v) = out.value.as_mut() {
            scatter.rows(&s.value, [&mut *v.x, &mut *v.y, &mut *v.z]);
        }
        if let Some(f) = out.flags.as_deref_mut() {
            scatter.row(sample_flags, f);
        }
        if let Some(l) = out.lobe.as_deref_mut() {
            scatter.row(lobe_index, l);
        }
        if let Some(k) = out.component.as_deref_mut() {
            scatter.row(component, k);
        }
        if let Some(e) = out.eta.as_deref_mut() {
            scatter.row(&s.eta, e);
        }
        if let Some(r) = out.roughness.as_deref_mut() {
            scatter.row(&s.roughness, r);
        }
    }
    finish_block(s, base, |lane| out.write(lane, &SampleResult::FAILED))
}

/// `job`'s lobe with `wo` and `wi` exchanged: its reverse pdf into `pdf_reverse`.
fn eval_reverse<'a>(
    kernels: Kernels,
    lobe: &dyn LobeType,
    job: EvalJob<'a>,
    pdf_reverse: &'a mut [f32],
) {
    let mut job = EvalJob {
        wo: job.wi,
        wi: job.wo,
        value: None,
        pdf: &mut pdf_reverse[..job.len],
        ..job
    };
    lobe.eval_lanes(kernels, &mut job);
}
