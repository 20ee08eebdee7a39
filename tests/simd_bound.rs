//! The batch entry points against the scalar calls at ill-conditioned inputs, on every
//! kernel set this CPU has (issue 12, A4): `conductor` (each Fresnel mode) and
//! `dielectric` with GGX and Beckmann normals, roughness from the delta threshold's
//! edge to 1 (alpha down to 1e-4 with anisotropy), the dielectric at eta 0.001, 0.7,
//! 1.0002, 1.5 and 1000 and from inside, their delta forms, `lambert` and `mirror`;
//! `cos_o` from 1 down to 1e-6; `wi` at and around the mirror and refracted directions
//! of the lobe's peak normal, sampled and random, and the samplers' far tails; in the
//! world frame and a tilted one.
//!
//! - Evaluations (value, pdf, reverse pdf, albedo) agree within `BATCH_TOLERANCE`
//!   relative plus `EVAL_ABS`, whatever the conditioning: the SIMD code rounds as the
//!   scalar code does but in the vectorized `exp` and in explicit `mul_add`s, whose
//!   last-bit differences nothing amplifies. (A fused `Vec3::dot` moved staged and
//!   local directions and half vectors by an ulp, which a narrow lobe at a grazing
//!   angle turns into any factor: the half vector's slope is a difference of nearly
//!   opposite unit vectors over `cos_o + cos_i`. The SIMD eval was 7.5% off at
//!   Beckmann r = 0.035, `cos_o` = 1e-3, and 1e23 times at alpha 1.3e-4, `cos_o` = 1e-5.)
//! - Samples: the samplers' vectorized `sin_cos`, `erf_inv` and `exp` move the
//!   direction (at most `SAMPLE_DIR`), and weight, pdf and value are each call's lobe
//!   at its own direction. Where the lobe is well conditioned ([`Case::conditioning`])
//!   every output is within the harness's `BATCH_SAMPLE_TOLERANCE`; elsewhere they
//!   differ as the lobe does between the two directions, by any factor (measured and
//!   printed, not bounded). Flags agree except where one call's sample is invalid and
//!   the other's direction or the view is within `HORIZON` of the surface (a view that
//!   grazes it reflects nearly backward, and the pair's half vector, the sum of nearly
//!   opposite vectors, decides the microfacet's side by rounding: 1 of 1.8M samples,
//!   at `cos_o` 1e-6, once the GGX sampler mapped its random numbers differently) or
//!   comes from the far tail `u0 > EDGE_ON` (microfacets seen edge-on, at the visible
//!   domain's boundary), and on at most `INDEX_MATCHED_FLAGS` of an index-matched
//!   dielectric's samples: its settled direction's validity hangs on a half vector
//!   that is a difference of nearly opposite vectors, which rounding decides (1 of its
//!   samples when caller directions within four ulps of unit length were first taken
//!   as they are).

mod common;
mod reference;

use common::{Block, Outputs, Rng, closure, lobe, rows, soa, soa_mut};
use glint::Closure;
use glint::batch::{self, BatchInput, EvalOutput, Exec, SampleOutput, SampleRandoms, Threads};
use glint::lobes::flags;
use glint::math::{Frame, Vec3};
use glint::simd::Kernels;
use glint::verify::{BATCH_SAMPLE_TOLERANCE, BATCH_TOLERANCE, batch_difference};
use reference::{Micro, Ndf, V};
use std::collections::BTreeMap;

/// Evaluations: `|batch - scalar| <= BATCH_TOLERANCE max(|batch|, |scalar|) + EVAL_ABS`.
/// `exp`'s result can be subnormal, with a relative error up to 1e-5 that the lobe
/// then scales up (measured: 1.1e-32 absolute at 4e-27, Beckmann near index-matched).
const EVAL_ABS: f64 = 1e-30;

/// Samples: largest coordinate difference of the sampled directions.
const SAMPLE_DIR: f64 = 1e-3;

/// Samples whose direction or view is within this height of the surface may be valid
/// in one call only.
const HORIZON: f64 = 1e-3;
/// So may samples with `u0` above this.
const EDGE_ON: f32 = 0.9999;
/// And this share of an index-matched dielectric's samples.
const INDEX_MATCHED_FLAGS: f64 = 2e-5;

struct Case {
    name: &'static str,
    label: String,
    block: Block,
    frame: Frame,
    /// `(alpha_x, alpha_y)` of microfacet lobes.
    alpha: Option<(f64, f64)>,
    /// The dielectric's eta.
    eta: Option<f64>,
}

impl Case {
    /// The lobe and distribution, without the parameters.
    fn family(&self) -> &str {
        self.label.split(" r ").next().unwrap()
    }

    /// A dielectric with `|eta - 1| < 0.01`.
    fn index_matched(&self) -> bool {
        self.eta.is_some_and(|e| (e - 1.0).abs() < 0.01)
    }

    /// What makes the f32 lobe ill-conditioned at this pair, if anything: alpha
    /// below 0.01 along an axis (`narrow`), `|cos_o|` or `|cos_i|` below 0.1
    /// (`grazing`), a dielectric with `|eta - 1| < 0.01` (`index-matched`: refraction
    /// barely bends, so the half vector is a difference of nearly opposite vectors).
    fn conditioning(&self, cos_o: f64, cos_i: f64) -> String {
        let mut r = Vec::new();
        if self.alpha.is_some_and(|(ax, ay)| ax.min(ay) < 0.01) {
            r.push("narrow");
        }
        if cos_o.abs().min(cos_i.abs()) < 0.1 {
            r.push("grazing");
        }
        if self.index_matched() {
            r.push("index-matched");
        }
        if r.is_empty() {
            WELL.to_string()
        } else {
            r.join("+")
        }
    }
}

const WELL: &str = "well-conditioned";

fn cases() -> Vec<Case> {
    let tilted = Frame::new(Vec3::new(0.3, -0.5, 0.81), Some(Vec3::new(0.2, 0.9, 0.1)));
    let frame = |k: usize| if k % 2 == 1 { tilted } else { Frame::IDENTITY };
    let mut v = Vec::new();
    for (n, ndf) in [Ndf::Ggx, Ndf::Beckmann].into_iter().enumerate() {
        for (i, r) in [0.018f32, 0.025, 0.0317, 0.035, 0.05, 0.1, 0.3, 1.0]
            .into_iter()
            .enumerate()
        {
            for (j, an) in [0.0f32, 0.5, 1.0].into_iter().enumerate() {
                let m = Micro::from_roughness(ndf, r, an);
                if m.ax.max(m.ay) < 1e-3 {
                    continue; // a delta lobe
                }
                let fresnel = ["artistic", "schlick", "conductor"][(i + j) % 3];
                v.push(Case {
                    name: "conductor",
                    label: format!("conductor {} r {r} an {an} {fresnel}", ndf.name()),
                    block: Block::defaults(lobe("conductor"))
                        .choice("distribution", ndf.name())
                        .float("roughness", r)
                        .float("anisotropic", an)
                        .choice("fresnel", fresnel),
                    frame: frame(n + i + j),
                    alpha: Some((m.ax, m.ay)),
                    eta: None,
                });
                for (k, eta) in [0.001f32, 0.7, 1.0002, 1.5, 1000.0].into_iter().enumerate() {
                    v.push(Case {
                        name: "dielectric",
                        label: format!("dielectric {} r {r} an {an} eta {eta}", ndf.name()),
                        block: Block::defaults(lobe("dielectric"))
                            .choice("distribution", ndf.name())
                            .float("roughness", r)
                            .float("anisotropic", an)
                            .float("eta", eta),
                        frame: frame(n + i + j + k + 1),
                        alpha: Some((m.ax, m.ay)),
                        eta: Some(f64::from(eta)),
                    });
                }
            }
        }
    }
    let plain = |name: &'static str, label: &str, block: Block, eta: Option<f64>, frame| Case {
        name,
        label: label.to_string(),
        block,
        frame,
        alpha: None,
        eta,
    };
    let conductor = Block::defaults(lobe("conductor")).float("roughness", 0.0);
    v.push(plain(
        "conductor",
        "conductor delta",
        conductor,
        None,
        tilted,
    ));
    for (k, eta) in [0.7f32, 1.5].into_iter().enumerate() {
        let block = Block::defaults(lobe("dielectric"))
            .float("roughness", 0.0)
            .float("eta", eta);
        let label = format!("dielectric smooth eta {eta}");
        v.push(plain(
            "dielectric",
            &label,
            block,
            Some(f64::from(eta)),
            frame(k),
        ));
    }
    let lambert = Block::defaults(lobe("lambert"));
    v.push(plain("lambert", "lambert", lambert, None, tilted));
    let mirror = Block::defaults(lobe("mirror"));
    v.push(plain("mirror", "mirror", mirror, None, Frame::IDENTITY));
    v
}

/// The local coordinates in `frame` of the world vector `w`, and back, in f64.
fn to_local(frame: &Frame, w: V) -> V {
    let [t, b, n] = [frame.t, frame.b, frame.n].map(V::from32);
    V::new(w.dot(t), w.dot(b), w.dot(n))
}

fn to_world(frame: &Frame, v: V) -> V {
    let [t, b, n] = [frame.t, frame.b, frame.n].map(V::from32);
    t * v.x + b * v.y + n * v.z
}

/// The inputs of one case (world directions) and each pair's local `cos_o`, `cos_i`.
#[derive(Default)]
struct Pairs {
    wo: Vec<Vec3<f32>>,
    wi: Vec<Vec3<f32>>,
    u: Vec<[f32; 3]>,
    cos: Vec<(f64, f64)>,
}

fn pairs(case: &Case, c: &Closure, rng: &mut Rng) -> Pairs {
    let mut p = Pairs::default();
    let (ax, ay) = case.alpha.unwrap_or((0.3, 0.3));
    let slopes = [0.0f64, 0.7, -0.7, 2.5, -2.5];
    for co in [1.0f64, 0.5, 0.1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
        for phi in [0.0f64, 37.0, 90.0] {
            // Two-sided lobes from inside too.
            for side in [1.0f64, -1.0]
                .into_iter()
                .take(1 + usize::from(case.eta.is_some()))
            {
                let (s, cphi) = phi.to_radians().sin_cos();
                let r = (1.0 - co * co).sqrt();
                let o = V::new(r * cphi, r * s, side * co);
                let wo = to_world(&case.frame, o).to32();
                let mut push = |w: V, u: [f32; 3]| {
                    p.wo.push(wo);
                    p.wi.push(to_world(&case.frame, w).to32());
                    p.u.push(u);
                    p.cos.push((o.z, w.z));
                };
                // Around the mirror and refracted directions of the lobe's peak normal.
                for &a in &slopes {
                    for &b in &slopes {
                        let m = V::new(-a * ax, -b * ay, 1.0).normalize() * side;
                        push(o.reflect(m), rng.u3());
                        if let Some((t, _)) = case.eta.and_then(|e| reference::refract(o, m, e)) {
                            push(t, rng.u3());
                        }
                    }
                }
                // The samplers' far tails, where they are steepest.
                let top = 1.0 - f32::EPSILON / 2.0;
                for u in [
                    [0.5, top, 0.3],
                    [0.5, 1.0 - 1e-5, 0.7],
                    [0.5, 0.4, 6e-8],
                    [0.5, 0.6, top],
                ] {
                    push(o.reflect(V::new(0.0, 0.0, side)), u);
                }
                // GGX's visible normals seen edge-on: the caps' point near `-v` (`v` the
                // stretched view), `u0` a few ulps below 1 at the azimuth of `-v.xy`
                // (`u1` at 0 and 1) and at `v.xy`'s own (the cap sum `c + v` of the
                // mapping before 2026-12-07 cancelled there: 0.13 apart at alpha 1).
                if let Some((ax, ay)) = case.alpha.filter(|_| case.label.contains(" ggx ")) {
                    let up = if o.z < 0.0 { o * -1.0 } else { o };
                    let own = (ay * up.y).atan2(ax * up.x) / std::f64::consts::TAU;
                    let own = own.rem_euclid(1.0) as f32;
                    let ulps =
                        |x: f32, k: i32| f32::from_bits(x.to_bits().saturating_add_signed(k));
                    for k in [1.0f32, 4.0] {
                        let u0 = 1.0 - k * f32::EPSILON / 2.0;
                        for u1 in [0.0, 6e-8, top, own, ulps(own, -3), ulps(own, 3)] {
                            push(o.reflect(V::new(0.0, 0.0, side)), [0.5, u0, u1.min(top)]);
                        }
                    }
                }
                let unit = Vec3::try_unit(wo.x, wo.y, wo.z, "wo").unwrap();
                for _ in 0..16 {
                    if let Ok(s) = c.sample(unit, rng.u3()) {
                        push(to_local(&case.frame, V::from32(s.wi)), rng.u3());
                    }
                }
                for _ in 0..6 {
                    let z = 1.0 - 2.0 * rng.f64();
                    let (sp, cp) = (2.0 * std::f64::consts::PI * rng.f64()).sin_cos();
                    let rr = (1.0 - z * z).sqrt();
                    push(V::new(rr * cp, rr * sp, z), rng.u3());
                }
            }
        }
    }
    p
}

/// The outputs compared: evaluations (value, pdf, reverse pdf, albedo) or samples.
#[derive(Clone, Copy, PartialEq)]
enum Check {
    Eval,
    Sample,
}

impl Outputs {
    fn scalar(check: Check, c: &Closure, p: &Pairs) -> Outputs {
        let mut o = Outputs::filled(p.wo.len(), 0.0, 0);
        let unit = |v: Vec3<f32>| Vec3::try_unit(v.x, v.y, v.z, "w").unwrap();
        for k in 0..p.wo.len() {
            let wo = unit(p.wo[k]);
            if check == Check::Eval {
                let e = c.eval(wo, unit(p.wi[k])).unwrap();
                let (value, albedo) = (e.value.to_array(), c.albedo(wo).unwrap().to_array());
                for ch in 0..3 {
                    o.value[ch][k] = value[ch];
                    o.albedo[ch][k] = albedo[ch];
                }
                o.pdf[k] = e.pdf;
                o.pdf_reverse[k] = e.pdf_reverse;
            } else if let Ok(s) = c.sample(wo, p.u[k]) {
                for ch in 0..3 {
                    o.s_wi[ch][k] = [s.wi.x, s.wi.y, s.wi.z][ch];
                    o.s_weight[ch][k] = s.weight.to_array()[ch];
                    o.s_value[ch][k] = s.value.to_array()[ch];
                }
                o.s_pdf[k] = s.pdf;
                o.s_flags[k] = s.flags;
            }
        }
        o
    }

    fn batch(check: Check, kernels: Kernels, c: &Closure, p: &Pairs) -> Outputs {
        let n = p.wo.len();
        let mut o = Outputs::filled(n, 0.0, 0);
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let wo = rows(&p.wo);
        let input = BatchInput {
            count: n,
            closures: c,
            active: None,
            wo: soa(&wo),
        };
        if check == Check::Eval {
            let wi = rows(&p.wi);
            let out = EvalOutput {
                value: soa_mut(&mut o.value),
                pdf: &mut o.pdf,
                pdf_reverse: Some(&mut o.pdf_reverse),
            };
            batch::eval(&exec, &input, soa(&wi), out).unwrap();
            batch::albedo(&exec, &input, soa_mut(&mut o.albedo)).unwrap();
            return o;
        }
        let u: [Vec<f32>; 3] = [0, 1, 2].map(|j| p.u.iter().map(|u| u[j]).collect());
        let randoms = SampleRandoms {
            u_lobe: &u[0],
            u0: &u[1],
            u1: &u[2],
        };
        let out = SampleOutput {
            wi: soa_mut(&mut o.s_wi),
            pdf: &mut o.s_pdf,
            weight: soa_mut(&mut o.s_weight),
            value: Some(soa_mut(&mut o.s_value)),
            flags: Some(&mut o.s_flags),
            lobe: None,
            component: None,
            eta: None,
            roughness: None,
        };
        // A failed sample is a zeroed lane with flags 0 (and an error naming the
        // first), as the scalar call's error.
        let _ = batch::sample(&exec, &input, randoms, out);
        o
    }
}

/// The worst value of each measure per key and where it occurred, and the outputs
/// outside their bounds.
#[derive(Default)]
struct Worst {
    table: BTreeMap<String, (f64, String)>,
    failures: Vec<String>,
    failed: usize,
    /// Samples with other flags than the scalar call's.
    other_flags: usize,
    /// An index-matched dielectric's samples, and those with other flags at neither
    /// boundary.
    index_matched: usize,
    index_matched_flags: usize,
}

impl Worst {
    fn note(&mut self, key: String, v: f64, at: &dyn Fn() -> String) {
        let e = self.table.entry(key).or_default();
        if v > e.0 {
            *e = (v, at());
        }
    }

    fn check(&mut self, ok: bool, what: impl FnOnce() -> String) {
        if !ok {
            self.failed += 1;
            if self.failures.len() < 8 {
                self.failures.push(what());
            }
        }
    }

    fn report(&self, what: &str, compared: usize) {
        println!("{what}: {compared} compared");
        if self.other_flags > 0 {
            println!("{what}: {} with other flags", self.other_flags);
        }
        if self.index_matched > 0 {
            println!(
                "{what}: {} of {} index-matched samples with other flags off the boundaries",
                self.index_matched_flags, self.index_matched
            );
        }
        assert!(
            self.index_matched_flags as f64 <= INDEX_MATCHED_FLAGS * self.index_matched as f64,
            "{what}: {} of {} index-matched samples with other flags",
            self.index_matched_flags,
            self.index_matched
        );
        for (key, (v, at)) in &self.table {
            println!("{what} {key}: {v:.2e} ({at})");
        }
        assert!(
            self.failures.is_empty(),
            "{what}: {} of {compared} outside the bound; first: {:#?}",
            self.failed,
            self.failures
        );
    }
}

/// Run `check` over every case and kernel set; `compare(case, pairs, lane, scalar
/// outputs, batch outputs, "ISA lobe" key prefix, worst)` records and returns how
/// many outputs it compared.
fn sweep(
    check: Check,
    seed: u64,
    mut compare: impl FnMut(&Case, &Pairs, usize, &Outputs, &Outputs, &str, &mut Worst) -> usize,
) -> (Worst, usize) {
    let mut rng = Rng::new(seed);
    let mut worst = Worst::default();
    let mut compared = 0;
    for case in cases() {
        let c = closure(case.name, &case.block, case.frame);
        let p = pairs(&case, &c, &mut rng);
        let scalar = Outputs::scalar(check, &c, &p);
        for kernels in Kernels::available() {
            let batch = Outputs::batch(check, kernels, &c, &p);
            let isa = format!("{:?} {}", kernels.isa(), case.family());
            for i in 0..p.wo.len() {
                compared += compare(&case, &p, i, &scalar, &batch, &isa, &mut worst);
            }
        }
    }
    (worst, compared)
}

/// `|a - b| / max(|a|, |b|)`, 0 when both are 0.
fn rel(a: f32, b: f32) -> f64 {
    let (a, b) = (f64::from(a), f64::from(b));
    let m = a.abs().max(b.abs());
    if m == 0.0 { 0.0 } else { (a - b).abs() / m }
}

fn within_eval_bound(a: f32, b: f32) -> bool {
    let (a, b) = (f64::from(a), f64::from(b));
    (a - b).abs() <= BATCH_TOLERANCE * a.abs().max(b.abs()) + EVAL_ABS
}

#[test]
fn evaluations_match_the_scalar_calls_at_ill_conditioned_inputs() {
    let (worst, compared) = sweep(Check::Eval, 41, |case, p, i, s, b, isa, worst| {
        let at = || {
            format!(
                "{} (frame n {:?}) wo {:?} wi {:?}",
                case.label, case.frame.n, p.wo[i], p.wi[i]
            )
        };
        let key = format!("{isa} {}", case.conditioning(p.cos[i].0, p.cos[i].1));
        let mut outputs = vec![
            ("pdf", b.pdf[i], s.pdf[i]),
            ("pdf_reverse", b.pdf_reverse[i], s.pdf_reverse[i]),
        ];
        for ch in 0..3 {
            outputs.push(("value", b.value[ch][i], s.value[ch][i]));
            outputs.push(("albedo", b.albedo[ch][i], s.albedo[ch][i]));
        }
        for &(what, x, y) in &outputs {
            if f64::from(x.abs().max(y.abs())) >= EVAL_ABS {
                worst.note(format!("{key} relative"), rel(x, y), &at);
                let at_values = || format!("batch {x:e}, scalar {y:e} at {}", at());
                worst.note(format!("{isa} {what} relative"), rel(x, y), &at_values);
            }
            if rel(x, y) > BATCH_TOLERANCE {
                let d = (f64::from(x) - f64::from(y)).abs();
                worst.note(format!("{key} absolute, where not relative"), d, &at);
            }
            worst.check(within_eval_bound(x, y), || {
                format!("{key} {what}: batch {x:e}, scalar {y:e} at {}", at())
            });
        }
        outputs.len()
    });
    worst.report("eval", compared);
}

#[test]
fn samples_match_the_scalar_calls_within_their_conditioning() {
    let (worst, compared) = sweep(Check::Sample, 43, |case, p, i, s, b, isa, worst| {
        let at = || {
            format!(
                "{} (frame n {:?}) wo {:?} u {:?}",
                case.label, case.frame.n, p.wo[i], p.u[i]
            )
        };
        let dir = |o: &Outputs| V::from32(Vec3::new(o.s_wi[0][i], o.s_wi[1][i], o.s_wi[2][i]));
        let (wb, ws) = (dir(b), dir(s));
        let (fb, fs) = (b.s_flags[i], s.s_flags[i]);
        let index_matched = case.index_matched();
        worst.index_matched += usize::from(index_matched);
        if fb != fs {
            // One of the two failed, and the other's direction grazes the surface or
            // its microfacet the view, or the lobe is index-matched (counted).
            let w = if fb != 0 { wb } else { ws };
            let height = to_local(&case.frame, w.normalize()).z.abs();
            let (cos_o, _) = p.cos[i];
            let grazing_view = cos_o.abs() <= HORIZON;
            let boundary = height <= HORIZON || grazing_view || p.u[i][1] > EDGE_ON;
            let one_failed = fb == 0 || fs == 0;
            worst.index_matched_flags += usize::from(one_failed && !boundary && index_matched);
            worst.check(one_failed && (boundary || index_matched), || {
                format!(
                    "{isa}: flags {fb} / {fs}, direction {w:?} at {height:e} from the surface, at {}",
                    at()
                )
            });
            worst.note(format!("{isa} other flags (height)"), height, &at);
            worst.other_flags += 1;
            return 1;
        }
        if fb == 0 {
            return 0;
        }
        if fb & flags::SPECULAR != 0 {
            // Delta events: no sampler, so the evaluations' rounding.
            let mut outputs = vec![("pdf", b.s_pdf[i], s.s_pdf[i])];
            for ch in 0..3 {
                outputs.push(("wi", b.s_wi[ch][i], s.s_wi[ch][i]));
                outputs.push(("weight", b.s_weight[ch][i], s.s_weight[ch][i]));
            }
            for &(what, x, y) in &outputs {
                worst.check(within_eval_bound(x, y), || {
                    format!(
                        "{isa} {what} (delta): batch {x:e}, scalar {y:e} at {}",
                        at()
                    )
                });
            }
            return 1;
        }
        let cos_i = to_local(&case.frame, ws.normalize()).z;
        let cond = case.conditioning(p.cos[i].0, cos_i);
        let key = format!("{isa} {cond}");
        let d = (wb - ws)
            .x
            .abs()
            .max((wb - ws).y.abs())
            .max((wb - ws).z.abs());
        worst.note(format!("{key} direction"), d, &at);
        worst.check(d <= SAMPLE_DIR, || {
            format!("{key}: directions {d:e} apart at {}", at())
        });
        let log_ratio = |x: f32, y: f32| (f64::from(x) / f64::from(y)).ln().abs();
        let mut outputs = vec![("pdf", b.s_pdf[i], s.s_pdf[i])];
        for ch in 0..3 {
            outputs.push(("wi", b.s_wi[ch][i], s.s_wi[ch][i]));
            outputs.push(("weight", b.s_weight[ch][i], s.s_weight[ch][i]));
            outputs.push(("value", b.s_value[ch][i], s.s_value[ch][i]));
        }
        for &(what, x, y) in &outputs {
            if what != "wi" {
                worst.note(format!("{key} {what} |ln ratio|"), log_ratio(x, y), &at);
            }
            if cond == WELL {
                // The harness's bound (verify::scalar_vs_batch), and its measure.
                let v = batch_difference(x, y);
                worst.note(format!("{key} {what} (harness measure)"), v, &at);
                worst.check(v <= BATCH_SAMPLE_TOLERANCE, || {
                    format!("{key} {what}: batch {x:e}, scalar {y:e} at {}", at())
                });
            }
        }
        1
    });
    worst.report("sample", compared);
}
