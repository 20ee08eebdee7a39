//! Numerical range of the microfacet lobes, scalar and on every batch kernel set this
//! CPU has, against the f64 references of `tests/reference`:
//! - grazing `wo` (issue 12, D6): local `cos_o` from 1e-1 down to the smallest f32
//!   denormal, 0 and -0, for `conductor` and `dielectric`, GGX and Beckmann, isotropic
//!   and anisotropic. The BRDF times cosine and the pdf stay bounded as `cos_o -> 0`
//!   (`G2` and `G1` vanish like `cos_o`), so the values must follow the reference down
//!   to its finite limit and be exactly 0 at `cos_o = 0`;
//! - the relative IOR range of `dielectric` (D9): eta from 0.001 to 1000.

mod common;
mod reference;

use common::{Block, Rng, close, closure, eval_on_every_kernel_set, lobe};
use glint::math::{Frame, Vec3};
use glint::verify::{BATCH_TOLERANCE, batch_difference};
use reference::{Fresnel, Micro, Ndf, V, cook_torrance, walter};

/// Local `cos_o` from 0.1 down through the denormals to the smallest f32 (1.4e-45),
/// then 0 and -0.
fn grazing_cosines() -> Vec<f32> {
    let mut z: Vec<f32> = (1..=45).map(|e| 10f32.powi(-e)).collect();
    z.extend([
        3e-39,
        1e-39,
        5e-41,
        1e-44,
        f32::from_bits(2),
        f32::from_bits(1),
    ]);
    z.sort_by(|a, b| b.total_cmp(a));
    z.extend([0.0, -0.0]);
    z
}

/// A unit `wo` at azimuth `phi` (degrees) and local `z`, as the closure calls and
/// batches normalize it (below `z = 1e-4` that leaves `z` unchanged).
fn grazing_wo(phi: f64, z: f32) -> Vec3<f32> {
    let (s, c) = phi.to_radians().sin_cos();
    let r = (1.0 - f64::from(z).powi(2)).sqrt();
    let v = V::new(r * c, r * s, f64::from(z)).to32();
    Vec3::try_unit(v.x, v.y, v.z, "wo").unwrap()
}

/// The f64 reference `(value, pdf)` of one pair.
type RefEval<'a> = &'a dyn Fn(V, V) -> (f64, f64);

/// Check one lobe's grazing sweep, `wo` above and below the surface; `wis` are the
/// fixed `wi` (world = local).
fn check_grazing(name: &str, block: &Block, reference: RefEval<'_>, wis: &[V], what: &str) {
    let c = closure(name, block, Frame::IDENTITY);
    let zs = grazing_cosines();
    let mut wo = Vec::new();
    let mut wi = Vec::new();
    for phi in [0.0, 50.0, 90.0] {
        for &w in wis {
            for side in [1.0f32, -1.0] {
                wo.extend(zs.iter().map(|&z| grazing_wo(phi, side * z)));
                let w = w.normalize().to32();
                let w = Vec3::try_unit(w.x, w.y, w.z, "wi").unwrap();
                wi.extend(zs.iter().map(|_| w));
            }
        }
    }
    // Grazing wi (wo and wi swapped): finite and as the reference (to 1e-3: transmission
    // of the narrow lobes amplifies f32 rounding of the half vector).
    for (source, lanes) in eval_on_every_kernel_set(&c, &wi, &wo) {
        for (k, &([value, ..], pdf)) in lanes.iter().enumerate() {
            let (want, want_pdf) = reference(V::from32(wi[k]), V::from32(wo[k]));
            let at = format!("{what} {source}: wo {:?} wi {:?}", wi[k], wo[k]);
            assert!(
                close(f64::from(value), want, 1e-3, 1e-9)
                    && close(f64::from(pdf), want_pdf, 1e-3, 1e-9),
                "{at}: value {value:e} pdf {pdf:e}, reference {want:e} {want_pdf:e}"
            );
        }
    }
    for (source, lanes) in eval_on_every_kernel_set(&c, &wo, &wi) {
        let mut limit = (0.0, 0.0);
        for (k, &([value, ..], pdf)) in lanes.iter().enumerate() {
            let (o, i) = (V::from32(wo[k]), V::from32(wi[k]));
            let at = format!("{what} {source}: wo {:?} wi {:?}", wo[k], wi[k]);
            assert!(
                value.is_finite() && pdf.is_finite() && value >= 0.0 && pdf >= 0.0,
                "{at}: value {value:e} pdf {pdf:e}"
            );
            if k % zs.len() == 0 {
                // The same pair as |wo.z| -> 0 on this side, in f64 far below f32's range.
                let edge = V::new(o.x, o.y, 0.0).normalize();
                limit = reference(V::new(edge.x, edge.y, 1e-150f64.copysign(o.z)), i);
            }
            if o.z == 0.0 {
                assert_eq!((value, pdf), (0.0, 0.0), "{at}: in the surface");
                continue;
            }
            let (want, want_pdf) = reference(o, i);
            for (got, want, limit, q) in [
                (value, want, limit.0, "value"),
                (pdf, want_pdf, limit.1, "pdf"),
            ] {
                let got = f64::from(got);
                assert!(
                    close(got, want, 2e-4, 1e-9),
                    "{at}: {q} {got:e}, reference {want:e}"
                );
                // Continuous down to the limit: within 1e-4 of it once |cos_o| < 1e-7.
                if o.z.abs() < 1e-7 {
                    assert!(
                        close(got, limit, 1e-4, 1e-9),
                        "{at}: {q} {got:e}, limit {limit:e}"
                    );
                }
            }
        }
    }
}

fn grazing_params(name: &str, ndf: Ndf, roughness: f32, anisotropic: f32) -> Block {
    Block::defaults(lobe(name))
        .choice("distribution", ndf.name())
        .float("roughness", roughness)
        .float("anisotropic", anisotropic)
}

const GRAZING_CASES: [(f32, f32); 4] = [(0.1, 0.0), (0.5, 0.0), (0.3, 0.8), (1.0, 1.0)];

#[test]
fn conductor_at_grazing_wo_follows_the_reference_to_its_limit() {
    let (f0, f90) = ([0.9, 0.5, 0.04], [1.0, 1.0, 1.0]);
    let fresnel = Fresnel::schlick(f0, f90);
    let wis = [
        V::new(-0.6, 0.0, 0.8),
        V::new(0.3, -0.4, 0.866),
        V::new(-0.98, 0.1, 0.17),
    ];
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for (r, an) in GRAZING_CASES {
            let block = grazing_params("conductor", ndf, r, an)
                .choice("fresnel", "schlick")
                .rgb("f0", f0)
                .rgb("f90", f90);
            let m = Micro::from_roughness(ndf, r, an);
            let reference = |o: V, i: V| {
                let (v, p) = cook_torrance(&m, &fresnel, o, i);
                (v[0], p)
            };
            let what = format!("conductor {ndf:?} r {r} aniso {an}");
            check_grazing("conductor", &block, &reference, &wis, &what);
        }
    }
}

#[test]
fn dielectric_at_grazing_wo_follows_the_reference_to_its_limit() {
    // Reflection and transmission, from outside and (wo below) from inside.
    let wis = [
        V::new(-0.6, 0.0, 0.8),
        V::new(0.3, -0.4, 0.866),
        V::new(0.3, -0.4, -0.866),
        V::new(-0.5, 0.1, -0.86),
        V::new(-0.6, 0.0, -0.8),
    ];
    for ndf in [Ndf::Ggx, Ndf::Beckmann] {
        for (r, an) in GRAZING_CASES {
            for eta in [1.5f32, 0.7] {
                let block = grazing_params("dielectric", ndf, r, an).float("eta", eta);
                let m = Micro::from_roughness(ndf, r, an);
                let reference = |o: V, i: V| walter(&m, f64::from(eta), o, i, false);
                let what = format!("dielectric {ndf:?} r {r} aniso {an} eta {eta}");
                check_grazing("dielectric", &block, &reference, &wis, &what);
            }
        }
    }
}

/// A unit vector from three uniforms, rounded to f32 and normalized as the closure
/// calls and batches do.
fn sphere(rng: &mut Rng) -> Vec3<f32> {
    let z = 1.0 - 2.0 * rng.f64();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.f64();
    let v = V::new(r * phi.cos(), r * phi.sin(), z).to32();
    Vec3::try_unit(v.x, v.y, v.z, "w").unwrap()
}

#[test]
fn dielectric_over_the_eta_range_matches_the_reference_on_every_isa() {
    let mut rng = Rng::new(12);
    let n = 3000;
    let wo: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    let wi: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    for eta in [0.001f32, 0.01, 0.1, 0.5, 0.9, 1.1, 2.0, 10.0, 100.0, 1000.0] {
        for ndf in [Ndf::Ggx, Ndf::Beckmann] {
            for r in [0.2f32, 0.6] {
                let block = grazing_params("dielectric", ndf, r, 0.0).float("eta", eta);
                let m = Micro::from_roughness(ndf, r, 0.0);
                let c = closure("dielectric", &block, Frame::IDENTITY);
                let results = eval_on_every_kernel_set(&c, &wo, &wi);
                let scalar = &results[0].1;
                for (source, lanes) in &results {
                    let (mut worst_ref, mut worst_scalar) = (0.0f64, 0.0f64);
                    for k in 0..n {
                        // Normalized in f64: at extreme eta, F hangs on 1 - (wo.m)^2 ~ 1e-6,
                        // which the ~1e-8 by which an f32 unit vector is not unit would shift.
                        let (o, i) = (V::from32(wo[k]).normalize(), V::from32(wi[k]).normalize());
                        let (want, want_pdf) = walter(&m, f64::from(eta), o, i, false);
                        let ([value, ..], pdf) = lanes[k];
                        worst_ref = worst_ref
                            .max(batch_difference(value, want as f32))
                            .max(batch_difference(pdf, want_pdf as f32));
                        worst_scalar = worst_scalar
                            .max(batch_difference(value, scalar[k].0[0]))
                            .max(batch_difference(pdf, scalar[k].1));
                    }
                    let what = format!("eta {eta} {ndf:?} r {r} {source}");
                    println!("{what}: reference {worst_ref:.2e}, scalar {worst_scalar:.2e}");
                    assert!(
                        worst_ref <= 1e-3,
                        "{what}: {worst_ref:.3e} from the reference"
                    );
                    assert!(
                        worst_scalar <= BATCH_TOLERANCE,
                        "{what}: {worst_scalar:.3e} from the scalar call"
                    );
                }
            }
        }
    }
}
