//! Chi-square goodness of fit of a lobe's `sample` against its `pdf` (after pbrt-v4's
//! `bsdfs_test.cpp` and Mitsuba 3's `chi2.py`): samples are binned on an equal-area
//! `(cos theta, phi)` grid over the whole sphere, expected counts come from integrating
//! the pdf over each cell (adaptive midpoint rule), cells expecting fewer than 5 are
//! pooled, and Pearson's statistic gives a p-value. A narrow lobe falls into one or two
//! cells of that grid, so each lobe is also binned in a [`Window`] centred on it and
//! scaled to its width, where it spans many cells.

use crate::lobes::{LobeType, Transport};
use crate::math::Vec3;
use std::f64::consts::PI;

/// Pool cells whose expected count is below this.
const MIN_EXPECTED: f64 = 5.0;

/// A partition of (part of) the sphere into cells, each parametrized over `[0, 1]^2`.
pub trait Cells {
    /// Number of cells.
    fn count(&self) -> usize;
    /// The cell holding unit vector `w`, when the partition covers it.
    fn locate(&self, w: Vec3<f32>) -> Option<usize>;
    /// The direction at fractions `(a, b)` of cell `index`, and the solid angle per
    /// unit area of `(a, b)` there.
    fn point(&self, index: usize, a: f64, b: f64) -> (Vec3<f32>, f64);
}

/// An equal-area grid: `n_theta` bands of `cos theta` in [-1, 1] times `n_phi` bins of phi.
#[derive(Clone, Copy, Debug)]
pub struct Grid {
    pub n_theta: usize,
    pub n_phi: usize,
}

impl Grid {
    pub fn cells(&self) -> usize {
        self.n_theta * self.n_phi
    }

    /// The cell holding unit vector `w`.
    pub fn cell(&self, w: Vec3<f32>) -> usize {
        let z = f64::from(w.z).clamp(-1.0, 1.0);
        let t = (((z + 1.0) / 2.0) * self.n_theta as f64) as usize;
        let mut phi = f64::from(w.y).atan2(f64::from(w.x));
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let p = ((phi / (2.0 * PI)) * self.n_phi as f64) as usize;
        t.min(self.n_theta - 1) * self.n_phi + p.min(self.n_phi - 1)
    }

    /// Solid angle of one cell.
    pub fn cell_area(&self) -> f64 {
        4.0 * PI / self.cells() as f64
    }
}

impl Cells for Grid {
    fn count(&self) -> usize {
        self.cells()
    }

    fn locate(&self, w: Vec3<f32>) -> Option<usize> {
        Some(self.cell(w))
    }

    fn point(&self, index: usize, a: f64, b: f64) -> (Vec3<f32>, f64) {
        let (t, p) = (index / self.n_phi, index % self.n_phi);
        let z = -1.0 + 2.0 * (t as f64 + a) / self.n_theta as f64;
        let phi = 2.0 * PI * (p as f64 + b) / self.n_phi as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
        (w, self.cell_area())
    }
}

/// Widest [`Window`]: its half-width in the tangent plane, `tan 75 degrees`.
pub const WINDOW_MAX_HALF_WIDTH: f64 = 3.732;

/// A square of `n x n` cells in the gnomonic (tangent-plane) projection about
/// `center`, `(u, v) = (w.t1, w.t2) / w.center` in `[-half, half]^2`, with `t1` in the
/// plane of `center` and the normal. Centred on a lobe and scaled to its width, it
/// resolves a lobe that falls into one cell of the sphere's [`Grid`]. Cells are
/// uniform in `(u, v)`, where the solid angle is `(1 + u^2 + v^2)^(-3/2) du dv`.
#[derive(Clone, Copy, Debug)]
pub struct Window {
    pub center: [f64; 3],
    t1: [f64; 3],
    t2: [f64; 3],
    /// Half the side of the square, in tangent-plane units.
    pub half: f64,
    pub n: usize,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = dot(v, v).sqrt();
    v.map(|c| c / l)
}

fn to64(w: Vec3<f32>) -> [f64; 3] {
    [w.x, w.y, w.z].map(f64::from)
}

impl Window {
    /// The window about the mean of `dirs` that holds 99% of them (a tenth wider),
    /// at most [`WINDOW_MAX_HALF_WIDTH`]; `None` without directions.
    pub fn around(dirs: &[Vec3<f32>], n: usize) -> Option<Window> {
        let mut sum = [0.0; 3];
        for d in dirs {
            let d = to64(*d);
            (0..3).for_each(|c| sum[c] += d[c]);
        }
        if dirs.is_empty() || dot(sum, sum) == 0.0 {
            return None;
        }
        let center = unit(sum);
        // t1: the normal's part across the center (any axis when they are parallel).
        let axis = if center[2].abs() < 0.999 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let k = dot(axis, center);
        let t1 = unit([0, 1, 2].map(|c| axis[c] - k * center[c]));
        let t2 = [
            center[1] * t1[2] - center[2] * t1[1],
            center[2] * t1[0] - center[0] * t1[2],
            center[0] * t1[1] - center[1] * t1[0],
        ];
        let mut window = Window {
            center,
            t1,
            t2,
            half: WINDOW_MAX_HALF_WIDTH,
            n,
        };
        let mut extent: Vec<f64> = dirs
            .iter()
            .map(|&d| {
                window
                    .tangent(d)
                    .map_or(f64::INFINITY, |(u, v)| u.abs().max(v.abs()))
            })
            .collect();
        extent.sort_by(f64::total_cmp);
        let q = extent[((extent.len() as f64 * 0.99) as usize).min(extent.len() - 1)];
        window.half = (1.1 * q).clamp(1e-6, WINDOW_MAX_HALF_WIDTH);
        Some(window)
    }

    /// Tangent-plane coordinates of `w` (`None` at or behind the horizon of `center`).
    fn tangent(&self, w: Vec3<f32>) -> Option<(f64, f64)> {
        let w = to64(w);
        let d = dot(w, self.center);
        (d > 1e-3).then(|| (dot(w, self.t1) / d, dot(w, self.t2) / d))
    }

    /// Coordinates of `w` scaled so that the window is `[-1, 1]^2` (`None` at or
    /// behind the horizon of `center`).
    pub fn coords(&self, w: Vec3<f32>) -> Option<(f64, f64)> {
        let (u, v) = self.tangent(w)?;
        Some((u / self.half, v / self.half))
    }
}

impl Cells for Window {
    fn count(&self) -> usize {
        self.n * self.n
    }

    fn locate(&self, w: Vec3<f32>) -> Option<usize> {
        let (u, v) = self
            .coords(w)
            .filter(|(u, v)| u.abs() < 1.0 && v.abs() < 1.0)?;
        let index = |x: f64| (((x + 1.0) / 2.0 * self.n as f64) as usize).min(self.n - 1);
        Some(index(u) * self.n + index(v))
    }

    fn point(&self, index: usize, a: f64, b: f64) -> (Vec3<f32>, f64) {
        let side = 2.0 * self.half / self.n as f64;
        let u = -self.half + side * ((index / self.n) as f64 + a);
        let v = -self.half + side * ((index % self.n) as f64 + b);
        let w = unit([0, 1, 2].map(|c| self.center[c] + u * self.t1[c] + v * self.t2[c]));
        let r2 = 1.0 + u * u + v * v;
        (
            Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32),
            side * side / (r2 * r2.sqrt()),
        )
    }
}

/// Integrals over every cell of `eval(wo, .)` in transport `mode`: `[r, g, b, pdf]`
/// (see [`integrate`]; `samples` sets the absolute floor).
pub fn integrate_cells(
    lobe: &dyn LobeType,
    params: &[f32],
    wo: Vec3<f32>,
    mode: Transport,
    grid: Grid,
    samples: usize,
    suspicious: impl Fn(usize, usize, &[f64; 4]) -> bool,
) -> Vec<[f64; 4]> {
    let f = |w: Vec3<f32>| {
        let e = lobe.eval(params, wo, w, mode);
        [e.value.r, e.value.g, e.value.b, e.pdf].map(f64::from)
    };
    integrate(&grid, f, 1e-2 / samples as f64, suspicious)
}

/// Integrals of `f` over every cell of `cells`.
///
/// Each cell starts as 8 x 8 blocks; a block is split in four while its one-point and
/// four-point midpoint estimates differ by more than 2e-4 relative and `floor` (a
/// hundredth of a count of a chi-square test), down to 12 levels (1/32768 of a cell
/// side). A peak narrower than a block can hide between the points, so cells that
/// `suspicious(cell, blocks, integral)` flags (where the samples disagree with the
/// integral, say) are integrated again from 32 x 32 and then 256 x 256 blocks. That only makes the quadrature more
/// accurate: it never changes what is integrated.
pub fn integrate<C: Cells>(
    cells: &C,
    f: impl Fn(Vec3<f32>) -> [f64; 4],
    floor: f64,
    suspicious: impl Fn(usize, usize, &[f64; 4]) -> bool,
) -> Vec<[f64; 4]> {
    let tolerance = |v: f64| (2e-4 * v).max(floor);
    let g = |index: usize, a: f64, b: f64| {
        let (w, density) = cells.point(index, a, b);
        f(w).map(|v| v * density)
    };
    let cell = |index: usize, blocks: usize| {
        let mut sum = [0.0; 4];
        let h = 1.0 / blocks as f64;
        for i in 0..blocks {
            for j in 0..blocks {
                let (a, b) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
                let block = refine(&g, &tolerance, index, a, b, h, g(index, a, b), 0);
                for c in 0..4 {
                    sum[c] += block[c];
                }
            }
        }
        sum
    };
    (0..cells.count())
        .map(|index| {
            let mut out = cell(index, 8);
            for (done, blocks) in [(8, 32), (32, 256)] {
                if !suspicious(index, done, &out) {
                    break;
                }
                out = cell(index, blocks);
            }
            out
        })
        .collect()
}

/// Integral of the square of side `h` centred at `(a, b)` of cell `index`, where
/// `center` is the integrand there.
#[allow(clippy::too_many_arguments)]
fn refine(
    f: &impl Fn(usize, f64, f64) -> [f64; 4],
    tolerance: &impl Fn(f64) -> f64,
    index: usize,
    a: f64,
    b: f64,
    h: f64,
    center: [f64; 4],
    depth: u32,
) -> [f64; 4] {
    let q = h / 4.0;
    let subs = [(-q, -q), (q, -q), (-q, q), (q, q)]
        .map(|(da, db)| (a + da, b + db, f(index, a + da, b + db)));
    let area = h * h;
    let mut fine = [0.0; 4];
    for (_, _, v) in &subs {
        for c in 0..4 {
            fine[c] += v[c] * area / 4.0;
        }
    }
    let converged = (0..4).all(|c| (fine[c] - center[c] * area).abs() <= tolerance(fine[c].abs()));
    if converged || depth >= 12 {
        return fine;
    }
    let mut sum = [0.0; 4];
    for (sa, sb, v) in subs {
        let r = refine(f, tolerance, index, sa, sb, h / 2.0, v, depth + 1);
        for c in 0..4 {
            sum[c] += r[c];
        }
    }
    sum
}

/// Result of one chi-square test.
#[derive(Clone, Debug)]
pub struct Chi2 {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// A cell with samples but zero expected count (an immediate failure).
    pub impossible_cell: bool,
}

/// Pearson's test of `observed` counts against `expected` counts (pooling small cells).
pub fn pearson(observed: &[u64], expected: &[f64]) -> Chi2 {
    let mut cells: Vec<(f64, f64)> = observed
        .iter()
        .zip(expected)
        .map(|(&o, &e)| (o as f64, e))
        .collect();
    let impossible_cell = cells.iter().any(|&(o, e)| o > 0.0 && e <= 0.0);
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut pooled_o, mut pooled_e) = (0.0, 0.0);
    let mut statistic = 0.0;
    let mut bins = 0;
    for (o, e) in cells {
        if e < MIN_EXPECTED {
            pooled_o += o;
            pooled_e += e;
        } else {
            statistic += (o - e) * (o - e) / e;
            bins += 1;
        }
    }
    if pooled_e > 0.0 {
        statistic += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        bins += 1;
    }
    let dof = bins.max(2) - 1;
    Chi2 {
        statistic,
        dof,
        p_value: if impossible_cell {
            0.0
        } else {
            gamma_q(dof as f64 / 2.0, statistic / 2.0)
        },
        impossible_cell,
    }
}

/// Two-sided p-value of a standard normal deviate `z`: `P(|Z| >= z) = Q(1/2, z^2 / 2)`.
pub fn normal_p_value(z: f64) -> f64 {
    gamma_q(0.5, 0.5 * z * z)
}

/// Regularized upper incomplete gamma function `Q(a, x)` (Numerical Recipes `gammq`:
/// series below `a + 1`, Lentz's continued fraction above).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_prefix = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        (1.0 - sum * ln_prefix.exp()).max(0.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (ln_prefix.exp() * h).clamp(0.0, 1.0)
    }
}

/// `ln Gamma(x)` for `x > 0` (Lanczos, g = 7, n = 9; ~1e-15 relative).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut sum = G[0];
    for (i, g) in G.iter().enumerate().skip(1) {
        sum += g / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_q_matches_known_chi_square_tails() {
        // Survival function of chi-square: dof 1 at 3.841459 is 0.05; dof 10 at
        // 23.20925 is 0.01; dof 100 at 124.3421 is 0.05 (standard tables).
        for (dof, x, p) in [
            (1.0, 3.841_459, 0.05),
            (10.0, 23.209_25, 0.01),
            (100.0, 124.342_1, 0.05),
        ] {
            let q = gamma_q(dof / 2.0, x / 2.0);
            assert!((q - p).abs() < 1e-5, "dof {dof}: {q} vs {p}");
        }
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
        // Two-sided normal tails: 1.959964 -> 0.05, 3.890592 -> 1e-4.
        assert!((normal_p_value(1.959_964) - 0.05).abs() < 1e-6);
        assert!((normal_p_value(3.890_592) - 1e-4).abs() < 1e-8);
    }
}
