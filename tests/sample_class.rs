//! The wider lobe contract: each sample's class (diffuse / glossy / specular) and
//! component, in the scalar closure calls and in every batch path (one shared
//! one-lobe closure in place, a shared mixture, per-lane closures staged), and the
//! `wo` bake (a mirror's Fresnel), checked against the f64 references of
//! `tests/reference`.

mod common;
mod reference;

use common::{Block, Rng, assert_close3, lobe, rows, soa, soa_mut};
use glint::batch::{self, BatchInput, ClosureSource, Exec, SampleOutput, SampleRandoms, Threads};
use glint::lobes::{Transport, flags};
use glint::math::{Frame, Vec3};
use glint::registry::Registry;
use glint::simd::Kernels;
use glint::{Closure, SampleResult};
use reference::{Fresnel, dir32, fresnel_dielectric};

const ETA: f32 = 1.5;

/// A finished closure of `lobes` (name, block), weight 1 each, built at `wo` if given.
fn closure(lobes: &[(&str, &Block)], wo: Option<Vec3<f32>>) -> Closure {
    let registry = Registry::with_builtins();
    let mut c = Closure::new(wo, Transport::Radiance);
    for (name, block) in lobes {
        let id = registry.find(name).expect("built-in lobe");
        c.add_lobe(
            &registry,
            id,
            [1.0; 3],
            Frame::new(Vec3::new(0.0, 0.0, 1.0), None),
            Some(block.as_slice()),
        )
        .expect("valid parameters");
    }
    c.finish().expect("a new closure finishes");
    c
}

fn dielectric(roughness: f32) -> Block {
    Block::defaults(lobe("dielectric"))
        .float("roughness", roughness)
        .float("eta", ETA)
}

/// The class and component a dielectric sample must report: the side from the
/// geometry (`wi` on `wo`'s side is reflection), specular at roughness 0.
fn expected_dielectric(wo: Vec3<f32>, s: &SampleResult, smooth: bool) -> (u32, u32) {
    let reflected = (s.wi.z > 0.0) == (wo.z > 0.0);
    let side = if reflected {
        flags::REFLECTION
    } else {
        flags::TRANSMISSION
    };
    let class = if smooth {
        flags::SPECULAR
    } else {
        flags::GLOSSY
    };
    (side | class, u32::from(!reflected))
}

#[test]
fn smooth_dielectric_samples_are_specular_reflection_0_or_transmission_1() {
    let c = closure(&[("dielectric", &dielectric(0.0))], None);
    for theta in [0.0, 30.0, 60.0, 85.0] {
        let (wo, wo64) = dir32(theta, 20.0);
        let f = fresnel_dielectric(wo64.z, f64::from(ETA)) as f32;
        // The event choice: below F reflects, above refracts.
        for (uc, reflected) in [(0.5 * f, true), (0.5 + 0.5 * f, false)] {
            let s = c
                .sample(wo, [uc, 0.3, 0.7])
                .expect("a smooth interface scatters");
            let (side, component) = if reflected {
                (flags::REFLECTION, 0)
            } else {
                (flags::TRANSMISSION, 1)
            };
            assert_eq!(s.flags, side | flags::SPECULAR, "theta {theta} uc {uc}");
            assert_eq!(s.component, component, "theta {theta} uc {uc}");
            assert_eq!(expected_dielectric(wo, &s, true), (s.flags, s.component));
        }
    }
}

#[test]
fn rough_dielectric_samples_are_glossy_with_the_side_as_component() {
    let c = closure(&[("dielectric", &dielectric(0.4))], None);
    let mut rng = Rng::new(14);
    let mut seen = [0usize; 2];
    for _ in 0..2000 {
        let (wo, _) = dir32(80.0 * rng.f64(), 360.0 * rng.f64());
        let Ok(s) = c.sample(wo, rng.u3()) else {
            continue;
        };
        assert_eq!(expected_dielectric(wo, &s, false), (s.flags, s.component));
        seen[s.component as usize] += 1;
    }
    assert!(
        seen[0] > 50 && seen[1] > 50,
        "both components sampled: {seen:?}"
    );
}

/// A batch sample's weight, flags and component per lane.
struct Sampled {
    weight: [Vec<f32>; 3],
    flags: Vec<u32>,
    component: Vec<u32>,
}

/// `batch::sample` over `wo` and the random rows `u` on `kernels`.
fn sample_batch<'a>(
    kernels: Kernels,
    closures: impl ClosureSource<'a>,
    wo: &'a [Vec<f32>; 3],
    u: &[Vec<f32>; 3],
) -> Sampled {
    let n = wo[0].len();
    let exec = Exec {
        kernels,
        threads: Threads::Caller,
    };
    let mut wi = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    let mut weight = wi.clone();
    let (mut pdf, mut flags, mut component) = (vec![0.0; n], vec![99; n], vec![99; n]);
    let input = BatchInput {
        count: n,
        closures,
        active: None,
        wo: soa(wo),
    };
    let randoms = SampleRandoms {
        u_lobe: &u[0],
        u0: &u[1],
        u1: &u[2],
    };
    let out = SampleOutput {
        wi: soa_mut(&mut wi),
        pdf: &mut pdf,
        weight: soa_mut(&mut weight),
        value: None,
        flags: Some(&mut flags),
        lobe: None,
        component: Some(&mut component),
        eta: None,
        roughness: None,
    };
    batch::sample(&exec, &input, randoms, out).expect("valid batch");
    Sampled {
        weight,
        flags,
        component,
    }
}

/// Every batch path's flags and component equal the scalar sample's, lane by lane.
fn batch_matches_scalar<'a>(
    closures: impl ClosureSource<'a> + Copy,
    scalar: &[&Closure],
    wo_rows: &'a [Vec<f32>; 3],
) {
    let n = scalar.len();
    let mut rng = Rng::new(3);
    let u_rows = [(); 3].map(|_| (0..n).map(|_| rng.f32()).collect::<Vec<_>>());
    for kernels in Kernels::available() {
        let b = sample_batch(kernels, closures, wo_rows, &u_rows);
        for i in 0..n {
            let wo = Vec3::new(wo_rows[0][i], wo_rows[1][i], wo_rows[2][i]);
            let u = [u_rows[0][i], u_rows[1][i], u_rows[2][i]];
            let (f, k) = scalar[i]
                .sample(wo, u)
                .map_or((0, 0), |s| (s.flags, s.component));
            assert_eq!((b.flags[i], b.component[i]), (f, k), "{kernels:?} lane {i}");
        }
    }
}

#[test]
fn batch_class_and_component_match_the_scalar_samples_on_every_path() {
    let (smooth, rough) = (dielectric(0.0), dielectric(0.4));
    let lambert = Block::defaults(lobe("lambert"));
    let n = 301;
    let mut rng = Rng::new(5);
    let wo: Vec<_> = (0..n)
        .map(|_| dir32(85.0 * rng.f64(), 360.0 * rng.f64()).0)
        .collect();
    let wo_rows = rows(&wo);
    for block in [&smooth, &rough] {
        // One shared one-lobe closure: sampled in place by the lobe's kernel.
        let one = closure(&[("dielectric", block)], None);
        batch_matches_scalar(&one, &vec![&one; n], &wo_rows);
        // One shared mixture: lobe choice and the mixture's finish over lanes.
        let mix = closure(&[("lambert", &lambert), ("dielectric", block)], None);
        batch_matches_scalar(&mix, &vec![&mix; n], &wo_rows);
    }
    // One closure per lane: grouped and staged, finished lane by lane.
    let all = [
        closure(&[("dielectric", &smooth)], None),
        closure(&[("lambert", &lambert), ("dielectric", &rough)], None),
        closure(&[("dielectric", &rough)], None),
    ];
    let per_lane: Vec<&Closure> = (0..n).map(|i| &all[i % all.len()]).collect();
    batch_matches_scalar(&per_lane[..], &per_lane, &wo_rows);
}

/// A mirror with a conductor's Fresnel (silver-like), whose `F(cos_o)` a closure
/// built with `wo` bakes.
fn conductor_mirror() -> (Block, Fresnel) {
    let (eta, k) = ([0.16, 0.14, 0.13], [4.0, 3.2, 2.4]);
    let b = Block::defaults(lobe("mirror"))
        .choice("fresnel", "conductor")
        .rgb("eta", eta)
        .rgb("k", k);
    (b, Fresnel::conductor(eta, k))
}

#[test]
fn a_baked_mirror_reads_its_bake_only_at_the_baked_wo() {
    let (block, fresnel) = conductor_mirror();
    let (wo, wo64) = dir32(70.0, 10.0);
    let baked = closure(&[("mirror", &block)], Some(wo));
    let unbaked = closure(&[("mirror", &block)], None);
    let at_wo = baked.sample(wo, [0.5; 3]).expect("reflects");
    assert_eq!(at_wo, unbaked.sample(wo, [0.5; 3]).expect("reflects"));
    assert_close3(
        at_wo.value.to_array(),
        fresnel.eval(wo64.z),
        1e-5,
        0.0,
        "F at the bake",
    );
    assert_eq!(baked.albedo(wo).unwrap(), unbaked.albedo(wo).unwrap());
    // Any other `wo` computes: the bake at 70 degrees would be far off at 20.
    for theta in [20.0, 69.9, 89.0] {
        let (other, other64) = dir32(theta, 200.0);
        let s = baked.sample(other, [0.5; 3]).expect("reflects");
        assert_close3(
            s.value.to_array(),
            fresnel.eval(other64.z),
            1e-5,
            0.0,
            "F elsewhere",
        );
        let a = baked.albedo(other).unwrap();
        assert_close3(
            a.to_array(),
            fresnel.eval(other64.z),
            1e-5,
            0.0,
            "albedo elsewhere",
        );
    }
}

#[test]
fn a_baked_mirror_in_batches_computes_each_lanes_fresnel() {
    let (block, fresnel) = conductor_mirror();
    let (wo, _) = dir32(70.0, 10.0);
    let baked = closure(&[("mirror", &block)], Some(wo));
    // Lanes at the baked `wo` and elsewhere, in one register and across registers.
    let n = 40;
    let dirs: Vec<_> = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                dir32(70.0, 10.0)
            } else {
                dir32(2.0 * i as f64, 7.0 * i as f64)
            }
        })
        .collect();
    let wo_rows = rows(&dirs.iter().map(|d| d.0).collect::<Vec<_>>());
    let u = [vec![0.5f32; n], vec![0.5f32; n], vec![0.5f32; n]];
    for kernels in Kernels::available() {
        let weight = sample_batch(kernels, &baked, &wo_rows, &u).weight;
        for (i, (_, d64)) in dirs.iter().enumerate() {
            let w = [weight[0][i], weight[1][i], weight[2][i]];
            assert_close3(
                w,
                fresnel.eval(d64.z),
                2e-5,
                0.0,
                &format!("{kernels:?} lane {i}"),
            );
        }
    }
}
