//! Every SIMD intrinsic is inlined into its kernel. An intrinsic compiled out of line
//! is a function call per vector operation: a closure or an iterator adapter in
//! lane-generic code (`array::map`, `from_fn`, `fold`) is a function of its own, without
//! the kernel's `#[target_feature]`, into which LLVM may not inline the intrinsic (the
//! Disney diffuse albedo ran 4x slower so). This test links every built-in lobe and
//! material kernel (through the registries) and lists this executable's symbols.

use std::process::Command;

/// Out-of-line functions of `core::arch` that are not vector arithmetic.
const ALLOWED: &[&str] = &["_xgetbv"];

#[test]
fn no_intrinsic_is_compiled_out_of_line() {
    if cfg!(debug_assertions) {
        eprintln!("skipped: unoptimized builds inline nothing (CI runs --release)");
        return;
    }
    // Reference every kernel: the registries hold each built-in's vtable.
    let registry = glint::registry::Registry::with_builtins();
    assert!(registry.iter().count() > 0);
    assert!(!glint::materials::BUILTIN_MATERIALS.is_empty());
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
