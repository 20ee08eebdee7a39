//! Two registers as one lane: every operation issues the same instruction on both
//! halves, one after the other, so a kernel's two independent dependency chains are
//! interleaved instruction by instruction. Kernels whose registers wait on long chains
//! of divisions and square roots (a closure's sample: sample, settle, evaluate) keep
//! the divider and the arithmetic ports busy with the other half meanwhile. Each lane's
//! arithmetic is the half's own, so the results are the bits of `L`.

use super::compound_assign;
use crate::math::lane::{MAX_LANES, ROW};
use crate::math::{Lane, Mask};
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// `2 L::LANES` lanes: the first half's, then the second's.
#[derive(Clone, Copy, Debug)]
pub struct Pair<L>(L, L);

/// The masks of a [`Pair`]'s halves.
#[derive(Clone, Copy)]
pub struct PairMask<L: Lane>(L::Mask, L::Mask);

macro_rules! binary_op {
    ($trait:ident $method:ident) => {
        impl<L: Lane> $trait for Pair<L> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Pair(self.0.$method(o.0), self.1.$method(o.1))
            }
        }
    };
}

binary_op!(Add add);
binary_op!(Sub sub);
binary_op!(Mul mul);
binary_op!(Div div);

compound_assign!(Pair<L>, L: Lane);

impl<L: Lane> Neg for Pair<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Pair(-self.0, -self.1)
    }
}

impl<L: Lane> BitAnd for PairMask<L> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        PairMask(self.0 & o.0, self.1 & o.1)
    }
}
impl<L: Lane> BitOr for PairMask<L> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        PairMask(self.0 | o.0, self.1 | o.1)
    }
}
impl<L: Lane> Not for PairMask<L> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        PairMask(!self.0, !self.1)
    }
}

impl<L: Lane> Mask for PairMask<L> {
    #[inline(always)]
    fn splat(value: bool) -> Self {
        PairMask(L::Mask::splat(value), L::Mask::splat(value))
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0.bits() | self.1.bits() << L::LANES
    }
    #[inline(always)]
    fn any(self) -> bool {
        (self.0 | self.1).any()
    }
    #[inline(always)]
    fn all(self) -> bool {
        (self.0 & self.1).all()
    }
}

macro_rules! halves {
    ($($method:ident),*) => {
        $(
            #[inline(always)]
            fn $method(self) -> Self {
                Pair(self.0.$method(), self.1.$method())
            }
        )*
    };
}

macro_rules! compares {
    ($($method:ident),*) => {
        $(
            #[inline(always)]
            fn $method(self, o: Self) -> PairMask<L> {
                PairMask(self.0.$method(o.0), self.1.$method(o.1))
            }
        )*
    };
}

impl<L: Lane> Lane for Pair<L> {
    type Mask = PairMask<L>;
    type Interleaved = Self;
    const LANES: usize = 2 * L::LANES;

    #[inline(always)]
    fn splat(value: f32) -> Self {
        Pair(L::splat(value), L::splat(value))
    }
    #[inline(always)]
    fn load(src: &[f32]) -> Self {
        Pair(L::load(src), L::load(&src[L::LANES..]))
    }
    #[inline(always)]
    fn store(self, dst: &mut [f32]) {
        self.0.store(dst);
        self.1.store(&mut dst[L::LANES..]);
    }
    #[inline(always)]
    fn load_tail(src: &[f32], n: usize, fill: f32) -> Self {
        match n.cmp(&L::LANES) {
            std::cmp::Ordering::Less => Pair(L::load_tail(src, n, fill), L::splat(fill)),
            std::cmp::Ordering::Equal => Pair(L::load(src), L::splat(fill)),
            std::cmp::Ordering::Greater => Pair(
                L::load(src),
                L::load_tail(&src[L::LANES..], n - L::LANES, fill),
            ),
        }
    }
    #[inline(always)]
    fn store_tail(self, dst: &mut [f32], n: usize) {
        match n.cmp(&L::LANES) {
            std::cmp::Ordering::Less => self.0.store_tail(dst, n),
            std::cmp::Ordering::Equal => self.0.store(dst),
            std::cmp::Ordering::Greater => {
                self.0.store(dst);
                self.1.store_tail(&mut dst[L::LANES..], n - L::LANES);
            }
        }
    }
    #[inline(always)]
    fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self {
        Pair(
            L::select(mask.0, if_true.0, if_false.0),
            L::select(mask.1, if_true.1, if_false.1),
        )
    }
    compares!(lt, le, gt, ge, eq);
    #[inline(always)]
    fn is_finite(self) -> Self::Mask {
        PairMask(self.0.is_finite(), self.1.is_finite())
    }
    halves!(abs, sqrt, rsqrt, exp, ln, ln_1p, acos, floor, round);
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Pair(self.0.min(o.0), self.1.min(o.1))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Pair(self.0.max(o.0), self.1.max(o.1))
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        Pair(self.0.mul_add(a.0, b.0), self.1.mul_add(a.1, b.1))
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s0, c0) = self.0.sin_cos();
        let (s1, c1) = self.1.sin_cos();
        (Pair(s0, s1), Pair(c0, c1))
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        Pair(self.0.atan2(x.0), self.1.atan2(x.1))
    }
    #[inline(always)]
    fn pow(self, e: Self) -> Self {
        Pair(self.0.pow(e.0), self.1.pow(e.1))
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        Pair(self.0.copysign(sign.0), self.1.copysign(sign.1))
    }
    #[inline(always)]
    fn lane0(self) -> f32 {
        self.0.lane0()
    }
    #[inline(always)]
    fn ldexp(self, e: Self) -> Self {
        Pair(self.0.ldexp(e.0), self.1.ldexp(e.1))
    }
    #[inline(always)]
    fn frexp(self) -> (Self, Self) {
        let (m0, e0) = self.0.frexp();
        let (m1, e1) = self.1.frexp();
        (Pair(m0, m1), Pair(e0, e1))
    }
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        Pair(L::gather(table, index.0), L::gather(table, index.1))
    }
    #[inline(always)]
    fn gather_adjacent(table: &[f32], index: Self) -> [Self; 2] {
        let [a0, b0] = L::gather_adjacent(table, index.0);
        let [a1, b1] = L::gather_adjacent(table, index.1);
        [Pair(a0, a1), Pair(b0, b1)]
    }
    #[inline(always)]
    fn row_adjacent(row: &[f32; ROW], index: Self) -> [Self; 2] {
        let [a0, b0] = L::row_adjacent(row, index.0);
        let [a1, b1] = L::row_adjacent(row, index.1);
        [Pair(a0, a1), Pair(b0, b1)]
    }
    /// Each half compressed by its own lanes, the second's written after the first's
    /// (through memory: the lanes cross the registers' boundary).
    #[inline(always)]
    fn compress(self, mask: Self::Mask) -> Self {
        let mut out = [0.0f32; MAX_LANES];
        self.0.compress(mask.0).store(&mut out);
        let first = mask.0.bits().count_ones() as usize;
        self.1.compress(mask.1).store(&mut out[first..]);
        Self::load(&out)
    }
    /// The first half expands the first lanes, the second those after them.
    #[inline(always)]
    fn expand(self, mask: Self::Mask) -> Self {
        let mut lanes = [0.0f32; MAX_LANES];
        self.store(&mut lanes);
        let first = mask.0.bits().count_ones() as usize;
        Pair(
            self.0.expand(mask.0),
            L::load(&lanes[first..]).expand(mask.1),
        )
    }
    #[inline(always)]
    fn gather_code_pair(table: &[u32], index: Self) -> (Self, Self) {
        let (a0, b0) = L::gather_code_pair(table, index.0);
        let (a1, b1) = L::gather_code_pair(table, index.1);
        (Pair(a0, a1), Pair(b0, b1))
    }
    #[inline(always)]
    fn gather_code_pairs_adjacent(table: &[u32], index: Self) -> [(Self, Self); 2] {
        let [(a0, b0), (c0, d0)] = L::gather_code_pairs_adjacent(table, index.0);
        let [(a1, b1), (c1, d1)] = L::gather_code_pairs_adjacent(table, index.1);
        [(Pair(a0, a1), Pair(b0, b1)), (Pair(c0, c1), Pair(d0, d1))]
    }
}

#[cfg(test)]
mod tests {
    use crate::math::lane::MAX_LANES;
    use crate::math::{Lane, Mask};
    use crate::simd::Kernels;

    /// Rows an [`ops_lanes`] run writes.
    const ROWS: usize = 12;

    /// Per register of `L::Interleaved`, then per half register of `L`, the same
    /// operations on `x` and `y` (rows `0..ROWS` and `ROWS..2 ROWS`); `masks` gets the
    /// interleaved lanes' `x < y` bits, `any` and `all`.
    #[inline(always)]
    fn ops_lanes<L: Lane>(x: &[f32], y: &[f32], out: &mut [Vec<f32>], masks: &mut Vec<u32>) {
        #[inline(always)]
        fn ops<W: Lane>(x: W, y: W) -> [W; ROWS] {
            let lt = x.lt(y);
            [
                x + y,
                x - y,
                x * y,
                x / y,
                -x,
                x.mul_add(y, x),
                x.abs().sqrt(),
                x.min(y),
                W::select(lt, x, y),
                W::select(x.is_finite(), x, y),
                x.floor(),
                x.sin_cos().0,
            ]
        }
        let w = L::Interleaved::LANES;
        for i in (0..x.len()).step_by(w) {
            let (a, b) = (L::Interleaved::load(&x[i..]), L::Interleaved::load(&y[i..]));
            for (r, v) in ops(a, b).into_iter().enumerate() {
                v.store(&mut out[r][i..]);
            }
            let lt = a.lt(b);
            masks.extend([lt.bits(), u32::from(lt.any()), u32::from(lt.all())]);
            for h in (i..i + w).step_by(L::LANES) {
                for (r, v) in ops(L::load(&x[h..]), L::load(&y[h..]))
                    .into_iter()
                    .enumerate()
                {
                    v.store(&mut out[ROWS + r][h..]);
                }
            }
        }
    }

    kernel!(ops_kernel<>(x: &[f32], y: &[f32], out: &mut [Vec<f32>], masks: &mut Vec<u32>) => ops_lanes);

    /// A tail of `n` lanes loaded with `fill` and stored back into `dst` (which
    /// keeps its values past `n`), then the lanes compressed and expanded by `mask`.
    #[inline(always)]
    fn tail_lanes<L: Lane>(src: &[f32], n: usize, mask: u32, dst: &mut [f32], moved: &mut [f32]) {
        let v = L::Interleaved::load_tail(src, n, -7.0);
        v.store_tail(dst, n);
        let mut all = [0.0f32; MAX_LANES];
        v.store(&mut all);
        // A mask with bit j set where lane j's index is in `mask`.
        let index = L::Interleaved::load(&std::array::from_fn::<f32, MAX_LANES, _>(|j| {
            (mask >> j & 1) as f32
        }));
        let m = index.eq(L::Interleaved::one());
        assert_eq!(m.bits(), mask & lanes_mask(L::Interleaved::LANES));
        v.compress(m).store(&mut moved[..]);
        v.compress(m).expand(m).store(&mut moved[MAX_LANES..]);
        moved[2 * MAX_LANES] = v.lane0();
        moved[2 * MAX_LANES + 1] = all[L::Interleaved::LANES - 1];
    }

    kernel!(tail_kernel<>(src: &[f32], n: usize, mask: u32, dst: &mut [f32], moved: &mut [f32]) => tail_lanes);

    fn lanes_mask(lanes: usize) -> u32 {
        if lanes >= 32 {
            u32::MAX
        } else {
            (1 << lanes) - 1
        }
    }

    fn values(n: usize, seed: u32) -> Vec<f32> {
        let special = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e-40,
            -3e-39,
            f32::MAX,
            f32::MIN_POSITIVE,
            0.5,
        ];
        (0..n as u32)
            .map(|i| {
                let h = (i ^ seed).wrapping_mul(2_654_435_761).rotate_left(7);
                if h.is_multiple_of(5) {
                    special[(h / 5) as usize % special.len()]
                } else {
                    (h as f32 / u32::MAX as f32 - 0.5) * 40.0
                }
            })
            .collect()
    }

    /// Each interleaved operation gives, lane for lane, the bits of the same operation
    /// on each half register; masks carry lane `j` in bit `j` across the halves.
    #[test]
    fn interleaved_lanes_are_their_halves() {
        let n = 4 * MAX_LANES;
        let (x, y) = (values(n, 1), values(n, 99));
        for kernels in Kernels::available() {
            let mut out = vec![vec![0.0f32; n]; 2 * ROWS];
            let mut masks = Vec::new();
            ops_kernel(kernels, &x, &y, &mut out, &mut masks);
            for r in 0..ROWS {
                let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&out[r]),
                    bits(&out[ROWS + r]),
                    "{:?}, op {r}",
                    kernels.isa()
                );
            }
            let w = kernels.isa().lanes() * if kernels.isa().lanes() > 1 { 2 } else { 1 };
            for (k, m) in masks.chunks(3).enumerate() {
                let expected: u32 = (0..w)
                    .filter(|&j| x[k * w + j] < y[k * w + j])
                    .map(|j| 1 << j)
                    .sum();
                assert_eq!(m[0], expected, "{:?}, register {k}", kernels.isa());
                assert_eq!(m[1], u32::from(expected != 0));
                assert_eq!(m[2], u32::from(expected == lanes_mask(w)));
            }
        }
    }

    /// Tails of every length load `fill` past `n` and store only their `n` lanes;
    /// compress and expand move lanes across the halves' boundary.
    #[test]
    fn interleaved_tails_and_compression() {
        let src = values(MAX_LANES, 5);
        for kernels in Kernels::available() {
            let w = kernels.isa().lanes() * if kernels.isa().lanes() > 1 { 2 } else { 1 };
            for n in 1..w {
                for mask in [0u32, 0x5555_5555, 0xffff_0001, 0x8000_0003, u32::MAX] {
                    let mut dst = vec![123.0f32; MAX_LANES];
                    let mut moved = vec![0.0f32; 2 * MAX_LANES + 2];
                    tail_kernel(kernels, &src, n, mask, &mut dst, &mut moved);
                    let lane = |j: usize| if j < n { src[j] } else { -7.0 };
                    let bits = |v: f32| v.to_bits();
                    for j in 0..MAX_LANES {
                        let want = if j < n { src[j] } else { 123.0 };
                        assert_eq!(
                            bits(dst[j]),
                            bits(want),
                            "{:?} n {n} lane {j}",
                            kernels.isa()
                        );
                    }
                    let set: Vec<usize> = (0..w).filter(|&j| mask >> j & 1 == 1).collect();
                    for (k, &j) in set.iter().enumerate() {
                        assert_eq!(
                            bits(moved[k]),
                            bits(lane(j)),
                            "{:?} compress",
                            kernels.isa()
                        );
                    }
                    for j in 0..w {
                        let want = if mask >> j & 1 == 1 { lane(j) } else { 0.0 };
                        assert_eq!(
                            bits(moved[MAX_LANES + j]),
                            bits(want),
                            "{:?} expand n {n} mask {mask:x} lane {j}",
                            kernels.isa()
                        );
                    }
                    assert_eq!(bits(moved[2 * MAX_LANES]), bits(lane(0)));
                    assert_eq!(bits(moved[2 * MAX_LANES + 1]), bits(lane(w - 1)));
                }
            }
        }
    }
}
