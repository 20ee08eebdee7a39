//! Plugin lobe declarations (glint_plugin.h's `glint_plugin_lobe_v1` or `_v2` and its
//! parameter table) decoded from bytes and validated as `glint_runtime_load_plugin` does, without
//! a shared library: any names (non-UTF-8, empty, odd characters), flags, kinds,
//! offsets, ranges (NaN, Inf), defaults, enum choices and block sizes are refused with
//! GLINT_ERROR_PLUGIN_PARAMS / _BLOCK_SIZE or accepted, never a crash, panic or leak.
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use glint::plugin::abi;
use libfuzzer_sys::fuzz_target;
use std::ffi::{CString, c_char, c_void};
use std::ptr::null;

/// A string the declaration may point at: NULL, or bytes up to the first NUL.
#[derive(Debug)]
struct Text(Option<CString>);

impl<'a> Arbitrary<'a> for Text {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        const NAMES: [&str; 6] = ["roughness", "tint", "ggx", "mode", "a_1", ""];
        Ok(Text(match u.int_in_range(0u8..=3)? {
            0 => None,
            1 | 2 => Some(CString::new(NAMES[u.choose_index(NAMES.len())?]).expect("no NUL")),
            _ => {
                let bytes: Vec<u8> = u
                    .arbitrary::<Vec<u8>>()?
                    .into_iter()
                    .take_while(|b| *b != 0)
                    .collect();
                Some(CString::new(bytes).expect("no NUL"))
            }
        }))
    }
}

impl Text {
    fn ptr(&self) -> *const c_char {
        self.0.as_ref().map_or(null(), |s| s.as_ptr())
    }
}

#[derive(Arbitrary, Debug)]
struct Param {
    name: Text,
    kind: u8,
    /// None: the packed layout's offset; else any byte offset.
    offset: Option<u32>,
    default_value: [f32; 3],
    min: f32,
    max: f32,
    choices: Option<Vec<Text>>,
    /// Declare one choice fewer than the array holds (still valid memory).
    fewer_choices: bool,
    doc: Text,
}

/// Each field is either what a correct plugin declares (None) or any value, so that
/// declarations the loader accepts are common and each check is reached alone.
#[derive(Arbitrary, Debug)]
struct Lobe {
    struct_size: Option<u32>,
    name: Text,
    summary: Text,
    /// Ok: GLINT_PLUGIN_FLAG_* bits (low 5 bits); Err: any bits.
    flags: Result<u8, u32>,
    reciprocal: u8,
    params: Option<Vec<Param>>,
    /// None: the packed size of the table's floats; else any byte count.
    block_size: Option<u32>,
    block_align: Option<u32>,
    /// Some(k): callback k % 3 (eval, sample, albedo) is NULL.
    missing_callback: Option<u8>,
    /// Some(n): declared as a version-2 lobe with `component_count` n (any value; the
    /// valid 1..=65536 is common when the fuzzer picks small numbers).
    version2: Option<u32>,
}

unsafe extern "C" fn eval(
    _: *const c_void,
    _: *const [f32; 3],
    _: *const [f32; 3],
    _: u32,
    _: *mut [f32; 3],
    _: *mut f32,
) {
}

unsafe extern "C" fn sample(
    _: *const c_void,
    _: *const [f32; 3],
    _: *const [f32; 3],
    _: u32,
    _: *mut abi::Sample,
) -> i32 {
    0
}

unsafe extern "C" fn sample_v2(
    _: *const c_void,
    _: *const [f32; 3],
    _: *const [f32; 3],
    _: u32,
    _: *mut abi::SampleV2,
) -> i32 {
    0
}

unsafe extern "C" fn albedo(_: *const c_void, _: *const [f32; 3], _: u32, _: *mut [f32; 3]) {}

fuzz_target!(|lobe: Lobe| {
    // The strings and arrays the declaration points into, alive until validation ends.
    let choice_arrays: Vec<Option<Vec<*const c_char>>> = lobe
        .params
        .iter()
        .flatten()
        .map(|p| {
            p.choices
                .as_ref()
                .map(|c| c.iter().map(Text::ptr).collect())
        })
        .collect();
    // Floats of the table so far: RGB parameters take 3, the others 1.
    let mut floats = 0u32;
    let params: Option<Vec<abi::Param>> = lobe.params.as_ref().map(|ps| {
        ps.iter()
            .zip(&choice_arrays)
            .map(|(p, choices)| abi::Param {
                name: p.name.ptr(),
                kind: p.kind as u32 % 4,
                offset: {
                    let packed = 4 * floats;
                    floats += if p.kind % 4 == abi::PARAM_RGB as u8 {
                        3
                    } else {
                        1
                    };
                    p.offset.unwrap_or(packed)
                },
                default_value: p.default_value,
                min: p.min,
                max: p.max,
                choices: choices.as_ref().map_or(null(), |c| c.as_ptr()),
                choice_count: choices.as_ref().map_or(0, |c| {
                    c.len().saturating_sub(p.fewer_choices as usize) as u32
                }),
                doc: p.doc.ptr(),
            })
            .collect()
    });
    let missing = lobe.missing_callback.map(|k| k % 3);
    let decl = abi::LobeV1 {
        struct_size: lobe.struct_size.unwrap_or(size_of::<abi::LobeV1>() as u32),
        name: lobe.name.ptr(),
        summary: lobe.summary.ptr(),
        flags: lobe.flags.map_or_else(|bits| bits, |b| (b & 0x1f) as u32),
        reciprocal: lobe.reciprocal as u32 % 3,
        params: params.as_ref().map_or(null(), |p| p.as_ptr()),
        param_count: params.as_ref().map_or(0, |p| p.len() as u32),
        block_size: lobe.block_size.unwrap_or(4 * floats),
        block_align: lobe.block_align.unwrap_or(4),
        eval: (missing != Some(0)).then_some(eval as abi::EvalFn),
        sample: (missing != Some(1)).then_some(sample as abi::SampleFn),
        albedo: (missing != Some(2)).then_some(albedo as abi::AlbedoFn),
        eval_batch: None,
    };
    let checked = match lobe.version2 {
        None => {
            // SAFETY: every pointer in `decl` is NULL or points into the vectors and
            // strings above, each array holding the count the declaration states.
            unsafe { glint::plugin::validate_declaration(&decl) }
        }
        Some(component_count) => {
            let v2 = abi::LobeV2 {
                struct_size: lobe.struct_size.unwrap_or(size_of::<abi::LobeV2>() as u32),
                name: decl.name,
                summary: decl.summary,
                flags: decl.flags,
                reciprocal: decl.reciprocal,
                params: decl.params,
                param_count: decl.param_count,
                block_size: decl.block_size,
                block_align: decl.block_align,
                eval: decl.eval,
                sample: (missing != Some(1)).then_some(sample_v2 as abi::SampleV2Fn),
                albedo: decl.albedo,
                eval_batch: None,
                component_count,
            };
            // SAFETY: as above; `v2` points where `decl` does.
            unsafe { glint::plugin::validate_declaration_v2(&v2) }
        }
    };
    if let Err(e) = checked {
        assert!(
            matches!(
                e.status,
                glint::Status::PluginParams | glint::Status::PluginBlockSize
            ),
            "status {:?}: {}",
            e.status,
            e.message
        );
        assert!(!e.message.is_empty());
    }
});
