//! Material batches: a sample's value and pdf are the material's eval at the `wi` it
//! returns, as a host passes it back to `glint_material_eval_batch`, on every ISA.

mod common;

use common::{Rng, soa, soa_mut};
use glint::batch::material::{self, MaterialInput};
use glint::batch::{EvalOutput, Exec, SampleOutput, SampleRandoms, Threads};
use glint::math::Vec3;
use glint::registry::Registry;
use glint::simd::Kernels;

fn sphere(rng: &mut Rng) -> Vec3<f32> {
    let z = 2.0 * rng.f32() - 1.0;
    let phi = std::f32::consts::TAU * rng.f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `n` random normals and a view direction on the side of each.
fn normals_and_views(rng: &mut Rng, n: usize) -> (Vec<Vec3<f32>>, Vec<Vec3<f32>>) {
    let normal: Vec<Vec3<f32>> = (0..n).map(|_| sphere(rng)).collect();
    let wo = normal
        .iter()
        .map(|&nrm| {
            let d = sphere(rng);
            if d.dot(nrm) < 0.0 { -d } else { d }
        })
        .collect();
    (normal, wo)
}

fn rows(v: &[Vec3<f32>]) -> [Vec<f32>; 3] {
    [
        v.iter().map(|d| d.x).collect(),
        v.iter().map(|d| d.y).collect(),
        v.iter().map(|d| d.z).collect(),
    ]
}

/// Specular at roughness 0 and clearcoat at gloss 1 (both alpha 0.001) peak at the
/// same direction: each is evaluated at the other's samples, where the last bit of
/// `wi` moves its value by 1e-4 unless the batch sees `wi` as an eval does.
#[test]
fn samples_carry_the_eval_at_their_direction() {
    let registry = Registry::with_builtins();
    let description = r#"{"material": "disney", "roughness": 0, "clearcoat": 1,
        "clearcoat_gloss": 1, "metallic": 0.3, "sheen": 0.5}"#;
    let material = glint::json::material_from_json(&registry, description, 0.0).unwrap();
    let n = 3000;
    let mut rng = Rng::new(0xba7c);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let (wo, normal) = (rows(&wo), rows(&normal));
    let u: Vec<Vec<f32>> = (0..3)
        .map(|_| (0..n).map(|_| rng.f32()).collect())
        .collect();
    let input = MaterialInput {
        count: n,
        material: &material,
        active: None,
        wo: soa(&wo),
        normal: soa(&normal),
        tangent: None,
        overrides: &[],
    };
    let mut compared = 0;
    let mut worst = 0.0f64;
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let mut wi = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let (mut weight, mut value) = (wi.clone(), wi.clone());
        let mut pdf = vec![0.0; n];
        let mut flags = vec![0u32; n];
        material::sample(
            &exec,
            &input,
            SampleRandoms {
                u_lobe: &u[0],
                u0: &u[1],
                u1: &u[2],
            },
            SampleOutput {
                wi: soa_mut(&mut wi),
                pdf: &mut pdf,
                weight: soa_mut(&mut weight),
                value: Some(soa_mut(&mut value)),
                flags: Some(&mut flags),
                lobe: None,
                component: None,
                eta: None,
                roughness: None,
            },
        )
        .unwrap();
        let mut e_value = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut e_pdf = vec![0.0; n];
        // Failed samples (wi = 0) are error lanes for eval; the rest are computed.
        let _ = material::eval(
            &exec,
            &input,
            soa(&wi),
            EvalOutput {
                value: soa_mut(&mut e_value),
                pdf: &mut e_pdf,
                pdf_reverse: None,
            },
        );
        let rel =
            |a: f32, b: f32| f64::from((a - b).abs()) / f64::from(a.abs().max(b.abs()).max(1e-30));
        for i in 0..n {
            if flags[i] == 0 || flags[i] & glint::lobes::flags::SPECULAR != 0 {
                continue;
            }
            worst = (0..3)
                .map(|c| rel(value[c][i], e_value[c][i]))
                .fold(rel(pdf[i], e_pdf[i]), f64::max)
                .max(worst);
            compared += 1;
        }
    }
    assert!(compared > 2000, "{compared} samples compared");
    assert!(worst < 5e-7, "sample vs eval at the returned wi: {worst:e}");
}

/// A hostile batch: lanes with a NaN normal, a zero-length tangent, a NaN and an
/// out-of-range override each get zero outputs, the lowest such lane's first error
/// (in the order a single shading point checks: wo, normal, tangent, overrides) is
/// reported, and every other lane equals the closure `Material::closure` builds for
/// it, given tangents and automatic ones mixed.
#[test]
fn failing_lanes_are_zeroed_and_the_rest_match_their_closures() {
    use glint::materials::Override;
    use glint::math::Frame;
    use glint::params::ParamKind;
    let registry = Registry::with_builtins();
    let description = r#"{"material": "disney", "metallic": 0.4, "clearcoat": 0.7,
        "sheen": 0.5, "anisotropic": 0.6, "subsurface": 0.3}"#;
    let material = glint::json::material_from_json(&registry, description, 1e-3).unwrap();
    let index = |name: &str| {
        let specs = material.kind().params();
        specs.iter().position(|s| s.name == name).unwrap() as u32
    };
    let n = 300;
    let mut rng = Rng::new(0xfa11);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let wi: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    // Every third lane leaves the tangent to the library (all zero).
    let tangent: Vec<Vec3<f32>> = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                Vec3::new(0.0, 0.0, 0.0)
            } else {
                sphere(&mut rng)
            }
        })
        .collect();
    let mut rough: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let mut color = [0; 3].map(|_| (0..n).map(|_| rng.f32()).collect::<Vec<f32>>());
    let (wo, wi, mut normal, mut tangent) = (rows(&wo), rows(&wi), rows(&normal), rows(&tangent));
    normal[0][7] = f32::NAN;
    rough[7] = 2.0;
    tangent[0][9] = 1e-30;
    (tangent[1][9], tangent[2][9]) = (0.0, 0.0);
    rough[20] = f32::NAN;
    color[1][40] = -1.0;
    let bad = [7, 9, 20, 40];
    let run = |normal: &[Vec<f32>; 3], tangent: &[Vec<f32>; 3], rough: &[f32]| {
        let overrides = [
            material::OverrideLanes {
                param: index("roughness"),
                kind: ParamKind::Float,
                value: [rough, rough, rough],
            },
            material::OverrideLanes {
                param: index("base_color"),
                kind: ParamKind::Rgb,
                value: [&color[0], &color[1], &color[2]],
            },
        ];
        let input = MaterialInput {
            count: n,
            material: &material,
            active: None,
            wo: soa(&wo),
            normal: soa(normal),
            tangent: Some(soa(tangent)),
            overrides: &overrides,
        };
        let exec = Exec {
            kernels: *Kernels::available().last().unwrap(),
            threads: Threads::Caller,
        };
        let mut value = [vec![-1.0; n], vec![-1.0; n], vec![-1.0; n]];
        let mut pdf = vec![-1.0; n];
        let result = material::eval(
            &exec,
            &input,
            soa(&wi),
            EvalOutput {
                value: soa_mut(&mut value),
                pdf: &mut pdf,
                pdf_reverse: None,
            },
        );
        (result.err().map(|e| e.message), value, pdf)
    };
    let (error, value, pdf) = run(&normal, &tangent, &rough);
    let error = error.expect("the batch reports its failing lanes");
    assert!(error.starts_with("lane 7: normal"), "{error}");
    for i in 0..n {
        let v = [value[0][i], value[1][i], value[2][i], pdf[i]];
        if bad.contains(&i) {
            assert_eq!(v, [0.0; 4], "failed lane {i}");
            continue;
        }
        let nrm = Vec3::new(normal[0][i], normal[1][i], normal[2][i]);
        let t = Vec3::new(tangent[0][i], tangent[1][i], tangent[2][i]);
        let t = (t.length_squared() > 0.0).then(|| t.normalize());
        let ctx = glint::materials::ShadingContext::new(
            Vec3::new(wo[0][i], wo[1][i], wo[2][i]).normalize(),
            Frame::new(nrm, t),
        );
        let overrides = [
            Override {
                param: index("roughness"),
                kind: ParamKind::Float,
                value: [rough[i], 0.0, 0.0],
            },
            Override {
                param: index("base_color"),
                kind: ParamKind::Rgb,
                value: [color[0][i], color[1][i], color[2][i]],
            },
        ];
        let closure = material.closure(&ctx, &overrides).unwrap();
        let e = closure
            .eval_forward(ctx.wo, Vec3::new(wi[0][i], wi[1][i], wi[2][i]))
            .unwrap();
        let want = [e.value.r, e.value.g, e.value.b, e.pdf];
        for (a, b) in v.iter().zip(want) {
            assert!(
                (a - b).abs() <= 2e-5 * b.abs().max(1e-3),
                "lane {i}: batch {v:?}, closure {want:?}"
            );
        }
    }
    // With lane 7 repaired, lane 9's tangent is the first error, then lane 20's override.
    (normal[0][7], rough[7]) = (0.0, 0.5);
    let (error, ..) = run(&normal, &tangent, &rough);
    assert!(
        error.as_deref().unwrap().starts_with("lane 9: tangent"),
        "{error:?}"
    );
    tangent[0][9] = 1.0;
    let (error, ..) = run(&normal, &tangent, &rough);
    let error = error.unwrap();
    assert!(error.starts_with("lane 20: overrides[0]"), "{error}");
}
