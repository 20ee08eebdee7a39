//! Nested parameter schemas (groups, arrays, tables): layout, defaults, validation,
//! JSON, lookup and overrides by element. Expected offsets and values are written out
//! by hand from the layout rules (README, "Parameter schemas"), not computed by the
//! code under test.

use glint::Status;
use glint::lobes::{Params, VerifyCase};
use glint::materials::{BuiltinMaterial, Context, Expansion, Material, MaterialModel, Override};
use glint::math::Lane;
use glint::params::{self, ParamKind, ParamSpec, Shape};
use glint::registry::Registry;

/// A schema with every shape: a value, a group (with an enum), an array of floats, a
/// table of {position, color} rows inside nothing, an array of colors in a group.
struct Nested;

const SCHEMA: &[ParamSpec] = &[
    ParamSpec::float("weight", 1.0, 0.0, 1.0, "value"),
    ParamSpec::group("coat", 4, "a group"),
    ParamSpec::float("coat.roughness", 0.1, 0.0, 1.0, ""),
    ParamSpec::rgb("coat.color", [1.0; 3], 0.0, 1.0, ""),
    ParamSpec::choice("coat.mode", &["a", "b"], 1, ""),
    ParamSpec::rgb("coat.tints", [0.5; 3], 0.0, 1.0, "").array(2, 1),
    ParamSpec::float("terms", 2.0, 0.0, 10.0, "").array(4, 0),
    ParamSpec::table("ramp", 2, 3, 2, "keys"),
    ParamSpec::float("ramp.position", 0.25, 0.0, 1.0, "").column(3),
    ParamSpec::rgb("ramp.color", [0.0; 3], 0.0, 1.0, "").column(3),
];

// Offsets by hand: weight 0; coat (no slots) 1; coat.roughness 1; coat.color 2..5;
// coat.mode 5; coat.tints count 6, elements 7..13; terms count 13, elements 14..18;
// ramp count 18; ramp.position 19..22; ramp.color 22..31. Block: 31 floats.
const OFFSETS: [usize; 10] = [0, 1, 1, 2, 5, 6, 13, 18, 19, 22];
const BLOCK: usize = 31;

impl MaterialModel for Nested {
    const NAME: &'static str = "nested_test";
    const SUMMARY: &'static str = "test schema";
    const PARAMS: &'static [ParamSpec] = SCHEMA;
    type Slots = (glint::lobes::lambert::Lambert,);
    const VERIFY_CASES: &'static [VerifyCase] = &[];
    fn expand<L: Lane>(p: Params<'_, L>, _ctx: &Context<L>, out: &mut Expansion<L>) {
        // The lambert color is ramp[1].color: a read at a fixed offset of the block.
        let c = p.rgb(22 + 3);
        out.weight[0] = glint::math::Rgb::new(L::one(), L::one(), L::one());
        out.params[0][0] = c.r;
        out.params[0][1] = c.g;
        out.params[0][2] = c.b;
    }
}

static NESTED: BuiltinMaterial<Nested> = BuiltinMaterial::new();

fn registry() -> (Registry, u32) {
    let mut r = Registry::with_builtins();
    let id = r.register_material(&NESTED).expect("register");
    (r, id)
}

fn defaults() -> Vec<f32> {
    let mut b = vec![f32::NAN; params::block_size(SCHEMA)];
    params::write_defaults(SCHEMA, &mut b);
    b
}

#[test]
fn layout_and_defaults() {
    assert_eq!(params::check_schema(SCHEMA), Ok(()));
    assert_eq!(params::block_size(SCHEMA), BLOCK);
    for (i, &o) in OFFSETS.iter().enumerate() {
        assert_eq!(params::offset_of(SCHEMA, i), o, "entry {i}");
    }
    let parents: Vec<Option<usize>> = (0..SCHEMA.len())
        .map(|i| params::parent_of(SCHEMA, i))
        .collect();
    let expected = [
        None,
        None,
        Some(1),
        Some(1),
        Some(1),
        Some(1),
        None,
        None,
        Some(7),
        Some(7),
    ];
    assert_eq!(parents, expected);
    let mut want = vec![1.0, 0.1, 1.0, 1.0, 1.0, 1.0, 1.0];
    want.extend([0.5; 6]); // coat.tints: count 1 at 6, two rgb elements
    want.push(0.0); // terms count
    want.extend([2.0; 4]);
    want.push(2.0); // ramp count
    want.extend([0.25; 3]);
    want.extend([0.0; 9]);
    assert_eq!(defaults(), want);
    // Flat schemas of every built-in lobe and material are still well formed.
    let r = Registry::with_builtins();
    for t in r.iter() {
        assert_eq!(params::check_schema(t.params()), Ok(()), "{}", t.name());
        assert!(t.params().iter().all(|s| s.shape == Shape::Value));
    }
    for m in r.materials() {
        assert_eq!(params::check_schema(m.params()), Ok(()), "{}", m.name());
    }
}

#[test]
fn bad_schemas_are_refused() {
    let bad: &[(&[ParamSpec], &str)] = &[
        (
            &[
                ParamSpec::group("g", 2, ""),
                ParamSpec::float("g.a", 0.0, 0.0, 1.0, ""),
            ],
            "fit",
        ),
        (
            &[
                ParamSpec::group("g", 1, ""),
                ParamSpec::float("a", 0.0, 0.0, 1.0, ""),
            ],
            "name",
        ),
        (
            &[ParamSpec::float("a", 0.0, 0.0, 1.0, "").array(17, 0)],
            "capacity",
        ),
        (
            &[ParamSpec::float("a", 0.0, 0.0, 1.0, "").array(2, 3)],
            "count",
        ),
        (
            &[ParamSpec::float("a", 0.0, 0.0, 1.0, "").column(2)],
            "outside a table",
        ),
        (
            &[
                ParamSpec::table("t", 1, 4, 0, ""),
                ParamSpec::float("t.a", 0.0, 0.0, 1.0, "").column(3),
            ],
            "capacity differs",
        ),
        (
            &[
                ParamSpec::table("t", 1, 4, 0, ""),
                ParamSpec::float("t.a", 0.0, 0.0, 1.0, ""),
            ],
            "only columns",
        ),
        (
            &[
                ParamSpec::group("g", 2, ""),
                ParamSpec::group("g.h", 1, ""),
                ParamSpec::float("g.h.a", 0.0, 0.0, 1.0, ""),
            ],
            "nest",
        ),
        (
            &[ParamSpec::choice("e", &["x"], 0, "").array(2, 0)],
            "float or rgb",
        ),
        (&[ParamSpec::float("a", 2.0, 0.0, 1.0, "")], "default"),
        (
            &[
                ParamSpec::float("a", 0.0, 0.0, 1.0, ""),
                ParamSpec::float("a", 0.0, 0.0, 1.0, ""),
            ],
            "twice",
        ),
        (&[ParamSpec::float("a[1]", 0.0, 0.0, 1.0, "")], "name"),
    ];
    for (specs, what) in bad {
        let e = params::check_schema(specs).expect_err(what);
        assert!(e.contains(what), "{e} should mention {what}");
    }
}

#[test]
fn validation_names_the_element() {
    let mut b = defaults();
    assert!(params::validate("t", SCHEMA, &b).is_ok());
    let cases: &[(usize, f32, Status, &str)] = &[
        (
            19 + 2,
            1.5,
            Status::OutOfRange,
            "t.ramp[2].position: 1.5 is outside",
        ),
        (
            22 + 3 + 2, // ramp[1].color.b
            f32::NAN,
            Status::InvalidArgument,
            "t.ramp[1].color: value NaN",
        ),
        (14 + 3, -1.0, Status::OutOfRange, "t.terms[3]: -1"),
        (
            7 + 3,
            f32::INFINITY,
            Status::InvalidArgument,
            "t.coat.tints[1]: value inf",
        ),
        (
            13,
            5.0,
            Status::OutOfRange,
            "t.terms: count 5 is not a whole number in [0, 4]",
        ),
        (18, 1.5, Status::OutOfRange, "t.ramp: count 1.5"),
        (18, -1.0, Status::OutOfRange, "t.ramp: count -1"),
        (6, f32::NAN, Status::OutOfRange, "t.coat.tints: count NaN"),
        (
            5,
            2.0,
            Status::OutOfRange,
            "t.coat.mode: 2 is not a choice index",
        ),
        (1, 1.01, Status::OutOfRange, "t.coat.roughness: 1.01"),
    ];
    for &(at, v, status, msg) in cases {
        let keep = b[at];
        b[at] = v;
        let e = params::validate("t", SCHEMA, &b).expect_err(msg);
        assert_eq!(e.status, status, "{}", e.message);
        assert!(e.message.starts_with(msg), "{} vs {msg}", e.message);
        b[at] = keep;
    }
    assert!(params::validate("t", SCHEMA, &b[..BLOCK - 1]).is_err());
}

#[test]
fn lookup_by_dotted_name_and_element() {
    let find = |n: &str| params::find("t", SCHEMA, n);
    let shift = params::ELEMENT_SHIFT;
    assert_eq!(find("coat.roughness").unwrap(), 2);
    assert_eq!(find("ramp").unwrap(), 7);
    assert_eq!(find("ramp.position").unwrap(), 8);
    assert_eq!(find("ramp[2].position").unwrap(), 8 | 2 << shift);
    assert_eq!(find("ramp[1].color").unwrap(), 9 | 1 << shift);
    assert_eq!(find("terms[3]").unwrap(), 6 | 3 << shift);
    assert_eq!(find("coat.tints[1]").unwrap(), 5 | 1 << shift);
    for (bad, status) in [
        ("ramp[3].position", Status::OutOfRange),
        ("terms[4]", Status::OutOfRange),
        ("terms[99999999999]", Status::UnknownName),
        ("ramp[1]", Status::UnknownName),
        ("terms[1].x", Status::UnknownName),
        ("weight[0]", Status::UnknownName),
        ("coat[0].roughness", Status::UnknownName),
        ("roughness", Status::UnknownName),
        ("terms[-1]", Status::UnknownName),
        ("", Status::UnknownName),
    ] {
        assert_eq!(find(bad).expect_err(bad).status, status, "{bad}");
    }
    // Addresses resolve to the value's block offset.
    let at = |a: u32| params::locate("t", SCHEMA, a, &"x").map(|s| s.offset);
    assert_eq!(at(8 | 2 << shift).unwrap(), 21);
    assert_eq!(at(9 | 1 << shift).unwrap(), 25);
    assert_eq!(at(6 | 3 << shift).unwrap(), 17);
    assert_eq!(at(5 | 1 << shift).unwrap(), 10);
    assert_eq!(at(4).unwrap(), 5);
    assert_eq!(at(1).unwrap_err().status, Status::InvalidArgument); // group header
    assert_eq!(at(7).unwrap_err().status, Status::InvalidArgument); // table header
    assert_eq!(at(2 | 1 << shift).unwrap_err().status, Status::OutOfRange); // one value
    assert_eq!(at(8 | 3 << shift).unwrap_err().status, Status::OutOfRange);
    assert_eq!(at(10).unwrap_err().status, Status::OutOfRange);
    assert_eq!(at(u32::MAX).unwrap_err().status, Status::OutOfRange);
}

fn json(r: &Registry, text: &str) -> Result<Vec<f32>, glint::Error> {
    glint::json::material_from_json(r, text, 0.0).map(|m| m.params().to_vec())
}

#[test]
fn json_nested_forms() {
    let (r, _) = registry();
    let b = json(
        &r,
        r#"{"material": "nested_test", "coat": {"roughness": 0.2, "mode": "a",
            "tints": [[0.1, 0.2, 0.3], 0.9]},
            "terms": [1, 2, 3],
            "ramp": [{"position": 0.5}, {"color": [0.4, 0.5, 0.6], "position": 0.75}]}"#,
    )
    .unwrap();
    let mut want = defaults();
    want[1] = 0.2;
    want[5] = 0.0;
    want[6] = 2.0;
    want[7..13].copy_from_slice(&[0.1, 0.2, 0.3, 0.9, 0.9, 0.9]);
    want[13] = 3.0;
    want[14..17].copy_from_slice(&[1.0, 2.0, 3.0]); // terms[3] keeps its default 2
    want[18] = 2.0;
    want[19] = 0.5;
    want[20] = 0.75; // ramp[0].color keeps its default, ramp[2] all defaults
    want[25..28].copy_from_slice(&[0.4, 0.5, 0.6]);
    assert_eq!(b, want);
    // The dotted name is the same parameter; an empty list sets the count to 0.
    let b = json(
        &r,
        r#"{"material": "nested_test", "coat.roughness": 0.2, "coat.mode": "a", "ramp": []}"#,
    )
    .unwrap();
    assert_eq!((b[1], b[5], b[18]), (0.2, 0.0, 0.0));
}

#[test]
fn json_errors_name_the_path() {
    let (r, _) = registry();
    let cases: &[(&str, Status, &str)] = &[
        (
            r#""terms": [1, 2, 3, 4, 5]"#,
            Status::OutOfRange,
            "5 values given; terms holds at most 4",
        ),
        (
            r#""ramp": [{}, {}, {}, {}]"#,
            Status::OutOfRange,
            "4 row objects given; ramp holds at most 3",
        ),
        (
            r#""ramp": [{"position": 0.5}, {"position": 2}]"#,
            Status::OutOfRange,
            "ramp[1].position: 2 is outside its range [0, 1]",
        ),
        (
            r#""terms": [1, 20]"#,
            Status::OutOfRange,
            "terms[1]: 20 is outside",
        ),
        (
            r#""coat": {"tints": [0.5, [1, 2, 3]]}"#,
            Status::OutOfRange,
            "coat.tints[1]: 2 is outside",
        ),
        (
            r#""terms": 3"#,
            Status::Parse,
            "expected a list of at most 4 values",
        ),
        (
            r#""ramp": [1]"#,
            Status::Parse,
            "\"ramp[0]\": expected an object",
        ),
        (
            r#""ramp": {"position": 1}"#,
            Status::Parse,
            "expected a list of at most 3 row objects",
        ),
        (
            r#""coat": 0.5"#,
            Status::Parse,
            "\"coat\": expected an object",
        ),
        (
            r#""coat": {"gloss": 1}"#,
            Status::UnknownName,
            "valid keys for coat: roughness, color, mode, tints",
        ),
        (
            r#""ramp": [{"pos": 1}]"#,
            Status::UnknownName,
            "valid keys for ramp: position, color",
        ),
        (
            r#""ramp.position": [1]"#,
            Status::UnknownName,
            "unknown key",
        ),
        (
            r#""coat": {"roughness": 0.2}, "coat.roughness": 0.3"#,
            Status::Parse,
            "given twice",
        ),
        (
            r#""terms": ["x"]"#,
            Status::Parse,
            "\"terms[0]\": expected a number",
        ),
        (
            r#""ramp": [{"color": [1, 2]}]"#,
            Status::Parse,
            "\"ramp[0].color\": expected [x, y, z]",
        ),
        (
            r#""coat": {"mode": "c"}"#,
            Status::UnknownName,
            "coat.mode: unknown choice",
        ),
    ];
    for &(body, status, msg) in cases {
        let text = format!(r#"{{"material": "nested_test", {body}}}"#);
        let e = json(&r, &text).expect_err(body);
        assert_eq!(e.status, status, "{body}: {}", e.message);
        assert!(e.message.contains(msg), "{body}: {} lacks {msg}", e.message);
    }
}

#[test]
fn overrides_by_element() {
    let (r, id) = registry();
    let m = Material::new(&r, id, None, 0.0).unwrap();
    let shift = params::ELEMENT_SHIFT;
    let set = |param: u32, kind: ParamKind, value: [f32; 3]| Override { param, kind, value };
    let mut out = vec![0.0; BLOCK];
    m.apply(
        &[
            set(9 | 1 << shift, ParamKind::Rgb, [0.1, 0.2, 0.3]),
            set(6 | 3 << shift, ParamKind::Float, [7.0; 3]),
            set(2, ParamKind::Float, [0.6; 3]),
        ],
        &mut out,
    )
    .unwrap();
    let mut want = defaults();
    want[25..28].copy_from_slice(&[0.1, 0.2, 0.3]);
    want[17] = 7.0;
    want[1] = 0.6;
    assert_eq!(out, want);
    // The expansion reads ramp[1].color: the closure's lambert color is the override.
    let ctx = glint::materials::ShadingContext::new(
        glint::math::Vec3::new(0.0, 0.0, 1.0),
        glint::math::Frame::new(glint::math::Vec3::new(0.0, 0.0, 1.0), None),
    );
    let c = m
        .closure(
            &ctx,
            &[set(9 | 1 << shift, ParamKind::Rgb, [0.1, 0.2, 0.3])],
        )
        .unwrap();
    let wi = glint::math::Vec3::new(0.0, 0.0, 1.0);
    let e = c.eval(wi, wi).unwrap();
    let pi = std::f32::consts::PI;
    assert!(
        (e.value.r - 0.1 / pi).abs() < 1e-6 && (e.value.b - 0.3 / pi).abs() < 1e-6,
        "{e:?}"
    );

    let cases: &[(Override, Status, &str)] = &[
        (
            set(9 | 3 << shift, ParamKind::Rgb, [0.0; 3]),
            Status::OutOfRange,
            "overrides[0]: element 3 of nested_test.ramp.color does not exist",
        ),
        (
            set(8 | 1 << shift, ParamKind::Float, [1.5; 3]),
            Status::OutOfRange,
            "overrides[0]: nested_test.ramp[1].position: 1.5 is outside",
        ),
        (
            set(6 | 2 << shift, ParamKind::Float, [f32::NAN; 3]),
            Status::InvalidArgument,
            "nested_test.terms[2]: value NaN",
        ),
        (
            set(8, ParamKind::Rgb, [0.0; 3]),
            Status::InvalidArgument,
            "ramp.position is a float, not an rgb",
        ),
        (
            set(7, ParamKind::Float, [0.0; 3]),
            Status::InvalidArgument,
            "ramp is a table",
        ),
        (
            set(1, ParamKind::Float, [0.0; 3]),
            Status::InvalidArgument,
            "coat is a group",
        ),
        (
            set(params::address(0, 1), ParamKind::Float, [0.0; 3]),
            Status::OutOfRange,
            "element 1 of nested_test.weight",
        ),
        (
            set(10, ParamKind::Float, [0.0; 3]),
            Status::OutOfRange,
            "parameter index 10 does not exist",
        ),
    ];
    for (o, status, msg) in cases {
        let e = m.apply(std::slice::from_ref(o), &mut out).expect_err(msg);
        assert_eq!(e.status, *status, "{}", e.message);
        assert!(e.message.contains(msg), "{} lacks {msg}", e.message);
    }
    // Material batches override single values only (by index, group members too).
    assert!(m.override_spec(0, 2, ParamKind::Float).is_ok());
    assert_eq!(
        m.override_spec(0, 6, ParamKind::Float).unwrap_err().status,
        Status::Unsupported
    );
    // A block from C is validated whole.
    let mut bad = defaults();
    bad[18] = 4.0;
    assert_eq!(
        Material::new(&r, id, Some(&bad), 0.0).err().unwrap().status,
        Status::OutOfRange
    );
}

/// `params::Bounds` (the quick check of lobe blocks added by C) accepts exactly the
/// blocks `params::validate` accepts, probed one value at a time at every lobe type's
/// edges, and no nested schema gets bounds.
#[test]
fn flat_schema_bounds_agree_with_validate() {
    assert!(params::Bounds::of(SCHEMA).is_none());
    let r = Registry::with_builtins();
    let tiny = f32::from_bits(1);
    for id in 0..r.len() as u32 {
        let lobe = r.get(id).unwrap();
        let specs = lobe.params();
        let bounds = params::Bounds::of(specs).expect("built-in lobe schemas are flat");
        let mut block = vec![0.0; params::block_size(specs)];
        params::write_defaults(specs, &mut block);
        assert!(bounds.admits(&block), "{} defaults", lobe.name());
        assert!(!bounds.admits(&block[1..]), "{}: short block", lobe.name());
        for at in 0..block.len() {
            let keep = block[at];
            let mut probes = vec![
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                -0.0,
                tiny,
                0.5,
                1.0,
                1.5,
                2.0,
                16_777_216.0,
                1e30,
                -1.0,
            ];
            for spec in specs {
                for edge in [spec.min, spec.max] {
                    probes.extend([edge, edge.next_down(), edge.next_up()]);
                }
            }
            for v in probes {
                block[at] = v;
                let valid = params::validate(lobe.name(), specs, &block).is_ok();
                assert_eq!(
                    bounds.admits(&block),
                    valid,
                    "{}: value {at} = {v:e}",
                    lobe.name()
                );
                assert_eq!(r.validate_block(id, &block).is_ok(), valid);
            }
            block[at] = keep;
        }
    }
}

/// A model that takes the built-in `lambert`'s name without being it.
struct Impostor;

impl glint::lobes::Model for Impostor {
    const NAME: &'static str = "lambert";
    const SUMMARY: &'static str = "not the built-in lambert";
    const PARAMS: &'static [ParamSpec] = &[ParamSpec::rgb("color", [0.8; 3], 0.0, 1.0, "")];
    const FLAGS: u32 = glint::lobes::flags::REFLECTION | glint::lobes::flags::DIFFUSE;
    const RECIPROCAL: bool = true;
    fn albedo_tolerance(_params: &[f32]) -> f32 {
        0.0
    }
    type Prepared<L: Lane> = ();
    fn prepare<L: Lane>(_decoded: Params<'_, L>) {}
    fn eval<L: Lane>(
        _p: &(),
        _wo: glint::math::Vec3<L>,
        _wi: glint::math::Vec3<L>,
        _mode: glint::lobes::Transport,
    ) -> glint::lobes::Eval<L> {
        glint::lobes::Eval::zero()
    }
    fn sample<L: Lane>(
        _p: &(),
        _wo: glint::math::Vec3<L>,
        _uc: L,
        _u0: L,
        _u1: L,
        _mode: glint::lobes::Transport,
        _settle: &mut impl glint::lobes::Settle<L>,
    ) -> glint::lobes::Sample<L> {
        glint::lobes::no_sample()
    }
    fn albedo<L: Lane>(
        _p: &(),
        _wo: glint::math::Vec3<L>,
        _mode: glint::lobes::Transport,
    ) -> glint::math::Rgb<L> {
        glint::math::Rgb::zero()
    }
}

/// A material whose slot names a registered type that is not its slot's model.
struct ImpostorMaterial;

impl MaterialModel for ImpostorMaterial {
    const NAME: &'static str = "impostor_test";
    const SUMMARY: &'static str = "slot model unlike its registered type";
    const PARAMS: &'static [ParamSpec] = &[ParamSpec::float("weight", 1.0, 0.0, 1.0, "")];
    type Slots = (Impostor,);
    fn expand<L: Lane>(_p: Params<'_, L>, _ctx: &Context<L>, _out: &mut Expansion<L>) {}
}

static IMPOSTOR: BuiltinMaterial<ImpostorMaterial> = BuiltinMaterial::new();

/// Closures are built by calling each slot's model directly, so the registered type
/// a slot's name resolves to must be that model: compiling refuses the material.
#[test]
fn a_slot_whose_name_is_another_model_is_refused() {
    let mut r = Registry::with_builtins();
    let id = r.register_material(&IMPOSTOR).expect("register");
    let e = Material::new(&r, id, None, 0.0).err().expect("refused");
    assert_eq!(e.status, Status::Unsupported);
    assert!(
        e.message.contains("slot 0") && e.message.contains("lambert"),
        "{}",
        e.message
    );
}
