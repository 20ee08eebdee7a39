//! Directional albedo of single-scattering microfacet lobes, tabulated once per
//! distribution at first use and read with linear interpolation.
//!
//! Reflection ([`ReflectionTable`]): with `c = wo.m` and Schlick's `s = (1 - c)^5`, a
//! Fresnel fitted as `F0 (1 - s) + F90 s - a c (1 - c)^6`
//! (`FresnelModel::split_sum_fit`) makes the albedo `F0 A + F90 B - a C`, where
//! `A = E[(1 - s) G2/G1]`, `B = E[s G2/G1]`, `C = E[c (1 - c)^6 G2/G1]` over visible
//! normals `m` and reflected directions above the surface. Grid: 32 (`mu = cos theta_o`)
//! x 48 (`r = sqrt(alpha)` in [0, 1.5]), 16 x 16 strata per cell.
//!
//! Dielectric ([`DielectricTable`]): `E[F G2/G1]` (reflection) and `E[(1 - F) G2/G1]`
//! (transmission, importance transport) over visible normals, on a 17 x 17 x 17 grid in
//! `|mu|` (remapped so the critical angle is a node), `r` in [0, 1.5] and
//! `t = |eta' - 1| / (eta' + 1)`
//! (so `t^2` is the normal-incidence reflectance) for `eta' > 1` and `eta' < 1`
//! separately, 8 x 8 strata per cell;
//! `t` beyond the grid (`eta'` above 39 or below 1/39) is clamped.
//!
//! Anisotropic lobes use the root-mean-square alpha, an isotropic stand-in whose error
//! grows with anisotropy (measured up to 39% at `anisotropic = 0.7`, roughness 1: the
//! true albedo also depends on the azimuth of `wo`). The tables' errors against
//! numerical integration are measured in the tests and by the verification harness.

use crate::fresnel;
use crate::math::{Lane, Vec3};
use crate::microfacet::{Distribution, NdfKind};
use std::sync::OnceLock;

const N: usize = 32;
/// Rows of the reflection table in `r = sqrt(alpha)`, spanning [0, R_MAX] at the spacing of
/// the `mu` columns, so anisotropic lobes' effective alpha (up to 2.25) stays on the grid.
const NR: usize = 48;
const R_MAX: f32 = 1.5;
const STRATA: usize = 16;

/// Stratified quadrature points `(u0, u1, weight)` on the unit square. With `warp`,
/// denser toward `u0 = 1` (`u0 = 1 - (1 - v)^2`, weighted by its Jacobian `2 (1 - v)`),
/// where the visible-normal samplers put the distribution's far tail.
fn strata(n: usize, warp: bool) -> impl Iterator<Item = (f32, f32, f64)> {
    (0..n * n).map(move |k| {
        let (i, j) = (k / n, k % n);
        let v = (i as f64 + 0.5) / n as f64;
        let (u0, jacobian) = if warp {
            (1.0 - (1.0 - v) * (1.0 - v), 2.0 * (1.0 - v))
        } else {
            (v, 1.0)
        };
        (
            u0 as f32,
            (j as f32 + 0.5) / n as f32,
            jacobian / (n * n) as f64,
        )
    })
}

/// Grid coordinate of `x` in [0, 1] on `n` points: the lower index and the fraction.
#[inline(always)]
fn grid<L: Lane>(x: L, n: usize) -> (L, L) {
    let pos = x.clamp(L::zero(), L::one()) * L::splat((n - 1) as f32);
    let i = pos.floor().min(L::splat((n - 2) as f32));
    (i, pos - i)
}

#[inline(always)]
fn lerp<L: Lane>(a: L, b: L, t: L) -> L {
    a + (b - a) * t
}

/// The isotropic distribution `kind` with `alpha = r^2` (not clamped to 1).
fn grid_distribution(kind: NdfKind, r: f32) -> Distribution<f32> {
    let alpha = (r * r).max(crate::microfacet::MIN_ALPHA);
    Distribution {
        kind,
        alpha_x: alpha,
        alpha_y: alpha,
    }
}

/// The lookup roughness of a (possibly anisotropic) distribution: `sqrt` of the
/// root-mean-square alpha, which tracks the energy of anisotropic lobes better than the
/// geometric mean (the wider axis dominates the shadowing of reflected directions).
#[inline(always)]
fn lookup_roughness<L: Lane>(dist: &Distribution<L>) -> L {
    (L::splat(0.5) * (dist.alpha_x * dist.alpha_x + dist.alpha_y * dist.alpha_y))
        .sqrt()
        .sqrt()
}

/// `wo` at `cos theta = mu` in the xz-plane.
fn direction(mu: f32) -> Vec3<f32> {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// The `A`, `B` and `C` tables of one distribution, `NR x N`, indexed `[r][mu]`.
pub struct ReflectionTable {
    abc: [Vec<f32>; 3],
}

impl ReflectionTable {
    /// The table for `kind`, computed on first use.
    pub fn get(kind: NdfKind) -> &'static ReflectionTable {
        static GGX: OnceLock<ReflectionTable> = OnceLock::new();
        static BECKMANN: OnceLock<ReflectionTable> = OnceLock::new();
        match kind {
            NdfKind::Ggx => GGX.get_or_init(|| ReflectionTable::compute(kind)),
            NdfKind::Beckmann => BECKMANN.get_or_init(|| ReflectionTable::compute(kind)),
        }
    }

    fn compute(kind: NdfKind) -> ReflectionTable {
        let mut abc = [vec![0.0; NR * N], vec![0.0; NR * N], vec![0.0; NR * N]];
        for ri in 0..NR {
            let dist = grid_distribution(kind, R_MAX * ri as f32 / (NR - 1) as f32);
            for mi in 0..N {
                // mu = 0 has no albedo of its own: use the limit from just above.
                let wo = direction((mi as f32 / (N - 1) as f32).max(1e-3));
                let g1 = dist.g1(wo);
                let mut sum = [0.0f64; 3];
                for (u0, u1, q) in strata(STRATA, true) {
                    let m = dist.sample_visible(wo, u0, u1);
                    let wi = wo.reflect(m);
                    if wi.z <= 0.0 {
                        continue;
                    }
                    let w = q * f64::from(dist.g2(wo, wi) / g1);
                    let c = f64::from(wo.dot(m).clamp(0.0, 1.0));
                    let s = (1.0 - c).powi(5);
                    sum[0] += w * (1.0 - s);
                    sum[1] += w * s;
                    sum[2] += w * c * (1.0 - c).powi(6);
                }
                for (table, total) in abc.iter_mut().zip(sum) {
                    table[ri * N + mi] = total as f32;
                }
            }
        }
        ReflectionTable { abc }
    }

    /// `(A, B, C)` at `mu = cos theta_o` and the distribution's roughness.
    #[inline(always)]
    pub fn lookup<L: Lane>(&self, mu: L, dist: &Distribution<L>) -> [L; 3] {
        let (x0, fx) = grid(mu, N);
        let (y0, fy) = grid(lookup_roughness(dist) * L::splat(1.0 / R_MAX), NR);
        let base = y0 * L::splat(N as f32) + x0;
        let row = L::splat(N as f32);
        let [a, b, c] = &self.abc;
        [
            bilerp(a, base, L::one(), row, fx, fy),
            bilerp(b, base, L::one(), row, fx, fy),
            bilerp(c, base, L::one(), row, fx, fy),
        ]
    }
}

/// Bilinear interpolation in `table` from index `base`, with `dx` and `dy` the index
/// steps of the two axes.
#[inline(always)]
fn bilerp<L: Lane>(table: &[f32], base: L, dx: L, dy: L, fx: L, fy: L) -> L {
    let (p00, p01) = (L::gather(table, base), L::gather(table, base + dx));
    let (p10, p11) = (
        L::gather(table, base + dy),
        L::gather(table, base + dy + dx),
    );
    lerp(lerp(p00, p01, fx), lerp(p10, p11, fx), fy)
}

/// Points per axis; odd, so the critical angle (x = 1/2, see [`critical_coordinate`]) is a node.
const DN: usize = 17;
const DIELECTRIC_STRATA: usize = 8;
/// Largest `t = |eta' - 1| / (eta' + 1)` on the grid (`eta' = 39`).
const T_MAX: f32 = 0.95;

/// The `mu` axis coordinate of the dielectric table: `mu` itself for `eta' > 1`; for
/// `eta' < 1`, `mu` remapped so the critical angle `mu_c = sqrt(1 - eta'^2)` sits at 1/2,
/// keeping the total-internal-reflection edge on a grid node for every IOR.
#[inline(always)]
fn critical_coordinate<L: Lane>(mu: L, eta: L) -> L {
    let mu_c = (L::one() - eta * eta).safe_sqrt();
    let below = L::splat(0.5) * mu.safe_div(mu_c);
    let above = L::splat(0.5) + L::splat(0.5) * (mu - mu_c).safe_div(L::one() - mu_c);
    let remapped = L::select(mu.lt(mu_c), below, above);
    L::select(eta.lt(L::one()), remapped, mu)
}

/// Inverse of [`critical_coordinate`].
fn critical_mu(x: f32, eta: f32) -> f32 {
    if eta >= 1.0 {
        return x;
    }
    let mu_c = (1.0 - eta * eta).max(0.0).sqrt();
    if x < 0.5 {
        2.0 * x * mu_c
    } else {
        mu_c + (2.0 * x - 1.0) * (1.0 - mu_c)
    }
}

/// Reflected and transmitted single-scattering albedo of the rough dielectric, indexed
/// `[side][t][r][x]` with side 0 for `eta' > 1`, 1 for `eta' < 1`, and `x` the
/// [`critical_coordinate`] of `mu`.
pub struct DielectricTable {
    reflect: Vec<f32>,
    transmit: Vec<f32>,
}

impl DielectricTable {
    /// The table for `kind`, computed on first use.
    pub fn get(kind: NdfKind) -> &'static DielectricTable {
        static GGX: OnceLock<DielectricTable> = OnceLock::new();
        static BECKMANN: OnceLock<DielectricTable> = OnceLock::new();
        match kind {
            NdfKind::Ggx => GGX.get_or_init(|| DielectricTable::compute(kind)),
            NdfKind::Beckmann => BECKMANN.get_or_init(|| DielectricTable::compute(kind)),
        }
    }

    fn compute(kind: NdfKind) -> DielectricTable {
        let size = 2 * DN * DN * DN;
        let (mut reflect, mut transmit) = (vec![0.0; size], vec![0.0; size]);
        for side in 0..2 {
            for ti in 0..DN {
                let t = T_MAX * ti as f32 / (DN - 1) as f32;
                let eta_above = (1.0 + t) / (1.0 - t);
                let eta = if side == 0 {
                    eta_above
                } else {
                    1.0 / eta_above
                };
                for ri in 0..DN {
                    let dist = grid_distribution(kind, R_MAX * ri as f32 / (DN - 1) as f32);
                    for mi in 0..DN {
                        let mu = critical_mu(mi as f32 / (DN - 1) as f32, eta);
                        let (r, tr) = Self::integrate(&dist, direction(mu.max(1e-3)), eta);
                        let index = ((side * DN + ti) * DN + ri) * DN + mi;
                        reflect[index] = r;
                        transmit[index] = tr;
                    }
                }
            }
        }
        DielectricTable { reflect, transmit }
    }

    /// `E[F G2/G1]` and `E[(1 - F) G2/G1]` for `wo` above an interface of relative IOR `eta`.
    fn integrate(dist: &Distribution<f32>, wo: Vec3<f32>, eta: f32) -> (f32, f32) {
        let g1 = dist.g1(wo);
        let (mut r, mut t) = (0.0f64, 0.0f64);
        for (u0, u1, q) in strata(DIELECTRIC_STRATA, false) {
            let m = dist.sample_visible(wo, u0, u1);
            let c = wo.dot(m);
            let f = fresnel::dielectric(c, eta);
            let wr = wo.reflect(m);
            if wr.z > 0.0 {
                r += q * f64::from(f * dist.g2(wo, wr) / g1);
            }
            // Snell on the microfacet (pbrt-v4 Refract), for c > 0.
            let sin2_t = (1.0 - c * c).max(0.0) / (eta * eta);
            if f < 1.0 && sin2_t < 1.0 {
                let cos_t = (1.0 - sin2_t).sqrt();
                let wt = -wo * (1.0 / eta) + m * (c / eta - cos_t);
                if wt.z < 0.0 {
                    t += q * f64::from((1.0 - f) * dist.g2(wo, wt) / g1);
                }
            }
        }
        (r as f32, t as f32)
    }

    /// Reflected and transmitted albedo (importance transport) at `|mu|`, for the relative
    /// IOR `eta'` seen from `wo`'s side.
    #[inline(always)]
    pub fn lookup<L: Lane>(&self, mu: L, dist: &Distribution<L>, eta: L) -> (L, L) {
        let t = (eta - L::one()).abs() / (eta + L::one());
        let side = L::select(eta.lt(L::one()), L::one(), L::zero());
        let (x0, fx) = grid(critical_coordinate(mu.abs(), eta), DN);
        let (y0, fy) = grid(lookup_roughness(dist) * L::splat(1.0 / R_MAX), DN);
        let (z0, fz) = grid(t * L::splat(1.0 / T_MAX), DN);
        let n = L::splat(DN as f32);
        let base = ((side * n + z0) * n + y0) * n + x0;
        let dz = L::splat((DN * DN) as f32);
        let (r0, r1) = (
            bilerp(&self.reflect, base, L::one(), n, fx, fy),
            bilerp(&self.reflect, base + dz, L::one(), n, fx, fy),
        );
        let (t0, t1) = (
            bilerp(&self.transmit, base, L::one(), n, fx, fy),
            bilerp(&self.transmit, base + dz, L::one(), n, fx, fy),
        );
        (lerp(r0, r1, fz), lerp(t0, t1, fz))
    }
}
