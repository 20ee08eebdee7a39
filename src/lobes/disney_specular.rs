//! `disney_specular`: the specular lobe of Disney's principled BRDF (Burley 2012,
//! section 5.4; restated in `shared/reference/formulas.md`):
//!
//! ```text
//! f  = Ds Fs Gs
//! Ds = GTR2_aniso(h, ax, ay)            (anisotropic GGX)
//! Fs = mix(f0, 1, FH),  FH = (1 - l.h)^5
//! Gs = SmithG_GGX_aniso(l, ax', ay') SmithG_GGX_aniso(v, ax', ay')
//! aspect = sqrt(1 - 0.9 anisotropic), ax = max(0.001, roughness^2 / aspect),
//! ay = max(0.001, roughness^2 aspect); the masking uses the 2012 remap
//! alpha_g = (0.5 + roughness / 2)^2 in place of roughness^2 ("specular was too hot for
//! small roughness", seed 003 section 5.6)
//! ```
//!
//! where `SmithG_GGX_aniso(w) = 1 / (w.z + sqrt((w.x ax)^2 + (w.y ay)^2 + w.z^2))` is
//! `G1 / (2 cos)`, so `Gs` carries the microfacet `1 / (4 cos_i cos_o)`. `ax` lies along
//! the frame's tangent.
//!
//! Parameters:
//! - `roughness` (float, [0, 1], default 0.5);
//! - `anisotropic` (float, [0, 1], default 0);
//! - `f0` (rgb, [0, 1], default 0.04): the normal-incidence color (Disney's `Cspec0`).
//!
//! Sampling draws GGX visible normals of `(ax, ay)` (Dupuy and Benyoub 2023), so the pdf is
//! `G1(wo) D / (4 cos_o)` with D's own Smith `G1`, while the value keeps the remapped
//! masking: the weight is not `F G2 / G1` as for the conductor, but it is smooth and
//! bounded. Roughness 0 is alpha 0.001, glossy (Burley's clamp), not a delta lobe.
//! Albedo: `f0 A + B` from `albedo_table::disney::SpecularTable` (and its anisotropic
//! companion). One-sided.

use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, both_above, class_of, flags,
};
use crate::albedo_table::disney::SpecularTable;
use crate::fresnel::HalfVector;
use crate::math::{INV_PI, Lane, Mask, Rgb, Vec3};
use crate::microfacet::{Ggx, Ndf, SmithNdf, burley_alpha};
use crate::params::{ParamSpec, offset_of};

pub struct DisneySpecular;

const ROUGHNESS: usize = offset_of(DisneySpecular::PARAMS, 0);
const ANISOTROPIC: usize = offset_of(DisneySpecular::PARAMS, 1);
const F0: usize = offset_of(DisneySpecular::PARAMS, 2);

/// Burley's floor of both alphas.
const MIN_ALPHA: f32 = 0.001;

pub struct Prepared<L> {
    dist: Ggx<L>,
    /// The masking's remapped alphas.
    gx: L,
    gy: L,
    f0: Rgb<L>,
    roughness: L,
    anisotropic: L,
}

/// `1 / SmithG_GGX_aniso(w, gx, gy) = w.z + sqrt((w.x gx)^2 + (w.y gy)^2 + w.z^2)`.
#[inline(always)]
fn smith_denominator<L: Lane>(w: Vec3<L>, gx: L, gy: L) -> L {
    let (x, y) = (w.x * gx, w.y * gy);
    w.z + x.mul_add(x, y.mul_add(y, w.z * w.z)).sqrt()
}

impl Model for DisneySpecular {
    const NAME: &'static str = "disney_specular";
    const SUMMARY: &'static str = "Disney principled specular (Burley 2012): anisotropic GTR2, Schlick, remapped Smith masking";
    const DECODE_COPIES: bool = true;
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::float(
            "roughness",
            0.5,
            0.0,
            1.0,
            "alpha = roughness^2 (at least 0.001); masking alpha (0.5 + roughness / 2)^2",
        ),
        ParamSpec::float(
            "anisotropic",
            0.0,
            0.0,
            1.0,
            "aspect sqrt(1 - 0.9 anisotropic), wider along the tangent",
        ),
        ParamSpec::rgb(
            "f0",
            [0.04; 3],
            0.0,
            1.0,
            "normal-incidence reflectance (Cspec0)",
        ),
    ];
    const FLAGS: u32 = flags::REFLECTION | flags::GLOSSY;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        // Below roughness 0.1 (alpha 0.01) the lobe is narrower than the energy check's
        // uniform quadrature resolves; roughness 0 is verified in the disney material's
        // corner case and by the hard cases.
        VerifyCase {
            name: "roughness 0.1",
            set: &[("roughness", 0.1)],
        },
        VerifyCase {
            name: "roughness 1",
            set: &[("roughness", 1.0)],
        },
        VerifyCase {
            name: "anisotropic 1",
            set: &[("anisotropic", 1.0), ("roughness", 0.4)],
        },
        VerifyCase {
            name: "f0 0",
            set: &[("f0", 0.0)],
        },
        VerifyCase {
            name: "f0 1",
            set: &[("f0", 1.0)],
        },
    ];

    const VALID_ABOVE: bool = true;
    type Prepared<L: Lane> = Prepared<L>;

    /// Tables of f64 quadratures, interpolated; measured against slope-space quadrature
    /// (tests/lobe_disney_specular.rs, roughness 0..1, anisotropic 0..1, `cos_o` 0.02..1,
    /// view azimuth 0..1.2): worst 0.54% isotropic (grazing, `cos_o` 0.02), 1.8%
    /// anisotropic (roughness 1, anisotropic 1).
    fn albedo_tolerance(params: &[f32]) -> f32 {
        if params[ANISOTROPIC] > 0.0 {
            0.025
        } else {
            0.01
        }
    }

    /// [`SpecularTable::estimate`]: exact when isotropic.
    fn albedo_estimate_tolerance(params: &[f32]) -> f32 {
        if params[ANISOTROPIC] > 0.0 { 0.2 } else { 0.0 }
    }

    #[inline(always)]
    fn prepare<L: Lane>(p: Params<'_, L>) -> Prepared<L> {
        let roughness = p.float(ROUGHNESS);
        let anisotropic = p.float(ANISOTROPIC);
        let (alpha_x, alpha_y) = burley_alpha(roughness, anisotropic, MIN_ALPHA);
        // The 2012 masking remap: alpha_g = (0.5 + roughness / 2)^2, stretched alike.
        let (gx, gy) = burley_alpha(
            L::splat(0.5) + L::splat(0.5) * roughness,
            anisotropic,
            MIN_ALPHA,
        );
        Prepared {
            dist: Ggx { alpha_x, alpha_y },
            gx,
            gy,
            f0: p.rgb(F0),
            roughness,
            anisotropic,
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        // No early exit for a register below the surface: a branch here would keep a
        // fused kernel from sharing the half vector with the other lobes.
        let half = HalfVector::of(wo, wi);
        let ok = both_above(wo, wi) & half.exists;
        // D = n / q^2 (`Ggx::q`); Gs = 1 / (a_i a_o); the VNDF pdf G1(wo) D / (4 cos_o)
        // (Heitz 2018 eq. 17) with G1(wo) / cos_o = 2 / b, b = cos_o + sigma(wo)
        // (`SmithNdf::sigma`). `q` is homogeneous of degree 2, so q(h) = q(s) / |s|^2
        // for the half vector's unnormalized `s`, and one division serves them all:
        // q(s)^2 >= 1e-24 |s|^4 with |s|^2 >= 2^-6 (`HalfVector::sum_len2`), a_i, a_o >=
        // 0.079 (the remapped alphas) and b >= 0.001 make the product a normal float.
        let axy = p.dist.alpha_x * p.dist.alpha_y;
        let n = axy * axy * axy * L::splat(INV_PI);
        let q = p.dist.q(half.sum);
        let a_i = smith_denominator(wi, p.gx, p.gy);
        let a_o = smith_denominator(wo, p.gx, p.gy);
        let b = wo.z + p.dist.sigma(wo, wo.z);
        let len2 = half.sum_len2;
        // `a_i a_o` once for both: a fused eval's multiplies share two pipes (AMD Zen
        // 5), and each one saved counts.
        let a_io = a_i * a_o;
        // 1 / (q(h)^2 a_i a_o b).
        let inv = len2 * len2 / L::select(ok, q * q * a_io * b, L::one());
        let pdf = L::select(ok, L::splat(0.5) * n * a_io * inv, L::zero());
        let fh = half.fh;
        // Zero where not `ok`. `wi.z` last: `n` is as small as 3e-19, and `n wi.z`
        // leaves the normal floats at grazing `wi` where the value does not.
        let scale = L::select(ok, n * b * inv * wi.z, L::zero());
        // mix(f0, 1, fh) scale = f0 (scale - fh scale) + fh scale: two multiplies and a
        // multiply-add a channel's three, with no cancellation (fh in [0, 1]).
        let white = fh * scale;
        let rest = scale - white;
        let value = p.f0.map(
            #[inline(always)]
            |f0| f0.mul_add(rest, white),
        );
        Eval { value, pdf }
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
        let wi = settle.settle(p.dist.sample_reflection(wo, u0, u1));
        // Value and pdf by eval at the settled direction, so both agree with eval to
        // the last bit.
        let e = Self::eval(p, wo, wi, mode);
        Sample {
            wi,
            value: e.value,
            pdf: e.pdf,
            // A zero pdf fails in `Sample::finish` ([`Model::VALID_ABOVE`]).
            valid: both_above(wo, wi),
            transmitted: L::Mask::splat(false),
            delta: L::Mask::splat(false),
            eta: L::one(),
            roughness: p.roughness,
            class: class_of(L::Mask::splat(false), Self::FLAGS),
            component: L::zero(),
        }
    }

    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        schlick_split(p, wo, SpecularTable::lookup(wo, p.roughness, p.anisotropic))
    }

    /// The isotropic table as `albedo`; anisotropic lanes at the table's nearest
    /// azimuth and aspect nodes ([`SpecularTable::estimate`]).
    #[inline(always)]
    fn albedo_estimate<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        schlick_split(
            p,
            wo,
            SpecularTable::estimate(wo, p.roughness, p.anisotropic),
        )
    }
}

/// The albedo `f0 A + B` from Schlick's split `(A, B)`; 0 below the surface.
#[inline(always)]
fn schlick_split<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, (a, b): (L, L)) -> Rgb<L> {
    let albedo = p.f0.map(
        #[inline(always)]
        |f0| f0 * a + b,
    );
    Rgb::select(wo.z.gt(L::zero()), albedo, Rgb::zero())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lobes::InPlace;

    /// A sample's value and pdf are `eval(wo, s.wi)` to the last bit.
    #[test]
    fn sample_matches_eval_bitwise() {
        let mut state = 0x1234_5678_u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut checked = 0;
        for _ in 0..20000 {
            let block = [rnd(), rnd(), rnd(), rnd(), rnd()];
            let p = DisneySpecular::prepare(Params::new(&block));
            let (ct, phi) = (rnd(), 2.0 * crate::math::PI * rnd());
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let wo = Vec3::new(st * phi.cos(), st * phi.sin(), ct).normalize();
            let s = DisneySpecular::sample(
                &p,
                wo,
                rnd(),
                rnd(),
                rnd(),
                Transport::Radiance,
                &mut InPlace,
            );
            if !s.valid {
                continue;
            }
            let e = DisneySpecular::eval(&p, wo, s.wi, Transport::Radiance);
            assert_eq!(s.pdf.to_bits(), e.pdf.to_bits());
            assert_eq!(
                s.value.to_array().map(f32::to_bits),
                e.value.to_array().map(f32::to_bits)
            );
            checked += 1;
        }
        assert!(checked > 10000, "{checked}");
    }
}
