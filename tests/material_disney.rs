//! The `disney` material against an independent f64 transcription of Burley 2012 as
//! `shared/reference/formulas.md` restates it (written here, not calling Glint), its
//! pruning against the full closure, and its albedo against quadrature.

mod common;
mod reference;

use common::Rng;
use glint::materials::{DEFAULT_PRUNE, Material, Override, ShadingContext};
use glint::math::{Frame, Vec3};
use glint::params::ParamKind;
use glint::registry::Registry;
use std::f64::consts::PI;

/// The 2012 parameters, in the material's schema order.
#[derive(Clone, Copy, Debug)]
struct Disney {
    base_color: [f64; 3],
    subsurface: f64,
    metallic: f64,
    specular: f64,
    specular_tint: f64,
    roughness: f64,
    anisotropic: f64,
    sheen: f64,
    sheen_tint: f64,
    clearcoat: f64,
    clearcoat_gloss: f64,
}

impl Disney {
    fn random(rng: &mut Rng) -> Disney {
        // Corners half of the time: 0 and 1 are where lobes switch off.
        let mut x = || match rng.f64() {
            u if u < 0.15 => 0.0,
            u if u < 0.3 => 1.0,
            _ => rng.f64(),
        };
        Disney {
            base_color: [x(), x(), x()],
            subsurface: x(),
            metallic: x(),
            specular: x(),
            specular_tint: x(),
            roughness: x(),
            anisotropic: x(),
            sheen: x(),
            sheen_tint: x(),
            clearcoat: x(),
            clearcoat_gloss: x(),
        }
    }

    fn block(&self) -> Vec<f32> {
        let mut b: Vec<f32> = self.base_color.iter().map(|&c| c as f32).collect();
        b.extend(
            [
                self.subsurface,
                self.metallic,
                self.specular,
                self.specular_tint,
                self.roughness,
                self.anisotropic,
                self.sheen,
                self.sheen_tint,
                self.clearcoat,
                self.clearcoat_gloss,
            ]
            .map(|v| v as f32),
        );
        b
    }

    /// The parameters as the material reads them (f32).
    fn rounded(&self) -> Disney {
        let r = |v: f64| f64::from(v as f32);
        Disney {
            base_color: self.base_color.map(r),
            subsurface: r(self.subsurface),
            metallic: r(self.metallic),
            specular: r(self.specular),
            specular_tint: r(self.specular_tint),
            roughness: r(self.roughness),
            anisotropic: r(self.anisotropic),
            sheen: r(self.sheen),
            sheen_tint: r(self.sheen_tint),
            clearcoat: r(self.clearcoat),
            clearcoat_gloss: r(self.clearcoat_gloss),
        }
    }

    /// `f(l, v)` (without the cosine), local frame, both above the surface.
    fn brdf(&self, l: [f64; 3], v: [f64; 3]) -> [f64; 3] {
        let [a, b, c] = self.brdf_terms(l, v);
        [0, 1, 2].map(|k| a[k] + b[k] + c[k])
    }

    /// The three terms of `f`: diffuse and sheen, specular, clearcoat.
    fn brdf_terms(&self, l: [f64; 3], v: [f64; 3]) -> [[f64; 3]; 3] {
        let (nl, nv) = (l[2], v[2]);
        if nl <= 0.0 || nv <= 0.0 {
            return [[0.0; 3]; 3];
        }
        let mix = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let sq = |x: f64| x * x;
        let schlick = |u: f64| (1.0 - u).clamp(0.0, 1.0).powi(5);
        let hu = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
        let len = (sq(hu[0]) + sq(hu[1]) + sq(hu[2])).sqrt();
        let h = hu.map(|c| c / len);
        let lh = l[0] * h[0] + l[1] * h[1] + l[2] * h[2];
        let nh = h[2];
        let c = self.base_color;
        let lum = 0.3 * c[0] + 0.6 * c[1] + 0.1 * c[2];
        let tint = c.map(|x| if lum > 0.0 { x / lum } else { 1.0 });
        let (fl, fv, fh) = (schlick(nl), schlick(nv), schlick(lh));
        let r = self.roughness;

        let fd90 = 0.5 + 2.0 * lh * lh * r;
        let fd = mix(1.0, fd90, fl) * mix(1.0, fd90, fv);
        let fss90 = lh * lh * r;
        let fss = mix(1.0, fss90, fl) * mix(1.0, fss90, fv);
        let ss = 1.25 * (fss * (1.0 / (nl + nv) - 0.5) + 0.5);

        let aspect = (1.0 - 0.9 * self.anisotropic).sqrt();
        let ax = (r * r / aspect).max(0.001);
        let ay = (r * r * aspect).max(0.001);
        let ds = 1.0 / (PI * ax * ay * sq(sq(h[0] / ax) + sq(h[1] / ay) + sq(h[2])));
        let ag = sq(0.5 + r / 2.0);
        let (axg, ayg) = ((ag / aspect).max(0.001), (ag * aspect).max(0.001));
        let smith =
            |w: [f64; 3]| 1.0 / (w[2] + (sq(w[0] * axg) + sq(w[1] * ayg) + sq(w[2])).sqrt());
        let gs = smith(l) * smith(v);

        let a = mix(0.1, 0.001, self.clearcoat_gloss);
        let dr = if a >= 1.0 {
            1.0 / PI
        } else {
            (a * a - 1.0) / (PI * (a * a).ln() * (1.0 + (a * a - 1.0) * nh * nh))
        };
        let fr = mix(0.04, 1.0, fh);
        let smith_iso =
            |cos: f64, a: f64| 1.0 / (cos + (a * a + cos * cos - a * a * cos * cos).sqrt());
        let gr = smith_iso(nl, 0.25) * smith_iso(nv, 0.25);

        let mut f = [[0.0; 3]; 3];
        for k in 0..3 {
            let cspec0 = mix(
                self.specular * 0.08 * mix(1.0, tint[k], self.specular_tint),
                c[k],
                self.metallic,
            );
            let csheen = mix(1.0, tint[k], self.sheen_tint);
            let fs = mix(cspec0, 1.0, fh);
            let fsheen = fh * self.sheen * csheen;
            f[0][k] =
                ((1.0 / PI) * mix(fd, ss, self.subsurface) * c[k] + fsheen) * (1.0 - self.metallic);
            f[1][k] = gs * fs * ds;
            f[2][k] = 0.25 * self.clearcoat * gr * fr * dr;
        }
        f
    }
}

fn registry() -> Registry {
    Registry::with_builtins()
}

fn material(registry: &Registry, d: &Disney, prune: f32) -> Material {
    let id = registry.find_material("disney").unwrap();
    Material::new(registry, id, Some(&d.block()), prune).unwrap()
}

fn direction(rng: &mut Rng) -> Vec3<f32> {
    let (ct, phi) = (rng.f64(), 2.0 * PI * rng.f64());
    let st = (1.0 - ct * ct).max(0.0).sqrt();
    Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32)
}

fn to64(v: Vec3<f32>) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

/// Whether f32 evaluation of `d` at `(l, v)` is well conditioned: its half vector
/// ([`half_vector_well_conditioned`]) and cosines of at least 1e-3.
fn well_conditioned(d: &Disney, l: [f64; 3], v: [f64; 3]) -> bool {
    l[2] > 1e-3 && v[2] > 1e-3 && half_vector_well_conditioned(d, l, v)
}

/// An f32 half vector is off by about 1e-7 (absolute) in `tan theta_h = t`, which
/// changes a distribution of width `alpha` by the relative `4e-7 t / (alpha^2 + t^2)`
/// (at most `2e-7 / alpha`, at `t = alpha`); cases where that exceeds 2e-5 for the
/// specular or (when present) the clearcoat are ill-conditioned. So are nearly opposite
/// directions: an f32 unit vector is unit to about 6e-8, which moves `1 + l.v` by as
/// much and `l.h` by `3e-8 / l.h`, which `FH = (1 - l.h)^5` amplifies five times; below
/// `l.h = 0.02` that exceeds 1e-5 (any formula for `l.h` hangs on those bits there).
fn half_vector_well_conditioned(d: &Disney, l: [f64; 3], v: [f64; 3]) -> bool {
    let cos2_d = (1.0 + l[0] * v[0] + l[1] * v[1] + l[2] * v[2]) / 2.0;
    if cos2_d < 0.02 * 0.02 {
        return false;
    }
    let hu = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let t = (hu[0] * hu[0] + hu[1] * hu[1]).sqrt() / hu[2];
    let kappa = |alpha: f64| 4e-7 * t / (alpha * alpha + t * t);
    let aspect = (1.0 - 0.9 * d.anisotropic).sqrt();
    let specular = (d.roughness * d.roughness * aspect).max(0.001);
    let coat = 0.1 + (0.001 - 0.1) * d.clearcoat_gloss;
    kappa(specular) < 2e-5 && (d.clearcoat == 0.0 || kappa(coat) < 2e-5)
}

#[test]
fn closure_eval_equals_the_2012_brdf() {
    let registry = registry();
    let mut rng = Rng::new(0x5eed_d15e);
    let (mut checked, mut worst) = (0, 0.0f64);
    for _ in 0..12_000 {
        let d = Disney::random(&mut rng);
        let m = material(&registry, &d, 0.0);
        let (v, l) = (direction(&mut rng), direction(&mut rng));
        let ctx = ShadingContext::new(v, Frame::IDENTITY);
        let closure = m.closure(&ctx, &[]).unwrap();
        let e = closure.eval(v, l).unwrap();
        let (l64, v64) = (to64(l), to64(v));
        if !well_conditioned(&d, l64, v64) {
            continue;
        }
        let want = d.rounded().brdf(l64, v64).map(|f| f * l64[2]);
        for (k, (&got, want)) in e.value.to_array().iter().zip(want).enumerate() {
            let err = (f64::from(got) - want).abs();
            let tol = 1e-4 * want.abs() + 1e-6;
            assert!(
                err <= tol,
                "channel {k}: {got} vs {want} (rel {:e}) at {d:?} l {l64:?} v {v64:?}",
                err / want.abs()
            );
            if want > 1e-3 {
                worst = worst.max(err / want);
            }
        }
        checked += 1;
    }
    assert!(checked >= 10_000, "{checked} well-conditioned pairs");
    eprintln!("worst relative error over {checked} pairs: {worst:e}");
}

/// Hostile geometry for the evals' merged denominators (one reciprocal per lobe, one
/// shared half vector): cosines down to the smallest denormal, 0, -0 and below,
/// directions nearly opposite and equal, at narrow, wide and anisotropic corners, on
/// the scalar call and every batch kernel set. Every value and pdf is finite and not
/// negative, both are 0 unless both directions are above the surface, and the value
/// follows the 2012 BRDF (1e-4 relative, 1e-6 absolute: grazing values are tiny)
/// wherever the half vector is well conditioned.
#[test]
fn hostile_geometry_is_finite_and_follows_the_2012_brdf() {
    let registry = registry();
    let every = Disney {
        base_color: [0.8, 0.2, 0.1],
        subsurface: 0.5,
        metallic: 0.3,
        specular: 0.5,
        specular_tint: 0.5,
        roughness: 0.0,
        anisotropic: 1.0,
        sheen: 1.0,
        sheen_tint: 0.5,
        clearcoat: 1.0,
        clearcoat_gloss: 1.0,
    };
    let corners = [
        every,
        Disney {
            roughness: 1.0,
            anisotropic: 0.0,
            clearcoat_gloss: 0.0,
            ..every
        },
        Disney {
            roughness: 0.5,
            anisotropic: 0.5,
            clearcoat_gloss: 0.5,
            ..every
        },
    ];
    let cosines: [f64; 11] = [
        1.0, 0.5, 1e-3, 1e-7, 1e-20, 1e-38, 1e-45, 0.0, -0.0, -1e-38, -0.5,
    ];
    let mut dirs = Vec::new();
    for phi in [0.0, 0.5 * PI, PI, 1.3] {
        for &z in &cosines {
            let s = (1.0 - z * z).sqrt();
            let (x, y) = ((s * f64::cos(phi)) as f32, (s * f64::sin(phi)) as f32);
            dirs.push(Vec3::try_unit(x, y, z as f32, "w").unwrap());
        }
    }
    let (mut wo, mut wi) = (Vec::new(), Vec::new());
    for &o in &dirs {
        for &i in &dirs {
            wo.push(o);
            wi.push(i);
        }
    }
    let mut compared = 0;
    for d in corners {
        let m = material(&registry, &d, 0.0);
        let ctx = ShadingContext::new(Vec3::new(0.0, 0.0, 1.0), Frame::IDENTITY);
        let closure = m.closure(&ctx, &[]).unwrap();
        for (source, lanes) in common::eval_on_every_kernel_set(&closure, &wo, &wi) {
            for (k, &(value, pdf)) in lanes.iter().enumerate() {
                let (o, i) = (to64(wo[k]), to64(wi[k]));
                let at = format!("{d:?} {source}: wo {o:?} wi {i:?}");
                assert!(
                    value.iter().all(|v| v.is_finite() && *v >= 0.0)
                        && pdf.is_finite()
                        && pdf >= 0.0,
                    "{at}: value {value:?} pdf {pdf:e}"
                );
                if !(o[2] > 0.0 && i[2] > 0.0) {
                    assert_eq!((value, pdf), ([0.0; 3], 0.0), "{at}: below the surface");
                    continue;
                }
                if !half_vector_well_conditioned(&d, i, o) {
                    continue;
                }
                let want = d.rounded().brdf(i, o).map(|f| f * i[2]);
                for (&got, want) in value.iter().zip(want) {
                    let got = f64::from(got);
                    assert!(
                        (got - want).abs() <= 1e-4 * want.abs() + 1e-6,
                        "{at}: value {got:e}, reference {want:e}"
                    );
                }
                compared += 1;
            }
        }
    }
    assert!(compared >= 2000, "{compared} pairs compared");
}

/// Base colors down to the smallest denormal keep their hue (`Ctint = base_color /
/// Cdlum`, whose reciprocal overflowed for a denormal luminance: values NaN and
/// infinite): the closure's eval follows the 2012 BRDF on the scalar call and every
/// kernel set, its albedo and samples are finite, and a material batch with these
/// colors as per-lane overrides gives each lane its closure's eval.
#[test]
fn tiny_base_colors_keep_their_hue() {
    use glint::batch::material::{MaterialInput, OverrideLanes};
    let registry = registry();
    let tinted = Disney {
        base_color: [0.0; 3],
        subsurface: 0.5,
        metallic: 0.3,
        specular: 0.5,
        specular_tint: 1.0,
        roughness: 0.5,
        anisotropic: 0.0,
        sheen: 1.0,
        sheen_tint: 1.0,
        clearcoat: 1.0,
        clearcoat_gloss: 0.5,
    };
    let colors: [[f32; 3]; 7] = [
        [0.0, 0.0, 1e-44],
        [1e-44, 0.0, 0.0],
        [0.0, 1.4e-45, 0.0],
        [1e-40, 1e-41, 0.0],
        [1e-38, 0.0, 2e-39],
        [3e-38, 1e-38, 1e-37],
        [0.8, 0.2, 0.1],
    ];
    let (o, i) = (
        Vec3::new(0.3f32, 0.2, 0.93).normalize(),
        Vec3::new(-0.2f32, 0.1, 0.97).normalize(),
    );
    let ctx = ShadingContext::new(o, Frame::IDENTITY);
    let mut want = Vec::new();
    for c in colors {
        let d = Disney {
            base_color: c.map(f64::from),
            ..tinted
        };
        let closure = material(&registry, &d, 0.0).closure(&ctx, &[]).unwrap();
        let reference = d.rounded().brdf(to64(i), to64(o)).map(|f| f * to64(i)[2]);
        for (source, lanes) in common::eval_on_every_kernel_set(&closure, &[o], &[i]) {
            let (value, pdf) = lanes[0];
            assert!(pdf.is_finite() && pdf > 0.0, "{c:?} {source}: pdf {pdf}");
            for (&got, want) in value.iter().zip(reference) {
                let got = f64::from(got);
                assert!(
                    (got - want).abs() <= 1e-4 * want.abs() + 1e-7,
                    "{c:?} {source}: value {value:?}, reference {reference:?}"
                );
            }
        }
        let albedo = closure.albedo(o).unwrap();
        let finite = |v: glint::math::Rgb<f32>| [v.r, v.g, v.b].iter().all(|x| x.is_finite());
        assert!(finite(albedo), "{c:?}: albedo {albedo:?}");
        for u in [[0.1, 0.3, 0.7], [0.5, 0.6, 0.2], [0.9, 0.8, 0.4]] {
            let s = closure.sample(o, u).unwrap();
            assert!(finite(s.weight) && s.pdf.is_finite(), "{c:?}: {s:?}");
        }
        want.push(closure.eval_forward(o, i).unwrap());
    }
    // The material batch, the colors as per-lane overrides.
    let m = material(&registry, &tinted, 0.0);
    let n = colors.len();
    let base: [Vec<f32>; 3] = [0, 1, 2].map(|k| colors.iter().map(|c| c[k]).collect());
    let rows = |v: Vec3<f32>| [vec![v.x; n], vec![v.y; n], vec![v.z; n]];
    let (wo, wi, normal) = (rows(o), rows(i), rows(Vec3::new(0.0, 0.0, 1.0)));
    let overrides = [OverrideLanes {
        param: 0,
        kind: ParamKind::Rgb,
        value: [&base[0], &base[1], &base[2]],
    }];
    let input = MaterialInput {
        count: n,
        material: &m,
        active: None,
        wo: common::soa(&wo),
        normal: common::soa(&normal),
        tangent: None,
        overrides: &overrides,
    };
    for kernels in glint::simd::Kernels::available() {
        let (value, pdf) = common::material_eval(kernels, &input, common::soa(&wi));
        for (lane, e) in want.iter().enumerate() {
            let got = [value[0][lane], value[1][lane], value[2][lane], pdf[lane]];
            let want = [e.value.r, e.value.g, e.value.b, e.pdf];
            for (a, b) in got.iter().zip(want) {
                assert!(
                    (a - b).abs() <= 1.5e-6 * b.abs().max(1e-30),
                    "{}: lane {lane} {got:?} vs closure {want:?}",
                    kernels.isa().name()
                );
            }
        }
    }
}

/// The closure emits only lobes that can contribute: no clearcoat at clearcoat 0, no
/// diffuse or sheen at metallic 1, no sheen at sheen 0; everything with every lobe on.
#[test]
fn only_contributing_lobes_are_emitted() {
    let registry = registry();
    let names = |d: &Disney| -> Vec<String> {
        let ctx = ShadingContext::new(Vec3::new(0.0, 0.6, 0.8), Frame::IDENTITY);
        material(&registry, d, 0.0)
            .closure(&ctx, &[])
            .unwrap()
            .lobes()
            .iter()
            .map(|l| l.lobe.name().to_string())
            .collect()
    };
    let base = Disney {
        base_color: [0.8, 0.5, 0.2],
        subsurface: 0.0,
        metallic: 0.0,
        specular: 0.5,
        specular_tint: 0.0,
        roughness: 0.5,
        anisotropic: 0.0,
        sheen: 0.0,
        sheen_tint: 0.5,
        clearcoat: 0.0,
        clearcoat_gloss: 1.0,
    };
    assert_eq!(names(&base), ["disney_diffuse", "disney_specular"]);
    let metal = Disney {
        metallic: 1.0,
        sheen: 1.0,
        ..base
    };
    assert_eq!(names(&metal), ["disney_specular"]);
    let all = Disney {
        sheen: 1.0,
        clearcoat: 1.0,
        metallic: 0.5,
        ..base
    };
    assert_eq!(
        names(&all),
        [
            "disney_diffuse",
            "disney_sheen",
            "disney_specular",
            "disney_clearcoat"
        ]
    );
}

/// A material closure's shape id (looked up per set of emitted slots) is the one a
/// closure of the same lobes built lobe by lobe gets, for every subset of the slots the
/// pruning and the parameters leave.
#[test]
fn shape_ids_are_those_of_the_same_lobes_added_one_by_one() {
    let registry = registry();
    let mut rng = Rng::new(41);
    let mut seen = std::collections::HashSet::new();
    for i in 0..400 {
        let mut d = Disney::random(&mut rng);
        // Some materials without sheen, clearcoat or diffuse.
        for (bit, value) in [
            (1, &mut d.sheen),
            (2, &mut d.clearcoat),
            (4, &mut d.metallic),
        ] {
            if i & bit != 0 {
                *value = if bit == 4 { 1.0 } else { 0.0 };
            }
        }
        let prune = [0.0, 0.02, 0.2][i % 3];
        let ctx = ShadingContext::new(direction(&mut rng), Frame::IDENTITY);
        let built = material(&registry, &d, prune).closure(&ctx, &[]).unwrap();
        let mut by_hand =
            glint::closure::Closure::new(Some(ctx.wo), glint::lobes::Transport::Radiance);
        for (k, l) in built.lobes().iter().enumerate() {
            let w = l.weight;
            by_hand
                .add_lobe(
                    &registry,
                    l.type_id,
                    [w.r, w.g, w.b],
                    l.frame,
                    Some(built.lobe_params(k)),
                )
                .unwrap();
        }
        by_hand.finish().unwrap();
        assert_eq!(built.shape_id(), by_hand.shape_id(), "case {i}: {d:?}");
        assert!(built.same_shape(&by_hand));
        seen.insert(built.lobes().len());
    }
    assert_eq!(seen.len(), 4, "lobe counts covered: {seen:?}");
}

/// A compiled material decodes the slots its parameters fix once (the clearcoat's
/// gloss); a point whose override changes them decodes its own: both give the closure
/// of a material compiled with the point's values, bit for bit.
#[test]
fn overridden_and_compiled_values_give_the_same_closures() {
    let registry = registry();
    let id = registry.find_material("disney").unwrap();
    let ctx = ShadingContext::new(Vec3::new(0.3, 0.2, 0.93), Frame::IDENTITY);
    let wi = Vec3::new(-0.35, -0.25, 0.9);
    let with = |block: &[f32], overrides: &[Override]| {
        let m = Material::new(&registry, id, Some(block), 0.0).unwrap();
        let c = m.closure(&ctx, overrides).unwrap();
        (c.eval(ctx.wo, wi).unwrap(), c.albedo(ctx.wo).unwrap())
    };
    let defaults = Material::new(&registry, id, None, 0.0).unwrap();
    let base = defaults.params().to_vec();
    // clearcoat 1 (entry 9); the gloss (entry 10) compiled or overridden.
    let at = |entry: usize| glint::params::offset_of(defaults.kind().params(), entry);
    for gloss in [0.0, 0.37, 1.0] {
        let mut compiled = base.clone();
        compiled[at(9)] = 1.0;
        compiled[at(10)] = gloss;
        let mut other = compiled.clone();
        other[at(10)] = 1.0 - gloss * 0.5;
        let set = Override {
            param: 10,
            kind: ParamKind::Float,
            value: [gloss, 0.0, 0.0],
        };
        let want = with(&compiled, &[]);
        assert_eq!(with(&other, &[set]), want, "gloss {gloss} overridden");
        assert_eq!(with(&compiled, &[set]), want, "gloss {gloss} set to itself");
    }
}

/// Directional albedo of the reference (f64): the smooth diffuse and sheen term by a
/// midpoint rule over directions, the specular and clearcoat terms in slope space
/// (`reference::slope_space_albedo`, stretched by the specular's alphas and, for
/// GTR1's tails, by 0.1).
fn reference_albedo(d: &Disney, v: [f64; 3]) -> [f64; 3] {
    let (nt, np) = (400, 200);
    let mut sum = [0.0; 3];
    for i in 0..nt {
        // mu = cos theta_i = s^2 (dense at grazing); d(omega) = 2 s ds d(phi).
        let s = (i as f64 + 0.5) / nt as f64;
        let mu = s * s;
        let st = (1.0 - mu * mu).sqrt();
        for j in 0..np {
            let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let l = [st * phi.cos(), st * phi.sin(), mu];
            let f = d.brdf_terms(l, v)[0];
            let w = mu * 2.0 * s / nt as f64 * 2.0 * PI / np as f64;
            for k in 0..3 {
                sum[k] += f[k] * w;
            }
        }
    }
    let aspect = (1.0 - 0.9 * d.anisotropic).sqrt();
    let a = d.roughness * d.roughness;
    let (ax, ay) = ((a / aspect).max(0.001), (a * aspect).max(0.001));
    for (k, sum) in sum.iter_mut().enumerate() {
        *sum += reference::slope_space_albedo(ax, ay, v, 600, |l, v| d.brdf_terms(l, v)[1][k]);
        if d.clearcoat > 0.0 {
            *sum +=
                reference::slope_space_albedo(0.1, 0.1, v, 600, |l, v| d.brdf_terms(l, v)[2][k]);
        }
    }
    sum
}

/// The material's albedo (lobe selection, a scanline host's ambient term) against
/// quadrature of the reference: within 2% (luminance) up to anisotropic 0.5; above,
/// the specular's stated tolerance (up to 5% at anisotropic 1) applies.
#[test]
fn albedo_matches_quadrature() {
    let registry = registry();
    let mut rng = Rng::new(0x00a1_bed0);
    let mut worst = 0.0f64;
    for _ in 0..40 {
        let d = Disney::rounded(&Disney::random(&mut rng));
        let m = material(&registry, &d, 0.0);
        let v = direction(&mut rng);
        if v.z < 0.05 {
            continue;
        }
        let closure = m
            .closure(&ShadingContext::new(v, Frame::IDENTITY), &[])
            .unwrap();
        let got = closure.albedo(v).unwrap().to_array();
        let want = reference_albedo(&d, to64(v));
        let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let got = lum(got.map(f64::from));
        let want = lum(want);
        let err = (got - want).abs() / want.max(1e-3);
        worst = worst.max(err);
        assert!(
            err < 0.02,
            "albedo {got} vs {want} ({err:e}) at {d:?} wo {v:?}"
        );
    }
    eprintln!("worst albedo error: {worst:e}");
}

/// A pruned closure differs from the full one by at most the pruned lobes'
/// `luminance(weight * albedo(wo))`. Pruning weighs lobes by their albedo estimates,
/// so each may exceed the threshold by its estimate's tolerance (1% for the diffuse,
/// 0 for the sheen and clearcoat, which are what faint lobes are here); this sample
/// stays within the threshold itself. Checked on the albedo.
#[test]
fn pruning_error_is_bounded_by_the_threshold() {
    let registry = registry();
    let mut rng = Rng::new(0x9e11);
    let mut pruned_some = 0;
    for _ in 0..2000 {
        let mut d = Disney::random(&mut rng);
        // Weak lobes: faint sheen and clearcoat, near-metal.
        d.sheen *= 0.01;
        d.clearcoat *= 0.01;
        let v = direction(&mut rng);
        if v.z < 0.01 {
            continue;
        }
        let ctx = ShadingContext::new(v, Frame::IDENTITY);
        let full = material(&registry, &d, 0.0).closure(&ctx, &[]).unwrap();
        let pruned = material(&registry, &d, DEFAULT_PRUNE)
            .closure(&ctx, &[])
            .unwrap();
        let dropped = full.lobes().len() - pruned.lobes().len();
        pruned_some += usize::from(dropped > 0);
        let a = full.albedo(v).unwrap().luminance();
        let b = pruned.albedo(v).unwrap().luminance();
        assert!(
            a - b >= -1e-6 && a - b <= dropped as f32 * DEFAULT_PRUNE + 1e-6,
            "albedo {a} -> {b} with {dropped} lobes pruned"
        );
    }
    assert!(pruned_some > 100, "{pruned_some} closures pruned a lobe");
}

/// Overrides set textured parameters by index; bad ones are errors that name them.
#[test]
fn overrides_replace_parameters_and_are_checked() {
    let registry = registry();
    let id = registry.find_material("disney").unwrap();
    let m = Material::new(&registry, id, None, 0.0).unwrap();
    let ctx = ShadingContext::new(Vec3::new(0.0, 0.6, 0.8), Frame::IDENTITY);
    let red = Override {
        param: 0,
        kind: ParamKind::Rgb,
        value: [1.0, 0.0, 0.0],
    };
    let metal = Override {
        param: 2,
        kind: ParamKind::Float,
        value: [1.0, 0.0, 0.0],
    };
    let c = m.closure(&ctx, &[red, metal]).unwrap();
    let wi = Vec3::new(0.0, -0.6, 0.8);
    let e = c.eval(ctx.wo, wi).unwrap().value.to_array();
    assert!(e[0] > 0.0 && e[1] < e[0] * 0.2, "{e:?}");
    let mut block = m.params().to_vec();
    block[..3].copy_from_slice(&[1.0, 0.0, 0.0]);
    block[4] = 1.0;
    let direct = Material::new(&registry, id, Some(&block), 0.0).unwrap();
    assert_eq!(
        direct
            .closure(&ctx, &[])
            .unwrap()
            .eval(ctx.wo, wi)
            .unwrap()
            .value,
        c.eval(ctx.wo, wi).unwrap().value
    );
    for (bad, says) in [
        (Override { param: 11, ..metal }, "does not exist"),
        (
            Override {
                kind: ParamKind::Rgb,
                ..metal
            },
            "is a float, not an rgb",
        ),
        (
            Override {
                value: [1.5, 0.0, 0.0],
                ..metal
            },
            "outside its range",
        ),
        (
            Override {
                value: [f32::NAN, 0.0, 0.0],
                ..metal
            },
            "not finite",
        ),
        (
            Override {
                value: [f32::INFINITY, 0.0, 0.0],
                ..metal
            },
            "not finite",
        ),
        (
            Override {
                value: [-1e-45, 0.0, 0.0],
                ..metal
            },
            "outside its range",
        ),
        (
            Override {
                value: [0.5, f32::NEG_INFINITY, 0.5],
                ..red
            },
            "not finite",
        ),
        (
            Override {
                value: [0.5, 0.5, 1.0000001],
                ..red
            },
            "outside its range",
        ),
    ] {
        let Err(e) = m.closure(&ctx, &[red, bad]) else {
            panic!("{bad:?} was accepted");
        };
        assert!(e.message.contains("overrides[1]"), "{}", e.message);
        assert!(e.message.contains(says), "{}", e.message);
    }
    // The range's ends, a denormal and -0 are in range.
    for v in [0.0, -0.0, 1e-45, 1.0] {
        let edge = Override {
            value: [v; 3],
            ..red
        };
        let at = Override {
            value: [v, 0.0, 0.0],
            ..metal
        };
        assert!(m.closure(&ctx, &[edge, at]).is_ok(), "{v} was refused");
    }
}

/// A closure's sample is valued where a host evaluates the `wi` it returns (passed back
/// through the C boundary's normalization), for every lobe of the mixture: at roughness
/// 0 (alpha 0.001) one ulp of `wi` moves the specular value by about 1e-4.
#[test]
fn samples_are_valued_at_the_direction_returned() {
    let registry = registry();
    let mut rng = Rng::new(0x5a3e);
    let frame = Frame::new(
        Vec3::new(0.3f32, -0.5, 0.8).normalize(),
        Some(Vec3::new(1.0, 0.2, 0.1)),
    );
    let mut worst = 0.0f64;
    for i in 0..400 {
        let mut d = Disney::random(&mut rng);
        d.roughness = 0.0;
        d.clearcoat_gloss = 1.0;
        let local = direction(&mut rng);
        let wo = frame.to_world(if i % 2 == 0 {
            local
        } else {
            Vec3::new(0.6, 0.0, 0.8)
        });
        let wo = Vec3::try_unit(wo.x, wo.y, wo.z, "wo").unwrap();
        let Ok(closure) =
            material(&registry, &d, 0.0).closure(&ShadingContext::new(wo, frame), &[])
        else {
            continue;
        };
        for _ in 0..200 {
            let u = [rng.f32(), rng.f32(), rng.f32()];
            let Ok(s) = closure.sample(wo, u) else {
                continue;
            };
            if s.flags & glint::lobes::flags::SPECULAR != 0 {
                continue;
            }
            let wi = Vec3::try_unit(s.wi.x, s.wi.y, s.wi.z, "wi").unwrap();
            let e = closure.eval_forward(wo, wi).unwrap();
            let rel = |a: f32, b: f32| {
                f64::from((a - b).abs()) / f64::from(a.abs().max(b.abs()).max(1e-30))
            };
            worst = worst
                .max(rel(s.pdf, e.pdf))
                .max(rel(s.value.r, e.value.r))
                .max(rel(s.value.g, e.value.g))
                .max(rel(s.value.b, e.value.b));
        }
    }
    assert!(worst < 1e-5, "sample vs eval at the returned wi: {worst:e}");
}

/// A material batch's pdf is its lane's closure's within `BATCH_TOLERANCE` with
/// subsurface, on every kernel set: the batch weighs the lobes by the diffuse's albedo
/// estimate on SIMD lanes, the closure on the scalar lane. A white, rough, anisotropic
/// material with a glossy clearcoat at per-lane roughness and subsurface; first the
/// audit's lane (`cos_o` 0.99, `wi` grazing: 2.7e-5 apart while the subsurface fit
/// cancelled). No pruning, so both keep every lobe.
#[test]
fn batch_pdf_with_subsurface_is_the_closures() {
    use glint::batch::material::{MaterialInput, OverrideLanes};
    use glint::verify::BATCH_TOLERANCE;
    let registry = registry();
    let d = Disney {
        base_color: [1.0; 3],
        subsurface: 1.0,
        metallic: 0.0,
        specular: 1.0,
        specular_tint: 0.0,
        roughness: 1.0,
        anisotropic: 1.0,
        sheen: 0.0,
        sheen_tint: 0.5,
        clearcoat: 1.0,
        clearcoat_gloss: 0.0,
    };
    let m = material(&registry, &d, 0.0);
    let index = |name: &str| common::param_index(&m, name);
    let unit = |v: Vec3<f32>| Vec3::try_unit(v.x, v.y, v.z, "w").unwrap();
    let n = 2048;
    let mut rng = Rng::new(0x55bd);
    // (-0x1.c89bcap-5, 0x1.f1e342p-4, 0x1.fb66c8p-1)
    let mut wo = vec![Vec3::new(-0.05573835, 0.12155462, 0.99101853)];
    let mut wi = vec![Vec3::new(1.0, 0.0, 0.01)];
    let (mut roughness, mut subsurface) = (vec![1.0f32], vec![1.0f32]);
    while wo.len() < n {
        wo.push(direction(&mut rng));
        wi.push(direction(&mut rng));
        roughness.push(rng.f32());
        subsurface.push(if rng.f64() < 0.2 { 1.0 } else { rng.f32() });
    }
    let want: Vec<f32> = (0..n)
        .map(|i| {
            let per_lane =
                [("roughness", roughness[i]), ("subsurface", subsurface[i])].map(|(name, v)| {
                    Override {
                        param: index(name),
                        kind: ParamKind::Float,
                        value: [v, 0.0, 0.0],
                    }
                });
            let ctx = ShadingContext::new(unit(wo[i]), Frame::IDENTITY);
            let c = m.closure(&ctx, &per_lane).unwrap();
            c.eval_forward(ctx.wo, unit(wi[i])).unwrap().pdf
        })
        .collect();
    let (wo, wi) = (common::rows(&wo), common::rows(&wi));
    let normal = [vec![0.0; n], vec![0.0; n], vec![1.0; n]];
    let overrides =
        [("roughness", &roughness), ("subsurface", &subsurface)].map(|(name, v)| OverrideLanes {
            param: index(name),
            kind: ParamKind::Float,
            value: [&v[..], &[], &[]],
        });
    let input = MaterialInput {
        count: n,
        material: &m,
        active: None,
        wo: common::soa(&wo),
        normal: common::soa(&normal),
        tangent: None,
        overrides: &overrides,
    };
    for kernels in glint::simd::Kernels::available() {
        let (_, pdf) = common::material_eval(kernels, &input, common::soa(&wi));
        let worst = (0..n)
            .map(|i| (f64::from((pdf[i] - want[i]).abs() / want[i].max(1e-30)), i))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        let isa = kernels.isa().name();
        eprintln!(
            "{isa}: batch pdf vs closure, worst {:.2e} (lane {})",
            worst.0, worst.1
        );
        let i = worst.1;
        assert!(
            worst.0 <= BATCH_TOLERANCE,
            "{isa} lane {i}: roughness {} subsurface {}: batch pdf {} vs closure {}",
            roughness[i],
            subsurface[i],
            pdf[i],
            want[i]
        );
    }
}
