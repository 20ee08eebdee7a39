//! The C ABI: the only place with `extern "C"`, raw pointers and `catch_unwind`.
//! `include/glint.h` is generated from these files by cbindgen (see `tests/header.rs`).
//!
//! Rules (../shared/DESIGN.md, "C ABI rules"; ARCHITECTURE.md): every function that can fail returns a
//! `glint_status` and leaves a per-thread message for `glint_last_error()`; every
//! body runs inside a panic boundary; structs that may grow begin with `struct_size`.

#![allow(non_camel_case_types)]

mod batch;
mod closure;
mod handle;
mod material;
mod runtime;

pub use batch::*;
pub use closure::*;
pub use material::*;
pub use runtime::*;

use crate::error::{Error, Status};
use handle::*;
use std::borrow::Cow;
use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// A status code: 0 (`GLINT_OK`) on success. A failing call (any status but
/// `GLINT_OK`, including `GLINT_NO_SAMPLE`) leaves every output it was given in one
/// state, set before anything else is checked: output handles NULL, numbers and ids
/// 0, strings NULL, float arrays zeroed, result and info structs zeroed except
/// `struct_size` (and `glint_sample_result.eta` = 1). A NULL output, or a struct whose
/// `struct_size` is too small, is not written. Batch calls zero the outputs of invalid
/// lanes (see `glint_eval_batch`). A failing builder call leaves its closure unchanged.
pub type glint_status = u32;

pub const GLINT_OK: glint_status = 0;
pub const GLINT_ERROR_NULL_POINTER: glint_status = 1;
pub const GLINT_ERROR_INVALID_ARGUMENT: glint_status = 2;
pub const GLINT_ERROR_OUT_OF_RANGE: glint_status = 3;
pub const GLINT_ERROR_UNKNOWN_NAME: glint_status = 4;
pub const GLINT_ERROR_PARSE: glint_status = 5;
pub const GLINT_ERROR_STRUCT_SIZE: glint_status = 6;
pub const GLINT_ERROR_ARENA_FULL: glint_status = 7;
pub const GLINT_ERROR_CLOSURE_FULL: glint_status = 8;
pub const GLINT_ERROR_INVALID_STATE: glint_status = 9;
pub const GLINT_ERROR_UNSUPPORTED: glint_status = 10;
/// Not an error: the closure cannot scatter from this direction (the result is
/// zeroed and `glint_last_error` is left unchanged).
pub const GLINT_NO_SAMPLE: glint_status = 11;
pub const GLINT_ERROR_PANIC: glint_status = 12;
pub const GLINT_ERROR_PLUGIN_NOT_FOUND: glint_status = 13;
pub const GLINT_ERROR_PLUGIN_NOT_LIBRARY: glint_status = 14;
pub const GLINT_ERROR_PLUGIN_NO_ENTRY: glint_status = 15;
pub const GLINT_ERROR_PLUGIN_ABI_REFUSED: glint_status = 16;
pub const GLINT_ERROR_DUPLICATE_NAME: glint_status = 17;
pub const GLINT_ERROR_PLUGIN_PARAMS: glint_status = 18;
pub const GLINT_ERROR_PLUGIN_BLOCK_SIZE: glint_status = 19;
/// A runtime, arena or closure handle that was destroyed, reset (closures of a reset
/// arena) or belongs to a destroyed runtime; see `glint_runtime_destroy`.
pub const GLINT_ERROR_INVALID_HANDLE: glint_status = 20;
/// Memory ran short (a batch's staging buffers could not grow).
pub const GLINT_ERROR_OUT_OF_MEMORY: glint_status = 21;

pub const GLINT_VERSION_MAJOR: u32 = 0;
pub const GLINT_VERSION_MINOR: u32 = 1;
pub const GLINT_VERSION_PATCH: u32 = 0;

/// Destroyed runtimes and arenas whose small handle shells stay readable, so that
/// using one is detected (`glint_runtime_destroy`, `glint_arena_destroy`).
pub const GLINT_QUARANTINE_SHELLS: usize = 1024;
/// Most bytes of closure slots that destroyed arenas keep readable, so that using
/// one of their closures is detected (`glint_arena_destroy`).
pub const GLINT_QUARANTINE_BYTES: usize = 16 << 20;

/// Most lobes in one closure.
pub const GLINT_MAX_LOBES: u32 = 16;

/// Most parameter values (floats) in one lobe's block, and in all lobes of one
/// closure together.
pub const GLINT_MAX_PARAM_VALUES: u32 = 512;
const _: () = assert!(GLINT_MAX_PARAM_VALUES as usize == crate::closure::MAX_PARAM_VALUES);

/// Sample and lobe-type flags.
pub const GLINT_FLAG_REFLECTION: u32 = 1;
pub const GLINT_FLAG_TRANSMISSION: u32 = 2;
pub const GLINT_FLAG_DIFFUSE: u32 = 4;
pub const GLINT_FLAG_GLOSSY: u32 = 8;
pub const GLINT_FLAG_SPECULAR: u32 = 16;

/// `glint_closure_begin` flag: the closure transports importance (adjoint), not radiance.
pub const GLINT_CLOSURE_IMPORTANCE: u32 = 1;

/// Parameter types of `glint_param_info.param_type`.
pub const GLINT_PARAM_FLOAT: u32 = 0;
pub const GLINT_PARAM_RGB: u32 = 1;
pub const GLINT_PARAM_ENUM: u32 = 2;
/// `param_type` of group and table headers, which hold no values of their own.
pub const GLINT_PARAM_NONE: u32 = 3;

/// `glint_param_info.shape`: how an entry of a parameter schema repeats and nests.
/// One value.
pub const GLINT_SHAPE_VALUE: u32 = 0;
/// Up to `capacity` values of `param_type`, element i at `offset + i * size`, and a
/// count at `count_offset`.
pub const GLINT_SHAPE_ARRAY: u32 = 1;
/// A header without values: the next `member_count` entries belong to it.
pub const GLINT_SHAPE_GROUP: u32 = 2;
/// A header holding the row count (at `offset`); the next `member_count` entries are
/// its columns.
pub const GLINT_SHAPE_TABLE: u32 = 3;
/// A table column: `capacity` values, row i at `offset + i * size`; its count is the
/// table's.
pub const GLINT_SHAPE_COLUMN: u32 = 4;
/// `glint_param_info.parent` of a top-level entry; `count_offset` of an entry without
/// a count.
pub const GLINT_PARAM_NO_INDEX: u32 = u32::MAX;
/// An override's `param` addresses element (array element or table row) `e` of entry
/// `i` as `i | e << GLINT_PARAM_ELEMENT_SHIFT`; `glint_*_param_find` returns such
/// addresses for names like `ramp[3].position`.
pub const GLINT_PARAM_ELEMENT_SHIFT: u32 = 16;
const _: () = assert!(GLINT_PARAM_ELEMENT_SHIFT == crate::params::ELEMENT_SHIFT);

/// A 3-vector (world-space direction or normal).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct glint_vec3 {
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

thread_local! {
    static LAST_ERROR: RefCell<Cow<'static, CStr>> = const { RefCell::new(Cow::Borrowed(c"")) };
}

fn set_last_error(message: &str) {
    // A message with an interior NUL is cut there rather than lost.
    let text = message.split('\0').next().unwrap_or_default();
    let mut bytes = Vec::new();
    // Memory may be what ran short: then the status's static description stands in.
    let c = match bytes.try_reserve_exact(text.len() + 1) {
        Ok(()) => {
            bytes.extend_from_slice(text.as_bytes());
            Cow::Owned(CString::new(bytes).expect("cut at the first NUL"))
        }
        Err(_) => Cow::Borrowed(Status::OutOfMemory.description()),
    };
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

/// Run an API body inside the panic boundary and turn its result into a status.
fn guard(body: impl FnOnce() -> Result<(), Error>) -> glint_status {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => GLINT_OK,
        Ok(Err(e)) => {
            if e.status != Status::NoSample {
                set_last_error(&e.message);
            }
            e.status as glint_status
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            set_last_error(&format!("internal error: {what}"));
            GLINT_ERROR_PANIC
        }
    }
}

fn null(what: impl std::fmt::Display) -> Error {
    Error::new(Status::NullPointer, format!("{what} is NULL"))
}

/// `&T` from a pointer the caller promises is NULL or valid.
///
/// # Safety
/// `p` is NULL or points to a live `T` for `'a`.
unsafe fn deref<'a, T>(p: *const T, what: &str) -> Result<&'a T, Error> {
    // SAFETY: the caller guarantees `p` is NULL or valid; NULL is checked by `as_ref`.
    unsafe { p.as_ref() }.ok_or_else(|| null(what))
}

/// `&mut T` from a pointer the caller promises is NULL or valid and unaliased.
///
/// # Safety
/// `p` is NULL or points to a live `T` not accessed elsewhere for `'a`.
unsafe fn deref_mut<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Error> {
    // SAFETY: the caller guarantees `p` is NULL or valid and unaliased.
    unsafe { p.as_mut() }.ok_or_else(|| null(what))
}

/// A parameter block argument of `count` floats: `None` for NULL with `count == 0`;
/// refused when NULL with a count, or when longer than any block (`max` values), before
/// a slice is made.
///
/// # Safety
/// `params` is NULL or valid for `count` floats.
unsafe fn param_block<'a>(
    params: *const f32,
    count: usize,
    max: usize,
) -> Result<Option<&'a [f32]>, Error> {
    match (params.is_null(), count) {
        (true, 0) => Ok(None),
        (true, _) => Err(null("params (with param_count > 0)")),
        (false, n) if n > max => Err(Error::new(
            Status::InvalidArgument,
            format!("param_count {n}: a parameter block has at most {max} values"),
        )),
        // SAFETY: non-NULL and `n` (at most `max`) floats per the contract.
        (false, n) => Ok(Some(unsafe { std::slice::from_raw_parts(params, n) })),
    }
}

/// A NUL-terminated UTF-8 string argument.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string that lives for `'a`.
unsafe fn c_str<'a>(p: *const c_char, what: &str) -> Result<&'a str, Error> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: non-NULL and NUL-terminated per the caller's contract.
    unsafe { CStr::from_ptr(p) }.to_str().map_err(|_| {
        Error::new(
            Status::InvalidArgument,
            format!("{what} is not valid UTF-8"),
        )
    })
}

/// Structs that begin with `struct_size`.
trait Sized32 {
    fn struct_size(&self) -> u32;
}

/// Output structs, which a failing call leaves in one state.
trait Output: Sized32 {
    /// The failure state: zeroed (NULL strings) except `struct_size`.
    fn failed(struct_size: u32) -> Self;
}

/// Check that a caller's struct is at least as large as this library's version of it.
#[inline(always)]
fn check_size<T: Sized32>(s: &T, what: &str) -> Result<(), Error> {
    let need = std::mem::size_of::<T>();
    if (s.struct_size() as usize) < need {
        return Err(struct_size_error(s.struct_size(), need, what));
    }
    Ok(())
}

#[cold]
fn struct_size_error(size: u32, need: usize, what: &str) -> Error {
    Error::new(
        Status::StructSize,
        format!("{what}.struct_size is {size} but this library needs {need}"),
    )
}

/// Output pointer to a struct that begins with `struct_size`, checked and set to its
/// failure state before the call does anything else (a NULL or too small struct is
/// not written).
///
/// # Safety
/// As [`deref_mut`].
#[inline(always)]
unsafe fn out_struct<'a, T: Output>(p: *mut T, what: &str) -> Result<&'a mut T, Error> {
    // SAFETY: forwarded contract.
    let s = unsafe { deref_mut(p, what) }?;
    check_size(s, what)?;
    *s = T::failed(s.struct_size());
    Ok(s)
}

/// A `struct_size` is the oldest version's `min_size` or at least this library's
/// `size_of::<T>()`: a size between them would cut an appended field in two.
fn check_version<T>(size: u32, min_size: usize, what: &str) -> Result<(), Error> {
    let size = size as usize;
    if size == min_size || size >= std::mem::size_of::<T>() {
        return Ok(());
    }
    Err(Error::new(
        Status::StructSize,
        format!(
            "{what}.struct_size is {size}: this library takes {min_size} (an older \
             version) or at least {}",
            std::mem::size_of::<T>()
        ),
    ))
}

/// A caller's output struct that may be an older, shorter version of `T` (a field
/// appended since): written whole into a copy, then its first `size` bytes.
struct VersionedOut<T> {
    p: *mut T,
    struct_size: u32,
    /// The caller's `struct_size`, at most `size_of::<T>()`.
    size: usize,
}

impl<T> VersionedOut<T> {
    fn write(&self, value: T) {
        // SAFETY: `out_versioned` checked `p` and the caller's contract gives `size`
        // writable bytes there; `value` holds at least `size` bytes (padding between
        // fields is copied as bytes and, as in any C struct, unspecified).
        unsafe {
            std::ptr::copy_nonoverlapping(
                (&value as *const T).cast::<u8>(),
                self.p.cast::<u8>(),
                self.size,
            );
        }
    }
}

/// Output pointer to a struct that begins with `struct_size` and is `min_size` bytes
/// (its oldest version) or the whole `T` ([`check_version`]), set to its failure state before the call
/// does anything else (a NULL or too small struct is not written).
///
/// # Safety
/// `p` is NULL or points to `struct_size` writable bytes, not accessed elsewhere.
unsafe fn out_versioned<T: Output>(
    p: *mut T,
    min_size: usize,
    what: &str,
) -> Result<VersionedOut<T>, Error> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: every version begins with `struct_size` (per the contract).
    let size = unsafe { p.cast::<u32>().read() };
    check_version::<T>(size, min_size, what)?;
    let out = VersionedOut {
        p,
        struct_size: size,
        size: (size as usize).min(std::mem::size_of::<T>()),
    };
    out.write(T::failed(size));
    Ok(out)
}

/// An argument struct that may be an older, shorter version of `T` (`min_size`
/// bytes, [`check_version`]): the caller's `struct_size` bytes over a zeroed `T`, so fields
/// appended since read as NULL or 0.
///
/// # Safety
/// `p` is NULL or points to `struct_size` readable bytes; an all-zero `T` is valid
/// (integers and raw pointers only).
unsafe fn args_versioned<T: Copy>(p: *const T, min_size: usize, what: &str) -> Result<T, Error> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: every version begins with `struct_size` (per the contract).
    let size = unsafe { p.cast::<u32>().read() };
    check_version::<T>(size, min_size, what)?;
    let mut args = std::mem::MaybeUninit::<T>::zeroed();
    // SAFETY: the caller's struct holds `size` bytes, the copy at most `size_of::<T>()`
    // of them; a zeroed `T` with any prefix of a valid `T` over it is valid (contract).
    unsafe {
        std::ptr::copy_nonoverlapping(
            p.cast::<u8>(),
            args.as_mut_ptr().cast::<u8>(),
            (size as usize).min(std::mem::size_of::<T>()),
        );
        Ok(args.assume_init())
    }
}

/// Output pointer, set to `failed` (what a failing call leaves) before the call does
/// anything else.
///
/// # Safety
/// `p` is NULL or valid for writes.
#[inline(always)]
unsafe fn out_value<'a, T>(p: *mut T, what: &str, failed: T) -> Result<&'a mut T, Error> {
    // SAFETY: forwarded contract.
    let out = unsafe { deref_mut(p, what) }?;
    *out = failed;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_constants_match_the_rust_statuses() {
        let c = [
            GLINT_OK,
            GLINT_ERROR_NULL_POINTER,
            GLINT_ERROR_INVALID_ARGUMENT,
            GLINT_ERROR_OUT_OF_RANGE,
            GLINT_ERROR_UNKNOWN_NAME,
            GLINT_ERROR_PARSE,
            GLINT_ERROR_STRUCT_SIZE,
            GLINT_ERROR_ARENA_FULL,
            GLINT_ERROR_CLOSURE_FULL,
            GLINT_ERROR_INVALID_STATE,
            GLINT_ERROR_UNSUPPORTED,
            GLINT_NO_SAMPLE,
            GLINT_ERROR_PANIC,
            GLINT_ERROR_PLUGIN_NOT_FOUND,
            GLINT_ERROR_PLUGIN_NOT_LIBRARY,
            GLINT_ERROR_PLUGIN_NO_ENTRY,
            GLINT_ERROR_PLUGIN_ABI_REFUSED,
            GLINT_ERROR_DUPLICATE_NAME,
            GLINT_ERROR_PLUGIN_PARAMS,
            GLINT_ERROR_PLUGIN_BLOCK_SIZE,
            GLINT_ERROR_INVALID_HANDLE,
            GLINT_ERROR_OUT_OF_MEMORY,
        ];
        assert_eq!(c.len(), Status::ALL.len());
        for (s, c) in Status::ALL.iter().zip(c) {
            assert_eq!(*s as u32, c, "{s:?}");
        }
        assert_eq!(Status::OutOfMemory as u32, GLINT_ERROR_OUT_OF_MEMORY);
        use crate::lobes::flags;
        assert_eq!(
            [
                flags::REFLECTION,
                flags::TRANSMISSION,
                flags::DIFFUSE,
                flags::GLOSSY,
                flags::SPECULAR
            ],
            [
                GLINT_FLAG_REFLECTION,
                GLINT_FLAG_TRANSMISSION,
                GLINT_FLAG_DIFFUSE,
                GLINT_FLAG_GLOSSY,
                GLINT_FLAG_SPECULAR
            ]
        );
        assert_eq!(GLINT_MAX_LOBES as usize, crate::closure::MAX_LOBES);
        let v = env!("CARGO_PKG_VERSION");
        assert_eq!(
            v,
            format!("{GLINT_VERSION_MAJOR}.{GLINT_VERSION_MINOR}.{GLINT_VERSION_PATCH}")
        );
    }

    #[test]
    fn a_panic_becomes_a_status_and_a_message() {
        let status = guard(|| panic!("boom"));
        assert_eq!(status, GLINT_ERROR_PANIC);
        let msg = LAST_ERROR.with(|e| e.borrow().to_str().unwrap().to_string());
        assert!(msg.contains("boom"), "{msg}");
    }
}
