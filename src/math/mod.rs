//! Math on lanes: the [`Lane`] trait, vectors and colors over it, shading frames,
//! and special functions.

pub mod frame;
pub mod lane;
pub mod special;
pub mod vec;
pub mod vmath;

pub use frame::{Frame, LaneFrame};
pub use lane::{Lane, Mask};
pub use vec::{Rgb, Vec3, inv_length};

pub const PI: f32 = std::f32::consts::PI;
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
