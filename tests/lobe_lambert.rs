//! `lambert` against its closed form: `eval = color / pi * cos_i`, `pdf = cos_i / pi`,
//! `albedo = color`, zero below the horizon, cosine-weighted samples of weight `color`.

mod common;
mod reference;

use common::{Block, Rng, assert_close, assert_close3, lobe};
use glint::lobes::Transport;
use reference::{V, dir32};
use std::f64::consts::PI;

const COLOR: [f32; 3] = [0.8, 0.3, 0.05];

fn params() -> Block {
    Block::defaults(lobe("lambert")).rgb("color", COLOR)
}

#[test]
fn eval_and_pdf_match_closed_form() {
    let l = lobe("lambert");
    let p = params();
    for (to, po) in [(0.0, 0.0), (30.0, 10.0), (75.0, 200.0), (89.0, 45.0)] {
        for (ti, pi) in [(0.0, 0.0), (20.0, 90.0), (60.0, 300.0), (88.0, 180.0)] {
            let (wo, _) = dir32(to, po);
            let (wi, wi64) = dir32(ti, pi);
            for mode in [Transport::Radiance, Transport::Importance] {
                let e = l.eval(p.as_slice(), wo, wi, mode);
                let what = format!("lambert wo ({to}, {po}) wi ({ti}, {pi}) {mode:?}");
                let want = COLOR.map(|c| f64::from(c) / PI * wi64.z);
                assert_close3(e.value.to_array(), want, 1e-6, 1e-9, &what);
                assert_close(f64::from(e.pdf), wi64.z / PI, 1e-6, 1e-9, &what);
            }
        }
    }
}

#[test]
fn below_horizon_is_zero() {
    let l = lobe("lambert");
    let p = params();
    let up = dir32(30.0, 0.0).0;
    let down = dir32(120.0, 40.0).0;
    for (wo, wi) in [(up, down), (down, up), (down, down)] {
        let e = l.eval(p.as_slice(), wo, wi, Transport::Radiance);
        assert_eq!(e.value.to_array(), [0.0; 3]);
        assert_eq!(e.pdf, 0.0);
    }
    assert_eq!(
        l.albedo(p.as_slice(), down, Transport::Radiance).to_array(),
        [0.0; 3]
    );
    let mut rng = Rng::new(7);
    for _ in 0..100 {
        let s = l.sample(p.as_slice(), down, rng.u3(), Transport::Radiance);
        assert!(!s.valid, "a sample from below the surface must fail");
        assert_eq!(s.pdf, 0.0);
        assert_eq!(s.value.to_array(), [0.0; 3]);
    }
}

#[test]
fn albedo_is_color() {
    let l = lobe("lambert");
    let p = params();
    for t in [0.0, 45.0, 85.0] {
        let a = l.albedo(p.as_slice(), dir32(t, 0.0).0, Transport::Radiance);
        assert_eq!(a.to_array(), COLOR);
    }
}

#[test]
fn samples_are_cosine_distributed_with_weight_color() {
    let l = lobe("lambert");
    let p = params();
    let (wo, _) = dir32(40.0, 70.0);
    let mut rng = Rng::new(1);
    let n = 20_000;
    // Moments of cosine-weighted directions: E[cos] = 2/3, E[cos^2] = 1/2, E[x] = E[y] = 0.
    let (mut m1, mut m2, mut mx, mut my) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..n {
        let s = l.sample(p.as_slice(), wo, rng.u3(), Transport::Radiance);
        assert!(s.valid && !s.delta && !s.transmitted);
        let wi = V::from32(s.wi);
        assert!((wi.length() - 1.0).abs() < 1e-6 && wi.z >= 0.0);
        assert_close(f64::from(s.pdf), wi.z / PI, 1e-5, 1e-9, "sample pdf");
        let w = s.weight().to_array();
        for c in 0..3 {
            assert_close(f64::from(w[c]), f64::from(COLOR[c]), 1e-5, 0.0, "weight");
        }
        let e = l.eval(p.as_slice(), wo, s.wi, Transport::Radiance);
        assert_close3(
            s.value.to_array(),
            e.value.to_array().map(f64::from),
            1e-6,
            1e-9,
            "sample value vs eval",
        );
        m1 += wi.z;
        m2 += wi.z * wi.z;
        mx += wi.x;
        my += wi.y;
    }
    let n = n as f64;
    // Four standard errors: sd(cos) = sqrt(1/2 - 4/9) = 0.236, sd(x) = 0.5.
    assert!(
        (m1 / n - 2.0 / 3.0).abs() < 4.0 * 0.236 / n.sqrt(),
        "E[cos] = {}",
        m1 / n
    );
    // sd(cos^2) = sqrt(1/3 - 1/4).
    assert!(
        (m2 / n - 0.5).abs() < 4.0 * 0.289 / n.sqrt(),
        "E[cos^2] = {}",
        m2 / n
    );
    assert!((mx / n).abs() < 4.0 * 0.5 / n.sqrt() && (my / n).abs() < 4.0 * 0.5 / n.sqrt());
}
