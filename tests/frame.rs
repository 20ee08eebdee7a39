//! Shading frames from user input (issue 12, D10): a tangent nearly parallel to a
//! normal that is not an axis must still give an orthonormal frame (Gram-Schmidt
//! accurate to f32 rounding, or the automatic tangent when nothing of the tangent is
//! left), and sampling through such a frame must agree with eval.

mod common;
mod reference;

use common::{Block, Rng, lobe};
use glint::Closure;
use glint::lobes::Transport;
use glint::math::{Frame, Vec3};
use glint::registry::Registry;
use reference::V;

/// Normals that are not axes, and for each a unit direction perpendicular to it (f64).
fn normals() -> Vec<(V, V)> {
    [
        V::new(0.3, -0.5, 0.81),
        V::new(-0.7, 0.1, -0.7),
        V::new(1.0, 1.0, 1.0),
        V::new(0.01, 0.9999, 0.002),
    ]
    .into_iter()
    .map(|n| {
        let n = V::from32(n.normalize().to32());
        let p = n.cross(V::new(0.2, 0.7, -0.4)).normalize();
        (n, p)
    })
    .collect()
}

/// Perpendicular parts of the tangent from 1e-1 down to 1e-30, and 0.
fn perpendicular_parts() -> Vec<f64> {
    let mut e: Vec<f64> = (1..=30).map(|k| 10f64.powi(-k)).collect();
    e.push(0.0);
    e
}

/// `|a.b|` in f64 of two f32 vectors.
fn dot(a: Vec3<f32>, b: Vec3<f32>) -> f64 {
    V::from32(a).dot(V::from32(b))
}

/// `f` is orthonormal and right-handed (`b = n x t`) to 1e-6, in f64.
fn assert_orthonormal(f: &Frame, what: &str) {
    for (q, v) in [
        ("t.n", dot(f.t, f.n)),
        ("b.n", dot(f.b, f.n)),
        ("t.b", dot(f.t, f.b)),
        ("|t| - 1", dot(f.t, f.t).sqrt() - 1.0),
        ("|b| - 1", dot(f.b, f.b).sqrt() - 1.0),
    ] {
        assert!(v.abs() <= 1e-6, "{what}: {q} = {v:e}");
    }
    let b = V::from32(f.n).cross(V::from32(f.t));
    assert!((b - V::from32(f.b)).length() <= 1e-6, "{what}: b");
}

/// Tangents well off the normal (`Frame::new` builds these frames in f32 up to 30
/// degrees from the normal, in f64 beyond): the frame's tangent is the normalized
/// perpendicular part, to 1e-6 of the f64 Gram-Schmidt, at any length and with a
/// normal a little off unit length.
#[test]
fn separated_tangents_give_their_perpendicular_part() {
    for (n, p) in normals() {
        let q = n.cross(p);
        for k in 0..8 {
            let angle = f64::from(k) * 0.8;
            let perp = p * angle.cos() + q * angle.sin();
            // Along the normal by these multiples of the perpendicular part: 1.73 is
            // 30.02 degrees from it (f32), 1.74 29.9 (f64).
            for along in [0.0, -0.3, 1.0, 1.73, -1.74, 10.0] {
                for (scale, n_scale) in [1.0, 3.7, 1e-3, 1e4, 1e-12, 1e12]
                    .into_iter()
                    .flat_map(|s| [(s, 1.0), (s, 0.998)])
                {
                    let t = ((perp + n * along) * scale).to32();
                    let nf = (n * n_scale).to32();
                    let f = Frame::new(nf, Some(t));
                    let what = format!("n {nf:?} t {t:?}: {f:?}");
                    if n_scale == 1.0 {
                        assert_orthonormal(&f, &what);
                    }
                    // The perpendicular part of the f32 tangent given, in f64 (a normal
                    // off unit length too).
                    let t64 = V::from32(t);
                    let n64 = V::from32(nf);
                    let want = (t64 - n64 * (n64.dot(t64) / n64.dot(n64))).normalize();
                    let off = (V::from32(f.t) - want).length();
                    assert!(off <= 1e-6, "{what}: tangent {off:e} from {want:?}");
                }
            }
        }
    }
}

#[test]
fn nearly_parallel_tangents_give_orthonormal_frames() {
    for (n, p) in normals() {
        for eps in perpendicular_parts() {
            for scale in [1.0, 3.7, 1e-3] {
                let t = ((n + p * eps) * scale).to32();
                let f = Frame::new(n.to32(), Some(t));
                let what = format!("n {n:?} perpendicular {eps:e} scale {scale}: {f:?}");
                assert_orthonormal(&f, &what);
                // Where the tangent's perpendicular part is well above f32 rounding, it
                // gives the frame's tangent.
                if eps >= 1e-4 {
                    assert!(V::from32(f.t).dot(p) > 0.999, "{what}: t.p");
                }
            }
        }
    }
}

#[test]
fn sampling_through_nearly_parallel_tangents_agrees_with_eval() {
    let registry = Registry::with_builtins();
    let id = registry.find("conductor").unwrap();
    let block = Block::defaults(lobe("conductor"))
        .float("roughness", 0.4)
        .float("anisotropic", 0.8);
    let mut rng = Rng::new(10);
    let mut worst = 0.0f64;
    for (n, p) in normals() {
        for eps in perpendicular_parts() {
            let t = (n + p * eps).to32();
            let mut c = Closure::new(None, Transport::Radiance);
            c.add_lobe(
                &registry,
                id,
                [1.0; 3],
                Frame::new(n.to32(), Some(t)),
                Some(block.as_slice()),
            )
            .unwrap();
            c.finish().unwrap();
            // 40 degrees off the normal.
            let wo = (n * 40f64.to_radians().cos() + p.cross(n) * 40f64.to_radians().sin()).to32();
            let wo = Vec3::try_unit(wo.x, wo.y, wo.z, "wo").unwrap();
            for _ in 0..100 {
                let Ok(s) = c.sample(wo, rng.u3()) else {
                    continue;
                };
                let e = c.eval(wo, s.wi).unwrap();
                let d = (f64::from(s.pdf) - f64::from(e.pdf)).abs() / f64::from(e.pdf.max(s.pdf));
                assert!(
                    d <= 1e-3,
                    "n {n:?} perpendicular {eps:e}: sample pdf {}, eval pdf {}",
                    s.pdf,
                    e.pdf
                );
                worst = worst.max(d);
            }
        }
    }
    println!("worst relative pdf difference {worst:.2e}");
}
