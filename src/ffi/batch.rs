//! Batch entry points over SoA arrays. Each argument struct begins with
//! `struct_size`; lanes take either one closure (`closure`) or one per lane
//! (`closures`, used when non-NULL); `active` (optional) skips lanes whose byte is 0,
//! leaving their outputs untouched.

use super::*;
use crate::batch::{
    self, BatchInput, EvalOutput, Exec, SampleOutput, SampleRandoms, Soa3, Soa3Mut,
};
use crate::closure::Closure;
use std::fmt::Display;

/// Most lanes one batch call takes (`count`; larger counts return
/// `GLINT_ERROR_OUT_OF_RANGE` before any array is read): lanes are indexed by 32-bit
/// integers.
pub const GLINT_MAX_BATCH_COUNT: u64 = 4_294_967_295;
const _: () = assert!(GLINT_MAX_BATCH_COUNT as usize == batch::MAX_COUNT);
// Every array of `count` elements (at most 8 bytes each) fits in `isize::MAX` bytes, as
// `std::slice::from_raw_parts` requires.
const _: () = assert!(batch::MAX_COUNT <= isize::MAX as usize / 8);

/// Arguments of `glint_eval_batch`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_eval_batch_args {
    /// Set by the caller to `sizeof(glint_eval_batch_args)`.
    pub struct_size: u32,
    pub count: usize,
    /// The closure of every lane, used when `closures` is NULL.
    pub closure: *const glint_closure,
    /// One closure per lane (`count` entries), or NULL.
    pub closures: *const *const glint_closure,
    /// Optional: `count` bytes, 0 = skip the lane.
    pub active: *const u8,
    pub wo_x: *const f32,
    pub wo_y: *const f32,
    pub wo_z: *const f32,
    pub wi_x: *const f32,
    pub wi_y: *const f32,
    pub wi_z: *const f32,
    pub value_r: *mut f32,
    pub value_g: *mut f32,
    pub value_b: *mut f32,
    pub pdf: *mut f32,
    /// Optional.
    pub pdf_reverse: *mut f32,
}

/// Arguments of `glint_pdf_batch`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_pdf_batch_args {
    /// Set by the caller to `sizeof(glint_pdf_batch_args)`.
    pub struct_size: u32,
    pub count: usize,
    pub closure: *const glint_closure,
    pub closures: *const *const glint_closure,
    pub active: *const u8,
    pub wo_x: *const f32,
    pub wo_y: *const f32,
    pub wo_z: *const f32,
    pub wi_x: *const f32,
    pub wi_y: *const f32,
    pub wi_z: *const f32,
    pub pdf: *mut f32,
}

/// Arguments of `glint_sample_batch`. Lanes that cannot scatter get `pdf = 0`,
/// zero `wi` and weight, and `flags = 0`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_sample_batch_args {
    /// Set by the caller to `sizeof(glint_sample_batch_args)`.
    pub struct_size: u32,
    pub count: usize,
    pub closure: *const glint_closure,
    pub closures: *const *const glint_closure,
    pub active: *const u8,
    pub wo_x: *const f32,
    pub wo_y: *const f32,
    pub wo_z: *const f32,
    pub u_lobe: *const f32,
    pub u0: *const f32,
    pub u1: *const f32,
    pub wi_x: *mut f32,
    pub wi_y: *mut f32,
    pub wi_z: *mut f32,
    pub pdf: *mut f32,
    pub weight_r: *mut f32,
    pub weight_g: *mut f32,
    pub weight_b: *mut f32,
    /// Optional outputs (NULL = not written).
    pub value_r: *mut f32,
    pub value_g: *mut f32,
    pub value_b: *mut f32,
    pub flags: *mut u32,
    pub lobe: *mut u32,
    pub eta: *mut f32,
    pub roughness: *mut f32,
    /// Optional: the component (sub-lobe) of each sample, 0 for failed lanes
    /// (`glint_sample_result.component`). Appended: a caller built against a header
    /// without it passes its smaller `struct_size`, and nothing is written here.
    pub component: *mut u32,
}

/// Arguments of `glint_albedo_batch`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_albedo_batch_args {
    /// Set by the caller to `sizeof(glint_albedo_batch_args)`.
    pub struct_size: u32,
    pub count: usize,
    pub closure: *const glint_closure,
    pub closures: *const *const glint_closure,
    pub active: *const u8,
    pub wo_x: *const f32,
    pub wo_y: *const f32,
    pub wo_z: *const f32,
    pub albedo_r: *mut f32,
    pub albedo_g: *mut f32,
    pub albedo_b: *mut f32,
}

/// `sizeof(glint_sample_batch_args)` before `component`: the oldest size accepted.
const SAMPLE_ARGS_V1_SIZE: usize = std::mem::offset_of!(glint_sample_batch_args, component);
/// The same for `glint_material_sample_batch_args`.
const MATERIAL_SAMPLE_ARGS_V1_SIZE: usize =
    std::mem::offset_of!(glint_material_sample_batch_args, component);
/// The same for `glint_material_eval_batch_args` before `direction_count`.
const MATERIAL_EVAL_ARGS_V1_SIZE: usize =
    std::mem::offset_of!(glint_material_eval_batch_args, direction_count);

/// The fields every batch argument struct shares.
struct CommonArgs {
    count: usize,
    closure: *const glint_closure,
    closures: *const *const glint_closure,
    active: *const u8,
    wo: [*const f32; 3],
}

macro_rules! batch_args {
    ($($t:ty),*) => {$(
        impl Sized32 for $t {
            fn struct_size(&self) -> u32 {
                self.struct_size
            }
        }
        impl $t {
            fn common(&self) -> CommonArgs {
                CommonArgs {
                    count: self.count,
                    closure: self.closure,
                    closures: self.closures,
                    active: self.active,
                    wo: [self.wo_x, self.wo_y, self.wo_z],
                }
            }
        }
    )*};
}
batch_args!(
    glint_eval_batch_args,
    glint_pdf_batch_args,
    glint_sample_batch_args,
    glint_albedo_batch_args
);

/// `count` elements at `p`, which must not be NULL. `what` is formatted only for the
/// error: a batch call allocates nothing but its staging, which may fail.
///
/// # Safety
/// `p` is NULL or valid for `count` reads.
#[inline]
unsafe fn input<'a, T>(p: *const T, count: usize, what: impl Display) -> Result<&'a [T], Error> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: non-NULL and valid for `count` elements per the contract.
    Ok(unsafe { std::slice::from_raw_parts(p, count) })
}

/// `count` writable elements at `p`, which must not be NULL (`what` as for [`input`]).
///
/// # Safety
/// `p` is NULL or valid for `count` writes and not aliased by another output.
#[inline]
unsafe fn output<'a, T>(p: *mut T, count: usize, what: impl Display) -> Result<&'a mut [T], Error> {
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: non-NULL, valid for `count` elements and unaliased per the contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, count) })
}

/// Like [`output`], but NULL means "not requested".
///
/// # Safety
/// As [`output`].
unsafe fn optional<'a, T>(p: *mut T, count: usize) -> Option<&'a mut [T]> {
    // SAFETY: forwarded contract.
    (!p.is_null()).then(|| unsafe { std::slice::from_raw_parts_mut(p, count) })
}

/// Per-lane closures from C handles.
#[derive(Clone, Copy)]
struct CClosures<'a>(&'a [*const glint_closure]);

impl<'a> batch::ClosureSource<'a> for CClosures<'a> {
    fn closure(&self, lane: usize) -> Result<&'a Closure, Error> {
        Ok(&self.handle(lane)?.closure)
    }
}

impl<'a> CClosures<'a> {
    fn handle(&self, lane: usize) -> Result<&'a glint_closure, Error> {
        // SAFETY: the caller passes NULL or closure handles (documented contract).
        unsafe { closure_handle(self.0[lane], "closures[lane]") }
    }
}

// SAFETY: the handles are only read, and finished closures are immutable; the API
// documents that closures may be shared by threads.
unsafe impl Sync for CClosures<'_> {}

/// Which closures the lanes use.
enum Lanes<'a> {
    One(&'a glint_closure),
    PerLane(CClosures<'a>),
}

impl Lanes<'_> {
    /// The kernels and threads of the runtime the closures were built with (for
    /// per-lane closures, the first active lane's with a valid handle: inactive lanes'
    /// handles are never read).
    fn exec(&self, active: Option<&[u8]>) -> Exec<'_> {
        let first = match self {
            Lanes::One(c) => Some(*c),
            Lanes::PerLane(c) => (0..c.0.len())
                .filter(|&lane| active.is_none_or(|a| a[lane] != 0))
                .find_map(|lane| c.handle(lane).ok()),
        };
        first
            .and_then(|c| c.runtime().ok())
            .map_or(Exec::scalar(), |rt| rt.runtime.exec())
    }
}

/// # Safety
/// Pointers as documented on the argument structs.
unsafe fn lanes<'a>(
    closure: *const glint_closure,
    closures: *const *const glint_closure,
    count: usize,
) -> Result<Lanes<'a>, Error> {
    if closures.is_null() {
        // SAFETY: per the contract.
        Ok(Lanes::One(unsafe {
            closure_handle(closure, "closure (and closures is NULL)")
        }?))
    } else {
        // SAFETY: per the contract.
        Ok(Lanes::PerLane(CClosures(unsafe {
            input(closures, count, "closures")
        }?)))
    }
}

/// # Safety
/// `x`, `y`, `z` are NULL or valid for `count` reads.
#[inline]
unsafe fn soa_in<'a>(
    x: *const f32,
    y: *const f32,
    z: *const f32,
    count: usize,
    what: &str,
) -> Result<Soa3<'a>, Error> {
    // SAFETY: per the contract.
    unsafe {
        Ok(Soa3 {
            x: input(x, count, format_args!("{what}_x"))?,
            y: input(y, count, format_args!("{what}_y"))?,
            z: input(z, count, format_args!("{what}_z"))?,
        })
    }
}

/// # Safety
/// `x`, `y`, `z` are NULL or valid for `count` writes and unaliased.
#[inline]
unsafe fn soa_out<'a>(
    x: *mut f32,
    y: *mut f32,
    z: *mut f32,
    count: usize,
    what: &str,
) -> Result<Soa3Mut<'a>, Error> {
    // SAFETY: per the contract.
    unsafe {
        Ok(Soa3Mut {
            x: output(x, count, format_args!("{what} (x/r)"))?,
            y: output(y, count, format_args!("{what} (y/g)"))?,
            z: output(z, count, format_args!("{what} (z/b)"))?,
        })
    }
}

/// The lanes' closures, active mask and `wo` of a batch call.
///
/// # Safety
/// Pointers as documented on the argument structs.
unsafe fn read_common<'a>(
    a: &CommonArgs,
) -> Result<(Lanes<'a>, Option<&'a [u8]>, Soa3<'a>), Error> {
    let n = a.count;
    batch::check_count(n)?;
    // SAFETY: per the contract, and `n` is small enough for a slice of any element.
    unsafe {
        let lanes = lanes(a.closure, a.closures, n)?;
        let active = (!a.active.is_null()).then(|| std::slice::from_raw_parts(a.active, n));
        let wo = soa_in(a.wo[0], a.wo[1], a.wo[2], n, "wo")?;
        Ok((lanes, active, wo))
    }
}

/// Run `f` with the batch input for whichever closure source the lanes use.
macro_rules! with_input {
    ($lanes:expr, $count:expr, $active:expr, $wo:expr, |$input:ident| $body:expr) => {
        match &$lanes {
            Lanes::One(c) => {
                let $input = BatchInput {
                    count: $count,
                    closures: &c.closure,
                    active: $active,
                    wo: $wo,
                };
                $body
            }
            Lanes::PerLane(c) => {
                let $input = BatchInput {
                    count: $count,
                    closures: *c,
                    active: $active,
                    wo: $wo,
                };
                $body
            }
        }
    };
}

/// `glint_eval` over SoA arrays. Every batch call runs on the kernel set (`isa=`) and
/// threads (`threads=`) of the runtime its closure was built with (with per-lane
/// closures, the first active lane's); lanes are grouped by closure shape (the same lobe
/// types, which may come from different runtimes), and results do not depend on the
/// thread count. Invalid lanes get zeroed outputs and the call returns the first one's
/// error (`lane i: ...`); the other lanes are computed. A `count` above
/// `GLINT_MAX_BATCH_COUNT` returns `GLINT_ERROR_OUT_OF_RANGE` before any array is read;
/// `GLINT_ERROR_OUT_OF_MEMORY` means staging buffers could not grow (then some blocks of
/// lanes may be left unwritten).
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on `glint_eval_batch_args`. No
/// output array of a batch call overlaps another of its arrays (a failing call zeroes
/// its outputs first; kernels store a lane after reading later lanes).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_eval_batch(args: *const glint_eval_batch_args) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { deref(args, "args") }?;
        check_size(a, "args")?;
        let n = a.count;
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (lanes, active, wo) = read_common(&a.common())?;
            let wi = soa_in(a.wi_x, a.wi_y, a.wi_z, n, "wi")?;
            let out = EvalOutput {
                value: soa_out(a.value_r, a.value_g, a.value_b, n, "value")?,
                pdf: output(a.pdf, n, "pdf")?,
                pdf_reverse: optional(a.pdf_reverse, n),
            };
            with_input!(lanes, n, active, wo, |input| batch::eval(
                &lanes.exec(active),
                &input,
                wi,
                out
            ))
        }
    })
}

/// `glint_pdf` over SoA arrays.
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on `glint_pdf_batch_args`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_pdf_batch(args: *const glint_pdf_batch_args) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { deref(args, "args") }?;
        check_size(a, "args")?;
        let n = a.count;
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (lanes, active, wo) = read_common(&a.common())?;
            let wi = soa_in(a.wi_x, a.wi_y, a.wi_z, n, "wi")?;
            let pdf = output(a.pdf, n, "pdf")?;
            with_input!(lanes, n, active, wo, |input| batch::pdf(
                &lanes.exec(active),
                &input,
                wi,
                pdf
            ))
        }
    })
}

/// `glint_sample` over SoA arrays.
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on `glint_sample_batch_args`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_sample_batch(args: *const glint_sample_batch_args) -> glint_status {
    guard(|| {
        // SAFETY: per the contract; the struct holds integers and raw pointers only.
        let a = &unsafe { args_versioned(args, SAMPLE_ARGS_V1_SIZE, "args") }?;
        let n = a.count;
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (lanes, active, wo) = read_common(&a.common())?;
            let u = SampleRandoms {
                u_lobe: input(a.u_lobe, n, "u_lobe")?,
                u0: input(a.u0, n, "u0")?,
                u1: input(a.u1, n, "u1")?,
            };
            let value = if a.value_r.is_null() && a.value_g.is_null() && a.value_b.is_null() {
                None
            } else {
                Some(soa_out(a.value_r, a.value_g, a.value_b, n, "value")?)
            };
            let out = SampleOutput {
                wi: soa_out(a.wi_x, a.wi_y, a.wi_z, n, "wi")?,
                pdf: output(a.pdf, n, "pdf")?,
                weight: soa_out(a.weight_r, a.weight_g, a.weight_b, n, "weight")?,
                value,
                flags: optional(a.flags, n),
                lobe: optional(a.lobe, n),
                component: optional(a.component, n),
                eta: optional(a.eta, n),
                roughness: optional(a.roughness, n),
            };
            with_input!(lanes, n, active, wo, |input| batch::sample(
                &lanes.exec(active),
                &input,
                u,
                out
            ))
        }
    })
}

/// Directional albedo (`glint_albedo`) over SoA arrays.
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on `glint_albedo_batch_args`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_albedo_batch(args: *const glint_albedo_batch_args) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { deref(args, "args") }?;
        check_size(a, "args")?;
        let n = a.count;
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (lanes, active, wo) = read_common(&a.common())?;
            let out = soa_out(a.albedo_r, a.albedo_g, a.albedo_b, n, "albedo")?;
            with_input!(lanes, n, active, wo, |input| batch::albedo(
                &lanes.exec(active),
                &input,
                out
            ))
        }
    })
}

/// Per-lane values of one parameter of a material batch: parameter `param` (its index
/// in the material type's schema) of type `param_type` (`GLINT_PARAM_*`), read from
/// `value[0]` (FLOAT, ENUM) or `value[0..3]` (RGB: r, g, b), `count` floats each.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_override_lanes {
    pub param: u32,
    pub param_type: u32,
    pub value: [*const f32; 3],
}

/// The lanes of a material batch: one compiled material, and per lane a shading
/// context (`wo` and the shading frame) and the textured parameters.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_material_lanes {
    pub material: *const glint_material,
    pub count: usize,
    /// Optional: `count` bytes, 0 = skip the lane.
    pub active: *const u8,
    pub wo_x: *const f32,
    pub wo_y: *const f32,
    pub wo_z: *const f32,
    pub normal_x: *const f32,
    pub normal_y: *const f32,
    pub normal_z: *const f32,
    /// Optional (all three NULL): tangents chosen automatically, as a zero tangent is.
    pub tangent_x: *const f32,
    pub tangent_y: *const f32,
    pub tangent_z: *const f32,
    /// `override_count` entries (at most 64), or NULL with `override_count == 0`.
    pub overrides: *const glint_override_lanes,
    pub override_count: usize,
}

/// Arguments of `glint_material_eval_batch`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_material_eval_batch_args {
    /// Set by the caller to `sizeof(glint_material_eval_batch_args)`.
    pub struct_size: u32,
    pub lanes: glint_material_lanes,
    pub wi_x: *const f32,
    pub wi_y: *const f32,
    pub wi_z: *const f32,
    pub value_r: *mut f32,
    pub value_g: *mut f32,
    pub value_b: *mut f32,
    pub pdf: *mut f32,
    /// Optional.
    pub pdf_reverse: *mut f32,
    /// Directions per lane, each lane expanded once for all of them (a scanline
    /// host's lights); 0 is taken as 1. `wi_*`, `value_*`, `pdf` and `pdf_reverse`
    /// hold `direction_count` blocks of `lanes.count` values: direction `d` of lane
    /// `j` at `d * count + j`. Appended: a caller built against a header without it
    /// passes its smaller `struct_size` and gets one direction.
    pub direction_count: usize,
    /// Optional (all three or none): each lane's directional albedo at `wo`, as
    /// `glint_material_albedo_batch` gives it, from the same expansion (a scanline
    /// host's ambient term). Appended with `direction_count`.
    pub albedo_r: *mut f32,
    pub albedo_g: *mut f32,
    pub albedo_b: *mut f32,
}

/// Arguments of `glint_material_pdf_batch`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_material_pdf_batch_args {
    /// Set by the caller to `sizeof(glint_material_pdf_batch_args)`.
    pub struct_size: u32,
    pub lanes: glint_material_lanes,
    pub wi_x: *const f32,
    pub wi_y: *const f32,
    pub wi_z: *const f32,
    pub pdf: *mut f32,
}

/// Arguments of `glint_material_sample_batch` (outputs as `glint_sample_batch_args`;
/// `lobe` receives the material's slot, see `glint_material_info.lobe_count`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_material_sample_batch_args {
    /// Set by the caller to `sizeof(glint_material_sample_batch_args)`.
    pub struct_size: u32,
    pub lanes: glint_material_lanes,
    pub u_lobe: *const f32,
    pub u0: *const f32,
    pub u1: *const f32,
    pub wi_x: *mut f32,
    pub wi_y: *mut f32,
    pub wi_z: *mut f32,
    pub pdf: *mut f32,
    pub weight_r: *mut f32,
    pub weight_g: *mut f32,
    pub weight_b: *mut f32,
    /// Optional outputs (NULL = not written).
    pub value_r: *mut f32,
    pub value_g: *mut f32,
    pub value_b: *mut f32,
    pub flags: *mut u32,
    pub lobe: *mut u32,
    pub eta: *mut f32,
    pub roughness: *mut f32,
    /// Optional: the component (sub-lobe) of each sample, 0 for failed lanes
    /// (`glint_sample_result.component`). Appended: a caller built against a header
    /// without it passes its smaller `struct_size`, and nothing is written here.
    pub component: *mut u32,
}

/// Arguments of `glint_material_albedo_batch`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct glint_material_albedo_batch_args {
    /// Set by the caller to `sizeof(glint_material_albedo_batch_args)`.
    pub struct_size: u32,
    pub lanes: glint_material_lanes,
    pub albedo_r: *mut f32,
    pub albedo_g: *mut f32,
    pub albedo_b: *mut f32,
}

macro_rules! sized {
    ($($t:ty),*) => {$(
        impl Sized32 for $t {
            fn struct_size(&self) -> u32 {
                self.struct_size
            }
        }
    )*};
}
sized!(
    glint_material_eval_batch_args,
    glint_material_pdf_batch_args,
    glint_material_albedo_batch_args
);

/// The checked lanes of a material batch, with its runtime's kernels and threads.
///
/// # Safety
/// Pointers as documented on `glint_material_lanes`.
unsafe fn material_lanes<'a>(
    l: &glint_material_lanes,
    overrides: &'a mut Vec<batch::material::OverrideLanes<'a>>,
) -> Result<(batch::material::MaterialInput<'a>, Exec<'a>), Error> {
    let n = l.count;
    batch::check_count(n)?;
    // SAFETY: per the contract; `n` is small enough for a slice of any element.
    unsafe {
        let (material, runtime) = super::material::material_ref(l.material)?;
        let active = (!l.active.is_null()).then(|| std::slice::from_raw_parts(l.active, n));
        let wo = soa_in(l.wo_x, l.wo_y, l.wo_z, n, "wo")?;
        let normal = soa_in(l.normal_x, l.normal_y, l.normal_z, n, "normal")?;
        let tangent = if l.tangent_x.is_null() && l.tangent_y.is_null() && l.tangent_z.is_null() {
            None
        } else {
            Some(soa_in(l.tangent_x, l.tangent_y, l.tangent_z, n, "tangent")?)
        };
        let given = super::material::overrides_in(l.overrides, l.override_count)?;
        for (i, o) in given.iter().enumerate() {
            let kind = super::material::param_kind(o.param_type, i)?;
            // The schema first: a wrong index or type names itself, not its arrays.
            material.override_spec(i, o.param, kind)?;
            let mut value: [&[f32]; 3] = [&[]; 3];
            for (c, v) in value.iter_mut().enumerate().take(kind.size()) {
                *v = input(o.value[c], n, format_args!("overrides[{i}].value[{c}]"))?;
            }
            overrides.push(batch::material::OverrideLanes {
                param: o.param,
                kind,
                value,
            });
        }
        let exec = runtime.live()?.runtime.exec();
        Ok((
            batch::material::MaterialInput {
                count: n,
                material,
                active,
                wo,
                normal,
                tangent,
                overrides,
            },
            exec,
        ))
    }
}

/// `glint_eval` of the closure `glint_material_closure` would build for each lane,
/// over SoA arrays, without building closures: the material expands per lane, each
/// slot's lobe runs its SIMD kernels over the lanes, pruning and lobe selection as in
/// the closure. Errors as `glint_eval_batch` (invalid lanes, including overrides out of
/// their range, are zeroed and the first is reported as `lane i: ...`).
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on the argument structs.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_eval_batch(
    args: *const glint_material_eval_batch_args,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract; the struct holds integers and raw pointers only.
        let a = &unsafe { args_versioned(args, MATERIAL_EVAL_ARGS_V1_SIZE, "args") }?;
        let n = a.lanes.count;
        let mut overrides = Vec::new();
        // SAFETY: the struct's pointers are valid for `count` elements (`direction_count`
        // blocks of them for the directions' rows) per the contract.
        unsafe {
            let (input, exec) = material_lanes(&a.lanes, &mut overrides)?;
            let directions = a.direction_count.max(1);
            let rows = batch::material::direction_rows(directions, n)?;
            let wi = soa_in(a.wi_x, a.wi_y, a.wi_z, rows, "wi")?;
            let out = EvalOutput {
                value: soa_out(a.value_r, a.value_g, a.value_b, rows, "value")?,
                pdf: output(a.pdf, rows, "pdf")?,
                pdf_reverse: optional(a.pdf_reverse, rows),
            };
            let albedo = [a.albedo_r, a.albedo_g, a.albedo_b]
                .iter()
                .any(|p| !p.is_null());
            let albedo = match albedo {
                true => Some(soa_out(a.albedo_r, a.albedo_g, a.albedo_b, n, "albedo")?),
                false => None,
            };
            batch::material::eval_directions(&exec, &input, wi, directions, out, albedo)
        }
    })
}

/// `glint_pdf` of each lane's material closure over SoA arrays (see
/// `glint_material_eval_batch`).
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on the argument structs.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_pdf_batch(
    args: *const glint_material_pdf_batch_args,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { deref(args, "args") }?;
        check_size(a, "args")?;
        let n = a.lanes.count;
        let mut overrides = Vec::new();
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (input, exec) = material_lanes(&a.lanes, &mut overrides)?;
            let wi = soa_in(a.wi_x, a.wi_y, a.wi_z, n, "wi")?;
            let pdf = output(a.pdf, n, "pdf")?;
            batch::material::pdf(&exec, &input, wi, pdf)
        }
    })
}

/// `glint_sample` of each lane's material closure over SoA arrays (see
/// `glint_material_eval_batch`); `lobe` receives the sampled slot.
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on the argument structs.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_sample_batch(
    args: *const glint_material_sample_batch_args,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract; the struct holds integers and raw pointers only.
        let a = &unsafe { args_versioned(args, MATERIAL_SAMPLE_ARGS_V1_SIZE, "args") }?;
        let n = a.lanes.count;
        let mut overrides = Vec::new();
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (input, exec) = material_lanes(&a.lanes, &mut overrides)?;
            let u = SampleRandoms {
                u_lobe: self::input(a.u_lobe, n, "u_lobe")?,
                u0: self::input(a.u0, n, "u0")?,
                u1: self::input(a.u1, n, "u1")?,
            };
            let value = if a.value_r.is_null() && a.value_g.is_null() && a.value_b.is_null() {
                None
            } else {
                Some(soa_out(a.value_r, a.value_g, a.value_b, n, "value")?)
            };
            let out = SampleOutput {
                wi: soa_out(a.wi_x, a.wi_y, a.wi_z, n, "wi")?,
                pdf: output(a.pdf, n, "pdf")?,
                weight: soa_out(a.weight_r, a.weight_g, a.weight_b, n, "weight")?,
                value,
                flags: optional(a.flags, n),
                lobe: optional(a.lobe, n),
                component: optional(a.component, n),
                eta: optional(a.eta, n),
                roughness: optional(a.roughness, n),
            };
            batch::material::sample(&exec, &input, u, out)
        }
    })
}

/// Directional albedo of each lane's material closure over SoA arrays (see
/// `glint_material_eval_batch`): for lobe selection and a scanline host's ambient term.
///
/// # Safety
/// `args` is NULL or valid; its pointers as documented on the argument structs.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_material_albedo_batch(
    args: *const glint_material_albedo_batch_args,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { deref(args, "args") }?;
        check_size(a, "args")?;
        let n = a.lanes.count;
        let mut overrides = Vec::new();
        // SAFETY: the struct's pointers are valid for `count` elements per the contract.
        unsafe {
            let (input, exec) = material_lanes(&a.lanes, &mut overrides)?;
            let out = soa_out(a.albedo_r, a.albedo_g, a.albedo_b, n, "albedo")?;
            batch::material::albedo(&exec, &input, out)
        }
    })
}
