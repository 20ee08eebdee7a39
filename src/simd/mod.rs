//! SIMD lane types and the run-time dispatch of kernels: this module holds the lane
//! types and the dispatch token ([`Kernels`]) only; the kernels themselves, generic
//! over [`Lane`], live in `crate::kernels` and `crate::math`.
//!
//! Mechanism: `core::arch` intrinsics behind the crate's own [`Lane`] trait. Each ISA
//! has one lane type (`avx2::F32x8`, `avx512::F32x16`) implementing `Lane` with
//! `#[inline(always)]` methods; the generic kernels (`crate::kernels`) are instantiated
//! once per ISA inside a `#[target_feature]` entry point, so every lobe's single
//! generic source is compiled to scalar, AVX2+FMA and AVX-512 code in the same
//! baseline x86-64 binary. We chose this over `pulp` or `fearless_simd` because the
//! lobes already speak `Lane` (one more trait layer would buy nothing), the surface
//! we need is small (about 40 operations per ISA), and it keeps the dependency list
//! short; `wide` and `std::simd` were ruled out (compile-time width, nightly).
//!
//! Soundness: a SIMD lane type must only run on a CPU with its features. The only
//! way to reach a kernel is through a [`Kernels`] value, whose constructor checks
//! the CPU at run time. The lane types are crate-private and named only by the
//! `kernel!` macro's `#[target_feature]` entry points.

use crate::error::{Error, Status};
use crate::kernels::delay::Stores;
use crate::math::Lane;

/// A public kernel that runs `$body` with the lane type of its `Kernels`: the
/// target-feature entry points are the only place SIMD code is entered.
macro_rules! kernel {
    ($(#[$doc:meta])* $name:ident <$($m:ident: $bound:path)?> ($($arg:ident: $ty:ty),*) $(-> $ret:ty)? => $body:ident) => {
        $(#[$doc])*
        pub fn $name<$($m: $bound)?>(kernels: $crate::simd::Kernels, $($arg: $ty),*) $(-> $ret)? {
            match kernels.isa() {
                $crate::simd::Isa::Scalar => $body::<$($m,)? f32>($($arg),*),
                #[cfg(target_arch = "x86_64")]
                $crate::simd::Isa::Avx2 => {
                    #[target_feature(enable = "avx2,fma")]
                    fn run<$($m: $bound)?>($($arg: $ty),*) $(-> $ret)? {
                        $body::<$($m,)? $crate::simd::avx2::F32x8>($($arg),*)
                    }
                    // SAFETY: `kernels` proves this CPU has AVX2 and FMA.
                    unsafe { run::<$($m)?>($($arg),*) }
                }
                #[cfg(target_arch = "x86_64")]
                $crate::simd::Isa::Avx512 => {
                    #[target_feature(enable = "avx512f")]
                    fn run<$($m: $bound)?>($($arg: $ty),*) $(-> $ret)? {
                        $body::<$($m,)? $crate::simd::avx512::F32x16>($($arg),*)
                    }
                    // SAFETY: `kernels` proves this CPU has AVX-512F.
                    unsafe { run::<$($m)?>($($arg),*) }
                }
                #[cfg(not(target_arch = "x86_64"))]
                _ => $body::<$($m,)? f32>($($arg),*),
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub(crate) mod avx2;
#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub(crate) mod avx512;
pub(crate) mod pair;
pub(crate) use kernel;

/// Call `core::arch` intrinsics from a lane method.
macro_rules! intrinsic {
    ($e:expr) => {
        // SAFETY: lane types of this module exist only inside kernels entered through
        // `Kernels`, whose constructor checked that the CPU has the ISA (module doc);
        // loads, stores and gathers stay inside slices their callers bounds-check.
        unsafe { $e }
    };
}
use intrinsic;

/// `+=`, `-=` and `*=` from the binary operators (of `$t`, generic over `$g: $bound`).
macro_rules! compound_assign {
    ($t:ty $(, $g:ident: $bound:path)*) => {
        impl<$($g: $bound),*> std::ops::AddAssign for $t {
            #[inline(always)]
            fn add_assign(&mut self, o: Self) {
                *self = *self + o;
            }
        }
        impl<$($g: $bound),*> std::ops::SubAssign for $t {
            #[inline(always)]
            fn sub_assign(&mut self, o: Self) {
                *self = *self - o;
            }
        }
        impl<$($g: $bound),*> std::ops::MulAssign for $t {
            #[inline(always)]
            fn mul_assign(&mut self, o: Self) {
                *self = *self * o;
            }
        }
    };
}
use compound_assign;

/// The `Lane` methods a SIMD lane type takes from `crate::math::vmath`.
macro_rules! elementary_functions_from_vmath {
    () => {
        #[inline(always)]
        fn exp(self) -> Self {
            crate::math::vmath::exp(self)
        }
        #[inline(always)]
        fn ln(self) -> Self {
            crate::math::vmath::ln(self)
        }
        #[inline(always)]
        fn ln_1p(self) -> Self {
            crate::math::vmath::ln_1p(self)
        }
        #[inline(always)]
        fn sin_cos(self) -> (Self, Self) {
            crate::math::vmath::sin_cos(self)
        }
        #[inline(always)]
        fn acos(self) -> Self {
            crate::math::vmath::acos(self)
        }
        #[inline(always)]
        fn atan2(self, x: Self) -> Self {
            crate::math::vmath::atan2(self, x)
        }
        #[inline(always)]
        fn pow(self, e: Self) -> Self {
            crate::math::vmath::pow(self, e)
        }
    };
}
use elementary_functions_from_vmath;

/// One Newton step `y + y r / 2`, `r = 1 - x y^2`, on a hardware estimate `y` of
/// `1 / sqrt(x)`, for `x` a positive normal float ([`Lane::rsqrt`]'s domain; at 0 the
/// step is NaN, no select keeps the estimate: every caller's argument is normal or
/// selected away, and the select was 2 of a sampler's multiply-pipe operations).
/// The residual and the update are fused, so only `x y` rounds before them: the
/// estimate's own error (up to 1.5 2^-12 on Intel, less on AMD) leaves 1.5 e^2 <= 2e-7.
#[inline(always)]
fn newton_rsqrt<L: Lane>(x: L, y: L) -> L {
    let residual = (x * y).mul_add(-y, L::one());
    (y * L::splat(0.5)).mul_add(residual, y)
}

/// An instruction set the batch kernels can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    Scalar,
    /// AVX2 with FMA: 8 lanes.
    Avx2,
    /// AVX-512 Foundation: 16 lanes.
    Avx512,
}

impl Isa {
    pub const ALL: [Isa; 3] = [Isa::Scalar, Isa::Avx2, Isa::Avx512];

    /// The name used in the runtime configuration (`isa=...`).
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }

    /// Lanes per SIMD register.
    pub fn lanes(self) -> usize {
        match self {
            Isa::Scalar => 1,
            Isa::Avx2 => 8,
            Isa::Avx512 => 16,
        }
    }

    /// Whether this CPU can run the ISA's kernels.
    pub fn is_supported(self) -> bool {
        match self {
            Isa::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }
}

/// Proof that the CPU runs an ISA: the only handle to the SIMD kernels; with whether
/// their fused kernels hold their outputs back ([`Stores`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernels {
    isa: Isa,
    stores: Stores,
}

impl Kernels {
    /// The kernels for `isa`, or `GLINT_ERROR_UNSUPPORTED` when this CPU lacks it.
    pub fn new(isa: Isa) -> Result<Kernels, Error> {
        if isa.is_supported() {
            Ok(Kernels::of(isa))
        } else {
            Err(Error::new(
                Status::Unsupported,
                format!(
                    "isa={}: this CPU does not support it; supported here: {}",
                    isa.name(),
                    Kernels::available()
                        .iter()
                        .map(|k| k.isa.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ))
        }
    }

    pub const fn scalar() -> Kernels {
        Kernels::of(Isa::Scalar)
    }

    const fn of(isa: Isa) -> Kernels {
        Kernels {
            isa,
            stores: Stores::Auto,
        }
    }

    /// The widest ISA this CPU supports.
    pub fn best() -> Kernels {
        Isa::ALL
            .iter()
            .rev()
            .find(|isa| isa.is_supported())
            .map_or(Kernels::scalar(), |&isa| Kernels::of(isa))
    }

    /// Every ISA this CPU supports, narrowest first.
    pub fn available() -> Vec<Kernels> {
        Isa::ALL
            .iter()
            .filter(|isa| isa.is_supported())
            .map(|&isa| Kernels::of(isa))
            .collect()
    }

    pub fn isa(self) -> Isa {
        self.isa
    }

    /// These kernels, their fused kernels storing as `stores` says.
    pub fn with_stores(self, stores: Stores) -> Kernels {
        Kernels { stores, ..self }
    }

    pub fn stores(self) -> Stores {
        self.stores
    }
}

/// Ask for the cache line of `row[at]` ahead of its load: a hint, with no effect on
/// any value. `at` may lie past the row's end (a prefetch cannot fault), so that a
/// loop need not check each row.
#[inline(always)]
pub fn prefetch(row: &[f32], at: usize) {
    let line = row.as_ptr().wrapping_add(at).cast::<i8>();
    #[cfg(target_arch = "x86_64")]
    // `_mm_prefetch` is an unsafe fn in older Rust (rust-version is 1.89).
    #[allow(unused_unsafe)]
    // SAFETY: a prefetch reads no value and cannot fault, whatever the address, and
    // every x86-64 CPU has SSE.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(line)
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = line;
}

/// Whether this CPU is AMD's: the vendor string of CPUID's leaf 0.
pub fn is_amd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static AMD: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *AMD.get_or_init(|| {
            // `__cpuid` is an unsafe fn in older Rust (rust-version is 1.89).
            #[allow(unused_unsafe)]
            // SAFETY: every x86-64 CPU has CPUID, and its leaf 0.
            let id = unsafe { std::arch::x86_64::__cpuid(0) };
            [id.ebx, id.edx, id.ecx]
                .iter()
                .flat_map(|r| r.to_le_bytes())
                .eq(*b"AuthenticAMD")
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// The vectorized math functions, for tests and benchmarks that measure each
/// ISA's implementation (`map_math`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MathFn {
    Exp,
    Ln,
    Ln1p,
    Sin,
    Cos,
    Acos,
    /// `atan2(x, y)`: `x` is the ordinate.
    Atan2,
    /// `pow(x, y)`.
    Pow,
    Sqrt,
    Rsqrt,
    Erf,
    Erfc,
    ErfInv,
    /// The sine of [`crate::math::azimuth`]: `sin(2 pi x)`.
    AzimuthSin,
    /// The cosine of [`crate::math::azimuth`]: `cos(2 pi x)`.
    AzimuthCos,
}

#[inline(always)]
fn apply<L: Lane>(f: MathFn, x: L, y: L) -> L {
    use crate::math::special;
    match f {
        MathFn::Exp => x.exp(),
        MathFn::Ln => x.ln(),
        MathFn::Ln1p => x.ln_1p(),
        MathFn::Sin => x.sin_cos().0,
        MathFn::Cos => x.sin_cos().1,
        MathFn::Acos => x.acos(),
        MathFn::Atan2 => x.atan2(y),
        MathFn::Pow => x.pow(y),
        MathFn::Sqrt => x.sqrt(),
        MathFn::Rsqrt => x.rsqrt(),
        MathFn::Erf => special::erf(x),
        MathFn::Erfc => special::erfc_nonneg(x),
        MathFn::ErfInv => special::erf_inv(x),
        MathFn::AzimuthSin => crate::math::azimuth(x).0,
        MathFn::AzimuthCos => crate::math::azimuth(x).1,
    }
}

/// `out[i] = f(x[i], y[i])` with the lane type of `kernels` (`y` is ignored by
/// one-argument functions). Lengths that are not a multiple of the lane count are
/// padded internally.
pub fn map_math(kernels: Kernels, f: MathFn, x: &[f32], y: &[f32], out: &mut [f32]) {
    assert!(x.len() == y.len() && x.len() == out.len());
    math_kernel(kernels, f, x, y, out);
}

kernel!(math_kernel<>(f: MathFn, x: &[f32], y: &[f32], out: &mut [f32]) => map_math_lanes);

#[inline(always)]
fn map_math_lanes<L: Lane>(f: MathFn, x: &[f32], y: &[f32], out: &mut [f32]) {
    let n = L::LANES;
    let mut pad = [[0.0f32; 16]; 3];
    for start in (0..x.len()).step_by(n) {
        let end = (start + n).min(x.len());
        let len = end - start;
        pad[0][..len].copy_from_slice(&x[start..end]);
        pad[1][..len].copy_from_slice(&y[start..end]);
        let r = apply(f, L::load(&pad[0]), L::load(&pad[1]));
        r.store(&mut pad[2]);
        out[start..end].copy_from_slice(&pad[2][..len]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::lane::ROW;

    /// A prefetch is a hint: past a row's end, of an empty row or at an index whose
    /// address wraps, it neither faults nor changes the row.
    #[test]
    fn prefetch_anywhere_is_harmless() {
        let row = [1.0f32, 2.0, 3.0];
        for at in [0, 2, 3, 16, 1 << 40, usize::MAX / 4, usize::MAX] {
            prefetch(&row, at);
            prefetch(&[], at);
        }
        assert_eq!(row, [1.0, 2.0, 3.0]);
    }

    /// `gather_adjacent` and `gather_code_pairs_adjacent` of every lane index of `index`
    /// into `out`: per register, both cells of each (eight rows: the f32 pair, then the
    /// two code pairs' four channels), and the same from single gathers.
    #[inline(always)]
    fn adjacent_lanes<L: Lane>(
        values: &[f32],
        codes: &[u32],
        index: &[f32],
        out: &mut [Vec<f32>; 12],
    ) {
        for i in (0..index.len()).step_by(L::LANES) {
            let at = L::load(&index[i..]);
            let [a, b] = L::gather_adjacent(values, at);
            let [(c, d), (e, f)] = L::gather_code_pairs_adjacent(codes, at);
            let (g, h) = L::gather_code_pair(codes, at);
            let (j, k) = L::gather_code_pair(codes, at + L::one());
            let rows = [
                a,
                b,
                c,
                d,
                e,
                f,
                L::gather(values, at),
                L::gather(values, at + L::one()),
                g,
                h,
                j,
                k,
            ];
            for (row, v) in out.iter_mut().zip(rows) {
                v.store(&mut row[i..]);
            }
        }
    }

    kernel!(adjacent<>(values: &[f32], codes: &[u32], index: &[f32], out: &mut [Vec<f32>; 12]) => adjacent_lanes);

    /// The 64-bit reads of adjacent cells return, on every ISA, the bits two single
    /// gathers return: at the table's first and last pairs and random cells.
    #[test]
    fn adjacent_gathers_read_two_cells() {
        let len = 1001;
        let values: Vec<f32> = (0..len).map(|i| (i as f32 * 0.37).sin() * 1e3).collect();
        let codes: Vec<u32> = (0..len as u32)
            .map(|i| i.wrapping_mul(2_654_435_761))
            .collect();
        let mut index: Vec<f32> = vec![0.0, (len - 2) as f32, 1.0, (len - 3) as f32];
        index.extend((0..60).map(|i| ((i * 7919) % (len - 1)) as f32));
        for kernels in Kernels::available() {
            let mut out: [Vec<f32>; 12] = std::array::from_fn(|_| vec![0.0; index.len()]);
            adjacent(kernels, &values, &codes, &index, &mut out);
            let bits = |r: &Vec<f32>| r.iter().map(|v| v.to_bits()).collect::<Vec<u32>>();
            for k in 0..6 {
                assert_eq!(
                    bits(&out[k]),
                    bits(&out[k + 6]),
                    "{:?}, row {k}",
                    kernels.isa()
                );
            }
            let scalar: Vec<f32> = index.iter().map(|&i| values[i as usize + 1]).collect();
            assert_eq!(bits(&out[1]), bits(&scalar), "{:?}", kernels.isa());
        }
    }

    /// `row_adjacent` and `gather_adjacent` of every lane index into `out` (rows 0-1 and
    /// 2-3).
    #[inline(always)]
    fn row_lanes<L: Lane>(row: &[f32; ROW], index: &[f32], out: &mut [Vec<f32>; 4]) {
        for i in (0..index.len()).step_by(L::LANES) {
            let at = L::load(&index[i..]);
            let [a, b] = L::row_adjacent(row, at);
            let [c, d] = L::gather_adjacent(row, at);
            for (r, v) in out.iter_mut().zip([a, b, c, d]) {
                v.store(&mut r[i..]);
            }
        }
    }

    kernel!(row_pick<>(row: &[f32; ROW], index: &[f32], out: &mut [Vec<f32>; 4]) => row_lanes);

    /// A row's cells picked by permutes are, on every ISA, the bits gathers read: every
    /// index of the row, in an order that crosses the row's halves and quarters within
    /// each register.
    #[test]
    fn row_picks_read_the_gathered_cells() {
        let mut row: [f32; ROW] = std::array::from_fn(|i| (i as f32 * 0.61).cos() * 1e3);
        row[5] = -0.0;
        row[40] = f32::from_bits(0x7fc0_1234);
        let mut index: Vec<f32> = (0..ROW - 1)
            .map(|i| ((i * 37) % (ROW - 1)) as f32)
            .collect();
        index.push(0.0);
        for kernels in Kernels::available() {
            let mut out: [Vec<f32>; 4] = std::array::from_fn(|_| vec![0.0; index.len()]);
            row_pick(kernels, &row, &index, &mut out);
            let bits = |r: &Vec<f32>| r.iter().map(|v| v.to_bits()).collect::<Vec<u32>>();
            for k in 0..2 {
                let want: Vec<u32> = index
                    .iter()
                    .map(|&i| row[i as usize + k].to_bits())
                    .collect();
                assert_eq!(bits(&out[k]), want, "{:?}, cell {k}", kernels.isa());
                assert_eq!(bits(&out[k + 2]), want, "{:?}, cell {k}", kernels.isa());
            }
        }
    }
}
