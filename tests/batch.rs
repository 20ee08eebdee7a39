//! The batch kernels on mixed batches: per-lane closures of many shapes (different
//! lobe types, counts, enumerated choices, transports and frames), inactive and
//! invalid lanes, several blocks; every kernel set this CPU has, compared lane by
//! lane with the scalar closure calls; and results independent of the thread count.

mod common;

use common::{Block, Outputs, Rng, lobe, soa, soa_mut};
use glint::batch::{
    self, BLOCK, BatchInput, ClosureSource, EvalOutput, Exec, SampleOutput, SampleRandoms, Soa3,
    Soa3Mut, Threads,
};
use glint::kernels::delay::{self, DELAY, STREAMING_LANES, Stores};
use glint::lobes::Transport;
use glint::math::{Frame, Vec3};
use glint::registry::Registry;
use glint::simd::Kernels;
use glint::verify::{BATCH_SAMPLE_TOLERANCE, BATCH_TOLERANCE, batch_difference};
use glint::{Closure, Runtime, Status};

/// A unit vector from three uniforms.
fn sphere(rng: &mut Rng) -> Vec3<f32> {
    let z = 1.0 - 2.0 * rng.f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * rng.f32();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Closures of different shapes: each entry is (lobe name, parameter block) lists.
fn closures(rng: &mut Rng) -> Vec<Closure> {
    let registry = Registry::with_builtins();
    let conductor = || Block::defaults(lobe("conductor"));
    let shapes: Vec<(Transport, Vec<(&str, Block)>)> = vec![
        (
            Transport::Radiance,
            vec![("lambert", Block::defaults(lobe("lambert")))],
        ),
        (
            Transport::Radiance,
            vec![("conductor", conductor().float("roughness", 0.4))],
        ),
        (
            Transport::Radiance,
            vec![(
                "conductor",
                conductor()
                    .choice("distribution", "beckmann")
                    .choice("fresnel", "conductor")
                    .float("anisotropic", 0.6),
            )],
        ),
        (
            Transport::Radiance,
            vec![
                ("lambert", Block::defaults(lobe("lambert"))),
                ("conductor", conductor().float("roughness", 0.2)),
            ],
        ),
        // Two narrow lobes (alpha 0.001) peaking at the same direction: each is
        // evaluated at the other's samples, where the last bit of `wi` moves its value
        // by 1e-4.
        (
            Transport::Radiance,
            vec![
                (
                    "disney_specular",
                    Block::defaults(lobe("disney_specular")).float("roughness", 0.0),
                ),
                (
                    "disney_clearcoat",
                    Block::defaults(lobe("disney_clearcoat")).float("gloss", 1.0),
                ),
            ],
        ),
        // Four lobes, as the disney material's: in-place samples group each lobe's
        // lanes into a run of their own.
        (
            Transport::Radiance,
            vec![
                (
                    "disney_diffuse",
                    Block::defaults(lobe("disney_diffuse")).float("roughness", 0.6),
                ),
                ("disney_sheen", Block::defaults(lobe("disney_sheen"))),
                (
                    "disney_specular",
                    Block::defaults(lobe("disney_specular"))
                        .float("roughness", 0.4)
                        .float("anisotropic", 0.5),
                ),
                (
                    "disney_clearcoat",
                    Block::defaults(lobe("disney_clearcoat")),
                ),
            ],
        ),
        // The other shapes the disney material emits (each fused in place).
        (
            Transport::Radiance,
            vec![
                ("disney_diffuse", Block::defaults(lobe("disney_diffuse"))),
                ("disney_sheen", Block::defaults(lobe("disney_sheen"))),
                ("disney_specular", Block::defaults(lobe("disney_specular"))),
            ],
        ),
        (
            Transport::Radiance,
            vec![
                ("disney_diffuse", Block::defaults(lobe("disney_diffuse"))),
                ("disney_specular", Block::defaults(lobe("disney_specular"))),
                (
                    "disney_clearcoat",
                    Block::defaults(lobe("disney_clearcoat")),
                ),
            ],
        ),
        (
            Transport::Radiance,
            vec![
                ("disney_diffuse", Block::defaults(lobe("disney_diffuse"))),
                ("disney_specular", Block::defaults(lobe("disney_specular"))),
            ],
        ),
        (
            Transport::Radiance,
            vec![(
                "dielectric",
                Block::defaults(lobe("dielectric")).float("roughness", 0.3),
            )],
        ),
        (
            Transport::Importance,
            vec![(
                "dielectric",
                Block::defaults(lobe("dielectric")).float("roughness", 0.5),
            )],
        ),
        (
            Transport::Radiance,
            vec![
                ("mirror", Block::defaults(lobe("mirror"))),
                ("lambert", Block::defaults(lobe("lambert"))),
                (
                    "dielectric",
                    Block::defaults(lobe("dielectric")).float("roughness", 0.0),
                ),
            ],
        ),
    ];
    let mut out = Vec::new();
    // Two closures per shape, with different parameters and frames, so groups mix
    // closures of one shape (per-lane parameters) as well as shapes. The first copy's
    // lobes share one frame (as a material's do, which in-place evals take once), the
    // second's each have their own.
    for copy in 0..2 {
        for (mode, lobes) in &shapes {
            let wo = (copy == 1).then(|| sphere(rng));
            let shared_frame = Frame::new(sphere(rng), None);
            let mut c = Closure::new(wo, *mode);
            for (name, block) in lobes {
                let id = registry.find(name).unwrap();
                let mut block = block.clone();
                if copy == 1 && block.has("roughness") {
                    let roughness = block.offset("roughness");
                    let r = block.values[roughness];
                    block.values[roughness] = (r + 0.1 * rng.f32()).min(1.0);
                }
                let weight = [0.3 + 0.7 * rng.f32(), 0.5, 0.9];
                let frame = if copy == 0 {
                    shared_frame
                } else {
                    Frame::new(sphere(rng), None)
                };
                c.add_lobe(&registry, id, weight, frame, Some(block.as_slice()))
                    .unwrap();
            }
            c.finish().unwrap();
            out.push(c);
        }
    }
    out
}

struct Lanes {
    wo: [Vec<f32>; 3],
    wi: [Vec<f32>; 3],
    u: [Vec<f32>; 3],
    active: Vec<u8>,
    which: Vec<usize>,
}

fn lanes(n: usize, shapes: usize, rng: &mut Rng) -> Lanes {
    let mut l = Lanes {
        wo: Default::default(),
        wi: Default::default(),
        u: Default::default(),
        active: Vec::new(),
        which: Vec::new(),
    };
    for i in 0..n {
        let (o, w) = (sphere(rng), sphere(rng));
        // Unnormalized inputs are normalized by the batch as by the scalar calls.
        let s = if i % 5 == 0 { 3.5 } else { 1.0 };
        for (c, (a, b)) in [(o.x, w.x), (o.y, w.y), (o.z, w.z)].into_iter().enumerate() {
            l.wo[c].push(a * s);
            l.wi[c].push(b);
            l.u[c].push(rng.f32());
        }
        l.active.push(u8::from(i % 11 != 3));
        // Runs of one closure, then switches, as a scanline host would have.
        l.which.push(if i % 64 < 40 {
            (i / 64) % shapes
        } else {
            (rng.next_u64() as usize) % shapes
        });
    }
    l
}

/// Run every batch entry point; `Err` carries each call's error.
fn run(
    exec: &Exec<'_>,
    per_lane: &[&Closure],
    l: &Lanes,
) -> (Outputs, Vec<Result<(), glint::Error>>) {
    run_with(exec, per_lane, per_lane.len(), Some(&l.active), l)
}

/// [`run`] over `n` lanes of any closure source, with an optional active mask.
fn run_with<'a>(
    exec: &Exec<'_>,
    closures: impl ClosureSource<'a>,
    n: usize,
    active: Option<&'a [u8]>,
    l: &'a Lanes,
) -> (Outputs, Vec<Result<(), glint::Error>>) {
    // Outputs start at a sentinel so lanes left untouched are visible.
    let mut o = Outputs::filled(n, -7.0, 99);
    let input = BatchInput {
        count: n,
        closures,
        active,
        wo: soa(&l.wo),
    };
    let eval = batch::eval(
        exec,
        &input,
        soa(&l.wi),
        EvalOutput {
            value: soa_mut(&mut o.value),
            pdf: &mut o.pdf,
            pdf_reverse: Some(&mut o.pdf_reverse),
        },
    );
    // Without the reverse pdf, a shared closure of a fused shape runs its single pass
    // (kernels::fused): the same bits.
    let mut forward = Outputs::filled(n, -7.0, 99);
    let again = batch::eval(
        exec,
        &input,
        soa(&l.wi),
        EvalOutput {
            value: soa_mut(&mut forward.value),
            pdf: &mut forward.pdf,
            pdf_reverse: None,
        },
    );
    assert_eq!(
        again.as_ref().err().map(|e| &e.message),
        eval.as_ref().err().map(|e| &e.message)
    );
    let bits = |rows: &[&Vec<f32>]| -> Vec<u32> {
        rows.iter()
            .flat_map(|r| r.iter().map(|v| v.to_bits()))
            .collect()
    };
    let [a, b, c] = &o.value;
    let [d, e, f] = &forward.value;
    assert!(
        bits(&[a, b, c, &o.pdf]) == bits(&[d, e, f, &forward.pdf]),
        "eval without the reverse pdf differs"
    );
    let pdf = batch::pdf(exec, &input, soa(&l.wi), &mut o.pdf_only);
    let albedo = batch::albedo(exec, &input, soa_mut(&mut o.albedo));
    let sample = batch::sample(
        exec,
        &input,
        SampleRandoms {
            u_lobe: &l.u[0],
            u0: &l.u[1],
            u1: &l.u[2],
        },
        SampleOutput {
            wi: soa_mut(&mut o.s_wi),
            pdf: &mut o.s_pdf,
            weight: soa_mut(&mut o.s_weight),
            value: Some(soa_mut(&mut o.s_value)),
            flags: Some(&mut o.s_flags),
            lobe: Some(&mut o.s_lobe),
            component: None,
            eta: Some(&mut o.s_eta),
            roughness: Some(&mut o.s_roughness),
        },
    );
    let results = vec![eval, pdf, albedo, sample];
    (o, results)
}

/// Compare every active lane with the scalar closure calls; returns the worst
/// `batch_difference` of evaluations and of samples.
fn worst_difference(per_lane: &[&Closure], l: &Lanes, o: &Outputs) -> (f64, f64) {
    let (mut worst, mut worst_sample) = (0.0f64, 0.0f64);
    for (i, &c) in per_lane.iter().enumerate() {
        if l.active[i] == 0 {
            assert_eq!(o.pdf[i], -7.0, "inactive lane {i} was written");
            assert_eq!(o.s_flags[i], 99, "inactive lane {i} was written");
            continue;
        }
        let wo = Vec3::try_unit(l.wo[0][i], l.wo[1][i], l.wo[2][i], "wo").unwrap();
        let wi = Vec3::try_unit(l.wi[0][i], l.wi[1][i], l.wi[2][i], "wi").unwrap();
        let mut cmp = |a: f32, b: f32, what: &str| {
            let d = batch_difference(a, b);
            assert!(d.is_finite(), "lane {i} {what}: batch {a}, scalar {b}");
            if what.starts_with("s_") {
                worst_sample = worst_sample.max(d);
            } else {
                worst = worst.max(d);
            }
        };
        let e = c.eval(wo, wi).unwrap();
        for k in 0..3 {
            cmp(o.value[k][i], e.value.to_array()[k], "value");
            cmp(
                o.albedo[k][i],
                c.albedo(wo).unwrap().to_array()[k],
                "albedo",
            );
        }
        cmp(o.pdf[i], e.pdf, "pdf");
        cmp(o.pdf_only[i], e.pdf, "pdf_only");
        cmp(o.pdf_reverse[i], e.pdf_reverse, "pdf_reverse");
        match c.sample(wo, [l.u[0][i], l.u[1][i], l.u[2][i]]) {
            Ok(s) => {
                assert_eq!(o.s_flags[i], s.flags, "lane {i} flags");
                assert_eq!(o.s_lobe[i], s.lobe, "lane {i} lobe");
                for k in 0..3 {
                    cmp(o.s_wi[k][i], [s.wi.x, s.wi.y, s.wi.z][k], "s_wi");
                    cmp(o.s_weight[k][i], s.weight.to_array()[k], "s_weight");
                    cmp(o.s_value[k][i], s.value.to_array()[k], "s_value");
                }
                cmp(o.s_pdf[i], s.pdf, "s_pdf");
                cmp(o.s_eta[i], s.eta, "s_eta");
                cmp(o.s_roughness[i], s.roughness, "s_roughness");
            }
            Err(e) => {
                assert_eq!(e.status, Status::NoSample);
                assert_eq!(
                    (o.s_pdf[i], o.s_flags[i]),
                    (0.0, 0),
                    "lane {i}: failed sample"
                );
            }
        }
    }
    (worst, worst_sample)
}

#[test]
fn mixed_batches_match_the_scalar_calls_on_every_isa() {
    let mut rng = Rng::new(7);
    let all = closures(&mut rng);
    let n = 2 * BLOCK + 777;
    let l = lanes(n, all.len(), &mut rng);
    let per_lane: Vec<&Closure> = l.which.iter().map(|&k| &all[k]).collect();
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let (o, results) = run(&exec, &per_lane, &l);
        for r in results {
            r.unwrap();
        }
        let (worst, worst_sample) = worst_difference(&per_lane, &l, &o);
        println!(
            "{:?}: worst difference {worst:.3e}, samples {worst_sample:.3e}",
            kernels.isa()
        );
        assert!(worst <= BATCH_TOLERANCE, "{:?}: {worst:.3e}", kernels.isa());
        assert!(
            worst_sample <= BATCH_SAMPLE_TOLERANCE,
            "{:?}: samples {worst_sample:.3e}",
            kernels.isa()
        );
    }
}

#[test]
fn one_shared_closure_matches_per_lane_closures() {
    let mut rng = Rng::new(11);
    let all = closures(&mut rng);
    let n = 1000;
    let l = lanes(n, 1, &mut rng);
    for c in &all {
        let per_lane: Vec<&Closure> = vec![c; n];
        for kernels in Kernels::available() {
            let exec = Exec {
                kernels,
                threads: Threads::Caller,
            };
            let (per, _) = run(&exec, &per_lane, &l);
            let input_shared = BatchInput {
                count: n,
                closures: c,
                active: Some(&l.active[..]),
                wo: soa(&l.wo),
            };
            let mut pdf = vec![-7.0; n];
            batch::pdf(&exec, &input_shared, soa(&l.wi), &mut pdf).unwrap();
            assert_eq!(pdf, per.pdf_only, "{:?}", kernels.isa());
        }
    }
}

/// Every ISA this CPU has, with its outputs held back and stored directly
/// (`stores=`): the same bits either way.
fn held_and_direct() -> Vec<Kernels> {
    Kernels::available()
        .into_iter()
        .flat_map(|k| [Stores::Held, Stores::Direct].map(|s| k.with_stores(s)))
        .collect()
}

/// A closure shared by every lane with no active mask runs in place: the kernels read
/// the caller's arrays, normalize in the kernel and end with a masked tail. Its
/// outputs must be bit-for-bit those of the staged path (the same closure given per
/// lane), at counts with tails and across chunks and blocks, and when some lanes
/// need the staged path's exact normalization (lengths beyond 1e12) or fail (NaN,
/// zero length, a non-finite random number), which sends their chunk back to staging;
/// with the eval's sums stored as computed or two registers later (`stores=`).
#[test]
fn shared_closures_in_place_match_the_staged_path_bit_for_bit() {
    let mut rng = Rng::new(21);
    let all = closures(&mut rng);
    // A call of STREAMING_LANES or more streams (kernels::delay): its fused kernels
    // prefetch the rows they read, up to past their ends; whether its rows,
    // each allocated apart, collide and it holds its outputs back depends on where the
    // allocator puts them (the ring's own test is
    // outputs_held_back_are_those_stored_directly_bit_for_bit).
    for n in [1, 13, 300, BLOCK + 37, STREAMING_LANES + DELAY + 37] {
        for bad in [false, true] {
            let mut l = lanes(n, 1, &mut rng);
            if bad && n > 200 {
                for c in 0..3 {
                    l.wo[c][5] *= 1e15;
                    l.wi[c][6] *= 1e20;
                    l.wo[c][150] = 0.0;
                }
                l.wi[1][7] = f32::NAN;
                l.u[2][199] = f32::INFINITY;
            }
            for c in &all {
                let per_lane: Vec<&Closure> = vec![c; n];
                for kernels in held_and_direct() {
                    let exec = Exec {
                        kernels,
                        threads: Threads::Caller,
                    };
                    let (staged, staged_results) = run_with(&exec, &per_lane[..], n, None, &l);
                    let (shared, shared_results) = run_with(&exec, c, n, None, &l);
                    let what = format!(
                        "{:?}, {:?}, {n} lanes, bad lanes {bad}",
                        kernels.isa(),
                        kernels.stores()
                    );
                    assert!(shared == staged, "{what}: outputs differ");
                    let messages = |r: Vec<Result<(), glint::Error>>| {
                        r.into_iter()
                            .map(|r| r.err().map(|e| e.message))
                            .collect::<Vec<_>>()
                    };
                    let expected = messages(staged_results);
                    assert_eq!(messages(shared_results), expected, "{what}");
                    if bad && n > 200 {
                        let first = |k: usize| expected[k].as_deref().unwrap_or("no error");
                        assert!(first(0).starts_with("lane 7: wi"), "{what}: {}", first(0));
                        assert!(first(2).starts_with("lane 150: wo"), "{what}: {}", first(2));
                        assert!(first(3).starts_with("lane 150: wo"), "{what}: {}", first(3));
                    }
                }
            }
        }
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut rng = Rng::new(5);
    let all = closures(&mut rng);
    let n = 5 * BLOCK + 123;
    let l = lanes(n, all.len(), &mut rng);
    let per_lane: Vec<&Closure> = l.which.iter().map(|&k| &all[k]).collect();
    let reference = run(&Runtime::new("threads=1").unwrap().exec(), &per_lane, &l).0;
    for config in ["threads=2", "threads=3", ""] {
        let rt = Runtime::new(config).unwrap();
        let (o, results) = run(&rt.exec(), &per_lane, &l);
        assert!(results.iter().all(Result::is_ok));
        assert!(o == reference, "{config}: results differ from threads=1");
    }
}

#[test]
fn bad_lanes_are_zeroed_and_reported_and_the_rest_computed() {
    let mut rng = Rng::new(3);
    let all = closures(&mut rng);
    let n = BLOCK + 100;
    let mut l = lanes(n, all.len(), &mut rng);
    l.active.fill(1);
    // Lane BLOCK + 5: NaN wo; lane 40: zero-length wo (the first bad lane); lane 41:
    // a non-finite random number; lane 42: an unfinished closure.
    l.wo[0][BLOCK + 5] = f32::NAN;
    for c in 0..3 {
        l.wo[c][40] = 0.0;
    }
    l.u[1][41] = f32::INFINITY;
    let unfinished = Closure::new(None, Transport::Radiance);
    let mut per_lane: Vec<&Closure> = l.which.iter().map(|&k| &all[k]).collect();
    per_lane[42] = &unfinished;
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Global,
        };
        let (o, results) = run(&exec, &per_lane, &l);
        let [eval, pdf, albedo, sample] = results.try_into().unwrap();
        for (what, r, status) in [
            ("eval", eval, Status::InvalidArgument),
            ("pdf", pdf, Status::InvalidArgument),
            ("albedo", albedo, Status::InvalidArgument),
            ("sample", sample, Status::InvalidArgument),
        ] {
            let e = r.expect_err(what);
            assert_eq!(e.status, status, "{what}: {}", e.message);
            assert!(
                e.message.starts_with("lane 40: wo"),
                "{what}: {}",
                e.message
            );
        }
        for bad in [40, 42, BLOCK + 5] {
            assert_eq!(o.pdf[bad], 0.0);
            assert_eq!(o.value[0][bad], 0.0);
            assert_eq!(o.albedo[1][bad], 0.0);
            assert_eq!((o.s_pdf[bad], o.s_flags[bad]), (0.0, 0));
        }
        assert_eq!((o.s_pdf[41], o.s_flags[41]), (0.0, 0));
        // Every other lane is computed as usual.
        for i in (0..n).filter(|i| ![40, 41, 42, BLOCK + 5].contains(i)) {
            assert!(
                o.pdf[i] >= 0.0 && o.pdf[i] != -7.0,
                "lane {i}: {}",
                o.pdf[i]
            );
            assert!(o.s_flags[i] != 99, "lane {i}");
        }
    }
}

/// The scalar kernel set runs the scalar calls' operations in the same order, so every
/// output of every active lane is bit-for-bit the scalar call's: every built-in lobe
/// alone and mixed, both transports, per-lane parameters and frames (issue 12, D12:
/// sample weights differed by 1 ulp in 13% of lanes, `value * (1 / pdf)`).
#[test]
fn scalar_kernels_match_the_scalar_calls_bit_for_bit() {
    let mut rng = Rng::new(12);
    let all = closures(&mut rng);
    let n = 3 * BLOCK + 50;
    let l = lanes(n, all.len(), &mut rng);
    let per_lane: Vec<&Closure> = l.which.iter().map(|&k| &all[k]).collect();
    let (o, results) = run(&Exec::scalar(), &per_lane, &l);
    for r in results {
        r.unwrap();
    }
    let (mut lanes_compared, mut samples_compared) = (0, 0);
    let mut mismatches: Vec<String> = Vec::new();
    let mut same = |what: &str, i: usize, batch: f32, scalar: f32| {
        if batch.to_bits() != scalar.to_bits() {
            mismatches.push(format!(
                "lane {i} {what}: batch {batch:e}, scalar {scalar:e}"
            ));
        }
    };
    for (i, &c) in per_lane.iter().enumerate() {
        if l.active[i] == 0 {
            continue;
        }
        lanes_compared += 1;
        let wo = Vec3::try_unit(l.wo[0][i], l.wo[1][i], l.wo[2][i], "wo").unwrap();
        let wi = Vec3::try_unit(l.wi[0][i], l.wi[1][i], l.wi[2][i], "wi").unwrap();
        let e = c.eval(wo, wi).unwrap();
        let albedo = c.albedo(wo).unwrap().to_array();
        for (k, (&value, &albedo)) in e.value.to_array().iter().zip(&albedo).enumerate() {
            same("value", i, o.value[k][i], value);
            same("albedo", i, o.albedo[k][i], albedo);
        }
        same("pdf", i, o.pdf[i], e.pdf);
        same("pdf_only", i, o.pdf_only[i], e.pdf);
        same("pdf_reverse", i, o.pdf_reverse[i], e.pdf_reverse);
        let Ok(s) = c.sample(wo, [l.u[0][i], l.u[1][i], l.u[2][i]]) else {
            assert_eq!((o.s_pdf[i], o.s_flags[i]), (0.0, 0), "lane {i}");
            continue;
        };
        samples_compared += 1;
        assert_eq!((o.s_flags[i], o.s_lobe[i]), (s.flags, s.lobe), "lane {i}");
        for k in 0..3 {
            same("s_wi", i, o.s_wi[k][i], [s.wi.x, s.wi.y, s.wi.z][k]);
            same("s_value", i, o.s_value[k][i], s.value.to_array()[k]);
            same("s_weight", i, o.s_weight[k][i], s.weight.to_array()[k]);
        }
        same("s_pdf", i, o.s_pdf[i], s.pdf);
        same("s_eta", i, o.s_eta[i], s.eta);
        same("s_roughness", i, o.s_roughness[i], s.roughness);
    }
    assert!(samples_compared > lanes_compared / 2);
    assert!(
        mismatches.is_empty(),
        "{} differences over {lanes_compared} lanes ({samples_compared} samples); first: {:#?}",
        mismatches.len(),
        &mismatches[..mismatches.len().min(8)]
    );
}

/// A batch sample's value and pdf are the batch eval's at the direction it returns,
/// bit for bit, on every kernel set (one half vector, no second eval; a mixture's
/// sums are every lobe's eval there, summed as the eval sums them): sample, then eval
/// at `(wo, sampled wi)`, for the closures of every built-in type and the disney
/// shapes, in place (one shared closure: fused or grouped by lobe) and staged (the
/// same closure per lane). Failed and delta samples have no eval to match and are
/// skipped.
#[test]
fn samples_carry_the_eval_at_their_direction_on_every_isa() {
    use glint::lobes::flags;
    let mut rng = Rng::new(31);
    let all = closures(&mut rng);
    let n = 2000;
    let l = lanes(n, 1, &mut rng);
    let mut checked = 0;
    for c in &all {
        let per_lane: Vec<&Closure> = vec![c; n];
        for kernels in Kernels::available() {
            let exec = Exec {
                kernels,
                threads: Threads::Caller,
            };
            for (o, how) in [
                (run_with(&exec, c, n, None, &l).0, "in place"),
                (run_with(&exec, &per_lane[..], n, None, &l).0, "staged"),
            ] {
                let input = BatchInput {
                    count: n,
                    closures: c,
                    active: None,
                    wo: soa(&l.wo),
                };
                let mut value = [vec![-7.0; n], vec![-7.0; n], vec![-7.0; n]];
                let mut pdf = vec![-7.0; n];
                // Failed samples return wi = 0, an error lane for eval; the others are
                // computed all the same.
                let _ = batch::eval(
                    &exec,
                    &input,
                    soa(&o.s_wi),
                    EvalOutput {
                        value: soa_mut(&mut value),
                        pdf: &mut pdf,
                        pdf_reverse: None,
                    },
                );
                for i in 0..n {
                    let f = o.s_flags[i];
                    if f == 0 || f & flags::SPECULAR != 0 {
                        continue;
                    }
                    let what = || {
                        format!(
                            "{:?} {how}, lane {i}, {}",
                            kernels.isa(),
                            c.lobes()[0].lobe.name()
                        )
                    };
                    assert_eq!(o.s_pdf[i].to_bits(), pdf[i].to_bits(), "pdf: {}", what());
                    for (ch, (s, e)) in o.s_value.iter().zip(&value).enumerate() {
                        assert_eq!(s[i].to_bits(), e[i].to_bits(), "value[{ch}]: {}", what());
                    }
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 10_000, "{checked} samples compared");
}

/// `c`'s eval and sample over `input` rows (`wo`, `wi`, `u`) in calls of `call`
/// lanes: into `out`, the eval's `value` and `pdf`, then the sample's `wi`, `pdf`,
/// `weight`, `value`, `eta` and `roughness`, and `ints`, its flags and lobes.
fn eval_and_sample(
    exec: &Exec<'_>,
    c: &Closure,
    input: &[&[f32]],
    out: &mut [&mut [f32]],
    ints: &mut [Vec<u32>; 2],
    call: usize,
) {
    let n = input[0].len();
    let [flags, lobes] = ints;
    for lo in (0..n).step_by(call) {
        let r = lo..(lo + call).min(n);
        let rows: Vec<&[f32]> = input.iter().map(|row| &row[r.clone()]).collect();
        let three = |k: usize| Soa3 {
            x: rows[k],
            y: rows[k + 1],
            z: rows[k + 2],
        };
        let batch = BatchInput {
            count: r.len(),
            closures: c,
            active: None,
            wo: three(0),
        };
        let o: Vec<&mut [f32]> = out.iter_mut().map(|row| &mut row[r.clone()]).collect();
        let Ok(
            [
                v0,
                v1,
                v2,
                pdf,
                w0,
                w1,
                w2,
                s_pdf,
                g0,
                g1,
                g2,
                s0,
                s1,
                s2,
                eta,
                rough,
            ],
        ) = <[&mut [f32]; 16]>::try_from(o)
        else {
            unreachable!("16 output rows")
        };
        let value = Soa3Mut {
            x: v0,
            y: v1,
            z: v2,
        };
        let eval_out = EvalOutput {
            value,
            pdf,
            pdf_reverse: None,
        };
        batch::eval(exec, &batch, three(3), eval_out).expect("eval");
        let u = SampleRandoms {
            u_lobe: rows[6],
            u0: rows[7],
            u1: rows[8],
        };
        let sample_out = SampleOutput {
            wi: Soa3Mut {
                x: w0,
                y: w1,
                z: w2,
            },
            pdf: s_pdf,
            weight: Soa3Mut {
                x: g0,
                y: g1,
                z: g2,
            },
            value: Some(Soa3Mut {
                x: s0,
                y: s1,
                z: s2,
            }),
            flags: Some(&mut flags[r.clone()]),
            lobe: Some(&mut lobes[r.clone()]),
            component: None,
            eta: Some(eta),
            roughness: Some(rough),
        };
        batch::sample(exec, &batch, u, sample_out).expect("sample");
    }
}

/// A call of STREAMING_LANES or more whose rows collide in the L2 cache's sets (the
/// rows of one allocation, 20 bytes apart in its 128 KB cycle) holds its outputs back
/// in a ring (kernels::delay) with `stores=held` (and `auto` on a CPU not AMD's): the
/// same bits as calls too small to stream over rows of their own. The rows start at
/// every offset within a line a float may (the ring releases each row's registers
/// moved onto its lines); a last block past the ring's length ends in a partial
/// register. With `stores=direct` the same call stores directly: the same bits again.
#[test]
fn outputs_held_back_are_those_stored_directly_bit_for_bit() {
    let mut rng = Rng::new(34);
    let all = closures(&mut rng);
    let n = STREAMING_LANES + DELAY + 37;
    let l = lanes(n, 1, &mut rng);
    // One allocation, a row every 128 KB and 20 bytes.
    let stride = n.next_multiple_of(32 << 10) + 5;
    for c in &all {
        for kernels in held_and_direct() {
            let exec = Exec {
                kernels,
                threads: Threads::Caller,
            };
            let mut arena = vec![0.0f32; 25 * stride];
            let (inputs, outputs) = arena.split_at_mut(9 * stride);
            let rows: Vec<&[f32]> = inputs
                .chunks_exact_mut(stride)
                .zip(l.wo.iter().chain(&l.wi).chain(&l.u))
                .map(|(row, v)| {
                    row[..n].copy_from_slice(v);
                    &row[..n]
                })
                .collect();
            let mut held: Vec<&mut [f32]> = outputs
                .chunks_exact_mut(stride)
                .map(|r| &mut r[..n])
                .collect();
            let offsets: std::collections::BTreeSet<usize> =
                held.iter().map(|r| r.as_ptr() as usize % 64).collect();
            assert_eq!(offsets.len(), 16, "output rows at every offset in a line");
            // On rayon's workers (a ring per thread), then on the caller's thread.
            let pool = Exec {
                kernels,
                threads: Threads::Global,
            };
            let mut again_ints = [vec![0; n], vec![0; n]];
            eval_and_sample(&pool, c, &rows, &mut held, &mut again_ints, n);
            let again: Vec<Vec<f32>> = held.iter().map(|r| r.to_vec()).collect();
            let mut held_ints = [vec![0; n], vec![0; n]];
            eval_and_sample(&exec, c, &rows, &mut held, &mut held_ints, n);

            // Rows of their own, in calls of one block.
            let mut direct = vec![vec![0.0f32; n]; 16];
            let mut direct_ints = [vec![0; n], vec![0; n]];
            let own: Vec<&[f32]> =
                l.wo.iter()
                    .chain(&l.wi)
                    .chain(&l.u)
                    .map(|v| &v[..])
                    .collect();
            let mut out: Vec<&mut [f32]> = direct.iter_mut().map(|v| &mut v[..]).collect();
            eval_and_sample(&exec, c, &own, &mut out, &mut direct_ints, BLOCK);

            let what = format!("{:?}, {:?}", kernels.isa(), kernels.stores());
            for (k, (a, b)) in held.iter().zip(&direct).enumerate() {
                let same = a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
                assert!(same, "{what}: output row {k} differs");
            }
            assert_eq!(held_ints, direct_ints, "{what}: flags or lobes differ");
            for (k, (a, b)) in again.iter().zip(&direct).enumerate() {
                let same = a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
                assert!(same, "{what}, rayon's workers: output row {k} differs");
            }
            assert_eq!(
                again_ints, direct_ints,
                "{what}, rayon's workers: flags or lobes"
            );
        }
    }
}

/// Which jobs may hold their outputs back (kernels::delay::streams): those of calls of
/// STREAMING_LANES or more, longer than the ring, on kernels whose `stores=` holds.
#[test]
fn only_streaming_jobs_hold_and_only_where_stores_says() {
    let held = Kernels::scalar().with_stores(Stores::Held);
    let lanes = DELAY + 1;
    assert!(delay::streams(held, STREAMING_LANES, lanes));
    assert!(!delay::streams(held, STREAMING_LANES - 1, lanes));
    assert!(!delay::streams(held, STREAMING_LANES, DELAY));
    let direct = Kernels::scalar().with_stores(Stores::Direct);
    assert!(!delay::streams(direct, STREAMING_LANES, lanes));
    assert_eq!(
        delay::streams(Kernels::scalar(), STREAMING_LANES, lanes),
        Stores::Auto.hold()
    );
}
