//! Scalar eval and sample per registered lobe (default parameters, local frame),
//! a whole-closure eval through the Rust API, and the `wo` bake (a conductor
//! mirror's Fresnel) read and missed. Run: `cargo bench --bench lobes`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glint::Closure;
use glint::lobes::Transport;
use glint::math::{Frame, Vec3};
use glint::params;
use glint::registry::Registry;
use std::hint::black_box;

const N: usize = 1024;

/// `wo`, `wi` and random triples for `N` calls.
struct Inputs {
    wo: Vec<Vec3<f32>>,
    wi: Vec<Vec3<f32>>,
    u: Vec<[f32; 3]>,
}

/// Deterministic directions in the upper hemisphere and random triples.
fn inputs() -> Inputs {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut dir = || {
        let z = next().max(0.01);
        let phi = 2.0 * std::f32::consts::PI * next();
        let r = (1.0 - z * z).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let wo: Vec<_> = (0..N).map(|_| dir()).collect();
    let wi: Vec<_> = (0..N).map(|_| dir()).collect();
    let u: Vec<_> = (0..N).map(|_| [next(), next(), next()]).collect();
    Inputs { wo, wi, u }
}

fn lobes(c: &mut Criterion) {
    let registry = Registry::with_builtins();
    let Inputs { wo, wi, u } = inputs();
    for lobe in registry.iter() {
        let mut block = vec![0.0; params::block_size(lobe.params())];
        params::write_defaults(lobe.params(), &mut block);
        let mut group = c.benchmark_group(lobe.name());
        group.throughput(Throughput::Elements(N as u64));
        group.bench_function("eval", |b| {
            b.iter(|| {
                for i in 0..N {
                    black_box(lobe.eval(&block, wo[i], wi[i], Transport::Radiance));
                }
            })
        });
        group.bench_function("sample", |b| {
            b.iter(|| {
                for i in 0..N {
                    black_box(lobe.sample(&block, wo[i], u[i], Transport::Radiance));
                }
            })
        });
        group.finish();
    }
}

fn closure(c: &mut Criterion) {
    let registry = Registry::with_builtins();
    let Inputs { wo, wi, u } = inputs();
    let json = r#"{"lobes": [
        {"type": "lambert", "weight": 0.5},
        {"type": "conductor", "roughness": 0.3, "fresnel": "artistic"}]}"#;
    let closure =
        glint::json::closure_from_json(&registry, json, None, glint::materials::DEFAULT_PRUNE)
            .expect("valid closure");
    let mut group = c.benchmark_group("closure_lambert_conductor");
    group.throughput(Throughput::Elements(N as u64));
    group.bench_function("eval", |b| {
        b.iter(|| {
            for i in 0..N {
                black_box(closure.eval(wo[i], wi[i]).ok());
            }
        })
    });
    group.bench_function("sample", |b| {
        b.iter(|| {
            for i in 0..N {
                black_box(closure.sample(wo[i], u[i]).ok());
            }
        })
    });
    group.finish();
}

/// A polished metal (lambert + a conductor mirror) built at each `wo`: the mirror
/// bakes `F(cos_o)`. Its samples at the baked `wo` read the bake; at another `wo`
/// they compute it, as every sample did before baking. Per shading point, a build
/// with `wo` (bake, then the selection albedo reads it) plus one sample against a
/// build without `wo` (selection albedo and sample each evaluate a Fresnel, the
/// count of a build with `wo` before baking).
fn baked(c: &mut Criterion) {
    let registry = Registry::with_builtins();
    let Inputs { wo, wi, u } = inputs();
    let (lambert, mirror) = (
        registry.find("lambert").unwrap(),
        registry.find("mirror").unwrap(),
    );
    let mirror_type = registry.get(mirror).unwrap();
    let mut conductor = vec![0.0; params::block_size(mirror_type.params())];
    params::write_defaults(mirror_type.params(), &mut conductor);
    // The Fresnel choice is the mirror's first parameter: 1 = conductor.
    conductor[0] = 1.0;
    let frame = Frame::new(Vec3::new(0.0, 0.0, 1.0), None);
    let build = |wo: Option<Vec3<f32>>| {
        let mut c = Closure::new(wo, Transport::Radiance);
        c.add_lobe(&registry, lambert, [0.2; 3], frame, None)
            .unwrap();
        c.add_lobe(&registry, mirror, [1.0; 3], frame, Some(&conductor))
            .unwrap();
        c.finish().unwrap();
        c
    };
    let closures: Vec<_> = wo.iter().map(|&w| build(Some(w))).collect();
    let mut group = c.benchmark_group("baked_mirror_conductor");
    group.throughput(Throughput::Elements(N as u64));
    for (name, at) in [("sample_at_baked_wo", &wo), ("sample_at_other_wo", &wi)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                for i in 0..N {
                    black_box(closures[i].sample_lobe(1, at[i], u[i]).ok());
                }
            })
        });
    }
    for (name, with_wo) in [
        ("build_sample_baked", true),
        ("build_sample_unbaked", false),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                for i in 0..N {
                    let c = build(with_wo.then_some(wo[i]));
                    black_box(c.sample(wo[i], u[i]).ok());
                }
            })
        });
    }
    group.finish();
}

criterion_group!(benches, lobes, closure, baked);
criterion_main!(benches);
