//! The lobe contract and the built-in lobes, one model per file.
//!
//! A lobe model implements [`Model`]: its parameter schema, and `eval`, `sample`
//! and `albedo` written once over the [`Lane`] type, in the lobe's local frame
//! (z = normal, directions pointing away from the surface). [`Builtin`] adapts a
//! model to the object-safe [`LobeType`] that the registry and closures use, so
//! plugin lobes (which are not generic) fit the same slot.
//!
//! Conventions (DESIGN.md): `eval` returns `f(wo, wi) |cos theta_i|` and the pdf of
//! sampling `wi`; delta lobes return 0 from eval and pdf, and their samples carry
//! the SPECULAR class, `value` = the reflected or transmitted fraction and `pdf` = the
//! discrete probability of the chosen event.
//!
//! A sample reports its own class (diffuse, glossy or specular: a dielectric's
//! sample is specular at roughness 0 and glossy above) and the component (sub-lobe)
//! it came from; [`class_of`] gives the class from the lobe type's flags for lobes
//! with one class. A lobe may bake what depends only on `wo` once per shading point
//! ([`Model::bake`]).

pub mod conductor;
pub mod dielectric;
pub mod disney_clearcoat;
pub mod disney_diffuse;
pub mod disney_sheen;
pub mod disney_specular;
pub mod fresnel_params;
pub mod lambert;
pub mod mirror;

use crate::kernels::{self, AlbedoJob, EvalJob, SampleJob};
use crate::math::{Frame, Lane, LaneFrame, Mask, Rgb, Vec3};
use crate::params::ParamSpec;
use crate::simd::Kernels;
use std::marker::PhantomData;

/// Sample and lobe flags (bit set), as in the C API's `GLINT_FLAG_*`.
pub mod flags {
    pub const REFLECTION: u32 = 1;
    pub const TRANSMISSION: u32 = 2;
    pub const DIFFUSE: u32 = 4;
    pub const GLOSSY: u32 = 8;
    pub const SPECULAR: u32 = 16;
}

/// Whether the path carries radiance (from the camera) or importance (from lights).
/// Only refraction differs: radiance transmission is scaled by `1 / eta^2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Transport {
    #[default]
    Radiance,
    Importance,
}

/// `f(wo, wi) |cos theta_i|` and the pdf of sampling `wi` from `wo`.
#[derive(Clone, Copy, Debug)]
pub struct Eval<L> {
    pub value: Rgb<L>,
    pub pdf: L,
}

impl<L: Lane> Eval<L> {
    #[inline(always)]
    pub fn zero() -> Self {
        Eval {
            value: Rgb::zero(),
            pdf: L::zero(),
        }
    }
}

/// The result of sampling a lobe. Lanes where `valid` is false failed to sample and
/// carry zeros.
#[derive(Clone, Copy, Debug)]
pub struct Sample<L: Lane> {
    pub wi: Vec3<L>,
    pub value: Rgb<L>,
    pub pdf: L,
    pub valid: L::Mask,
    pub transmitted: L::Mask,
    pub delta: L::Mask,
    /// Relative IOR crossed by a transmitted sample, 1 otherwise.
    pub eta: L,
    /// The lobe's roughness in [0, 1] (0 for delta samples), a hint for path regularization.
    pub roughness: L,
    /// The sample's class bit, `flags::DIFFUSE`, `GLOSSY` or `SPECULAR` (the latter
    /// exactly where `delta`), as a lane value; 0 where the sample failed.
    pub class: L,
    /// The component (sub-lobe) sampled, a small integer: a dielectric's reflection 0
    /// and transmission 1; 0 for lobes of one component.
    pub component: L,
}

/// Largest component index a sample reports (staged rows pack it beside the event
/// bits in a float-exact integer).
pub const MAX_COMPONENT: f32 = 65535.0;

/// The class of a sample from its `delta` lanes and its lobe type's flags: SPECULAR
/// for delta events, else the type's DIFFUSE / GLOSSY bit (a type declaring both, as
/// a V1 plugin may, reports both).
#[inline(always)]
pub fn class_of<L: Lane>(delta: L::Mask, lobe_flags: u32) -> L {
    L::select(
        delta,
        L::splat(flags::SPECULAR as f32),
        L::splat((lobe_flags & (flags::DIFFUSE | flags::GLOSSY)) as f32),
    )
}

impl<L: Lane> Sample<L> {
    /// Zero the lanes that are invalid or whose pdf or value is not a finite
    /// positive number, so that no caller ever sees NaN or a weight with zero pdf.
    #[inline(always)]
    pub fn finish(mut self) -> Self {
        let ok = self.valid
            & self.pdf.gt(L::zero())
            & self.pdf.is_finite()
            & (self.wi.x + self.wi.y + self.wi.z).is_finite()
            & self.value.r.is_finite()
            & self.value.g.is_finite()
            & self.value.b.is_finite();
        self.valid = ok;
        self.pdf = L::select(ok, self.pdf, L::zero());
        self.value = Rgb::select(
            ok,
            self.value.map(
                #[inline(always)]
                |v| v.max(L::zero()),
            ),
            Rgb::zero(),
        );
        self.wi = Vec3::select(ok, self.wi, Vec3::new(L::zero(), L::zero(), L::zero()));
        self.class = L::select(ok, self.class, L::zero());
        self.component = L::select(
            ok,
            self.component.max(L::zero()).min(L::splat(MAX_COMPONENT)),
            L::zero(),
        );
        self
    }

    /// `a` in the lanes of `mask`, `b` elsewhere.
    #[inline(always)]
    pub fn select(mask: L::Mask, a: Self, b: Self) -> Self {
        Sample {
            wi: Vec3::select(mask, a.wi, b.wi),
            value: Rgb::select(mask, a.value, b.value),
            pdf: L::select(mask, a.pdf, b.pdf),
            valid: (mask & a.valid) | (!mask & b.valid),
            transmitted: (mask & a.transmitted) | (!mask & b.transmitted),
            delta: (mask & a.delta) | (!mask & b.delta),
            eta: L::select(mask, a.eta, b.eta),
            roughness: L::select(mask, a.roughness, b.roughness),
            class: L::select(mask, a.class, b.class),
            component: L::select(mask, a.component, b.component),
        }
    }

    /// `value / pdf`, 0 where the sample failed.
    #[inline(always)]
    pub fn weight(&self) -> Rgb<L> {
        let pdf = self.pdf;
        self.value.map(
            #[inline(always)]
            |v| v.safe_div(pdf),
        )
    }
}

impl Sample<f32> {
    /// The `GLINT_FLAG_*` bits of a scalar sample: reflection or transmission, and
    /// its class.
    pub fn flags(&self) -> u32 {
        let side = if self.transmitted {
            flags::TRANSMISSION
        } else {
            flags::REFLECTION
        };
        side | self.class as u32
    }
}

/// Where a sampled local direction ends up. A closure returns samples in world space:
/// the local direction its `eval` then sees is the world one taken back to the
/// lobe's frame, a few ulps from the sampled one, which a narrow lobe at grazing
/// turns into a large change of value. Settling first lets the sample compute value
/// and pdf at exactly that direction, with no second evaluation.
pub trait Settle<L: Lane> {
    /// The local direction the caller will see for the sampled local `wi`.
    fn settle(&mut self, wi: Vec3<L>) -> Vec3<L>;
}

/// Samples returned in the lobe's frame (lobe calls, the harness): nothing moves.
pub struct InPlace;

impl<L: Lane> Settle<L> for InPlace {
    #[inline(always)]
    fn settle(&mut self, wi: Vec3<L>) -> Vec3<L> {
        wi
    }
}

/// Samples returned in world space through `frame`; `world` holds the last settled
/// direction (unit, world space).
pub struct ToWorld<L> {
    pub frame: LaneFrame<L>,
    pub world: Vec3<L>,
}

impl<L: Lane> ToWorld<L> {
    #[inline(always)]
    pub fn new(frame: LaneFrame<L>) -> Self {
        ToWorld {
            frame,
            world: Vec3::new(L::zero(), L::zero(), L::zero()),
        }
    }
}

impl<L: Lane> Settle<L> for ToWorld<L> {
    #[inline(always)]
    fn settle(&mut self, wi: Vec3<L>) -> Vec3<L> {
        let world = self.frame.to_world(wi).normalize();
        self.world = world;
        // The local direction as an eval given `world` computes it: every eval path
        // normalizes its input (`Vec3::unit_from`), and normalizing a unit vector can
        // still move its last bit, which a narrow lobe would amplify.
        self.frame.to_local(world.unit_from(world.length_squared()))
    }
}

/// Read access to a lobe's parameter block, laid out by its schema: one value per
/// lane, or one value for every lane (a closure shared by the batch).
#[derive(Clone, Copy)]
pub struct Params<'a, L> {
    source: ParamSource<'a, L>,
}

#[derive(Clone, Copy)]
enum ParamSource<'a, L> {
    Lanes(&'a [L]),
    /// Splatted on read, so a shared closure's block is not copied into registers.
    Shared(&'a [f32]),
    /// Staged rows, value `p` of the register at lane `at` at `rows[p * stride + at..]`:
    /// loaded on read, so a kernel keeps in registers only the values its lobes use.
    Rows {
        rows: &'a [f32],
        count: usize,
        stride: usize,
        at: usize,
    },
}

impl<'a, L: Lane> Params<'a, L> {
    #[inline(always)]
    pub fn new(raw: &'a [L]) -> Self {
        Params {
            source: ParamSource::Lanes(raw),
        }
    }
    /// The same block for every lane.
    #[inline(always)]
    pub fn shared(raw: &'a [f32]) -> Self {
        Params {
            source: ParamSource::Shared(raw),
        }
    }
    /// The `count` values of a register of lanes at `at` in rows of `stride` values.
    #[inline(always)]
    pub fn rows(rows: &'a [f32], count: usize, stride: usize, at: usize) -> Self {
        Params {
            source: ParamSource::Rows {
                rows,
                count,
                stride,
                at,
            },
        }
    }
    /// Whether the block holds `len` values.
    #[inline(always)]
    pub fn holds(&self, len: usize) -> bool {
        let held = match self.source {
            ParamSource::Lanes(raw) => raw.len(),
            ParamSource::Shared(raw) => raw.len(),
            ParamSource::Rows { count, .. } => count,
        };
        held >= len
    }
    #[inline(always)]
    pub fn float(&self, offset: usize) -> L {
        match self.source {
            ParamSource::Lanes(raw) => raw[offset],
            ParamSource::Shared(raw) => L::splat(raw[offset]),
            ParamSource::Rows {
                rows,
                count,
                stride,
                at,
            } => {
                assert!(offset < count);
                L::load(&rows[offset * stride + at..])
            }
        }
    }
    #[inline(always)]
    pub fn rgb(&self, offset: usize) -> Rgb<L> {
        Rgb::new(
            self.float(offset),
            self.float(offset + 1),
            self.float(offset + 2),
        )
    }
    /// An enumerated choice; uniform across lanes by construction of batch groups.
    #[inline(always)]
    pub fn choice(&self, offset: usize) -> usize {
        match self.source {
            ParamSource::Lanes(raw) => raw[offset].lane0() as usize,
            ParamSource::Shared(raw) => raw[offset] as usize,
            ParamSource::Rows { .. } => self.float(offset).lane0() as usize,
        }
    }
}

/// A lobe model, written once over the lane type.
pub trait Model: Send + Sync + 'static {
    const NAME: &'static str;
    /// One line for registries and UIs.
    const SUMMARY: &'static str;
    const PARAMS: &'static [ParamSpec];
    /// Every flag a sample of this lobe may carry.
    const FLAGS: u32;
    /// Whether `f(wo, wi) == f(wi, wo)` holds for the raw BSDF (radiance transport).
    const RECIPROCAL: bool;
    /// How many components (sub-lobes) samples report: 0 .. COMPONENTS - 1.
    const COMPONENTS: u32 = 1;

    /// Parameter sets the verification harness must cover, hardest corners included
    /// (the defaults are always covered).
    const VERIFY_CASES: &'static [VerifyCase] = &[];
    /// Documented relative accuracy of `albedo` with these parameters (the harness checks it).
    fn albedo_tolerance(params: &[f32]) -> f32;
    /// The largest directional albedo the model has with these parameters: 1 for an
    /// energy-conserving lobe (the default). A model that is not energy conserving by
    /// design (Burley 2012's diffuse) states its own bound, and the harness's energy
    /// check holds its sampled albedo to that instead of 1.
    fn energy_bound(_params: &[f32]) -> f32 {
        1.0
    }
    /// Documented relative accuracy of [`Model::albedo_estimate`] against `albedo`
    /// with these parameters (the harness checks it); 0 when they are the same.
    fn albedo_estimate_tolerance(_params: &[f32]) -> f32 {
        0.0
    }

    /// Length of the decoded block [`Model::decode`] writes.
    const DECODED_LEN: usize = crate::params::block_size(Self::PARAMS);
    /// Decode a validated parameter block once, in `f32` (when a lobe is added to a
    /// closure): roughness to alpha, Fresnel mode resolved, Gulbrandsen to complex IOR.
    /// `out` has [`Model::DECODED_LEN`] values. The default copies the block.
    fn decode(params: &[f32], out: &mut [f32]) {
        out.copy_from_slice(params);
    }
    /// Whether [`Model::decode`] is the default copy, so blocks in rows (material
    /// batches) decode as whole rows. Opt-in; tests/decode_rows.rs checks the claim
    /// of every registered type.
    const DECODE_COPIES: bool = false;
    /// The leading part of the decoded block that `eval` and `sample` read: blocks
    /// staged per lane for them stop there (what follows only `albedo` reads).
    const LANE_DECODED_LEN: usize = Self::DECODED_LEN;
    /// Bake what depends only on the parameters and `wo` (local, unit) into the
    /// decoded block, once per shading point: closures built with a `wo` call it after
    /// `decode`, and eval, sample and albedo at that `wo` read the result instead of
    /// recomputing it ([`baked_or`]). The lobe lays the values out in its block and
    /// `decode` marks them unbaked (a NaN key, which no `wo` matches), so blocks that
    /// are never baked (material batches, lobe calls) compute as before. Default:
    /// nothing to bake, no cost.
    fn bake(_decoded: &mut [f32], _wo: Vec3<f32>, _mode: Transport) {}

    /// A decoded block as the model's functions read it.
    type Prepared<L: Lane>;

    /// Read a decoded block ([`Model::decode`]) into lanes.
    fn prepare<L: Lane>(decoded: Params<'_, L>) -> Self::Prepared<L>;
    fn eval<L: Lane>(p: &Self::Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, mode: Transport) -> Eval<L>;
    /// Whether a sample's `valid` is exactly [`both_above`] at the settled direction,
    /// and what it returns besides `wi`, value and pdf does not depend on that
    /// direction: a fused mixture sample (`kernels::fused`) then samples each lobe in
    /// place and settles only the direction each lane keeps. Default: false.
    const VALID_ABOVE: bool = false;
    /// `uc` chooses among discrete events (reflect or refract); `u0`, `u1` pick the
    /// direction. The sampled direction goes through `settle` before anything is
    /// computed from it: value, pdf and validity are those of the settled direction,
    /// which is the one returned (the direction the caller's `eval` will see).
    fn sample<L: Lane>(
        p: &Self::Prepared<L>,
        wo: Vec3<L>,
        uc: L,
        u0: L,
        u1: L,
        mode: Transport,
        settle: &mut impl Settle<L>,
    ) -> Sample<L>;
    /// Directional albedo `R(wo)`: the integral of `eval(wo, wi)` over all `wi`.
    fn albedo<L: Lane>(p: &Self::Prepared<L>, wo: Vec3<L>, mode: Transport) -> Rgb<L>;
    /// What lobe selection and pruning weigh the lobe by: `albedo`, or a cheaper
    /// estimate of it within [`Model::albedo_estimate_tolerance`]. Selection only
    /// needs shares, and every shading point pays for them. Default: `albedo`.
    #[inline(always)]
    fn albedo_estimate<L: Lane>(p: &Self::Prepared<L>, wo: Vec3<L>, mode: Transport) -> Rgb<L> {
        Self::albedo(p, wo, mode)
    }
}

/// A lobe type as the registry and closures see it: scalar, object-safe, and the
/// same for built-in and plugin lobes.
pub trait LobeType: Send + Sync {
    fn name(&self) -> &str;
    fn summary(&self) -> &str;
    fn params(&self) -> &[ParamSpec];
    fn flags(&self) -> u32;
    fn reciprocal(&self) -> bool;
    /// How many components (sub-lobes) samples report ([`Model::COMPONENTS`]).
    fn component_count(&self) -> u32 {
        1
    }
    fn eval(&self, params: &[f32], wo: Vec3<f32>, wi: Vec3<f32>, mode: Transport) -> Eval<f32>;

    /// Length of this type's decoded parameter block.
    fn decoded_len(&self) -> usize {
        crate::params::block_size(self.params())
    }
    /// The leading part of a decoded block that eval and sample read
    /// ([`Model::LANE_DECODED_LEN`]).
    fn lane_decoded_len(&self) -> usize {
        self.decoded_len()
    }
    /// Decode a validated parameter block once (closures store the result; the
    /// `*_decoded` calls and the batch jobs read it). The default copies it.
    fn decode(&self, params: &[f32], out: &mut [f32]) {
        out.copy_from_slice(params);
    }
    /// [`Model::bake`]: a decoded block's values that depend on `wo` alone.
    fn bake(&self, _decoded: &mut [f32], _wo: Vec3<f32>, _mode: Transport) {}
    /// Whether [`LobeType::decode`] copies the block ([`Model::DECODE_COPIES`]).
    fn decode_copies(&self) -> bool {
        false
    }
    /// [`LobeType::decode`] of `len` lanes' blocks in rows (value `p` of lane `j` at
    /// `p * len + j`, in `params` and in `out`).
    fn decode_rows(&self, params: &[f32], out: &mut [f32], len: usize) {
        decode_rows(params, out, len, |block, decoded| {
            self.decode(block, decoded)
        });
    }
    /// [`LobeType::eval`] from a decoded block.
    fn eval_decoded(
        &self,
        decoded: &[f32],
        wo: Vec3<f32>,
        wi: Vec3<f32>,
        mode: Transport,
    ) -> Eval<f32> {
        self.eval(decoded, wo, wi, mode)
    }
    /// [`LobeType::sample`] from a decoded block.
    fn sample_decoded(
        &self,
        decoded: &[f32],
        wo: Vec3<f32>,
        u: [f32; 3],
        mode: Transport,
    ) -> Sample<f32> {
        self.sample(decoded, wo, u, mode)
    }
    /// Sample in `frame` from the world-space `wo`: the returned `wi` is world space
    /// (unit), and value and pdf are exactly `eval_decoded` at `frame.to_local(wi)`.
    /// The default samples locally and evaluates there again; built-in lobes settle
    /// the direction first ([`Settle`]) and evaluate once.
    fn sample_world(
        &self,
        decoded: &[f32],
        frame: &Frame,
        wo: Vec3<f32>,
        u: [f32; 3],
        mode: Transport,
    ) -> Sample<f32> {
        let wo = frame.to_local(wo);
        let mut s = self.sample_decoded(decoded, wo, u, mode);
        // Valued at the direction returned, as the built-in lobes' samples are.
        let mut settle = ToWorld::new(LaneFrame::splat(frame));
        let wi = settle.settle(s.wi);
        if s.valid && !s.delta {
            let e = self.eval_decoded(decoded, wo, wi, mode);
            (s.value, s.pdf) = (e.value, e.pdf);
        }
        s.wi = settle.world;
        s.finish()
    }
    /// [`LobeType::albedo`] from a decoded block.
    fn albedo_decoded(&self, decoded: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        self.albedo(decoded, wo, mode)
    }
    /// [`Model::albedo_estimate`] from a decoded block: what selection and pruning
    /// weigh the lobe by. The default is [`LobeType::albedo_decoded`].
    fn albedo_estimate_decoded(&self, decoded: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        self.albedo_decoded(decoded, wo, mode)
    }
    /// Documented relative accuracy of [`LobeType::albedo_estimate_decoded`] against
    /// the albedo with these parameters; 0 (the default) when they are the same.
    fn albedo_estimate_tolerance(&self, _params: &[f32]) -> f32 {
        0.0
    }

    /// `eval_decoded(wo, wi)` and the reverse pdf `eval_decoded(wi, wo).pdf` (built-in
    /// lobes read the block once for both).
    fn eval_decoded_with_reverse(
        &self,
        decoded: &[f32],
        wo: Vec3<f32>,
        wi: Vec3<f32>,
        mode: Transport,
    ) -> (Eval<f32>, f32) {
        (
            self.eval_decoded(decoded, wo, wi, mode),
            self.eval_decoded(decoded, wi, wo, mode).pdf,
        )
    }
    fn sample(&self, params: &[f32], wo: Vec3<f32>, u: [f32; 3], mode: Transport) -> Sample<f32>;
    fn albedo(&self, params: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32>;
    /// Parameter sets the verification harness covers besides the defaults.
    fn verify_cases(&self) -> &[VerifyCase] {
        &[]
    }
    /// Documented relative accuracy of `albedo` with these parameters.
    fn albedo_tolerance(&self, params: &[f32]) -> f32;
    /// The largest directional albedo with these parameters ([`Model::energy_bound`]).
    fn energy_bound(&self, _params: &[f32]) -> f32 {
        1.0
    }
    /// Outputs zeroed because they were NaN, infinite or negative (plugin lobes; the
    /// built-in lobes never produce them).
    fn sanitized_count(&self) -> u64 {
        0
    }

    /// `eval` over a group of lanes (the batch kernels), whose parameters are decoded
    /// blocks. The default loops over [`LobeType::eval_decoded`]; built-in lobes run
    /// their SIMD kernels.
    fn eval_lanes(&self, _kernels: Kernels, job: &mut EvalJob<'_>) {
        kernels::eval_each_lane(job, |d, wo, wi, mode| self.eval_decoded(d, wo, wi, mode));
    }
    /// `sample` over a group of lanes; the default loops over [`LobeType::sample_world`].
    fn sample_lanes(&self, _kernels: Kernels, job: &mut SampleJob<'_>) {
        kernels::sample_each_lane(job, |d, frame, wo, u, mode| {
            self.sample_world(d, frame, wo, u, mode)
        });
    }
    /// Whether the `*_lanes` calls take jobs over the caller's own arrays
    /// (`kernels::Directions::Raw`, any length, one-lobe closure samples finished in
    /// the kernel). Lobes without SIMD kernels get staged jobs only.
    fn has_kernels(&self) -> bool {
        false
    }
    /// The built-in model behind this type, by which fused closure kernels
    /// (`kernels::fused`) know it; None for plugin lobes.
    fn model(&self) -> Option<std::any::TypeId> {
        None
    }
    /// `albedo` (or its estimate, as `job.estimate` says) over a group of lanes; the
    /// default loops over [`LobeType::albedo_decoded`] or
    /// [`LobeType::albedo_estimate_decoded`].
    fn albedo_lanes(&self, _kernels: Kernels, job: &mut AlbedoJob<'_>) {
        if job.estimate {
            kernels::albedo_each_lane(job, |d, wo, mode| self.albedo_estimate_decoded(d, wo, mode));
        } else {
            kernels::albedo_each_lane(job, |d, wo, mode| self.albedo_decoded(d, wo, mode));
        }
    }
}

/// A named parameter set for the verification harness: the defaults with `set`
/// overridden (enum choices by index).
#[derive(Clone, Copy, Debug)]
pub struct VerifyCase {
    pub name: &'static str,
    pub set: &'static [(&'static str, f32)],
}

/// The [`LobeType`] of a built-in [`Model`].
pub struct Builtin<M>(PhantomData<M>);

impl<M> Builtin<M> {
    pub const fn new() -> Self {
        Builtin(PhantomData)
    }
}

impl<M: Model> Default for Builtin<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: Model> LobeType for Builtin<M> {
    fn name(&self) -> &str {
        M::NAME
    }
    fn summary(&self) -> &str {
        M::SUMMARY
    }
    fn params(&self) -> &[ParamSpec] {
        M::PARAMS
    }
    fn flags(&self) -> u32 {
        M::FLAGS
    }
    fn reciprocal(&self) -> bool {
        M::RECIPROCAL
    }
    fn component_count(&self) -> u32 {
        M::COMPONENTS
    }
    fn eval(&self, params: &[f32], wo: Vec3<f32>, wi: Vec3<f32>, mode: Transport) -> Eval<f32> {
        self.eval_decoded(&decoded::<M>(params), wo, wi, mode)
    }
    fn eval_decoded_with_reverse(
        &self,
        decoded: &[f32],
        wo: Vec3<f32>,
        wi: Vec3<f32>,
        mode: Transport,
    ) -> (Eval<f32>, f32) {
        let p = M::prepare(Params::new(decoded));
        (M::eval(&p, wo, wi, mode), M::eval(&p, wi, wo, mode).pdf)
    }
    fn sample(&self, params: &[f32], wo: Vec3<f32>, u: [f32; 3], mode: Transport) -> Sample<f32> {
        self.sample_decoded(&decoded::<M>(params), wo, u, mode)
    }
    fn albedo(&self, params: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        self.albedo_decoded(&decoded::<M>(params), wo, mode)
    }
    fn decoded_len(&self) -> usize {
        M::DECODED_LEN
    }
    fn lane_decoded_len(&self) -> usize {
        M::LANE_DECODED_LEN
    }
    fn decode(&self, params: &[f32], out: &mut [f32]) {
        M::decode(params, out);
    }
    fn bake(&self, decoded: &mut [f32], wo: Vec3<f32>, mode: Transport) {
        M::bake(decoded, wo, mode);
    }
    fn decode_copies(&self) -> bool {
        M::DECODE_COPIES
    }
    fn decode_rows(&self, params: &[f32], out: &mut [f32], len: usize) {
        if M::DECODE_COPIES && params.len() == out.len() {
            out.copy_from_slice(params);
        } else {
            decode_rows(params, out, len, M::decode);
        }
    }
    fn eval_decoded(
        &self,
        decoded: &[f32],
        wo: Vec3<f32>,
        wi: Vec3<f32>,
        mode: Transport,
    ) -> Eval<f32> {
        M::eval(&M::prepare(Params::new(decoded)), wo, wi, mode)
    }
    fn sample_decoded(
        &self,
        decoded: &[f32],
        wo: Vec3<f32>,
        u: [f32; 3],
        mode: Transport,
    ) -> Sample<f32> {
        let p = M::prepare(Params::new(decoded));
        M::sample(&p, wo, u[0], u[1], u[2], mode, &mut InPlace).finish()
    }
    fn sample_world(
        &self,
        decoded: &[f32],
        frame: &Frame,
        wo: Vec3<f32>,
        u: [f32; 3],
        mode: Transport,
    ) -> Sample<f32> {
        let p = M::prepare(Params::new(decoded));
        let mut settle = ToWorld::new(LaneFrame::splat(frame));
        let mut s = M::sample(&p, frame.to_local(wo), u[0], u[1], u[2], mode, &mut settle);
        s.wi = settle.world;
        s.finish()
    }
    fn albedo_decoded(&self, decoded: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        M::albedo(&M::prepare(Params::new(decoded)), wo, mode)
    }
    fn verify_cases(&self) -> &[VerifyCase] {
        M::VERIFY_CASES
    }
    fn albedo_tolerance(&self, params: &[f32]) -> f32 {
        M::albedo_tolerance(params)
    }
    fn albedo_estimate_decoded(&self, decoded: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        M::albedo_estimate(&M::prepare(Params::new(decoded)), wo, mode)
    }
    fn albedo_estimate_tolerance(&self, params: &[f32]) -> f32 {
        M::albedo_estimate_tolerance(params)
    }
    fn energy_bound(&self, params: &[f32]) -> f32 {
        M::energy_bound(params)
    }
    fn has_kernels(&self) -> bool {
        true
    }
    fn model(&self) -> Option<std::any::TypeId> {
        Some(std::any::TypeId::of::<M>())
    }
    fn eval_lanes(&self, kernels: Kernels, job: &mut EvalJob<'_>) {
        kernels::eval::<M>(kernels, job);
    }
    fn sample_lanes(&self, kernels: Kernels, job: &mut SampleJob<'_>) {
        kernels::sample::<M>(kernels, job);
    }
    fn albedo_lanes(&self, kernels: Kernels, job: &mut AlbedoJob<'_>) {
        kernels::albedo::<M>(kernels, job);
    }
}

/// Most values a decoded parameter block holds (as the SIMD kernels' register file).
pub const MAX_DECODED_LEN: usize = kernels::MAX_LOBE_PARAMS;

/// `params` decoded into a stack block (its first `M::DECODED_LEN` values).
#[inline(always)]
fn decoded<M: Model>(params: &[f32]) -> DecodedBlock {
    let mut block = DecodedBlock([0.0; MAX_DECODED_LEN], M::DECODED_LEN);
    M::decode(params, &mut block.0[..M::DECODED_LEN]);
    block
}

/// `decode` of each lane's block in rows (see [`LobeType::decode_rows`]).
#[inline(always)]
fn decode_rows(params: &[f32], out: &mut [f32], len: usize, decode: impl Fn(&[f32], &mut [f32])) {
    let (size, decoded_size) = (params.len() / len, out.len() / len);
    let mut block = [0.0f32; MAX_DECODED_LEN];
    let mut decoded = [0.0f32; MAX_DECODED_LEN];
    for j in 0..len {
        for (p, v) in block[..size].iter_mut().enumerate() {
            *v = params[p * len + j];
        }
        decode(&block[..size], &mut decoded[..decoded_size]);
        for (p, &v) in decoded[..decoded_size].iter().enumerate() {
            out[p * len + j] = v;
        }
    }
}

/// A decoded block on the stack.
struct DecodedBlock([f32; MAX_DECODED_LEN], usize);

impl std::ops::Deref for DecodedBlock {
    type Target = [f32];
    fn deref(&self) -> &[f32] {
        &self.0[..self.1]
    }
}

/// `baked` (a value [`Model::bake`] computed at a `wo` whose key was `key`) where
/// every lane's `at` equals `key`, else `compute()`: a register of lanes either
/// reads the bake or computes, and an unbaked (NaN) key always computes.
#[inline(always)]
pub fn baked_or<L: Lane, T>(at: L, key: L, baked: T, compute: impl FnOnce() -> T) -> T {
    if at.eq(key).all() { baked } else { compute() }
}

/// Lanes where both directions are strictly above the surface.
#[inline(always)]
pub fn both_above<L: Lane>(wo: Vec3<L>, wi: Vec3<L>) -> L::Mask {
    wo.z.gt(L::zero()) & wi.z.gt(L::zero())
}

/// A sample where every lane failed.
#[inline(always)]
pub fn no_sample<L: Lane>() -> Sample<L> {
    Sample {
        wi: Vec3::new(L::zero(), L::zero(), L::zero()),
        value: Rgb::zero(),
        pdf: L::zero(),
        valid: L::Mask::splat(false),
        transmitted: L::Mask::splat(false),
        delta: L::Mask::splat(false),
        eta: L::one(),
        roughness: L::zero(),
        class: L::zero(),
        component: L::zero(),
    }
}
