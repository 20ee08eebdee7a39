//! Every normal distribution, by quadrature in f64 over the hemisphere of normals,
//! independently of the lobes built on it: `D` is normalized (`int D(m) m.z dm = 1`), a
//! Smith distribution's `Lambda` belongs to its `D` (the visible normals of every view
//! integrate to 1, Heitz 2014 eq. 38), and the sampler draws normals with the density
//! `pdf` states (sample means of test functions against their quadratures). The Smith
//! distributions come from `NdfKind::ALL`, so one added to the list is checked here.

use glint::math::Vec3;
use glint::microfacet::{Distribution, Gtr1, Ndf, NdfKind, SmithNdf};

/// `sum f(m) dm` over the upper hemisphere on a grid `theta = (pi / 2) s^2` (dense at
/// the pole, where the sharpest distributions peak) by the midpoint rule in `s` and `phi`.
fn hemisphere(f: impl Fn(Vec3<f32>) -> f64) -> f64 {
    let (ns, np) = (3000, 256);
    let mut sum = 0.0;
    for i in 0..ns {
        let s = (i as f64 + 0.5) / ns as f64;
        let theta = std::f64::consts::FRAC_PI_2 * s * s;
        // d theta = pi s ds; solid angle sin theta d theta d phi.
        let jacobian = std::f64::consts::PI * s / ns as f64 * theta.sin();
        for j in 0..np {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
            let m = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            sum += f(m) * jacobian * 2.0 * std::f64::consts::PI / np as f64;
        }
    }
    sum
}

fn views() -> Vec<Vec3<f32>> {
    [0.0f32, 30.0, 60.0, 80.0]
        .iter()
        .map(|deg| {
            let (t, p) = (deg.to_radians(), 0.6f32);
            Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
        })
        .collect()
}

/// Every Smith distribution at a few alphas (sharp, medium, anisotropic, roughest),
/// with a name for messages.
fn smith_cases() -> Vec<(String, Distribution<f32>)> {
    let mut cases = Vec::new();
    for &kind in NdfKind::ALL {
        for (ax, ay) in [(0.05, 0.05), (0.3, 0.3), (0.5, 0.1), (1.0, 1.0)] {
            let dist = Distribution {
                kind,
                alpha_x: ax,
                alpha_y: ay,
            };
            cases.push((format!("{} alpha ({ax}, {ay})", kind.name()), dist));
        }
    }
    cases
}

/// Sample means of `m.z`, `m.x^2` and `m.x m.y + m.y` over 500 x 500 jittered
/// stratified draws against their quadratures under `pdf`: a sampler whose density is
/// not `pdf` moves at least one of them.
fn check_sampler<N: Ndf<f32>>(ndf: &N, w: Vec3<f32>, what: &str) {
    let tests: [fn(Vec3<f32>) -> f64; 3] = [
        |m| f64::from(m.z),
        |m| f64::from(m.x * m.x),
        |m| f64::from(m.x * m.y + m.y),
    ];
    let n = 500;
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut jitter = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut means = [0.0f64; 3];
    for i in 0..n {
        for j in 0..n {
            let u0 = ((i as f32 + jitter()) / n as f32).min(1.0 - 1e-7);
            let u1 = ((j as f32 + jitter()) / n as f32).min(1.0 - 1e-7);
            let m = ndf.sample(w, u0, u1);
            for (mean, t) in means.iter_mut().zip(tests) {
                *mean += t(m) / (n * n) as f64;
            }
        }
    }
    for (k, (mean, t)) in means.iter().zip(tests).enumerate() {
        let expected = hemisphere(|m| t(m) * f64::from(ndf.pdf(w, m)));
        assert!(
            (mean - expected).abs() < 3e-3,
            "{what}, view {w:?}: test function {k}: sample mean {mean:.5} vs quadrature {expected:.5}"
        );
    }
}

#[test]
fn smith_distributions_are_normalized_and_their_lambda_matches() {
    for (what, dist) in smith_cases() {
        let norm = hemisphere(|m| f64::from(dist.d(m) * m.z));
        assert!((norm - 1.0).abs() < 2e-3, "{what}: int D cos = {norm}");
        for w in views() {
            let visible = hemisphere(|m| f64::from(dist.pdf_visible(w, m)));
            assert!(
                (visible - 1.0).abs() < 3e-3,
                "{what}, view {w:?}: int D_w = {visible}"
            );
        }
    }
}

#[test]
fn smith_samplers_draw_their_pdf() {
    for (what, dist) in smith_cases() {
        for w in views() {
            check_sampler(&dist, w, &what);
        }
    }
}

fn gtr1(a: f64) -> Gtr1<f32> {
    let [a2, norm, ln_a2, inv_one_minus_a2] = Gtr1::constants(a).map(|c| c as f32);
    Gtr1 {
        a2,
        norm,
        ln_a2,
        inv_one_minus_a2,
    }
}

#[test]
fn gtr1_is_normalized_and_samples_its_pdf() {
    for a in [0.001, 0.01, 0.1, 0.5] {
        let ndf = gtr1(a);
        let norm = hemisphere(|m| f64::from(ndf.d(m) * m.z));
        assert!((norm - 1.0).abs() < 2e-3, "GTR1 a {a}: int D cos = {norm}");
        check_sampler(&ndf, Vec3::new(0.0, 0.0, 1.0), &format!("GTR1 a {a}"));
    }
}

/// The choice names and kinds line up, so a block's `distribution` index names the
/// distribution its name says.
#[test]
fn kinds_round_trip_through_their_choice_index() {
    assert_eq!(NdfKind::ALL.len(), NdfKind::NAMES.len());
    for (i, &kind) in NdfKind::ALL.iter().enumerate() {
        assert_eq!(NdfKind::from_choice(i), kind);
        assert_eq!(kind.name(), NdfKind::NAMES[i]);
    }
    assert_eq!(NdfKind::from_choice(0).name(), "ggx");
    assert_eq!(NdfKind::from_choice(1).name(), "beckmann");
}

/// GGX's visible normals where they are seen edge-on follow the caps mapping (Dupuy and
/// Benyoub 2023, the azimuth measured from `-v.xy`'s, `v` the stretched view) evaluated
/// in f64 as written, `m = c + v`: `u0` 1 to 64 ulps below 1, `u1` at and near the
/// azimuth of `-v.xy` (where `c + v` cancels) and elsewhere, alpha 0.25 and 1, views
/// from 10 to 89 degrees. In f64 the sum loses 24 of 53 bits there; in f32 (the mapping
/// before 2026-12-07) it was 1e-2 off.
#[test]
fn ggx_edge_on_visible_normals_follow_the_caps_mapping() {
    use glint::microfacet::Ggx;
    use std::f64::consts::TAU;
    let mut worst = 0.0f64;
    for (ax, ay) in [(0.25f32, 0.25f32), (1.0, 1.0), (0.25, 1.0)] {
        let ggx = Ggx {
            alpha_x: ax,
            alpha_y: ay,
        };
        for theta in [10.0f64, 49.5, 80.0, 89.0] {
            let (st, ct) = theta.to_radians().sin_cos();
            let w = Vec3::new(
                (st * 0.6f64.cos()) as f32,
                (st * 0.6f64.sin()) as f32,
                ct as f32,
            );
            for k in [1.0f32, 2.0, 8.0, 64.0] {
                let u0 = 1.0 - k * f32::EPSILON / 2.0;
                for u1 in [0.0f32, 1e-7, 3e-6, 0.25, 0.5, 0.999_999_9] {
                    let got = ggx.sample(w, u0, u1);
                    // f64: the stretched view, the cap's point c (height z from u0,
                    // azimuth from -v.xy), m = c + v, unstretched (m.z floored at 1e-6
                    // as the sampler does) and normalized.
                    let (ax, ay) = (f64::from(ax), f64::from(ay));
                    let v = [ax * f64::from(w.x), ay * f64::from(w.y), f64::from(w.z)];
                    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    let v = v.map(|c| c / len);
                    let (u0, u1) = (f64::from(u0), f64::from(u1));
                    let z = (1.0 - u0) * (1.0 + v[2]) - v[2];
                    let sin_theta = (1.0 - z * z).max(0.0).sqrt();
                    let phi = TAU * u1 + (-v[1]).atan2(-v[0]);
                    let m = [
                        sin_theta * phi.cos() + v[0],
                        sin_theta * phi.sin() + v[1],
                        z + v[2],
                    ];
                    let m = [ax * m[0], ay * m[1], m[2].max(1e-6)];
                    let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
                    let got_m = [got.x, got.y, got.z];
                    let d = (0..3)
                        .map(|c| (f64::from(got_m[c]) - m[c] / len).abs())
                        .fold(0.0, f64::max);
                    assert!(
                        d <= 1e-5,
                        "alpha ({ax}, {ay}), view {theta} deg, u0 = 1 - {k} ulp/2, u1 {u1}: {got:?} is {d:e} from {m:?}"
                    );
                    worst = worst.max(d);
                }
            }
        }
    }
    eprintln!("worst: {worst:e}");
}
