//! GGX (Trowbridge-Reitz), anisotropic: `D(m) = 1 / (pi ax ay t^2)` with
//! `t = (m.x / ax)^2 + (m.y / ay)^2 + m.z^2` (Walter et al. 2007 eq. 33, Heitz 2014 eq. 85), Smith
//! `Lambda = (sqrt(1 + p^2 / z^2) - 1) / 2` with `p^2 = (ax w.x)^2 + (ay w.y)^2`
//! (Heitz 2014 eq. 86), visible normals by Dupuy and Benyoub 2023's spherical caps.

use super::{Ndf, SmithNdf, View, upper};
use crate::math::{Lane, PI, Vec3, azimuth};

#[derive(Clone, Copy, Debug)]
pub struct Ggx<L> {
    pub alpha_x: L,
    pub alpha_y: L,
}

impl<L: Lane> Ggx<L> {
    /// `p^2 = (alpha_x w.x)^2 + (alpha_y w.y)^2`. This sum of squares and the others
    /// below are multiply-adds: their terms are positive, so nothing amplifies an
    /// ulp of rounding (unlike `Vec3::dot`'s differences).
    #[inline(always)]
    fn projected2(&self, w: Vec3<L>) -> L {
        let (x, y) = (self.alpha_x * w.x, self.alpha_y * w.y);
        x.mul_add(x, y * y)
    }

    /// `q = t (ax ay)^2 = (h.x ay)^2 + (h.y ax)^2 + (h.z ax ay)^2`, so that
    /// `D = (ax ay)^3 / (pi q^2)` without dividing by the alphas; for a unit `h`,
    /// `q >= min(ax, ay, ax ay)^2`: at least 1e-14 when one alpha is at least
    /// `DELTA_ALPHA` and the other `MIN_ALPHA`.
    #[inline(always)]
    pub fn q(&self, h: Vec3<L>) -> L {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let (x, y, z) = (h.x * ay, h.y * ax, h.z * (ax * ay));
        x.mul_add(x, y.mul_add(y, z * z))
    }
}

impl<L: Lane> Ndf<L> for Ggx<L> {
    #[inline(always)]
    fn d(&self, m: Vec3<L>) -> L {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let sx = m.x / ax;
        let sy = m.y / ay;
        let t = sx.mul_add(sx, sy.mul_add(sy, m.z * m.z));
        let value = L::one().safe_div(L::splat(PI) * ax * ay * t * t);
        L::select(m.z.gt(L::zero()), value, L::zero())
    }

    /// Dupuy and Benyoub 2023, "Sampling Visible GGX Normals with Spherical Caps": in
    /// the configuration stretched to the unit hemisphere, the visible normals seen
    /// from `v` are `c + v` for `c` uniform on the unit sphere's cap `z > -v.z`;
    /// stretched back (`w` flipped to the upper hemisphere when below it). The same
    /// density as Heitz 2018's listing 1 with fewer square roots and divisions. `u0`
    /// picks the cap's height, `u1` the azimuth (from `-v.xy`'s, see
    /// `Ggx::visible_normal`) by [`azimuth`], as the other distributions and the
    /// cosine hemisphere take it, so a fused sample computes one azimuth pair.
    #[inline(always)]
    fn sample(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        // The normal's length by `rsqrt`: an error in it scales the normal without
        // turning it, and the sample's value and pdf come from the settled direction.
        // Its square is >= 1e-12, a normal float.
        self.visible_normal(w, u0, u1).normalize_estimate()
    }

    /// `w` reflected about the unnormalized `Ggx::visible_normal` `m`:
    /// `m 2 (w.m) / |m|^2 - w`, one division in place of the normalization.
    #[inline(always)]
    fn sample_reflection(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        let m = self.visible_normal(w, u0, u1);
        m * (L::splat(2.0) * w.dot(m) / m.length_squared()) - w
    }

    #[inline(always)]
    fn pdf(&self, w: Vec3<L>, m: Vec3<L>) -> L {
        self.pdf_visible(w, m)
    }
}

impl<L: Lane> Ggx<L> {
    /// [`Ndf::sample`]'s normal before it is made unit, its squared length >= 1e-12.
    #[inline(always)]
    fn visible_normal(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        let w = upper(w);
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        // The stretched view made unit by `rsqrt` (relative error 2.1e-7: the caps'
        // density moves by as little; the sample's value and pdf come from its settled
        // direction): a fused Disney sample 2-4% faster than with a division and a
        // square root. `|v|^2 >= min(1, ax, ay)^2`, a normal float.
        let v = Vec3::new(ax * w.x, ay * w.y, w.z).normalize_estimate();
        // The cap's height z = (1 - u0)(1 + v.z) - v.z, measured from both ends without
        // cancellation: z + v.z = (1 - u0)(1 + v.z) and, with 1 - v.z^2 = |v.xy|^2,
        // 1 - z^2 = u0 (|v.xy|^2 + (1 - u0)(1 + v.z)^2).
        let above = L::one() + v.z;
        let one_minus_u0 = L::one() - u0;
        let lift = one_minus_u0 * above;
        let r2 = v.x * v.x + v.y * v.y;
        let sin2 = u0 * (r2 + lift * above);
        let sin_theta = sin2.safe_sqrt();
        let (sin_phi, cos_phi) = azimuth(u1);
        // The point's offset from `v` in xy, `c.xy + v.xy`, with the azimuth measured
        // counterclockwise from `-d`, `d = v.xy / r` (r = |v.xy|): `a d + b (d.y, -d.x)`
        // with `a = r - sin_theta cos_phi`, `b = sin_theta sin_phi`. Summed as
        // `c.xy + v.xy` it cancelled where the point nears `-v` (u0 near 1 at the
        // azimuth of `-v.xy`: the normal seen edge-on), turning the normal by up to
        // 0.13 rad at alpha 1. Here `a = (r - sin_theta) + sin_theta (1 - cos_phi)`,
        // `r - sin_theta = (r^2 - sin^2) / (r + sin_theta)` with
        // `r^2 - sin^2 = (1 - u0) (r^2 - u0 above^2)`, and `1 - cos_phi` as
        // `sin_phi^2 / (1 + cos_phi)` where `cos_phi > 0`: no term cancels, and one
        // division serves both.
        let has_axis = r2.ge(L::splat(1e-30));
        let inv_r = L::select(has_axis, r2.rsqrt(), L::zero());
        let (dx, dy) = (L::select(has_axis, v.x * inv_r, L::one()), v.y * inv_r);
        let r = r2 * inv_r;
        let near = one_minus_u0 * (r2 - u0 * (above * above));
        let positive = cos_phi.gt(L::zero());
        let (turn, turn_den) = (
            L::select(positive, sin_phi * sin_phi, L::one() - cos_phi),
            L::select(positive, L::one() + cos_phi, L::one()),
        );
        let span = r + sin_theta;
        let a = near
            .mul_add(turn_den, sin_theta * turn * span)
            .safe_div(span * turn_den);
        let b = sin_theta * sin_phi;
        let m = Vec3::new(a.mul_add(dx, b * dy), a.mul_add(dy, -(b * dx)), lift);
        Vec3::new(ax * m.x, ay * m.y, m.z.max(L::splat(1e-6)))
    }
}

impl<L: Lane> SmithNdf<L> for Ggx<L> {
    #[inline(always)]
    fn alpha(&self) -> (L, L) {
        (self.alpha_x, self.alpha_y)
    }

    /// `(sqrt(z^2 + p^2) - |z|) / 2`, in the form without cancellation:
    /// `p^2 / (2 (sqrt(z^2 + p^2) + |z|))`.
    #[inline(always)]
    fn lambda_cos(&self, w: Vec3<L>) -> L {
        let proj2 = self.projected2(w);
        let z = w.z.abs();
        proj2.safe_div(L::splat(2.0) * (z.mul_add(z, proj2).sqrt() + z))
    }

    /// `2 Lambda |z| = sqrt(z^2 + p^2) - |z|`, so `sigma = sqrt(z^2 + p^2)`: one sqrt, no
    /// division. For a unit `w`, `sigma >= min(1, alpha_x, alpha_y) >= MIN_ALPHA`.
    #[inline(always)]
    fn sigma(&self, w: Vec3<L>, z: L) -> L {
        z.mul_add(z, self.projected2(w)).sqrt()
    }

    /// `D = (ax ay)^3 / (pi q^2)` ([`Ggx::q`]), so `P = 2 (ax ay)^3 / (pi q^2 B)`: one
    /// division. `q >= 1e-14` on non-delta lanes and `B >= MIN_ALPHA`, so that
    /// denominator is a positive normal float.
    #[inline(always)]
    fn pair_density(&self, v: &View<L>, h: Vec3<L>) -> L {
        let axy = self.alpha_x * self.alpha_y;
        let q = self.q(h);
        L::splat(2.0) * (axy * axy * axy) / (L::splat(PI) * q * q * v.b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sample_reflection` is `w` reflected about `sample`'s normal: against the
    /// reflection in f64 about that normal made unit in f64, for views from normal
    /// incidence to 1e-30 above the horizon and alphas from 1e-3 to 1, isotropic and
    /// anisotropic; a unit vector.
    #[test]
    fn sample_reflection_reflects_the_sampled_normal() {
        let mut worst = (0.0f64, String::new());
        for (ax, ay) in [
            (1e-3, 1e-3),
            (0.05, 0.05),
            (0.3, 0.3),
            (1.0, 1.0),
            (0.8, 0.02),
        ] {
            let dist = Ggx {
                alpha_x: ax,
                alpha_y: ay,
            };
            for cos_o in [1.0f32, 0.7, 0.2, 1e-3, 1e-7, 1e-30] {
                let sin_o = (1.0 - cos_o * cos_o).sqrt();
                let w = Vec3::new(sin_o * 0.6, sin_o * 0.8, cos_o);
                for i in 0..256 {
                    let u0 = (i as f32 + 0.5) / 256.0;
                    let u1 = ((i * 97 % 256) as f32 + 0.5) / 256.0;
                    let r = dist.sample_reflection(w, u0, u1);
                    let m = dist.sample(w, u0, u1);
                    let m = [m.x, m.y, m.z].map(f64::from);
                    let len = m.iter().map(|c| c * c).sum::<f64>().sqrt();
                    let m = m.map(|c| c / len);
                    let w = [w.x, w.y, w.z].map(f64::from);
                    let dot: f64 = (0..3).map(|k| w[k] * m[k]).sum();
                    let expected: [f64; 3] = std::array::from_fn(|k| 2.0 * dot * m[k] - w[k]);
                    let got = [r.x, r.y, r.z].map(f64::from);
                    let err = (0..3)
                        .map(|k| (got[k] - expected[k]).abs())
                        .fold(0.0, f64::max)
                        .max((got.iter().map(|c| c * c).sum::<f64>().sqrt() - 1.0).abs());
                    if err.is_nan() || err > worst.0 {
                        worst = (
                            err,
                            format!("alpha ({ax}, {ay}), cos_o {cos_o}, u ({u0}, {u1})"),
                        );
                    }
                }
            }
        }
        assert!(worst.0 < 2e-6, "error {:.3e} at {}", worst.0, worst.1);
    }
}
