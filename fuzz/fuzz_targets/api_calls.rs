//! Sequences of C API calls decoded from bytes: runtimes, arenas, closure building
//! (blocks and JSON), scalar and per-lobe queries, and batches with arbitrary counts,
//! active masks, per-lane closures and floats (NaN, Inf, denormals included);
//! compiled materials (JSON documents and parameter blocks, destroyed and outliving
//! their runtime), their closures from arbitrary shading contexts and overrides, and
//! material batches with arbitrary lanes and per-lane overrides.
//!
//! Valid but hostile: every pointer passed is NULL or valid for what the contract
//! says (arrays hold `count` elements; closures are used only while their arena has
//! not been reset or destroyed and their runtime lives). What the library promises,
//! and this target checks:
//! - no crash, no memory error (ASan), no panic (libfuzzer-sys aborts on any, even
//!   one the API's panic boundary catches);
//! - a failing call returns a known status with a message;
//! - on GLINT_OK every value, pdf, weight and albedo is finite and >= 0, and sampled
//!   directions are finite (README: "never a crash, NaN, Inf").
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use glint::ffi::*;
use libfuzzer_sys::fuzz_target;
use std::ffi::{CStr, CString, c_char};
use std::ptr::{null, null_mut};

/// A float that is often special: the values where numerics break, else any bits.
#[derive(Clone, Copy, Debug)]
struct F(f32);

const SPECIAL: [f32; 24] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    0.999_999_94,
    1e-41,
    -1e-41,
    1e-38,
    1e-20,
    1e-7,
    f32::MIN_POSITIVE,
    f32::MAX,
    -f32::MAX,
    3e38,
    1e38,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NAN,
    f32::EPSILON,
    0.001,
    0.17,
    2.0,
    1.5,
];

impl<'a> Arbitrary<'a> for F {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(F(match u.int_in_range(0u8..=3)? {
            0 => SPECIAL[u.choose_index(SPECIAL.len())?],
            1 => f32::from_bits(u.arbitrary()?),
            // A value in [-1, 1]: directions and random numbers of ordinary calls.
            _ => u.int_in_range(-32768i32..=32768)? as f32 / 32768.0,
        }))
    }
}

#[derive(Arbitrary, Clone, Copy, Debug)]
struct V3(F, F, F);

impl V3 {
    fn c(self) -> glint_vec3 {
        glint_vec3 {
            x: self.0.0,
            y: self.1.0,
            z: self.2.0,
        }
    }
}

/// Runtime configurations: the thread and ISA settings batches run on.
const CONFIGS: [Option<&CStr>; 5] = [
    None,
    Some(c"threads=1"),
    Some(c"threads=2"),
    Some(c"isa=scalar threads=1"),
    Some(c"isa=scalar;threads=2"),
];

#[derive(Arbitrary, Debug)]
enum BatchKind {
    Eval { pdf_reverse: bool },
    Pdf,
    Sample { optional: u8 },
    Albedo,
}

/// Where each lane's closure comes from.
#[derive(Arbitrary, Debug)]
enum LaneClosures {
    /// `closure` for every lane (an index into the live closures, or NULL).
    One(Option<u8>),
    /// `closures[i]`: a live closure, NULL, or (inactive lanes only, where the README
    /// promises nothing is read) a pointer that is not a closure.
    PerLane(Vec<Option<u8>>),
}

#[derive(Arbitrary, Debug)]
enum Op {
    CreateRuntime(u8),
    /// A configuration string through `Settings::parse` and, when cheap, a runtime.
    CreateRuntimeConfig(String),
    DestroyRuntime(u8),
    CreateArena(u16),
    CreateArenaHuge(bool),
    ResetArena(u8),
    DestroyArena(u8),
    Begin {
        runtime: u8,
        arena: u8,
        wo: Option<V3>,
        flags: u8,
    },
    AddLobe {
        closure: u8,
        type_id: u8,
        weight: Option<[F; 3]>,
        frame: Option<(V3, V3)>,
        /// Defaults (NULL), the type's defaults with some floats replaced, or any floats.
        params: Option<Vec<(u16, F)>>,
        full_block: bool,
    },
    Finish(u8),
    FromJson {
        runtime: u8,
        arena: u8,
        text: String,
        wo: Option<V3>,
    },
    Eval(u8, V3, V3),
    Sample(u8, V3, F, F, F),
    Pdf(u8, V3, V3),
    Albedo(u8, V3),
    EvalLobe(u8, u8, V3, V3),
    SampleLobe(u8, u8, V3, F, F, F),
    PdfLobe(u8, u8, V3, V3),
    AlbedoLobe(u8, u8, V3),
    LobeQuery(u8, u8),
    TypeQuery {
        runtime: u8,
        type_id: u8,
        param: u8,
        name: String,
    },
    Batch {
        kind: BatchKind,
        count: u16,
        lanes: LaneClosures,
        active: Option<Vec<u8>>,
        floats: Vec<F>,
    },
    CreateMaterial {
        runtime: u8,
        doc: MaterialDoc,
    },
    CreateMaterialParams {
        runtime: u8,
        type_id: u8,
        /// The type's defaults with some floats replaced (`count` of them passed), or NULL.
        params: Option<Vec<(u8, F)>>,
        count: u8,
    },
    DestroyMaterial(u8),
    MaterialClosure {
        material: u8,
        arena: u8,
        context: Option<Context>,
        struct_size: u8,
        overrides: Option<Vec<OverrideIn>>,
    },
    MaterialBatch {
        kind: BatchKind,
        material: u8,
        count: u16,
        active: Option<Vec<u8>>,
        tangent: bool,
        /// Each override's parameter (an index or element address) and type; its
        /// values are columns of `floats`.
        overrides: Vec<(u32, u8)>,
        floats: Vec<F>,
    },
    MaterialTypeQuery {
        runtime: u8,
        type_id: u8,
        param: u8,
        name: String,
    },
}

/// The disney material's parameters, then names no material has.
const MATERIAL_KEYS: [&str; 13] = [
    "base_color",
    "subsurface",
    "metallic",
    "specular",
    "specular_tint",
    "roughness",
    "anisotropic",
    "sheen",
    "sheen_tint",
    "clearcoat",
    "clearcoat_gloss",
    "colour",
    "lobes",
];

/// A material description: `{"material": "disney", ...}` with some keys set (a
/// number or a triple, whichever the key wants or not; non-finite numbers are not
/// JSON), or any text.
#[derive(Arbitrary, Debug)]
enum MaterialDoc {
    Disney(Vec<(u8, bool, F, F, F)>),
    Text(String),
}

impl MaterialDoc {
    fn text(&self) -> String {
        match self {
            MaterialDoc::Text(t) => t.clone(),
            MaterialDoc::Disney(keys) => {
                let mut doc = String::from("{\"material\": \"disney\"");
                for (key, triple, a, b, c) in keys {
                    let key = MATERIAL_KEYS[*key as usize % MATERIAL_KEYS.len()];
                    if *triple {
                        doc += &format!(", \"{key}\": [{}, {}, {}]", a.0, b.0, c.0);
                    } else {
                        doc += &format!(", \"{key}\": {}", a.0);
                    }
                }
                doc + "}"
            }
        }
    }
}

/// A shading context's fields (zero vectors where `None`: the automatic tangent, the
/// shading normal as the geometric one).
#[derive(Arbitrary, Debug)]
struct Context {
    wo: V3,
    normal: V3,
    tangent: Option<V3>,
    geometric_normal: Option<V3>,
    position: V3,
    reference_position: V3,
    footprint: F,
    uv: (F, F),
}

/// One override of a material closure: parameter (index or element address), type
/// (one past the known ones too) and value.
#[derive(Arbitrary, Debug)]
struct OverrideIn {
    param: u32,
    param_type: u8,
    value: [F; 3],
}

/// A parameter index, often one of the first few (real parameters), sometimes with
/// an element, sometimes anything.
fn param_index(p: u32) -> u32 {
    match p % 4 {
        0 | 1 => (p >> 2) % 12,
        2 => ((p >> 2) % 12) | ((p >> 8) % 3) << GLINT_PARAM_ELEMENT_SHIFT,
        _ => p,
    }
}

struct MaterialHandle {
    handle: *mut glint_material,
    /// Its runtime's index, `None` once that runtime is destroyed (calls must fail).
    runtime: Option<usize>,
}

struct Closure {
    handle: *mut glint_closure,
    arena: usize,
    runtime: usize,
}

#[derive(Default)]
struct State {
    runtimes: Vec<*mut glint_runtime>,
    arenas: Vec<*mut glint_arena>,
    closures: Vec<Closure>,
    materials: Vec<MaterialHandle>,
}

fn pick<T>(v: &[T], i: u8) -> Option<&T> {
    (!v.is_empty()).then(|| &v[i as usize % v.len()])
}

/// One of the statuses the library defines (every `glint::Status`).
fn known_status(st: glint_status) -> bool {
    usize::try_from(st).is_ok_and(|s| s < glint::Status::ALL.len())
}

/// A failing call must name a known status and leave a message.
fn check_status(st: glint_status, what: &str) {
    assert!(known_status(st), "{what}: unknown status {st}");
    assert_ne!(st, GLINT_ERROR_PANIC, "{what}: panic");
    if st != GLINT_OK && st != GLINT_NO_SAMPLE {
        // SAFETY: glint_last_error returns a NUL-terminated string valid until the next
        // failing call on this thread.
        let message = unsafe { CStr::from_ptr(glint_last_error()) };
        assert!(!message.is_empty(), "{what}: status {st} without a message");
    }
}

fn check_values(st: glint_status, what: &str, values: &[f32]) {
    check_status(st, what);
    if st == GLINT_OK {
        for v in values {
            assert!(v.is_finite() && *v >= 0.0, "{what}: output {v} on GLINT_OK");
        }
    }
}

fn check_sample(st: glint_status, what: &str, s: &glint_sample_result) {
    check_values(st, what, &[s.value[0], s.value[1], s.value[2], s.pdf]);
    check_values(st, what, &s.weight);
    if st == GLINT_OK {
        assert!(
            s.wi.x.is_finite() && s.wi.y.is_finite() && s.wi.z.is_finite(),
            "{what}: wi {:?} on GLINT_OK",
            s.wi
        );
    }
}

impl State {
    fn closure(&self, i: u8) -> *mut glint_closure {
        pick(&self.closures, i).map_or(null_mut(), |c| c.handle)
    }

    fn forget_arena_closures(&mut self, arena: usize) {
        self.closures.retain(|c| c.arena != arena);
    }

    fn add_runtime(&mut self, config: Option<&CStr>) {
        if self.runtimes.len() >= 3 {
            return;
        }
        let mut rt = null_mut();
        // SAFETY: config NULL or NUL-terminated; out writable.
        let st = unsafe { glint_runtime_create(config.map_or(null(), CStr::as_ptr), &mut rt) };
        check_status(st, "glint_runtime_create");
        if st == GLINT_OK {
            self.runtimes.push(rt);
        } else {
            assert!(rt.is_null(), "failed glint_runtime_create wrote a handle");
        }
    }

    fn place(
        &mut self,
        st: glint_status,
        handle: *mut glint_closure,
        arena: usize,
        runtime: usize,
    ) {
        if st == GLINT_OK {
            assert!(!handle.is_null());
            self.closures.push(Closure {
                handle,
                arena,
                runtime,
            });
        }
    }

    fn run(&mut self, op: Op) {
        match op {
            Op::CreateRuntime(i) => self.add_runtime(CONFIGS[i as usize % CONFIGS.len()]),
            Op::CreateRuntimeConfig(text) => {
                let Ok(text) = CString::new(text) else { return };
                // Only configurations that stay small: no plugin directory scans and
                // at most two pool threads per runtime (the fuzzer runs thousands).
                let cheap = glint::runtime::Settings::parse(text.to_str().unwrap_or(""))
                    .is_ok_and(|s| s.plugins.is_none() && (1..=2).contains(&s.threads));
                if cheap {
                    self.add_runtime(Some(&text));
                }
            }
            Op::DestroyRuntime(i) => {
                if self.runtimes.len() < 2 {
                    return;
                }
                // Runtime 0 is the shared first runtime, never destroyed.
                let i = 1 + i as usize % (self.runtimes.len() - 1);
                // Closures must not outlive their runtime (glint_runtime_destroy's
                // contract): drop every arena holding one first.
                let arenas: Vec<usize> = self
                    .closures
                    .iter()
                    .filter(|c| c.runtime == i)
                    .map(|c| c.arena)
                    .collect();
                for a in arenas {
                    // SAFETY: a live arena; its closures are forgotten below.
                    check_status(unsafe { glint_arena_reset(self.arenas[a]) }, "reset");
                    self.forget_arena_closures(a);
                }
                // SAFETY: a live runtime, destroyed once (removed from the list).
                unsafe { glint_runtime_destroy(self.runtimes.swap_remove(i)) };
                let moved = self.runtimes.len();
                for c in &mut self.closures {
                    if c.runtime == moved {
                        c.runtime = i;
                    }
                }
                // Materials outlive their runtime: their calls must fail from now on.
                for m in &mut self.materials {
                    m.runtime = match m.runtime {
                        Some(r) if r == i => None,
                        Some(r) if r == moved => Some(i),
                        r => r,
                    };
                }
            }
            Op::CreateArena(capacity) => self.add_arena(capacity as usize % 70),
            Op::CreateArenaHuge(max) => self.add_arena(if max { usize::MAX } else { 1 << 62 }),
            Op::ResetArena(i) => {
                if let Some(&a) = pick(&self.arenas, i) {
                    // SAFETY: a live arena.
                    check_status(unsafe { glint_arena_reset(a) }, "glint_arena_reset");
                    self.forget_arena_closures(i as usize % self.arenas.len());
                }
            }
            Op::DestroyArena(i) => {
                if self.arenas.is_empty() {
                    return;
                }
                let i = i as usize % self.arenas.len();
                self.forget_arena_closures(i);
                // SAFETY: a live arena, destroyed once (removed from the list).
                unsafe { glint_arena_destroy(self.arenas.swap_remove(i)) };
                let moved = self.arenas.len();
                for c in &mut self.closures {
                    if c.arena == moved {
                        c.arena = i;
                    }
                }
            }
            Op::Begin {
                runtime,
                arena,
                wo,
                flags,
            } => {
                let (Some(&rt), Some(&a)) =
                    (pick(&self.runtimes, runtime), pick(&self.arenas, arena))
                else {
                    return;
                };
                let wo = wo.map(V3::c);
                let mut out = null_mut();
                // SAFETY: live handles; wo NULL or readable; out writable.
                let st = unsafe {
                    glint_closure_begin(
                        rt,
                        a,
                        wo.as_ref().map_or(null(), |w| w),
                        flags as u32 % 3,
                        &mut out,
                    )
                };
                check_status(st, "glint_closure_begin");
                let (a, r) = (
                    arena as usize % self.arenas.len(),
                    runtime as usize % self.runtimes.len(),
                );
                self.place(st, out, a, r);
            }
            Op::AddLobe {
                closure,
                type_id,
                weight,
                frame,
                params,
                full_block,
            } => {
                let Some(c) = pick(&self.closures, closure) else {
                    return;
                };
                let rt = self.runtimes[c.runtime];
                let mut types = 0;
                // SAFETY: a live runtime; out writable.
                check_status(
                    unsafe { glint_lobe_type_count(rt, &mut types) },
                    "type_count",
                );
                // One past the last id too: an unknown type.
                let type_id = type_id as u32 % (types + 1);
                let weight = weight.map(|w| [w[0].0, w[1].0, w[2].0]);
                let frame = frame.map(|(n, t)| glint_frame {
                    normal: n.c(),
                    tangent: t.c(),
                });
                let block = params.map(|edits| {
                    let mut block = vec![0.0f32; 600];
                    // SAFETY: a live runtime; `block` holds 600 floats.
                    let st =
                        unsafe { glint_lobe_param_defaults(rt, type_id, block.as_mut_ptr(), 600) };
                    let mut info = lobe_info();
                    // SAFETY: a live runtime; out writable with struct_size set.
                    let size = if st == GLINT_OK
                        && unsafe { glint_lobe_type_info(rt, type_id, &mut info) } == GLINT_OK
                    {
                        info.param_block_size as usize
                    } else {
                        edits.len() % 600
                    };
                    for (at, v) in &edits {
                        block[*at as usize % 600] = v.0;
                    }
                    block.truncate(if full_block { size } else { edits.len() % 600 });
                    block
                });
                let mut index = u32::MAX;
                // SAFETY: a live closure; weight NULL or 3 floats; frame NULL or
                // readable; params NULL (count 0) or `len` floats; out_index writable.
                let st = unsafe {
                    glint_closure_add_lobe(
                        c.handle,
                        type_id,
                        weight.as_ref().map_or(null(), |w| w.as_ptr()),
                        frame.as_ref().map_or(null(), |f| f),
                        block.as_ref().map_or(null(), |b| b.as_ptr()),
                        block.as_ref().map_or(0, Vec::len),
                        &mut index,
                    )
                };
                check_status(st, "glint_closure_add_lobe");
                if st == GLINT_OK {
                    assert!((index as usize) < 16, "lobe index {index}");
                }
            }
            Op::Finish(i) => {
                // SAFETY: NULL or a live closure.
                check_status(unsafe { glint_closure_finish(self.closure(i)) }, "finish");
            }
            Op::FromJson {
                runtime,
                arena,
                text,
                wo,
            } => {
                let (Some(&rt), Some(&a)) =
                    (pick(&self.runtimes, runtime), pick(&self.arenas, arena))
                else {
                    return;
                };
                let text: Vec<u8> = text.bytes().take_while(|b| *b != 0).collect();
                let text = CString::new(text).expect("no NUL");
                let wo = wo.map(V3::c);
                let mut out = null_mut();
                // SAFETY: live handles; text NUL-terminated; wo NULL or readable.
                let st = unsafe {
                    glint_closure_from_json(
                        rt,
                        a,
                        text.as_ptr(),
                        wo.as_ref().map_or(null(), |w| w),
                        &mut out,
                    )
                };
                check_status(st, "glint_closure_from_json");
                let (a, r) = (
                    arena as usize % self.arenas.len(),
                    runtime as usize % self.runtimes.len(),
                );
                self.place(st, out, a, r);
            }
            Op::Eval(i, wo, wi) => {
                let mut e = eval_result();
                // SAFETY: NULL or a live closure; out writable with struct_size set.
                let st = unsafe { glint_eval(self.closure(i), wo.c(), wi.c(), &mut e) };
                check_values(
                    st,
                    "glint_eval",
                    &[e.value[0], e.value[1], e.value[2], e.pdf, e.pdf_reverse],
                );
            }
            Op::Sample(i, wo, a, b, c) => {
                let mut s = sample_result();
                // SAFETY: as above.
                let st = unsafe { glint_sample(self.closure(i), wo.c(), a.0, b.0, c.0, &mut s) };
                check_sample(st, "glint_sample", &s);
            }
            Op::Pdf(i, wo, wi) => {
                let mut pdf = 0.0;
                // SAFETY: as above.
                let st = unsafe { glint_pdf(self.closure(i), wo.c(), wi.c(), &mut pdf) };
                check_values(st, "glint_pdf", &[pdf]);
            }
            Op::Albedo(i, wo) => {
                let mut albedo = [0.0; 3];
                // SAFETY: as above; 3 writable floats.
                let st = unsafe { glint_albedo(self.closure(i), wo.c(), albedo.as_mut_ptr()) };
                check_values(st, "glint_albedo", &albedo);
            }
            Op::EvalLobe(i, lobe, wo, wi) => {
                let mut e = eval_result();
                // SAFETY: as above.
                let st = unsafe {
                    glint_eval_lobe(self.closure(i), lobe as u32 % 18, wo.c(), wi.c(), &mut e)
                };
                check_values(
                    st,
                    "glint_eval_lobe",
                    &[e.value[0], e.value[1], e.value[2], e.pdf, e.pdf_reverse],
                );
            }
            Op::SampleLobe(i, lobe, wo, a, b, c) => {
                let mut s = sample_result();
                // SAFETY: as above.
                let st = unsafe {
                    glint_sample_lobe(
                        self.closure(i),
                        lobe as u32 % 18,
                        wo.c(),
                        a.0,
                        b.0,
                        c.0,
                        &mut s,
                    )
                };
                check_sample(st, "glint_sample_lobe", &s);
            }
            Op::PdfLobe(i, lobe, wo, wi) => {
                let mut pdf = 0.0;
                // SAFETY: as above.
                let st = unsafe {
                    glint_pdf_lobe(self.closure(i), lobe as u32 % 18, wo.c(), wi.c(), &mut pdf)
                };
                check_values(st, "glint_pdf_lobe", &[pdf]);
            }
            Op::AlbedoLobe(i, lobe, wo) => {
                let mut albedo = [0.0; 3];
                // SAFETY: as above.
                let st = unsafe {
                    glint_albedo_lobe(
                        self.closure(i),
                        lobe as u32 % 18,
                        wo.c(),
                        albedo.as_mut_ptr(),
                    )
                };
                check_values(st, "glint_albedo_lobe", &albedo);
            }
            Op::LobeQuery(i, index) => {
                let c = self.closure(i);
                let (mut n, mut type_id, mut p) = (0, 0, 0.0);
                // SAFETY: NULL or a live closure; outs writable.
                check_status(unsafe { glint_closure_lobe_count(c, &mut n) }, "lobe_count");
                // SAFETY: as above.
                let st = unsafe { glint_closure_lobe(c, index as u32 % 18, &mut type_id, &mut p) };
                check_values(st, "glint_closure_lobe", &[p]);
            }
            Op::TypeQuery {
                runtime,
                type_id,
                param,
                name,
            } => self.type_query(runtime, type_id, param, name),
            Op::Batch {
                kind,
                count,
                lanes,
                active,
                floats,
            } => self.batch(kind, count as usize % 300, lanes, active, floats),
            Op::CreateMaterial { runtime, doc } => {
                let Some(&rt) = pick(&self.runtimes, runtime) else {
                    return;
                };
                let text: Vec<u8> = doc.text().bytes().take_while(|b| *b != 0).collect();
                let text = CString::new(text).expect("no NUL");
                let mut out = null_mut();
                // SAFETY: a live runtime; text NUL-terminated; out writable.
                let st = unsafe { glint_material_create(rt, text.as_ptr(), &mut out) };
                check_status(st, "glint_material_create");
                self.add_material(st, out, runtime);
            }
            Op::CreateMaterialParams {
                runtime,
                type_id,
                params,
                count,
            } => {
                let Some(&rt) = pick(&self.runtimes, runtime) else {
                    return;
                };
                let type_id = u32::from(type_id % 3);
                let block = params.map(|edits| {
                    let mut block = vec![0.5f32; 64];
                    let mut info = material_info();
                    // SAFETY: a live runtime; out writable with struct_size set.
                    let size = if unsafe { glint_material_type_info(rt, type_id, &mut info) }
                        == GLINT_OK
                    {
                        info.param_block_size as usize
                    } else {
                        16
                    };
                    for (at, v) in &edits {
                        block[*at as usize % 64] = v.0;
                    }
                    // The whole block, or a wrong count.
                    block.truncate(if count % 4 == 0 {
                        count as usize % 64
                    } else {
                        size
                    });
                    block
                });
                let mut out = null_mut();
                // SAFETY: a live runtime; params NULL (count 0) or `len` floats.
                let st = unsafe {
                    glint_material_create_from_params(
                        rt,
                        type_id,
                        block.as_ref().map_or(null(), |b| b.as_ptr()),
                        block.as_ref().map_or(0, Vec::len),
                        &mut out,
                    )
                };
                check_status(st, "glint_material_create_from_params");
                self.add_material(st, out, runtime);
            }
            Op::DestroyMaterial(i) => {
                if self.materials.is_empty() {
                    return;
                }
                let m = self
                    .materials
                    .swap_remove(i as usize % self.materials.len());
                // SAFETY: a live material, destroyed once (removed from the list).
                unsafe { glint_material_destroy(m.handle) };
            }
            Op::MaterialClosure {
                material,
                arena,
                context,
                struct_size,
                overrides,
            } => self.material_closure(material, arena, context, struct_size, overrides),
            Op::MaterialBatch {
                kind,
                material,
                count,
                active,
                tangent,
                overrides,
                floats,
            } => {
                let n = count as usize % 300;
                self.material_batch(kind, material, n, active, tangent, overrides, floats)
            }
            Op::MaterialTypeQuery {
                runtime,
                type_id,
                param,
                name,
            } => self.material_type_query(runtime, type_id, param, name),
        }
    }

    fn add_material(&mut self, st: glint_status, handle: *mut glint_material, runtime: u8) {
        if st == GLINT_OK {
            assert!(!handle.is_null());
            if self.materials.len() >= 4 {
                // SAFETY: just created, destroyed once.
                unsafe { glint_material_destroy(handle) };
                return;
            }
            let runtime = Some(runtime as usize % self.runtimes.len());
            self.materials.push(MaterialHandle { handle, runtime });
        } else {
            assert!(
                handle.is_null(),
                "failed material constructor wrote a handle"
            );
        }
    }

    fn material(&self, i: u8) -> (*const glint_material, Option<usize>) {
        pick(&self.materials, i).map_or((null(), None), |m| (m.handle, m.runtime))
    }

    fn material_closure(
        &mut self,
        material: u8,
        arena: u8,
        context: Option<Context>,
        struct_size: u8,
        overrides: Option<Vec<OverrideIn>>,
    ) {
        let Some(&a) = pick(&self.arenas, arena) else {
            return;
        };
        let (m, runtime) = self.material(material);
        let zero = glint_vec3::default();
        let full = size_of::<glint_shading_context>() as u32;
        let context = context.map(|c| glint_shading_context {
            // Too small for some fields, or larger (a newer header's) than this one.
            struct_size: match struct_size % 8 {
                0 => 0,
                1 => 8,
                2 => full - 4,
                _ => full,
            },
            wo: c.wo.c(),
            normal: c.normal.c(),
            tangent: c.tangent.map_or(zero, V3::c),
            geometric_normal: c.geometric_normal.map_or(zero, V3::c),
            position: c.position.c(),
            reference_position: c.reference_position.c(),
            footprint: c.footprint.0,
            uv: [c.uv.0.0, c.uv.1.0],
        });
        let overrides: Option<Vec<glint_override>> = overrides.map(|o| {
            o.iter()
                .map(|o| glint_override {
                    param: param_index(o.param),
                    param_type: u32::from(o.param_type % 5),
                    value: o.value.map(|v| v.0),
                })
                .collect()
        });
        let mut out = null_mut();
        // SAFETY: material NULL, live or destroyed-but-quarantined (with a live or
        // quarantined runtime); a live arena; context NULL or readable; overrides NULL
        // or `len` entries; out writable.
        let st = unsafe {
            glint_material_closure(
                m,
                a,
                context.as_ref().map_or(null(), |c| c),
                overrides.as_ref().map_or(null(), |o| o.as_ptr()),
                overrides.as_ref().map_or(0, Vec::len),
                &mut out,
            )
        };
        check_status(st, "glint_material_closure");
        if st != GLINT_OK {
            assert!(
                out.is_null(),
                "failed glint_material_closure wrote a handle"
            );
            return;
        }
        let runtime = runtime.expect("a closure from a material whose runtime is gone");
        self.place(st, out, arena as usize % self.arenas.len(), runtime);
        // The closure is finished: its queries succeed at an ordinary direction.
        let mut albedo = [0.0f32; 3];
        let wo = glint_vec3 {
            x: 0.3,
            y: 0.2,
            z: 0.9,
        };
        // SAFETY: a live finished closure; 3 writable floats.
        let st = unsafe { glint_albedo(out, wo, albedo.as_mut_ptr()) };
        assert_eq!(st, GLINT_OK, "albedo of a material closure");
        check_values(st, "material closure albedo", &albedo);
    }

    #[allow(clippy::too_many_arguments)]
    fn material_batch(
        &self,
        kind: BatchKind,
        material: u8,
        n: usize,
        active: Option<Vec<u8>>,
        tangent: bool,
        overrides: Vec<(u32, u8)>,
        floats: Vec<F>,
    ) {
        let (m, runtime) = self.material(material);
        let active: Option<Vec<u8>> =
            active.map(|a| (0..n).map(|i| a.get(i).copied().unwrap_or(1) % 3).collect());
        let is_active = |i: usize| active.as_ref().is_none_or(|a| a[i] != 0);
        let overrides: Vec<(u32, u8)> = overrides.into_iter().take(4).collect();
        // Columns from the fuzzer's floats (cycled), else 0.5: wo, normal, tangent,
        // wi or u, then three per override.
        let columns = 12 + 3 * overrides.len();
        let column = |k: usize| -> Vec<f32> {
            (0..n)
                .map(|i| match floats.len() {
                    0 => 0.5,
                    len => floats[(i * columns + k) % len].0,
                })
                .collect()
        };
        let inputs: Vec<Vec<f32>> = (0..columns).map(column).collect();
        let lanes_overrides: Vec<glint_override_lanes> = overrides
            .iter()
            .enumerate()
            .map(|(j, &(param, kind))| glint_override_lanes {
                param: param_index(param),
                param_type: u32::from(kind % 5),
                value: [0, 1, 2].map(|c| inputs[12 + 3 * j + c].as_ptr()),
            })
            .collect();
        let lanes = glint_material_lanes {
            material: m,
            count: n,
            active: active.as_ref().map_or(null(), |a| a.as_ptr()),
            wo_x: inputs[0].as_ptr(),
            wo_y: inputs[1].as_ptr(),
            wo_z: inputs[2].as_ptr(),
            normal_x: inputs[3].as_ptr(),
            normal_y: inputs[4].as_ptr(),
            normal_z: inputs[5].as_ptr(),
            tangent_x: if tangent { inputs[6].as_ptr() } else { null() },
            tangent_y: if tangent { inputs[7].as_ptr() } else { null() },
            tangent_z: if tangent { inputs[8].as_ptr() } else { null() },
            overrides: if lanes_overrides.is_empty() {
                null()
            } else {
                lanes_overrides.as_ptr()
            },
            override_count: lanes_overrides.len(),
        };
        let mut out: Vec<Vec<f32>> = (0..12).map(|_| vec![f32::NAN; n]).collect();
        let mut words: Vec<Vec<u32>> = (0..3).map(|_| vec![u32::MAX; n]).collect();
        let [o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11] = &mut out[..] else {
            unreachable!()
        };
        let [flags, lobe, component] = &mut words[..] else {
            unreachable!()
        };
        let wi = [9, 10, 11].map(|k| inputs[k].as_ptr());
        let (st, checked): (glint_status, Vec<&[f32]>) = match kind {
            BatchKind::Eval { pdf_reverse } => {
                let args = glint_material_eval_batch_args {
                    struct_size: size_of::<glint_material_eval_batch_args>() as u32,
                    lanes,
                    wi_x: wi[0],
                    wi_y: wi[1],
                    wi_z: wi[2],
                    value_r: o0.as_mut_ptr(),
                    value_g: o1.as_mut_ptr(),
                    value_b: o2.as_mut_ptr(),
                    pdf: o3.as_mut_ptr(),
                    pdf_reverse: if pdf_reverse {
                        o4.as_mut_ptr()
                    } else {
                        null_mut()
                    },
                    direction_count: 1,
                    albedo_r: o5.as_mut_ptr(),
                    albedo_g: o6.as_mut_ptr(),
                    albedo_b: o7.as_mut_ptr(),
                };
                // SAFETY: every array holds `n` elements; the material NULL, live or
                // quarantined.
                let st = unsafe { glint_material_eval_batch(&args) };
                let mut checked: Vec<&[f32]> = vec![o0, o1, o2, o3, o5, o6, o7];
                if pdf_reverse {
                    checked.push(o4);
                }
                (st, checked)
            }
            BatchKind::Pdf => {
                let args = glint_material_pdf_batch_args {
                    struct_size: size_of::<glint_material_pdf_batch_args>() as u32,
                    lanes,
                    wi_x: wi[0],
                    wi_y: wi[1],
                    wi_z: wi[2],
                    pdf: o0.as_mut_ptr(),
                };
                // SAFETY: as above.
                let st = unsafe { glint_material_pdf_batch(&args) };
                (st, vec![o0])
            }
            BatchKind::Sample { optional } => {
                let opt = |bit: u8, p: *mut f32| if optional & bit != 0 { p } else { null_mut() };
                let word = |bit: u8, p: *mut u32| if optional & bit != 0 { p } else { null_mut() };
                let args = glint_material_sample_batch_args {
                    struct_size: size_of::<glint_material_sample_batch_args>() as u32,
                    lanes,
                    u_lobe: wi[0],
                    u0: wi[1],
                    u1: wi[2],
                    wi_x: o9.as_mut_ptr(),
                    wi_y: o10.as_mut_ptr(),
                    wi_z: o11.as_mut_ptr(),
                    pdf: o3.as_mut_ptr(),
                    weight_r: o4.as_mut_ptr(),
                    weight_g: o5.as_mut_ptr(),
                    weight_b: o6.as_mut_ptr(),
                    value_r: opt(1, o0.as_mut_ptr()),
                    value_g: opt(1, o1.as_mut_ptr()),
                    value_b: opt(1, o2.as_mut_ptr()),
                    flags: word(2, flags.as_mut_ptr()),
                    lobe: word(4, lobe.as_mut_ptr()),
                    eta: opt(8, o7.as_mut_ptr()),
                    roughness: opt(16, o8.as_mut_ptr()),
                    component: word(32, component.as_mut_ptr()),
                };
                // SAFETY: as above.
                let st = unsafe { glint_material_sample_batch(&args) };
                let mut checked: Vec<&[f32]> = vec![o3, o4, o5, o6];
                if optional & 1 != 0 {
                    checked.extend([&o0[..], &o1[..], &o2[..]]);
                }
                for w in [&o9[..], &o10[..], &o11[..]] {
                    for (i, x) in w.iter().enumerate() {
                        assert!(
                            !is_active(i) || st != GLINT_OK || x.is_finite(),
                            "material sample batch wi {x}"
                        );
                    }
                }
                (st, checked)
            }
            BatchKind::Albedo => {
                let args = glint_material_albedo_batch_args {
                    struct_size: size_of::<glint_material_albedo_batch_args>() as u32,
                    lanes,
                    albedo_r: o0.as_mut_ptr(),
                    albedo_g: o1.as_mut_ptr(),
                    albedo_b: o2.as_mut_ptr(),
                };
                // SAFETY: as above.
                let st = unsafe { glint_material_albedo_batch(&args) };
                (st, vec![o0, o1, o2])
            }
        };
        check_status(st, "material batch");
        if runtime.is_none() && n > 0 {
            assert_ne!(st, GLINT_OK, "a material batch without a live material");
        }
        for column in checked {
            for (i, x) in column.iter().enumerate() {
                if is_active(i) {
                    assert!(
                        st != GLINT_OK || (x.is_finite() && *x >= 0.0),
                        "material batch lane {i}: {x} on GLINT_OK"
                    );
                } else {
                    assert!(x.is_nan(), "material batch lane {i}: inactive lane written");
                }
            }
        }
    }

    fn material_type_query(&self, runtime: u8, type_id: u8, param: u8, name: String) {
        let Some(&rt) = pick(&self.runtimes, runtime) else {
            return;
        };
        let Ok(name) = CString::new(name) else { return };
        let (type_id, param) = (u32::from(type_id % 3), u32::from(param % 14));
        let mut info = material_info();
        let mut pinfo = param_info();
        let (mut count, mut id, mut index) = (0, 0, 0);
        // SAFETY: a live runtime; strings NUL-terminated; outs writable with
        // struct_size set.
        unsafe {
            check_status(
                glint_material_type_count(rt, &mut count),
                "material_type_count",
            );
            check_status(
                glint_material_type_find(rt, name.as_ptr(), &mut id),
                "material_type_find",
            );
            check_status(
                glint_material_type_info(rt, type_id, &mut info),
                "material_type_info",
            );
            check_status(
                glint_material_param_info(rt, type_id, param, &mut pinfo),
                "material_param_info",
            );
            check_status(
                glint_material_param_find(rt, type_id, name.as_ptr(), &mut index),
                "material_param_find",
            );
        }
    }

    fn add_arena(&mut self, capacity: usize) {
        if self.arenas.len() >= 4 {
            return;
        }
        let mut a = null_mut();
        // SAFETY: out writable.
        let st = unsafe { glint_arena_create(capacity, &mut a) };
        check_status(st, "glint_arena_create");
        if st == GLINT_OK {
            self.arenas.push(a);
        }
    }

    fn type_query(&self, runtime: u8, type_id: u8, param: u8, name: String) {
        let Some(&rt) = pick(&self.runtimes, runtime) else {
            return;
        };
        let Ok(name) = CString::new(name) else { return };
        let (type_id, param) = (type_id as u32 % 12, param as u32 % 12);
        let mut info = lobe_info();
        let mut pinfo = param_info();
        let (mut id, mut index, mut choice) = (0, 0, 0.0);
        let mut block = [0.0f32; 8];
        // SAFETY: a live runtime; strings NUL-terminated; outs writable with
        // struct_size set; `block` holds the 8 floats passed as its capacity.
        unsafe {
            check_status(
                glint_lobe_type_find(rt, name.as_ptr(), &mut id),
                "type_find",
            );
            check_status(glint_lobe_type_info(rt, type_id, &mut info), "type_info");
            check_status(
                glint_lobe_param_info(rt, type_id, param, &mut pinfo),
                "param_info",
            );
            check_status(
                glint_lobe_param_find(rt, type_id, name.as_ptr(), &mut index),
                "param_find",
            );
            check_status(
                glint_lobe_param_choice(rt, type_id, param, name.as_ptr(), &mut choice),
                "param_choice",
            );
            check_status(
                glint_lobe_param_defaults(rt, type_id, block.as_mut_ptr(), 8),
                "param_defaults",
            );
        }
    }

    fn batch(
        &self,
        kind: BatchKind,
        n: usize,
        lanes: LaneClosures,
        active: Option<Vec<u8>>,
        floats: Vec<F>,
    ) {
        let active: Option<Vec<u8>> =
            active.map(|a| (0..n).map(|i| a.get(i).copied().unwrap_or(1) % 3).collect());
        let is_active = |i: usize| active.as_ref().is_none_or(|a| a[i] != 0);
        let (one, per_lane): (*const glint_closure, Option<Vec<*const glint_closure>>) = match lanes
        {
            LaneClosures::One(i) => (i.map_or(null_mut(), |i| self.closure(i)), None),
            LaneClosures::PerLane(picks) => {
                let v = (0..n)
                    .map(|i| match picks.get(i).copied().flatten() {
                        Some(255) if !is_active(i) => 0x10 as *const glint_closure,
                        Some(k) => self.closure(k),
                        None => null(),
                    })
                    .collect();
                (null(), Some(v))
            }
        };
        // Twelve input columns, filled from the fuzzer's floats (cycled), else 0.5.
        let column = |k: usize| -> Vec<f32> {
            (0..n)
                .map(|i| match floats.len() {
                    0 => 0.5,
                    len => floats[(i * 12 + k) % len].0,
                })
                .collect()
        };
        let inputs: Vec<Vec<f32>> = (0..9).map(column).collect();
        let mut out: Vec<Vec<f32>> = (0..12).map(|_| vec![f32::NAN; n]).collect();
        let mut words: Vec<Vec<u32>> = (0..2).map(|_| vec![u32::MAX; n]).collect();
        let closures = per_lane.as_ref().map_or(null(), |v| v.as_ptr());
        let active_ptr = active.as_ref().map_or(null(), |a| a.as_ptr());
        let [o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11] = &mut out[..] else {
            unreachable!()
        };
        let [flags, lobe] = &mut words[..] else {
            unreachable!()
        };
        let (st, checked): (glint_status, Vec<&[f32]>) = match kind {
            BatchKind::Eval { pdf_reverse } => {
                let args = glint_eval_batch_args {
                    struct_size: size_of::<glint_eval_batch_args>() as u32,
                    count: n,
                    closure: one,
                    closures,
                    active: active_ptr,
                    wo_x: inputs[0].as_ptr(),
                    wo_y: inputs[1].as_ptr(),
                    wo_z: inputs[2].as_ptr(),
                    wi_x: inputs[3].as_ptr(),
                    wi_y: inputs[4].as_ptr(),
                    wi_z: inputs[5].as_ptr(),
                    value_r: o0.as_mut_ptr(),
                    value_g: o1.as_mut_ptr(),
                    value_b: o2.as_mut_ptr(),
                    pdf: o3.as_mut_ptr(),
                    pdf_reverse: if pdf_reverse {
                        o4.as_mut_ptr()
                    } else {
                        null_mut()
                    },
                };
                // SAFETY: every array holds `n` elements; closures live (or NULL, or
                // not dereferenceable only on inactive lanes).
                let st = unsafe { glint_eval_batch(&args) };
                // The reverse pdf only where asked for (else its column is not written).
                let mut checked: Vec<&[f32]> = vec![o0, o1, o2, o3];
                if pdf_reverse {
                    checked.push(o4);
                }
                (st, checked)
            }
            BatchKind::Pdf => {
                let args = glint_pdf_batch_args {
                    struct_size: size_of::<glint_pdf_batch_args>() as u32,
                    count: n,
                    closure: one,
                    closures,
                    active: active_ptr,
                    wo_x: inputs[0].as_ptr(),
                    wo_y: inputs[1].as_ptr(),
                    wo_z: inputs[2].as_ptr(),
                    wi_x: inputs[3].as_ptr(),
                    wi_y: inputs[4].as_ptr(),
                    wi_z: inputs[5].as_ptr(),
                    pdf: o0.as_mut_ptr(),
                };
                // SAFETY: as above.
                let st = unsafe { glint_pdf_batch(&args) };
                (st, vec![o0])
            }
            BatchKind::Sample { optional } => {
                let opt = |bit: u8, p: *mut f32| if optional & bit != 0 { p } else { null_mut() };
                let args = glint_sample_batch_args {
                    struct_size: size_of::<glint_sample_batch_args>() as u32,
                    count: n,
                    closure: one,
                    closures,
                    active: active_ptr,
                    wo_x: inputs[0].as_ptr(),
                    wo_y: inputs[1].as_ptr(),
                    wo_z: inputs[2].as_ptr(),
                    u_lobe: inputs[6].as_ptr(),
                    u0: inputs[7].as_ptr(),
                    u1: inputs[8].as_ptr(),
                    wi_x: o9.as_mut_ptr(),
                    wi_y: o10.as_mut_ptr(),
                    wi_z: o11.as_mut_ptr(),
                    pdf: o3.as_mut_ptr(),
                    weight_r: o4.as_mut_ptr(),
                    weight_g: o5.as_mut_ptr(),
                    weight_b: o6.as_mut_ptr(),
                    value_r: opt(1, o0.as_mut_ptr()),
                    value_g: opt(1, o1.as_mut_ptr()),
                    value_b: opt(1, o2.as_mut_ptr()),
                    flags: if optional & 2 != 0 {
                        flags.as_mut_ptr()
                    } else {
                        null_mut()
                    },
                    lobe: if optional & 4 != 0 {
                        lobe.as_mut_ptr()
                    } else {
                        null_mut()
                    },
                    eta: opt(8, o7.as_mut_ptr()),
                    roughness: opt(16, o8.as_mut_ptr()),
                    component: null_mut(),
                };
                // SAFETY: as above.
                let st = unsafe { glint_sample_batch(&args) };
                let mut checked: Vec<&[f32]> = vec![o3, o4, o5, o6];
                if optional & 1 != 0 {
                    checked.extend([&o0[..], &o1[..], &o2[..]]);
                }
                for w in [&o9[..], &o10[..], &o11[..]] {
                    for (i, x) in w.iter().enumerate() {
                        assert!(
                            !is_active(i) || st != GLINT_OK || x.is_finite(),
                            "sample batch wi {x}"
                        );
                    }
                }
                (st, checked)
            }
            BatchKind::Albedo => {
                let args = glint_albedo_batch_args {
                    struct_size: size_of::<glint_albedo_batch_args>() as u32,
                    count: n,
                    closure: one,
                    closures,
                    active: active_ptr,
                    wo_x: inputs[0].as_ptr(),
                    wo_y: inputs[1].as_ptr(),
                    wo_z: inputs[2].as_ptr(),
                    albedo_r: o0.as_mut_ptr(),
                    albedo_g: o1.as_mut_ptr(),
                    albedo_b: o2.as_mut_ptr(),
                };
                // SAFETY: as above.
                let st = unsafe { glint_albedo_batch(&args) };
                (st, vec![o0, o1, o2])
            }
        };
        check_status(st, "batch");
        // Active lanes of a successful batch hold finite, non-negative outputs;
        // inactive lanes are never written (they keep the NaN put there).
        for column in checked {
            for (i, x) in column.iter().enumerate() {
                if is_active(i) {
                    assert!(
                        st != GLINT_OK || (x.is_finite() && *x >= 0.0),
                        "batch lane {i}: {x} on GLINT_OK"
                    );
                } else {
                    assert!(x.is_nan(), "batch lane {i}: inactive lane written ({x})");
                }
            }
        }
    }
}

fn eval_result() -> glint_eval_result {
    glint_eval_result {
        struct_size: size_of::<glint_eval_result>() as u32,
        ..Default::default()
    }
}

fn sample_result() -> glint_sample_result {
    glint_sample_result {
        struct_size: size_of::<glint_sample_result>() as u32,
        ..Default::default()
    }
}

fn lobe_info() -> glint_lobe_info {
    glint_lobe_info {
        struct_size: size_of::<glint_lobe_info>() as u32,
        name: null::<c_char>(),
        summary: null::<c_char>(),
        flags: 0,
        reciprocal: 0,
        param_count: 0,
        param_block_size: 0,
        component_count: 0,
    }
}

fn material_info() -> glint_material_info {
    glint_material_info {
        struct_size: size_of::<glint_material_info>() as u32,
        name: null(),
        summary: null(),
        param_count: 0,
        param_block_size: 0,
        lobe_count: 0,
    }
}

fn param_info() -> glint_param_info {
    glint_param_info {
        struct_size: size_of::<glint_param_info>() as u32,
        name: null(),
        param_type: 0,
        offset: 0,
        size: 0,
        default_value: [0.0; 3],
        min: 0.0,
        max: 0.0,
        choice_count: 0,
        choices: null(),
        doc: null(),
        shape: 0,
        parent: 0,
        member_count: 0,
        capacity: 0,
        count_offset: 0,
        default_count: 0,
    }
}

impl Drop for State {
    fn drop(&mut self) {
        for m in &self.materials {
            // SAFETY: live materials, destroyed once.
            unsafe { glint_material_destroy(m.handle) };
        }
        for &a in &self.arenas {
            // SAFETY: live arenas, destroyed once, before their closures' runtimes.
            unsafe { glint_arena_destroy(a) };
        }
        for &r in &self.runtimes[1..] {
            // SAFETY: live runtimes, destroyed once (not the shared first one).
            unsafe { glint_runtime_destroy(r) };
        }
    }
}

/// The runtime every input starts with, created once (creating one per input would
/// dominate the run time); inputs never destroy it.
fn first_runtime() -> *mut glint_runtime {
    struct Shared(*mut glint_runtime);
    // SAFETY: a runtime is read-only after setup and may be shared between threads.
    unsafe impl Send for Shared {}
    // SAFETY: as above.
    unsafe impl Sync for Shared {}
    static RT: std::sync::OnceLock<Shared> = std::sync::OnceLock::new();
    RT.get_or_init(|| {
        let mut rt = null_mut();
        // SAFETY: a NUL-terminated config; out writable.
        assert_eq!(
            unsafe { glint_runtime_create(c"threads=1".as_ptr(), &mut rt) },
            GLINT_OK
        );
        Shared(rt)
    })
    .0
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut state = State::default();
    // Every input starts from a usable runtime and arena.
    state.runtimes.push(first_runtime());
    state.add_arena(8);
    for _ in 0..64 {
        let Ok(op) = Op::arbitrary(&mut u) else { break };
        state.run(op);
    }
});
