//! The closure mixture over lanes, written once: the scalar calls (`Closure`) use
//! its `f32` instance, the batch kernels its vector instances.
//!
//! A closure samples lobe `k` with probability `p_k` ([`choose`]); the sample's value
//! is the sum over lobes of `weight * f |cos|` at the sampled direction and its pdf
//! the mixture `sum p_j pdf_j` (in the batch kernels, the closure's eval there to the
//! bit: every lobe evaluated and summed as an eval sums them), except for delta
//! events, which carry the chosen lobe's own value and `p_k` times the event's
//! discrete probability. [`finish`]
//! turns that into the sample a caller receives: `weight = value / pdf`, and a lane
//! whose pdf or weight is not a positive finite number fails, reading all zero
//! (`eta` 1).

use crate::lobes::{Sample, flags};
use crate::math::lane::MAX_LANES;
use crate::math::{Lane, Mask, Rgb, Vec3};

/// The largest `f32` below 1, so that `u < 1` for every sample dimension.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A random number clamped into [0, 1), as every sampling routine expects.
#[inline(always)]
pub fn clamp_random<L: Lane>(u: L) -> L {
    u.max(L::zero()).min(L::splat(ONE_MINUS_EPSILON))
}

/// The lobe `u` selects among lobes chosen with `probabilities` (summing to 1), as
/// an index per lane, and `u` rescaled to [0, 1) within the lobe's bin for reuse as
/// the lobe's own discrete choice; `None` when no lobe can be chosen.
#[inline(always)]
pub fn choose<L: Lane>(probabilities: &[f32], u: L) -> Option<(L, L)> {
    let last = probabilities.iter().rposition(|&p| p > 0.0)?;
    let u = clamp_random(u);
    let mut found = L::Mask::splat(false);
    let (mut index, mut start, mut width) = (L::zero(), L::zero(), L::zero());
    let mut end = 0.0f32;
    for (k, &p) in probabilities.iter().enumerate() {
        let bin_start = end;
        end += p;
        if p > 0.0 {
            let hit = !found & u.lt(L::splat(end));
            index = L::select(hit, L::splat(k as f32), index);
            start = L::select(hit, L::splat(bin_start), start);
            width = L::select(hit, L::splat(p), width);
            found = found | hit;
        }
    }
    // Round-off left `u` past the last bin: the last lobe that can be chosen.
    let p_last = probabilities[last];
    index = L::select(found, index, L::splat(last as f32));
    start = L::select(found, start, L::splat(1.0 - p_last));
    width = L::select(found, width, L::splat(p_last));
    Some((index, clamp_random((u - start) / width)))
}

/// The closure's value and pdf at a sample of a lobe chosen with probability `p`,
/// whose own value and pdf are `own`: delta events carry the lobe's own value and `p`
/// times its discrete probability (no other lobe has them); other events the
/// mixture's value and pdf at the sampled direction, `mixture()` (run only when some
/// lane needs it).
#[inline(always)]
pub fn sampled<L: Lane>(
    delta: L::Mask,
    own: (Rgb<L>, L),
    p: L,
    mixture: impl FnOnce() -> (Rgb<L>, L),
) -> (Rgb<L>, L) {
    let own = (own.0, p * own.1);
    if delta.all() {
        return own;
    }
    let (value, pdf) = mixture();
    (
        Rgb::select(delta, own.0, value),
        L::select(delta, own.1, pdf),
    )
}

/// A closure's sample as the caller receives it; failed lanes hold zeros (`eta` 1).
#[derive(Clone, Copy, Debug)]
pub struct ClosureSample<L: Lane> {
    pub wi: Vec3<L>,
    pub value: Rgb<L>,
    pub pdf: L,
    pub weight: Rgb<L>,
    pub ok: L::Mask,
    pub transmitted: L::Mask,
    pub delta: L::Mask,
    pub eta: L,
    pub roughness: L,
    /// The chosen lobe's sample class (`flags::DIFFUSE`, `GLOSSY`, `SPECULAR`) and
    /// component ([`Sample`]); 0 on failed lanes.
    pub class: L,
    pub component: L,
}

/// The closure's sample from the chosen lobe's sample `s` (world-space `wi`) and the
/// mixture's `value` and `pdf` there. The weight is `value / pdf`, one division per
/// channel (never `value * (1 / pdf)`, which overflows for denormal pdfs).
#[inline(always)]
pub fn finish<L: Lane>(s: &Sample<L>, value: Rgb<L>, pdf: L) -> ClosureSample<L> {
    let weight = value.map(
        #[inline(always)]
        |v| v / pdf,
    );
    let ok = s.valid
        & pdf.gt(L::zero())
        & pdf.is_finite()
        & weight.r.is_finite()
        & weight.g.is_finite()
        & weight.b.is_finite();
    let zero = L::zero();
    ClosureSample {
        wi: Vec3::select(ok, s.wi, Vec3::new(zero, zero, zero)),
        value: Rgb::select(ok, value, Rgb::zero()),
        pdf: L::select(ok, pdf, zero),
        weight: Rgb::select(ok, weight, Rgb::zero()),
        ok,
        transmitted: s.transmitted & ok,
        delta: s.delta & ok,
        eta: L::select(ok, s.eta, L::one()),
        roughness: L::select(ok, s.roughness, zero),
        class: L::select(ok, s.class, zero),
        component: L::select(ok, s.component, zero),
    }
}

/// The `GLINT_FLAG_*` bits of each lane of `c`: reflection or transmission, and the
/// sample's class; 0 for failed lanes.
#[inline(always)]
pub fn flags<L: Lane>(c: &ClosureSample<L>) -> [u32; MAX_LANES] {
    // In float lanes: the side bits (1, 2) and the class bits (4, 8, 16) are disjoint,
    // so their sum is their union, and every value is exact.
    let side = L::select(
        c.transmitted,
        L::splat(flags::TRANSMISSION as f32),
        L::splat(flags::REFLECTION as f32),
    );
    let mut lanes = [0.0f32; MAX_LANES];
    L::select(c.ok, side + c.class, L::zero()).store(&mut lanes);
    lanes.map(|f| f as u32)
}

/// The component of each lane of `c` (0 for failed lanes).
#[inline(always)]
pub fn components<L: Lane>(c: &ClosureSample<L>) -> [u32; MAX_LANES] {
    let mut lanes = [0.0f32; MAX_LANES];
    c.component.store(&mut lanes);
    lanes.map(|k| k as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(valid: bool) -> Sample<f32> {
        Sample {
            wi: Vec3::new(0.0, 0.0, 1.0),
            value: Rgb::zero(),
            pdf: 1.0,
            valid,
            transmitted: true,
            delta: false,
            eta: 1.5,
            roughness: 0.3,
            class: flags::GLOSSY as f32,
            component: 1.0,
        }
    }

    #[test]
    fn weights_divide_and_non_finite_weights_fail() {
        let v = Rgb::new(3e-45, 0.0, 6e-45);
        let c = finish(&sample(true), v, 3e-45);
        assert!(c.ok);
        assert_eq!(c.weight.to_array(), [1.0, 0.0, 2.0]);
        for (value, pdf) in [
            (Rgb::new(1e30, 0.0, 0.0), 1e-30),
            (v, 0.0),
            (v, f32::INFINITY),
            (v, f32::NAN),
        ] {
            let c = finish(&sample(true), value, pdf);
            assert!(!c.ok, "{value:?} / {pdf}");
            assert_eq!((c.pdf, c.eta, c.roughness), (0.0, 1.0, 0.0));
            assert_eq!((flags(&c)[0], components(&c)[0]), (0, 0));
        }
        let c = finish(&sample(false), v, 1.0);
        assert!(!c.ok && c.weight.to_array() == [0.0; 3]);
    }

    #[test]
    fn flags_name_the_side_and_the_sample_class() {
        let c = finish(&sample(true), Rgb::splat(0.5), 1.0);
        assert_eq!(flags(&c)[0], flags::TRANSMISSION | flags::GLOSSY);
        assert_eq!(components(&c)[0], 1);
        let delta = Sample {
            delta: true,
            transmitted: false,
            class: flags::SPECULAR as f32,
            component: 0.0,
            ..sample(true)
        };
        let c = finish(&delta, Rgb::splat(0.5), 1.0);
        assert_eq!(flags(&c)[0], flags::REFLECTION | flags::SPECULAR);
        assert_eq!(components(&c)[0], 0);
    }

    #[test]
    fn lobe_choice_rescales_within_the_bin_and_skips_empty_lobes() {
        let p = [0.25, 0.0, 0.75];
        assert_eq!(choose(&p, 0.1f32), Some((0.0, 0.4)));
        assert_eq!(choose(&p, 0.25f32), Some((2.0, 0.0)));
        assert_eq!(choose(&p, 2.0f32).map(|c| c.0), Some(2.0));
        assert_eq!(choose(&p, -1.0f32), Some((0.0, 0.0)));
        assert_eq!(choose(&[0.0, 0.0], 0.5f32), None);
        // Round-off: probabilities summing below 1 leave u past the last bin.
        let short = [0.5, 0.499_999];
        let (k, reused) = choose(&short, 0.999_999_9f32).unwrap();
        assert_eq!(k, 1.0);
        assert!((0.0..1.0).contains(&reused));
    }
}
