//! Arenas, closure building, and eval / sample / pdf / albedo on a closure or one lobe.

use super::*;
use crate::closure::{Arena, Closure, EvalResult, Recycle, SampleResult};
use crate::json;
use crate::lobes::Transport;
use crate::math::{Frame, Vec3};

/// An arena of closures owned by the caller; one thread at a time. A small shell
/// (see `handle`) around its slots.
#[repr(C)]
pub struct glint_arena {
    tag: Tag,
    /// Bumped by every reset; closure handles carry the one they were built in.
    generation: u16,
    arena: Arena<glint_closure>,
}
const _: () = assert!(std::mem::offset_of!(glint_arena, tag) == 0);

/// A closure: built inside an arena, immutable and thread-safe once finished.
#[repr(C)]
pub struct glint_closure {
    /// `closure_tag(generation)` while live, then poisoned by reset or destroy.
    tag: Tag,
    /// Beside the tag: every call reads both.
    runtime: *const glint_runtime,
    pub(crate) closure: Closure,
}
const _: () = assert!(std::mem::offset_of!(glint_closure, tag) == 0);

impl glint_closure {
    /// The runtime the closure was built with, if it was not destroyed; a separate
    /// object, so its borrow does not hold the closure.
    #[inline(always)]
    pub(crate) fn runtime<'r>(&self) -> Result<&'r LiveRuntime, Error> {
        // SAFETY: the runtime was live when the closure was built, and a destroyed
        // runtime's shell stays readable while quarantined (`glint_runtime_destroy`).
        unsafe { &*self.runtime }.live().map_err(of_the_closure)
    }
}

#[cold]
fn of_the_closure(e: Error) -> Error {
    invalid(format!("the closure's {}", e.message))
}

/// The closure a handle names, checked: its slot's tag matches the handle's
/// generation and its runtime is live.
///
/// # Safety
/// `p` is NULL or a handle from a closure constructor (see `glint_arena_destroy`).
#[inline(always)]
pub(crate) unsafe fn closure_handle<'a>(
    p: *const glint_closure,
    what: &str,
) -> Result<&'a glint_closure, Error> {
    let (slot, generation) = decode(p);
    // SAFETY: forwarded contract; reset slots stay allocated, destroyed ones readable
    // while quarantined.
    let c = unsafe { deref(slot, what) }?;
    check_closure_tag(&c.tag, generation, what)?;
    c.runtime()?;
    Ok(c)
}

/// As [`closure_handle`], for building.
///
/// # Safety
/// As [`closure_handle`], and no other thread uses the closure.
unsafe fn closure_handle_mut<'a>(p: *mut glint_closure) -> Result<&'a mut glint_closure, Error> {
    // SAFETY: forwarded contract.
    unsafe { closure_handle(p, "closure") }?;
    // SAFETY: checked above; the caller guarantees exclusive use.
    Ok(unsafe { &mut *decode(p).0.cast_mut() })
}

/// A live arena.
///
/// # Safety
/// `p` is NULL or a handle from `glint_arena_create` (see `glint_arena_destroy`).
unsafe fn arena_mut<'a>(p: *mut glint_arena) -> Result<&'a mut glint_arena, Error> {
    // SAFETY: forwarded contract; destroyed shells stay readable while quarantined.
    let a = unsafe { deref_mut(shell_mut(p), "arena") }?;
    check_tag(&a.tag, ARENA_LIVE, ARENA_DEAD, "arena")?;
    Ok(a)
}

impl Recycle for glint_closure {
    fn recycle(&mut self) {
        self.closure.recycle();
    }

    fn free_storage(&mut self) {
        self.closure.free_storage();
    }
}

impl glint_arena {
    /// Poison the tag of every closure in the arena.
    fn poison(&mut self, poison: u64) {
        for slot in self.arena.iter() {
            slot.tag.set(poison);
        }
    }
}

/// A shading frame: unit normal and an optional tangent (all zeros: chosen
/// automatically). Neither needs to be normalized; the tangent is made orthogonal.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct glint_frame {
    pub normal: glint_vec3,
    pub tangent: glint_vec3,
}

/// Result of an eval.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct glint_eval_result {
    /// Set by the caller to `sizeof(glint_eval_result)`.
    pub struct_size: u32,
    /// `f(wo, wi) |cos theta_i|`, linear RGB.
    pub value: [f32; 3],
    /// Solid-angle density of sampling `wi` from `wo`.
    pub pdf: f32,
    /// Density of sampling `wo` from `wi`.
    pub pdf_reverse: f32,
}

impl Sized32 for glint_eval_result {
    fn struct_size(&self) -> u32 {
        self.struct_size
    }
}

impl Output for glint_eval_result {
    fn failed(struct_size: u32) -> Self {
        glint_eval_result {
            struct_size,
            ..Default::default()
        }
    }
}

/// Result of a sample. For SPECULAR samples, `value` is the reflected or
/// transmitted fraction and `pdf` the discrete probability of the event.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct glint_sample_result {
    /// Set by the caller to `sizeof(glint_sample_result)`.
    pub struct_size: u32,
    /// Sampled direction, unit, world space, pointing away from the surface.
    pub wi: glint_vec3,
    pub value: [f32; 3],
    pub pdf: f32,
    /// `value / pdf`.
    pub weight: [f32; 3],
    /// `GLINT_FLAG_REFLECTION` or `_TRANSMISSION`, with `_DIFFUSE`, `_GLOSSY` or `_SPECULAR`.
    pub flags: u32,
    /// Index of the lobe that was sampled.
    pub lobe: u32,
    /// Relative IOR crossed (transmission), else 1.
    pub eta: f32,
    /// Roughness of the sampled lobe in [0, 1] (0 for specular).
    pub roughness: f32,
    /// The component (sub-lobe) of the sampled lobe: a `dielectric`'s reflection 0,
    /// transmission 1; 0 for lobes of one component. Appended: a caller built against
    /// a header without it passes its smaller `struct_size` and gets the fields it has.
    pub component: u32,
}

/// `sizeof(glint_sample_result)` before `component` was appended: the oldest size
/// the sample calls accept.
const SAMPLE_RESULT_V1_SIZE: usize = std::mem::offset_of!(glint_sample_result, component);

impl Sized32 for glint_sample_result {
    fn struct_size(&self) -> u32 {
        self.struct_size
    }
}

impl Output for glint_sample_result {
    /// Zeroed, with the neutral `eta` = 1.
    fn failed(struct_size: u32) -> Self {
        glint_sample_result {
            struct_size,
            eta: 1.0,
            ..Default::default()
        }
    }
}

pub(crate) fn vec3_in(v: glint_vec3, what: &str) -> Result<Vec3<f32>, Error> {
    Vec3::try_unit(v.x, v.y, v.z, what)
}

fn vec3_out(v: Vec3<f32>) -> glint_vec3 {
    glint_vec3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// # Safety
/// As [`closure_handle`].
#[inline(always)]
unsafe fn closure_ref<'a>(p: *const glint_closure) -> Result<&'a Closure, Error> {
    // SAFETY: forwarded contract.
    Ok(&unsafe { closure_handle(p, "closure") }?.closure)
}

/// Create an arena with room for `capacity` closures.
///
/// # Safety
/// `out` is NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_arena_create(
    capacity: usize,
    out: *mut *mut glint_arena,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", std::ptr::null_mut()) }?;
        let arena = Arena::new(capacity)?;
        *out = Box::into_raw(Box::new(glint_arena {
            tag: Tag::new(ARENA_LIVE),
            generation: 0,
            arena,
        }));
        Ok(())
    })
}

/// Free every closure of the arena at once. Their handles become invalid, and any
/// call with one returns `GLINT_ERROR_INVALID_HANDLE`, also after a new closure
/// reuses the slot (each handle carries the arena's reset count modulo 65536, so
/// only a handle from exactly a multiple of 65536 resets ago goes undetected).
///
/// # Safety
/// `arena` is NULL or a handle from `glint_arena_create` (see `glint_arena_destroy`).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_arena_reset(arena: *mut glint_arena) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { arena_mut(arena) }?;
        a.poison(CLOSURE_RESET);
        a.arena.reset();
        a.generation = a.generation.wrapping_add(1);
        Ok(())
    })
}

/// Destroy an arena and its closures (NULL is ignored). Afterwards a call with the
/// arena or one of its closures returns `GLINT_ERROR_INVALID_HANDLE`, and destroying
/// it again is ignored and leaves that message for `glint_last_error`. This holds
/// while the arena is quarantined: its shell until `GLINT_QUARANTINE_SHELLS` (1024) more
/// runtimes and arenas were destroyed (destroying materials does not count), its
/// closure slots while its shell is and the most recently destroyed arenas' slots
/// total at most `GLINT_QUARANTINE_BYTES` (16 MiB; an arena larger than that frees
/// them at once). Beyond that, for pointers never returned by this library and for
/// calls that race with the destroy, the behaviour is undefined.
///
/// # Safety
/// `arena` is NULL or a handle from `glint_arena_create`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_arena_destroy(arena: *mut glint_arena) {
    guard(|| {
        let arena = shell_mut(arena);
        if arena.is_null() {
            return Ok(());
        }
        // SAFETY: a handle from glint_arena_create, live or quarantined.
        let a = unsafe { &mut *arena };
        poison(&a.tag, ARENA_LIVE, ARENA_DEAD, "arena")?;
        a.poison(CLOSURE_DEAD);
        // The slots' headers (their tags) stay readable while quarantined; the lobes
        // and blocks they held are freed now.
        a.arena.free_storage();
        let mut bytes = a.arena.capacity() * std::mem::size_of::<glint_closure>();
        if bytes > GLINT_QUARANTINE_BYTES {
            a.arena.release();
            bytes = 0;
        }
        // SAFETY: created by Box::into_raw in glint_arena_create; the tag is now dead,
        // so no later call takes ownership again.
        quarantine(unsafe { Box::from_raw(arena) }, bytes);
        Ok(())
    });
}

/// Destroyed arenas wait with destroyed runtimes; their slots leave first when the
/// slots of destroyed arenas exceed `GLINT_QUARANTINE_BYTES`.
impl Quarantined for glint_arena {
    fn release_slots(&mut self) {
        self.arena.release();
    }
}

fn transport(flags: u32) -> Result<Transport, Error> {
    match flags {
        0 => Ok(Transport::Radiance),
        GLINT_CLOSURE_IMPORTANCE => Ok(Transport::Importance),
        _ => Err(Error::new(
            Status::InvalidArgument,
            format!("closure flags {flags:#x}: valid flags are 0 and GLINT_CLOSURE_IMPORTANCE"),
        )),
    }
}

/// The checked arguments both closure constructors share: the output handle (set to
/// NULL until a closure is placed), the runtime, the arena and the optional `wo`.
///
/// # Safety
/// Each pointer is NULL or valid as documented on the constructors.
unsafe fn constructor_args<'a>(
    runtime: *const glint_runtime,
    arena: *mut glint_arena,
    wo: *const glint_vec3,
    out: *mut *mut glint_closure,
) -> Result<ConstructorArgs<'a>, Error> {
    // SAFETY: per the contract.
    let out = unsafe { out_value(out, "out", std::ptr::null_mut()) }?;
    // SAFETY: per the contract.
    let runtime = unsafe { deref(shell(runtime), "runtime") }?;
    runtime.live()?;
    // SAFETY: per the contract.
    let arena = unsafe { arena_mut(arena) }?;
    // SAFETY: per the contract.
    let wo = unsafe { wo.as_ref() }
        .map(|w| vec3_in(*w, "wo"))
        .transpose()?;
    Ok(ConstructorArgs {
        runtime,
        arena,
        wo,
        out,
    })
}

struct ConstructorArgs<'a> {
    runtime: &'a glint_runtime,
    arena: &'a mut glint_arena,
    wo: Option<Vec3<f32>>,
    out: &'a mut *mut glint_closure,
}

/// Store a closure in the arena and hand out its handle.
fn place(
    runtime: &glint_runtime,
    arena: &mut glint_arena,
    closure: Closure,
    out: &mut *mut glint_closure,
) -> Result<(), Error> {
    let generation = arena.generation;
    let slot = arena.arena.alloc(glint_closure {
        tag: Tag::new(closure_tag(generation)),
        closure,
        runtime,
    })?;
    *out = encode(slot, generation)?;
    Ok(())
}

/// Begin an empty closure in the arena's next slot, reusing the storage a closure
/// left there, and hand out its handle.
fn place_empty(
    runtime: &glint_runtime,
    arena: &mut glint_arena,
    wo: Option<Vec3<f32>>,
    mode: Transport,
    out: &mut *mut glint_closure,
) -> Result<(), Error> {
    let generation = arena.generation;
    let slot = arena.arena.alloc_with(
        || glint_closure {
            tag: Tag::new(closure_tag(generation)),
            closure: Closure::new(wo, mode),
            runtime,
        },
        |slot| {
            slot.tag.set(closure_tag(generation));
            slot.closure.restart(wo, mode);
            slot.runtime = runtime;
        },
    )?;
    *out = encode(slot, generation)?;
    Ok(())
}

/// Build a closure in the arena's next slot with `build` (which restarts it),
/// reusing the storage a closure left there, and hand out its handle.
///
/// # Safety
/// `arena` is NULL or a handle from `glint_arena_create`, not used by another thread.
pub(crate) unsafe fn place_built(
    runtime: &glint_runtime,
    arena: *mut glint_arena,
    out: &mut *mut glint_closure,
    build: impl FnOnce(&mut Closure) -> Result<(), Error>,
) -> Result<(), Error> {
    // SAFETY: per the contract.
    let arena = unsafe { arena_mut(arena) }?;
    let generation = arena.generation;
    let slot = arena.arena.alloc_with(
        || glint_closure {
            tag: Tag::new(closure_tag(generation)),
            closure: Closure::new(None, Transport::Radiance),
            runtime,
        },
        |slot| {
            slot.tag.set(closure_tag(generation));
            slot.runtime = runtime;
        },
    )?;
    build(&mut slot.closure)?;
    *out = encode(slot, generation)?;
    Ok(())
}

/// Begin a closure in `arena`. `wo` (world space, toward the viewer) may be NULL; when
/// given, it fixes view-dependent lobe weights and lobe selection. `flags` is 0 or
/// `GLINT_CLOSURE_IMPORTANCE`. Add lobes, then call `glint_closure_finish`.
///
/// # Safety
/// Handles are NULL or live; `wo` NULL or readable; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_closure_begin(
    runtime: *const glint_runtime,
    arena: *mut glint_arena,
    wo: *const glint_vec3,
    flags: u32,
    out: *mut *mut glint_closure,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { constructor_args(runtime, arena, wo, out) }?;
        place_empty(a.runtime, a.arena, a.wo, transport(flags)?, a.out)
    })
}

/// Add a lobe of type `type_id` with RGB `weight` (>= 0) in `frame`. `params` holds
/// the lobe type's whole parameter block (`param_count == param_block_size`; see
/// `glint_lobe_param_info`), or is NULL with `param_count == 0` for the defaults.
/// `out_index` (may be NULL) receives the lobe's index in the closure. A closure's
/// storage grows with its lobes (its arena slot keeps it across resets); memory short
/// for it is `GLINT_ERROR_OUT_OF_MEMORY`, the closure unchanged and still open.
///
/// # Safety
/// `closure` is NULL or live and not finished elsewhere; `weight` NULL or 3 floats;
/// `frame` NULL or readable; `params` NULL or `param_count` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_closure_add_lobe(
    closure: *mut glint_closure,
    type_id: u32,
    weight: *const f32,
    frame: *const glint_frame,
    params: *const f32,
    param_count: usize,
    out_index: *mut u32,
) -> glint_status {
    guard(|| {
        // SAFETY: NULL or writable per the contract.
        let out_index = unsafe { out_index.as_mut() }.map(|i| {
            *i = 0;
            i
        });
        // SAFETY: per the contract.
        let c = unsafe { closure_handle_mut(closure) }?;
        if weight.is_null() {
            return Err(null("weight"));
        }
        // SAFETY: non-NULL and 3 floats per the contract.
        let weight = unsafe { std::ptr::read(weight as *const [f32; 3]) };
        // SAFETY: per the contract.
        let frame = unsafe { deref(frame, "frame") }?;
        let n = vec3_in(frame.normal, "frame.normal")?;
        let t = frame.tangent;
        let tangent = if t.x == 0.0 && t.y == 0.0 && t.z == 0.0 {
            None
        } else {
            Some(vec3_in(t, "frame.tangent")?)
        };
        // SAFETY: per the contract.
        let params = unsafe { param_block(params, param_count, GLINT_MAX_PARAM_VALUES as usize) }?;
        let registry = &c.runtime()?.runtime.registry;
        let index =
            c.closure
                .add_lobe(registry, type_id, weight, Frame::new(n, tangent), params)?;
        if let Some(i) = out_index {
            *i = index as u32;
        }
        Ok(())
    })
}

/// Finish a closure: fixes lobe selection; afterwards it is immutable and may be
/// evaluated from any thread.
///
/// # Safety
/// `closure` is NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_closure_finish(closure: *mut glint_closure) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        unsafe { closure_handle_mut(closure) }?.closure.finish()
    })
}

/// Build and finish a whole closure from the JSON description `json_text` (see the README).
///
/// # Safety
/// Handles are NULL or live; `json_text` NULL or NUL-terminated; `wo` NULL or readable;
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_closure_from_json(
    runtime: *const glint_runtime,
    arena: *mut glint_arena,
    json_text: *const c_char,
    wo: *const glint_vec3,
    out: *mut *mut glint_closure,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let a = unsafe { constructor_args(runtime, arena, wo, out) }?;
        // SAFETY: per the contract.
        let text = unsafe { c_str(json_text, "json_text") }?;
        let closure = {
            let runtime = &a.runtime.live()?.runtime;
            json::closure_from_json(&runtime.registry, text, a.wo, runtime.settings.prune)?
        };
        place(a.runtime, a.arena, closure, a.out)
    })
}

/// Number of lobes in a closure.
///
/// # Safety
/// `closure` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_closure_lobe_count(
    closure: *const glint_closure,
    out: *mut u32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0) }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        *out = c.lobes().len() as u32;
        Ok(())
    })
}

/// The type id and selection probability of lobe `index`.
///
/// # Safety
/// `closure` NULL or live; `type_id` and `probability` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_closure_lobe(
    closure: *const glint_closure,
    index: u32,
    type_id: *mut u32,
    probability: *mut f32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract (both are reset before either is reported NULL).
        let (type_id, probability) = unsafe {
            (
                out_value(type_id, "type_id", 0),
                out_value(probability, "probability", 0.0),
            )
        };
        let (type_id, probability) = (type_id?, probability?);
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        c.check_finished().map_err(|_| {
            Error::new(
                Status::InvalidState,
                "the closure is not finished: selection probabilities exist after glint_closure_finish",
            )
        })?;
        let l = c.lobes().get(index as usize).ok_or_else(|| {
            Error::new(
                Status::OutOfRange,
                format!(
                    "lobe index {index} is out of range: the closure has {} lobes",
                    c.lobes().len()
                ),
            )
        })?;
        *type_id = l.type_id;
        *probability = l.probability;
        Ok(())
    })
}

fn write_eval(out: &mut glint_eval_result, r: EvalResult) {
    *out = glint_eval_result {
        struct_size: out.struct_size,
        value: r.value.to_array(),
        pdf: r.pdf,
        pdf_reverse: r.pdf_reverse,
    };
}

fn write_sample(out: VersionedOut<glint_sample_result>, s: SampleResult) {
    out.write(glint_sample_result {
        struct_size: out.struct_size,
        wi: vec3_out(s.wi),
        value: s.value.to_array(),
        pdf: s.pdf,
        weight: s.weight.to_array(),
        flags: s.flags,
        lobe: s.lobe,
        eta: s.eta,
        roughness: s.roughness,
        component: s.component,
    });
}

/// The 3 floats at `out`, zeroed (the failure state) before the call does anything else.
///
/// # Safety
/// `out` is NULL or 3 writable floats.
unsafe fn out_rgb<'a>(out: *mut f32) -> Result<&'a mut [f32; 3], Error> {
    // SAFETY: forwarded contract.
    unsafe { out_value(out.cast::<[f32; 3]>(), "out", [0.0; 3]) }
}

/// The closure at `(wo, wi)`: `sum_k weight_k f_k |cos theta_i|`, the mixture pdf
/// and the reverse pdf (for bidirectional hosts; it evaluates every lobe twice, so
/// unidirectional hosts call `glint_eval_forward`). Directions are world space and
/// need not be normalized.
///
/// # Safety
/// `closure` NULL or live; `out` NULL or writable with `struct_size` set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_eval(
    closure: *const glint_closure,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut glint_eval_result,
) -> glint_status {
    // SAFETY: per the contract.
    unsafe { eval_call(closure, wo, wi, out, true) }
}

/// `glint_eval` without the reverse pdf: value and pdf only, each lobe evaluated
/// once; `out->pdf_reverse` is set to 0.
///
/// # Safety
/// As `glint_eval`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_eval_forward(
    closure: *const glint_closure,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut glint_eval_result,
) -> glint_status {
    // SAFETY: per the contract.
    unsafe { eval_call(closure, wo, wi, out, false) }
}

/// `Closure::eval_lobe` or `Closure::eval_lobe_forward`.
type LobeEval = fn(&Closure, usize, Vec3<f32>, Vec3<f32>) -> Result<EvalResult, Error>;

/// The body of `glint_eval` and `glint_eval_forward` (`reverse` false).
///
/// # Safety
/// As `glint_eval`.
unsafe fn eval_call(
    closure: *const glint_closure,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut glint_eval_result,
    reverse: bool,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_struct(out, "result") }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        let (wo, wi) = (vec3_in(wo, "wo")?, vec3_in(wi, "wi")?);
        write_eval(out, c.eval_with(wo, wi, reverse)?);
        Ok(())
    })
}

/// Sample the closure: `u_lobe` picks a lobe, `u0`, `u1` a direction (all in [0, 1)).
/// Returns `GLINT_NO_SAMPLE` when nothing can be scattered; on any failure the result
/// is zeroed (`eta` = 1).
///
/// # Safety
/// `closure` NULL or live; `out` NULL or writable with `struct_size` set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_sample(
    closure: *const glint_closure,
    wo: glint_vec3,
    u_lobe: f32,
    u0: f32,
    u1: f32,
    out: *mut glint_sample_result,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_versioned(out, SAMPLE_RESULT_V1_SIZE, "result") }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        write_sample(out, c.sample(vec3_in(wo, "wo")?, [u_lobe, u0, u1])?);
        Ok(())
    })
}

/// The mixture pdf of sampling `wi` from `wo`.
///
/// # Safety
/// `closure` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_pdf(
    closure: *const glint_closure,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut f32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0.0) }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        let pdf = c.pdf(vec3_in(wo, "wo")?, vec3_in(wi, "wi")?)?;
        *out = pdf;
        Ok(())
    })
}

/// Directional albedo `R(wo)` of the closure (RGB, written to `out[0..3]`).
///
/// # Safety
/// `closure` NULL or live; `out` NULL or 3 writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_albedo(
    closure: *const glint_closure,
    wo: glint_vec3,
    out: *mut f32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_rgb(out) }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        *out = c.albedo(vec3_in(wo, "wo")?)?.to_array();
        Ok(())
    })
}

/// Lobe `lobe` alone: `weight f |cos theta_i|` and that lobe's own pdfs.
///
/// # Safety
/// As `glint_eval`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_eval_lobe(
    closure: *const glint_closure,
    lobe: u32,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut glint_eval_result,
) -> glint_status {
    // SAFETY: per the contract.
    unsafe { eval_lobe_call(closure, lobe, wo, wi, out, Closure::eval_lobe) }
}

/// `glint_eval_lobe` without the reverse pdf (`out->pdf_reverse` is set to 0).
///
/// # Safety
/// As `glint_eval`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_eval_lobe_forward(
    closure: *const glint_closure,
    lobe: u32,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut glint_eval_result,
) -> glint_status {
    // SAFETY: per the contract.
    unsafe { eval_lobe_call(closure, lobe, wo, wi, out, Closure::eval_lobe_forward) }
}

/// The body of `glint_eval_lobe` and `glint_eval_lobe_forward`.
///
/// # Safety
/// As `glint_eval`.
unsafe fn eval_lobe_call(
    closure: *const glint_closure,
    lobe: u32,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut glint_eval_result,
    eval: LobeEval,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_struct(out, "result") }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        let (wo, wi) = (vec3_in(wo, "wo")?, vec3_in(wi, "wi")?);
        write_eval(out, eval(c, lobe as usize, wo, wi)?);
        Ok(())
    })
}

/// Sample lobe `lobe` alone (`u_c` chooses among its discrete events, e.g. reflect or
/// refract); value and pdf are that lobe's own.
///
/// # Safety
/// As `glint_sample`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_sample_lobe(
    closure: *const glint_closure,
    lobe: u32,
    wo: glint_vec3,
    u_c: f32,
    u0: f32,
    u1: f32,
    out: *mut glint_sample_result,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_versioned(out, SAMPLE_RESULT_V1_SIZE, "result") }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        write_sample(
            out,
            c.sample_lobe(lobe as usize, vec3_in(wo, "wo")?, [u_c, u0, u1])?,
        );
        Ok(())
    })
}

/// The pdf of lobe `lobe` alone.
///
/// # Safety
/// As `glint_pdf`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_pdf_lobe(
    closure: *const glint_closure,
    lobe: u32,
    wo: glint_vec3,
    wi: glint_vec3,
    out: *mut f32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_value(out, "out", 0.0) }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        let pdf = c.pdf_lobe(lobe as usize, vec3_in(wo, "wo")?, vec3_in(wi, "wi")?)?;
        *out = pdf;
        Ok(())
    })
}

/// `weight * albedo(wo)` of lobe `lobe` alone.
///
/// # Safety
/// As `glint_albedo`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn glint_albedo_lobe(
    closure: *const glint_closure,
    lobe: u32,
    wo: glint_vec3,
    out: *mut f32,
) -> glint_status {
    guard(|| {
        // SAFETY: per the contract.
        let out = unsafe { out_rgb(out) }?;
        // SAFETY: per the contract.
        let c = unsafe { closure_ref(closure) }?;
        *out = c.albedo_lobe(lobe as usize, vec3_in(wo, "wo")?)?.to_array();
        Ok(())
    })
}
