//! `Settings::parse` and `Runtime::new`: the configuration string's keys and values,
//! with errors that name the valid keys and values.

use glint::runtime::{CONFIG_KEYS, Isa, Settings};
use glint::{Runtime, Status};

#[test]
fn defaults_and_valid_values() {
    assert_eq!(Settings::parse("").unwrap().isa, Isa::Auto);
    assert_eq!(Settings::parse("  \t\n").unwrap(), Settings::default());
    assert_eq!(Settings::parse("isa=auto").unwrap().isa, Isa::Auto);
    assert_eq!(Settings::parse("isa=scalar").unwrap().isa, Isa::Scalar);
    // Separators: whitespace, commas, semicolons; the last value wins.
    assert_eq!(
        Settings::parse("isa=auto, isa=scalar").unwrap().isa,
        Isa::Scalar
    );
    assert_eq!(
        Settings::parse("isa=scalar;isa=auto").unwrap().isa,
        Isa::Auto
    );
    assert_eq!(CONFIG_KEYS, ["isa"]);
    let rt = Runtime::new("isa=scalar").unwrap();
    assert_eq!(rt.settings.isa, Isa::Scalar);
    assert_eq!(
        rt.registry.names(),
        ["lambert", "conductor", "dielectric", "mirror"]
    );
}

#[test]
fn simd_isas_are_unsupported_in_this_build() {
    for isa in ["avx2", "avx512"] {
        let e = Settings::parse(&format!("isa={isa}")).unwrap_err();
        assert_eq!(e.status, Status::Unsupported, "{isa}: {}", e.message);
        assert!(
            e.message.contains(isa) && e.message.contains("auto, scalar"),
            "{}",
            e.message
        );
        let e = Runtime::new(&format!("isa={isa}"))
            .err()
            .expect("runtime must fail");
        assert_eq!(e.status, Status::Unsupported);
    }
}

#[test]
fn unknown_key_names_valid_keys() {
    let e = Settings::parse("threads=4").unwrap_err();
    assert_eq!(e.status, Status::UnknownName);
    assert!(
        e.message.contains("threads") && e.message.contains("valid keys: isa"),
        "{}",
        e.message
    );
    let e = Settings::parse("isa=scalar threads=4").unwrap_err();
    assert_eq!(e.status, Status::UnknownName);
    // Keys are case-sensitive.
    assert_eq!(
        Settings::parse("ISA=scalar").unwrap_err().status,
        Status::UnknownName
    );
}

#[test]
fn bad_values_and_syntax() {
    let e = Settings::parse("isa=sse9").unwrap_err();
    assert_eq!(e.status, Status::OutOfRange);
    assert!(
        e.message.contains("sse9") && e.message.contains("auto, scalar"),
        "{}",
        e.message
    );
    let e = Settings::parse("isa").unwrap_err();
    assert_eq!(e.status, Status::Parse);
    assert!(
        e.message.contains("key=value") && e.message.contains("isa"),
        "{}",
        e.message
    );
    assert_eq!(
        Settings::parse("isa=").unwrap_err().status,
        Status::OutOfRange
    );
}
