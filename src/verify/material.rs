//! Materials through the harness: [`MaterialLobe`] presents a material type as a lobe
//! type whose parameter block is the material's, each call building the closure
//! `Material::closure` builds at that `wo` (identity frame), so every lobe check
//! (chi-square, consistency, reciprocity, energy, hard cases at the schema's corners
//! and random parameters) runs on the whole expansion: weights, selection
//! probabilities and the mixture. Pruning is off (`prune = 0`): the harness checks the
//! model; `tests/material_disney.rs` bounds what pruning changes.

use crate::closure::Closure;
use crate::error::Error;
use crate::lobes::{Eval, LobeType, Sample, Transport, VerifyCase, flags};
use crate::materials::{Material, MaterialType, ShadingContext};
use crate::math::{Frame, Rgb, Vec3};
use crate::params::{self, ParamSpec};
use crate::registry::Registry;

/// A material type as a lobe type, for the harness.
pub struct MaterialLobe {
    name: String,
    kind: &'static dyn MaterialType,
    type_id: u32,
    registry: Registry,
    flags: u32,
    reciprocal: bool,
    /// The most components a slot's lobe reports.
    components: u32,
}

impl MaterialLobe {
    /// Material type `type_id` of a registry holding the built-in lobes.
    pub fn new(type_id: u32) -> Result<MaterialLobe, Error> {
        let registry = Registry::with_builtins();
        let kind = registry.material(type_id)?;
        let default = Material::new(&registry, type_id, None, 0.0)?;
        let flags = default.slots().iter().fold(0, |f, (_, l)| f | l.flags());
        let reciprocal = default.slots().iter().all(|(_, l)| l.reciprocal());
        let components = default
            .slots()
            .iter()
            .map(|(_, l)| l.component_count())
            .fold(1, u32::max);
        Ok(MaterialLobe {
            name: format!("material {}", kind.name()),
            kind,
            type_id,
            registry,
            flags,
            reciprocal,
            components,
        })
    }

    /// The closure at `wo` and `wo` normalized as the C boundary does (every call of
    /// the closure takes that one).
    fn closure(&self, params: &[f32], wo: Vec3<f32>) -> Option<(Closure, Vec3<f32>)> {
        let material = Material::new(&self.registry, self.type_id, Some(params), 0.0).ok()?;
        let wo = Vec3::try_unit(wo.x, wo.y, wo.z, "wo").ok()?;
        let closure = material
            .closure(&ShadingContext::new(wo, Frame::IDENTITY), &[])
            .ok()?;
        Some((closure, wo))
    }
}

impl LobeType for MaterialLobe {
    fn name(&self) -> &str {
        &self.name
    }
    fn summary(&self) -> &str {
        self.kind.summary()
    }
    fn params(&self) -> &[ParamSpec] {
        self.kind.params()
    }
    fn flags(&self) -> u32 {
        self.flags
    }
    fn reciprocal(&self) -> bool {
        self.reciprocal
    }
    fn component_count(&self) -> u32 {
        self.components
    }
    fn eval(&self, params: &[f32], wo: Vec3<f32>, wi: Vec3<f32>, mode: Transport) -> Eval<f32> {
        debug_assert_eq!(mode, Transport::Radiance);
        let Some((c, wo)) = self.closure(params, wo) else {
            return Eval::zero();
        };
        // Normalized as the C boundary does (a sample is valued at that direction).
        let Ok(wi) = Vec3::try_unit(wi.x, wi.y, wi.z, "wi") else {
            return Eval::zero();
        };
        c.eval_forward(wo, wi).map_or(Eval::zero(), |e| Eval {
            value: e.value,
            pdf: e.pdf,
        })
    }
    fn sample(&self, params: &[f32], wo: Vec3<f32>, u: [f32; 3], _mode: Transport) -> Sample<f32> {
        let failed = crate::lobes::no_sample();
        let Some((c, wo)) = self.closure(params, wo) else {
            return failed;
        };
        match c.sample(wo, u) {
            Ok(s) => Sample {
                wi: s.wi,
                value: s.value,
                pdf: s.pdf,
                valid: true,
                transmitted: s.flags & flags::TRANSMISSION != 0,
                delta: s.flags & flags::SPECULAR != 0,
                eta: s.eta,
                roughness: s.roughness,
                class: (s.flags & (flags::DIFFUSE | flags::GLOSSY | flags::SPECULAR)) as f32,
                component: s.component as f32,
            },
            Err(_) => failed,
        }
    }
    fn albedo(&self, params: &[f32], wo: Vec3<f32>, _mode: Transport) -> Rgb<f32> {
        self.closure(params, wo)
            .and_then(|(c, wo)| c.albedo(wo).ok())
            .unwrap_or(Rgb::zero())
    }
    fn verify_cases(&self) -> &[VerifyCase] {
        self.kind.verify_cases()
    }
    /// The sum over slots of the largest weight channel times the slot lobe's bound.
    fn energy_bound(&self, params: &[f32]) -> f32 {
        let Ok(material) = Material::new(&self.registry, self.type_id, Some(params), 0.0) else {
            return 1.0;
        };
        let e = self.kind.expand(
            params,
            &ShadingContext::new(Vec3::new(0.0, 0.0, 1.0), Frame::IDENTITY).lanes(),
        );
        let sum: f32 = material
            .slots()
            .iter()
            .enumerate()
            .map(|(k, (_, lobe))| {
                let w = e.weight[k];
                w.r.max(w.g).max(w.b)
                    * lobe.energy_bound(&e.params[k][..params::block_size(lobe.params())])
            })
            .sum();
        sum.max(1.0)
    }

    /// The largest documented tolerance of the lobes the material emits with these
    /// parameters (at normal incidence).
    fn albedo_tolerance(&self, params: &[f32]) -> f32 {
        let Ok(material) = Material::new(&self.registry, self.type_id, Some(params), 0.0) else {
            return 0.0;
        };
        let e = self.kind.expand(
            params,
            &ShadingContext::new(Vec3::new(0.0, 0.0, 1.0), Frame::IDENTITY).lanes(),
        );
        material
            .slots()
            .iter()
            .enumerate()
            .map(|(k, (_, lobe))| {
                lobe.albedo_tolerance(&e.params[k][..params::block_size(lobe.params())])
            })
            .fold(0.0, f32::max)
    }
}
