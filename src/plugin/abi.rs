//! Rust mirrors of `include/glint_plugin.h`, ABI versions 1 and 2. Field order and types
//! must match the header exactly: plugins set every `struct_size` from the C
//! compiler's `sizeof`, and the loader refuses sizes smaller than these (so the
//! C tests that load the example plugins check the two agree).

use std::ffi::c_char;

/// The newest plugin ABI version this library speaks (it loads every older one too).
pub const HOST_ABI_VERSION: u32 = 2;

pub const PARAM_FLOAT: u32 = 0;
pub const PARAM_RGB: u32 = 1;
pub const PARAM_ENUM: u32 = 2;

pub const EVENT_TRANSMITTED: u32 = 1;
pub const EVENT_DELTA: u32 = 2;

#[repr(C)]
pub struct Param {
    pub name: *const c_char,
    pub kind: u32,
    pub offset: u32,
    pub default_value: [f32; 3],
    pub min: f32,
    pub max: f32,
    pub choices: *const *const c_char,
    pub choice_count: u32,
    pub doc: *const c_char,
}

#[repr(C)]
#[derive(Default)]
pub struct Sample {
    pub wi: [f32; 3],
    pub value: [f32; 3],
    pub pdf: f32,
    pub events: u32,
    pub eta: f32,
    pub roughness: f32,
}

#[repr(C)]
pub struct EvalBatch {
    pub struct_size: u32,
    pub transport: u32,
    pub count: usize,
    pub params: *const *const std::ffi::c_void,
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
}

pub type EvalFn = unsafe extern "C" fn(
    params: *const std::ffi::c_void,
    wo: *const [f32; 3],
    wi: *const [f32; 3],
    transport: u32,
    value: *mut [f32; 3],
    pdf: *mut f32,
);
pub type SampleFn = unsafe extern "C" fn(
    params: *const std::ffi::c_void,
    wo: *const [f32; 3],
    u: *const [f32; 3],
    transport: u32,
    out: *mut Sample,
) -> i32;
pub type AlbedoFn = unsafe extern "C" fn(
    params: *const std::ffi::c_void,
    wo: *const [f32; 3],
    transport: u32,
    albedo: *mut [f32; 3],
);
pub type EvalBatchFn = unsafe extern "C" fn(batch: *const EvalBatch);

#[repr(C)]
pub struct LobeV1 {
    pub struct_size: u32,
    pub name: *const c_char,
    pub summary: *const c_char,
    pub flags: u32,
    pub reciprocal: u32,
    pub params: *const Param,
    pub param_count: u32,
    pub block_size: u32,
    pub block_align: u32,
    pub eval: Option<EvalFn>,
    pub sample: Option<SampleFn>,
    pub albedo: Option<AlbedoFn>,
    pub eval_batch: Option<EvalBatchFn>,
}

#[repr(C)]
pub struct PluginV1 {
    pub struct_size: u32,
    pub name: *const c_char,
    pub lobe_count: u32,
    pub lobes: *const LobeV1,
}

/// `glint_plugin_sample_v2`: V1's fields after `struct_size`, then class and component.
#[repr(C)]
#[derive(Default)]
pub struct SampleV2 {
    pub struct_size: u32,
    pub wi: [f32; 3],
    pub value: [f32; 3],
    pub pdf: f32,
    pub events: u32,
    pub eta: f32,
    pub roughness: f32,
    pub sample_class: u32,
    pub component: u32,
}

pub type SampleV2Fn = unsafe extern "C" fn(
    params: *const std::ffi::c_void,
    wo: *const [f32; 3],
    u: *const [f32; 3],
    transport: u32,
    out: *mut SampleV2,
) -> i32;

#[repr(C)]
pub struct LobeV2 {
    pub struct_size: u32,
    pub name: *const c_char,
    pub summary: *const c_char,
    pub flags: u32,
    pub reciprocal: u32,
    pub params: *const Param,
    pub param_count: u32,
    pub block_size: u32,
    pub block_align: u32,
    pub eval: Option<EvalFn>,
    pub sample: Option<SampleV2Fn>,
    pub albedo: Option<AlbedoFn>,
    pub eval_batch: Option<EvalBatchFn>,
    pub component_count: u32,
}

#[repr(C)]
pub struct PluginV2 {
    pub struct_size: u32,
    pub name: *const c_char,
    pub lobe_count: u32,
    pub lobes: *const LobeV2,
}

pub type EntryFn = unsafe extern "C" fn(
    host_abi_version: u32,
    plugin_abi_version: *mut u32,
    table: *mut *const std::ffi::c_void,
) -> i32;
