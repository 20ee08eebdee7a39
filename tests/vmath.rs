//! Accuracy of the math functions the kernels use, against f64, on every ISA this CPU
//! runs (`map_math`) and for the generic `glint::math::vmath` functions instantiated on
//! plain `f32` (unfused `mul_add`): each function is swept densely over its domain
//! (uniform, pseudo-random and log-spaced points plus edges) and its maximum error is
//! checked against the bound in [`TABLE`]. The bounds of the vmath rows are the ones
//! stated in `src/math/vmath.rs`. Special values are checked separately.
//!
//! `cargo test --release --test vmath -- --nocapture` prints the measured tables.

#![allow(clippy::excessive_precision)] // constants to f64 precision

mod reference;

use glint::math::vmath;
use glint::simd::{Isa, Kernels, MathFn, map_math};
use std::f64::consts::PI;
use std::sync::OnceLock;

// ---------------------------------------------------------------------------------
// The table

#[derive(Clone, Copy, Debug, PartialEq)]
enum Metric {
    /// `|got - want|`.
    Abs,
    /// `|got - want| / |want|` (0 where both are 0).
    Rel,
}

/// One function on one domain: how its error is measured and the bounds.
struct Row {
    f: MathFn,
    domain: &'static str,
    metric: Metric,
    /// Bound on `Isa::Scalar` (the `f32` lane: std's libm for the elementary functions).
    scalar: f64,
    /// Bound on the SIMD ISAs, and for `vmath::*::<f32>` (the vmath rows: the bound
    /// stated in vmath's doc comments).
    simd: f64,
    /// The arguments: `(x, y)` in `MathFn` order (Atan2: ordinate first; Pow: base).
    inputs: fn() -> Vec<(f32, f32)>,
}

const TABLE: &[Row] = &[
    Row {
        f: MathFn::Exp,
        domain: "[-87.33, 88.72] (normal results)",
        metric: Metric::Rel,
        scalar: 1e-7,
        simd: 1.5e-7,
        inputs: exp_normal,
    },
    Row {
        f: MathFn::Exp,
        domain: "[-103.97, -87.34] (subnormal results)",
        metric: Metric::Abs,
        scalar: 1.5e-45,
        simd: 1.5e-45,
        inputs: exp_subnormal,
    },
    Row {
        f: MathFn::Ln,
        domain: "(0, max], subnormals included",
        metric: Metric::Rel,
        scalar: 1e-7,
        simd: 1.5e-7,
        inputs: ln,
    },
    Row {
        f: MathFn::Ln1p,
        domain: "(-1, max]",
        metric: Metric::Rel,
        scalar: 1.5e-7,
        simd: 2e-7,
        inputs: ln_1p,
    },
    Row {
        f: MathFn::Sin,
        domain: "[-1e4, 1e4]",
        metric: Metric::Abs,
        scalar: 1e-7,
        simd: 1.5e-7,
        inputs: sin_cos,
    },
    Row {
        f: MathFn::Cos,
        domain: "[-1e4, 1e4]",
        metric: Metric::Abs,
        scalar: 1e-7,
        simd: 1.5e-7,
        inputs: sin_cos,
    },
    Row {
        f: MathFn::Acos,
        domain: "[-1, 1]",
        metric: Metric::Abs,
        scalar: 3e-7,
        simd: 3e-7,
        inputs: acos,
    },
    Row {
        f: MathFn::Atan2,
        domain: "plane, |x|,|y| <= 1e30, x != -0",
        metric: Metric::Abs,
        scalar: 3e-7,
        simd: 2.5e-7,
        inputs: atan2,
    },
    Row {
        f: MathFn::Pow,
        domain: "x in (0, max], |e ln x| <= 80",
        metric: Metric::Rel,
        scalar: 1e-7,
        simd: 2.5e-7,
        inputs: pow,
    },
    Row {
        f: MathFn::Sqrt,
        domain: "[0, max], subnormals included",
        metric: Metric::Rel,
        scalar: 6e-8,
        simd: 6e-8,
        inputs: sqrt,
    },
    Row {
        f: MathFn::Rsqrt,
        domain: "[min normal, max]",
        metric: Metric::Rel,
        scalar: 1.2e-7,
        simd: 2.5e-7,
        inputs: rsqrt,
    },
    Row {
        f: MathFn::Erf,
        domain: "[-10, 10]",
        metric: Metric::Abs,
        scalar: 6e-7,
        simd: 6e-7,
        inputs: erf,
    },
    Row {
        f: MathFn::Erfc,
        domain: "[0, 9] (normal results)",
        metric: Metric::Rel,
        scalar: 1e-5,
        simd: 1e-5,
        inputs: erfc,
    },
    Row {
        f: MathFn::ErfInv,
        domain: "1e-37 <= |x| <= 1 - 2^-23",
        metric: Metric::Rel,
        scalar: 4e-7,
        simd: 4e-7,
        inputs: erf_inv,
    },
    Row {
        f: MathFn::ErfInv,
        domain: "|x| = 1 - 2^-24 (clamped to 1 - 2^-23)",
        metric: Metric::Rel,
        scalar: 2.5e-2,
        simd: 2.5e-2,
        inputs: erf_inv_last,
    },
    Row {
        f: MathFn::AzimuthSin,
        domain: "[-2, 2] (random numbers in [0, 1])",
        metric: Metric::Abs,
        scalar: 2.5e-7,
        simd: 2.5e-7,
        inputs: azimuth,
    },
    Row {
        f: MathFn::AzimuthCos,
        domain: "[-2, 2] (random numbers in [0, 1])",
        metric: Metric::Abs,
        scalar: 2.5e-7,
        simd: 2.5e-7,
        inputs: azimuth,
    },
];

/// The f64 reference of `f` at the exact f64 values of its f32 arguments.
fn reference(f: MathFn, x: f64, y: f64) -> f64 {
    match f {
        MathFn::Exp => x.exp(),
        MathFn::Ln => x.ln(),
        MathFn::Ln1p => x.ln_1p(),
        MathFn::Sin => x.sin(),
        MathFn::Cos => x.cos(),
        MathFn::Acos => x.acos(),
        MathFn::Atan2 => x.atan2(y),
        MathFn::Pow => x.powf(y),
        MathFn::Sqrt => x.sqrt(),
        MathFn::Rsqrt => 1.0 / x.sqrt(),
        MathFn::Erf => erf_f64(x),
        MathFn::Erfc => reference::erfc(x),
        MathFn::ErfInv => erf_inv_f64(x),
        MathFn::AzimuthSin => (2.0 * PI * x).sin(),
        MathFn::AzimuthCos => (2.0 * PI * x).cos(),
    }
}

/// The vmath function behind `f`, on `f32`; `None` for functions vmath does not define.
fn vmath_f32(f: MathFn) -> Option<fn(f32, f32) -> f32> {
    Some(match f {
        MathFn::Exp => |x, _| vmath::exp(x),
        MathFn::Ln => |x, _| vmath::ln(x),
        MathFn::Ln1p => |x, _| vmath::ln_1p(x),
        MathFn::Sin => |x, _| vmath::sin_cos(x).0,
        MathFn::Cos => |x, _| vmath::sin_cos(x).1,
        MathFn::Acos => |x, _| vmath::acos(x),
        MathFn::Atan2 => |y, x| vmath::atan2(y, x),
        MathFn::Pow => |x, e| vmath::pow(x, e),
        MathFn::AzimuthSin => |x, _| glint::math::azimuth(x).0,
        MathFn::AzimuthCos => |x, _| glint::math::azimuth(x).1,
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------
// f64 references not in std

/// `erf` to ~1e-16 relative: its Maclaurin series below 0.5, else `1 - erfc`.
fn erf_f64(x: f64) -> f64 {
    let a = x.abs();
    if a < 0.5 {
        // erf(x) = 2/sqrt(pi) sum_n (-1)^n x^(2n+1) / (n! (2n+1))
        let (mut term, mut sum, mut n) = (a, a, 0.0);
        while term.abs() > 1e-18 * sum {
            n += 1.0;
            term *= -a * a / n;
            sum += term / (2.0 * n + 1.0);
        }
        (2.0 / PI.sqrt() * sum).copysign(x)
    } else {
        (1.0 - reference::erfc(a)).copysign(x)
    }
}

/// `erf_inv` by Newton's method: on `erf(z) = |x|` below 0.5, on
/// `ln erfc(z) = ln(1 - |x|)` above (no cancellation near 1).
fn erf_inv_f64(x: f64) -> f64 {
    let a = x.abs();
    let mut z = if a < 0.5 {
        a * PI.sqrt() / 2.0
    } else {
        // erfc(z) ~ exp(-z^2) / (z sqrt(pi)), solved by one fixed-point step.
        let z0 = (-(1.0 - a).ln()).sqrt();
        (-((1.0 - a) * z0 * PI.sqrt()).ln()).max(0.25).sqrt()
    };
    for _ in 0..100 {
        let dz = if a < 0.5 {
            (erf_f64(z) - a) / (2.0 / PI.sqrt() * (-z * z).exp())
        } else {
            let e = reference::erfc(z);
            // d/dz ln erfc(z) = -2/sqrt(pi) exp(-z^2) / erfc(z)
            -(e.ln() - (1.0 - a).ln()) * e / (2.0 / PI.sqrt() * (-z * z).exp())
        };
        z -= dz;
        if dz.abs() <= 1e-15 * z.abs() {
            break;
        }
    }
    z.copysign(x)
}

#[test]
fn erf_references_agree() {
    // erf(erf_inv(x)) = x, near +-1 through erfc (1 - |x| to relative precision).
    for x in lin(-1.0, 1.0, 2001).chain(around(&[1.0 - f32::EPSILON, 1e-30], 16)) {
        let x = f64::from(x);
        if x.abs() >= 1.0 {
            continue;
        }
        let z = erf_inv_f64(x);
        assert!(
            (erf_f64(z) - x).abs() <= 1e-15 * x.abs(),
            "erf(erf_inv({x}))"
        );
        if x.abs() > 0.5 {
            let gap = 1.0 - x.abs();
            assert!((reference::erfc(z.abs()) - gap).abs() <= 1e-12 * gap, "{x}");
        }
    }
    // The series and the erfc branch meet at 0.5.
    let (below, above) = (erf_f64(0.5 - 1e-12), erf_f64(0.5));
    assert!((above - below).abs() < 1e-12);
}

// ---------------------------------------------------------------------------------
// Sweeps

/// Points per sweep component: 2^20 (2^15 in debug builds), times the integer in the
/// environment variable `GLINT_VMATH_DENSITY` if set (vmath's doc comments quote the
/// maxima measured with `GLINT_VMATH_DENSITY=16`).
fn points() -> usize {
    let base = if cfg!(debug_assertions) {
        1 << 15
    } else {
        1 << 20
    };
    let density = std::env::var("GLINT_VMATH_DENSITY").ok();
    base * density.and_then(|d| d.parse().ok()).unwrap_or(1)
}

/// `n` points evenly inside `[lo, hi]` (cell midpoints).
fn lin(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
    (0..n).map(move |i| (lo + (hi - lo) * (i as f64 + 0.5) / n as f64) as f32)
}

/// `n` points evenly spaced in `ln` over `[lo, hi]`, both positive.
fn geom(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
    let (a, b) = (lo.ln(), hi.ln());
    (0..n).map(move |i| (a + (b - a) * i as f64 / (n - 1) as f64).exp() as f32)
}

/// Deterministic uniform random numbers in `[0, 1)` (xorshift64*).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f32 {
        (lo + (hi - lo) * self.uniform()) as f32
    }
}

/// `n` random points in `[lo, hi]`.
fn rand(lo: f64, hi: f64, n: usize, seed: u64) -> impl Iterator<Item = f32> {
    let mut rng = Rng(seed);
    (0..n).map(move |_| rng.range(lo, hi))
}

/// The `k` f32 values on each side of each of `values` (and the values).
fn around(values: &[f32], k: i32) -> Vec<f32> {
    let mut out = Vec::new();
    for &v in values {
        for d in -k..=k {
            // Step through the ordered bit pattern, crossing zero correctly.
            let i = v.to_bits() as i32;
            let ordered = if i < 0 { i32::MIN - i } else { i } + d;
            let bits = if ordered < 0 {
                i32::MIN - ordered
            } else {
                ordered
            };
            out.push(f32::from_bits(bits as u32));
        }
    }
    out
}

fn unary(xs: impl IntoIterator<Item = f32>) -> Vec<(f32, f32)> {
    xs.into_iter().map(|x| (x, 0.0)).collect()
}

fn exp_normal() -> Vec<(f32, f32)> {
    let lo = f64::from(f32::MIN_POSITIVE).ln();
    let hi = f64::from(f32::MAX).ln();
    let xs = lin(-87.4, 88.8, points())
        .chain(rand(-87.4, 88.8, points() / 2, 1))
        .chain(lin(-1.0, 1.0, points() / 4))
        .chain(around(&[lo as f32, hi as f32, 0.0], 4096));
    unary(xs.filter(|&x| (lo..=hi).contains(&f64::from(x))))
}

fn exp_subnormal() -> Vec<(f32, f32)> {
    let lo = (0.5 * f64::from(f32::from_bits(1))).ln(); // rounds to 0 below
    let hi = f64::from(f32::MIN_POSITIVE).ln();
    let xs = lin(-104.0, -87.3, points() / 2).chain(around(&[lo as f32, hi as f32], 4096));
    unary(xs.filter(|&x| (lo..hi).contains(&f64::from(x))))
}

fn ln() -> Vec<(f32, f32)> {
    let xs = geom(f64::from(f32::from_bits(1)), f64::from(f32::MAX), points())
        .chain(lin(0.5, 2.0, points() / 2))
        .chain(rand(0.0, 10.0, points() / 4, 2))
        .chain(around(
            &[1.0, f32::MIN_POSITIVE, f32::MAX, 2.0f32.sqrt()],
            4096,
        ));
    unary(xs.filter(|&x| x > 0.0 && x.is_finite()))
}

fn ln_1p() -> Vec<(f32, f32)> {
    let near_minus_one = geom(6e-8, 0.5, points() / 4).map(|d| -1.0 + d);
    let xs = lin(-1.0, 1.0, points())
        .chain(geom(1e-30, f64::from(f32::MAX), points() / 2))
        .chain(geom(1e-30, 1.0, points() / 4).map(|x| -x))
        .chain(near_minus_one)
        .chain(around(&[0.0, 1.0, f32::EPSILON, -0.5, f32::MAX], 4096));
    unary(xs.filter(|&x| x > -1.0 && x.is_finite()))
}

fn sin_cos() -> Vec<(f32, f32)> {
    let quarter_turns: Vec<f32> = (-6366..=6366)
        .step_by(7)
        .map(|k| (f64::from(k) * PI / 2.0) as f32)
        .collect();
    let xs = lin(-2.0 * PI, 2.0 * PI, points())
        .chain(lin(-1e4, 1e4, points()))
        .chain(rand(-1e4, 1e4, points() / 2, 3))
        .chain(geom(1e-30, 1e4, points() / 4))
        .chain(geom(1e-30, 1e4, points() / 4).map(|x| -x))
        .chain(around(&quarter_turns, 8));
    unary(xs.filter(|x| x.abs() <= 1e4))
}

fn azimuth() -> Vec<(f32, f32)> {
    let eighths: Vec<f32> = (-16..=16).map(|k| k as f32 / 8.0).collect();
    let xs = lin(0.0, 1.0, points())
        .chain(rand(-2.0, 2.0, points() / 2, 8))
        .chain(geom(1e-30, 1.0, points() / 4))
        .chain(geom(1e-30, 1.0, points() / 4).map(|x| -x))
        .chain(around(&eighths, 4096));
    unary(xs.filter(|x| x.abs() <= 2.0))
}

fn acos() -> Vec<(f32, f32)> {
    let xs = lin(-1.0, 1.0, points())
        .chain(rand(-1.0, 1.0, points() / 2, 4))
        .chain(around(&[-1.0, -0.5, 0.0, 0.5, 1.0], 1 << 16));
    unary(xs.filter(|x| x.abs() <= 1.0))
}

fn atan2() -> Vec<(f32, f32)> {
    let mut v = Vec::new();
    // Every direction at radii from subnormal to 1e30.
    let mut rng = Rng(5);
    for r in geom(1e-38, 1e30, points()) {
        let t = (rng.uniform() * 2.0 - 1.0) * PI;
        let r = f64::from(r);
        v.push(((r * t.sin()) as f32, (r * t.cos()) as f32));
    }
    // A lattice through the square [-4, 4]^2, both axes included.
    let k = if cfg!(debug_assertions) { 201 } else { 1001 };
    for i in 0..k {
        for j in 0..k {
            let c = |i: usize| (8.0 * i as f64 / (k - 1) as f64 - 4.0) as f32;
            v.push((c(i), c(j)));
        }
    }
    // Ratios around the reduction boundaries tan(pi/8), 1, tan(3pi/8).
    for t in [0.414_213_562_373_095, 1.0, 2.414_213_562_373_095] {
        for d in around(&[t], 4096) {
            for s in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                v.push((s.0 * d, s.1));
                v.push((s.0, s.1 * d));
            }
        }
    }
    for &a in &[0.0, 1e-45, 1e-30, 1.0, 1e30] {
        v.extend([
            (a, 1.0),
            (-a, 1.0),
            (a, -1.0),
            (-a, -1.0),
            (1.0, a),
            (-1.0, a),
        ]);
    }
    v.retain(|&(y, x)| !(x == 0.0 && x.is_sign_negative()) && y.is_finite() && x.is_finite());
    v
}

fn pow() -> Vec<(f32, f32)> {
    let mut v = Vec::new();
    let mut rng = Rng(6);
    // Any base, exponents up to |e ln x| = 80.
    for x in geom(f64::from(f32::from_bits(1)), f64::from(f32::MAX), points()) {
        let l = f64::from(x).ln().abs().max(1e-30);
        v.push((x, ((rng.uniform() * 2.0 - 1.0) * 80.0 / l) as f32));
    }
    // Bases next to 1 with exponents up to 1e9: the double-f32 logarithm at work.
    for x in around(&[1.0], 1 << 15) {
        let l = f64::from(x).ln().abs().max(1e-30);
        v.push((x, ((rng.uniform() * 2.0 - 1.0) * 80.0 / l) as f32));
    }
    // Moderate bases and exponents, and the usual ones.
    for _ in 0..points() / 2 {
        v.push((rng.range(0.0, 4.0), rng.range(-10.0, 10.0)));
    }
    for x in lin(0.0, 10.0, points() / 64) {
        for e in [-3.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 2.2, 3.0] {
            v.push((x, e));
        }
    }
    v.retain(|&(x, e)| {
        x > 0.0 && x.is_finite() && (f64::from(e) * f64::from(x).ln()).abs() <= 80.0
    });
    v
}

fn sqrt() -> Vec<(f32, f32)> {
    let xs = geom(f64::from(f32::from_bits(1)), f64::from(f32::MAX), points())
        .chain(lin(0.0, 4.0, points() / 2))
        .chain(around(&[0.0, 1.0, f32::MIN_POSITIVE, f32::MAX], 64));
    unary(xs.filter(|&x| x >= 0.0 && x.is_finite()))
}

fn rsqrt() -> Vec<(f32, f32)> {
    let xs = geom(f64::from(f32::MIN_POSITIVE), f64::from(f32::MAX), points())
        .chain(lin(0.01, 4.0, points() / 2))
        .chain(around(&[1.0, 2.0, 4.0, f32::MIN_POSITIVE, f32::MAX], 4096));
    unary(xs.filter(|&x| x >= f32::MIN_POSITIVE && x.is_finite()))
}

fn erf() -> Vec<(f32, f32)> {
    let xs = lin(-6.0, 6.0, points())
        .chain(rand(-10.0, 10.0, points() / 4, 7))
        .chain(geom(1e-30, 1.0, points() / 8))
        .chain(geom(1e-30, 1.0, points() / 8).map(|x| -x));
    unary(xs)
}

fn erfc() -> Vec<(f32, f32)> {
    let xs = lin(0.0, 9.0, points()).chain(geom(1e-30, 9.0, points() / 4));
    unary(xs.filter(|&x| (0.0..=9.0).contains(&x)))
}

fn erf_inv() -> Vec<(f32, f32)> {
    let n = points() / 2;
    let xs = lin(-1.0, 1.0, n)
        .chain(geom(1e-30, 1.0, n / 4))
        .chain(geom(1e-30, 1.0, n / 4).map(|x| -x))
        .chain(around(&[1.0, -1.0, 0.0], 4096));
    // Below 1e-37 the result (~0.89 x) is subnormal, its relative precision lost; the
    // f32 next to +-1 is clamped by erf_inv (the next row).
    let last = 1.0 - f32::EPSILON / 2.0;
    unary(xs.filter(|x| (1e-37..last).contains(&x.abs())))
}

fn erf_inv_last() -> Vec<(f32, f32)> {
    let last = 1.0 - f32::EPSILON / 2.0;
    unary([-last, last])
}

// ---------------------------------------------------------------------------------
// Measurement

/// A row's inputs and their f64 reference values.
struct Cases {
    x: Vec<f32>,
    y: Vec<f32>,
    want: Vec<f64>,
}

/// Every row's cases, built once (in parallel) for all the tests of this file.
fn cases() -> &'static [Cases] {
    static CASES: OnceLock<Vec<Cases>> = OnceLock::new();
    CASES.get_or_init(|| {
        std::thread::scope(|s| {
            let handles: Vec<_> = TABLE
                .iter()
                .map(|row| {
                    s.spawn(move || {
                        let (x, y): (Vec<f32>, Vec<f32>) = (row.inputs)().into_iter().unzip();
                        let want = x
                            .iter()
                            .zip(&y)
                            .map(|(&x, &y)| reference(row.f, f64::from(x), f64::from(y)))
                            .collect();
                        Cases { x, y, want }
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        })
    })
}

/// The largest error of one implementation over one row, and where.
struct Worst {
    err: f64,
    at: (f32, f32),
    got: f32,
    want: f64,
}

/// The error of `got`; never NaN (a NaN or infinite result where a finite one belongs
/// counts as an infinite error).
fn error(metric: Metric, got: f32, want: f64) -> f64 {
    let got = f64::from(got);
    if got == want {
        0.0
    } else if !(got - want).is_finite() {
        f64::INFINITY
    } else {
        match metric {
            Metric::Abs => (got - want).abs(),
            Metric::Rel => (got - want).abs() / want.abs(),
        }
    }
}

fn worst(metric: Metric, cases: &Cases, got: &[f32]) -> Worst {
    let mut w = Worst {
        err: 0.0,
        at: (0.0, 0.0),
        got: 0.0,
        want: 0.0,
    };
    for (i, (&g, &want)) in got.iter().zip(&cases.want).enumerate() {
        let err = error(metric, g, want);
        if err > w.err {
            w = Worst {
                err,
                at: (cases.x[i], cases.y[i]),
                got: g,
                want,
            };
        }
    }
    w
}

fn name(f: MathFn) -> String {
    format!("{f:?}")
}

/// Measure `eval` (returning false: not applicable) on every row against its bound
/// (`bound` picks the column), print the table and return the rows over their bound.
fn measure_table(
    label: &str,
    eval: impl Fn(MathFn, &[f32], &[f32], &mut [f32]) -> bool,
    bound: impl Fn(&Row) -> f64,
) -> Vec<String> {
    let mut report = format!(
        "\n{label}\n{:<7} {:<38} {:<4} {:>10} {:>9}  worst at (x, y) -> got / f64\n",
        "fn", "domain", "", "max error", "bound"
    );
    let mut failures = Vec::new();
    for (row, cases) in TABLE.iter().zip(cases()) {
        let mut got = vec![0.0; cases.x.len()];
        if !eval(row.f, &cases.x, &cases.y, &mut got) {
            continue;
        }
        let w = worst(row.metric, cases, &got);
        let bound = bound(row);
        let line = format!(
            "{:<7} {:<38} {:<4} {:>10.3e} {:>9.2e}  ({:e}, {:e}) -> {:e} / {:e} [{} points]",
            name(row.f),
            row.domain,
            format!("{:?}", row.metric).to_lowercase(),
            w.err,
            bound,
            w.at.0,
            w.at.1,
            w.got,
            w.want,
            cases.x.len(),
        );
        if w.err > bound {
            failures.push(format!("{label}: {line}"));
        }
        report.push_str(&line);
        report.push('\n');
    }
    println!("{report}");
    failures
}

fn assert_within(failures: Vec<String>) {
    assert!(
        failures.is_empty(),
        "over the bound:\n{}",
        failures.join("\n")
    );
}

#[test]
fn every_isa_meets_the_table() {
    let mut failures = Vec::new();
    for kernels in Kernels::available() {
        let isa = kernels.isa();
        failures.extend(measure_table(
            &format!("isa={}", isa.name()),
            |f, x, y, out| {
                map_math(kernels, f, x, y, out);
                true
            },
            |row| {
                if isa == Isa::Scalar {
                    row.scalar
                } else {
                    row.simd
                }
            },
        ));
    }
    assert_within(failures);
}

#[test]
fn vmath_on_f32_meets_the_table() {
    assert_within(measure_table(
        "vmath::<f32> (unfused mul_add)",
        |f, x, y, out| match vmath_f32(f) {
            Some(g) => {
                for ((o, &x), &y) in out.iter_mut().zip(x).zip(y) {
                    *o = g(x, y);
                }
                true
            }
            None => false,
        },
        |row| row.simd,
    ));
}

// ---------------------------------------------------------------------------------
// Special values

#[derive(Clone, Copy, Debug)]
enum Want {
    /// Equal (`==`: the sign of zero is not checked).
    Is(f32),
    Nan,
    /// Within this relative error of the value.
    Near(f64, f64),
    /// Within this relative error of the f64 reference.
    Ref(f64),
    /// In `[lo, hi]`.
    Within(f32, f32),
}

/// `(f, x, y, want, libm)`: `libm` false where std's libm (the scalar ISA) differs by
/// design (vmath clamps `acos`'s argument).
const SPECIAL: &[(MathFn, f32, f32, Want, bool)] = {
    use MathFn::*;
    use Want::*;
    const INF: f32 = f32::INFINITY;
    const NAN: f32 = f32::NAN;
    const PI: f64 = std::f64::consts::PI;
    &[
        (Exp, NAN, 0.0, Nan, true),
        (Exp, INF, 0.0, Is(INF), true),
        (Exp, -INF, 0.0, Is(0.0), true),
        (Exp, 0.0, 0.0, Is(1.0), true),
        (Exp, 1.0, 0.0, Ref(2e-7), true),
        (Exp, 88.72, 0.0, Ref(2e-7), true),
        (Exp, 88.73, 0.0, Is(INF), true),
        (Exp, 1000.0, 0.0, Is(INF), true),
        (Exp, -100.0, 0.0, Ref(0.02), true),
        (Exp, -103.98, 0.0, Is(0.0), true),
        (Exp, -200.0, 0.0, Is(0.0), true),
        (Ln, 0.0, 0.0, Is(-INF), true),
        (Ln, -0.0, 0.0, Is(-INF), true),
        (Ln, -1.0, 0.0, Nan, true),
        (Ln, -INF, 0.0, Nan, true),
        (Ln, INF, 0.0, Is(INF), true),
        (Ln, NAN, 0.0, Nan, true),
        (Ln, 1.0, 0.0, Is(0.0), true),
        (Ln, 1e-45, 0.0, Ref(2e-7), true),
        (Ln, f32::MAX, 0.0, Ref(2e-7), true),
        (Ln1p, -1.0, 0.0, Is(-INF), true),
        (Ln1p, -2.0, 0.0, Nan, true),
        (Ln1p, -INF, 0.0, Nan, true),
        (Ln1p, INF, 0.0, Is(INF), true),
        (Ln1p, NAN, 0.0, Nan, true),
        (Ln1p, 0.0, 0.0, Is(0.0), true),
        (Ln1p, 1e-10, 0.0, Ref(2e-7), true),
        (Ln1p, -1e-10, 0.0, Ref(2e-7), true),
        (Ln1p, 1e-30, 0.0, Ref(2e-7), true),
        (Ln1p, f32::MAX, 0.0, Ref(2e-7), true),
        (Sin, INF, 0.0, Nan, true),
        (Sin, -INF, 0.0, Nan, true),
        (Sin, NAN, 0.0, Nan, true),
        (Sin, 0.0, 0.0, Is(0.0), true),
        (Sin, 1e-30, 0.0, Ref(2e-7), true),
        (Cos, INF, 0.0, Nan, true),
        (Cos, -INF, 0.0, Nan, true),
        (Cos, NAN, 0.0, Nan, true),
        (Cos, 0.0, 0.0, Is(1.0), true),
        // Past the accurate range: finite and in [-1, 1].
        (Sin, 1e6, 0.0, Within(-1.0, 1.0), true),
        (Sin, 1e30, 0.0, Within(-1.0, 1.0), true),
        (Sin, -f32::MAX, 0.0, Within(-1.0, 1.0), true),
        (Cos, 1e6, 0.0, Within(-1.0, 1.0), true),
        (Cos, 1e30, 0.0, Within(-1.0, 1.0), true),
        (Cos, f32::MAX, 0.0, Within(-1.0, 1.0), true),
        (AzimuthSin, NAN, 0.0, Nan, true),
        (AzimuthSin, INF, 0.0, Nan, true),
        (AzimuthCos, -INF, 0.0, Nan, true),
        (AzimuthSin, 0.0, 0.0, Is(0.0), true),
        (AzimuthCos, 0.0, 0.0, Is(1.0), true),
        (AzimuthSin, 0.5, 0.0, Is(0.0), true),
        (AzimuthCos, 0.5, 0.0, Is(-1.0), true),
        (AzimuthCos, 1.0, 0.0, Is(1.0), true),
        (AzimuthSin, 0.25, 0.0, Near(1.0, 2.5e-7), true),
        (
            AzimuthCos,
            1.0 - f32::EPSILON / 2.0,
            0.0,
            Near(1.0, 1.5e-7),
            true,
        ),
        // Beyond the random numbers' range: finite and in [-1, 1].
        (AzimuthSin, 1e30, 0.0, Within(-1.0, 1.0), true),
        (AzimuthCos, -3.75e6, 0.0, Within(-1.0, 1.0), true),
        (Acos, 1.0, 0.0, Is(0.0), true),
        (Acos, -1.0, 0.0, Near(PI, 1e-7), true),
        (Acos, 0.0, 0.0, Near(PI / 2.0, 1e-7), true),
        (Acos, 1.000_000_1, 0.0, Is(0.0), false),
        (Acos, -1.000_000_1, 0.0, Near(PI, 1e-7), false),
        (Acos, 2.0, 0.0, Is(0.0), false),
        (Acos, NAN, 0.0, Nan, true),
        (Atan2, 0.0, 0.0, Is(0.0), true),
        (Atan2, 0.0, 1.0, Is(0.0), true),
        (Atan2, 0.0, -1.0, Near(PI, 1e-7), true),
        (Atan2, -0.0, -1.0, Near(-PI, 1e-7), true),
        (Atan2, 1.0, 0.0, Near(PI / 2.0, 1e-7), true),
        (Atan2, -1.0, 0.0, Near(-PI / 2.0, 1e-7), true),
        (Atan2, INF, INF, Near(PI / 4.0, 1e-7), true),
        (Atan2, INF, -INF, Near(3.0 * PI / 4.0, 1e-7), true),
        (Atan2, -INF, -INF, Near(-3.0 * PI / 4.0, 1e-7), true),
        (Atan2, 1.0, INF, Is(0.0), true),
        (Atan2, 1.0, -INF, Near(PI, 1e-7), true),
        (Atan2, -1.0, -INF, Near(-PI, 1e-7), true),
        (Atan2, INF, 1.0, Near(PI / 2.0, 1e-7), true),
        (Atan2, 1e-45, 1e-45, Near(PI / 4.0, 1e-7), true),
        (Atan2, 1e30, 1e-30, Near(PI / 2.0, 1e-7), true),
        (Atan2, NAN, 1.0, Nan, true),
        (Atan2, 1.0, NAN, Nan, true),
        (Pow, 0.0, 2.0, Is(0.0), true),
        (Pow, 0.0, 0.5, Is(0.0), true),
        (Pow, 0.0, -1.0, Is(INF), true),
        (Pow, 0.0, INF, Is(0.0), true),
        (Pow, 0.0, -INF, Is(INF), true),
        (Pow, 0.0, 0.0, Is(1.0), true),
        (Pow, 2.0, 0.0, Is(1.0), true),
        (Pow, INF, 0.0, Is(1.0), true),
        (Pow, NAN, 0.0, Is(1.0), true),
        (Pow, 1.0, NAN, Is(1.0), true),
        (Pow, 1.0, INF, Is(1.0), true),
        (Pow, 2.0, NAN, Nan, true),
        (Pow, NAN, 2.0, Nan, true),
        (Pow, -1.0, 0.5, Nan, true),
        (Pow, INF, 2.0, Is(INF), true),
        (Pow, INF, -2.0, Is(0.0), true),
        (Pow, 0.5, INF, Is(0.0), true),
        (Pow, 2.0, INF, Is(INF), true),
        (Pow, 2.0, -INF, Is(0.0), true),
        (Pow, 0.5, -INF, Is(INF), true),
        (Pow, 2.0, 200.0, Is(INF), true),
        (Pow, 2.0, -200.0, Is(0.0), true),
        (Pow, 2.0, -149.0, Is(1e-45), true),
        (Pow, 1e-45, 0.5, Ref(2e-7), true),
        (Pow, 10.0, 38.0, Ref(2e-7), true),
    ]
};

fn check_special(label: &str, libm: bool, eval: impl Fn(MathFn, f32, f32) -> f32) {
    let mut failures = Vec::new();
    for &(f, x, y, want, libm_too) in SPECIAL {
        if libm && !libm_too {
            continue;
        }
        let got = eval(f, x, y);
        let ok = match want {
            Want::Is(w) => got == w,
            Want::Nan => got.is_nan(),
            Want::Near(w, rel) => (f64::from(got) - w).abs() <= rel * w.abs(),
            Want::Within(lo, hi) => (lo..=hi).contains(&got),
            Want::Ref(rel) => {
                let w = reference(f, f64::from(x), f64::from(y));
                (f64::from(got) - w).abs() <= rel * w.abs()
            }
        };
        if !ok {
            failures.push(format!("{f:?}({x:e}, {y:e}) = {got:e}, want {want:?}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{label}: wrong special values:\n{}",
        failures.join("\n")
    );
}

#[test]
fn special_values() {
    check_special("vmath::<f32>", false, |f, x, y| {
        vmath_f32(f).expect("a vmath function")(x, y)
    });
    for kernels in Kernels::available() {
        let isa = kernels.isa();
        check_special(
            &format!("isa={}", isa.name()),
            isa == Isa::Scalar,
            |f, x, y| {
                let mut out = [0.0];
                map_math(kernels, f, &[x], &[y], &mut out);
                out[0]
            },
        );
    }
}

/// The scalar lane's `floor` (by truncation, no libm call) equals the f64 floor
/// everywhere: integers and halves on both sides of zero, denormals, the 2^23 edge,
/// huge values, infinities and NaN.
#[test]
fn scalar_floor_matches_f64_floor() {
    use glint::math::Lane;
    let mut xs = vec![
        0.0f32,
        -0.0,
        1e-45,
        -1e-45,
        0.5,
        -0.5,
        1.0,
        -1.0,
        -1.5,
        8_388_607.5,
        -8_388_607.5,
        8_388_608.0,
        -8_388_609.0,
        3e38,
        -3e38,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    xs.extend(rand(-1e4, 1e4, 100_000, 7));
    xs.extend(around(&[1.0, -1.0, 2.0, -2.0, 1024.0, -1024.0], 4));
    for x in xs {
        let expected = f64::from(x).floor() as f32;
        assert_eq!(<f32 as Lane>::floor(x), expected, "floor({x:e})");
    }
    assert!(<f32 as Lane>::floor(f32::NAN).is_nan());
}

/// `vmath::estrin9` evaluates `c[0] x^8 + ... + c[8]` (the order `horner` takes):
/// against f64 at 4097 points of [0, 1], for coefficients of both signs and of the
/// magnitudes of the Disney diffuse's subsurface fit, within 1e-6 of the sum of the
/// terms' magnitudes (8 roundings deep at most).
#[test]
fn estrin9_evaluates_the_polynomial() {
    let c: [f32; 9] = [-7.0, 49.0, -126.3, 152.2, -80.8, 3.4, 11.9, -2.6, 0.4];
    for i in 0..=4096 {
        let x = i as f32 / 4096.0;
        let (mut exact, mut scale) = (0.0f64, 0.0f64);
        for (k, &ck) in c.iter().enumerate() {
            let term = f64::from(ck) * f64::from(x).powi(8 - k as i32);
            exact += term;
            scale += term.abs();
        }
        let got = f64::from(vmath::estrin9(x, c));
        assert!(
            (got - exact).abs() <= 1e-6 * scale,
            "x {x}: {got} against {exact}"
        );
    }
}
