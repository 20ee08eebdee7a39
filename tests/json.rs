//! The JSON closure format: a valid example per lobe type (parameters land at their
//! schema offsets, weights, frames and transport are honoured, and the result evaluates
//! exactly like the same closure built by hand), and every kind of error with the
//! status and a message that names the problem and lists what is valid.

mod common;

use common::{Block, lobe};
use glint::json::closure_from_json;
use glint::lobes::Transport;
use glint::math::{Frame, Vec3};
use glint::registry::Registry;
use glint::{Closure, Error, Status};

fn parse(text: &str) -> Result<Closure, Error> {
    closure_from_json(
        &Registry::with_builtins(),
        text,
        None,
        glint::materials::DEFAULT_PRUNE,
    )
}

#[track_caller]
fn expect_error(text: &str, status: Status, needles: &[&str]) -> Error {
    let e = match parse(text) {
        Ok(_) => panic!("expected {status:?} for {text}"),
        Err(e) => e,
    };
    assert_eq!(e.status, status, "{text}: {}", e.message);
    for n in needles {
        assert!(
            e.message.contains(n),
            "{text}: message {:?} should mention {n:?}",
            e.message
        );
    }
    e
}

/// The README example, one lobe of each type.
const README: &str = r#"{ "lobes": [
  { "type": "lambert", "weight": 0.6, "color": [0.8, 0.3, 0.2] },
  { "type": "conductor", "distribution": "ggx", "roughness": 0.35, "anisotropic": 0.5,
    "tangent": [1, 0, 0], "fresnel": "artistic",
    "reflectivity": [0.95, 0.64, 0.54], "edge_tint": [1.0, 0.98, 0.9] },
  { "type": "conductor", "distribution": "beckmann", "roughness": 0.2,
    "fresnel": "conductor", "eta": [0.2, 0.92, 1.1], "k": [3.9, 2.45, 2.14] },
  { "type": "dielectric", "roughness": 0.1, "eta": 1.5 },
  { "type": "mirror", "fresnel": "schlick", "f0": 0.9, "f90": 1.0 }
] }"#;

#[test]
fn readme_example_parses_every_lobe() {
    let c = parse(README).unwrap();
    assert!(c.is_finished());
    assert_eq!(c.transport(), Transport::Radiance);
    let names: Vec<&str> = c.lobes().iter().map(|l| l.lobe.name()).collect();
    assert_eq!(
        names,
        ["lambert", "conductor", "conductor", "dielectric", "mirror"]
    );
    assert_eq!(c.lobes()[0].weight.to_array(), [0.6; 3]);
    assert_eq!(c.lobes()[1].weight.to_array(), [1.0; 3]);

    let expected = [
        Block::defaults(lobe("lambert")).rgb("color", [0.8, 0.3, 0.2]),
        Block::defaults(lobe("conductor"))
            .choice("distribution", "ggx")
            .float("roughness", 0.35)
            .float("anisotropic", 0.5)
            .choice("fresnel", "artistic")
            .rgb("reflectivity", [0.95, 0.64, 0.54])
            .rgb("edge_tint", [1.0, 0.98, 0.9]),
        Block::defaults(lobe("conductor"))
            .choice("distribution", "beckmann")
            .float("roughness", 0.2)
            .choice("fresnel", "conductor")
            .rgb("eta", [0.2, 0.92, 1.1])
            .rgb("k", [3.9, 2.45, 2.14]),
        Block::defaults(lobe("dielectric"))
            .float("roughness", 0.1)
            .float("eta", 1.5),
        Block::defaults(lobe("mirror"))
            .choice("fresnel", "schlick")
            .rgb("f0", [0.9; 3])
            .rgb("f90", [1.0; 3]),
    ];
    for (k, b) in expected.iter().enumerate() {
        assert_eq!(c.lobe_params(k), b.as_slice(), "lobe {k} parameters");
    }
    // Explicit values really moved away from the defaults (the test is not vacuous).
    let d = Block::defaults(lobe("conductor"));
    assert_eq!(d.get("distribution"), [0.0]);
    assert_eq!(c.lobe_params(2)[d.offset("distribution")], 1.0);
    assert_eq!(c.lobe_params(2)[d.offset("fresnel")], 1.0);
}

#[test]
fn json_closure_evaluates_like_a_hand_built_one() {
    let text = r#"{ "transport": "importance", "lobes": [
        { "type": "lambert", "weight": [0.2, 0.4, 0.6], "color": 0.5 },
        { "type": "dielectric", "weight": 0.7, "normal": [0, 0.6, 0.8], "tangent": [1, 0, 0],
          "distribution": "beckmann", "roughness": 0.4, "anisotropic": 0.6, "eta": 1.33 } ] }"#;
    let wo = Vec3::new(0.3, 0.2, (1.0f32 - 0.13).sqrt());
    let registry = Registry::with_builtins();
    let c = closure_from_json(&registry, text, Some(wo), glint::materials::DEFAULT_PRUNE).unwrap();
    assert_eq!(c.transport(), Transport::Importance);
    let n = Vec3::new(0.0, 0.6, 0.8);
    let frame = Frame::new(n, Some(Vec3::new(1.0, 0.0, 0.0)));
    assert_eq!(c.lobes()[1].frame, frame);
    assert_eq!(c.lobes()[0].frame, Frame::IDENTITY);

    let mut h = Closure::new(Some(wo), Transport::Importance);
    let lambert = Block::defaults(lobe("lambert")).rgb("color", [0.5; 3]);
    let diel = Block::defaults(lobe("dielectric"))
        .choice("distribution", "beckmann")
        .float("roughness", 0.4)
        .float("anisotropic", 0.6)
        .float("eta", 1.33);
    h.add_lobe(
        &registry,
        registry.find("lambert").unwrap(),
        [0.2, 0.4, 0.6],
        Frame::IDENTITY,
        Some(lambert.as_slice()),
    )
    .unwrap();
    h.add_lobe(
        &registry,
        registry.find("dielectric").unwrap(),
        [0.7; 3],
        frame,
        Some(diel.as_slice()),
    )
    .unwrap();
    h.finish().unwrap();
    for k in 0..2 {
        assert_eq!(c.lobes()[k].probability, h.lobes()[k].probability);
    }
    for wi in [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(-0.3, -0.2, -(1.0f32 - 0.13).sqrt()),
        Vec3::new(0.6, 0.0, 0.8),
    ] {
        assert_eq!(c.eval(wo, wi).unwrap(), h.eval(wo, wi).unwrap());
    }
    assert_eq!(
        c.sample(wo, [0.7, 0.1, 0.4]).unwrap(),
        h.sample(wo, [0.7, 0.1, 0.4]).unwrap()
    );
}

#[test]
fn normal_is_normalized_and_defaults_fill_the_rest() {
    let c =
        parse(r#"{"lobes":[{"type":"mirror","normal":[0,0,2]},{"type":"dielectric"}]}"#).unwrap();
    assert_eq!(c.lobes()[0].frame.n, Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(c.lobe_params(0), Block::defaults(lobe("mirror")).as_slice());
    assert_eq!(
        c.lobe_params(1),
        Block::defaults(lobe("dielectric")).as_slice()
    );
}

#[test]
fn an_empty_lobe_list_is_an_error() {
    expect_error(
        r#"{"lobes": []}"#,
        Status::Parse,
        &["\"lobes\"", "at least one lobe"],
    );
}

#[test]
fn duplicate_keys_are_errors_naming_the_key() {
    for (text, key) in [
        (
            r#"{"lobes": [{"type": "lambert", "type": "mirror"}]}"#,
            "type",
        ),
        (
            r#"{"lobes": [{"type": "mirror"}], "lobes": [{"type": "lambert"}]}"#,
            "lobes",
        ),
        (
            r#"{"lobes": [{"type": "lambert", "color": 0.1, "color": 0.9}]}"#,
            "color",
        ),
        (
            r#"{"transport": "radiance", "lobes": [{"type": "lambert"}], "transport": "importance"}"#,
            "transport",
        ),
    ] {
        expect_error(
            text,
            Status::Parse,
            &["duplicate key", &format!("\"{key}\"")],
        );
    }
}

#[test]
fn a_zero_tangent_is_automatic_as_in_the_c_api() {
    let auto = parse(r#"{"lobes": [{"type": "conductor", "normal": [0, 0.6, 0.8]}]}"#).unwrap();
    let zero = parse(
        r#"{"lobes": [{"type": "conductor", "normal": [0, 0.6, 0.8], "tangent": [0, 0, 0]}]}"#,
    )
    .unwrap();
    assert_eq!(zero.lobes()[0].frame, auto.lobes()[0].frame);
    // A tangent along the normal has no usable part either: automatic, as in C.
    let along = parse(
        r#"{"lobes": [{"type": "conductor", "normal": [0, 0.6, 0.8], "tangent": [0, 3, 4]}]}"#,
    )
    .unwrap();
    assert_eq!(along.lobes()[0].frame, auto.lobes()[0].frame);
}

#[test]
fn a_leading_byte_order_mark_is_skipped() {
    let c = parse("\u{feff}{\"lobes\": [{\"type\": \"lambert\"}]}").unwrap();
    assert_eq!(c.lobes().len(), 1);
    // Anywhere else it is a stray character.
    expect_error(
        "{\"lobes\": [{\"type\": \"lambert\"}]} \u{feff}",
        Status::Parse,
        &["malformed JSON"],
    );
}

#[test]
fn control_characters_are_escaped_in_messages() {
    // JSON escapes of control characters in keys, a lobe type and a choice.
    for (text, status) in [
        (
            r#"{"lobes": [{"type": "lambert", "co\u0007lor": 1}]}"#,
            Status::UnknownName,
        ),
        (r#"{"lo\u001b[31mbes": []}"#, Status::UnknownName),
        (
            r#"{"lobes": [{"type": "lam\u0007bert"}]}"#,
            Status::UnknownName,
        ),
        (
            r#"{"lobes": [{"type": "conductor", "fresnel": "sch\u0007lick"}]}"#,
            Status::UnknownName,
        ),
        (
            r#"{"lobes": [{"type": "lambert", "co\u0007lor": 1, "co\u0007lor": 2}]}"#,
            Status::Parse,
        ),
    ] {
        // Shown JSON-escaped: \u0007, \u001b.
        let e = expect_error(text, status, &["\\u00"]);
        assert!(
            !e.message.chars().any(char::is_control),
            "{text:?}: raw control character in {:?}",
            e.message
        );
    }
}

#[test]
fn malformed_json() {
    expect_error(
        r#"{"lobes": [ {"type": "lambert" ] }"#,
        Status::Parse,
        &["malformed JSON"],
    );
    expect_error("", Status::Parse, &["malformed JSON"]);
    expect_error(r#"{"lobes": [], }"#, Status::Parse, &["malformed JSON"]);
}

#[test]
fn wrong_structure() {
    expect_error("[1, 2]", Status::Parse, &["JSON object", "lobes"]);
    expect_error("{}", Status::Parse, &["\"lobes\" array"]);
    expect_error(
        r#"{"lobes": {"type": "lambert"}}"#,
        Status::Parse,
        &["\"lobes\" array"],
    );
    expect_error(r#"{"lobes": [3]}"#, Status::Parse, &["lobes[0]", "object"]);
    expect_error(
        r#"{"lobes": [{"color": 0.5}]}"#,
        Status::Parse,
        &[
            "lobes[0]",
            "\"type\"",
            "lambert, conductor, dielectric, mirror",
        ],
    );
}

#[test]
fn unknown_lobe_type_lists_valid_types() {
    expect_error(
        r#"{"lobes": [{"type": "lambert"}, {"type": "plastic"}]}"#,
        Status::UnknownName,
        &["plastic", "lambert, conductor, dielectric, mirror"],
    );
}

#[test]
fn unknown_keys_list_valid_keys() {
    let e = expect_error(
        r#"{"lobes": [{"type": "dielectric", "ior": 1.5}]}"#,
        Status::UnknownName,
        &[
            "lobes[0]",
            "ior",
            "type",
            "weight",
            "normal",
            "tangent",
            "distribution",
            "roughness",
            "anisotropic",
            "eta",
        ],
    );
    assert!(e.message.contains("dielectric"));
    expect_error(
        r#"{"lobes": [], "mode": "radiance"}"#,
        Status::UnknownName,
        &["mode", "lobes, transport"],
    );
}

#[test]
fn bad_choices_list_valid_choices() {
    expect_error(
        r#"{"lobes": [{"type": "conductor", "distribution": "phong"}]}"#,
        Status::UnknownName,
        &["distribution", "phong", "ggx, beckmann"],
    );
    expect_error(
        r#"{"lobes": [{"type": "mirror", "fresnel": "dielectric"}]}"#,
        Status::UnknownName,
        &["fresnel", "dielectric", "schlick, conductor, artistic"],
    );
    expect_error(
        r#"{"transport": "photons", "lobes": []}"#,
        Status::UnknownName,
        &["transport", "radiance", "importance"],
    );
}

#[test]
fn out_of_range_values_name_the_parameter() {
    expect_error(
        r#"{"lobes": [{"type": "conductor", "roughness": 1.5}]}"#,
        Status::OutOfRange,
        &["roughness", "1.5", "[0, 1]"],
    );
    expect_error(
        r#"{"lobes": [{"type": "lambert", "color": [0.5, -0.1, 0.5]}]}"#,
        Status::OutOfRange,
        &["color", "-0.1"],
    );
    expect_error(
        r#"{"lobes": [{"type": "dielectric", "eta": 0}]}"#,
        Status::OutOfRange,
        &["eta", "0.001, 1000"],
    );
    // Beyond f32: infinite after conversion.
    expect_error(
        r#"{"lobes": [{"type": "dielectric", "eta": 1e40}]}"#,
        Status::InvalidArgument,
        &["eta", "finite"],
    );
    expect_error(
        r#"{"lobes": [{"type": "lambert", "weight": -1}]}"#,
        Status::InvalidArgument,
        &["weight"],
    );
}

#[test]
fn wrong_types() {
    expect_error(
        r#"{"lobes": [{"type": "conductor", "roughness": "rough"}]}"#,
        Status::Parse,
        &["roughness", "expected a number", "rough"],
    );
    expect_error(
        r#"{"lobes": [{"type": "lambert", "color": [1, 0.5]}]}"#,
        Status::Parse,
        &["color", "[x, y, z]"],
    );
    expect_error(
        r#"{"lobes": [{"type": "lambert", "color": [1, "a", 0]}]}"#,
        Status::Parse,
        &["color", "expected a number"],
    );
    expect_error(
        r#"{"lobes": [{"type": "conductor", "distribution": 1}]}"#,
        Status::Parse,
        &["distribution", "ggx, beckmann"],
    );
    expect_error(r#"{"lobes": [{"type": 3}]}"#, Status::Parse, &["\"type\""]);
    expect_error(
        r#"{"lobes": [{"type": "lambert", "normal": [0, 0]}]}"#,
        Status::Parse,
        &["normal"],
    );
    expect_error(
        r#"{"lobes": [{"type": "lambert", "normal": [0, 0, 0]}]}"#,
        Status::InvalidArgument,
        &["normal", "zero length"],
    );
    expect_error(
        r#"{"lobes": [{"type": "lambert", "tangent": "x"}]}"#,
        Status::Parse,
        &["tangent"],
    );
    expect_error(
        r#"{"transport": 1, "lobes": []}"#,
        Status::UnknownName,
        &["transport"],
    );
}

/// A material entry whose lobes would take the closure past 16 is refused with the
/// limit named, and one that fits is expanded after the lobes before it.
#[test]
fn a_material_past_the_lobe_limit_is_refused() {
    let lobes = [r#"{"type": "lambert"}"#; 15].join(",");
    let disney = r#"{"material": "disney", "clearcoat": 1, "sheen": 1}"#;
    expect_error(
        &format!(r#"{{"lobes": [{lobes}, {disney}]}}"#),
        Status::ClosureFull,
        &["16"],
    );
    let lobes = [r#"{"type": "lambert"}"#; 12].join(",");
    let c = parse(&format!(r#"{{"lobes": [{lobes}, {disney}]}}"#)).unwrap();
    assert!(c.lobes().len() > 13 && c.lobes().len() <= 16);
}

#[test]
fn too_many_lobes() {
    let lobes = vec![r#"{"type": "lambert"}"#; 17].join(",");
    expect_error(
        &format!(r#"{{"lobes": [{lobes}]}}"#),
        Status::ClosureFull,
        &["16"],
    );
    let lobes = vec![r#"{"type": "lambert"}"#; 16].join(",");
    assert_eq!(
        parse(&format!(r#"{{"lobes": [{lobes}]}}"#))
            .unwrap()
            .lobes()
            .len(),
        16
    );
}
