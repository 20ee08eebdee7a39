//! `lambert`: ideal diffuse reflection, `f = color / pi` (Lambert 1760; seed 001,
//! "Light Intensities").
//!
//! Parameters:
//! - `color` (rgb, [0, 1], default 0.8): the albedo.
//!
//! Sampling is cosine-weighted (`pdf = cos theta_i / pi`), so the sample weight is
//! exactly `color`. Albedo is the closed form `color`. One-sided: 0 below the surface.

use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, both_above, class_of, flags,
};
use crate::math::{INV_PI, Lane, Mask, Rgb, Vec3, azimuth};
use crate::params::{ParamSpec, offset_of};

pub struct Lambert;

const COLOR: usize = offset_of(Lambert::PARAMS, 0);

pub struct Prepared<L> {
    color: Rgb<L>,
}

impl Model for Lambert {
    const NAME: &'static str = "lambert";
    const SUMMARY: &'static str = "Ideal diffuse reflection (Lambert)";
    const DECODE_COPIES: bool = true;
    const PARAMS: &'static [ParamSpec] = &[ParamSpec::rgb(
        "color",
        [0.8; 3],
        0.0,
        1.0,
        "diffuse albedo",
    )];
    const FLAGS: u32 = flags::REFLECTION | flags::DIFFUSE;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "white",
            set: &[("color", 1.0)],
        },
        VerifyCase {
            name: "black",
            set: &[("color", 0.0)],
        },
    ];

    type Prepared<L: Lane> = Prepared<L>;

    /// Closed form: exact up to rounding.
    fn albedo_tolerance(_params: &[f32]) -> f32 {
        1e-5
    }

    #[inline(always)]
    fn prepare<L: Lane>(params: Params<'_, L>) -> Prepared<L> {
        Prepared {
            color: params.rgb(COLOR),
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        let ok = both_above(wo, wi);
        let cos_i = L::select(ok, wi.z, L::zero());
        Eval {
            value: p.color * (cos_i * L::splat(INV_PI)),
            pdf: cos_i * L::splat(INV_PI),
        }
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
        let wi = settle.settle(cosine_hemisphere(u0, u1));
        let valid = both_above(wo, wi);
        let pdf = L::select(valid, wi.z, L::zero()) * L::splat(INV_PI);
        Sample {
            wi,
            value: p.color * pdf,
            pdf,
            valid,
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
        Rgb::select(wo.z.gt(L::zero()), p.color, Rgb::zero())
    }
}

/// A cosine-distributed direction (density `cos theta / pi`) by Malley's method: a
/// uniform disk point lifted to the hemisphere. Shared by the diffuse-like lobes.
#[inline(always)]
pub(crate) fn cosine_hemisphere<L: Lane>(u0: L, u1: L) -> Vec3<L> {
    let r = u0.sqrt();
    let (sin_phi, cos_phi) = azimuth(u1);
    let z = (L::one() - u0).safe_sqrt();
    Vec3::new(r * cos_phi, r * sin_phi, z)
}
