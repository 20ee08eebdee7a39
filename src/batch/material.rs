//! Batches over one compiled material: per-lane shading contexts and overrides,
//! expanded and evaluated without building a closure per lane.
//!
//! A block is cut into chunks of [`CHUNK`] active lanes. Each chunk stages, per lane,
//! the unit `wo`, the shading frame and the parameter block with the lane's overrides,
//! and expands it in one SIMD pass (`kernels::expand`: `MaterialModel::expand`, the
//! same code as `Material::build_closure`, then each slot's block decoded and its
//! albedo estimate, whose `luminance(weight * albedo)` prunes the slot per lane and
//! sets the selection probabilities by the closure's rule, `closure::selection`). An
//! eval or pdf without the reverse pdf is finished in that pass: every kept slot
//! evaluated from the registers, weighted and summed in slot order. The other calls
//! get per-slot SoA rows of decoded lobe blocks, weights and probabilities, and run
//! each slot's lobe kernels over them (`LobeLanes::PerLane`): the albedos, an eval
//! with the reverse pdf slot by slot, or a sample (each slot over the lanes that chose
//! it, sorted into runs, then the mixture at the sampled direction). A lane's result is
//! that of the closure `glint_material_closure` builds for it, up to the batch
//! kernels' rounding; slots every lane pruned are skipped.

use super::stage::{
    LaneError, Scratch, grow, padded, rows3, stage_directions, view3, with_scratch,
};
use super::{
    EvalOutput, Exec, SampleOutput, SampleRandoms, Soa3, Soa3Mut, SplitLanes, check_count,
    check_len, finish_lane, run_blocks,
};
use crate::closure::{SampleResult, check_randoms};
use crate::error::{Error, Status};
use crate::kernels::expand::{
    ExpandEval, ExpandJob, ExpandLanes, ExpandSample, RawValue, StagedRows,
};
use crate::kernels::fused::{self, FusedRows, FusedRowsJob, MAX_FUSED, RowsSample};
use crate::kernels::material_rows::{self, ChooseJob};
use crate::kernels::{
    AlbedoJob, Directions, EvalJob, FinishJob, FinishLobe, LANE_MULTIPLE, LobeLanes, SampleJob,
    finish_mixture, sort_rows, unsort_rows,
};
use crate::lobes::Transport;
use crate::materials::compiled::MAX_MATERIAL_PARAMS;
use crate::materials::{MAX_SLOTS, Material};
use crate::math::lane::MAX_LANES;
use crate::math::{Frame, Vec3};
use crate::params::{self, ParamKind};
use crate::registry::LobeRef;
use crate::simd::Kernels;
use std::ops::Range;

/// Active lanes staged at once: every slot's rows stay in the L2 cache.
const CHUNK: usize = 256;

/// A parameter set per lane: `value[c][lane]` for component `c` (one for `float`
/// and `enum`, three for `rgb`).
#[derive(Clone, Copy)]
pub struct OverrideLanes<'a> {
    pub param: u32,
    pub kind: ParamKind,
    pub value: [&'a [f32]; 3],
}

/// The per-lane inputs of a material batch.
pub struct MaterialInput<'a> {
    pub count: usize,
    pub material: &'a Material,
    /// Nonzero = active; `None` = all lanes active.
    pub active: Option<&'a [u8]>,
    pub wo: Soa3<'a>,
    pub normal: Soa3<'a>,
    /// `None`: tangents chosen automatically (as an all-zero `glint_frame.tangent`).
    pub tangent: Option<Soa3<'a>>,
    pub overrides: &'a [OverrideLanes<'a>],
}

impl MaterialInput<'_> {
    fn is_active(&self, lane: usize) -> bool {
        self.active.is_none_or(|a| a[lane] != 0)
    }

    /// Every array holds `count` lanes; every override names a parameter of the
    /// material's schema with its kind.
    fn check(&self) -> Result<(), Error> {
        check_count(self.count)?;
        if let Some(a) = self.active {
            check_len(a.len(), self.count, "active")?;
        }
        self.wo.check(self.count, "wo")?;
        self.normal.check(self.count, "normal")?;
        if let Some(t) = &self.tangent {
            t.check(self.count, "tangent")?;
        }
        if self.overrides.len() > MAX_MATERIAL_PARAMS {
            return Err(Error::new(
                Status::OutOfRange,
                format!(
                    "{} overrides: a material has at most {MAX_MATERIAL_PARAMS} parameters",
                    self.overrides.len()
                ),
            ));
        }
        for (i, o) in self.overrides.iter().enumerate() {
            self.material.override_spec(i, o.param, o.kind)?;
            for c in 0..o.kind.size() {
                check_len(
                    o.value[c].len(),
                    self.count,
                    format_args!("overrides[{i}].value[{c}]"),
                )?;
            }
        }
        Ok(())
    }
}

/// Per-slot rows of a chunk.
#[derive(Default)]
pub(super) struct SlotRows {
    /// Each lane's material block (overrides applied): value `p` of lane `j` at
    /// `p * len + j`.
    input: Vec<f32>,
    /// Each lane's unit shading normal.
    normal: [Vec<f32>; 3],
    /// Decoded blocks: slot `k`'s value `p` of lane `j` at `(k * MAX_PARAMS + p) * len + j`.
    params: Vec<f32>,
    weight: Vec<f32>,
    probability: Vec<f32>,
    frame: Vec<f32>,
    /// Each slot's `weight * albedo(wo)`, laid out as `weight`.
    albedo: Vec<f32>,
    /// Whether any lane keeps the slot.
    live: [bool; MAX_SLOTS],
    sorted: SortedRows,
}

/// A material sample's rows in the order of the slots its lanes chose
/// ([`sample_sorted`]), each row `stride` values: the frame, `wo` and `u`; one slot's
/// decoded block and weight at a time; the outputs.
#[derive(Default)]
pub(super) struct SortedRows {
    shared: Vec<f32>,
    slot: Vec<f32>,
    out: Vec<f32>,
}

/// Most decoded values a slot's lobe block holds in the rows.
const MAX_PARAMS: usize = crate::lobes::MAX_DECODED_LEN;

impl SlotRows {
    fn reserve(&mut self, len: usize, block_len: usize) -> Result<(), Error> {
        super::stage::reserve(&mut self.input, block_len * len)?;
        for row in &mut self.normal {
            super::stage::reserve(row, len)?;
        }
        super::stage::reserve(&mut self.params, MAX_SLOTS * MAX_PARAMS * len)?;
        super::stage::reserve(&mut self.weight, MAX_SLOTS * 3 * len)?;
        super::stage::reserve(&mut self.probability, MAX_SLOTS * len)?;
        super::stage::reserve(&mut self.albedo, MAX_SLOTS * 3 * len)?;
        super::stage::reserve(&mut self.frame, 9 * len)
    }

    /// Slot `k`'s rows as the kernels read them.
    fn lanes(&self, k: usize, param_count: usize, len: usize) -> LobeLanes<'_> {
        let rows = self.slot(k, param_count, len);
        LobeLanes::PerLane {
            params: rows.params,
            param_count,
            frame: &self.frame[..9 * len],
            weight: rows.weight,
            probability: rows.probability,
            stride: len,
        }
    }

    /// Slot `k`'s own rows (the frame rows are every slot's).
    fn slot(&self, k: usize, param_count: usize, len: usize) -> FusedRows<'_> {
        let p = k * MAX_PARAMS * len;
        FusedRows {
            params: &self.params[p..p + param_count * len],
            param_count,
            weight: &self.weight[k * 3 * len..(k + 1) * 3 * len],
            probability: &self.probability[k * len..(k + 1) * len],
        }
    }
}

/// Stage the chunk's lanes `lanes` (`len` padded): unit `wo` into `s.wo`, frames and
/// per-lane material blocks; then the expansion in SIMD, each slot's blocks decoded,
/// pruned by its albedo estimate and given its selection probability. Lanes with
/// invalid inputs are flagged in `s.failed` and staged with valid stand-ins. With an
/// `eval`, the unit `wi` is staged into `s.wi` after the overrides. Without one, a
/// chunk the raw path takes is staged in the expansion's pass ([`stage_raw`]).
fn stage_chunk(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    lanes: &[u32],
    len: usize,
    s: &mut Scratch,
    errors: &mut LaneError,
    eval: Option<StageEval<'_, '_>>,
) -> Result<(), Error> {
    if eval.is_none() && stage_raw(kernels, input, lanes, len, s)? {
        return Ok(());
    }
    let material = input.material;
    let block_len = material.params().len();
    s.reserve_rows(len)?;
    super::stage::reserve(&mut s.failed, len)?;
    s.material.reserve(len, block_len)?;
    let failed = grow(&mut s.failed, len);
    failed.fill(0);
    let rows = &mut s.material;
    // In the order the scalar call checks them: a lane reports its first error.
    let mut any = stage_directions(
        kernels,
        input.wo,
        "wo",
        lanes,
        rows3(&mut s.wo, len),
        failed,
        errors,
    );
    any |= stage_directions(
        kernels,
        input.normal,
        "normal",
        lanes,
        rows3(&mut rows.normal, len),
        failed,
        errors,
    );
    any |= stage_frames(kernels, input, lanes, len, rows, failed, errors);
    let (failed_override, per_lane) = stage_blocks(input, lanes, len, rows, failed, errors);
    any |= failed_override;
    s.any_failed = any;
    let mut evals = Vec::new();
    let mut albedo = None;
    if let Some(e) = eval {
        // Each direction's `wi` after the lane's own inputs, its failures (the lane's
        // and its `wi`'s) in that direction's flags.
        let k = e.errors.len();
        super::stage::reserve(&mut s.failed_directions, k * len)?;
        for row in s.wi.iter_mut().chain(&mut s.value).chain([&mut s.pdf]) {
            super::stage::reserve(row, k * len)?;
        }
        let [x, y, z] = rows3(&mut s.wi, k * len);
        let rows = x
            .chunks_exact_mut(len)
            .zip(y.chunks_exact_mut(len))
            .zip(z.chunks_exact_mut(len));
        let flags = grow(&mut s.failed_directions, k * len).chunks_exact_mut(len);
        for (d, ((((x, y), z), flags), errors)) in rows.zip(flags).zip(&mut *e.errors).enumerate() {
            flags.copy_from_slice(failed);
            let wi = direction(e.wi, d, e.count);
            s.any_failed |= stage_directions(kernels, wi, "wi", lanes, [x, y, z], flags, errors);
        }
        if e.in_pass {
            super::stage::reserve(&mut evals, k)?;
            let wi = view3(&s.wi, k * len);
            let [x, y, z] = rows3(&mut s.value, k * len);
            let values = x
                .chunks_exact_mut(len)
                .zip(y.chunks_exact_mut(len))
                .zip(z.chunks_exact_mut(len));
            for (d, (((x, y), z), pdf)) in values
                .zip(grow(&mut s.pdf, k * len).chunks_exact_mut(len))
                .enumerate()
            {
                let at = d * len..(d + 1) * len;
                evals.push(ExpandEval {
                    wi: wi.map(|row| &row[at.clone()]),
                    value: e.want_value.then_some([x, y, z]),
                    pdf,
                });
            }
            if e.albedo {
                for row in &mut s.albedo {
                    super::stage::reserve(row, len)?;
                }
                albedo = Some(rows3(&mut s.albedo, len));
            }
        }
    }
    let mut job = ExpandJob {
        len,
        lanes: ExpandLanes::Staged {
            params: &rows.input[..block_len * len],
            per_lane,
            frame: &rows.frame[..9 * len],
            wo: view3(&s.wo, len),
        },
        material: material.params(),
        prune: material.prune(),
        known: material.decoded_defaults(),
        decoded: grow(&mut rows.params, MAX_SLOTS * MAX_PARAMS * len),
        weight: grow(&mut rows.weight, MAX_SLOTS * 3 * len),
        probability: grow(&mut rows.probability, MAX_SLOTS * len),
        kept: [false; MAX_SLOTS],
        sample: None,
        albedo,
        evals: &mut evals,
        staged: None,
        out_of_range: false,
    };
    material.kind().expand_lanes(kernels, &mut job);
    rows.live = job.kept;
    Ok(())
}

/// What an eval asks of [`stage_chunk`]: each direction's `wi` staged (direction `d`
/// at `d len` of `s.wi`, its failed lanes at `d len` of `s.failed_directions`), and
/// with `in_pass` the values (when `want_value`) and pdfs of every direction, and the
/// albedos when asked, finished in the staging pass into `s.value`, `s.pdf` and
/// `s.albedo` (`kernels::expand::ExpandEval`) instead of the slots' rows written.
struct StageEval<'a, 'e> {
    /// Every direction's `wi`, `count` lanes a direction.
    wi: Soa3<'a>,
    count: usize,
    /// Each direction's errors of its `wi` (a lane's other errors go to `errors`).
    errors: &'e mut [LaneError],
    want_value: bool,
    in_pass: bool,
    albedo: bool,
}

/// Each lane's shading frame (from the staged normal and the caller's tangent, as
/// `Frame::new`) into the frame rows. Returns whether a tangent failed.
fn stage_frames(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    lanes: &[u32],
    len: usize,
    rows: &mut SlotRows,
    failed: &mut [u8],
    errors: &mut LaneError,
) -> bool {
    let mut any = false;
    let frame_rows = grow(&mut rows.frame, 9 * len);
    // Every lane's frame from its normal alone first (`Frame::new` without a tangent).
    material_rows::frames(kernels, view3(&rows.normal, len), frame_rows);
    // Then the lanes with a tangent (all-zero ones leave the choice to the library).
    if let Some(tangents) = &input.tangent {
        let (t, b) = frame_rows.split_at_mut(3 * len);
        let ([tx, ty, tz], [bx, by, bz]) = (split_rows(t, len), split_rows(b, len));
        let [sx, sy, sz] = view3(&rows.normal, len);
        for (j, &lane) in lanes.iter().enumerate() {
            let lane = lane as usize;
            let (x, y, z) = (tangents.x[lane], tangents.y[lane], tangents.z[lane]);
            if x == 0.0 && y == 0.0 && z == 0.0 {
                continue;
            }
            match Vec3::try_unit(x, y, z, "tangent") {
                Ok(tangent) => {
                    let f = Frame::new(Vec3::new(sx[j], sy[j], sz[j]), Some(tangent));
                    (tx[j], ty[j], tz[j]) = (f.t.x, f.t.y, f.t.z);
                    (bx[j], by[j], bz[j]) = (f.b.x, f.b.y, f.b.z);
                }
                Err(e) => {
                    failed[j] = 1;
                    any = true;
                    errors.fail(lane, e);
                }
            }
        }
    }
    any
}

/// The overrides into the block rows: each overridden value's row gathered and
/// range-checked row by row (lane by lane, for the error, only when a row fails), its
/// padding the material's value. Lanes that fail here or failed before get the
/// material's own values, a valid stand-in. The rows of values no override sets are
/// not written: every lane has the material's. Returns whether an override failed,
/// and which values have rows.
fn stage_blocks(
    input: &MaterialInput<'_>,
    lanes: &[u32],
    len: usize,
    rows: &mut SlotRows,
    failed: &mut [u8],
    errors: &mut LaneError,
) -> (bool, [bool; MAX_MATERIAL_PARAMS]) {
    let material = input.material;
    let (specs, defaults) = (material.kind().params(), material.params());
    let blocks = grow(&mut rows.input, defaults.len() * len);
    let n = lanes.len();
    let mut overridden = [false; MAX_MATERIAL_PARAMS];
    for o in input.overrides {
        let at = params::offset_of(specs, o.param as usize);
        overridden[at..at + o.kind.size()].fill(true);
    }
    for ((row, &v), &o) in blocks.chunks_exact_mut(len).zip(defaults).zip(&overridden) {
        if o {
            row[n..].fill(v);
        }
    }
    let mut any = false;
    for (i, o) in input.overrides.iter().enumerate() {
        let spec = &specs[o.param as usize];
        let at = params::offset_of(specs, o.param as usize);
        let size = o.kind.size();
        // Enums are checked lane by lane: a choice index must also be whole.
        let mut in_range = spec.kind != ParamKind::Enum;
        for c in 0..size {
            let row = &mut blocks[(at + c) * len..][..n];
            gather(row, o.value[c], lanes);
            in_range &= row.iter().fold(true, |ok, &v| ok & spec.in_range(v));
        }
        if in_range {
            continue;
        }
        for (j, &lane) in lanes.iter().enumerate() {
            let mut value = [0.0f32; 3];
            for (c, v) in value[..size].iter_mut().enumerate() {
                *v = blocks[(at + c) * len + j];
            }
            if let Err(e) = material.check_override_value(i, spec, &value[..size]) {
                failed[j] = 1;
                any = true;
                errors.fail(lane as usize, e);
            }
        }
    }
    // Failed lanes, here or before.
    if failed[..n].contains(&1) {
        for j in (0..n).filter(|&j| failed[j] != 0) {
            for (p, &v) in defaults.iter().enumerate().filter(|&(p, _)| overridden[p]) {
                blocks[p * len + j] = v;
            }
        }
    }
    (any, overridden)
}

/// `row[j] = src[lanes[j]]`.
fn gather(row: &mut [f32], src: &[f32], lanes: &[u32]) {
    match (lanes.first(), lanes.last()) {
        (Some(&a), Some(&b)) if (b - a) as usize + 1 == lanes.len() => {
            row.copy_from_slice(&src[a as usize..=b as usize]);
        }
        _ => {
            for (r, &lane) in row.iter_mut().zip(lanes) {
                *r = src[lane as usize];
            }
        }
    }
}

/// Each live slot's `weight * albedo(wo)` into the albedo rows.
fn slot_albedos(
    kernels: Kernels,
    material: &Material,
    len: usize,
    s: &mut Scratch,
    live: &[bool; MAX_SLOTS],
) {
    let rows = &mut s.material;
    // Out of the rows while the kernels read them, put back at the end.
    let mut albedo_rows = std::mem::take(&mut rows.albedo);
    let albedo = grow(&mut albedo_rows, MAX_SLOTS * 3 * len);
    // The albedo jobs read (and ignore) probability rows.
    grow(&mut rows.probability, MAX_SLOTS * len);
    for (k, (_, lobe)) in material.slots().iter().enumerate() {
        if !live[k] {
            continue;
        }
        let (r, gb) = albedo[k * 3 * len..(k + 1) * 3 * len].split_at_mut(len);
        let (g, b) = gb.split_at_mut(len);
        let mut job = AlbedoJob {
            len,
            mode: Transport::Radiance,
            directions: Directions::Unit,
            wo: view3(&s.wo, len),
            lobe: rows.lanes(k, lobe.decoded_len(), len),
            store: true,
            estimate: false,
            value: [r, g, b],
            out_of_range: false,
        };
        lobe.albedo_lanes(kernels, &mut job);
    }
    rows.albedo = albedo_rows;
}

/// The chunks of active lanes of `range`: `f(lanes)` for each.
fn for_chunks(
    input: &MaterialInput<'_>,
    range: Range<usize>,
    s: &mut Scratch,
    mut f: impl FnMut(&[u32], &mut Scratch) -> Result<(), Error>,
) -> Result<(), Error> {
    let mut lanes = std::mem::take(&mut s.chunk);
    let mut result = Ok(());
    let mut lane = range.start;
    while lane < range.end && result.is_ok() {
        lanes.clear();
        if input.active.is_none() {
            let end = range.end.min(lane + CHUNK);
            lanes.extend(lane as u32..end as u32);
            lane = end;
        }
        while lane < range.end && lanes.len() < CHUNK {
            if input.is_active(lane) {
                lanes.push(lane as u32);
            }
            lane += 1;
        }
        if !lanes.is_empty() {
            result = f(&lanes, s);
        }
    }
    s.chunk = lanes;
    result
}

/// Eval (with `want_value`), pdf and (with `want_reverse`) reverse pdf of every active
/// lane, slot by slot. `sampled`: `wi` is a sample's, returned as it is
/// (`Directions::Sampled`).
fn eval_chunk(
    kernels: Kernels,
    material: &Material,
    len: usize,
    s: &mut Scratch,
    sampled: bool,
    (want_value, want_reverse): (bool, bool),
) {
    let Scratch {
        material: rows,
        wo,
        wi,
        value,
        pdf,
        pdf_reverse,
        ..
    } = s;
    let ([vr, vg, vb], pdf, pdf_reverse) =
        (rows3(value, len), grow(pdf, len), grow(pdf_reverse, len));
    // The first live slot stores, the others add; without one, zeros.
    let mut first = true;
    for (k, (_, lobe)) in material.slots().iter().enumerate() {
        if !rows.live[k] {
            continue;
        }
        let mut job = EvalJob {
            len,
            mode: Transport::Radiance,
            directions: if sampled {
                Directions::Sampled
            } else {
                Directions::Unit
            },
            wo: view3(wo, len),
            wi: view3(wi, len),
            lobe: rows.lanes(k, lobe.lane_decoded_len(), len),
            store: first,
            value: want_value.then(|| [&mut vr[..len], &mut vg[..len], &mut vb[..len]]),
            pdf: &mut pdf[..len],
            out_of_range: false,
        };
        lobe.eval_lanes(kernels, &mut job);
        if want_reverse {
            super::eval_reverse(kernels, &**lobe, job, pdf_reverse);
        }
        first = false;
    }
    if first {
        for row in [vr, vg, vb, pdf, pdf_reverse] {
            row.fill(0.0);
        }
    }
}

/// A staged chunk's samples ([`stage_sample`]) in one kernel when the live slots'
/// lobes, in order, are one of the fused shapes (`kernels::fused::rows`): the rows
/// [`sample_slot_by_slot`] fills, the same bits. False, and nothing written, when they
/// are not.
fn sample_fused(kernels: Kernels, material: &Material, len: usize, s: &mut Scratch) -> bool {
    let Scratch {
        material: rows,
        wo,
        wi,
        u,
        value,
        pdf,
        sample_value,
        sample_pdf,
        eta,
        roughness,
        events,
        chosen,
        ..
    } = s;
    let empty = FusedRows {
        params: &[],
        param_count: 0,
        weight: &[],
        probability: &[],
    };
    let (mut models, mut slots, mut n) = ([None; MAX_FUSED], [empty; MAX_FUSED], 0);
    let mut labels = [0.0; MAX_FUSED];
    for (k, (_, lobe)) in material.slots().iter().enumerate() {
        if !rows.live[k] {
            continue;
        }
        if n == MAX_FUSED {
            return false;
        }
        models[n] = lobe.model();
        slots[n] = rows.slot(k, lobe.lane_decoded_len(), len);
        labels[n] = k as f32;
        n += 1;
    }
    let Some(kernel) = fused::for_rows(&models[..n]) else {
        return false;
    };
    let [sv_r, sv_g, sv_b] = sample_value;
    kernel(
        kernels,
        &mut FusedRowsJob {
            len,
            mode: Transport::Radiance,
            frame: &rows.frame[..9 * len],
            wo: view3(wo, len),
            u: view3(u, len),
            slots,
            labels,
            chosen: &chosen[..len],
            out: RowsSample {
                wi: rows3(wi, len),
                own_value: [grow(sv_r, len), grow(sv_g, len), grow(sv_b, len)],
                own_pdf: grow(sample_pdf, len),
                eta: grow(eta, len),
                roughness: grow(roughness, len),
                events: grow(events, len),
                value: rows3(value, len),
                pdf: grow(pdf, len),
            },
        },
    );
    true
}

/// `out[lane] = staged[j]`, 0 for failed lanes.
fn scatter(lanes: &[u32], base: usize, failed: &[u8], staged: &[f32], out: &mut [f32]) {
    let (n, first) = (lanes.len(), lanes[0] as usize - base);
    if lanes[n - 1] as usize - base - first + 1 != n {
        for (j, &lane) in lanes.iter().enumerate() {
            out[lane as usize - base] = if failed[j] != 0 { 0.0 } else { staged[j] };
        }
        return;
    }
    // Consecutive lanes: one copy, then the failed ones zeroed.
    let out = &mut out[first..first + n];
    out.copy_from_slice(&staged[..n]);
    if failed[..n].contains(&1) {
        for (o, _) in out.iter_mut().zip(&failed[..n]).filter(|&(_, &f)| f != 0) {
            *o = 0.0;
        }
    }
}

/// `eval` of the material at every active lane; `pdf_reverse` as `glint_eval_batch`.
pub fn eval(
    exec: &Exec<'_>,
    input: &MaterialInput<'_>,
    wi: Soa3<'_>,
    out: EvalOutput<'_>,
) -> Result<(), Error> {
    eval_directions(exec, input, wi, 1, out, None)
}

/// [`eval`] at `directions` directions per lane, each lane expanded once for all of
/// them (a scanline host's lights): `wi`'s and `out`'s rows hold `directions` blocks of
/// `count` values, direction `d` of lane `j` at `d * count + j`. With `albedo`, the
/// lanes' albedos ([`albedo`]) from the same expansion. Each lane and direction gets
/// what [`eval`] of that direction alone gives, to the bit; a lane with bad input
/// (its `wo`, normal or overrides) gets zeros in every direction, a bad `wi` in its
/// direction only. The error reported is the lowest failing lane's, in the first
/// direction it fails, named when there are several.
pub fn eval_directions(
    exec: &Exec<'_>,
    input: &MaterialInput<'_>,
    wi: Soa3<'_>,
    directions: usize,
    out: EvalOutput<'_>,
    albedo: Option<Soa3Mut<'_>>,
) -> Result<(), Error> {
    let n = input.count;
    input.check()?;
    let rows = direction_rows(directions, n)?;
    wi.check(rows, "wi")?;
    out.value.check(rows, "value")?;
    check_len(out.pdf.len(), rows, "pdf")?;
    if let Some(rev) = &out.pdf_reverse {
        check_len(rev.len(), rows, "pdf_reverse")?;
    }
    if let Some(a) = &albedo {
        a.check(n, "albedo")?;
    }
    if n == 0 {
        return Ok(());
    }
    let mut outputs = Vec::new();
    super::stage::reserve(&mut outputs, directions)?;
    let EvalOutput {
        value,
        pdf,
        pdf_reverse,
    } = out;
    let mut rev = pdf_reverse.map(|r| r[..rows].chunks_exact_mut(n));
    for (((x, y), z), pdf) in value.x[..rows]
        .chunks_exact_mut(n)
        .zip(value.y[..rows].chunks_exact_mut(n))
        .zip(value.z[..rows].chunks_exact_mut(n))
        .zip(pdf[..rows].chunks_exact_mut(n))
    {
        outputs.push(DirectionOutput {
            value: Some(Soa3Mut { x, y, z }),
            pdf,
            pdf_reverse: rev.as_mut().and_then(Iterator::next),
        });
    }
    let out = MaterialEvalOutput {
        directions: outputs,
        albedo,
    };
    run_blocks(exec, n, out, |start, mut out| {
        eval_block(exec.kernels, input, wi, start, &mut out)
    })
}

/// The rows of `directions` directions of `count` lanes: an error unless `directions`
/// is at least 1 and the product a batch's count ([`check_count`]).
pub fn direction_rows(directions: usize, count: usize) -> Result<usize, Error> {
    if directions == 0 {
        return Err(Error::new(
            Status::OutOfRange,
            "directions = 0: an eval takes at least one direction per lane",
        ));
    }
    let rows = directions.checked_mul(count).ok_or_else(|| {
        Error::new(
            Status::OutOfRange,
            format!("{directions} directions of {count} lanes overflow"),
        )
    })?;
    check_count(rows)?;
    Ok(rows)
}

/// `pdf` of the material at every active lane.
pub fn pdf(
    exec: &Exec<'_>,
    input: &MaterialInput<'_>,
    wi: Soa3<'_>,
    out: &mut [f32],
) -> Result<(), Error> {
    input.check()?;
    wi.check(input.count, "wi")?;
    check_len(out.len(), input.count, "pdf")?;
    let mut directions = Vec::new();
    super::stage::reserve(&mut directions, 1)?;
    directions.push(DirectionOutput {
        value: None,
        pdf: out,
        pdf_reverse: None,
    });
    let out = MaterialEvalOutput {
        directions,
        albedo: None,
    };
    run_blocks(exec, input.count, out, |start, mut out| {
        eval_block(exec.kernels, input, wi, start, &mut out)
    })
}

/// One direction's outputs of an eval.
struct DirectionOutput<'o> {
    value: Option<Soa3Mut<'o>>,
    pdf: &'o mut [f32],
    pdf_reverse: Option<&'o mut [f32]>,
}

impl SplitLanes for DirectionOutput<'_> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        let (value, value2) = self.value.split_lanes(lanes);
        let (pdf, pdf2) = self.pdf.split_lanes(lanes);
        let (rev, rev2) = self.pdf_reverse.split_lanes(lanes);
        (
            DirectionOutput {
                value,
                pdf,
                pdf_reverse: rev,
            },
            DirectionOutput {
                value: value2,
                pdf: pdf2,
                pdf_reverse: rev2,
            },
        )
    }
}

/// An eval's outputs: each direction's, and the albedos asked with them.
struct MaterialEvalOutput<'o> {
    directions: Vec<DirectionOutput<'o>>,
    albedo: Option<Soa3Mut<'o>>,
}

impl SplitLanes for MaterialEvalOutput<'_> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        // The upper halves' list: a few words a direction, against the caller's rows
        // of at least 16 bytes per lane and direction.
        let mut high = Vec::with_capacity(self.directions.len());
        let mut low = self.directions;
        for d in &mut low {
            let taken = std::mem::replace(
                d,
                DirectionOutput {
                    value: None,
                    pdf: &mut [],
                    pdf_reverse: None,
                },
            );
            let (l, h) = taken.split_lanes(lanes);
            *d = l;
            high.push(h);
        }
        let (albedo, albedo2) = self.albedo.split_lanes(lanes);
        (
            MaterialEvalOutput {
                directions: low,
                albedo,
            },
            MaterialEvalOutput {
                directions: high,
                albedo: albedo2,
            },
        )
    }
}

/// Direction `d`'s rows of `wi` (`count` lanes a direction).
fn direction(wi: Soa3<'_>, d: usize, count: usize) -> Soa3<'_> {
    let rows = d * count..(d + 1) * count;
    Soa3 {
        x: &wi.x[rows.clone()],
        y: &wi.y[rows.clone()],
        z: &wi.z[rows],
    }
}

fn eval_block(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    wi: Soa3<'_>,
    start: usize,
    out: &mut MaterialEvalOutput<'_>,
) -> Result<(), Error> {
    let end = (start + super::BLOCK).min(input.count);
    // The reverse pdf is taken slot by slot, over the slots' rows.
    let in_pass = out.directions.iter().all(|d| d.pdf_reverse.is_none());
    // Every lane active: the block in one expansion (per chunk, its setup took 4% of a
    // Disney material's eval); when some lane needs staging, the chunks below redo
    // the block.
    if in_pass && input.active.is_none() && eval_raw(kernels, input, wi, start..end, start, out)? {
        return Ok(());
    }
    let directions = out.directions.len();
    let mut failures = Vec::new();
    super::stage::reserve(&mut failures, directions)?;
    failures.resize_with(directions, LaneError::default);
    let mut lane_errors = LaneError::default();
    with_scratch(|s| {
        for_chunks(input, start..end, s, |lanes, s| {
            if in_pass
                && let Some(range) = consecutive(lanes)
                && eval_raw(kernels, input, wi, range, start, out)?
            {
                return Ok(());
            }
            let errors = (&mut lane_errors, &mut failures[..]);
            eval_staged(kernels, input, wi, lanes, start, s, errors, out)
        })
    })?;
    // The lowest failing lane; in a lane, its own inputs' error before its `wi`'s.
    let lane_level = lane_errors.lane().map(|lane| (lane, None));
    let first = failures
        .iter()
        .enumerate()
        .filter_map(|(d, f)| f.lane().map(|lane| (lane, Some(d))))
        .chain(lane_level)
        .min_by_key(|&(lane, d)| (lane, d.is_some()));
    let (d, error) = match first {
        None => return Ok(()),
        Some((_, None)) => (None, lane_errors.take()),
        Some((_, Some(d))) => (Some(d), failures[d].take()),
    };
    let e = error.expect("a failing lane has an error");
    // A `wi`'s error names its direction (when there are several); a lane's own
    // inputs' error belongs to every direction.
    Err(match d {
        Some(d) if directions > 1 => Error::new(e.status, format!("direction {d}, {}", e.message)),
        _ => e,
    })
}

/// A chunk's eval, staged: the lanes' inputs once and each direction's `wi`, every
/// direction's value and pdf and the albedos finished in the staging pass from one
/// expansion; with the reverse pdf, direction by direction, slot by slot over the
/// slots' rows. `errors`: the lanes' own, and each direction's `wi`'s.
#[allow(clippy::too_many_arguments)]
fn eval_staged(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    wi: Soa3<'_>,
    lanes: &[u32],
    start: usize,
    s: &mut Scratch,
    (errors, failures): (&mut LaneError, &mut [LaneError]),
    out: &mut MaterialEvalOutput<'_>,
) -> Result<(), Error> {
    let len = padded(lanes.len());
    let want_value = out.directions.iter().any(|d| d.value.is_some());
    if out.directions.iter().all(|d| d.pdf_reverse.is_none()) {
        let eval = StageEval {
            wi,
            count: input.count,
            errors: failures,
            want_value,
            in_pass: true,
            albedo: out.albedo.is_some(),
        };
        stage_chunk(kernels, input, lanes, len, s, errors, Some(eval))?;
        for (d, o) in out.directions.iter_mut().enumerate() {
            scatter_direction(lanes, start, s, d * len..(d + 1) * len, o);
        }
        if let Some(a) = out.albedo.as_mut() {
            for (staged, out) in s.albedo.iter().zip([&mut *a.x, &mut *a.y, &mut *a.z]) {
                scatter(lanes, start, &s.failed, staged, out);
            }
        }
        return Ok(());
    }
    for (d, (o, failure)) in out.directions.iter_mut().zip(failures).enumerate() {
        let eval = StageEval {
            wi: direction(wi, d, input.count),
            count: input.count,
            errors: std::slice::from_mut(failure),
            want_value,
            in_pass: false,
            albedo: false,
        };
        stage_chunk(kernels, input, lanes, len, s, errors, Some(eval))?;
        eval_chunk(kernels, input.material, len, s, false, (want_value, true));
        scatter_direction(lanes, start, s, 0..len, o);
    }
    if let Some(a) = out.albedo.as_mut() {
        albedo_chunk(kernels, input, lanes, start, s, errors, a)?;
    }
    Ok(())
}

/// One direction's staged outputs (at `rows` of the scratch rows) to the caller's,
/// zero where the lane or its `wi` failed.
fn scatter_direction(
    lanes: &[u32],
    start: usize,
    s: &Scratch,
    rows: Range<usize>,
    out: &mut DirectionOutput<'_>,
) {
    let failed = &s.failed_directions[rows.clone()];
    if let Some(v) = out.value.as_mut() {
        for (staged, out) in s.value.iter().zip([&mut *v.x, &mut *v.y, &mut *v.z]) {
            scatter(lanes, start, failed, &staged[rows.clone()], out);
        }
    }
    scatter(lanes, start, failed, &s.pdf[rows.clone()], out.pdf);
    if let Some(rev) = out.pdf_reverse.as_deref_mut() {
        scatter(lanes, start, failed, &s.pdf_reverse[rows], rev);
    }
}

/// The caller's lanes of a chunk of consecutive lanes, and each overridden value's
/// row in `overrides`, when the chunk can be taken from the caller's arrays as they
/// are ([`ExpandLanes::Raw`]): not with enum overrides (checked lane by lane) or a value
/// overridden twice.
fn raw_lanes<'a>(
    input: &MaterialInput<'a>,
    lanes: &[u32],
    overrides: &mut [Option<RawValue<'a>>],
) -> Option<Range<usize>> {
    raw_range(input, consecutive(lanes)?, overrides)
}

/// `lanes` as a range, when they are consecutive (and not empty).
fn consecutive(lanes: &[u32]) -> Option<Range<usize>> {
    let (first, last) = (*lanes.first()? as usize, *lanes.last()? as usize);
    (last - first + 1 == lanes.len()).then_some(first..last + 1)
}

/// [`raw_lanes`] of consecutive lanes `lanes`.
fn raw_range<'a>(
    input: &MaterialInput<'a>,
    lanes: Range<usize>,
    overrides: &mut [Option<RawValue<'a>>],
) -> Option<Range<usize>> {
    if input.overrides.iter().any(|o| o.kind == ParamKind::Enum) {
        return None;
    }
    let specs = input.material.kind().params();
    for o in input.overrides {
        let spec = &specs[o.param as usize];
        let at = params::offset_of(specs, o.param as usize);
        for (c, value) in overrides[at..at + o.kind.size()].iter_mut().enumerate() {
            // A value overridden twice: the staged path checks each override's range
            // (the last one's value is the lane's); a row here holds one range.
            if value.is_some() {
                return None;
            }
            *value = Some(RawValue {
                row: &o.value[c][lanes.clone()],
                min: spec.min,
                max: spec.max,
            });
        }
    }
    Some(lanes)
}

/// The caller's rows `v` at `lanes`.
fn caller_rows<'a>(v: Soa3<'a>, lanes: &Range<usize>) -> [&'a [f32]; 3] {
    [v.x, v.y, v.z].map(|row| &row[lanes.clone()])
}

/// [`ExpandLanes::Raw`] over the caller's `lanes` ([`raw_lanes`]).
fn raw_expand_lanes<'a>(
    input: &MaterialInput<'a>,
    lanes: &Range<usize>,
    overrides: &'a [Option<RawValue<'a>>],
) -> ExpandLanes<'a> {
    ExpandLanes::Raw {
        count: lanes.len(),
        overrides,
        normal: caller_rows(input.normal, lanes),
        tangent: input.tangent.map(|t| caller_rows(t, lanes)),
        wo: caller_rows(input.wo, lanes),
    }
}

/// The in-pass eval of a chunk of consecutive lanes from the caller's arrays straight
/// into the outputs ([`ExpandLanes::Raw`]), every direction (and the albedo when asked)
/// from one expansion: no copies, no rows. False, and the outputs of the chunk not
/// valid, when it cannot be taken so ([`raw_lanes`]) or some lane's input is outside
/// what the raw path takes; the chunk is then staged, which writes every lane and
/// reports each lane's error.
fn eval_raw(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    wi: Soa3<'_>,
    lanes: Range<usize>,
    start: usize,
    out: &mut MaterialEvalOutput<'_>,
) -> Result<bool, Error> {
    let material = input.material;
    let mut overrides = [None; MAX_MATERIAL_PARAMS];
    let overrides = &mut overrides[..material.params().len()];
    let Some(lanes) = raw_range(input, lanes, overrides) else {
        return Ok(false);
    };
    let at = lanes.start - start..lanes.end - start;
    let mut evals = Vec::new();
    super::stage::reserve(&mut evals, out.directions.len())?;
    for (d, o) in out.directions.iter_mut().enumerate() {
        let value = o.value.as_mut().map(|v| {
            [
                &mut v.x[at.clone()],
                &mut v.y[at.clone()],
                &mut v.z[at.clone()],
            ]
        });
        evals.push(ExpandEval {
            wi: caller_rows(direction(wi, d, input.count), &lanes),
            value,
            pdf: &mut o.pdf[at.clone()],
        });
    }
    let albedo = out
        .albedo
        .as_mut()
        .map(|a| [&mut *a.x, &mut *a.y, &mut *a.z].map(|row| &mut row[at.clone()]));
    let mut job = raw_pass_job(input, &lanes, overrides, (&mut evals, None, albedo));
    material.kind().expand_lanes(kernels, &mut job);
    Ok(!job.out_of_range)
}

/// What an expansion finishes in its pass: evals (and an albedo with them or alone)
/// or a sample.
type InPass<'a> = (
    &'a mut [ExpandEval<'a>],
    Option<ExpandSample<'a>>,
    Option<[&'a mut [f32]; 3]>,
);

/// An expansion of the caller's consecutive `lanes` ([`raw_expand_lanes`]) that
/// finishes an eval, a sample or an albedo in its pass, writing no rows.
fn raw_pass_job<'a>(
    input: &MaterialInput<'a>,
    lanes: &Range<usize>,
    overrides: &'a [Option<RawValue<'a>>],
    (evals, sample, albedo): InPass<'a>,
) -> ExpandJob<'a> {
    let material = input.material;
    ExpandJob {
        len: lanes.len(),
        lanes: raw_expand_lanes(input, lanes, overrides),
        material: material.params(),
        prune: material.prune(),
        known: material.decoded_defaults(),
        decoded: &mut [],
        weight: &mut [],
        probability: &mut [],
        kept: [false; MAX_SLOTS],
        evals,
        sample,
        albedo,
        staged: None,
        out_of_range: false,
    }
}

/// A chunk of consecutive lanes staged from the caller's arrays in the expansion's
/// pass ([`ExpandLanes::Raw`] writing [`StagedRows`]): the rows [`stage_chunk`] writes
/// for a sample or an albedo, without its copies and passes. False when the
/// chunk cannot be taken so ([`raw_lanes`]) or some lane's input is outside what the
/// raw path takes (`stage_chunk` then stages it, which reports each lane's error).
fn stage_raw(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    lanes: &[u32],
    len: usize,
    s: &mut Scratch,
) -> Result<bool, Error> {
    let material = input.material;
    let mut overrides = [None; MAX_MATERIAL_PARAMS];
    let overrides = &mut overrides[..material.params().len()];
    let Some(lanes) = raw_lanes(input, lanes, overrides) else {
        return Ok(false);
    };
    s.reserve_rows(len)?;
    super::stage::reserve(&mut s.failed, len)?;
    s.material.reserve(len, material.params().len())?;
    grow(&mut s.failed, len).fill(0);
    s.any_failed = false;
    let rows = &mut s.material;
    let mut job = ExpandJob {
        len,
        lanes: raw_expand_lanes(input, &lanes, overrides),
        material: material.params(),
        prune: material.prune(),
        known: material.decoded_defaults(),
        decoded: grow(&mut rows.params, MAX_SLOTS * MAX_PARAMS * len),
        weight: grow(&mut rows.weight, MAX_SLOTS * 3 * len),
        probability: grow(&mut rows.probability, MAX_SLOTS * len),
        kept: [false; MAX_SLOTS],
        sample: None,
        albedo: None,
        evals: &mut [],
        staged: Some(StagedRows {
            frame: grow(&mut rows.frame, 9 * len),
            wo: rows3(&mut s.wo, len),
        }),
        out_of_range: false,
    };
    material.kind().expand_lanes(kernels, &mut job);
    rows.live = job.kept;
    Ok(!job.out_of_range)
}

/// Directional albedo of the material at every active lane (what
/// `glint_albedo` of the lane's closure returns).
pub fn albedo(exec: &Exec<'_>, input: &MaterialInput<'_>, out: Soa3Mut<'_>) -> Result<(), Error> {
    input.check()?;
    out.check(input.count, "albedo")?;
    run_blocks(exec, input.count, out, |start, mut out| {
        let end = (start + super::BLOCK).min(input.count);
        // Every lane active: the block in one pass (`albedo_raw`); when some lane needs
        // staging, the chunks below redo the block.
        if input.active.is_none() && albedo_raw(exec.kernels, input, start..end, start, &mut out) {
            return Ok(());
        }
        let mut failure = LaneError::default();
        with_scratch(|s| {
            for_chunks(input, start..end, s, |lanes, s| {
                if let Some(range) = consecutive(lanes)
                    && albedo_raw(exec.kernels, input, range, start, &mut out)
                {
                    return Ok(());
                }
                albedo_chunk(exec.kernels, input, lanes, start, s, &mut failure, &mut out)
            })
        })?;
        failure.take().map_or(Ok(()), Err)
    })
}

/// The albedos of a chunk's lanes, staged: each kept slot's `weight * albedo` (a
/// dropped slot's weight is 0 on its lane; pruning weighed them by estimates) from
/// the slots' rows, summed in slot order.
fn albedo_chunk(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    lanes: &[u32],
    start: usize,
    s: &mut Scratch,
    failure: &mut LaneError,
    out: &mut Soa3Mut<'_>,
) -> Result<(), Error> {
    let len = padded(lanes.len());
    stage_chunk(kernels, input, lanes, len, s, failure, None)?;
    let live = s.material.live;
    slot_albedos(kernels, input.material, len, s, &live);
    let sum = rows3(&mut s.value, len);
    let rows = &s.material;
    for row in sum {
        row.fill(0.0);
    }
    for k in (0..input.material.slots().len()).filter(|&k| rows.live[k]) {
        let p = &rows.probability[k * len..][..len];
        for (c, sum) in s.value.iter_mut().enumerate() {
            let a = &rows.albedo[(3 * k + c) * len..][..len];
            // Zipped slices of one length: no bounds checks, so it vectorizes
            // (indexed, this loop was 23% of a Disney material's albedo).
            for ((sum, &a), &p) in sum[..len].iter_mut().zip(a).zip(p) {
                *sum += if p > 0.0 { a } else { 0.0 };
            }
        }
    }
    for (staged, out) in s.value.iter().zip([&mut *out.x, &mut *out.y, &mut *out.z]) {
        scatter(lanes, start, &s.failed, staged, out);
    }
    Ok(())
}

/// The albedos of consecutive lanes from the caller's arrays straight into the
/// outputs, in the expansion's pass ([`ExpandJob::albedo`]): no copies, no rows. False,
/// and the outputs of the lanes not valid, as [`sample_raw`].
fn albedo_raw(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    lanes: Range<usize>,
    start: usize,
    out: &mut Soa3Mut<'_>,
) -> bool {
    let mut overrides = [None; MAX_MATERIAL_PARAMS];
    let overrides = &mut overrides[..input.material.params().len()];
    let Some(lanes) = raw_range(input, lanes, overrides) else {
        return false;
    };
    let at = lanes.start - start..lanes.end - start;
    let rows = [&mut *out.x, &mut *out.y, &mut *out.z].map(|row| &mut row[at.clone()]);
    let mut job = raw_pass_job(input, &lanes, overrides, (&mut [], None, Some(rows)));
    input.material.kind().expand_lanes(kernels, &mut job);
    !job.out_of_range
}

/// Sample the material at every active lane: choose a slot with `u_lobe` (by the
/// lane's selection probabilities), sample it, add the other slots' evals there.
pub fn sample(
    exec: &Exec<'_>,
    input: &MaterialInput<'_>,
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
        let end = (start + super::BLOCK).min(n);
        // Every lane active: the block in one pass (`sample_raw`); when some lane needs
        // staging, the chunks below redo the block.
        if input.active.is_none()
            && sample_raw(exec.kernels, input, &u, start..end, start, &mut out)
        {
            return Ok(());
        }
        let mut failure = LaneError::default();
        with_scratch(|s| {
            for_chunks(input, start..end, s, |lanes, s| {
                if let Some(range) = consecutive(lanes)
                    && sample_raw(exec.kernels, input, &u, range, start, &mut out)
                {
                    return Ok(());
                }
                sample_chunk(
                    exec.kernels,
                    input,
                    &u,
                    lanes,
                    start,
                    s,
                    &mut failure,
                    &mut out,
                )
            })
        })?;
        failure.take().map_or(Ok(()), Err)
    })
}

/// The samples of consecutive lanes from the caller's arrays straight into the
/// outputs, in the expansion's pass (`kernels::expand::ExpandSample`): no copies, no
/// rows, no passes over them. False, and the outputs of the lanes not valid, when the
/// material's slots are not a fused shape, the lanes cannot be taken so
/// ([`raw_lanes`]) or some lane's input is outside what the raw path takes (a random
/// number not finite among them); the chunk is then staged, which writes every lane
/// and reports each lane's error.
fn sample_raw(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    u: &SampleRandoms<'_>,
    lanes: Range<usize>,
    start: usize,
    out: &mut SampleOutput<'_>,
) -> bool {
    let material = input.material;
    if !material.kind().samples_in_pass() {
        return false;
    }
    let mut overrides = [None; MAX_MATERIAL_PARAMS];
    let overrides = &mut overrides[..material.params().len()];
    let Some(lanes) = raw_range(input, lanes, overrides) else {
        return false;
    };
    let local = lanes.start - start..lanes.end - start;
    let sample = ExpandSample {
        u: [u.u_lobe, u.u0, u.u1].map(|row| &row[lanes.clone()]),
        out: out.finish_rows(&local),
    };
    let mut job = raw_pass_job(input, &lanes, overrides, (&mut [], Some(sample), None));
    material.kind().expand_lanes(kernels, &mut job);
    !job.out_of_range
}

/// Rows a material sample sorts: the frame, `wo` and `u` (shared by every slot's run),
/// the sampling slot's decoded block and weight, and the sample's outputs.
const SORTED_SHARED: usize = 15;
const SORTED_SLOT: usize = MAX_PARAMS + 3;
const SORTED_OUT: usize = 10;

/// Each slot's sample over the lanes that chose it: the rows sorted into runs by
/// chosen slot (`kernels::sort_rows`, as a closure batch's mixture sample), each
/// slot's sampler over its run, and the outputs (`wi`, value, pdf, eta, roughness,
/// events) back in lane order (`kernels::unsort_rows`); padding lanes repeat the last
/// lane's. The same per-lane operations as sampling every lane and keeping the chosen
/// ones, so the same bits, at a cost that follows the lanes each slot has.
fn sample_sorted(
    kernels: Kernels,
    slots: &[(u32, LobeRef)],
    rows: &mut SlotRows,
    chosen: &[f32],
    picks: &[usize; MAX_SLOTS],
    (wo, u): ([&[f32]; 3], [&[f32]; 3]),
    mut outputs: [&mut [f32]; SORTED_OUT],
) -> Result<(), Error> {
    let (count, n) = (slots.len(), chosen.len());
    let len = outputs[0].len();
    let mut starts = [0usize; MAX_SLOTS + 1];
    for k in 0..count {
        starts[k + 1] = starts[k] + picks[k].next_multiple_of(LANE_MULTIPLE);
    }
    // Whole registers are stored past each run's end.
    let stride = starts[count] + MAX_LANES;
    let sorted = &mut rows.sorted;
    super::stage::reserve(&mut sorted.shared, SORTED_SHARED * stride)?;
    super::stage::reserve(&mut sorted.slot, SORTED_SLOT * stride)?;
    super::stage::reserve(&mut sorted.out, SORTED_OUT * stride)?;
    // Out of the rows while the slots' rows are read, put back at the end.
    let mut taken = std::mem::take(sorted);
    let sorted = &mut taken;
    let mut src = [&[][..]; SORTED_SHARED];
    let frame = rows.frame[..9 * len].chunks_exact(len);
    for (s, row) in src.iter_mut().zip(frame.chain(wo).chain(u)) {
        *s = row;
    }
    let shared = grow(&mut sorted.shared, SORTED_SHARED * stride);
    let mut dst = split_rows::<SORTED_SHARED>(shared, stride);
    sort_rows(kernels, chosen, &starts[..=count], &src, &mut dst);
    grow(&mut sorted.slot, SORTED_SLOT * stride);
    grow(&mut sorted.out, SORTED_OUT * stride);
    let shared = &sorted.shared[..SORTED_SHARED * stride];
    for (k, (_, lobe)) in slots.iter().enumerate() {
        if picks[k] == 0 {
            continue;
        }
        let run = starts[k]..starts[k + 1];
        // The slot's block and weight into its run alone (every other run empty).
        let mut only = [run.end; MAX_SLOTS + 1];
        only[..=k].fill(run.start);
        let param_count = lobe.lane_decoded_len();
        let own = rows.slot(k, param_count, len);
        let mut src = [&[][..]; SORTED_SLOT];
        let own_rows = own
            .params
            .chunks_exact(len)
            .chain(own.weight.chunks_exact(len));
        for (s, row) in src.iter_mut().zip(own_rows) {
            *s = row;
        }
        let m = param_count + 3;
        let mut dst = split_rows::<SORTED_SLOT>(&mut sorted.slot, stride);
        sort_rows(kernels, chosen, &only[..=count], &src[..m], &mut dst[..m]);
        let slot_rows = &sorted.slot[..];
        let [x, y, z, r, g, b, pdf, eta, roughness, events] =
            split_rows::<SORTED_OUT>(&mut sorted.out, stride).map(|row| &mut row[run.clone()]);
        let mut job = SampleJob {
            len: run.len(),
            mode: Transport::Radiance,
            directions: Directions::Unit,
            wo: [9, 10, 11].map(|row| at(shared, row, stride, &run)),
            u: [12, 13, 14].map(|row| at(shared, row, stride, &run)),
            lobe: LobeLanes::PerLane {
                params: &slot_rows[run.start..],
                param_count,
                frame: &shared[run.start..],
                weight: &slot_rows[param_count * stride + run.start..],
                // Read only for a closure's only lobe: any row.
                probability: at(slot_rows, param_count, stride, &run),
                stride,
            },
            wi: [x, y, z],
            value: [r, g, b],
            pdf,
            eta,
            roughness,
            events: Some(events),
            closure: None,
            only: None,
            out_of_range: false,
        };
        lobe.sample_lanes(kernels, &mut job);
    }
    let mut src = [&[][..]; SORTED_OUT];
    for (s, row) in src.iter_mut().zip(sorted.out.chunks_exact(stride)) {
        *s = row;
    }
    let mut dst = outputs.each_mut().map(|row| &mut row[..n]);
    unsort_rows(kernels, chosen, &starts[..=count], &src, &mut dst);
    for row in &mut outputs {
        let last = row[n - 1];
        row[n..].fill(last);
    }
    rows.sorted = taken;
    Ok(())
}

/// Row `row` of sorted rows of `stride` values, over `run`.
fn at<'a>(rows: &'a [f32], row: usize, stride: usize, run: &Range<usize>) -> &'a [f32] {
    &rows[row * stride + run.start..][..run.len()]
}

/// `N` rows of `stride` values from the front of `v`.
fn split_rows<const N: usize>(v: &mut [f32], stride: usize) -> [&mut [f32]; N] {
    let mut rest = v;
    std::array::from_fn(|_| {
        let (row, tail) = std::mem::take(&mut rest).split_at_mut(stride);
        rest = tail;
        row
    })
}

/// Stage a sample's chunk (`stage_chunk`), its random numbers and each lane's chosen
/// slot.
fn stage_sample(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    u: &SampleRandoms<'_>,
    lanes: &[u32],
    len: usize,
    s: &mut Scratch,
    failure: &mut LaneError,
) -> Result<(), Error> {
    let n = lanes.len();
    stage_chunk(kernels, input, lanes, len, s, failure, None)?;
    let slots = input.material.slots();
    // The random numbers, padding lanes repeating the last lane's; then the lobe
    // choice, as `Closure::sample` makes it.
    let mut u_rows = rows3(&mut s.u, len);
    for (row, src) in u_rows.iter_mut().zip([u.u_lobe, u.u0, u.u1]) {
        gather(&mut row[..n], src, lanes);
    }
    // A lane with a non-finite one fails, as `Closure::sample` refuses it, and samples
    // with a valid stand-in (checked lane by lane only when a row has one; the rows
    // by a fold without early exit, which vectorizes).
    let finite = |row: &[f32]| row.iter().fold(true, |ok, v| ok & v.is_finite());
    if !u_rows.iter().all(|row| finite(&row[..n])) {
        for (j, &lane) in lanes.iter().enumerate() {
            let [a, b, c] = &mut u_rows;
            if let Err(e) = check_randoms([a[j], b[j], c[j]]) {
                (a[j], b[j], c[j]) = (0.5, 0.5, 0.5);
                s.failed[j] = 1;
                s.any_failed = true;
                failure.fail(lane as usize, e);
            }
        }
    }
    for row in &mut u_rows {
        let last = row[n - 1];
        row[n..].fill(last);
    }
    material_rows::choose(
        kernels,
        &mut ChooseJob {
            len,
            count: slots.len(),
            probability: &s.material.probability[..slots.len() * len],
            u: &mut s.u[0][..len],
            chosen: grow(&mut s.chosen, len),
        },
    );
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn sample_chunk(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    u: &SampleRandoms<'_>,
    lanes: &[u32],
    base: usize,
    s: &mut Scratch,
    failure: &mut LaneError,
    out: &mut SampleOutput<'_>,
) -> Result<(), Error> {
    let len = padded(lanes.len());
    let n = lanes.len();
    stage_sample(kernels, input, u, lanes, len, s, failure)?;
    if !sample_fused(kernels, input.material, len, s) {
        sample_slot_by_slot(kernels, input.material, len, n, s)?;
    }
    // `sample_pdf` holds `p_k pdf_k` now: the chosen slot's probability is 1 below.
    let first = lanes[0] as usize - base;
    if lanes[n - 1] as usize - lanes[0] as usize + 1 == n {
        finish_in_place(kernels, s, first..first + n, out);
        if s.any_failed {
            for (&lane, _) in lanes.iter().zip(&s.failed).filter(|&(_, &f)| f != 0) {
                out.write(lane as usize - base, &SampleResult::FAILED);
            }
        }
    } else {
        for (j, &lane) in lanes.iter().enumerate() {
            let r = if s.failed[j] != 0 {
                SampleResult::FAILED
            } else {
                finish_lane(s, j, s.chosen[j] as usize, 1.0, true)
            };
            out.write(lane as usize - base, &r);
        }
    }
    Ok(())
}

/// A chunk's samples when its slots are not a fused shape: each chosen slot samples
/// its own lanes, sorted into runs by slot ([`sample_sorted`]), and the mixture is
/// summed slot by slot.
fn sample_slot_by_slot(
    kernels: Kernels,
    material: &Material,
    len: usize,
    n: usize,
    s: &mut Scratch,
) -> Result<(), Error> {
    let slots = material.slots();
    let Scratch {
        material: rows,
        wo,
        wi,
        u: u_rows,
        sample_value,
        sample_pdf,
        eta,
        roughness,
        events,
        chosen,
        ..
    } = &mut *s;
    let chosen = &chosen[..len];
    // How many lanes chose each slot (a count per slot vectorizes; an increment per
    // lane is a chain through memory).
    let mut picks = [0usize; MAX_SLOTS];
    for (k, p) in picks[..slots.len()].iter_mut().enumerate() {
        let slot = k as f32;
        *p = chosen[..n]
            .iter()
            .fold(0, |c, &x| c + usize::from(x == slot));
    }
    // Each chosen slot samples its own lanes, sorted into runs by slot.
    let [sv_r, sv_g, sv_b] = sample_value;
    let [wi_x, wi_y, wi_z] = rows3(wi, len);
    let outputs = [
        wi_x,
        wi_y,
        wi_z,
        grow(sv_r, len),
        grow(sv_g, len),
        grow(sv_b, len),
        grow(sample_pdf, len),
        grow(eta, len),
        grow(roughness, len),
        grow(events, len),
    ];
    let inputs = (view3(wo, len), view3(u_rows, len));
    sample_sorted(kernels, slots, rows, &chosen[..n], &picks, inputs, outputs)?;
    material_rows::chosen_pdf(
        kernels,
        &rows.probability[..slots.len() * len],
        slots.len(),
        chosen,
        &mut sample_pdf[..len],
    );
    // The mixture: the material's eval at the sampled directions, summed in slot
    // order as `eval` sums it (the chosen slot's eval there is its sample's value and
    // pdf), so that a sample's value and pdf are the eval's at its `wi`, to the bit.
    eval_chunk(kernels, material, len, s, true, (true, false));
    Ok(())
}

/// The samples of a chunk of consecutive lanes finished in SIMD (`mixture::finish`)
/// straight into the caller's rows `local`.
fn finish_in_place(kernels: Kernels, s: &Scratch, local: Range<usize>, out: &mut SampleOutput<'_>) {
    let n = local.len();
    let mut job = FinishJob {
        len: n,
        lobe: FinishLobe::PerLane(&s.chosen[..n]),
        probability: 1.0,
        wi: view3(&s.wi, n),
        own_value: view3(&s.sample_value, n),
        own_pdf: &s.sample_pdf[..n],
        events: &s.events[..n],
        eta: &s.eta[..n],
        roughness: &s.roughness[..n],
        value: view3(&s.value, n),
        pdf: &s.pdf[..n],
        out: out.finish_rows(&local),
    };
    finish_mixture(kernels, &mut job);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::Registry;

    /// A small xorshift generator in [0, 1).
    fn randoms(seed: u32, n: usize) -> Vec<f32> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                (state >> 8) as f32 / (1u32 << 24) as f32
            })
            .collect()
    }

    /// Each set of slots the disney material emits: every lobe, no clearcoat (with
    /// [`TestLanes::overrides`] given `coat`, a clearcoat on some lanes only), no
    /// sheen, diffuse and specular, specular and clearcoat, the specular alone.
    const SHAPES: [&str; 6] = [
        r#"{"material": "disney", "sheen": 1, "clearcoat": 1, "subsurface": 0.5, "anisotropic": 0.4}"#,
        r#"{"material": "disney", "sheen": 0.7, "clearcoat": 0}"#,
        r#"{"material": "disney", "sheen": 0, "clearcoat": 0.8, "clearcoat_gloss": 0.3}"#,
        r#"{"material": "disney", "sheen": 0, "clearcoat": 0, "roughness": 0}"#,
        r#"{"material": "disney", "metallic": 1, "clearcoat": 1}"#,
        r#"{"material": "disney", "metallic": 1, "anisotropic": 0.5}"#,
    ];

    /// Per-lane inputs: unit views, normals and tangents on both hemispheres, random
    /// numbers, a roughness and a clearcoat on every third lane.
    struct TestLanes {
        wo: [Vec<f32>; 3],
        normal: [Vec<f32>; 3],
        tangent: [Vec<f32>; 3],
        u: [Vec<f32>; 3],
        roughness: Vec<f32>,
        coat: Vec<f32>,
    }

    impl TestLanes {
        fn new(seed: u32, n: usize) -> TestLanes {
            let unit = |k: u32| -> [Vec<f32>; 3] {
                let [x, y, z] = [0, 1, 2].map(|c| randoms(seed * 7 + k * 3 + c, n));
                let mut rows: [Vec<f32>; 3] = Default::default();
                for j in 0..n {
                    let d = Vec3::new(x[j] - 0.5, y[j] - 0.5, z[j] - 0.5).normalize();
                    for (row, c) in rows.iter_mut().zip([d.x, d.y, d.z]) {
                        row.push(c);
                    }
                }
                rows
            };
            TestLanes {
                wo: unit(1),
                normal: unit(2),
                tangent: unit(3),
                u: [0, 1, 2].map(|c| randoms(seed + 20 + c, n)),
                roughness: randoms(seed + 11, n),
                coat: (0..n).map(|j| (j % 3 / 2) as f32).collect(),
            }
        }

        /// The roughness override, and with `coat` the clearcoat one.
        fn overrides(&self, coat: bool) -> Vec<OverrideLanes<'_>> {
            let mut overrides = vec![OverrideLanes {
                param: 5,
                kind: ParamKind::Float,
                value: [&self.roughness, &[], &[]],
            }];
            if coat {
                overrides.push(OverrideLanes {
                    param: 9,
                    kind: ParamKind::Float,
                    value: [&self.coat, &[], &[]],
                });
            }
            overrides
        }

        /// A batch over every lane, with the tangents when `with_tangent`.
        fn input<'a>(
            &'a self,
            material: &'a Material,
            overrides: &'a [OverrideLanes<'a>],
            with_tangent: bool,
        ) -> MaterialInput<'a> {
            MaterialInput {
                count: self.u[0].len(),
                material,
                active: None,
                wo: soa(&self.wo),
                normal: soa(&self.normal),
                tangent: with_tangent.then(|| soa(&self.tangent)),
                overrides,
            }
        }

        fn randoms(&self) -> SampleRandoms<'_> {
            SampleRandoms {
                u_lobe: &self.u[0],
                u0: &self.u[1],
                u1: &self.u[2],
            }
        }
    }

    fn soa(r: &[Vec<f32>; 3]) -> Soa3<'_> {
        let [x, y, z] = r.each_ref().map(|v| &v[..]);
        Soa3 { x, y, z }
    }

    /// One path's outputs for [`in_pass_is_staged`]: whether it took the lanes, and
    /// every output row as bits.
    type Outputs = (bool, Vec<Vec<u32>>);

    /// For each of the [`SHAPES`] (per-lane roughness, normals and views on both
    /// hemispheres) and kernel set, `run(material, coat, kernels, lanes, in_pass)`
    /// gives the same bits in the expansion's pass as staged, with more than a quarter
    /// of the lanes above 0 in output row `lit`; with `spoil` applied to the lanes the
    /// pass does not take them and the staged path fails one.
    fn in_pass_is_staged(
        seed: u32,
        lit: usize,
        spoil: fn(&mut TestLanes),
        run: impl Fn(&Material, bool, Kernels, &TestLanes, bool) -> Outputs,
    ) {
        let registry = Registry::with_builtins();
        let n = 203;
        for (shape, description) in SHAPES.iter().enumerate() {
            let material = crate::json::material_from_json(&registry, description, 0.001).unwrap();
            let lanes = TestLanes::new(seed + shape as u32, n);
            let mut spoiled = TestLanes::new(seed + shape as u32, n);
            spoil(&mut spoiled);
            for kernels in Kernels::available() {
                let what = format!("{description} on {}", kernels.isa().name());
                let go = |lanes: &TestLanes, in_pass| {
                    run(&material, shape == 1, kernels, lanes, in_pass)
                };
                let (taken, in_pass) = go(&lanes, true);
                assert!(taken, "{what}");
                let (_, staged) = go(&lanes, false);
                for (k, (a, b)) in in_pass.iter().zip(&staged).enumerate() {
                    let lane = a.iter().zip(b).position(|(a, b)| a != b);
                    assert!(lane.is_none(), "output {k}, lane {lane:?}: {what}");
                }
                let above = in_pass[lit].iter().filter(|&&v| f32::from_bits(v) > 0.0);
                assert!(above.count() > n / 4, "{what}");
                assert!(!go(&spoiled, true).0, "{what}");
                assert!(!go(&spoiled, false).0, "{what}");
            }
        }
    }

    /// A sample in the expansion's pass (`sample_raw`) writes every output the staged
    /// path (`sample_chunk`: rows, the fused rows kernel, `finish_mixture`) writes,
    /// with the same bits ([`in_pass_is_staged`]); a lane with a random number not
    /// finite leaves the chunk to the staged path.
    #[test]
    fn samples_in_the_expansion_pass_are_the_staged_samples() {
        let spoil = |lanes: &mut TestLanes| lanes.u[1][17] = f32::NAN;
        in_pass_is_staged(
            0x5a3d,
            3,
            spoil,
            |material, coat, kernels, lanes, in_pass| {
                let overrides = lanes.overrides(coat);
                let input = lanes.input(material, &overrides, false);
                let n = input.count;
                let mut f = [0; 12].map(|_| vec![0.0f32; n]);
                let mut k = [0; 3].map(|_| vec![0u32; n]);
                let [wx, wy, wz, pdf, wr, wg, wb, vr, vg, vb, eta, rough] = &mut f;
                let [flags, lobe, component] = &mut k;
                let mut out = SampleOutput {
                    wi: Soa3Mut {
                        x: wx,
                        y: wy,
                        z: wz,
                    },
                    pdf,
                    weight: Soa3Mut {
                        x: wr,
                        y: wg,
                        z: wb,
                    },
                    value: Some(Soa3Mut {
                        x: vr,
                        y: vg,
                        z: vb,
                    }),
                    flags: Some(flags),
                    lobe: Some(lobe),
                    component: Some(component),
                    eta: Some(eta),
                    roughness: Some(rough),
                };
                let u = lanes.randoms();
                let taken = if in_pass {
                    sample_raw(kernels, &input, &u, 0..n, 0, &mut out)
                } else {
                    let (mut s, mut failure) = (Scratch::default(), LaneError::default());
                    let all: Vec<u32> = (0..n as u32).collect();
                    sample_chunk(kernels, &input, &u, &all, 0, &mut s, &mut failure, &mut out)
                        .unwrap();
                    failure.take().is_none()
                };
                let bits = |row: &Vec<f32>| row.iter().map(|v| v.to_bits()).collect();
                (taken, f.iter().map(bits).chain(k).collect())
            },
        );
    }

    /// An albedo in the expansion's pass (`albedo_raw`) is the staged path's
    /// (`albedo_chunk`: rows, each slot's albedo kernel, the sum), bit for bit
    /// ([`in_pass_is_staged`]); a lane with a NaN view leaves the chunk to the staged
    /// path.
    #[test]
    fn albedos_in_the_expansion_pass_are_the_staged_albedos() {
        let spoil = |lanes: &mut TestLanes| lanes.wo[0][30] = f32::NAN;
        in_pass_is_staged(
            0xa1be,
            0,
            spoil,
            |material, coat, kernels, lanes, in_pass| {
                let overrides = lanes.overrides(coat);
                let input = lanes.input(material, &overrides, false);
                let n = input.count;
                let mut rows = [0; 3].map(|_| vec![0.0f32; n]);
                let [x, y, z] = &mut rows;
                let mut out = Soa3Mut { x, y, z };
                let taken = if in_pass {
                    albedo_raw(kernels, &input, 0..n, 0, &mut out)
                } else {
                    let (mut s, mut failure) = (Scratch::default(), LaneError::default());
                    let all: Vec<u32> = (0..n as u32).collect();
                    albedo_chunk(kernels, &input, &all, 0, &mut s, &mut failure, &mut out).unwrap();
                    failure.take().is_none()
                };
                let bits = |row: &Vec<f32>| row.iter().map(|v| v.to_bits()).collect();
                (taken, rows.iter().map(bits).collect())
            },
        );
    }

    /// `sample_fused` fills every row `sample_slot_by_slot` fills with the same bits,
    /// for each of the [`SHAPES`] of two slots or more (one slot is no fused shape),
    /// per-lane roughness, frames and views on both hemispheres, on every kernel set.
    #[test]
    fn fused_samples_are_the_slot_by_slot_rows() {
        let registry = Registry::with_builtins();
        let n = 203;
        for (shape, description) in SHAPES[..5].iter().enumerate() {
            let material = crate::json::material_from_json(&registry, description, 0.001).unwrap();
            let lanes = TestLanes::new(0x5eed + shape as u32, n);
            let overrides = lanes.overrides(shape == 1);
            let input = lanes.input(&material, &overrides, true);
            let u = lanes.randoms();
            let all: Vec<u32> = (0..n as u32).collect();
            let len = padded(n);
            for kernels in Kernels::available() {
                let [mut fused, mut by_slot] = [Scratch::default(), Scratch::default()];
                for s in [&mut fused, &mut by_slot] {
                    s.reserve_rows(len).unwrap();
                    let mut failure = LaneError::default();
                    stage_sample(kernels, &input, &u, &all, len, s, &mut failure).unwrap();
                    assert!(failure.take().is_none());
                }
                assert!(sample_fused(kernels, &material, len, &mut fused));
                sample_slot_by_slot(kernels, &material, len, n, &mut by_slot).unwrap();
                let rows = |s: &Scratch| -> Vec<Vec<u32>> {
                    let [a, b, c] = &s.wi;
                    let [d, e, f] = &s.sample_value;
                    let [g, h, i] = &s.value;
                    [a, b, c, d, e, f, g, h, i]
                        .into_iter()
                        .chain([&s.sample_pdf, &s.eta, &s.roughness, &s.events, &s.pdf])
                        .map(|row| row[..n].iter().map(|v| v.to_bits()).collect())
                        .collect()
                };
                let what = format!("{description} on {}", kernels.isa().name());
                for (k, (a, b)) in rows(&fused).iter().zip(rows(&by_slot)).enumerate() {
                    let lane = a.iter().zip(&b).position(|(a, b)| a != b);
                    assert!(lane.is_none(), "row {k}, lane {lane:?}: {what}");
                }
                assert!(fused.pdf[..n].iter().filter(|&&p| p > 0.0).count() > n / 4);
            }
        }
    }
}
