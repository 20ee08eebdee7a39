//! Orthonormal shading frames: each lobe of a closure carries its own
//! (seed 000 "Layering": layers may have their own bumped normals).

use super::vec::{Vec3, inv_length};
use super::{Lane, Mask};

/// Tangent `t`, bitangent `b = n x t` and normal `n`, all unit length and orthogonal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub t: Vec3<f32>,
    pub b: Vec3<f32>,
    pub n: Vec3<f32>,
}

impl Frame {
    /// The frame whose local axes equal the world axes.
    pub const IDENTITY: Frame = Frame {
        t: Vec3 {
            x: 1.0,
            y: 0.0,
            z: 0.0,
        },
        b: Vec3 {
            x: 0.0,
            y: 1.0,
            z: 0.0,
        },
        n: Vec3 {
            x: 0.0,
            y: 0.0,
            z: 1.0,
        },
    };

    /// Build a frame from a unit normal and an optional tangent hint. The tangent is
    /// made orthogonal to `n` by Gram-Schmidt (in f64 when it is nearly parallel to
    /// `n`, where in f32 the projection `t - n (n.t)` would keep rounding errors of
    /// `n.t` along `n`), so the frame is orthonormal to f32 rounding; the bitangent is
    /// `n x t`. When the tangent is missing, not finite, or its part perpendicular to
    /// `n` is below [`Self::PARALLEL_TANGENT`] of its length (nothing left of it but
    /// rounding), one is chosen with Duff et al. 2017 ("Building an Orthonormal Basis,
    /// Revisited").
    ///
    /// Inlined but for the f64 path, which returns the tangent alone (in registers):
    /// out of line, or merged from two paths as whole frames or pairs of axes, the
    /// frame went through memory and was read back with wider loads than its stores (a
    /// store-forwarding stall at every shading point).
    #[inline(always)]
    pub fn new(n: Vec3<f32>, tangent: Option<Vec3<f32>>) -> Frame {
        let t = tangent.and_then(|t| match separated_tangent(n, t) {
            (perp, true) => Some(perp),
            _ => Self::near_tangent(n, t),
        });
        let (t, b) = match t {
            Some(t) => (t, n.cross(t)),
            None => duff_axes(n),
        };
        Frame { t, b, n }
    }

    /// [`Self::new`]'s tangent by Gram-Schmidt in f64, for a tangent within 30 degrees
    /// of the normal or of a length out of [`separated_tangent`]'s range; None
    /// when nothing of it is left but rounding.
    #[cold]
    #[inline(never)]
    fn near_tangent(n: Vec3<f32>, t: Vec3<f32>) -> Option<Vec3<f32>> {
        let (n64, t) = (F64::from(n), F64::from(t));
        // Divided by |n|^2: an f32 normal is unit only to ~1e-8, and that much of
        // n.t ~ 1 would stay in a small perpendicular part.
        let perp = t.sub(n64.scale(n64.dot(t) / n64.dot(n64)));
        let len2 = perp.dot(perp);
        (len2 > (Self::PARALLEL_TANGENT * Self::PARALLEL_TANGENT) * t.dot(t))
            .then(|| perp.scale(1.0 / len2.sqrt()).to32())
    }

    /// Relative size of a tangent's part perpendicular to the normal below which
    /// [`Self::new`] treats the tangent as absent.
    pub const PARALLEL_TANGENT: f64 = 1e-6;

    #[inline]
    pub fn to_local(&self, v: Vec3<f32>) -> Vec3<f32> {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3<f32>) -> Vec3<f32> {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// A shading frame with one lane per component (a [`Frame`] splatted, or one frame
/// per lane).
#[derive(Clone, Copy, Debug)]
pub struct LaneFrame<L> {
    pub t: Vec3<L>,
    pub b: Vec3<L>,
    pub n: Vec3<L>,
    /// Every lane's frame is [`Frame::IDENTITY`] (equal as floats: an axis component of
    /// -0 gives the same products wherever [`Self::passes`] holds): the rotations
    /// return a direction as it is where that is what their products give.
    pub identity: bool,
}

impl<L: Lane> LaneFrame<L> {
    #[inline(always)]
    pub fn splat(f: &Frame) -> Self {
        let v = |v: Vec3<f32>| Vec3::splat(v.x, v.y, v.z);
        LaneFrame {
            t: v(f.t),
            b: v(f.b),
            n: v(f.n),
            identity: *f == Frame::IDENTITY,
        }
    }
    /// Per-lane axes.
    #[inline(always)]
    pub fn new(t: Vec3<L>, b: Vec3<L>, n: Vec3<L>) -> Self {
        LaneFrame {
            t,
            b,
            n,
            identity: false,
        }
    }
    /// Whether the rotations give `v` itself: with the identity's axes each component
    /// of `to_local` is `x 1 + (±0 + ±0)` and of `to_world` `(x 1 + ±0) + ±0`, which is
    /// `x` unless `x` is zero (its sign then comes from the other components') or a
    /// component is not finite (`inf 0`). A product of the components in `(0, inf)`
    /// rules both out (one that underflows or overflows takes the products).
    #[inline(always)]
    fn passes(&self, v: Vec3<L>) -> bool {
        // The flag first: other frames pay for no product.
        if !self.identity {
            return false;
        }
        nonzero_finite(v.x * v.y * v.z)
    }
    #[inline(always)]
    pub fn to_local(&self, v: Vec3<L>) -> Vec3<L> {
        if self.passes(v) {
            return v;
        }
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
    /// [`Self::to_local`] of two directions, the same results as two calls: one check
    /// for both where the frame is the identity (a product of all six components in
    /// `(0, inf)` has each direction's three there too).
    #[inline(always)]
    pub fn to_local_pair(&self, a: Vec3<L>, b: Vec3<L>) -> (Vec3<L>, Vec3<L>) {
        if self.identity && nonzero_finite(a.x * a.y * a.z * (b.x * b.y * b.z)) {
            return (a, b);
        }
        (self.to_local(a), self.to_local(b))
    }
    #[inline(always)]
    pub fn to_world(&self, v: Vec3<L>) -> Vec3<L> {
        if self.passes(v) {
            return v;
        }
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// Whether every lane of the product `p` is in `(0, inf)` in magnitude
/// ([`LaneFrame::passes`]' test).
#[inline(always)]
fn nonzero_finite<L: Lane>(p: L) -> bool {
    let p = p.abs();
    (p.gt(L::zero()) & p.lt(L::splat(f32::INFINITY))).all()
}

/// A 3-vector in f64 for [`Frame::new`]'s Gram-Schmidt.
#[derive(Clone, Copy)]
struct F64([f64; 3]);

impl F64 {
    fn from(v: Vec3<f32>) -> F64 {
        F64([f64::from(v.x), f64::from(v.y), f64::from(v.z)])
    }
    fn to32(self) -> Vec3<f32> {
        Vec3::new(self.0[0] as f32, self.0[1] as f32, self.0[2] as f32)
    }
    fn dot(self, o: F64) -> f64 {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    fn scale(self, s: f64) -> F64 {
        F64(self.0.map(|c| c * s))
    }
    fn sub(self, o: F64) -> F64 {
        F64([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}

/// [`Frame::new`]'s tangent in f32 where f32 is as accurate, and the lanes where it is:
/// a tangent at least 30 degrees off the normal (`(n.t)^2 <= 3/4 |t|^2 |n|^2`), whose
/// perpendicular part is then at least half its length, so the rounding of `n.t` (a
/// few ulps of `|t|`) leaves at most twice that along `n` after normalizing. Other
/// lanes take `Frame::near_tangent`'s f64 path. The common case (a host's tangent from
/// its own frame) so skips f64 divisions and a square root on every shading point;
/// for any lane type, so material batches build tangent frames in registers with
/// `Frame::new`'s bits.
#[inline(always)]
pub fn separated_tangent<L: Lane>(n: Vec3<L>, t: Vec3<L>) -> (Vec3<L>, L::Mask) {
    let (tt, nn) = (t.length_squared(), n.length_squared());
    let nt = n.dot(t);
    let separated =
        tt.ge(L::splat(1e-18)) & tt.le(L::splat(1e18)) & (nt * nt).le(L::splat(0.75) * tt * nn);
    // Divided by |n|^2 as in f64 (a caller's normal may be off unit length); by
    // `inv_length` squared, which needs no division for a unit normal.
    let inv_n = inv_length(nn);
    let perp = t - n * (nt * (inv_n * inv_n));
    (perp * inv_length(perp.length_squared()), separated)
}

/// Tangent and bitangent `n x t` of a unit normal `n`, an orthonormal right-handed
/// basis without branches (Duff et al. 2017, listing 3), for any lane type: material
/// batches build their frames with it over rows, and get `Frame::new`'s bits.
#[inline(always)]
pub fn duff_axes<L: Lane>(n: Vec3<L>) -> (Vec3<L>, Vec3<L>) {
    let sign = L::one().copysign(n.z);
    let a = -(L::one() / (sign + n.z));
    let b = n.x * n.y * a;
    (
        Vec3::new(L::one() + sign * n.x * n.x * a, sign * b, -(sign * n.x)),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::{Kernels, kernel};

    /// `to_local` and `to_world` of a splatted frame, and `to_local_pair` of `v` and `w`
    /// (each row one component).
    #[inline(always)]
    fn rotate_lanes<L: Lane>(
        frame: &Frame,
        (v, w): (&[Vec<f32>; 3], &[Vec<f32>; 3]),
        out: &mut [Vec<f32>; 12],
    ) {
        let axes = LaneFrame::<L>::splat(frame);
        for i in (0..v[0].len()).step_by(L::LANES) {
            let (d, e) = (at::<L>(v, i), at::<L>(w, i));
            let (local, world) = (axes.to_local(d), axes.to_world(d));
            let (pair_d, pair_e) = axes.to_local_pair(d, e);
            let rows = [
                local.x, local.y, local.z, world.x, world.y, world.z, pair_d.x, pair_d.y, pair_d.z,
                pair_e.x, pair_e.y, pair_e.z,
            ];
            for (row, r) in out.iter_mut().zip(rows) {
                r.store(&mut row[i..]);
            }
        }
    }

    /// Lanes `i..` of three rows. (A function: a closure would lose the kernel's target
    /// features.)
    #[inline(always)]
    fn at<L: Lane>(rows: &[Vec<f32>; 3], i: usize) -> Vec3<L> {
        Vec3::new(
            L::load(&rows[0][i..]),
            L::load(&rows[1][i..]),
            L::load(&rows[2][i..]),
        )
    }

    kernel!(rotate<>(
        frame: &Frame,
        rows: (&[Vec<f32>; 3], &[Vec<f32>; 3]),
        out: &mut [Vec<f32>; 12]
    ) => rotate_lanes);

    /// The identity frame's pass-through gives, on every ISA, the bits of the scalar
    /// frame's products, for the identity and a frame equal to it with -0 zeros: zeros
    /// of either sign beside components of either sign, components whose product
    /// underflows, infinities and NaN (NaN for NaN); `to_local_pair` those of two
    /// `to_local` calls, with each direction beside the others in turn.
    #[test]
    fn the_identity_passes_directions_through_with_the_products_bits() {
        let values = [
            0.0,
            -0.0,
            0.6,
            -0.6,
            1.0,
            -1.0,
            1e-20,
            -1e-30,
            f32::MIN_POSITIVE / 4.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut v: [Vec<f32>; 3] = Default::default();
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    for (row, c) in v.iter_mut().zip([x, y, z]) {
                        row.push(c);
                    }
                }
            }
        }
        // Whole registers of every width.
        while !v[0].len().is_multiple_of(16) {
            for row in v.iter_mut() {
                row.push(0.5);
            }
        }
        let n = v[0].len();
        // The second direction of each pair: the same values a third of the way on.
        let w: [Vec<f32>; 3] = std::array::from_fn(|c| {
            let mut row = v[c].clone();
            row.rotate_left(n / 3);
            row
        });
        // The identity, and a frame equal to it as floats with every zero -0.
        let signed = Frame {
            t: Vec3::new(1.0, -0.0, -0.0),
            b: Vec3::new(-0.0, 1.0, -0.0),
            n: Vec3::new(-0.0, -0.0, 1.0),
        };
        for frame in [Frame::IDENTITY, signed] {
            let mut expected: [Vec<u32>; 12] = Default::default();
            for i in 0..n {
                let d = Vec3::new(v[0][i], v[1][i], v[2][i]);
                let e = Vec3::new(w[0][i], w[1][i], w[2][i]);
                let (local, world, local_e) =
                    (frame.to_local(d), frame.to_world(d), frame.to_local(e));
                let values = [
                    local.x, local.y, local.z, world.x, world.y, world.z, local.x, local.y,
                    local.z, local_e.x, local_e.y, local_e.z,
                ];
                for (row, c) in expected.iter_mut().zip(values) {
                    row.push(c.to_bits());
                }
            }
            for kernels in Kernels::available() {
                let mut out: [Vec<f32>; 12] = std::array::from_fn(|_| vec![0.0; n]);
                rotate(kernels, &frame, (&v, &w), &mut out);
                for (k, (got, want)) in out.iter().zip(&expected).enumerate() {
                    for i in 0..n {
                        // A NaN's sign and payload depend on the operands' order.
                        let same = if f32::from_bits(want[i]).is_nan() {
                            got[i].is_nan()
                        } else {
                            got[i].to_bits() == want[i]
                        };
                        assert!(
                            same,
                            "{:?}, {frame:?}, output {k}, inputs ({}, {}, {}), ({}, {}, {})",
                            kernels.isa(),
                            v[0][i],
                            v[1][i],
                            v[2][i],
                            w[0][i],
                            w[1][i],
                            w[2][i]
                        );
                    }
                }
            }
        }
    }
}
