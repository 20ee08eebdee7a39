//! Closures: weighted sets of lobes, each with its own shading frame, built in a
//! caller-owned [`Arena`] and immutable once finished.
//!
//! Lobe selection for sampling is proportional to `luminance(weight * albedo(wo))`,
//! with each lobe's albedo estimate (`Model::albedo_estimate`: the albedo, or a
//! cheaper estimate within a documented tolerance), computed once in [`Closure::finish`] from the `wo` given at creation (or, without
//! one, from normal incidence in each lobe's frame). `eval` and `pdf` return the
//! full mixture, so `pdf` is exactly the density `sample` draws from.

mod arena;

pub use arena::{Arena, Recycle};

use crate::error::{Error, Status};
use crate::kernels::mixture;
use crate::lobes::Transport;
use crate::math::{Frame, Rgb, Vec3};
use crate::params;
use crate::registry::{LobeRef, Registry};

/// Most lobes a closure holds (`GLINT_MAX_LOBES`).
pub const MAX_LOBES: usize = 16;
/// Most parameter values (floats) all lobes of one closure hold together.
pub const MAX_PARAM_VALUES: usize = 512;
/// Largest lobe weight component `add_lobe` (and so JSON) accepts. A closure sums at
/// most [`MAX_LOBES`] terms `weight * f |cos|`, so with this bound a closure's value
/// stays finite for every per-lobe value (weight 1) up to `f32::MAX / (16 * 1e16)`
/// = 2.1e21, fourteen orders of magnitude above the largest a built-in lobe returns
/// (a GGX peak at the delta threshold), and albedos (at most 1 per lobe) and selection
/// shares stay far from overflow.
pub const MAX_LOBE_WEIGHT: f32 = 1e16;

/// A lobe's (or a material entry's) RGB weight: finite, >= 0 and at most
/// [`MAX_LOBE_WEIGHT`] per component.
pub(crate) fn check_weight(owner: &str, weight: [f32; 3]) -> Result<(), Error> {
    if let Some(i) = weight.iter().position(|w| !w.is_finite() || *w < 0.0) {
        return Err(Error::new(
            Status::InvalidArgument,
            format!(
                "{owner}: weight[{i}] = {} must be finite and >= 0",
                weight[i]
            ),
        ));
    }
    if let Some(i) = weight.iter().position(|w| *w > MAX_LOBE_WEIGHT) {
        return Err(Error::new(
            Status::OutOfRange,
            format!(
                "{owner}: weight[{i}] = {:e} exceeds the largest lobe weight, {MAX_LOBE_WEIGHT:e}",
                weight[i]
            ),
        ));
    }
    Ok(())
}

/// One lobe of a closure; its blocks are ranges of the closure's `values`.
#[derive(Clone)]
pub struct LobeInstance {
    pub lobe: LobeRef,
    pub type_id: u32,
    pub weight: Rgb<f32>,
    pub frame: Frame,
    params_start: u16,
    params_len: u16,
    decoded_start: u16,
    decoded_len: u16,
    /// Probability of choosing this lobe when sampling.
    pub probability: f32,
}

/// Value (cosine included), pdf and reverse pdf of a pair of directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalResult {
    pub value: Rgb<f32>,
    pub pdf: f32,
    /// `pdf(wi -> wo)`, for bidirectional hosts.
    pub pdf_reverse: f32,
}

/// A sampled direction and what comes with it (DESIGN.md, "Conventions").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleResult {
    pub wi: Vec3<f32>,
    pub value: Rgb<f32>,
    pub pdf: f32,
    pub weight: Rgb<f32>,
    /// `GLINT_FLAG_*`: the side and the sample's class.
    pub flags: u32,
    pub lobe: u32,
    /// The component (sub-lobe) of the sampled lobe ([`crate::lobes::Sample`]).
    pub component: u32,
    pub eta: f32,
    pub roughness: f32,
}

impl SampleResult {
    /// A failed sample as batches report it: every output zero, `eta` 1, as
    /// `kernels::mixture::finish` leaves failed lanes.
    pub const FAILED: SampleResult = SampleResult {
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
        component: 0,
        eta: 1.0,
        roughness: 0.0,
    };
}

/// A weighted set of lobes, sized to what it holds: the lobes and their blocks live
/// in two vectors whose storage an arena slot keeps across resets ([`Recycle`]).
#[derive(Clone)]
pub struct Closure {
    lobes: Vec<LobeInstance>,
    /// Each lobe's raw parameter block followed by the same block decoded once
    /// (`LobeType::decode`), as every call reads it.
    values: Vec<f32>,
    /// Raw values held, bounded by [`MAX_PARAM_VALUES`]. That bounds the decoded
    /// values too: a plugin's decoded block is its raw block, and a built-in type's is
    /// at most `MAX_DECODED_LEN` per lobe.
    params_len: usize,
    /// A hash of the shape ([`Self::same_shape`]), fixed by `finish`.
    shape_id: u64,
    wo: Option<Vec3<f32>>,
    mode: Transport,
    finished: bool,
}

impl Closure {
    /// An empty closure; `wo` (unit, world space) fixes view-dependent choices.
    pub fn new(wo: Option<Vec3<f32>>, mode: Transport) -> Closure {
        Closure {
            lobes: Vec::new(),
            values: Vec::new(),
            params_len: 0,
            shape_id: 0,
            wo,
            mode,
            finished: false,
        }
    }

    /// Make this an empty closure as [`Closure::new`] does, keeping the storage.
    pub fn restart(&mut self, wo: Option<Vec3<f32>>, mode: Transport) {
        self.recycle();
        self.wo = wo;
        self.mode = mode;
    }

    /// The `wo` (unit, world space) given at creation, if any.
    pub fn view(&self) -> Option<Vec3<f32>> {
        self.wo
    }

    pub fn transport(&self) -> Transport {
        self.mode
    }

    pub fn is_finished(&self) -> bool {
        self.finished
    }

    pub fn lobes(&self) -> &[LobeInstance] {
        &self.lobes
    }

    fn lobe_count(&self) -> usize {
        self.lobes.len()
    }

    /// Whether `other` has the same lobe types (the same registered objects, whatever
    /// runtime they come from) in the same order, the same enumerated
    /// choices and the same transport: lanes of such closures share batch kernels.
    pub fn same_shape(&self, other: &Closure) -> bool {
        self.shape_id == other.shape_id
            && self.lobes.len() == other.lobes.len()
            && self.mode == other.mode
            && (0..self.lobe_count()).all(|k| {
                let (a, b) = (&self.lobes[k], &other.lobes[k]);
                same_lobe_type(a, b)
                    && params::same_choices(
                        a.lobe.params(),
                        self.lobe_params(k),
                        other.lobe_params(k),
                    )
            })
    }

    /// A hash of the closure's shape, equal for closures of the same shape (set by
    /// `finish`): batches look shapes up by it, then confirm with `same_shape`.
    pub fn shape_id(&self) -> u64 {
        self.shape_id
    }

    /// The decoded parameter block of lobe `index`, as the `*_decoded` calls and the
    /// batch kernels read it.
    pub fn lobe_decoded(&self, index: usize) -> &[f32] {
        let l = &self.lobes[index];
        let start = l.decoded_start as usize;
        &self.values[start..start + l.decoded_len as usize]
    }

    /// The parameter block of lobe `index`.
    pub fn lobe_params(&self, index: usize) -> &[f32] {
        let l = &self.lobes[index];
        let start = l.params_start as usize;
        &self.values[start..start + l.params_len as usize]
    }

    /// Add a lobe of type `type_id`. `params` is a full block laid out by the type's
    /// schema, or `None` for the defaults. Returns the lobe's index.
    pub fn add_lobe(
        &mut self,
        registry: &Registry,
        type_id: u32,
        weight: [f32; 3],
        frame: Frame,
        params: Option<&[f32]>,
    ) -> Result<usize, Error> {
        if self.finished {
            return Err(Error::new(
                Status::InvalidState,
                "the closure is finished; lobes can only be added before glint_closure_finish",
            ));
        }
        let lobe = registry.get(type_id)?;
        check_weight(lobe.name(), weight)?;
        if let Some(values) = params {
            registry.validate_block(type_id, values)?;
        }
        self.push_lobe(
            lobe,
            type_id,
            Rgb::new(weight[0], weight[1], weight[2]),
            frame,
            params,
        )
    }

    /// Add a lobe whose weight and block are known to be valid (a material's
    /// expansion): only the closure's capacity and memory are checked.
    pub(crate) fn push_lobe(
        &mut self,
        lobe: &LobeRef,
        type_id: u32,
        weight: Rgb<f32>,
        frame: Frame,
        params: Option<&[f32]>,
    ) -> Result<usize, Error> {
        let size = params::block_size(lobe.params());
        let decoded_size = lobe.decoded_len();
        self.make_room(size, decoded_size)?;
        let start = self.values.len();
        self.values.resize(start + size + decoded_size, 0.0);
        let (block, decoded) = self.values[start..].split_at_mut(size);
        match params {
            Some(values) => block.copy_from_slice(values),
            None => params::write_defaults(lobe.params(), block),
        }
        lobe.decode(block, decoded);
        if let Some(wo) = self.wo {
            lobe.bake(decoded, frame.to_local(wo), self.mode);
        }
        Ok(self.record_lobe(lobe, type_id, weight, frame, start, size, decoded_size))
    }

    /// [`Self::push_lobe`] of a block already decoded (and baked at the closure's `wo`):
    /// a material decodes its slots to prune them before adding them.
    #[inline(always)]
    pub(crate) fn push_decoded(
        &mut self,
        lobe: &LobeRef,
        type_id: u32,
        weight: Rgb<f32>,
        frame: Frame,
        block: &[f32],
        decoded: &[f32],
    ) -> Result<usize, Error> {
        self.make_room(block.len(), decoded.len())?;
        let start = self.values.len();
        self.values.extend_from_slice(block);
        self.values.extend_from_slice(decoded);
        Ok(self.record_lobe(
            lobe,
            type_id,
            weight,
            frame,
            start,
            block.len(),
            decoded.len(),
        ))
    }

    /// Room for one more lobe whose raw and decoded blocks take `size` and
    /// `decoded_size` values.
    #[inline(always)]
    fn make_room(&mut self, size: usize, decoded_size: usize) -> Result<(), Error> {
        if self.lobe_count() == MAX_LOBES {
            return Err(Error::new(
                Status::ClosureFull,
                format!("a closure holds at most {MAX_LOBES} lobes"),
            ));
        }
        if self.params_len + size > MAX_PARAM_VALUES {
            return Err(Error::new(
                Status::ClosureFull,
                format!("the closure's lobes hold at most {MAX_PARAM_VALUES} parameter values"),
            ));
        }
        self.lobes.try_reserve(1).map_err(|_| out_of_memory())?;
        self.values
            .try_reserve(size + decoded_size)
            .map_err(|_| out_of_memory())
    }

    /// The lobe whose blocks were appended at `start`; returns its index.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn record_lobe(
        &mut self,
        lobe: &LobeRef,
        type_id: u32,
        weight: Rgb<f32>,
        frame: Frame,
        start: usize,
        size: usize,
        decoded_size: usize,
    ) -> usize {
        // `make_room` reserved the place. A push the compiler sees within capacity
        // writes the record in place; one that may grow built it on the stack and
        // copied it, reading narrow stores back as wide loads (a store-forwarding
        // stall per lobe: 14 ns of a Disney closure). The type is cloned first: a
        // plugin's reference count is an atomic the capacity check must follow.
        let lobe = lobe.clone();
        if self.lobes.len() < self.lobes.capacity() {
            self.lobes.push(LobeInstance {
                lobe,
                type_id,
                weight,
                frame,
                params_start: start as u16,
                params_len: size as u16,
                decoded_start: (start + size) as u16,
                decoded_len: decoded_size as u16,
                probability: 0.0,
            });
        } else {
            unreachable!("make_room reserves a lobe's place");
        }
        self.params_len += size;
        self.lobe_count() - 1
    }

    /// Fix the lobe selection probabilities; the closure is immutable afterwards.
    pub fn finish(&mut self) -> Result<(), Error> {
        let n = self.lobe_count();
        let mut shares = [0.0f32; MAX_LOBES];
        // One lobe is chosen with probability 1 whatever its albedo.
        if n > 1 && !self.finished {
            for (k, l) in self.lobes().iter().enumerate() {
                let wo = self
                    .wo
                    .map_or(Vec3::splat(0.0, 0.0, 1.0), |w| l.frame.to_local(w));
                let albedo = l
                    .lobe
                    .albedo_estimate_decoded(self.lobe_decoded(k), wo, self.mode);
                shares[k] = (l.weight * albedo).luminance();
            }
        }
        self.finish_with_shares(&mut shares[..n], None)
    }

    /// [`Self::finish`] with each lobe's `luminance(weight * albedo(wo))` (albedo
    /// estimates) already known (a material computes them to prune its lobes), and
    /// the shape id when known (a material's, per set of emitted slots).
    pub(crate) fn finish_with_shares(
        &mut self,
        shares: &mut [f32],
        shape_id: Option<u64>,
    ) -> Result<(), Error> {
        if self.finished {
            return Err(Error::new(
                Status::InvalidState,
                "the closure is already finished",
            ));
        }
        select(shares, |k| self.lobes[k].weight.luminance());
        for (lobe, &p) in self.lobes.iter_mut().zip(shares.iter()) {
            lobe.probability = p;
        }
        self.shape_id = shape_id.unwrap_or_else(|| self.hash_shape());
        debug_assert_eq!(self.shape_id, self.hash_shape());
        self.finished = true;
        Ok(())
    }

    /// What `same_shape` compares, hashed: lobe type identities, enumerated choices,
    /// transport.
    fn hash_shape(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = ShapeHasher::default();
        (self.lobe_count(), self.mode == Transport::Radiance).hash(&mut h);
        for (k, l) in self.lobes().iter().enumerate() {
            let identity = &*l.lobe as *const dyn crate::lobes::LobeType as *const () as usize;
            (l.type_id, identity).hash(&mut h);
            let specs = l.lobe.params();
            params::for_each_choice(specs, self.lobe_params(k), |c| c.hash(&mut h));
        }
        h.finish()
    }

    pub(crate) fn check_finished(&self) -> Result<(), Error> {
        if self.finished {
            Ok(())
        } else {
            Err(Error::new(
                Status::InvalidState,
                "the closure is not finished; call glint_closure_finish first",
            ))
        }
    }

    fn check_lobe(&self, index: usize) -> Result<&LobeInstance, Error> {
        self.check_finished()?;
        self.lobes().get(index).ok_or_else(|| {
            Error::new(
                Status::OutOfRange,
                format!(
                    "lobe index {index} is out of range: the closure has {} lobes",
                    self.lobe_count()
                ),
            )
        })
    }

    /// `weight * f * |cos|` and the unconditional pdf of one lobe.
    fn eval_one(&self, k: usize, wo: Vec3<f32>, wi: Vec3<f32>) -> (Rgb<f32>, f32) {
        let l = &self.lobes[k];
        let e = l.lobe.eval_decoded(
            self.lobe_decoded(k),
            l.frame.to_local(wo),
            l.frame.to_local(wi),
            self.mode,
        );
        (l.weight * e.value, e.pdf)
    }

    /// [`Self::eval_one`] and, with `reverse`, lobe `k`'s reverse pdf (else 0).
    fn eval_one_with(&self, k: usize, wo: Vec3<f32>, wi: Vec3<f32>, reverse: bool) -> EvalResult {
        if !reverse {
            let (value, pdf) = self.eval_one(k, wo, wi);
            return EvalResult {
                value,
                pdf,
                pdf_reverse: 0.0,
            };
        }
        let l = &self.lobes[k];
        let (e, pdf_reverse) = l.lobe.eval_decoded_with_reverse(
            self.lobe_decoded(k),
            l.frame.to_local(wo),
            l.frame.to_local(wi),
            self.mode,
        );
        EvalResult {
            value: l.weight * e.value,
            pdf: e.pdf,
            pdf_reverse,
        }
    }

    fn mixture(&self, wo: Vec3<f32>, wi: Vec3<f32>) -> (Rgb<f32>, f32) {
        let mut value = Rgb::zero();
        let mut pdf = 0.0;
        for k in 0..self.lobe_count() {
            let (v, p) = self.eval_one(k, wo, wi);
            value = value + v;
            pdf += self.lobes[k].probability * p;
        }
        (value, pdf)
    }

    fn mixture_pdf(&self, wo: Vec3<f32>, wi: Vec3<f32>) -> f32 {
        self.mixture(wo, wi).1
    }

    /// The whole closure at `(wo, wi)` (unit vectors, world space), with the reverse
    /// pdf (each lobe is evaluated twice).
    pub fn eval(&self, wo: Vec3<f32>, wi: Vec3<f32>) -> Result<EvalResult, Error> {
        self.eval_with(wo, wi, true)
    }

    /// [`Self::eval`] without the reverse pdf (`pdf_reverse` is 0): one evaluation
    /// per lobe, for unidirectional hosts.
    pub fn eval_forward(&self, wo: Vec3<f32>, wi: Vec3<f32>) -> Result<EvalResult, Error> {
        self.eval_with(wo, wi, false)
    }

    /// [`Self::eval`] (`reverse`) or [`Self::eval_forward`].
    #[inline]
    pub fn eval_with(
        &self,
        wo: Vec3<f32>,
        wi: Vec3<f32>,
        reverse: bool,
    ) -> Result<EvalResult, Error> {
        self.check_finished()?;
        let mut sum = EvalResult {
            value: Rgb::zero(),
            pdf: 0.0,
            pdf_reverse: 0.0,
        };
        for (k, l) in self.lobes().iter().enumerate() {
            let e = self.eval_one_with(k, wo, wi, reverse);
            sum.value = sum.value + e.value;
            sum.pdf += l.probability * e.pdf;
            sum.pdf_reverse += l.probability * e.pdf_reverse;
        }
        Ok(sum)
    }

    /// The mixture pdf of sampling `wi` from `wo`.
    pub fn pdf(&self, wo: Vec3<f32>, wi: Vec3<f32>) -> Result<f32, Error> {
        self.check_finished()?;
        Ok(self.mixture_pdf(wo, wi))
    }

    /// Directional albedo: the sum of each lobe's `weight * albedo(wo)`.
    pub fn albedo(&self, wo: Vec3<f32>) -> Result<Rgb<f32>, Error> {
        self.check_finished()?;
        Ok(self
            .lobes()
            .iter()
            .enumerate()
            .fold(Rgb::zero(), |acc, (k, l)| {
                acc + l.weight
                    * l.lobe
                        .albedo_decoded(self.lobe_decoded(k), l.frame.to_local(wo), self.mode)
            }))
    }

    /// Sample the closure: choose a lobe with `u[0]`, then a direction with the rest.
    pub fn sample(&self, wo: Vec3<f32>, u: [f32; 3]) -> Result<SampleResult, Error> {
        self.check_finished()?;
        check_randoms(u)?;
        let (chosen, u_reused) = self.choose_lobe(u[0]).ok_or_else(no_sample)?;
        let probability = self.lobes[chosen].probability;
        let [_, u0, u1] = clamp_randoms(u);
        self.sample_from(chosen, wo, [u_reused, u0, u1], Some(probability))
    }

    /// The lobe `u_lobe` selects and `u_lobe` rescaled to [0, 1) within its bin, or
    /// `None` when no lobe can be chosen ([`mixture::choose`]).
    pub(crate) fn choose_lobe(&self, u_lobe: f32) -> Option<(usize, f32)> {
        let mut probabilities = [0.0f32; MAX_LOBES];
        for (p, l) in probabilities.iter_mut().zip(self.lobes()) {
            *p = l.probability;
        }
        mixture::choose(&probabilities[..self.lobe_count()], u_lobe).map(|(k, u)| (k as usize, u))
    }

    /// Sample lobe `index` alone: value is `weight * f |cos|`, pdf that lobe's own.
    pub fn sample_lobe(
        &self,
        index: usize,
        wo: Vec3<f32>,
        u: [f32; 3],
    ) -> Result<SampleResult, Error> {
        self.check_lobe(index)?;
        check_randoms(u)?;
        self.sample_from(index, wo, clamp_randoms(u), None)
    }

    /// Sample lobe `k`; with `mixture = Some(p_k)` the result describes the whole
    /// closure (mixture value and pdf), else the lobe alone.
    fn sample_from(
        &self,
        k: usize,
        wo: Vec3<f32>,
        u: [f32; 3],
        mixture: Option<f32>,
    ) -> Result<SampleResult, Error> {
        let l = &self.lobes[k];
        // The lobe's value and pdf are its eval at exactly the returned world-space
        // `wi` (`LobeType::sample_world`); the other lobes are evaluated there.
        let s = l
            .lobe
            .sample_world(self.lobe_decoded(k), &l.frame, wo, u, self.mode);
        if !s.valid {
            return Err(no_sample());
        }
        let wi = s.wi;
        // The other lobes see `wi` as an eval given it sees it, normalized once more
        // (the chosen lobe's value is settled there): a narrow lobe turns that last
        // bit into a relative 1e-4 at alpha 0.001.
        let wi_eval = wi.unit_from(wi.length_squared());
        let own = (l.weight * s.value, s.pdf);
        let (value, pdf) = match mixture {
            // Summed in lobe order, as `eval` sums them.
            Some(p) => mixture::sampled(s.delta, own, p, || {
                (0..self.lobe_count()).fold((Rgb::zero(), 0.0), |(value, pdf), j| {
                    let (v, q) = if j == k {
                        own
                    } else {
                        self.eval_one(j, wo, wi_eval)
                    };
                    (value + v, pdf + self.lobes[j].probability * q)
                })
            }),
            None => own,
        };
        let c = mixture::finish(&s, value, pdf);
        if !c.ok {
            return Err(no_sample());
        }
        Ok(SampleResult {
            wi,
            value,
            pdf,
            weight: c.weight,
            flags: mixture::flags(&c)[0],
            lobe: k as u32,
            component: mixture::components(&c)[0],
            eta: s.eta,
            roughness: s.roughness,
        })
    }

    /// Lobe `index` alone at `(wo, wi)`: `weight * f |cos|`, its own pdf and reverse pdf.
    pub fn eval_lobe(
        &self,
        index: usize,
        wo: Vec3<f32>,
        wi: Vec3<f32>,
    ) -> Result<EvalResult, Error> {
        self.check_lobe(index)?;
        Ok(self.eval_one_with(index, wo, wi, true))
    }

    /// [`Self::eval_lobe`] without the reverse pdf (`pdf_reverse` is 0).
    pub fn eval_lobe_forward(
        &self,
        index: usize,
        wo: Vec3<f32>,
        wi: Vec3<f32>,
    ) -> Result<EvalResult, Error> {
        self.check_lobe(index)?;
        Ok(self.eval_one_with(index, wo, wi, false))
    }

    /// The pdf of lobe `index` alone.
    pub fn pdf_lobe(&self, index: usize, wo: Vec3<f32>, wi: Vec3<f32>) -> Result<f32, Error> {
        self.check_lobe(index)?;
        Ok(self.eval_one(index, wo, wi).1)
    }

    /// `weight * albedo(wo)` of lobe `index`.
    pub fn albedo_lobe(&self, index: usize, wo: Vec3<f32>) -> Result<Rgb<f32>, Error> {
        let l = self.check_lobe(index)?;
        Ok(l.weight
            * l.lobe
                .albedo_decoded(self.lobe_decoded(index), l.frame.to_local(wo), self.mode))
    }
}

impl Recycle for Closure {
    fn recycle(&mut self) {
        self.lobes.clear();
        self.values.clear();
        self.params_len = 0;
        self.shape_id = 0;
        self.finished = false;
    }

    fn free_storage(&mut self) {
        self.recycle();
        self.lobes = Vec::new();
        self.values = Vec::new();
    }
}

/// The hasher of shape ids: a few words per lobe, hashed at every `finish`, where
/// SipHash's setup and rounds cost more than the rest of the hash. Multiply-rotate
/// mixing (as FxHash) spreads the words well enough for a lookup table that confirms
/// every hit with `same_shape`.
#[derive(Default)]
struct ShapeHasher(u64);

impl std::hash::Hasher for ShapeHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }

    fn write_u32(&mut self, x: u32) {
        self.write_u64(u64::from(x));
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

fn out_of_memory() -> Error {
    Error::new(
        Status::OutOfMemory,
        "out of memory: the closure's storage could not grow",
    )
}

/// Whether two lobes are of the same registered type. The type id alone is not enough:
/// two runtimes give different plugin lobes the same id (and may give them one name).
/// Each plugin lobe is its own object, so the data pointer tells them apart; built-in
/// types may be zero-sized (one address for all), but their ids differ in every registry.
fn same_lobe_type(a: &LobeInstance, b: &LobeInstance) -> bool {
    a.type_id == b.type_id
        && std::ptr::addr_eq(&*a.lobe as *const dyn crate::lobes::LobeType, &*b.lobe)
}

/// Selection probabilities of lobes whose `luminance(weight * albedo(wo))` are `shares`
/// (one per lobe), in place: proportional to them; a single lobe is chosen with
/// probability 1; without any reflecting lobe, proportional to `weight_luminance(k)`,
/// then uniform. (In place: a returned array of every possible lobe went through the
/// stack, about 10 ns of a closure's build.)
pub(crate) fn select(shares: &mut [f32], weight_luminance: impl Fn(usize) -> f32) {
    if let [only] = shares {
        *only = 1.0;
        return;
    }
    let mut sum = 0.0;
    for s in shares.iter_mut() {
        *s = s.max(0.0);
        sum += *s;
    }
    if sum <= 0.0 {
        sum = 0.0;
        for (k, s) in shares.iter_mut().enumerate() {
            *s = weight_luminance(k).max(0.0);
            sum += *s;
        }
    }
    if sum <= 0.0 {
        shares.fill(1.0);
    }
    normalize_shares(shares);
}

/// Scale `shares` (finite, >= 0, not all 0) into probabilities proportional to them:
/// times the reciprocal of their sum (summed in order), one division. Where the sum or
/// its reciprocal is not finite (shares near the largest or the smallest floats) they
/// are divided by the largest first, then by their sum.
fn normalize_shares(shares: &mut [f32]) {
    let total = shares.iter().fold(0.0f32, |t, &s| t + s);
    let inv = 1.0 / total;
    if total.is_finite() && inv.is_finite() {
        for p in shares.iter_mut() {
            *p *= inv;
        }
        return;
    }
    let largest = shares.iter().fold(0.0f32, |m, &s| m.max(s));
    let mut total = 0.0f32;
    for p in shares.iter_mut() {
        *p /= largest;
        total += *p;
    }
    for p in shares.iter_mut() {
        *p /= total;
    }
}

pub(crate) use mixture::ONE_MINUS_EPSILON;

/// Random numbers clamped into [0, 1), as every sampling routine expects.
pub(crate) fn clamp_randoms(u: [f32; 3]) -> [f32; 3] {
    u.map(mixture::clamp_random)
}

/// Random numbers must be finite (they are clamped into [0, 1)).
pub(crate) fn check_randoms(u: [f32; 3]) -> Result<(), Error> {
    match u.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(Error::new(
            Status::InvalidArgument,
            format!("random number {i} ({}) is not finite", u[i]),
        )),
        None => Ok(()),
    }
}

fn no_sample() -> Error {
    Error::new(
        Status::NoSample,
        "no sample: the closure cannot scatter from this direction",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_near_the_smallest_float_normalize_without_overflow() {
        // Their sum's reciprocal overflows: the fallback divides by the largest.
        let mut p = [1e-44, 3e-44, 0.0];
        normalize_shares(&mut p);
        assert!(p.iter().all(|p| p.is_finite()), "{p:?}");
        assert!((p[1] / p[0] - 3.0).abs() < 0.2 && p[2] == 0.0, "{p:?}");
        assert!((p.iter().sum::<f32>() - 1.0).abs() <= 1e-6, "{p:?}");
    }

    #[test]
    fn shares_near_the_largest_float_normalize_without_overflow() {
        let mut p = [3e38, 3e38, 0.0, f32::MAX];
        normalize_shares(&mut p);
        let share = 3e38 / f32::MAX;
        let expected = share / (2.0 * share + 1.0);
        assert!((p[0] - expected).abs() <= 1e-6 && p[0] == p[1], "{p:?}");
        assert_eq!(p[2], 0.0);
        assert!((p.iter().sum::<f32>() - 1.0).abs() <= 1e-6, "{p:?}");
    }
}
