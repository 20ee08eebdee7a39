//! Grouping and staging for the batch kernels: which lanes run together, and the
//! padded SoA arrays they read and write. All buffers live in a per-thread
//! [`Scratch`] that only grows, so steady-state batch calls do not allocate; every
//! growth is reserved with `try_reserve`, so a shortage of memory is an error
//! (`Status::OutOfMemory`), never an abort.

use super::{BatchInput, ClosureSource, Soa3};
use crate::closure::{Closure, ONE_MINUS_EPSILON, check_randoms};
use crate::error::{Error, Status};
use crate::kernels::{LANE_MULTIPLE, LobeLanes, normalize};
use crate::math::Vec3;
use crate::simd::Kernels;
use std::cell::RefCell;
use std::collections::HashMap;
use std::ops::Range;

/// Lanes of one block whose closures have one shape (and, when sampling, chose
/// the same lobe).
pub(super) struct Group {
    /// A lane whose closure represents the shape.
    pub rep: usize,
    /// That closure's address, to tell whether all lanes share it.
    closure: usize,
    /// Whether every lane has the representative's closure.
    pub uniform: bool,
    /// The chosen lobe (sampling only).
    pub lobe: usize,
    /// Global lane indices, ascending.
    pub lanes: Vec<u32>,
}

/// Groups of a block, the lanes that failed before grouping, and the first error.
#[derive(Default)]
pub(super) struct Groups {
    list: Vec<Group>,
    used: usize,
    /// Lanes that get zero outputs without being computed.
    pub failed: Vec<u32>,
    pub error: LaneError,
    /// Per block-local lane: the lobe-choice number rescaled for the chosen lobe.
    pub u_reused: Vec<f32>,
    /// Group by (shape id, chosen lobe), for the groups created this block.
    index: HashMap<(u64, usize), usize>,
}

/// The error of a block's lowest failing lane.
#[derive(Default)]
pub(super) struct LaneError(Option<(usize, Error)>);

impl LaneError {
    /// Record a lane's failure; the lowest lane's first error is kept.
    pub fn fail(&mut self, lane: usize, e: Error) {
        if self.0.as_ref().is_none_or(|(l, _)| lane < *l) {
            self.0 = Some((lane, e));
        }
    }

    /// The failing lane kept, if any.
    pub fn lane(&self) -> Option<usize> {
        self.0.as_ref().map(|&(lane, _)| lane)
    }

    /// The error, prefixed with its lane's index.
    pub fn take(&mut self) -> Option<Error> {
        self.0
            .take()
            .map(|(lane, e)| Error::new(e.status, format!("lane {lane}: {}", e.message)))
    }
}

/// The random numbers of a sampling call.
#[derive(Clone, Copy)]
pub(super) struct Randoms<'a> {
    pub u: [&'a [f32]; 3],
}

impl Groups {
    pub fn groups(&self) -> &[Group] {
        &self.list[..self.used]
    }

    pub fn list_mut(&mut self) -> &mut [Group] {
        &mut self.list[..self.used]
    }

    /// Record a lane's failure; the lowest lane's error is reported.
    pub fn fail(&mut self, lane: usize, e: Error) {
        self.error.fail(lane, e);
    }

    /// The error of the lowest failing lane, prefixed with its index.
    pub fn take_error(&mut self) -> Option<Error> {
        self.error.take()
    }

    /// Group the active lanes of `range`. With `randoms`, each lane also chooses its
    /// lobe (as `Closure::sample` does); lanes with nothing to choose fail silently.
    /// Fails only when memory is short.
    pub fn build<'a, C: ClosureSource<'a>>(
        &mut self,
        input: &BatchInput<'a, C>,
        range: Range<usize>,
        randoms: Option<Randoms<'_>>,
    ) -> Result<(), Error> {
        self.used = 0;
        self.index.clear();
        self.failed.clear();
        self.error = LaneError::default();
        self.u_reused.clear();
        reserve(&mut self.failed, range.len())?;
        reserve(&mut self.u_reused, range.len())?;
        self.u_reused.resize(range.len(), 0.0);
        let start = range.start;
        if randoms.is_none() && input.active.is_none() && input.closures.is_shared() {
            // One closure, every lane: one group, no per-lane work.
            match input
                .closures
                .closure(start)
                .and_then(|c| c.check_finished())
            {
                Ok(()) => {
                    let g = self.find_or_add(input, start, 0)?;
                    let lanes = &mut self.list[g].lanes;
                    reserve(lanes, range.len())?;
                    lanes.extend(range.map(|l| l as u32));
                }
                Err(e) => {
                    self.failed.extend(range.map(|l| l as u32));
                    self.fail(start, e);
                }
            }
            return Ok(());
        }
        if let Some(r) = randoms
            && input.active.is_none()
            && input.closures.is_shared()
            && self.single_lobe_fast_path(input, range.clone(), r)?
        {
            return Ok(());
        }
        // A shared closure is resolved and checked once.
        let shared = input.closures.is_shared().then(|| {
            input.closures.closure(start).and_then(|c| {
                c.check_finished()?;
                Ok(c)
            })
        });
        // The previous lane's closure and group: consecutive lanes usually match.
        let mut previous: Option<(*const Closure, usize, usize)> = None;
        for lane in range {
            if !input.is_active(lane) {
                continue;
            }
            let resolved = match &shared {
                Some(c) => c.clone(),
                None => input.closures.closure(lane).and_then(|c| {
                    c.check_finished()?;
                    Ok(c)
                }),
            };
            let closure = match resolved {
                Ok(c) => c,
                Err(e) => {
                    self.failed.push(lane as u32);
                    self.fail(lane, e);
                    continue;
                }
            };
            let lobe = match randoms {
                None => 0,
                Some(r) => {
                    let u = [r.u[0][lane], r.u[1][lane], r.u[2][lane]];
                    let choice = check_randoms(u).map(|()| closure.choose_lobe(u[0]));
                    match choice {
                        Ok(Some((k, u_reused))) => {
                            self.u_reused[lane - start] = u_reused;
                            k
                        }
                        Ok(None) => {
                            self.failed.push(lane as u32);
                            continue;
                        }
                        Err(e) => {
                            self.failed.push(lane as u32);
                            self.fail(lane, e);
                            continue;
                        }
                    }
                }
            };
            let ptr = closure as *const Closure;
            let g = match previous {
                Some((p, k, g)) if p == ptr && k == lobe => g,
                _ => self.find_or_add(input, lane, lobe)?,
            };
            let group = &mut self.list[g];
            let need = group.lanes.len() + 1;
            reserve(&mut group.lanes, need)?;
            group.lanes.push(lane as u32);
            group.uniform &= group.closure == ptr as usize;
            previous = Some((ptr, lobe, g));
        }
        Ok(())
    }

    /// Sampling a shared one-lobe closure with finite random numbers: every lane
    /// takes lobe 0 (as `Closure::choose_lobe` would), without per-lane work.
    fn single_lobe_fast_path<'a, C: ClosureSource<'a>>(
        &mut self,
        input: &BatchInput<'a, C>,
        range: Range<usize>,
        r: Randoms<'_>,
    ) -> Result<bool, Error> {
        let start = range.start;
        let one_lobe = input.closures.closure(start).is_ok_and(|c| {
            c.is_finished() && c.lobes().len() == 1 && c.lobes()[0].probability == 1.0
        });
        let finite = r.u.iter().all(|u| {
            u[range.clone()]
                .iter()
                .fold(true, |ok, x| ok & x.is_finite())
        });
        if !(one_lobe && finite) {
            return Ok(false);
        }
        for (reused, &u) in self.u_reused.iter_mut().zip(&r.u[0][range.clone()]) {
            *reused = u.clamp(0.0, ONE_MINUS_EPSILON);
        }
        let g = self.find_or_add(input, start, 0)?;
        let lanes = &mut self.list[g].lanes;
        reserve(lanes, range.len())?;
        lanes.extend(range.map(|l| l as u32));
        Ok(true)
    }

    /// The group of `lane`'s closure shape and `lobe`, created if new.
    fn find_or_add<'a, C: ClosureSource<'a>>(
        &mut self,
        input: &BatchInput<'a, C>,
        lane: usize,
        lobe: usize,
    ) -> Result<usize, Error> {
        let closure = input.closures.closure(lane).expect("resolved before");
        let rep = |g: usize| {
            input
                .closures
                .closure(self.list[g].rep)
                .expect("resolved before")
        };
        let key = (closure.shape_id(), lobe);
        if let Some(&g) = self.index.get(&key) {
            if closure.same_shape(rep(g)) {
                return Ok(g);
            }
            // Two shapes with one id (a hash collision): search the groups.
            let found =
                (0..self.used).find(|&g| self.list[g].lobe == lobe && closure.same_shape(rep(g)));
            if let Some(g) = found {
                return Ok(g);
            }
        }
        if self.used == self.list.len() {
            reserve(&mut self.list, self.used + 1)?;
            self.list.push(Group {
                rep: 0,
                closure: 0,
                uniform: true,
                lobe: 0,
                lanes: Vec::new(),
            });
        }
        let g = &mut self.list[self.used];
        g.rep = lane;
        g.closure = closure as *const Closure as usize;
        g.uniform = true;
        g.lobe = lobe;
        g.lanes.clear();
        self.used += 1;
        if !self.index.contains_key(&key) {
            self.index.try_reserve(1).map_err(|_| out_of_memory())?;
            self.index.insert(key, self.used - 1);
        }
        Ok(self.used - 1)
    }
}

/// Room for `len` values in `v`, or `Status::OutOfMemory`.
pub(super) fn reserve<T>(v: &mut Vec<T>, len: usize) -> Result<(), Error> {
    match len.checked_sub(v.len()) {
        Some(more) if more > 0 => v.try_reserve(more).map_err(|_| out_of_memory()),
        _ => Ok(()),
    }
}

fn out_of_memory() -> Error {
    Error::new(
        Status::OutOfMemory,
        "out of memory: the batch's staging buffers could not grow",
    )
}

/// Grow `v` to at least `len` values (never shrinks, never zeroes); within what
/// [`Scratch::reset`] reserved, this does not allocate.
pub(super) fn grow<T: Copy + Default>(v: &mut Vec<T>, len: usize) -> &mut [T] {
    if v.len() < len {
        v.resize(len, T::default());
    }
    &mut v[..len]
}

/// `len` values of each of three rows.
pub(super) fn rows3(v: &mut [Vec<f32>; 3], len: usize) -> [&mut [f32]; 3] {
    let [a, b, c] = v;
    [grow(a, len), grow(b, len), grow(c, len)]
}

/// Read-only views of three rows.
pub(super) fn view3(v: &[Vec<f32>; 3], len: usize) -> [&[f32]; 3] {
    [&v[0][..len], &v[1][..len], &v[2][..len]]
}

/// A group's length rounded up to whole registers.
pub(super) fn padded(lanes: usize) -> usize {
    lanes.div_ceil(LANE_MULTIPLE) * LANE_MULTIPLE
}

/// Stage `src` at `lanes` into `rows` (`len` values each), normalized, padding with
/// +z. Lanes with invalid directions are flagged in `failed`, reported to `errors`,
/// and staged as +z; returns whether there were any.
pub(super) fn stage_directions(
    kernels: Kernels,
    src: Soa3<'_>,
    what: &str,
    lanes: &[u32],
    mut rows: [&mut [f32]; 3],
    failed: &mut [u8],
    errors: &mut LaneError,
) -> bool {
    let len = rows[0].len();
    let n = lanes.len();
    let sources = [src.x, src.y, src.z];
    match (lanes.first(), lanes.last()) {
        (Some(&a), Some(&b)) if (b - a) as usize + 1 == n => {
            for (row, src) in rows.iter_mut().zip(sources) {
                row[..n].copy_from_slice(&src[a as usize..=b as usize]);
            }
        }
        _ => {
            for (row, src) in rows.iter_mut().zip(sources) {
                for (r, &lane) in row.iter_mut().zip(lanes) {
                    *r = src[lane as usize];
                }
            }
        }
    }
    for (row, pad) in rows.iter_mut().zip([0.0, 0.0, 1.0]) {
        row[n..].fill(pad);
    }
    if !normalize(kernels, &mut rows, len) {
        return false;
    }
    // Some lane is invalid, or tiny or huge: stage the group as the scalar path does.
    let mut any_failed = false;
    for (j, &lane) in lanes.iter().enumerate() {
        let lane = lane as usize;
        let v = Vec3::try_unit(src.x[lane], src.y[lane], src.z[lane], what).unwrap_or_else(|e| {
            failed[j] = 1;
            any_failed = true;
            errors.fail(lane, e);
            Vec3::new(0.0, 0.0, 1.0)
        });
        rows[0][j] = v.x;
        rows[1][j] = v.y;
        rows[2][j] = v.z;
    }
    any_failed
}

/// Staged per-lane data of one lobe for groups whose lanes have different closures.
#[derive(Default)]
pub(super) struct LobeRows {
    params: Vec<f32>,
    frame: Vec<f32>,
    weight: Vec<f32>,
    probability: Vec<f32>,
}

impl LobeRows {
    /// Lobe `k` of the group's closures, as the kernels read it; per-lane blocks hold
    /// what eval and sample read, or the whole decoded block for `albedo`.
    pub fn lanes<'s, 'a: 's, C: ClosureSource<'a>>(
        &'s mut self,
        input: &BatchInput<'a, C>,
        group: &Group,
        k: usize,
        len: usize,
        albedo: bool,
    ) -> LobeLanes<'s> {
        let closure_of = |lane: usize| input.closures.closure(lane).expect("resolved before");
        let rep = closure_of(group.rep);
        if group.uniform {
            let l = &rep.lobes()[k];
            return LobeLanes::Uniform {
                params: rep.lobe_decoded(k),
                frame: l.frame,
                weight: l.weight,
                probability: l.probability,
            };
        }
        let param_count = if albedo {
            rep.lobe_decoded(k).len()
        } else {
            rep.lobes()[k].lobe.lane_decoded_len()
        };
        let params = grow(&mut self.params, param_count * len);
        let frame = grow(&mut self.frame, 9 * len);
        let weight = grow(&mut self.weight, 3 * len);
        let probability = grow(&mut self.probability, len);
        // Padding lanes repeat the first lane, so they hold valid parameters.
        let lane_at = |j: usize| group.lanes[j.min(group.lanes.len() - 1)] as usize;
        for j in 0..len {
            let c = closure_of(lane_at(j));
            let l = &c.lobes()[k];
            for (p, &v) in c.lobe_decoded(k)[..param_count].iter().enumerate() {
                params[p * len + j] = v;
            }
            let axes = [l.frame.t, l.frame.b, l.frame.n];
            for (a, axis) in axes.iter().enumerate() {
                frame[3 * a * len + j] = axis.x;
                frame[(3 * a + 1) * len + j] = axis.y;
                frame[(3 * a + 2) * len + j] = axis.z;
            }
            for (c, w) in l.weight.to_array().into_iter().enumerate() {
                weight[c * len + j] = w;
            }
            probability[j] = l.probability;
        }
        LobeLanes::PerLane {
            params,
            param_count,
            frame,
            weight,
            probability,
            stride: len,
        }
    }
}

/// Every buffer a block needs.
#[derive(Default)]
pub(super) struct Scratch {
    pub groups: Groups,
    pub lobe: LobeRows,
    pub wo: [Vec<f32>; 3],
    pub wi: [Vec<f32>; 3],
    pub u: [Vec<f32>; 3],
    pub failed: Vec<u8>,
    /// An eval's lanes failed in each direction (`failed` or their `wi`), `len` a
    /// direction.
    pub failed_directions: Vec<u8>,
    /// Whether any lane of the current group is flagged in `failed`.
    pub any_failed: bool,
    /// Accumulated value, pdf and reverse pdf.
    pub value: [Vec<f32>; 3],
    /// A material eval's albedos, taken in its staging pass.
    pub albedo: [Vec<f32>; 3],
    pub pdf: Vec<f32>,
    pub pdf_reverse: Vec<f32>,
    /// The chosen lobe's sample.
    pub sample_value: [Vec<f32>; 3],
    pub sample_pdf: Vec<f32>,
    pub eta: Vec<f32>,
    pub roughness: Vec<f32>,
    /// Packed events, class and component (`kernels::pack_events`).
    pub events: Vec<f32>,
    pub flags: Vec<u32>,
    pub lobe_index: Vec<u32>,
    pub component: Vec<u32>,
    /// The lobe each lane of an in-place mixture sample chose, as a float index.
    pub chosen: Vec<f32>,
    /// A material batch's chunk: its active lanes and its slots' rows.
    pub chunk: Vec<u32>,
    pub material: super::material::SlotRows,
    pub compact: Compact,
    /// Rings to hold a streaming call's outputs back in (`kernels::delay`).
    pub rings: crate::kernels::delay::Rings,
}

/// An in-place mixture sample's chunk in the order of the lobes its lanes chose
/// (`kernels::sort_rows`): the inputs in that order and the closure's outputs before
/// they go back (`kernels::unsort_rows`).
#[derive(Default)]
pub(super) struct Compact {
    pub wo: [Vec<f32>; 3],
    pub u: [Vec<f32>; 3],
    /// `wo` and the sampled `wi` in the frame the closure's lobes share.
    pub wo_local: [Vec<f32>; 3],
    pub wi_local: [Vec<f32>; 3],
    pub wi: [Vec<f32>; 3],
    pub weight: [Vec<f32>; 3],
    pub value: [Vec<f32>; 3],
    pub pdf: Vec<f32>,
    pub eta: Vec<f32>,
    pub roughness: Vec<f32>,
    /// Rows of integers (flags, lobe, component) as the bits of floats, sorted, and
    /// back in lane order.
    pub bits: [Vec<f32>; 3],
    pub unsorted: [Vec<f32>; 3],
}

impl Scratch {
    /// Reserve the rows an in-place chunk of `len` lanes uses.
    pub fn reserve_rows(&mut self, len: usize) -> Result<(), Error> {
        for rows in [
            &mut self.wo,
            &mut self.wi,
            &mut self.u,
            &mut self.value,
            &mut self.sample_value,
            &mut self.compact.wo,
            &mut self.compact.u,
            &mut self.compact.wo_local,
            &mut self.compact.wi_local,
            &mut self.compact.wi,
            &mut self.compact.weight,
            &mut self.compact.value,
            &mut self.compact.bits,
            &mut self.compact.unsorted,
        ] {
            for row in rows {
                reserve(row, len)?;
            }
        }
        for row in [
            &mut self.pdf,
            &mut self.sample_pdf,
            &mut self.eta,
            &mut self.roughness,
            &mut self.chosen,
            &mut self.events,
            &mut self.compact.pdf,
            &mut self.compact.eta,
            &mut self.compact.roughness,
        ] {
            reserve(row, len)?;
        }
        for row in [&mut self.flags, &mut self.lobe_index, &mut self.component] {
            reserve(row, len)?;
        }
        Ok(())
    }

    /// Reserve every buffer a group of `len` lanes of `closure`'s shape needs, then
    /// zero the accumulators and failure flags.
    pub fn reset(&mut self, len: usize, closure: &Closure) -> Result<(), Error> {
        let params = (0..closure.lobes().len())
            .map(|k| closure.lobe_decoded(k).len())
            .max()
            .unwrap_or(0);
        let lobe = &mut self.lobe;
        reserve(&mut lobe.params, params * len)?;
        reserve(&mut lobe.frame, 9 * len)?;
        reserve(&mut lobe.weight, 3 * len)?;
        reserve(&mut lobe.probability, len)?;
        self.reserve_rows(len)?;
        reserve(&mut self.pdf_reverse, len)?;
        reserve(&mut self.failed, len)?;
        reserve(&mut self.flags, len)?;
        reserve(&mut self.lobe_index, len)?;
        reserve(&mut self.component, len)?;
        for row in rows3(&mut self.value, len) {
            row.fill(0.0);
        }
        grow(&mut self.pdf, len).fill(0.0);
        grow(&mut self.pdf_reverse, len).fill(0.0);
        grow(&mut self.failed, len).fill(0);
        self.any_failed = false;
        Ok(())
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Run `f` with this thread's scratch buffers.
pub(super) fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|s| match s.try_borrow_mut() {
        Ok(mut s) => f(&mut s),
        // Reentered (a lobe callback calling the batch API): use fresh buffers.
        Err(_) => f(&mut Scratch::default()),
    })
}
