//! Gives the shared library its soname, `libglint.so.<ABI major>`, so hosts link
//! against the ABI version rather than the file.

fn main() {
    let major = env!("CARGO_PKG_VERSION_MAJOR");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libglint.so.{major}");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
