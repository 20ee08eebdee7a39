//! The lane abstraction: every lobe is written once against [`Lane`], a value
//! that holds one `f32` per SIMD lane. The scalar path instantiates it with
//! plain `f32`; the SIMD batch kernels add vector lane types that implement the
//! same trait, so no lobe is ever written twice.
//!
//! Control flow that differs per lane is written with masks and [`Lane::select`];
//! `Mask::any`/`Mask::all` let code skip work no lane needs.

use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Not, Sub, SubAssign};

/// Most lanes of any lane type (two AVX-512 registers, `simd::pair::Pair`).
pub const MAX_LANES: usize = 32;

/// Cells of a row [`Lane::row_adjacent`] reads (an albedo table's `cos_o` axis).
pub const ROW: usize = 64;

/// A per-lane boolean.
pub trait Mask: Copy + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self> {
    fn splat(value: bool) -> Self;
    /// Bit `j` set when lane `j` is set.
    fn bits(self) -> u32;
    /// True when at least one lane is set.
    fn any(self) -> bool;
    /// True when every lane is set.
    fn all(self) -> bool;
}

/// A per-lane `f32`, with the operations lobes need.
pub trait Lane:
    Copy
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    type Mask: Mask;
    /// The lane type of kernels bound by their dependency chains rather than by their
    /// arithmetic (a sample draws, settles and evaluates, each step waiting on
    /// divisions and square roots): two registers interleaved instruction by
    /// instruction on the SIMD lanes (`simd::pair::Pair`, the same bits), the scalar
    /// lane itself.
    type Interleaved: Lane;
    /// Number of `f32` lanes (1 for the scalar lane).
    const LANES: usize;

    fn splat(value: f32) -> Self;
    /// The first `LANES` values of `src`.
    fn load(src: &[f32]) -> Self;
    /// Write the lanes to the first `LANES` values of `dst`.
    fn store(self, dst: &mut [f32]);
    /// The first `n < LANES` values of `src` and `fill` in the other lanes (a masked
    /// tail: nothing past `src[n - 1]` is read).
    #[inline(always)]
    fn load_tail(src: &[f32], n: usize, fill: f32) -> Self {
        let mut lanes = [fill; MAX_LANES];
        lanes[..n].copy_from_slice(&src[..n]);
        Self::load(&lanes)
    }
    /// Write the first `n < LANES` lanes to `dst[..n]` (nothing else is written).
    #[inline(always)]
    fn store_tail(self, dst: &mut [f32], n: usize) {
        let mut lanes = [0.0; MAX_LANES];
        self.store(&mut lanes);
        dst[..n].copy_from_slice(&lanes[..n]);
    }
    fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self;

    fn lt(self, other: Self) -> Self::Mask;
    fn le(self, other: Self) -> Self::Mask;
    fn gt(self, other: Self) -> Self::Mask;
    fn ge(self, other: Self) -> Self::Mask;
    fn eq(self, other: Self) -> Self::Mask;
    /// Lanes that are neither NaN nor infinite.
    fn is_finite(self) -> Self::Mask;

    fn abs(self) -> Self;
    fn min(self, other: Self) -> Self;
    fn max(self, other: Self) -> Self;
    /// `self * a + b`, fused where the ISA has FMA.
    fn mul_add(self, a: Self, b: Self) -> Self;
    fn sqrt(self) -> Self;
    /// `1 / sqrt(self)` for a positive normal float (tests/vmath.rs); SIMD lanes give
    /// NaN at 0 and may treat subnormals as 0.
    fn rsqrt(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    /// `ln(1 + self)`, accurate for small arguments.
    fn ln_1p(self) -> Self;
    fn sin_cos(self) -> (Self, Self);
    /// `acos` of `self` clamped to [-1, 1] (round-off outside is not NaN).
    fn acos(self) -> Self;
    /// `atan2(self, x)`: the angle of the point `(x, self)`, in [-pi, pi].
    fn atan2(self, x: Self) -> Self;
    /// `self^e` for `self >= 0`.
    fn pow(self, e: Self) -> Self;
    fn copysign(self, sign: Self) -> Self;
    /// The value of the first lane. Used only for parameters that are uniform across
    /// a batch group (enumerated choices), which the batch layer guarantees.
    fn lane0(self) -> f32;
    fn floor(self) -> Self;
    /// Round to the nearest integer, ties to even.
    fn round(self) -> Self;
    /// `self * 2^e` for integral `e` in [-126, 127] (the building block of `exp`).
    fn ldexp(self, e: Self) -> Self;
    /// `(m, e)` with `self = m * 2^e`, `m` in [1, 2) and `e` integral, for finite
    /// positive normal `self` (the building block of `ln`); other inputs give
    /// unspecified finite values.
    fn frexp(self) -> (Self, Self);
    /// `table[index]` per lane; `index` holds integral values in `0..table.len()`.
    fn gather(table: &[f32], index: Self) -> Self;
    /// `table[index]` and `table[index + 1]` per lane (`index + 1 < table.len()`): two
    /// cells adjacent along a table's stride-1 axis, which the SIMD lanes read with one
    /// 64-bit gather per lane instead of two 32-bit ones.
    #[inline(always)]
    fn gather_adjacent(table: &[f32], index: Self) -> [Self; 2] {
        [
            Self::gather(table, index),
            Self::gather(table, index + Self::one()),
        ]
    }
    /// [`Lane::gather_adjacent`] within one row of [`ROW`] cells (`index` in
    /// `0..ROW - 1`): the same values, which AVX-512 picks from four registers by
    /// permutes instead of a gather (a table row shared by every lane, such as one
    /// roughness's row of an albedo table).
    #[inline(always)]
    fn row_adjacent(row: &[f32; ROW], index: Self) -> [Self; 2] {
        Self::gather_adjacent(row, index)
    }
    /// The lanes where `mask` is set, in lane order, moved to the front; the other
    /// lanes are unspecified.
    fn compress(self, mask: Self::Mask) -> Self;
    /// The inverse of [`Lane::compress`]: the first `mask.bits().count_ones()` lanes, in
    /// order, moved to the lanes where `mask` is set; the other lanes zero.
    fn expand(self, mask: Self::Mask) -> Self;
    /// The two 16-bit codes packed little-endian in `table[index]` (low, high), as
    /// integral `f32`; `index` as for [`Lane::gather`]. One gather reads a pair of
    /// fixed-point table channels (the Disney specular's `A` and `B`).
    fn gather_code_pair(table: &[u32], index: Self) -> (Self, Self);
    /// [`Lane::gather_code_pair`] at `index` and `index + 1`, as
    /// [`Lane::gather_adjacent`] reads them.
    #[inline(always)]
    fn gather_code_pairs_adjacent(table: &[u32], index: Self) -> [(Self, Self); 2] {
        [
            Self::gather_code_pair(table, index),
            Self::gather_code_pair(table, index + Self::one()),
        ]
    }
    /// `table[index + k]` for `k` in `0..K`: each lane's row of `K` consecutive values
    /// (`index + K <= table.len()`). The scalar lane reads the row as one slice.
    #[inline(always)]
    fn gather_row<const K: usize>(table: &[f32], index: Self) -> [Self; K] {
        let mut row = [Self::zero(); K];
        for (k, v) in row.iter_mut().enumerate() {
            *v = Self::gather(table, index + Self::splat(k as f32));
        }
        row
    }

    #[inline(always)]
    fn zero() -> Self {
        Self::splat(0.0)
    }
    #[inline(always)]
    fn one() -> Self {
        Self::splat(1.0)
    }
    #[inline(always)]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
    #[inline(always)]
    fn sqr(self) -> Self {
        self * self
    }
    /// `sqrt(max(self, 0))`: never NaN for slightly negative round-off.
    #[inline(always)]
    fn safe_sqrt(self) -> Self {
        self.max(Self::zero()).sqrt()
    }
    /// `self / d` where `d != 0`, else 0. Keeps guarded divisions readable.
    #[inline(always)]
    fn safe_div(self, d: Self) -> Self {
        let nonzero = d.abs().gt(Self::zero());
        Self::select(
            nonzero,
            self / Self::select(nonzero, d, Self::one()),
            Self::zero(),
        )
    }
}

impl Mask for bool {
    #[inline(always)]
    fn splat(value: bool) -> Self {
        value
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self)
    }
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
}

impl Lane for f32 {
    type Mask = bool;
    type Interleaved = f32;
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(value: f32) -> Self {
        value
    }
    #[inline(always)]
    fn load(src: &[f32]) -> Self {
        src[0]
    }
    #[inline(always)]
    fn store(self, dst: &mut [f32]) {
        dst[0] = self;
    }
    #[inline(always)]
    fn select(mask: bool, if_true: Self, if_false: Self) -> Self {
        if mask { if_true } else { if_false }
    }
    #[inline(always)]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[inline(always)]
    fn le(self, other: Self) -> bool {
        self <= other
    }
    #[inline(always)]
    fn gt(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn ge(self, other: Self) -> bool {
        self >= other
    }
    #[inline(always)]
    fn eq(self, other: Self) -> bool {
        self == other
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        f32::min(self, other)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        f32::max(self, other)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        // Plain multiply-add: `f32::mul_add` is a libm call without FMA in the baseline ISA.
        self * a + b
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        1.0 / f32::sqrt(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        f32::exp(self)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        f32::ln(self)
    }
    #[inline(always)]
    fn ln_1p(self) -> Self {
        f32::ln_1p(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        f32::sin_cos(self)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        // Clamped as `vmath::acos` is: round-off just outside [-1, 1] is not NaN.
        f32::acos(self.clamp(-1.0, 1.0))
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        f32::atan2(self, x)
    }
    #[inline(always)]
    fn pow(self, e: Self) -> Self {
        f32::powf(self, e)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }
    #[inline(always)]
    fn lane0(self) -> f32 {
        self
    }
    #[inline(always)]
    fn floor(self) -> Self {
        // By truncation: `f32::floor` is a libm call without SSE4.1 in the baseline ISA
        // (table lookups floor each axis). Beyond 2^23 (and for NaN) `self` is integral.
        if self.abs() < 8_388_608.0 {
            let t = self as i32 as f32;
            if t > self { t - 1.0 } else { t }
        } else {
            self
        }
    }
    #[inline(always)]
    fn round(self) -> Self {
        f32::round_ties_even(self)
    }
    #[inline(always)]
    fn ldexp(self, e: Self) -> Self {
        // 2^e built from its exponent bits: exact for e in [-126, 127].
        self * f32::from_bits(((e as i32 + 127) as u32) << 23)
    }
    #[inline(always)]
    fn frexp(self) -> (Self, Self) {
        let bits = self.to_bits();
        let e = ((bits >> 23) & 0xff) as i32 - 127;
        (f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000), e as f32)
    }
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        table[index as usize]
    }
    #[inline(always)]
    fn compress(self, _mask: bool) -> Self {
        self
    }
    #[inline(always)]
    fn expand(self, mask: bool) -> Self {
        if mask { self } else { 0.0 }
    }
    #[inline(always)]
    fn gather_code_pair(table: &[u32], index: Self) -> (Self, Self) {
        let pair = table[index as usize];
        ((pair & 0xffff) as f32, (pair >> 16) as f32)
    }
    #[inline(always)]
    fn gather_row<const K: usize>(table: &[f32], index: Self) -> [Self; K] {
        let at = index as usize;
        let mut row = [0.0; K];
        row.copy_from_slice(&table[at..at + K]);
        row
    }
}
