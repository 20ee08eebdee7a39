//! Batches over one compiled material: per-lane shading contexts and overrides,
//! expanded and evaluated without building a closure per lane.
//!
//! A block is cut into chunks of [`CHUNK`] active lanes. Each chunk stages, per lane,
//! the unit `wo`, the shading frame and the parameter block with the lane's overrides,
//! expands it (`MaterialModel::expand`, the same code as `Material::build_closure`)
//! into per-slot SoA rows of decoded lobe blocks and weights, and runs each slot's
//! lobe kernels over the rows (`LobeLanes::PerLane`): first the albedo, whose
//! `luminance(weight * albedo)` prunes the slot per lane and sets the selection
//! probabilities by the closure's rule (`closure::selection`), then eval, pdf or
//! sample. A lane's result is that of the closure `glint_material_closure` builds for
//! it, up to the batch kernels' rounding; slots every lane pruned are skipped.

use super::stage::{Scratch, grow, padded, rows3, view3, with_scratch};
use super::{
    EvalOutput, Exec, SampleOutput, SampleRandoms, Soa3, Soa3Mut, SplitLanes, check_count,
    check_len, finish_lane, run_blocks,
};
use crate::closure::{MAX_LOBES, SampleResult, selection};
use crate::error::{Error, Status};
use crate::kernels::expand::ExpandJob;
use crate::kernels::{AlbedoJob, Directions, EvalJob, LobeLanes, SampleJob, mixture};
use crate::lobes::Transport;
use crate::materials::compiled::MAX_MATERIAL_PARAMS;
use crate::materials::{MAX_SLOT_PARAMS, MAX_SLOTS, Material};
use crate::math::{Frame, Rgb, Vec3};
use crate::params::{self, ParamKind};
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
    /// `wo` in each lane's shading frame.
    local_wo: [Vec<f32>; 3],
    /// The blocks `expand` writes: slot `k`'s value `p` of lane `j` at
    /// `(k * MAX_SLOT_PARAMS + p) * len + j`.
    raw: Vec<f32>,
    /// Decoded blocks: slot `k`'s value `p` of lane `j` at `(k * MAX_PARAMS + p) * len + j`.
    params: Vec<f32>,
    weight: Vec<f32>,
    probability: Vec<f32>,
    frame: Vec<f32>,
    /// Each slot's `luminance(weight * albedo(wo))`: slot `k`'s of lane `j` at `k * len + j`.
    shares: Vec<f32>,
    /// Whether any lane emits the slot.
    live: [bool; MAX_SLOTS],
}

/// Most decoded values a slot's lobe block holds in the rows.
const MAX_PARAMS: usize = crate::lobes::MAX_DECODED_LEN;

impl SlotRows {
    fn reserve(&mut self, len: usize, block_len: usize) -> Result<(), Error> {
        super::stage::reserve(&mut self.input, block_len * len)?;
        for row in &mut self.local_wo {
            super::stage::reserve(row, len)?;
        }
        super::stage::reserve(&mut self.raw, MAX_SLOTS * MAX_SLOT_PARAMS * len)?;
        super::stage::reserve(&mut self.params, MAX_SLOTS * MAX_PARAMS * len)?;
        super::stage::reserve(&mut self.weight, MAX_SLOTS * 3 * len)?;
        super::stage::reserve(&mut self.probability, MAX_SLOTS * len)?;
        super::stage::reserve(&mut self.shares, MAX_SLOTS * len)?;
        super::stage::reserve(&mut self.frame, 9 * len)
    }

    /// Slot `k`'s rows as the kernels read them.
    fn lanes(&self, k: usize, param_count: usize, len: usize) -> LobeLanes<'_> {
        let p = k * MAX_PARAMS * len;
        LobeLanes::PerLane {
            params: &self.params[p..p + param_count * len],
            param_count,
            frame: &self.frame[..9 * len],
            weight: &self.weight[k * 3 * len..(k + 1) * 3 * len],
            probability: &self.probability[k * len..(k + 1) * len],
            stride: len,
        }
    }
}

/// The first failing lane's error.
#[derive(Default)]
struct Failure(Option<(usize, Error)>);

impl Failure {
    fn fail(&mut self, lane: usize, e: Error) {
        if self.0.as_ref().is_none_or(|(l, _)| lane < *l) {
            self.0 = Some((lane, e));
        }
    }

    fn into_result(self) -> Result<(), Error> {
        self.0.map_or(Ok(()), |(lane, e)| {
            Err(Error::new(e.status, format!("lane {lane}: {}", e.message)))
        })
    }
}

/// Stage the chunk's lanes `lanes` (`len` padded): unit `wo` into `s.wo`, frames and
/// per-lane material blocks; then the expansion in SIMD, each slot's blocks decoded,
/// and each slot's albedo prunes it and sets the selection probabilities. Lanes with
/// invalid inputs are flagged in `s.failed`.
fn stage_chunk(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    lanes: &[u32],
    len: usize,
    s: &mut Scratch,
    failure: &mut Failure,
) -> Result<(), Error> {
    let material = input.material;
    let slots = material.slots();
    let block_len = material.params().len();
    s.reserve_rows(len)?;
    super::stage::reserve(&mut s.failed, len)?;
    s.material.reserve(len, block_len)?;
    let failed = grow(&mut s.failed, len);
    failed.fill(0);
    s.any_failed = false;
    let rows = &mut s.material;
    let blocks = grow(&mut rows.input, block_len * len);
    let frame_rows = grow(&mut rows.frame, 9 * len);
    let [wo_x, wo_y, wo_z] = rows3(&mut s.wo, len);
    let [lo_x, lo_y, lo_z] = rows3(&mut rows.local_wo, len);
    let n = lanes.len();
    let mut block = [0.0f32; MAX_MATERIAL_PARAMS];
    for j in 0..len {
        let lane = lanes[j.min(n - 1)] as usize;
        let (wo, frame) = lane_inputs(input, lane, &mut block[..block_len]).unwrap_or_else(|e| {
            if j < n {
                failed[j] = 1;
                s.any_failed = true;
                failure.fail(lane, e);
            }
            // A valid stand-in, so the kernels compute finite values it discards.
            block[..block_len].copy_from_slice(material.params());
            (Vec3::new(0.0, 0.0, 1.0), Frame::IDENTITY)
        });
        (wo_x[j], wo_y[j], wo_z[j]) = (wo.x, wo.y, wo.z);
        let local = frame.to_local(wo);
        (lo_x[j], lo_y[j], lo_z[j]) = (local.x, local.y, local.z);
        for (a, axis) in [frame.t, frame.b, frame.n].iter().enumerate() {
            frame_rows[3 * a * len + j] = axis.x;
            frame_rows[(3 * a + 1) * len + j] = axis.y;
            frame_rows[(3 * a + 2) * len + j] = axis.z;
        }
        for (p, &v) in block[..block_len].iter().enumerate() {
            blocks[p * len + j] = v;
        }
    }
    let mut block_lens = [0; MAX_SLOTS];
    for (b, (_, lobe)) in block_lens.iter_mut().zip(slots) {
        *b = params::block_size(lobe.params());
    }
    material.kind().expand_lanes(
        kernels,
        &mut ExpandJob {
            len,
            params: &rows.input[..block_len * len],
            param_count: block_len,
            wo: view3(&rows.local_wo, len),
            block_len: block_lens,
            weight: grow(&mut rows.weight, MAX_SLOTS * 3 * len),
            blocks: grow(&mut rows.raw, MAX_SLOTS * MAX_SLOT_PARAMS * len),
        },
    );
    let params = grow(&mut rows.params, MAX_SLOTS * MAX_PARAMS * len);
    let mut raw = [0.0f32; MAX_SLOT_PARAMS];
    let mut decoded = [0.0f32; MAX_PARAMS];
    for (k, (_, lobe)) in slots.iter().enumerate() {
        let (raw, decoded) = (
            &mut raw[..block_lens[k]],
            &mut decoded[..lobe.decoded_len()],
        );
        for j in 0..len {
            for (p, r) in raw.iter_mut().enumerate() {
                *r = rows.raw[(k * MAX_SLOT_PARAMS + p) * len + j];
            }
            lobe.decode(raw, decoded);
            for (p, &v) in decoded.iter().enumerate() {
                params[(k * MAX_PARAMS + p) * len + j] = v;
            }
        }
    }
    prune(kernels, input.material, len, s)
}

/// Lane `lane`'s unit `wo`, its frame, and into `block` the material's parameters
/// with the lane's overrides.
fn lane_inputs(
    input: &MaterialInput<'_>,
    lane: usize,
    block: &mut [f32],
) -> Result<(Vec3<f32>, Frame), Error> {
    let material = input.material;
    let kind = material.kind();
    let specs = kind.params();
    let wo = Vec3::try_unit(input.wo.x[lane], input.wo.y[lane], input.wo.z[lane], "wo")?;
    let normal = Vec3::try_unit(
        input.normal.x[lane],
        input.normal.y[lane],
        input.normal.z[lane],
        "normal",
    )?;
    let tangent = match &input.tangent {
        Some(t) if t.x[lane] != 0.0 || t.y[lane] != 0.0 || t.z[lane] != 0.0 => {
            Some(Vec3::try_unit(t.x[lane], t.y[lane], t.z[lane], "tangent")?)
        }
        _ => None,
    };
    block.copy_from_slice(material.params());
    for (i, o) in input.overrides.iter().enumerate() {
        let at = params::offset_of(specs, o.param as usize);
        let n = o.kind.size();
        for c in 0..n {
            block[at + c] = o.value[c][lane];
        }
        material.check_override_value(i, &specs[o.param as usize], &block[at..at + n])?;
    }
    Ok((wo, Frame::new(normal, tangent)))
}

/// Each slot's `weight * albedo(wo)` (into the probability rows' place: `s.value`),
/// then per lane the closure's pruning and selection rules.
fn prune(kernels: Kernels, material: &Material, len: usize, s: &mut Scratch) -> Result<(), Error> {
    let slots = material.slots();
    let rows = &mut s.material;
    // Out of the rows while the kernels read them, put back at the end.
    let mut share_rows = std::mem::take(&mut rows.shares);
    let shares = grow(&mut share_rows, slots.len() * len);
    grow(&mut rows.probability, MAX_SLOTS * len).fill(1.0);
    for (k, (_, lobe)) in slots.iter().enumerate() {
        let w = &rows.weight[k * 3 * len..(k + 1) * 3 * len];
        rows.live[k] = w.iter().any(|&w| w > 0.0);
        if !rows.live[k] {
            continue;
        }
        let [vr, vg, vb] = rows3(&mut s.value, len);
        let mut job = AlbedoJob {
            len,
            mode: Transport::Radiance,
            directions: Directions::Unit,
            wo: view3(&s.wo, len),
            lobe: rows.lanes(k, lobe.decoded_len(), len),
            store: true,
            value: [vr, vg, vb],
            out_of_range: false,
        };
        lobe.albedo_lanes(kernels, &mut job);
        for j in 0..len {
            let a = Rgb::new(s.value[0][j], s.value[1][j], s.value[2][j]);
            shares[k * len + j] = a.luminance();
        }
    }
    let prune = material.prune();
    let (weight, probability) = (&mut rows.weight, &mut rows.probability);
    for j in 0..len {
        let mut kept = [0usize; MAX_LOBES];
        let mut kept_shares = [0.0f32; MAX_LOBES];
        let mut n = 0;
        let mut strongest: Option<(f32, usize)> = None;
        for (k, live) in rows.live[..slots.len()].iter().enumerate() {
            let w = Rgb::new(
                weight[k * 3 * len + j],
                weight[(k * 3 + 1) * len + j],
                weight[(k * 3 + 2) * len + j],
            );
            if !live || !(w.r > 0.0 || w.g > 0.0 || w.b > 0.0) {
                continue;
            }
            let share = shares[k * len + j];
            if share < prune {
                if strongest.is_none_or(|(s, _)| share > s) {
                    strongest = Some((share, k));
                }
                continue;
            }
            (kept[n], kept_shares[n]) = (k, share);
            n += 1;
        }
        if let (0, Some((share, k))) = (n, strongest) {
            (kept[0], kept_shares[0]) = (k, share);
            n = 1;
        }
        let weight_of = |k: usize| {
            Rgb::new(
                weight[k * 3 * len + j],
                weight[(k * 3 + 1) * len + j],
                weight[(k * 3 + 2) * len + j],
            )
        };
        let p = selection(&kept_shares[..n], |i| weight_of(kept[i]).luminance());
        let mut is_kept = [false; MAX_SLOTS];
        for (i, &k) in kept[..n].iter().enumerate() {
            is_kept[k] = true;
            probability[k * len + j] = p[i];
        }
        for k in 0..slots.len() {
            if !is_kept[k] {
                probability[k * len + j] = 0.0;
                for c in 0..3 {
                    weight[(k * 3 + c) * len + j] = 0.0;
                }
            }
        }
    }
    for k in 0..slots.len() {
        rows.live[k] = rows.probability[k * len..(k + 1) * len]
            .iter()
            .any(|&p| p > 0.0);
    }
    rows.shares = share_rows;
    Ok(())
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

/// Eval (with `want_value`) or pdf of every active lane.
fn eval_chunk(
    kernels: Kernels,
    material: &Material,
    len: usize,
    s: &mut Scratch,
    want_value: bool,
    want_reverse: bool,
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
    for row in rows3(value, len) {
        row.fill(0.0);
    }
    grow(pdf, len).fill(0.0);
    grow(pdf_reverse, len).fill(0.0);
    for (k, (_, lobe)) in material.slots().iter().enumerate() {
        if !rows.live[k] {
            continue;
        }
        let [vr, vg, vb] = &mut *value;
        let mut job = EvalJob {
            len,
            mode: Transport::Radiance,
            directions: Directions::Unit,
            wo: view3(wo, len),
            wi: view3(wi, len),
            lobe: rows.lanes(k, lobe.lane_decoded_len(), len),
            store: false,
            value: want_value.then(|| [&mut vr[..len], &mut vg[..len], &mut vb[..len]]),
            pdf: &mut pdf[..len],
            except: None,
            out_of_range: false,
        };
        lobe.eval_lanes(kernels, &mut job);
        if want_reverse {
            let mut job = EvalJob {
                wo: view3(wi, len),
                wi: view3(wo, len),
                value: None,
                pdf: &mut pdf_reverse[..len],
                ..job
            };
            lobe.eval_lanes(kernels, &mut job);
        }
    }
}

/// Stage `wi` of `lanes` into `s.wi` (unit); invalid lanes are flagged.
fn stage_wi(wi: Soa3<'_>, lanes: &[u32], len: usize, s: &mut Scratch, failure: &mut Failure) {
    let n = lanes.len();
    let [x, y, z] = rows3(&mut s.wi, len);
    for j in 0..len {
        let lane = lanes[j.min(n - 1)] as usize;
        let v = Vec3::try_unit(wi.x[lane], wi.y[lane], wi.z[lane], "wi").unwrap_or_else(|e| {
            if j < n {
                s.failed[j] = 1;
                s.any_failed = true;
                failure.fail(lane, e);
            }
            Vec3::new(0.0, 0.0, 1.0)
        });
        (x[j], y[j], z[j]) = (v.x, v.y, v.z);
    }
}

/// `out[lane] = staged[j]`, 0 for failed lanes.
fn scatter(lanes: &[u32], base: usize, failed: &[u8], staged: &[f32], out: &mut [f32]) {
    for (j, &lane) in lanes.iter().enumerate() {
        out[lane as usize - base] = if failed[j] != 0 { 0.0 } else { staged[j] };
    }
}

/// `eval` of the material at every active lane; `pdf_reverse` as `glint_eval_batch`.
pub fn eval(
    exec: &Exec<'_>,
    input: &MaterialInput<'_>,
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
    let out = MaterialEvalOutput {
        value: Some(out.value),
        pdf: out.pdf,
        pdf_reverse: out.pdf_reverse,
    };
    run_blocks(exec, n, out, |start, mut out| {
        eval_block(exec.kernels, input, wi, start, &mut out)
    })
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
    let out = MaterialEvalOutput {
        value: None,
        pdf: out,
        pdf_reverse: None,
    };
    run_blocks(exec, input.count, out, |start, mut out| {
        eval_block(exec.kernels, input, wi, start, &mut out)
    })
}

struct MaterialEvalOutput<'o> {
    value: Option<Soa3Mut<'o>>,
    pdf: &'o mut [f32],
    pdf_reverse: Option<&'o mut [f32]>,
}

impl SplitLanes for MaterialEvalOutput<'_> {
    fn split_lanes(self, lanes: usize) -> (Self, Self) {
        let (value, value2) = self.value.split_lanes(lanes);
        let (pdf, pdf2) = self.pdf.split_lanes(lanes);
        let (rev, rev2) = self.pdf_reverse.split_lanes(lanes);
        (
            MaterialEvalOutput {
                value,
                pdf,
                pdf_reverse: rev,
            },
            MaterialEvalOutput {
                value: value2,
                pdf: pdf2,
                pdf_reverse: rev2,
            },
        )
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
    let mut failure = Failure::default();
    with_scratch(|s| {
        for_chunks(input, start..end, s, |lanes, s| {
            let len = padded(lanes.len());
            stage_chunk(kernels, input, lanes, len, s, &mut failure)?;
            stage_wi(wi, lanes, len, s, &mut failure);
            let want_reverse = out.pdf_reverse.is_some();
            eval_chunk(
                kernels,
                input.material,
                len,
                s,
                out.value.is_some(),
                want_reverse,
            );
            if let Some(v) = out.value.as_mut() {
                for (staged, out) in s.value.iter().zip([&mut *v.x, &mut *v.y, &mut *v.z]) {
                    scatter(lanes, start, &s.failed, staged, out);
                }
            }
            scatter(lanes, start, &s.failed, &s.pdf, out.pdf);
            if let Some(rev) = out.pdf_reverse.as_deref_mut() {
                scatter(lanes, start, &s.failed, &s.pdf_reverse, rev);
            }
            Ok(())
        })
    })?;
    failure.into_result()
}

/// Directional albedo of the material at every active lane (what
/// `glint_albedo` of the lane's closure returns).
pub fn albedo(exec: &Exec<'_>, input: &MaterialInput<'_>, out: Soa3Mut<'_>) -> Result<(), Error> {
    input.check()?;
    out.check(input.count, "albedo")?;
    run_blocks(exec, input.count, out, |start, out| {
        let end = (start + super::BLOCK).min(input.count);
        let mut failure = Failure::default();
        with_scratch(|s| {
            for_chunks(input, start..end, s, |lanes, s| {
                let len = padded(lanes.len());
                stage_chunk(exec.kernels, input, lanes, len, s, &mut failure)?;
                let mut sum = [vec![0.0f32; len], vec![0.0f32; len], vec![0.0f32; len]];
                for (k, (_, lobe)) in input.material.slots().iter().enumerate() {
                    if !s.material.live[k] {
                        continue;
                    }
                    let [vr, vg, vb] = rows3(&mut s.value, len);
                    let mut job = AlbedoJob {
                        len,
                        mode: Transport::Radiance,
                        directions: Directions::Unit,
                        wo: view3(&s.wo, len),
                        lobe: s.material.lanes(k, lobe.decoded_len(), len),
                        store: true,
                        value: [vr, vg, vb],
                        out_of_range: false,
                    };
                    lobe.albedo_lanes(exec.kernels, &mut job);
                    for (sum, v) in sum.iter_mut().zip(&s.value) {
                        for (a, b) in sum.iter_mut().zip(v) {
                            *a += b;
                        }
                    }
                }
                for (staged, out) in sum.iter().zip([&mut *out.x, &mut *out.y, &mut *out.z]) {
                    scatter(lanes, start, &s.failed, staged, out);
                }
                Ok(())
            })
        })?;
        failure.into_result()
    })
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
        let mut failure = Failure::default();
        with_scratch(|s| {
            for_chunks(input, start..end, s, |lanes, s| {
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
        failure.into_result()
    })
}

#[allow(clippy::too_many_arguments)]
fn sample_chunk(
    kernels: Kernels,
    input: &MaterialInput<'_>,
    u: &SampleRandoms<'_>,
    lanes: &[u32],
    base: usize,
    s: &mut Scratch,
    failure: &mut Failure,
    out: &mut SampleOutput<'_>,
) -> Result<(), Error> {
    let len = padded(lanes.len());
    let n = lanes.len();
    stage_chunk(kernels, input, lanes, len, s, failure)?;
    let slots = input.material.slots();
    // The lobe choice, as `Closure::sample` makes it.
    let chosen = grow(&mut s.chosen, len);
    let [uc, u0, u1] = rows3(&mut s.u, len);
    let mut probabilities = [0.0f32; MAX_SLOTS];
    for j in 0..len {
        let lane = lanes[j.min(n - 1)] as usize;
        for (k, p) in probabilities[..slots.len()].iter_mut().enumerate() {
            *p = s.material.probability[k * len + j];
        }
        let (k, reused) =
            mixture::choose(&probabilities[..slots.len()], u.u_lobe[lane]).unwrap_or((0.0, 0.5));
        (chosen[j], uc[j], u0[j], u1[j]) = (k, reused, u.u0[lane], u.u1[lane]);
    }
    let mut any = [false; MAX_SLOTS];
    for &k in &chosen[..n] {
        any[k as usize] = true;
    }
    let Scratch {
        material: rows,
        wo,
        wi,
        u: u_rows,
        value,
        pdf,
        sample_value,
        sample_pdf,
        eta,
        roughness,
        events,
        chosen,
        ..
    } = &mut *s;
    let [sv_r, sv_g, sv_b] = sample_value;
    let (sv_r, sv_g, sv_b) = (grow(sv_r, len), grow(sv_g, len), grow(sv_b, len));
    for (k, (_, lobe)) in slots.iter().enumerate() {
        if !any[k] {
            continue;
        }
        let mut job = SampleJob {
            len,
            mode: Transport::Radiance,
            directions: Directions::Unit,
            wo: view3(wo, len),
            u: view3(u_rows, len),
            lobe: rows.lanes(k, lobe.lane_decoded_len(), len),
            wi: rows3(wi, len),
            value: [&mut sv_r[..], &mut sv_g[..], &mut sv_b[..]],
            pdf: grow(sample_pdf, len),
            eta: grow(eta, len),
            roughness: grow(roughness, len),
            events: Some(grow(events, len)),
            closure: None,
            only: Some((&chosen[..len], k as f32)),
            out_of_range: false,
        };
        lobe.sample_lanes(kernels, &mut job);
    }
    // The chosen slot's own value and `p_k` times its pdf, then the other slots'
    // evals at the sampled direction.
    let [vr, vg, vb] = rows3(value, len);
    let pdf = grow(pdf, len);
    for j in 0..len {
        let k = chosen[j] as usize;
        (vr[j], vg[j], vb[j]) = (sv_r[j], sv_g[j], sv_b[j]);
        pdf[j] = rows.probability[k * len + j] * sample_pdf[j];
    }
    for (k, (_, lobe)) in slots.iter().enumerate() {
        if !rows.live[k] || chosen[..n].iter().all(|&c| c as usize == k) {
            continue;
        }
        let [vr, vg, vb] = &mut *value;
        let mut job = EvalJob {
            len,
            mode: Transport::Radiance,
            directions: Directions::Sampled,
            wo: view3(wo, len),
            wi: view3(wi, len),
            lobe: rows.lanes(k, lobe.lane_decoded_len(), len),
            store: false,
            value: Some([&mut vr[..len], &mut vg[..len], &mut vb[..len]]),
            pdf: &mut pdf[..len],
            except: Some((&chosen[..len], k as f32)),
            out_of_range: false,
        };
        lobe.eval_lanes(kernels, &mut job);
    }
    for (j, &lane) in lanes.iter().enumerate() {
        let at = lane as usize - base;
        let k = s.chosen[j] as usize;
        let r = if s.failed[j] != 0 {
            SampleResult::FAILED
        } else {
            let p = s.material.probability[k * len + j];
            finish_lane(s, j, k, p, true, slots[k].1.flags())
        };
        out.write(at, &r);
    }
    Ok(())
}
