//! Closures: the mixture's eval is the weighted sum of the lobes' evals and its pdf is
//! `sum_k p_k pdf_k` with `p_k` proportional to `luminance(weight_k albedo_k(wo))`
//! (expected values from the f64 references), mixture sampling is consistent with
//! eval and pdf and unbiased, per-lobe frames transform correctly, and the arena and
//! closure limits and states report the documented statuses.

mod common;
mod reference;

use common::{Block, Rng, assert_close, assert_close3, lobe};
use glint::closure::{MAX_LOBE_WEIGHT, MAX_LOBES};
use glint::lobes::{Transport, flags};
use glint::math::{Frame, Rgb, Vec3};
use glint::registry::Registry;
use glint::{Arena, Closure, Status};
use reference::{
    Fresnel, Micro, Ndf, V, cook_torrance, cook_torrance_albedo, walter, walter_albedo,
};
use std::f64::consts::PI;

const W_LAMBERT: [f32; 3] = [0.5, 0.4, 0.3];
const COLOR: [f32; 3] = [0.7, 0.5, 0.2];
const W_CONDUCTOR: [f32; 3] = [0.8, 0.8, 1.0];
const F0: [f32; 3] = [0.9, 0.6, 0.3];
const F90: [f32; 3] = [1.0, 0.9, 0.8];
const W_DIELECTRIC: [f32; 3] = [0.3, 0.35, 0.4];
const W_MIRROR: [f32; 3] = [0.2, 0.2, 0.2];

fn id(registry: &Registry, name: &str) -> u32 {
    registry.find(name).unwrap()
}

fn conductor_block() -> (Block, Micro, Fresnel) {
    (
        Block::defaults(lobe("conductor"))
            .float("roughness", 0.4)
            .float("anisotropic", 0.5)
            .choice("fresnel", "schlick")
            .rgb("f0", F0)
            .rgb("f90", F90),
        Micro::from_roughness(Ndf::Ggx, 0.4, 0.5),
        Fresnel::schlick(F0, F90),
    )
}

fn dielectric_block() -> (Block, Micro) {
    (
        Block::defaults(lobe("dielectric"))
            .choice("distribution", "beckmann")
            .float("roughness", 0.35)
            .float("eta", 1.45),
        Micro::from_roughness(Ndf::Beckmann, 0.35, 0.0),
    )
}

/// Lambert + conductor + dielectric (+ mirror), all in the identity frame.
fn mixture(wo: Vec3<f32>, with_mirror: bool) -> Closure {
    let mut c = Closure::new(Some(wo), Transport::Radiance);
    fill_mixture(&mut c, with_mirror);
    c
}

/// Add [`mixture`]'s lobes to the empty closure `c` and finish it.
fn fill_mixture(c: &mut Closure, with_mirror: bool) {
    let registry = Registry::with_builtins();
    let l = Block::defaults(lobe("lambert")).rgb("color", COLOR);
    let (cb, _, _) = conductor_block();
    let (db, _) = dielectric_block();
    let add = |c: &mut Closure, name: &str, w: [f32; 3], b: &Block| {
        c.add_lobe(
            &registry,
            id(&registry, name),
            w,
            Frame::IDENTITY,
            Some(b.as_slice()),
        )
        .unwrap()
    };
    assert_eq!(add(c, "lambert", W_LAMBERT, &l), 0);
    assert_eq!(add(c, "conductor", W_CONDUCTOR, &cb), 1);
    assert_eq!(add(c, "dielectric", W_DIELECTRIC, &db), 2);
    if with_mirror {
        let mb = Block::defaults(lobe("mirror"));
        assert_eq!(add(c, "mirror", W_MIRROR, &mb), 3);
    }
    c.finish().unwrap();
}

/// The f64 reference of each lobe of [`mixture`]: `(weight * f |cos_i|, pdf)`.
fn reference_lobes(wo: V, wi: V) -> [([f64; 3], f64); 3] {
    let (_, cm, cf) = conductor_block();
    let (_, dm) = dielectric_block();
    let lam = if wo.z > 0.0 && wi.z > 0.0 {
        (COLOR.map(|c| f64::from(c) / PI * wi.z), wi.z / PI)
    } else {
        ([0.0; 3], 0.0)
    };
    let con = cook_torrance(&cm, &cf, wo, wi);
    let (dv, dp) = walter(&dm, 1.45, wo, wi, false);
    let weigh = |w: [f32; 3], v: [f64; 3]| [0, 1, 2].map(|c| f64::from(w[c]) * v[c]);
    [
        (weigh(W_LAMBERT, lam.0), lam.1),
        (weigh(W_CONDUCTOR, con.0), con.1),
        (weigh(W_DIELECTRIC, [dv; 3]), dp),
    ]
}

fn luminance(c: Rgb<f32>) -> f64 {
    0.2126 * f64::from(c.r) + 0.7152 * f64::from(c.g) + 0.0722 * f64::from(c.b)
}

#[test]
fn selection_probabilities_follow_weighted_albedo() {
    for with_mirror in [false, true] {
        let (wo, _) = reference::dir32(40.0, 20.0);
        let c = mixture(wo, with_mirror);
        let shares: Vec<f64> = c
            .lobes()
            .iter()
            .enumerate()
            .map(|(k, l)| luminance(l.weight * l.lobe.albedo(c.lobe_params(k), wo, c.transport())))
            .collect();
        let total: f64 = shares.iter().sum();
        let sum: f64 = c.lobes().iter().map(|l| f64::from(l.probability)).sum();
        assert_close(sum, 1.0, 1e-6, 0.0, "probabilities sum to 1");
        for (k, l) in c.lobes().iter().enumerate() {
            assert!(l.probability > 0.0);
            assert_close(
                f64::from(l.probability),
                shares[k] / total,
                1e-5,
                0.0,
                "p_k",
            );
        }
    }
}

#[test]
fn mixture_eval_is_weighted_sum_and_pdf_is_mixture() {
    let mut rng = Rng::new(31);
    for (to, po) in [(10.0, 0.0), (45.0, 120.0), (75.0, 300.0)] {
        let (wo, wo64) = reference::dir32(to, po);
        let c = mixture(wo, true);
        let p: Vec<f64> = c.lobes().iter().map(|l| f64::from(l.probability)).collect();
        for _ in 0..300 {
            // Random directions over the whole sphere, plus some near the specular peak.
            let z = 2.0 * rng.f64() - 1.0;
            let phi = 2.0 * PI * rng.f64();
            let s = (1.0 - z * z).sqrt();
            let mut wi = V::new(s * phi.cos(), s * phi.sin(), z);
            if rng.f64() < 0.3 {
                wi = (V::new(-wo64.x, -wo64.y, wo64.z) + wi * 0.2).normalize();
            }
            let wi32 = wi.to32();
            let wi = V::from32(wi32);
            let lobes = reference_lobes(wo64, wi);
            let mut value = [0.0; 3];
            let mut pdf = 0.0;
            for (k, (v, pk)) in lobes.iter().enumerate() {
                for ch in 0..3 {
                    value[ch] += v[ch];
                }
                pdf += p[k] * pk;
            }
            let reverse: f64 = reference_lobes(wi, wo64)
                .iter()
                .enumerate()
                .map(|(k, (_, pk))| p[k] * pk)
                .sum();
            let e = c.eval(wo, wi32).unwrap();
            let what = format!("wo ({to}, {po}) wi {wi:?}");
            assert_close3(e.value.to_array(), value, 1e-4, 1e-12, &what);
            assert_close(f64::from(e.pdf), pdf, 1e-4, 1e-12, &what);
            assert_close(f64::from(e.pdf_reverse), reverse, 1e-4, 1e-12, &what);
            assert_close(f64::from(c.pdf(wo, wi32).unwrap()), pdf, 1e-4, 1e-12, &what);
            // Per lobe: eval_lobe and pdf_lobe are that lobe alone.
            for (k, (v, pk)) in lobes.iter().enumerate() {
                let el = c.eval_lobe(k, wo, wi32).unwrap();
                assert_close3(el.value.to_array(), *v, 1e-4, 1e-12, &what);
                assert_close(f64::from(el.pdf), *pk, 1e-4, 1e-12, &what);
                assert_eq!(c.pdf_lobe(k, wo, wi32).unwrap(), el.pdf);
            }
            // The mirror lobe is delta: nothing in eval.
            let em = c.eval_lobe(3, wo, wi32).unwrap();
            assert_eq!((em.value.to_array(), em.pdf), ([0.0; 3], 0.0));
        }
    }
}

#[test]
fn mixture_samples_are_consistent_and_unbiased() {
    let mut rng = Rng::new(37);
    let (to, po) = (35.0, 50.0);
    let (wo, wo64) = reference::dir32(to, po);
    let c = mixture(wo, true);
    let p: Vec<f64> = c.lobes().iter().map(|l| f64::from(l.probability)).collect();
    let n = 20_000;
    let mut counts = [0usize; 4];
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        let s = match c.sample(wo, rng.u3()) {
            Ok(s) => s,
            Err(e) => {
                assert_eq!(e.status, Status::NoSample);
                continue;
            }
        };
        counts[s.lobe as usize] += 1;
        let wi = V::from32(s.wi);
        let side = if wi.z > 0.0 {
            flags::REFLECTION
        } else {
            flags::TRANSMISSION
        };
        for ch in 0..3 {
            let w = f64::from(s.weight.to_array()[ch]);
            assert_close(
                w,
                f64::from(s.value.to_array()[ch]) / f64::from(s.pdf),
                1e-6,
                0.0,
                "weight = value / pdf",
            );
            sum[ch] += w;
            sum2[ch] += w * w;
        }
        if s.flags & flags::SPECULAR != 0 {
            assert_eq!(s.lobe, 3, "only the mirror is specular here");
            assert_eq!(s.flags, flags::REFLECTION | flags::SPECULAR);
            assert_close(f64::from(s.pdf), p[3], 1e-6, 0.0, "p_mirror * 1");
            // The default mirror reflects everything: value = its weight.
            assert_eq!(s.value.to_array(), W_MIRROR);
            continue;
        }
        let class = if s.lobe == 0 {
            flags::DIFFUSE
        } else {
            flags::GLOSSY
        };
        assert_eq!(s.flags, side | class, "flags of a lobe {} sample", s.lobe);
        let lobes = reference_lobes(wo64, wi);
        let value = [0, 1, 2].map(|ch| lobes.iter().map(|(v, _)| v[ch]).sum::<f64>());
        let pdf: f64 = lobes.iter().enumerate().map(|(k, (_, pk))| p[k] * pk).sum();
        let what = format!("lobe {} wi {wi:?}", s.lobe);
        assert_close3(s.value.to_array(), value, 1e-3, 1e-12, &what);
        assert_close(f64::from(s.pdf), pdf, 1e-3, 1e-12, &what);
    }
    // Lobe choice frequencies (4 standard errors).
    for k in 0..4 {
        let f = counts[k] as f64 / n as f64;
        let se = (p[k] * (1.0 - p[k]) / n as f64).sqrt();
        assert!(
            (f - p[k]).abs() < 4.0 * se,
            "lobe {k}: frequency {f} vs p {}",
            p[k]
        );
    }
    // Mean weight = sum_k weight_k albedo_k(wo), albedos from the f64 references.
    let (_, cm, cf) = conductor_block();
    let (_, dm) = dielectric_block();
    let ca = cook_torrance_albedo(&cm, &cf, wo64, 160);
    let (dr, dt) = walter_albedo(&dm, 1.45, wo64, false, 160);
    let mf = 1.0; // the default mirror: Schlick with f0 = f90 = 1
    for ch in 0..3 {
        let want = f64::from(W_LAMBERT[ch]) * f64::from(COLOR[ch])
            + f64::from(W_CONDUCTOR[ch]) * ca[ch]
            + f64::from(W_DIELECTRIC[ch]) * (dr + dt)
            + f64::from(W_MIRROR[ch]) * mf;
        let mean = sum[ch] / n as f64;
        let se = ((sum2[ch] / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            (mean - want).abs() < 4.0 * se,
            "channel {ch}: mean weight {mean} vs {want} (se {se:.1e})"
        );
    }
}

#[test]
fn sample_lobe_is_that_lobe_alone() {
    let mut rng = Rng::new(41);
    let (wo, wo64) = reference::dir32(50.0, 10.0);
    let c = mixture(wo, false);
    for k in 0..3 {
        for _ in 0..200 {
            let Ok(s) = c.sample_lobe(k, wo, rng.u3()) else {
                continue;
            };
            assert_eq!(s.lobe as usize, k);
            let (v, pk) = reference_lobes(wo64, V::from32(s.wi))[k];
            assert_close3(s.value.to_array(), v, 1e-3, 1e-12, &format!("lobe {k}"));
            assert_close(f64::from(s.pdf), pk, 1e-3, 1e-12, &format!("lobe {k}"));
        }
    }
}

/// A frame in f64 from a normal and a tangent hint (Gram-Schmidt), and the same vectors
/// in f32 for the library.
fn frame64(n: V, t_hint: V) -> ((V, V, V), Vec3<f32>, Vec3<f32>) {
    let n = n.normalize();
    let n32 = n.to32();
    let n = V::from32(n32);
    let t = (t_hint - n * n.dot(t_hint)).normalize();
    let b = n.cross(t);
    ((t, b, n), n32, t_hint.to32())
}

fn to_local((t, b, n): (V, V, V), w: V) -> V {
    V::new(w.dot(t), w.dot(b), w.dot(n))
}

#[test]
fn per_lobe_frames_transform_correctly() {
    let registry = Registry::with_builtins();
    let (cb, cm, cf) = conductor_block();
    // The conductor is anisotropic, so the tangent matters as much as the normal.
    let (fc, nc, tc) = frame64(V::new(0.3, -0.2, 1.0), V::new(1.0, 0.5, 0.0));
    let (fl, nl, _) = frame64(V::new(-0.4, 0.1, 1.0), V::new(1.0, 0.0, 0.0));
    let (wo, wo64) = reference::dir32(30.0, 200.0);
    let mut c = Closure::new(Some(wo), Transport::Radiance);
    let lb = Block::defaults(lobe("lambert")).rgb("color", COLOR);
    c.add_lobe(
        &registry,
        id(&registry, "conductor"),
        W_CONDUCTOR,
        Frame::new(nc, Some(tc)),
        Some(cb.as_slice()),
    )
    .unwrap();
    c.add_lobe(
        &registry,
        id(&registry, "lambert"),
        W_LAMBERT,
        Frame::new(nl, None),
        Some(lb.as_slice()),
    )
    .unwrap();
    c.finish().unwrap();
    let reference_at = |wi: V| {
        let (lo, li) = (to_local(fc, wo64), to_local(fc, wi));
        let (v, p) = cook_torrance(&cm, &cf, lo, li);
        let con = [0, 1, 2].map(|ch| f64::from(W_CONDUCTOR[ch]) * v[ch]);
        let (lo, li) = (to_local(fl, wo64), to_local(fl, wi));
        let lam = if lo.z > 0.0 && li.z > 0.0 {
            [0, 1, 2].map(|ch| f64::from(W_LAMBERT[ch] * COLOR[ch]) / PI * li.z)
        } else {
            [0.0; 3]
        };
        let lam_pdf = if lo.z > 0.0 && li.z > 0.0 {
            li.z / PI
        } else {
            0.0
        };
        (con, p, lam, lam_pdf)
    };
    let p0 = f64::from(c.lobes()[0].probability);
    let p1 = f64::from(c.lobes()[1].probability);
    let mut rng = Rng::new(43);
    let mut checked = 0;
    for _ in 0..400 {
        let z = rng.f64();
        let phi = 2.0 * PI * rng.f64();
        let s = (1.0 - z * z).sqrt();
        // Around the conductor's specular direction in its own frame, and random.
        let mut wi = V::new(s * phi.cos(), s * phi.sin(), z);
        if rng.f64() < 0.5 {
            let n = fc.2;
            wi = (wo64.reflect(n) + wi * 0.3).normalize();
        }
        let wi32 = wi.to32();
        let wi = V::from32(wi32);
        let (con, cp, lam, lp) = reference_at(wi);
        let what = format!("wi {wi:?}");
        let e0 = c.eval_lobe(0, wo, wi32).unwrap();
        assert_close3(e0.value.to_array(), con, 2e-4, 1e-12, &what);
        assert_close(f64::from(e0.pdf), cp, 2e-4, 1e-12, &what);
        let e1 = c.eval_lobe(1, wo, wi32).unwrap();
        assert_close3(e1.value.to_array(), lam, 2e-4, 1e-12, &what);
        let e = c.eval(wo, wi32).unwrap();
        let sum = [0, 1, 2].map(|ch| con[ch] + lam[ch]);
        assert_close3(e.value.to_array(), sum, 2e-4, 1e-12, &what);
        assert_close(f64::from(e.pdf), p0 * cp + p1 * lp, 2e-4, 1e-12, &what);
        // Against the lobe evaluated directly in its local frame.
        let frame = Frame::new(nc, Some(tc));
        let direct = c.lobes()[0].lobe.eval(
            c.lobe_params(0),
            frame.to_local(wo),
            frame.to_local(wi32),
            Transport::Radiance,
        );
        assert_eq!(
            e0.value.to_array(),
            (Rgb::from_array(W_CONDUCTOR) * direct.value).to_array()
        );
        if con[0] > 0.0 {
            checked += 1;
        }
    }
    assert!(checked > 100, "{checked}");
    // Samples come back in world space.
    for _ in 0..300 {
        let Ok(s) = c.sample(wo, rng.u3()) else {
            continue;
        };
        let wi = V::from32(s.wi);
        assert!((wi.length() - 1.0).abs() < 1e-5);
        let (con, cp, lam, lp) = reference_at(wi);
        let sum = [0, 1, 2].map(|ch| con[ch] + lam[ch]);
        let what = format!("sample of lobe {} wi {wi:?}", s.lobe);
        assert_close3(s.value.to_array(), sum, 1e-3, 1e-12, &what);
        assert_close(f64::from(s.pdf), p0 * cp + p1 * lp, 1e-3, 1e-12, &what);
        // A conductor sample is above the conductor's own surface.
        if s.lobe == 0 {
            assert!(to_local(fc, wi).z > 0.0);
        }
    }
}

#[test]
fn arena_capacity() {
    assert_eq!(
        Arena::<Closure>::new(0).err().unwrap().status,
        Status::InvalidArgument
    );
    let mut arena = Arena::new(3).unwrap();
    assert_eq!(arena.capacity(), 3);
    for i in 0..3 {
        let c = arena
            .alloc(Closure::new(None, Transport::Radiance))
            .unwrap();
        assert!(!c.is_finished());
        assert_eq!(arena.len(), i + 1);
    }
    let e = arena
        .alloc(Closure::new(None, Transport::Radiance))
        .err()
        .unwrap();
    assert_eq!(e.status, Status::ArenaFull);
    assert!(e.message.contains('3'), "{}", e.message);
    assert_eq!(arena.len(), 3);
    arena.reset();
    assert!(arena.is_empty());
    assert_eq!(arena.capacity(), 3);
    arena
        .alloc(Closure::new(None, Transport::Radiance))
        .unwrap();
}

/// Closures are sized to what they hold (the 16-slot record with two 512-float blocks
/// was 5560 bytes), and a slot reused after a reset keeps its storage and nothing
/// else: a closure built there, after a full 16-lobe one of another shape, evaluates,
/// samples and hashes its shape bit for bit as one built fresh.
#[test]
fn recycled_slots_build_closures_like_fresh_ones() {
    let size = std::mem::size_of::<Closure>();
    assert!(size <= 128, "a closure record is {size} bytes");
    let registry = Registry::with_builtins();
    let wo = Vec3::new(0.3f32, -0.2, 0.9);
    let wo = wo * (1.0 / wo.length_squared().sqrt());
    let fresh = mixture(wo, true);
    let mut arena = Arena::new(2).unwrap();
    for _ in 0..2 {
        let c = arena
            .alloc(Closure::new(None, Transport::Importance))
            .unwrap();
        for _ in 0..MAX_LOBES {
            c.add_lobe(
                &registry,
                id(&registry, "conductor"),
                [1.0; 3],
                Frame::IDENTITY,
                None,
            )
            .unwrap();
        }
        c.finish().unwrap();
    }
    arena.reset();
    assert!(arena.is_empty());
    let mode = Transport::Radiance;
    let c = arena
        .alloc_with(
            || panic!("the slot is recycled, not made"),
            |c| c.restart(Some(wo), mode),
        )
        .unwrap();
    assert!(!c.is_finished());
    assert!(c.lobes().is_empty());
    fill_mixture(c, true);
    assert_eq!(c.shape_id(), fresh.shape_id());
    assert!(c.same_shape(&fresh));
    let mut rng = Rng::new(7);
    for _ in 0..2000 {
        let [x, y, z] = rng.u3().map(|v| 2.0 * v - 1.0);
        let wi = Vec3::new(x, y, z + 1e-3);
        let wi = wi * (1.0 / wi.length_squared().sqrt());
        assert_eq!(c.eval(wo, wi).unwrap(), fresh.eval(wo, wi).unwrap());
        let u = rng.u3();
        assert_eq!(
            c.sample(wo, u).map_err(|e| e.status),
            fresh.sample(wo, u).map_err(|e| e.status)
        );
    }
}

#[test]
fn seventeenth_lobe_is_closure_full() {
    let registry = Registry::with_builtins();
    let lambert = id(&registry, "lambert");
    let mut c = Closure::new(None, Transport::Radiance);
    for k in 0..MAX_LOBES {
        assert_eq!(
            c.add_lobe(&registry, lambert, [1.0; 3], Frame::IDENTITY, None)
                .unwrap(),
            k
        );
    }
    assert_eq!(MAX_LOBES, 16);
    let e = c
        .add_lobe(&registry, lambert, [1.0; 3], Frame::IDENTITY, None)
        .unwrap_err();
    assert_eq!(e.status, Status::ClosureFull);
    assert_eq!(c.lobes().len(), 16);
    c.finish().unwrap();
    // 16 equal lobes: each chosen with probability 1/16, eval is 16 times one lobe.
    for l in c.lobes() {
        assert_close(f64::from(l.probability), 1.0 / 16.0, 1e-6, 0.0, "p");
    }
    let (wo, wi) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.6, 0.0, 0.8));
    let e = c.eval(wo, wi).unwrap();
    assert_close(
        f64::from(e.value.r),
        16.0 * 0.8 * 0.8 / PI,
        1e-5,
        0.0,
        "16 lobes",
    );
    assert_close(f64::from(e.pdf), 0.8 / PI, 1e-5, 0.0, "mixture pdf");
}

#[test]
fn unfinished_and_finished_states() {
    let registry = Registry::with_builtins();
    let lambert = id(&registry, "lambert");
    let mut c = Closure::new(None, Transport::Radiance);
    c.add_lobe(&registry, lambert, [1.0; 3], Frame::IDENTITY, None)
        .unwrap();
    let (wo, wi) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.6, 0.0, 0.8));
    let u = [0.5; 3];
    let states = [
        c.eval(wo, wi).err(),
        c.pdf(wo, wi).err(),
        c.sample(wo, u).err(),
        c.albedo(wo).err(),
        c.eval_lobe(0, wo, wi).err(),
        c.pdf_lobe(0, wo, wi).err(),
        c.sample_lobe(0, wo, u).err(),
        c.albedo_lobe(0, wo).err(),
    ];
    for (i, e) in states.into_iter().enumerate() {
        let e = e.unwrap_or_else(|| panic!("call {i} on an unfinished closure succeeded"));
        assert_eq!(e.status, Status::InvalidState, "call {i}: {}", e.message);
        assert!(e.message.contains("finish"), "{}", e.message);
    }
    c.finish().unwrap();
    assert_eq!(c.finish().unwrap_err().status, Status::InvalidState);
    let e = c
        .add_lobe(&registry, lambert, [1.0; 3], Frame::IDENTITY, None)
        .unwrap_err();
    assert_eq!(e.status, Status::InvalidState);
    assert!(c.eval(wo, wi).is_ok());
    // Finished: lobe index out of range, non-finite random numbers.
    assert_eq!(
        c.eval_lobe(1, wo, wi).unwrap_err().status,
        Status::OutOfRange
    );
    assert_eq!(
        c.sample(wo, [f32::NAN, 0.5, 0.5]).unwrap_err().status,
        Status::InvalidArgument
    );
    assert_close3(
        c.albedo(wo).unwrap().to_array(),
        [0.8; 3],
        1e-6,
        0.0,
        "albedo",
    );
}

#[test]
fn add_lobe_validates_its_arguments() {
    let registry = Registry::with_builtins();
    let mut c = Closure::new(None, Transport::Radiance);
    let conductor = id(&registry, "conductor");
    assert_eq!(
        c.add_lobe(&registry, 99, [1.0; 3], Frame::IDENTITY, None)
            .unwrap_err()
            .status,
        Status::OutOfRange
    );
    let e = c
        .add_lobe(
            &registry,
            conductor,
            [1.0, f32::NAN, 1.0],
            Frame::IDENTITY,
            None,
        )
        .unwrap_err();
    assert_eq!(e.status, Status::InvalidArgument);
    assert!(e.message.contains("weight[1]"), "{}", e.message);
    let short = [0.0f32; 3];
    assert_eq!(
        c.add_lobe(
            &registry,
            conductor,
            [1.0; 3],
            Frame::IDENTITY,
            Some(&short)
        )
        .unwrap_err()
        .status,
        Status::InvalidArgument
    );
    let b = Block::defaults(lobe("conductor")).float("roughness", 2.0);
    let e = c
        .add_lobe(
            &registry,
            conductor,
            [1.0; 3],
            Frame::IDENTITY,
            Some(b.as_slice()),
        )
        .unwrap_err();
    assert_eq!(e.status, Status::OutOfRange);
    assert!(e.message.contains("roughness"), "{}", e.message);
    let mut b = Block::defaults(lobe("conductor"));
    let at = b.offset("distribution");
    b.values[at] = 0.5;
    let e = c
        .add_lobe(
            &registry,
            conductor,
            [1.0; 3],
            Frame::IDENTITY,
            Some(b.as_slice()),
        )
        .unwrap_err();
    assert_eq!(e.status, Status::OutOfRange);
    assert!(e.message.contains("ggx, beckmann"), "{}", e.message);
    assert!(c.lobes().is_empty(), "failed adds leave nothing behind");
}

/// `count` lamberts (color 1) of weight `w`, normal +z.
fn lamberts(count: usize, w: f32) -> Result<Closure, glint::Error> {
    let registry = Registry::with_builtins();
    let block = Block::defaults(lobe("lambert")).rgb("color", [1.0; 3]);
    let mut c = Closure::new(None, Transport::Radiance);
    for _ in 0..count {
        c.add_lobe(
            &registry,
            id(&registry, "lambert"),
            [w; 3],
            Frame::new(Vec3::new(0.0, 0.0, 1.0), None),
            Some(block.as_slice()),
        )?;
    }
    c.finish()?;
    Ok(c)
}

/// Eval, sample and albedo of a closure, for a failure message.
fn describe(c: &Closure) -> String {
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    let wi = Vec3::new(-0.2, 0.1, 0.9).normalize();
    format!(
        "eval {:?}, sample {:?}, albedo {:?}",
        c.eval(wo, wi),
        c.sample(wo, [0.3, 0.6, 0.2]).map(|s| (s.pdf, s.weight)),
        c.albedo(wo)
    )
}

/// Weights beyond `MAX_LOBE_WEIGHT` are refused, from the Rust API and from JSON, with
/// a message naming the bound (issue 12, D7: two lamberts at 3e38 gave NO_SAMPLE, a
/// zero pdf with a nonzero value and an infinite albedo; sixteen at 1e38 an infinite
/// eval).
#[test]
fn lobe_weights_above_the_bound_are_refused() {
    let bound = format!("{:e}", MAX_LOBE_WEIGHT);
    for (count, w) in [
        (2, 3e38),
        (16, 1e38),
        (1, f32::MAX),
        (1, MAX_LOBE_WEIGHT * 1.0001),
    ] {
        let e = match lamberts(count, w) {
            Ok(c) => panic!("{count} lobes of weight {w:e} accepted: {}", describe(&c)),
            Err(e) => e,
        };
        assert_eq!(e.status, Status::OutOfRange, "{}", e.message);
        assert!(e.message.contains(&bound), "{}", e.message);
        assert!(e.message.contains("weight[0]"), "{}", e.message);
    }
    let json = r#"{"lobes": [{"type": "lambert", "weight": [1, 3e38, 1]}]}"#;
    let Err(e) = glint::json::closure_from_json(
        &Registry::with_builtins(),
        json,
        None,
        glint::materials::DEFAULT_PRUNE,
    ) else {
        panic!("JSON weight 3e38 accepted");
    };
    assert_eq!(e.status, Status::OutOfRange, "{}", e.message);
    assert!(
        e.message.contains(&bound) && e.message.contains("weight[1]"),
        "{}",
        e.message
    );
}

/// A full closure at the largest weight stays finite and consistent: the f64 value of
/// sixteen lamberts, `16 w cos_i / pi`, the pdf `cos_i / pi`, weight `16 w`.
#[test]
fn full_closures_at_the_largest_weight_stay_finite() {
    let w = MAX_LOBE_WEIGHT;
    let c = lamberts(MAX_LOBES, w).unwrap();
    let (wo, wi) = (
        Vec3::new(0.3, 0.2, 0.9).normalize(),
        Vec3::new(-0.2, 0.1, 0.9).normalize(),
    );
    for l in c.lobes() {
        assert_close(l.probability as f64, 1.0 / 16.0, 1e-6, 0.0, "probability");
    }
    let e = c.eval(wo, wi).unwrap();
    let cos_pi = f64::from(wi.z) / PI;
    let value = 16.0 * f64::from(w) * cos_pi;
    assert_close3(e.value.to_array(), [value; 3], 1e-5, 0.0, "value");
    assert_close(e.pdf as f64, cos_pi, 1e-5, 0.0, "pdf");
    let s = c.sample(wo, [0.3, 0.6, 0.2]).unwrap();
    let expected = 16.0 * f64::from(w);
    assert_close3(
        s.weight.to_array(),
        [expected; 3],
        1e-5,
        0.0,
        "sample weight",
    );
    let albedo = c.albedo(wo).unwrap();
    assert_close3(albedo.to_array(), [expected; 3], 1e-5, 0.0, "albedo");
}

/// Shape ids (the batch's O(1) grouping key) agree exactly when `same_shape` does:
/// parameters and frames do not change a shape; lobe types, their order, an
/// enumerated choice and the transport do.
#[test]
fn shape_ids_follow_same_shape() {
    let registry = Registry::with_builtins();
    let build = |names: &[&str], fresnel: &str, mode: Transport, roughness: f32| {
        let mut c = Closure::new(None, mode);
        for name in names {
            let mut block = Block::defaults(lobe(name));
            if *name == "conductor" {
                block = block
                    .choice("fresnel", fresnel)
                    .float("roughness", roughness);
            }
            let frame = Frame::new(Vec3::new(0.0, roughness, 1.0).normalize(), None);
            c.add_lobe(
                &registry,
                id(&registry, name),
                [1.0; 3],
                frame,
                Some(block.as_slice()),
            )
            .unwrap();
        }
        c.finish().unwrap();
        c
    };
    let r = Transport::Radiance;
    let base = build(&["lambert", "conductor"], "schlick", r, 0.3);
    let same = build(&["lambert", "conductor"], "schlick", r, 0.7);
    let others = [
        build(&["conductor", "lambert"], "schlick", r, 0.3),
        build(&["lambert", "conductor"], "conductor", r, 0.3),
        build(
            &["lambert", "conductor"],
            "schlick",
            Transport::Importance,
            0.3,
        ),
        build(&["lambert"], "schlick", r, 0.3),
    ];
    assert!(base.same_shape(&same) && base.shape_id() == same.shape_id());
    for o in &others {
        assert!(!base.same_shape(o));
        assert_ne!(base.shape_id(), o.shape_id());
    }
}
