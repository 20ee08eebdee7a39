//! Test plumbing shared by the integration tests: lobe lookup, parameter blocks built
//! by parameter name from each lobe's schema, one-lobe closures, SoA rows for the batch
//! calls, the eval of a closure on every kernel set, a deterministic random generator
//! and tolerance checks. No expected value is computed here (see `tests/reference`).
#![allow(dead_code)]

use glint::Closure;
use glint::batch::{self, BatchInput, EvalOutput, Exec, Soa3, Soa3Mut, Threads};
use glint::lobes::{LobeType, Transport};
use glint::math::{Frame, Vec3};
use glint::params::{ParamKind, ParamSpec, block_size, offset_of, write_defaults};
use glint::registry::{BUILTINS, Registry};
use glint::simd::Kernels;

/// The built-in lobe type named `name`.
pub fn lobe(name: &str) -> &'static dyn LobeType {
    let registry = Registry::with_builtins();
    let id = registry.find(name).expect("built-in lobe");
    BUILTINS[id as usize]
}

/// A lobe's parameter block, starting from the schema's defaults and edited by name.
#[derive(Clone, Debug)]
pub struct Block {
    specs: &'static [ParamSpec],
    pub values: Vec<f32>,
}

impl Block {
    pub fn defaults(lobe: &'static dyn LobeType) -> Block {
        let specs = lobe.params();
        let mut values = vec![0.0; block_size(specs)];
        write_defaults(specs, &mut values);
        Block { specs, values }
    }

    fn index(&self, name: &str) -> usize {
        self.specs
            .iter()
            .position(|s| s.name == name)
            .unwrap_or_else(|| panic!("no parameter named {name}"))
    }

    /// Whether the schema has a parameter `name`.
    pub fn has(&self, name: &str) -> bool {
        self.specs.iter().any(|s| s.name == name)
    }

    /// Offset of parameter `name` in the block.
    pub fn offset(&self, name: &str) -> usize {
        offset_of(self.specs, self.index(name))
    }

    pub fn float(mut self, name: &str, v: f32) -> Block {
        let i = self.index(name);
        assert_eq!(
            self.specs[i].kind,
            ParamKind::Float,
            "{name} is not a float"
        );
        let at = offset_of(self.specs, i);
        self.values[at] = v;
        self
    }

    pub fn rgb(mut self, name: &str, v: [f32; 3]) -> Block {
        let i = self.index(name);
        assert_eq!(self.specs[i].kind, ParamKind::Rgb, "{name} is not an rgb");
        let at = offset_of(self.specs, i);
        self.values[at..at + 3].copy_from_slice(&v);
        self
    }

    pub fn choice(mut self, name: &str, choice: &str) -> Block {
        let i = self.index(name);
        let index = self.specs[i]
            .choices()
            .iter()
            .position(|c| *c == choice)
            .unwrap_or_else(|| panic!("{name} has no choice {choice}"));
        let at = offset_of(self.specs, i);
        self.values[at] = index as f32;
        self
    }

    /// The values of parameter `name` (1 or 3 slots).
    pub fn get(&self, name: &str) -> &[f32] {
        let i = self.index(name);
        let at = offset_of(self.specs, i);
        &self.values[at..at + self.specs[i].kind.size()]
    }

    pub fn as_slice(&self) -> &[f32] {
        &self.values
    }
}

/// A finished radiance closure of one lobe of weight 1 in `frame`.
pub fn closure(name: &str, block: &Block, frame: Frame) -> Closure {
    let registry = Registry::with_builtins();
    let mut c = Closure::new(None, Transport::Radiance);
    let id = registry.find(name).expect("built-in lobe");
    c.add_lobe(&registry, id, [1.0; 3], frame, Some(block.as_slice()))
        .expect("valid parameters");
    c.finish().expect("a new closure finishes");
    c
}

/// SoA rows (x, y, z) of `v`.
pub fn rows(v: &[Vec3<f32>]) -> [Vec<f32>; 3] {
    [
        v.iter().map(|a| a.x).collect(),
        v.iter().map(|a| a.y).collect(),
        v.iter().map(|a| a.z).collect(),
    ]
}

pub fn soa(r: &[Vec<f32>; 3]) -> Soa3<'_> {
    Soa3 {
        x: &r[0],
        y: &r[1],
        z: &r[2],
    }
}

pub fn soa_mut(r: &mut [Vec<f32>; 3]) -> Soa3Mut<'_> {
    let [x, y, z] = r;
    Soa3Mut { x, y, z }
}

/// SplitMix64: a small deterministic generator for sample points.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 24 random bits (exactly representable in f32).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn u3(&mut self) -> [f32; 3] {
        [self.f32(), self.f32(), self.f32()]
    }
}

/// `n` pairs `(wo, wi)` of unit directions above the surface, nearly opposite and
/// grazing: `wo = (x, y, z)` at height `z` from 1e-4 down to 1e-22 (log-uniform, so
/// `|wo + wi|^2` reaches the subnormals), `|y| <= z` and `x` (1 in f32) its unit
/// length; `wi = (-x, dy - y, t z)` with `|dy| <= 2 z`, `t` in [0.05, 1]: `wo + wi =
/// (0, dy, (1 + t) z)` up to an ulp of each component, a half vector from the normal
/// to 62 degrees. Half the pairs swap `x` and `y`. Both are unit to f32 precision.
pub fn opposite_grazing_pairs(rng: &mut Rng, n: usize) -> Vec<(Vec3<f32>, Vec3<f32>)> {
    (0..n)
        .map(|_| {
            let z = 10f64.powf(-4.0 - 18.0 * rng.f64());
            let (y, dy) = (z * (2.0 * rng.f64() - 1.0), z * (4.0 * rng.f64() - 2.0));
            let x = (1.0 - y * y - z * z).sqrt();
            let t = 0.05 + 0.95 * rng.f64();
            let (wo, wi) = ([x, y, z], [-x, dy - y, t * z]);
            let swap = rng.f64() < 0.5;
            let v = |w: [f64; 3]| {
                let (a, b) = if swap { (w[1], w[0]) } else { (w[0], w[1]) };
                Vec3::new(a as f32, b as f32, w[2] as f32)
            };
            (v(wo), v(wi))
        })
        .collect()
}

/// `|actual - expected| <= rel |expected| + abs`.
pub fn close(actual: f64, expected: f64, rel: f64, abs: f64) -> bool {
    (actual - expected).abs() <= rel * expected.abs() + abs
}

/// Assert [`close`], naming `what` and both values.
#[track_caller]
pub fn assert_close(actual: f64, expected: f64, rel: f64, abs: f64, what: &str) {
    assert!(
        close(actual, expected, rel, abs),
        "{what}: actual {actual:.9e}, expected {expected:.9e} (rel err {:.3e}, tol rel {rel:.1e} + abs {abs:.1e})",
        (actual - expected).abs() / expected.abs().max(1e-300)
    );
}

/// Assert [`close`] channel by channel.
#[track_caller]
pub fn assert_close3(actual: [f32; 3], expected: [f64; 3], rel: f64, abs: f64, what: &str) {
    for c in 0..3 {
        assert_close(
            f64::from(actual[c]),
            expected[c],
            rel,
            abs,
            &format!("{what} [channel {c}]"),
        );
    }
}

/// Each source's `(value, pdf)` per lane, named by the source.
pub type EvalsBySource = Vec<(String, Vec<([f32; 3], f32)>)>;

/// `(value, pdf)` of `c` at every pair: the scalar closure call first (on the
/// directions normalized as the C entry points and the batches normalize them:
/// normalizing a unit f32 vector again can move it by an ulp), then one batch per
/// kernel set this CPU has.
pub fn eval_on_every_kernel_set(c: &Closure, wo: &[Vec3<f32>], wi: &[Vec3<f32>]) -> EvalsBySource {
    let unit = |v: Vec3<f32>| Vec3::try_unit(v.x, v.y, v.z, "w").unwrap();
    let scalar = wo
        .iter()
        .zip(wi)
        .map(|(&o, &i)| {
            let e = c.eval(unit(o), unit(i)).unwrap();
            (e.value.to_array(), e.pdf)
        })
        .collect();
    let mut out = vec![("scalar call".to_string(), scalar)];
    let (o, i) = (rows(wo), rows(wi));
    let n = wo.len();
    for kernels in Kernels::available() {
        let exec = Exec {
            kernels,
            threads: Threads::Caller,
        };
        let input = BatchInput {
            count: n,
            closures: c,
            active: None,
            wo: soa(&o),
        };
        let mut value = [vec![-7.0; n], vec![-7.0; n], vec![-7.0; n]];
        let mut pdf = vec![-7.0; n];
        batch::eval(
            &exec,
            &input,
            soa(&i),
            EvalOutput {
                value: soa_mut(&mut value),
                pdf: &mut pdf,
                pdf_reverse: None,
            },
        )
        .unwrap();
        let lanes = (0..n)
            .map(|k| ([value[0][k], value[1][k], value[2][k]], pdf[k]))
            .collect();
        out.push((format!("{:?} batch", kernels.isa()), lanes));
    }
    out
}

/// Every output of the four batch calls for `n` lanes, as SoA rows.
#[derive(PartialEq, Debug)]
pub struct Outputs {
    pub value: [Vec<f32>; 3],
    pub pdf: Vec<f32>,
    pub pdf_reverse: Vec<f32>,
    pub pdf_only: Vec<f32>,
    pub albedo: [Vec<f32>; 3],
    pub s_wi: [Vec<f32>; 3],
    pub s_weight: [Vec<f32>; 3],
    pub s_value: [Vec<f32>; 3],
    pub s_pdf: Vec<f32>,
    pub s_flags: Vec<u32>,
    pub s_lobe: Vec<u32>,
    pub s_eta: Vec<f32>,
    pub s_roughness: Vec<f32>,
}

impl Outputs {
    /// Every float output `value` and every integer output `code` (a sentinel shows
    /// the lanes a call left untouched).
    pub fn filled(n: usize, value: f32, code: u32) -> Outputs {
        let rows = || [vec![value; n], vec![value; n], vec![value; n]];
        Outputs {
            value: rows(),
            pdf: vec![value; n],
            pdf_reverse: vec![value; n],
            pdf_only: vec![value; n],
            albedo: rows(),
            s_wi: rows(),
            s_weight: rows(),
            s_value: rows(),
            s_pdf: vec![value; n],
            s_flags: vec![code; n],
            s_lobe: vec![code; n],
            s_eta: vec![value; n],
            s_roughness: vec![value; n],
        }
    }
}

/// The schema index of material parameter `name`.
pub fn param_index(material: &glint::materials::Material, name: &str) -> u32 {
    let specs = material.kind().params();
    specs
        .iter()
        .position(|s| s.name == name)
        .expect("a parameter of the material") as u32
}

/// A material batch's eval (value rows, pdf) of `input`'s lanes at `wi` on `kernels`.
pub fn material_eval(
    kernels: Kernels,
    input: &batch::material::MaterialInput<'_>,
    wi: Soa3<'_>,
) -> ([Vec<f32>; 3], Vec<f32>) {
    let n = input.count;
    let exec = Exec {
        kernels,
        threads: Threads::Caller,
    };
    let mut value = [vec![0.0f32; n], vec![0.0; n], vec![0.0; n]];
    let mut pdf = vec![0.0f32; n];
    let out = EvalOutput {
        value: soa_mut(&mut value),
        pdf: &mut pdf,
        pdf_reverse: None,
    };
    batch::material::eval(&exec, input, wi, out).expect("a valid batch");
    (value, pdf)
}
