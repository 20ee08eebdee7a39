//! `conductor`: rough metallic reflection, the Cook-Torrance microfacet BRDF
//! `f = D(h) G2(wo, wi) F(wo.h) / (4 cos_o cos_i)` (Walter et al. 2007 eq. 20) with
//! GGX or Beckmann normals, anisotropy, Smith height-correlated masking-shadowing and
//! visible-normal sampling (see `crate::microfacet`).
//!
//! Parameters:
//! - `distribution` (enum `ggx` | `beckmann`, default `ggx`);
//! - `roughness` (float, [0, 1], default 0.3): `alpha = roughness^2`; below
//!   `microfacet::DELTA_ALPHA` the lobe is a perfect mirror (delta);
//! - `anisotropic` (float, [0, 1], default 0): stretches alpha along the frame's tangent;
//! - the Fresnel group (`fresnel` = `schlick` | `conductor` | `artistic`, default
//!   `artistic`, with `f0`, `f90`, `eta`, `k`, `reflectivity`, `edge_tint`).
//!
//! Sampling draws a visible normal, so the weight is `F G2 / G1`. Albedo: the
//! reflection tables of `crate::albedo_table` (isotropic, or over aspect and view
//! azimuth), weighting the lobe's Fresnel at 13 nodes of `wo.m`; exact `F(cos_o)` when
//! delta.
//! One-sided: 0 when either direction is below the surface.

use super::fresnel_params::{self, with_fresnel_params};
use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, both_above, class_of, flags,
};
use crate::albedo_table::{FresnelNodes, ReflectionTable};
use crate::fresnel::FresnelModel;
use crate::math::{Lane, Mask, Rgb, Vec3};
use crate::microfacet::{Distribution, Ndf, NdfKind, SmithNdf, View};
use crate::params::{ParamSpec, offset_of};

pub struct Conductor;

/// Choices of the `distribution` parameter, shared by every microfacet lobe.
pub const DISTRIBUTION_CHOICES: &[&str] = NdfKind::NAMES;

/// Length of a decoded microfacet distribution: kind, `alpha_x`, `alpha_y`, roughness.
pub(crate) const DISTRIBUTION_DECODED_LEN: usize = 4;

/// Decodes the `distribution`, `roughness` and `anisotropic` parameters that open a
/// microfacet lobe's block into `out[..DISTRIBUTION_DECODED_LEN]`.
pub(crate) fn decode_distribution(params: &[f32], out: &mut [f32]) -> Distribution<f32> {
    let (kind, roughness, anisotropic) = (params[0], params[1], params[2]);
    let dist =
        Distribution::from_roughness(NdfKind::from_choice(kind as usize), roughness, anisotropic);
    out[..DISTRIBUTION_DECODED_LEN].copy_from_slice(&[kind, dist.alpha_x, dist.alpha_y, roughness]);
    dist
}

/// Reads what [`decode_distribution`] wrote: the distribution and the roughness.
#[inline(always)]
pub(crate) fn read_distribution<L: Lane>(decoded: &Params<'_, L>) -> (Distribution<L>, L) {
    let dist = Distribution {
        kind: NdfKind::from_choice(decoded.choice(0)),
        alpha_x: decoded.float(1),
        alpha_y: decoded.float(2),
    };
    (dist, decoded.float(3))
}

const DISTRIBUTION: usize = offset_of(Conductor::PARAMS, 0);
const ROUGHNESS: usize = offset_of(Conductor::PARAMS, 1);
const ANISOTROPIC: usize = offset_of(Conductor::PARAMS, 2);
// `decode_distribution` reads the three as the block's first parameters.
const _: () = assert!(DISTRIBUTION == 0 && ROUGHNESS == 1 && ANISOTROPIC == 2);
const FRESNEL: usize = offset_of(Conductor::PARAMS, 3);

pub struct Prepared<L> {
    dist: Distribution<L>,
    fresnel: FresnelModel<L>,
    /// Read only by `albedo`; `None` in blocks staged for eval and sample.
    nodes: Option<FresnelNodes<L>>,
    roughness: L,
}

/// Where the conductor's decoded Fresnel group and albedo nodes start.
const DECODED_FRESNEL: usize = DISTRIBUTION_DECODED_LEN;
const DECODED_NODES: usize = DECODED_FRESNEL + fresnel_params::DECODED_LEN;

impl Model for Conductor {
    const NAME: &'static str = "conductor";
    const SUMMARY: &'static str =
        "Rough conductor: GGX/Beckmann microfacets, anisotropic, Schlick/complex/artistic Fresnel";
    const PARAMS: &'static [ParamSpec] = with_fresnel_params!(2;
        ParamSpec::choice("distribution", DISTRIBUTION_CHOICES, 0, "microfacet normal distribution"),
        ParamSpec::float("roughness", 0.3, 0.0, 1.0, "alpha = roughness^2; below 0.0316 a perfect mirror"),
        ParamSpec::float("anisotropic", 0.0, 0.0, 1.0, "stretch along the tangent (Burley 2012 mapping)"),
    );
    const FLAGS: u32 = flags::REFLECTION | flags::GLOSSY | flags::SPECULAR;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "ggx rough aniso schlick",
            set: &[("roughness", 0.6), ("anisotropic", 0.8), ("fresnel", 0.0)],
        },
        VerifyCase {
            name: "beckmann conductor",
            set: &[("distribution", 1.0), ("roughness", 0.5), ("fresnel", 1.0)],
        },
        VerifyCase {
            name: "beckmann aniso",
            set: &[
                ("distribution", 1.0),
                ("roughness", 0.15),
                ("anisotropic", 0.5),
            ],
        },
        VerifyCase {
            name: "ggx near-specular",
            set: &[("roughness", 0.06)],
        },
        VerifyCase {
            name: "ggx roughest",
            set: &[("roughness", 1.0)],
        },
        VerifyCase {
            name: "beckmann roughest",
            set: &[("distribution", 1.0), ("roughness", 1.0)],
        },
        VerifyCase {
            name: "delta",
            set: &[("roughness", 0.0)],
        },
    ];

    type Prepared<L: Lane> = Prepared<L>;

    /// Measured in tests/albedo.rs over roughness 0.05..1, `cos_o` 0.02..1, view azimuth
    /// 0..90 degrees, every Fresnel mode: worst 1.54% isotropic and up to
    /// `anisotropic = 0.7`, 3.9% at 0.9, 5.6% at 1.
    fn albedo_tolerance(params: &[f32]) -> f32 {
        0.02 + 0.04 * params[ANISOTROPIC].powi(6)
    }

    /// The distribution (`decode_distribution`), the decoded Fresnel group
    /// (`fresnel_params::decode`), then the albedo's conductor nodes
    /// (`fresnel_params::decode_nodes`).
    const DECODED_LEN: usize = DECODED_NODES + fresnel_params::NODES_LEN;
    const LANE_DECODED_LEN: usize = DECODED_NODES;

    fn decode(params: &[f32], out: &mut [f32]) {
        decode_distribution(params, out);
        let (fresnel, nodes) = out[DECODED_FRESNEL..].split_at_mut(fresnel_params::DECODED_LEN);
        fresnel_params::decode(params, FRESNEL, fresnel);
        fresnel_params::decode_nodes(fresnel, nodes);
    }

    #[inline(always)]
    fn prepare<L: Lane>(decoded: Params<'_, L>) -> Prepared<L> {
        let (dist, roughness) = read_distribution(&decoded);
        let fresnel = fresnel_params::read(&decoded, DECODED_FRESNEL);
        Prepared {
            dist,
            nodes: fresnel_params::read_nodes(&decoded, DECODED_NODES, &fresnel),
            fresnel,
            roughness,
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        if !(wo.z.gt(L::zero()) & !p.dist.is_delta()).any() {
            return Eval::zero();
        }
        reflect_finish(p, &p.dist.view(wo), wo, wi)
    }

    #[inline(always)]
    fn sample<L: Lane>(
        p: &Prepared<L>,
        wo: Vec3<L>,
        _uc: L,
        u0: L,
        u1: L,
        _mode: Transport,
        settle: &mut impl Settle<L>,
    ) -> Sample<L> {
        let delta = p.dist.is_delta();
        let up = Vec3::splat(0.0, 0.0, 1.0);
        let m = Vec3::select(delta, up, p.dist.sample(wo, u0, u1));
        let wi = settle.settle(wo.reflect(m));
        // Value and pdf by eval's own finish at the settled wi (the wo side computed
        // the same way), so that both agree with eval to the last bit: narrow lobes
        // amplify the rounding between the sampled m and eval's half vector.
        let e = reflect_finish(p, &p.dist.view(wo), wo, wi);
        // The Fresnel term at wo only where a lane is delta: per channel it costs as
        // much as the rest of the value.
        let value = if delta.any() {
            Rgb::select(delta, p.fresnel.eval(wo.z), e.value)
        } else {
            e.value
        };
        Sample {
            wi,
            value,
            pdf: L::select(delta, L::one(), e.pdf),
            valid: both_above(wo, wi) & (delta | e.pdf.gt(L::zero())),
            transmitted: L::Mask::splat(false),
            delta,
            eta: L::one(),
            roughness: L::select(delta, L::zero(), p.roughness),
            class: class_of(delta, Self::FLAGS),
            component: L::zero(),
        }
    }

    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        // The Fresnel-node table when rough, exact `F(cos_o)` where delta.
        let rough = ReflectionTable::albedo(wo, &p.dist, &p.fresnel, p.nodes.as_ref());
        let delta = p.dist.is_delta();
        let albedo = if delta.any() {
            Rgb::select(delta, p.fresnel.eval(wo.z), rough)
        } else {
            rough
        };
        Rgb::select(wo.z.gt(L::zero()), albedo, Rgb::zero())
    }
}

/// The `wi` side of the conductor's eval, given the `wo` side `v` ([`Distribution::view`]):
/// `f cos_i = D G2 F / (4 cos_o)` (Walter 2007 eq. 20; the `cos_i` of the
/// cosine-weighted value cancels the BRDF's `1 / cos_i`) and the VNDF pdf
/// `G1(wo) D / (4 cos_o)` (Heitz 2018 eq. 17). With `P, rho` of
/// [`Distribution::pair`]: `pdf = P / 4`, `value = F pdf rho` (`rho = G2 / G1`).
/// GGX: 3 divisions (`1 / |h|`, `P`, `rho`) and 3 sqrt (`|h|`, `sigma_o`, `sigma_i`)
/// per lane besides the Fresnel term.
#[inline(always)]
fn reflect_finish<L: Lane>(p: &Prepared<L>, v: &View<L>, wo: Vec3<L>, wi: Vec3<L>) -> Eval<L> {
    let hu = wo + wi;
    let len2 = hu.length_squared();
    // len2 > 0 on lanes with both directions above: 1 / |h| is finite there.
    let ok = both_above(wo, wi) & !p.dist.is_delta() & len2.gt(L::zero());
    let inv_len = L::one() / len2.sqrt();
    let h = hu * inv_len;
    let (pp, rho, a_ok) = p.dist.pair(v, h, wi);
    let ok = ok & a_ok;
    let pdf = L::select(ok, L::splat(0.25) * pp, L::zero());
    let value = p.fresnel.eval(wo.dot(h)) * (pdf * rho);
    Eval {
        value: Rgb::select(ok, value, Rgb::zero()),
        pdf,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lobes::InPlace;
    use crate::params::write_defaults;

    /// A sample's value and pdf are `eval(wo, s.wi)` to the last bit, for random
    /// parameters (both NDFs, every Fresnel mode) and directions.
    #[test]
    fn sample_matches_eval_bitwise() {
        let mut state = 0x2545_f491_u32;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut block = vec![0.0f32; crate::params::block_size(Conductor::PARAMS)];
        let mut checked = 0;
        for i in 0..20000 {
            write_defaults(Conductor::PARAMS, &mut block);
            block[DISTRIBUTION] = (i % 2) as f32;
            block[ROUGHNESS] = 0.03 + 0.97 * rnd();
            block[ANISOTROPIC] = rnd();
            block[FRESNEL] = (i / 2 % 3) as f32;
            let mut decoded = [0.0; Conductor::DECODED_LEN];
            Conductor::decode(&block, &mut decoded);
            let p = Conductor::prepare(Params::new(&decoded));
            let (ct, phi) = (rnd(), 2.0 * crate::math::PI * rnd());
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let wo = Vec3::new(st * phi.cos(), st * phi.sin(), ct).normalize();
            let s = Conductor::sample(
                &p,
                wo,
                rnd(),
                rnd(),
                rnd(),
                Transport::Radiance,
                &mut InPlace,
            );
            if !s.valid || s.delta {
                continue;
            }
            let e = Conductor::eval(&p, wo, s.wi, Transport::Radiance);
            assert_eq!(s.pdf.to_bits(), e.pdf.to_bits(), "pdf at {wo:?} {:?}", s.wi);
            for (a, b) in [
                (s.value.r, e.value.r),
                (s.value.g, e.value.g),
                (s.value.b, e.value.b),
            ] {
                assert_eq!(a.to_bits(), b.to_bits(), "value at {wo:?} {:?}", s.wi);
            }
            checked += 1;
        }
        assert!(checked > 10000, "{checked} samples checked");
    }
}
