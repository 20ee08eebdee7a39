//! The batch kernels, written once over [`Lane`] and instantiated per ISA.
//!
//! A kernel runs one lobe of a group of lanes (lanes whose closures have the same
//! shape) over SoA arrays staged by `crate::batch`: it moves directions into the
//! lobe's frame, calls the lobe's generic `eval`, `sample` or `albedo`, and
//! accumulates `weight * value` and `probability * pdf`. Lobe parameters are
//! decoded (`Model::prepare`) once per job when every lane shares the closure, once
//! per register of lanes otherwise.

use super::Kernels;
use crate::lobes::{Model, Params, ToWorld, Transport};
use crate::math::{Frame, Lane, LaneFrame, Mask, Rgb, Vec3};

/// Most parameter values one lobe type may have to run in the SIMD kernels.
pub const MAX_LOBE_PARAMS: usize = 64;

/// Lanes every job length is a multiple of (the widest register).
pub const LANE_MULTIPLE: usize = 16;

/// `SampleJob::events` bits.
pub const EVENT_VALID: u8 = 1;
pub const EVENT_TRANSMITTED: u8 = 2;
pub const EVENT_DELTA: u8 = 4;

/// One lobe of the closures of a group of lanes.
#[derive(Clone, Copy)]
pub enum LobeLanes<'a> {
    /// Every lane has the same closure.
    Uniform {
        params: &'a [f32],
        frame: Frame,
        weight: Rgb<f32>,
        probability: f32,
    },
    /// SoA rows of `stride` values: `params` has `param_count` rows, `frame` nine
    /// (t, b, n, each x, y, z), `weight` three, `probability` one.
    PerLane {
        params: &'a [f32],
        param_count: usize,
        frame: &'a [f32],
        weight: &'a [f32],
        probability: &'a [f32],
        stride: usize,
    },
}

/// Inputs of an eval or pdf job; `value` and `pdf` are accumulated into.
pub struct EvalJob<'a> {
    /// Lanes to compute, a multiple of [`LANE_MULTIPLE`]; padding lanes hold any
    /// unit directions.
    pub len: usize,
    pub mode: Transport,
    pub wo: [&'a [f32]; 3],
    pub wi: [&'a [f32]; 3],
    pub lobe: LobeLanes<'a>,
    /// `+= weight * f |cos theta_i|`, when wanted.
    pub value: Option<[&'a mut [f32]; 3]>,
    /// `+= probability * pdf`.
    pub pdf: &'a mut [f32],
}

/// A sampling job: every lane samples this lobe. Outputs are overwritten.
pub struct SampleJob<'a> {
    pub len: usize,
    pub mode: Transport,
    pub wo: [&'a [f32]; 3],
    /// Event choice and the two direction dimensions.
    pub u: [&'a [f32]; 3],
    pub lobe: LobeLanes<'a>,
    /// World-space unit direction.
    pub wi: [&'a mut [f32]; 3],
    /// `weight * value`.
    pub value: [&'a mut [f32]; 3],
    /// The lobe's own pdf (or discrete probability for delta events).
    pub pdf: &'a mut [f32],
    pub eta: &'a mut [f32],
    pub roughness: &'a mut [f32],
    /// `EVENT_*` bits.
    pub events: &'a mut [u8],
}

/// An albedo job; `value` is accumulated into (`+= weight * albedo`).
pub struct AlbedoJob<'a> {
    pub len: usize,
    pub mode: Transport,
    pub wo: [&'a [f32]; 3],
    pub lobe: LobeLanes<'a>,
    pub value: [&'a mut [f32]; 3],
}

/// A lobe instance's per-lane data, loaded or splatted.
struct LaneLobe<L> {
    frame: LaneFrame<L>,
    weight: Rgb<L>,
    probability: L,
}

#[inline(always)]
fn load3<L: Lane>(rows: [&[f32]; 3], i: usize) -> Vec3<L> {
    Vec3::new(
        L::load(&rows[0][i..]),
        L::load(&rows[1][i..]),
        L::load(&rows[2][i..]),
    )
}

/// Frame axis `axis` (rows `3 axis .. 3 axis + 2` of `stride` values) at lane `i`.
#[inline(always)]
fn load_row3<L: Lane>(frame: &[f32], stride: usize, axis: usize, i: usize) -> Vec3<L> {
    let row = 3 * axis * stride + i;
    Vec3::new(
        L::load(&frame[row..]),
        L::load(&frame[row + stride..]),
        L::load(&frame[row + 2 * stride..]),
    )
}

#[inline(always)]
fn store3<L: Lane>(v: [L; 3], rows: &mut [&mut [f32]; 3], i: usize) {
    for (value, row) in v.into_iter().zip(rows.iter_mut()) {
        value.store(&mut row[i..]);
    }
}

#[inline(always)]
fn accumulate<L: Lane>(value: L, row: &mut [f32], i: usize) {
    (L::load(&row[i..]) + value).store(&mut row[i..]);
}

/// The work of a kernel on one register of lanes. A trait rather than a closure:
/// closures are separate functions that LLVM may leave un-inlined, and outside the
/// `#[target_feature]` entry point the intrinsics inside them become calls.
trait RegisterOp<M: Model, L: Lane> {
    fn run(&mut self, i: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>);
}

/// Run `op` on every register of lanes of a job of `len` lanes.
#[inline(always)]
fn for_each_register<M: Model, L: Lane>(
    lobe: LobeLanes<'_>,
    len: usize,
    op: &mut impl RegisterOp<M, L>,
) {
    let mut raw = [L::zero(); MAX_LOBE_PARAMS];
    match lobe {
        LobeLanes::Uniform {
            params,
            frame,
            weight,
            probability,
        } => {
            for (r, &p) in raw.iter_mut().zip(params) {
                *r = L::splat(p);
            }
            let prepared = M::prepare(Params::new(&raw[..params.len()]));
            let lanes = LaneLobe {
                frame: LaneFrame::splat(&frame),
                weight: Rgb::new(L::splat(weight.r), L::splat(weight.g), L::splat(weight.b)),
                probability: L::splat(probability),
            };
            for i in (0..len).step_by(L::LANES) {
                op.run(i, &prepared, &lanes);
            }
        }
        LobeLanes::PerLane {
            params,
            param_count,
            frame,
            weight,
            probability,
            stride,
        } => {
            for i in (0..len).step_by(L::LANES) {
                for (p, r) in raw[..param_count].iter_mut().enumerate() {
                    *r = L::load(&params[p * stride + i..]);
                }
                let prepared = M::prepare(Params::new(&raw[..param_count]));
                let lanes = LaneLobe {
                    frame: LaneFrame {
                        t: load_row3(frame, stride, 0, i),
                        b: load_row3(frame, stride, 1, i),
                        n: load_row3(frame, stride, 2, i),
                    },
                    weight: Rgb::new(
                        L::load(&weight[i..]),
                        L::load(&weight[stride + i..]),
                        L::load(&weight[2 * stride + i..]),
                    ),
                    probability: L::load(&probability[i..]),
                };
                op.run(i, &prepared, &lanes);
            }
        }
    }
}

impl<M: Model, L: Lane> RegisterOp<M, L> for EvalJob<'_> {
    #[inline(always)]
    fn run(&mut self, i: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>) {
        let wo = lanes.frame.to_local(load3(self.wo, i));
        let wi = lanes.frame.to_local(load3(self.wi, i));
        let e = M::eval(p, wo, wi, self.mode);
        if let Some(value) = &mut self.value {
            let v = lanes.weight * e.value;
            accumulate(v.r, value[0], i);
            accumulate(v.g, value[1], i);
            accumulate(v.b, value[2], i);
        }
        accumulate(lanes.probability * e.pdf, self.pdf, i);
    }
}

impl<M: Model, L: Lane> RegisterOp<M, L> for SampleJob<'_> {
    #[inline(always)]
    fn run(&mut self, i: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>) {
        let wo = lanes.frame.to_local(load3(self.wo, i));
        let (uc, u0, u1) = (
            L::load(&self.u[0][i..]),
            L::load(&self.u[1][i..]),
            L::load(&self.u[2][i..]),
        );
        let mut settle = ToWorld::new(lanes.frame);
        let s = M::sample(p, wo, uc, u0, u1, self.mode, &mut settle);
        let s = crate::lobes::Sample {
            wi: settle.world,
            ..s
        }
        .finish();
        let w = s.wi;
        store3([w.x, w.y, w.z], &mut self.wi, i);
        let v = lanes.weight * s.value;
        store3([v.r, v.g, v.b], &mut self.value, i);
        s.pdf.store(&mut self.pdf[i..]);
        s.eta.store(&mut self.eta[i..]);
        s.roughness.store(&mut self.roughness[i..]);
        let (valid, transmitted, delta) = (s.valid.bits(), s.transmitted.bits(), s.delta.bits());
        for (j, e) in self.events[i..i + L::LANES].iter_mut().enumerate() {
            let bit = |m: u32, flag: u8| if m >> j & 1 != 0 { flag } else { 0 };
            *e = bit(valid, EVENT_VALID)
                | bit(transmitted, EVENT_TRANSMITTED)
                | bit(delta, EVENT_DELTA);
        }
    }
}

impl<M: Model, L: Lane> RegisterOp<M, L> for AlbedoJob<'_> {
    #[inline(always)]
    fn run(&mut self, i: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>) {
        let wo = lanes.frame.to_local(load3(self.wo, i));
        let v = lanes.weight * M::albedo(p, wo, self.mode);
        accumulate(v.r, self.value[0], i);
        accumulate(v.g, self.value[1], i);
        accumulate(v.b, self.value[2], i);
    }
}

#[inline(always)]
fn eval_body<M: Model, L: Lane>(job: &mut EvalJob<'_>) {
    for_each_register::<M, L>(job.lobe, job.len, job);
}

#[inline(always)]
fn sample_body<M: Model, L: Lane>(job: &mut SampleJob<'_>) {
    for_each_register::<M, L>(job.lobe, job.len, job);
}

#[inline(always)]
fn albedo_body<M: Model, L: Lane>(job: &mut AlbedoJob<'_>) {
    for_each_register::<M, L>(job.lobe, job.len, job);
}

/// Normalize the staged directions in place; returns whether any lane's squared
/// length is not a finite number in [1e-24, 1e24] (those lanes are left alone, and
/// the batch layer re-stages the group exactly).
#[inline(always)]
fn normalize_body<L: Lane>(v: &mut [&mut [f32]; 3], len: usize) -> bool {
    let mut any = false;
    for i in (0..len).step_by(L::LANES) {
        let d = load3::<L>([&*v[0], &*v[1], &*v[2]], i);
        let len2 = d.length_squared();
        let ok = len2.ge(L::splat(1e-24)) & len2.le(L::splat(1e24));
        let n = Vec3::select(ok, d * (L::one() / len2.sqrt()), d);
        store3([n.x, n.y, n.z], v, i);
        any |= !ok.all();
    }
    any
}

kernel!(
    /// `M::eval` over a job's lanes.
    eval<M>(job: &mut EvalJob<'_>) => eval_body
);
kernel!(
    /// `M::sample` over a job's lanes.
    sample<M>(job: &mut SampleJob<'_>) => sample_body
);
kernel!(
    /// `M::albedo` over a job's lanes.
    albedo<M>(job: &mut AlbedoJob<'_>) => albedo_body
);
kernel!(
    /// Normalize `len` staged directions (a multiple of `LANE_MULTIPLE`); true when
    /// some lane's length is out of the fast path's range.
    normalize<>(v: &mut [&mut [f32]; 3], len: usize) -> bool => normalize_body
);

impl LobeLanes<'_> {
    /// Lane `i`'s parameter block (into `params`), frame, weight and probability.
    pub(crate) fn lane(&self, i: usize, params: &mut Vec<f32>) -> (Frame, Rgb<f32>, f32) {
        params.clear();
        match *self {
            LobeLanes::Uniform {
                params: p,
                frame,
                weight,
                probability,
            } => {
                params.extend_from_slice(p);
                (frame, weight, probability)
            }
            LobeLanes::PerLane {
                params: p,
                param_count,
                frame,
                weight,
                probability,
                stride,
            } => {
                params.extend((0..param_count).map(|k| p[k * stride + i]));
                let v = |k: usize| {
                    Vec3::new(
                        frame[3 * k * stride + i],
                        frame[(3 * k + 1) * stride + i],
                        frame[(3 * k + 2) * stride + i],
                    )
                };
                let w = Rgb::new(weight[i], weight[stride + i], weight[2 * stride + i]);
                (
                    Frame {
                        t: v(0),
                        b: v(1),
                        n: v(2),
                    },
                    w,
                    probability[i],
                )
            }
        }
    }
}

fn lane_vec(rows: [&[f32]; 3], i: usize) -> Vec3<f32> {
    Vec3::new(rows[0][i], rows[1][i], rows[2][i])
}

/// [`EvalJob`] one lane at a time through a scalar `eval` (lobes without kernels).
pub fn eval_each_lane(
    job: &mut EvalJob<'_>,
    eval: impl Fn(&[f32], Vec3<f32>, Vec3<f32>, Transport) -> crate::lobes::Eval<f32>,
) {
    let mut params = Vec::new();
    for i in 0..job.len {
        let (frame, weight, probability) = job.lobe.lane(i, &mut params);
        let wo = frame.to_local(lane_vec(job.wo, i));
        let wi = frame.to_local(lane_vec(job.wi, i));
        let e = eval(&params, wo, wi, job.mode);
        if let Some(value) = &mut job.value {
            for (row, v) in value.iter_mut().zip((weight * e.value).to_array()) {
                row[i] += v;
            }
        }
        job.pdf[i] += probability * e.pdf;
    }
}

/// [`SampleJob`] one lane at a time through a scalar `sample`.
pub fn sample_each_lane(
    job: &mut SampleJob<'_>,
    sample: impl Fn(&[f32], Vec3<f32>, [f32; 3], Transport) -> crate::lobes::Sample<f32>,
) {
    let mut params = Vec::new();
    for i in 0..job.len {
        let (frame, weight, _) = job.lobe.lane(i, &mut params);
        let wo = frame.to_local(lane_vec(job.wo, i));
        let s = sample(&params, wo, job.u.map(|row| row[i]), job.mode).finish();
        let wi = frame.to_world(s.wi).normalize();
        for (row, v) in job.wi.iter_mut().zip([wi.x, wi.y, wi.z]) {
            row[i] = v;
        }
        for (row, v) in job.value.iter_mut().zip((weight * s.value).to_array()) {
            row[i] = v;
        }
        job.pdf[i] = s.pdf;
        job.eta[i] = s.eta;
        job.roughness[i] = s.roughness;
        let flag = |set: bool, bit: u8| if set { bit } else { 0 };
        job.events[i] = flag(s.valid, EVENT_VALID)
            | flag(s.transmitted, EVENT_TRANSMITTED)
            | flag(s.delta, EVENT_DELTA);
    }
}

/// [`AlbedoJob`] one lane at a time through a scalar `albedo`.
pub fn albedo_each_lane(
    job: &mut AlbedoJob<'_>,
    albedo: impl Fn(&[f32], Vec3<f32>, Transport) -> Rgb<f32>,
) {
    let mut params = Vec::new();
    for i in 0..job.len {
        let (frame, weight, _) = job.lobe.lane(i, &mut params);
        let wo = frame.to_local(lane_vec(job.wo, i));
        let v = weight * albedo(&params, wo, job.mode);
        for (row, v) in job.value.iter_mut().zip(v.to_array()) {
            row[i] += v;
        }
    }
}
