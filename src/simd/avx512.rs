//! The AVX-512 lane: sixteen `f32` in a `__m512`, masks in a `__mmask16`.
//! Only AVX-512 Foundation instructions are used (integer forms for bit logic,
//! since the `_ps` logic ops need AVX-512DQ).

use super::{compound_assign, elementary_functions_from_vmath, intrinsic, newton_rsqrt};
use crate::math::lane::ROW;
use crate::math::{Lane, Mask};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Sixteen `f32` lanes.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct F32x16(__m512);

/// Sixteen lane flags, one bit each.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct M16(__mmask16);

macro_rules! binary_op {
    ($trait:ident $method:ident $intr:ident) => {
        impl $trait for F32x16 {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                F32x16(intrinsic!($intr(self.0, o.0)))
            }
        }
    };
}

binary_op!(Add add _mm512_add_ps);
binary_op!(Sub sub _mm512_sub_ps);
binary_op!(Mul mul _mm512_mul_ps);
binary_op!(Div div _mm512_div_ps);
compound_assign!(F32x16);

impl F32x16 {
    /// Integral lane values as indices into a table of `len` elements, clamped into it
    /// so no gather can read outside it (NaN -> 0).
    #[inline(always)]
    fn table_index(self, len: usize) -> __m512i {
        assert!(len > 0 && len <= i32::MAX as usize);
        intrinsic!(_mm512_min_epi32(
            _mm512_max_epi32(_mm512_cvttps_epi32(self.0), _mm512_setzero_si512()),
            _mm512_set1_epi32(len as i32 - 1)
        ))
    }
    #[inline(always)]
    fn bits(self) -> __m512i {
        intrinsic!(_mm512_castps_si512(self.0))
    }
    #[inline(always)]
    fn from_bits(bits: __m512i) -> Self {
        F32x16(intrinsic!(_mm512_castsi512_ps(bits)))
    }
    #[inline(always)]
    fn cmp<const OP: i32>(self, o: Self) -> M16 {
        M16(intrinsic!(_mm512_cmp_ps_mask::<OP>(self.0, o.0)))
    }
}

const SIGN: i32 = i32::MIN;

impl Neg for F32x16 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::from_bits(intrinsic!(_mm512_xor_si512(
            self.bits(),
            _mm512_set1_epi32(SIGN)
        )))
    }
}

impl BitAnd for M16 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        M16(self.0 & o.0)
    }
}
impl BitOr for M16 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        M16(self.0 | o.0)
    }
}
impl Not for M16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        M16(!self.0)
    }
}

impl Mask for M16 {
    #[inline(always)]
    fn splat(value: bool) -> Self {
        M16(if value { 0xffff } else { 0 })
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self.0)
    }
    #[inline(always)]
    fn any(self) -> bool {
        self.0 != 0
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.0 == 0xffff
    }
}

impl Lane for F32x16 {
    type Mask = M16;
    type Interleaved = super::pair::Pair<Self>;
    const LANES: usize = 16;

    #[inline(always)]
    fn splat(value: f32) -> Self {
        F32x16(intrinsic!(_mm512_set1_ps(value)))
    }
    #[inline(always)]
    fn load(src: &[f32]) -> Self {
        let src = &src[..16];
        F32x16(intrinsic!(_mm512_loadu_ps(src.as_ptr())))
    }
    #[inline(always)]
    fn store(self, dst: &mut [f32]) {
        let dst = &mut dst[..16];
        intrinsic!(_mm512_storeu_ps(dst.as_mut_ptr(), self.0))
    }
    #[inline(always)]
    fn select(mask: M16, if_true: Self, if_false: Self) -> Self {
        F32x16(intrinsic!(_mm512_mask_blend_ps(
            mask.0, if_false.0, if_true.0
        )))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M16 {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M16 {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M16 {
        self.cmp::<_CMP_GT_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M16 {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M16 {
        self.cmp::<_CMP_EQ_OQ>(o)
    }
    #[inline(always)]
    fn is_finite(self) -> M16 {
        self.abs().lt(Self::splat(f32::INFINITY))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F32x16(intrinsic!(_mm512_abs_ps(self.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // As minps: a NaN `self` gives `o`, as `f32::min` does.
        F32x16(intrinsic!(_mm512_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F32x16(intrinsic!(_mm512_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        F32x16(intrinsic!(_mm512_fmadd_ps(self.0, a.0, b.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F32x16(intrinsic!(_mm512_sqrt_ps(self.0)))
    }
    /// The 14-bit hardware estimate refined by one Newton step (see `newton_rsqrt`).
    #[inline(always)]
    fn rsqrt(self) -> Self {
        let y = F32x16(intrinsic!(_mm512_rsqrt14_ps(self.0)));
        newton_rsqrt(self, y)
    }
    elementary_functions_from_vmath!();
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        // Ternary logic 0xE4 = (C & A) | (!C & B) with C the sign mask: sign bit from
        // `sign`, the rest from `self`.
        Self::from_bits(intrinsic!(_mm512_ternarylogic_epi32::<0xE4>(
            sign.bits(),
            self.bits(),
            _mm512_set1_epi32(SIGN)
        )))
    }
    #[inline(always)]
    fn lane0(self) -> f32 {
        intrinsic!(_mm512_cvtss_f32(self.0))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        F32x16(intrinsic!(_mm512_roundscale_ps::<
            { _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC },
        >(self.0)))
    }
    #[inline(always)]
    fn round(self) -> Self {
        F32x16(intrinsic!(_mm512_roundscale_ps::<
            { _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC },
        >(self.0)))
    }
    #[inline(always)]
    fn ldexp(self, e: Self) -> Self {
        F32x16(intrinsic!(_mm512_scalef_ps(self.0, e.0)))
    }
    #[inline(always)]
    fn frexp(self) -> (Self, Self) {
        let mantissa = intrinsic!(_mm512_getmant_ps::<_MM_MANT_NORM_1_2, _MM_MANT_SIGN_ZERO>(
            self.0
        ));
        let exponent = intrinsic!(_mm512_getexp_ps(self.0));
        (F32x16(mantissa), F32x16(exponent))
    }
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        let index = index.table_index(table.len());
        F32x16(intrinsic!(_mm512_i32gather_ps::<4>(index, table.as_ptr())))
    }
    #[inline(always)]
    fn gather_adjacent(table: &[f32], index: Self) -> [Self; 2] {
        // No `map`: its closure would be a function without the kernel's target
        // features (tests/simd_inlining.rs).
        let [first, second] = adjacent_cells(table.as_ptr().cast(), table.len(), index);
        [
            F32x16(intrinsic!(_mm512_castsi512_ps(first))),
            F32x16(intrinsic!(_mm512_castsi512_ps(second))),
        ]
    }
    #[inline(always)]
    fn row_adjacent(row: &[f32; ROW], index: Self) -> [Self; 2] {
        let first = index.table_index(ROW - 1);
        let second = intrinsic!(_mm512_add_epi32(first, _mm512_set1_epi32(1)));
        // No `map`: its closure would be a function without the kernel's target
        // features (tests/simd_inlining.rs).
        let quarters = [
            Self::load(&row[..]).0,
            Self::load(&row[16..]).0,
            Self::load(&row[32..]).0,
            Self::load(&row[48..]).0,
        ];
        [
            F32x16(pick_cell(&quarters, first)),
            F32x16(pick_cell(&quarters, second)),
        ]
    }
    #[inline(always)]
    fn compress(self, mask: M16) -> Self {
        F32x16(intrinsic!(_mm512_maskz_compress_ps(mask.0, self.0)))
    }
    #[inline(always)]
    fn expand(self, mask: M16) -> Self {
        F32x16(intrinsic!(_mm512_maskz_expand_ps(mask.0, self.0)))
    }
    #[inline(always)]
    fn gather_code_pair(table: &[u32], index: Self) -> (Self, Self) {
        let index = index.table_index(table.len());
        split_codes(intrinsic!(_mm512_i32gather_epi32::<4>(
            index,
            table.as_ptr().cast()
        )))
    }
    #[inline(always)]
    fn gather_code_pairs_adjacent(table: &[u32], index: Self) -> [(Self, Self); 2] {
        let [first, second] = adjacent_cells(table.as_ptr(), table.len(), index);
        [split_codes(first), split_codes(second)]
    }
}

/// Cell `index` (in `0..ROW`) of a row held as four registers: each half of the row
/// picked by one two-register permute, the half chosen by the index's bit 5.
#[inline(always)]
fn pick_cell(quarters: &[__m512; 4], index: __m512i) -> __m512 {
    let low = intrinsic!(_mm512_permutex2var_ps(quarters[0], index, quarters[1]));
    let high = intrinsic!(_mm512_permutex2var_ps(quarters[2], index, quarters[3]));
    let upper = intrinsic!(_mm512_test_epi32_mask(index, _mm512_set1_epi32(32)));
    intrinsic!(_mm512_mask_blend_ps(upper, low, high))
}

/// Each lane's 32-bit cells `index` and `index + 1` of a table of `len` cells at
/// `table`, by one 64-bit gather per lane; the first cell is clamped into
/// `0..len - 1`, so the read stays inside (`F32x16::table_index`).
#[inline(always)]
fn adjacent_cells(table: *const u32, len: usize, index: F32x16) -> [__m512i; 2] {
    assert!(len >= 2);
    let index = index.table_index(len - 1);
    let base = table.cast::<i64>();
    // Lanes 0-7 and 8-15, each lane's two cells in its 64 bits (the first low).
    let low = intrinsic!(_mm512_i32gather_epi64::<4>(
        _mm512_castsi512_si256(index),
        base
    ));
    let high = intrinsic!(_mm512_i32gather_epi64::<4>(
        _mm512_extracti64x4_epi64::<1>(index),
        base
    ));
    let first = intrinsic!(_mm512_setr_epi32(
        0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30
    ));
    let second = intrinsic!(_mm512_add_epi32(first, _mm512_set1_epi32(1)));
    [
        intrinsic!(_mm512_permutex2var_epi32(low, first, high)),
        intrinsic!(_mm512_permutex2var_epi32(low, second, high)),
    ]
}

/// The two 16-bit codes of each lane's `u32` (low, high), as integral `f32`.
#[inline(always)]
fn split_codes(pair: __m512i) -> (F32x16, F32x16) {
    let low = intrinsic!(_mm512_and_si512(pair, _mm512_set1_epi32(0xffff)));
    let high = intrinsic!(_mm512_srli_epi32::<16>(pair));
    (
        F32x16(intrinsic!(_mm512_cvtepi32_ps(low))),
        F32x16(intrinsic!(_mm512_cvtepi32_ps(high))),
    )
}
