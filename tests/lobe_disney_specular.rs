//! `disney_specular` against an independent f64 transcription of Burley 2012's
//! specular (formulas.md): eval and pdf at random parameters and directions, albedo
//! against quadrature over the hemisphere, zero below the horizon.

mod common;
mod reference;

use common::{Block, Rng, assert_close, assert_close3, lobe, opposite_grazing_pairs};
use glint::lobes::Transport;
use glint::math::Vec3;
use std::f64::consts::PI;

fn sq(x: f64) -> f64 {
    x * x
}

/// `f(l, v)` and the VNDF pdf of `l`, f64, local frame.
fn reference(
    roughness: f64,
    anisotropic: f64,
    f0: [f64; 3],
    l: [f64; 3],
    v: [f64; 3],
) -> ([f64; 3], f64) {
    if l[2] <= 0.0 || v[2] <= 0.0 {
        return ([0.0; 3], 0.0);
    }
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    let (ax, ay) = (
        (sq(roughness) / aspect).max(0.001),
        (sq(roughness) * aspect).max(0.001),
    );
    let ag = sq(0.5 + roughness / 2.0);
    let (gx, gy) = ((ag / aspect).max(0.001), (ag * aspect).max(0.001));
    let hu = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let n = (sq(hu[0]) + sq(hu[1]) + sq(hu[2])).sqrt();
    let h = hu.map(|c| c / n);
    let d = 1.0 / (PI * ax * ay * sq(sq(h[0] / ax) + sq(h[1] / ay) + sq(h[2])));
    let smith = |w: [f64; 3]| 1.0 / (w[2] + (sq(w[0] * gx) + sq(w[1] * gy) + sq(w[2])).sqrt());
    // l.h = |l + v| / 2 for unit l, v: the dot product of f32 directions in f64 is
    // off by their distance from unit length (1e-8), all of l.h for opposite pairs.
    let fh = (1.0 - n / 2.0).clamp(0.0, 1.0).powi(5);
    let f = f0.map(|f0| d * (f0 + (1.0 - f0) * fh) * smith(l) * smith(v));
    // Heitz 2018 eq. 17: G1(v) D / (4 cos_v), G1 of D's own alphas.
    let lambda_term = (sq(ax * v[0]) + sq(ay * v[1]) + sq(v[2])).sqrt();
    let g1 = 2.0 * v[2] / (v[2] + lambda_term);
    (f, g1 * d / (4.0 * v[2]))
}

fn dir(rng: &mut Rng) -> Vec3<f32> {
    let (ct, phi) = (rng.f64(), 2.0 * PI * rng.f64());
    let st = (1.0 - ct * ct).sqrt();
    Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32)
}

fn v64(v: Vec3<f32>) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

fn block(roughness: f32, anisotropic: f32, f0: [f32; 3]) -> Block {
    Block::defaults(lobe("disney_specular"))
        .float("roughness", roughness)
        .float("anisotropic", anisotropic)
        .rgb("f0", f0)
}

/// Assert eval and pdf at `(wo, wi)` within 1e-4 of the formula (relative, plus
/// `abs`) where it is well conditioned: an f32 half vector is off by ~1e-7 in tan
/// theta_h. False, and nothing checked, where it is not.
fn matches_the_formula(
    (r, a, f0): (f32, f32, [f32; 3]),
    wo: Vec3<f32>,
    wi: Vec3<f32>,
    abs: f64,
) -> bool {
    let (lo, li) = (v64(wo), v64(wi));
    let hu = [lo[0] + li[0], lo[1] + li[1], lo[2] + li[2]];
    let t = (sq(hu[0]) + sq(hu[1])).sqrt() / hu[2];
    let alpha = (f64::from(r) * f64::from(r) * (1.0 - 0.9 * f64::from(a)).sqrt()).max(0.001);
    if 4e-7 * t / (sq(alpha) + sq(t)) > 2e-5 {
        return false;
    }
    let e = lobe("disney_specular").eval(block(r, a, f0).as_slice(), wo, wi, Transport::Radiance);
    let (f, pdf) = reference(f64::from(r), f64::from(a), f0.map(f64::from), li, lo);
    let what = format!("r {r} a {a} wo {wo:?} wi {wi:?}");
    assert_close3(e.value.to_array(), f.map(|f| f * li[2]), 1e-4, abs, &what);
    assert_close(f64::from(e.pdf), pdf, 1e-4, abs, &format!("pdf, {what}"));
    true
}

#[test]
fn eval_and_pdf_match_the_formula() {
    let mut rng = Rng::new(7);
    let mut checked = 0;
    for _ in 0..20_000 {
        let params = (rng.f32(), rng.f32(), [rng.f32(), rng.f32(), rng.f32()]);
        let (wo, wi) = (dir(&mut rng), dir(&mut rng));
        if wo.z >= 1e-3 && wi.z >= 1e-3 && matches_the_formula(params, wo, wi, 1e-7) {
            checked += 1;
        }
    }
    assert!(checked > 10_000, "{checked}");
}

/// Nearly opposite grazing pairs (`common::opposite_grazing_pairs`), whose `|wo +
/// wi|^2` goes down to the subnormals: the lobe scales the half vector's sum
/// (`fresnel::HalfVector::scale`) and stays within 1e-4 of the formula, value and pdf.
#[test]
fn nearly_opposite_grazing_pairs_match_the_formula() {
    let mut rng = Rng::new(21);
    let mut checked = 0;
    for (wo, wi) in opposite_grazing_pairs(&mut rng, 20_000) {
        let params = (rng.f32(), rng.f32(), [rng.f32(), rng.f32(), rng.f32()]);
        if matches_the_formula(params, wo, wi, 0.0) {
            checked += 1;
        }
    }
    assert!(checked > 10_000, "{checked}");
}

#[test]
fn zero_below_the_horizon() {
    let l = lobe("disney_specular");
    let p = block(0.5, 0.3, [0.5; 3]);
    let up = Vec3::new(0.0, 0.6, 0.8);
    let down = Vec3::new(0.0, 0.6, -0.8);
    for (wo, wi) in [(up, down), (down, up), (down, down)] {
        let e = l.eval(p.as_slice(), wo, wi, Transport::Radiance);
        assert_eq!((e.value.to_array(), e.pdf), ([0.0; 3], 0.0));
    }
    assert_eq!(
        l.albedo(p.as_slice(), down, Transport::Radiance).to_array(),
        [0.0; 3]
    );
}

/// `int f cos_i` over the hemisphere, in slope space (`reference::slope_space_albedo`).
fn quadrature(roughness: f64, anisotropic: f64, f0: f64, v: [f64; 3]) -> f64 {
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    let (ax, ay) = (
        (sq(roughness) / aspect).max(0.001),
        (sq(roughness) * aspect).max(0.001),
    );
    reference::slope_space_albedo(ax, ay, v, 800, |l, v| {
        reference(roughness, anisotropic, [f0; 3], l, v).0[0]
    })
}

/// The table's albedo against quadrature: within the documented tolerance (relative to
/// albedos above 0.05, absolute below). Measured here: 0.54% isotropic (grazing,
/// `cos_o` 0.02), 1.8% anisotropic (roughness 1, anisotropic 1, normal incidence).
#[test]
fn albedo_matches_quadrature() {
    let l = lobe("disney_specular");
    let mut worst = (0.0f64, String::new());
    for &r in &[0.0f32, 0.1, 0.2, 0.35, 0.5, 0.8, 1.0] {
        for &a in &[0.0f32, 0.5, 0.9, 1.0] {
            for &mu in &[0.02f64, 0.05, 0.2, 0.5, 0.9, 1.0] {
                for &phi in &[0.0f64, 0.5, 1.2] {
                    for &f0 in &[0.0f32, 1.0] {
                        let st = (1.0 - mu * mu).sqrt();
                        let v = [st * phi.cos(), st * phi.sin(), mu];
                        let wo = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
                        let got = l
                            .albedo(block(r, a, [f0; 3]).as_slice(), wo, Transport::Radiance)
                            .r;
                        let v = v64(wo);
                        let want = quadrature(f64::from(r), f64::from(a), f64::from(f0), v);
                        let tol = f64::from(l.albedo_tolerance(block(r, a, [f0; 3]).as_slice()));
                        let err = (f64::from(got) - want).abs() / want.max(0.05) / tol;
                        if err > worst.0 {
                            worst = (
                                err,
                                format!("r {r} a {a} mu {mu} phi {phi} f0 {f0}: {got} vs {want}"),
                            );
                        }
                    }
                }
            }
        }
    }
    eprintln!(
        "worst albedo error / tolerance {:.3} at {}",
        worst.0, worst.1
    );
    assert!(
        worst.0 <= 1.0,
        "{:.3} of the tolerance at {}",
        worst.0,
        worst.1
    );
}

/// The albedo estimate that lobe selection and pruning use against the table's
/// albedo: the same bits where isotropic; anisotropic, over views between the table's
/// nodes, within 8% at the 99th percentile and the documented 20% at worst (measured
/// here: 7.8% and 16.6%, the worst at anisotropic 0.9 and `cos_o` below 0.003).
#[test]
fn albedo_estimate_within_its_tolerance() {
    let l = lobe("disney_specular");
    let mut errors = Vec::new();
    let mut worst = (0.0f32, String::new());
    for im in 1..=40 {
        let mu = (im as f32 / 40.0).powi(2);
        for ip in 0..10 {
            let phi = (ip as f32 + 0.37) / 10.0 * std::f32::consts::FRAC_PI_2;
            let st = (1.0 - mu * mu).sqrt();
            let wo = Vec3::new(st * phi.cos(), st * phi.sin(), mu);
            for ir in 0..=20 {
                for ia in 0..=10 {
                    let (r, a) = (ir as f32 / 20.0, ia as f32 / 10.0);
                    for f0 in [0.02f32, 0.04, 0.5, 1.0] {
                        let b = block(r, a, [f0; 3]);
                        let mut decoded = vec![0.0; l.decoded_len()];
                        l.decode(b.as_slice(), &mut decoded);
                        let want = l.albedo(b.as_slice(), wo, Transport::Radiance).r;
                        let got = l
                            .albedo_estimate_decoded(&decoded, wo, Transport::Radiance)
                            .r;
                        if a == 0.0 {
                            assert_eq!(got.to_bits(), want.to_bits(), "isotropic r {r} mu {mu}");
                            continue;
                        }
                        let err = (got - want).abs() / want;
                        errors.push(err);
                        if err > worst.0 {
                            worst = (err, format!("r {r} a {a} mu {mu} phi {phi} f0 {f0}"));
                        }
                    }
                }
            }
        }
    }
    errors.sort_by(f32::total_cmp);
    let p99 = errors[errors.len() * 99 / 100];
    eprintln!(
        "estimate: p99 {p99:.4}, worst {:.4} at {}",
        worst.0, worst.1
    );
    let tol = l.albedo_estimate_tolerance(block(0.5, 1.0, [1.0; 3]).as_slice());
    assert!(p99 <= 0.08, "p99 {p99}");
    assert!(worst.0 <= tol, "{} at {}", worst.0, worst.1);
}
