//! Plugin lobe declarations (glint_plugin.h's `glint_plugin_lobe_v1` and its parameter
//! table) decoded from bytes and validated as `glint_runtime_load_plugin` does, without
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
            1 => Some(CString::new(NAMES[u.choose_index(NAMES.len())?]).expect("no NUL")),
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
    /// Offset in floats (stored as bytes), or any byte offset.
    offset: Result<u8, u32>,
    default_value: [f32; 3],
    min: f32,
    max: f32,
    choices: Option<Vec<Text>>,
    /// Declare one choice fewer than the array holds (still valid memory).
    fewer_choices: bool,
    doc: Text,
}

#[derive(Arbitrary, Debug)]
struct Lobe {
    struct_size_short: bool,
    name: Text,
    summary: Text,
    flags: u32,
    reciprocal: u8,
    params: Option<Vec<Param>>,
    /// Block size in floats (stored as bytes), or any byte count.
    block: Result<u16, u32>,
    block_align: u8,
    callbacks: u8,
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
    let params: Option<Vec<abi::Param>> = lobe.params.as_ref().map(|ps| {
        ps.iter()
            .zip(&choice_arrays)
            .map(|(p, choices)| abi::Param {
                name: p.name.ptr(),
                kind: p.kind as u32 % 4,
                offset: match p.offset {
                    Ok(floats) => 4 * floats as u32,
                    Err(bytes) => bytes,
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
    let decl = abi::LobeV1 {
        struct_size: size_of::<abi::LobeV1>() as u32 - 4 * lobe.struct_size_short as u32,
        name: lobe.name.ptr(),
        summary: lobe.summary.ptr(),
        flags: lobe.flags,
        reciprocal: lobe.reciprocal as u32,
        params: params.as_ref().map_or(null(), |p| p.as_ptr()),
        param_count: params.as_ref().map_or(0, |p| p.len() as u32),
        block_size: match lobe.block {
            Ok(floats) => 4 * floats as u32,
            Err(bytes) => bytes,
        },
        block_align: lobe.block_align as u32,
        eval: (lobe.callbacks & 1 != 0).then_some(eval as abi::EvalFn),
        sample: (lobe.callbacks & 2 != 0).then_some(sample as abi::SampleFn),
        albedo: (lobe.callbacks & 4 != 0).then_some(albedo as abi::AlbedoFn),
        eval_batch: None,
    };
    // SAFETY: every pointer in `decl` is NULL or points into the vectors and strings
    // above, each array holding the count the declaration states.
    if let Err(e) = unsafe { glint::plugin::validate_declaration(&decl) } {
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
