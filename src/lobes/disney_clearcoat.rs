//! `disney_clearcoat`: the clearcoat lobe of Disney's principled BRDF (Burley 2012,
//! section 5.4; restated in `shared/reference/formulas.md`):
//!
//! ```text
//! f  = Dr Fr Gr
//! Dr = GTR1(n.h, a) = (a^2 - 1) / (pi ln(a^2) (1 + (a^2 - 1) cos_h^2)),
//!      a = mix(0.1, 0.001, gloss)                       (Berry's distribution)
//! Fr = mix(0.04, 1, FH),  FH = (1 - l.h)^5               (IOR 1.5)
//! Gr = SmithG_GGX(n.l, 0.25) SmithG_GGX(n.v, 0.25),
//!      SmithG_GGX(c, a) = 1 / (c + sqrt(a^2 + c^2 - a^2 c^2))
//! ```
//!
//! The masking's roughness is fixed at 0.25 whatever the gloss; `Gr` carries the
//! microfacet `1 / (4 cos_i cos_o)`. The Disney material weights the lobe by
//! `0.25 clearcoat`.
//!
//! Parameters:
//! - `gloss` (float, [0, 1], default 1): clearcoatGloss.
//!
//! `Dr` is [`Gtr1`], its constants computed once per lobe in f64 at decode.
//!
//! Sampling: GTR1 half vectors in closed form ([`Gtr1`]'s sampler), `l = reflect(v, h)`,
//! pdf `Dr cos_h / (4 v.h)`. Albedo from `albedo_table::disney::ClearcoatTable`. One-sided.

use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, both_above, class_of, flags,
};
use crate::albedo_table::disney::ClearcoatTable;
use crate::fresnel::HalfVector;
use crate::math::{Lane, Mask, Rgb, Vec3};
use crate::microfacet::{Gtr1, Ndf};
use crate::params::{ParamSpec, offset_of};

pub struct DisneyClearcoat;

const GLOSS: usize = offset_of(DisneyClearcoat::PARAMS, 0);

/// The decoded block: gloss, then GTR1's constants ([`Gtr1::constants`]).
const D_GLOSS: usize = 0;
const D_A2: usize = 1;
const D_NORM: usize = 2;
const D_LN_A2: usize = 3;
const D_INV_1MA2: usize = 4;

pub struct Prepared<L> {
    gloss: L,
    gtr1: Gtr1<L>,
}

/// `1 / SmithG_GGX(c, 0.25) = c + sqrt(a^2 + c^2 - a^2 c^2)`, the root's argument as
/// `c^2 (1 - a^2) + a^2` (no cancellation: both terms are positive).
#[inline(always)]
fn smith_denominator<L: Lane>(c: L) -> L {
    let a2 = 0.0625;
    c + (c * c).mul_add(L::splat(1.0 - a2), L::splat(a2)).sqrt()
}

impl Model for DisneyClearcoat {
    const NAME: &'static str = "disney_clearcoat";
    const SUMMARY: &'static str =
        "Disney principled clearcoat (Burley 2012): GTR1, Schlick IOR 1.5, masking roughness 0.25";
    const PARAMS: &'static [ParamSpec] = &[ParamSpec::float(
        "gloss",
        1.0,
        0.0,
        1.0,
        "GTR1 alpha mix(0.1, 0.001, gloss)",
    )];
    const FLAGS: u32 = flags::REFLECTION | flags::GLOSSY;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "gloss 0",
            set: &[("gloss", 0.0)],
        },
        VerifyCase {
            name: "gloss 0.5",
            set: &[("gloss", 0.5)],
        },
    ];

    const VALID_ABOVE: bool = true;
    type Prepared<L: Lane> = Prepared<L>;

    /// Table of f64 quadratures, interpolated: measured in
    /// tests/lobe_disney_clearcoat.rs (gloss 0..1, `cos_o` 0.02..1): worst 0.09%.
    fn albedo_tolerance(_params: &[f32]) -> f32 {
        0.005
    }

    const DECODED_LEN: usize = 5;

    fn decode(params: &[f32], out: &mut [f32]) {
        out[D_GLOSS] = params[GLOSS];
        // a = mix(0.1, 0.001, gloss) <= 0.1, so ln(a^2) <= -4.6.
        let a = 0.1 + (0.001 - 0.1) * f64::from(params[GLOSS].clamp(0.0, 1.0));
        for (o, c) in out[D_A2..].iter_mut().zip(Gtr1::constants(a)) {
            *o = c as f32;
        }
    }

    #[inline(always)]
    fn prepare<L: Lane>(p: Params<'_, L>) -> Prepared<L> {
        Prepared {
            gloss: p.float(D_GLOSS),
            gtr1: Gtr1 {
                a2: p.float(D_A2),
                norm: p.float(D_NORM),
                ln_a2: p.float(D_LN_A2),
                inv_one_minus_a2: p.float(D_INV_1MA2),
            },
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        // No early exit for a register below the surface: a branch here would keep a
        // fused kernel from sharing the half vector with the other lobes.
        let half = HalfVector::of(wo, wi);
        let h = half.sum;
        let ok = both_above(wo, wi) & half.exists & h.z.gt(L::zero());
        // Dr = norm / e (`Gtr1::denominator`), Gr = 1 / (c_i c_o), and the pdf
        // Dr cos_h / (4 v.h) with v.h = |wo + wi| / 2. `e` is homogeneous of degree 2:
        // for the half vector's unnormalized `s` = c (wo + wi) (`HalfVector::scale`),
        // e(h) = e(s) / |s|^2 and cos_h / v.h = 2 c s.z / |s|^2, so one division serves
        // both: e(s) >= a^2 |s|^2 >= 1.5e-8 and c_i, c_o >= 0.25.
        let e = p.gtr1.denominator(h);
        let c_io = smith_denominator(wi.z) * smith_denominator(wo.z);
        let inv = L::one() / L::select(ok, e * c_io, L::one());
        let norm = p.gtr1.norm;
        let pdf = L::select(
            ok,
            L::splat(0.5) * norm * h.z * half.scale * c_io * inv,
            L::zero(),
        );
        let fr = L::splat(0.96).mul_add(half.fh, L::splat(0.04));
        let value = norm * fr * wi.z * half.sum_len2 * inv;
        let value = L::select(ok, value, L::zero());
        Eval {
            value: Rgb::new(value, value, value),
            pdf,
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
        let h = p.gtr1.sample(wo, u0, u1);
        let wi = settle.settle(wo.reflect(h));
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
            // The width of the coat as a roughness: sqrt(alpha).
            roughness: (L::splat(0.1) + L::splat(0.001 - 0.1) * p.gloss).sqrt(),
            class: class_of(L::Mask::splat(false), Self::FLAGS),
            component: L::zero(),
        }
    }

    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        let a = L::select(
            wo.z.gt(L::zero()),
            ClearcoatTable::lookup(wo, p.gloss),
            L::zero(),
        );
        Rgb::new(a, a, a)
    }
}
