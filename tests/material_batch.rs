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
    let normal: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    let wo: Vec<Vec3<f32>> = normal
        .iter()
        .map(|&nrm| {
            let d = sphere(&mut rng);
            if d.dot(nrm) < 0.0 { -d } else { d }
        })
        .collect();
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
