//! A material's expansion over staged lanes, one register at a time and in one pass:
//! `expand` ([`MaterialModel::expand`], written once over the lane type) from the
//! per-lane parameter blocks (overrides applied) and `wo` taken into each lane's
//! shading frame;
//! each slot's block decoded and its albedo estimated; then pruning and selection
//! ([`super::material_rows::select`]). The slots' models are known statically
//! ([`MaterialModel::Slots`]), so every slot's decode, estimate and block sizes are
//! inlined, and nothing between the expansion and the selection leaves the registers.
//! Each step is the closure's (`materials::compiled::emit`), operation for operation,
//! so the rows hold the bits a closure per lane would.

use super::fused::{self, MAX_FUSED, Shape, Term};
use super::mixture::clamp_random;
use super::{
    FinishOutput, load, load_frame, load3, material_rows, store, store_frame, unit_in_range,
};
use crate::error::Error;
use crate::lobes::{MAX_DECODED_LEN, Model, Params, Transport};
use crate::materials::compiled::{DecodedBlock, MAX_MATERIAL_PARAMS};
use crate::materials::{
    Context, Expansion, MAX_SLOT_PARAMS, MAX_SLOTS, MaterialModel, SlotModels, SlotVisitor,
};
use crate::math::frame::{duff_axes, separated_tangent};
use crate::math::lane::MAX_LANES;
use crate::math::{Lane, LaneFrame, Mask, Rgb, Vec3};
use crate::params::block_size;
use crate::simd::kernel;

/// Inputs and outputs of an expansion over `len` lanes.
pub struct ExpandJob<'a> {
    pub len: usize,
    /// Where each lane's inputs come from.
    pub lanes: ExpandLanes<'a>,
    /// The material's own block: the values without rows.
    pub material: &'a [f32],
    /// `Material::prune`: a slot whose share is below it is dropped.
    pub prune: f32,
    /// Decoded blocks known beforehand (`Material::decoded_defaults`): lanes whose slot
    /// block is one of them copy it instead of decoding.
    pub known: &'a [Option<DecodedBlock>],
    /// Slot `k`'s decoded block, value `p` of lane `j` at `(k MAX_DECODED_LEN + p) len + j`.
    /// These rows, `weight` and `probability` are not written when `evals`, `sample`
    /// or `albedo` is given.
    pub decoded: &'a mut [f32],
    /// Slot `k`'s weight, channel `c` of lane `j` at `(3 k + c) len + j`; zero where
    /// the slot is dropped.
    pub weight: &'a mut [f32],
    /// Slot `k`'s selection probability of lane `j` at `k len + j` (0 where dropped).
    pub probability: &'a mut [f32],
    /// Out: slots with a nonzero probability on some lane.
    pub kept: [bool; MAX_SLOTS],
    /// The material's eval at each lane's `wi`, in the same pass: one entry per
    /// direction, every direction of a lane from its one expansion (a scanline host's
    /// lights). Empty: no eval.
    pub evals: &'a mut [ExpandEval<'a>],
    /// With [`ExpandLanes::Raw`] and slots that are a fused shape: each lane's sample,
    /// in the same pass.
    pub sample: Option<ExpandSample<'a>>,
    /// The material's directional albedo, `sum_k weight_k albedo_k(wo)` over the kept
    /// slots in slot order (what the staged path sums from the slots' albedo rows),
    /// into these rows in the same pass (with `evals` or alone).
    pub albedo: Option<[&'a mut [f32]; 3]>,
    /// With [`ExpandLanes::Raw`] and no `evals`: rows the samplers read, written in the
    /// same pass as the staged path writes them.
    pub staged: Option<StagedRows<'a>>,
    /// Out, with [`ExpandLanes::Raw`]: some lane's input is not one the staged path
    /// takes as it is (a direction outside [`super::Directions::Raw`]'s range, an override
    /// value out of its range); the outputs are then not valid.
    pub out_of_range: bool,
}

/// Each lane's shading frame (nine rows of `len`: t, b, n, each x, y, z) and unit `wo`.
pub struct StagedRows<'a> {
    pub frame: &'a mut [f32],
    pub wo: [&'a mut [f32]; 3],
}

/// Where an expansion's per-lane inputs come from.
pub enum ExpandLanes<'a> {
    /// Rows the batch layer staged (`len` a multiple of [`super::LANE_MULTIPLE`]).
    Staged {
        /// The material's values, each lane's where `per_lane` says so: value `p` of
        /// lane `j` at `p * len + j`.
        params: &'a [f32],
        /// The values with rows in `params` (overridden on some lane).
        per_lane: [bool; MAX_MATERIAL_PARAMS],
        /// Each lane's shading frame: nine rows (t, b, n, each x, y, z).
        frame: &'a [f32],
        /// Unit `wo` in world space.
        wo: [&'a [f32]; 3],
    },
    /// The caller's arrays from a chunk's first lane (`count` lanes; the registers
    /// past them see the staged path's padding), taken as the staged path takes them:
    /// `wo`, the normal, the tangent and an eval's `wi` normalized in the kernel
    /// ([`super::Directions::Raw`]), each lane's frame from its normal and tangent
    /// (`Frame::new`; a tangent it would take in f64 is out of range here), override
    /// values checked against their range.
    Raw {
        count: usize,
        /// Value `p`'s row and range where an override sets it (one entry per value).
        overrides: &'a [Option<RawValue<'a>>],
        normal: [&'a [f32]; 3],
        /// The caller's tangents (all zero on a lane: chosen from the normal), or none.
        tangent: Option<[&'a [f32]; 3]>,
        wo: [&'a [f32]; 3],
    },
}

/// Tangent and bitangent of unit normals `n` and a caller's tangents `given` (padding
/// zero), as `Frame::new` of the tangent `Vec3::try_unit` makes of it: chosen from the
/// normal where a tangent is all zero; the lanes where the tangent is outside what
/// `Vec3::try_unit` and the f32 Gram-Schmidt take are out of range (the staged path
/// reports or takes them).
#[inline(always)]
fn tangent_axes<L: Lane>(n: Vec3<L>, given: [L; 3]) -> (Vec3<L>, Vec3<L>, L::Mask) {
    let [x, y, z] = given;
    let automatic = x.eq(L::zero()) & y.eq(L::zero()) & z.eq(L::zero());
    let (unit, unit_ok) = unit_in_range(Vec3::new(x, y, z));
    let (t, separated) = separated_tangent(n, unit);
    let (mut t, mut b) = (t, n.cross(t));
    if automatic.any() {
        let (duff_t, duff_b) = duff_axes(n);
        t = Vec3::select(automatic, duff_t, t);
        b = Vec3::select(automatic, duff_b, b);
    }
    (t, b, automatic | (unit_ok & separated))
}

/// An overridden value's row in the caller's array, and its range.
#[derive(Clone, Copy)]
pub struct RawValue<'a> {
    pub row: &'a [f32],
    pub min: f32,
    pub max: f32,
}

impl RawValue<'_> {
    /// No row: a placeholder.
    const NONE: Self = RawValue {
        row: &[],
        min: 0.0,
        max: 0.0,
    };
}

/// An eval in the expansion's pass: what `kernels::fused::rows` computes from the rows
/// (`sum_k weight_k f_k` and `sum_k p_k pdf_k` over the kept slots, in slot order, each
/// term as the eval kernels compute it), from the registers instead.
pub struct ExpandEval<'a> {
    /// `wi` in world space: unit, or the caller's with [`ExpandLanes::Raw`].
    pub wi: [&'a [f32]; 3],
    pub value: Option<[&'a mut [f32]; 3]>,
    pub pdf: &'a mut [f32],
}

/// A sample in the expansion's pass: each lane's slot chosen by its selection
/// probabilities ([`material_rows::choose_register`], the choice `Closure::sample`
/// makes), sampled, every slot evaluated there and the sample finished into the
/// caller's rows ([`fused::sample_finished`], the arithmetic of the staged path's
/// `kernels::fused::rows` and `finish_mixture`). A slot dropped on a lane has weight
/// and probability 0 there: it adds `0 f` and `0 pdf`.
pub struct ExpandSample<'a> {
    /// The caller's random numbers: the slot choice, then the direction's two
    /// dimensions. A lane with one not finite makes the job's outputs not valid
    /// (`out_of_range`), as the staged path fails that lane.
    pub u: [&'a [f32]; 3],
    pub out: FinishOutput<'a>,
}

/// One register of an [`ExpandSample`], as [`SlotModels::sample_fused`] takes it.
pub struct SlotSample<'r, 'o, L: Lane> {
    /// Each slot's decoded block.
    decoded: &'r [[L; MAX_DECODED_LEN]; MAX_SLOTS],
    terms: [Term<L>; MAX_FUSED],
    /// Each lane's chosen slot, its frame and local `wo`, and its random numbers.
    chosen: L,
    at: (LaneFrame<L>, Vec3<L>),
    u: [L; 3],
    out: &'r mut FinishOutput<'o>,
    /// The register's first lane and lane count.
    lanes: (usize, usize),
}

/// [`SlotModels::sample_fused`] of slots that are the fused shape `S`.
#[inline(always)]
pub fn sample_slots<S: Shape, L: Lane>(r: SlotSample<'_, '_, L>) -> bool {
    let mut params = [Params::shared(&[]); MAX_FUSED];
    for (p, decoded) in params.iter_mut().zip(r.decoded).take(S::LOBES) {
        *p = Params::new(decoded);
    }
    let p = S::prepare(&params);
    let register = (r.chosen, r.at, r.u);
    fused::sample_finished::<S, L>(&p, &r.terms, register, Transport::Radiance, r.out, r.lanes);
    true
}

/// One register's slots: decoded (into the rows, when wanted), estimated.
/// `BY_SLOT`: take each slot's estimate only where some lane weights it (and none when
/// no lane weights two slots). A register whose lanes weight every slot, some lane two
/// or more, takes the form without those branches, so LLVM computes what the
/// estimates share (`sqrt(cos_o)` of the table lookups) once; the same estimates either
/// way.
struct Slots<'j, L, const BY_SLOT: bool> {
    i: usize,
    len: usize,
    wo: Vec3<L>,
    expansion: &'j Expansion<L>,
    /// The last block each slot decoded (or the known one).
    cache: &'j mut [Option<DecodedBlock>; MAX_SLOTS],
    rows: Option<&'j mut [f32]>,
    /// Each slot's decoded block (its first `DECODED_LEN` values).
    decoded: &'j mut [[L; MAX_DECODED_LEN]; MAX_SLOTS],
    share: [L; MAX_SLOTS],
    /// Whether no lane weights two slots: each lane's slot is chosen with probability
    /// 1 whatever its share (`material_rows::select`), so no estimate is taken (as a
    /// closure skips a slot's weighted alone).
    alone: bool,
}

impl<L: Lane, const BY_SLOT: bool> SlotVisitor for Slots<'_, L, BY_SLOT> {
    #[inline(always)]
    fn slot<M: Model>(&mut self, k: usize) -> Result<(), Error> {
        let raw = &self.expansion.params[k][..block_size(M::PARAMS)];
        let decoded = &mut self.decoded[k][..M::DECODED_LEN];
        if M::DECODE_COPIES && raw.len() == decoded.len() {
            decoded.copy_from_slice(raw);
        } else {
            decode::<M, L>(raw, decoded, &mut self.cache[k]);
        }
        let decoded = &self.decoded[k][..M::DECODED_LEN];
        if let Some(rows) = self.rows.as_deref_mut() {
            let (len, i) = (self.len, self.i);
            for (p, v) in decoded.iter().enumerate() {
                v.store(&mut rows[(k * MAX_DECODED_LEN + p) * len + i..]);
            }
        }
        let weight = self.expansion.weight[k];
        let zero = L::zero();
        let emitted = weight.any_positive();
        if BY_SLOT && self.alone {
            self.share[k] = L::select(emitted, L::one(), zero);
        } else if !BY_SLOT || emitted.any() {
            let p = M::prepare(Params::new(decoded));
            let albedo = M::albedo_estimate(&p, self.wo, Transport::Radiance);
            self.share[k] = L::select(emitted, (weight * albedo).luminance(), zero);
        }
        Ok(())
    }
}

/// Each slot's weight and block zeroed.
struct Zero<'e, L>(&'e mut Expansion<L>);

impl<L: Lane> SlotVisitor for Zero<'_, L> {
    #[inline(always)]
    fn slot<M: Model>(&mut self, k: usize) -> Result<(), Error> {
        self.0.weight[k] = Rgb::zero();
        self.0.params[k][..block_size(M::PARAMS)].fill(L::zero());
        Ok(())
    }
}

/// One register's eval sums over its kept slots (`kernels::fused::rows`'s terms).
/// `SKIP_DROPPED`: skip slots kept on no lane of the register. Without it every slot
/// is evaluated with no branch between them, so LLVM computes what their evals share
/// (the half vector) once; a register that keeps every slot on some lane takes that
/// form (the same sums: no slot is skipped either way).
struct EvalSlots<'j, L, const SKIP_DROPPED: bool> {
    decoded: &'j [[L; MAX_DECODED_LEN]; MAX_SLOTS],
    weight: &'j [Rgb<L>; MAX_SLOTS],
    probability: &'j [L; MAX_SLOTS],
    wo: Vec3<L>,
    wi: Vec3<L>,
    sum: Option<(Rgb<L>, L)>,
}

impl<L: Lane, const SKIP_DROPPED: bool> SlotVisitor for EvalSlots<'_, L, SKIP_DROPPED> {
    #[inline(always)]
    fn slot<M: Model>(&mut self, k: usize) -> Result<(), Error> {
        let probability = self.probability[k];
        // A slot kept on no lane adds `0 f`: nothing.
        if SKIP_DROPPED && !probability.gt(L::zero()).any() {
            return Ok(());
        }
        let p = M::prepare(Params::new(&self.decoded[k][..M::DECODED_LEN]));
        let e = M::eval(&p, self.wo, self.wi, Transport::Radiance);
        let term = Term {
            weight: self.weight[k],
            probability,
        };
        self.sum = Some(match self.sum {
            None => fused::weighted(&term, e),
            Some(sum) => fused::add_weighted(sum, &term, e),
        });
        Ok(())
    }
}

/// `M::decode` of each lane's `raw` block into `out`: lanes whose block is `cache`'s
/// copy its decoded block; the others decode, one at a time, and become the cache.
#[inline(always)]
fn decode<M: Model, L: Lane>(raw: &[L], out: &mut [L], cache: &mut Option<DecodedBlock>) {
    let n = raw.len();
    if let Some(c) = cache
        && holds(raw, &c.raw[..n])
    {
        for (o, &v) in out.iter_mut().zip(&c.decoded) {
            *o = L::splat(v);
        }
        return;
    }
    let mut lanes = [[0.0f32; MAX_LANES]; MAX_SLOT_PARAMS];
    for (row, v) in lanes.iter_mut().zip(raw) {
        v.store(row);
    }
    let block = |j: usize| {
        let mut b = [0.0f32; MAX_SLOT_PARAMS];
        for (v, row) in b.iter_mut().zip(&lanes) {
            *v = row[j];
        }
        b
    };
    let mut decoded = [[0.0f32; MAX_LANES]; MAX_DECODED_LEN];
    for j in 0..L::LANES {
        let b = block(j);
        let c = match cache.take() {
            Some(c) if c.decodes(&b[..n]) => c,
            _ => {
                let mut c = DecodedBlock {
                    raw: b,
                    decoded: [0.0; MAX_DECODED_LEN],
                };
                M::decode(&c.raw[..n], &mut c.decoded[..out.len()]);
                c
            }
        };
        for (row, &v) in decoded.iter_mut().zip(&c.decoded[..out.len()]) {
            row[j] = v;
        }
        *cache = Some(c);
    }
    for (o, row) in out.iter_mut().zip(&decoded) {
        *o = L::load(row);
    }
}

/// Whether every lane of `raw` holds `block`, bit for bit: equal, and with the same
/// sign (equal floats differ in their bits only as -0 and +0).
#[inline(always)]
fn holds<L: Lane>(raw: &[L], block: &[f32]) -> bool {
    // Plain loops: a closure is a function without the kernel's target features
    // (tests/simd_inlining.rs).
    let mut all = true;
    for (&v, &x) in raw.iter().zip(block) {
        let sign = L::one().copysign(v).eq(L::splat(1f32.copysign(x)));
        all &= (v.eq(L::splat(x)) & sign).all();
    }
    all
}

/// The slots' decoded blocks, weights and selection probabilities of one register.
type SlotTerms<'j, L> = (
    &'j [[L; MAX_DECODED_LEN]; MAX_SLOTS],
    &'j [Rgb<L>; MAX_SLOTS],
    &'j [L; MAX_SLOTS],
);

/// One register's albedo sum over its slots kept on some lane ([`ExpandJob::albedo`]).
struct AlbedoSlots<'j, L> {
    decoded: &'j [[L; MAX_DECODED_LEN]; MAX_SLOTS],
    weight: &'j [Rgb<L>; MAX_SLOTS],
    probability: &'j [L; MAX_SLOTS],
    wo: Vec3<L>,
    sum: Rgb<L>,
}

impl<L: Lane> SlotVisitor for AlbedoSlots<'_, L> {
    #[inline(always)]
    fn slot<M: Model>(&mut self, k: usize) -> Result<(), Error> {
        let kept = self.probability[k].gt(L::zero());
        // A slot kept on no lane adds zeros: nothing (its tables are not read).
        if !kept.any() {
            return Ok(());
        }
        let p = M::prepare(Params::new(&self.decoded[k][..M::DECODED_LEN]));
        let albedo = self.weight[k] * M::albedo(&p, self.wo, Transport::Radiance);
        self.sum = self.sum + Rgb::select(kept, albedo, Rgb::zero());
        Ok(())
    }
}

/// [`EvalSlots`]' sums at `(wo, wi)`.
#[inline(always)]
fn eval_sums<M: MaterialModel, L: Lane, const SKIP_DROPPED: bool>(
    (decoded, weight, probability): SlotTerms<'_, L>,
    wo: Vec3<L>,
    wi: Vec3<L>,
) -> Option<(Rgb<L>, L)> {
    let mut sums = EvalSlots::<L, SKIP_DROPPED> {
        decoded,
        weight,
        probability,
        wo,
        wi,
        sum: None,
    };
    M::Slots::visit(&mut sums).expect("an eval does not fail");
    sums.sum
}

/// [`Slots`] of one register visited: each slot's share.
#[inline(always)]
fn stage_slots<M: MaterialModel, L: Lane, const BY_SLOT: bool>(
    mut slots: Slots<'_, L, BY_SLOT>,
) -> [L; MAX_SLOTS] {
    M::Slots::visit(&mut slots).expect("a slot's staging does not fail");
    slots.share
}

/// [`expand_lanes`] two registers at a time (`Lane::Interleaved`): the albedo
/// estimates' gathers and the frames' divisions of one register overlap the other's
/// arithmetic (Disney material eval, AVX-512: 77 -> 81-87 M lanes/s).
#[inline(always)]
fn expand_body<M: MaterialModel, L: Lane>(job: &mut ExpandJob<'_>) {
    expand_lanes::<M, L::Interleaved>(job);
}

#[inline(always)]
fn expand_lanes<M: MaterialModel, L: Lane>(job: &mut ExpandJob<'_>) {
    let len = job.len;
    let param_count = job.material.len();
    debug_assert!(param_count <= MAX_MATERIAL_PARAMS);
    let count = M::Slots::NAMES.len();
    let mut cache = [None; MAX_SLOTS];
    cache[..job.known.len()].copy_from_slice(job.known);
    let mut raw = [L::zero(); MAX_MATERIAL_PARAMS];
    for (r, &v) in raw.iter_mut().zip(job.material) {
        *r = L::splat(v);
    }
    let zero = Vec3::new(L::zero(), L::zero(), L::zero());
    let mut e = Expansion::<L>::default();
    // Out of the loop: each register writes what it reads.
    let mut decoded = [[L::zero(); MAX_DECODED_LEN]; MAX_SLOTS];
    let mut in_range = L::Mask::splat(true);
    // The values with rows, listed once: each register reads only those (a loop over
    // every value testing for a row was 4% of a Disney eval's instructions).
    let mut rows = [(0, RawValue::NONE); MAX_MATERIAL_PARAMS];
    let mut row_count = 0;
    for p in 0..param_count {
        let value = match &job.lanes {
            ExpandLanes::Staged { per_lane, .. } => per_lane[p].then_some(RawValue::NONE),
            ExpandLanes::Raw { overrides, .. } => overrides[p],
        };
        if let Some(value) = value {
            rows[row_count] = (p, value);
            row_count += 1;
        }
    }
    let rows = &rows[..row_count];
    for i in (0..len).step_by(L::LANES) {
        let n = L::LANES.min(len - i);
        let (frame, wo) = match &job.lanes {
            ExpandLanes::Staged {
                params, frame, wo, ..
            } => {
                debug_assert!(len.is_multiple_of(L::LANES));
                for &(p, _) in rows {
                    raw[p] = L::load(&params[p * len + i..]);
                }
                (load_frame::<L>(frame, len, i), load3::<L>(*wo, i, L::LANES))
            }
            ExpandLanes::Raw {
                count,
                normal,
                tangent,
                wo,
                ..
            } => {
                // A register past the caller's lanes (a padded chunk's last on AVX2)
                // reads none of them: all padding.
                let (at, n) = (i.min(*count), count.saturating_sub(i).min(L::LANES));
                for &(p, o) in rows {
                    let v = load::<L>(o.row, at, n, job.material[p]);
                    // `ParamSpec::in_range`.
                    in_range = in_range
                        & v.abs().le(L::splat(f32::MAX))
                        & v.ge(L::splat(o.min))
                        & v.le(L::splat(o.max));
                    raw[p] = v;
                }
                let (normal, normal_ok) = unit_in_range(load3::<L>(*normal, at, n));
                let (t, b, tangent_ok) = match tangent {
                    // Zero padding: an automatic tangent. Not `array::map`: it took
                    // the loads out of line (tests/simd_inlining.rs).
                    Some([x, y, z]) => {
                        let pad = |row| load::<L>(row, at, n, 0.0);
                        tangent_axes(normal, [pad(x), pad(y), pad(z)])
                    }
                    None => {
                        let (t, b) = duff_axes(normal);
                        (t, b, L::Mask::splat(true))
                    }
                };
                in_range = in_range & tangent_ok;
                let frame = LaneFrame::new(t, b, normal);
                let (wo, wo_ok) = unit_in_range(load3::<L>(*wo, at, n));
                in_range = in_range & normal_ok & wo_ok;
                if let Some(rows) = job.staged.as_mut() {
                    store_frame(&frame, rows.frame, len, i);
                    for (v, row) in [wo.x, wo.y, wo.z].into_iter().zip(rows.wo.iter_mut()) {
                        v.store(&mut row[i..]);
                    }
                }
                (frame, wo)
            }
        };
        // Material batches take no positions, footprints or uvs: zero, as a context
        // that leaves them unset.
        let ctx = Context {
            wo: frame.to_local(wo),
            position: zero,
            reference_position: zero,
            footprint: L::zero(),
            uv: [L::zero(); 2],
        };
        // What is read back starts at zero for each register, as a fresh `Expansion`
        // would (zeroing all of it costs more than the expansion); by each slot's
        // static block size, in registers (a runtime length was a `memset` call per
        // slot per register), and dropped where `expand` writes.
        M::Slots::visit(&mut Zero(&mut e)).expect("zeroing does not fail");
        M::expand(Params::new(&raw[..param_count]), &ctx, &mut e);
        let (mut weighted, mut every_emitted) = (L::zero(), true);
        for w in &e.weight[..count] {
            let emitted = w.any_positive();
            weighted += L::select(emitted, L::one(), L::zero());
            every_emitted &= emitted.any();
        }
        let alone = weighted.le(L::one()).all();
        let in_pass = !job.evals.is_empty() || job.sample.is_some() || job.albedo.is_some();
        let rows = (!in_pass).then_some(&mut *job.decoded);
        macro_rules! slots {
            ($by_slot:literal) => {
                stage_slots::<M, L, $by_slot>(Slots {
                    i,
                    len,
                    wo: ctx.wo,
                    expansion: &e,
                    cache: &mut cache,
                    rows,
                    decoded: &mut decoded,
                    share: [L::zero(); MAX_SLOTS],
                    alone,
                })
            };
        }
        let share = if every_emitted && !alone {
            slots!(false)
        } else {
            slots!(true)
        };
        let mut weight = e.weight;
        let probability = material_rows::select(count, job.prune, &share, &mut weight);
        for (kept, p) in job.kept[..count].iter_mut().zip(&probability) {
            *kept |= p.gt(L::zero()).any();
        }
        if let Some(rows) = job.albedo.as_mut() {
            let mut sums = AlbedoSlots {
                decoded: &decoded,
                weight: &weight,
                probability: &probability,
                wo: ctx.wo,
                sum: Rgb::zero(),
            };
            M::Slots::visit(&mut sums).expect("an albedo does not fail");
            for (v, row) in sums.sum.to_array().into_iter().zip(rows.iter_mut()) {
                store(v, row, i, n);
            }
            if job.evals.is_empty() {
                continue;
            }
        }
        if let Some(sample) = job.sample.as_mut() {
            let u_lobe = load::<L>(sample.u[0], i, n, 0.5);
            let u0 = load::<L>(sample.u[1], i, n, 0.5);
            let u1 = load::<L>(sample.u[2], i, n, 0.5);
            in_range = in_range & u_lobe.is_finite() & u0.is_finite() & u1.is_finite();
            let (chosen, reused) = material_rows::choose_register(&probability[..count], u_lobe);
            let mut terms = [Term::zero(); MAX_FUSED];
            for (k, t) in terms.iter_mut().enumerate().take(count) {
                *t = Term {
                    weight: weight[k],
                    probability: probability[k],
                };
            }
            let taken = M::Slots::sample_fused(SlotSample {
                decoded: &decoded,
                terms,
                chosen,
                at: (frame, ctx.wo),
                u: [reused, clamp_random(u0), clamp_random(u1)],
                out: &mut sample.out,
                lanes: (i, n),
            });
            if !taken {
                in_range = L::Mask::splat(false);
            }
            continue;
        }
        if job.evals.is_empty() {
            for k in 0..count {
                probability[k].store(&mut job.probability[k * len + i..]);
                for (c, v) in weight[k].to_array().into_iter().enumerate() {
                    v.store(&mut job.weight[(3 * k + c) * len + i..]);
                }
            }
            continue;
        }
        let mut every_kept = true;
        for p in &probability[..count] {
            every_kept &= p.gt(L::zero()).any();
        }
        let terms = (&decoded, &weight, &probability);
        for eval in job.evals.iter_mut() {
            let wi = load3::<L>(eval.wi, i, n);
            let wi = match job.lanes {
                ExpandLanes::Staged { .. } => wi,
                ExpandLanes::Raw { .. } => {
                    let (wi, ok) = unit_in_range(wi);
                    in_range = in_range & ok;
                    wi
                }
            };
            let wi = frame.to_local(wi);
            let sum = if every_kept {
                eval_sums::<M, L, false>(terms, ctx.wo, wi)
            } else {
                eval_sums::<M, L, true>(terms, ctx.wo, wi)
            };
            let (value, pdf) = sum.unwrap_or((Rgb::zero(), L::zero()));
            if let Some(rows) = eval.value.as_mut() {
                for (v, row) in value.to_array().into_iter().zip(rows.iter_mut()) {
                    store(v, row, i, n);
                }
            }
            store(pdf, eval.pdf, i, n);
        }
    }
    job.out_of_range = !in_range.all();
}

kernel!(
    /// `M::expand` over a job's lanes, with each slot decoded, pruned and selected.
    expand<M: MaterialModel>(job: &mut ExpandJob<'_>) => expand_body
);
