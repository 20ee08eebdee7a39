//! Compiled materials: a material type, a validated parameter block and the slots'
//! lobe types, resolved once per scene material; per shading point, overrides,
//! expansion, pruning and the closure.

use super::{
    Expansion, MAX_SLOT_PARAMS, MAX_SLOTS, MaterialModel, MaterialType, ShadingContext, SlotModels,
    SlotVisitor,
};
use crate::closure::{Closure, MAX_LOBES};
use crate::error::{Error, Status};
use crate::lobes::{MAX_DECODED_LEN, Model, Params, Transport};
use crate::math::{Frame, Rgb, Vec3};
use crate::params::{self, ParamKind, ParamSpec};
use crate::registry::{LobeRef, Registry};

/// Most parameter values a material type's block may hold.
pub const MAX_MATERIAL_PARAMS: usize = 64;

/// A textured parameter for one shading point: parameter `param` (its index in the
/// schema) set to `value` (one value for `float` and `enum`, three for `rgb`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Override {
    pub param: u32,
    /// The kind the caller means; a mismatch with the schema is an error.
    pub kind: ParamKind,
    pub value: [f32; 3],
}

/// A material ready to shade: validated and resolved once.
#[derive(Clone)]
pub struct Material {
    kind: &'static dyn MaterialType,
    type_id: u32,
    /// The validated block, zero-padded: a point's copy is one fixed-size move.
    params: [f32; MAX_MATERIAL_PARAMS],
    param_count: usize,
    /// Each schema entry's value (element 0), resolved here so that per-point overrides
    /// by entry index skip `params::locate`; None for group and table headers.
    entries: Box<[Option<params::Slot<'static>>]>,
    /// Each slot's lobe type id and type.
    slots: Vec<(u32, LobeRef)>,
    /// Each slot's raw block length.
    block_lens: [usize; MAX_SLOTS],
    /// The slots whose decode is more than a copy, with the raw block the material's
    /// own parameters expand to (at normal incidence) and its decoded block: a point
    /// whose slot block equals it (its overrides leave the slot alone) copies the
    /// decoded block instead of decoding again (the clearcoat's takes logarithms).
    decoded_defaults: Vec<Option<DecodedBlock>>,
    /// The shape id of a closure of this material alone, by the set of emitted slots
    /// (bit `k` for slot `k`); empty when a slot's type has enumerated parameters,
    /// whose choices are part of the shape.
    shape_ids: Box<[u64]>,
    prune: f32,
}

impl Material {
    /// Compile material type `type_id` of `registry` with `params` (a full block laid
    /// out by its schema, or `None` for the defaults); lobes whose
    /// `luminance(weight * albedo(wo))` is below `prune` are not emitted.
    pub fn new(
        registry: &Registry,
        type_id: u32,
        params: Option<&[f32]>,
        prune: f32,
    ) -> Result<Material, Error> {
        let kind = registry.material(type_id)?;
        let specs = kind.params();
        if params::block_size(specs) > MAX_MATERIAL_PARAMS {
            return Err(Error::new(
                Status::Unsupported,
                format!(
                    "material {}: more than {MAX_MATERIAL_PARAMS} parameter values",
                    kind.name()
                ),
            ));
        }
        let param_count = params::block_size(specs);
        let mut padded = [0.0; MAX_MATERIAL_PARAMS];
        let block = &mut padded[..param_count];
        match params {
            Some(values) => {
                params::validate(kind.name(), specs, values)?;
                block.copy_from_slice(values);
            }
            None => params::write_defaults(specs, block),
        }
        let slots = kind
            .lobes()
            .iter()
            .map(|name| {
                let id = registry.find(name)?;
                let lobe = registry.get(id)?.clone();
                if params::block_size(lobe.params()) > MAX_SLOT_PARAMS
                    || lobe.decoded_len() > MAX_DECODED_LEN
                {
                    return Err(Error::new(
                        Status::Unsupported,
                        format!(
                            "material {}: lobe type {name} has more than {MAX_SLOT_PARAMS} parameter values \
                             or {MAX_DECODED_LEN} decoded values",
                            kind.name()
                        ),
                    ));
                }
                Ok((id, lobe))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        // `emit` calls the slots' models directly: the registered types must be them.
        let models = kind.slot_models();
        if let Some(k) = (0..slots.len()).find(|&k| slots[k].1.model() != Some(models[k])) {
            return Err(Error::new(
                Status::Unsupported,
                format!(
                    "material {}: slot {k}'s lobe type {} is not the built-in model the material was built with",
                    kind.name(),
                    slots[k].1.name()
                ),
            ));
        }
        let entries = (0..specs.len() as u32)
            .map(|i| params::locate(kind.name(), kind.params(), i, &"").ok())
            .collect();
        let mut block_lens = [0; MAX_SLOTS];
        for (len, (_, lobe)) in block_lens.iter_mut().zip(&slots) {
            *len = params::block_size(lobe.params());
        }
        let shape_ids = shape_ids(&slots)?;
        let decoded_defaults = decoded_defaults(kind, block, &slots, &block_lens);
        Ok(Material {
            kind,
            type_id,
            params: padded,
            param_count,
            entries,
            slots,
            block_lens,
            decoded_defaults,
            shape_ids,
            prune,
        })
    }

    pub fn kind(&self) -> &'static dyn MaterialType {
        self.kind
    }

    pub fn type_id(&self) -> u32 {
        self.type_id
    }

    /// The compiled parameter block (overrides are applied to a copy per point).
    pub fn params(&self) -> &[f32] {
        &self.params[..self.param_count]
    }

    /// The compiled block followed by zeros: a point's copy to apply overrides to.
    pub fn padded_params(&self) -> [f32; MAX_MATERIAL_PARAMS] {
        self.params
    }

    /// [`Material::decoded_defaults`] of each slot.
    pub(crate) fn decoded_defaults(&self) -> &[Option<DecodedBlock>] {
        &self.decoded_defaults
    }

    /// The pruning threshold.
    pub fn prune(&self) -> f32 {
        self.prune
    }

    /// The lobe type id and type of each slot.
    pub fn slots(&self) -> &[(u32, LobeRef)] {
        &self.slots
    }

    /// The compiled block with `overrides` applied, into `out` (which holds
    /// `self.params().len()` values). An override's `param` is an address
    /// ([`params::address`]: an entry, or an element of an array or table column).
    /// Errors name the override and the parameter's path.
    pub fn apply(&self, overrides: &[Override], out: &mut [f32]) -> Result<(), Error> {
        out.copy_from_slice(self.params());
        for (i, o) in overrides.iter().enumerate() {
            self.apply_one(i, o, out)?;
        }
        Ok(())
    }

    /// Override `i` applied to `out`, a block [`Self::apply`] started. (Inlined: it
    /// runs per override per shading point; the checked path with its messages is not.)
    #[inline(always)]
    pub fn apply_one(&self, i: usize, o: &Override, out: &mut [f32]) -> Result<(), Error> {
        // A float or rgb entry set in range (NaN is not): the common case, in place.
        if let Some(Some(slot)) = self.entries.get(o.param as usize) {
            let spec = slot.spec;
            match (spec.kind, o.kind) {
                (ParamKind::Float, ParamKind::Float) if spec.in_range(o.value[0]) => {
                    out[slot.offset] = o.value[0];
                    return Ok(());
                }
                (ParamKind::Rgb, ParamKind::Rgb) if o.value.iter().all(|&v| spec.in_range(v)) => {
                    out[slot.offset..slot.offset + 3].copy_from_slice(&o.value);
                    return Ok(());
                }
                _ => {}
            }
        }
        self.apply_checked(i, o, out)
    }

    /// [`Self::apply_one`] with every check and its message.
    #[cold]
    #[inline(never)]
    fn apply_checked(&self, i: usize, o: &Override, out: &mut [f32]) -> Result<(), Error> {
        let slot = self.override_slot(i, o.param, o.kind)?;
        let value = &o.value[..o.kind.size()];
        self.check_element(i, slot.spec, value, slot.element)?;
        out[slot.offset..slot.offset + value.len()].copy_from_slice(value);
        Ok(())
    }

    /// The values of override `i` for `spec` are in its range (the error names the
    /// override).
    pub fn check_override_value(
        &self,
        i: usize,
        spec: &ParamSpec,
        value: &[f32],
    ) -> Result<(), Error> {
        self.check_element(i, spec, value, 0)
    }

    fn check_element(
        &self,
        i: usize,
        spec: &ParamSpec,
        value: &[f32],
        element: usize,
    ) -> Result<(), Error> {
        params::check_values(self.kind.name(), spec, value, element)
            .map_err(|e| Error::new(e.status, format!("overrides[{i}]: {}", e.message)))
    }

    /// The value override `i`, of address `param` as a `kind`, sets (errors: unknown
    /// index or element, a group or table header, wrong kind).
    pub fn override_slot(
        &self,
        i: usize,
        param: u32,
        kind: ParamKind,
    ) -> Result<params::Slot<'_>, Error> {
        let what = format_args!("overrides[{i}]");
        let slot = match self.entries.get(param as usize) {
            Some(Some(slot)) => *slot,
            _ => params::locate(self.kind.name(), self.kind.params(), param, &what)?,
        };
        if slot.spec.kind != kind {
            return Err(Error::new(
                Status::InvalidArgument,
                format!(
                    "{what}: {}.{} is {}, not {}",
                    self.kind.name(),
                    slot.spec.name,
                    kind_name(slot.spec.kind),
                    kind_name(kind)
                ),
            ));
        }
        Ok(slot)
    }

    /// The schema entry override `i`, of parameter `param` as a `kind`, sets, for the
    /// material batches, which override single values only (by entry index, so
    /// inside groups too): arrays and table cells are an `Unsupported` error there.
    pub fn override_spec(
        &self,
        i: usize,
        param: u32,
        kind: ParamKind,
    ) -> Result<&ParamSpec, Error> {
        let slot = self.override_slot(i, param, kind)?;
        if slot.spec.repeated() {
            return Err(Error::new(
                Status::Unsupported,
                format!(
                    "overrides[{i}]: {}.{} is an array or table column; material batches \
                     override single values only",
                    self.kind.name(),
                    slot.spec.name
                ),
            ));
        }
        Ok(slot.spec)
    }

    /// Build (and finish) the closure of one shading point into `closure`, which is
    /// restarted: expansion, pruning, selection probabilities.
    pub fn build_closure(
        &self,
        closure: &mut Closure,
        ctx: &ShadingContext,
        overrides: &[Override],
    ) -> Result<(), Error> {
        let mut block = [0.0f32; MAX_MATERIAL_PARAMS];
        let block = &mut block[..self.param_count];
        self.apply(overrides, block)?;
        self.build_closure_from(closure, ctx, block)
    }

    /// [`Self::build_closure`] from a block [`Self::apply`] wrote: fails only when
    /// memory is short.
    pub fn build_closure_from(
        &self,
        closure: &mut Closure,
        ctx: &ShadingContext,
        block: &[f32],
    ) -> Result<(), Error> {
        closure.restart(Some(ctx.wo), Transport::Radiance);
        let mut shares = [0.0; MAX_LOBES];
        let slots = self.emit(closure, ctx, block, Rgb::new(1.0, 1.0, 1.0), &mut shares)?;
        let kept = slots.count_ones() as usize;
        let shape_id = self.shape_ids.get(slots as usize).copied();
        closure.finish_with_shares(&mut shares[..kept], shape_id)
    }

    /// Add the lobes of one shading point (`block`: the parameters with its overrides
    /// applied) to the open `closure`, their weights scaled by `scale`: expansion, then
    /// pruning. Returns the emitted slots (bit `k` for slot `k`; at least one: when
    /// every lobe is below the threshold, the strongest is kept) and writes each added
    /// lobe's `luminance(weight * albedo estimate(wo))`, in order, to `shares`, as
    /// `Closure::finish` would compute it. (An out parameter: the emitter's scalar
    /// stores read back as a returned array stalled store forwarding.)
    pub(crate) fn emit(
        &self,
        closure: &mut Closure,
        ctx: &ShadingContext,
        block: &[f32],
        scale: Rgb<f32>,
        shares: &mut [f32; MAX_LOBES],
    ) -> Result<u32, Error> {
        self.kind.emit(self, closure, ctx, block, scale, shares)
    }

    /// The closure of one shading point, as a new value.
    pub fn closure(&self, ctx: &ShadingContext, overrides: &[Override]) -> Result<Closure, Error> {
        let mut closure = Closure::new(Some(ctx.wo), Transport::Radiance);
        self.build_closure(&mut closure, ctx, overrides)?;
        Ok(closure)
    }
}

/// [`Material::emit`] for material model `M` (whose slots `material` holds).
#[inline(always)]
pub(crate) fn emit<M: MaterialModel>(
    material: &Material,
    closure: &mut Closure,
    ctx: &ShadingContext,
    block: &[f32],
    scale: Rgb<f32>,
    shares: &mut [f32; MAX_LOBES],
) -> Result<u32, Error> {
    let local = ctx.lanes();
    let mut expansion = Expansion::default();
    M::expand(Params::new(block), &local, &mut expansion);
    let candidates = expansion.weight[..M::Slots::NAMES.len()]
        .iter()
        .filter(|&&w| (scale * w).any_positive())
        .count();
    let mut emitter = Emitter {
        material,
        alone: candidates == 1,
        // Blocks are baked at the closure's `wo` (as `push_lobe` does); estimates
        // are at the context's.
        bake_wo: closure.view().map(|wo| ctx.frame.to_local(wo)),
        closure,
        frame: ctx.frame,
        wo: local.wo,
        expansion: &expansion,
        scale,
        shares,
        emitted: 0,
        strongest: None,
    };
    M::Slots::visit(&mut emitter)?;
    let Emitter {
        closure,
        shares,
        emitted,
        strongest,
        ..
    } = emitter;
    if let (0, Some((share, k))) = (emitted, strongest) {
        let (type_id, lobe) = &material.slots[k];
        let raw = &expansion.params[k][..material.block_lens[k]];
        let weight = scale * expansion.weight[k];
        closure.push_lobe(lobe, *type_id, weight, ctx.frame, Some(raw))?;
        shares[0] = share;
        return Ok(1 << k);
    }
    Ok(emitted)
}

/// [`emit`]'s walk over the slots.
struct Emitter<'a> {
    material: &'a Material,
    closure: &'a mut Closure,
    frame: Frame,
    /// The context's `wo` in the shading frame: the estimates' direction.
    wo: Vec3<f32>,
    bake_wo: Option<Vec3<f32>>,
    expansion: &'a Expansion<f32>,
    scale: Rgb<f32>,
    shares: &'a mut [f32; MAX_LOBES],
    emitted: u32,
    /// The strongest pruned slot, kept when every slot is pruned.
    strongest: Option<(f32, usize)>,
    /// Whether one slot alone has a weight: it is kept (pruned, it would be the
    /// strongest) and chosen with probability 1, so its estimate is not needed.
    alone: bool,
}

impl SlotVisitor for Emitter<'_> {
    /// Slot `k` decoded, baked and estimated on the stack, then pruned or added.
    #[inline(always)]
    fn slot<M: Model>(&mut self, k: usize) -> Result<(), Error> {
        let weight = self.scale * self.expansion.weight[k];
        if !weight.any_positive() {
            return Ok(());
        }
        let raw = &self.expansion.params[k][..params::block_size(M::PARAMS)];
        debug_assert!(params::validate(M::NAME, M::PARAMS, raw).is_ok());
        // Zeroed, as `push_lobe` hands `decode` its block.
        let mut decoded = [0.0f32; MAX_DECODED_LEN];
        let decoded = &mut decoded[..M::DECODED_LEN];
        match &self.material.decoded_defaults[k] {
            Some(d) if d.decodes(raw) => decoded.copy_from_slice(&d.decoded[..decoded.len()]),
            _ => M::decode(raw, decoded),
        }
        let mode = self.closure.transport();
        if let Some(wo) = self.bake_wo {
            M::bake(decoded, wo, mode);
        }
        let share = if self.alone {
            1.0
        } else {
            let albedo = M::albedo_estimate(&M::prepare(Params::new(decoded)), self.wo, mode);
            (weight * albedo).luminance()
        };
        if share < self.material.prune {
            if self.strongest.is_none_or(|(s, _)| share > s) {
                self.strongest = Some((share, k));
            }
            return Ok(());
        }
        let (type_id, lobe) = &self.material.slots[k];
        self.closure
            .push_decoded(lobe, *type_id, weight, self.frame, raw, decoded)?;
        self.shares[self.emitted.count_ones() as usize] = share;
        self.emitted |= 1 << k;
        Ok(())
    }
}

/// A slot's raw block and the block it decodes to.
#[derive(Clone, Copy)]
pub struct DecodedBlock {
    pub raw: [f32; MAX_SLOT_PARAMS],
    pub decoded: [f32; MAX_DECODED_LEN],
}

impl DecodedBlock {
    /// Whether `raw` is this block's raw block, bit for bit (-0 and 0 may decode
    /// apart).
    #[inline(always)]
    pub fn decodes(&self, raw: &[f32]) -> bool {
        raw.iter()
            .zip(&self.raw)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

/// [`Material::decoded_defaults`]: the slots whose decode is not a copy, decoded once
/// from the expansion of `params` at normal incidence.
fn decoded_defaults(
    kind: &dyn MaterialType,
    params: &[f32],
    slots: &[(u32, LobeRef)],
    block_lens: &[usize; MAX_SLOTS],
) -> Vec<Option<DecodedBlock>> {
    let ctx = ShadingContext::new(Vec3::new(0.0, 0.0, 1.0), Frame::IDENTITY);
    let e = kind.expand(params, &ctx.lanes());
    slots
        .iter()
        .enumerate()
        .map(|(k, (_, lobe))| {
            if lobe.decode_copies() {
                return None;
            }
            let mut d = DecodedBlock {
                raw: e.params[k],
                decoded: [0.0; MAX_DECODED_LEN],
            };
            let raw = &d.raw[..block_lens[k]];
            // A block outside the schema (a slot that weight 0 leaves unset) is never
            // emitted as is: nothing to cache.
            params::validate(lobe.name(), lobe.params(), raw).ok()?;
            lobe.decode(raw, &mut d.decoded[..lobe.decoded_len()]);
            Some(d)
        })
        .collect()
}

/// [`Material::shape_ids`] of `slots`: each set's closure built once (with the
/// slots' default blocks) and its shape id read.
fn shape_ids(slots: &[(u32, LobeRef)]) -> Result<Box<[u64]>, Error> {
    if slots.iter().any(|(_, l)| params::has_choices(l.params())) {
        return Ok(Box::new([]));
    }
    (0..1u32 << slots.len())
        .map(|set| {
            let mut closure = Closure::new(None, Transport::Radiance);
            for (k, (type_id, lobe)) in slots.iter().enumerate() {
                if set & 1 << k != 0 {
                    let white = Rgb::new(1.0, 1.0, 1.0);
                    closure.push_lobe(lobe, *type_id, white, Frame::IDENTITY, None)?;
                }
            }
            closure.finish()?;
            Ok(closure.shape_id())
        })
        .collect()
}

fn kind_name(kind: ParamKind) -> &'static str {
    match kind {
        ParamKind::Float => "a float",
        ParamKind::Rgb => "an rgb",
        ParamKind::Enum => "an enum",
    }
}
