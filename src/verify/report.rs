//! Harness results, pass/fail decisions, and the Markdown and JSON reports.

use super::{
    BATCH_SAMPLE_TOLERANCE, BATCH_TOLERANCE, CHI2_ALPHA, CLOSURE_CONSISTENCY_TOLERANCE,
    CONSISTENCY_TOLERANCE, RECIPROCITY_TOLERANCE, Tier,
};
use serde_json::{Value, json};

/// Allowed error of the pdf's integral over the sphere beyond 3 standard errors of the
/// absorbed share (the adaptive cell integration's own error).
pub const PDF_INTEGRAL_TOLERANCE: f64 = 2e-3;

/// One chi-square test.
#[derive(Clone, Debug)]
pub struct Chi2Row {
    pub cos_theta_o: f32,
    pub statistic: f64,
    pub dof: usize,
    /// NaN when the test does not apply (every sample was a delta).
    pub p_value: f64,
    /// Share of samples that failed (absorbed).
    pub absorbed: f64,
    pub pdf_integral: f64,
}

impl Chi2Row {
    pub fn not_applicable(cos_theta_o: f32, absorbed: f64) -> Chi2Row {
        Chi2Row {
            cos_theta_o,
            statistic: 0.0,
            dof: 0,
            p_value: f64::NAN,
            absorbed,
            pdf_integral: 0.0,
        }
    }
    pub fn applies(&self) -> bool {
        !self.p_value.is_nan()
    }
}

/// A moment of the weights within a window: `E[weight g 1_W]` for `g = 1, u, v`
/// against a quadrature of `eval`.
#[derive(Clone, Copy, Debug)]
pub struct Moment {
    pub estimate: f64,
    pub standard_error: f64,
    pub quadrature: f64,
    pub p_value: f64,
}

/// Names of the window moments, in [`WindowRow::moments`] order.
pub const MOMENT_NAMES: [&str; 3] = ["1", "u", "v"];

/// One lobe-centred window test (see `chi2::Window`).
#[derive(Clone, Debug)]
pub struct WindowRow {
    pub cos_theta_o: f32,
    /// `"same side"` (reflection) or `"other side"` (transmission) of the surface.
    pub side: &'static str,
    /// Half-width of the window in the tangent plane (`tan` of the angle).
    pub half_width: f64,
    /// Samples that fell into the window.
    pub inside: u64,
    pub chi2: Chi2Row,
    pub moments: [Moment; 3],
}

impl WindowRow {
    /// Every p-value of the row: the chi-square test and the three moments.
    pub fn p_values(&self) -> impl Iterator<Item = f64> + '_ {
        std::iter::once(self.chi2.p_value)
            .chain(self.moments.iter().map(|m| m.p_value))
            .filter(|p| !p.is_nan())
    }
}

/// Results of one parameter set of one lobe.
#[derive(Clone, Debug)]
pub struct CaseReport {
    pub case: String,
    pub chi2: Vec<Chi2Row>,
    pub windows: Vec<WindowRow>,
    pub consistency_max_err: f64,
    /// Worst relative mismatch of a closure's sample (world space, a tilted frame)
    /// against the closure's `eval` at the returned direction.
    pub closure_consistency_max_err: f64,
    pub pdf_integral_max_err: f64,
    pub flag_errors: u64,
    pub reciprocity_max_err: Option<f64>,
    pub albedo_min: f64,
    pub albedo_max: f64,
    pub energy_violations: u64,
    pub uniform_mismatches: u64,
    pub albedo_max_rel_err: f64,
    pub albedo_failures: u64,
    /// The first albedo failure: where, what was claimed, what was estimated.
    pub albedo_failure_detail: Option<String>,
    /// Worst relative difference of the albedo estimate (selection, pruning) from
    /// the albedo, and how many channels exceed its documented tolerance.
    pub albedo_estimate_max_rel_err: f64,
    pub albedo_estimate_failures: u64,
    pub batch_max_err: f64,
    /// Worst batch-vs-scalar difference of sample outputs.
    pub batch_sample_err: f64,
}

impl CaseReport {
    pub fn new(case: String) -> CaseReport {
        CaseReport {
            case,
            chi2: Vec::new(),
            windows: Vec::new(),
            consistency_max_err: 0.0,
            closure_consistency_max_err: 0.0,
            pdf_integral_max_err: 0.0,
            flag_errors: 0,
            reciprocity_max_err: None,
            albedo_min: f64::INFINITY,
            albedo_max: f64::NEG_INFINITY,
            energy_violations: 0,
            uniform_mismatches: 0,
            albedo_max_rel_err: 0.0,
            albedo_failures: 0,
            albedo_failure_detail: None,
            albedo_estimate_max_rel_err: 0.0,
            albedo_estimate_failures: 0,
            batch_max_err: 0.0,
            batch_sample_err: 0.0,
        }
    }

    /// Smallest chi-square p-value (NaN when no test applied).
    pub fn chi2_p_min(&self) -> f64 {
        self.chi2
            .iter()
            .filter(|r| r.applies())
            .map(|r| r.p_value)
            .fold(f64::NAN, f64::min)
    }

    /// Smallest p-value of the window tests (NaN when none applied).
    pub fn window_p_min(&self) -> f64 {
        self.windows
            .iter()
            .flat_map(WindowRow::p_values)
            .fold(f64::NAN, f64::min)
    }

    /// Number of statistical tests (chi-square and moments) of this case.
    pub fn tests(&self) -> usize {
        self.chi2.iter().filter(|r| r.applies()).count()
            + self
                .windows
                .iter()
                .map(|w| w.p_values().count())
                .sum::<usize>()
    }

    /// The checks this case fails, each with the measured value.
    pub fn failures(&self, alpha_per_test: f64) -> Vec<String> {
        let mut out = Vec::new();
        for r in self
            .chi2
            .iter()
            .filter(|r| r.applies() && r.p_value < alpha_per_test)
        {
            out.push(format!(
                "chi-square: p = {:.3e} < {alpha_per_test:.3e} at cos_o = {} (X^2 = {:.1}, dof {})",
                r.p_value, r.cos_theta_o, r.statistic, r.dof
            ));
        }
        for w in &self.windows {
            let at = format!(
                "at cos_o = {} ({}, half-width {:.3e}, {} samples inside)",
                w.cos_theta_o, w.side, w.half_width, w.inside
            );
            if w.chi2.applies() && w.chi2.p_value < alpha_per_test {
                out.push(format!(
                    "window chi-square: p = {:.3e} < {alpha_per_test:.3e} {at} (X^2 = {:.1}, dof {})",
                    w.chi2.p_value, w.chi2.statistic, w.chi2.dof
                ));
            }
            for (m, name) in w.moments.iter().zip(MOMENT_NAMES) {
                if m.p_value < alpha_per_test {
                    out.push(format!(
                        "window moment E[weight {name}]: {:.5e} +- {:.1e} vs quadrature {:.5e} \
                         (p = {:.3e}) {at}",
                        m.estimate, m.standard_error, m.quadrature, m.p_value
                    ));
                }
            }
        }
        if self.consistency_max_err > CONSISTENCY_TOLERANCE {
            out.push(format!(
                "consistency: sample vs eval error {:.3e}",
                self.consistency_max_err
            ));
        }
        if self.closure_consistency_max_err > CLOSURE_CONSISTENCY_TOLERANCE {
            out.push(format!(
                "consistency: closure sample vs eval at the returned wi error {:.3e}",
                self.closure_consistency_max_err
            ));
        }
        if self.pdf_integral_max_err > PDF_INTEGRAL_TOLERANCE {
            let worst = self.chi2.iter().filter(|r| r.applies()).max_by(|a, b| {
                (a.pdf_integral + a.absorbed - 1.0)
                    .abs()
                    .total_cmp(&(b.pdf_integral + b.absorbed - 1.0).abs())
            });
            out.push(format!(
                "consistency: pdf integral off by {:.3e} beyond 3 standard errors{}",
                self.pdf_integral_max_err,
                worst.map_or(String::new(), |r| format!(
                    " (cos_o {}: integral {:.5}, absorbed {:.5})",
                    r.cos_theta_o, r.pdf_integral, r.absorbed
                ))
            ));
        }
        if self.flag_errors > 0 {
            out.push(format!(
                "consistency: {} samples with bad flags, class or component, or failed-sample data",
                self.flag_errors
            ));
        }
        if let Some(e) = self
            .reciprocity_max_err
            .filter(|e| *e > RECIPROCITY_TOLERANCE)
        {
            out.push(format!("reciprocity: error {e:.3e}"));
        }
        if self.energy_violations > 0 {
            out.push(format!(
                "energy: albedo above 1 (max {:.4})",
                self.albedo_max
            ));
        }
        if self.uniform_mismatches > 0 {
            out.push(format!(
                "energy: importance and uniform estimates disagree ({} channels)",
                self.uniform_mismatches
            ));
        }
        if self.albedo_failures > 0 {
            out.push(format!(
                "energy: albedo(wo) off its documented tolerance (relative error {:.3e}; {})",
                self.albedo_max_rel_err,
                self.albedo_failure_detail.as_deref().unwrap_or("")
            ));
        }
        if self.albedo_estimate_failures > 0 {
            out.push(format!(
                "energy: albedo estimate off its documented tolerance (relative error {:.3e})",
                self.albedo_estimate_max_rel_err
            ));
        }
        if self.batch_max_err > BATCH_TOLERANCE {
            out.push(format!(
                "batch: differs from scalar by {:.3e}",
                self.batch_max_err
            ));
        }
        if self.batch_sample_err > BATCH_SAMPLE_TOLERANCE {
            out.push(format!(
                "batch: samples differ from scalar by {:.3e}",
                self.batch_sample_err
            ));
        }
        out
    }
}

/// The hard-case sweep of one lobe.
#[derive(Clone, Debug, Default)]
pub struct HardReport {
    pub evaluations: u64,
    pub failures: u64,
    pub first_failure: Option<String>,
}

/// Everything verified about one lobe type.
#[derive(Clone, Debug)]
pub struct LobeReport {
    pub lobe: String,
    pub reciprocal: bool,
    pub cases: Vec<CaseReport>,
    pub hard: HardReport,
    /// Outputs the lobe type had to have repaired during the run (`LobeType::sanitized_count`).
    pub sanitized: u64,
}

/// A whole run.
#[derive(Clone, Debug)]
pub struct Report {
    pub tier: Tier,
    pub lobes: Vec<LobeReport>,
    /// Number of statistical tests (chi-square and window moments) in the run.
    pub chi2_tests: usize,
    /// Sidak-corrected significance of each: `1 - (1 - CHI2_ALPHA)^(1 / chi2_tests)`.
    pub alpha_per_test: f64,
}

impl Report {
    pub fn new(tier: Tier, lobes: Vec<LobeReport>) -> Report {
        let chi2_tests = lobes
            .iter()
            .flat_map(|l| &l.cases)
            .map(CaseReport::tests)
            .sum::<usize>()
            .max(1);
        Report {
            tier,
            lobes,
            chi2_tests,
            alpha_per_test: 1.0 - (1.0 - CHI2_ALPHA).powf(1.0 / chi2_tests as f64),
        }
    }

    /// Every failed check, as "lobe / case: what".
    pub fn failures(&self) -> Vec<String> {
        let mut out = Vec::new();
        for l in &self.lobes {
            for c in &l.cases {
                for f in c.failures(self.alpha_per_test) {
                    out.push(format!("{} / {}: {f}", l.lobe, c.case));
                }
            }
            if l.sanitized > 0 {
                out.push(format!(
                    "{}: {} outputs broke the lobe contract and were repaired (NaN, infinite, negative or huge values, a plugin sample's class or component)",
                    l.lobe, l.sanitized
                ));
            }
            if l.hard.failures > 0 {
                out.push(format!(
                    "{}: {} hard-case failures, first: {}",
                    l.lobe,
                    l.hard.failures,
                    l.hard.first_failure.as_deref().unwrap_or("")
                ));
            }
        }
        out
    }

    pub fn passed(&self) -> bool {
        self.failures().is_empty()
    }

    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "# Glint verification report\n\nTier: {:?}. Statistical tests (chi-square on the sphere \
             and in lobe-centred windows, window moments): {}, each at significance \
             {:.3e} (Sidak for an overall {CHI2_ALPHA}). Tolerances: consistency {CONSISTENCY_TOLERANCE:e} \
             (closure, world space: {CLOSURE_CONSISTENCY_TOLERANCE:e}), reciprocity {RECIPROCITY_TOLERANCE:e}, batch {BATCH_TOLERANCE:e} (samples \
             {BATCH_SAMPLE_TOLERANCE:e}; kernel sets compared: {}), pdf integral \
             {PDF_INTEGRAL_TOLERANCE:e} beyond 3 standard errors.\n\n\
             | lobe | parameter set | chi2 min p | window min p | consistency max err | closure consistency err | pdf integral err | reciprocity err | albedo min | albedo max | albedo(wo) rel err | batch max err | batch sample err | result |\n\
             | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
            self.tier,
            self.chi2_tests,
            self.alpha_per_test,
            crate::simd::Kernels::available()
                .iter()
                .map(|k| k.isa().name())
                .collect::<Vec<_>>()
                .join(", ")
        );
        for l in &self.lobes {
            for c in &l.cases {
                let p = c.chi2_p_min();
                let fails = c.failures(self.alpha_per_test);
                s += &format!(
                    "| {} | {} | {} | {} | {:.2e} | {:.2e} | {:.2e} | {} | {:.4} | {:.4} | {:.2e} | {:.1e} | {:.1e} | {} |\n",
                    l.lobe,
                    c.case,
                    if p.is_nan() {
                        "n/a (delta)".into()
                    } else {
                        format!("{p:.3}")
                    },
                    {
                        let w = c.window_p_min();
                        if w.is_nan() {
                            "n/a".into()
                        } else {
                            format!("{w:.3}")
                        }
                    },
                    c.consistency_max_err,
                    c.closure_consistency_max_err,
                    c.pdf_integral_max_err,
                    c.reciprocity_max_err
                        .map_or("not reciprocal".into(), |e| format!("{e:.2e}")),
                    c.albedo_min,
                    c.albedo_max,
                    c.albedo_max_rel_err,
                    c.batch_max_err,
                    c.batch_sample_err,
                    if fails.is_empty() {
                        "pass".to_string()
                    } else {
                        fails.join("; ")
                    }
                );
            }
        }
        s += "\n| lobe | hard-case evaluations | failures | sanitized outputs |\n| --- | --- | --- | --- |\n";
        for l in &self.lobes {
            s += &format!(
                "| {} | {} | {} | {} |\n",
                l.lobe, l.hard.evaluations, l.hard.failures, l.sanitized
            );
        }
        let failures = self.failures();
        s += &if failures.is_empty() {
            "\nAll checks passed.\n".to_string()
        } else {
            format!("\n## Failures\n\n- {}\n", failures.join("\n- "))
        };
        s
    }

    pub fn to_json(&self) -> Value {
        let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
        json!({
            "tier": format!("{:?}", self.tier),
            "chi2_tests": self.chi2_tests,
            "alpha_per_test": self.alpha_per_test,
            "passed": self.passed(),
            "lobes": self.lobes.iter().map(|l| json!({
                "lobe": l.lobe,
                "reciprocal": l.reciprocal,
                "hard_case_evaluations": l.hard.evaluations,
                "hard_case_failures": l.hard.failures,
                "hard_case_first_failure": l.hard.first_failure,
                "sanitized_outputs": l.sanitized,
                "cases": l.cases.iter().map(|c| json!({
                    "case": c.case,
                    "chi2": c.chi2.iter().map(|r| json!({
                        "cos_theta_o": r.cos_theta_o,
                        "statistic": r.statistic,
                        "dof": r.dof,
                        "p_value": num(r.p_value),
                        "absorbed": r.absorbed,
                        "pdf_integral": r.pdf_integral,
                    })).collect::<Vec<_>>(),
                    "windows": c.windows.iter().map(|w| json!({
                        "cos_theta_o": w.cos_theta_o,
                        "side": w.side,
                        "half_width": w.half_width,
                        "inside": w.inside,
                        "statistic": w.chi2.statistic,
                        "dof": w.chi2.dof,
                        "p_value": num(w.chi2.p_value),
                        "moments": w.moments.iter().zip(MOMENT_NAMES).map(|(m, name)| json!({
                            "g": name,
                            "estimate": m.estimate,
                            "standard_error": m.standard_error,
                            "quadrature": m.quadrature,
                            "p_value": num(m.p_value),
                        })).collect::<Vec<_>>(),
                    })).collect::<Vec<_>>(),
                    "consistency_max_err": num(c.consistency_max_err),
                    "closure_consistency_max_err": num(c.closure_consistency_max_err),
                    "pdf_integral_max_err": num(c.pdf_integral_max_err),
                    "flag_errors": c.flag_errors,
                    "reciprocity_max_err": c.reciprocity_max_err.map(num),
                    "albedo_min": num(c.albedo_min),
                    "albedo_max": num(c.albedo_max),
                    "energy_violations": c.energy_violations,
                    "uniform_mismatches": c.uniform_mismatches,
                    "albedo_max_rel_err": num(c.albedo_max_rel_err),
                    "albedo_failures": c.albedo_failures,
                    "albedo_estimate_max_rel_err": num(c.albedo_estimate_max_rel_err),
                    "albedo_estimate_failures": c.albedo_estimate_failures,
                    "batch_max_err": num(c.batch_max_err),
                    "batch_sample_err": num(c.batch_sample_err),
                    "failures": c.failures(self.alpha_per_test),
                })).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        })
    }
}
