//! Small vector types over a lane: [`Vec3`] for directions, [`Rgb`] for spectra.

use super::lane::{Lane, Mask};
use std::ops::{Add, Mul, Neg, Sub};

/// A 3-vector with one lane per component.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3<L> {
    pub x: L,
    pub y: L,
    pub z: L,
}

/// Squared lengths within this of 1 are normalized by [`inv_length`]'s series.
const NEAR_UNIT: f32 = 1.0 / 1024.0;

/// Squared lengths within this of 1 (four ulps of 1.0; a direction normalized in f32
/// lands there) are unit as they are ([`Vec3::unit_from`]).
const UNIT: f32 = 4.0 * f32::EPSILON;

/// `1 / sqrt(len2)`, the scale that normalizes a vector of squared length `len2` (0 for
/// 0). Near 1 (`|len2 - 1| <= 2^-10`: every direction a renderer or a sampler hands
/// over) it is the series `1 - e/2 + 3e^2/8 - 5e^3/16` in `e = len2 - 1`, whose
/// truncation error is below 3e-13, so that it is within an ulp of the exact form
/// without a division or a square root; elsewhere the exact form. The same operations on
/// every lane type (no fused multiply-add), so scalar and batch calls agree bit for bit,
/// and a register whose lanes are all near 1 does no division or square root.
#[inline(always)]
pub fn inv_length<L: Lane>(len2: L) -> L {
    let e = len2 - L::one();
    let series = L::one() + e * (L::splat(-0.5) + e * (L::splat(0.375) + e * L::splat(-0.3125)));
    let near = e.abs().le(L::splat(NEAR_UNIT));
    if near.all() {
        return series;
    }
    L::select(near, series, L::one().safe_div(len2.sqrt()))
}

impl<L: Lane> Vec3<L> {
    #[inline(always)]
    pub fn new(x: L, y: L, z: L) -> Self {
        Self { x, y, z }
    }
    #[inline(always)]
    pub fn splat(x: f32, y: f32, z: f32) -> Self {
        Self::new(L::splat(x), L::splat(y), L::splat(z))
    }
    /// Products rounded before the sum, never fused, so that every lane type rounds as
    /// the scalar `f32` lane does: staged and local directions and half vectors have
    /// the same bits in the batch kernels as in the scalar calls. An ulp matters: a
    /// half vector's slope is a difference of nearly opposite unit vectors over
    /// `cos_o + cos_i`, which a narrow lobe at a grazing angle turns into any factor
    /// (a fused dot made the AVX2 eval 1e23 times off; `tests/simd_bound.rs`).
    #[inline(always)]
    pub fn dot(self, o: Self) -> L {
        self.x * o.x + (self.y * o.y + self.z * o.z)
    }
    /// [`Self::dot`] by multiply-adds (one rounding fewer per term, and fewer
    /// instructions), for the uses whose rounding nothing amplifies: sums of squares,
    /// and cosines a lobe only scales by (never a half vector's or a direction's).
    #[inline(always)]
    pub fn dot_fused(self, o: Self) -> L {
        self.x.mul_add(o.x, self.y.mul_add(o.y, self.z * o.z))
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    #[inline(always)]
    pub fn length_squared(self) -> L {
        self.dot(self)
    }
    /// Unit vector; a zero vector stays zero instead of becoming NaN.
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * inv_length(self.length_squared())
    }
    /// A caller's direction `self`, of squared length `len2`, made unit: as it is where
    /// `len2` is within [`UNIT`] of 1 (scaling would move it by about an ulp, no closer
    /// to unit), else times [`inv_length`]. The same rule on every lane type, so scalar
    /// and batch calls agree bit for bit; a register whose lanes are all unit does no
    /// arithmetic beyond the test. Not for a sampled direction's own normalization:
    /// its length differs between ISAs by an ulp (`rsqrt`), and the rule's threshold
    /// would pass one and scale the other (an index-matched dielectric, eta 1.0002, turned that into a
    /// sample valid on AVX2 only; tests/simd_bound.rs).
    #[inline(always)]
    pub fn unit_from(self, len2: L) -> Self {
        let unit = (len2 - L::one()).abs().le(L::splat(UNIT));
        if unit.all() {
            return self;
        }
        Vec3::select(unit, self, self * inv_length(len2))
    }
    /// Unit vector through the lane's `rsqrt` (a hardware estimate and one Newton
    /// step: relative error 2.1e-7 at most, tests/vmath.rs), for sampled directions
    /// that no later result must reproduce bit for bit. `|self|^2` must be a normal
    /// float: legacy AVX2 estimates treat subnormals as zero.
    #[inline(always)]
    pub fn normalize_estimate(self) -> Self {
        self * self.length_squared().rsqrt()
    }
    #[inline(always)]
    pub fn select(mask: L::Mask, a: Self, b: Self) -> Self {
        Self::new(
            L::select(mask, a.x, b.x),
            L::select(mask, a.y, b.y),
            L::select(mask, a.z, b.z),
        )
    }
    /// Mirror `self` about `n`: `2 (self.n) n - self` (both pointing away from the surface).
    #[inline(always)]
    pub fn reflect(self, n: Self) -> Self {
        n * (L::splat(2.0) * self.dot(n)) - self
    }
}

impl<L: Lane> Add for Vec3<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<L: Lane> Sub for Vec3<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<L: Lane> Mul<L> for Vec3<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: L) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}
impl<L: Lane> Neg for Vec3<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

/// Linear RGB with one lane per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb<L> {
    pub r: L,
    pub g: L,
    pub b: L,
}

impl<L: Lane> Rgb<L> {
    #[inline(always)]
    pub fn new(r: L, g: L, b: L) -> Self {
        Self { r, g, b }
    }
    #[inline(always)]
    pub fn splat(v: L) -> Self {
        Self::new(v, v, v)
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat(L::zero())
    }
    #[inline(always)]
    pub fn to_array(self) -> [L; 3] {
        [self.r, self.g, self.b]
    }
    #[inline(always)]
    pub fn from_array(c: [L; 3]) -> Self {
        Self::new(c[0], c[1], c[2])
    }
    /// Apply `f` to each channel.
    #[inline(always)]
    pub fn map(self, f: impl Fn(L) -> L) -> Self {
        Self::new(f(self.r), f(self.g), f(self.b))
    }
    /// Combine two colors channel by channel.
    #[inline(always)]
    pub fn zip(self, o: Self, f: impl Fn(L, L) -> L) -> Self {
        Self::new(f(self.r, o.r), f(self.g, o.g), f(self.b, o.b))
    }
    #[inline(always)]
    pub fn select(mask: L::Mask, a: Self, b: Self) -> Self {
        a.zip(
            b,
            #[inline(always)]
            |x, y| L::select(mask, x, y),
        )
    }
    /// The lanes where some channel is > 0.
    #[inline(always)]
    pub fn any_positive(self) -> L::Mask {
        let zero = L::zero();
        self.r.gt(zero) | self.g.gt(zero) | self.b.gt(zero)
    }
    /// Rec. 709 luminance.
    #[inline(always)]
    pub fn luminance(self) -> L {
        self.r * L::splat(0.2126) + self.g * L::splat(0.7152) + self.b * L::splat(0.0722)
    }
}

impl<L: Lane> Add for Rgb<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.zip(
            o,
            #[inline(always)]
            |a, b| a + b,
        )
    }
}
impl<L: Lane> Mul for Rgb<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.zip(
            o,
            #[inline(always)]
            |a, b| a * b,
        )
    }
}
impl<L: Lane> Mul<L> for Rgb<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: L) -> Self {
        self.map(
            #[inline(always)]
            |a| a * s,
        )
    }
}

impl Vec3<f32> {
    /// A unit vector from user input: rejects NaN, infinities and vectors too short
    /// to normalize reliably (length below 1e-12), naming `what` in the error.
    ///
    /// The common case is inlined: returned out of line, the `Result`'s narrow stores
    /// were read back as a wider load by the caller, a store-forwarding stall on every
    /// scalar call's directions.
    #[inline(always)]
    pub fn try_unit(x: f32, y: f32, z: f32, what: &str) -> Result<Self, crate::error::Error> {
        // The batch kernels' rule, so scalar and batch calls see the same directions;
        // a squared length in range implies finite components.
        let v = Vec3::new(x, y, z);
        let len2 = v.length_squared();
        if (1e-24..=1e24).contains(&len2) {
            return Ok(v.unit_from(len2));
        }
        Self::try_unit_far(x, y, z, what)
    }

    /// [`Self::try_unit`] outside the squared-length range: an error for a non-finite
    /// or too short vector; lengths far from 1 normalized in f64 so they neither
    /// underflow nor overflow.
    #[cold]
    #[inline(never)]
    fn try_unit_far(x: f32, y: f32, z: f32, what: &str) -> Result<Self, crate::error::Error> {
        use crate::error::{Error, Status};
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(Error::new(
                Status::InvalidArgument,
                format!("{what} = ({x}, {y}, {z}) is not finite"),
            ));
        }
        let (dx, dy, dz) = (f64::from(x), f64::from(y), f64::from(z));
        let len = (dx * dx + dy * dy + dz * dz).sqrt();
        if len < 1e-12 {
            return Err(Error::new(
                Status::InvalidArgument,
                format!("{what} = ({x}, {y}, {z}) has zero length"),
            ));
        }
        Ok(Vec3::new(
            (dx / len) as f32,
            (dy / len) as f32,
            (dz / len) as f32,
        ))
    }
}
