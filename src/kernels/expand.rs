//! A material's `expand` over staged lanes: the per-lane parameter blocks (overrides
//! applied) and `wo` in each lane's shading frame in, each slot's weight and lobe block
//! out, one register of lanes at a time ([`MaterialModel::expand`] is written once
//! over the lane type).

use crate::lobes::Params;
use crate::materials::compiled::MAX_MATERIAL_PARAMS;
use crate::materials::{Context, Expansion, MAX_SLOT_PARAMS, MAX_SLOTS, MaterialModel, SlotModels};
use crate::math::{Lane, Rgb, Vec3};
use crate::simd::kernel;

/// Inputs and outputs of an expansion over `len` staged lanes (a multiple of
/// [`super::LANE_MULTIPLE`]).
pub struct ExpandJob<'a> {
    pub len: usize,
    /// The material's blocks: value `p` of lane `j` at `p * len + j`.
    pub params: &'a [f32],
    pub param_count: usize,
    /// Unit `wo` in each lane's shading frame.
    pub wo: [&'a [f32]; 3],
    /// Values of each slot's lobe block (the rest of its rows are not written).
    pub block_len: [usize; MAX_SLOTS],
    /// Slot `k`'s weight, channel `c` of lane `j` at `(3 k + c) len + j`.
    pub weight: &'a mut [f32],
    /// Slot `k`'s block, value `p` of lane `j` at `(k MAX_SLOT_PARAMS + p) len + j`.
    pub blocks: &'a mut [f32],
}

#[inline(always)]
fn expand_body<M: MaterialModel, L: Lane>(job: &mut ExpandJob<'_>) {
    let len = job.len;
    debug_assert!(len.is_multiple_of(L::LANES) && job.param_count <= MAX_MATERIAL_PARAMS);
    let slots = M::Slots::NAMES.len();
    let mut raw = [L::zero(); MAX_MATERIAL_PARAMS];
    let zero = Vec3::new(L::zero(), L::zero(), L::zero());
    let mut e = Expansion::<L>::default();
    for i in (0..len).step_by(L::LANES) {
        for (p, r) in raw[..job.param_count].iter_mut().enumerate() {
            *r = L::load(&job.params[p * len + i..]);
        }
        // Material batches take no positions, footprints or uvs: zero, as a context
        // that leaves them unset.
        let ctx = Context {
            wo: Vec3::new(
                L::load(&job.wo[0][i..]),
                L::load(&job.wo[1][i..]),
                L::load(&job.wo[2][i..]),
            ),
            position: zero,
            reference_position: zero,
            footprint: L::zero(),
            uv: [L::zero(); 2],
        };
        // What is read back starts at zero for each register, as a fresh `Expansion`
        // would (zeroing all of it costs more than the expansion).
        for k in 0..slots {
            e.weight[k] = Rgb::zero();
            for v in &mut e.params[k][..job.block_len[k]] {
                *v = L::zero();
            }
        }
        M::expand(Params::new(&raw[..job.param_count]), &ctx, &mut e);
        for k in 0..slots {
            let Rgb { r, g, b } = e.weight[k];
            r.store(&mut job.weight[3 * k * len + i..]);
            g.store(&mut job.weight[(3 * k + 1) * len + i..]);
            b.store(&mut job.weight[(3 * k + 2) * len + i..]);
            for (p, v) in e.params[k][..job.block_len[k]].iter().enumerate() {
                v.store(&mut job.blocks[(k * MAX_SLOT_PARAMS + p) * len + i..]);
            }
        }
    }
}

kernel!(
    /// `M::expand` over a job's lanes.
    expand<M: MaterialModel>(job: &mut ExpandJob<'_>) => expand_body
);
