//! Fresnel reflectance: Schlick, exact dielectric, exact conductor, and
//! Gulbrandsen's artist-friendly conductor parameterization.

use crate::math::{Lane, Mask, Rgb, Vec3};

/// Generalized Schlick: `F0 + (F90 - F0) (1 - cos)^5` (Schlick 1994; seed 000's `FrnlBlend`).
#[inline(always)]
pub fn schlick<L: Lane>(f0: L, f90: L, cos_theta: L) -> L {
    (f90 - f0).mul_add(schlick_weight(cos_theta), f0)
}

/// Schlick's weight `clamp(1 - cos, 0, 1)^5` (Burley 2012's `SchlickWeight`).
#[inline(always)]
pub fn schlick_weight<L: Lane>(cos_theta: L) -> L {
    fifth_power((L::one() - cos_theta).clamp(L::zero(), L::one()))
}

/// [`schlick_weight`] without the clamp, for a cosine in [0, 1] (where the clamp
/// changes nothing) or on lanes the caller selects away.
#[inline(always)]
pub fn schlick_weight_in_range<L: Lane>(cos_theta: L) -> L {
    fifth_power(L::one() - cos_theta)
}

#[inline(always)]
fn fifth_power<L: Lane>(m: L) -> L {
    let m2 = m * m;
    m2 * m2 * m
}

/// The half vector of a reflection pair of unit directions and what Disney's lobes
/// take from it, without normalizing it: the lobes' homogeneous forms of `h` (GGX's
/// `q`, GTR1's denominator) take `wo + wi` as it is, so their divisions do not wait on
/// a square root and a division (the longest chain of a fused Disney eval). Once
/// inlined, every lobe of a fused kernel that asks shares it.
#[derive(Clone, Copy)]
pub struct HalfVector<L: Lane> {
    /// `wo + wi` times [`Self::scale`]; 0 when `wo = -wi`.
    pub sum: Vec3<L>,
    /// `|sum|^2`: in [2^-6, 2^34) where the half vector exists.
    pub sum_len2: L,
    /// The power of two `sum` is `wo + wi` times: 1 unless `|wo + wi|^2 < 2^-6`, where
    /// the homogeneous forms of a narrow lobe would leave the normal floats (GGX's
    /// `q^2` scales as `|wo + wi|^4` and is as small as 1e-24 at unit length). A power
    /// of two scales without rounding, so each lane's bits are those of the unscaled
    /// form wherever that stays normal, whatever its neighbours.
    pub scale: L,
    /// Burley's `FH = (1 - l.h)^5`.
    pub fh: L,
    /// Whether `wo + wi` is not 0.
    pub exists: L::Mask,
}

/// [`HalfVector::sum_len2`]'s floor: below it the sum is scaled.
const SUM_LEN2_MIN: f32 = 1.0 / 64.0;

impl<L: Lane> HalfVector<L> {
    /// With `len = |wo + wi|`, `l.h = len / 2` and `1 - l.h = |wo - wi|^2 / (2 (2 + len))`
    /// (no cancellation as `l.h -> 1`). Symmetric in `wo` and `wi`, so reciprocal to the
    /// last bit.
    #[inline(always)]
    pub fn of(wo: Vec3<L>, wi: Vec3<L>) -> Self {
        let sum = wo + wi;
        let len2 = sum.length_squared();
        let d = wo - wi;
        let m = (d.dot_fused(d) * L::splat(0.5) / (L::splat(2.0) + len2.sqrt())).min(L::one());
        let (sum, sum_len2, scale) = scaled(sum, len2);
        HalfVector {
            sum,
            sum_len2,
            scale,
            fh: fifth_power(m),
            exists: len2.gt(L::zero()),
        }
    }
}

/// `(c sum, |c sum|^2, c)` with `c` the power of two that brings `|sum|^2 = len2` (0 <
/// len2 < 2^-6) into [2^-6, 2^34), in steps of 2^20 (the smallest positive `len2`,
/// 2^-149, takes four); `c = 1` elsewhere. The steps only run in registers with such a
/// lane (nearly opposite directions: rare).
#[inline(always)]
fn scaled<L: Lane>(sum: Vec3<L>, len2: L) -> (Vec3<L>, L, L) {
    let floor = L::splat(SUM_LEN2_MIN);
    if !(len2.lt(floor) & len2.gt(L::zero())).any() {
        return (sum, len2, L::one());
    }
    let mut c = L::one();
    for _ in 0..4 {
        // `(len2 c) c`: `c c` overflows at the fourth step.
        c = L::select((len2 * c * c).lt(floor), c * L::splat(1048576.0), c);
    }
    let sum = sum * c;
    (sum, sum.length_squared(), c)
}

/// Burley's `FH = (1 - l.h)^5` of a reflection pair ([`HalfVector::fh`]; 0 when
/// `wo = -wi`).
#[inline(always)]
pub fn schlick_weight_pair<L: Lane>(wo: Vec3<L>, wi: Vec3<L>) -> L {
    HalfVector::of(wo, wi).fh
}

/// Exact unpolarized Fresnel reflectance of a dielectric interface with relative
/// IOR `eta` (inside over outside); `cos_theta_i < 0` means the ray arrives from inside.
/// Returns 1 under total internal reflection.
#[inline(always)]
pub fn dielectric<L: Lane>(cos_theta_i: L, eta: L) -> L {
    let cos_i = cos_theta_i.clamp(-L::one(), L::one());
    dielectric_sin2(cos_i, (L::one() - cos_i * cos_i).max(L::zero()), eta)
}

/// [`dielectric`] given also `sin^2 theta_i`. Near normal incidence `1 - cos^2` loses
/// most of its digits in f32, and with an extreme `eta` (`sin^2 theta_t = sin^2 theta_i
/// / eta^2`) they decide between refraction and total internal reflection: callers that
/// can form `sin^2` without cancellation (as `|w x m|^2`) pass it here.
#[inline(always)]
pub fn dielectric_sin2<L: Lane>(cos_theta_i: L, sin2_i: L, eta: L) -> L {
    let cos_i = cos_theta_i.clamp(-L::one(), L::one());
    let inside = cos_i.lt(L::zero());
    let eta = L::select(inside, L::one() / eta, eta);
    let cos_i = cos_i.abs();
    let sin2_t = sin2_i / (eta * eta);
    let tir = sin2_t.ge(L::one());
    let cos_t = (L::one() - sin2_t).safe_sqrt();
    let r_parl = (eta * cos_i - cos_t).safe_div(eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t).safe_div(cos_i + eta * cos_t);
    let f = L::splat(0.5) * (r_parl * r_parl + r_perp * r_perp);
    L::select(tir, L::one(), f.min(L::one()))
}

/// Exact unpolarized Fresnel reflectance of a conductor with complex IOR `eta + i k`
/// (real-valued form of the Fresnel equations, e.g. Lagarde 2013, "Memo on Fresnel
/// equations"), for `cos_theta` in [0, 1].
#[inline(always)]
pub fn conductor<L: Lane>(cos_theta: L, eta: L, k: L) -> L {
    conductor_with(cos_theta, &ConductorIor::new(eta, k))
}

/// The terms of [`conductor`] that depend on the IOR alone.
pub struct ConductorIor<L> {
    /// `eta^2 - k^2`.
    diff: L,
    /// `4 eta^2 k^2`.
    cross: L,
}

impl<L: Lane> ConductorIor<L> {
    #[inline(always)]
    pub fn new(eta: L, k: L) -> Self {
        let (eta2, k2) = (eta * eta, k * k);
        ConductorIor {
            diff: eta2 - k2,
            cross: L::splat(4.0) * eta2 * k2,
        }
    }
}

/// [`conductor`] at `cos_theta` with the IOR's terms computed once.
#[inline(always)]
pub fn conductor_with<L: Lane>(cos_theta: L, ior: &ConductorIor<L>) -> L {
    let cos = cos_theta.clamp(L::zero(), L::one());
    let cos2 = cos * cos;
    let sin2 = L::one() - cos2;
    let t0 = ior.diff - sin2;
    let a2_plus_b2 = (t0 * t0 + ior.cross).safe_sqrt();
    let a = (L::splat(0.5) * (a2_plus_b2 + t0)).safe_sqrt();
    let t1 = a2_plus_b2 + cos2;
    let t2 = L::splat(2.0) * a * cos;
    let t3 = cos2 * a2_plus_b2 + sin2 * sin2;
    let t4 = t2 * sin2;
    // With rs = (t1 - t2) / (t1 + t2) and rp = rs (t3 - t4) / (t3 + t4),
    // (rs + rp) / 2 = rs t3 / (t3 + t4): one division. The product of the denominators
    // cannot underflow: t1 + t2 >= cos^2 and t3 + t4 >= sin^4, so one is >= 1/4.
    ((t1 - t2) * t3)
        .safe_div((t1 + t2) * (t3 + t4))
        .clamp(L::zero(), L::one())
}

/// [`conductor`] at `N` angles; a plain loop of the inlined form, which the scalar
/// instance vectorizes across the angles (a closure's albedo evaluates 14 of them per
/// channel).
#[inline(always)]
pub fn conductor_at<L: Lane, const N: usize>(cos_theta: [L; N], ior: &ConductorIor<L>) -> [L; N] {
    let mut out = [L::zero(); N];
    for (f, &cos) in out.iter_mut().zip(cos_theta.iter()) {
        *f = conductor_with(cos, ior);
    }
    out
}

/// The largest reflectivity Gulbrandsen's mapping accepts: `n_max` and `k` diverge as
/// `r -> 1`, so reflectivity is clamped here (F at normal incidence stays >= 0.9999).
pub const GULBRANDSEN_MAX_REFLECTIVITY: f32 = 0.9999;

/// Gulbrandsen 2014 (JCGT 3(4)): reflectivity `r` and edge tint `g` to a complex IOR
/// `(n, k)`, for one channel.
#[inline(always)]
pub fn gulbrandsen_ior<L: Lane>(r: L, g: L) -> (L, L) {
    let r = r.clamp(L::zero(), L::splat(GULBRANDSEN_MAX_REFLECTIVITY));
    let g = g.clamp(L::zero(), L::one());
    let sqrt_r = r.sqrt();
    let n_min = (L::one() - r) / (L::one() + r);
    let n_max = (L::one() + sqrt_r) / (L::one() - sqrt_r);
    let n = g * n_min + (L::one() - g) * n_max;
    let k2 = (r * (n + L::one()).sqr() - (n - L::one()).sqr()) / (L::one() - r);
    (n, k2.safe_sqrt())
}

/// How a reflective lobe computes its Fresnel term; shared by every conductor-like lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FresnelModel<L> {
    /// Schlick with normal and grazing reflectance per channel.
    Schlick { f0: Rgb<L>, f90: Rgb<L> },
    /// Exact conductor with complex IOR per channel.
    Conductor { eta: Rgb<L>, k: Rgb<L> },
}

impl<L: Lane> FresnelModel<L> {
    /// The Gulbrandsen parameterization resolved once to an exact conductor.
    #[inline(always)]
    pub fn artistic(reflectivity: Rgb<L>, edge_tint: Rgb<L>) -> Self {
        let (er, kr) = gulbrandsen_ior(reflectivity.r, edge_tint.r);
        let (eg, kg) = gulbrandsen_ior(reflectivity.g, edge_tint.g);
        let (eb, kb) = gulbrandsen_ior(reflectivity.b, edge_tint.b);
        FresnelModel::Conductor {
            eta: Rgb::new(er, eg, eb),
            k: Rgb::new(kr, kg, kb),
        }
    }

    #[inline(always)]
    pub fn eval(&self, cos_theta: L) -> Rgb<L> {
        match self {
            FresnelModel::Schlick { f0, f90 } => f0.zip(
                *f90,
                #[inline(always)]
                |a, b| schlick(a, b, cos_theta),
            ),
            FresnelModel::Conductor { eta, k } => eta.zip(
                *k,
                #[inline(always)]
                |n, k| conductor(cos_theta, n, k),
            ),
        }
    }
}
