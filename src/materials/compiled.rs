//! Compiled materials: a material type, a validated parameter block and the slots'
//! lobe types, resolved once per scene material; per shading point, overrides,
//! expansion, pruning and the closure.

use super::{MAX_SLOT_PARAMS, MaterialType, ShadingContext};
use crate::closure::{Closure, MAX_LOBES};
use crate::error::{Error, Status};
use crate::lobes::Transport;
use crate::math::Rgb;
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

impl Override {
    /// A placeholder (parameter 0 set to 0), for arrays filled later.
    pub const NONE: Override = Override {
        param: 0,
        kind: ParamKind::Float,
        value: [0.0; 3],
    };
}

/// A material ready to shade: validated and resolved once.
#[derive(Clone)]
pub struct Material {
    kind: &'static dyn MaterialType,
    type_id: u32,
    params: Vec<f32>,
    /// Each schema entry's value (element 0), resolved here so that per-point overrides
    /// by entry index skip `params::locate`; None for group and table headers.
    entries: Box<[Option<params::Slot<'static>>]>,
    /// Each slot's lobe type id and type.
    slots: Vec<(u32, LobeRef)>,
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
        let mut block = vec![0.0; params::block_size(specs)];
        match params {
            Some(values) => {
                params::validate(kind.name(), specs, values)?;
                block.copy_from_slice(values);
            }
            None => params::write_defaults(specs, &mut block),
        }
        let slots = kind
            .lobes()
            .iter()
            .map(|name| {
                let id = registry.find(name)?;
                let lobe = registry.get(id)?.clone();
                if params::block_size(lobe.params()) > MAX_SLOT_PARAMS {
                    return Err(Error::new(
                        Status::Unsupported,
                        format!(
                            "material {}: lobe type {name} has more than {MAX_SLOT_PARAMS} parameter values",
                            kind.name()
                        ),
                    ));
                }
                Ok((id, lobe))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let entries = (0..specs.len() as u32)
            .map(|i| params::locate(kind.name(), kind.params(), i, &"").ok())
            .collect();
        Ok(Material {
            kind,
            type_id,
            params: block,
            entries,
            slots,
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
        &self.params
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
        out.copy_from_slice(&self.params);
        for (i, o) in overrides.iter().enumerate() {
            let slot = self.override_slot(i, o.param, o.kind)?;
            let value = &o.value[..o.kind.size()];
            self.check_element(i, slot.spec, value, slot.element)?;
            out[slot.offset..slot.offset + value.len()].copy_from_slice(value);
        }
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
        let block = &mut block[..self.params.len()];
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
        let (shares, kept) = self.emit(closure, ctx, block, Rgb::new(1.0, 1.0, 1.0))?;
        closure.finish_with_shares(&shares[..kept])
    }

    /// Add the lobes of one shading point (`block`: the parameters with its overrides
    /// applied) to the open `closure`, their weights
    /// scaled by `scale`: expansion, then pruning. Returns each added lobe's
    /// `luminance(weight * albedo(wo))` with its albedo estimate, as `Closure::finish`
    /// would compute it, and
    /// how many were added (at least one: when every lobe is below the threshold, the
    /// strongest is kept).
    pub(crate) fn emit(
        &self,
        closure: &mut Closure,
        ctx: &ShadingContext,
        block: &[f32],
        scale: Rgb<f32>,
    ) -> Result<([f32; MAX_LOBES], usize), Error> {
        let local = ctx.lanes();
        let e = self.kind.expand(block, &local);
        let first = closure.lobes().len();
        let mut shares = [0.0f32; MAX_LOBES];
        let mut kept = 0;
        // The strongest pruned slot, kept when every slot is pruned.
        let mut strongest: Option<(f32, usize)> = None;
        let push = |closure: &mut Closure, k: usize| {
            let (type_id, lobe) = &self.slots[k];
            let block = &e.params[k][..params::block_size(lobe.params())];
            debug_assert!(params::validate(lobe.name(), lobe.params(), block).is_ok());
            closure.push_lobe(lobe, *type_id, scale * e.weight[k], ctx.frame, Some(block))
        };
        for k in 0..self.slots.len() {
            let weight = scale * e.weight[k];
            if !(weight.r > 0.0 || weight.g > 0.0 || weight.b > 0.0) {
                continue;
            }
            let at = push(closure, k)?;
            let lobe = &self.slots[k].1;
            let albedo = lobe.albedo_estimate_decoded(
                closure.lobe_decoded(at),
                local.wo,
                closure.transport(),
            );
            let share = (weight * albedo).luminance();
            if share < self.prune {
                closure.pop_lobe();
                if strongest.is_none_or(|(s, _)| share > s) {
                    strongest = Some((share, k));
                }
                continue;
            }
            shares[kept] = share;
            kept += 1;
        }
        if let (0, Some((share, k))) = (kept, strongest) {
            push(closure, k)?;
            shares[0] = share;
            kept = 1;
        }
        debug_assert_eq!(closure.lobes().len(), first + kept);
        Ok((shares, kept))
    }

    /// The closure of one shading point, as a new value.
    pub fn closure(&self, ctx: &ShadingContext, overrides: &[Override]) -> Result<Closure, Error> {
        let mut closure = Closure::new(Some(ctx.wo), Transport::Radiance);
        self.build_closure(&mut closure, ctx, overrides)?;
        Ok(closure)
    }
}

fn kind_name(kind: ParamKind) -> &'static str {
    match kind {
        ParamKind::Float => "a float",
        ParamKind::Rgb => "an rgb",
        ParamKind::Enum => "an enum",
    }
}
