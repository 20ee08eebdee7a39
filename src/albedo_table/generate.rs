//! The offline integration behind the committed albedo tables: each cell is a
//! stratified quadrature over visible normals (the distribution's own sampler, so the
//! integrand `G2/G1` times a bounded Fresnel term is smooth and at most 1), accumulated
//! in f64. Run by `tests/albedo_tables.rs`, which compares sampled cells with the
//! committed files and rewrites them with `GLINT_BLESS=1` (minutes on 2 cores).

use super::*;
use rayon::prelude::*;

/// Strata per axis: the isotropic reflection and dielectric cells, then the
/// anisotropic ones (whose wide axis tilts most facets, leaving few normals that
/// reflect above the surface).
const REFLECTION_STRATA: usize = 32;
const REFLECTION_ANISOTROPIC_STRATA: usize = 48;
const DIELECTRIC_STRATA: usize = 48;
const DIELECTRIC_ANISOTROPIC_STRATA: usize = 24;

/// Where [`strata`] concentrates its `u0` points.
#[derive(Clone, Copy)]
pub(super) enum Warp {
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
pub(super) fn strata(n: usize, warp: Warp) -> impl Iterator<Item = (f32, f32, f64)> {
    (0..n * n).map(move |k| {
        let (i, j) = (k / n, k % n);
        let v = (i as f64 + 0.5) / n as f64;
        let (u0, jacobian) = match warp {
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

/// The distribution `kind` with geometric-mean alpha `r^2` (floored at `MIN_ALPHA`) and
/// aspect `log10(alpha_x / alpha_y)` node `si`.
fn distribution(kind: NdfKind, r: f32, si: usize) -> Distribution<f32> {
    let alpha = row_alpha(r);
    let sqrt_ratio = 10f32.powf(0.5 * si as f32 / (NS - 1) as f32);
    Distribution {
        kind,
        alpha_x: alpha * sqrt_ratio,
        alpha_y: alpha / sqrt_ratio,
    }
}

/// `wo` at `cos theta = mu` and azimuth node `pi` from the x axis (the wider one).
fn direction(mu: f32, pi: usize) -> Vec3<f32> {
    let phi = std::f32::consts::FRAC_PI_2 * pi as f32 / (NP - 1) as f32;
    let sin = (1.0 - mu * mu).max(0.0).sqrt();
    Vec3::new(sin * phi.cos(), sin * phi.sin(), mu)
}

/// The hat-function weights `H_k` of `E[F(c) G2/G1]`, then `A = E[(1 - s) G2/G1]` and
/// `B = E[s G2/G1]` with Schlick's `s = (1 - c)^5`, for `wo`.
fn reflection_cell(dist: &Distribution<f32>, wo: Vec3<f32>, n: usize, warp: Warp) -> Vec<f64> {
    let g1 = dist.g1(wo);
    let mut h = vec![0.0f64; CHANNELS];
    for (u0, u1, q) in strata(n, warp) {
        let m = dist.sample(wo, u0, u1);
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

/// `E[F G2/G1]` and `E[(1 - F) G2/G1]` for `wo` above an interface of relative IOR `eta`.
fn dielectric_cell(
    dist: &Distribution<f32>,
    wo: Vec3<f32>,
    eta: f32,
    n: usize,
    warp: Warp,
) -> Vec<f64> {
    let g1 = dist.g1(wo);
    let (mut r, mut t) = (0.0f64, 0.0f64);
    for (u0, u1, q) in strata(n, warp) {
        let m = dist.sample(wo, u0, u1);
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
    vec![r, t]
}

/// `eta'` at `t` node `ti` on `side` (0: `eta' > 1`, 1: `eta' < 1`).
fn side_eta(side: usize, ti: usize) -> f32 {
    let t = T_MAX * ti as f32 / (DT - 1) as f32;
    let eta = (1.0 + t) / (1.0 - t);
    if side == 0 { eta } else { 1.0 / eta }
}

/// `mu` at [`dielectric_coordinate`] `x` (by bisection; the map is monotone), floored
/// at 1e-4: `mu = 0` has no albedo of its own, only the limit from above.
fn dielectric_mu(x: f32, eta: f32, alpha: f32) -> f32 {
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..48 {
        let mid = 0.5 * (lo + hi);
        if dielectric_coordinate(mid, eta, alpha) < x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)).max(1e-4)
}

/// Splits `index` into digits of the mixed radix `sizes` (most significant first).
fn digits<const K: usize>(mut index: usize, sizes: [usize; K]) -> [usize; K] {
    let mut out = [0; K];
    for k in (0..K).rev() {
        out[k] = index % sizes[k];
        index /= sizes[k];
    }
    out
}

/// The channels of cell `index` of `table`.
pub fn cell(table: Table, index: usize) -> Vec<f64> {
    let kind = table.kind;
    let r_node = |ri: usize, n: usize, max: f32| max * ri as f32 / (n - 1) as f32;
    match table.layout {
        Layout::Reflection => {
            let [ri, mi] = digits(index, [NR, N]);
            let dist = distribution(kind, r_node(ri, NR, R_MAX), 0);
            let wo = direction(reflection_mu(mi), 0);
            reflection_cell(&dist, wo, REFLECTION_STRATA, Warp::Tail)
        }
        Layout::ReflectionAnisotropic => {
            let [pi, si, ri, mi] = digits(index, [NP, NS, NR_ANISO, N]);
            if si == 0 {
                // Aspect 1 is the isotropic table's cell, so the two tables agree there.
                return cell(Table::new(Layout::Reflection, kind), ri * N + mi);
            }
            let dist = distribution(kind, r_node(ri, NR, R_MAX), si);
            let wo = direction(reflection_mu(mi), pi);
            reflection_cell(&dist, wo, REFLECTION_ANISOTROPIC_STRATA, Warp::BothEnds)
        }
        Layout::Dielectric => {
            let [side, ti, ri, xi] = digits(index, [2, DT, DR, DX]);
            let eta = side_eta(side, ti);
            let r = r_node(ri, DR, 1.0);
            let mu = dielectric_mu(xi as f32 / (DX - 1) as f32, eta, row_alpha(r));
            let dist = distribution(kind, r, 0);
            dielectric_cell(&dist, direction(mu, 0), eta, DIELECTRIC_STRATA, Warp::Tail)
        }
        Layout::DielectricAnisotropic => {
            let [side, ti, pi, si, ri, xi] = digits(index, [2, DT, NP, NS, DR, DX_ANISO]);
            let eta = side_eta(side, ti);
            let r = r_node(ri, DR, 1.0);
            let mu = dielectric_mu(xi as f32 / (DX_ANISO - 1) as f32, eta, row_alpha(r));
            // Aspect 1 is integrated as the isotropic table's cells are.
            let (n, warp, pi) = if si == 0 {
                (DIELECTRIC_STRATA, Warp::Tail, 0)
            } else {
                (DIELECTRIC_ANISOTROPIC_STRATA, Warp::BothEnds, pi)
            };
            let dist = distribution(kind, r, si);
            dielectric_cell(&dist, direction(mu, pi), eta, n, warp)
        }
    }
}

/// A channel value in [0, 1] as 16-bit fixed point.
pub fn quantize(value: f64) -> u16 {
    (value.clamp(0.0, 1.0) * f64::from(u16::MAX)).round() as u16
}

/// The inverse of [`quantize`].
pub fn dequantize(code: u16) -> f32 {
    f32::from(code) / f32::from(u16::MAX)
}

/// Every cell of `table`, quantized, in the committed file's byte order (little endian),
/// integrated on rayon's threads.
pub fn generate(table: Table) -> Vec<u8> {
    (0..table.cells())
        .into_par_iter()
        .flat_map_iter(|index| cell(table, index).into_iter())
        .flat_map_iter(|value| quantize(value).to_le_bytes())
        .collect()
}
