//! Material batches: a sample's value and pdf are the material's eval at the `wi` it
//! returns, as a host passes it back to `glint_material_eval_batch`, on every ISA.

mod common;

use common::{Rng, soa, soa_mut};
use glint::batch::material::{self, MaterialInput};
use glint::batch::{EvalOutput, Exec, SampleOutput, SampleRandoms, Soa3Mut, Threads};
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

/// Random tangents, every `every`-th lane (from lane 0) left to the library (all zero).
fn tangents(rng: &mut Rng, n: usize, every: usize) -> Vec<Vec3<f32>> {
    (0..n)
        .map(|i| {
            if i % every == 0 {
                Vec3::new(0.0, 0.0, 0.0)
            } else {
                sphere(rng)
            }
        })
        .collect()
}

fn rows(v: &[Vec3<f32>]) -> [Vec<f32>; 3] {
    [
        v.iter().map(|d| d.x).collect(),
        v.iter().map(|d| d.y).collect(),
        v.iter().map(|d| d.z).collect(),
    ]
}

/// A sample's value and pdf are the material's eval at its `wi`, to the bit. Specular
/// at roughness 0 and clearcoat at gloss 1 (both alpha 0.001) peak at the same
/// direction: each is evaluated at the other's samples, where the last bit of `wi`
/// moves its value by 1e-4 unless the batch sees `wi` as an eval does.
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
        for i in 0..n {
            if flags[i] == 0 || flags[i] & glint::lobes::flags::SPECULAR != 0 {
                continue;
            }
            let isa = kernels.isa();
            assert_eq!(
                pdf[i].to_bits(),
                e_pdf[i].to_bits(),
                "{isa:?}: lane {i} pdf"
            );
            for c in 0..3 {
                let (s, e) = (value[c][i], e_value[c][i]);
                assert_eq!(s.to_bits(), e.to_bits(), "{isa:?}: lane {i} value {s} {e}");
            }
            compared += 1;
        }
    }
    assert!(compared > 2000, "{compared} samples compared");
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
    let index = |name: &str| common::param_index(&material, name);
    let n = 300;
    let mut rng = Rng::new(0xfa11);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let wi: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    // Every third lane leaves the tangent to the library.
    let tangent = tangents(&mut rng, n, 3);
    let mut rough: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let mut color = [0; 3].map(|_| (0..n).map(|_| rng.f32()).collect::<Vec<f32>>());
    let (mut wo, wi, mut normal, mut tangent) =
        (rows(&wo), rows(&wi), rows(&normal), rows(&tangent));
    // Valid lanes of the second chunk whose lengths are outside the range the batch
    // kernels normalize (squared lengths above 1e24, some overflowing f32; below 1e-24
    // a direction is an error): staged, they match their closures.
    for c in 0..3 {
        (wo[c][270], wo[c][275]) = (wo[c][270] * 1e15, wo[c][275] * 1e25);
        (normal[c][280], normal[c][285]) = (normal[c][280] * 1e13, normal[c][285] * 1e20);
    }
    normal[0][7] = f32::NAN;
    rough[7] = 2.0;
    tangent[0][9] = 1e-30;
    (tangent[1][9], tangent[2][9]) = (0.0, 0.0);
    rough[20] = f32::NAN;
    color[1][40] = -1.0;
    let bad = [7, 9, 20, 40];
    let run = |normal: &[Vec<f32>; 3],
               tangent: Option<&[Vec<f32>; 3]>,
               rough: &[f32],
               color: &[Vec<f32>; 3]| {
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
            tangent: tangent.map(soa),
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
        let error = result.err().map(|e| e.message);
        // Samples and albedos stage the same lanes (from the caller's arrays too
        // without tangents): the same first error.
        let half = vec![0.5f32; n];
        let mut rows: [Vec<f32>; 7] = std::array::from_fn(|_| vec![0.0f32; n]);
        let [x, y, z, wx, wy, wz, p] = &mut rows;
        let sampled = material::sample(
            &exec,
            &input,
            SampleRandoms {
                u_lobe: &half,
                u0: &half,
                u1: &half,
            },
            SampleOutput {
                wi: Soa3Mut { x, y, z },
                pdf: p,
                weight: Soa3Mut {
                    x: wx,
                    y: wy,
                    z: wz,
                },
                value: None,
                flags: None,
                lobe: None,
                component: None,
                eta: None,
                roughness: None,
            },
        );
        assert_eq!(sampled.err().map(|e| e.message), error, "sample");
        let albedo = material::albedo(&exec, &input, Soa3Mut { x, y, z });
        assert_eq!(albedo.err().map(|e| e.message), error, "albedo");
        (error, value, pdf)
    };
    // Without tangents the chunks are taken from the caller's arrays in one pass
    // (`batch::material::eval_raw`, `stage_raw`) until a lane fails; lane 9 does not
    // fail then.
    for with_tangents in [true, false] {
        let tangents = with_tangents.then_some(&tangent);
        let (error, value, pdf) = run(&normal, tangents, &rough, &color);
        let error = error.expect("the batch reports its failing lanes");
        assert!(error.starts_with("lane 7: normal"), "{error}");
        for i in 0..n {
            let v = [value[0][i], value[1][i], value[2][i], pdf[i]];
            if bad.contains(&i) && (with_tangents || i != 9) {
                assert_eq!(v, [0.0; 4], "failed lane {i}");
                continue;
            }
            // The library's rule for any length (`Vec3::try_unit`).
            let unit = |v: &[Vec<f32>; 3]| Vec3::try_unit(v[0][i], v[1][i], v[2][i], "v").unwrap();
            let nrm = unit(&normal);
            let t = tangents.map(|t| Vec3::new(t[0][i], t[1][i], t[2][i]));
            let t = t
                .filter(|t| t.length_squared() > 0.0)
                .map(|t| t.normalize());
            let ctx = glint::materials::ShadingContext::new(unit(&wo), Frame::new(nrm, t));
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
    }
    // With lane 7 repaired, lane 9's tangent is the first error, then lane 20's override.
    (normal[0][7], rough[7]) = (0.0, 0.5);
    let (error, ..) = run(&normal, Some(&tangent), &rough, &color);
    assert!(
        error.as_deref().unwrap().starts_with("lane 9: tangent"),
        "{error:?}"
    );
    tangent[0][9] = 1.0;
    for tangents in [Some(&tangent), None] {
        let (error, ..) = run(&normal, tangents, &rough, &color);
        let error = error.unwrap();
        assert!(error.starts_with("lane 20: overrides[0]"), "{error}");
    }
    // Each bound of an override's range, on both paths.
    rough[20] = 0.5;
    for tangents in [Some(&tangent), None] {
        let (error, ..) = run(&normal, tangents, &rough, &color);
        let error = error.unwrap();
        assert!(error.starts_with("lane 40: overrides[1]"), "{error}");
    }
    (rough[7], color[1][40]) = (1.5, 0.5);
    for tangents in [Some(&tangent), None] {
        let (error, ..) = run(&normal, tangents, &rough, &color);
        let error = error.unwrap();
        assert!(error.starts_with("lane 7: overrides[0]"), "{error}");
    }
}

/// Per-lane parameters of a batch: name and one row per component.
type LaneParams = Vec<(&'static str, Vec<Vec<f32>>)>;

/// Samples, evals and albedos of a batch over `description` (pruned at `prune`) equal
/// those of the closure `Material::closure` builds per lane, on every ISA, for
/// consecutive lanes and for lanes an active mask scatters, random views, normals,
/// tangents (every other one automatic) and the per-lane `params`; `u_lobe` NaN or
/// infinite on lanes 5, 6 and 8 (when there are) fails those lanes as
/// `Closure::sample` fails (the batch's error names lane 5). Returns each lane's
/// closure's lobe count and whether its albedo's luminance is below `prune`.
fn matches_closures(
    description: &str,
    prune: f32,
    n: usize,
    seed: u64,
    params: impl Fn(&mut Rng) -> LaneParams,
) -> Vec<(usize, bool)> {
    use glint::materials::{Override, ShadingContext};
    use glint::math::Frame;
    use glint::params::ParamKind;
    let registry = Registry::with_builtins();
    let material = glint::json::material_from_json(&registry, description, prune).unwrap();
    let index = |name: &str| common::param_index(&material, name);
    let mut rng = Rng::new(seed);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let tangent = tangents(&mut rng, n, 2);
    let wi: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    let (wo, wi, normal, tangent) = (rows(&wo), rows(&wi), rows(&normal), rows(&tangent));
    let params = params(&mut rng);
    let mut u = [0; 3].map(|_| (0..n).map(|_| rng.f32()).collect::<Vec<f32>>());
    for (lane, x) in [(5, f32::NAN), (6, f32::INFINITY), (8, f32::NEG_INFINITY)] {
        if lane < n {
            u[0][lane] = x;
        }
    }
    let kind = |rows: &[Vec<f32>]| {
        if rows.len() == 3 {
            ParamKind::Rgb
        } else {
            ParamKind::Float
        }
    };
    let overrides: Vec<material::OverrideLanes<'_>> = params
        .iter()
        .map(|(name, rows)| material::OverrideLanes {
            param: index(name),
            kind: kind(rows),
            value: [0, 1, 2].map(|c| rows.get(c).map_or(&[][..], |r| &r[..])),
        })
        .collect();
    let closure = |i: usize, with_tangent: bool| {
        let t = Vec3::new(tangent[0][i], tangent[1][i], tangent[2][i]);
        let t = (with_tangent && t.length_squared() > 0.0).then(|| t.normalize());
        let nrm = Vec3::new(normal[0][i], normal[1][i], normal[2][i]);
        let ctx = ShadingContext::new(
            Vec3::new(wo[0][i], wo[1][i], wo[2][i]).normalize(),
            Frame::new(nrm, t),
        );
        let per_lane: Vec<Override> = params
            .iter()
            .map(|(name, rows)| Override {
                param: index(name),
                kind: kind(rows),
                value: [0, 1, 2].map(|c| rows.get(c).map_or(0.0, |r| r[i])),
            })
            .collect();
        (material.closure(&ctx, &per_lane).unwrap(), ctx.wo)
    };
    let near = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * b.abs().max(1e-3);
    let active: Vec<u8> = (0..n).map(|i| u8::from(i % 3 != 1)).collect();
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        // Without a mask or tangents, evals take the chunks from the caller's arrays
        // (`batch::material::eval_raw`).
        let runs = [(None, true), (Some(&active[..]), true), (None, false)];
        for (mask, with_tangent) in runs {
            let input = MaterialInput {
                count: n,
                material: &material,
                active: mask,
                wo: soa(&wo),
                normal: soa(&normal),
                tangent: with_tangent.then(|| soa(&tangent)),
                overrides: &overrides,
            };
            let is_active = |i: usize| mask.is_none_or(|m| m[i] != 0);
            let mut s_wi = [vec![-1.0; n], vec![-1.0; n], vec![-1.0; n]];
            let (mut weight, mut value, mut albedo) = (s_wi.clone(), s_wi.clone(), s_wi.clone());
            let (mut pdf, mut eta) = (vec![-1.0; n], vec![-1.0; n]);
            let (mut flags, mut component) = (vec![99u32; n], vec![99u32; n]);
            let randoms = SampleRandoms {
                u_lobe: &u[0],
                u0: &u[1],
                u1: &u[2],
            };
            let out = SampleOutput {
                wi: soa_mut(&mut s_wi),
                pdf: &mut pdf,
                weight: soa_mut(&mut weight),
                value: Some(soa_mut(&mut value)),
                flags: Some(&mut flags),
                lobe: None,
                component: Some(&mut component),
                eta: Some(&mut eta),
                roughness: None,
            };
            let sampled = material::sample(&exec, &input, randoms, out);
            if n > 5 {
                let e = sampled.unwrap_err().message;
                assert!(e.starts_with("lane 5: random number 0 (NaN)"), "{e}");
            } else {
                sampled.unwrap();
            }
            material::albedo(&exec, &input, soa_mut(&mut albedo)).unwrap();
            let mut e_value = [vec![-1.0; n], vec![-1.0; n], vec![-1.0; n]];
            let mut e_pdf = vec![-1.0; n];
            let out = EvalOutput {
                value: soa_mut(&mut e_value),
                pdf: &mut e_pdf,
                pdf_reverse: None,
            };
            material::eval(&exec, &input, soa(&wi), out).unwrap();
            let isa = kernels.isa().name();
            for i in (0..n).filter(|&i| is_active(i)) {
                let (c, wo) = closure(i, with_tangent);
                let want = c.sample(wo, [u[0][i], u[1][i], u[2][i]]);
                let got_ok = pdf[i] > 0.0;
                let what = format!(
                    "{isa}, mask {}, tangents {with_tangent}, lane {i}",
                    mask.is_some()
                );
                match want {
                    Ok(s) => {
                        assert!(got_ok, "{what}: closure sampled, batch failed");
                        assert_eq!((flags[i], component[i]), (s.flags, s.component), "{what}");
                        let got = [s_wi[0][i], s_wi[1][i], s_wi[2][i]];
                        for (a, b) in got.iter().zip([s.wi.x, s.wi.y, s.wi.z]) {
                            assert!((a - b).abs() <= 1e-4, "{what}: wi {got:?} vs {:?}", s.wi);
                        }
                        let got = [weight[0][i], weight[1][i], weight[2][i], eta[i], pdf[i]];
                        let want = [s.weight.r, s.weight.g, s.weight.b, s.eta, s.pdf];
                        for (k, (&a, b)) in got.iter().zip(want).enumerate() {
                            // The batch's pdf is at `wi` normalized once more (see
                            // `samples_carry_the_eval_at_their_direction`): 2e-4 at
                            // alpha 0.001; weights are ratios, and do not move.
                            let tol = if k == 4 { 1e-3 } else { 1e-4 };
                            assert!(near(a, b, tol), "{what}: {got:?} vs {want:?}");
                        }
                        assert!(value.iter().all(|v| v[i].is_finite()), "{what}");
                    }
                    Err(_) => assert!(!got_ok && weight.iter().all(|w| w[i] == 0.0), "{what}"),
                }
                let a = c.albedo(wo).unwrap();
                let e = c
                    .eval_forward(wo, Vec3::new(wi[0][i], wi[1][i], wi[2][i]).normalize())
                    .unwrap();
                let got = [albedo[0][i], albedo[1][i], albedo[2][i]];
                let got =
                    got.into_iter()
                        .chain([e_value[0][i], e_value[1][i], e_value[2][i], e_pdf[i]]);
                let want = [a.r, a.g, a.b, e.value.r, e.value.g, e.value.b, e.pdf];
                for (a, b) in got.zip(want) {
                    assert!(near(a, b, 2e-5), "{what}: albedo and eval {a} vs {b}");
                }
            }
            // Inactive lanes are left alone.
            for i in (0..n).filter(|&i| !is_active(i)) {
                assert_eq!(
                    (pdf[i], e_pdf[i], albedo[0][i], flags[i]),
                    (-1.0, -1.0, -1.0, 99)
                );
            }
        }
    }
    (0..n)
        .map(|i| {
            let (c, wo) = closure(i, true);
            (c.lobes().len(), c.albedo(wo).unwrap().luminance() < prune)
        })
        .collect()
}

/// Pruning keeps several slots on some lanes, one on others, and on others falls back
/// to the strongest pruned slot (a closure of one lobe whose albedo's luminance is
/// below the threshold): a threshold of 0.2 over random base colors and views.
/// Per-lane roughness uniform in [0, 1) and base color channels `u^power` (dark lanes
/// more often with a higher power).
fn roughness_and_color(rng: &mut Rng, n: usize, power: i32) -> LaneParams {
    vec![
        ("roughness", vec![(0..n).map(|_| rng.f32()).collect()]),
        (
            "base_color",
            (0..3)
                .map(|_| (0..n).map(|_| rng.f32().powi(power)).collect())
                .collect(),
        ),
    ]
}

#[test]
fn pruned_lanes_sample_eval_and_albedo_as_their_closures() {
    let description = r#"{"material": "disney", "metallic": 0.2, "clearcoat": 0.6,
        "sheen": 0.8, "anisotropic": 0.5, "subsurface": 0.4, "clearcoat_gloss": 0.7}"#;
    let outcomes = matches_closures(description, 0.2, 400, 0x5e1e, |rng| {
        roughness_and_color(rng, 400, 3)
    });
    assert!(outcomes.iter().any(|&(k, _)| k > 1));
    assert!(outcomes.contains(&(1, false)) && outcomes.contains(&(1, true)));
}

/// Slots emitted on some lanes only (diffuse off where metallic is 1, clearcoat off
/// where it is 0), one emitted on none (sheen 0), over one register and a tail.
#[test]
fn slots_emitted_on_some_lanes_match_their_closures() {
    let description = r#"{"material": "disney", "sheen": 0, "roughness": 0.4}"#;
    let outcomes = matches_closures(description, 0.0, 17, 0xe1, |_| {
        vec![
            ("metallic", vec![(0..17).map(|i| (i % 2) as f32).collect()]),
            (
                "clearcoat",
                vec![(0..17).map(|i| (i % 3 / 2) as f32).collect()],
            ),
        ]
    });
    let counts: Vec<usize> = outcomes.iter().map(|&(k, _)| k).collect();
    assert!(
        counts.contains(&1) && counts.contains(&2) && counts.contains(&3),
        "{counts:?}"
    );
}

/// Metals without clearcoat weight the specular alone on every lane: the closure and
/// the batch add it without an albedo estimate, kept whatever its share (a prune of
/// 0.9 is above it on dark lanes) and chosen with probability 1; per-lane roughness and
/// base color, over registers and a tail.
#[test]
fn lanes_weighting_one_slot_alone_match_their_closures() {
    let description = r#"{"material": "disney", "metallic": 1, "anisotropic": 0.3}"#;
    let outcomes = matches_closures(description, 0.9, 37, 0x3e7a, |rng| {
        roughness_and_color(rng, 37, 2)
    });
    assert!(outcomes.iter().all(|&(k, _)| k == 1), "{outcomes:?}");
    assert!(outcomes.iter().any(|&(_, below)| below), "{outcomes:?}");
}

/// Per-lane anisotropy at the specular estimate's aspect nodes: a closure finds the
/// nearest node by binary search, the batch by counting comparisons (or by the binary
/// search where a register's lanes share the value); the two agree on
/// each midpoint between nodes and on the floats either side of it (midpoints from
/// the table's node formula, `anisotropic = (1 - 10^-x) / 0.9` at `x = (k + 1/2) / 12`).
#[test]
fn per_lane_anisotropy_at_the_estimate_nodes_matches_the_closures() {
    let description = r#"{"material": "disney", "anisotropic": 0.5, "roughness": 0.3}"#;
    let mut values = Vec::new();
    for k in 0..12 {
        let x = (k as f64 + 0.5) / 12.0;
        let m = ((1.0 - 10f64.powf(-x)) / 0.9) as f32;
        values.extend([m.next_down(), m, m.next_up()]);
    }
    values.extend([0.0, 1e-30, 0.5, 1.0]);
    let n = values.len() * 3;
    let anisotropic: Vec<f32> = (0..n).map(|i| values[i % values.len()]).collect();
    matches_closures(description, 0.0, n, 0xa150, |_| {
        vec![("anisotropic", vec![anisotropic.clone()])]
    });
    // The same value on every lane: the batch takes one binary search per register.
    for &v in &values {
        matches_closures(description, 0.0, 17, 0xa151, |_| {
            vec![("anisotropic", vec![vec![v; 17]])]
        });
    }
}

/// Views on either side of each boundary between the specular estimate's azimuth
/// nodes (found by bisection on a closure's pdf, which jumps there by the estimate's
/// step): a batch selects as the closures do, on every ISA, to the last float of `wo`.
#[test]
fn views_at_the_estimate_azimuth_boundaries_match_the_closures() {
    use glint::materials::ShadingContext;
    use glint::math::Frame;
    let registry = Registry::with_builtins();
    let description = r#"{"material": "disney", "anisotropic": 0.7, "roughness": 0.3}"#;
    let material = glint::json::material_from_json(&registry, description, 0.0).unwrap();
    let wi = Vec3::new(0.3f32, -0.2, 0.93).normalize();
    let (mu, st) = (0.1f64, (1.0 - 0.01f64).sqrt());
    let view = |phi: f64| {
        let v = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, mu as f32);
        v.normalize()
    };
    let pdf = |wo: Vec3<f32>| {
        let ctx = ShadingContext::new(wo, Frame::IDENTITY);
        let c = material.closure(&ctx, &[]).unwrap();
        c.eval_forward(wo, wi).unwrap().pdf
    };
    let mut views = Vec::new();
    let mut smallest_step = f32::INFINITY;
    for k in 0..18 {
        let middle = (k as f64 + 0.5) / 18.0 * std::f64::consts::FRAC_PI_2;
        let (mut lo, mut hi) = (middle - 0.01, middle + 0.01);
        let (mut below, mut above) = (pdf(view(lo)), pdf(view(hi)));
        // Toward the step: the pdf also drifts with the view, far less than it steps.
        loop {
            let mid = 0.5 * (lo + hi);
            if view(mid) == view(lo) || view(mid) == view(hi) {
                break;
            }
            let p = pdf(view(mid));
            if (p - below).abs() < (p - above).abs() {
                (lo, below) = (mid, p);
            } else {
                (hi, above) = (mid, p);
            }
        }
        if k > 0 {
            smallest_step = smallest_step.min((below - above).abs() / below);
        }
        views.extend([view(lo), view(hi)]);
    }
    // Each boundary is a step well above the comparison's tolerance (measured: 7e-4 at
    // least), but the first: near the tangent the table's first two azimuths agree.
    assert!(smallest_step > 1e-4, "smallest step {smallest_step:e}");
    let n = views.len();
    let wo = rows(&views);
    let normal = [vec![0.0; n], vec![0.0; n], vec![1.0; n]];
    let wi_rows = rows(&vec![wi; n]);
    let want: Vec<f32> = views.iter().map(|&v| pdf(v)).collect();
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let input = MaterialInput {
            count: n,
            material: &material,
            active: None,
            wo: soa(&wo),
            normal: soa(&normal),
            tangent: None,
            overrides: &[],
        };
        let mut value = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut got = vec![0.0; n];
        let out = EvalOutput {
            value: soa_mut(&mut value),
            pdf: &mut got,
            pdf_reverse: None,
        };
        material::eval(&exec, &input, soa(&wi_rows), out).unwrap();
        for i in 0..n {
            assert!(
                (got[i] - want[i]).abs() <= 2e-5 * want[i],
                "{:?} lane {i}: batch pdf {} vs closure {}",
                kernels.isa(),
                got[i],
                want[i]
            );
        }
    }
}

/// Per-lane clearcoat gloss: the clearcoat's decode takes logarithms in f64, so the
/// expansion decodes a block once and copies it while lanes repeat it. Whole registers
/// of the material's own gloss, of 0, of -0 (the same value, other bits), of a new
/// value and of it again; then lanes that alternate, with -0 beside 0.
#[test]
fn per_lane_clearcoat_gloss_matches_the_closures() {
    let description = r#"{"material": "disney", "clearcoat": 1, "clearcoat_gloss": 0.6}"#;
    let gloss = |i: usize| match i {
        0..16 => 0.6,
        16..32 => 0.0,
        32..48 => -0.0,
        48..80 => 0.25,
        _ => [0.0, -0.0, 0.6, 1.0, 0.25][i % 5],
    };
    let outcomes = matches_closures(description, 0.0, 120, 0x6105, |_| {
        vec![("clearcoat_gloss", vec![(0..120).map(gloss).collect()])]
    });
    assert!(outcomes.iter().all(|&(k, _)| k == 3), "{outcomes:?}");
}

/// A material batch's eval is finished in its staging pass (`kernels::expand`) unless
/// the reverse pdf is wanted, which takes the slots one by one: both give the same
/// bits, value and pdf, and so does the pdf call, for each set of emitted slots (every lobe, no clearcoat, no sheen, diffuse and specular, specular and
/// clearcoat; slots emitted on some lanes only), over per-lane overrides, frames and
/// inactive lanes, on every ISA.
#[test]
fn fused_evals_are_the_slot_by_slot_sums() {
    use glint::params::ParamKind;
    let shapes = [
        r#"{"material": "disney", "sheen": 1, "clearcoat": 1, "subsurface": 0.5, "anisotropic": 0.4}"#,
        r#"{"material": "disney", "sheen": 0.7, "clearcoat": 0}"#,
        r#"{"material": "disney", "sheen": 0, "clearcoat": 0.8, "clearcoat_gloss": 0.3}"#,
        r#"{"material": "disney", "sheen": 0, "clearcoat": 0, "roughness": 0.1}"#,
        r#"{"material": "disney", "metallic": 1, "clearcoat": 1}"#,
    ];
    let registry = Registry::with_builtins();
    // Three chunks: a block in one expansion against the staged chunks.
    let n = 715;
    let mut rng = Rng::new(0xf05e);
    for (s, description) in shapes.iter().enumerate() {
        let material = glint::json::material_from_json(&registry, description, 0.001).unwrap();
        let (normal, wo) = normals_and_views(&mut rng, n);
        let tangent = rows(&tangents(&mut rng, n, 3));
        let wi: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
        let (wo, wi, normal) = (rows(&wo), rows(&wi), rows(&normal));
        let roughness: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
        // Shape 1 with the clearcoat back on a third of the lanes: every lobe there.
        let coat: Vec<f32> = (0..n)
            .map(|i| if s == 1 { (i % 3 / 2) as f32 } else { 0.0 })
            .collect();
        let mut overrides = vec![material::OverrideLanes {
            param: 5,
            kind: ParamKind::Float,
            value: [&roughness, &[], &[]],
        }];
        if s == 1 {
            overrides.push(material::OverrideLanes {
                param: 9,
                kind: ParamKind::Float,
                value: [&coat, &[], &[]],
            });
        }
        let active: Vec<u8> = (0..n).map(|i| u8::from(i % 5 != 2)).collect();
        // Inactive lanes and tangents stage the chunks; without either they are taken
        // from the caller's arrays (`batch::material::eval_raw`).
        for staged in [true, false] {
            let input = MaterialInput {
                count: n,
                material: &material,
                active: staged.then_some(&active[..]),
                wo: soa(&wo),
                normal: soa(&normal),
                tangent: staged.then(|| soa(&tangent)),
                overrides: &overrides,
            };
            for kernels in Kernels::available() {
                let exec = Exec {
                    kernels,
                    threads: Threads::Caller,
                };
                let run = |reverse: bool| {
                    let mut value = [vec![0.0f32; n], vec![0.0; n], vec![0.0; n]];
                    let (mut pdf, mut pdf_reverse) = (vec![0.0f32; n], vec![0.0f32; n]);
                    let out = EvalOutput {
                        value: soa_mut(&mut value),
                        pdf: &mut pdf,
                        pdf_reverse: reverse.then_some(&mut pdf_reverse[..]),
                    };
                    material::eval(&exec, &input, soa(&wi), out).unwrap();
                    (value, pdf)
                };
                let (fused, slot_by_slot) = (run(false), run(true));
                let mut pdf_only = vec![0.0f32; n];
                material::pdf(&exec, &input, soa(&wi), &mut pdf_only).unwrap();
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
                let what = format!("{description} on {}, staged {staged}", kernels.isa().name());
                for c in 0..3 {
                    assert_eq!(
                        bits(&fused.0[c]),
                        bits(&slot_by_slot.0[c]),
                        "value {c}: {what}"
                    );
                }
                assert_eq!(bits(&fused.1), bits(&slot_by_slot.1), "pdf: {what}");
                assert_eq!(bits(&pdf_only), bits(&slot_by_slot.1), "pdf call: {what}");
                assert!(fused.1.iter().any(|&p| p > 0.0), "{what}");
            }
        }
    }
}

/// An eval at several directions per lane, with the albedo asked in the same call
/// (`material::eval_directions`, a scanline host's lights and ambient term), gives
/// each direction what an eval of that direction alone gives and the albedo call's
/// albedos, to the bit, on every ISA: lanes taken in one pass, an active mask, given
/// tangents (staged), a lane failing everywhere (NaN normal), a `wi` failing in one
/// direction only (zero length) and a valid lane outside the raw path's range
/// (staged). The error names the lowest failing lane and its direction.
#[test]
fn several_directions_and_the_albedo_are_each_call_alone() {
    use glint::params::ParamKind;
    let registry = Registry::with_builtins();
    let description = r#"{"material": "disney", "metallic": 0.3, "clearcoat": 0.8,
        "sheen": 0.6, "anisotropic": 0.5, "subsurface": 0.4}"#;
    let material = glint::json::material_from_json(&registry, description, 1e-3).unwrap();
    let index = |name: &str| common::param_index(&material, name);
    let (n, k) = (613, 3);
    let mut rng = Rng::new(0xd1ec);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let wi: Vec<Vec3<f32>> = (0..n * k).map(|_| sphere(&mut rng)).collect();
    let tangent = tangents(&mut rng, n, 3);
    let rough: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let color = [0; 3].map(|_| (0..n).map(|_| rng.f32()).collect::<Vec<f32>>());
    let (mut wo, mut wi, mut normal, tangent) =
        (rows(&wo), rows(&wi), rows(&normal), rows(&tangent));
    let active: Vec<u8> = (0..n).map(|i| u8::from(i % 5 != 2)).collect();
    let overrides = [
        material::OverrideLanes {
            param: index("roughness"),
            kind: ParamKind::Float,
            value: [&rough, &rough, &rough],
        },
        material::OverrideLanes {
            param: index("base_color"),
            kind: ParamKind::Rgb,
            value: [&color[0], &color[1], &color[2]],
        },
    ];
    for hostile in [false, true] {
        if hostile {
            normal[1][300] = f32::NAN;
            (wi[0][n + 290], wi[1][n + 290], wi[2][n + 290]) = (0.0, 0.0, 0.0);
            for row in &mut wo {
                row[450] *= 1e25;
            }
        }
        for (mask, tangents) in [(false, false), (true, false), (false, true)] {
            let input = MaterialInput {
                count: n,
                material: &material,
                active: mask.then_some(&active[..]),
                wo: soa(&wo),
                normal: soa(&normal),
                tangent: tangents.then(|| soa(&tangent)),
                overrides: &overrides,
            };
            let runs = Kernels::available().into_iter();
            for (kernels, reverse) in runs.flat_map(|k| [(k, false), (k, true)]) {
                let exec = Exec {
                    kernels,
                    threads: Threads::Caller,
                };
                let fill = |len: usize| [0; 4].map(|_| vec![-7.0f32; len]);
                let (mut all, mut albedo) = (fill(n * k), fill(n));
                let [r, g, b, p] = &mut all;
                let [ar, ag, ab, _] = &mut albedo;
                // With the reverse pdf, direction by direction over the slots' rows.
                let mut rev = reverse.then(|| vec![-7.0f32; n * k]);
                let result = material::eval_directions(
                    &exec,
                    &input,
                    soa(&wi),
                    k,
                    EvalOutput {
                        value: Soa3Mut { x: r, y: g, z: b },
                        pdf: p,
                        pdf_reverse: rev.as_deref_mut(),
                    },
                    Some(Soa3Mut {
                        x: ar,
                        y: ag,
                        z: ab,
                    }),
                );
                let error = result.err().map(|e| e.message);
                let mut errors = Vec::new();
                for d in 0..k {
                    let at = d * n..(d + 1) * n;
                    let wi_d = [0, 1, 2].map(|c| wi[c][at.clone()].to_vec());
                    let mut one = fill(n);
                    let [r, g, b, p] = &mut one;
                    let mut rev_one = reverse.then(|| vec![-7.0f32; n]);
                    let alone = material::eval(
                        &exec,
                        &input,
                        soa(&wi_d),
                        EvalOutput {
                            value: Soa3Mut { x: r, y: g, z: b },
                            pdf: p,
                            pdf_reverse: rev_one.as_deref_mut(),
                        },
                    );
                    if let (Some(all), Some(one)) = (&rev, &rev_one) {
                        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&all[at.clone()]), bits(one), "reverse pdf, {d}");
                    }
                    errors.push(alone.err().map(|e| e.message.to_string()));
                    for (c, row) in one.iter().enumerate() {
                        let got = &all[c][at.clone()];
                        for j in 0..n {
                            assert_eq!(
                                got[j].to_bits(),
                                row[j].to_bits(),
                                "{kernels:?} mask {mask} tangents {tangents} hostile \
                                 {hostile}: lane {j} direction {d} output {c}"
                            );
                        }
                    }
                }
                let mut one = fill(n);
                let [r, g, b, _] = &mut one;
                let albedo_alone = material::albedo(&exec, &input, Soa3Mut { x: r, y: g, z: b });
                for c in 0..3 {
                    for j in 0..n {
                        assert_eq!(
                            albedo[c][j].to_bits(),
                            one[c][j].to_bits(),
                            "{kernels:?} mask {mask} tangents {tangents}: albedo of lane {j}"
                        );
                    }
                }
                if !hostile {
                    assert_eq!(error, None);
                    assert!(albedo_alone.is_ok());
                    continue;
                }
                // Lane 290's `wi` fails in direction 1 only, before lane 300's normal.
                let errors: Vec<String> = errors.into_iter().map(Option::unwrap).collect();
                assert!(errors[0].starts_with("lane 300: normal"), "{}", errors[0]);
                assert!(errors[1].starts_with("lane 290: wi"), "{}", errors[1]);
                assert_eq!(errors[2], errors[0]);
                let named = format!("direction 1, {}", errors[1]);
                assert_eq!(error.as_deref(), Some(named.as_str()));
                let albedo_error = albedo_alone.unwrap_err().message;
                assert!(
                    albedo_error.starts_with("lane 300: normal"),
                    "{albedo_error}"
                );
            }
        }
    }
}

/// A value overridden twice is checked in both overrides, whichever path takes the
/// lanes: an out-of-range or NaN first override fails its lanes even where the second
/// is valid (the raw path keeps one row per value, so such lanes are staged).
#[test]
fn a_value_overridden_twice_checks_both_overrides() {
    use glint::params::ParamKind;
    let registry = Registry::with_builtins();
    let material =
        glint::json::material_from_json(&registry, r#"{"material": "disney"}"#, 1e-3).unwrap();
    let n = 37;
    let mut rng = Rng::new(0xd0b1);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let wi: Vec<Vec3<f32>> = (0..n).map(|_| sphere(&mut rng)).collect();
    let (wo, wi, normal) = (rows(&wo), rows(&wi), rows(&normal));
    let valid = vec![0.5f32; n];
    for bad in [1.5, f32::NAN] {
        let mut first = vec![0.25f32; n];
        first[11] = bad;
        let overrides = [&first, &valid].map(|row| material::OverrideLanes {
            param: 5,
            kind: ParamKind::Float,
            value: [row, row, row],
        });
        let input = MaterialInput {
            count: n,
            material: &material,
            active: None,
            wo: soa(&wo),
            normal: soa(&normal),
            tangent: None,
            overrides: &overrides,
        };
        for kernels in Kernels::available() {
            let exec = Exec {
                kernels,
                threads: Threads::Caller,
            };
            let mut out = [0; 4].map(|_| vec![-1.0f32; n]);
            let [r, g, b, p] = &mut out;
            let result = material::eval(
                &exec,
                &input,
                soa(&wi),
                EvalOutput {
                    value: Soa3Mut { x: r, y: g, z: b },
                    pdf: p,
                    pdf_reverse: None,
                },
            );
            let error = result.expect_err("lane 11's first override is out of range");
            assert!(
                error.message.starts_with("lane 11: overrides[0]"),
                "{kernels:?}: {}",
                error.message
            );
            for (j, v) in out.iter().map(|row| row[11]).enumerate() {
                assert_eq!(v, 0.0, "{kernels:?}: output {j} of the failed lane");
            }
            // The other lanes take the second override's value, as a closure does.
            let second = MaterialInput {
                overrides: &overrides[1..],
                ..input
            };
            let mut want = [0; 4].map(|_| vec![-1.0f32; n]);
            let [r, g, b, p] = &mut want;
            let output = EvalOutput {
                value: Soa3Mut { x: r, y: g, z: b },
                pdf: p,
                pdf_reverse: None,
            };
            material::eval(&exec, &second, soa(&wi), output).unwrap();
            for (got, want) in out.iter().zip(&want) {
                for j in (0..n).filter(|&j| j != 11) {
                    assert_eq!(got[j].to_bits(), want[j].to_bits(), "{kernels:?}: lane {j}");
                }
            }
            let [r, g, b, _] = &mut out;
            let albedo = material::albedo(&exec, &input, Soa3Mut { x: r, y: g, z: b });
            let message = albedo.expect_err("the albedo checks it too").message;
            assert!(message.starts_with("lane 11: overrides[0]"), "{message}");
        }
    }
}

/// Tangent frames built in the one-pass (raw) path equal the staged path's
/// (`Frame::new` lane by lane), to the bit, on every ISA, for evals (two directions
/// and the albedo), pdfs, samples and albedos: a host's tangents (60 to 90 degrees off
/// the normal, unnormalized, some of length 1e-11), automatic ones (zero and -0), and
/// in the last chunk lanes the raw path leaves to the staged one (a tangent within 30
/// degrees of the normal or along it, of length 1e13); with NaN, denormal, underflowing
/// and infinite tangents, the same error and zeros. Staging is forced by overriding the roughness twice with the same row.
#[test]
fn tangent_frames_in_one_pass_equal_the_staged_ones() {
    use glint::params::ParamKind;
    let registry = Registry::with_builtins();
    let description = r#"{"material": "disney", "metallic": 0.2, "clearcoat": 0.7,
        "sheen": 0.5, "anisotropic": 0.8, "subsurface": 0.3}"#;
    let material = glint::json::material_from_json(&registry, description, 1e-3).unwrap();
    let n = 301;
    let mut rng = Rng::new(0x7a9e);
    let (normal, wo) = normals_and_views(&mut rng, n);
    let mut tangent = tangents(&mut rng, n, 3);
    for (i, t) in tangent.iter_mut().enumerate() {
        let nrm = normal[i];
        // A host's tangents: off the normal by more than 30 degrees (else f64, staged).
        let across = (*t - nrm * nrm.dot(*t)).normalize();
        if t.length_squared() > 0.0 {
            *t = across + nrm * (rng.f32() - 0.5);
        }
        *t = match i % 31 {
            1 => *t * 7.5,
            4 => Vec3::new(-0.0, 0.0, -0.0),
            // In the last chunk only (lanes 256 on; the one-pass path leaves the chunk
            // to the staged one): 10 degrees off the normal, along it, length 1e13.
            7 if i >= 256 => nrm + across * 0.176,
            10 if i >= 256 => nrm,
            13 if i >= 256 => *t * 1e13,
            16 => *t * 1e-11,
            _ => *t,
        };
    }
    let wi: Vec<Vec3<f32>> = (0..2 * n).map(|_| sphere(&mut rng)).collect();
    let rough: Vec<f32> = (0..n).map(|_| rng.f32()).collect();
    let u = [0; 3].map(|_| (0..n).map(|_| rng.f32()).collect::<Vec<f32>>());
    let (wo, wi, normal, mut tangent) = (rows(&wo), rows(&wi), rows(&normal), rows(&tangent));
    let roughness = material::OverrideLanes {
        param: common::param_index(&material, "roughness"),
        kind: ParamKind::Float,
        value: [&rough, &rough, &rough],
    };
    let twice = [roughness, roughness];
    type Outputs = (Option<String>, Vec<Vec<u32>>);
    let run = |exec: &Exec<'_>, input: &MaterialInput<'_>| -> Outputs {
        let fill = |len: usize| [0; 4].map(|_| vec![-7.0f32; len]);
        let (mut e, mut albedo) = (fill(2 * n), fill(n));
        let [r, g, b, p] = &mut e;
        let [ar, ag, ab, _] = &mut albedo;
        let mut errors = vec![material::eval_directions(
            exec,
            input,
            soa(&wi),
            2,
            EvalOutput {
                value: Soa3Mut { x: r, y: g, z: b },
                pdf: p,
                pdf_reverse: None,
            },
            Some(Soa3Mut {
                x: ar,
                y: ag,
                z: ab,
            }),
        )];
        let [r, g, b, p] = &mut albedo;
        errors.push(material::albedo(exec, input, Soa3Mut { x: r, y: g, z: b }));
        let one: [Vec<f32>; 3] = [0, 1, 2].map(|c| wi[c][..n].to_vec());
        errors.push(material::pdf(exec, input, soa(&one), p));
        let (mut s_wi, mut weight) = (fill(n), fill(n));
        let [x, y, z, pdf] = &mut s_wi;
        let [wr, wg, wb, eta] = &mut weight;
        let (mut flags, mut component) = (vec![99u32; n], vec![99u32; n]);
        errors.push(material::sample(
            exec,
            input,
            SampleRandoms {
                u_lobe: &u[0],
                u0: &u[1],
                u1: &u[2],
            },
            SampleOutput {
                wi: Soa3Mut { x, y, z },
                pdf,
                weight: Soa3Mut {
                    x: wr,
                    y: wg,
                    z: wb,
                },
                value: None,
                flags: Some(&mut flags),
                lobe: None,
                component: Some(&mut component),
                eta: Some(eta),
                roughness: None,
            },
        ));
        let message = errors
            .into_iter()
            .find_map(|r| r.err().map(|e| e.message.into_owned()));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
        let mut out: Vec<Vec<u32>> = e
            .iter()
            .chain(&albedo)
            .chain(&s_wi)
            .map(|v| bits(v))
            .collect();
        out.extend(weight.iter().map(|v| bits(v)));
        out.extend([flags, component]);
        (message, out)
    };
    for hostile in [false, true] {
        if hostile {
            // A NaN, a denormal, an underflowing square and an infinite tangent.
            tangent[1][200] = f32::NAN;
            for (lane, t) in [(230, [1e-40, 0.0, 0.0]), (240, [0.0, -1e-30, 0.0])]
                .into_iter()
                .chain([(250, [f32::INFINITY, 0.0, 1.0])])
            {
                (tangent[0][lane], tangent[1][lane], tangent[2][lane]) = (t[0], t[1], t[2]);
            }
        }
        for kernels in Kernels::available() {
            let exec = Exec {
                kernels,
                threads: Threads::Caller,
            };
            let input = |overrides| MaterialInput {
                count: n,
                material: &material,
                active: None,
                wo: soa(&wo),
                normal: soa(&normal),
                tangent: Some(soa(&tangent)),
                overrides,
            };
            let (raw, staged) = (run(&exec, &input(&twice[..1])), run(&exec, &input(&twice)));
            let what = format!("{kernels:?}, hostile {hostile}");
            assert_eq!(raw.0, staged.0, "{what}");
            if hostile {
                let e = raw.0.as_deref().unwrap_or("");
                assert!(e.starts_with("lane 200: tangent"), "{what}: {e}");
                // The eval's pdf row (both directions) of the failed lanes.
                for lane in [200, 230, 240, 250, n + 200, n + 250] {
                    assert_eq!(raw.1[3][lane], 0, "{what}: lane {lane}'s pdf");
                }
            }
            for (k, (a, b)) in raw.1.iter().zip(&staged.1).enumerate() {
                let lane = a.iter().zip(b).position(|(a, b)| a != b);
                assert_eq!(lane, None, "{what}: output {k} differs at that lane");
            }
        }
    }
}
