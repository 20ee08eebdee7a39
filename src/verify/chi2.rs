//! Chi-square goodness of fit of a lobe's `sample` against its `pdf` (after pbrt-v4's
//! `bsdfs_test.cpp` and Mitsuba 3's `chi2.py`): samples are binned on an equal-area
//! `(cos theta, phi)` grid over the whole sphere, expected counts come from integrating
//! the pdf over each cell (adaptive midpoint rule), cells expecting fewer than 5 are
//! pooled, and Pearson's statistic gives a p-value.

use crate::lobes::{LobeType, Transport};
use crate::math::Vec3;
use std::f64::consts::PI;

/// Pool cells whose expected count is below this.
const MIN_EXPECTED: f64 = 5.0;

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

    /// The direction at cell-relative coordinates: band `t`, bin `p`, fractions `(a, b)`.
    fn direction(&self, t: usize, p: usize, a: f64, b: f64) -> Vec3<f32> {
        let z = -1.0 + 2.0 * (t as f64 + a) / self.n_theta as f64;
        let phi = 2.0 * PI * (p as f64 + b) / self.n_phi as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
    }

    /// Solid angle of one cell.
    pub fn cell_area(&self) -> f64 {
        4.0 * PI / self.cells() as f64
    }
}

/// Integrals over every cell of `eval(wo, .)` in transport `mode`: `[r, g, b, pdf]`.
///
/// Each cell starts as 8 x 8 blocks; a block is split in four while its one-point and
/// four-point midpoint estimates differ by more than 2e-4 relative and a hundredth of
/// a count of a chi-square test with `samples` draws, down to
/// 12 levels (1/32768 of a cell side). A peak narrower than a block can hide between
/// the points, so cells that `suspicious` flags (where the samples disagree with the
/// integral) are integrated again from 32 x 32 and then 256 x 256 blocks. That only
/// makes the quadrature more accurate: it never changes what is integrated.
pub fn integrate_cells(
    lobe: &dyn LobeType,
    params: &[f32],
    wo: Vec3<f32>,
    mode: Transport,
    grid: Grid,
    samples: usize,
    suspicious: impl Fn(usize, &[f64; 4]) -> bool,
) -> Vec<[f64; 4]> {
    let area = grid.cell_area();
    // Relative accuracy for the integrals the consistency and energy checks sum; the
    // absolute floor (a hundredth of a count) ends refinement where a block is empty.
    let floor = 1e-2 / (area * samples as f64);
    let tolerance = |v: f64| (2e-4 * v).max(floor);
    let f = |t: usize, p: usize, a: f64, b: f64| {
        let e = lobe.eval(params, wo, grid.direction(t, p, a, b), mode);
        [e.value.r, e.value.g, e.value.b, e.pdf].map(f64::from)
    };
    let cell = |t: usize, p: usize, blocks: usize| {
        let mut sum = [0.0; 4];
        let h = 1.0 / blocks as f64;
        for i in 0..blocks {
            for j in 0..blocks {
                let (a, b) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
                let block = refine(&f, &tolerance, t, p, a, b, h, f(t, p, a, b), 0);
                for c in 0..4 {
                    sum[c] += block[c];
                }
            }
        }
        sum.map(|s| s * area)
    };
    let mut out = vec![[0.0; 4]; grid.cells()];
    for t in 0..grid.n_theta {
        for p in 0..grid.n_phi {
            let index = t * grid.n_phi + p;
            out[index] = cell(t, p, 8);
            for blocks in [32, 256] {
                if !suspicious(index, &out[index]) {
                    break;
                }
                out[index] = cell(t, p, blocks);
            }
        }
    }
    out
}

/// Integral (as a fraction of the cell) of the square of side `h` centred at `(a, b)`,
/// where `center` is the integrand there.
#[allow(clippy::too_many_arguments)]
fn refine(
    f: &impl Fn(usize, usize, f64, f64) -> [f64; 4],
    tolerance: &impl Fn(f64) -> f64,
    t: usize,
    p: usize,
    a: f64,
    b: f64,
    h: f64,
    center: [f64; 4],
    depth: u32,
) -> [f64; 4] {
    let q = h / 4.0;
    let subs = [(-q, -q), (q, -q), (-q, q), (q, q)]
        .map(|(da, db)| (a + da, b + db, f(t, p, a + da, b + db)));
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
        let r = refine(f, tolerance, t, p, sa, sb, h / 2.0, v, depth + 1);
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
    }
}
