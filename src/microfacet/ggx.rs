//! GGX (Trowbridge-Reitz), anisotropic: `D(m) = 1 / (pi ax ay t^2)` with
//! `t = (m.x / ax)^2 + (m.y / ay)^2 + m.z^2` (Walter et al. 2007 eq. 33, Heitz 2014 eq. 85), Smith
//! `Lambda = (sqrt(1 + p^2 / z^2) - 1) / 2` with `p^2 = (ax w.x)^2 + (ay w.y)^2`
//! (Heitz 2014 eq. 86), visible normals by Heitz 2018's listing 1.

use super::{Ndf, SmithNdf, View, upper};
use crate::math::{Lane, PI, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct Ggx<L> {
    pub alpha_x: L,
    pub alpha_y: L,
}

impl<L: Lane> Ggx<L> {
    /// `p^2 = (alpha_x w.x)^2 + (alpha_y w.y)^2`.
    #[inline(always)]
    fn projected2(&self, w: Vec3<L>) -> L {
        (self.alpha_x * w.x).sqr() + (self.alpha_y * w.y).sqr()
    }

    /// `q = t (ax ay)^2 = (h.x ay)^2 + (h.y ax)^2 + (h.z ax ay)^2`, so that
    /// `D = (ax ay)^3 / (pi q^2)` without dividing by the alphas; for a unit `h`,
    /// `q >= min(ax, ay, ax ay)^2`: at least 1e-14 when one alpha is at least
    /// `DELTA_ALPHA` and the other `MIN_ALPHA`.
    #[inline(always)]
    pub fn q(&self, h: Vec3<L>) -> L {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        (h.x * ay).sqr() + (h.y * ax).sqr() + (h.z * (ax * ay)).sqr()
    }
}

impl<L: Lane> Ndf<L> for Ggx<L> {
    #[inline(always)]
    fn d(&self, m: Vec3<L>) -> L {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let sx = m.x / ax;
        let sy = m.y / ay;
        let t = sx * sx + sy * sy + m.z * m.z;
        let value = L::one().safe_div(L::splat(PI) * ax * ay * t * t);
        L::select(m.z.gt(L::zero()), value, L::zero())
    }

    /// Heitz 2018, "Sampling the GGX Distribution of Visible Normals", listing 1
    /// (`w` flipped to the upper hemisphere when below it).
    #[inline(always)]
    fn sample(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        let w = upper(w);
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        let vh = Vec3::new(ax * w.x, ay * w.y, w.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let inv_len = L::one().safe_div(len2.sqrt());
        let has_len = len2.gt(L::zero());
        let t1 = Vec3::new(
            L::select(has_len, -vh.y * inv_len, L::one()),
            L::select(has_len, vh.x * inv_len, L::zero()),
            L::zero(),
        );
        let t2 = vh.cross(t1);
        let r = u0.sqrt();
        let (sin_phi, cos_phi) = (L::splat(2.0 * PI) * u1).sin_cos();
        let p1 = r * cos_phi;
        let s = L::splat(0.5) * (L::one() + vh.z);
        // `1 - p1^2` and `1 - p1^2 - p2^2` without their cancellation near the disk's
        // edge (u0 -> 1), where it made the normal hang on the last bits of sin_cos:
        // with h = sqrt(1 - p1^2) = sqrt((1 - u0) + u0 sin^2), h - r sin = (1 - u0) /
        // (h + r sin) for sin >= 0, p2 = h - s (h - r sin) and 1 - p1^2 - p2^2 =
        // (h - p2)(h + p2).
        let rest = L::one() - u0;
        let h = (u0 * sin_phi * sin_phi + rest).safe_sqrt();
        let rs = r * sin_phi;
        let gap = L::select(sin_phi.ge(L::zero()), rest.safe_div(h + rs), h - rs);
        let h_minus_p2 = s * gap;
        let p2 = h - h_minus_p2;
        let nz = (h_minus_p2 * (h + p2)).safe_sqrt();
        let nh = t1 * p1 + t2 * p2 + vh * nz;
        // The normal's length by `rsqrt`: an error in it scales the normal without
        // turning it, and the sample's value and pdf come from the settled direction.
        // Its square is >= 1e-12, a normal float.
        Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(L::splat(1e-6))).normalize_estimate()
    }

    #[inline(always)]
    fn pdf(&self, w: Vec3<L>, m: Vec3<L>) -> L {
        self.pdf_visible(w, m)
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
        proj2.safe_div(L::splat(2.0) * ((z * z + proj2).sqrt() + z))
    }

    /// `2 Lambda |z| = sqrt(z^2 + p^2) - |z|`, so `sigma = sqrt(z^2 + p^2)`: one sqrt, no
    /// division. For a unit `w`, `sigma >= min(1, alpha_x, alpha_y) >= MIN_ALPHA`.
    #[inline(always)]
    fn sigma(&self, w: Vec3<L>, z: L) -> L {
        (z * z + self.projected2(w)).sqrt()
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
