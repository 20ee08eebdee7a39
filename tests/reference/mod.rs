//! Independent f64 evaluations of the published formulas the lobes implement. Nothing
//! here calls the library's own math (`glint::fresnel`, `glint::microfacet`,
//! `glint::albedo_table`): the tests compare the library's f32 results against these.
//!
//! Sources:
//! - GGX / Trowbridge-Reitz and Beckmann NDFs, anisotropic, Smith `Lambda` and the
//!   height-correlated `G2 = 1 / (1 + Lambda(wo) + Lambda(wi))`: Heitz 2014,
//!   "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (eqs. 72,
//!   86, 99), with the Burley 2012 anisotropy mapping `alpha_x = r^2 / aspect`,
//!   `alpha_y = r^2 aspect`, `aspect = sqrt(1 - 0.9 anisotropic)`.
//! - Cook-Torrance reflection `f = D G2 F / (4 cos_o cos_i)` (Walter et al. 2007 eq. 20)
//!   and the visible-normal pdf `G1(wo) D(h) / (4 cos_o)` (Heitz 2018 eq. 17).
//! - Walter et al. 2007 rough transmission (eq. 21) and its Jacobian (eq. 17).
//! - Dielectric Fresnel in Walter 2007's (Cook-Torrance 1982) `g`-form (eq. 22); conductor
//!   Fresnel from the complex amplitude reflectances `r_s`, `r_p` (complex arithmetic);
//!   Schlick 1994; Gulbrandsen 2014 (JCGT 3(4)).
#![allow(dead_code)]

use glint::math::Vec3;
use std::f64::consts::PI;
use std::ops::{Add, Div, Mul, Neg, Sub};

// ---------------------------------------------------------------------------------
// Vectors

/// A 3-vector in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl V {
    pub const fn new(x: f64, y: f64, z: f64) -> V {
        V { x, y, z }
    }
    /// The exact f64 value of an f32 vector.
    pub fn from32(v: Vec3<f32>) -> V {
        V::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
    }
    pub fn to32(self) -> Vec3<f32> {
        Vec3::new(self.x as f32, self.y as f32, self.z as f32)
    }
    pub fn dot(self, o: V) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    pub fn cross(self, o: V) -> V {
        V::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    pub fn length(self) -> f64 {
        self.dot(self).sqrt()
    }
    pub fn normalize(self) -> V {
        self * (1.0 / self.length())
    }
    /// Mirror about the unit vector `n`: `2 (w.n) n - w`.
    pub fn reflect(self, n: V) -> V {
        n * (2.0 * self.dot(n)) - self
    }
}

impl Add for V {
    type Output = V;
    fn add(self, o: V) -> V {
        V::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl Sub for V {
    type Output = V;
    fn sub(self, o: V) -> V {
        V::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<f64> for V {
    type Output = V;
    fn mul(self, s: f64) -> V {
        V::new(self.x * s, self.y * s, self.z * s)
    }
}
impl Neg for V {
    type Output = V;
    fn neg(self) -> V {
        V::new(-self.x, -self.y, -self.z)
    }
}

/// The unit direction at polar angle `theta_deg` from +z and azimuth `phi_deg`.
pub fn dir(theta_deg: f64, phi_deg: f64) -> V {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    V::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// [`dir`] rounded to f32, and that f32 vector's exact f64 value: the library and the
/// reference see exactly the same numbers.
pub fn dir32(theta_deg: f64, phi_deg: f64) -> (Vec3<f32>, V) {
    let v = dir(theta_deg, phi_deg).to32();
    (v, V::from32(v))
}

// ---------------------------------------------------------------------------------
// Complex numbers (for the conductor Fresnel equations)

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C {
    pub re: f64,
    pub im: f64,
}

impl C {
    pub const fn new(re: f64, im: f64) -> C {
        C { re, im }
    }
    pub const fn real(re: f64) -> C {
        C { re, im: 0.0 }
    }
    pub fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    /// Principal square root (branch cut on the negative real axis, result `re >= 0`).
    pub fn sqrt(self) -> C {
        let r = self.norm_sqr().sqrt();
        let re = (0.5 * (r + self.re)).max(0.0).sqrt();
        let im = (0.5 * (r - self.re)).max(0.0).sqrt();
        C::new(re, if self.im < 0.0 { -im } else { im })
    }
}

impl Add for C {
    type Output = C;
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
}
impl Sub for C {
    type Output = C;
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
}
impl Mul for C {
    type Output = C;
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}
impl Div for C {
    type Output = C;
    fn div(self, o: C) -> C {
        let d = o.norm_sqr();
        C::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}

// ---------------------------------------------------------------------------------
// Fresnel

/// Schlick 1994: `f0 + (f90 - f0) (1 - cos)^5`.
pub fn schlick(f0: f64, f90: f64, cos: f64) -> f64 {
    f0 + (f90 - f0) * (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

/// Unpolarized reflectance from a medium of index 1 onto one of complex index `eta`
/// (absorbing when `im > 0`), at incidence cosine `cos` in [0, 1]:
/// `r_s = (cos - eta cos_t) / (cos + eta cos_t)`, `r_p = (eta cos - cos_t) / (eta cos + cos_t)`,
/// `cos_t = sqrt(1 - sin^2 / eta^2)` (complex), `F = (|r_s|^2 + |r_p|^2) / 2`.
/// For a real `eta < 1` past the critical angle `cos_t` is imaginary and `F = 1`.
pub fn fresnel_complex(cos: f64, eta: C) -> f64 {
    let c = C::real(cos);
    let sin2 = C::real(1.0 - cos * cos);
    let cos_t = (C::real(1.0) - sin2 / (eta * eta)).sqrt();
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    0.5 * (rs.norm_sqr() + rp.norm_sqr())
}

/// Exact conductor reflectance for the complex IOR `n + i k`.
pub fn fresnel_conductor(cos: f64, n: f64, k: f64) -> f64 {
    fresnel_complex(cos, C::new(n, k))
}

/// Exact dielectric reflectance at incidence cosine `cos >= 0` onto relative IOR `eta`
/// (transmitted side over incident side), in the form of Walter 2007 eq. 22
/// (Cook and Torrance 1982): `g = sqrt(eta^2 - 1 + c^2)`,
/// `F = (g - c)^2 / (2 (g + c)^2) (1 + ((c (g + c) - 1) / (c (g - c) + 1))^2)`;
/// `g^2 < 0` is total internal reflection, `F = 1`.
pub fn fresnel_dielectric_rel(cos: f64, eta: f64) -> f64 {
    let c = cos.abs();
    let g2 = eta * eta - 1.0 + c * c;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - c) / (g + c);
    let b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    0.5 * a * a * (1.0 + b * b)
}

/// Dielectric reflectance for an interface with IOR `eta` inside over outside, where
/// `cos_signed < 0` means the light arrives from inside.
pub fn fresnel_dielectric(cos_signed: f64, eta: f64) -> f64 {
    if cos_signed >= 0.0 {
        fresnel_dielectric_rel(cos_signed, eta)
    } else {
        fresnel_dielectric_rel(-cos_signed, 1.0 / eta)
    }
}

/// Gulbrandsen 2014: reflectivity `r` and edge tint `g` to the complex IOR `(n, k)`.
pub fn gulbrandsen(r: f64, g: f64) -> (f64, f64) {
    let n_min = (1.0 - r) / (1.0 + r);
    let n_max = (1.0 + r.sqrt()) / (1.0 - r.sqrt());
    let n = g * n_min + (1.0 - g) * n_max;
    let k2 = (r * (n + 1.0).powi(2) - (n - 1.0).powi(2)) / (1.0 - r);
    (n, k2.max(0.0).sqrt())
}

/// A per-channel Fresnel model.
#[derive(Clone, Copy, Debug)]
pub enum Fresnel {
    Schlick { f0: [f64; 3], f90: [f64; 3] },
    Conductor { n: [f64; 3], k: [f64; 3] },
}

impl Fresnel {
    pub fn schlick(f0: [f32; 3], f90: [f32; 3]) -> Fresnel {
        Fresnel::Schlick {
            f0: f0.map(f64::from),
            f90: f90.map(f64::from),
        }
    }
    pub fn conductor(n: [f32; 3], k: [f32; 3]) -> Fresnel {
        Fresnel::Conductor {
            n: n.map(f64::from),
            k: k.map(f64::from),
        }
    }
    /// Gulbrandsen's reflectivity and edge tint resolved to a complex IOR per channel.
    pub fn artistic(r: [f32; 3], g: [f32; 3]) -> Fresnel {
        let mut n = [0.0; 3];
        let mut k = [0.0; 3];
        for c in 0..3 {
            (n[c], k[c]) = gulbrandsen(f64::from(r[c]), f64::from(g[c]));
        }
        Fresnel::Conductor { n, k }
    }
    pub fn eval(&self, cos: f64) -> [f64; 3] {
        match self {
            Fresnel::Schlick { f0, f90 } => [0, 1, 2].map(|c| schlick(f0[c], f90[c], cos)),
            Fresnel::Conductor { n, k } => [0, 1, 2].map(|c| fresnel_conductor(cos, n[c], k[c])),
        }
    }
}

// ---------------------------------------------------------------------------------
// Special functions

/// `erfc(x)` in f64 to ~1e-15 relative: for `x < 2.5` through
/// `erf(x) = 2/sqrt(pi) exp(-x^2) sum_n 2^n x^(2n+1) / (1 3 5 ... (2n+1))` (positive
/// terms, no cancellation), beyond it the continued fraction
/// `erfc(x) = exp(-x^2)/sqrt(pi) / (x + (1/2)/(x + 1/(x + (3/2)/(x + ...))))`.
pub fn erfc(x: f64) -> f64 {
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    let x2 = x * x;
    if x < 2.5 {
        let (mut term, mut sum) = (x, x);
        let mut n = 0.0;
        while term > 1e-18 * sum {
            n += 1.0;
            term *= 2.0 * x2 / (2.0 * n + 1.0);
            sum += term;
        }
        1.0 - 2.0 / PI.sqrt() * (-x2).exp() * sum
    } else {
        let mut t = x;
        // 50 levels: converged to f64 precision for x >= 2.5 (checked against 400).
        for k in (1..=50).rev() {
            t = x + 0.5 * f64::from(k) / t;
        }
        (-x2).exp() / PI.sqrt() / t
    }
}

// ---------------------------------------------------------------------------------
// Microfacet distributions

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ndf {
    Ggx,
    Beckmann,
}

impl Ndf {
    pub fn name(self) -> &'static str {
        match self {
            Ndf::Ggx => "ggx",
            Ndf::Beckmann => "beckmann",
        }
    }
}

/// An anisotropic microfacet distribution.
#[derive(Clone, Copy, Debug)]
pub struct Micro {
    pub ndf: Ndf,
    pub ax: f64,
    pub ay: f64,
}

impl Micro {
    /// `alpha = roughness^2`, Burley's aspect, floored at the documented `1e-4`.
    pub fn from_roughness(ndf: Ndf, roughness: f32, anisotropic: f32) -> Micro {
        let alpha = f64::from(roughness).powi(2);
        let aspect = (1.0 - 0.9 * f64::from(anisotropic)).sqrt();
        Micro {
            ndf,
            ax: (alpha / aspect).max(1e-4),
            ay: (alpha * aspect).max(1e-4),
        }
    }

    pub fn isotropic(ndf: Ndf, alpha: f64) -> Micro {
        Micro {
            ndf,
            ax: alpha,
            ay: alpha,
        }
    }

    /// `D(m)`, 0 below the surface.
    pub fn d(&self, m: V) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (ax, ay) = (self.ax, self.ay);
        let c2 = m.z * m.z;
        match self.ndf {
            // 1 / (pi ax ay ((x/ax)^2 + (y/ay)^2 + z^2)^2)
            Ndf::Ggx => {
                let t = (m.x / ax).powi(2) + (m.y / ay).powi(2) + c2;
                1.0 / (PI * ax * ay * t * t)
            }
            // exp(-tan^2 (cos^2 phi / ax^2 + sin^2 phi / ay^2)) / (pi ax ay cos^4)
            Ndf::Beckmann => {
                let e = ((m.x / ax).powi(2) + (m.y / ay).powi(2)) / c2;
                (-e).exp() / (PI * ax * ay * c2 * c2)
            }
        }
    }

    /// Smith `Lambda(w)` with the projected roughness `alpha_w` along `w`'s azimuth.
    pub fn lambda(&self, w: V) -> f64 {
        let proj2 = (self.ax * w.x).powi(2) + (self.ay * w.y).powi(2);
        if proj2 == 0.0 {
            return 0.0;
        }
        match self.ndf {
            Ndf::Ggx => 0.5 * (-1.0 + (1.0 + proj2 / (w.z * w.z)).sqrt()),
            Ndf::Beckmann => {
                let a = w.z.abs() / proj2.sqrt();
                0.5 * ((-a * a).exp() / (a * PI.sqrt()) - erfc(a))
            }
        }
    }

    pub fn g1(&self, w: V) -> f64 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing.
    pub fn g2(&self, wo: V, wi: V) -> f64 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of normals visible from `w` (either side): `G1(w) |w.m| D(m) / |w.z|`.
    pub fn pdf_visible(&self, w: V, m: V) -> f64 {
        self.g1(w) * w.dot(m).abs() * self.d(m) / w.z.abs()
    }
}

// ---------------------------------------------------------------------------------
// Lobe models

/// Cook-Torrance reflection: `(f |cos_i|, pdf)` per channel with
/// `f = D(h) G2 F(wo.h) / (4 cos_o cos_i)` and the visible-normal pdf
/// `G1(wo) D(h) / (4 cos_o)`. One-sided.
pub fn cook_torrance(m: &Micro, fresnel: &Fresnel, wo: V, wi: V) -> ([f64; 3], f64) {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return ([0.0; 3], 0.0);
    }
    let h = (wo + wi).normalize();
    let d = m.d(h);
    let g2 = m.g2(wo, wi);
    let f = fresnel.eval(wo.dot(h));
    let brdf = |fc: f64| d * g2 * fc / (4.0 * wo.z * wi.z);
    (
        [brdf(f[0]) * wi.z, brdf(f[1]) * wi.z, brdf(f[2]) * wi.z],
        m.g1(wo) * d / (4.0 * wo.z),
    )
}

/// Walter et al. 2007 for an interface with IOR `eta` inside (z < 0) over outside:
/// `(f |cos_i|, pdf)`. Reflection `F D G2 / (4 |cos_o cos_i|)`; transmission
/// `|wi.h| |wo.h| / (|cos_i| |cos_o|) n^2 (1 - F) D G2 / (n_i wi.h + n_o wo.h)^2` with
/// `n_o`, `n_i` the indices on `wo`'s and `wi`'s sides and `n = n_o` for radiance (Walter's
/// form) or `n = n_i` for importance (the adjoint). `F` is the exact Fresnel of
/// `|wo.h|` from `wo`'s side. `G2` is the height-correlated `1 / (1 + Lambda_o + Lambda_i)`
/// on both sides, as in pbrt-v4 (Heitz 2014's exact height-correlated form for
/// transmission is a Beta function; the library documents the former). The pdf picks
/// reflection with probability `F` and samples visible normals: `F G1 D / (4 |cos_o|)` and
/// `(1 - F) G1 D |wo.h| / |cos_o| n_i^2 |wi.h| / (n_i wi.h + n_o wo.h)^2`.
pub fn walter(m: &Micro, eta: f64, wo: V, wi: V, importance: bool) -> (f64, f64) {
    let (co, ci) = (wo.z, wi.z);
    if co == 0.0 || ci == 0.0 {
        return (0.0, 0.0);
    }
    let n_o = if co > 0.0 { 1.0 } else { eta };
    if co * ci > 0.0 {
        let mut h = (wo + wi).normalize();
        if h.z < 0.0 {
            h = -h;
        }
        if wo.dot(h) * co <= 0.0 || wi.dot(h) * ci <= 0.0 {
            return (0.0, 0.0);
        }
        let n_other = if co > 0.0 { eta } else { 1.0 };
        let f = fresnel_dielectric_rel(wo.dot(h).abs(), n_other / n_o);
        let (d, g2, g1) = (m.d(h), m.g2(wo, wi), m.g1(wo));
        (f * d * g2 / (4.0 * co.abs()), f * g1 * d / (4.0 * co.abs()))
    } else {
        let n_i = if ci > 0.0 { 1.0 } else { eta };
        let mut h = -(wi * n_i + wo * n_o).normalize();
        if h.z < 0.0 {
            h = -h;
        }
        let (oh, ih) = (wo.dot(h), wi.dot(h));
        if oh * co <= 0.0 || ih * ci <= 0.0 {
            return (0.0, 0.0);
        }
        let f = fresnel_dielectric_rel(oh.abs(), n_i / n_o);
        let (d, g2) = (m.d(h), m.g2(wo, wi));
        let denom = (n_i * ih + n_o * oh).powi(2);
        let n = if importance { n_i } else { n_o };
        let value = (ih * oh).abs() * n * n * (1.0 - f) * d * g2 / (co.abs() * denom);
        let pdf = (1.0 - f) * m.pdf_visible(wo, h) * n_i * n_i * ih.abs() / denom;
        (value, pdf)
    }
}

/// Snell refraction of `w` through the plane of unit normal `n` (either side) with IOR
/// `eta` on the side `n` does not point to, over the side it points to. Returns the
/// refracted direction and the relative IOR `eta'` (transmitted over incident), or
/// `None` under total internal reflection.
pub fn refract(w: V, n: V, eta: f64) -> Option<(V, f64)> {
    let c = w.dot(n);
    let (n, eta, c) = if c < 0.0 {
        (-n, 1.0 / eta, -c)
    } else {
        (n, eta, c)
    };
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // Tangential part scaled by 1/eta, normal part -cos_t.
    let tangential = (w - n * c) * (-1.0 / eta);
    Some((tangential - n * cos_t, eta))
}

// ---------------------------------------------------------------------------------
// Quadrature

/// Gauss-Legendre nodes and weights of order `n` on `[lo, hi]` (Newton on the
/// three-term recurrence of the Legendre polynomials).
pub fn gauss_legendre(n: usize, lo: f64, hi: f64) -> Vec<(f64, f64)> {
    (1..=n)
        .map(|i| {
            let mut x = (PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let kf = k as f64;
                    (p0, p1) = (p1, ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            (lo + (hi - lo) * (x + 1.0) / 2.0, w * (hi - lo) / 2.0)
        })
        .collect()
}

/// Gauss-Legendre nodes of order `n` on each piece of `[breaks[0], breaks.last()]`.
pub fn gauss_legendre_pieces(n: usize, breaks: &[f64]) -> Vec<(f64, f64)> {
    breaks
        .windows(2)
        .flat_map(|w| gauss_legendre(n, w[0], w[1]))
        .collect()
}

/// `int f(m) d omega_m` over the upper hemisphere by the midpoint rule in
/// `(w, phi)` with `tan theta = alpha w / (1 - w)`: nodes concentrate where an NDF of
/// roughness `alpha` has its mass, and the map covers theta in [0, pi/2).
pub fn integrate_normals(
    alpha: f64,
    n_w: usize,
    n_phi: usize,
    mut f: impl FnMut(V) -> [f64; 3],
) -> [f64; 3] {
    let mut sum = [0.0; 3];
    let dphi = 2.0 * PI / n_phi as f64;
    for i in 0..n_w {
        let w = (i as f64 + 0.5) / n_w as f64;
        let t = w / (1.0 - w);
        let theta = (alpha * t).atan();
        // d theta / d w = alpha / (1 + alpha^2 t^2) / (1 - w)^2
        let jac = alpha / (1.0 + alpha * alpha * t * t) / ((1.0 - w) * (1.0 - w));
        let (s, c) = theta.sin_cos();
        let weight = s * jac / n_w as f64 * dphi;
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * dphi;
            let v = f(V::new(s * phi.cos(), s * phi.sin(), c));
            for k in 0..3 {
                sum[k] += v[k] * weight;
            }
        }
    }
    sum
}

/// Directional albedo of [`cook_torrance`]: `int f |cos_i| d omega_i`, written over
/// microfacet normals (`d omega_i = 4 |wo.m| d omega_m`):
/// `int F(wo.m) D(m) G2(wo, wi) (wo.m) / cos_o d omega_m` over `wo.m > 0`, `wi.z > 0`.
pub fn cook_torrance_albedo(m: &Micro, fresnel: &Fresnel, wo: V, n: usize) -> [f64; 3] {
    let alpha = (m.ax * m.ay).sqrt();
    let lambda_o = m.lambda(wo);
    integrate_normals(alpha, n, n, |h| {
        let oh = wo.dot(h);
        let wi = wo.reflect(h);
        if oh <= 0.0 || wi.z <= 0.0 {
            return [0.0; 3];
        }
        let g2 = 1.0 / (1.0 + lambda_o + m.lambda(wi));
        let s = m.d(h) * g2 * oh / wo.z;
        fresnel.eval(oh).map(|f| f * s)
    })
}

/// Directional albedo of [`walter`] split into `(reflected, transmitted)`: the integral
/// of `f |cos_i|` over each hemisphere of `wi`, written over microfacet normals `m`
/// (upper hemisphere, facing `wo`: `(wo.m) cos_o > 0`). With the Jacobians
/// `d omega_i = 4 |wo.m| d omega_m` (reflection) and
/// `d omega_i = (n_i wi.m + n_o wo.m)^2 / (n_i^2 |wi.m|) d omega_m` (refraction) this is
/// `int D |wo.m| / |cos_o| [F G2(wo, w_r) + (n / n_i)^2 (1 - F) G2(wo, w_t)] d omega_m`,
/// `n = n_o` (radiance) or `n_i` (importance), each term only where its `wi` lands on the
/// proper side.
pub fn walter_albedo(m: &Micro, eta: f64, wo: V, importance: bool, n: usize) -> (f64, f64) {
    let co = wo.z;
    let n_o = if co > 0.0 { 1.0 } else { eta };
    let n_i = if co > 0.0 { eta } else { 1.0 };
    let scale = if importance { 1.0 } else { (n_o / n_i).powi(2) };
    let alpha = (m.ax * m.ay).sqrt();
    let lambda_o = m.lambda(wo);
    let [r, t, _] = integrate_normals(alpha, n, n, |h| {
        let oh = wo.dot(h);
        if oh * co <= 0.0 {
            return [0.0; 3];
        }
        let base = m.d(h) * oh.abs() / co.abs();
        let f = fresnel_dielectric_rel(oh.abs(), n_i / n_o);
        let wr = wo.reflect(h);
        let refl = if wr.z * co > 0.0 {
            f * base / (1.0 + lambda_o + m.lambda(wr))
        } else {
            0.0
        };
        let trans = match refract(wo, h, eta) {
            Some((wt, _)) if wt.z * co < 0.0 && f < 1.0 => {
                scale * (1.0 - f) * base / (1.0 + lambda_o + m.lambda(wt))
            }
            _ => 0.0,
        };
        [refl, trans, 0.0]
    });
    (r, t)
}

/// `int f(l) cos_l d(omega_l)` over the upper hemisphere for a lobe peaked around the
/// mirror direction of `v`, integrated over half vectors in slope space stretched by
/// `(ax, ay)`: `h = normalize(-sx, -sy, 1)`, `(sx, sy) = rho (ax cos psi, ay sin psi)`,
/// `rho = x / (1 - x)`, `d(omega_l) = 4 |v.h| d(omega_h)`, `d(omega_h) = dsx dsy /
/// (1 + s^2)^(3/2)`: a microfacet lobe of roughness about `(ax, ay)` is smooth in
/// `(x, psi)`, so a midpoint rule of `n x n` points resolves it (independent of the
/// samplers under test). `f` takes `(l, v)` in the local frame.
#[allow(dead_code)]
pub fn slope_space_albedo(
    ax: f64,
    ay: f64,
    v: [f64; 3],
    n: usize,
    f: impl Fn([f64; 3], [f64; 3]) -> f64,
) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let x = (i as f64 + 0.5) / n as f64;
        let rho = x / (1.0 - x);
        let drho = 1.0 / ((1.0 - x) * (1.0 - x));
        for j in 0..n {
            let psi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
            let (sx, sy) = (rho * ax * psi.cos(), rho * ay * psi.sin());
            let s2 = sx * sx + sy * sy;
            let norm = (1.0 + s2).sqrt();
            let h = [-sx / norm, -sy / norm, 1.0 / norm];
            let vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            if vh <= 0.0 {
                continue;
            }
            let l = [0, 1, 2].map(|k| 2.0 * vh * h[k] - v[k]);
            if l[2] <= 0.0 {
                continue;
            }
            let jacobian = ax * ay * rho * drho / (1.0 + s2).powf(1.5);
            sum += f(l, v) * l[2] * 4.0 * vh * jacobian;
        }
    }
    sum * (1.0 / n as f64) * (2.0 * std::f64::consts::PI / n as f64)
}
