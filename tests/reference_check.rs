//! Checks of the f64 reference itself (tests/reference), so that a lobe test failing
//! points at the library, not at the oracle: erfc against tabulated values, the two
//! independent dielectric Fresnel derivations against each other, NDF normalization and
//! the quadrature rule, Gulbrandsen's round trip, and a known Smith identity.

#![allow(clippy::excessive_precision)] // tabulated values as published

mod reference;

use reference::*;

#[test]
fn erfc_matches_tabulated_values() {
    // Abramowitz and Stegun / high-precision values.
    let table = [
        (0.0, 1.0),
        (0.1, 0.887_537_083_981_715_1),
        (0.5, 0.479_500_122_186_953_5),
        (1.0, 0.157_299_207_050_285_13),
        (2.0, 0.004_677_734_981_047_266),
        (2.5, 0.000_406_952_017_444_958_9),
        (3.0, 2.209_049_699_858_544e-5),
        (4.0, 1.541_725_790_028_002e-8),
        (5.0, 1.537_459_794_428_035e-12),
        (-1.0, 1.842_700_792_949_715),
    ];
    for (x, want) in table {
        let got = erfc(x);
        assert!(
            ((got - want) / want).abs() < 1e-13,
            "erfc({x}) = {got:e}, want {want:e}"
        );
    }
    // Continuity across the switch between series and continued fraction.
    let (a, b) = (erfc(2.5 - 1e-12), erfc(2.5 + 1e-12));
    assert!(((a - b) / a).abs() < 1e-10);
}

#[test]
fn dielectric_fresnel_forms_agree() {
    // Walter's g-form against the complex amplitude form with a real index, including
    // total internal reflection (eta < 1) where cos_t becomes imaginary.
    for eta in [1.0001, 1.33, 1.5, 2.4, 1.0 / 1.5, 0.5] {
        for i in 0..=100 {
            let cos = i as f64 / 100.0;
            let a = fresnel_dielectric_rel(cos, eta);
            let b = fresnel_complex(cos, C::real(eta));
            assert!((a - b).abs() < 1e-12, "eta {eta} cos {cos}: {a} vs {b}");
        }
    }
    // Known values: normal incidence ((n-1)/(n+1))^2, grazing 1, Brewster r_p = 0.
    assert!((fresnel_dielectric_rel(1.0, 1.5) - 0.04).abs() < 1e-15);
    assert!((fresnel_dielectric_rel(0.0, 1.5) - 1.0).abs() < 1e-15);
    let brewster = 1.5f64.atan().cos();
    let rs = {
        let ct = (1.0 - (1.0 - brewster * brewster) / 2.25).sqrt();
        (brewster - 1.5 * ct) / (brewster + 1.5 * ct)
    };
    assert!((fresnel_dielectric_rel(brewster, 1.5) - 0.5 * rs * rs).abs() < 1e-14);
    // From inside beyond the critical angle.
    assert_eq!(fresnel_dielectric(-0.5, 1.5), 1.0);
}

#[test]
fn conductor_fresnel_limits() {
    // Normal incidence: |(eta - 1) / (eta + 1)|^2; grazing: 1; k = 0: the dielectric.
    let (n, k) = (0.2, 3.9);
    let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
    assert!((fresnel_conductor(1.0, n, k) - want).abs() < 1e-14);
    assert!((fresnel_conductor(0.0, n, k) - 1.0).abs() < 1e-14);
    for i in 0..=20 {
        let c = i as f64 / 20.0;
        assert!((fresnel_conductor(c, 1.5, 0.0) - fresnel_dielectric_rel(c, 1.5)).abs() < 1e-12);
        let f = fresnel_conductor(c, n, k);
        assert!((0.0..=1.0).contains(&f));
    }
}

#[test]
fn gulbrandsen_round_trip() {
    // By construction F(normal incidence) of (n, k) equals the reflectivity.
    for r in [0.04, 0.3, 0.54, 0.64, 0.95] {
        for g in [0.0, 0.5, 0.9, 1.0] {
            let (n, k) = gulbrandsen(r, g);
            let f = fresnel_conductor(1.0, n, k);
            assert!((f - r).abs() < 1e-12, "r {r} g {g}: F(1) = {f}");
        }
    }
}

#[test]
fn ndf_normalization_and_quadrature() {
    // int D(m) (m.z) d omega = 1, and int D(m) (w.m) d omega = cos_w (1 + Lambda(w)) / ...
    // i.e. the projected-area identity int D (w.m)+ = cos_w + Lambda(w) cos_w = cos_w / G1(w).
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for alpha in [0.04, 0.1, 0.3, 0.7, 1.0] {
            let m = Micro::isotropic(ndf, alpha);
            let [norm, _, _] = integrate_normals(alpha, 256, 64, |h| [m.d(h) * h.z, 0.0, 0.0]);
            assert!((norm - 1.0).abs() < 2e-5, "{ndf:?} alpha {alpha}: {norm}");
            let w = dir(60.0, 0.0);
            let [proj, _, _] =
                integrate_normals(alpha, 256, 256, |h| [m.d(h) * w.dot(h).max(0.0), 0.0, 0.0]);
            let want = w.z / m.g1(w);
            assert!(
                (proj - want).abs() < 2e-4 * want,
                "{ndf:?} alpha {alpha}: projected area {proj} vs {want}"
            );
        }
        // Anisotropic normalization.
        let m = Micro {
            ndf,
            ax: 0.3,
            ay: 0.08,
        };
        let [norm, _, _] = integrate_normals((0.3f64 * 0.08).sqrt(), 512, 256, |h| {
            [m.d(h) * h.z, 0.0, 0.0]
        });
        assert!((norm - 1.0).abs() < 2e-4, "{ndf:?} anisotropic: {norm}");
    }
}

#[test]
fn smith_lambda_known_values() {
    // GGX: Lambda = (sqrt(1 + alpha^2 tan^2) - 1) / 2; Beckmann at a = 1:
    // (exp(-1)/sqrt(pi) - erfc(1)) / 2.
    let m = Micro::isotropic(Ndf::Ggx, 0.5);
    let w = dir(45.0, 30.0);
    assert!((m.lambda(w) - 0.5 * ((1.25f64).sqrt() - 1.0)).abs() < 1e-14);
    let b = Micro::isotropic(Ndf::Beckmann, 1.0);
    let want = 0.5 * ((-1.0f64).exp() / std::f64::consts::PI.sqrt() - 0.157_299_207_050_285_13);
    assert!((b.lambda(dir(45.0, 0.0)) - want).abs() < 1e-14);
}

#[test]
fn refract_obeys_snell() {
    let n = V::new(0.0, 0.0, 1.0);
    let w = dir(50.0, 20.0);
    let (t, etap) = refract(w, n, 1.5).unwrap();
    assert_eq!(etap, 1.5);
    let sin_t = (t.x * t.x + t.y * t.y).sqrt();
    assert!((sin_t * 1.5 - 50f64.to_radians().sin()).abs() < 1e-14);
    assert!(t.z < 0.0 && (t.length() - 1.0).abs() < 1e-14);
    // Back out again.
    let (back, etap) = refract(t, n, 1.5).unwrap();
    assert!((etap - 1.0 / 1.5).abs() < 1e-15);
    assert!((back - w).length() < 1e-14);
    // Beyond the critical angle from inside.
    assert!(refract(-dir(60.0, 0.0), n, 1.5).is_none());
}
