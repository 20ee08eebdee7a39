//! Plugin lobe types: shared libraries built against `include/glint_plugin.h` that
//! export `glint_plugin_entry`. [`load`] opens one with libloading, negotiates the ABI
//! version (1 or 2: [`register_table`] reads either table), validates every lobe declaration and parameter table, and only then
//! registers the lobe types, so a failure never leaves a half-registered plugin.
//! Libraries are never unloaded (unloading code with thread-local state crashes); the
//! lobe records Glint allocates for them are shared by the registry and the closures
//! that use them ([`LobeRef::Shared`]) and freed with the last of those.
//!
//! A [`PluginLobe`] is a [`LobeType`] like any built-in: closures, JSON, batches and
//! the verification harness use it unchanged. Its outputs are sanitized, so that
//! nothing a plugin returns makes a closure's output non-finite, and each repair is
//! counted ([`LobeType::sanitized_count`]):
//! - values, pdfs and albedos that are NaN, infinite or negative become 0; finite ones
//!   above [`PLUGIN_MAX_VALUE`] become [`PLUGIN_MAX_VALUE`];
//! - a sample whose pdf is below [`PLUGIN_MIN_PDF`] (or not a number), or whose
//!   direction is not unit, is no sample (a valid pdf below the floor, as a sharp lobe's
//!   tail gives, is not counted); its weight `value / pdf` is then at most
//!   `PLUGIN_MAX_VALUE / PLUGIN_MIN_PDF` = 1e28 per unit of lobe weight;
//! - every callback gets a copy of the closure's parameter block, so a plugin that
//!   writes to its `const` block cannot change a finished closure; a call that wrote
//!   is counted;
//! - a version-2 sample's class that is not one of the three, not among the type's
//!   flags or not SPECULAR exactly for delta events becomes the type's class (what a
//!   version-1 sample reports), a component beyond the type's `component_count` becomes
//!   0 (each counted). What can be checked statically (struct sizes, a class among the
//!   flags, `component_count` in range) is checked at load.

pub mod abi;
mod intern;
#[cfg(test)]
mod tests;

use crate::error::{Error, Status};
use crate::kernels::{self, EvalJob};
use crate::lobes::{Eval, LobeType, MAX_COMPONENT, Sample, Transport, VerifyCase, class_of, flags};
use crate::math::{Rgb, Vec3};
use crate::params::{self, ParamKind, ParamSpec};
use crate::registry::{LobeRef, Registry};
use crate::simd::Kernels;
use intern::{intern, intern_str};
use std::ffi::{CStr, c_char, c_void};
use std::mem::MaybeUninit;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

pub use abi::HOST_ABI_VERSION;

/// Relative accuracy the harness holds a plugin lobe's `albedo` to (the V1 ABI has
/// no field to declare one).
pub const PLUGIN_ALBEDO_TOLERANCE: f32 = 0.1;

/// Largest value channel, pdf or albedo channel kept from a plugin; larger finite
/// ones are clamped to it. 1e16 is far above any physical `f |cos|` (a GGX peak at
/// alpha = 1e-6 is 3e11), and leaves room for sixteen lobes of weights up to 2e21
/// before a closure's sum could overflow `f32`.
pub const PLUGIN_MAX_VALUE: f32 = 1e16;

/// Smallest pdf a plugin's sample may have; below it the sample is no sample (counted).
/// Samples of density below `p` have total probability at most `4 pi p` (5e-11 here),
/// so dropping them loses nothing measurable, while `value / pdf` stays finite.
pub const PLUGIN_MIN_PDF: f32 = 1e-12;

/// Load the plugin at `path` and register its lobe types; returns their ids.
pub fn load(registry: &mut Registry, path: &Path) -> Result<Vec<u32>, Error> {
    let shown = path.display();
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(Error::new(
                Status::PluginNotFound,
                format!("plugin {shown}: no such file"),
            ));
        }
        Err(e) => {
            return Err(Error::new(
                Status::PluginNotFound,
                format!("plugin {shown}: cannot access it ({e})"),
            ));
        }
        Ok(m) if m.is_dir() => {
            return Err(Error::new(
                Status::PluginNotLibrary,
                format!("plugin {shown}: is a directory, not a shared library"),
            ));
        }
        // Anything else (a device, a text file) is for the dynamic loader to judge.
        Ok(_) => {}
    }
    // SAFETY: loading runs the library's initializers; plugins are trusted native code
    // by contract (glint_plugin.h), as any library a host links.
    let library = unsafe { libloading::Library::new(path) }.map_err(|e| {
        Error::new(
            Status::PluginNotLibrary,
            format!("plugin {shown}: not a loadable shared library ({e})"),
        )
    })?;
    // SAFETY: the symbol's type is the one glint_plugin.h declares for this name.
    let entry = unsafe { library.get::<abi::EntryFn>(b"glint_plugin_entry\0") }.map_err(|_| {
        Error::new(
            Status::PluginNoEntry,
            format!("plugin {shown}: does not export glint_plugin_entry"),
        )
    })?;
    let mut version = 0u32;
    let mut table: *const c_void = std::ptr::null();
    // SAFETY: the entry's contract (glint_plugin.h); both out-pointers are valid.
    let refused = unsafe { entry(HOST_ABI_VERSION, &mut version, &mut table) };
    if refused != 0 {
        return Err(Error::new(
            Status::PluginAbiRefused,
            format!(
                "plugin {shown}: refused ABI version {HOST_ABI_VERSION} (glint_plugin_entry returned {refused})"
            ),
        ));
    }
    if !(1..=HOST_ABI_VERSION).contains(&version) {
        return Err(Error::new(
            Status::PluginAbiRefused,
            format!(
                "plugin {shown}: answered ABI version {version}; this library speaks 1..={HOST_ABI_VERSION}"
            ),
        ));
    }
    // SAFETY: the entry answered `version` with that version's table, which lives as
    // long as the library (glint_plugin.h), and the library is never unloaded below.
    let ids = unsafe { register_table(registry, version, table, &shown.to_string()) }?;
    // Never unloaded: the lobe types' callbacks point into the library.
    std::mem::forget(library);
    Ok(ids)
}

/// Validate the table a plugin's entry handed over for ABI `version` (1 or 2) and
/// register its lobe types, all or none; returns their ids. `origin` names the plugin
/// in messages. [`load`] calls this with a library's table; the unit tests with tables
/// declared in Rust.
///
/// # Safety
/// `table` is NULL or a table of ABI `version` whose pointers are NULL or valid as
/// glint_plugin.h requires of a plugin, for as long as the registered types live.
unsafe fn register_table(
    registry: &mut Registry,
    version: u32,
    table: *const c_void,
    origin: &str,
) -> Result<Vec<u32>, Error> {
    let malformed =
        |what: String| Error::new(Status::PluginParams, format!("plugin {origin}: {what}"));
    let lobes = match version {
        // SAFETY: the caller's contract: a version-1 table (NULL checked by `table_lobes`).
        1 => unsafe {
            table_lobes(table.cast::<abi::PluginV1>(), "glint_plugin_v1", |t| {
                (t.struct_size, t.lobe_count, t.lobes)
            })
        }
        .map_err(malformed)
        .and_then(|decls| checked_lobes(decls, Decl::v1, origin)),
        // SAFETY: as above, a version-2 table.
        2 => unsafe {
            table_lobes(table.cast::<abi::PluginV2>(), "glint_plugin_v2", |t| {
                (t.struct_size, t.lobe_count, t.lobes)
            })
        }
        .map_err(malformed)
        .and_then(|decls| checked_lobes(decls, Decl::v2, origin)),
        v => Err(Error::new(
            Status::PluginAbiRefused,
            format!("plugin {origin}: ABI version {v} is not one this library speaks"),
        )),
    }?;
    let mut checked: Vec<PluginLobe> = Vec::with_capacity(lobes.len());
    for lobe in lobes {
        if registry.find(lobe.name).is_ok() || checked.iter().any(|l| l.name == lobe.name) {
            return Err(Error::new(
                Status::DuplicateName,
                format!(
                    "plugin {origin}: a lobe type named \"{}\" is already registered",
                    lobe.name
                ),
            ));
        }
        checked.push(lobe);
    }
    checked
        .into_iter()
        .map(|l| registry.register(LobeRef::Shared(Arc::new(l))))
        .collect()
}

/// Each declaration of `decls`, validated through `decl`; the first failure names its lobe.
fn checked_lobes<L>(
    decls: &[L],
    decl: fn(&L) -> Result<Decl, Error>,
    origin: &str,
) -> Result<Vec<PluginLobe>, Error> {
    decls
        .iter()
        .enumerate()
        .map(|(i, d)| {
            decl(d).and_then(PluginLobe::new).map_err(|e| {
                Error::new(
                    e.status,
                    format!("plugin {origin}: lobe {i}: {}", e.message),
                )
            })
        })
        .collect()
}

/// The lobe declarations of a plugin table of type `T` (`what` in messages), whose
/// `fields` are its struct_size, lobe_count and lobes; NULL and short tables refused.
///
/// # Safety
/// `table` is NULL or valid for reads of `T`, and its lobes hold lobe_count entries.
unsafe fn table_lobes<'a, T, L>(
    table: *const T,
    what: &str,
    fields: impl Fn(&T) -> (u32, u32, *const L),
) -> Result<&'a [L], String> {
    // SAFETY: the caller's contract; NULL is checked.
    let table = unsafe { table.as_ref() }.ok_or("glint_plugin_entry returned no table")?;
    let (struct_size, count, lobes) = fields(table);
    if (struct_size as usize) < size_of::<T>() {
        return Err(format!(
            "{what}.struct_size {struct_size} < {}",
            size_of::<T>()
        ));
    }
    if count == 0 {
        return Ok(&[]);
    }
    if lobes.is_null() {
        return Err("lobes is NULL".into());
    }
    // SAFETY: `lobes` holds `count` declarations (non-NULL checked above).
    Ok(unsafe { std::slice::from_raw_parts(lobes, count as usize) })
}

/// Validate one lobe declaration exactly as [`load`] does, registering nothing: the
/// fuzz target `plugin_decl` (fuzz/) feeds it decoded declarations without a library.
///
/// # Safety
/// Every pointer in `decl` is NULL or valid as glint_plugin.h requires of a plugin.
pub unsafe fn validate_declaration(decl: &abi::LobeV1) -> Result<(), Error> {
    Decl::v1(decl).and_then(PluginLobe::new).map(drop)
}

/// [`validate_declaration`] for a version-2 declaration (`glint_plugin_lobe_v2`).
///
/// # Safety
/// As for [`validate_declaration`].
pub unsafe fn validate_declaration_v2(decl: &abi::LobeV2) -> Result<(), Error> {
    Decl::v2(decl).and_then(PluginLobe::new).map(drop)
}

/// Every `*.so` file in `dir`, in file-name order.
pub fn plugins_in(dir: &Path) -> Result<Vec<std::path::PathBuf>, Error> {
    let entries = std::fs::read_dir(dir).map_err(|e| {
        Error::new(
            Status::PluginNotFound,
            format!("plugins={}: cannot read the directory ({e})", dir.display()),
        )
    })?;
    let mut paths: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "so"))
        .collect();
    paths.sort();
    Ok(paths)
}

/// A lobe type declared by a plugin.
pub struct PluginLobe {
    /// Strings of the library's, which is never unloaded.
    name: &'static str,
    summary: &'static str,
    params: Box<[ParamSpec]>,
    /// Floats in the parameter block.
    block_len: usize,
    flags: u32,
    reciprocal: bool,
    eval: abi::EvalFn,
    sample: Sampler,
    albedo: abi::AlbedoFn,
    eval_batch: Option<abi::EvalBatchFn>,
    /// Each float parameter at its minimum and at its maximum, for the harness.
    verify_cases: Box<[VerifyCase]>,
    sanitized: AtomicU64,
}

/// A string the plugin owns forever, checked: non-NULL UTF-8.
fn plugin_str(p: *const c_char, what: &str) -> Result<&'static str, Error> {
    if p.is_null() {
        return Err(Error::new(Status::PluginParams, format!("{what} is NULL")));
    }
    // SAFETY: non-NULL, NUL-terminated and static by the ABI contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| Error::new(Status::PluginParams, format!("{what} is not UTF-8")))
}

/// Lobe and parameter names: `[a-z0-9_]+`.
fn identifier(p: *const c_char, what: &str) -> Result<&'static str, Error> {
    let s = plugin_str(p, what)?;
    if s.is_empty()
        || !s
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_')
    {
        return Err(Error::new(
            Status::PluginParams,
            format!("{what} \"{s}\" is not a name of [a-z0-9_]+"),
        ));
    }
    Ok(s)
}

const CLASSES: u32 = flags::DIFFUSE | flags::GLOSSY | flags::SPECULAR;
const ALL_FLAGS: u32 = flags::REFLECTION | flags::TRANSMISSION | CLASSES;

/// Most components a version-2 lobe may declare: samples report 0 ..= MAX_COMPONENT.
const MAX_COMPONENTS: u32 = MAX_COMPONENT as u32 + 1;

/// A version's `sample` callback: V1 samples carry no class or component.
#[derive(Clone, Copy)]
enum Sampler {
    V1(abi::SampleFn),
    V2 {
        sample: abi::SampleV2Fn,
        component_count: u32,
    },
}

/// The fields every ABI version's lobe declaration has, read after its struct_size
/// was checked; `sample` is None when the plugin left it NULL.
struct Decl {
    name: *const c_char,
    summary: *const c_char,
    flags: u32,
    reciprocal: u32,
    params: *const abi::Param,
    param_count: u32,
    block_size: u32,
    block_align: u32,
    eval: Option<abi::EvalFn>,
    sample: Option<Sampler>,
    albedo: Option<abi::AlbedoFn>,
    eval_batch: Option<abi::EvalBatchFn>,
}

/// Refuse a declaration whose struct_size is below the size of `T`.
fn struct_size<T>(size: u32, what: &str) -> Result<(), Error> {
    if (size as usize) < size_of::<T>() {
        return Err(Error::new(
            Status::PluginParams,
            format!("{what}.struct_size {size} < {}", size_of::<T>()),
        ));
    }
    Ok(())
}

/// A [`Decl`] of the fields V1 and V2 declarations share, with `sample` the version's.
macro_rules! decl {
    ($d:expr, $sample:expr) => {
        Decl {
            name: $d.name,
            summary: $d.summary,
            flags: $d.flags,
            reciprocal: $d.reciprocal,
            params: $d.params,
            param_count: $d.param_count,
            block_size: $d.block_size,
            block_align: $d.block_align,
            eval: $d.eval,
            sample: $sample,
            albedo: $d.albedo,
            eval_batch: $d.eval_batch,
        }
    };
}

impl Decl {
    fn v1(d: &abi::LobeV1) -> Result<Decl, Error> {
        struct_size::<abi::LobeV1>(d.struct_size, "glint_plugin_lobe_v1")?;
        Ok(decl!(d, d.sample.map(Sampler::V1)))
    }

    fn v2(d: &abi::LobeV2) -> Result<Decl, Error> {
        struct_size::<abi::LobeV2>(d.struct_size, "glint_plugin_lobe_v2")?;
        let sample = d.sample.map(|sample| Sampler::V2 {
            sample,
            component_count: d.component_count,
        });
        Ok(decl!(d, sample))
    }
}

impl PluginLobe {
    /// Validate a declaration.
    fn new(d: Decl) -> Result<PluginLobe, Error> {
        let bad = |m: String| Error::new(Status::PluginParams, m);
        let name = identifier(d.name, "name")?;
        let summary = plugin_str(d.summary, "summary")?;
        let context = |e: Error| Error::new(e.status, format!("{name}: {}", e.message));
        let (Some(eval), Some(sample), Some(albedo)) = (d.eval, d.sample, d.albedo) else {
            return Err(bad(format!(
                "{name}: eval, sample and albedo must not be NULL"
            )));
        };
        if d.flags & !ALL_FLAGS != 0 || d.flags & (flags::REFLECTION | flags::TRANSMISSION) == 0 {
            return Err(bad(format!(
                "{name}: flags {:#x}: must be GLINT_PLUGIN_FLAG_* bits including a side",
                d.flags
            )));
        }
        if let Sampler::V2 {
            component_count, ..
        } = sample
        {
            if d.flags & CLASSES == 0 {
                return Err(bad(format!(
                    "{name}: flags {:#x}: a version-2 lobe declares the classes its samples report (DIFFUSE, GLOSSY or SPECULAR)",
                    d.flags
                )));
            }
            if !(1..=MAX_COMPONENTS).contains(&component_count) {
                return Err(bad(format!(
                    "{name}: component_count {component_count} is not in 1..={MAX_COMPONENTS}"
                )));
            }
        }
        if d.reciprocal > 1 {
            return Err(bad(format!("{name}: reciprocal must be 0 or 1")));
        }
        let params = param_table(&d).map_err(context)?;
        let floats = params::block_size(&params);
        if d.block_size as usize != 4 * floats || d.block_align != 4 {
            return Err(Error::new(
                Status::PluginBlockSize,
                format!(
                    "{name}: block_size {} and block_align {} must be {} and 4 (the table declares {floats} floats)",
                    d.block_size,
                    d.block_align,
                    4 * floats
                ),
            ));
        }
        if floats > crate::closure::MAX_PARAM_VALUES {
            return Err(Error::new(
                Status::PluginBlockSize,
                format!(
                    "{name}: {floats} parameter floats exceed a closure's {}",
                    crate::closure::MAX_PARAM_VALUES
                ),
            ));
        }
        Ok(PluginLobe {
            name,
            summary,
            verify_cases: corner_cases(&params),
            params,
            block_len: floats,
            flags: d.flags,
            reciprocal: d.reciprocal == 1,
            eval,
            sample,
            albedo,
            eval_batch: d.eval_batch,
            sanitized: AtomicU64::new(0),
        })
    }

    fn count(&self, n: u64) {
        if n > 0 {
            self.sanitized.fetch_add(n, Ordering::Relaxed);
        }
    }

    /// `v` if finite and in [0, PLUGIN_MAX_VALUE]; else 0, or the maximum for a
    /// larger finite `v` (counted).
    fn clean(&self, v: f32) -> f32 {
        if (0.0..=PLUGIN_MAX_VALUE).contains(&v) {
            v
        } else {
            self.count(1);
            if v.is_finite() && v > 0.0 {
                PLUGIN_MAX_VALUE
            } else {
                0.0
            }
        }
    }

    fn clean_rgb(&self, c: [f32; 3]) -> Rgb<f32> {
        Rgb::new(self.clean(c[0]), self.clean(c[1]), self.clean(c[2]))
    }

    /// A sample's class and component: a V2 sample's own (`reported`: class,
    /// component and the type's component_count) where they keep the rules of
    /// glint_plugin_sample_v2, else (counted) what a V1 sample reports, the type's class
    /// from `class_of` and component 0.
    fn class_and_component(&self, delta: bool, reported: Option<(u32, u32, u32)>) -> (f32, f32) {
        let fallback = class_of::<f32>(delta, self.flags);
        let Some((class, component, component_count)) = reported else {
            return (fallback, 0.0);
        };
        let class_ok = matches!(class, flags::DIFFUSE | flags::GLOSSY | flags::SPECULAR)
            && class & self.flags != 0
            && (class == flags::SPECULAR) == delta;
        let component_ok = component < component_count;
        self.count(u64::from(!class_ok) + u64::from(!component_ok));
        (
            if class_ok { class as f32 } else { fallback },
            if component_ok { component as f32 } else { 0.0 },
        )
    }

    /// Call `f` with a private copy of the parameter block `params`: a plugin may
    /// write through its `const` pointer, and the closure's block must not change.
    /// A copy costs a few nanoseconds for a typical block (a checksum would read the
    /// block twice and could only report the damage); a call that wrote is counted.
    fn with_block<R>(&self, params: &[f32], f: impl FnOnce(*const c_void) -> R) -> R {
        debug_assert_eq!(params.len(), self.block_len);
        let mut buffer = [MaybeUninit::<f32>::uninit(); crate::closure::MAX_PARAM_VALUES];
        let copy = &mut buffer[..params.len()];
        // SAFETY: `copy` and `params` have the same length and do not overlap; the
        // copy initializes every element `block` views.
        let block = unsafe {
            std::ptr::copy_nonoverlapping(params.as_ptr(), copy.as_mut_ptr().cast(), params.len());
            std::slice::from_raw_parts_mut(copy.as_mut_ptr().cast::<f32>(), params.len())
        };
        let result = f(block.as_mut_ptr().cast_const().cast());
        if !same_bits(block, params) {
            self.count(1);
        }
        result
    }
}

/// Whether two blocks hold the same bits (NaN-safe).
fn same_bits(a: &[f32], b: &[f32]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The parameter table as a schema, checked: the packed layout in table order.
fn param_table(d: &Decl) -> Result<Box<[ParamSpec]>, Error> {
    let bad = |m: String| Error::new(Status::PluginParams, m);
    if d.param_count > 0 && d.params.is_null() {
        return Err(bad("params is NULL".into()));
    }
    let mut specs = Vec::with_capacity(d.param_count as usize);
    let mut offset = 0usize;
    for i in 0..d.param_count as usize {
        // SAFETY: `params` holds `param_count` entries (checked non-NULL above).
        let p = unsafe { &*d.params.add(i) };
        let name = identifier(p.name, &format!("parameter {i} name"))?;
        let doc = if p.doc.is_null() {
            ""
        } else {
            plugin_str(p.doc, "doc")?
        };
        let (kind, choices) = match p.kind {
            abi::PARAM_FLOAT => (ParamKind::Float, &[][..]),
            abi::PARAM_RGB => (ParamKind::Rgb, &[][..]),
            abi::PARAM_ENUM => {
                if p.choice_count == 0 || p.choices.is_null() {
                    return Err(bad(format!("parameter {name}: an enum needs choices")));
                }
                let choices: Vec<&'static str> = (0..p.choice_count as usize)
                    // SAFETY: `choices` holds `choice_count` strings (non-NULL checked).
                    .map(|c| {
                        identifier(unsafe { *p.choices.add(c) }, &format!("{name} choice {c}"))
                            .map(intern_str)
                    })
                    .collect::<Result<_, _>>()?;
                (ParamKind::Enum, intern(choices).as_slice())
            }
            k => return Err(bad(format!("parameter {name}: unknown type {k}"))),
        };
        if p.offset as usize != 4 * offset {
            return Err(bad(format!(
                "parameter {name}: offset {} is not the packed layout's {} (floats in table order)",
                p.offset,
                4 * offset
            )));
        }
        if specs.iter().any(|s: &ParamSpec| s.name == name) {
            return Err(bad(format!("parameter {name} is declared twice")));
        }
        let spec = match kind {
            ParamKind::Enum => {
                let index = p.default_value[0];
                if !(index >= 0.0 && (index as usize) < choices.len() && index.fract() == 0.0) {
                    return Err(bad(format!(
                        "parameter {name}: default choice {index} out of range"
                    )));
                }
                ParamSpec::choice(name, choices, index as usize, doc)
            }
            _ => {
                if !(p.min.is_finite() && p.max.is_finite() && p.min <= p.max) {
                    return Err(bad(format!(
                        "parameter {name}: range [{}, {}] is not finite with min <= max",
                        p.min, p.max
                    )));
                }
                let n = kind.size();
                if let Some(v) = p.default_value[..n]
                    .iter()
                    .find(|v| !(p.min..=p.max).contains(*v))
                {
                    return Err(bad(format!(
                        "parameter {name}: default {v} outside [{}, {}]",
                        p.min, p.max
                    )));
                }
                if n == 1 {
                    ParamSpec::float(name, p.default_value[0], p.min, p.max, doc)
                } else {
                    ParamSpec::rgb(name, p.default_value, p.min, p.max, doc)
                }
            }
        };
        offset += kind.size();
        specs.push(spec);
    }
    Ok(specs.into_boxed_slice())
}

/// Verification cases for a plugin lobe type (which cannot declare its own in ABI V1):
/// every float parameter with a range, alone at its minimum and at its maximum.
fn corner_cases(params: &[ParamSpec]) -> Box<[VerifyCase]> {
    params
        .iter()
        .filter(|p| p.kind == ParamKind::Float && p.min < p.max)
        .flat_map(|p| {
            [("min", p.min), ("max", p.max)].map(|(end, v)| VerifyCase {
                name: intern(format!("{} {end}", p.name)).as_str(),
                set: intern(vec![(intern_str(p.name), v)]).as_slice(),
            })
        })
        .collect()
}

fn transport(mode: Transport) -> u32 {
    match mode {
        Transport::Radiance => 0,
        Transport::Importance => 1,
    }
}

impl LobeType for PluginLobe {
    fn name(&self) -> &str {
        self.name
    }
    fn summary(&self) -> &str {
        self.summary
    }
    fn params(&self) -> &[ParamSpec] {
        &self.params
    }
    fn flags(&self) -> u32 {
        self.flags
    }
    fn reciprocal(&self) -> bool {
        self.reciprocal
    }
    fn component_count(&self) -> u32 {
        match self.sample {
            Sampler::V1(_) => 1,
            Sampler::V2 {
                component_count, ..
            } => component_count,
        }
    }

    fn eval(&self, params: &[f32], wo: Vec3<f32>, wi: Vec3<f32>, mode: Transport) -> Eval<f32> {
        let (mut value, mut pdf) = ([0.0f32; 3], 0.0f32);
        // SAFETY: the callback was checked non-NULL; `block` is a copy of this type's
        // validated block; every pointer is valid for the call (glint_plugin.h contract).
        self.with_block(params, |block| unsafe {
            (self.eval)(
                block,
                &[wo.x, wo.y, wo.z],
                &[wi.x, wi.y, wi.z],
                transport(mode),
                &mut value,
                &mut pdf,
            )
        });
        Eval {
            value: self.clean_rgb(value),
            pdf: self.clean(pdf),
        }
    }

    fn sample(&self, params: &[f32], wo: Vec3<f32>, u: [f32; 3], mode: Transport) -> Sample<f32> {
        let wo = [wo.x, wo.y, wo.z];
        let (produced, s, reported) = match self.sample {
            Sampler::V1(sample) => {
                let mut s = abi::Sample::default();
                // SAFETY: the callback was checked non-NULL; `block` is a copy of this
                // type's validated block; every pointer is valid for the call.
                let produced = self.with_block(params, |block| unsafe {
                    sample(block, &wo, &u, transport(mode), &mut s)
                });
                (produced, s, None)
            }
            Sampler::V2 {
                sample,
                component_count,
            } => {
                let mut s = abi::SampleV2 {
                    struct_size: size_of::<abi::SampleV2>() as u32,
                    ..Default::default()
                };
                // SAFETY: as above, with the version-2 sample the callback writes.
                let produced = self.with_block(params, |block| unsafe {
                    sample(block, &wo, &u, transport(mode), &mut s)
                });
                let v1 = abi::Sample {
                    wi: s.wi,
                    value: s.value,
                    pdf: s.pdf,
                    events: s.events,
                    eta: s.eta,
                    roughness: s.roughness,
                };
                (
                    produced,
                    v1,
                    Some((s.sample_class, s.component, component_count)),
                )
            }
        };
        if produced == 0 {
            return crate::lobes::no_sample();
        }
        let wi = Vec3::new(s.wi[0], s.wi[1], s.wi[2]);
        let length = wi.length_squared().sqrt();
        if !(length.is_finite() && (length - 1.0).abs() < 1e-3) {
            self.count(1);
            return crate::lobes::no_sample();
        }
        // A tiny but valid pdf is the floor's doing, not the plugin's fault: not counted.
        if s.pdf.is_nan() || s.pdf < PLUGIN_MIN_PDF {
            self.count(u64::from(s.pdf.is_nan() || s.pdf < 0.0));
            return crate::lobes::no_sample();
        }
        let eta = if s.eta.is_finite() && s.eta > 0.0 {
            s.eta
        } else {
            self.count(1);
            1.0
        };
        let delta = s.events & abi::EVENT_DELTA != 0;
        let (class, component) = self.class_and_component(delta, reported);
        Sample {
            wi: wi.normalize(),
            value: self.clean_rgb(s.value),
            pdf: self.clean(s.pdf),
            valid: true,
            transmitted: s.events & abi::EVENT_TRANSMITTED != 0,
            delta,
            class,
            component,
            eta,
            roughness: if s.roughness.is_finite() {
                s.roughness.clamp(0.0, 1.0)
            } else {
                0.0
            },
        }
        .finish()
    }

    fn albedo(&self, params: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        let mut albedo = [0.0f32; 3];
        // SAFETY: as in `eval`.
        self.with_block(params, |block| unsafe {
            (self.albedo)(block, &[wo.x, wo.y, wo.z], transport(mode), &mut albedo)
        });
        self.clean_rgb(albedo)
    }

    fn albedo_tolerance(&self, _params: &[f32]) -> f32 {
        PLUGIN_ALBEDO_TOLERANCE
    }

    fn verify_cases(&self) -> &[VerifyCase] {
        &self.verify_cases
    }

    fn sanitized_count(&self) -> u64 {
        self.sanitized.load(Ordering::Relaxed)
    }

    fn eval_lanes(&self, _kernels: Kernels, job: &mut EvalJob<'_>) {
        let Some(batch) = self.eval_batch else {
            return kernels::eval_each_lane(job, |params, wo, wi, mode| {
                self.eval(params, wo, wi, mode)
            });
        };
        let n = job.len;
        // Local directions and copies of the per-lane parameter blocks (the plugin may
        // write to them), then one callback for all lanes.
        let mut local = vec![[0.0f32; 6]; n];
        let mut blocks: Vec<Vec<f32>> = Vec::with_capacity(n);
        let mut weights = Vec::with_capacity(n);
        for (i, l) in local.iter_mut().enumerate() {
            let mut block = Vec::new();
            let (frame, weight, probability) = job.lobe.lane(i, &mut block);
            let wo = frame.to_local(Vec3::new(job.wo[0][i], job.wo[1][i], job.wo[2][i]));
            let wi = frame.to_local(Vec3::new(job.wi[0][i], job.wi[1][i], job.wi[2][i]));
            *l = [wo.x, wo.y, wo.z, wi.x, wi.y, wi.z];
            blocks.push(block);
            weights.push((weight, probability));
        }
        let column = |k: usize| local.iter().map(|l| l[k]).collect::<Vec<f32>>();
        let (wo_x, wo_y, wo_z, wi_x, wi_y, wi_z) = (
            column(0),
            column(1),
            column(2),
            column(3),
            column(4),
            column(5),
        );
        let originals = blocks.clone();
        let pointers: Vec<*const c_void> = blocks
            .iter_mut()
            .map(|b| b.as_mut_ptr().cast_const().cast())
            .collect();
        let (mut r, mut g, mut b, mut pdf) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let args = abi::EvalBatch {
            struct_size: size_of::<abi::EvalBatch>() as u32,
            transport: transport(job.mode),
            count: n,
            params: pointers.as_ptr(),
            wo_x: wo_x.as_ptr(),
            wo_y: wo_y.as_ptr(),
            wo_z: wo_z.as_ptr(),
            wi_x: wi_x.as_ptr(),
            wi_y: wi_y.as_ptr(),
            wi_z: wi_z.as_ptr(),
            value_r: r.as_mut_ptr(),
            value_g: g.as_mut_ptr(),
            value_b: b.as_mut_ptr(),
            pdf: pdf.as_mut_ptr(),
        };
        // SAFETY: every array holds `n` elements and outlives the call; the parameter
        // blocks are writable copies of this type's validated blocks.
        unsafe { batch(&args) };
        let wrote = blocks
            .iter()
            .zip(&originals)
            .filter(|(b, o)| !same_bits(b, o))
            .count();
        self.count(wrote as u64);
        for (i, (weight, probability)) in weights.into_iter().enumerate() {
            let value = weight * self.clean_rgb([r[i], g[i], b[i]]);
            if let Some(rows) = &mut job.value {
                for (row, v) in rows.iter_mut().zip(value.to_array()) {
                    row[i] += v;
                }
            }
            job.pdf[i] += probability * self.clean(pdf[i]);
        }
    }
}
