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

/// `(sin, cos)` of the azimuth `2 pi u` of a sampler's random number `u` in [0, 1], the
/// turn taken as `u - round(u)` in [-1/2, 1/2] (exact) and kept in turns
/// ([`vmath::sin_cos_turn`]): `2 pi u` rounded in f32 is off by up to 4.8e-7 near a
/// full turn, as far as `u = 1 - 2^-24` is from it. Every sampler takes its azimuth
/// so, and a fused sample computes one pair. The same code on every lane type.
#[inline(always)]
pub fn azimuth<L: Lane>(u: L) -> (L, L) {
    vmath::sin_cos_turn(u - u.round())
}
