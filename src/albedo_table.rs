//! Directional albedo of single-scattering microfacet lobes, tabulated once per
//! distribution at first use and read with linear interpolation.
//!
//! Reflection ([`ReflectionTable`]): the albedo of a lobe with Fresnel `F(c)`, `c = wo.m`,
//! is `E[F(c) G2/G1]` over visible normals `m` and reflected directions above the surface.
//! Schlick's `F0 (1 - s) + F90 s`, `s = (1 - c)^5`, gives `F0 A + F90 B` exactly
//! (`A = E[(1 - s) G2/G1]`, `B = E[s G2/G1]`). Any other curve (exact conductor, artistic)
//! is Schlick's with `F0 = F(1)`, `F90 = 1` plus its departure `d(c)` from it, and `d`
//! replaced by its piecewise-linear interpolant on the nodes `c_k = (k / 12)^2` (dense
//! toward grazing, where conductor curves bend) adds `sum_k d(c_k) H_k` with
//! `H_k = E[hat_k(c) G2/G1]`: one table serves every Fresnel model. Isotropic grid:
//! 32 `mu = cos theta_o` nodes at `sqrt(mu)` spacing (dense toward grazing) x 48
//! `r = sqrt(alpha)` in [0, 1.5] (the dielectric reads it at the root-mean-square alpha of
//! anisotropic lobes, up to 2.25), 16 x 16 strata per cell.
//!
//! Anisotropic lobes ([`ReflectionTable::get_anisotropic`], computed at the first
//! anisotropic lookup) add two axes: the aspect `log10(alpha_x / alpha_y)` in [0, 1]
//! (Burley's mapping reaches 10 at `anisotropic = 1`), and the azimuth of `wo` from the
//! wider axis in [0, 90] degrees; `r` is the geometric mean `sqrt(sqrt(alpha_x alpha_y))`.
//! The albedo is not a function of the projected roughness `alpha_o` alone (at normal
//! incidence it depends on both axes while `alpha_o` is undefined), hence the table.
//! 16 x 16 strata per cell, warped toward both ends of `u0`.
//!
//! Dielectric ([`DielectricTable`]): `E[F G2/G1]` (reflection) and `E[(1 - F) G2/G1]`
//! (transmission, importance transport) over visible normals, on a 17 x 17 x 17 grid in
//! `|mu|` (remapped so the critical angle is a node), `r` in [0, 1.5] and
//! `t = |eta' - 1| / (eta' + 1)`
//! (so `t^2` is the normal-incidence reflectance) for `eta' > 1` and `eta' < 1`
//! separately, 8 x 8 strata per cell;
//! `t` beyond the grid (`eta'` above 39 or below 1/39) is clamped.
//!
//! The tables' errors against numerical integration are measured in tests/albedo.rs and
//! by the verification harness.

use crate::fresnel::{self, FresnelModel};
use crate::math::{Lane, Mask, Rgb, Vec3};
use crate::microfacet::{Distribution, NdfKind};
use std::sync::OnceLock;

/// `mu` nodes of the reflection tables.
const N: usize = 32;
/// Rows of the isotropic reflection table in `r = sqrt(alpha)`, spanning [0, R_MAX].
const NR: usize = 48;
const R_MAX: f32 = 1.5;
const STRATA: usize = 16;
/// Intervals of the piecewise-linear Fresnel interpolant; nodes `c_k = (k / FRESNEL_K)^2`.
const FRESNEL_K: usize = 12;
/// Fresnel nodes.
const FRESNEL_NODES: usize = FRESNEL_K + 1;
/// Channels of a reflection table cell: the `H_k`, then Schlick's `A` and `B`.
const CHANNELS: usize = FRESNEL_NODES + 2;
/// Rows of the anisotropic table in `r`: the isotropic rows up to `r = 1.02`.
const NR_ANISO: usize = 33;
/// Aspect nodes, `log10(alpha_x / alpha_y)` in [0, 1].
const NS: usize = 6;
/// Azimuth nodes in [0, 90] degrees from the wider axis.
const NP: usize = 7;
const ANISO_STRATA: usize = 16;

/// Where [`strata`] concentrates its `u0` points.
#[derive(Clone, Copy)]
enum Warp {
    None,
    /// Toward `u0 = 1`, where the visible-normal samplers put the distribution's far tail:
    /// `u0 = 1 - (1 - v)^2`.
    Tail,
    /// Toward both ends, `u0 = v^2 (3 - 2 v)`: also the normals near the center of the
    /// projected disk, the only ones that reflect above the surface when a wide
    /// anisotropic axis tilts most facets.
    BothEnds,
}

/// Stratified quadrature points `(u0, u1, weight)` on the unit square, `u0` warped by
/// `warp` and weighted by its Jacobian.
fn strata(n: usize, warp: Warp) -> impl Iterator<Item = (f32, f32, f64)> {
    (0..n * n).map(move |k| {
        let (i, j) = (k / n, k % n);
        let v = (i as f64 + 0.5) / n as f64;
        let (u0, jacobian) = match warp {
            Warp::None => (v, 1.0),
            Warp::Tail => (1.0 - (1.0 - v) * (1.0 - v), 2.0 * (1.0 - v)),
            Warp::BothEnds => (v * v * (3.0 - 2.0 * v), 6.0 * v * (1.0 - v)),
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

/// The roughness axis of the anisotropic table: `sqrt` of the geometric-mean alpha.
#[inline(always)]
fn mean_roughness<L: Lane>(dist: &Distribution<L>) -> L {
    (dist.alpha_x * dist.alpha_y).sqrt().sqrt()
}

/// The isotropic stand-in roughness of the dielectric table: `sqrt` of the
/// root-mean-square alpha, which tracks the energy of anisotropic lobes better than the
/// geometric mean (the wider axis dominates the shadowing); its error is measured in
/// tests/albedo.rs.
#[inline(always)]
pub fn rms_roughness<L: Lane>(dist: &Distribution<L>) -> L {
    (L::splat(0.5) * (dist.alpha_x * dist.alpha_x + dist.alpha_y * dist.alpha_y))
        .sqrt()
        .sqrt()
}

/// `wo` at `cos theta = mu` and azimuth `phi`.
fn direction(mu: f32, phi: f32) -> Vec3<f32> {
    let sin = (1.0 - mu * mu).max(0.0).sqrt();
    Vec3::new(sin * phi.cos(), sin * phi.sin(), mu)
}

/// `mu` at node `i` of the reflection tables' `sqrt(mu)` axis; `mu = 0` has no albedo of
/// its own: the limit from just above.
fn reflection_mu(i: usize) -> f32 {
    let x = i as f32 / (N - 1) as f32;
    (x * x).max(1e-4)
}

/// Fresnel node `k`, `c_k = (k / FRESNEL_K)^2`.
fn fresnel_node(k: usize) -> f32 {
    let x = k as f32 / FRESNEL_K as f32;
    x * x
}

/// The hat-function weights `H_k` of `E[F(c) G2/G1]`, then `A = E[(1 - s) G2/G1]` and
/// `B = E[s G2/G1]` with Schlick's `s = (1 - c)^5`, for `wo`.
fn reflection_cell(
    dist: &Distribution<f32>,
    wo: Vec3<f32>,
    strata_n: usize,
    warp: Warp,
) -> [f64; CHANNELS] {
    let g1 = dist.g1(wo);
    let mut h = [0.0f64; CHANNELS];
    for (u0, u1, q) in strata(strata_n, warp) {
        let m = dist.sample_visible(wo, u0, u1);
        let wi = wo.reflect(m);
        if wi.z <= 0.0 {
            continue;
        }
        let w = q * f64::from(dist.g2(wo, wi) / g1);
        let c = f64::from(wo.dot(m).clamp(0.0, 1.0));
        let x = c.sqrt() * FRESNEL_K as f64;
        let j = (x.floor() as usize).min(FRESNEL_K - 1);
        let (c0, c1) = (f64::from(fresnel_node(j)), f64::from(fresnel_node(j + 1)));
        let t = ((c - c0) / (c1 - c0)).clamp(0.0, 1.0);
        h[j] += w * (1.0 - t);
        h[j + 1] += w * t;
        let schlick = (1.0 - c).powi(5);
        h[FRESNEL_NODES] += w * (1.0 - schlick);
        h[FRESNEL_NODES + 1] += w * schlick;
    }
    h
}

/// The channels of [`reflection_cell`] for one distribution, `CHANNELS` per cell.
/// Isotropic: cells `[r][mu]`; anisotropic: `[phi][aspect][r][mu]`.
pub struct ReflectionTable {
    h: Vec<f32>,
}

impl ReflectionTable {
    /// The isotropic table for `kind`, computed on first use.
    pub fn get(kind: NdfKind) -> &'static ReflectionTable {
        static GGX: OnceLock<ReflectionTable> = OnceLock::new();
        static BECKMANN: OnceLock<ReflectionTable> = OnceLock::new();
        match kind {
            NdfKind::Ggx => GGX.get_or_init(|| ReflectionTable::compute(kind)),
            NdfKind::Beckmann => BECKMANN.get_or_init(|| ReflectionTable::compute(kind)),
        }
    }

    /// The anisotropic table for `kind`, computed on first use.
    pub fn get_anisotropic(kind: NdfKind) -> &'static ReflectionTable {
        static GGX: OnceLock<ReflectionTable> = OnceLock::new();
        static BECKMANN: OnceLock<ReflectionTable> = OnceLock::new();
        match kind {
            NdfKind::Ggx => GGX.get_or_init(|| ReflectionTable::compute_anisotropic(kind)),
            NdfKind::Beckmann => {
                BECKMANN.get_or_init(|| ReflectionTable::compute_anisotropic(kind))
            }
        }
    }

    fn compute(kind: NdfKind) -> ReflectionTable {
        let mut h = Vec::with_capacity(NR * N * CHANNELS);
        for ri in 0..NR {
            let dist = grid_distribution(kind, R_MAX * ri as f32 / (NR - 1) as f32);
            for mi in 0..N {
                let wo = direction(reflection_mu(mi), 0.0);
                let cell = reflection_cell(&dist, wo, STRATA, Warp::Tail);
                h.extend(cell.map(|v| v as f32));
            }
        }
        ReflectionTable { h }
    }

    fn compute_anisotropic(kind: NdfKind) -> ReflectionTable {
        let iso = ReflectionTable::get(kind);
        let cell_size = N * CHANNELS;
        let mut h = Vec::with_capacity(NP * NS * NR_ANISO * cell_size);
        for pi in 0..NP {
            let phi = std::f32::consts::FRAC_PI_2 * pi as f32 / (NP - 1) as f32;
            for si in 0..NS {
                let sqrt_ratio = 10f32.powf(0.5 * si as f32 / (NS - 1) as f32);
                for ri in 0..NR_ANISO {
                    let r = R_MAX * ri as f32 / (NR - 1) as f32;
                    if si == 0 {
                        h.extend_from_slice(&iso.h[ri * cell_size..(ri + 1) * cell_size]);
                        continue;
                    }
                    let alpha = (r * r).max(crate::microfacet::MIN_ALPHA);
                    let dist = Distribution {
                        kind,
                        alpha_x: alpha * sqrt_ratio,
                        alpha_y: alpha / sqrt_ratio,
                    };
                    for mi in 0..N {
                        let wo = direction(reflection_mu(mi), phi);
                        let cell = reflection_cell(&dist, wo, ANISO_STRATA, Warp::BothEnds);
                        h.extend(cell.map(|v| v as f32));
                    }
                }
            }
        }
        ReflectionTable { h }
    }

    /// Isotropic lanes: the grid corners `(index, weight)` of `(mu, r)`.
    #[inline(always)]
    fn corners_isotropic<L: Lane>(mu: L, r: L) -> [(L, L); 4] {
        let (x0, fx) = grid(mu.max(L::zero()).sqrt(), N);
        let (y0, fy) = grid(r * L::splat(1.0 / R_MAX), NR);
        let base = y0 * L::splat(N as f32) + x0;
        let row = L::splat(N as f32);
        let (gx, gy) = (L::one() - fx, L::one() - fy);
        [
            (base, gx * gy),
            (base + L::one(), fx * gy),
            (base + row, gx * fy),
            (base + row + L::one(), fx * fy),
        ]
    }

    /// Anisotropic lanes: the 16 grid corners `(cell index, weight)` of
    /// `(mu, r, aspect, azimuth)` for `wo` and `dist`.
    #[inline(always)]
    fn corners_anisotropic<L: Lane>(wo: Vec3<L>, dist: &Distribution<L>) -> [(L, L); 16] {
        let wide_x = dist.alpha_x.ge(dist.alpha_y);
        let (wide, narrow) = (
            dist.alpha_x.max(dist.alpha_y),
            dist.alpha_x.min(dist.alpha_y),
        );
        let (along, across) = (
            L::select(wide_x, wo.x, wo.y).abs(),
            L::select(wide_x, wo.y, wo.x).abs(),
        );
        let phi = across.atan2(along) * L::splat(std::f32::consts::FRAC_2_PI);
        let aspect = (wide / narrow).ln() * L::splat(1.0 / std::f32::consts::LN_10);
        let r = mean_roughness(dist);
        let (x0, fx) = grid(wo.z.max(L::zero()).sqrt(), N);
        // The r axis is the isotropic one, truncated to NR_ANISO rows.
        let r_pos = (r * L::splat((NR - 1) as f32 / R_MAX))
            .clamp(L::zero(), L::splat((NR_ANISO - 1) as f32));
        let y0 = r_pos.floor().min(L::splat((NR_ANISO - 2) as f32));
        let fy = r_pos - y0;
        let (z0, fz) = grid(aspect, NS);
        let (w0, fw) = grid(phi, NP);
        let axes = [
            (x0, fx, 1.0),
            (y0, fy, N as f32),
            (z0, fz, (N * NR_ANISO) as f32),
            (w0, fw, (N * NR_ANISO * NS) as f32),
        ];
        let mut base = L::zero();
        for (i, _, stride) in axes {
            base += i * L::splat(stride);
        }
        std::array::from_fn(|corner| {
            let (mut index, mut weight) = (base, L::one());
            for (bit, (_, f, stride)) in axes.iter().enumerate() {
                if corner >> bit & 1 == 1 {
                    index += L::splat(*stride);
                    weight *= *f;
                } else {
                    weight *= L::one() - *f;
                }
            }
            (index, weight)
        })
    }

    /// `sum_corners weight channel(corner)` for every channel.
    #[inline(always)]
    fn weights<L: Lane>(&self, corners: &[(L, L)]) -> [L; CHANNELS] {
        let stride = L::splat(CHANNELS as f32);
        let mut h = [L::zero(); CHANNELS];
        for &(cell, weight) in corners {
            let at = cell * stride;
            for (k, hk) in h.iter_mut().enumerate() {
                *hk = weight.mul_add(L::gather(&self.h, at + L::splat(k as f32)), *hk);
            }
        }
        h
    }

    /// The channels for `wo` above the surface and `dist`, isotropic or not.
    #[inline(always)]
    fn lookup<L: Lane>(wo: Vec3<L>, dist: &Distribution<L>) -> [L; CHANNELS] {
        let iso = ReflectionTable::get(dist.kind)
            .weights(&Self::corners_isotropic(wo.z, mean_roughness(dist)));
        let anisotropic = anisotropic(dist);
        if !anisotropic.any() {
            return iso;
        }
        let aniso = ReflectionTable::get_anisotropic(dist.kind)
            .weights(&Self::corners_anisotropic(wo, dist));
        std::array::from_fn(|k| L::select(anisotropic, aniso[k], iso[k]))
    }

    /// The single-scattering albedo `E[F(wo.m) G2/G1]` of a reflection lobe, for `wo`
    /// above the surface. Schlick is exact in `A` and `B`; a conductor is Schlick's
    /// `F0 A + B` (`F0 = F(1)`, `F(0) = 1`) plus its departure from that curve,
    /// interpolated at the Fresnel nodes: small and smooth, so little interpolation error.
    #[inline(always)]
    pub fn albedo<L: Lane>(
        wo: Vec3<L>,
        dist: &Distribution<L>,
        fresnel: &FresnelModel<L>,
    ) -> Rgb<L> {
        let h = Self::lookup(wo, dist);
        let (a, b) = (h[FRESNEL_NODES], h[FRESNEL_NODES + 1]);
        let sum = match fresnel {
            FresnelModel::Schlick { f0, f90 } => *f0 * a + *f90 * b,
            FresnelModel::Conductor { .. } => {
                let f0 = fresnel.eval(L::one());
                let mut sum = f0 * a + Rgb::splat(b);
                for (k, &hk) in h[..FRESNEL_NODES].iter().enumerate() {
                    let c = L::splat(fresnel_node(k));
                    let departure = fresnel.eval(c).zip(
                        f0,
                        #[inline(always)]
                        |f, f0| f - fresnel::schlick(f0, L::one(), c),
                    );
                    sum = sum + departure * hk;
                }
                sum
            }
        };
        sum.map(|v| v.max(L::zero()))
    }

    /// The shadowing albedo `E[G2/G1]` (the albedo with `F = 1`).
    #[inline(always)]
    pub fn shadowing<L: Lane>(wo: Vec3<L>, dist: &Distribution<L>) -> L {
        let h = Self::lookup(wo, dist);
        h[FRESNEL_NODES] + h[FRESNEL_NODES + 1]
    }
}

/// Lanes whose distribution is anisotropic (beyond rounding).
#[inline(always)]
fn anisotropic<L: Lane>(dist: &Distribution<L>) -> L::Mask {
    dist.alpha_x
        .max(dist.alpha_y)
        .gt(dist.alpha_x.min(dist.alpha_y) * L::splat(1.0 + 1e-5))
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
const DIELECTRIC_STRATA: usize = 16;
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
                        let (r, tr) = Self::integrate(&dist, direction(mu.max(1e-3), 0.0), eta);
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
        for (u0, u1, q) in strata(DIELECTRIC_STRATA, Warp::None) {
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

    /// Reflected and transmitted albedo (importance transport) at `|mu|` and isotropic
    /// roughness `r = sqrt(alpha)`, for the relative IOR `eta'` seen from `wo`'s side.
    #[inline(always)]
    pub fn lookup<L: Lane>(&self, mu: L, r: L, eta: L) -> (L, L) {
        let t = (eta - L::one()).abs() / (eta + L::one());
        let side = L::select(eta.lt(L::one()), L::one(), L::zero());
        let (x0, fx) = grid(critical_coordinate(mu.abs(), eta), DN);
        let (y0, fy) = grid(r * L::splat(1.0 / R_MAX), DN);
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
