//! Closures of built-in lobes evaluated in one pass. A batch over one shared closure
//! whose lobes share a frame (a material's) otherwise takes the directions into the
//! frame once and then runs each lobe's kernel over the chunk, each reading the local
//! directions and adding into the outputs. When the closure's lobe types, in order,
//! are one of the [`SHAPES`], one kernel instantiated for those models does it all per
//! register: the directions are normalized and taken into the frame in registers,
//! every lobe is evaluated on them (LLVM merges what the lobes compute alike, such as
//! the half vector) and the sums are stored once. The arithmetic is the unfused
//! path's, operation for operation, so the outputs are the same bits.

use super::{Directions, MAX_LOBE_PARAMS, direction, store};
use crate::closure::Closure;
use crate::lobes::disney_clearcoat::DisneyClearcoat;
use crate::lobes::disney_diffuse::DisneyDiffuse;
use crate::lobes::disney_sheen::DisneySheen;
use crate::lobes::disney_specular::DisneySpecular;
use crate::lobes::{Model, Params, Transport};
use crate::math::{Frame, Lane, LaneFrame, Rgb, Vec3};
use crate::simd::{Kernels, kernel};
use std::any::TypeId;

/// Most lobes of a fused shape.
const MAX_FUSED: usize = 4;

/// One lobe of a fused job: its decoded block, weight and selection probability.
#[derive(Clone, Copy)]
pub struct FusedLobe<'a> {
    pub params: &'a [f32],
    pub weight: Rgb<f32>,
    pub probability: f32,
}

/// A fused eval over the caller's raw direction rows (normalized as
/// [`Directions::Raw`] normalizes them).
pub struct FusedEvalJob<'a> {
    pub mode: Transport,
    pub frame: Frame,
    pub wo: [&'a [f32]; 3],
    pub wi: [&'a [f32]; 3],
    /// The closure's lobes in order (as many as the shape has; the rest unused).
    pub lobes: [FusedLobe<'a>; MAX_FUSED],
    /// `sum weight_k f_k cos` (when wanted) and `sum p_k pdf_k`, one per lane.
    pub value: Option<[&'a mut [f32]; 3]>,
    pub pdf: &'a mut [f32],
}

/// A tuple of lobe models evaluated together.
pub trait Shape: 'static {
    type Prepared<L: Lane>;
    /// Whether `models` are this shape's models, in order.
    fn matches(models: &[Option<TypeId>]) -> bool;
    fn prepare<L: Lane>(lobes: &[FusedLobe<'_>; MAX_FUSED]) -> Self::Prepared<L>;
    /// `(sum weight_k f_k, sum p_k pdf_k)` in lobe order at `(wo, wi)`. Without `own`
    /// as an eval sums (from the first lobe's terms, as lobe kernels store then add);
    /// with `own = (k, value, p pdf)`, a mixture at lobe `k`'s sample, whose own terms
    /// stand for lobe `k`'s, summed from zero as a mixture sample's rows are.
    fn sum<L: Lane>(
        p: &Self::Prepared<L>,
        lobes: &[FusedLobe<'_>; MAX_FUSED],
        own: Option<(usize, Rgb<L>, L)>,
        wo: Vec3<L>,
        wi: Vec3<L>,
        mode: Transport,
    ) -> (Rgb<L>, L);
}

/// `weight f` and `p pdf` of one lobe, as the eval kernel computes them.
#[inline(always)]
fn weighted<M: Model, L: Lane>(
    p: &M::Prepared<L>,
    lobe: &FusedLobe<'_>,
    wo: Vec3<L>,
    wi: Vec3<L>,
    mode: Transport,
) -> (Rgb<L>, L) {
    let e = M::eval(p, wo, wi, mode);
    let w = lobe.weight;
    let weight = Rgb::new(L::splat(w.r), L::splat(w.g), L::splat(w.b));
    (weight * e.value, L::splat(lobe.probability) * e.pdf)
}

macro_rules! shape {
    ($first:ident $(, $m:ident)*) => {
        impl<$first: Model $(, $m: Model)*> Shape for ($first, $($m,)*) {
            type Prepared<L: Lane> = ($first::Prepared<L>, $($m::Prepared<L>,)*);
            fn matches(models: &[Option<TypeId>]) -> bool {
                let shape = [TypeId::of::<$first>() $(, TypeId::of::<$m>())*];
                models.len() == shape.len()
                    && models.iter().zip(shape).all(|(m, s)| *m == Some(s))
            }
            #[inline(always)]
            fn prepare<L: Lane>(lobes: &[FusedLobe<'_>; MAX_FUSED]) -> Self::Prepared<L> {
                let first = $first::prepare(Params::shared(lobes[0].params));
                let mut k = 0;
                (first, $({
                    k += 1;
                    $m::prepare(Params::shared(lobes[k].params))
                },)*)
            }
            #[inline(always)]
            #[allow(non_snake_case)]
            fn sum<L: Lane>(
                p: &Self::Prepared<L>,
                lobes: &[FusedLobe<'_>; MAX_FUSED],
                own: Option<(usize, Rgb<L>, L)>,
                wo: Vec3<L>,
                wi: Vec3<L>,
                mode: Transport,
            ) -> (Rgb<L>, L) {
                let ($first, $($m,)*) = p;
                let (v, q) = match own {
                    Some((0, v, q)) => (v, q),
                    _ => weighted::<$first, L>($first, &lobes[0], wo, wi, mode),
                };
                let (mut value, mut pdf) = match own {
                    Some(_) => (Rgb::zero() + v, L::zero() + q),
                    None => (v, q),
                };
                let mut k = 0;
                $(
                    k += 1;
                    let (v, q) = match own {
                        Some((o, v, q)) if o == k => (v, q),
                        _ => weighted::<$m, L>($m, &lobes[k], wo, wi, mode),
                    };
                    value = value + v;
                    pdf += q;
                )*
                (value, pdf)
            }
        }
    };
}

shape!(A, B);
shape!(A, B, C);
shape!(A, B, C, D);

#[inline(always)]
fn eval_body<S: Shape, L: Lane>(job: &mut FusedEvalJob<'_>) -> bool {
    let len = job.pdf.len();
    let p = S::prepare::<L>(&job.lobes);
    let frame = LaneFrame::<L>::splat(&job.frame);
    let mut out_of_range = false;
    for i in (0..len).step_by(L::LANES) {
        let n = L::LANES.min(len - i);
        let wo = direction(job.wo, i, n, Directions::Raw, &mut out_of_range);
        let wi = direction(job.wi, i, n, Directions::Raw, &mut out_of_range);
        if out_of_range {
            return false;
        }
        let (value, pdf) = S::sum(
            &p,
            &job.lobes,
            None,
            frame.to_local(wo),
            frame.to_local(wi),
            job.mode,
        );
        if let Some(rows) = &mut job.value {
            for (v, row) in value.to_array().into_iter().zip(rows.iter_mut()) {
                store(v, row, i, n);
            }
        }
        store(pdf, job.pdf, i, n);
    }
    true
}

/// A mixture sample's sums over a chunk sorted by chosen lobe: lobe `k`'s samples
/// in rows `starts[k]..starts[k + 1]` (whole registers).
pub struct FusedMixtureJob<'a> {
    pub mode: Transport,
    pub frame: Frame,
    /// The closure's lobes in order (as [`FusedEvalJob::lobes`]).
    pub lobes: [FusedLobe<'a>; MAX_FUSED],
    pub starts: &'a [usize],
    /// Unit `wo` and the sampled `wi` (normalized once more, as an eval given it back
    /// would: [`Directions::Sampled`]), world space.
    pub wo: [&'a [f32]; 3],
    pub wi: [&'a [f32]; 3],
    /// Each row's own sample: weighted value and pdf (not yet times `p`).
    pub own_value: [&'a [f32]; 3],
    pub own_pdf: &'a [f32],
    /// The mixture's value and `sum p_k pdf_k`.
    pub value: [&'a mut [f32]; 3],
    pub pdf: &'a mut [f32],
}

#[inline(always)]
fn mixture_body<S: Shape, L: Lane>(job: &mut FusedMixtureJob<'_>) {
    let p = S::prepare::<L>(&job.lobes);
    let frame = LaneFrame::<L>::splat(&job.frame);
    let mut unused = false;
    for (own, run) in job.starts.windows(2).enumerate() {
        let probability = L::splat(job.lobes[own].probability);
        for i in (run[0]..run[1]).step_by(L::LANES) {
            let wo = direction(job.wo, i, L::LANES, Directions::Unit, &mut unused);
            let wi = direction(job.wi, i, L::LANES, Directions::Sampled, &mut unused);
            let own_value = Rgb::new(
                L::load(&job.own_value[0][i..]),
                L::load(&job.own_value[1][i..]),
                L::load(&job.own_value[2][i..]),
            );
            let own_pdf = probability * L::load(&job.own_pdf[i..]);
            let (value, pdf) = S::sum(
                &p,
                &job.lobes,
                Some((own, own_value, own_pdf)),
                frame.to_local(wo),
                frame.to_local(wi),
                job.mode,
            );
            for (v, row) in value.to_array().into_iter().zip(job.value.iter_mut()) {
                v.store(&mut row[i..]);
            }
            pdf.store(&mut job.pdf[i..]);
        }
    }
}

kernel!(
    /// A fused shape's eval over a job's lanes (`eval_body`); false when some
    /// direction is outside [`Directions::Raw`]'s range (outputs incomplete).
    eval<S: Shape>(job: &mut FusedEvalJob<'_>) -> bool => eval_body
);
kernel!(
    /// A fused shape's mixture sums over a sorted sample chunk (`mixture_body`).
    mixture<S: Shape>(job: &mut FusedMixtureJob<'_>) => mixture_body
);

/// A fused eval kernel.
pub type FusedEval = fn(Kernels, &mut FusedEvalJob<'_>) -> bool;
/// A fused mixture kernel.
pub type FusedMixture = fn(Kernels, &mut FusedMixtureJob<'_>);
/// [`Shape::matches`] of a shape.
type Matches = fn(&[Option<TypeId>]) -> bool;

/// The fused shapes: those the `disney` material emits (its specular always, the
/// diffuse unless metallic 1, the sheen with the diffuse, the clearcoat unless 0).
type Diffuse = DisneyDiffuse;
type Sheen = DisneySheen;
type Specular = DisneySpecular;
type Clearcoat = DisneyClearcoat;
type Every = (Diffuse, Sheen, Specular, Clearcoat);
type NoClearcoat = (Diffuse, Sheen, Specular);
type NoSheen = (Diffuse, Specular, Clearcoat);
type Plastic = (Diffuse, Specular);
type Metal = (Specular, Clearcoat);
const SHAPES: [(Matches, FusedEval, FusedMixture); 5] = [
    (Every::matches, eval::<Every>, mixture::<Every>),
    (
        NoClearcoat::matches,
        eval::<NoClearcoat>,
        mixture::<NoClearcoat>,
    ),
    (NoSheen::matches, eval::<NoSheen>, mixture::<NoSheen>),
    (Plastic::matches, eval::<Plastic>, mixture::<Plastic>),
    (Metal::matches, eval::<Metal>, mixture::<Metal>),
];

/// The fused kernels of a closure's shape, and its lobes as their jobs take them.
pub struct Fused<'a> {
    pub eval: FusedEval,
    pub mixture: FusedMixture,
    pub lobes: [FusedLobe<'a>; MAX_FUSED],
}

/// The fused kernels of `closure`'s shape, when there are.
pub fn for_closure(closure: &Closure) -> Option<Fused<'_>> {
    let lobes = closure.lobes();
    if lobes.len() < 2 || lobes.len() > MAX_FUSED {
        return None;
    }
    let mut models = [None; MAX_FUSED];
    for (m, l) in models.iter_mut().zip(lobes) {
        *m = l.lobe.model();
    }
    let models = &models[..lobes.len()];
    let &(_, eval, mixture) = SHAPES.iter().find(|(matches, ..)| matches(models))?;
    let mut out = [FusedLobe {
        params: &[],
        weight: Rgb::new(0.0, 0.0, 0.0),
        probability: 0.0,
    }; MAX_FUSED];
    for (k, (o, l)) in out.iter_mut().zip(lobes).enumerate() {
        debug_assert!(closure.lobe_decoded(k).len() <= MAX_LOBE_PARAMS);
        *o = FusedLobe {
            params: closure.lobe_decoded(k),
            weight: l.weight,
            probability: l.probability,
        };
    }
    Some(Fused {
        eval,
        mixture,
        lobes: out,
    })
}
