//! `conductor` against the f64 Cook-Torrance reference of `tests/reference`:
//! `eval = D G2 F / (4 cos_o cos_i) cos_i` and `pdf = G1(wo) D(h) / (4 cos_o)` for GGX and
//! Beckmann, isotropic and anisotropic, with each Fresnel mode; the table-based albedo
//! against f64 quadrature of the f64 BRDF; the delta (mirror) case; and sampling
//! (sample value and pdf equal eval, and the mean sample weight converges to the albedo).

mod common;
mod reference;

use common::{Block, Rng, assert_close, assert_close3, lobe};
use glint::lobes::{LobeType, Transport, flags};
use glint::math::{Frame, Vec3};
use glint::registry::Registry;
use glint::{Closure, Status};
use reference::{Fresnel, Micro, Ndf, V, cook_torrance, cook_torrance_albedo, dir32};

const SCHLICK_F0: [f32; 3] = [0.9, 0.5, 0.04];
const SCHLICK_F90: [f32; 3] = [1.0, 0.8, 1.0];
/// Copper-like complex IOR (not the schema default).
const ETA: [f32; 3] = [0.27, 0.68, 1.22];
const K: [f32; 3] = [3.61, 2.63, 2.29];
/// Artistic parameters with a low edge tint (a curve far from Schlick's).
const REFLECTIVITY: [f32; 3] = [0.91, 0.42, 0.2];
const EDGE_TINT: [f32; 3] = [0.95, 0.7, 0.3];
/// Gold-like artistic parameters (the schema's defaults, written out).
const GOLD_REFLECTIVITY: [f32; 3] = [0.95, 0.64, 0.54];
const GOLD_EDGE_TINT: [f32; 3] = [1.0, 0.98, 0.9];

/// Quadrature nodes per dimension: relative error below 2.2e-4 against 1024 nodes over
/// the albedo grids used here (roughness 0.2..1, mu 0.1..1, both NDFs).
const QUAD: usize = 160;

#[derive(Clone, Copy, Debug)]
enum Mode {
    Schlick,
    Conductor,
    Artistic,
    ArtisticGold,
}
const MODES: [Mode; 4] = [
    Mode::Schlick,
    Mode::Conductor,
    Mode::Artistic,
    Mode::ArtisticGold,
];

fn conductor() -> &'static dyn LobeType {
    lobe("conductor")
}

/// The library's parameter block and the matching reference.
fn setup(ndf: Ndf, roughness: f32, anisotropic: f32, mode: Mode) -> (Block, Micro, Fresnel) {
    let b = Block::defaults(conductor())
        .choice("distribution", ndf.name())
        .float("roughness", roughness)
        .float("anisotropic", anisotropic);
    let (b, f) = match mode {
        Mode::Schlick => (
            b.choice("fresnel", "schlick")
                .rgb("f0", SCHLICK_F0)
                .rgb("f90", SCHLICK_F90),
            Fresnel::schlick(SCHLICK_F0, SCHLICK_F90),
        ),
        Mode::Conductor => (
            b.choice("fresnel", "conductor").rgb("eta", ETA).rgb("k", K),
            Fresnel::conductor(ETA, K),
        ),
        Mode::Artistic => (
            b.choice("fresnel", "artistic")
                .rgb("reflectivity", REFLECTIVITY)
                .rgb("edge_tint", EDGE_TINT),
            Fresnel::artistic(REFLECTIVITY, EDGE_TINT),
        ),
        Mode::ArtisticGold => (
            b.choice("fresnel", "artistic")
                .rgb("reflectivity", GOLD_REFLECTIVITY)
                .rgb("edge_tint", GOLD_EDGE_TINT),
            Fresnel::artistic(GOLD_REFLECTIVITY, GOLD_EDGE_TINT),
        ),
    };
    (b, Micro::from_roughness(ndf, roughness, anisotropic), f)
}

/// A direction in f32 for the library and its exact f64 value for the reference.
type Dir = (Vec3<f32>, V);

/// `(wo, wi)` pairs: a few arbitrary ones, and ones built around half vectors at
/// 0..30 degrees so that D is never negligible.
fn pairs() -> Vec<(Dir, Dir)> {
    let mut out = Vec::new();
    for ((to, po), (ti, pi)) in [
        ((30.0, 0.0), (45.0, 180.0)),
        ((60.0, 20.0), (20.0, 250.0)),
        ((10.0, 100.0), (70.0, 300.0)),
        ((75.0, 0.0), (75.0, 180.0)),
        ((45.0, 30.0), (50.0, 200.0)),
        ((85.0, 135.0), (30.0, 300.0)),
    ] {
        out.push((dir32(to, po), dir32(ti, pi)));
    }
    for (to, po) in [(20.0, 40.0), (55.0, 200.0), (80.0, 10.0)] {
        for (th, ph) in [(0.0, 0.0), (5.0, 60.0), (15.0, 150.0), (30.0, 270.0)] {
            let (wo, wo64) = dir32(to, po);
            let h = reference::dir(th, ph);
            let wi = wo64.reflect(h);
            if wi.z > 0.05 {
                let wi32 = wi.to32();
                out.push(((wo, wo64), (wi32, V::from32(wi32))));
            }
        }
    }
    out
}

#[test]
fn eval_and_pdf_match_cook_torrance() {
    let l = conductor();
    let mut worst = 0.0f64;
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for (r, an) in [(0.3, 0.0), (0.6, 0.0), (0.45, 0.8), (1.0, 0.3)] {
            for mode in MODES {
                let (b, m, f) = setup(ndf, r, an, mode);
                for ((wo, wo64), (wi, wi64)) in pairs() {
                    let (want, want_pdf) = cook_torrance(&m, &f, wo64, wi64);
                    for transport in [Transport::Radiance, Transport::Importance] {
                        let e = l.eval(b.as_slice(), wo, wi, transport);
                        let what = format!(
                            "{ndf:?} r {r} aniso {an} {mode:?} wo {wo64:?} wi {wi64:?} {transport:?}"
                        );
                        let v = e.value.to_array();
                        for c in 0..3 {
                            worst = worst.max((f64::from(v[c]) - want[c]).abs() / want[c]);
                        }
                        assert_close3(v, want, 1e-4, 1e-20, &what);
                        assert_close(f64::from(e.pdf), want_pdf, 1e-4, 1e-20, &what);
                    }
                }
            }
        }
    }
    eprintln!("conductor eval: worst relative error vs f64 {worst:.2e}");
}

/// Smith Lambda is 0 for a direction along the normal (nothing is masked). Any
/// `wo` or `wi` exactly at normal incidence must evaluate like its neighbours.
#[test]
fn eval_at_normal_incidence() {
    let l = conductor();
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        let (b, m, f) = setup(ndf, 0.5, 0.0, Mode::Schlick);
        let (n, n64) = dir32(0.0, 0.0);
        for (t, p) in [(10.0, 0.0), (30.0, 120.0)] {
            let (w, w64) = dir32(t, p);
            for (wo, wo64, wi, wi64) in [(n, n64, w, w64), (w, w64, n, n64)] {
                let (want, want_pdf) = cook_torrance(&m, &f, wo64, wi64);
                let e = l.eval(b.as_slice(), wo, wi, Transport::Radiance);
                let what = format!("{ndf:?} r 0.5 at normal incidence: wo {wo64:?} wi {wi64:?}");
                assert_close3(e.value.to_array(), want, 1e-4, 1e-20, &what);
                assert_close(f64::from(e.pdf), want_pdf, 1e-4, 1e-20, &what);
            }
        }
    }
}

#[test]
fn below_horizon_is_zero() {
    let l = conductor();
    let (b, _, _) = setup(Ndf::Ggx, 0.5, 0.0, Mode::Schlick);
    let up = dir32(30.0, 0.0).0;
    let down = dir32(120.0, 40.0).0;
    for (wo, wi) in [(up, down), (down, up), (down, down)] {
        let e = l.eval(b.as_slice(), wo, wi, Transport::Radiance);
        assert_eq!(e.value.to_array(), [0.0; 3]);
        assert_eq!(e.pdf, 0.0);
    }
    assert_eq!(
        l.albedo(b.as_slice(), down, Transport::Radiance).to_array(),
        [0.0; 3]
    );
    let mut rng = Rng::new(3);
    for _ in 0..200 {
        let s = l.sample(b.as_slice(), down, rng.u3(), Transport::Radiance);
        assert!(!s.valid && s.pdf == 0.0 && s.value.to_array() == [0.0; 3]);
    }
}

/// Max relative error of the library's albedo against f64 quadrature over a grid of
/// roughness and `mu = cos theta_o` (normal incidence is tested separately).
fn albedo_error(ndf: Ndf, mode: Mode) -> f64 {
    let l = conductor();
    let mut worst = 0.0f64;
    for r in [0.2f32, 0.35, 0.5, 0.75, 1.0] {
        for mu in [0.1f64, 0.25, 0.5, 0.75, 0.9] {
            let (b, m, f) = setup(ndf, r, 0.0, mode);
            let (wo, wo64) = dir32(mu.acos().to_degrees(), 0.0);
            let want = cook_torrance_albedo(&m, &f, wo64, QUAD);
            let got = l.albedo(b.as_slice(), wo, Transport::Radiance).to_array();
            for c in 0..3 {
                let e = (f64::from(got[c]) - want[c]).abs() / want[c];
                if e > worst {
                    worst = e;
                }
            }
        }
    }
    eprintln!("conductor albedo {ndf:?} {mode:?}: worst relative error {worst:.4}");
    worst
}

// The reflection table is exact in its Fresnel weighting for Schlick; a complex IOR adds
// the piecewise-linear interpolation of its departure from Schlick at 13 nodes of wo.m
// (see `albedo_table`). Measured over the grid above: GGX 0.33% and Beckmann 0.99% for
// Schlick, the copper-like IOR, gold-like artistic parameters and the low edge tint
// (0.3) alike; tests/albedo.rs covers grazing, narrow and anisotropic lobes.

#[test]
fn albedo_ggx_schlick_matches_quadrature() {
    let e = albedo_error(Ndf::Ggx, Mode::Schlick);
    assert!(e < 0.01, "GGX Schlick albedo error {e}");
}

#[test]
fn albedo_beckmann_schlick_matches_quadrature() {
    let e = albedo_error(Ndf::Beckmann, Mode::Schlick);
    assert!(e < 0.025, "Beckmann Schlick albedo error {e}");
}

#[test]
fn albedo_ggx_conductor_matches_quadrature() {
    let e = albedo_error(Ndf::Ggx, Mode::Conductor);
    assert!(e < 0.015, "GGX conductor albedo error {e}");
}

#[test]
fn albedo_beckmann_conductor_matches_quadrature() {
    let e = albedo_error(Ndf::Beckmann, Mode::Conductor);
    assert!(e < 0.03, "Beckmann conductor albedo error {e}");
}

#[test]
fn albedo_ggx_artistic_matches_quadrature() {
    let e = albedo_error(Ndf::Ggx, Mode::ArtisticGold);
    assert!(e < 0.01, "GGX artistic albedo error {e}");
}

#[test]
fn albedo_beckmann_artistic_matches_quadrature() {
    let e = albedo_error(Ndf::Beckmann, Mode::ArtisticGold);
    assert!(e < 0.025, "Beckmann artistic albedo error {e}");
}

#[test]
fn albedo_artistic_low_edge_tint_error_is_bounded() {
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        let e = albedo_error(ndf, Mode::Artistic);
        assert!(
            e < 0.025,
            "{ndf:?} artistic (edge tint 0.3) albedo error {e}"
        );
    }
}

/// Albedo at exactly normal incidence, the direction closures use when created
/// without `wo`.
#[test]
fn albedo_at_normal_incidence() {
    let l = conductor();
    let (wo, wo64) = dir32(0.0, 0.0);
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for r in [0.5f32, 0.75, 1.0] {
            let (b, m, f) = setup(ndf, r, 0.0, Mode::Schlick);
            let want = cook_torrance_albedo(&m, &f, wo64, QUAD);
            let got = l.albedo(b.as_slice(), wo, Transport::Radiance).to_array();
            assert_close3(
                got,
                want,
                0.03,
                0.0,
                &format!("{ndf:?} r {r} albedo at mu = 1"),
            );
        }
    }
}

#[test]
fn delta_when_smooth() {
    let l = conductor();
    let registry = Registry::with_builtins();
    let id = registry.find("conductor").unwrap();
    let mut rng = Rng::new(11);
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for r in [0.0f32, 0.01, 0.03] {
            for mode in MODES {
                let (b, _, f) = setup(ndf, r, 0.0, mode);
                for (t, p) in [(0.0, 0.0), (35.0, 60.0), (70.0, 200.0), (88.0, 300.0)] {
                    let (wo, wo64) = dir32(t, p);
                    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
                    let what = format!("{ndf:?} roughness {r} {mode:?} wo ({t}, {p})");
                    let e = l.eval(b.as_slice(), wo, mirror, Transport::Radiance);
                    assert_eq!(e.value.to_array(), [0.0; 3], "{what}: delta eval");
                    assert_eq!(e.pdf, 0.0, "{what}: delta pdf");
                    let want = f.eval(wo64.z);
                    for _ in 0..4 {
                        let s = l.sample(b.as_slice(), wo, rng.u3(), Transport::Radiance);
                        assert!(s.valid && s.delta && !s.transmitted, "{what}");
                        assert_eq!(s.wi, mirror, "{what}: mirror direction");
                        assert_eq!(s.pdf, 1.0, "{what}: discrete probability");
                        assert_eq!(s.roughness, 0.0);
                        assert_close3(s.value.to_array(), want, 1e-4, 0.0, &what);
                    }
                    let a = l.albedo(b.as_slice(), wo, Transport::Radiance);
                    assert_close3(a.to_array(), want, 1e-4, 0.0, &format!("{what}: albedo"));
                }
                // Through a closure: the SPECULAR | REFLECTION flags and weight F.
                let (wo, wo64) = dir32(40.0, 10.0);
                let mut c = Closure::new(Some(wo), Transport::Radiance);
                c.add_lobe(&registry, id, [1.0; 3], Frame::IDENTITY, Some(b.as_slice()))
                    .unwrap();
                c.finish().unwrap();
                let s = c.sample(wo, rng.u3()).unwrap();
                assert_eq!(s.flags, flags::REFLECTION | flags::SPECULAR);
                assert_eq!(s.pdf, 1.0);
                assert_close3(
                    s.weight.to_array(),
                    f.eval(wo64.z),
                    1e-4,
                    0.0,
                    "closure weight",
                );
                let e = c.eval(wo, s.wi).unwrap();
                assert_eq!((e.value.to_array(), e.pdf), ([0.0; 3], 0.0));
            }
        }
    }
    // Just above the threshold (alpha = 1.1e-3 > 1e-3) the lobe is glossy again.
    let (b, _, _) = setup(Ndf::Ggx, 0.033, 0.0, Mode::Schlick);
    let s = l.sample(
        b.as_slice(),
        dir32(30.0, 0.0).0,
        [0.5; 3],
        Transport::Radiance,
    );
    assert!(s.valid && !s.delta);
}

/// Each sample's value and pdf equal eval at the sampled direction, and match the f64
/// reference there.
#[test]
fn samples_match_eval() {
    let l = conductor();
    let mut rng = Rng::new(5);
    let mut worst = 0.0f64;
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for (r, an) in [(0.2, 0.0), (0.5, 0.0), (0.4, 0.9), (1.0, 0.0)] {
            let (b, m, f) = setup(ndf, r, an, Mode::Artistic);
            for (t, p) in [(0.5, 0.0), (30.0, 10.0), (60.0, 100.0), (85.0, 250.0)] {
                let (wo, wo64) = dir32(t, p);
                for _ in 0..500 {
                    let s = l.sample(b.as_slice(), wo, rng.u3(), Transport::Radiance);
                    if !s.valid {
                        assert_eq!((s.pdf, s.value.to_array()), (0.0, [0.0; 3]));
                        continue;
                    }
                    assert!(!s.delta && !s.transmitted && s.wi.z > 0.0);
                    assert_eq!(s.roughness, r);
                    let wi64 = V::from32(s.wi);
                    assert!((wi64.length() - 1.0).abs() < 1e-5, "unit wi");
                    let e = l.eval(b.as_slice(), wo, s.wi, Transport::Radiance);
                    let what = format!("{ndf:?} r {r} aniso {an} wo ({t}, {p}) wi {wi64:?}");
                    let ev = e.value.to_array().map(f64::from);
                    assert_close3(s.value.to_array(), ev, 1e-3, 1e-12, &what);
                    assert_close(f64::from(s.pdf), f64::from(e.pdf), 1e-3, 1e-12, &what);
                    let (want, want_pdf) = cook_torrance(&m, &f, wo64, wi64);
                    assert_close3(s.value.to_array(), want, 1e-3, 1e-12, &what);
                    assert_close(f64::from(s.pdf), want_pdf, 1e-3, 1e-12, &what);
                    worst = worst.max((f64::from(s.pdf) - want_pdf).abs() / want_pdf);
                }
            }
        }
    }
    eprintln!("conductor samples: worst pdf error vs f64 {worst:.2e}");
}

/// The mean sample weight is an unbiased estimate of the albedo only if samples are
/// drawn with density `pdf`: compare it with f64 quadrature (4 standard errors).
#[test]
fn mean_sample_weight_converges_to_albedo() {
    let l = conductor();
    let mut rng = Rng::new(17);
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for (r, t) in [(0.2f32, 20.0), (0.5, 60.0), (0.9, 45.0), (0.7, 80.0)] {
            let (b, m, f) = setup(ndf, r, 0.0, Mode::Conductor);
            let (wo, wo64) = dir32(t, 30.0);
            let want = cook_torrance_albedo(&m, &f, wo64, QUAD);
            let n = 20_000;
            let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
            for _ in 0..n {
                let s = l.sample(b.as_slice(), wo, rng.u3(), Transport::Radiance);
                let w = s.weight().to_array();
                for c in 0..3 {
                    sum[c] += f64::from(w[c]);
                    sum2[c] += f64::from(w[c]).powi(2);
                }
            }
            for c in 0..3 {
                let mean = sum[c] / n as f64;
                let se = ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt();
                assert!(
                    (mean - want[c]).abs() < 4.0 * se + 1e-4,
                    "{ndf:?} r {r} theta_o {t} channel {c}: mean weight {mean} vs albedo {} (se {se:.2e})",
                    want[c]
                );
            }
        }
    }
}

#[test]
fn invalid_sample_never_has_weight() {
    // Grazing wo with a rough lobe: many visible normals reflect below the horizon.
    let l = conductor();
    let (b, _, _) = setup(Ndf::Ggx, 1.0, 0.0, Mode::Schlick);
    let (wo, _) = dir32(89.0, 0.0);
    let mut rng = Rng::new(23);
    let mut invalid = 0;
    for _ in 0..2000 {
        let s = l.sample(b.as_slice(), wo, rng.u3(), Transport::Radiance);
        if s.valid {
            assert!(s.pdf > 0.0 && s.pdf.is_finite() && s.wi.z > 0.0);
            assert!(
                s.weight()
                    .to_array()
                    .iter()
                    .all(|w| w.is_finite() && *w >= 0.0)
            );
        } else {
            invalid += 1;
            assert_eq!((s.pdf, s.value.to_array()), (0.0, [0.0; 3]));
        }
    }
    assert!(
        invalid > 0,
        "expected some samples below the horizon at grazing"
    );
    let registry = Registry::with_builtins();
    let mut c = Closure::new(Some(wo), Transport::Radiance);
    c.add_lobe(
        &registry,
        registry.find("conductor").unwrap(),
        [1.0; 3],
        Frame::IDENTITY,
        Some(b.as_slice()),
    )
    .unwrap();
    c.finish().unwrap();
    let mut no_sample = 0;
    for _ in 0..500 {
        match c.sample(wo, rng.u3()) {
            Ok(s) => assert!(s.pdf > 0.0),
            Err(e) => {
                assert_eq!(e.status, Status::NoSample);
                no_sample += 1;
            }
        }
    }
    assert!(no_sample > 0);
}
