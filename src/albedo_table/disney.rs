//! Directional albedo of the Disney specular and clearcoat lobes (Burley 2012), whose
//! masking (separable Smith with a remapped or fixed roughness) the microfacet tables
//! do not describe. Both are integrated offline in f64 by stratified quadrature in the
//! lobe's own sampling variables and committed in `data/albedo/` as 16-bit codes
//! (tests/albedo_tables.rs spot-checks them; `GLINT_BLESS=disney` regenerates them).
//! Every table has [`NM`] `cos_o` nodes at `sqrt(cos_o)` spacing (narrow lobes at
//! grazing change by 3% between 32 such nodes).
//!
//! - specular: Schlick's split `f0 A + B`, `A = E[(1 - s) w]`, `B = E[s w]`,
//!   `s = (1 - l.h)^5`, over visible GGX normals of `(ax, ay)` with
//!   `w = 4 cos_o cos_i Gs(l) Gs(v) / G1(v)` (48 x 48 strata, warped toward the
//!   distribution's far tail). Isotropic ([`SpecularTable`], 8 KB): `sqrt(cos_o)` x
//!   `sqrt(roughness)` (33 nodes, dense toward the narrow lobes, whose grazing albedo
//!   changes fastest). Anisotropic ([`SpecularAnisotropicTable`], 2 MB): also the log
//!   aspect `-log10(1 - 0.9 anisotropic)` (13 nodes; the albedo is smooth in it, while in
//!   `anisotropic` itself it bends toward 1; node 0 is the isotropic table) and the
//!   azimuth of `wo` from the tangent (19 nodes, 0..90 degrees: at aspect 10 the grazing
//!   albedo doubles between the axes), strata warped toward both ends of the disk;
//! - clearcoat ([`ClearcoatTable`]): `E[Fr Gr 4 cos_i (v.h) / cos_h]` over GTR1 half
//!   vectors (64 x 64 strata warped toward grazing half vectors); axes `sqrt(cos_o)` and gloss (33).
//!
//! Errors against independent quadrature are measured in tests/lobe_disney_specular.rs,
//! tests/lobe_disney_clearcoat.rs and by the harness.

use super::generate::{Warp, strata};
use super::{corners, grid};
use crate::math::lane::ROW;
use crate::math::{Lane, Mask, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
use std::f64::consts::PI;
use std::sync::OnceLock;

const NM: usize = 64;
const NR: usize = 33;
const NA: usize = 13;
const NP: usize = 19;
const NG: usize = 33;
/// Strata per axis of each specular cell's quadrature (the weights of wide lobes jump
/// where reflected directions cross the horizon).
const STRATA: usize = 48;
const COAT_STRATA: usize = 64;

/// `cos_o` of node `i` of the `sqrt(cos_o)` axis (dense toward grazing).
fn mu_node(i: usize) -> f64 {
    let x = i as f64 / (NM - 1) as f64;
    (x * x).max(1e-4)
}

/// Disney's alphas (formulas.md): D's `(ax, ay)` and the masking's remapped ones.
pub fn specular_alphas(roughness: f64, anisotropic: f64) -> ([f64; 2], [f64; 2]) {
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    let a = roughness * roughness;
    let g = (0.5 + roughness / 2.0).powi(2);
    (
        [(a / aspect).max(0.001), (a * aspect).max(0.001)],
        [(g / aspect).max(0.001), (g * aspect).max(0.001)],
    )
}

/// Burley's `SmithG_GGX_aniso`: `1 / (w.z + sqrt((w.x ax)^2 + (w.y ay)^2 + w.z^2))`.
fn smith_separable(w: [f64; 3], a: [f64; 2]) -> f64 {
    1.0 / (w[2] + ((w[0] * a[0]).powi(2) + (w[1] * a[1]).powi(2) + w[2] * w[2]).sqrt())
}

/// A GGX visible normal for `v` (Heitz 2018, listing 1), in f64.
fn ggx_visible(v: [f64; 3], a: [f64; 2], u0: f64, u1: f64) -> [f64; 3] {
    let vh = normalize([a[0] * v[0], a[1] * v[1], v[2]]);
    let len2 = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if len2 > 0.0 {
        [-vh[1] / len2.sqrt(), vh[0] / len2.sqrt(), 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = [
        vh[1] * t1[2] - vh[2] * t1[1],
        vh[2] * t1[0] - vh[0] * t1[2],
        vh[0] * t1[1] - vh[1] * t1[0],
    ];
    let r = u0.sqrt();
    let phi = 2.0 * PI * u1;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).sqrt() + s * r * phi.sin();
    let nz = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = [0, 1, 2].map(|k| t1[k] * p1 + t2[k] * p2 + vh[k] * nz);
    normalize([a[0] * nh[0], a[1] * nh[1], nh[2].max(1e-9)])
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / l)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn reflect(v: [f64; 3], m: [f64; 3]) -> [f64; 3] {
    let d = 2.0 * dot(v, m);
    [0, 1, 2].map(|k| d * m[k] - v[k])
}

/// `(A, B)` of the specular at `v` (f64 quadrature over stratified visible normals).
fn specular_cell(v: [f64; 3], roughness: f64, anisotropic: f64, warp: Warp) -> [f64; 2] {
    let (a, g) = specular_alphas(roughness, anisotropic);
    let g1 =
        2.0 * v[2] / (v[2] + ((a[0] * v[0]).powi(2) + (a[1] * v[1]).powi(2) + v[2] * v[2]).sqrt());
    let gv = smith_separable(v, g);
    let mut sum = [0.0; 2];
    for (u0, u1, q) in strata(STRATA, warp) {
        let m = ggx_visible(v, a, f64::from(u0), f64::from(u1));
        let l = reflect(v, m);
        if l[2] <= 0.0 {
            continue;
        }
        let w = q * 4.0 * v[2] * l[2] * smith_separable(l, g) * gv / g1;
        let s = (1.0 - dot(l, m)).clamp(0.0, 1.0).powi(5);
        sum[0] += w * (1.0 - s);
        sum[1] += w * s;
    }
    sum
}

/// The clearcoat's GTR1 alpha for `gloss`.
pub fn clearcoat_alpha(gloss: f64) -> f64 {
    0.1 + (0.001 - 0.1) * gloss
}

/// The clearcoat's albedo at `v` (f64 quadrature over `COAT_STRATA^2` GTR1 half
/// vectors, the `cos_h` coordinate warped toward grazing half vectors at `u = 1`, whose
/// reflections cross the horizon).
pub fn clearcoat_cell(v: [f64; 3], gloss: f64) -> f64 {
    let a2 = clearcoat_alpha(gloss).powi(2);
    let smith = |c: f64| 1.0 / (c + (0.0625 + c * c - 0.0625 * c * c).sqrt());
    let mut sum = 0.0;
    for (u, u_phi, q) in strata(COAT_STRATA, Warp::Tail) {
        // sin_h^2 = a^2 ((a^2)^(-u) - 1) / (1 - a^2): no cancellation at the peak.
        let sin2 = a2 * (a2.powf(-f64::from(u)) - 1.0) / (1.0 - a2);
        let (sin_h, cos_h) = (sin2.sqrt(), (1.0 - sin2).max(0.0).sqrt());
        let phi = 2.0 * PI * f64::from(u_phi);
        let h = [sin_h * phi.cos(), sin_h * phi.sin(), cos_h];
        let vh = dot(v, h);
        let l = reflect(v, h);
        if l[2] <= 0.0 || vh <= 0.0 {
            continue;
        }
        let fr = 0.04 + 0.96 * (1.0 - vh).clamp(0.0, 1.0).powi(5);
        sum += q * fr * smith(l[2]) * smith(v[2]) * 4.0 * l[2] * vh / cos_h;
    }
    // f = D Fr Gr with Gr = G(l) G(v) including 1 / (4 cos cos): the weight is
    // f cos_i / (D cos_h / (4 v.h)).
    sum
}

fn view(mu: f64, phi: f64) -> [f64; 3] {
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    [s * phi.cos(), s * phi.sin(), mu]
}

/// The committed bytes of a table of `len` 16-bit codes, checked against its layout.
fn checked<'a>(bytes: &'a [u8], len: usize, name: &str) -> &'a [u8] {
    assert_eq!(
        bytes.len(),
        2 * len,
        "data/albedo/{name} does not match its layout: regenerate it with \
         GLINT_BLESS=disney cargo test --release --test albedo_tables"
    );
    bytes
}

/// The committed values of a table (16-bit codes, as the microfacet tables).
fn decode(bytes: &[u8], len: usize, name: &str) -> Vec<f32> {
    checked(bytes, len, name)
        .chunks_exact(2)
        .map(|b| super::generate::dequantize(u16::from_le_bytes([b[0], b[1]])))
        .collect()
}

/// The committed codes of a two-channel table, kept as codes: each cell's pair in one
/// little-endian `u32` (half the memory of decoded values, one gather per corner).
fn code_pairs(bytes: &[u8], cells: usize, name: &str) -> Vec<u32> {
    checked(bytes, 2 * cells, name)
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// Every cell of a table, integrated on all cores, as 16-bit codes.
fn generate(cells: usize, cell: impl Fn(usize) -> Vec<f64> + Sync) -> Vec<u8> {
    use rayon::prelude::*;
    (0..cells)
        .into_par_iter()
        .flat_map_iter(|i| cell(i).into_iter())
        .map(super::generate::quantize)
        .flat_map(|code| code.to_le_bytes())
        .collect()
}

/// `sqrt(roughness)` at node `i`, and the roughness.
fn roughness_node(i: usize) -> f64 {
    (i as f64 / (NR - 1) as f64).powi(2)
}

/// The anisotropic table's aspect axis, `-log10(1 - 0.9 anisotropic)` in [0, 1].
#[inline(always)]
fn aspect_coordinate<L: Lane>(anisotropic: L) -> L {
    let a = anisotropic.clamp(L::zero(), L::one());
    -(-(L::splat(0.9) * a)).ln_1p() * L::splat(std::f32::consts::LOG10_E)
}

/// The azimuth of `(x, y)` (both at least 0) from the tangent, in azimuth nodes (0 to
/// `NP - 1`): `atan(min / max)` by Rajan et al. 2006's cubic (within 0.0015 rad, 0.02
/// of a node), reflected about 45 degrees where `y > x`. Multiplies and adds only, no
/// `atan2`, whose scalar and SIMD versions differ in the last bits: every lane type
/// computes these bits, so a closure and a material batch find the same node.
#[inline(always)]
fn azimuth_position<L: Lane>(x: L, y: L) -> L {
    let (lo, hi) = (x.min(y), x.max(y));
    let q = L::select(hi.gt(L::zero()), lo / hi, L::zero());
    let atan =
        L::splat(FRAC_PI_4) * q - q * (q - L::one()) * (L::splat(0.2447) + L::splat(0.0663) * q);
    let phi = L::select(y.gt(x), L::splat(FRAC_PI_2) - atan, atan);
    (phi * L::splat((NP - 1) as f32 / FRAC_PI_2)).min(L::splat((NP - 1) as f32))
}

/// The interpolated `(A, B)` over the corners `c` of a table of [`code_pairs`]: the
/// codes are interpolated and scaled once (as [`super::generate::dequantize`]).
#[inline(always)]
fn sum_pairs<L: Lane, const C: usize>(pairs: &[u32], c: [(L, L); C]) -> (L, L) {
    let (mut a, mut b) = (L::zero(), L::zero());
    // `corners`' first axis is `cos_o`'s, of stride 1: corners 2j and 2j + 1 are
    // adjacent cells, read together.
    for corner in c.chunks_exact(2) {
        let cells = L::gather_code_pairs_adjacent(pairs, corner[0].0);
        for ((ca, cb), &(_, w)) in cells.into_iter().zip(corner) {
            a = w.mul_add(ca, a);
            b = w.mul_add(cb, b);
        }
    }
    let scale = L::splat(1.0 / f32::from(u16::MAX));
    (a * scale, b * scale)
}

/// One point's [`grid`]: the lower index as an integer (`pos` is at least 0, so its
/// truncation is its floor).
#[inline(always)]
fn grid_one(x: f32, n: usize) -> (usize, f32) {
    let pos = x.clamp(0.0, 1.0) * (n - 1) as f32;
    // Through `i32`: a float's conversion to `usize` takes several more instructions.
    let i = (pos as i32).min(n as i32 - 2);
    (i as usize, pos - i as f32)
}

/// One point's bilinear interpolation over `cos_o` (stride 1) and a second axis (stride
/// [`NM`]) from cell `base`: the four corners' values and weights, in [`corners`]' order
/// (the same weights). A closure's build converted each float index of the lanes' path
/// (several instructions each) and bounds-checked every lookup; here one window of the
/// table is checked once.
#[inline(always)]
fn bilinear_one<T: Copy>(
    table: &[T],
    base: usize,
    (im, fm): (usize, f32),
    (ir, fr): (usize, f32),
) -> ([T; 4], [f32; 4]) {
    let at = base + ir * NM + im;
    let window = &table[at..at + NM + 2];
    let weights = [
        (1.0 - fm) * (1.0 - fr),
        fm * (1.0 - fr),
        (1.0 - fm) * fr,
        fm * fr,
    ];
    ([window[0], window[1], window[NM], window[NM + 1]], weights)
}

/// The [`ROW`] cells of a table from cell `at`: one row of its `cos_o` axis.
#[inline(always)]
fn row(values: &[f32], at: usize) -> &[f32; ROW] {
    const { assert!(NM == ROW) };
    values[at..at + ROW].try_into().expect("a row is ROW cells")
}

/// `sum_k weights[k] values[k]` summed in pairs: a closure's build waits on this chain
/// (in order, it was four additions long).
#[inline(always)]
fn weighted_sum(values: [f32; 4], weights: [f32; 4]) -> f32 {
    (weights[0] * values[0] + weights[1] * values[1])
        + (weights[2] * values[2] + weights[3] * values[3])
}

/// The isotropic Disney specular's albedo table (module docs).
pub struct SpecularTable;

impl SpecularTable {
    pub const FILE: &'static str = "disney_specular.u16";
    pub const CELLS: usize = NR * NM;
    pub const CHANNELS: usize = 2;

    /// `(A, B)` of cell `i` (`[sqrt(roughness)][mu]`).
    pub fn cell(i: usize) -> Vec<f64> {
        let (m, r) = (i % NM, i / NM);
        let v = view(mu_node(m), 0.0);
        specular_cell(v, roughness_node(r), 0.0, Warp::Tail).to_vec()
    }

    /// The whole table as committed.
    pub fn generate() -> Vec<u8> {
        generate(Self::CELLS, Self::cell)
    }

    fn pairs() -> &'static [u32] {
        static PAIRS: OnceLock<Vec<u32>> = OnceLock::new();
        PAIRS.get_or_init(|| {
            code_pairs(
                include_bytes!("../../data/albedo/disney_specular.u16"),
                Self::CELLS,
                Self::FILE,
            )
        })
    }

    /// `f0 A + B` as `(A, B)` at `wo` (above the surface) for `roughness` and
    /// `anisotropic` in [0, 1]: lanes with `anisotropic > 0` read
    /// [`SpecularAnisotropicTable`], whose first aspect node is this table.
    #[inline(always)]
    pub fn lookup<L: Lane>(wo: Vec3<L>, roughness: L, anisotropic: L) -> (L, L) {
        let stretched = anisotropic.gt(L::zero());
        if L::LANES == 1 && !stretched.any() {
            // The estimate's path, so that the two agree to the bit where isotropic.
            let wo = Vec3::new(wo.x.lane0(), wo.y.lane0(), wo.z.lane0());
            let (a, b) = Self::estimate_one(wo, roughness.lane0(), 0.0);
            return (L::splat(a), L::splat(b));
        }
        let m = grid(wo.z.clamp(L::zero(), L::one()).sqrt(), NM);
        let r = grid(roughness.max(L::zero()).sqrt(), NR);
        if stretched.all() {
            return SpecularAnisotropicTable::lookup(wo, m, r, anisotropic);
        }
        let (a, b) = sum_pairs::<L, 4>(
            Self::pairs(),
            corners(L::zero(), [(m.0, m.1, 1), (r.0, r.1, NM)]),
        );
        if !stretched.any() {
            return (a, b);
        }
        let (aa, ab) = SpecularAnisotropicTable::lookup(wo, m, r, anisotropic);
        (L::select(stretched, aa, a), L::select(stretched, ab, b))
    }

    /// [`Self::lookup`] as lobe selection and pruning weigh the lobe: the same where
    /// `anisotropic` is 0; elsewhere the anisotropic table at the nearest azimuth and
    /// aspect nodes, interpolated over `cos_o` and roughness only (4 gathers instead
    /// of 16). Measured against `lookup` (tests/lobe_disney_specular.rs): within 8% at
    /// 99% of views and parameters, 17% at worst (anisotropic 0.9, `cos_o` below 0.003).
    #[inline(always)]
    pub fn estimate<L: Lane>(wo: Vec3<L>, roughness: L, anisotropic: L) -> (L, L) {
        if L::LANES == 1 {
            let wo = Vec3::new(wo.x.lane0(), wo.y.lane0(), wo.z.lane0());
            let (a, b) = Self::estimate_one(wo, roughness.lane0(), anisotropic.lane0());
            return (L::splat(a), L::splat(b));
        }
        let m = grid(wo.z.clamp(L::zero(), L::one()).sqrt(), NM);
        let r = grid(roughness.max(L::zero()).sqrt(), NR);
        let (pairs, base) = if anisotropic.gt(L::zero()).any() {
            // Isotropic lanes read aspect node 0, the isotropic table's cells.
            let (ia, ip) = SpecularAnisotropicTable::nearest_nodes(wo, anisotropic);
            let base = ia * L::splat((NM * NR) as f32) + ip * L::splat((NM * NR * NA) as f32);
            (SpecularAnisotropicTable::pairs(), base)
        } else {
            (Self::pairs(), L::zero())
        };
        sum_pairs::<L, 4>(pairs, corners(base, [(m.0, m.1, 1), (r.0, r.1, NM)]))
    }

    /// [`Self::estimate`] of one point, with integer indices.
    #[inline(always)]
    fn estimate_one(wo: Vec3<f32>, roughness: f32, anisotropic: f32) -> (f32, f32) {
        let (pairs, base) = if anisotropic > 0.0 {
            let (aspect, azimuth) = SpecularAnisotropicTable::nearest_node_indices(wo, anisotropic);
            let base = (aspect + azimuth * NA) * NM * NR;
            (SpecularAnisotropicTable::pairs(), base)
        } else {
            (Self::pairs(), 0)
        };
        let m = grid_one(wo.z.clamp(0.0, 1.0).sqrt(), NM);
        let r = grid_one(roughness.max(0.0).sqrt(), NR);
        let (pairs, weights) = bilinear_one(pairs, base, m, r);
        let scale = 1.0 / f32::from(u16::MAX);
        (
            weighted_sum(pairs.map(|p| (p & 0xffff) as f32), weights) * scale,
            weighted_sum(pairs.map(|p| (p >> 16) as f32), weights) * scale,
        )
    }
}

/// The anisotropic Disney specular's albedo table (module docs).
pub struct SpecularAnisotropicTable;

impl SpecularAnisotropicTable {
    pub const FILE: &'static str = "disney_specular_anisotropic.u16";
    pub const CELLS: usize = NP * NA * NR * NM;
    pub const CHANNELS: usize = 2;

    /// `(A, B)` of cell `i` (`[phi][aspect][sqrt(roughness)][mu]`).
    pub fn cell(i: usize) -> Vec<f64> {
        let (m, r, a, p) = (i % NM, i / NM % NR, i / (NM * NR) % NA, i / (NM * NR * NA));
        if a == 0 {
            // Isotropic: the isotropic table's cell, so the two agree there.
            return SpecularTable::cell(r * NM + m);
        }
        // The inverse of `aspect_coordinate`.
        let x = a as f64 / (NA - 1) as f64;
        let anisotropic = ((1.0 - 10f64.powf(-x)) / 0.9).min(1.0);
        let v = view(mu_node(m), p as f64 / (NP - 1) as f64 * PI / 2.0);
        specular_cell(v, roughness_node(r), anisotropic, Warp::BothEnds).to_vec()
    }

    /// The whole table as committed (minutes on two cores).
    pub fn generate() -> Vec<u8> {
        generate(Self::CELLS, Self::cell)
    }

    fn pairs() -> &'static [u32] {
        static PAIRS: OnceLock<Vec<u32>> = OnceLock::new();
        PAIRS.get_or_init(|| {
            code_pairs(
                include_bytes!("../../data/albedo/disney_specular_anisotropic.u16"),
                Self::CELLS,
                Self::FILE,
            )
        })
    }

    /// The nearest aspect and azimuth nodes of `anisotropic` and `wo`, from
    /// comparisons and [`azimuth_position`] alone (no `ln_1p` or `atan2`, whose scalar
    /// and SIMD versions differ in the last bits: the node must be the same on every
    /// ISA, or a closure and a material batch would select apart).
    #[inline(always)]
    fn nearest_nodes<L: Lane>(wo: Vec3<L>, anisotropic: L) -> (L, L) {
        let aspects = Self::aspect_midpoints();
        let (one, zero) = (L::one(), L::zero());
        // `anisotropic` is most often the material's own, the same on every lane: one
        // binary search then (the same count: the comparisons are monotone).
        let first = anisotropic.lane0();
        let mut aspect = zero;
        if anisotropic.eq(L::splat(first)).all() {
            aspect = L::splat(aspects.partition_point(|&m| first > m) as f32);
        } else {
            for &a in aspects {
                aspect += L::select(anisotropic.gt(L::splat(a)), one, zero);
            }
        }
        let azimuth = (azimuth_position(wo.x.abs(), wo.y.abs()) + L::splat(0.5)).floor();
        (aspect, azimuth)
    }

    /// [`Self::nearest_nodes`] of one point: the aspect by binary search (the
    /// comparisons are monotone along the sorted midpoints), the azimuth by the same
    /// operations as the lanes'.
    #[inline(always)]
    fn nearest_node_indices(wo: Vec3<f32>, anisotropic: f32) -> (usize, usize) {
        let aspects = Self::aspect_midpoints();
        let azimuth = (azimuth_position(wo.x.abs(), wo.y.abs()) + 0.5).floor();
        (
            aspects.partition_point(|&m| anisotropic > m),
            azimuth as usize,
        )
    }

    /// The midpoints between aspect nodes, as `anisotropic`.
    fn aspect_midpoints() -> &'static [f32; NA - 1] {
        static MIDPOINTS: OnceLock<[f32; NA - 1]> = OnceLock::new();
        MIDPOINTS.get_or_init(|| {
            std::array::from_fn(|k| {
                // The inverse of `aspect_coordinate`.
                let x = (k as f64 + 0.5) / (NA - 1) as f64;
                ((1.0 - 10f64.powf(-x)) / 0.9) as f32
            })
        })
    }

    /// `(A, B)` at `wo` with the `cos_o` and roughness grid positions `m`, `r`.
    #[inline(always)]
    fn lookup<L: Lane>(wo: Vec3<L>, m: (L, L), r: (L, L), anisotropic: L) -> (L, L) {
        let phi = wo.y.abs().atan2(wo.x.abs()) * L::splat(std::f32::consts::FRAC_2_PI);
        // Along the normal the azimuth is undefined and the albedo isotropic.
        let phi = L::select(wo.x.abs().max(wo.y.abs()).gt(L::zero()), phi, L::zero());
        let (ip, fp) = grid(phi, NP);
        let (ia, fa) = grid(aspect_coordinate(anisotropic), NA);
        sum_pairs::<L, 16>(
            Self::pairs(),
            corners(
                L::zero(),
                [
                    (m.0, m.1, 1),
                    (r.0, r.1, NM),
                    (ia, fa, NM * NR),
                    (ip, fp, NM * NR * NA),
                ],
            ),
        )
    }
}

/// The Disney clearcoat's albedo table (module docs).
pub struct ClearcoatTable;

impl ClearcoatTable {
    pub const FILE: &'static str = "disney_clearcoat.u16";
    pub const CELLS: usize = NG * NM;
    pub const CHANNELS: usize = 1;

    /// The albedo of cell `i` (`[gloss][mu]`).
    pub fn cell(i: usize) -> Vec<f64> {
        let (m, g) = (i % NM, i / NM);
        vec![clearcoat_cell(
            view(mu_node(m), 0.0),
            g as f64 / (NG - 1) as f64,
        )]
    }

    /// The whole table as committed.
    pub fn generate() -> Vec<u8> {
        generate(Self::CELLS, Self::cell)
    }

    fn values() -> &'static [f32] {
        static VALUES: OnceLock<Vec<f32>> = OnceLock::new();
        VALUES.get_or_init(|| {
            decode(
                include_bytes!("../../data/albedo/disney_clearcoat.u16"),
                Self::CELLS * Self::CHANNELS,
                Self::FILE,
            )
        })
    }

    /// The albedo at `wo` (above the surface) for `gloss` in [0, 1].
    #[inline(always)]
    pub fn lookup<L: Lane>(wo: Vec3<L>, gloss: L) -> L {
        if L::LANES == 1 {
            return L::splat(Self::lookup_one(wo.z.lane0(), gloss.lane0()));
        }
        let (im, fm) = grid(wo.z.clamp(L::zero(), L::one()).sqrt(), NM);
        let (ig, fg) = grid(gloss, NG);
        let c: [(L, L); 4] = corners(L::zero(), [(im, fm, 1), (ig, fg, NM)]);
        let values = Self::values();
        // `clearcoat_gloss` is most often the material's own, one gloss row pair on
        // every lane: the rows' cells are picked rather than gathered (the same ones).
        let first = ig.lane0();
        let one_row_pair = ig.eq(L::splat(first)).all();
        let mut sum = L::zero();
        // `corners`' first axis is `cos_o`'s, of stride 1: corners 2j and 2j + 1 are
        // adjacent cells, read together.
        for (j, corner) in c.chunks_exact(2).enumerate() {
            let cells = if one_row_pair {
                L::row_adjacent(row(values, (first as usize + j) * NM), im)
            } else {
                L::gather_adjacent(values, corner[0].0)
            };
            for (v, &(_, w)) in cells.into_iter().zip(corner) {
                sum = w.mul_add(v, sum);
            }
        }
        sum
    }

    /// [`Self::lookup`] of one point, with integer indices.
    #[inline(always)]
    fn lookup_one(cos_o: f32, gloss: f32) -> f32 {
        let m = grid_one(cos_o.clamp(0.0, 1.0).sqrt(), NM);
        let g = grid_one(gloss, NG);
        let (values, weights) = bilinear_one(Self::values(), 0, m, g);
        weighted_sum(values, weights)
    }
}
