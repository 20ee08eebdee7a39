//! Every SIMD intrinsic is inlined into its kernel. An intrinsic compiled out of line
//! is a function call per vector operation: a closure or an iterator adapter in
//! lane-generic code (`array::map`, `from_fn`, `fold`) is a function of its own, without
//! the kernel's `#[target_feature]`, into which LLVM may not inline the intrinsic (the
//! Disney diffuse albedo ran 4x slower so; the material sample's rows kernel spent
//! 3% of its time in a `map` of random-number loads). This test links every built-in
//! lobe and material kernel (through the registries, and one call of each batch entry
//! point for the kernels only the batch layer runs) and lists this executable's
//! symbols.

use std::process::Command;

/// Out-of-line functions of `core::arch` that are not vector arithmetic.
const ALLOWED: &[&str] = &["_xgetbv"];

#[test]
fn no_intrinsic_is_compiled_out_of_line() {
    if cfg!(debug_assertions) {
        eprintln!("skipped: unoptimized builds inline nothing (CI runs --release)");
        return;
    }
    // Reference every kernel: the registries hold each built-in's vtable, and the
    // batch calls (closures and materials) reach the kernels the batch layer runs.
    let registry = glint::registry::Registry::with_builtins();
    assert!(registry.iter().count() > 0);
    assert!(!glint::materials::BUILTIN_MATERIALS.is_empty());
    run_every_batch_call(&registry);
    let exe = std::env::current_exe().expect("test executable");
    let out = match Command::new("nm")
        .args(["-C", "--defined-only"])
        .arg(&exe)
        .output()
    {
        Ok(out) if out.status.success() => out,
        other => panic!("nm (binutils) is needed to list symbols: {other:?}"),
    };
    let symbols = String::from_utf8_lossy(&out.stdout);
    let out_of_line: Vec<&str> = symbols
        .lines()
        .filter_map(|l| l.split_once(" t ").or_else(|| l.split_once(" T ")))
        .map(|(_, name)| name)
        .filter(|name| name.contains("core_arch::") && !ALLOWED.iter().any(|a| name.ends_with(a)))
        .collect();
    assert!(
        out_of_line.is_empty(),
        "{} intrinsics compiled out of line: {:?}",
        out_of_line.len(),
        out_of_line
    );
}

/// Each batch entry point once, over a closure and over a material, on every kernel set.
fn run_every_batch_call(registry: &glint::registry::Registry) {
    use glint::batch::material::{self, MaterialInput};
    use glint::batch::{
        self as closures_batch, BatchInput, EvalOutput, Exec, SampleOutput, SampleRandoms,
    };
    use glint::batch::{Soa3, Soa3Mut, Threads};
    let m = glint::json::material_from_json(
        registry,
        r#"{"material": "disney", "sheen": 1, "clearcoat": 1, "anisotropic": 0.5}"#,
        1e-3,
    )
    .unwrap();
    let n = 40;
    let z = vec![0.0f32; n];
    let up = vec![1.0f32; n];
    let half = vec![0.5f32; n];
    let dir = Soa3 {
        x: &z,
        y: &z,
        z: &up,
    };
    let closure = m
        .closure(
            &glint::materials::ShadingContext::new(
                glint::math::Vec3::new(0.0, 0.0, 1.0),
                glint::math::Frame::IDENTITY,
            ),
            &[],
        )
        .unwrap();
    let randoms = SampleRandoms {
        u_lobe: &half,
        u0: &half,
        u1: &half,
    };
    for kernels in glint::simd::Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let mut rows: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0f32; n]);
        let [a, b, c, d, e, f, g, h, pdf] = &mut rows;
        let closures = BatchInput {
            count: n,
            closures: &closure,
            active: None,
            wo: dir,
        };
        let materials = MaterialInput {
            count: n,
            material: &m,
            active: None,
            wo: dir,
            normal: dir,
            tangent: None,
            overrides: &[],
        };
        closures_batch::eval(
            &exec,
            &closures,
            dir,
            EvalOutput {
                value: Soa3Mut { x: a, y: b, z: c },
                pdf,
                pdf_reverse: None,
            },
        )
        .unwrap();
        // With the reverse pdf the slots are taken one by one; without, in one pass.
        for reverse in [true, false] {
            material::eval(
                &exec,
                &materials,
                dir,
                EvalOutput {
                    value: Soa3Mut { x: a, y: b, z: c },
                    pdf,
                    pdf_reverse: reverse.then_some(&mut d[..]),
                },
            )
            .unwrap();
        }
        for over_closure in [true, false] {
            let out = SampleOutput {
                wi: Soa3Mut { x: a, y: b, z: c },
                pdf,
                weight: Soa3Mut { x: d, y: e, z: f },
                value: None,
                flags: None,
                lobe: None,
                component: None,
                eta: Some(g),
                roughness: Some(h),
            };
            let u = randoms;
            if over_closure {
                closures_batch::sample(&exec, &closures, u, out).unwrap();
            } else {
                material::sample(&exec, &materials, u, out).unwrap();
            }
        }
        material::albedo(&exec, &materials, Soa3Mut { x: a, y: b, z: c }).unwrap();
        closures_batch::albedo(&exec, &closures, Soa3Mut { x: a, y: b, z: c }).unwrap();
    }
}
