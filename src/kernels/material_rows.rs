//! The rows of a material batch (`crate::batch::material`) around its lobe kernels,
//! one register of lanes at a time: shading frames from normals, one register's
//! pruning and selection probabilities from each slot's `weight * albedo`, and the
//! slot each sample chooses. Each repeats, per lane, the scalar closure's operations
//! in the same order (`Frame::new`, `Material::emit`, `closure::selection`,
//! `mixture::choose`), so the rows hold the bits a closure per lane would.

use super::mixture::clamp_random;
use super::store_frame;
use crate::materials::MAX_SLOTS;
use crate::math::frame::duff_axes;
use crate::math::{Lane, LaneFrame, Mask, Rgb, Vec3};
use crate::simd::kernel;

/// `frame` (nine rows of `len`: t, b, n, each x, y, z) from unit normals (`Frame::new`
/// without a tangent).
#[inline(always)]
fn frames_body<L: Lane>(normal: [&[f32]; 3], frame: &mut [f32]) {
    let len = normal[0].len();
    debug_assert!(len.is_multiple_of(L::LANES) && frame.len() >= 9 * len);
    for i in (0..len).step_by(L::LANES) {
        let n = Vec3::new(
            L::load(&normal[0][i..]),
            L::load(&normal[1][i..]),
            L::load(&normal[2][i..]),
        );
        let (t, b) = duff_axes(n);
        store_frame(&LaneFrame::new(t, b, n), frame, len, i);
    }
}

/// One register's pruning and selection over a material's first `count` slots, by
/// the closure's rules (`Material::emit`, `closure::selection`) with the same
/// operations in the same order, so the same probabilities: `share[k]` is slot `k`'s
/// `luminance(weight * albedo estimate(wo))` (0 where it is not emitted, that is where
/// no weight channel is > 0). Returns each slot's selection probability (0 where it is
/// dropped) and zeroes the weights of dropped slots.
#[inline(always)]
pub fn select<L: Lane>(
    count: usize,
    prune: f32,
    share: &[L; MAX_SLOTS],
    weight: &mut [Rgb<L>; MAX_SLOTS],
) -> [L; MAX_SLOTS] {
    let (zero, one) = (L::zero(), L::one());
    let mut keep = [zero; MAX_SLOTS];
    // `Material::emit`: an emitted slot is kept unless its share is below `prune`.
    let mut emitted = [L::Mask::splat(false); MAX_SLOTS];
    let mut kept = zero;
    for k in 0..count {
        emitted[k] = weight[k].any_positive();
        keep[k] = L::select(emitted[k] & share[k].ge(L::splat(prune)), one, zero);
        kept += keep[k];
    }
    // The first strongest pruned slot is kept where every slot is pruned (rare: the
    // search only runs in registers with such a lane).
    let none = kept.eq(zero);
    if none.any() {
        let mut strongest = L::splat(-1.0);
        let mut strongest_share = L::splat(f32::NEG_INFINITY);
        for k in 0..count {
            let stronger = emitted[k] & keep[k].eq(zero) & share[k].gt(strongest_share);
            strongest_share = L::select(stronger, share[k], strongest_share);
            strongest = L::select(stronger, L::splat(k as f32), strongest);
        }
        for (k, p) in keep[..count].iter_mut().enumerate() {
            let fallback = none & strongest.eq(L::splat(k as f32));
            *p = L::select(fallback, one, *p);
        }
    }
    // `closure::selection` of the kept slots: 1 for a single one, else their shares,
    // or their weights' luminances, or ones, whichever first sums above 0.
    let (mut n, mut share_sum) = (zero, zero);
    for k in 0..count {
        n += keep[k];
        share_sum += keep[k] * share[k].max(zero);
    }
    let by_share = share_sum.gt(zero);
    let mut by = [zero; MAX_SLOTS];
    if by_share.all() {
        for k in 0..count {
            by[k] = share[k].max(zero);
        }
    } else {
        let mut weight_sum = zero;
        for k in 0..count {
            weight_sum += keep[k] * weight[k].luminance().max(zero);
        }
        for k in 0..count {
            by[k] = L::select(
                by_share,
                share[k].max(zero),
                L::select(weight_sum.gt(zero), weight[k].luminance().max(zero), one),
            );
        }
    }
    let mut total = zero;
    for k in 0..count {
        keep[k] *= L::select(n.eq(one), one, by[k]);
        total += keep[k];
    }
    // `normalize_shares`: times the reciprocal of the sum in slot order, or where that
    // is not finite divided by the largest, then by the sum. A lane without any
    // emitted slot keeps zeros.
    let inv = one / total;
    let direct = total.is_finite() & inv.is_finite();
    if direct.all() {
        for p in &mut keep[..count] {
            *p *= inv;
        }
    } else {
        let mut largest = zero;
        for p in &keep[..count] {
            largest = largest.max(*p);
        }
        let largest = L::select(largest.gt(zero), largest, one);
        let mut scaled_total = zero;
        let mut scaled = keep;
        for p in &mut scaled[..count] {
            *p = *p / largest;
            scaled_total += *p;
        }
        let scaled_total = L::select(scaled_total.gt(zero), scaled_total, one);
        for (p, s) in keep[..count].iter_mut().zip(scaled) {
            *p = L::select(direct, *p * inv, s / scaled_total);
        }
    }
    for (p, w) in keep[..count].iter().zip(weight.iter_mut()) {
        *w = Rgb::select(p.gt(zero), *w, Rgb::zero());
    }
    keep
}

/// The slot each lane's `u` chooses by its probabilities, and `u` rescaled within
/// the slot's bin.
pub struct ChooseJob<'a> {
    pub len: usize,
    pub count: usize,
    /// Rows as [`super::expand::ExpandJob::probability`].
    pub probability: &'a [f32],
    /// In: the lanes' `u_lobe`; out: `u` rescaled for the chosen slot.
    pub u: &'a mut [f32],
    /// The chosen slot (as a float index).
    pub chosen: &'a mut [f32],
}

/// `mixture::choose` with a probability row per lane ([`choose_register`]).
#[inline(always)]
fn choose_body<L: Lane>(job: &mut ChooseJob<'_>) {
    let len = job.len;
    for i in (0..len).step_by(L::LANES) {
        let mut probability = [L::zero(); MAX_SLOTS];
        for (k, p) in probability[..job.count].iter_mut().enumerate() {
            *p = L::load(&job.probability[k * len + i..]);
        }
        let (chosen, reused) = choose_register(&probability[..job.count], L::load(&job.u[i..]));
        chosen.store(&mut job.chosen[i..]);
        reused.store(&mut job.u[i..]);
    }
}

/// `mixture::choose` with each lane's own slot probabilities: the slot `x` chooses
/// and `x` rescaled within its bin, by the same bins and round-off rule; a lane
/// without any slot to choose gets slot 0 and 0.5 (as the scalar loop it replaces).
#[inline(always)]
pub fn choose_register<L: Lane>(probability: &[L], x: L) -> (L, L) {
    // A NaN `u` clamps to 0, as `f32::max` takes it.
    let u = clamp_random(L::select(x.ge(L::zero()), x, L::zero()));
    let mut found = L::Mask::splat(false);
    let mut any = L::Mask::splat(false);
    let (mut index, mut start, mut width) = (L::zero(), L::zero(), L::zero());
    let (mut last, mut p_last) = (L::zero(), L::zero());
    let mut end = L::zero();
    for (k, &p) in probability.iter().enumerate() {
        let bin_start = end;
        end += p;
        let positive = p.gt(L::zero());
        let hit = positive & !found & u.lt(end);
        let slot = L::splat(k as f32);
        index = L::select(hit, slot, index);
        start = L::select(hit, bin_start, start);
        width = L::select(hit, p, width);
        found = found | hit;
        last = L::select(positive, slot, last);
        p_last = L::select(positive, p, p_last);
        any = any | positive;
    }
    index = L::select(found, index, last);
    start = L::select(found, start, L::one() - p_last);
    width = L::select(found, width, p_last);
    let reused = clamp_random((u - start) / width);
    (
        L::select(any, index, L::zero()),
        L::select(any, reused, L::splat(0.5)),
    )
}

/// The chosen slot's selection probability times its own sample's pdf, in place in
/// `own_pdf` (in: the sample's pdf).
#[inline(always)]
fn chosen_pdf_body<L: Lane>(
    probability: &[f32],
    count: usize,
    chosen: &[f32],
    own_pdf: &mut [f32],
) {
    let len = chosen.len();
    for i in (0..len).step_by(L::LANES) {
        let k = L::load(&chosen[i..]);
        let mut p = L::zero();
        for slot in 0..count {
            let row = L::load(&probability[slot * len + i..]);
            p = L::select(k.eq(L::splat(slot as f32)), row, p);
        }
        (p * L::load(&own_pdf[i..])).store(&mut own_pdf[i..]);
    }
}

kernel!(
    /// Frames from unit normal rows (`frames_body`).
    frames<>(normal: [&[f32]; 3], frame: &mut [f32]) => frames_body
);
kernel!(
    /// Each lane's slot choice (`choose_body`).
    choose<>(job: &mut ChooseJob<'_>) => choose_body
);
kernel!(
    /// `p_k pdf_k` of each lane's chosen slot (`chosen_pdf_body`).
    chosen_pdf<>(probability: &[f32], count: usize, chosen: &[f32], own_pdf: &mut [f32]) => chosen_pdf_body
);

#[cfg(test)]
mod tests {
    use super::*;

    /// `select` over one lane is `Material::emit`'s pruning and `closure::select`, bit
    /// for bit, on shares and weights that take each of its branches: kept and pruned
    /// slots, every slot pruned (the first strongest kept), kept shares summing to 0
    /// (by the weights' luminances, or uniform), huge shares (normalized through the
    /// largest), slots without a weight.
    #[test]
    fn select_is_the_closure_rule() {
        let shares = [0.0, -0.0, 1e-4, 1e-3, 0.3, 1.0, 2.5, 3e38, f32::MAX];
        let channels = [0.0, 0.5, 1.0, 1e30];
        let mut state = 0x9e37_79b9_u32;
        let mut pick = move |n: usize| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as usize % n
        };
        for case in 0..200_000 {
            let count = 1 + pick(MAX_SLOTS.min(5));
            let prune = [0.0, 1e-3, 0.2][pick(3)];
            let mut share = [0.0f32; MAX_SLOTS];
            let mut weight = [Rgb::zero(); MAX_SLOTS];
            for k in 0..count {
                share[k] = shares[pick(shares.len())];
                let c = [0; 3].map(|_| channels[pick(channels.len())]);
                weight[k] = Rgb::new(c[0], c[1], c[2]);
            }
            // The closure's rule over the emitted slots.
            let (mut kept, mut kept_shares, mut strongest) = (vec![], vec![], None);
            for k in 0..count {
                if !weight[k].any_positive() {
                    continue;
                }
                if share[k] < prune {
                    if strongest.is_none_or(|(s, _)| share[k] > s) {
                        strongest = Some((share[k], k));
                    }
                    continue;
                }
                kept.push(k);
                kept_shares.push(share[k]);
            }
            if let (true, Some((s, k))) = (kept.is_empty(), strongest) {
                kept.push(k);
                kept_shares.push(s);
            }
            if !kept.is_empty() {
                crate::closure::select(&mut kept_shares, |j| weight[kept[j]].luminance());
            }
            let mut want = [0.0f32; MAX_SLOTS];
            for (&k, &p) in kept.iter().zip(&kept_shares) {
                want[k] = p;
            }
            let mut got_weight = weight;
            let got = select::<f32>(count, prune, &share, &mut got_weight);
            assert_eq!(
                got.map(f32::to_bits),
                want.map(f32::to_bits),
                "case {case}: shares {:?}, weights {:?}, prune {prune}: {got:?} vs {want:?}",
                &share[..count],
                &weight[..count]
            );
            for k in 0..count {
                let w = if want[k] > 0.0 {
                    weight[k]
                } else {
                    Rgb::zero()
                };
                assert_eq!(got_weight[k], w, "case {case}: weight {k}");
            }
        }
    }
}
