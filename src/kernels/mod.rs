//! The batch kernels, written once over [`Lane`] and instantiated per ISA by
//! `crate::simd::kernel!`.
//!
//! A kernel runs one lobe over SoA rows of lanes: it moves directions into the
//! lobe's frame, calls the lobe's generic `eval`, `sample` or `albedo`, and stores
//! or accumulates `weight * value` and `probability * pdf`. The rows are either the
//! caller's own arrays (one closure shared by every lane: any length, the last
//! register a masked tail, directions normalized in the kernel, results written in
//! place) or rows `crate::batch` staged (unit directions, padded to whole
//! registers). Lobe parameters are decoded blocks (`LobeType::decode`), read once per
//! job when every lane shares the closure, once per register otherwise. The closure
//! mixture over lanes (lobe choice, the sample's weight and flags) is in [`mixture`].

pub mod delay;
pub mod expand;
pub mod fused;
pub mod material_rows;
pub mod mixture;

use crate::albedo_table::FRESNEL_CURVE_COS;
use crate::closure::MAX_LOBES;
use crate::fresnel;
use crate::lobes::{Model, Params, Sample, ToWorld, Transport};
use crate::math::lane::MAX_LANES;
use crate::math::{Frame, Lane, LaneFrame, Mask, Rgb, Vec3};
use crate::simd::kernel;
use mixture::ClosureSample;

/// Most parameter values one lobe type may have to run in the SIMD kernels.
pub const MAX_LOBE_PARAMS: usize = 64;

/// Lanes every staged row is padded to a multiple of (the widest register).
pub const LANE_MULTIPLE: usize = MAX_LANES;

/// `SampleJob::events`: one float-exact integer per lane ([`pack_events`]), the
/// `EVENT_*` bits plus the sample's class bit (`flags::DIFFUSE`, `GLOSSY`,
/// `SPECULAR`) times `EVENT_CLASS` plus its component times `EVENT_COMPONENT`
/// (at most 7 + 28 * 8 + 65535 * 256 < 2^24).
pub const EVENT_VALID: u32 = 1;
pub const EVENT_TRANSMITTED: u32 = 2;
pub const EVENT_DELTA: u32 = 4;
pub const EVENT_CLASS: u32 = 8;
pub const EVENT_COMPONENT: u32 = 256;

/// `value` where `m`, else 0.
#[inline(always)]
fn where_set<L: Lane>(m: L::Mask, value: u32) -> L {
    L::select(m, L::splat(value as f32), L::zero())
}

/// A sample's events, class and component as one lane value (see [`EVENT_VALID`]).
#[inline(always)]
pub fn pack_events<L: Lane>(s: &Sample<L>) -> L {
    where_set::<L>(s.valid, EVENT_VALID)
        + where_set::<L>(s.transmitted, EVENT_TRANSMITTED)
        + where_set::<L>(s.delta, EVENT_DELTA)
        + s.class * L::splat(EVENT_CLASS as f32)
        + s.component * L::splat(EVENT_COMPONENT as f32)
}

/// What [`pack_events`] packed: `valid`, `transmitted`, `delta`, `class`, `component`.
#[inline(always)]
pub fn unpack_events<L: Lane>(e: L) -> (L::Mask, L::Mask, L::Mask, L, L) {
    let component = (e * L::splat(1.0 / EVENT_COMPONENT as f32)).floor();
    let low = e - component * L::splat(EVENT_COMPONENT as f32);
    let class = (low * L::splat(1.0 / EVENT_CLASS as f32)).floor();
    let bits = low - class * L::splat(EVENT_CLASS as f32);
    (
        event_bit(bits, EVENT_VALID),
        event_bit(bits, EVENT_TRANSMITTED),
        event_bit(bits, EVENT_DELTA),
        class,
        component,
    )
}

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

/// How a job's directions arrive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Directions {
    /// Unit vectors (staged by the batch layer).
    Unit,
    /// The caller's vectors: the kernel normalizes them by `Vec3::try_unit`'s rule for
    /// squared lengths in [1e-24, 1e24] and sets the job's `out_of_range` when a lane
    /// is outside it (or not finite). Such a job's outputs are not valid: the batch
    /// layer computes its lanes again through staging, which handles every length.
    Raw,
    /// Unit `wo`; `wi` a direction a sample returned, normalized once more as an eval
    /// given it back would normalize it (the sampled lobe's value is settled there, and
    /// a narrow lobe turns that last bit into a relative 1e-4 at alpha 0.001).
    Sampled,
    /// Unit vectors already in the lobe's local frame ([`to_local`]: the lobes of a
    /// closure that share one frame take them into it once): eval only.
    Local,
}

impl Directions {
    /// How `wo` arrives in a job whose directions are `self`.
    #[inline(always)]
    fn of_wo(self) -> Directions {
        match self {
            Directions::Sampled => Directions::Unit,
            d => d,
        }
    }
}

/// Inputs of an eval or pdf job.
pub struct EvalJob<'a> {
    /// Lanes to compute: any count for [`LobeLanes::Uniform`], a multiple of
    /// [`LANE_MULTIPLE`] for [`LobeLanes::PerLane`].
    pub len: usize,
    pub mode: Transport,
    pub directions: Directions,
    pub wo: [&'a [f32]; 3],
    pub wi: [&'a [f32]; 3],
    pub lobe: LobeLanes<'a>,
    /// Overwrite the outputs (the closure's first lobe) rather than add to them.
    pub store: bool,
    /// `weight * f |cos theta_i|`, when wanted.
    pub value: Option<[&'a mut [f32]; 3]>,
    /// `probability * pdf`.
    pub pdf: &'a mut [f32],
    /// See [`Directions::Raw`].
    pub out_of_range: bool,
}

/// Lanes of a register whose `chosen` value is `k`.
#[inline(always)]
fn chosen_mask<L: Lane>(only: Option<(&[f32], f32)>, i: usize, n: usize) -> Option<L::Mask> {
    // A `match`, not `Option::map`: the closure could stay out of line (`RegisterOp`).
    #[allow(clippy::manual_map)]
    match only {
        Some((chosen, k)) => Some(load::<L>(chosen, i, n, -1.0).eq(L::splat(k))),
        None => None,
    }
}

/// A sampling job: every lane samples this lobe. Outputs are overwritten.
pub struct SampleJob<'a> {
    pub len: usize,
    pub mode: Transport,
    pub directions: Directions,
    pub wo: [&'a [f32]; 3],
    /// Event choice (already rescaled for this lobe) and the two direction
    /// dimensions; clamped into [0, 1) here. Not finite: `out_of_range`.
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
    /// Packed events (staged jobs, [`pack_events`]), or `None` when `closure`
    /// finishes the sample.
    pub events: Option<&'a mut [f32]>,
    /// The closure's sample, when this lobe is the closure's only one (probability
    /// 1): weight, flags, lobe index and component written here, failed lanes zeroed
    /// ([`mixture::finish`]).
    pub closure: Option<ClosureRows<'a>>,
    /// `(chosen, k)`: only lanes whose `chosen` lobe is `k` are written.
    pub only: Option<(&'a [f32], f32)>,
    pub out_of_range: bool,
}

/// The outputs of a one-lobe closure's sample besides the lobe's own.
pub struct ClosureRows<'a> {
    pub weight: [&'a mut [f32]; 3],
    pub flags: Option<&'a mut [u32]>,
    pub lobe: Option<&'a mut [u32]>,
    pub component: Option<&'a mut [u32]>,
}

/// An albedo job.
pub struct AlbedoJob<'a> {
    pub len: usize,
    pub mode: Transport,
    pub directions: Directions,
    pub wo: [&'a [f32]; 3],
    pub lobe: LobeLanes<'a>,
    pub store: bool,
    /// The lobes' albedo estimates ([`Model::albedo_estimate`]), as selection and
    /// pruning weigh them, instead of their albedos.
    pub estimate: bool,
    /// `weight * albedo`.
    pub value: [&'a mut [f32]; 3],
    pub out_of_range: bool,
}

/// The last step of a shared closure's mixture sample, over the rows of the lanes
/// that chose one lobe: that lobe's sample (`own`), the mixture's value and pdf at
/// its direction, and the closure's outputs ([`mixture::finish`]).
pub struct FinishJob<'a> {
    pub len: usize,
    /// The chosen lobe and its selection probability.
    pub lobe: FinishLobe<'a>,
    pub probability: f32,
    pub wi: [&'a [f32]; 3],
    pub own_value: [&'a [f32]; 3],
    pub own_pdf: &'a [f32],
    pub events: &'a [f32],
    pub eta: &'a [f32],
    pub roughness: &'a [f32],
    pub value: [&'a [f32]; 3],
    pub pdf: &'a [f32],
    pub out: FinishOutput<'a>,
}

/// The lobe index a finished sample reports: one for the whole job (a closure's run
/// of lanes that chose it), or each lane's, as floats (a material batch's slots).
#[derive(Clone, Copy)]
pub enum FinishLobe<'a> {
    One(u32),
    PerLane(&'a [f32]),
}

/// A closure's sample outputs; optional ones are skipped when `None`.
pub struct FinishOutput<'a> {
    pub wi: [&'a mut [f32]; 3],
    pub pdf: &'a mut [f32],
    pub weight: [&'a mut [f32]; 3],
    pub value: Option<[&'a mut [f32]; 3]>,
    pub flags: Option<&'a mut [u32]>,
    pub lobe: Option<&'a mut [u32]>,
    pub component: Option<&'a mut [u32]>,
    pub eta: Option<&'a mut [f32]>,
    pub roughness: Option<&'a mut [f32]>,
}

impl FinishOutput<'_> {
    /// The rows cut to `len` lanes (each at least as long), so that a loop over them
    /// needs no bounds checks of its own (as `fused::eval_lanes` cuts its rows).
    #[inline(always)]
    pub fn cut(&mut self, len: usize) -> FinishOutput<'_> {
        let [x, y, z] = &mut self.wi;
        let [r, g, b] = &mut self.weight;
        FinishOutput {
            wi: [&mut x[..len], &mut y[..len], &mut z[..len]],
            pdf: &mut self.pdf[..len],
            weight: [&mut r[..len], &mut g[..len], &mut b[..len]],
            value: self
                .value
                .as_mut()
                .map(|[r, g, b]| [&mut r[..len], &mut g[..len], &mut b[..len]]),
            flags: self.flags.as_deref_mut().map(|f| &mut f[..len]),
            lobe: self.lobe.as_deref_mut().map(|l| &mut l[..len]),
            component: self.component.as_deref_mut().map(|c| &mut c[..len]),
            eta: self.eta.as_deref_mut().map(|e| &mut e[..len]),
            roughness: self.roughness.as_deref_mut().map(|r| &mut r[..len]),
        }
    }
}

#[inline(always)]
fn finish_body<L: Lane>(job: &mut FinishJob<'_>) {
    let probability = L::splat(job.probability);
    for i in (0..job.len).step_by(L::LANES) {
        let n = L::LANES.min(job.len - i);
        let (valid, transmitted, delta, class, component) =
            unpack_events(load::<L>(job.events, i, n, 0.0));
        let own_value = load_rgb::<L>(job.own_value, i, n);
        let own_pdf = load::<L>(job.own_pdf, i, n, 0.0);
        let s = Sample {
            wi: load3(job.wi, i, n),
            value: own_value,
            pdf: own_pdf,
            valid,
            transmitted,
            delta,
            eta: load(job.eta, i, n, 1.0),
            roughness: load(job.roughness, i, n, 0.0),
            class,
            component,
        };
        let (value, pdf) = mixture::sampled(
            delta,
            (own_value, own_pdf),
            probability,
            #[inline(always)]
            || (load_rgb(job.value, i, n), load(job.pdf, i, n, 0.0)),
        );
        let c = mixture::finish(&s, value, pdf);
        let lobe = match job.lobe {
            FinishLobe::One(k) => L::splat(k as f32),
            FinishLobe::PerLane(chosen) => load(chosen, i, n, 0.0),
        };
        store_finished(&c, lobe, &mut job.out, i, n);
    }
}

/// A closure's finished samples `c` of the `n` lanes at `i`, drawn from the lobes
/// `lobe` (indices as lane values), stored to the outputs asked for.
#[inline(always)]
pub(crate) fn store_finished<L: Lane>(
    c: &ClosureSample<L>,
    lobe: L,
    out: &mut FinishOutput<'_>,
    i: usize,
    n: usize,
) {
    for (v, row) in [c.wi.x, c.wi.y, c.wi.z].into_iter().zip(out.wi.iter_mut()) {
        store(v, row, i, n);
    }
    store(c.pdf, out.pdf, i, n);
    for (v, row) in c.weight.to_array().into_iter().zip(out.weight.iter_mut()) {
        store(v, row, i, n);
    }
    if let Some(rows) = out.value.as_mut() {
        for (v, row) in c.value.to_array().into_iter().zip(rows.iter_mut()) {
            store(v, row, i, n);
        }
    }
    if let Some(e) = out.eta.as_deref_mut() {
        store(c.eta, e, i, n);
    }
    if let Some(r) = out.roughness.as_deref_mut() {
        store(c.roughness, r, i, n);
    }
    if let Some(f) = out.flags.as_deref_mut() {
        f[i..i + n].copy_from_slice(&mixture::flags(c)[..n]);
    }
    if let Some(k) = out.component.as_deref_mut() {
        k[i..i + n].copy_from_slice(&mixture::components(c)[..n]);
    }
    if let Some(l) = out.lobe.as_deref_mut() {
        let mut lanes = [0.0f32; MAX_LANES];
        L::select(c.ok, lobe, L::zero()).store(&mut lanes);
        for (l, &k) in l[i..i + n].iter_mut().zip(&lanes) {
            *l = k as u32;
        }
    }
}

/// Whether the `EVENT_*` bit `bit` is set in the events `e` (small integers held
/// exactly in floats): `floor(e / bit)` is odd.
#[inline(always)]
fn event_bit<L: Lane>(e: L, bit: u32) -> L::Mask {
    let shifted = (e * L::splat(1.0 / bit as f32)).floor();
    (shifted - L::splat(2.0) * (shifted * L::splat(0.5)).floor()).eq(L::one())
}

#[inline(always)]
fn load_rgb<L: Lane>(rows: [&[f32]; 3], i: usize, n: usize) -> Rgb<L> {
    Rgb::new(
        load(rows[0], i, n, 0.0),
        load(rows[1], i, n, 0.0),
        load(rows[2], i, n, 0.0),
    )
}

/// A lobe instance's per-lane data, loaded or splatted.
struct LaneLobe<L> {
    frame: LaneFrame<L>,
    weight: Rgb<L>,
    probability: L,
}

/// Register `i` of `row`: `L::LANES` values, or the first `n` and `fill`.
#[inline(always)]
fn load<L: Lane>(row: &[f32], i: usize, n: usize, fill: f32) -> L {
    if n == L::LANES {
        L::load(&row[i..])
    } else {
        L::load_tail(&row[i..], n, fill)
    }
}

#[inline(always)]
fn store<L: Lane>(v: L, row: &mut [f32], i: usize, n: usize) {
    if n == L::LANES {
        v.store(&mut row[i..]);
    } else {
        v.store_tail(&mut row[i..], n);
    }
}

/// `row[i..] = v` in the lanes of `only` (all lanes when `None`).
#[inline(always)]
fn store_where<L: Lane>(only: Option<L::Mask>, v: L, row: &mut [f32], i: usize, n: usize) {
    let v = match only {
        Some(mask) => L::select(mask, v, load(row, i, n, 0.0)),
        None => v,
    };
    store(v, row, i, n);
}

/// `row[i..] = w f`, or `+= w f` by one fused multiply-add unless `overwrite` (as a
/// fused kernel sums its lobes, `kernels::fused`).
#[inline(always)]
fn put_product<L: Lane>(w: L, f: L, row: &mut [f32], (i, n): (usize, usize), overwrite: bool) {
    let v = if overwrite {
        w * f
    } else {
        w.mul_add(f, load::<L>(row, i, n, 0.0))
    };
    store(v, row, i, n);
}

/// `row[i..] = v`, or `+= v` unless `overwrite`.
#[inline(always)]
fn put<L: Lane>(v: L, row: &mut [f32], i: usize, n: usize, overwrite: bool) {
    let v = if overwrite {
        v
    } else {
        load::<L>(row, i, n, 0.0) + v
    };
    store(v, row, i, n);
}

/// A direction register; tail lanes hold +z.
#[inline(always)]
fn load3<L: Lane>(rows: [&[f32]; 3], i: usize, n: usize) -> Vec3<L> {
    Vec3::new(
        load(rows[0], i, n, 0.0),
        load(rows[1], i, n, 0.0),
        load(rows[2], i, n, 1.0),
    )
}

/// `d` normalized by `Vec3::try_unit`'s rule for squared lengths in [1e-24, 1e24],
/// and the lanes in that range.
#[inline(always)]
fn unit_in_range<L: Lane>(d: Vec3<L>) -> (Vec3<L>, L::Mask) {
    let len2 = d.length_squared();
    let ok = len2.ge(L::splat(1e-24)) & len2.le(L::splat(1e24));
    (d.unit_from(len2), ok)
}

/// A job's direction register, normalized when the job's directions are raw;
/// `out_of_range` is set when a lane cannot be.
#[inline(always)]
fn direction<L: Lane>(
    rows: [&[f32]; 3],
    i: usize,
    n: usize,
    directions: Directions,
    out_of_range: &mut bool,
) -> Vec3<L> {
    let d = load3(rows, i, n);
    match directions {
        Directions::Unit | Directions::Local => d,
        Directions::Sampled => d.unit_from(d.length_squared()),
        Directions::Raw => {
            let (unit, ok) = unit_in_range(d);
            *out_of_range |= !ok.all();
            unit
        }
    }
}

/// Colour `k` (rows `3 k .. 3 k + 2` of `stride` values) at lane `i`.
#[inline(always)]
fn rgb_at<L: Lane>(rows: &[f32], k: usize, stride: usize, i: usize) -> Rgb<L> {
    Rgb::new(
        L::load(&rows[3 * k * stride + i..]),
        L::load(&rows[(3 * k + 1) * stride + i..]),
        L::load(&rows[(3 * k + 2) * stride + i..]),
    )
}

/// [`load_frame`]'s inverse: the register's frames at lane `i` into nine rows of
/// `stride` values.
#[inline(always)]
fn store_frame<L: Lane>(f: &LaneFrame<L>, frame: &mut [f32], stride: usize, i: usize) {
    let axes = [
        f.t.x, f.t.y, f.t.z, f.b.x, f.b.y, f.b.z, f.n.x, f.n.y, f.n.z,
    ];
    for (row, v) in axes.into_iter().enumerate() {
        v.store(&mut frame[row * stride + i..]);
    }
}

/// The frames of the register at lane `i` from nine rows of `stride` values (t, b, n,
/// each x, y, z).
#[inline(always)]
fn load_frame<L: Lane>(frame: &[f32], stride: usize, i: usize) -> LaneFrame<L> {
    LaneFrame::new(
        load_axis(frame, stride, 0, i),
        load_axis(frame, stride, 1, i),
        load_axis(frame, stride, 2, i),
    )
}

/// Frame axis `axis` (rows `3 axis .. 3 axis + 2` of `stride` values) at lane `i`.
#[inline(always)]
fn load_axis<L: Lane>(frame: &[f32], stride: usize, axis: usize, i: usize) -> Vec3<L> {
    let row = 3 * axis * stride + i;
    Vec3::new(
        L::load(&frame[row..]),
        L::load(&frame[row + stride..]),
        L::load(&frame[row + 2 * stride..]),
    )
}

/// The work of a kernel on one register of `n` lanes at `i`. A trait rather than a
/// closure: closures are separate functions that LLVM may leave un-inlined, and
/// outside the `#[target_feature]` entry point the intrinsics inside them become calls.
trait RegisterOp<M: Model, L: Lane> {
    fn run(&mut self, i: usize, n: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>);
}

/// Run `op` on every register of lanes of a job of `len` lanes.
#[inline(always)]
fn for_each_register<M: Model, L: Lane>(
    lobe: LobeLanes<'_>,
    len: usize,
    op: &mut impl RegisterOp<M, L>,
) {
    match lobe {
        LobeLanes::Uniform {
            params,
            frame,
            weight,
            probability,
        } => {
            let prepared = M::prepare(Params::shared(params));
            let lanes = LaneLobe {
                frame: LaneFrame::splat(&frame),
                weight: Rgb::new(L::splat(weight.r), L::splat(weight.g), L::splat(weight.b)),
                probability: L::splat(probability),
            };
            for i in (0..len).step_by(L::LANES) {
                op.run(i, L::LANES.min(len - i), &prepared, &lanes);
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
                let prepared = M::prepare(Params::rows(params, param_count, stride, i));
                let lanes = LaneLobe {
                    frame: load_frame(frame, stride, i),
                    weight: Rgb::new(
                        L::load(&weight[i..]),
                        L::load(&weight[stride + i..]),
                        L::load(&weight[2 * stride + i..]),
                    ),
                    probability: L::load(&probability[i..]),
                };
                op.run(i, L::LANES, &prepared, &lanes);
            }
        }
    }
}

impl<M: Model, L: Lane> RegisterOp<M, L> for EvalJob<'_> {
    #[inline(always)]
    fn run(&mut self, i: usize, n: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>) {
        let wo = direction(
            self.wo,
            i,
            n,
            self.directions.of_wo(),
            &mut self.out_of_range,
        );
        let wi = direction(self.wi, i, n, self.directions, &mut self.out_of_range);
        let (wo, wi) = if self.directions == Directions::Local {
            (wo, wi)
        } else {
            lanes.frame.to_local_pair(wo, wi)
        };
        let e = M::eval(p, wo, wi, self.mode);
        if let Some(rows) = &mut self.value {
            let terms = lanes.weight.to_array().into_iter().zip(e.value.to_array());
            for ((w, f), row) in terms.zip(rows.iter_mut()) {
                put_product(w, f, row, (i, n), self.store);
            }
        }
        put_product(lanes.probability, e.pdf, self.pdf, (i, n), self.store);
    }
}

impl<M: Model, L: Lane> RegisterOp<M, L> for SampleJob<'_> {
    #[inline(always)]
    fn run(&mut self, i: usize, n: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>) {
        let wo = direction(self.wo, i, n, self.directions, &mut self.out_of_range);
        // No `array::map` here: its closure may stay out of line, and the intrinsics
        // inside it with it (see `RegisterOp`).
        let uc = load::<L>(self.u[0], i, n, 0.5);
        let u0 = load::<L>(self.u[1], i, n, 0.5);
        let u1 = load::<L>(self.u[2], i, n, 0.5);
        self.out_of_range |= !(uc.is_finite() & u0.is_finite() & u1.is_finite()).all();
        let (uc, u0, u1) = (
            mixture::clamp_random(uc),
            mixture::clamp_random(u0),
            mixture::clamp_random(u1),
        );
        let mut settle = ToWorld::new(lanes.frame);
        let s = M::sample(
            p,
            lanes.frame.to_local(wo),
            uc,
            u0,
            u1,
            self.mode,
            &mut settle,
        );
        let s = Sample {
            wi: settle.world,
            ..s
        }
        .finish();
        let value = lanes.weight * s.value;
        let (wi, value, pdf, eta, roughness) = match &mut self.closure {
            None => (s.wi, value, s.pdf, s.eta, s.roughness),
            Some(rows) => {
                // The closure's only lobe: its value and pdf are the mixture's.
                let c = mixture::finish(&s, value, lanes.probability * s.pdf);
                for (w, row) in c.weight.to_array().into_iter().zip(rows.weight.iter_mut()) {
                    store(w, row, i, n);
                }
                if let Some(f) = rows.flags.as_deref_mut() {
                    f[i..i + n].copy_from_slice(&mixture::flags(&c)[..n]);
                }
                if let Some(k) = rows.component.as_deref_mut() {
                    k[i..i + n].copy_from_slice(&mixture::components(&c)[..n]);
                }
                if let Some(l) = rows.lobe.as_deref_mut() {
                    l[i..i + n].fill(0);
                }
                (c.wi, c.value, c.pdf, c.eta, c.roughness)
            }
        };
        let only = chosen_mask::<L>(self.only, i, n);
        for (v, row) in [wi.x, wi.y, wi.z].into_iter().zip(self.wi.iter_mut()) {
            store_where(only, v, row, i, n);
        }
        for (v, row) in value.to_array().into_iter().zip(self.value.iter_mut()) {
            store_where(only, v, row, i, n);
        }
        store_where(only, pdf, self.pdf, i, n);
        store_where(only, eta, self.eta, i, n);
        store_where(only, roughness, self.roughness, i, n);
        if let Some(events) = self.events.as_deref_mut() {
            store_where(only, pack_events(&s), events, i, n);
        }
    }
}

impl<M: Model, L: Lane> RegisterOp<M, L> for AlbedoJob<'_> {
    #[inline(always)]
    fn run(&mut self, i: usize, n: usize, p: &M::Prepared<L>, lanes: &LaneLobe<L>) {
        let wo = direction(self.wo, i, n, self.directions, &mut self.out_of_range);
        let local = lanes.frame.to_local(wo);
        let albedo = if self.estimate {
            M::albedo_estimate(p, local, self.mode)
        } else {
            M::albedo(p, local, self.mode)
        };
        let v = lanes.weight * albedo;
        for (v, row) in v.to_array().into_iter().zip(self.value.iter_mut()) {
            put(v, row, i, n, self.store);
        }
    }
}

/// Two registers at a time, as [`sample_body`].
#[inline(always)]
fn eval_body<M: Model, L: Lane>(job: &mut EvalJob<'_>) {
    for_each_register::<M, L::Interleaved>(job.lobe, job.len, job);
}

/// Two registers at a time (`Lane::Interleaved`): a sample's chain of divisions and
/// square roots (draw, settle, evaluate) leaves the ports idle for one register alone.
#[inline(always)]
fn sample_body<M: Model, L: Lane>(job: &mut SampleJob<'_>) {
    for_each_register::<M, L::Interleaved>(job.lobe, job.len, job);
}

/// Two registers at a time, as [`sample_body`]: the tables' gathers of one overlap
/// the other's arithmetic.
#[inline(always)]
fn albedo_body<M: Model, L: Lane>(job: &mut AlbedoJob<'_>) {
    for_each_register::<M, L::Interleaved>(job.lobe, job.len, job);
}

/// Normalize the staged directions in place; returns whether any lane's squared
/// length is not a finite number in [1e-24, 1e24] (those lanes are left alone, and
/// the batch layer re-stages the group exactly).
#[inline(always)]
fn normalize_body<L: Lane>(v: &mut [&mut [f32]; 3], len: usize) -> bool {
    let mut any = false;
    for i in (0..len).step_by(L::LANES) {
        let d = load3::<L>([&*v[0], &*v[1], &*v[2]], i, L::LANES);
        let (unit, ok) = unit_in_range(d);
        let n = Vec3::select(ok, unit, d);
        for (c, row) in [n.x, n.y, n.z].into_iter().zip(v.iter_mut()) {
            c.store(&mut row[i..]);
        }
        any |= !ok.all();
    }
    any
}

/// The directions `src`, arriving as `directions` says and normalized as a job's
/// would be, taken into `frame`, into `dst`; false when some lane's length is out of
/// [`Directions::Raw`]'s range (the outputs are then incomplete).
#[inline(always)]
fn to_local_body<L: Lane>(
    frame: &Frame,
    directions: Directions,
    src: [&[f32]; 3],
    dst: &mut [&mut [f32]; 3],
) -> bool {
    let len = src[0].len();
    let frame = LaneFrame::<L>::splat(frame);
    let mut out_of_range = false;
    for i in (0..len).step_by(L::LANES) {
        let n = L::LANES.min(len - i);
        let unit = direction::<L>(src, i, n, directions, &mut out_of_range);
        if out_of_range {
            return false;
        }
        let local = frame.to_local(unit);
        for (c, row) in [local.x, local.y, local.z].into_iter().zip(dst.iter_mut()) {
            store(c, row, i, n);
        }
    }
    true
}

/// The lobe each lane's `u` chooses among `probabilities` ([`mixture::choose`]), as
/// an index in `chosen`, and `u` rescaled for it in `reused`; false when some `u` is
/// not finite or no lobe can be chosen (the outputs are then incomplete). `starts`
/// (one more than `probabilities`) gets the runs the lanes make in lobe order: lobe
/// `k`'s lanes will be rows `starts[k]..starts[k + 1]` of sorted rows ([`sort_rows`]),
/// each run padded to whole registers ([`LANE_MULTIPLE`]).
#[inline(always)]
fn choose_body<L: Lane>(
    probabilities: &[f32],
    u: &[f32],
    chosen: &mut [f32],
    reused: &mut [f32],
    starts: &mut [usize],
) -> bool {
    let count = probabilities.len();
    starts.fill(0);
    for i in (0..u.len()).step_by(L::LANES) {
        let n = L::LANES.min(u.len() - i);
        let x = load::<L>(u, i, n, 0.5);
        let Some((k, r)) = mixture::choose(probabilities, x) else {
            return false;
        };
        if !x.is_finite().all() {
            return false;
        }
        store(k, chosen, i, n);
        store(r, reused, i, n);
        let real = u32::MAX >> (32 - n);
        for (j, start) in starts[1..=count].iter_mut().enumerate() {
            *start += (k.eq(L::splat(j as f32)).bits() & real).count_ones() as usize;
        }
    }
    for k in 0..count {
        starts[k + 1] = starts[k] + starts[k + 1].next_multiple_of(LANE_MULTIPLE);
    }
    true
}

/// The rows `src` (one value per lane of `chosen`) in lobe order: each lobe's lanes,
/// in lane order, packed into its run of `starts` ([`choose_body`]) by `compress`, the
/// run's padding repeating its first lane. `dst` rows hold `starts[last]` rows plus
/// [`MAX_LANES`] (whole registers are stored; each run's overflow is overwritten by
/// the next run).
#[inline(always)]
fn sort_rows_body<L: Lane>(
    chosen: &[f32],
    starts: &[usize],
    src: &[&[f32]],
    dst: &mut [&mut [f32]],
) {
    let len = chosen.len();
    for (k, run) in starts.windows(2).enumerate() {
        let (start, end) = (run[0], run[1]);
        if start == end {
            continue;
        }
        let mut at = start;
        for i in (0..len).step_by(L::LANES) {
            let n = L::LANES.min(len - i);
            let mask = load::<L>(chosen, i, n, -1.0).eq(L::splat(k as f32));
            let m = mask.bits().count_ones() as usize;
            if m == 0 {
                continue;
            }
            for (s, d) in src.iter().zip(dst.iter_mut()) {
                load::<L>(s, i, n, 0.0).compress(mask).store(&mut d[at..]);
            }
            at += m;
        }
        for d in dst.iter_mut() {
            let first = d[start];
            d[at..end].fill(first);
        }
    }
}

/// The inverse of [`sort_rows_body`]: each lane of `chosen` takes its row of the
/// sorted `src` (rows of `starts[last]` plus [`MAX_LANES`] values) into `dst`.
#[inline(always)]
fn unsort_rows_body<L: Lane>(
    chosen: &[f32],
    starts: &[usize],
    src: &[&[f32]],
    dst: &mut [&mut [f32]],
) {
    let (len, count) = (chosen.len(), starts.len() - 1);
    let mut at = [0usize; MAX_LOBES];
    at[..count].copy_from_slice(&starts[..count]);
    let mut masks = [L::Mask::splat(false); MAX_LOBES];
    for i in (0..len).step_by(L::LANES) {
        let n = L::LANES.min(len - i);
        let c = load::<L>(chosen, i, n, -1.0);
        for (k, mask) in masks[..count].iter_mut().enumerate() {
            *mask = c.eq(L::splat(k as f32));
        }
        for (s, d) in src.iter().zip(dst.iter_mut()) {
            let mut v = L::zero();
            for (&mask, &at) in masks[..count].iter().zip(&at) {
                if mask.any() {
                    v = L::select(mask, L::load(&s[at..]).expand(mask), v);
                }
            }
            store(v, d, i, n);
        }
        for (at, mask) in at.iter_mut().zip(&masks[..count]) {
            *at += mask.bits().count_ones() as usize;
        }
    }
}

/// Values of a conductor's Fresnel curve at [`FRESNEL_CURVE_COS`].
pub const CURVE_LEN: usize = FRESNEL_CURVE_COS.len();

#[inline(always)]
fn conductor_curve_body<L: Lane>(eta: [f32; 3], k: [f32; 3], out: &mut [[f32; CURVE_LEN]; 3]) {
    for ((&eta, &k), row) in eta.iter().zip(&k).zip(out.iter_mut()) {
        let ior = fresnel::ConductorIor::new(L::splat(eta), L::splat(k));
        for i in (0..CURVE_LEN).step_by(L::LANES) {
            let n = L::LANES.min(CURVE_LEN - i);
            let cos = load::<L>(&FRESNEL_CURVE_COS, i, n, 1.0);
            store(fresnel::conductor_with(cos, &ior), row, i, n);
        }
    }
}

kernel!(
    /// A conductor's Fresnel curve per channel at [`FRESNEL_CURVE_COS`], for the
    /// albedo's `FresnelNodes` (a closure computes them when a conductor is added).
    /// `fresnel::conductor_with` has no fused operations, so every ISA gives the same bits.
    conductor_curve<>(eta: [f32; 3], k: [f32; 3], out: &mut [[f32; CURVE_LEN]; 3]) => conductor_curve_body
);
kernel!(
    /// Directions into one frame (`to_local_body`).
    to_local<>(frame: &Frame, directions: Directions, src: [&[f32]; 3], dst: &mut [&mut [f32]; 3]) -> bool => to_local_body
);
kernel!(
    /// Choose the lobe of each lane of a shared closure (`choose_body`).
    choose_lobes<>(probabilities: &[f32], u: &[f32], chosen: &mut [f32], reused: &mut [f32], starts: &mut [usize]) -> bool => choose_body
);
kernel!(
    /// Rows into lobe order (`sort_rows_body`).
    sort_rows<>(chosen: &[f32], starts: &[usize], src: &[&[f32]], dst: &mut [&mut [f32]]) => sort_rows_body
);
kernel!(
    /// Rows from lobe order back into lane order (`unsort_rows_body`).
    unsort_rows<>(chosen: &[f32], starts: &[usize], src: &[&[f32]], dst: &mut [&mut [f32]]) => unsort_rows_body
);
kernel!(
    /// Finish a shared closure's mixture samples (`finish_body`).
    finish_mixture<>(job: &mut FinishJob<'_>) => finish_body
);
kernel!(
    /// `M::eval` over a job's lanes.
    eval<M: Model>(job: &mut EvalJob<'_>) => eval_body
);
kernel!(
    /// `M::sample` over a job's lanes.
    sample<M: Model>(job: &mut SampleJob<'_>) => sample_body
);
kernel!(
    /// `M::albedo` over a job's lanes.
    albedo<M: Model>(job: &mut AlbedoJob<'_>) => albedo_body
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

/// [`EvalJob`] one lane at a time through a scalar `eval` of a decoded block (lobes
/// without kernels; their jobs are staged, so directions are unit).
pub fn eval_each_lane(
    job: &mut EvalJob<'_>,
    eval: impl Fn(&[f32], Vec3<f32>, Vec3<f32>, Transport) -> crate::lobes::Eval<f32>,
) {
    debug_assert!(job.directions != Directions::Raw);
    let mut params = Vec::new();
    for i in 0..job.len {
        let (frame, weight, probability) = job.lobe.lane(i, &mut params);
        let wo = frame.to_local(lane_vec(job.wo, i));
        let wi = lane_vec(job.wi, i);
        let wi = frame.to_local(if job.directions == Directions::Sampled {
            wi.unit_from(wi.length_squared())
        } else {
            wi
        });
        let e = eval(&params, wo, wi, job.mode);
        let overwrite = job.store;
        let put = |out: &mut f32, v: f32| *out = if overwrite { v } else { *out + v };
        if let Some(value) = &mut job.value {
            for (row, v) in value.iter_mut().zip((weight * e.value).to_array()) {
                put(&mut row[i], v);
            }
        }
        put(&mut job.pdf[i], probability * e.pdf);
    }
}

/// [`SampleJob`] one lane at a time through a scalar `sample_world`.
pub fn sample_each_lane(
    job: &mut SampleJob<'_>,
    sample: impl Fn(&[f32], &Frame, Vec3<f32>, [f32; 3], Transport) -> Sample<f32>,
) {
    debug_assert!(job.directions == Directions::Unit && job.closure.is_none());
    debug_assert!(job.only.is_none());
    let mut params = Vec::new();
    for i in 0..job.len {
        let (frame, weight, _) = job.lobe.lane(i, &mut params);
        let u = job.u.map(|row| mixture::clamp_random(row[i]));
        let s = sample(&params, &frame, lane_vec(job.wo, i), u, job.mode);
        for (row, v) in job.wi.iter_mut().zip([s.wi.x, s.wi.y, s.wi.z]) {
            row[i] = v;
        }
        for (row, v) in job.value.iter_mut().zip((weight * s.value).to_array()) {
            row[i] = v;
        }
        job.pdf[i] = s.pdf;
        job.eta[i] = s.eta;
        job.roughness[i] = s.roughness;
        if let Some(events) = job.events.as_deref_mut() {
            events[i] = pack_events(&s);
        }
    }
}

/// [`AlbedoJob`] one lane at a time through a scalar `albedo`.
pub fn albedo_each_lane(
    job: &mut AlbedoJob<'_>,
    albedo: impl Fn(&[f32], Vec3<f32>, Transport) -> Rgb<f32>,
) {
    debug_assert_eq!(job.directions, Directions::Unit);
    let mut params = Vec::new();
    for i in 0..job.len {
        let (frame, weight, _) = job.lobe.lane(i, &mut params);
        let wo = frame.to_local(lane_vec(job.wo, i));
        let v = weight * albedo(&params, wo, job.mode);
        for (row, v) in job.value.iter_mut().zip(v.to_array()) {
            row[i] = if job.store { v } else { row[i] + v };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::Kernels;

    /// `compress` then `expand` under every mask of one register of lane values
    /// `1..=LANES`: the set lanes packed to the front in order, then back in place
    /// with zeros elsewhere. Returns the first failing mask.
    #[inline(always)]
    fn compress_expand_body<L: Lane>() -> Option<u32> {
        let values: [f32; MAX_LANES] = std::array::from_fn(|j| (j + 1) as f32);
        let v = L::load(&values);
        for mask in 0..1u32 << L::LANES {
            let flags: [f32; MAX_LANES] = std::array::from_fn(|j| (mask >> j & 1) as f32);
            let m = L::load(&flags).eq(L::one());
            let (mut packed, mut spread) = ([0.0; MAX_LANES], [0.0; MAX_LANES]);
            v.compress(m).store(&mut packed);
            v.compress(m).expand(m).store(&mut spread);
            let set: Vec<f32> = (0..L::LANES)
                .filter(|j| mask >> j & 1 == 1)
                .map(|j| values[j])
                .collect();
            let in_place = (0..L::LANES).all(|j| spread[j] == flags[j] * values[j]);
            if packed[..set.len()] != set[..] || !in_place {
                return Some(mask);
            }
        }
        None
    }

    kernel!(
        /// `compress_expand_body` on a kernel set.
        compress_expand<>() -> Option<u32> => compress_expand_body
    );

    /// Each lane of the normalize kernel takes `Vec3::try_unit`'s rule, bit for bit, on
    /// every kernel set: squared lengths within four ulps of 1 as they are (registers
    /// all such, or mixed with lanes the series or the exact form scales), others
    /// scaled.
    #[test]
    fn kernels_normalize_each_lane_as_the_scalar_rule() {
        let len = 4 * MAX_LANES;
        let mut state = 0x9e37_79b9_u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        let mut rows: [Vec<f32>; 3] = Default::default();
        for i in 0..len {
            let d = Vec3::new(rnd(), rnd(), rnd() + 2.0).normalize();
            // The first two registers unit only; then lengths about an ulp and
            // 1e-6 off, 1.5 and 3e-5 (series and exact) among unit lanes.
            let scale = match (i >= 2 * MAX_LANES, i % 5) {
                (false, _) | (true, 0) => 1.0,
                (true, 1) => 1.0 + f32::EPSILON,
                (true, 2) => 1.0 + 1e-6,
                (true, 3) => 1.5,
                _ => 3e-5,
            };
            for (row, c) in rows.iter_mut().zip([d.x, d.y, d.z]) {
                row.push(c * scale);
            }
        }
        let want: Vec<Vec3<f32>> = (0..len)
            .map(|i| Vec3::try_unit(rows[0][i], rows[1][i], rows[2][i], "d").unwrap())
            .collect();
        let unit = |i: usize| {
            let d = Vec3::new(rows[0][i], rows[1][i], rows[2][i]);
            (d.length_squared() - 1.0).abs() <= 4.0 * f32::EPSILON
        };
        assert!((0..2 * MAX_LANES).all(unit));
        for (i, w) in want.iter().enumerate().filter(|&(i, _)| unit(i)) {
            let d = [rows[0][i], rows[1][i], rows[2][i]];
            assert_eq!(
                [w.x, w.y, w.z].map(f32::to_bits),
                d.map(f32::to_bits),
                "lane {i}"
            );
        }
        for kernels in Kernels::available() {
            let mut out = rows.clone();
            let [x, y, z] = &mut out;
            let far = normalize(kernels, &mut [&mut x[..], &mut y[..], &mut z[..]], len);
            assert!(!far, "{:?}", kernels.isa());
            for (i, w) in want.iter().enumerate() {
                let got = [out[0][i], out[1][i], out[2][i]].map(f32::to_bits);
                assert_eq!(
                    got,
                    [w.x, w.y, w.z].map(f32::to_bits),
                    "{:?} lane {i}",
                    kernels.isa()
                );
            }
        }
    }

    #[test]
    fn compress_and_expand_invert_each_other_under_every_mask() {
        for kernels in Kernels::available() {
            assert_eq!(compress_expand(kernels), None, "{:?}", kernels.isa());
        }
    }
}
