//! The Fresnel parameter group shared by the reflective lobes (`conductor`, `mirror`):
//! one schema, one decoder, so every lobe names and reads them the same way.

use super::Params;
use crate::fresnel::FresnelModel;
use crate::math::Lane;

/// Choices of the `fresnel` parameter.
pub const FRESNEL_CHOICES: &[&str] = &["schlick", "conductor", "artistic"];

/// A schema made of the lobe's own parameters `$head` followed by the Fresnel group
/// (`fresnel`, `f0`, `f90`, `eta`, `k`, `reflectivity`, `edge_tint`), whose default
/// model is choice `$default_model`.
macro_rules! with_fresnel_params {
    ($default_model:expr; $($head:expr),* $(,)?) => {
        &[
            $($head,)*
            $crate::params::ParamSpec::choice(
                "fresnel",
                $crate::lobes::fresnel_params::FRESNEL_CHOICES,
                $default_model,
                "schlick: f0/f90; conductor: complex IOR eta + i k; artistic: Gulbrandsen 2014 reflectivity/edge_tint",
            ),
            $crate::params::ParamSpec::rgb("f0", [1.0; 3], 0.0, 1.0, "schlick: reflectance at normal incidence"),
            $crate::params::ParamSpec::rgb("f90", [1.0; 3], 0.0, 1.0, "schlick: reflectance at grazing incidence"),
            $crate::params::ParamSpec::rgb("eta", [0.2, 0.92, 1.1], 0.001, 1000.0, "conductor: real part of the IOR (default: gold)"),
            $crate::params::ParamSpec::rgb("k", [3.9, 2.45, 2.14], 0.0, 1000.0, "conductor: imaginary part of the IOR (default: gold)"),
            $crate::params::ParamSpec::rgb("reflectivity", [0.95, 0.64, 0.54], 0.0, 1.0, "artistic: reflectance at normal incidence"),
            $crate::params::ParamSpec::rgb("edge_tint", [1.0, 0.98, 0.9], 0.0, 1.0, "artistic: color toward grazing angles"),
        ]
    };
}
pub(crate) use with_fresnel_params;

/// Decode the Fresnel group starting at block offset `at`.
#[inline(always)]
pub fn decode<L: Lane>(params: &Params<'_, L>, at: usize) -> FresnelModel<L> {
    let rgb = |i: usize| params.rgb(at + 1 + 3 * i);
    match params.choice(at) {
        0 => FresnelModel::Schlick {
            f0: rgb(0),
            f90: rgb(1),
        },
        1 => FresnelModel::Conductor {
            eta: rgb(2),
            k: rgb(3),
        },
        _ => FresnelModel::artistic(rgb(4), rgb(5)),
    }
}
