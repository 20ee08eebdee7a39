//! Orthonormal shading frames: each lobe of a closure carries its own
//! (seed 000 "Layering": layers may have their own bumped normals).

use super::vec::Vec3;

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
    /// made orthogonal to `n` (Gram-Schmidt); when it is missing or parallel to `n`,
    /// one is chosen with Duff et al. 2017 ("Building an Orthonormal Basis, Revisited").
    pub fn new(n: Vec3<f32>, tangent: Option<Vec3<f32>>) -> Frame {
        let t = tangent
            .map(|t| t - n * n.dot(t))
            .filter(|t| t.length_squared() > 1e-12)
            .map(Vec3::normalize)
            .unwrap_or_else(|| Self::duff_tangent(n));
        Frame {
            t,
            b: n.cross(t),
            n,
        }
    }

    fn duff_tangent(n: Vec3<f32>) -> Vec3<f32> {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x)
    }

    #[inline]
    pub fn to_local(&self, v: Vec3<f32>) -> Vec3<f32> {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3<f32>) -> Vec3<f32> {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}
