//! The AVX2 + FMA lane: eight `f32` in a `__m256`, masks as all-ones lanes.

use super::{elementary_functions_from_vmath, intrinsic, newton_rsqrt};
use crate::math::{Lane, Mask};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Eight `f32` lanes.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct F32x8(__m256);

/// Eight lane flags (all bits set or clear per lane).
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct M32x8(__m256);

macro_rules! binary_op {
    ($trait:ident $method:ident $intr:ident) => {
        impl $trait for F32x8 {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                F32x8(intrinsic!($intr(self.0, o.0)))
            }
        }
    };
}

binary_op!(Add add _mm256_add_ps);
binary_op!(Sub sub _mm256_sub_ps);
binary_op!(Mul mul _mm256_mul_ps);
binary_op!(Div div _mm256_div_ps);
super::compound_assign!(F32x8);

impl Neg for F32x8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        F32x8(intrinsic!(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))))
    }
}

impl BitAnd for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        M32x8(intrinsic!(_mm256_and_ps(self.0, o.0)))
    }
}
impl BitOr for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        M32x8(intrinsic!(_mm256_or_ps(self.0, o.0)))
    }
}
impl Not for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        M32x8(intrinsic!(_mm256_xor_ps(
            self.0,
            _mm256_castsi256_ps(_mm256_set1_epi32(-1))
        )))
    }
}

impl Mask for M32x8 {
    #[inline(always)]
    fn splat(value: bool) -> Self {
        M32x8(intrinsic!(_mm256_castsi256_ps(_mm256_set1_epi32(
            -i32::from(value)
        ))))
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        intrinsic!(_mm256_movemask_ps(self.0)) as u32
    }
    #[inline(always)]
    fn any(self) -> bool {
        self.bits() != 0
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.bits() == 0xff
    }
}

/// `_mm256_permutevar8x32_ps` indices for `compress` under each 8-bit mask: the set
/// lanes in order, then lane 0.
static COMPRESS: [[i32; 8]; 256] = permutations(false);
/// ... and for `expand`: each set lane takes the next lane from the front.
static EXPAND: [[i32; 8]; 256] = permutations(true);

const fn permutations(expand: bool) -> [[i32; 8]; 256] {
    let mut table = [[0; 8]; 256];
    let mut mask = 0;
    while mask < 256 {
        let (mut lane, mut next) = (0, 0);
        while lane < 8 {
            if mask >> lane & 1 == 1 {
                if expand {
                    table[mask][lane] = next;
                } else {
                    table[mask][next as usize] = lane as i32;
                }
                next += 1;
            }
            lane += 1;
        }
        mask += 1;
    }
    table
}

impl F32x8 {
    /// Integral lane values as indices into a table of `len` elements, clamped into it
    /// so no gather can read outside it (NaN -> 0).
    #[inline(always)]
    fn table_index(self, len: usize) -> __m256i {
        assert!(len > 0 && len <= i32::MAX as usize);
        intrinsic!(_mm256_min_epi32(
            _mm256_max_epi32(_mm256_cvttps_epi32(self.0), _mm256_setzero_si256()),
            _mm256_set1_epi32(len as i32 - 1)
        ))
    }
    #[inline(always)]
    fn cmp<const OP: i32>(self, o: Self) -> M32x8 {
        M32x8(intrinsic!(_mm256_cmp_ps::<OP>(self.0, o.0)))
    }
    #[inline(always)]
    fn bits(self) -> __m256i {
        intrinsic!(_mm256_castps_si256(self.0))
    }
}

impl Lane for F32x8 {
    type Mask = M32x8;
    type Interleaved = super::pair::Pair<Self>;
    const LANES: usize = 8;

    #[inline(always)]
    fn splat(value: f32) -> Self {
        F32x8(intrinsic!(_mm256_set1_ps(value)))
    }
    #[inline(always)]
    fn load(src: &[f32]) -> Self {
        let src = &src[..8];
        F32x8(intrinsic!(_mm256_loadu_ps(src.as_ptr())))
    }
    #[inline(always)]
    fn store(self, dst: &mut [f32]) {
        let dst = &mut dst[..8];
        intrinsic!(_mm256_storeu_ps(dst.as_mut_ptr(), self.0))
    }
    #[inline(always)]
    fn select(mask: M32x8, if_true: Self, if_false: Self) -> Self {
        F32x8(intrinsic!(_mm256_blendv_ps(if_false.0, if_true.0, mask.0)))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_GT_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_EQ_OQ>(o)
    }
    #[inline(always)]
    fn is_finite(self) -> M32x8 {
        self.abs().lt(Self::splat(f32::INFINITY))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F32x8(intrinsic!(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // minps returns its second operand when either is NaN: a NaN `self` gives `o`,
        // as `f32::min` does.
        F32x8(intrinsic!(_mm256_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        F32x8(intrinsic!(_mm256_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        F32x8(intrinsic!(_mm256_fmadd_ps(self.0, a.0, b.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F32x8(intrinsic!(_mm256_sqrt_ps(self.0)))
    }
    /// The 12-bit hardware estimate refined by one Newton step: relative error
    /// below 2.5e-7 for normal positive inputs (measured in tests/vmath.rs);
    /// 0 -> inf, inf -> 0, negative -> NaN.
    #[inline(always)]
    fn rsqrt(self) -> Self {
        let y = F32x8(intrinsic!(_mm256_rsqrt_ps(self.0)));
        newton_rsqrt(self, y)
    }
    elementary_functions_from_vmath!();
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        let s = intrinsic!(_mm256_set1_ps(-0.0));
        F32x8(intrinsic!(_mm256_or_ps(
            _mm256_andnot_ps(s, self.0),
            _mm256_and_ps(s, sign.0)
        )))
    }
    #[inline(always)]
    fn lane0(self) -> f32 {
        intrinsic!(_mm256_cvtss_f32(self.0))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        F32x8(intrinsic!(_mm256_round_ps::<
            { _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC },
        >(self.0)))
    }
    #[inline(always)]
    fn round(self) -> Self {
        F32x8(intrinsic!(_mm256_round_ps::<
            { _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC },
        >(self.0)))
    }
    #[inline(always)]
    fn ldexp(self, e: Self) -> Self {
        let biased = intrinsic!(_mm256_add_epi32(
            _mm256_cvtps_epi32(e.0),
            _mm256_set1_epi32(127)
        ));
        let scale = intrinsic!(_mm256_castsi256_ps(_mm256_slli_epi32::<23>(biased)));
        self * F32x8(scale)
    }
    #[inline(always)]
    fn frexp(self) -> (Self, Self) {
        let bits = self.bits();
        let exponent = intrinsic!(_mm256_sub_epi32(
            _mm256_srli_epi32::<23>(_mm256_and_si256(bits, _mm256_set1_epi32(0x7f80_0000))),
            _mm256_set1_epi32(127)
        ));
        let mantissa = intrinsic!(_mm256_or_si256(
            _mm256_and_si256(bits, _mm256_set1_epi32(0x007f_ffff)),
            _mm256_set1_epi32(0x3f80_0000)
        ));
        (
            F32x8(intrinsic!(_mm256_castsi256_ps(mantissa))),
            F32x8(intrinsic!(_mm256_cvtepi32_ps(exponent))),
        )
    }
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        let index = index.table_index(table.len());
        F32x8(intrinsic!(_mm256_i32gather_ps::<4>(table.as_ptr(), index)))
    }
    #[inline(always)]
    fn gather_adjacent(table: &[f32], index: Self) -> [Self; 2] {
        let [first, second] = adjacent_cells(table.as_ptr().cast(), table.len(), index);
        [
            F32x8(intrinsic!(_mm256_castsi256_ps(first))),
            F32x8(intrinsic!(_mm256_castsi256_ps(second))),
        ]
    }
    #[inline(always)]
    fn compress(self, mask: M32x8) -> Self {
        let index = &COMPRESS[mask.bits() as usize];
        let index = intrinsic!(_mm256_loadu_si256(index.as_ptr().cast()));
        F32x8(intrinsic!(_mm256_permutevar8x32_ps(self.0, index)))
    }
    #[inline(always)]
    fn expand(self, mask: M32x8) -> Self {
        let index = &EXPAND[mask.bits() as usize];
        let index = intrinsic!(_mm256_loadu_si256(index.as_ptr().cast()));
        let spread = F32x8(intrinsic!(_mm256_permutevar8x32_ps(self.0, index)));
        Self::select(mask, spread, Self::zero())
    }
    #[inline(always)]
    fn gather_code_pair(table: &[u32], index: Self) -> (Self, Self) {
        let index = index.table_index(table.len());
        split_codes(intrinsic!(_mm256_i32gather_epi32::<4>(
            table.as_ptr().cast(),
            index
        )))
    }
    #[inline(always)]
    fn gather_code_pairs_adjacent(table: &[u32], index: Self) -> [(Self, Self); 2] {
        let [first, second] = adjacent_cells(table.as_ptr(), table.len(), index);
        [split_codes(first), split_codes(second)]
    }
}

/// Each lane's 32-bit cells `index` and `index + 1` of a table of `len` cells at
/// `table`, by one 64-bit gather per lane; the first cell is clamped into
/// `0..len - 1`, so the read stays inside (`F32x8::table_index`).
#[inline(always)]
fn adjacent_cells(table: *const u32, len: usize, index: F32x8) -> [__m256i; 2] {
    assert!(len >= 2);
    let index = index.table_index(len - 1);
    let base = table.cast::<i64>();
    // Lanes 0-3 and 4-7, each lane's two cells in its 64 bits (the first low).
    let low = intrinsic!(_mm256_i32gather_epi64::<4>(
        base,
        _mm256_castsi256_si128(index)
    ));
    let high = intrinsic!(_mm256_i32gather_epi64::<4>(
        base,
        _mm256_extracti128_si256::<1>(index)
    ));
    // Each half's first cells, then its second ones.
    let order = intrinsic!(_mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7));
    let low = intrinsic!(_mm256_permutevar8x32_epi32(low, order));
    let high = intrinsic!(_mm256_permutevar8x32_epi32(high, order));
    [
        intrinsic!(_mm256_permute2x128_si256::<0x20>(low, high)),
        intrinsic!(_mm256_permute2x128_si256::<0x31>(low, high)),
    ]
}

/// The two 16-bit codes of each lane's `u32` (low, high), as integral `f32`.
#[inline(always)]
fn split_codes(pair: __m256i) -> (F32x8, F32x8) {
    let low = intrinsic!(_mm256_and_si256(pair, _mm256_set1_epi32(0xffff)));
    let high = intrinsic!(_mm256_srli_epi32::<16>(pair));
    (
        F32x8(intrinsic!(_mm256_cvtepi32_ps(low))),
        F32x8(intrinsic!(_mm256_cvtepi32_ps(high))),
    )
}
