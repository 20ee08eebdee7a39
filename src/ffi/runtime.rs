//! Version, status strings, the runtime and the lobe registry.

use super::*;
use crate::params::{self, ParamKind, ParamSpec, Shape};
use crate::runtime::Runtime;
use crate::simd::Isa;

/// C strings of one lobe or material type, made once so the registry can hand out
/// pointers.
pub(crate) struct LobeStrings {
    pub(crate) name: CString,
    pub(crate) summary: CString,
    params: Vec<ParamStrings>,
}

struct ParamStrings {
    name: CString,
    choices: CString,
    doc: CString,
}

fn c_string(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}

/// The runtime handle: a small shell (see `handle`) around what the runtime owns.
#[repr(C)]
pub struct glint_runtime {
    tag: Tag,
    /// `None` once destroyed.
    live: Option<Box<LiveRuntime>>,
}
const _: () = assert!(std::mem::offset_of!(glint_runtime, tag) == 0);

/// Destroyed runtimes wait with destroyed arenas.
impl Quarantined for glint_runtime {}

/// What a live runtime owns: the registry and settings. Read-only after setup.
pub(crate) struct LiveRuntime {
    pub(crate) runtime: Runtime,
    strings: Vec<LobeStrings>,
    materials: Vec<LobeStrings>,
}

impl glint_runtime {
    fn new(runtime: Runtime) -> Self {
        let materials = runtime
            .registry
            .materials()
            .iter()
            .map(|m| LobeStrings::new(m.name(), m.summary(), m.params()))
            .collect();
        let mut live = LiveRuntime {
            runtime,
            strings: Vec::new(),
            materials,
        };
        live.cache_strings();
        glint_runtime {
            tag: Tag::new(RUNTIME_LIVE),
            live: Some(Box::new(live)),
        }
    }

    /// The runtime's contents, or `GLINT_ERROR_INVALID_HANDLE` once destroyed (the
    /// tag says so; the contents are gone).
    #[inline(always)]
    pub(crate) fn live(&self) -> Result<&LiveRuntime, Error> {
        check_tag(&self.tag, RUNTIME_LIVE, RUNTIME_DEAD, "runtime")?;
        self.live.as_deref().ok_or_else(destroyed)
    }

    fn live_mut(&mut self) -> Result<&mut LiveRuntime, Error> {
        check_tag(&self.tag, RUNTIME_LIVE, RUNTIME_DEAD, "runtime")?;
        self.live.as_deref_mut().ok_or_else(destroyed)
    }
}

impl LiveRuntime {
    /// C strings for lobe types registered since the last call. Existing strings
    /// never move (each `CString` owns its buffer), so pointers handed out stay valid.
    fn cache_strings(&mut self) {
        let known = self.strings.len();
        self.strings.extend(
            self.runtime
                .registry
                .iter()
                .skip(known)
                .map(|t| LobeStrings::new(t.name(), t.summary(), t.params())),
        );
    }

    /// The C strings of material type `id` (a valid id).
    pub(crate) fn material_strings(&self, id: u32) -> &LobeStrings {
        &self.materials[id as usize]
    }
}

impl LobeStrings {
    fn new(name: &str, summary: &str, params: &[ParamSpec]) -> Self {
        LobeStrings {
            name: c_string(name),
            summary: c_string(summary),
            params: params
                .iter()
                .map(|p| ParamStrings {
                    name: c_string(p.name),
                    choices: c_string(&p.choices().join("|")),
                    doc: c_string(p.doc),
                })
                .collect(),
        }
    }
}

/// Describe entry `index` of the type `owner` with schema `specs` and C strings
/// `strings` (lobe and material types alike).
pub(crate) fn fill_param_info(
    owner: &str,
    specs: &[ParamSpec],
    strings: &LobeStrings,
    index: u32,
    out: &mut glint_param_info,
) -> Result<(), Error> {
    let i = index as usize;
    let spec = specs.get(i).ok_or_else(|| {
        Error::new(
            Status::OutOfRange,
            format!(
                "{owner} has {} parameters; index {index} is out of range",
                specs.len()
            ),
        )
    })?;
    let s = &strings.params[i];
    let offset = params::offset_of(specs, i);
    let parent = params::parent_of(specs, i);
    let count_offset = match (spec.shape, parent) {
        (Shape::Array | Shape::Table, _) => offset as u32,
        (Shape::Column, Some(table)) => params::offset_of(specs, table) as u32,
        _ => GLINT_PARAM_NO_INDEX,
    };
    let header = matches!(spec.shape, Shape::Group | Shape::Table);
    *out = glint_param_info {
        struct_size: out.struct_size,
        name: s.name.as_ptr(),
        param_type: match spec.kind {
            _ if header => GLINT_PARAM_NONE,
            ParamKind::Float => GLINT_PARAM_FLOAT,
            ParamKind::Rgb => GLINT_PARAM_RGB,
            ParamKind::Enum => GLINT_PARAM_ENUM,
        },
        offset: (offset + spec.element_offset(0)) as u32,
        size: match spec.shape {
            Shape::Group => 0,
            Shape::Table => 1,
            _ => spec.kind.size() as u32,
        },
        default_value: spec.default,
        min: spec.min,
        max: spec.max,
        choice_count: spec.choices().len() as u32,
        choices: s.choices.as_ptr(),
        doc: s.doc.as_ptr(),
        shape: match spec.shape {
            Shape::Value => GLINT_SHAPE_VALUE,
            Shape::Array => GLINT_SHAPE_ARRAY,
            Shape::Group => GLINT_SHAPE_GROUP,
            Shape::Table => GLINT_SHAPE_TABLE,
            Shape::Column => GLINT_SHAPE_COLUMN,
        },
        parent: parent.map_or(GLINT_PARAM_NO_INDEX, |p| p as u32),
        member_count: spec.members,
        capacity: spec.capacity,
        count_offset,
        default_count: spec.count,
    };
    Ok(())
}

/// The address of the parameter named `name` in `specs` (of the type `owner`): an
/// entry's index, or an element's ([`params::find`]).
pub(crate) fn param_index(owner: &str, specs: &[ParamSpec], name: &str) -> Result<u32, Error> {
    params::find(owner, specs, name)
}

/// `struct_size` of `glint_param_info` as first published (through `doc`), still
/// accepted: such callers get those fields.
const PARAM_INFO_V1_SIZE: usize = std::mem::offset_of!(glint_param_info, shape);

/// Fill a caller's `glint_param_info` of the first published size or the current
/// one (or larger) with `fill`; failure leaves the failure state. A NULL struct or
/// any other `struct_size` is an error and nothing is written.
///
/// # Safety
/// `p` is NULL or valid for writes of its `struct_size` bytes (at least the field).
pub(crate) unsafe fn param_info_out(
    p: *mut glint_param_info,
    fill: impl FnOnce(&mut glint_param_info) -> Result<(), Error>,
) -> Result<(), Error> {
    if p.is_null() {
        return Err(null("info"));
    }
    // SAFETY: non-NULL; the caller's struct begins with `struct_size`.
    let size = unsafe { std::ptr::addr_of!((*p).struct_size).read() };
    let full = std::mem::size_of::<glint_param_info>();
    if size as usize != PARAM_INFO_V1_SIZE && (size as usize) < full {
        return Err(Error::new(
            Status::StructSize,
            format!(
                "info.struct_size is {size}; this library takes {PARAM_INFO_V1_SIZE} (first \
                 version) or at least {full}"
            ),
        ));
    }
    let mut info = glint_param_info::failed(size);
    let result = fill(&mut info);
    if result.is_err() {
        info = glint_param_info::failed(size);
    }
    // SAFETY: the caller's struct holds `size` bytes; the copy stops at ours.
    unsafe {
        std::ptr::copy_nonoverlapping(
            (&raw const info).cast::<u8>(),
            p.cast::<u8>(),
            (size as usize).min(full),
        );
    }
    result
}

#[cold]
fn destroyed() -> Error {
    invalid("runtime was destroyed".into())
}

/// A live runtime from a handle the caller promises is NULL or from
/// `glint_runtime_create` (destroyed handles are detected while quarantined).
///
/// # Safety
/// `p` is NULL or a handle from `glint_runtime_create`, as documented on
/// `glint_runtime_destroy`.
pub(crate) unsafe fn runtime_ref<'a>(p: *const glint_runtime) -> Result<&'a LiveRuntime, Error> {
    // SAFETY: forwarded contract; destroyed shells stay readable while quarantined.
    unsafe { deref(shell(p), "runtime") }?.live()
}

/// Description of a lobe type.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_lobe_info {
    /// Set by the caller to `sizeof(glint_lobe_info)`.
    pub struct_size: u32,
    pub name: *const c_char,
    pub summary: *const c_char,
    /// Every `GLINT_FLAG_*` a sample of this lobe may carry.
    pub flags: u32,
    /// 1 when `f(wo, wi) == f(wi, wo)`.
    pub reciprocal: u32,
    pub param_count: u32,
    /// Floats in the parameter block `glint_closure_add_lobe` takes.
    pub param_block_size: u32,
    /// How many components (sub-lobes) its samples report
    /// (`glint_sample_result.component` is below it): a `dielectric` 2 (reflection,
    /// transmission), other built-ins 1, a plugin what it declares. Appended: a caller
    /// built against a header without it passes that header's `sizeof` and is not
    /// written past it.
    pub component_count: u32,
}

/// `struct_size` of `glint_lobe_info` before `component_count`, still accepted.
const LOBE_INFO_V1_SIZE: usize = std::mem::offset_of!(glint_lobe_info, component_count);

impl Sized32 for glint_lobe_info {
    fn struct_size(&self) -> u32 {
        self.struct_size
    }
}

impl Output for glint_lobe_info {
    fn failed(struct_size: u32) -> Self {
        glint_lobe_info {
            struct_size,
            name: std::ptr::null(),
            summary: std::ptr::null(),
            flags: 0,
            reciprocal: 0,
            param_count: 0,
            param_block_size: 0,
            component_count: 0,
        }
    }
}

/// Description of one parameter of a lobe type.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_param_info {
    /// Set by the caller to `sizeof(glint_param_info)`.
    pub struct_size: u32,
    /// The full name: `roughness`, `coat.roughness` (group member), `ramp.position`
    /// (table column).
    pub name: *const c_char,
    /// `GLINT_PARAM_FLOAT`, `GLINT_PARAM_RGB` or `GLINT_PARAM_ENUM` (of each element
    /// of an array or column); `GLINT_PARAM_NONE` for group and table headers.
    pub param_type: u32,
    /// Position of the first value in the parameter block (of a table: its count).
    pub offset: u32,
    /// Number of floats of one value (1, or 3 for RGB; a table 1, a group 0).
    pub size: u32,
    /// Default value (RGB: all three; ENUM: the choice index).
    pub default_value: [f32; 3],
    /// Inclusive range of every component (ENUM: 0 .. choice_count - 1).
    pub min: f32,
    pub max: f32,
    pub choice_count: u32,
    /// ENUM choices separated by '|', e.g. "ggx|beckmann"; "" otherwise.
    pub choices: *const c_char,
    pub doc: *const c_char,
    /// Fields below were added with nested schemas; a caller passing the first
    /// version's `struct_size` (through `doc`) does not get them. `GLINT_SHAPE_*`.
    pub shape: u32,
    /// Index of the group or table the entry belongs to; `GLINT_PARAM_NO_INDEX` at
    /// the top level.
    pub parent: u32,
    /// Group and table headers: how many entries after this one belong to it.
    pub member_count: u32,
    /// Arrays, tables and columns: most elements (rows); 0 otherwise.
    pub capacity: u32,
    /// Arrays, tables and columns: block offset of the count (a whole number of
    /// elements in use, in [0, capacity]); `GLINT_PARAM_NO_INDEX` otherwise.
    pub count_offset: u32,
    /// Arrays and tables: the default count.
    pub default_count: u32,
}

impl Sized32 for glint_param_info {
    fn struct_size(&self) -> u32 {
        self.struct_size
    }
}

impl Output for glint_param_info {
    fn failed(struct_size: u32) -> Self {
        glint_param_info {
            struct_size,
            name: std::ptr::null(),
            param_type: 0,
            offset: 0,
            size: 0,
            default_value: [0.0; 3],
            min: 0.0,
            max: 0.0,
            choice_count: 0,
            choices: std::ptr::null(),
            doc: std::ptr::null(),
            shape: 0,
            parent: GLINT_PARAM_NO_INDEX,
            member_count: 0,
            capacity: 0,
            count_offset: GLINT_PARAM_NO_INDEX,
            default_count: 0,
        }
    }
}

/// The library version as `MAJOR * 10000 + MINOR * 100 + PATCH`.
#[unsafe(no_mangle)]
pub extern "C" fn glint_version() -> u32 {
    GLINT_VERSION_MAJOR * 10000 + GLINT_VERSION_MINOR * 100 + GLINT_VERSION_PATCH
}

/// A static description of a status code (never NULL).
#[unsafe(no_mangle)]
pub extern "C" fn glint_status_string(status: glint_status) -> *const c_char {
    Status::ALL
        .get(status as usize)
        .map_or(c"unknown status code", |s| s.description())
        .as_ptr()
}

/// The message of the last failed call on this thread ("" if none). Valid until the
/// next failing call on the same thread.
#[unsafe(no_mangle)]
pub extern "C" fn glint_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Create a runtime. `config` is NULL or `key=value` pairs separated by spaces,
/// commas or semicolons; valid keys: `isa` (`auto` | `scalar` | `avx2` | `avx512`;
/// an ISA this CPU lacks is `GLINT_ERROR_UNSUPPORTED`), `threads` (0 = one per
/// core, the default; 1 = batch calls stay on the calling thread; N = a pool of N),
/// `plugins` (a directory whose `*.so` plugins are loaded, in file-name order),
/// `prune` (in [0, 1], default 0.001: materials do not emit a lobe whose
/// `luminance(weight * albedo(wo))`, by the lobe's albedo estimate, is below it) and
/// `stores` (`auto` | `held` | `direct`: whether a batch over a Disney closure
/// stores its outputs after later loads, in calls of 32768 lanes or more whose output
/// rows collide with their input rows in the L2 cache through a ring; `auto`, the
/// default, holds them except on AMD CPUs). Results are the same bits under every
/// `stores`.
///
/// # Safety
/// `config` is NULL or a NUL-terminated string; `out` is valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_runtime_create(
    config: *const c_char,
    out: *mut *mut glint_runtime,
) -> glint_status {
    guard(|| {
        // SAFETY: `out` is NULL or writable per the contract.
        let out = unsafe { deref_mut(out, "out") }?;
        *out = std::ptr::null_mut();
        let config = if config.is_null() {
            ""
        } else {
            // SAFETY: non-NULL and NUL-terminated per the contract.
            unsafe { c_str(config, "config") }?
        };
        let runtime = Runtime::new(config)?;
        *out = Box::into_raw(Box::new(glint_runtime::new(runtime)));
        Ok(())
    })
}

/// Destroy a runtime (NULL is ignored). Arenas and closures made with it must not be
/// used afterwards: closure calls then return `GLINT_ERROR_INVALID_HANDLE`, as does a
/// call on the destroyed runtime; destroying it again is ignored and leaves that
/// message for `glint_last_error`. This holds while the handle's small shell is
/// quarantined, that is until `GLINT_QUARANTINE_SHELLS` (1024) more runtimes and arenas
/// were destroyed (destroying materials does not count); after that, and for pointers
/// never returned by `glint_runtime_create`, the behaviour is undefined, as is a call
/// that races with the destroy.
///
/// # Safety
/// `runtime` is NULL or a handle from `glint_runtime_create`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_runtime_destroy(runtime: *mut glint_runtime) {
    guard(|| {
        let runtime = shell_mut(runtime);
        if runtime.is_null() {
            return Ok(());
        }
        // SAFETY: a handle from glint_runtime_create, live or quarantined.
        let rt = unsafe { &mut *runtime };
        poison(&rt.tag, RUNTIME_LIVE, RUNTIME_DEAD, "runtime")?;
        rt.live = None;
        // SAFETY: created by Box::into_raw in glint_runtime_create; the tag is now
        // dead, so no later call takes ownership again.
        quarantine(unsafe { Box::from_raw(runtime) }, 0);
        Ok(())
    });
}

/// The kernel set batch calls on this runtime's closures use: `"scalar"`, `"avx2"`
/// or `"avx512"` (static string; `isa=auto` resolves to the widest the CPU has).
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_runtime_isa(
    runtime: *const glint_runtime,
    out: *mut *const c_char,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", std::ptr::null()) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        let name = match rt.runtime.kernels().isa() {
            Isa::Scalar => c"scalar",
            Isa::Avx2 => c"avx2",
            Isa::Avx512 => c"avx512",
        };
        *out = name.as_ptr();
        Ok(())
    })
}

/// Load the plugin shared library at `path` (built against `glint_plugin.h`) and
/// register its lobe types, which then work like built-in ones. Plugins are never
/// unloaded. On error nothing is registered, the status names the cause
/// (`GLINT_ERROR_PLUGIN_*`, `GLINT_ERROR_DUPLICATE_NAME`) and the runtime keeps working.
/// Not thread-safe: load plugins before the runtime is shared between threads.
///
/// # Safety
/// `runtime` is NULL or valid and not in use by another thread; `path` NULL or
/// NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_runtime_load_plugin(
    runtime: *mut glint_runtime,
    path: *const c_char,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let rt = unsafe { deref_mut(shell_mut(runtime), "runtime") }?.live_mut()?;
        // SAFETY: per the contract.
        let path = unsafe { c_str(path, "path") }?;
        rt.runtime.load_plugin(std::path::Path::new(path))?;
        rt.cache_strings();
        Ok(())
    })
}

/// How many outputs of lobe type `type_id` were zeroed because they were NaN,
/// infinite or negative (values, pdfs) or unusable directions: always 0 for built-in
/// lobes; for a plugin lobe, a nonzero count means the plugin is broken.
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_sanitized_count(
    runtime: *const glint_runtime,
    type_id: u32,
    out: *mut u64,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        let count = rt.runtime.registry.get(type_id)?.sanitized_count();
        *out = count;
        Ok(())
    })
}

/// Number of registered lobe types; their ids are `0 .. count - 1`.
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_type_count(
    runtime: *const glint_runtime,
    out: *mut u32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        *out = rt.runtime.registry.len() as u32;
        Ok(())
    })
}

/// The id of the lobe type named `name`.
///
/// # Safety
/// `runtime` is NULL or valid; `name` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_type_find(
    runtime: *const glint_runtime,
    name: *const c_char,
    out: *mut u32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        // SAFETY: per the contract.
        let name = unsafe { c_str(name, "name") }?;
        let id = rt.runtime.registry.find(name)?;
        *out = id;
        Ok(())
    })
}

/// Describe lobe type `id`. The strings live as long as the runtime.
/// `out->struct_size` is `sizeof(glint_lobe_info)` or the size before
/// `component_count` was appended.
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or a writable struct with `struct_size` set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_type_info(
    runtime: *const glint_runtime,
    id: u32,
    out: *mut glint_lobe_info,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_versioned(out, LOBE_INFO_V1_SIZE, "info") }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        let t = rt.runtime.registry.get(id)?;
        let s = &rt.strings[id as usize];
        out.write(glint_lobe_info {
            struct_size: out.struct_size,
            name: s.name.as_ptr(),
            summary: s.summary.as_ptr(),
            flags: t.flags(),
            reciprocal: u32::from(t.reciprocal()),
            param_count: t.params().len() as u32,
            param_block_size: params::block_size(t.params()) as u32,
            component_count: t.component_count(),
        });
        Ok(())
    })
}

/// Describe entry `index` of lobe type `id`'s schema (entries in order: a group or
/// table header is followed by its members). `out->struct_size` is
/// `sizeof(glint_param_info)` or the first version's size (fields through `doc`).
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or a writable struct with `struct_size` set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_param_info(
    runtime: *const glint_runtime,
    id: u32,
    index: u32,
    out: *mut glint_param_info,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        unsafe {
            param_info_out(out, |out| {
                let rt = runtime_ref(runtime)?;
                let t = rt.runtime.registry.get(id)?;
                fill_param_info(t.name(), t.params(), &rt.strings[id as usize], index, out)
            })
        }
    })
}

/// The index of the parameter named `name` (its full name, e.g. `coat.roughness`) of
/// lobe type `id`, or the address of an element (`weights[2]`, `ramp[3].position`:
/// see `GLINT_PARAM_ELEMENT_SHIFT`).
///
/// # Safety
/// `runtime` is NULL or valid; `name` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_param_find(
    runtime: *const glint_runtime,
    id: u32,
    name: *const c_char,
    out: *mut u32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        // SAFETY: per the contract.
        let name = unsafe { c_str(name, "name") }?;
        let t = rt.runtime.registry.get(id)?;
        *out = param_index(t.name(), t.params(), name)?;
        Ok(())
    })
}

/// The index of choice `choice` of enum parameter `index` of lobe type `id`, as a
/// float ready to store in a parameter block.
///
/// # Safety
/// `runtime` is NULL or valid; `choice` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_param_choice(
    runtime: *const glint_runtime,
    id: u32,
    index: u32,
    choice: *const c_char,
    out: *mut f32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0.0) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        // SAFETY: per the contract.
        let choice = unsafe { c_str(choice, "choice") }?;
        let t = rt.runtime.registry.get(id)?;
        let spec = t.params().get(index as usize).ok_or_else(|| {
            Error::new(
                Status::OutOfRange,
                format!("{}: parameter index {index} is out of range", t.name()),
            )
        })?;
        if spec.kind != ParamKind::Enum {
            return Err(Error::new(
                Status::InvalidArgument,
                format!("{}.{} is not an enum parameter", t.name(), spec.name),
            ));
        }
        let value = spec.choice_index(t.name(), choice)? as f32;
        *out = value;
        Ok(())
    })
}

/// Write the default parameter block of lobe type `id` to `out[0 .. param_block_size)`;
/// `capacity` (floats available at `out`) must be at least its `param_block_size`.
/// On failure `out[0 .. min(capacity, GLINT_MAX_PARAM_VALUES))` is zeroed: no block is
/// longer, and a wild capacity (bytes for floats, `SIZE_MAX`) is not written through.
///
/// # Safety
/// `runtime` is NULL or valid; `out` NULL or valid for `capacity` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_lobe_param_defaults(
    runtime: *const glint_runtime,
    id: u32,
    out: *mut f32,
    capacity: usize,
) -> glint_status {
    guard(|| {
        if out.is_null() {
            return Err(null("out"));
        }
        // SAFETY: non-NULL and valid for `capacity` floats per the contract; no more
        // are used.
        let out = unsafe {
            std::slice::from_raw_parts_mut(out, capacity.min(GLINT_MAX_PARAM_VALUES as usize))
        };
        // Success writes only the block; failure zeroes all of `out`.
        let defaults = |out: &mut [f32]| {
            // SAFETY: per the contract.
            let rt = unsafe { runtime_ref(runtime) }?;
            let t = rt.runtime.registry.get(id)?;
            let size = params::block_size(t.params());
            if capacity < size {
                return Err(Error::new(
                    Status::OutOfRange,
                    format!("{} needs {size} floats; capacity is {capacity}", t.name()),
                ));
            }
            params::write_defaults(t.params(), &mut out[..size]);
            Ok(())
        };
        defaults(out).inspect_err(|_| out.fill(0.0))
    })
}
