//! `mirror`: perfect specular reflection, a delta lobe: `wi = reflect(wo, n)` with
//! the reflected fraction given by the shared Fresnel group (default: Schlick with
//! `f0 = f90 = 1`, a perfect white mirror).
//!
//! Parameters: the Fresnel group (`fresnel` = `schlick` | `conductor` | `artistic`,
//! with `f0`, `f90`, `eta`, `k`, `reflectivity`, `edge_tint`).
//!
//! eval and pdf are 0 (delta); a sample has value `F(cos_o)`, pdf 1 (the discrete
//! probability) and the SPECULAR class. Albedo is exactly `F(cos_o)`. One-sided.
//! `F(cos_o)` depends on `wo` alone: a closure built with a `wo` bakes it once
//! (the selection albedo and every sample at that `wo` read it).

use super::fresnel_params::{self, with_fresnel_params};
use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, baked_or, class_of, flags,
};
use crate::fresnel::FresnelModel;
use crate::math::{Lane, Mask, Rgb, Vec3};
use crate::params::{ParamSpec, offset_of};

pub struct Mirror;

const FRESNEL: usize = offset_of(Mirror::PARAMS, 0);
/// Decoded block: the Fresnel group, then the bake: `cos_o` (NaN = unbaked) and `F(cos_o)`.
const BAKED: usize = fresnel_params::DECODED_LEN;

pub struct Prepared<L> {
    fresnel: FresnelModel<L>,
    baked_cos: L,
    baked_f: Rgb<L>,
}

impl<L: Lane> Prepared<L> {
    /// `F(cos_o)`, baked or computed.
    #[inline(always)]
    fn fresnel(&self, cos_o: L) -> Rgb<L> {
        baked_or(
            cos_o,
            self.baked_cos,
            self.baked_f,
            #[inline(always)]
            || self.fresnel.eval(cos_o),
        )
    }
}

impl Model for Mirror {
    const NAME: &'static str = "mirror";
    const SUMMARY: &'static str = "Perfect specular reflection (delta) with a choice of Fresnel";
    const PARAMS: &'static [ParamSpec] = with_fresnel_params!(0;);
    const FLAGS: u32 = flags::REFLECTION | flags::SPECULAR;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "conductor",
            set: &[("fresnel", 1.0)],
        },
        VerifyCase {
            name: "artistic",
            set: &[("fresnel", 2.0)],
        },
    ];

    type Prepared<L: Lane> = Prepared<L>;

    /// Closed form: exact up to rounding.
    fn albedo_tolerance(_params: &[f32]) -> f32 {
        1e-5
    }

    const DECODED_LEN: usize = BAKED + 4;

    fn decode(params: &[f32], out: &mut [f32]) {
        fresnel_params::decode(params, FRESNEL, out);
        out[BAKED..].fill(f32::NAN);
    }

    fn bake(decoded: &mut [f32], wo: Vec3<f32>, _mode: Transport) {
        let f = fresnel_params::read(&Params::<f32>::new(decoded), 0).eval(wo.z);
        decoded[BAKED] = wo.z;
        decoded[BAKED + 1..].copy_from_slice(&f.to_array());
    }

    #[inline(always)]
    fn prepare<L: Lane>(decoded: Params<'_, L>) -> Prepared<L> {
        Prepared {
            fresnel: fresnel_params::read(&decoded, 0),
            baked_cos: decoded.float(BAKED),
            baked_f: decoded.rgb(BAKED + 1),
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(_p: &Prepared<L>, _wo: Vec3<L>, _wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        Eval::zero()
    }

    #[inline(always)]
    fn sample<L: Lane>(
        p: &Prepared<L>,
        wo: Vec3<L>,
        _uc: L,
        _u0: L,
        _u1: L,
        _mode: Transport,
        settle: &mut impl Settle<L>,
    ) -> Sample<L> {
        Sample {
            wi: settle.settle(Vec3::new(-wo.x, -wo.y, wo.z)),
            value: p.fresnel(wo.z),
            pdf: L::one(),
            valid: wo.z.gt(L::zero()),
            transmitted: L::Mask::splat(false),
            delta: L::Mask::splat(true),
            eta: L::one(),
            roughness: L::zero(),
            class: class_of(L::Mask::splat(true), Self::FLAGS),
            component: L::zero(),
        }
    }

    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        Rgb::select(wo.z.gt(L::zero()), p.fresnel(wo.z), Rgb::zero())
    }
}
