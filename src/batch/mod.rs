//! Batch evaluation over SoA arrays. The arguments are shaped for the SIMD
//! kernels (separate x/y/z arrays, an optional active mask, one closure or one
//! per lane); this version runs each active lane through the scalar path.
//!
//! Lanes whose inputs are invalid (NaN, infinite or zero-length directions) get
//! zeroed outputs, the other lanes are still computed, and the call reports the
//! first bad lane. Inactive lanes are not read or written.

use crate::closure::{Closure, EvalResult, SampleResult};
use crate::error::{Error, Status};
use crate::math::{Rgb, Vec3};

/// Where each lane's closure comes from.
pub trait ClosureSource<'a> {
    fn closure(&self, lane: usize) -> Result<&'a Closure, Error>;
}

/// One closure shared by every lane.
impl<'a> ClosureSource<'a> for &'a Closure {
    fn closure(&self, _lane: usize) -> Result<&'a Closure, Error> {
        Ok(self)
    }
}

/// One closure per lane.
impl<'a> ClosureSource<'a> for &'a [&'a Closure] {
    fn closure(&self, lane: usize) -> Result<&'a Closure, Error> {
        Ok(self[lane])
    }
}

/// Three SoA component arrays.
#[derive(Clone, Copy)]
pub struct Soa3<'a> {
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
}

impl Soa3<'_> {
    fn unit(&self, lane: usize, what: &str) -> Result<Vec3<f32>, Error> {
        Vec3::try_unit(self.x[lane], self.y[lane], self.z[lane], what)
    }
}

/// Mutable SoA component arrays.
pub struct Soa3Mut<'a> {
    pub x: &'a mut [f32],
    pub y: &'a mut [f32],
    pub z: &'a mut [f32],
}

impl Soa3Mut<'_> {
    fn set(&mut self, lane: usize, v: [f32; 3]) {
        self.x[lane] = v[0];
        self.y[lane] = v[1];
        self.z[lane] = v[2];
    }
}

/// Shared inputs of every batch call.
pub struct BatchInput<'a, C> {
    pub count: usize,
    pub closures: C,
    /// Nonzero = active; `None` = all lanes active.
    pub active: Option<&'a [u8]>,
    pub wo: Soa3<'a>,
}

impl<'a, C: ClosureSource<'a>> BatchInput<'a, C> {
    /// For every active lane, `compute` its result and hand it to `write`
    /// (`None` for a lane that failed). The first failure is returned after all
    /// lanes ran.
    fn for_each_lane<T>(
        &self,
        compute: impl Fn(usize, &'a Closure, Vec3<f32>) -> Result<T, Error>,
        mut write: impl FnMut(usize, Option<T>),
    ) -> Result<(), Error> {
        let mut first_error: Option<Error> = None;
        for i in 0..self.count {
            if self.active.is_some_and(|a| a[i] == 0) {
                continue;
            }
            let result = self
                .closures
                .closure(i)
                .and_then(|c| compute(i, c, self.wo.unit(i, "wo")?));
            match result {
                Ok(r) => write(i, Some(r)),
                Err(e) => {
                    write(i, None);
                    if first_error.is_none() {
                        first_error =
                            Some(Error::new(e.status, format!("lane {i}: {}", e.message)));
                    }
                }
            }
        }
        first_error.map_or(Ok(()), Err)
    }
}

/// Outputs of [`eval`].
pub struct EvalOutput<'a> {
    pub value: Soa3Mut<'a>,
    pub pdf: &'a mut [f32],
    pub pdf_reverse: Option<&'a mut [f32]>,
}

/// `eval` on every active lane.
pub fn eval<'a, C: ClosureSource<'a>>(
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    mut out: EvalOutput<'_>,
) -> Result<(), Error> {
    input.for_each_lane(
        |i, closure, wo| closure.eval(wo, wi.unit(i, "wi")?),
        |i, r| {
            let r = r.unwrap_or(EvalResult {
                value: Rgb::zero(),
                pdf: 0.0,
                pdf_reverse: 0.0,
            });
            out.value.set(i, r.value.to_array());
            out.pdf[i] = r.pdf;
            if let Some(rev) = out.pdf_reverse.as_deref_mut() {
                rev[i] = r.pdf_reverse;
            }
        },
    )
}

/// `pdf` on every active lane.
pub fn pdf<'a, C: ClosureSource<'a>>(
    input: &BatchInput<'a, C>,
    wi: Soa3<'_>,
    out: &mut [f32],
) -> Result<(), Error> {
    input.for_each_lane(
        |i, closure, wo| closure.pdf(wo, wi.unit(i, "wi")?),
        |i, p| out[i] = p.unwrap_or(0.0),
    )
}

/// Random numbers of [`sample`], one array per dimension.
#[derive(Clone, Copy)]
pub struct SampleRandoms<'a> {
    pub u_lobe: &'a [f32],
    pub u0: &'a [f32],
    pub u1: &'a [f32],
}

/// Outputs of [`sample`]; the optional ones are skipped when `None`.
pub struct SampleOutput<'a> {
    pub wi: Soa3Mut<'a>,
    pub pdf: &'a mut [f32],
    pub weight: Soa3Mut<'a>,
    pub value: Option<Soa3Mut<'a>>,
    pub flags: Option<&'a mut [u32]>,
    pub lobe: Option<&'a mut [u32]>,
    pub eta: Option<&'a mut [f32]>,
    pub roughness: Option<&'a mut [f32]>,
}

impl SampleOutput<'_> {
    fn write(&mut self, i: usize, s: &SampleResult) {
        self.wi.set(i, [s.wi.x, s.wi.y, s.wi.z]);
        self.pdf[i] = s.pdf;
        self.weight.set(i, s.weight.to_array());
        if let Some(v) = self.value.as_mut() {
            v.set(i, s.value.to_array());
        }
        if let Some(f) = self.flags.as_deref_mut() {
            f[i] = s.flags;
        }
        if let Some(l) = self.lobe.as_deref_mut() {
            l[i] = s.lobe;
        }
        if let Some(e) = self.eta.as_deref_mut() {
            e[i] = s.eta;
        }
        if let Some(r) = self.roughness.as_deref_mut() {
            r[i] = s.roughness;
        }
    }
}

/// A failed sample as the batch reports it: every output zero, `eta` 1.
const FAILED: SampleResult = SampleResult {
    wi: Vec3 {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    },
    value: Rgb {
        r: 0.0,
        g: 0.0,
        b: 0.0,
    },
    pdf: 0.0,
    weight: Rgb {
        r: 0.0,
        g: 0.0,
        b: 0.0,
    },
    flags: 0,
    lobe: 0,
    eta: 1.0,
    roughness: 0.0,
};

/// `sample` on every active lane. A lane that cannot scatter is not an error: it
/// gets `pdf = 0` and zero weight, as `glint_sample` returns `GLINT_NO_SAMPLE`.
pub fn sample<'a, C: ClosureSource<'a>>(
    input: &BatchInput<'a, C>,
    u: SampleRandoms<'_>,
    mut out: SampleOutput<'_>,
) -> Result<(), Error> {
    input.for_each_lane(
        |i, closure, wo| match closure.sample(wo, [u.u_lobe[i], u.u0[i], u.u1[i]]) {
            Err(e) if e.status == Status::NoSample => Ok(FAILED),
            r => r,
        },
        |i, s| out.write(i, &s.unwrap_or(FAILED)),
    )
}
