//! Version-2 tables declared here rather than in a shared library, through the loader's
//! own `register_table`: every static rule of glint_plugin.h's V2 structs as a load
//! error that registers nothing, each per-sample class and component rule as a counted
//! repair seen through `Closure::sample`, V1 tables reporting their type's class and
//! component 0, and the harness failing a lobe whose samples needed repairs. (The
//! compiled plugins, the C API and the sample batch: c_tests/test_plugins_v2.c.)

use super::*;
use crate::closure::Closure;
use crate::math::Frame;
use crate::verify::{Report, Tier, verify_lobe};
use std::f32::consts::PI;

/// Block of the test lobe: reflectance, then what every sample reports: class,
/// component, and 1 for a delta (mirror) event.
const REFLECTANCE: usize = 0;
const CLASS: usize = 1;
const COMPONENT: usize = 2;
const DELTA: usize = 3;

fn param(name: &'static CStr, default: f32, max: f32) -> abi::Param {
    abi::Param {
        name: name.as_ptr(),
        kind: abi::PARAM_FLOAT,
        offset: 0,
        default_value: [default, 0.0, 0.0],
        min: 0.0,
        max,
        choices: std::ptr::null(),
        choice_count: 0,
        doc: std::ptr::null(),
    }
}

/// The parameter table, forever (the registered types point into it).
fn params() -> *const abi::Param {
    let mut table = [
        param(c"reflectance", 0.5, 1.0),
        param(c"class", flags::DIFFUSE as f32, 64.0),
        param(c"component", 0.0, 70000.0),
        param(c"delta", 0.0, 1.0),
    ];
    for (i, p) in table.iter_mut().enumerate() {
        p.offset = 4 * i as u32;
    }
    Box::leak(Box::new(table)).as_ptr()
}

/// Lambert: value = reflectance cos_i / pi, one-sided.
unsafe extern "C" fn eval(
    params: *const c_void,
    wo: *const [f32; 3],
    wi: *const [f32; 3],
    _: u32,
    value: *mut [f32; 3],
    pdf: *mut f32,
) {
    // SAFETY: Glint passes a 4-float block and valid direction and output pointers.
    unsafe {
        let k = *params.cast::<f32>();
        let c = if (*wo)[2] > 0.0 && (*wi)[2] > 0.0 {
            (*wi)[2]
        } else {
            0.0
        };
        *value = [k * c / PI; 3];
        *pdf = c / PI;
    }
}

unsafe extern "C" fn albedo(params: *const c_void, wo: *const [f32; 3], _: u32, a: *mut [f32; 3]) {
    // SAFETY: as in `eval`.
    unsafe {
        *a = [if (*wo)[2] > 0.0 {
            *params.cast::<f32>()
        } else {
            0.0
        }; 3]
    }
}

/// Lambert's cosine-weighted sample, or the mirror direction as a delta event.
fn lambert_sample(p: &[f32], wo: [f32; 3], u: [f32; 3]) -> ([f32; 3], [f32; 3], f32, u32) {
    if p[DELTA] >= 0.5 {
        return (
            [-wo[0], -wo[1], wo[2]],
            [p[REFLECTANCE]; 3],
            1.0,
            abi::EVENT_DELTA,
        );
    }
    let (r, phi) = (u[1].sqrt(), 2.0 * PI * u[2]);
    let ci = (1.0 - u[1]).sqrt();
    (
        [r * phi.cos(), r * phi.sin(), ci],
        [p[REFLECTANCE] * ci / PI; 3],
        ci / PI,
        0,
    )
}

/// A sample callback's arguments as a block, `wo`, `u` and the sample to fill.
///
/// # Safety
/// The pointers are valid as Glint passes them: a 4-float block, directions, a sample.
unsafe fn sample_args<'a, S>(
    params: *const c_void,
    wo: *const [f32; 3],
    u: *const [f32; 3],
    out: *mut S,
) -> (&'a [f32], [f32; 3], [f32; 3], &'a mut S) {
    // SAFETY: the caller's contract.
    unsafe {
        (
            std::slice::from_raw_parts(params.cast::<f32>(), 4),
            *wo,
            *u,
            &mut *out,
        )
    }
}

/// The V2 sample: the class and component the block says. Refuses to sample when Glint
/// did not set struct_size.
unsafe extern "C" fn sample_v2(
    params: *const c_void,
    wo: *const [f32; 3],
    u: *const [f32; 3],
    _: u32,
    out: *mut abi::SampleV2,
) -> i32 {
    // SAFETY: Glint passes a 4-float block, valid directions and its own sample.
    let (p, wo, u, out) = unsafe { sample_args(params, wo, u, out) };
    if out.struct_size as usize != size_of::<abi::SampleV2>() || wo[2] <= 0.0 {
        return 0;
    }
    (out.wi, out.value, out.pdf, out.events) = lambert_sample(p, wo, u);
    out.eta = 1.0;
    out.sample_class = p[CLASS] as u32;
    out.component = p[COMPONENT] as u32;
    1
}

unsafe extern "C" fn sample_v1(
    params: *const c_void,
    wo: *const [f32; 3],
    u: *const [f32; 3],
    _: u32,
    out: *mut abi::Sample,
) -> i32 {
    // SAFETY: Glint passes a 4-float block, valid directions and its own sample.
    let (p, wo, u, out) = unsafe { sample_args(params, wo, u, out) };
    if wo[2] <= 0.0 {
        return 0;
    }
    (out.wi, out.value, out.pdf, out.events) = lambert_sample(p, wo, u);
    out.eta = 1.0;
    1
}

fn lobe_v2(name: &'static CStr, lobe_flags: u32, component_count: u32) -> abi::LobeV2 {
    abi::LobeV2 {
        struct_size: size_of::<abi::LobeV2>() as u32,
        name: name.as_ptr(),
        summary: c"a test lobe".as_ptr(),
        flags: lobe_flags,
        reciprocal: 1,
        params: params(),
        param_count: 4,
        block_size: 16,
        block_align: 4,
        eval: Some(eval),
        sample: Some(sample_v2),
        albedo: Some(albedo),
        eval_batch: None,
        component_count,
    }
}

/// A V2 table of `lobes`, forever.
fn table_v2(lobes: Vec<abi::LobeV2>) -> *const c_void {
    let lobes = Box::leak(lobes.into_boxed_slice());
    let table = abi::PluginV2 {
        struct_size: size_of::<abi::PluginV2>() as u32,
        name: c"test".as_ptr(),
        lobe_count: lobes.len() as u32,
        lobes: lobes.as_ptr(),
    };
    (Box::leak(Box::new(table)) as *const abi::PluginV2).cast()
}

fn register(
    registry: &mut Registry,
    version: u32,
    table: *const c_void,
) -> Result<Vec<u32>, Error> {
    // SAFETY: every table here is NULL or built by this file, valid forever.
    unsafe { register_table(registry, version, table, "test") }
}

const DIFFUSE_GLOSSY: u32 = flags::REFLECTION | flags::DIFFUSE | flags::GLOSSY;

/// One sample of the lobe `id` with this class, component and delta setting, from a
/// closure in a tilted frame; the number of repairs it caused.
fn sample(registry: &Registry, id: u32, reported: [f32; 3]) -> (u32, u32, u64) {
    let lobe = registry.get(id).unwrap();
    let before = lobe.sanitized_count();
    let frame = Frame::new(Vec3::new(0.2, -0.3, 0.9).normalize(), None);
    let mut c = Closure::new(None, Transport::Radiance);
    let block = [0.7, reported[0], reported[1], reported[2]];
    c.add_lobe(registry, id, [1.0; 3], frame, Some(&block))
        .unwrap();
    c.finish().unwrap();
    let wo = frame.to_world(Vec3::new(0.3, 0.1, 0.8).normalize());
    let s = c.sample(wo, [0.5, 0.3, 0.7]).expect("a sample");
    assert!(s.weight.r > 0.0 && s.weight.r.is_finite());
    (s.flags, s.component, lobe.sanitized_count() - before)
}

#[test]
fn v2_samples_report_their_class_and_component() {
    let mut registry = Registry::with_builtins();
    let ids = register(
        &mut registry,
        2,
        table_v2(vec![lobe_v2(c"layers", DIFFUSE_GLOSSY, 3)]),
    )
    .unwrap();
    let r = flags::REFLECTION;
    for (class, component) in [(flags::DIFFUSE, 0), (flags::GLOSSY, 2), (flags::DIFFUSE, 1)] {
        assert_eq!(
            sample(&registry, ids[0], [class as f32, component as f32, 0.0]),
            (r | class, component, 0)
        );
    }
}

#[test]
fn broken_classes_and_components_are_repaired_and_counted() {
    let mut registry = Registry::with_builtins();
    let lobes = vec![
        lobe_v2(c"layers", DIFFUSE_GLOSSY, 3),
        lobe_v2(
            c"mirror_or_matte",
            flags::REFLECTION | flags::DIFFUSE | flags::SPECULAR,
            1,
        ),
    ];
    let ids = register(&mut registry, 2, table_v2(lobes)).unwrap();
    let (r, d, g, s) = (
        flags::REFLECTION,
        flags::DIFFUSE,
        flags::GLOSSY,
        flags::SPECULAR,
    );
    // (lobe, [class, component, delta]) -> (flags, component, repairs); a repaired class
    // is what a V1 sample of the type reports (both of `layers`' classes).
    let cases = [
        (0, [0, 0, 0], (r | d | g, 0, 1)),     // class unset
        (0, [d | g, 1, 0], (r | d | g, 1, 1)), // two classes
        (0, [r | d, 1, 0], (r | d | g, 1, 1)), // a side bit, not a class
        (0, [s, 0, 0], (r | d | g, 0, 1)),     // undeclared (and not delta)
        (0, [64, 0, 0], (r | d | g, 0, 1)),    // no flag at all
        (0, [g, 3, 0], (r | g, 0, 1)),         // component == component_count
        (0, [g, 70000, 0], (r | g, 0, 1)),     // past MAX_COMPONENT too
        (0, [0, 9, 0], (r | d | g, 0, 2)),     // both
        (1, [s, 0, 1], (r | s, 0, 0)),         // delta and SPECULAR: kept
        (1, [d, 0, 1], (r | s, 0, 1)),         // delta must be SPECULAR
        (1, [s, 0, 0], (r | d, 0, 1)),         // SPECULAR must be delta
        (1, [d, 0, 0], (r | d, 0, 0)),
    ];
    for (lobe, reported, expected) in cases {
        let reported = reported.map(|v| v as f32);
        assert_eq!(
            sample(&registry, ids[lobe], reported),
            expected,
            "{lobe} {reported:?}"
        );
    }
}

#[test]
fn v1_tables_report_the_type_class() {
    let v2 = lobe_v2(c"glossy_v1", flags::REFLECTION | flags::GLOSSY, 1);
    let lobe = abi::LobeV1 {
        struct_size: size_of::<abi::LobeV1>() as u32,
        name: v2.name,
        summary: v2.summary,
        flags: v2.flags,
        reciprocal: 1,
        params: v2.params,
        param_count: 4,
        block_size: 16,
        block_align: 4,
        eval: Some(eval),
        sample: Some(sample_v1),
        albedo: Some(albedo),
        eval_batch: None,
    };
    let table = abi::PluginV1 {
        struct_size: size_of::<abi::PluginV1>() as u32,
        name: c"v1".as_ptr(),
        lobe_count: 1,
        lobes: Box::leak(Box::new(lobe)),
    };
    let table: *const abi::PluginV1 = Box::leak(Box::new(table));
    let mut registry = Registry::with_builtins();
    let ids = register(&mut registry, 1, table.cast()).unwrap();
    let r = flags::REFLECTION;
    // The block's class and component mean nothing to a V1 sample.
    assert_eq!(
        sample(&registry, ids[0], [0.0, 5.0, 0.0]),
        (r | flags::GLOSSY, 0, 0)
    );
    assert_eq!(
        sample(&registry, ids[0], [0.0, 0.0, 1.0]),
        (r | flags::SPECULAR, 0, 0)
    );
}

#[test]
fn hostile_v2_tables_fail_at_load_and_register_nothing() {
    let ok = || lobe_v2(c"fine", DIFFUSE_GLOSSY, 2);
    let with = |f: fn(&mut abi::LobeV2)| {
        let mut l = ok();
        f(&mut l);
        table_v2(vec![ok(), l])
    };
    let lobeless = |struct_size: u32, lobe_count: u32| -> *const c_void {
        let t = abi::PluginV2 {
            struct_size,
            name: c"lobeless".as_ptr(),
            lobe_count,
            lobes: std::ptr::null(),
        };
        (Box::leak(Box::new(t)) as *const abi::PluginV2).cast()
    };
    let (short_table, null_lobes) = (
        lobeless(4, 0),
        lobeless(size_of::<abi::PluginV2>() as u32, 3),
    );
    let cases: Vec<(u32, *const c_void, Status, &str)> = vec![
        (2, std::ptr::null(), Status::PluginParams, "no table"),
        (
            2,
            short_table,
            Status::PluginParams,
            "glint_plugin_v2.struct_size 4 <",
        ),
        (2, null_lobes, Status::PluginParams, "lobes is NULL"),
        (
            0,
            table_v2(vec![ok()]),
            Status::PluginAbiRefused,
            "ABI version 0",
        ),
        (
            3,
            table_v2(vec![ok()]),
            Status::PluginAbiRefused,
            "ABI version 3",
        ),
        (
            2,
            with(|l| l.struct_size = size_of::<abi::LobeV1>() as u32),
            Status::PluginParams,
            "lobe 1: glint_plugin_lobe_v2.struct_size",
        ),
        (
            2,
            with(|l| l.struct_size = 0),
            Status::PluginParams,
            "struct_size 0",
        ),
        (
            2,
            with(|l| l.component_count = 0),
            Status::PluginParams,
            "component_count 0",
        ),
        (
            2,
            with(|l| l.component_count = 65537),
            Status::PluginParams,
            "component_count 65537",
        ),
        (
            2,
            with(|l| l.flags = flags::REFLECTION),
            Status::PluginParams,
            "classes",
        ),
        (
            2,
            with(|l| l.flags = flags::TRANSMISSION | 32),
            Status::PluginParams,
            "flags 0x22",
        ),
        (
            2,
            with(|l| l.sample = None),
            Status::PluginParams,
            "must not be NULL",
        ),
        (
            2,
            with(|l| l.name = c"lambert".as_ptr()),
            Status::DuplicateName,
            "lambert",
        ),
        (
            2,
            with(|l| l.name = c"fine".as_ptr()),
            Status::DuplicateName,
            "fine",
        ),
    ];
    for (version, table, status, mention) in cases {
        let mut registry = Registry::with_builtins();
        let before = registry.names().len();
        let e = register(&mut registry, version, table).unwrap_err();
        assert_eq!(e.status, status, "{}", e.message);
        assert!(e.message.contains(mention), "{mention}: {}", e.message);
        assert_eq!(registry.names().len(), before, "{}", e.message);
    }
    // The limits themselves load.
    let mut registry = Registry::with_builtins();
    let mut most = lobe_v2(c"most", flags::REFLECTION | flags::SPECULAR, 65536);
    most.flags |= flags::TRANSMISSION;
    register(&mut registry, 2, table_v2(vec![most])).unwrap();
}

#[test]
fn the_harness_fails_a_lobe_whose_samples_needed_repairs() {
    let mut registry = Registry::with_builtins();
    let mut lobe = lobe_v2(c"unset_class", DIFFUSE_GLOSSY, 1);
    // Every sample leaves its class unset (the default the harness samples with).
    let params = lobe.params.cast_mut();
    // SAFETY: `params` is this test's own table of four entries, not yet shared.
    unsafe { (*params.add(CLASS)).default_value[0] = 0.0 };
    lobe.params = params;
    let id = register(&mut registry, 2, table_v2(vec![lobe])).unwrap()[0];
    let report = Report::new(
        Tier::Fast,
        vec![verify_lobe(registry.get(id).unwrap(), Tier::Fast)],
    );
    let failures = report.failures();
    assert!(
        failures
            .iter()
            .any(|f| f.contains("unset_class") && f.contains("repaired")),
        "{failures:?}"
    );
}
