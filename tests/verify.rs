//! The verification harness: the fast tier passes for every registered lobe and
//! material, and each deliberately broken lobe is caught by the check that matches
//! its defect.

use glint::lobes::{Eval, LobeType, Sample, Transport, flags};
use glint::math::{Rgb, Vec3};
use glint::params::ParamSpec;
use glint::registry::Registry;
use glint::verify::{self, Report, Tier};
use std::f32::consts::{FRAC_1_PI, PI};

#[test]
fn fast_tier_passes_for_every_registered_lobe() {
    let registry = Registry::with_builtins();
    let report = verify::verify_registry(&registry, Tier::Fast);
    let verified: Vec<&str> = report.lobes.iter().map(|l| l.lobe.as_str()).collect();
    let materials: Vec<String> = registry
        .material_names()
        .iter()
        .map(|m| format!("material {m}"))
        .collect();
    let expected: Vec<&str> = registry
        .names()
        .into_iter()
        .chain(materials.iter().map(String::as_str))
        .collect();
    assert_eq!(
        verified, expected,
        "every registered lobe and material is verified"
    );
    for l in &report.lobes {
        assert!(
            l.hard.evaluations > 10_000,
            "{}: {} hard-case evaluations",
            l.lobe,
            l.hard.evaluations
        );
        assert!(!l.cases.is_empty());
    }
    assert!(report.passed(), "{}", report.failures().join("\n"));
}

/// How a test lobe departs from an honest Lambertian.
#[derive(Clone, Copy, PartialEq)]
enum Defect {
    /// Samples cosine-weighted but reports a pdf tilted by `1 + 0.5 x` (still
    /// normalized, and sample and eval agree with each other).
    WrongPdf,
    /// Returns a negative value for directions with `x < -0.5`.
    NegativeValue,
    /// `f` depends on `wo` only, while the lobe claims reciprocity.
    NonReciprocal,
    /// Reflects 130% of the light, and says so in its albedo.
    AlbedoAboveOne,
    /// Honest, but its `albedo` claims 0.6 for a true 0.8.
    WrongAlbedo,
    /// Honest, but its albedo estimate (selection, pruning) is 0.7, 12% off, where it
    /// documents 5%.
    WrongEstimate,
    /// Honest, but its samples report component 1 of a type with one component.
    ComponentOutOfRange,
}

struct Broken(Defect);

impl Broken {
    fn f(&self, wo: Vec3<f32>, wi: Vec3<f32>) -> f32 {
        let base = match self.0 {
            Defect::AlbedoAboveOne => 1.3,
            _ => 0.8,
        } * FRAC_1_PI;
        match self.0 {
            Defect::NegativeValue if wi.x < -0.5 => -0.1,
            Defect::NonReciprocal => base * (0.5 + 0.5 * wo.z),
            _ => base,
        }
    }
    fn pdf(&self, wi: Vec3<f32>) -> f32 {
        let tilt = if self.0 == Defect::WrongPdf {
            1.0 + 0.5 * wi.x
        } else {
            1.0
        };
        wi.z * FRAC_1_PI * tilt
    }
}

impl LobeType for Broken {
    fn name(&self) -> &str {
        "broken"
    }
    fn summary(&self) -> &str {
        "a deliberately broken Lambertian"
    }
    fn params(&self) -> &[ParamSpec] {
        &[]
    }
    fn flags(&self) -> u32 {
        flags::REFLECTION | flags::DIFFUSE
    }
    fn reciprocal(&self) -> bool {
        true
    }
    fn eval(&self, _p: &[f32], wo: Vec3<f32>, wi: Vec3<f32>, _mode: Transport) -> Eval<f32> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Eval::zero();
        }
        Eval {
            value: Rgb::splat(self.f(wo, wi) * wi.z),
            pdf: self.pdf(wi),
        }
    }
    fn sample(&self, p: &[f32], wo: Vec3<f32>, u: [f32; 3], mode: Transport) -> Sample<f32> {
        let r = u[1].sqrt();
        let phi = 2.0 * PI * u[2];
        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u[1]).max(0.0).sqrt());
        let e = self.eval(p, wo, wi, mode);
        Sample {
            wi,
            value: e.value,
            pdf: e.pdf,
            valid: wo.z > 0.0 && wi.z > 0.0,
            transmitted: false,
            delta: false,
            eta: 1.0,
            roughness: 1.0,
            class: flags::DIFFUSE as f32,
            component: if self.0 == Defect::ComponentOutOfRange {
                1.0
            } else {
                0.0
            },
        }
    }
    fn albedo(&self, _p: &[f32], wo: Vec3<f32>, _mode: Transport) -> Rgb<f32> {
        let a = match self.0 {
            Defect::AlbedoAboveOne => 1.3,
            Defect::WrongAlbedo => 0.6,
            Defect::NonReciprocal => 0.8 * (0.5 + 0.5 * wo.z),
            _ => 0.8,
        };
        Rgb::splat(if wo.z > 0.0 { a } else { 0.0 })
    }
    fn albedo_tolerance(&self, _params: &[f32]) -> f32 {
        1e-3
    }
    fn albedo_estimate_decoded(&self, p: &[f32], wo: Vec3<f32>, mode: Transport) -> Rgb<f32> {
        let a = self.albedo(p, wo, mode);
        if self.0 == Defect::WrongEstimate {
            a * 0.875
        } else {
            a
        }
    }
    fn albedo_estimate_tolerance(&self, _params: &[f32]) -> f32 {
        0.05
    }
}

static WRONG_PDF: Broken = Broken(Defect::WrongPdf);
static NEGATIVE: Broken = Broken(Defect::NegativeValue);
static NON_RECIPROCAL: Broken = Broken(Defect::NonReciprocal);
static ABOVE_ONE: Broken = Broken(Defect::AlbedoAboveOne);
static WRONG_ALBEDO: Broken = Broken(Defect::WrongAlbedo);
static WRONG_ESTIMATE: Broken = Broken(Defect::WrongEstimate);
static COMPONENT_OUT_OF_RANGE: Broken = Broken(Defect::ComponentOutOfRange);

fn verify(lobe: &'static Broken) -> Report {
    let lobe: &'static dyn LobeType = lobe;
    Report::new(
        Tier::Fast,
        vec![verify::verify_lobe(&lobe.into(), Tier::Fast)],
    )
}

#[test]
fn a_wrong_pdf_fails_chi_square() {
    let r = verify(&WRONG_PDF);
    let case = &r.lobes[0].cases[0];
    assert!(
        case.chi2_p_min() < r.alpha_per_test,
        "p = {}",
        case.chi2_p_min()
    );
    assert!(
        r.failures().iter().any(|f| f.contains("chi-square")),
        "{:?}",
        r.failures()
    );
    // Sample and eval agree with each other and the pdf still integrates to 1, so the
    // consistency checks cannot see it (the biased weights also trip the energy checks).
    assert_eq!(case.consistency_max_err, 0.0);
    assert!(case.pdf_integral_max_err < 2e-3);
    assert!(
        !r.failures().iter().any(|f| f.contains("consistency")),
        "{:?}",
        r.failures()
    );
}

#[test]
fn a_negative_value_fails_the_hard_cases() {
    let r = verify(&NEGATIVE);
    assert!(r.lobes[0].hard.failures > 0);
    let first = r.lobes[0].hard.first_failure.clone().unwrap_or_default();
    assert!(first.starts_with("eval"), "{first}");
    assert!(!r.passed());
}

#[test]
fn a_false_reciprocity_claim_fails_reciprocity() {
    let r = verify(&NON_RECIPROCAL);
    let err = r.lobes[0].cases[0]
        .reciprocity_max_err
        .expect("claims reciprocity");
    assert!(err > verify::RECIPROCITY_TOLERANCE, "{err}");
    assert!(
        r.failures().iter().any(|f| f.contains("reciprocity")),
        "{:?}",
        r.failures()
    );
}

#[test]
fn albedo_above_one_fails_energy() {
    let r = verify(&ABOVE_ONE);
    let case = &r.lobes[0].cases[0];
    assert!(case.energy_violations > 0);
    assert!(case.albedo_max > 1.2, "{}", case.albedo_max);
    assert!(
        r.failures().iter().any(|f| f.contains("albedo above 1")),
        "{:?}",
        r.failures()
    );
}

#[test]
fn a_wrong_albedo_claim_fails_the_albedo_check() {
    let r = verify(&WRONG_ALBEDO);
    assert!(r.lobes[0].cases[0].albedo_failures > 0);
    assert!(
        r.failures().iter().all(|f| f.contains("albedo(wo)")),
        "{:?}",
        r.failures()
    );
}

#[test]
fn the_honest_lambert_passes_the_same_checks() {
    // The control: the same harness on the built-in Lambertian finds nothing.
    let registry = Registry::with_builtins();
    let lambert = registry.get(registry.find("lambert").unwrap()).unwrap();
    let r = Report::new(Tier::Fast, vec![verify::verify_lobe(lambert, Tier::Fast)]);
    assert!(r.passed(), "{:?}", r.failures());
}

#[test]
fn an_estimate_off_its_tolerance_fails_the_estimate_check() {
    let r = verify(&WRONG_ESTIMATE);
    let case = &r.lobes[0].cases[0];
    assert!(case.albedo_estimate_failures > 0);
    assert!((case.albedo_estimate_max_rel_err - 0.125).abs() < 1e-6);
    assert!(
        r.failures().iter().all(|f| f.contains("albedo estimate")),
        "{:?}",
        r.failures()
    );
}

#[test]
fn a_component_beyond_the_count_fails_consistency() {
    let r = verify(&COMPONENT_OUT_OF_RANGE);
    assert!(r.lobes[0].cases[0].flag_errors > 0);
    assert!(
        r.failures()
            .iter()
            .all(|f| f.contains("class or component")),
        "{:?}",
        r.failures()
    );
}
