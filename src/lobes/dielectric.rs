//! `dielectric`: a rough dielectric interface that reflects and refracts (Walter
//! et al. 2007, "Microfacet Models for Refraction through Rough Surfaces"), two-sided:
//! `wo` below the surface means the path is inside the medium.
//!
//! Reflection `f_r = F D G2 / (4 |cos_o cos_i|)` (Walter eq. 20); transmission
//! `f_t = |wi.h| |wo.h| eta_t^2 (1 - F) D G2 / (|cos_i cos_o| (eta_i wi.h + eta_t wo.h)^2)`
//! (Walter eq. 21), divided by `eta^2` for radiance transport (Veach 1997 §5.2),
//! so it is not reciprocal. Reflection is chosen with probability `F(wo.m)` for a
//! sampled visible normal `m`; total internal reflection gives `F = 1`.
//!
//! Parameters:
//! - `distribution` (enum `ggx` | `beckmann`, default `ggx`);
//! - `roughness` (float, [0, 1], default 0.1): below `microfacet::DELTA_ALPHA`
//!   (`roughness < 0.0316`) the interface is smooth: exact delta reflection and refraction;
//! - `anisotropic` (float, [0, 1], default 0);
//! - `eta` (float, [0.001, 1000], default 1.5): IOR inside over outside. Within
//!   1e-4 of 1 the interface is index-matched and treated as smooth (the rough
//!   half-vector is undefined when `wi = -wo`).
//!
//! Albedo: exact `F + (1 - F) / eta'^2` (radiance) when smooth; otherwise the reflected
//! and transmitted single-scattering tables of `crate::albedo_table` (isotropic, or over
//! aspect and view azimuth), the transmitted part times `1 / eta'^2` in radiance.

use super::conductor::{
    DISTRIBUTION_CHOICES, DISTRIBUTION_DECODED_LEN, decode_distribution, read_distribution,
};
use super::{Eval, Model, Params, Sample, Settle, Transport, VerifyCase, class_of, flags};
use crate::albedo_table::DielectricTable;
use crate::fresnel;
use crate::math::{Lane, Mask, Rgb, Vec3};
use crate::microfacet::{Distribution, Ndf, SmithNdf, View};
use crate::params::{ParamSpec, offset_of};

pub struct Dielectric;

/// `|eta - 1|` below which the interface is index-matched (smooth pass-through).
pub const INDEX_MATCHED: f32 = 1e-4;

const DISTRIBUTION: usize = offset_of(Dielectric::PARAMS, 0);
const ROUGHNESS: usize = offset_of(Dielectric::PARAMS, 1);
const ANISOTROPIC: usize = offset_of(Dielectric::PARAMS, 2);
// `decode_distribution` reads the three as the block's first parameters.
const _: () = assert!(DISTRIBUTION == 0 && ROUGHNESS == 1 && ANISOTROPIC == 2);
const ETA: usize = offset_of(Dielectric::PARAMS, 3);

pub struct Prepared<L: Lane> {
    dist: Distribution<L>,
    eta: L,
    roughness: L,
    smooth: L::Mask,
}

/// Refract `w` through the interface with normal `n` and relative IOR `eta`
/// (pbrt-v4 `Refract`). Returns the refracted direction, the IOR ratio `eta'` seen
/// from `w`'s side, and the lanes without total internal reflection.
#[inline(always)]
fn refract<L: Lane>(w: Vec3<L>, n: Vec3<L>, eta: L) -> (Vec3<L>, L, L::Mask) {
    let cos_i = n.dot(w);
    let inside = cos_i.lt(L::zero());
    let eta = L::select(inside, L::one() / eta, eta);
    let n = Vec3::select(inside, -n, n);
    let cos_i = cos_i.abs();
    // |w x n|^2, not 1 - cos_i^2: accurate near normal incidence (see fresnel::dielectric_sin2).
    let sin2_t = w.cross(n).length_squared() / (eta * eta);
    let ok = sin2_t.lt(L::one());
    let cos_t = (L::one() - sin2_t).safe_sqrt();
    // Normalized: with extreme eta the two terms nearly cancel.
    let wt = (-w * (L::one() / eta) + n * (cos_i / eta - cos_t)).normalize();
    (wt, eta, ok)
}

/// `a b > 0`, without the product's underflow to 0 at denormal cosines.
#[inline(always)]
fn same_sign<L: Lane>(a: L, b: L) -> L::Mask {
    (a * L::one().copysign(b)).gt(L::zero()) & b.abs().gt(L::zero())
}

/// The radiance-transport scale of a transmitted path, `1 / eta'^2`.
#[inline(always)]
fn transmission_scale<L: Lane>(etap: L, mode: Transport) -> L {
    match mode {
        Transport::Radiance => L::one() / (etap * etap),
        Transport::Importance => L::one(),
    }
}

impl Dielectric {
    /// Value (cosine included) and pdf of the rough interface for a pair whose
    /// generalized half vector is `wm` (Walter eqs. 20, 21 and the Jacobians 14, 17),
    /// from the `wo` side `v` ([`Distribution::view`]), and the lanes where the
    /// microfacet terms are defined. With `P = G1(wo) D / |cos_o|` and `rho = G2 / G1`
    /// of [`Distribution::pair`] (Heitz 2014 eqs. 38, 99; Heitz 2018 eq. 17):
    /// reflection `pdf = F P / 4`, `value = pdf rho`; transmission `pdf = (1 - F) P
    /// |wo.m| |wi.m| / (wi.m + wo.m / eta')^2`, `value = pdf rho / eta'^2` (radiance).
    /// One `D`, one `Lambda` per direction, one division for `P` and one for `rho`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn rough_eval<L: Lane>(
        p: &Prepared<L>,
        v: &View<L>,
        wo: Vec3<L>,
        wi: Vec3<L>,
        wm: Vec3<L>,
        etap: L,
        reflect: L::Mask,
        mode: Transport,
    ) -> (L, L, L::Mask) {
        let (wo_m, wi_m) = (wo.dot(wm), wi.dot(wm));
        // sin^2(wo, wm) without cancellation: wo x (wi etap + wo) = etap (wo x wi).
        let sin2_om = (wo.cross(wi) * etap)
            .length_squared()
            .safe_div((wi * etap + wo).length_squared());
        let f = fresnel::dielectric_sin2(wo_m, sin2_om, p.eta);
        // P and rho stay finite at grazing wo, where G1 and G2 vanish like cos_o.
        let (pp, rho, pair_ok) = p.dist.pair(v, wm, wi);
        let refl_pdf = L::splat(0.25) * pp * f;
        let refl_value = refl_pdf * rho;
        let denom = (wi_m + wo_m / etap).sqr();
        let t = L::one() - f;
        let trans_pdf = (pp * wo_m.abs() * wi_m.abs() * t).safe_div(denom);
        let trans_value = trans_pdf * rho * transmission_scale(etap, mode);
        (
            L::select(reflect, refl_value, trans_value),
            L::select(reflect, refl_pdf, trans_pdf),
            // D(m) is 0 for m.z <= 0, which pair does not test.
            pair_ok & wm.z.gt(L::zero()),
        )
    }

    /// [`Model::eval`] given the `wo` side `v`: eval and sample both end here, so a
    /// sample's value and pdf are eval's at its direction to the last bit.
    #[inline(always)]
    fn eval_from<L: Lane>(
        p: &Prepared<L>,
        v: &View<L>,
        wo: Vec3<L>,
        wi: Vec3<L>,
        mode: Transport,
    ) -> Eval<L> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        let reflect = same_sign(cos_o, cos_i);
        let etap = L::select(
            reflect,
            L::one(),
            L::select(cos_o.gt(L::zero()), p.eta, L::one() / p.eta),
        );
        // Generalized half vector (Walter eq. 16), on the normal's side.
        let wm_raw = wi * etap + wo;
        let wm = wm_raw.normalize();
        let wm = Vec3::select(wm.z.lt(L::zero()), -wm, wm);
        // Discard back-facing microfacets (Walter §5.3).
        let valid = !p.smooth
            & cos_i.abs().gt(L::zero())
            & cos_o.abs().gt(L::zero())
            & wm_raw.length_squared().gt(L::zero())
            & same_sign(wm.dot(wi), cos_i)
            & same_sign(wm.dot(wo), cos_o);
        if !valid.any() {
            return Eval::zero();
        }
        let (value, pdf, ok) = Self::rough_eval(p, v, wo, wi, wm, etap, reflect, mode);
        let valid = valid & ok;
        Eval {
            value: Rgb::splat(L::select(valid, value, L::zero())),
            pdf: L::select(valid, pdf, L::zero()),
        }
    }
}

impl Model for Dielectric {
    const NAME: &'static str = "dielectric";
    const SUMMARY: &'static str =
        "Rough dielectric interface (Walter 2007): reflection and refraction, delta when smooth";
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::choice(
            "distribution",
            DISTRIBUTION_CHOICES,
            0,
            "microfacet normal distribution",
        ),
        ParamSpec::float(
            "roughness",
            0.1,
            0.0,
            1.0,
            "alpha = roughness^2; below 0.0316 smooth (delta)",
        ),
        ParamSpec::float(
            "anisotropic",
            0.0,
            0.0,
            1.0,
            "stretch along the tangent (Burley 2012 mapping)",
        ),
        ParamSpec::float(
            "eta",
            1.5,
            0.001,
            1000.0,
            "relative IOR, inside over outside",
        ),
    ];
    const FLAGS: u32 = flags::REFLECTION | flags::TRANSMISSION | flags::GLOSSY | flags::SPECULAR;
    const RECIPROCAL: bool = false;
    /// Reflection 0, transmission 1.
    const COMPONENTS: u32 = 2;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "ggx rough",
            set: &[("roughness", 0.5)],
        },
        VerifyCase {
            name: "beckmann water",
            set: &[("distribution", 1.0), ("roughness", 0.3), ("eta", 1.33)],
        },
        VerifyCase {
            name: "ggx eta below 1",
            set: &[("roughness", 0.3), ("eta", 0.7)],
        },
        VerifyCase {
            name: "ggx near-specular diamond",
            set: &[("roughness", 0.06), ("eta", 2.4)],
        },
        VerifyCase {
            name: "ggx roughest aniso",
            set: &[("roughness", 1.0), ("anisotropic", 0.7)],
        },
        VerifyCase {
            name: "smooth",
            set: &[("roughness", 0.0)],
        },
        VerifyCase {
            name: "index-matched",
            set: &[("eta", 1.0)],
        },
    ];

    type Prepared<L: Lane> = Prepared<L>;

    /// Measured in tests/albedo.rs (roughness 0.05..1, `|cos_o|` 0.02..1, view azimuth
    /// 0..90 degrees, both sides): worst 2.5% isotropic (grazing from inside), then
    /// 3.0%, 4.7%, 7.6%, 16% and 25% at `anisotropic` 0.25, 0.5, 0.7, 0.9 and 1 (wide
    /// lobes seen from inside at roughness 1).
    fn albedo_tolerance(params: &[f32]) -> f32 {
        0.03 + 0.25 * params[ANISOTROPIC].powi(3)
    }

    /// The distribution (`decode_distribution`), `eta`, and 1 where the interface is
    /// smooth (delta or index-matched), else 0.
    const DECODED_LEN: usize = DISTRIBUTION_DECODED_LEN + 2;

    fn decode(params: &[f32], out: &mut [f32]) {
        let dist = decode_distribution(params, out);
        let eta = params[ETA];
        let smooth = dist.is_delta() || (eta - 1.0).abs() < INDEX_MATCHED;
        out[DISTRIBUTION_DECODED_LEN..].copy_from_slice(&[eta, f32::from(u8::from(smooth))]);
    }

    #[inline(always)]
    fn prepare<L: Lane>(decoded: Params<'_, L>) -> Prepared<L> {
        let (dist, roughness) = read_distribution(&decoded);
        Prepared {
            dist,
            roughness,
            eta: decoded.float(DISTRIBUTION_DECODED_LEN),
            smooth: decoded
                .float(DISTRIBUTION_DECODED_LEN + 1)
                .gt(L::splat(0.5)),
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, mode: Transport) -> Eval<L> {
        if p.smooth.all() {
            return Eval::zero();
        }
        Self::eval_from(p, &p.dist.view(wo), wo, wi, mode)
    }

    #[inline(always)]
    fn sample<L: Lane>(
        p: &Prepared<L>,
        wo: Vec3<L>,
        uc: L,
        u0: L,
        u1: L,
        mode: Transport,
        settle: &mut impl Settle<L>,
    ) -> Sample<L> {
        let up = Vec3::splat(0.0, 0.0, 1.0);
        let wm = Vec3::select(p.smooth, up, p.dist.sample(wo, u0, u1));
        let wo_m = wo.dot(wm);
        let f = fresnel::dielectric_sin2(wo_m, wo.cross(wm).length_squared(), p.eta);
        let reflect = uc.lt(f);
        let (wt, etap_t, no_tir) = refract(wo, wm, p.eta);
        let wi = settle.settle(Vec3::select(reflect, wo.reflect(wm), wt));
        let etap = L::select(reflect, L::one(), etap_t);
        let same_side = same_sign(wo.z, wi.z);
        let opposite = same_sign(-wo.z, wi.z);
        let valid = (reflect & same_side) | (!reflect & no_tir & opposite);
        // Smooth: the discrete probabilities F and 1 - F, value the same fraction.
        let t_scale = transmission_scale(etap, mode);
        let smooth_value = L::select(reflect, f, (L::one() - f) * t_scale);
        let smooth_pdf = L::select(reflect, f, L::one() - f);
        // Rough: value and pdf by eval's own finish at the settled wi (the wo side
        // computed the same way), so both agree with eval to the last bit.
        let e = if p.smooth.all() {
            Eval::zero()
        } else {
            Self::eval_from(p, &p.dist.view(wo), wo, wi, mode)
        };
        Sample {
            wi,
            value: Rgb::select(p.smooth, Rgb::splat(smooth_value), e.value),
            pdf: L::select(p.smooth, smooth_pdf, e.pdf),
            valid: valid & (p.smooth | e.pdf.gt(L::zero())),
            transmitted: !reflect,
            delta: p.smooth,
            eta: etap,
            roughness: L::select(p.smooth, L::zero(), p.roughness),
            class: class_of(p.smooth, Self::FLAGS),
            // Reflection 0, transmission 1.
            component: L::select(reflect, L::zero(), L::one()),
        }
    }

    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, mode: Transport) -> Rgb<L> {
        let cos_o = wo.z;
        let etap = L::select(cos_o.gt(L::zero()), p.eta, L::one() / p.eta);
        let scale = transmission_scale(etap, mode);
        let f = fresnel::dielectric(cos_o, p.eta);
        let smooth = f + (L::one() - f) * scale;
        let (r, t) = DielectricTable::lookup(wo, &p.dist, etap);
        let rough = r + t * scale;
        let albedo = L::select(p.smooth, smooth, rough);
        Rgb::splat(L::select(cos_o.eq(L::zero()), L::zero(), albedo))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lobes::InPlace;
    use crate::params::write_defaults;

    /// A rough sample's value and pdf are `eval(wo, s.wi)` to the last bit, for random
    /// parameters (both NDFs, eta on both sides of 1), both sides and both transports.
    #[test]
    fn sample_matches_eval_bitwise() {
        let mut state = 0x1234_5677_u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut block = vec![0.0f32; crate::params::block_size(Dielectric::PARAMS)];
        let mut checked = 0;
        for i in 0..20000 {
            write_defaults(Dielectric::PARAMS, &mut block);
            block[DISTRIBUTION] = (i % 2) as f32;
            block[ROUGHNESS] = 0.04 + 0.96 * rnd();
            block[ANISOTROPIC] = rnd();
            block[ETA] = [1.5, 0.7, 2.4, 1.33][i / 2 % 4];
            let mut decoded = [0.0; Dielectric::DECODED_LEN];
            Dielectric::decode(&block, &mut decoded);
            let p = Dielectric::prepare(Params::new(&decoded));
            let (ct, phi) = (rnd(), 2.0 * crate::math::PI * rnd());
            let ct = if i % 3 == 0 { -ct } else { ct };
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let wo = Vec3::new(st * phi.cos(), st * phi.sin(), ct).normalize();
            let mode = if i % 5 == 0 {
                Transport::Importance
            } else {
                Transport::Radiance
            };
            let s = Dielectric::sample(&p, wo, rnd(), rnd(), rnd(), mode, &mut InPlace);
            if !s.valid || s.delta {
                continue;
            }
            let e = Dielectric::eval(&p, wo, s.wi, mode);
            assert_eq!(s.pdf.to_bits(), e.pdf.to_bits(), "pdf at {wo:?} {:?}", s.wi);
            assert_eq!(
                s.value.r.to_bits(),
                e.value.r.to_bits(),
                "value at {wo:?} {:?}",
                s.wi
            );
            checked += 1;
        }
        assert!(checked > 10000, "{checked} samples checked");
    }
}
