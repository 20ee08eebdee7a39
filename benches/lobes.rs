//! Scalar eval and sample per registered lobe (default parameters, local frame),
//! and a whole-closure eval through the Rust API. Run: `cargo bench --bench lobes`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glint::lobes::Transport;
use glint::math::Vec3;
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

criterion_group!(benches, lobes, closure);
criterion_main!(benches);
