//! Materials: artist parameters that expand, at each shading point, into a few
//! weighted lobes.
//!
//! A material model implements [`MaterialModel`]: its parameter schema (the same
//! [`ParamSpec`] tables as lobes), the lobe types it may emit (one per *slot*), and
//! `expand`, written once over the [`Lane`] type like the lobes: given its parameters
//! and a shading context it writes each slot's weight and lobe parameter block. A slot
//! whose weight is zero is not emitted. [`BuiltinMaterial`] adapts a model to the
//! object-safe [`MaterialType`] that the registry lists and [`Material`] (a compiled
//! material) uses.
//!
//! A compiled [`Material`] holds a validated parameter block and its slots' lobe types,
//! resolved once per scene material. Per shading point it takes overrides (textured
//! parameters, by index), expands, and builds a closure: each lobe's
//! `luminance(weight * albedo(wo))`, with the lobe's albedo estimate
//! (`Model::albedo_estimate`), both prunes it (below the runtime's `prune=` threshold
//! it is not emitted) and sets its selection probability. The slots' models are known
//! at compile time ([`MaterialModel::Slots`]), so this per-point path is one
//! monomorphized function per material type: no virtual call per slot, and each
//! slot's decode, estimate and block copies inlined with their sizes known.

pub mod compiled;
pub mod disney;

pub use compiled::{Material, Override};

use crate::closure::{Closure, MAX_LOBES};
use crate::error::Error;
use crate::kernels::expand::{ExpandJob, SlotSample, sample_slots};
use crate::lobes::{Model, Params, VerifyCase};
use crate::math::{Frame, Lane, Rgb, Vec3};
use crate::params::ParamSpec;
use crate::simd::Kernels;
use std::any::TypeId;
use std::marker::PhantomData;

/// Most lobes one material emits.
pub const MAX_SLOTS: usize = 8;
/// Most parameter values of one slot's lobe block.
pub const MAX_SLOT_PARAMS: usize = 16;

/// Default of the `prune=` setting: a lobe whose `luminance(weight * albedo(wo))` is
/// below it is not emitted.
pub const DEFAULT_PRUNE: f32 = 1e-3;

/// Where and how a surface is seen, in world space (`glint_shading_context`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingContext {
    /// Toward the viewer, unit.
    pub wo: Vec3<f32>,
    /// The shading frame the material's lobes use.
    pub frame: Frame,
    /// Unit geometric normal.
    pub geometric_normal: Vec3<f32>,
    pub position: Vec3<f32>,
    /// The position in the object's reference (rest) space: procedural patterns such
    /// as glitter stay attached to a deforming surface.
    pub reference_position: Vec3<f32>,
    /// Radius of the pixel's footprint on the surface (world units, >= 0).
    pub footprint: f32,
    pub uv: [f32; 2],
}

impl ShadingContext {
    /// A context with only a view direction and a frame (the rest zero).
    pub fn new(wo: Vec3<f32>, frame: Frame) -> Self {
        let zero = Vec3::splat(0.0, 0.0, 0.0);
        ShadingContext {
            wo,
            frame,
            geometric_normal: frame.n,
            position: zero,
            reference_position: zero,
            footprint: 0.0,
            uv: [0.0; 2],
        }
    }

    /// What `expand` sees: `wo` in the shading frame, the rest as given.
    pub fn lanes(&self) -> Context<f32> {
        Context {
            wo: self.frame.to_local(self.wo),
            position: self.position,
            reference_position: self.reference_position,
            footprint: self.footprint,
            uv: self.uv,
        }
    }
}

/// The shading context over lanes, as `expand` reads it.
#[derive(Clone, Copy, Debug)]
pub struct Context<L> {
    /// Toward the viewer, in the shading frame (z = normal).
    pub wo: Vec3<L>,
    pub position: Vec3<L>,
    pub reference_position: Vec3<L>,
    pub footprint: L,
    pub uv: [L; 2],
}

/// What `expand` writes: per slot, the lobe's weight (zero: not emitted) and its
/// parameter block, laid out by the slot's lobe type.
#[derive(Clone, Copy, Debug)]
pub struct Expansion<L> {
    pub weight: [Rgb<L>; MAX_SLOTS],
    pub params: [[L; MAX_SLOT_PARAMS]; MAX_SLOTS],
}

impl<L: Lane> Default for Expansion<L> {
    #[inline(always)]
    fn default() -> Self {
        Expansion {
            weight: [Rgb::zero(); MAX_SLOTS],
            params: [[L::zero(); MAX_SLOT_PARAMS]; MAX_SLOTS],
        }
    }
}

/// A material model, written once over the lane type.
pub trait MaterialModel: Send + Sync + 'static {
    const NAME: &'static str;
    /// One line for registries and UIs.
    const SUMMARY: &'static str;
    const PARAMS: &'static [ParamSpec];
    /// The lobe model of each slot, in order: a tuple of built-in [`Model`]s.
    type Slots: SlotModels;
    /// Parameter sets the verification harness covers besides the defaults.
    const VERIFY_CASES: &'static [VerifyCase] = &[];

    /// Write each slot's weight and lobe block for `params` (a validated block, with
    /// overrides applied) seen from `ctx`. Every block written for a nonzero weight
    /// must be valid for its lobe type's schema (clamped into range).
    fn expand<L: Lane>(params: Params<'_, L>, ctx: &Context<L>, out: &mut Expansion<L>);
}

/// The lobe models of a material's slots, in order (a tuple of up to [`MAX_SLOTS`]
/// built-in models).
pub trait SlotModels: 'static {
    /// Each slot's lobe type, by registered name.
    const NAMES: &'static [&'static str];
    /// Each slot's model ([`crate::lobes::LobeType::model`]).
    fn models() -> Vec<TypeId>;
    /// `visitor.slot::<M>(k)` for each slot `k` in order, with `M` its model; stops at
    /// the first error.
    fn visit(visitor: &mut impl SlotVisitor) -> Result<(), Error>;
    /// Whether the slots are a fused shape (2 to
    /// [`MAX_FUSED`](crate::kernels::fused::MAX_FUSED) of them), which a
    /// material batch samples in its expansion's pass.
    const FUSED: bool;
    /// One register's sample in the expansion's pass ([`sample_slots`]);
    /// false, and nothing written, when the slots are not a fused shape.
    fn sample_fused<L: Lane>(register: SlotSample<'_, '_, L>) -> bool;
}

/// What [`SlotModels::visit`] calls per slot.
pub trait SlotVisitor {
    fn slot<M: Model>(&mut self, k: usize) -> Result<(), Error>;
}

macro_rules! slot_models {
    ($fused:literal, $sample:ident; $($m:ident $k:literal),+) => {
        impl<$($m: Model),+> SlotModels for ($($m,)+) {
            const NAMES: &'static [&'static str] = &[$($m::NAME),+];
            fn models() -> Vec<TypeId> {
                vec![$(TypeId::of::<$m>()),+]
            }
            #[inline(always)]
            fn visit(visitor: &mut impl SlotVisitor) -> Result<(), Error> {
                $(visitor.slot::<$m>($k)?;)+
                Ok(())
            }
            const FUSED: bool = $fused;
            #[inline(always)]
            fn sample_fused<L: Lane>(register: SlotSample<'_, '_, L>) -> bool {
                $sample::<Self, L>(register)
            }
        }
    };
}

/// [`SlotModels::sample_fused`] of slots that are not a fused shape (`S`, unused,
/// keeps the macro's one call form with [`sample_slots`]).
#[allow(clippy::extra_unused_type_parameters)]
#[inline(always)]
fn not_fused<S, L: Lane>(_register: SlotSample<'_, '_, L>) -> bool {
    false
}

slot_models!(false, not_fused; A 0);
slot_models!(true, sample_slots; A 0, B 1);
slot_models!(true, sample_slots; A 0, B 1, C 2);
slot_models!(true, sample_slots; A 0, B 1, C 2, D 3);
slot_models!(false, not_fused; A 0, B 1, C 2, D 3, E 4);
slot_models!(false, not_fused; A 0, B 1, C 2, D 3, E 4, F 5);
slot_models!(false, not_fused; A 0, B 1, C 2, D 3, E 4, F 5, G 6);
slot_models!(false, not_fused; A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7);

/// A material type as the registry sees it: object-safe, scalar.
pub trait MaterialType: Send + Sync {
    fn name(&self) -> &str;
    fn summary(&self) -> &str;
    fn params(&self) -> &[ParamSpec];
    fn lobes(&self) -> &[&'static str];
    /// Each slot's lobe model ([`MaterialModel::Slots`]).
    fn slot_models(&self) -> Vec<TypeId>;
    fn verify_cases(&self) -> &[VerifyCase];
    fn expand(&self, params: &[f32], ctx: &Context<f32>) -> Expansion<f32>;
    /// [`Material::emit`] for this type's slots, monomorphized.
    fn emit(
        &self,
        material: &Material,
        closure: &mut Closure,
        ctx: &ShadingContext,
        block: &[f32],
        scale: Rgb<f32>,
        shares: &mut [f32; MAX_LOBES],
    ) -> Result<u32, Error>;
    /// `expand` over staged lanes in SIMD, each slot decoded, estimated, pruned and
    /// selected, and with `job.eval` the eval too (material batches: `kernels::expand`).
    fn expand_lanes(&self, kernels: Kernels, job: &mut ExpandJob<'_>);
    /// Whether `expand_lanes` takes a sample in its pass (`job.sample`): the slots
    /// are a fused shape ([`SlotModels::FUSED`]).
    fn samples_in_pass(&self) -> bool;
}

/// The [`MaterialType`] of a built-in [`MaterialModel`].
pub struct BuiltinMaterial<M>(PhantomData<M>);

impl<M> BuiltinMaterial<M> {
    pub const fn new() -> Self {
        BuiltinMaterial(PhantomData)
    }
}

impl<M: MaterialModel> Default for BuiltinMaterial<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: MaterialModel> MaterialType for BuiltinMaterial<M> {
    fn name(&self) -> &str {
        M::NAME
    }
    fn summary(&self) -> &str {
        M::SUMMARY
    }
    fn params(&self) -> &[ParamSpec] {
        M::PARAMS
    }
    fn lobes(&self) -> &[&'static str] {
        M::Slots::NAMES
    }
    fn slot_models(&self) -> Vec<TypeId> {
        M::Slots::models()
    }
    fn verify_cases(&self) -> &[VerifyCase] {
        M::VERIFY_CASES
    }
    fn expand(&self, params: &[f32], ctx: &Context<f32>) -> Expansion<f32> {
        let mut out = Expansion::default();
        M::expand(Params::new(params), ctx, &mut out);
        out
    }
    fn emit(
        &self,
        material: &Material,
        closure: &mut Closure,
        ctx: &ShadingContext,
        block: &[f32],
        scale: Rgb<f32>,
        shares: &mut [f32; MAX_LOBES],
    ) -> Result<u32, Error> {
        compiled::emit::<M>(material, closure, ctx, block, scale, shares)
    }
    fn expand_lanes(&self, kernels: Kernels, job: &mut ExpandJob<'_>) {
        crate::kernels::expand::expand::<M>(kernels, job);
    }
    fn samples_in_pass(&self) -> bool {
        M::Slots::FUSED
    }
}

/// Every built-in material type, in registration (id) order.
pub static BUILTIN_MATERIALS: &[&(dyn MaterialType + 'static)] =
    &[&BuiltinMaterial::<disney::Disney>::new()];
