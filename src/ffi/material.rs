//! Material types, compiled materials and shading contexts.

use super::closure::{glint_arena, glint_closure, place_built, vec3_in};
use super::runtime::{fill_param_info, param_info_out, runtime_ref};
use super::*;
use crate::materials::{Material, Override, ShadingContext, compiled::MAX_MATERIAL_PARAMS};
use crate::math::{Frame, Vec3};
use crate::params::{self, ParamKind};

pub(crate) const MATERIAL_LIVE: u64 = u64::from_be_bytes(*b"GLMTLIVE");
pub(crate) const MATERIAL_DEAD: u64 = u64::from_be_bytes(*b"GLMTDEAD");

/// A compiled material: a material type with its parameters validated and resolved
/// once (`glint_material_create`). Immutable and thread-safe; a small shell (see
/// `handle`) around the material.
#[repr(C)]
pub struct glint_material {
    tag: Tag,
    runtime: *const glint_runtime,
    /// `None` once destroyed.
    material: Option<Material>,
}
const _: () = assert!(std::mem::offset_of!(glint_material, tag) == 0);

/// Destroyed materials wait in their own queue, so that destroying many never frees
/// the shell of a destroyed runtime early.
impl Quarantined for glint_material {
    fn queue(&self) -> Queue {
        Queue::Materials
    }
}

/// A live material and its live runtime.
///
/// # Safety
/// `p` is NULL or a handle from a material constructor (see `glint_material_destroy`).
pub(crate) unsafe fn material_ref<'a>(
    p: *const glint_material,
) -> Result<(&'a Material, &'a glint_runtime), Error> {
    // SAFETY: forwarded contract; destroyed shells stay readable while quarantined.
    let m = unsafe { deref(shell(p), "material") }?;
    check_tag(&m.tag, MATERIAL_LIVE, MATERIAL_DEAD, "material")?;
    // SAFETY: the runtime was live when the material was made, and a destroyed
    // runtime's shell stays readable while quarantined.
    let runtime = unsafe { &*m.runtime };
    runtime
        .live()
        .map_err(|e| invalid(format!("the material's {}", e.message)))?;
    let material = m
        .material
        .as_ref()
        .ok_or_else(|| invalid("material was destroyed".into()))?;
    Ok((material, runtime))
}

/// Description of a material type.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_material_info {
    /// Set by the caller to `sizeof(glint_material_info)`.
    pub struct_size: u32,
    pub name: *const c_char,
    pub summary: *const c_char,
    pub param_count: u32,
    /// Floats in the parameter block `glint_material_create_from_params` takes.
    pub param_block_size: u32,
    /// Most lobes one shading point's closure holds.
    pub lobe_count: u32,
}

impl Sized32 for glint_material_info {
    fn struct_size(&self) -> u32 {
        self.struct_size
    }
}

impl Output for glint_material_info {
    fn failed(struct_size: u32) -> Self {
        glint_material_info {
            struct_size,
            name: std::ptr::null(),
            summary: std::ptr::null(),
            param_count: 0,
            param_block_size: 0,
            lobe_count: 0,
        }
    }
}

/// Where and how a surface is seen, world space. Begins with `struct_size`, so
/// fields can be added; a material reads what it needs (the Disney material reads
/// `wo` and the frame), but every field given must be valid.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct glint_shading_context {
    /// Set by the caller to `sizeof(glint_shading_context)`.
    pub struct_size: u32,
    /// Toward the viewer (need not be normalized).
    pub wo: glint_vec3,
    /// The shading frame: normal and an optional tangent (all zeros: automatic), as
    /// in `glint_frame`.
    pub normal: glint_vec3,
    pub tangent: glint_vec3,
    /// The geometric normal (all zeros: the shading normal).
    pub geometric_normal: glint_vec3,
    pub position: glint_vec3,
    /// The position in the object's reference (rest) space.
    pub reference_position: glint_vec3,
    /// Radius of the pixel's footprint on the surface, >= 0.
    pub footprint: f32,
    pub uv: [f32; 2],
}

impl Sized32 for glint_shading_context {
    fn struct_size(&self) -> u32 {
        self.struct_size
    }
}

/// A textured parameter of one shading point: parameter `param` (its index in the
/// material type's schema, see `glint_material_param_info`, or the address of an
/// array element or table cell: `index | element << GLINT_PARAM_ELEMENT_SHIFT`, as
/// `glint_material_param_find` returns for `ramp[3].position`) of type `param_type`
/// (`GLINT_PARAM_*`, checked against the schema) set to `value` (`value[0]` for
/// FLOAT and ENUM).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct glint_override {
    pub param: u32,
    pub param_type: u32,
    pub value: [f32; 3],
}

/// The kind `overrides[i].param_type` names (inlined, the message formatted only on
/// error: this runs per override per shading point).
#[inline(always)]
pub(crate) fn param_kind(param_type: u32, i: usize) -> Result<ParamKind, Error> {
    match param_type {
        GLINT_PARAM_FLOAT => Ok(ParamKind::Float),
        GLINT_PARAM_RGB => Ok(ParamKind::Rgb),
        GLINT_PARAM_ENUM => Ok(ParamKind::Enum),
        t => Err(unknown_param_type(t, i)),
    }
}

#[cold]
fn unknown_param_type(param_type: u32, i: usize) -> Error {
    Error::new(
        Status::InvalidArgument,
        format!(
            "overrides[{i}]: param_type {param_type} is not GLINT_PARAM_FLOAT, GLINT_PARAM_RGB or GLINT_PARAM_ENUM"
        ),
    )
}

/// Whether every component of `v` is finite. (Checked apart from building the
/// context's vector: a `Result<Vec3>` went through the stack as two 4-byte stores read
/// back as one 8-byte load, which stalled store forwarding.)
#[inline(always)]
fn check_finite(v: glint_vec3, what: &str) -> Result<(), Error> {
    if v.x.is_finite() && v.y.is_finite() && v.z.is_finite() {
        Ok(())
    } else {
        Err(not_finite(v, what))
    }
}

#[cold]
fn not_finite(v: glint_vec3, what: &str) -> Error {
    Error::new(
        Status::InvalidArgument,
        format!("{what} ({}, {}, {}) is not finite", v.x, v.y, v.z),
    )
}

fn is_zero(v: glint_vec3) -> bool {
    v.x == 0.0 && v.y == 0.0 && v.z == 0.0
}

/// The caller's context, checked, into `out`. (Written in place and inlined: a
/// context returned in a `Result` was moved out of it, its scalar stores read back as
/// wider loads, store-forwarding stalls in every material closure.)
#[inline(always)]
pub(crate) fn shading_context(
    c: &glint_shading_context,
    out: &mut ShadingContext,
) -> Result<(), Error> {
    check_size(c, "context")?;
    out.wo = vec3_in(c.wo, "context.wo")?;
    let normal = vec3_in(c.normal, "context.normal")?;
    let tangent = if is_zero(c.tangent) {
        None
    } else {
        Some(vec3_in(c.tangent, "context.tangent")?)
    };
    out.geometric_normal = if is_zero(c.geometric_normal) {
        normal
    } else {
        vec3_in(c.geometric_normal, "context.geometric_normal")?
    };
    if !(c.footprint.is_finite() && c.footprint >= 0.0) {
        return Err(Error::new(
            Status::InvalidArgument,
            format!("context.footprint {} must be finite and >= 0", c.footprint),
        ));
    }
    if !(c.uv[0].is_finite() && c.uv[1].is_finite()) {
        return Err(Error::new(
            Status::InvalidArgument,
            format!("context.uv ({}, {}) is not finite", c.uv[0], c.uv[1]),
        ));
    }
    check_finite(c.position, "context.position")?;
    check_finite(c.reference_position, "context.reference_position")?;
    let (p, r) = (c.position, c.reference_position);
    out.frame = Frame::new(normal, tangent);
    out.position = Vec3::new(p.x, p.y, p.z);
    out.reference_position = Vec3::new(r.x, r.y, r.z);
    out.footprint = c.footprint;
    out.uv = c.uv;
    Ok(())
}

/// The caller's `count` overrides (scalar or per lane): none for 0, else at most one
/// per parameter value, so a wild count is refused before any entry past the real
/// ones is read.
///
/// # Safety
/// `overrides` is NULL or valid for `count` entries.
pub(crate) unsafe fn overrides_in<'a, T>(
    overrides: *const T,
    count: usize,
) -> Result<&'a [T], Error> {
    if count == 0 {
        return Ok(&[]);
    }
    if overrides.is_null() {
        return Err(null("overrides (with override_count > 0)"));
    }
    if count > MAX_MATERIAL_PARAMS {
        return Err(Error::new(
            Status::OutOfRange,
            format!(
                "override_count {count}: a material has at most {MAX_MATERIAL_PARAMS} parameter values"
            ),
        ));
    }
    // SAFETY: non-NULL and `count` (at most 64) entries per the contract.
    Ok(unsafe { std::slice::from_raw_parts(overrides, count) })
}

/// The caller's overrides applied to `block`, a copy of the material's values.
///
/// # Safety
/// `overrides` is NULL or valid for `count` entries.
pub(crate) unsafe fn apply_overrides(
    m: &Material,
    overrides: *const glint_override,
    count: usize,
    block: &mut [f32],
) -> Result<(), Error> {
    // SAFETY: forwarded contract.
    let given = unsafe { overrides_in(overrides, count) }?;
    for (i, o) in given.iter().enumerate() {
        let o = Override {
            param: o.param,
            kind: param_kind(o.param_type, i)?,
            value: o.value,
        };
        m.apply_one(i, &o, block)?;
    }
    Ok(())
}

/// Number of material types; their ids are `0 .. count - 1`.
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_type_count(
    runtime: *const glint_runtime,
    out: *mut u32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0) }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        *out = rt.runtime.registry.materials().len() as u32;
        Ok(())
    })
}

/// The id of the material type named `name`.
///
/// # Safety
/// `runtime` is NULL or valid; `name` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_type_find(
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
        *out = rt.runtime.registry.find_material(name)?;
        Ok(())
    })
}

/// Describe material type `id`. The strings live as long as the runtime.
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or a writable struct with `struct_size` set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_type_info(
    runtime: *const glint_runtime,
    id: u32,
    out: *mut glint_material_info,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_struct(out, "info") }?;
        // SAFETY: per the contract.
        let rt = unsafe { runtime_ref(runtime) }?;
        let t = rt.runtime.registry.material(id)?;
        let s = rt.material_strings(id);
        *out = glint_material_info {
            struct_size: out.struct_size,
            name: s.name.as_ptr(),
            summary: s.summary.as_ptr(),
            param_count: t.params().len() as u32,
            param_block_size: params::block_size(t.params()) as u32,
            lobe_count: t.lobes().len() as u32,
        };
        Ok(())
    })
}

/// Describe parameter `index` of material type `id` (as `glint_lobe_param_info`).
///
/// # Safety
/// `runtime` is NULL or valid; `out` is NULL or a writable struct with `struct_size` set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_param_info(
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
                let t = rt.runtime.registry.material(id)?;
                fill_param_info(t.name(), t.params(), rt.material_strings(id), index, out)
            })
        }
    })
}

/// The index of the parameter named `name` of material type `id`, or an element's
/// address (as `glint_lobe_param_find`).
///
/// # Safety
/// `runtime` is NULL or valid; `name` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_param_find(
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
        let t = rt.runtime.registry.material(id)?;
        *out = super::runtime::param_index(t.name(), t.params(), name)?;
        Ok(())
    })
}

fn place_material(
    runtime: &glint_runtime,
    material: Material,
    out: &mut *mut glint_material,
) -> Result<(), Error> {
    *out = Box::into_raw(Box::new(glint_material {
        tag: Tag::new(MATERIAL_LIVE),
        runtime,
        material: Some(material),
    }));
    Ok(())
}

/// Compile a material from its JSON description, `{"material": "disney",
/// "base_color": [0.8, 0.1, 0.1], ...}` (every key but `material` a parameter of the
/// type's schema; see the README): validated and resolved once, for every shading
/// point of a scene material. Free it with `glint_material_destroy`.
///
/// # Safety
/// `runtime` is NULL or live; `json_text` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_create(
    runtime: *const glint_runtime,
    json_text: *const c_char,
    out: *mut *mut glint_material,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", std::ptr::null_mut()) }?;
        // SAFETY: per the contract.
        let shell = unsafe { deref(shell(runtime), "runtime") }?;
        let rt = &shell.live()?.runtime;
        // SAFETY: per the contract.
        let text = unsafe { c_str(json_text, "json_text") }?;
        let material = crate::json::material_from_json(&rt.registry, text, rt.settings.prune)?;
        place_material(shell, material, out)
    })
}

/// Compile material type `type_id` with `params`, its whole parameter block
/// (`param_count == param_block_size`, see `glint_material_param_info`), or NULL with
/// `param_count == 0` for the defaults.
///
/// # Safety
/// `runtime` is NULL or live; `params` NULL or `param_count` floats; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_create_from_params(
    runtime: *const glint_runtime,
    type_id: u32,
    params: *const f32,
    param_count: usize,
    out: *mut *mut glint_material,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", std::ptr::null_mut()) }?;
        // SAFETY: per the contract.
        let shell = unsafe { deref(shell(runtime), "runtime") }?;
        let rt = &shell.live()?.runtime;
        // SAFETY: per the contract.
        let params = unsafe { param_block(params, param_count, MAX_MATERIAL_PARAMS) }?;
        let material = Material::new(&rt.registry, type_id, params, rt.settings.prune)?;
        place_material(shell, material, out)
    })
}

/// Destroy a material (NULL is ignored). Closures built from it stay valid. A call
/// with the destroyed handle returns `GLINT_ERROR_INVALID_HANDLE` while its shell is
/// quarantined, that is until `GLINT_QUARANTINE_SHELLS` (1024) more materials were
/// destroyed (material destroys are counted apart from runtime and arena destroys).
///
/// # Safety
/// `material` is NULL or a handle from a material constructor.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_destroy(material: *mut glint_material) {
    guard(|| {
        let material = shell_mut(material);
        if material.is_null() {
            return Ok(());
        }
        // SAFETY: a handle from a material constructor, live or quarantined.
        let m = unsafe { &mut *material };
        poison(&m.tag, MATERIAL_LIVE, MATERIAL_DEAD, "material")?;
        m.material = None;
        // SAFETY: created by Box::into_raw in `place_material`; the tag is now dead,
        // so no later call takes ownership again.
        quarantine(unsafe { Box::from_raw(material) }, 0);
        Ok(())
    });
}

/// Build (and finish) the closure of one shading point of `material` in `arena`:
/// `overrides` (NULL with `override_count == 0` for none; at most 64) set textured
/// parameters for this point; the material expands into weighted lobes in the
/// context's frame, drops those whose `luminance(weight * albedo(wo))` (by each lobe's
/// albedo estimate, README "Pruning") is below the runtime's `prune=` threshold, and
/// fixes lobe selection from the rest. The context and overrides are checked before the
/// arena is touched, so a failing call uses no slot.
///
/// # Safety
/// Handles are NULL or live; `context` NULL or readable; `overrides` NULL or valid
/// for `override_count` entries; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_closure(
    material: *const glint_material,
    arena: *mut glint_arena,
    context: *const glint_shading_context,
    overrides: *const glint_override,
    override_count: usize,
    out: *mut *mut glint_closure,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", std::ptr::null_mut()) }?;
        // SAFETY: per the contract.
        let (m, runtime) = unsafe { material_ref(material) }?;
        // SAFETY: per the contract.
        let mut ctx = ShadingContext::new(Vec3::splat(0.0, 0.0, 1.0), Frame::IDENTITY);
        shading_context(unsafe { deref(context, "context") }?, &mut ctx)?;
        // The compiled block itself when nothing overrides it (no copy).
        let mut padded;
        let block = if override_count == 0 {
            m.params()
        } else {
            padded = m.padded_params();
            let block = &mut padded[..m.params().len()];
            // SAFETY: per the contract.
            unsafe { apply_overrides(m, overrides, override_count, block) }?;
            block
        };
        // SAFETY: per the contract.
        unsafe {
            place_built(runtime, arena, out, |closure| {
                m.build_closure_from(closure, &ctx, block)
            })
        }
    })
}
