//! Directional albedo of single-scattering microfacet lobes, read from tables with
//! multilinear interpolation. The tables are integrated offline by [`generate`] and
//! committed in `data/albedo/` as 16-bit fixed point (every channel lies in [0, 1];
//! quantization step 1.5e-5); `tests/albedo_tables.rs` proves them fresh and regenerates
//! them with `GLINT_BLESS=1`. First use only decodes them (microseconds).
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
//! `r = sqrt(alpha)` in [0, 1.5]. Anisotropic lobes add two axes: the aspect
//! `log10(alpha_x / alpha_y)` in [0, 1] (Burley's mapping reaches 10 at
//! `anisotropic = 1`), and the azimuth of `wo` from the wider axis in [0, 90] degrees;
//! `r` is then the geometric mean `sqrt(sqrt(alpha_x alpha_y))`. The albedo is not a
//! function of the projected roughness alone (at normal incidence it depends on both
//! axes while the projected roughness is undefined), hence the axes.
//!
//! Dielectric ([`DielectricTable`]): `E[F G2/G1]` (reflection) and `E[(1 - F) G2/G1]`
//! (transmission, importance transport) over visible normals, over `|mu|`, `r` in [0, 1]
//! and `t = |eta' - 1| / (eta' + 1)` (so `t^2` is the normal-incidence reflectance), for
//! `eta' > 1` and `eta' < 1` separately, and for anisotropic lobes over the same aspect
//! and azimuth axes. Seen from the denser side the albedo changes within about `alpha` of
//! the critical angle `mu_c = sqrt(1 - eta'^2)` (total internal reflection sets in), so
//! there the `mu` axis is warped per roughness ([`dielectric_coordinate`]) to put half
//! its nodes within a few `alpha` of `mu_c`. `t` beyond the grid (`eta'` above 39 or
//! below 1/39) is clamped.
//!
//! The tables' errors against an independent f64 quadrature are measured in
//! tests/albedo.rs and by the verification harness.

pub mod disney;
pub mod generate;

use crate::fresnel::{self, FresnelModel};
use crate::math::{Lane, Mask, Rgb, Vec3};
use crate::microfacet::{Distribution, MIN_ALPHA, Ndf, NdfKind, SmithNdf, smith_ndfs};
use std::sync::OnceLock;

/// `mu` nodes of the reflection tables.
const N: usize = 32;
/// Rows of the isotropic reflection table in `r = sqrt(alpha)`, spanning [0, R_MAX].
const NR: usize = 48;
const R_MAX: f32 = 1.5;
/// Intervals of the piecewise-linear Fresnel interpolant; nodes `c_k = (k / FRESNEL_K)^2`.
const FRESNEL_K: usize = 12;
/// Fresnel nodes.
pub const FRESNEL_NODES: usize = FRESNEL_K + 1;
/// Channels of a reflection table cell: the `H_k`, then Schlick's `A` and `B`.
const CHANNELS: usize = FRESNEL_NODES + 2;
/// Rows of the anisotropic reflection table in `r`: the isotropic rows up to `r = 1.02`.
const NR_ANISO: usize = 33;
/// Aspect nodes, `log10(alpha_x / alpha_y)` in [0, 1].
const NS: usize = 6;
/// Azimuth nodes in [0, 90] degrees from the wider axis.
const NP: usize = 7;

/// `mu` nodes (in [`dielectric_coordinate`]) of the isotropic dielectric table (dense
/// enough for grazing views from inside, 2 of whose 4 quarters the critical-angle warp
/// takes), and of the anisotropic one.
const DX: usize = 41;
const DX_ANISO: usize = 25;
/// `r` nodes of the dielectric tables, spanning [0, 1].
const DR: usize = 17;
/// `t` nodes of the dielectric tables, spanning [0, T_MAX]. Seen from inside, wide
/// anisotropic lobes transmit in a peak over `mu` that moves with `eta'` faster than
/// the critical angle: half as many nodes gave 18% errors between them.
const DT: usize = 17;
/// Largest `t = |eta' - 1| / (eta' + 1)` on the grid (`eta' = 39`).
const T_MAX: f32 = 0.95;
/// Dielectric channels: reflection, transmission.
const DIELECTRIC_CHANNELS: usize = 2;
/// Half-width of the critical-angle warp in `mu`, per unit `alpha eta'`
/// (`d mu = sin theta_c d theta = eta' d theta`, facets tilted by about `alpha`), and
/// its floor for the smoothest rows.
const TIR_WIDTH: f32 = 2.0;
const TIR_MIN_WIDTH: f32 = 1e-3;

/// The table files of every layout for every kind, layout-major in [`Layout::ALL`] and
/// [`NdfKind::ALL`] order ([`Table::index`]).
macro_rules! table_files {
    ({} $($variant:ident $name:literal),+) => {
        [
            $(include_bytes!(concat!("../../data/albedo/reflection_", $name, ".u16")).as_slice(),)+
            $(include_bytes!(concat!("../../data/albedo/reflection_anisotropic_", $name, ".u16")).as_slice(),)+
            $(include_bytes!(concat!("../../data/albedo/dielectric_", $name, ".u16")).as_slice(),)+
            $(include_bytes!(concat!("../../data/albedo/dielectric_anisotropic_", $name, ".u16")).as_slice(),)+
        ]
    };
}
const FILES: [&[u8]; TABLES] = smith_ndfs!(table_files! {});
/// One table per layout and kind.
const TABLES: usize = Layout::ALL.len() * NdfKind::ALL.len();

/// The grid layouts a table can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// `[r][mu]` cells of [`CHANNELS`].
    Reflection,
    /// `[phi][aspect][r][mu]` cells of [`CHANNELS`].
    ReflectionAnisotropic,
    /// `[side][t][r][x]` cells of reflection and transmission.
    Dielectric,
    /// `[side][t][phi][aspect][r][x]` cells of reflection and transmission.
    DielectricAnisotropic,
}

impl Layout {
    pub const ALL: [Layout; 4] = [
        Layout::Reflection,
        Layout::ReflectionAnisotropic,
        Layout::Dielectric,
        Layout::DielectricAnisotropic,
    ];
}

/// One committed table: a layout for one distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Table {
    pub layout: Layout,
    pub kind: NdfKind,
}

impl Table {
    /// Every table, in [`Table::index`] order.
    pub fn all() -> impl Iterator<Item = Table> {
        Layout::ALL.into_iter().flat_map(|layout| {
            NdfKind::ALL
                .iter()
                .map(move |&kind| Table::new(layout, kind))
        })
    }

    const fn new(layout: Layout, kind: NdfKind) -> Table {
        Table { layout, kind }
    }

    fn index(self) -> usize {
        NdfKind::ALL.len() * self.layout as usize + self.kind as usize
    }

    /// The file name under `data/albedo/`.
    pub fn file_name(self) -> String {
        let layout = match self.layout {
            Layout::Reflection => "reflection",
            Layout::ReflectionAnisotropic => "reflection_anisotropic",
            Layout::Dielectric => "dielectric",
            Layout::DielectricAnisotropic => "dielectric_anisotropic",
        };
        format!("{layout}_{}.u16", self.kind.name())
    }

    /// Cells in the table.
    pub fn cells(self) -> usize {
        match self.layout {
            Layout::Reflection => NR * N,
            Layout::ReflectionAnisotropic => NP * NS * NR_ANISO * N,
            Layout::Dielectric => 2 * DT * DR * DX,
            Layout::DielectricAnisotropic => 2 * DT * NP * NS * DR * DX_ANISO,
        }
    }

    /// Values per cell.
    pub fn channels(self) -> usize {
        match self.layout {
            Layout::Reflection | Layout::ReflectionAnisotropic => CHANNELS,
            Layout::Dielectric | Layout::DielectricAnisotropic => DIELECTRIC_CHANNELS,
        }
    }

    /// The decoded values, `channels()` per cell.
    fn values(self) -> &'static [f32] {
        static DECODED: [OnceLock<Vec<f32>>; TABLES] = [const { OnceLock::new() }; TABLES];
        DECODED[self.index()].get_or_init(|| {
            let bytes = FILES[self.index()];
            let len = self.cells() * self.channels();
            assert_eq!(
                bytes.len(),
                2 * len,
                "data/albedo/{} does not match its layout: regenerate it with \
                 GLINT_BLESS=1 cargo test --release --test albedo_tables",
                self.file_name()
            );
            bytes
                .chunks_exact(2)
                .map(|b| generate::dequantize(u16::from_le_bytes([b[0], b[1]])))
                .collect()
        })
    }
}

/// Grid coordinate of `x` in [0, 1] on `n` points: the lower index and the fraction.
#[inline(always)]
pub(super) fn grid<L: Lane>(x: L, n: usize) -> (L, L) {
    let pos = x.clamp(L::zero(), L::one()) * L::splat((n - 1) as f32);
    let i = pos.floor().min(L::splat((n - 2) as f32));
    (i, pos - i)
}

/// The `C = 2^A` corners `(cell index, weight)` of multilinear interpolation from cell
/// `base`, over axes `(lower index, fraction, stride in cells)`.
#[inline(always)]
pub(super) fn corners<L: Lane, const A: usize, const C: usize>(
    base: L,
    axes: [(L, L, usize); A],
) -> [(L, L); C] {
    debug_assert_eq!(C, 1 << A);
    let mut origin = base;
    for (i, _, stride) in axes {
        origin += i * L::splat(stride as f32);
    }
    // A loop, not `array::from_fn`: its closure would be a function without the
    // kernel's target features (tests/simd_inlining.rs).
    let mut out = [(origin, L::one()); C];
    for (corner, (index, weight)) in out.iter_mut().enumerate() {
        for (bit, (_, f, stride)) in axes.iter().enumerate() {
            if corner >> bit & 1 == 1 {
                *index += L::splat(*stride as f32);
                *weight *= *f;
            } else {
                *weight *= L::one() - *f;
            }
        }
    }
    out
}

/// `sum_corners weight value(corner, k)` for each of the `K` channels of `table`.
#[inline(always)]
fn interpolate<L: Lane, const K: usize>(table: Table, corners: &[(L, L)]) -> [L; K] {
    let values = table.values();
    let stride = L::splat(K as f32);
    let mut sum = [L::zero(); K];
    for &(cell, weight) in corners {
        let row = L::gather_row::<K>(values, cell * stride);
        for (s, v) in sum.iter_mut().zip(row) {
            *s = weight.mul_add(v, *s);
        }
    }
    sum
}

/// The roughness axis of every table: `sqrt` of the geometric-mean alpha.
#[inline(always)]
fn mean_roughness<L: Lane>(dist: &Distribution<L>) -> L {
    (dist.alpha_x * dist.alpha_y).sqrt().sqrt()
}

/// Lanes whose distribution is anisotropic (beyond rounding).
#[inline(always)]
fn anisotropic<L: Lane>(dist: &Distribution<L>) -> L::Mask {
    dist.alpha_x
        .max(dist.alpha_y)
        .gt(dist.alpha_x.min(dist.alpha_y) * L::splat(1.0 + 1e-5))
}

/// The anisotropic axes of `wo` and `dist`: the azimuth from the wider axis in [0, 1]
/// (0 along it) and the aspect `log10(alpha_wide / alpha_narrow)`.
#[inline(always)]
fn anisotropic_coordinates<L: Lane>(wo: Vec3<L>, dist: &Distribution<L>) -> (L, L) {
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
    (phi, aspect)
}

/// The reflection tables (see the module documentation).
pub struct ReflectionTable;

impl ReflectionTable {
    /// The channels for `wo` above the surface and `dist`, isotropic or not.
    #[inline(always)]
    fn lookup<L: Lane>(wo: Vec3<L>, dist: &Distribution<L>) -> [L; CHANNELS] {
        let r = mean_roughness(dist);
        let (x0, fx) = grid(wo.z.max(L::zero()).sqrt(), N);
        let (y0, fy) = grid(r * L::splat(1.0 / R_MAX), NR);
        let iso = interpolate(
            Table::new(Layout::Reflection, dist.kind),
            &corners::<L, 2, 4>(L::zero(), [(x0, fx, 1), (y0, fy, N)]),
        );
        let anisotropic = anisotropic(dist);
        if !anisotropic.any() {
            return iso;
        }
        let (phi, aspect) = anisotropic_coordinates(wo, dist);
        // The r axis is the isotropic one, truncated to NR_ANISO rows.
        let r_pos = (r * L::splat((NR - 1) as f32 / R_MAX))
            .clamp(L::zero(), L::splat((NR_ANISO - 1) as f32));
        let y0 = r_pos.floor().min(L::splat((NR_ANISO - 2) as f32));
        let (z0, fz) = grid(aspect, NS);
        let (w0, fw) = grid(phi, NP);
        let aniso: [L; CHANNELS] = interpolate(
            Table::new(Layout::ReflectionAnisotropic, dist.kind),
            &corners::<L, 4, 16>(
                L::zero(),
                [
                    (x0, fx, 1),
                    (y0, r_pos - y0, N),
                    (z0, fz, N * NR_ANISO),
                    (w0, fw, N * NR_ANISO * NS),
                ],
            ),
        );
        let mut h = iso;
        for (h, a) in h.iter_mut().zip(aniso) {
            *h = L::select(anisotropic, a, *h);
        }
        h
    }

    /// The single-scattering albedo `E[F(wo.m) G2/G1]` of a reflection lobe, for `wo`
    /// above the surface. Schlick is exact in `A` and `B`; a conductor is Schlick's
    /// `F0 A + B` (`F0 = F(1)`, `F(0) = 1`) plus its departure from that curve,
    /// interpolated at the Fresnel nodes: small and smooth, so little interpolation error.
    /// `nodes` are the conductor's [`FresnelNodes`] when the caller has them (closures
    /// compute them once per lobe); otherwise they are computed here.
    #[inline(always)]
    pub fn albedo<L: Lane>(
        wo: Vec3<L>,
        dist: &Distribution<L>,
        fresnel: &FresnelModel<L>,
        nodes: Option<&FresnelNodes<L>>,
    ) -> Rgb<L> {
        let h = Self::lookup(wo, dist);
        let (a, b) = (h[FRESNEL_NODES], h[FRESNEL_NODES + 1]);
        let sum = match fresnel {
            FresnelModel::Schlick { f0, f90 } => *f0 * a + *f90 * b,
            FresnelModel::Conductor { eta, k } => {
                let computed;
                let nodes = match nodes {
                    Some(n) => n,
                    None => {
                        computed = FresnelNodes::of_conductor(*eta, *k);
                        &computed
                    }
                };
                let mut sum = nodes.f0 * a + Rgb::splat(b);
                for (d, &hj) in nodes.departures.iter().zip(&h[..FRESNEL_NODES]) {
                    sum = sum + *d * hj;
                }
                sum
            }
        };
        sum.map(|v| v.max(L::zero()))
    }
}

/// A conductor's Fresnel curve as [`ReflectionTable::albedo`] reads it, per channel:
/// `F(1)` and the departures `F(c_j) - Schlick(F(1), 1, c_j)` at the Fresnel nodes
/// `c_j`. They depend on the IOR alone, so a closure computes them once, when the lobe
/// is added, instead of 13 exact Fresnel terms per channel at every albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelNodes<L> {
    pub f0: Rgb<L>,
    pub departures: [Rgb<L>; FRESNEL_NODES],
}

impl<L: Lane> FresnelNodes<L> {
    /// Values of [`Self::to_values`]: `f0`, then each departure, as `r, g, b`.
    pub const LEN: usize = 3 * (FRESNEL_NODES + 1);

    /// From a conductor's Fresnel curve per channel at [`FRESNEL_CURVE_COS`].
    #[inline(always)]
    pub fn from_curve(curve: [[L; FRESNEL_NODES + 1]; 3]) -> Self {
        let [fr, fg, fb] = curve;
        let f0 = Rgb::new(fr[FRESNEL_NODES], fg[FRESNEL_NODES], fb[FRESNEL_NODES]);
        let mut departures = [Rgb::splat(L::zero()); FRESNEL_NODES];
        for (j, d) in departures.iter_mut().enumerate() {
            let cos = L::splat(FRESNEL_CURVE_COS[j]);
            *d = Rgb::new(
                fr[j] - fresnel::schlick(f0.r, L::one(), cos),
                fg[j] - fresnel::schlick(f0.g, L::one(), cos),
                fb[j] - fresnel::schlick(f0.b, L::one(), cos),
            );
        }
        FresnelNodes { f0, departures }
    }

    #[inline(always)]
    pub fn of_conductor(eta: Rgb<L>, k: Rgb<L>) -> Self {
        // A loop, not `array::map` (tests/simd_inlining.rs).
        let mut cos = [L::zero(); FRESNEL_CURVE_COS.len()];
        for (c, &x) in cos.iter_mut().zip(&FRESNEL_CURVE_COS) {
            *c = L::splat(x);
        }
        let curve = |eta: L, k: L| fresnel::conductor_at(cos, &fresnel::ConductorIor::new(eta, k));
        Self::from_curve([curve(eta.r, k.r), curve(eta.g, k.g), curve(eta.b, k.b)])
    }
}

impl FresnelNodes<f32> {
    /// Writes [`Self::LEN`] values into `out`.
    pub fn to_values(&self, out: &mut [f32]) {
        for (rgb, chunk) in std::iter::once(&self.f0)
            .chain(&self.departures)
            .zip(out.chunks_exact_mut(3))
        {
            chunk.copy_from_slice(&rgb.to_array());
        }
    }
}

/// `mu` at node `i` of the reflection tables' `sqrt(mu)` axis; `mu = 0` has no albedo of
/// its own: the limit from just above.
fn reflection_mu(i: usize) -> f32 {
    let x = i as f32 / (N - 1) as f32;
    (x * x).max(1e-4)
}

/// Fresnel node `k`, `c_k = (k / FRESNEL_K)^2`.
const fn fresnel_node(k: usize) -> f32 {
    let x = k as f32 / FRESNEL_K as f32;
    x * x
}

/// The Fresnel nodes `c_k` ([`fresnel_node`]), then normal incidence, 1: where
/// [`FresnelNodes`] evaluates a conductor's Fresnel curve.
pub const FRESNEL_CURVE_COS: [f32; FRESNEL_NODES + 1] = {
    let mut c = [1.0; FRESNEL_NODES + 1];
    let mut k = 0;
    while k < FRESNEL_NODES {
        c[k] = fresnel_node(k);
        k += 1;
    }
    c
};

/// `s (len + w) / (len (s + w))`: maps [0, len] onto [0, 1] with half its range within
/// `w` of 0 (0 when `len = 0`).
#[inline(always)]
fn rational_warp<L: Lane>(s: L, len: L, w: L) -> L {
    (s * (len + w)).safe_div(len * (s + w))
}

/// The `mu` axis coordinate in [0, 1] of the dielectric tables. For `eta' > 1`,
/// `sqrt(mu)` (dense toward grazing). For `eta' < 1` the critical angle `mu_c` sits at
/// 1/2; on each side, half of the side's nodes follow [`rational_warp`] with half-width
/// `w = TIR_WIDTH alpha eta' + TIR_MIN_WIDTH` around `mu_c`, the other half `sqrt`
/// spacing toward grazing (below) or even spacing toward the normal (above).
#[inline(always)]
fn dielectric_coordinate<L: Lane>(mu: L, eta: L, alpha: L) -> L {
    let half = L::splat(0.5);
    let mu_c = (L::one() - eta * eta).safe_sqrt();
    let w = L::splat(TIR_WIDTH) * alpha * eta + L::splat(TIR_MIN_WIDTH);
    let (below, above) = ((mu_c - mu).max(L::zero()), (mu - mu_c).max(L::zero()));
    let above_len = L::one() - mu_c;
    let q_below = half * rational_warp(below, mu_c, w)
        + half * (L::one() - (L::one() - below.safe_div(mu_c)).safe_sqrt());
    let q_above = half * rational_warp(above, above_len, w) + half * above.safe_div(above_len);
    let inside = L::select(mu.lt(mu_c), half - half * q_below, half + half * q_above);
    L::select(eta.lt(L::one()), inside, mu.max(L::zero()).sqrt())
}

/// Alpha of a table row or lane at roughness coordinate `r`.
#[inline(always)]
fn row_alpha<L: Lane>(r: L) -> L {
    (r * r).max(L::splat(MIN_ALPHA))
}

/// The dielectric tables (see the module documentation).
pub struct DielectricTable;

impl DielectricTable {
    /// Reflected and transmitted albedo (importance transport) of `dist` at `wo`, taken
    /// on the side of `wo` (`wo.z` may be negative), for the relative IOR `eta'` seen from
    /// that side.
    #[inline(always)]
    pub fn lookup<L: Lane>(wo: Vec3<L>, dist: &Distribution<L>, eta: L) -> (L, L) {
        let r = mean_roughness(dist);
        let t = (eta - L::one()).abs() / (eta + L::one());
        let side = L::select(eta.lt(L::one()), L::one(), L::zero());
        let mu = wo.z.abs();
        let x = dielectric_coordinate(mu, eta, row_alpha(r));
        let (x0, fx) = grid(x, DX);
        let (y0, fy) = grid(r, DR);
        let (z0, fz) = grid(t * L::splat(1.0 / T_MAX), DT);
        let [ri, ti] = interpolate(
            Table::new(Layout::Dielectric, dist.kind),
            &corners::<L, 3, 8>(
                side * L::splat((DT * DR * DX) as f32),
                [(x0, fx, 1), (y0, fy, DX), (z0, fz, DR * DX)],
            ),
        );
        let anisotropic = anisotropic(dist);
        if !anisotropic.any() {
            return (ri, ti);
        }
        let (phi, aspect) = anisotropic_coordinates(wo, dist);
        let (s0, fs) = grid(aspect, NS);
        let (p0, fp) = grid(phi, NP);
        let (x0, fx) = grid(x, DX_ANISO);
        let row = DR * DX_ANISO;
        let [ra, ta] = interpolate(
            Table::new(Layout::DielectricAnisotropic, dist.kind),
            &corners::<L, 5, 32>(
                side * L::splat((DT * NP * NS * row) as f32),
                [
                    (x0, fx, 1),
                    (y0, fy, DX_ANISO),
                    (s0, fs, row),
                    (p0, fp, NS * row),
                    (z0, fz, NP * NS * row),
                ],
            ),
        );
        (
            L::select(anisotropic, ra, ri),
            L::select(anisotropic, ta, ti),
        )
    }
}
