//! The Fresnel parameter group shared by the reflective lobes (`conductor`, `mirror`):
//! one schema, one decoder, so every lobe names and reads them the same way.

use super::Params;
use crate::albedo_table::{FRESNEL_NODES, FresnelNodes};
use crate::fresnel::FresnelModel;
use crate::kernels;
use crate::math::{Lane, Rgb};
use crate::simd::Kernels;

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

/// Values of the decoded Fresnel group ([`decode`]): the model (0 Schlick, 1
/// conductor), then `f0`, `f90` or `eta`, `k`.
pub const DECODED_LEN: usize = 7;

/// Decode the Fresnel group starting at raw block offset `at` into `out`
/// ([`DECODED_LEN`] values), once: Gulbrandsen's artistic parameters become the
/// complex IOR they stand for.
pub fn decode(params: &[f32], at: usize, out: &mut [f32]) {
    let raw = Params::<f32>::new(params);
    let rgb = |i: usize| raw.rgb(at + 1 + 3 * i);
    let (model, a, b) = match raw.choice(at) {
        0 => (0.0, rgb(0), rgb(1)),
        1 => (1.0, rgb(2), rgb(3)),
        _ => match FresnelModel::artistic(rgb(4), rgb(5)) {
            FresnelModel::Conductor { eta, k } => (1.0, eta, k),
            FresnelModel::Schlick { f0, f90 } => (0.0, f0, f90),
        },
    };
    out[0] = model;
    out[1..4].copy_from_slice(&a.to_array());
    out[4..7].copy_from_slice(&b.to_array());
}

/// Read the decoded Fresnel group at decoded block offset `at`.
#[inline(always)]
pub fn read<L: Lane>(decoded: &Params<'_, L>, at: usize) -> FresnelModel<L> {
    let (a, b) = (decoded.rgb(at + 1), decoded.rgb(at + 4));
    match decoded.choice(at) {
        0 => FresnelModel::Schlick { f0: a, f90: b },
        _ => FresnelModel::Conductor { eta: a, k: b },
    }
}

/// Values of the decoded conductor nodes ([`decode_nodes`]).
pub const NODES_LEN: usize = FresnelNodes::<f32>::LEN;

/// After a decoded Fresnel group `fresnel` ([`decode`]), the albedo's
/// [`FresnelNodes`] of a conductor ([`NODES_LEN`] values; zeros for Schlick, which
/// needs none).
pub fn decode_nodes(fresnel: &[f32], out: &mut [f32]) {
    match read(&Params::<f32>::new(fresnel), 0) {
        FresnelModel::Conductor { eta, k } => {
            let mut curve = [[0.0; kernels::CURVE_LEN]; 3];
            kernels::conductor_curve(Kernels::best(), eta.to_array(), k.to_array(), &mut curve);
            FresnelNodes::from_curve(curve).to_values(out);
        }
        FresnelModel::Schlick { .. } => out[..NODES_LEN].fill(0.0),
    }
}

/// The conductor nodes at decoded offset `at` when `fresnel` is a conductor and the
/// block holds them (blocks staged for eval and sample stop before them).
#[inline(always)]
pub fn read_nodes<L: Lane>(
    decoded: &Params<'_, L>,
    at: usize,
    fresnel: &FresnelModel<L>,
) -> Option<FresnelNodes<L>> {
    if !matches!(fresnel, FresnelModel::Conductor { .. }) || !decoded.holds(at + NODES_LEN) {
        return None;
    }
    let mut nodes = FresnelNodes {
        f0: decoded.rgb(at),
        departures: [Rgb::splat(L::zero()); FRESNEL_NODES],
    };
    for (j, d) in nodes.departures.iter_mut().enumerate() {
        *d = decoded.rgb(at + 3 * (j + 1));
    }
    Some(nodes)
}
