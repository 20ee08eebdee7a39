//! `Vec3::try_unit`, the check every direction a host passes goes through: non-finite
//! components and lengths below 1e-12 are errors naming the argument; every other
//! vector comes back unit, its direction that of the f64 normalization, whatever its
//! length (denormal components to lengths whose square overflows f32).

mod common;

use common::Rng;
use glint::math::Vec3;

/// The f64 normalization of `(x, y, z)`, the reference.
fn unit64(x: f32, y: f32, z: f32) -> [f64; 3] {
    let v = [f64::from(x), f64::from(y), f64::from(z)];
    let len = v.iter().map(|c| c * c).sum::<f64>().sqrt();
    v.map(|c| c / len)
}

fn assert_unit_along(x: f32, y: f32, z: f32) {
    let u = Vec3::try_unit(x, y, z, "d").unwrap_or_else(|e| panic!("({x}, {y}, {z}): {e:?}"));
    let r = unit64(x, y, z);
    for (got, want) in [u.x, u.y, u.z].into_iter().zip(r) {
        assert!(
            (f64::from(got) - want).abs() <= 4e-7,
            "({x}, {y}, {z}) -> ({}, {}, {}), want {r:?}",
            u.x,
            u.y,
            u.z
        );
    }
}

fn assert_error(x: f32, y: f32, z: f32, says: &str) {
    match Vec3::try_unit(x, y, z, "context.wo") {
        Ok(u) => panic!("({x}, {y}, {z}) accepted as ({}, {}, {})", u.x, u.y, u.z),
        Err(e) => {
            assert!(
                e.message.contains("context.wo") && e.message.contains(says),
                "({x}, {y}, {z}): {}",
                e.message
            );
        }
    }
}

#[test]
fn non_finite_components_are_errors() {
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for k in 0..3 {
            // With the other components small, unit or large enough that the squared
            // length alone would overflow: the check does not lean on it.
            for other in [0.0, 1e-30, 0.6, 3e30] {
                let mut v = [other; 3];
                v[k] = bad;
                assert_error(v[0], v[1], v[2], "not finite");
            }
        }
    }
}

#[test]
fn vectors_shorter_than_1e_12_are_errors() {
    for len in [0.0f32, 1e-45, 1e-38, 1e-20, 1e-13, 9.9e-13] {
        for (x, y, z) in [(len, 0.0, 0.0), (0.0, -len, 0.0), (0.0, 0.0, len)] {
            assert_error(x, y, z, "zero length");
        }
    }
    // Three components each below 1e-12 whose length is not.
    assert_unit_along(8e-13, -8e-13, 8e-13);
}

#[test]
fn every_other_length_normalizes() {
    let mut rng = Rng::new(0xd1ec);
    let mut rnd = move || rng.f32() * 2.0 - 1.0;
    // Lengths from just above the error threshold, through the squared-length range
    // [1e-24, 1e24] and near 1 (the series), to squares that overflow f32.
    for scale in [
        1.01e-12, 1e-11, 1e-6, 0.5, 0.999, 1.0, 1.0005, 2.0, 1e6, 1e11, 1e13, 1e20, 1e37, 3e38,
    ] {
        for _ in 0..200 {
            let (x, y, z) = (rnd(), rnd(), rnd());
            let len = ((x * x + y * y + z * z) as f64).sqrt() as f32;
            if len < 0.1 {
                continue;
            }
            // Scaled after dividing, so that no factor overflows.
            assert_unit_along(x / len * scale, y / len * scale, z / len * scale);
        }
    }
    assert_unit_along(f32::MAX, f32::MAX, -f32::MAX);
    assert_unit_along(1e-12, 1e-12, 1e-12);
}
