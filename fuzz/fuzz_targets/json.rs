//! The JSON closure parser through the C ABI (`glint_closure_from_json`): any bytes
//! as the description, a finished closure or a clear error, never a crash or panic;
//! a closure it accepts evaluates, samples and reports albedo finitely.
#![no_main]

use glint::ffi::*;
use libfuzzer_sys::fuzz_target;
use std::ffi::{CStr, CString};
use std::ptr::null_mut;
use std::sync::OnceLock;

struct Handles {
    runtime: *mut glint_runtime,
}

// SAFETY: a runtime is read-only after setup and may be shared between threads.
unsafe impl Send for Handles {}
// SAFETY: as above.
unsafe impl Sync for Handles {}

fn runtime() -> *mut glint_runtime {
    static RT: OnceLock<Handles> = OnceLock::new();
    RT.get_or_init(|| {
        let mut runtime = null_mut();
        // SAFETY: a NUL-terminated config; out writable.
        let st = unsafe { glint_runtime_create(c"threads=1".as_ptr(), &mut runtime) };
        assert_eq!(st, GLINT_OK);
        Handles { runtime }
    })
    .runtime
}

fn finite(values: &[f32], what: &str, json: &CStr) {
    for v in values {
        assert!(v.is_finite() && *v >= 0.0, "{what}: {v} for {json:?}");
    }
}

/// Directions a host meets: overhead, oblique, grazing, below the surface.
const DIRECTIONS: [glint_vec3; 4] = [
    glint_vec3 {
        x: 0.0,
        y: 0.0,
        z: 1.0,
    },
    glint_vec3 {
        x: 0.3,
        y: 0.2,
        z: 0.9,
    },
    glint_vec3 {
        x: 1.0,
        y: 0.0,
        z: 0.01,
    },
    glint_vec3 {
        x: -0.2,
        y: 0.4,
        z: -0.8,
    },
];

fuzz_target!(|data: &[u8]| {
    let text: Vec<u8> = data.iter().copied().take_while(|b| *b != 0).collect();
    let text = CString::new(text).expect("no NUL");
    let mut arena = null_mut();
    let mut closure = null_mut();
    // SAFETY: out writable; the runtime lives forever; text is NUL-terminated.
    let st = unsafe {
        assert_eq!(glint_arena_create(1, &mut arena), GLINT_OK);
        glint_closure_from_json(
            runtime(),
            arena,
            text.as_ptr(),
            std::ptr::null(),
            &mut closure,
        )
    };
    assert_ne!(st, GLINT_ERROR_PANIC, "panic for {text:?}");
    let known = usize::try_from(st).is_ok_and(|s| s < glint::Status::ALL.len());
    assert!(known, "unknown status {st}");
    if st != GLINT_OK {
        // SAFETY: the message of the failed call, NUL-terminated.
        let message = unsafe { CStr::from_ptr(glint_last_error()) };
        assert!(
            !message.is_empty(),
            "status {st} without a message for {text:?}"
        );
        assert!(closure.is_null(), "failed parse wrote a handle");
    } else {
        for (k, &wo) in DIRECTIONS.iter().enumerate() {
            let wi = DIRECTIONS[(k + 1) % DIRECTIONS.len()];
            let mut e = glint_eval_result {
                struct_size: size_of::<glint_eval_result>() as u32,
                ..Default::default()
            };
            let mut s = glint_sample_result {
                struct_size: size_of::<glint_sample_result>() as u32,
                ..Default::default()
            };
            let mut albedo = [0.0f32; 3];
            // SAFETY: a live finished closure; outs writable with struct_size set.
            unsafe {
                assert_eq!(glint_eval(closure, wo, wi, &mut e), GLINT_OK);
                let sampled = glint_sample(closure, wo, 0.3, 0.6, 0.2, &mut s);
                assert!(
                    sampled == GLINT_OK || sampled == GLINT_NO_SAMPLE,
                    "sample: {sampled}"
                );
                assert_eq!(glint_albedo(closure, wo, albedo.as_mut_ptr()), GLINT_OK);
            }
            finite(
                &[e.value[0], e.value[1], e.value[2], e.pdf, e.pdf_reverse],
                "eval",
                &text,
            );
            finite(
                &[s.value[0], s.value[1], s.value[2], s.pdf],
                "sample",
                &text,
            );
            finite(&s.weight, "sample weight", &text);
            finite(&albedo, "albedo", &text);
        }
    }
    // SAFETY: created above, destroyed once.
    unsafe { glint_arena_destroy(arena) };
});
