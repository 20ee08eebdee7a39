//! `disney_sheen`: the sheen lobe of Disney's principled BRDF (Burley 2012,
//! "Physically-Based Shading at Disney", section 5.3; `shared/reference/formulas.md`,
//! "Disney principled BRDF"): `f = FH color` with `FH = SchlickWeight(l.h) =
//! (1 - l.h)^5` and `l.h = sqrt((1 + l.v) / 2)`, a rim at grazing angles for cloth.
//! The Disney material scales it by `sheen Csheen (1 - metallic)` through the lobe
//! weight.
//!
//! Parameters:
//! - `color` (rgb, [0, 1], default 1).
//!
//! Sampling is cosine-weighted (`pdf = cos_i / pi`), weight `pi FH color`. One-sided:
//! 0 below the surface.
//!
//! Albedo: `color S(cos_o)` with `S(a) = int FH cos_i d(omega_i)`, from 0.0885 at grazing
//! to 2.57e-4 at normal view. The azimuthal average of `(1 - l.h)^5` leads to elliptic
//! integrals, so `S` is a degree-14 polynomial in `1 - cos_o` (the Chebyshev interpolant
//! of an f64 quadrature at 40 nodes, converted to monomials): worst relative error
//! 8.9e-6 in f32 against f64 quadrature at 403 cosines from 1e-7 to 1
//! (tests/lobe_disney_sheen.rs). Selection and pruning weigh the lobe by a degree-5
//! fit of it, within 0.1% (its coefficients are all positive: no cancellation, so
//! SIMD's fused multiply-adds and the scalar lane's unfused ones agree).

use super::lambert::cosine_hemisphere;
use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, both_above, class_of, flags,
};
use crate::fresnel::schlick_weight_pair;
use crate::math::vmath::horner;
use crate::math::{INV_PI, Lane, Mask, Rgb, Vec3};
use crate::params::{ParamSpec, offset_of};

pub struct DisneySheen;

const COLOR: usize = offset_of(DisneySheen::PARAMS, 0);

pub struct Prepared<L> {
    color: Rgb<L>,
}

/// `S(a)` as a polynomial in `x = 1 - a`, lowest degree first (module docs).
const ALBEDO_FIT: [f32; 15] = [
    2.572579e-4,
    6.514978e-3,
    2.7182615e-2,
    3.363837e-2,
    1.2530529e-4,
    1.4268227e-1,
    -7.6747225e-1,
    2.913595e0,
    -7.683588e0,
    1.42588e1,
    -1.8555673e1,
    1.657762e1,
    -9.687461e0,
    3.3360078e0,
    -5.1377464e-1,
];

/// [`ALBEDO_FIT`] to 0.1% (least squares in relative error at 2001 points of [0, 1]),
/// highest degree first.
const ALBEDO_ESTIMATE_FIT: [f32; 6] = [
    4.312956e-3,
    1.907512e-2,
    3.087303e-2,
    2.75248e-2,
    6.498031e-3,
    2.574075e-4,
];

/// `FH cos_i`, 0 unless both directions are above the surface.
#[inline(always)]
fn shape<L: Lane>(wo: Vec3<L>, wi: Vec3<L>) -> L {
    L::select(
        both_above(wo, wi),
        schlick_weight_pair(wo, wi) * wi.z,
        L::zero(),
    )
}

impl Model for DisneySheen {
    const NAME: &'static str = "disney_sheen";
    const SUMMARY: &'static str = "Disney principled sheen (Burley 2012): (1 - l.h)^5 color";
    const DECODE_COPIES: bool = true;
    const PARAMS: &'static [ParamSpec] = &[ParamSpec::rgb(
        "color",
        [1.0; 3],
        0.0,
        1.0,
        "sheen color (the Disney material passes sheen * Csheen through the weight)",
    )];
    const FLAGS: u32 = flags::REFLECTION | flags::DIFFUSE;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "black",
            set: &[("color", 0.0)],
        },
        VerifyCase {
            name: "tinted",
            set: &[("color", 0.4)],
        },
    ];

    const VALID_ABOVE: bool = true;
    type Prepared<L: Lane> = Prepared<L>;

    /// Polynomial fit: measured worst relative error 8.9e-6 (module docs).
    fn albedo_tolerance(_params: &[f32]) -> f32 {
        1e-4
    }

    /// [`ALBEDO_ESTIMATE_FIT`] against [`ALBEDO_FIT`]: 0.1% at worst (at grazing).
    fn albedo_estimate_tolerance(_params: &[f32]) -> f32 {
        2e-3
    }

    /// `color S(cos_o)` is largest at grazing (`S(0) = 0.0885`): far below 1, and the
    /// bound a material scaling the lobe by `sheen Csheen` (up to 10) sums.
    fn energy_bound(params: &[f32]) -> f32 {
        let p = Self::prepare(Params::new(params));
        let a = Self::albedo(&p, Vec3::new(1.0, 0.0, 1e-6), Transport::Radiance);
        a.r.max(a.g).max(a.b) * 1.001
    }

    #[inline(always)]
    fn prepare<L: Lane>(params: Params<'_, L>) -> Prepared<L> {
        Prepared {
            color: params.rgb(COLOR),
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        Eval {
            value: p.color * shape(wo, wi),
            pdf: L::select(both_above(wo, wi), wi.z, L::zero()) * L::splat(INV_PI),
        }
    }

    #[inline(always)]
    fn sample<L: Lane>(
        p: &Prepared<L>,
        wo: Vec3<L>,
        _uc: L,
        u0: L,
        u1: L,
        mode: Transport,
        settle: &mut impl Settle<L>,
    ) -> Sample<L> {
        let wi = settle.settle(cosine_hemisphere(u0, u1));
        let e = Self::eval(p, wo, wi, mode);
        Sample {
            wi,
            value: e.value,
            pdf: e.pdf,
            valid: both_above(wo, wi),
            transmitted: L::Mask::splat(false),
            delta: L::Mask::splat(false),
            eta: L::one(),
            roughness: L::one(),
            class: class_of(L::Mask::splat(false), Self::FLAGS),
            component: L::zero(),
        }
    }

    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        let x = L::one() - wo.z.clamp(L::zero(), L::one());
        // Horner, as a loop: a closure would lose the kernel's target features.
        let mut s = L::zero();
        for &c in ALBEDO_FIT.iter().rev() {
            s = s * x + L::splat(c);
        }
        Rgb::select(wo.z.gt(L::zero()), p.color * s, Rgb::zero())
    }

    /// [`ALBEDO_ESTIMATE_FIT`]: 6 multiply-adds instead of 14 multiplies and adds.
    #[inline(always)]
    fn albedo_estimate<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        let x = L::one() - wo.z.clamp(L::zero(), L::one());
        let s = horner(x, ALBEDO_ESTIMATE_FIT);
        Rgb::select(wo.z.gt(L::zero()), p.color * s, Rgb::zero())
    }
}
