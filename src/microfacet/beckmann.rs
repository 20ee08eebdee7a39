//! Beckmann, anisotropic: `D(m) = exp(-((m.x / ax)^2 + (m.y / ay)^2) / m.z^2) / (pi ax ay
//! m.z^4)` (Walter et al. 2007 eq. 25), Smith `Lambda = (exp(-a^2) / (a sqrt(pi)) -
//! erfc(a)) / 2` with `a = |z| / p`, `p^2 = (ax w.x)^2 + (ay w.y)^2` (Heitz 2014 eq. 72),
//! visible normals by Heitz and d'Eon 2014 (as in pbrt-v3).

use super::{Ndf, SmithNdf, upper};
use crate::math::special::{INV_SQRT_PI, erf, erf_inv, erfc_nonneg};
use crate::math::{Lane, Mask, PI, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct Beckmann<L> {
    pub alpha_x: L,
    pub alpha_y: L,
}

impl<L: Lane> Ndf<L> for Beckmann<L> {
    #[inline(always)]
    fn d(&self, m: Vec3<L>) -> L {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let sx = m.x / ax;
        let sy = m.y / ay;
        let z2 = m.z * m.z;
        let e = (sx * sx + sy * sy).safe_div(z2);
        let value = (-e).exp().safe_div(L::splat(PI) * ax * ay * z2 * z2);
        L::select(m.z.gt(L::zero()), value, L::zero())
    }

    /// Heitz and d'Eon 2014 ("Importance Sampling Microfacet-Based BSDFs using the
    /// Distribution of Visible Normals"): stretch, sample the slope of the unit-roughness
    /// distribution, rotate and unstretch (`w` flipped to the upper hemisphere when below
    /// it). The stretched view's tangent and azimuth come straight from its components:
    /// `sqrt(1 - cos^2)` of a normalized vector loses the tangent near normal incidence
    /// (an f32 cosine resolves no angle below 3.5e-4).
    #[inline(always)]
    fn sample(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        let w = upper(w);
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let (wx, wy) = (ax * w.x, ay * w.y);
        let len = (wx * wx + wy * wy).sqrt();
        let has_phi = len.gt(L::zero());
        let cos_phi = L::select(has_phi, wx.safe_div(len), L::one());
        let sin_phi = L::select(has_phi, wy.safe_div(len), L::zero());
        let max_tan = L::splat(1e6);
        let tan_theta = L::select(w.z.gt(len / max_tan), len.safe_div(w.z), max_tan);
        let (sx, sy) = sample_slopes(tan_theta, u0, u1);
        let rx = cos_phi * sx - sin_phi * sy;
        let ry = sin_phi * sx + cos_phi * sy;
        Vec3::new(-rx * ax, -ry * ay, L::one()).normalize()
    }

    #[inline(always)]
    fn pdf(&self, w: Vec3<L>, m: Vec3<L>) -> L {
        self.pdf_visible(w, m)
    }
}

impl<L: Lane> SmithNdf<L> for Beckmann<L> {
    #[inline(always)]
    fn alpha(&self) -> (L, L) {
        (self.alpha_x, self.alpha_y)
    }

    /// `(p exp(-a^2) / sqrt(pi) - |z| erfc(a)) / 2` with `a = |z| / p`.
    #[inline(always)]
    fn lambda_cos(&self, w: Vec3<L>) -> L {
        let proj2 = (self.alpha_x * w.x).sqr() + (self.alpha_y * w.y).sqr();
        let z = w.z.abs();
        let p = proj2.sqrt();
        let a = z.safe_div(p);
        let lam =
            L::splat(0.5) * (p * (-(a * a)).exp() * L::splat(INV_SQRT_PI) - z * erfc_nonneg(a));
        // Lambda < 1e-9 past a = 4, where the two terms cancel in f32; along the
        // normal (p = 0) a is 0 by safe_div but Lambda is 0.
        L::select(
            a.lt(L::splat(4.0)) & p.gt(L::zero()),
            lam.max(L::zero()),
            L::zero(),
        )
    }
}

/// Slopes of visible normals of the unit-roughness Beckmann distribution seen at
/// `tan theta` (pbrt-v3 `BeckmannSample11`: a fitted initial guess refined by a
/// safeguarded Newton-bisection on the inverse CDF). The slope along the view has
/// density `~ exp(-x^2) (1 - x tan theta)` for `x < cot theta` (Heitz and d'Eon 2014
/// eq. 11), CDF `(1 + erf(x) + tan theta exp(-x^2) / sqrt(pi)) / (1 + erf(cot theta) +
/// tan theta exp(-cot^2 theta) / sqrt(pi))`, which is well conditioned in `b = erf(x)`
/// at every angle: at normal incidence it is `(1 + b) / 2`, and near it the view's
/// tilt enters linearly through `tan theta`. There is no normal-incidence branch.
#[inline(always)]
fn sample_slopes<L: Lane>(tan_theta: L, u0: L, u1: L) -> (L, L) {
    let u0c = u0.clamp(L::splat(1e-6), L::splat(1.0 - 1e-7));
    let u1c = u1.clamp(L::splat(1e-6), L::splat(1.0 - 1e-7));
    // erf(1e6) = 1 and exp(-1e12) = 0: the normal-incidence limit, reached smoothly.
    let cot_theta = L::one() / tan_theta.max(L::splat(1e-6));
    let mut a = -L::one();
    let mut c = erf(cot_theta);
    let theta = tan_theta.atan2(L::one());
    let fit = L::one()
        + theta * (L::splat(-0.876) + theta * (L::splat(0.4265) - L::splat(0.0594) * theta));
    let mut b = c - (L::one() + c) * (fit * (-u0c).ln_1p()).exp();
    let normalization = L::one()
        / (L::one() + c + L::splat(INV_SQRT_PI) * tan_theta * (-(cot_theta * cot_theta)).exp());
    let mut done = L::Mask::splat(false);
    for _ in 0..10 {
        let outside = b.lt(a) | b.gt(c);
        b = L::select(outside, L::splat(0.5) * (a + c), b);
        let inv_erf = erf_inv(b);
        let value = normalization
            * (L::one() + b + L::splat(INV_SQRT_PI) * tan_theta * (-(inv_erf * inv_erf)).exp())
            - u0c;
        let derivative = normalization * (L::one() - inv_erf * tan_theta);
        done = done | value.abs().lt(L::splat(1e-5));
        if done.all() {
            break;
        }
        let positive = value.gt(L::zero());
        c = L::select(positive & !done, b, c);
        a = L::select(!positive & !done, b, a);
        b = L::select(done, b, b - value.safe_div(derivative));
    }
    (erf_inv(b), erf_inv(L::splat(2.0) * u1c - L::one()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `G(x) = int_{-inf}^{x} e^{-s^2} (1 - s t) ds` for `x` on a uniform grid over
    /// `[-8, min(8, 1 / t)]`, by the trapezoid rule in f64 (step 1e-4: error ~1e-9):
    /// the unnormalized CDF of the slope of a visible unit-roughness Beckmann normal
    /// along the view azimuth, seen at `tan theta = t` (Heitz and d'Eon 2014 eq. 11,
    /// `D_w(m) ~ P22(x, y) (cos theta - x sin theta)`), independent of the sampler.
    struct SlopeCdf {
        lo: f64,
        h: f64,
        cumulative: Vec<f64>,
    }

    impl SlopeCdf {
        fn new(t: f64) -> SlopeCdf {
            let (lo, h) = (-8.0, 1e-4);
            let hi = if t > 0.0 { (1.0 / t).min(8.0) } else { 8.0 };
            let density = |s: f64| (-s * s).exp() * (1.0 - s * t).max(0.0);
            let n = ((hi - lo) / h).ceil() as usize;
            let mut cumulative = vec![0.0; n + 1];
            for i in 1..=n {
                let (a, b) = (lo + (i - 1) as f64 * h, (lo + i as f64 * h).min(hi));
                cumulative[i] = cumulative[i - 1] + 0.5 * (b - a) * (density(a) + density(b));
            }
            SlopeCdf { lo, h, cumulative }
        }

        /// The normalized CDF at `x`.
        fn at(&self, x: f64) -> f64 {
            let n = self.cumulative.len() - 1;
            let f = ((x - self.lo) / self.h).clamp(0.0, n as f64);
            let i = (f as usize).min(n - 1);
            let g =
                self.cumulative[i] + (f - i as f64) * (self.cumulative[i + 1] - self.cumulative[i]);
            g / self.cumulative[n]
        }
    }

    /// Every sampled visible normal, mapped back to unit-roughness slopes along and
    /// across the view azimuth, sits where the exact CDFs equal the random numbers
    /// used, for views from 0 to 89.9 degrees and alpha from 1e-3 to 1 (isotropic and
    /// anisotropic): the sampler follows the view at every angle, with no snapping to
    /// normal incidence.
    #[test]
    fn beckmann_visible_slopes_invert_the_exact_cdf() {
        let gaussian = SlopeCdf::new(0.0);
        let mut worst = (0.0f64, String::new());
        for &(ax, ay) in &[
            (1e-3f32, 1e-3f32),
            (3e-3, 3e-3),
            (0.01, 0.01),
            (0.03, 0.03),
            (0.1, 0.1),
            (0.3, 0.3),
            (1.0, 1.0),
            (0.02, 0.005),
        ] {
            let dist = Beckmann {
                alpha_x: ax,
                alpha_y: ay,
            };
            for &deg in &[
                0.0f64, 1e-3, 0.1, 1.0, 10.0, 20.0, 45.0, 50.0, 54.0, 60.0, 75.0, 85.0, 89.0, 89.9,
            ] {
                let (theta, phi) = (deg.to_radians(), 0.7f64);
                let w = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                // The stretched view (Heitz and d'Eon 2014 sec. 4): its tangent and azimuth.
                let (sx, sy) = (f64::from(ax * w.x), f64::from(ay * w.y));
                let len = (sx * sx + sy * sy).sqrt();
                let t = len / f64::from(w.z);
                let (cos_p, sin_p) = if len > 0.0 {
                    (sx / len, sy / len)
                } else {
                    (1.0, 0.0)
                };
                let along = SlopeCdf::new(t);
                for i in 0..400 {
                    let u0 = 0.002 + 0.996 * (i as f32 + 0.5) / 400.0;
                    let u1 = 0.002 + 0.996 * ((i * 7919 % 400) as f32 + 0.5) / 400.0;
                    let m = dist.sample(w, u0, u1);
                    let mx = -f64::from(m.x) / f64::from(m.z) / f64::from(ax);
                    let my = -f64::from(m.y) / f64::from(m.z) / f64::from(ay);
                    let x = cos_p * mx + sin_p * my;
                    let y = -sin_p * mx + cos_p * my;
                    let err = (along.at(x) - f64::from(u0))
                        .abs()
                        .max((gaussian.at(y) - f64::from(u1)).abs());
                    if err > worst.0 {
                        worst = (
                            err,
                            format!("alpha ({ax}, {ay}), theta_o {deg} deg, u ({u0}, {u1})"),
                        );
                    }
                }
            }
        }
        assert!(worst.0 < 5e-5, "CDF error {:.3e} at {}", worst.0, worst.1);
    }
}
