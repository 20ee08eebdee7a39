//! `include/glint.h` must be what cbindgen generates from `src/ffi` today.
//! Regenerate with `GLINT_BLESS=1 cargo test --test header`.

use std::path::Path;

fn generate() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut out = Vec::new();
    cbindgen::Builder::new()
        .with_config(config)
        // mod.rs brings its submodules (runtime, closure, batch) with it.
        .with_src(root.join("src/ffi/mod.rs"))
        .generate()
        .expect("cbindgen failed")
        .write(&mut out);
    String::from_utf8(out).expect("utf-8 header")
}

#[test]
fn committed_header_is_fresh() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/glint.h");
    let fresh = generate();
    if std::env::var_os("GLINT_BLESS").is_some() {
        std::fs::write(&path, &fresh).expect("write header");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "include/glint.h is stale: run `GLINT_BLESS=1 cargo test --test header` and commit it"
    );
}
