//! The per-case checks of the harness (see the module docs of `verify`).

use super::chi2::{self, Cells, Grid, Window};
use super::report::{CaseReport, Chi2Row, HardReport, Moment, WindowRow};
use super::{Budget, ParamSet, Rng, batch_difference, corner_sets};
use crate::batch::{
    self, BatchInput, EvalOutput, Exec, SampleOutput, SampleRandoms, Soa3, Soa3Mut, Threads,
};
use crate::closure::Closure;
use crate::lobes::{LobeType, Sample, Transport, flags};
use crate::math::{Frame, Rgb, Vec3};
use crate::params::{self, ParamKind};
use crate::registry::{LobeRef, Registry};
use crate::simd::Kernels;

/// `wo` at `cos theta`, at an azimuth that differs per call so anisotropy is exercised.
fn direction(cos_theta: f32, phi: f32) -> Vec3<f32> {
    let s = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta)
}

/// Uniform direction on the sphere.
fn uniform_sphere(rng: &mut Rng) -> Vec3<f32> {
    let z = 1.0 - 2.0 * rng.uniform();
    direction(z, 2.0 * std::f32::consts::PI * rng.uniform())
}

/// Relative difference with a floor, so values that are both ~0 agree.
fn rel_err(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(floor)
}

fn rgb64(c: Rgb<f32>) -> [f64; 3] {
    c.to_array().map(f64::from)
}

/// Whether `lobe` scatters below its surface (two-sided).
fn transmits(lobe: &dyn LobeType) -> bool {
    lobe.flags() & flags::TRANSMISSION != 0
}

/// The `wo` directions a check uses: the given cosines, mirrored below the surface
/// for lobes that transmit.
fn wo_set(lobe: &dyn LobeType, cosines: &[f32]) -> Vec<Vec3<f32>> {
    let mut out: Vec<Vec3<f32>> = cosines
        .iter()
        .enumerate()
        .map(|(i, &c)| direction(c, 0.4 + 1.3 * i as f32))
        .collect();
    if transmits(lobe) {
        out.extend(
            cosines
                .iter()
                .enumerate()
                .map(|(i, &c)| direction(-c, 2.1 + 0.9 * i as f32)),
        );
    }
    out
}

pub(super) fn verify_case(
    lobe: &LobeRef,
    set: &ParamSet,
    budget: &Budget,
    rng: &mut Rng,
) -> CaseReport {
    let p = set.block.as_slice();
    let mut report = verify_sampling(lobe, set, budget, rng);
    if lobe.reciprocal() {
        report.reciprocity_max_err = Some(reciprocity(&**lobe, p, budget.reciprocity_pairs, rng));
    }
    for wo in wo_set(&**lobe, budget.energy_cos_theta) {
        energy(&**lobe, p, wo, budget, rng, &mut report);
    }
    (report.batch_max_err, report.batch_sample_err) =
        scalar_vs_batch(lobe, p, budget.batch_lanes, rng);
    report
}

/// The sampling checks of a case: chi-square on the sphere and consistency, the
/// lobe-centred windows, and the closure's world-space consistency.
pub(super) fn verify_sampling(
    lobe: &LobeRef,
    set: &ParamSet,
    budget: &Budget,
    rng: &mut Rng,
) -> CaseReport {
    let p = set.block.as_slice();
    let mut report = CaseReport::new(set.name.clone());
    for wo in wo_set(&**lobe, budget.chi2_cos_theta) {
        chi2_and_consistency(&**lobe, p, wo, budget, rng, &mut report);
    }
    for wo in wo_set(&**lobe, budget.window_cos_theta) {
        window_tests(&**lobe, p, wo, budget, rng, &mut report);
    }
    report.closure_consistency_max_err = closure_consistency(lobe, p, budget, rng);
    report
}

/// `r + g + b` of a color.
fn lum(c: Rgb<f32>) -> f64 {
    rgb64(c).iter().sum()
}

/// Lobe-centred window tests from `wo`: pilot samples place a [`Window`] on each side
/// of the surface the lobe scatters to; then a chi-square test of where samples fall
/// within it (conditional on how many do, so what lies outside does not matter), and
/// moment tests `E[weight g 1_W] = int_W f g` for `g = 1, u, v` (window coordinates)
/// against an f64 quadrature of `eval`. A narrow lobe spans many cells of its window,
/// and a sampler that drifts off the pdf by a fraction of the lobe's width moves the
/// first moments by many standard errors.
fn window_tests(
    lobe: &dyn LobeType,
    p: &[f32],
    wo: Vec3<f32>,
    budget: &Budget,
    rng: &mut Rng,
    report: &mut CaseReport,
) {
    let mode = Transport::Radiance;
    let mut sides: [Vec<Vec3<f32>>; 2] = [Vec::new(), Vec::new()];
    for _ in 0..budget.window_pilot {
        let s = lobe.sample(p, wo, rng.uniform3(), mode);
        if s.valid && !s.delta {
            sides[usize::from(s.wi.z * wo.z < 0.0)].push(s.wi);
        }
    }
    let min_pilot = (budget.window_pilot / 50).max(50);
    let windows: Vec<(&'static str, Window)> = ["same side", "other side"]
        .into_iter()
        .zip(&sides)
        .filter(|(_, dirs)| dirs.len() >= min_pilot)
        .filter_map(|(side, dirs)| Some((side, Window::around(dirs, budget.window_cells)?)))
        .collect();
    if windows.is_empty() {
        return;
    }
    let n = budget.window_samples;
    let cells = budget.window_cells * budget.window_cells;
    let mut observed = vec![vec![0u64; cells]; windows.len()];
    // Per window: sums and sums of squares of weight * (1, u, v) inside it.
    let mut sums = vec![[[0.0f64; 2]; 3]; windows.len()];
    for _ in 0..n {
        let s = lobe.sample(p, wo, rng.uniform3(), mode);
        if !s.valid || s.delta {
            continue;
        }
        let weight = lum(s.weight());
        for (k, (_, window)) in windows.iter().enumerate() {
            let Some(cell) = window.locate(s.wi) else {
                continue;
            };
            observed[k][cell] += 1;
            let (u, v) = window.coords(s.wi).unwrap_or_default();
            for (sum, g) in sums[k].iter_mut().zip([1.0, u, v]) {
                let x = weight * g;
                sum[0] += x;
                sum[1] += x * x;
            }
        }
    }
    for (k, (side, window)) in windows.iter().enumerate() {
        let f = |w: Vec3<f32>| {
            let e = lobe.eval(p, wo, w, mode);
            let (u, v) = window.coords(w).unwrap_or_default();
            let value = lum(e.value);
            [f64::from(e.pdf), value, value * u, value * v]
        };
        let obs = &observed[k];
        let integral = chi2::integrate(window, f, 1e-2 / n as f64, |cell, _, v| {
            far_off(obs[cell], v[0] * n as f64)
        });
        let inside: u64 = obs.iter().sum();
        let total: f64 = integral.iter().map(|c| c[0]).sum();
        let chi2 = if inside == 0 || total <= 0.0 {
            Chi2Row::not_applicable(wo.z, 0.0)
        } else {
            let expected: Vec<f64> = integral
                .iter()
                .map(|c| c[0] / total * inside as f64)
                .collect();
            let test = chi2::pearson(obs, &expected);
            Chi2Row {
                cos_theta_o: wo.z,
                statistic: test.statistic,
                dof: test.dof,
                p_value: test.p_value,
                absorbed: 0.0,
                pdf_integral: total,
            }
        };
        let quadrature: [f64; 3] = [1, 2, 3].map(|c| integral.iter().map(|v| v[c]).sum());
        // The quadrature's own error: 2e-4 of the window's integral (|u|, |v| < 1).
        let allowance = 2e-4 * quadrature[0].abs();
        let moments = [0, 1, 2].map(|j| {
            let [s1, s2] = sums[k][j];
            let estimate = s1 / n as f64;
            let standard_error = ((s2 / n as f64 - estimate * estimate).max(0.0) / n as f64).sqrt();
            let excess = ((estimate - quadrature[j]).abs() - allowance).max(0.0);
            let p_value = if excess == 0.0 {
                1.0
            } else if standard_error > 0.0 {
                chi2::normal_p_value(excess / standard_error)
            } else {
                0.0
            };
            Moment {
                estimate,
                standard_error,
                quadrature: quadrature[j],
                p_value,
            }
        });
        report.windows.push(WindowRow {
            cos_theta_o: wo.z,
            side,
            half_width: window.half,
            inside,
            chi2,
            moments,
        });
    }
}

/// Whether `observed` counts are far (3 sigma) off `expected`, or there are any where
/// nothing is expected: the cells whose quadrature is refined (a sliver of the pdf's
/// support can hide between the points of a coarse quadrature).
fn far_off(observed: u64, expected: f64) -> bool {
    let o = observed as f64;
    (o - expected) * (o - expected) > 9.0 * expected.max(1.0) || (o > 0.0 && expected <= 0.0)
}

/// Chi-square test and consistency of samples from `wo`.
fn chi2_and_consistency(
    lobe: &dyn LobeType,
    p: &[f32],
    wo: Vec3<f32>,
    budget: &Budget,
    rng: &mut Rng,
    report: &mut CaseReport,
) {
    let grid: Grid = budget.chi2_grid;
    let m = budget.chi2_samples;
    let mut observed = vec![0u64; grid.cells()];
    let (mut absorbed, mut delta) = (0usize, 0usize);
    for i in 0..m {
        let mode = if i % 2 == 0 {
            Transport::Radiance
        } else {
            Transport::Importance
        };
        let s = lobe.sample(p, wo, rng.uniform3(), mode);
        let check = i < budget.consistency_samples;
        if !s.valid {
            absorbed += 1;
            if s.pdf != 0.0 || s.value.to_array() != [0.0; 3] {
                report.flag_errors += 1;
            }
            continue;
        }
        if !sample_kind_ok(lobe.flags(), lobe.component_count(), &s) {
            report.flag_errors += 1;
        }
        if s.delta {
            delta += 1;
        } else if mode == Transport::Radiance {
            observed[grid.cell(s.wi)] += 1;
        }
        if check {
            report.consistency_max_err = report
                .consistency_max_err
                .max(consistency(lobe, p, wo, &s, mode));
        }
    }
    // Only radiance samples were binned (half of them); delta samples are not in the pdf.
    let binned = m.div_ceil(2);
    let delta_share = delta as f64 / m as f64;
    let absorbed_share = absorbed as f64 / m as f64;
    if delta_share >= 1.0 - absorbed_share - 1e-12 {
        report
            .chi2
            .push(Chi2Row::not_applicable(wo.z, absorbed_share));
        return;
    }
    // Cells whose counts are far off their expectation get a finer quadrature.
    // So do cells holding more than 2% of the pdf, at every level: a narrow lobe within
    // them can agree with each cell's counts to 3 sigma and still be missed by more than
    // the integral's tolerance in all (Beckmann alpha 0.01 at cos_o 0.03 reflects into
    // a sliver 1e-3 rad wide in azimuth: 32 blocks per cell lost 2.5e-3 of the
    // integral, which an f64 slope-space integration puts at 0.99293).
    let integral = chi2::integrate_cells(
        lobe,
        p,
        wo,
        Transport::Radiance,
        grid,
        m,
        |cell, _blocks, v| far_off(observed[cell], v[3] * binned as f64) || v[3] > 0.02,
    );
    let total: f64 = integral.iter().map(|c| c[3]).sum();
    let expected: Vec<f64> = integral.iter().map(|c| c[3] * binned as f64).collect();
    let test = chi2::pearson(&observed, &expected);
    // pdf integral against the share of samples that are neither absorbed nor delta.
    let share = 1.0 - absorbed_share - delta_share;
    let se = (share * (1.0 - share) / m as f64).sqrt();
    let pdf_err = ((total - share).abs() - 3.0 * se).max(0.0);
    report.pdf_integral_max_err = report.pdf_integral_max_err.max(pdf_err);
    report.chi2.push(Chi2Row {
        cos_theta_o: wo.z,
        statistic: test.statistic,
        dof: test.dof,
        p_value: test.p_value,
        absorbed: absorbed_share,
        pdf_integral: total,
    });
}

/// Whether a valid sample's flags are among its lobe type's `lobe_flags`, its class
/// is SPECULAR exactly where it is a delta event (value a fraction, pdf a discrete
/// probability) and otherwise the type's DIFFUSE or GLOSSY class, and its component
/// is a whole number below the type's component count.
fn sample_kind_ok(lobe_flags: u32, components: u32, s: &Sample<f32>) -> bool {
    let class = s.class as u32;
    let class_ok = if s.delta {
        class == flags::SPECULAR
    } else {
        class != 0 && class & !(lobe_flags & (flags::DIFFUSE | flags::GLOSSY)) == 0
    };
    s.flags() & !lobe_flags == 0
        && class as f32 == s.class
        && class_ok
        && s.component.fract() == 0.0
        && s.component < components as f32
        && s.component >= 0.0
}

/// Largest relative mismatch between a sample and `eval` at its direction; delta
/// samples must evaluate to 0 and carry a finite weight.
fn consistency(
    lobe: &dyn LobeType,
    p: &[f32],
    wo: Vec3<f32>,
    s: &Sample<f32>,
    mode: Transport,
) -> f64 {
    let e = lobe.eval(p, wo, s.wi, mode);
    let weight_ok = s
        .weight()
        .to_array()
        .iter()
        .all(|w| w.is_finite() && *w >= 0.0);
    if !weight_ok || s.pdf.is_nan() || s.pdf <= 0.0 {
        return f64::INFINITY;
    }
    if s.delta {
        return if e.pdf == 0.0 && e.value.to_array() == [0.0; 3] {
            0.0
        } else {
            f64::INFINITY
        };
    }
    let value_err = rgb64(s.value)
        .iter()
        .zip(rgb64(e.value))
        .map(|(a, b)| rel_err(*a, b, 1e-12))
        .fold(0.0, f64::max);
    value_err.max(rel_err(f64::from(s.pdf), f64::from(e.pdf), 1e-12))
}

/// `cos theta_o` (in the lobe's frame) of the closure consistency check: grazing, where
/// the rounding of a world-space direction moves a narrow lobe's value the most.
const CLOSURE_CONSISTENCY_COS: [f32; 5] = [0.7, 0.3, 0.05, 0.02, 0.005];

/// Largest relative mismatch between a closure's sample and the closure's `eval` at
/// the world-space `wi` it returns, as a host passes it back, for the lobe alone in a
/// tilted frame (so that world and local directions differ in every component).
fn closure_consistency(lobe: &LobeRef, p: &[f32], budget: &Budget, rng: &mut Rng) -> f64 {
    let frame = Frame::new(
        Vec3::new(0.3f32, -0.5, 0.8).normalize(),
        Some(Vec3::new(1.0, 0.2, 0.1)),
    );
    let closure = single_lobe_closure(lobe, p, frame);
    let mut cosines = CLOSURE_CONSISTENCY_COS.to_vec();
    if transmits(&**lobe) {
        cosines.extend(CLOSURE_CONSISTENCY_COS.map(|c| -c));
    }
    let per_direction = budget.consistency_samples / cosines.len();
    let mut worst = 0.0f64;
    for (i, &c) in cosines.iter().enumerate() {
        let wo = frame
            .to_world(direction(c, 0.5 + 1.1 * i as f32))
            .normalize();
        for _ in 0..per_direction {
            let Ok(s) = closure.sample(wo, rng.uniform3()) else {
                continue;
            };
            if s.flags & flags::SPECULAR != 0 {
                continue;
            }
            // `wi` as a host's eval reads it: the C calls and the batch kernels
            // normalize the directions they are given (`Vec3::try_unit`'s rule).
            let wi = Vec3::try_unit(s.wi.x, s.wi.y, s.wi.z, "wi").expect("a unit sample");
            let e = closure.eval(wo, wi).expect("finished closure");
            let value = rgb64(s.value)
                .iter()
                .zip(rgb64(e.value))
                .map(|(a, b)| rel_err(*a, b, 1e-30))
                .fold(0.0, f64::max);
            worst = worst
                .max(value)
                .max(rel_err(f64::from(s.pdf), f64::from(e.pdf), 1e-30));
        }
    }
    worst
}

/// Largest relative asymmetry `|f(wo, wi) - f(wi, wo)|` over random pairs.
fn reciprocity(lobe: &dyn LobeType, p: &[f32], pairs: usize, rng: &mut Rng) -> f64 {
    let mut worst = 0.0f64;
    for _ in 0..pairs {
        let (wo, wi) = (uniform_sphere(rng), uniform_sphere(rng));
        if wo.z.abs() < 1e-3 || wi.z.abs() < 1e-3 {
            continue;
        }
        let forward = rgb64(lobe.eval(p, wo, wi, Transport::Radiance).value)
            .map(|v| v / f64::from(wi.z.abs()));
        let backward = rgb64(lobe.eval(p, wi, wo, Transport::Radiance).value)
            .map(|v| v / f64::from(wo.z.abs()));
        let scale = forward
            .iter()
            .chain(&backward)
            .fold(0.0f64, |a, b| a.max(b.abs()));
        for c in 0..3 {
            worst = worst.max(rel_err(forward[c], backward[c], (scale * 1e-6).max(1e-12)));
        }
    }
    worst
}

/// The energy cross-check's quadrature resolves the sphere as finely as a chi-square
/// test of this many samples would, whatever the tier's sample count.
const QUADRATURE_COUNTS: usize = 1_000_000;

/// Mean and standard error per channel of `n` draws of `f`.
fn mean_se(n: usize, mut f: impl FnMut() -> [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let (mut s1, mut s2) = ([0.0; 3], [0.0; 3]);
    for _ in 0..n {
        let x = f();
        for c in 0..3 {
            s1[c] += x[c];
            s2[c] += x[c] * x[c];
        }
    }
    let nf = n as f64;
    let mean = s1.map(|s| s / nf);
    let se = [0, 1, 2].map(|c| ((s2[c] / nf - mean[c] * mean[c]).max(0.0) / nf).sqrt());
    (mean, se)
}

/// Directional albedo at `wo`: `<= 1` (or the lobe's `energy_bound`) in importance transport, importance sampling
/// against uniform sampling, and the lobe's `albedo` against the estimate.
fn energy(
    lobe: &dyn LobeType,
    p: &[f32],
    wo: Vec3<f32>,
    budget: &Budget,
    rng: &mut Rng,
    report: &mut CaseReport,
) {
    let (n, grid) = (budget.energy_samples, budget.chi2_grid);
    let weight = |rng: &mut Rng, mode| {
        let s = lobe.sample(p, wo, rng.uniform3(), mode);
        (rgb64(s.weight()), s.delta)
    };
    let mut any_delta = false;
    // Per-cell sums of the importance-sampling weights (and their squares), to find
    // the cells where the quadrature below needs refining.
    let mut per_cell = vec![[0.0f64; 2]; grid.cells()];
    let (mean, se) = mean_se(n, || {
        let s = lobe.sample(p, wo, rng.uniform3(), Transport::Importance);
        any_delta |= s.delta;
        let w = rgb64(s.weight());
        if s.valid && !s.delta {
            let cell = &mut per_cell[grid.cell(s.wi)];
            let lum = w.iter().sum::<f64>();
            cell[0] += lum;
            cell[1] += lum * lum;
        }
        w
    });
    let bound = f64::from(lobe.energy_bound(p));
    for c in 0..3 {
        report.albedo_min = report.albedo_min.min(mean[c]);
        report.albedo_max = report.albedo_max.max(mean[c]);
        if mean[c] > bound + 3.0 * se[c] + 1e-6 {
            report.energy_violations += 1;
        }
    }
    // Quadrature of eval over the sphere (uniform cells, adaptively refined) sees no
    // delta lobe, so the cross-check needs none; nor can it resolve a narrow peak at the
    // grid's pole, so it skips `wo` along the normal.
    if !any_delta && wo.z.abs() < 0.999 {
        let nf = n as f64;
        let cells = chi2::integrate_cells(
            lobe,
            p,
            wo,
            Transport::Importance,
            grid,
            QUADRATURE_COUNTS,
            |cell, _, v| {
                let [sum, sum2] = per_cell[cell];
                let estimate = sum / nf;
                let se = (sum2 / nf / nf).sqrt();
                (estimate - (v[0] + v[1] + v[2])).abs() > 5.0 * se + 1e-5
            },
        );
        for c in 0..3 {
            let quadrature: f64 = cells.iter().map(|v| v[c]).sum();
            if (quadrature - mean[c]).abs() > 4.0 * se[c] + 1e-3 * quadrature.abs() + 1e-5 {
                report.uniform_mismatches += 1;
            }
        }
    }
    // The lobe's own albedo, in radiance transport (what hosts use).
    let (radiance, rse) = mean_se(n, || weight(rng, Transport::Radiance).0);
    let claimed = rgb64(lobe.albedo(p, wo, Transport::Radiance));
    let tol = f64::from(lobe.albedo_tolerance(p));
    for c in 0..3 {
        let err = (claimed[c] - radiance[c]).abs();
        report.albedo_max_rel_err = report
            .albedo_max_rel_err
            .max(((err - 3.0 * rse[c]).max(0.0)) / radiance[c].max(1e-3));
        if err > tol * radiance[c].max(claimed[c]) + 3.0 * rse[c] + 1e-4 {
            report.albedo_failures += 1;
            report.albedo_failure_detail.get_or_insert_with(|| {
                format!(
                    "cos_o {}: albedo {:.4} vs estimate {:.4} +- {:.1e}",
                    wo.z, claimed[c], radiance[c], rse[c]
                )
            });
        }
    }
    // The estimate that selection and pruning weigh the lobe by, against its albedo.
    let mut decoded = vec![0.0; lobe.decoded_len()];
    lobe.decode(p, &mut decoded);
    let estimate = rgb64(lobe.albedo_estimate_decoded(&decoded, wo, Transport::Radiance));
    let tol = f64::from(lobe.albedo_estimate_tolerance(p));
    for c in 0..3 {
        let err = (estimate[c] - claimed[c]).abs();
        let scale = claimed[c].max(estimate[c]);
        if scale > 0.0 {
            report.albedo_estimate_max_rel_err =
                report.albedo_estimate_max_rel_err.max(err / scale);
        }
        if err > tol * scale + 1e-6 {
            report.albedo_estimate_failures += 1;
        }
    }
}

/// A finished closure holding only `lobe` with parameters `p` in `frame` (registered
/// on the fly when it is not a built-in, as plugin lobes will be).
fn single_lobe_closure(lobe: &LobeRef, p: &[f32], frame: Frame) -> Closure {
    let mut registry = Registry::with_builtins();
    let type_id = registry
        .find(lobe.name())
        .or_else(|_| registry.register(lobe.clone()))
        .expect("a lobe type with a new name registers");
    let mut closure = Closure::new(None, Transport::Radiance);
    closure
        .add_lobe(&registry, type_id, [1.0; 3], frame, Some(p))
        .expect("verified parameters are valid");
    closure.finish().expect("a new closure finishes");
    closure
}

/// The batch entry points against the scalar closure calls, on a closure holding
/// only this lobe, with every kernel set this CPU has; every seventh lane inactive.
/// Returns the worst [`batch_difference`] of evaluations (eval, pdf, albedo) and of
/// samples.
fn scalar_vs_batch(lobe: &LobeRef, p: &[f32], lanes: usize, rng: &mut Rng) -> (f64, f64) {
    let closure = single_lobe_closure(lobe, p, Frame::IDENTITY);
    let dirs = |rng: &mut Rng| -> [Vec<f32>; 3] {
        let v: Vec<Vec3<f32>> = (0..lanes).map(|_| uniform_sphere(rng)).collect();
        [
            v.iter().map(|d| d.x).collect(),
            v.iter().map(|d| d.y).collect(),
            v.iter().map(|d| d.z).collect(),
        ]
    };
    let (wo, wi) = (dirs(rng), dirs(rng));
    let u: [Vec<f32>; 3] = [0, 1, 2].map(|_| (0..lanes).map(|_| rng.uniform()).collect());
    let active: Vec<u8> = (0..lanes).map(|i| u8::from(i % 7 != 6)).collect();
    let input = BatchInput {
        count: lanes,
        closures: &closure,
        active: Some(&active),
        wo: soa(&wo),
    };
    let expected: Vec<_> = (0..lanes)
        .map(|i| {
            // The scalar C entry points normalize exactly as the batch does.
            let o = Vec3::try_unit(wo[0][i], wo[1][i], wo[2][i], "wo").expect("unit");
            let w = Vec3::try_unit(wi[0][i], wi[1][i], wi[2][i], "wi").expect("unit");
            let e = closure.eval(o, w).expect("finished closure");
            let s = closure.sample(o, [u[0][i], u[1][i], u[2][i]]).ok();
            (e, s, closure.albedo(o).expect("finished closure"))
        })
        .collect();
    let (mut worst, mut worst_sample) = (0.0f64, 0.0f64);
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let b = BatchResults::run(&exec, &input, soa(&wi), &u);
        let mut cmp = |a: f32, b: f32| worst = worst.max(batch_difference(a, b));
        let mut cmp_sample =
            |a: f32, b: f32| worst_sample = worst_sample.max(batch_difference(a, b));
        for i in (0..lanes).filter(|&i| active[i] != 0) {
            let (e, s, albedo) = &expected[i];
            for c in 0..3 {
                cmp(b.value[c][i], e.value.to_array()[c]);
                cmp(b.albedo[c][i], albedo.to_array()[c]);
            }
            cmp(b.pdf[i], e.pdf);
            cmp(b.pdf_reverse[i], e.pdf_reverse);
            cmp(b.pdf_only[i], e.pdf);
            match s {
                Some(s) => {
                    for c in 0..3 {
                        cmp_sample(b.s_wi[c][i], [s.wi.x, s.wi.y, s.wi.z][c]);
                        cmp_sample(b.s_weight[c][i], s.weight.to_array()[c]);
                    }
                    cmp_sample(b.s_pdf[i], s.pdf);
                    cmp_sample(b.s_flags[i] as f32, s.flags as f32);
                    cmp_sample(b.s_component[i] as f32, s.component as f32);
                }
                None => cmp_sample(b.s_pdf[i], 0.0),
            }
        }
    }
    (worst, worst_sample)
}

fn soa(v: &[Vec<f32>; 3]) -> Soa3<'_> {
    Soa3 {
        x: &v[0],
        y: &v[1],
        z: &v[2],
    }
}

fn soa_mut(v: &mut [Vec<f32>; 3]) -> Soa3Mut<'_> {
    let [x, y, z] = v;
    Soa3Mut { x, y, z }
}

/// Every output of the batch entry points for one input.
struct BatchResults {
    value: [Vec<f32>; 3],
    pdf: Vec<f32>,
    pdf_reverse: Vec<f32>,
    pdf_only: Vec<f32>,
    albedo: [Vec<f32>; 3],
    s_wi: [Vec<f32>; 3],
    s_weight: [Vec<f32>; 3],
    s_pdf: Vec<f32>,
    s_flags: Vec<u32>,
    s_component: Vec<u32>,
}

impl BatchResults {
    fn run(
        exec: &Exec<'_>,
        input: &BatchInput<'_, &Closure>,
        wi: Soa3<'_>,
        u: &[Vec<f32>; 3],
    ) -> BatchResults {
        let n = input.count;
        let rows = || [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut r = BatchResults {
            value: rows(),
            pdf: vec![0.0; n],
            pdf_reverse: vec![0.0; n],
            pdf_only: vec![0.0; n],
            albedo: rows(),
            s_wi: rows(),
            s_weight: rows(),
            s_pdf: vec![0.0; n],
            s_flags: vec![0; n],
            s_component: vec![0; n],
        };
        let out = EvalOutput {
            value: soa_mut(&mut r.value),
            pdf: &mut r.pdf,
            pdf_reverse: Some(&mut r.pdf_reverse),
        };
        batch::eval(exec, input, wi, out).expect("valid batch");
        batch::pdf(exec, input, wi, &mut r.pdf_only).expect("valid batch");
        batch::albedo(exec, input, soa_mut(&mut r.albedo)).expect("valid batch");
        let randoms = SampleRandoms {
            u_lobe: &u[0],
            u0: &u[1],
            u1: &u[2],
        };
        let out = SampleOutput {
            wi: soa_mut(&mut r.s_wi),
            pdf: &mut r.s_pdf,
            weight: soa_mut(&mut r.s_weight),
            value: None,
            flags: Some(&mut r.s_flags),
            lobe: None,
            component: Some(&mut r.s_component),
            eta: None,
            roughness: None,
        };
        batch::sample(exec, input, randoms, out).expect("valid batch");
        r
    }
}

/// Directions the hard cases pair up: poles, grazing angles above and below, the
/// horizon, and a few ordinary ones.
fn hard_directions() -> Vec<Vec3<f32>> {
    let mut d = vec![Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0)];
    for (i, c) in [1e-4f32, 1e-3, 0.01, 0.05, -1e-4, -0.05]
        .into_iter()
        .enumerate()
    {
        d.push(direction(c, 0.3 + i as f32));
    }
    d.push(Vec3::new(1.0, 0.0, 0.0));
    d.push(Vec3::new(0.6, 0.8, 0.0));
    for (i, c) in [0.9f32, 0.5, -0.5, -0.9].into_iter().enumerate() {
        d.push(direction(c, 1.7 + 2.0 * i as f32));
    }
    d
}

/// Random parameters over the whole schema: floats and colors uniform in their range
/// (log-uniform for ranges over more than two decades), enums uniform.
fn random_block(lobe: &dyn LobeType, rng: &mut Rng) -> Vec<f32> {
    let specs = lobe.params();
    let mut block = vec![0.0; params::block_size(specs)];
    for (i, spec) in specs.iter().enumerate() {
        let offset = params::offset_of(specs, i);
        for slot in &mut block[offset..offset + spec.kind.size()] {
            *slot = match spec.kind {
                ParamKind::Enum => {
                    let n = spec.choices.len();
                    ((rng.uniform() * n as f32) as usize).min(n - 1) as f32
                }
                _ if spec.min > 0.0 && spec.max / spec.min > 100.0 => (spec.min.ln()
                    + rng.uniform() * (spec.max / spec.min).ln())
                .exp()
                .clamp(spec.min, spec.max),
                _ => spec.min + rng.uniform() * (spec.max - spec.min),
            };
        }
    }
    block
}

/// Everything a lobe returns at the hard cases: never NaN, Inf or negative, never a
/// weight with a zero pdf.
pub(super) fn hard_cases(
    lobe: &LobeRef,
    sets: &[ParamSet],
    budget: &Budget,
    rng: &mut Rng,
) -> HardReport {
    let mut blocks: Vec<Vec<f32>> = sets.iter().map(|s| s.block.clone()).collect();
    blocks.extend(corner_sets(&**lobe));
    blocks.extend((0..budget.random_param_sets).map(|_| random_block(&**lobe, rng)));
    let dirs = hard_directions();
    let one_minus = 1.0 - f32::EPSILON / 2.0;
    let fixed_u = [
        [0.0f32; 3],
        [one_minus; 3],
        [0.5; 3],
        [0.0, one_minus, 0.5],
        [one_minus, 0.0, 1e-7],
    ];
    let mut report = HardReport::default();
    let mut fail = |report: &mut HardReport, what: String| {
        report.failures += 1;
        if report.first_failure.is_none() {
            report.first_failure = Some(what);
        }
    };
    let bad = |x: f32| !x.is_finite() || x < 0.0;
    for block in &blocks {
        let p = block.as_slice();
        for &mode in &[Transport::Radiance, Transport::Importance] {
            for &wo in &dirs {
                let mut wis = dirs.clone();
                wis.extend([
                    wo,
                    -wo,
                    Vec3::new(-wo.x, -wo.y, wo.z),
                    Vec3::new(wo.x, wo.y, -wo.z),
                ]);
                for wi in wis {
                    let e = lobe.eval(p, wo, wi, mode);
                    report.evaluations += 1;
                    if e.value.to_array().into_iter().any(bad) || bad(e.pdf) {
                        fail(
                            &mut report,
                            format!("eval {p:?} wo {wo:?} wi {wi:?}: {e:?}"),
                        );
                    }
                }
                let randoms = fixed_u
                    .iter()
                    .copied()
                    .chain((0..4).map(|_| rng.uniform3()));
                for u in randoms.collect::<Vec<_>>() {
                    let s = lobe.sample(p, wo, u, mode);
                    report.evaluations += 1;
                    let weight = s.weight().to_array();
                    let broken = if s.valid {
                        bad(s.pdf)
                            || s.pdf == 0.0
                            || s.value.to_array().into_iter().chain(weight).any(bad)
                            || (s.wi.length_squared() - 1.0).abs() > 1e-3
                    } else {
                        s.pdf != 0.0 || s.value.to_array() != [0.0; 3]
                    };
                    if broken {
                        fail(
                            &mut report,
                            format!("sample {p:?} wo {wo:?} u {u:?}: {s:?}"),
                        );
                    }
                }
                let a = lobe.albedo(p, wo, mode);
                report.evaluations += 1;
                if a.to_array().into_iter().any(bad) {
                    fail(&mut report, format!("albedo {p:?} wo {wo:?}: {a:?}"));
                }
            }
        }
    }
    boundary_inputs(lobe, &sets[0].block, &mut report, &mut fail);
    report
}

/// Unnormalized and near-zero-length directions through the checks the C boundary
/// applies (`Vec3::try_unit`) and then a closure: either a clean error or finite results.
fn boundary_inputs(
    lobe: &LobeRef,
    p: &[f32],
    report: &mut HardReport,
    fail: &mut impl FnMut(&mut HardReport, String),
) {
    let closure = single_lobe_closure(lobe, p, Frame::IDENTITY);
    let base = [
        (0.3f32, -0.2f32, 0.9f32),
        (0.0, 0.0, 1.0),
        (1.0, 0.0, 1e-6),
        (-0.4, 0.1, -0.8),
    ];
    let scales = [1e-30f32, 1e-20, 1e-6, 3.7, 1e20, 1e30, 1e-45];
    for &(x, y, z) in &base {
        for &k in &scales {
            let Ok(wo) = Vec3::try_unit(x * k, y * k, z * k, "wo") else {
                continue;
            };
            for &(a, b, c) in &base {
                let Ok(wi) = Vec3::try_unit(a / k, b / k, c / k, "wi") else {
                    continue;
                };
                report.evaluations += 1;
                match closure.eval(wo, wi) {
                    Ok(e)
                        if e.value
                            .to_array()
                            .iter()
                            .chain(&[e.pdf, e.pdf_reverse])
                            .all(|v| v.is_finite() && *v >= 0.0) => {}
                    other => fail(report, format!("closure eval at scale {k}: {other:?}")),
                }
            }
        }
    }
}
