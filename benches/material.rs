//! Material batches against a batch over one prebuilt closure of the same material
//! (issue 14's target: at least half the prebuilt closure's lane rate, expansion
//! included). The `disney` material with every lobe on (the parameters of
//! scripts/bench_vs_mitsuba.py's `principled` case); the material batch gets per-lane
//! `wo`, a normal and two overrides per lane (base color and roughness, as a textured
//! host passes), the prebuilt closure only `wo`. Eval, sample and albedo (a scanline
//! host's ambient term), on the calling thread, at 4096 and 65536 lanes; and a scanline
//! host's shading with two lights (`scanline2`): the albedo and the eval at two
//! directions per lane, one material call (`material::eval_directions`) against the
//! prebuilt closure's albedo and two evals. Run: `cargo bench --bench material`.

mod common;

use common::{Uniform, soa, soa_mut, zeros};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glint::batch::material::{self, MaterialInput, OverrideLanes};
use glint::batch::{self, BatchInput, EvalOutput, Exec, SampleOutput, SampleRandoms, Threads};
use glint::materials::{Material, ShadingContext};
use glint::math::{Frame, Vec3};
use glint::params::ParamKind;
use glint::registry::Registry;
use glint::simd::Kernels;
use std::hint::black_box;
use std::time::Duration;

const SIZES: [usize; 2] = [4096, 1 << 16];

const DISNEY: &str = r#"{"material": "disney", "base_color": [0.8, 0.2, 0.1],
    "metallic": 0.3, "roughness": 0.5, "anisotropic": 0.4, "sheen": 1, "subsurface": 0.5,
    "clearcoat": 1, "clearcoat_gloss": 0.8, "specular": 0.5}"#;

/// SoA inputs and outputs for `n` lanes.
struct Lanes {
    wo: [Vec<f32>; 3],
    wi: [Vec<f32>; 3],
    normal: [Vec<f32>; 3],
    u: [Vec<f32>; 3],
    base_color: [Vec<f32>; 3],
    roughness: Vec<f32>,
    value: [Vec<f32>; 3],
    pdf: Vec<f32>,
    /// Two directions per lane (`scanline2`): `wi`, value and pdf rows of `2 n`.
    wi2: [Vec<f32>; 3],
    value2: [Vec<f32>; 3],
    pdf2: Vec<f32>,
    s_wi: [Vec<f32>; 3],
    weight: [Vec<f32>; 3],
}

impl Lanes {
    fn new(n: usize) -> Lanes {
        let mut u = Uniform::new();
        Lanes {
            wo: u.directions(n),
            wi: u.directions(n),
            normal: [vec![0.0; n], vec![0.0; n], vec![1.0; n]],
            u: [0, 1, 2].map(|_| u.row(n)),
            base_color: [0, 1, 2].map(|c| {
                u.row(n)
                    .iter()
                    .map(|x| 0.1 + 0.2 * c as f32 + 0.5 * x)
                    .collect()
            }),
            roughness: u.row(n).iter().map(|x| 0.3 + 0.4 * x).collect(),
            value: zeros(n),
            pdf: vec![0.0; n],
            wi2: u.directions(2 * n),
            value2: zeros(2 * n),
            pdf2: vec![0.0; 2 * n],
            s_wi: zeros(n),
            weight: zeros(n),
        }
    }
}

fn sample_output(l: &mut Lanes) -> (SampleRandoms<'_>, SampleOutput<'_>) {
    (
        SampleRandoms {
            u_lobe: &l.u[0],
            u0: &l.u[1],
            u1: &l.u[2],
        },
        SampleOutput {
            wi: soa_mut(&mut l.s_wi),
            pdf: &mut l.pdf,
            weight: soa_mut(&mut l.weight),
            value: None,
            flags: None,
            lobe: None,
            component: None,
            eta: None,
            roughness: None,
        },
    )
}

/// `eval` or `sample` of the material batch over `l`.
/// The batch call a benchmark times.
#[derive(Clone, Copy)]
enum Call {
    Eval,
    Sample,
    Albedo,
    /// The albedo and the eval at two directions per lane.
    Scanline2,
}

fn run_material(exec: &Exec<'_>, m: &Material, l: &mut Lanes, call: Call) {
    let (base_color, roughness) = (
        std::mem::take(&mut l.base_color),
        std::mem::take(&mut l.roughness),
    );
    let overrides = [
        OverrideLanes {
            param: 0,
            kind: ParamKind::Rgb,
            value: [&base_color[0], &base_color[1], &base_color[2]],
        },
        OverrideLanes {
            param: 5,
            kind: ParamKind::Float,
            value: [&roughness, &[], &[]],
        },
    ];
    let (wo, normal) = (std::mem::take(&mut l.wo), std::mem::take(&mut l.normal));
    let input = MaterialInput {
        count: l.pdf.len(),
        material: m,
        active: None,
        wo: soa(&wo),
        normal: soa(&normal),
        tangent: None,
        overrides: &overrides,
    };
    match call {
        Call::Sample => {
            let (u, out) = sample_output(l);
            material::sample(exec, &input, u, out).expect("valid batch");
        }
        Call::Eval => {
            let out = EvalOutput {
                value: soa_mut(&mut l.value),
                pdf: &mut l.pdf,
                pdf_reverse: None,
            };
            material::eval(exec, &input, soa(&l.wi), out).expect("valid batch");
        }
        Call::Albedo => material::albedo(exec, &input, soa_mut(&mut l.value)).expect("valid batch"),
        Call::Scanline2 => {
            let out = EvalOutput {
                value: soa_mut(&mut l.value2),
                pdf: &mut l.pdf2,
                pdf_reverse: None,
            };
            let albedo = Some(soa_mut(&mut l.value));
            material::eval_directions(exec, &input, soa(&l.wi2), 2, out, albedo)
                .expect("valid batch");
        }
    }
    (l.wo, l.normal, l.base_color, l.roughness) = (wo, normal, base_color, roughness);
}

/// `eval` or `sample` of one prebuilt closure shared by every lane of `l`.
fn run_closure(exec: &Exec<'_>, c: &glint::Closure, l: &mut Lanes, call: Call) {
    let wo = std::mem::take(&mut l.wo);
    let input = BatchInput {
        count: l.pdf.len(),
        closures: c,
        active: None,
        wo: soa(&wo),
    };
    match call {
        Call::Sample => {
            let (u, out) = sample_output(l);
            batch::sample(exec, &input, u, out).expect("valid batch");
        }
        Call::Eval => {
            let out = EvalOutput {
                value: soa_mut(&mut l.value),
                pdf: &mut l.pdf,
                pdf_reverse: None,
            };
            batch::eval(exec, &input, soa(&l.wi), out).expect("valid batch");
        }
        Call::Albedo => batch::albedo(exec, &input, soa_mut(&mut l.value)).expect("valid batch"),
        Call::Scanline2 => {
            batch::albedo(exec, &input, soa_mut(&mut l.value)).expect("valid batch");
            let n = l.pdf.len();
            let [x, y, z] = &l.wi2;
            let [r, g, b] = &mut l.value2;
            for ((((x, y), z), (r, (g, b))), pdf) in x
                .chunks_exact(n)
                .zip(y.chunks_exact(n))
                .zip(z.chunks_exact(n))
                .zip(
                    r.chunks_exact_mut(n)
                        .zip(g.chunks_exact_mut(n).zip(b.chunks_exact_mut(n))),
                )
                .zip(l.pdf2.chunks_exact_mut(n))
            {
                let out = EvalOutput {
                    value: glint::batch::Soa3Mut { x: r, y: g, z: b },
                    pdf,
                    pdf_reverse: None,
                };
                let wi = glint::batch::Soa3 { x, y, z };
                batch::eval(exec, &input, wi, out).expect("valid batch");
            }
        }
    }
    l.wo = wo;
}

fn materials(c: &mut Criterion) {
    let registry = Registry::with_builtins();
    let m = glint::json::material_from_json(&registry, DISNEY, 0.0).expect("valid material");
    let wo = Vec3::new(0.3f32, 0.2, 0.93).normalize();
    let prebuilt = m
        .closure(&ShadingContext::new(wo, Frame::IDENTITY), &[])
        .expect("closure");
    let mut lanes: Vec<Lanes> = SIZES.iter().map(|&n| Lanes::new(n)).collect();
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let mut group = c.benchmark_group(format!("disney/{}", kernels.isa().name()));
        for l in lanes.iter_mut() {
            let n = l.pdf.len();
            group.throughput(Throughput::Elements(n as u64));
            for (what, call) in [
                ("eval", Call::Eval),
                ("sample", Call::Sample),
                ("albedo", Call::Albedo),
                ("scanline2", Call::Scanline2),
            ] {
                group.bench_function(BenchmarkId::new(format!("material_{what}"), n), |b| {
                    b.iter(|| run_material(&exec, &m, black_box(l), call))
                });
                group.bench_function(BenchmarkId::new(format!("closure_{what}"), n), |b| {
                    b.iter(|| run_closure(&exec, &prebuilt, black_box(l), call))
                });
            }
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = materials
}
criterion_main!(benches);
