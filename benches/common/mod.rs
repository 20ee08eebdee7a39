//! Inputs shared by the batch benchmarks: SoA rows of directions and random numbers.
#![allow(dead_code)]

use glint::batch::{Soa3, Soa3Mut};

/// A xorshift generator of uniform numbers in [0, 1): the same inputs every run.
pub struct Uniform(u64);

impl Uniform {
    pub fn new() -> Uniform {
        Uniform(0x2545_f491_4f6c_dd1d)
    }

    pub fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A unit direction in the upper hemisphere (`z >= 0.01`).
    pub fn direction(&mut self) -> [f32; 3] {
        let z = self.next().max(0.01);
        let phi = 2.0 * std::f32::consts::PI * self.next();
        let r = (1.0 - z * z).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    }

    /// `n` directions as SoA rows.
    pub fn directions(&mut self, n: usize) -> [Vec<f32>; 3] {
        let mut rows: [Vec<f32>; 3] = Default::default();
        for _ in 0..n {
            let d = self.direction();
            for c in 0..3 {
                rows[c].push(d[c]);
            }
        }
        rows
    }

    /// `n` numbers.
    pub fn row(&mut self, n: usize) -> Vec<f32> {
        (0..n).map(|_| self.next()).collect()
    }
}

pub fn zeros(n: usize) -> [Vec<f32>; 3] {
    [vec![0.0; n], vec![0.0; n], vec![0.0; n]]
}

pub fn soa(v: &[Vec<f32>; 3]) -> Soa3<'_> {
    Soa3 {
        x: &v[0],
        y: &v[1],
        z: &v[2],
    }
}

pub fn soa_mut(v: &mut [Vec<f32>; 3]) -> Soa3Mut<'_> {
    let [x, y, z] = v;
    Soa3Mut { x, y, z }
}
