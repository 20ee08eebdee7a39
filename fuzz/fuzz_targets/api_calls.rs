//! Sequences of C API calls decoded from bytes: runtimes, arenas, closure building
//! (blocks and JSON), scalar and per-lobe queries, and batches with arbitrary counts,
//! active masks, per-lane closures and floats (NaN, Inf, denormals included).
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
}

fn pick<T>(v: &[T], i: u8) -> Option<&T> {
    (!v.is_empty()).then(|| &v[i as usize % v.len()])
}

/// A failing call must name a known status and leave a message.
fn check_status(st: glint_status, what: &str) {
    assert!(
        st <= GLINT_ERROR_PLUGIN_BLOCK_SIZE,
        "{what}: unknown status {st}"
    );
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
                (st, vec![o0, o1, o2, o3, o4])
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
