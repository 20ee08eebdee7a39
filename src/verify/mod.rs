//! The verification harness: every registered lobe type, over its default parameters
//! and the parameter sets it declares (`LobeType::verify_cases`), goes through
//!
//! 1. chi-square goodness of fit of `sample` against `pdf` ([`chi2`]), on the sphere and
//!    in lobe-centred windows: a chi-square test in a tangent-plane window centred on each
//!    part of the lobe (reflection, transmission) and scaled to its width, where a
//!    narrow lobe spans many cells, and moment tests of the weights there
//!    (`E[weight g]`, `g = 1, u, v`) against quadratures of `eval`; run for every case
//!    and for narrow variants of every lobe with a `roughness` ([`narrow_sets`]);
//! 2. consistency: sampled value and pdf equal `eval` (relative [`CONSISTENCY_TOLERANCE`]),
//!    and a closure's world-space sample equals the closure's `eval` at the returned
//!    direction (relative [`CLOSURE_CONSISTENCY_TOLERANCE`], tilted frame, grazing `wo`),
//!    weight = value / pdf, flags within the lobe's, delta samples evaluate to 0, and the
//!    pdf integrates to 1 minus the share of samples that fail (absorbed);
//! 3. reciprocity `f(wo, wi) = f(wi, wo)` of the raw BSDF for lobes that declare it;
//! 4. energy: directional albedo `<= 1` within 3 standard errors (importance transport,
//!    where refraction carries no `1/eta^2` radiance compression), estimated by importance
//!    sampling and cross-checked by a uniform, adaptively refined quadrature of `eval`
//!    over the sphere, and the lobe's `albedo(wo)`
//!    against that estimate within its documented tolerance, and its albedo estimate
//!    (selection, pruning) against `albedo(wo)` within the estimate's tolerance;
//! 5. hard cases: grazing, horizon, below-surface, equal and opposite directions, every
//!    schema parameter at its corners (0, 1e-7, 1e-4, the delta threshold and either
//!    side of it, 1, IOR 1 +- 1e-6, 1e-3, 1e3...) and random parameters over each
//!    schema's range, plus unnormalized and near-zero-length inputs through the checks
//!    the C boundary applies: never NaN, Inf, negative values or pdfs, never a weight
//!    with a zero pdf;
//! 6. scalar vs batch: the batch entry points agree with the scalar ones.
//!
//! Two tiers: [`Tier::Fast`] runs inside `cargo test`, [`Tier::Full`] from the
//! `glint-verify` command, which writes `target/verify/report.md` and `report.json`.

mod checks;
pub mod chi2;
pub mod material;
mod report;

pub use report::{CaseReport, Chi2Row, HardReport, LobeReport, Moment, Report, WindowRow};

use crate::lobes::LobeType;
use crate::params::{self, ParamKind};
use crate::registry::{LobeRef, Registry};

/// Maximum relative difference between a sample's value/pdf and `eval` at its direction.
pub const CONSISTENCY_TOLERANCE: f64 = 1e-4;
/// Maximum relative difference between a closure's sample (value, pdf) and the
/// closure's `eval` at the world-space direction the sample returns: they are
/// evaluated at the same direction, so only summation order may differ.
pub const CLOSURE_CONSISTENCY_TOLERANCE: f64 = 1e-6;
/// Maximum relative asymmetry of reciprocal lobes.
pub const RECIPROCITY_TOLERANCE: f64 = 1e-4;
/// Maximum [`batch_difference`] between batch and scalar results. The scalar kernels
/// match the scalar calls exactly; the SIMD kernels round as they do except in the
/// vectorized `exp` (Beckmann) and explicit `mul_add`s, whose last-bit differences
/// nothing amplifies (`Vec3::dot` does not fuse: see there). `tests/simd_bound.rs`
/// measured up to 4.4e-7 at ill-conditioned inputs (Beckmann lobes; GGX, lambert and
/// mirror bit for bit), so the bound is 3x that.
pub const BATCH_TOLERANCE: f64 = 1.5e-6;
/// Maximum [`batch_difference`] of sample outputs: the sampled direction itself
/// moves by the vectorized trigonometry's error, and value, weight and pdf are
/// evaluated there.
pub const BATCH_SAMPLE_TOLERANCE: f64 = 2e-3;
/// Magnitude below which batch and scalar results are compared absolutely.
pub const BATCH_FLOOR: f64 = 1e-2;

/// Relative difference of a batch result `a` from the scalar `b`, absolute below
/// [`BATCH_FLOOR`].
pub fn batch_difference(a: f32, b: f32) -> f64 {
    let (a, b) = (f64::from(a), f64::from(b));
    (a - b).abs() / a.abs().max(b.abs()).max(BATCH_FLOOR)
}
/// Overall significance of all chi-square tests of a run (Sidak-corrected per test).
pub const CHI2_ALPHA: f64 = 0.01;

/// How much work each check does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    /// Seconds per lobe; runs in `cargo test`.
    Fast,
    /// At least 1M samples per chi-square test and 1M hard-case evaluations per lobe.
    Full,
}

/// Sample counts and grid sizes of a tier.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    pub chi2_samples: usize,
    pub chi2_grid: chi2::Grid,
    pub chi2_cos_theta: &'static [f32],
    /// Samples of each lobe-centred window test (chi-square and moments).
    pub window_samples: usize,
    /// Samples that place the windows.
    pub window_pilot: usize,
    /// Cells per side of a window.
    pub window_cells: usize,
    /// `cos theta_o` of the window tests: the chi-square angles and 45-60 degrees,
    /// where a view-independent sampler of a narrow lobe is hardest to see.
    pub window_cos_theta: &'static [f32],
    pub consistency_samples: usize,
    pub reciprocity_pairs: usize,
    pub energy_samples: usize,
    pub energy_cos_theta: &'static [f32],
    pub random_param_sets: usize,
    pub batch_lanes: usize,
}

impl Tier {
    pub fn budget(self) -> Budget {
        match self {
            Tier::Fast => Budget {
                chi2_samples: 40_000,
                chi2_grid: chi2::Grid {
                    n_theta: 10,
                    n_phi: 20,
                },
                chi2_cos_theta: &[0.9, 0.35, 0.05],
                window_samples: 500_000,
                window_pilot: 4_000,
                window_cells: 10,
                window_cos_theta: &[0.9, std::f32::consts::FRAC_1_SQRT_2, 0.6428, 0.5, 0.05],
                consistency_samples: 2_000,
                reciprocity_pairs: 2_000,
                energy_samples: 10_000,
                energy_cos_theta: &[1.0, 0.7, 0.3, 0.05],
                random_param_sets: 20,
                batch_lanes: 256,
            },
            Tier::Full => Budget {
                chi2_samples: 1_000_000,
                chi2_grid: chi2::Grid {
                    n_theta: 20,
                    n_phi: 40,
                },
                chi2_cos_theta: &[0.95, 0.6, 0.2, 0.03],
                window_samples: 2_000_000,
                window_pilot: 20_000,
                window_cells: 16,
                window_cos_theta: &[
                    0.95,
                    std::f32::consts::FRAC_1_SQRT_2,
                    0.6428,
                    0.6,
                    0.5,
                    0.2,
                    0.03,
                ],
                consistency_samples: 100_000,
                reciprocity_pairs: 100_000,
                energy_samples: 200_000,
                energy_cos_theta: &[1.0, 0.9, 0.7, 0.5, 0.3, 0.1, 0.02],
                random_param_sets: 1_300,
                batch_lanes: 4096,
            },
        }
    }
}

/// A parameter set to verify: the defaults with named overrides applied.
pub struct ParamSet {
    pub name: String,
    pub block: Vec<f32>,
}

/// The defaults and every declared case of `lobe`, as parameter blocks.
pub fn param_sets(lobe: &dyn LobeType) -> Vec<ParamSet> {
    let specs = lobe.params();
    let mut defaults = vec![0.0; params::block_size(specs)];
    params::write_defaults(specs, &mut defaults);
    let mut sets = vec![ParamSet {
        name: "defaults".into(),
        block: defaults.clone(),
    }];
    for case in lobe.verify_cases() {
        let mut block = defaults.clone();
        for (name, value) in case.set {
            let index = specs
                .iter()
                .position(|s| s.name == *name)
                .unwrap_or_else(|| {
                    panic!(
                        "{}: verify case \"{}\" names unknown parameter {name}",
                        lobe.name(),
                        case.name
                    )
                });
            let offset = params::offset_of(specs, index);
            let n = specs[index].kind.size();
            block[offset..offset + n].fill(*value);
        }
        sets.push(ParamSet {
            name: case.name.into(),
            block,
        });
    }
    sets
}

/// Roughness of the [`narrow_sets`]: `alpha = 0.01`, a lobe about a degree wide.
pub const NARROW_ROUGHNESS: f32 = 0.1;

/// Narrow variants of a lobe whose schema has a float `roughness`: the defaults at
/// [`NARROW_ROUGHNESS`], once per choice of each enum parameter (distribution,
/// Fresnel model...), duplicates removed. Empty for lobes without a roughness.
pub fn narrow_sets(lobe: &dyn LobeType) -> Vec<ParamSet> {
    let specs = lobe.params();
    let Some(roughness) = specs
        .iter()
        .position(|s| s.name == "roughness" && matches!(s.kind, ParamKind::Float))
    else {
        return Vec::new();
    };
    let mut base = vec![0.0; params::block_size(specs)];
    params::write_defaults(specs, &mut base);
    base[params::offset_of(specs, roughness)] = NARROW_ROUGHNESS;
    let mut sets = vec![ParamSet {
        name: format!("narrow (roughness {NARROW_ROUGHNESS})"),
        block: base.clone(),
    }];
    for (i, spec) in specs.iter().enumerate() {
        if spec.kind != ParamKind::Enum {
            continue;
        }
        for (c, choice) in spec.choices.iter().enumerate() {
            let mut block = base.clone();
            block[params::offset_of(specs, i)] = c as f32;
            if sets.iter().all(|s| s.block != block) {
                sets.push(ParamSet {
                    name: format!(
                        "narrow (roughness {NARROW_ROUGHNESS}, {} {choice})",
                        spec.name
                    ),
                    block,
                });
            }
        }
    }
    sets
}

/// Values every float or color parameter is tried at (those within its range), besides
/// its min, max and default: zero and tiny roughness, the delta threshold and either side
/// of it, unit and near-unit IOR, extreme IORs.
pub fn corner_values(min: f32, max: f32) -> Vec<f32> {
    let threshold = crate::microfacet::DELTA_ALPHA.sqrt();
    let mut v = vec![
        min,
        max,
        0.0,
        1e-7,
        1e-4,
        threshold,
        threshold * (1.0 - 1e-6),
        threshold * (1.0 + 1e-6),
        0.5,
        1.0,
        1.0 - 1e-6,
        1.0 + 1e-6,
        1e-3,
        1e3,
    ];
    v.retain(|x| (min..=max).contains(x));
    v
}

/// One-at-a-time corners of `lobe`'s schema around its defaults.
pub fn corner_sets(lobe: &dyn LobeType) -> Vec<Vec<f32>> {
    let specs = lobe.params();
    let mut defaults = vec![0.0; params::block_size(specs)];
    params::write_defaults(specs, &mut defaults);
    let mut sets = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let offset = params::offset_of(specs, i);
        let n = spec.kind.size();
        let values = match spec.kind {
            ParamKind::Enum => (0..spec.choices.len()).map(|c| c as f32).collect(),
            _ => corner_values(spec.min, spec.max),
        };
        for v in values {
            let mut block = defaults.clone();
            block[offset..offset + n].fill(v);
            sets.push(block);
        }
    }
    sets
}

/// A small deterministic generator (xorshift64*) for reproducible runs.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn uniform3(&mut self) -> [f32; 3] {
        [self.uniform(), self.uniform(), self.uniform()]
    }
}

/// Verify one lobe type at the given tier (chi-square significance left for the
/// caller's [`Report`] to decide, since it depends on the number of tests in the run).
pub fn verify_lobe(lobe: &LobeRef, tier: Tier) -> LobeReport {
    let budget = tier.budget();
    let sanitized_before = lobe.sanitized_count();
    let mut rng = Rng::new(0x6c69_6e74 ^ lobe.name().len() as u64);
    let sets = param_sets(&**lobe);
    let mut cases: Vec<CaseReport> = sets
        .iter()
        .map(|set| checks::verify_case(lobe, set, &budget, &mut rng))
        .collect();
    cases.extend(
        narrow_sets(&**lobe)
            .iter()
            .map(|set| checks::verify_sampling(lobe, set, &budget, &mut rng)),
    );
    let hard = checks::hard_cases(lobe, &sets, &budget, &mut rng);
    LobeReport {
        lobe: lobe.name().to_string(),
        reciprocal: lobe.reciprocal(),
        cases,
        hard,
        sanitized: lobe.sanitized_count() - sanitized_before,
    }
}

/// Verify every lobe type of `registry`, then every material type (as a lobe:
/// [`material::MaterialLobe`]).
pub fn verify_registry(registry: &Registry, tier: Tier) -> Report {
    let mut reports: Vec<LobeReport> = registry
        .iter()
        .map(|lobe| verify_lobe(lobe, tier))
        .collect();
    reports.extend((0..registry.materials().len() as u32).map(|id| verify_material(id, tier)));
    Report::new(tier, reports)
}

/// Verify built-in material type `type_id` through [`material::MaterialLobe`].
pub fn verify_material(type_id: u32, tier: Tier) -> LobeReport {
    let lobe = material::MaterialLobe::new(type_id)
        .unwrap_or_else(|e| panic!("material type {type_id}: {}", e.message));
    verify_lobe(&LobeRef::Shared(std::sync::Arc::new(lobe)), tier)
}
