//! Glint: an embeddable BSDF shading runtime for host renderers.
//!
//! Module map (see ARCHITECTURE.md for the data flow):

pub mod albedo_table;
pub mod batch;
pub mod closure;
pub mod error;
pub mod ffi;
pub mod fresnel;
pub mod json;
pub mod kernels;
pub mod lobes;
pub mod materials;
pub mod math;
pub mod microfacet;
pub mod params;
pub mod plugin;
pub mod registry;
pub mod runtime;
pub mod simd;
pub mod verify;

pub use closure::{Arena, Closure, EvalResult, SampleResult};
pub use error::{Error, Status};
pub use runtime::Runtime;
