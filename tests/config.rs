//! `Settings::parse` and `Runtime::new`: the configuration string's keys and values,
//! with errors that name the valid keys and values.

use glint::kernels::delay::Stores;
use glint::runtime::{CONFIG_KEYS, IsaSetting, MAX_THREADS, Settings};
use glint::simd::{Isa, Kernels, is_amd};
use glint::{Runtime, Status};

#[test]
fn defaults_and_valid_values() {
    assert_eq!(Settings::parse("").unwrap().isa, IsaSetting::Auto);
    assert_eq!(Settings::parse("  \t\n").unwrap(), Settings::default());
    assert_eq!(Settings::parse("isa=auto").unwrap().isa, IsaSetting::Auto);
    assert_eq!(
        Settings::parse("isa=scalar").unwrap().isa,
        IsaSetting::Only(Isa::Scalar)
    );
    // Separators: whitespace, commas, semicolons; the last value wins.
    assert_eq!(
        Settings::parse("isa=auto, isa=scalar").unwrap().isa,
        IsaSetting::Only(Isa::Scalar)
    );
    assert_eq!(
        Settings::parse("isa=scalar;isa=auto").unwrap().isa,
        IsaSetting::Auto
    );
    assert_eq!(
        Settings::parse("isa=avx512").unwrap().isa,
        IsaSetting::Only(Isa::Avx512)
    );
    assert_eq!(Settings::parse("threads=3").unwrap().threads, 3);
    assert_eq!(Settings::parse("").unwrap().threads, 0);
    assert_eq!(
        CONFIG_KEYS,
        ["isa", "threads", "plugins", "prune", "stores"]
    );
    assert_eq!(Settings::parse("").unwrap().prune, 1e-3);
    assert_eq!(Settings::parse("prune=0").unwrap().prune, 0.0);
    assert_eq!(Settings::parse("prune=0.25").unwrap().prune, 0.25);
    for bad in ["prune=-0.1", "prune=2", "prune=nan", "prune=x"] {
        let e = Settings::parse(bad).unwrap_err();
        assert_eq!(e.status, Status::OutOfRange, "{bad}");
        assert!(e.message.contains("[0, 1]"), "{}", e.message);
    }
    let rt = Runtime::new("isa=scalar").unwrap();
    assert_eq!(rt.settings.isa, IsaSetting::Only(Isa::Scalar));
    assert_eq!(rt.kernels(), Kernels::scalar());
    assert_eq!(
        rt.registry.names(),
        [
            "lambert",
            "conductor",
            "dielectric",
            "mirror",
            "disney_diffuse",
            "disney_sheen",
            "disney_specular",
            "disney_clearcoat"
        ]
    );
}

#[test]
fn every_isa_this_cpu_has_can_be_forced_and_the_others_are_refused() {
    assert_eq!(Runtime::new("").unwrap().kernels(), Kernels::best());
    for isa in Isa::ALL {
        let config = format!("isa={}", isa.name());
        match Runtime::new(&config) {
            Ok(rt) => {
                assert!(isa.is_supported());
                assert_eq!(rt.kernels().isa(), isa);
            }
            Err(e) => {
                assert!(!isa.is_supported(), "{config}: {}", e.message);
                assert_eq!(e.status, Status::Unsupported);
                assert!(
                    e.message.contains(isa.name()) && e.message.contains("scalar"),
                    "{}",
                    e.message
                );
            }
        }
    }
}

#[test]
fn threads_values() {
    for n in [0, 1, 2, MAX_THREADS] {
        assert_eq!(Settings::parse(&format!("threads={n}")).unwrap().threads, n);
    }
    for bad in ["-1", "x", "", "1025", "2.5"] {
        let e = Settings::parse(&format!("threads={bad}")).unwrap_err();
        assert_eq!(e.status, Status::OutOfRange, "threads={bad}");
        assert!(e.message.contains("threads="), "{}", e.message);
    }
    assert!(Runtime::new("threads=2").is_ok());
}

#[test]
fn unknown_key_names_valid_keys() {
    let e = Settings::parse("frobnicate=4").unwrap_err();
    assert_eq!(e.status, Status::UnknownName);
    assert!(
        e.message.contains("frobnicate") && e.message.contains("valid keys: isa, threads"),
        "{}",
        e.message
    );
    let e = Settings::parse("isa=scalar lanes=4").unwrap_err();
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
        e.message.contains("sse9") && e.message.contains("auto, scalar, avx2, avx512"),
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

/// `stores=`: whether the fused kernels hold their outputs back (kernels::delay::Stores);
/// the runtime's kernels carry it. `auto` holds the outputs back except on AMD's CPUs,
/// whose vendor `/proc/cpuinfo` also names.
#[test]
fn stores_values() {
    assert_eq!(Settings::parse("").unwrap().stores, Stores::Auto);
    for (value, stores) in [
        ("auto", Stores::Auto),
        ("held", Stores::Held),
        ("direct", Stores::Direct),
    ] {
        let config = format!("stores={value}");
        assert_eq!(Settings::parse(&config).unwrap().stores, stores);
        let rt = Runtime::new(&format!("{config} isa=scalar")).unwrap();
        assert_eq!(rt.kernels(), Kernels::scalar().with_stores(stores));
    }
    for bad in ["", "ring", "Held", "1"] {
        let e = Settings::parse(&format!("stores={bad}")).unwrap_err();
        assert_eq!(e.status, Status::OutOfRange, "stores={bad}");
        assert!(e.message.contains("auto, held, direct"), "{}", e.message);
    }
    assert!(Stores::Held.hold());
    assert!(!Stores::Direct.hold());
    if let Ok(cpuinfo) = std::fs::read_to_string("/proc/cpuinfo") {
        let vendor = cpuinfo
            .lines()
            .find_map(|l| l.strip_prefix("vendor_id"))
            .map(|v| v.trim_start_matches([' ', '\t', ':']).trim());
        if let Some(vendor) = vendor {
            assert_eq!(is_amd(), vendor == "AuthenticAMD", "vendor_id {vendor}");
            assert_eq!(Stores::Auto.hold(), vendor != "AuthenticAMD");
        }
    }
}
