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

mod stage;

use crate::closure::{Closure, ONE_MINUS_EPSILON, SampleResult, sample_weight};
use crate::error::{Error, Status};
use crate::lobes::flags;
use crate::math::{Rgb, Vec3};
use crate::simd::Kernels;
use crate::simd::kernels::{
    AlbedoJob, EVENT_DELTA, EVENT_TRANSMITTED, EVENT_VALID, EvalJob, SampleJob,
};
use stage::{Randoms, Scratch, grow, padded, rows3, stage_directions, view3, with_scratch};
use std::fmt;

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
    fn check(&self, count: usize, what: &str) -> Result<(), Error> {
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
        with_scratch(|s| eval_block(exec.kernels, input, wi, start, s, &mut out))
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
        with_scratch(|s| eval_block(exec.kernels, input, wi, start, s, &mut out))
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

/// Eval the block starting at lane `start`.
fn eval_block<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    start: usize,
    s: &mut Scratch,
    out: &mut EvalBlockOutput<'_>,
) -> Result<(), Error> {
    let end = (start + BLOCK).min(input.count);
    s.groups.build(input, start..end, None)?;
    for g in 0..s.groups.groups().len() {
        let (len, closure) = begin_group(input, s, g)?;
        stage_input(kernels, input, s, g, len, Some(wi));
        let (value, reverse) = (out.value.is_some(), out.pdf_reverse.is_some());
        eval_lobes(kernels, input, s, g, closure, value, reverse);
        let group = &s.groups.groups()[g];
        let scatter = Scatter::new(&group.lanes, start, &s.failed, s.any_failed);
        if let Some(v) = out.value.as_mut() {
            scatter.rows(&s.value, [&mut *v.x, &mut *v.y, &mut *v.z]);
        }
        scatter.row(&s.pdf, out.pdf);
        if let Some(rev) = out.pdf_reverse.as_deref_mut() {
            scatter.row(&s.pdf_reverse, rev);
        }
    }
    finish_block(s, start, |lane| {
        if let Some(v) = out.value.as_mut() {
            v.set(lane, [0.0; 3]);
        }
        out.pdf[lane] = 0.0;
        if let Some(rev) = out.pdf_reverse.as_deref_mut() {
            rev[lane] = 0.0;
        }
    })
}

/// Accumulate every lobe of group `g`'s `closure` at the staged `wo` and `wi`: the
/// pdf into `s.pdf`, with `want_value` the value into `s.value`, with `want_reverse`
/// the pdf of `wi` to `wo` into `s.pdf_reverse`.
fn eval_lobes<'a, C: ClosureSource<'a>>(
    kernels: Kernels,
    input: &BatchInput<'a, C>,
    s: &mut Scratch,
    g: usize,
    closure: &Closure,
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
        let lanes = lobe.lanes(input, group, k, len);
        let [vr, vg, vb] = &mut *value;
        let mut job = EvalJob {
            len,
            mode: closure.transport(),
            wo: view3(wo, len),
            wi: view3(wi, len),
            lobe: lanes,
            value: want_value.then(|| [&mut vr[..len], &mut vg[..len], &mut vb[..len]]),
            pdf: &mut pdf[..len],
        };
        l.lobe.eval_lanes(kernels, &mut job);
        if want_reverse {
            let mut job = EvalJob {
                len,
                mode: closure.transport(),
                wo: view3(wi, len),
                wi: view3(wo, len),
                lobe: lanes,
                value: None,
                pdf: &mut pdf_reverse[..len],
            };
            l.lobe.eval_lanes(kernels, &mut job);
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
        *any_failed |= stage_directions(kernels, src, what, &lanes, len, rows, failed, groups);
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
    run_blocks(exec, input.count, out, |start, mut out| {
        with_scratch(|s| {
            let end = (start + BLOCK).min(input.count);
            s.groups.build(input, start..end, None)?;
            for g in 0..s.groups.groups().len() {
                let (len, closure) = begin_group(input, s, g)?;
                stage_input(exec.kernels, input, s, g, len, None);
                let group = &s.groups.groups()[g];
                for (k, l) in closure.lobes().iter().enumerate() {
                    let lanes = s.lobe.lanes(input, group, k, len);
                    let mut job = AlbedoJob {
                        len,
                        mode: closure.transport(),
                        wo: view3(&s.wo, len),
                        lobe: lanes,
                        value: rows3(&mut s.value, len),
                    };
                    l.lobe.albedo_lanes(exec.kernels, &mut job);
                }
                Scatter::new(&group.lanes, start, &s.failed, s.any_failed)
                    .rows(&s.value, [&mut *out.x, &mut *out.y, &mut *out.z]);
            }
            finish_block(s, start, |lane| out.set(lane, [0.0; 3]))
        })
    })
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
            (self.eta.as_ref().map(|e| e.len()), "eta"),
            (self.roughness.as_ref().map(|r| r.len()), "roughness"),
        ] {
            if let Some(len) = len {
                check_len(len, count, what)?;
            }
        }
        Ok(())
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
        if let Some(e) = self.eta.as_deref_mut() {
            e[i] = s.eta;
        }
        if let Some(r) = self.roughness.as_deref_mut() {
            r[i] = s.roughness;
        }
    }
}

/// A failed sample as the batch reports it: every output zero, `eta` 1.
const FAILED: SampleResult = SampleResult {
    wi: Vec3 {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    },
    value: Rgb {
        r: 0.0,
        g: 0.0,
        b: 0.0,
    },
    pdf: 0.0,
    weight: Rgb {
        r: 0.0,
        g: 0.0,
        b: 0.0,
    },
    flags: 0,
    lobe: 0,
    eta: 1.0,
    roughness: 0.0,
};

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
    let randoms = Randoms {
        u: [u.u_lobe, u.u0, u.u1],
    };
    s.groups.build(input, start..end, Some(randoms))?;
    for g in 0..s.groups.groups().len() {
        let (len, closure) = begin_group(input, s, g)?;
        stage_input(kernels, input, s, g, len, None);
        let group = &s.groups.groups()[g];
        let k = group.lobe;
        let lobe = &closure.lobes()[k].lobe;
        // The chosen lobe's random numbers: the rescaled lobe choice, then u0 and u1
        // clamped into [0, 1) as `Closure::sample` does.
        let [uc, u0, u1] = rows3(&mut s.u, len);
        let n = group.lanes.len();
        for (j, &lane) in group.lanes.iter().enumerate() {
            let lane = lane as usize;
            (uc[j], u0[j], u1[j]) = (s.groups.u_reused[lane - start], u.u0[lane], u.u1[lane]);
        }
        for row in [&mut *u0, &mut *u1] {
            for x in &mut row[..n] {
                *x = x.clamp(0.0, ONE_MINUS_EPSILON);
            }
        }
        for row in [uc, u0, u1] {
            row[n..].fill(0.5);
        }
        let lanes = s.lobe.lanes(input, group, k, len);
        let [sv_r, sv_g, sv_b] = &mut s.sample_value;
        let mut job = SampleJob {
            len,
            mode: closure.transport(),
            wo: view3(&s.wo, len),
            u: view3(&s.u, len),
            lobe: lanes,
            wi: rows3(&mut s.wi, len),
            value: [grow(sv_r, len), grow(sv_g, len), grow(sv_b, len)],
            pdf: grow(&mut s.sample_pdf, len),
            eta: grow(&mut s.eta, len),
            roughness: grow(&mut s.roughness, len),
            events: grow(&mut s.events, len),
        };
        lobe.sample_lanes(kernels, &mut job);
        // Value and pdf at the returned world-space `wi`, as `Closure::sample` computes
        // them (the lobe's local result is off by the frame round trip's rounding).
        eval_lobes(kernels, input, s, g, closure, true, false);
        let group = &s.groups.groups()[g];
        // Final value, pdf, weight and flags, staged in place (the random-number rows
        // hold the weight), then written back row by row.
        let lobe_flags = lobe.flags();
        let n = group.lanes.len();
        let events = &s.events[..n];
        let [vr, vg, vb] = &mut s.value;
        let (vr, vg, vb) = (&mut vr[..n], &mut vg[..n], &mut vb[..n]);
        let pdf = &mut s.pdf[..n];
        // Delta samples are not in the mixture eval: the chosen lobe's own value, and its
        // discrete probability times the lobe's selection probability.
        for j in (0..n).filter(|&j| events[j] & EVENT_DELTA != 0) {
            let lane = group.lanes[j] as usize;
            let c = input.closures.closure(lane).expect("resolved before");
            (vr[j], vg[j], vb[j]) = (
                s.sample_value[0][j],
                s.sample_value[1][j],
                s.sample_value[2][j],
            );
            pdf[j] = c.lobes()[k].probability * s.sample_pdf[j];
        }
        let [wr, wg, wb] = rows3(&mut s.u, len);
        let (wr, wg, wb) = (&mut wr[..n], &mut wg[..n], &mut wb[..n]);
        let sample_flags = &mut grow(&mut s.flags, len)[..n];
        let lobe_index = &mut grow(&mut s.lobe_index, len)[..n];
        let failed = &s.failed[..n];
        let class = lobe_flags & (flags::DIFFUSE | flags::GLOSSY);
        let mut any_bad = false;
        for j in 0..n {
            let e = events[j];
            let weight = (failed[j] == 0 && e & EVENT_VALID != 0)
                .then(|| sample_weight(Rgb::new(vr[j], vg[j], vb[j]), pdf[j]))
                .flatten();
            let ok = weight.is_some();
            any_bad |= !ok;
            [wr[j], wg[j], wb[j]] = weight.unwrap_or(Rgb::zero()).to_array();
            let side = if e & EVENT_TRANSMITTED != 0 {
                flags::TRANSMISSION
            } else {
                flags::REFLECTION
            };
            let class = if e & EVENT_DELTA != 0 {
                flags::SPECULAR
            } else {
                class
            };
            sample_flags[j] = if ok { side | class } else { 0 };
            lobe_index[j] = if ok { k as u32 } else { 0 };
        }
        if any_bad {
            // Failed samples read as all zero (eta 1), as `FAILED`.
            for j in 0..n {
                if sample_flags[j] == 0 {
                    (wr[j], wg[j], wb[j]) = (0.0, 0.0, 0.0);
                    (vr[j], vg[j], vb[j]) = (0.0, 0.0, 0.0);
                    for row in s.wi.iter_mut() {
                        row[j] = 0.0;
                    }
                    pdf[j] = 0.0;
                    s.eta[j] = 1.0;
                    s.roughness[j] = 0.0;
                }
            }
        }
        let (sample_flags, lobe_index) = (&s.flags, &s.lobe_index);
        let scatter = Scatter::new(&group.lanes, start, &s.failed, false);
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
        if let Some(e) = out.eta.as_deref_mut() {
            scatter.row(&s.eta, e);
        }
        if let Some(r) = out.roughness.as_deref_mut() {
            scatter.row(&s.roughness, r);
        }
    }
    finish_block(s, start, |lane| out.write(lane, &FAILED))
}
