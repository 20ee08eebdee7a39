//! Batch throughput per lobe and kernel set, at 64, 4096 and 1M lanes, one closure
//! shared by every lane (default parameters: the conductor uses Gulbrandsen's
//! artistic Fresnel), on the calling thread; the 1M eval also on every core; and the
//! memory-bandwidth bound of a 1M eval (a streaming pass that reads and writes the
//! same bytes). Run: `cargo bench --bench batch`, then `scripts/bench_report.py`.

mod common;

use common::{Uniform, soa, soa_mut, zeros};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glint::Closure;
use glint::batch::{self, BatchInput, EvalOutput, Exec, SampleOutput, SampleRandoms, Threads};
use glint::lobes::Transport;
use glint::math::Frame;
use glint::registry::Registry;
use glint::simd::Kernels;
use std::hint::black_box;
use std::time::Duration;

const SIZES: [usize; 3] = [64, 4096, 1 << 20];

/// SoA inputs and outputs for `n` lanes.
struct Lanes {
    wo: [Vec<f32>; 3],
    wi: [Vec<f32>; 3],
    u: [Vec<f32>; 3],
    value: [Vec<f32>; 3],
    pdf: Vec<f32>,
    s_wi: [Vec<f32>; 3],
    weight: [Vec<f32>; 3],
}

impl Lanes {
    fn new(n: usize) -> Lanes {
        // wo and wi interleaved, as they were drawn before.
        let mut u = Uniform::new();
        let (mut wo, mut wi): ([Vec<f32>; 3], [Vec<f32>; 3]) = Default::default();
        for _ in 0..n {
            for rows in [&mut wo, &mut wi] {
                let d = u.direction();
                for c in 0..3 {
                    rows[c].push(d[c]);
                }
            }
        }
        Lanes {
            wo,
            wi,
            u: [0, 1, 2].map(|_| u.row(n)),
            value: zeros(n),
            pdf: vec![0.0; n],
            s_wi: zeros(n),
            weight: zeros(n),
        }
    }
}

fn eval(exec: &Exec<'_>, closure: &Closure, l: &mut Lanes) {
    let input = BatchInput {
        count: l.pdf.len(),
        closures: closure,
        active: None,
        wo: soa(&l.wo),
    };
    let out = EvalOutput {
        value: soa_mut(&mut l.value),
        pdf: &mut l.pdf,
        pdf_reverse: None,
    };
    batch::eval(exec, &input, soa(&l.wi), out).expect("valid batch");
}

fn sample(exec: &Exec<'_>, closure: &Closure, l: &mut Lanes) {
    let input = BatchInput {
        count: l.pdf.len(),
        closures: closure,
        active: None,
        wo: soa(&l.wo),
    };
    let u = SampleRandoms {
        u_lobe: &l.u[0],
        u0: &l.u[1],
        u1: &l.u[2],
    };
    let out = SampleOutput {
        wi: soa_mut(&mut l.s_wi),
        pdf: &mut l.pdf,
        weight: soa_mut(&mut l.weight),
        value: None,
        flags: None,
        lobe: None,
        component: None,
        eta: None,
        roughness: None,
    };
    batch::sample(exec, &input, u, out).expect("valid batch");
}

/// A closure holding one lobe with its default parameters.
fn closure(registry: &Registry, id: u32) -> Closure {
    let mut c = Closure::new(None, Transport::Radiance);
    c.add_lobe(registry, id, [1.0; 3], Frame::IDENTITY, None)
        .expect("valid lobe");
    c.finish().expect("finishes");
    c
}

fn batches(c: &mut Criterion) {
    let registry = Registry::with_builtins();
    let mut lanes: Vec<Lanes> = SIZES.iter().map(|&n| Lanes::new(n)).collect();
    for (id, lobe) in registry.iter().enumerate() {
        let closure = closure(&registry, id as u32);
        for kernels in Kernels::available() {
            let exec = Exec {
                kernels,
                threads: Threads::Caller,
            };
            let mut group = c.benchmark_group(format!("{}/{}", lobe.name(), kernels.isa().name()));
            for l in lanes.iter_mut() {
                let n = l.pdf.len();
                group.throughput(Throughput::Elements(n as u64));
                group.bench_function(BenchmarkId::new("eval", n), |b| {
                    b.iter(|| eval(&exec, &closure, black_box(l)))
                });
                group.bench_function(BenchmarkId::new("sample", n), |b| {
                    b.iter(|| sample(&exec, &closure, black_box(l)))
                });
            }
            // 1M lanes on every core.
            let l = lanes.last_mut().expect("sizes");
            let all_cores = Exec {
                kernels,
                threads: Threads::Global,
            };
            group.bench_function(BenchmarkId::new("eval_all_cores", l.pdf.len()), |b| {
                b.iter(|| eval(&all_cores, &closure, black_box(l)))
            });
            group.finish();
        }
    }
}

/// The bytes a 1M-lane eval reads (wo, wi: 24 per lane) and writes (value, pdf: 16),
/// streamed once: the memory-bandwidth bound of that eval.
fn bandwidth(c: &mut Criterion) {
    let n = SIZES[2];
    let l = Lanes::new(n);
    let mut value = [vec![0.0f32; n], vec![0.0; n], vec![0.0; n]];
    let mut pdf = vec![0.0f32; n];
    let mut group = c.benchmark_group("bandwidth");
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function(BenchmarkId::new("stream_eval_bytes", n), |b| {
        b.iter(|| {
            let [vr, vg, vb] = &mut value;
            for i in 0..n {
                vr[i] = l.wo[0][i] + l.wi[0][i];
                vg[i] = l.wo[1][i] + l.wi[1][i];
                vb[i] = l.wo[2][i] + l.wi[2][i];
                pdf[i] = l.wo[2][i];
            }
            black_box(&mut value);
            black_box(&mut pdf);
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = batches, bandwidth
}
criterion_main!(benches);
