//! Directional albedo of single-scattering microfacet reflection, tabulated once
//! per distribution and looked up by the lobes' `albedo`.
//!
//! With Schlick's weight `s(c) = (1 - c)^5`, the albedo of a reflection lobe with
//! Fresnel `F0 + (F90 - F0) s` splits into `F0 A + F90 B` (the "split sum"), where
//! `A(mu, r) = E[(1 - s(wo.m)) G2/G1]` and `B(mu, r) = E[s(wo.m) G2/G1]` over visible
//! normals `m` (so `A + B` is the lobe's energy with `F = 1`). The table is filled at
//! first use by stratified visible-normal sampling (16 x 16 strata per cell) over a
//! 32 x 32 grid in `mu = cos theta_o` and `r = sqrt(alpha)`, and read with bilinear
//! interpolation; anisotropic lobes use `alpha = sqrt(alpha_x alpha_y)`. The table's
//! error against numerical integration is measured in `tests/lobes_albedo.rs`.

use crate::math::{Lane, Vec3};
use crate::microfacet::{Distribution, NdfKind};
use std::sync::OnceLock;

const N: usize = 32;
const STRATA: usize = 16;

/// The `A` and `B` tables of one distribution, `N x N`, indexed `[r][mu]`.
pub struct AlbedoTable {
    a: Vec<f32>,
    b: Vec<f32>,
}

impl AlbedoTable {
    /// The table for `kind`, computed on first use.
    pub fn get(kind: NdfKind) -> &'static AlbedoTable {
        static GGX: OnceLock<AlbedoTable> = OnceLock::new();
        static BECKMANN: OnceLock<AlbedoTable> = OnceLock::new();
        match kind {
            NdfKind::Ggx => GGX.get_or_init(|| AlbedoTable::compute(kind)),
            NdfKind::Beckmann => BECKMANN.get_or_init(|| AlbedoTable::compute(kind)),
        }
    }

    fn compute(kind: NdfKind) -> AlbedoTable {
        let mut a = vec![0.0; N * N];
        let mut b = vec![0.0; N * N];
        for ri in 0..N {
            let r = ri as f32 / (N - 1) as f32;
            let dist = Distribution::<f32>::from_roughness(kind, r, 0.0);
            for mi in 0..N {
                // mu = 0 has no albedo of its own: use the limit from just above.
                let mu = (mi as f32 / (N - 1) as f32).max(1e-3);
                let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let g1 = dist.g1(wo);
                let (mut sum_a, mut sum_b) = (0.0f64, 0.0f64);
                for i in 0..STRATA {
                    for j in 0..STRATA {
                        let u0 = (i as f32 + 0.5) / STRATA as f32;
                        let u1 = (j as f32 + 0.5) / STRATA as f32;
                        let m = dist.sample_visible(wo, u0, u1);
                        let wi = wo.reflect(m);
                        if wi.z <= 0.0 {
                            continue;
                        }
                        let w = f64::from(dist.g2(wo, wi) / g1);
                        let s = f64::from((1.0 - wo.dot(m)).clamp(0.0, 1.0)).powi(5);
                        sum_a += w * (1.0 - s);
                        sum_b += w * s;
                    }
                }
                let n = (STRATA * STRATA) as f64;
                a[ri * N + mi] = (sum_a / n) as f32;
                b[ri * N + mi] = (sum_b / n) as f32;
            }
        }
        AlbedoTable { a, b }
    }

    /// `(A, B)` at `mu = cos theta_o` and the distribution's roughness.
    #[inline(always)]
    pub fn lookup<L: Lane>(&self, mu: L, dist: &Distribution<L>) -> (L, L) {
        let r = (dist.alpha_x * dist.alpha_y).sqrt().sqrt();
        let scale = L::splat((N - 1) as f32);
        let x = mu.clamp(L::zero(), L::one()) * scale;
        let y = r.clamp(L::zero(), L::one()) * scale;
        let max_index = L::splat((N - 2) as f32);
        let x0 = x.floor().min(max_index);
        let y0 = y.floor().min(max_index);
        let (fx, fy) = (x - x0, y - y0);
        let base = y0 * L::splat(N as f32) + x0;
        let bilerp = |t: &[f32]| {
            let v00 = L::gather(t, base);
            let v10 = L::gather(t, base + L::one());
            let v01 = L::gather(t, base + L::splat(N as f32));
            let v11 = L::gather(t, base + L::splat(N as f32 + 1.0));
            let top = v00 + (v10 - v00) * fx;
            let bottom = v01 + (v11 - v01) * fx;
            top + (bottom - top) * fy
        };
        (bilerp(&self.a), bilerp(&self.b))
    }
}
