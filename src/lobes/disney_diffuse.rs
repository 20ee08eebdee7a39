//! `disney_diffuse`: the diffuse lobe of Disney's principled BRDF (Burley 2012,
//! "Physically-Based Shading at Disney", section 5.3; restated in
//! `shared/reference/formulas.md`, "Disney principled BRDF"):
//!
//! ```text
//! f  = (1/pi) mix(Fd, ss, subsurface) base_color
//! Fd = mix(1, Fd90, FL) mix(1, Fd90, FV),     Fd90  = 0.5 + 2 roughness cos^2(theta_d)
//! ss = 1.25 (Fss (1 / (cos_i + cos_o) - 0.5) + 0.5)
//! Fss = mix(1, Fss90, FL) mix(1, Fss90, FV),  Fss90 = roughness cos^2(theta_d)
//! ```
//!
//! with the Schlick weights `FL = (1 - cos_i)^5`, `FV = (1 - cos_o)^5` and
//! `cos^2(theta_d) = (l.h)^2 = (1 + l.v) / 2` (no half vector needed). Smooth surfaces
//! darken at grazing (the Fresnel shadow: `Fd90 = 0.5` halves one direction's factor),
//! rough ones brighten up to `Fd90 = 2.5` (roughness 1, `theta_d = 0`); `ss` is
//! Burley's Hanrahan-Krueger-like flattened subsurface shape.
//!
//! Parameters:
//! - `base_color` (rgb, [0, 1], default 0.8);
//! - `roughness` (float, [0, 1], default 0.5);
//! - `subsurface` (float, [0, 1], default 0): blend from `Fd` to `ss`.
//!
//! Sampling is cosine-weighted (`pdf = cos_i / pi`), so the weight is
//! `mix(Fd, ss, subsurface) base_color`. One-sided: 0 below the surface.
//!
//! The model is reciprocal but not energy conserving: with a white base color its
//! albedo exceeds 1 from roughness 0.5 (1.006 at normal view) up to 1.56 (roughness 1,
//! grazing view). `energy_bound` states it (the largest closed-form albedo over `cos_o`),
//! and the harness's energy check holds the sampled albedo to that bound.
//!
//! Albedo: closed form, one family of its integrals by a 12-point Gauss-Legendre rule
//! from `cos_o = 0.1` on, where the closed form cancels (see `albedo` below): worst
//! relative error 4.3e-7 against f64 quadrature over roughness and subsurface in
//! {0, 0.25, 0.5, 0.75, 1} and `cos_o` from 1e-6 to 1 (tests/lobe_disney_diffuse.rs).
//! Its estimate (lobe selection and pruning) keeps the `Fd` part's closed form, which
//! is cheap, and replaces the subsurface part's logarithm and quadrature by a fit:
//! quadratic in roughness (as the closed form is) with coefficients of degree 8 in
//! `sqrt(cos_o)`, centered ([`SS_FIT`]): no table, no gather.

use super::lambert::cosine_hemisphere;
use super::{
    Eval, Model, Params, Sample, Settle, Transport, VerifyCase, both_above, class_of, flags,
};
use crate::fresnel::{schlick_weight, schlick_weight_in_range};
use crate::math::vmath::estrin9;
use crate::math::{INV_PI, Lane, Mask, Rgb, Vec3};
use crate::params::{ParamSpec, offset_of};

pub struct DisneyDiffuse;

const BASE_COLOR: usize = offset_of(DisneyDiffuse::PARAMS, 0);
const ROUGHNESS: usize = offset_of(DisneyDiffuse::PARAMS, 1);
const SUBSURFACE: usize = offset_of(DisneyDiffuse::PARAMS, 2);

pub struct Prepared<L> {
    base_color: Rgb<L>,
    roughness: L,
    subsurface: L,
    /// The blend's weights with `1 / pi` (and `ss`'s 1.25) in them: `(1 - subsurface)
    /// / pi`, `1.25 subsurface / pi`, so that an eval does not multiply by them.
    fd_weight: L,
    ss_weight: L,
}

/// `mix(1, F90, FL) mix(1, F90, FV) = (1 + (F90 - 1) FL) (1 + (F90 - 1) FV)`. A
/// function, not a closure: a closure is a function of its own that LLVM may leave out
/// of line, without the kernel's target features (tests/simd_inlining.rs).
#[inline(always)]
fn fresnel_pair<L: Lane>(f90_minus_1: L, (fl, fv): (L, L)) -> L {
    f90_minus_1.mul_add(fl, L::one()) * f90_minus_1.mul_add(fv, L::one())
}

/// `mix(Fd, ss, subsurface) cos_i / pi`, 0 unless both directions are above the
/// surface. `ss cos_i` is written `1.25 (Fss (cos_i / (cos_i + cos_o) - cos_i / 2) +
/// cos_i / 2)`, finite for any positive cosines.
#[inline(always)]
fn shape<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>) -> L {
    let ok = both_above(wo, wi);
    let (cos_o, cos_i) = (wo.z.min(L::one()), wi.z.min(L::one()));
    // `(1 + l.v) / 2` as one multiply-add: the same rounding (halving is exact).
    let cos2_d = wo
        .dot_fused(wi)
        .mul_add(L::splat(0.5), L::splat(0.5))
        .clamp(L::zero(), L::one());
    // The cosines are in (0, 1] wherever the shape is kept (`ok`).
    let weights = (
        schlick_weight_in_range(cos_i),
        schlick_weight_in_range(cos_o),
    );
    let fd = fresnel_pair(
        (L::splat(2.0) * p.roughness).mul_add(cos2_d, L::splat(-0.5)),
        weights,
    );
    let fss = fresnel_pair(p.roughness.mul_add(cos2_d, -L::one()), weights);
    let half = cos_i * L::splat(0.5);
    // Where a direction is below the surface the sum may be 0: divided by 1 there, and
    // selected away below.
    let ratio = cos_i / L::select(ok, cos_i + cos_o, L::one());
    let ss = fss.mul_add(ratio - half, half);
    let mixed = (fd * cos_i).mul_add(p.fd_weight, ss * p.ss_weight);
    L::select(ok, mixed, L::zero())
}

/// `2 int_0^1 <F> mu w(mu) dmu` for `F = mix(1, 1 + k, FL) mix(1, 1 + k, FV)` with
/// `k = k0 + k1 (l.v)`, averaged over the azimuth of `wi` (`<.>`): with `a = cos_o`,
/// `<l.v> = a mu` and `<(l.v)^2> = a^2 mu^2 + (1 - a^2)(1 - mu^2) / 2`, so `<k>` and
/// `<k^2>` are polynomials in `mu` and the integral reduces to the moments
/// `t_j = int mu^j w` and `u_j = int mu^j FL w` (`t = [t1, t2]`, `u = [u1, u2, u3]`).
#[inline(always)]
fn fresnel_pair_moment<L: Lane>(k0: L, k1: L, a: L, fv: L, t: [L; 2], u: [L; 3]) -> L {
    let (a2, half) = (a * a, L::splat(0.5));
    // <k> = k0 + c1 mu; <k^2> = e0 + e1 mu + e2 mu^2.
    let c1 = k1 * a;
    let e0 = k0 * k0 + k1 * k1 * (L::one() - a2) * half;
    let e1 = L::splat(2.0) * k0 * c1;
    let e2 = k1 * k1 * (L::splat(3.0) * a2 - L::one()) * half;
    // mu <F> = mu + <k> mu (FL + FV) + <k^2> mu FL FV.
    let sum = t[0]
        + k0 * (u[0] + fv * t[0])
        + c1 * (u[1] + fv * t[1])
        + fv * (e0 * u[0] + e1 * u[1] + e2 * u[2]);
    L::splat(2.0) * sum
}

/// The cosine below which the albedo is evaluated at this cosine (`ln(1 + 1/a)` stays
/// finite; the albedo's change below it is under 1e-10).
const ALBEDO_MIN_COS: f32 = 1e-12;

/// From this `cos_o` on, `u_j = int mu^j FL / (mu + a)` comes from [`QUAD_NODES`]: the
/// recurrence's `u_j` carry `a^j (1 + a)^5 J_0` (up to `22 J_0` at `a = 1`), which
/// cancels to a small value and amplifies the rounding of `ln` (5.9e-6 between the
/// scalar and SIMD `ln` at `a = 1`); below it the factor is at most 0.39.
const QUAD_MIN_COS: f32 = 0.1;

/// 12-point Gauss-Legendre nodes on [0, 1] and weights times `mu (1 - mu)^5`: for
/// `a >= 0.1` the pole of `1 / (mu + a)` is far enough that the rule's error is below
/// 1.7e-7 (absolute, on `u_1..u_3`).
const QUAD_NODES: [f32; 12] = [
    9.219683e-3,
    4.794137e-2,
    1.1504866e-1,
    2.0634103e-1,
    3.1608425e-1,
    4.373833e-1,
    5.626167e-1,
    6.8391575e-1,
    7.93659e-1,
    8.8495134e-1,
    9.520586e-1,
    9.907803e-1,
];
const QUAD_WEIGHTS: [f32; 12] = [
    2.0762892e-4,
    2.0051016e-3,
    4.9978253e-3,
    6.600538e-3,
    5.521523e-3,
    3.0715038e-3,
    1.1218876e-3,
    2.519184e-4,
    3.0156846e-5,
    1.4276765e-6,
    1.2892093e-8,
    1.556834e-12,
];

impl Model for DisneyDiffuse {
    const NAME: &'static str = "disney_diffuse";
    const SUMMARY: &'static str =
        "Disney principled diffuse (Burley 2012): grazing retro-reflection, subsurface blend";
    const DECODE_COPIES: bool = true;
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::rgb("base_color", [0.8; 3], 0.0, 1.0, "diffuse color"),
        ParamSpec::float(
            "roughness",
            0.5,
            0.0,
            1.0,
            "Fd90 = 0.5 + 2 roughness cos^2(theta_d): darker (0) or brighter (1) at grazing",
        ),
        ParamSpec::float(
            "subsurface",
            0.0,
            0.0,
            1.0,
            "blend to Burley's Hanrahan-Krueger-like subsurface shape",
        ),
    ];
    const FLAGS: u32 = flags::REFLECTION | flags::DIFFUSE;
    const RECIPROCAL: bool = true;
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "smooth white",
            set: &[("roughness", 0.0), ("base_color", 1.0)],
        },
        VerifyCase {
            name: "black",
            set: &[("base_color", 0.0)],
        },
        VerifyCase {
            name: "rough",
            set: &[("roughness", 1.0), ("base_color", 0.65)],
        },
        VerifyCase {
            name: "rough white (albedo above 1)",
            set: &[("roughness", 1.0), ("base_color", 1.0)],
        },
        VerifyCase {
            name: "subsurface 0.5",
            set: &[("subsurface", 0.5)],
        },
        VerifyCase {
            name: "smooth subsurface 1",
            set: &[("roughness", 0.0), ("subsurface", 1.0)],
        },
        VerifyCase {
            name: "rough subsurface 1",
            set: &[
                ("roughness", 1.0),
                ("subsurface", 1.0),
                ("base_color", 0.65),
            ],
        },
    ];

    const VALID_ABOVE: bool = true;
    type Prepared<L: Lane> = Prepared<L>;

    /// Closed form (and Gauss-Legendre) in f32: measured worst relative error 4.3e-7
    /// (module docs).
    fn albedo_tolerance(_params: &[f32]) -> f32 {
        1e-4
    }

    /// [`SS_FIT`]: within 3e-4 of the closed form (least squares over 257 `cos_o` x 33
    /// roughness, tests/lobe_disney_diffuse.rs measures it).
    fn albedo_estimate_tolerance(_params: &[f32]) -> f32 {
        1e-3
    }

    /// The closed-form albedo's largest channel over 65 `cos_o` from grazing to normal
    /// (it is smooth in `cos_o`; the 1e-3 margin covers the grid), at least 1.
    fn energy_bound(params: &[f32]) -> f32 {
        let p = Self::prepare(Params::new(params));
        (0..=64)
            .map(|i| {
                let cos_o = (i as f32 / 64.0).max(1e-6);
                let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
                let a = Self::albedo(&p, wo, Transport::Radiance);
                a.r.max(a.g).max(a.b)
            })
            .fold(1.0, f32::max)
            * 1.001
    }

    #[inline(always)]
    fn prepare<L: Lane>(params: Params<'_, L>) -> Prepared<L> {
        let subsurface = params.float(SUBSURFACE);
        Prepared {
            base_color: params.rgb(BASE_COLOR),
            roughness: params.float(ROUGHNESS),
            subsurface,
            fd_weight: (L::one() - subsurface) * L::splat(INV_PI),
            ss_weight: subsurface * L::splat(1.25 * INV_PI),
        }
    }

    #[inline(always)]
    fn eval<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, wi: Vec3<L>, _mode: Transport) -> Eval<L> {
        let pdf = L::select(both_above(wo, wi), wi.z, L::zero()) * L::splat(INV_PI);
        Eval {
            value: p.base_color * shape(p, wo, wi),
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

    /// `R(wo) = base_color ((1 - subsurface) A_d + subsurface A_ss)` with `a = cos_o`,
    /// both terms by [`fresnel_pair_moment`]:
    /// - `A_d` (`k0 = roughness - 1/2`, `k1 = roughness`) with the Beta integrals
    ///   `t_j = 1/(j+1)`, `u_j = j! 5! / (j+6)!`;
    /// - `A_ss = 1.25 (S_w - S_1 / 2 + 1/2)` (`k0 = roughness/2 - 1`,
    ///   `k1 = roughness/2`), `S_1` with the weights above and `S_w` with
    ///   `w = 1 / (mu + a)`: `t_j = J_j`, `u_j = sum_i C(5, i) (-1)^i J_(j+i)`, where
    ///   `J_n = int_0^1 mu^n / (mu + a) dmu = 1/n - a J_(n-1)`, `J_0 = ln((1 + a) / a)`
    ///   (the recurrence only shrinks errors for `a <= 1`; `a J_0 -> 0` as `a -> 0`);
    ///   from `a = 0.1` on, `u_j` by Gauss-Legendre ([`QUAD_MIN_COS`]).
    #[inline(always)]
    fn albedo<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        let a = wo.z.clamp(L::splat(ALBEDO_MIN_COS), L::one());
        let fv = schlick_weight(a);
        let r = p.roughness;
        let half = L::splat(0.5);
        let (t_poly, u_poly) = polynomial_moments();
        let a_d = fresnel_pair_moment(r - half, r, a, fv, t_poly, u_poly);

        let mut j = [L::zero(); 9];
        j[0] = ((L::one() + a) / a).ln();
        for n in 1..9 {
            j[n] = L::splat(1.0 / n as f32) - a * j[n - 1];
        }
        // (1 - mu)^5 = sum_i C(5, i) (-1)^i mu^i.
        let binomial = [1.0, -5.0, 10.0, -10.0, 5.0, -1.0];
        // Plain loops, here and below: a closure is a function without the kernel's
        // target features (tests/simd_inlining.rs).
        let mut u_recurrence = [L::zero(); 3];
        for (k, u) in u_recurrence.iter_mut().enumerate() {
            for (i, &c) in binomial.iter().enumerate() {
                *u += L::splat(c) * j[k + 1 + i];
            }
        }
        let mut u_quad = [L::zero(); 3];
        for (&mu, &w) in QUAD_NODES.iter().zip(&QUAD_WEIGHTS) {
            let mu = L::splat(mu);
            let w1 = L::splat(w) / (mu + a);
            u_quad[0] += w1;
            u_quad[1] += w1 * mu;
            u_quad[2] += w1 * mu * mu;
        }
        let quad = a.ge(L::splat(QUAD_MIN_COS));
        let mut u_w = u_recurrence;
        for (u, q) in u_w.iter_mut().zip(u_quad) {
            *u = L::select(quad, q, *u);
        }
        let (k0, k1) = (r * half - L::one(), r * half);
        let s_w = fresnel_pair_moment(k0, k1, a, fv, [j[1], j[2]], u_w);
        let s_1 = fresnel_pair_moment(k0, k1, a, fv, t_poly, u_poly);
        let a_ss = L::splat(1.25) * (s_w - s_1 * half + half);

        let s = p.subsurface;
        let total = a_d * (L::one() - s) + a_ss * s;
        Rgb::select(wo.z.gt(L::zero()), p.base_color * total, Rgb::zero())
    }

    /// The `Fd` part in closed form, the subsurface part by [`SS_FIT`].
    #[inline(always)]
    fn albedo_estimate<L: Lane>(p: &Prepared<L>, wo: Vec3<L>, _mode: Transport) -> Rgb<L> {
        let a = wo.z.clamp(L::splat(ALBEDO_MIN_COS), L::one());
        let r = p.roughness;
        let (t_poly, u_poly) = polynomial_moments();
        let a_d = fresnel_pair_moment(r - L::splat(0.5), r, a, schlick_weight(a), t_poly, u_poly);
        let s = p.subsurface;
        // Without subsurface (most materials) the blend is `a_d * 1 + a_ss * 0`, `a_d`'s
        // bits: the fit's 27 coefficients are skipped.
        let total = if s.gt(L::zero()).any() {
            // `2 sqrt(cos_o) - 1` as one multiply-add: the same rounding (doubling is
            // exact).
            let t = a.sqrt().mul_add(L::splat(2.0), -L::one());
            let [c0, c1, c2] = SS_FIT;
            let a_ss = estrin9(t, c0) + r * (estrin9(t, c1) + r * estrin9(t, c2));
            a_d * (L::one() - s) + a_ss * s
        } else {
            a_d
        };
        Rgb::select(wo.z.gt(L::zero()), p.base_color * total, Rgb::zero())
    }
}

/// The `t` and `u` moments of the `Fd` shape's polynomial weights (`mu^0` and the
/// closed-form `u_j = int mu^j (1 - mu)^5`), as `fresnel_pair_moment` takes them.
#[inline(always)]
fn polynomial_moments<L: Lane>() -> ([L; 2], [L; 3]) {
    (
        [L::splat(0.5), L::splat(1.0 / 3.0)],
        [
            L::splat(1.0 / 42.0),
            L::splat(1.0 / 168.0),
            L::splat(1.0 / 504.0),
        ],
    )
}

/// The subsurface shape's albedo (white base color) is `c0 + c1 r + c2 r^2` in the
/// roughness `r`; each `c` as a polynomial in `t = 2 sqrt(cos_o) - 1`, highest degree
/// first (least squares of the relative error against `albedo` over 257 `cos_o` from
/// 1e-8 to 1 and 33 roughnesses: worst 2.8e-4).
///
/// Centered because the SIMD lanes' multiply-adds are fused and the scalar lane's are
/// not, and a material batch (SIMD) must select lobes as its lane's closure (scalar)
/// does. In powers of `sqrt(cos_o)` on [0, 1] the same polynomials have coefficients up
/// to 152, whose terms sum to 700 in magnitude for an albedo of 0.76 (roughness 1,
/// `cos_o = 1`): that cancellation put the lanes 2.6e-5 apart. On [-1, 1] the terms
/// sum to at most 8.5 times the albedo, and the lanes agree within 5e-7
/// (tests/lobe_disney_diffuse.rs). The coefficients are those polynomials rewritten
/// exactly in `t`, then rounded to f32 (which moves the fit by at most 1e-7).
const SS_FIT: [[f32; 9]; 3] = [
    [
        -2.7354611e-2,
        1.642267e-1,
        -5.8353104e-2,
        -5.751976e-1,
        6.123489e-1,
        5.20007e-1,
        -1.0520557e0,
        -4.705534e-2,
        1.2122191e0,
    ],
    [
        -2.6925893e-3,
        -6.153869e-2,
        7.928061e-2,
        2.1412283e-1,
        -3.9183626e-1,
        -6.58064e-2,
        5.486723e-1,
        -4.532002e-1,
        1.4406255e-1,
    ],
    [
        -1.5676467e-2,
        2.47799e-2,
        -3.96315e-3,
        1.4110357e-3,
        4.3660216e-3,
        -5.4369435e-2,
        7.8213476e-2,
        -4.3918803e-2,
        9.122716e-3,
    ],
];
