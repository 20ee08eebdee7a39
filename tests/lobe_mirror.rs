//! `mirror`: a delta lobe. eval and pdf are 0; a sample is the mirror direction with
//! value = F(cos_o) (f64 reference for each Fresnel mode), pdf = 1 and the SPECULAR flag;
//! albedo = F(cos_o); nothing below the surface.

mod common;
mod reference;

use common::{Block, Rng, assert_close3, lobe};
use glint::Closure;
use glint::lobes::{Transport, flags};
use glint::math::{Frame, Vec3};
use glint::registry::Registry;
use reference::{Fresnel, dir32};

fn cases() -> Vec<(String, Block, Fresnel)> {
    let l = lobe("mirror");
    let d = Block::defaults(l);
    vec![
        (
            "default (white)".into(),
            d.clone(),
            Fresnel::schlick([1.0; 3], [1.0; 3]),
        ),
        (
            "schlick".into(),
            d.clone()
                .choice("fresnel", "schlick")
                .rgb("f0", [0.04, 0.5, 0.9])
                .rgb("f90", [1.0, 0.7, 0.95]),
            Fresnel::schlick([0.04, 0.5, 0.9], [1.0, 0.7, 0.95]),
        ),
        (
            "conductor".into(),
            d.clone()
                .choice("fresnel", "conductor")
                .rgb("eta", [0.14, 0.37, 1.44])
                .rgb("k", [4.0, 2.4, 1.9]),
            Fresnel::conductor([0.14, 0.37, 1.44], [4.0, 2.4, 1.9]),
        ),
        (
            "artistic".into(),
            d.choice("fresnel", "artistic")
                .rgb("reflectivity", [0.97, 0.7, 0.3])
                .rgb("edge_tint", [0.9, 0.6, 0.2]),
            Fresnel::artistic([0.97, 0.7, 0.3], [0.9, 0.6, 0.2]),
        ),
    ]
}

#[test]
fn delta_reflection_with_each_fresnel_mode() {
    let l = lobe("mirror");
    let mut rng = Rng::new(4);
    for (name, b, f) in cases() {
        for (t, p) in [
            (0.0, 0.0),
            (20.0, 45.0),
            (50.0, 130.0),
            (75.0, 250.0),
            (89.5, 10.0),
        ] {
            let (wo, wo64) = dir32(t, p);
            let what = format!("mirror {name} wo ({t}, {p})");
            let want = f.eval(wo64.z);
            let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
            for mode in [Transport::Radiance, Transport::Importance] {
                let e = l.eval(b.as_slice(), wo, mirror, mode);
                assert_eq!((e.value.to_array(), e.pdf), ([0.0; 3], 0.0), "{what}: eval");
                let s = l.sample(b.as_slice(), wo, rng.u3(), mode);
                assert!(s.valid && s.delta && !s.transmitted, "{what}");
                assert_eq!(s.wi, mirror, "{what}: direction");
                assert_eq!(s.pdf, 1.0, "{what}: pdf");
                assert_eq!((s.eta, s.roughness), (1.0, 0.0));
                assert_close3(
                    s.value.to_array(),
                    want,
                    1e-4,
                    0.0,
                    &format!("{what}: value"),
                );
                assert_close3(
                    s.weight().to_array(),
                    want,
                    1e-4,
                    0.0,
                    &format!("{what}: weight"),
                );
                let a = l.albedo(b.as_slice(), wo, mode);
                assert_close3(a.to_array(), want, 1e-4, 0.0, &format!("{what}: albedo"));
            }
        }
    }
}

#[test]
fn artistic_reflectivity_is_normal_incidence_reflectance() {
    // Gulbrandsen's mapping is built so that F(0 deg) = reflectivity; F -> 1 at grazing.
    let l = lobe("mirror");
    let r = [0.97f32, 0.7, 0.3];
    let b = Block::defaults(l)
        .choice("fresnel", "artistic")
        .rgb("reflectivity", r)
        .rgb("edge_tint", [0.9, 0.6, 0.2]);
    let a = l.albedo(b.as_slice(), dir32(0.0, 0.0).0, Transport::Radiance);
    assert_close3(a.to_array(), r.map(f64::from), 1e-4, 0.0, "F(0 deg)");
    let (wo, wo64) = dir32(89.99, 0.0);
    let a = l.albedo(b.as_slice(), wo, Transport::Radiance);
    let want = Fresnel::artistic(r, [0.9, 0.6, 0.2]).eval(wo64.z);
    assert!(want.iter().all(|f| *f > 0.99 && *f < 1.0));
    assert_close3(a.to_array(), want, 1e-4, 0.0, "F(89.99 deg)");
}

#[test]
fn nothing_below_the_surface() {
    let l = lobe("mirror");
    let mut rng = Rng::new(9);
    for (name, b, _) in cases() {
        let (wo, _) = dir32(120.0, 30.0);
        let s = l.sample(b.as_slice(), wo, rng.u3(), Transport::Radiance);
        assert!(!s.valid, "{name}");
        assert_eq!((s.pdf, s.value.to_array()), (0.0, [0.0; 3]), "{name}");
        let a = l.albedo(b.as_slice(), wo, Transport::Radiance);
        assert_eq!(a.to_array(), [0.0; 3], "{name}");
    }
}

#[test]
fn closure_sample_is_specular_reflection() {
    let registry = Registry::with_builtins();
    let id = registry.find("mirror").unwrap();
    let mut rng = Rng::new(6);
    for (name, b, f) in cases() {
        let (wo, wo64) = dir32(35.0, 80.0);
        let mut c = Closure::new(Some(wo), Transport::Radiance);
        c.add_lobe(
            &registry,
            id,
            [0.5, 1.0, 2.0],
            Frame::IDENTITY,
            Some(b.as_slice()),
        )
        .unwrap();
        c.finish().unwrap();
        let s = c.sample(wo, rng.u3()).unwrap();
        assert_eq!(s.flags, flags::REFLECTION | flags::SPECULAR, "{name}");
        assert_eq!(s.wi, Vec3::new(-wo.x, -wo.y, wo.z));
        assert_eq!(s.pdf, 1.0);
        let fw = f.eval(wo64.z);
        let want = [0.5 * fw[0], fw[1], 2.0 * fw[2]];
        assert_close3(
            s.weight.to_array(),
            want,
            1e-4,
            0.0,
            &format!("{name}: weight"),
        );
        let e = c.eval(wo, s.wi).unwrap();
        assert_eq!(
            (e.value.to_array(), e.pdf, e.pdf_reverse),
            ([0.0; 3], 0.0, 0.0)
        );
    }
}
