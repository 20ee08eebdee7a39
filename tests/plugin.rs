//! The plugin loader's failures that need no compiled plugin: a missing file, a file
//! that is not a shared library (text, a directory, a device), a library without the
//! entry symbol, the `plugins=`
//! config key. Each leaves the registry as it was. (The example plugins and every
//! other loader error are exercised in C: c_tests/test_plugins.c.)

use glint::registry::Registry;
use glint::{Runtime, Status};
use std::path::{Path, PathBuf};

fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glint-plugin-test-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[track_caller]
fn fails_cleanly(path: &Path, status: Status, mention: &str) {
    let mut registry = Registry::with_builtins();
    let before = registry.names().len();
    let e = glint::plugin::load(&mut registry, path).unwrap_err();
    assert_eq!(e.status, status, "{}", e.message);
    assert!(e.message.contains(mention), "{}", e.message);
    assert_eq!(registry.names().len(), before, "nothing registered");
}

#[test]
fn missing_file() {
    let path = Path::new("/nonexistent/glint/plugin.so");
    fails_cleanly(path, Status::PluginNotFound, "/nonexistent/glint/plugin.so");
}

#[test]
fn not_a_shared_library() {
    let dir = scratch_dir("text");
    let path = dir.join("text.so");
    std::fs::write(&path, "this is not an ELF file\n").unwrap();
    fails_cleanly(
        &path,
        Status::PluginNotLibrary,
        "not a loadable shared library",
    );
}

#[test]
fn a_directory_is_not_a_library() {
    let dir = scratch_dir("directory");
    fails_cleanly(&dir, Status::PluginNotLibrary, "is a directory");
}

#[test]
fn a_device_is_not_a_library() {
    // The loader's own message, not "no such file".
    let e = {
        let mut registry = Registry::with_builtins();
        glint::plugin::load(&mut registry, Path::new("/dev/null")).unwrap_err()
    };
    assert_eq!(e.status, Status::PluginNotLibrary, "{}", e.message);
    assert!(
        e.message.contains("/dev/null") && !e.message.contains("no such file"),
        "{}",
        e.message
    );
    fails_cleanly(
        Path::new("/dev/null"),
        Status::PluginNotLibrary,
        "not a loadable shared library",
    );
}

#[test]
fn library_without_the_entry_symbol() {
    // Any real shared library that is not a plugin: the C math library.
    let libm = Path::new("/lib/x86_64-linux-gnu/libm.so.6");
    if libm.exists() {
        fails_cleanly(libm, Status::PluginNoEntry, "glint_plugin_entry");
    }
}

#[test]
fn plugins_config_key() {
    let e = Runtime::new("plugins=/nonexistent/glint")
        .err()
        .expect("missing directory");
    assert_eq!(e.status, Status::PluginNotFound, "{}", e.message);
    let dir = scratch_dir("config");
    assert_eq!(
        Runtime::new(&format!("plugins={}", dir.display()))
            .unwrap()
            .registry
            .names()
            .len(),
        Registry::with_builtins().names().len(),
        "an empty directory loads nothing"
    );
    std::fs::write(dir.join("broken.so"), "text").unwrap();
    std::fs::write(dir.join("ignored.txt"), "not a plugin name").unwrap();
    let e = Runtime::new(&format!("plugins={}", dir.display()))
        .err()
        .expect("a broken plugin fails the runtime");
    assert_eq!(e.status, Status::PluginNotLibrary, "{}", e.message);
    assert!(e.message.contains("broken.so"), "{}", e.message);
}
