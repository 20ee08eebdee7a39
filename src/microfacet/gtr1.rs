//! GTR1 (Berry's distribution; Burley 2012 eq. 4 with gamma = 1):
//! `D(m) = (a^2 - 1) / (pi ln(a^2) (1 + (a^2 - 1) cos_m^2))`, isotropic, `a < 1`. It has
//! no Smith masking of its own (Disney's clearcoat masks with GGX at a fixed 0.25), so it
//! is an [`Ndf`] only.
//!
//! Sampling is of `D(m) cos_m` in closed form (Burley 2012 appendix B.2): `phi = 2 pi
//! u0`, `cos_m^2 = (1 - (a^2)^(1 - u1)) / (1 - a^2)`, written as
//! `sin_m^2 = a^2 ((a^2)^(-u1) - 1) / (1 - a^2)` and
//! `cos_m^2 = (1 - a^2 (a^2)^(-u1)) / (1 - a^2)`, so that the small `sin_m^2` near the
//! peak is not the difference of two numbers near 1.

use super::Ndf;
use crate::math::{Lane, Vec3, azimuth};

/// GTR1 by its constants, computed once per lobe in f64 ([`Gtr1::constants`]).
#[derive(Clone, Copy, Debug)]
pub struct Gtr1<L> {
    /// `a^2`.
    pub a2: L,
    /// `(a^2 - 1) / (pi ln(a^2))`, the numerator of `D`.
    pub norm: L,
    /// `ln(a^2)`.
    pub ln_a2: L,
    /// `1 / (1 - a^2)`.
    pub inv_one_minus_a2: L,
}

impl Gtr1<f32> {
    /// `[a^2, (a^2 - 1) / (pi ln(a^2)), ln(a^2), 1 / (1 - a^2)]` for `a` in (0, 1), in f64.
    pub fn constants(a: f64) -> [f64; 4] {
        let a2 = a * a;
        let ln_a2 = a2.ln();
        [
            a2,
            (a2 - 1.0) / (std::f64::consts::PI * ln_a2),
            ln_a2,
            1.0 / (1.0 - a2),
        ]
    }
}

impl<L: Lane> Gtr1<L> {
    /// `D`'s denominator `1 + (a^2 - 1) cos_m^2` for a unit `m`, written `a^2 cos_m^2 +
    /// sin_m^2` with `sin_m^2` from `m`'s tangent components: `1 - cos_m^2` would cancel
    /// near the peak, where `a^2` is as small as 1e-6. At least `a^2`.
    #[inline(always)]
    pub fn denominator(&self, m: Vec3<L>) -> L {
        (self.a2 * m.z).mul_add(m.z, m.x.mul_add(m.x, m.y * m.y))
    }
}

impl<L: Lane> Ndf<L> for Gtr1<L> {
    /// `norm / denominator(m)`.
    #[inline(always)]
    fn d(&self, m: Vec3<L>) -> L {
        let value = self.norm / self.denominator(m);
        L::select(m.z.gt(L::zero()), value, L::zero())
    }

    #[inline(always)]
    fn sample(&self, _w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        // t = (a^2)^(-u0) in [1, 1 / a^2]; the azimuth from u1, as the other
        // distributions and the cosine hemisphere take it, so that a fused sample
        // computes one azimuth pair for every lobe.
        let t = (-(u0 * self.ln_a2)).exp();
        let sin2 = (self.a2 * (t - L::one()) * self.inv_one_minus_a2).clamp(L::zero(), L::one());
        let cos2 = ((L::one() - self.a2 * t) * self.inv_one_minus_a2).max(L::zero());
        let sin_m = sin2.sqrt();
        let (sin_phi, cos_phi) = azimuth(u1);
        Vec3::new(sin_m * cos_phi, sin_m * sin_phi, cos2.sqrt())
    }

    #[inline(always)]
    fn pdf(&self, _w: Vec3<L>, m: Vec3<L>) -> L {
        self.d(m) * m.z.max(L::zero())
    }
}
