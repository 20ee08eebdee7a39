//! Shared microfacet physics, open to new normal distributions.
//!
//! - [`Ndf`]: a normal distribution `D(m)` with a sampler and its density; GTR1
//!   ([`Gtr1`], Disney's clearcoat) is only this.
//! - [`SmithNdf`]: an anisotropic distribution with Smith masking, given by its
//!   `Lambda`; the shared terms (G1, height-correlated G2 (Heitz 2014), the pair terms
//!   of an eval, visible-normal densities) are provided methods written once here.
//!   [`Ggx`] (Dupuy and Benyoub 2023 sampling) and [`Beckmann`] (Heitz and d'Eon 2014) implement it.
//! - [`Distribution`]: a Smith distribution chosen at run time (the `distribution`
//!   parameter of the microfacet lobes), dispatching to the list in [`smith_ndfs!`].
//!
//! Adding a Smith distribution: one file implementing [`Ndf`] and [`SmithNdf`], one line
//! in [`smith_ndfs!`] (its enum variant and choice name), and its committed albedo
//! tables (`GLINT_BLESS=1 cargo test --release --test albedo_tables` writes them).
//!
//! All directions are in the local frame (z = normal).

mod beckmann;
mod ggx;
mod gtr1;

pub use beckmann::Beckmann;
pub use ggx::Ggx;
pub use gtr1::Gtr1;

use crate::math::{Lane, Vec3};

/// Smallest alpha a distribution is evaluated with.
pub const MIN_ALPHA: f32 = 1e-4;
/// Below this alpha (in both directions) a microfacet lobe is a delta lobe:
/// it is sampled as a perfect specular interface, and eval and pdf return 0.
/// With `alpha = roughness^2` this is `roughness < 0.0316`.
pub const DELTA_ALPHA: f32 = 1e-3;

/// A normal distribution of microfacets.
pub trait Ndf<L: Lane>: Copy {
    /// `D(m)`, normalized so that the integral of `D(m) m.z` over the hemisphere is 1;
    /// 0 below the surface.
    fn d(&self, m: Vec3<L>) -> L;
    /// A microfacet normal for the view `w` from two random numbers in [0, 1).
    fn sample(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L>;
    /// The solid-angle density of [`Self::sample`]'s normals for `w`.
    fn pdf(&self, w: Vec3<L>, m: Vec3<L>) -> L;
    /// `w` reflected about a normal [`Self::sample`] draws for it. Override when the
    /// sampler's normal reflects more cheaply before it is made unit.
    #[inline(always)]
    fn sample_reflection(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        w.reflect(self.sample(w, u0, u1))
    }
}

/// A distribution with Smith masking-shadowing, anisotropic with per-lane alphas.
/// [`Ndf::sample`] samples visible normals and [`Ndf::pdf`] is
/// [`SmithNdf::pdf_visible`].
pub trait SmithNdf<L: Lane>: Ndf<L> {
    fn alpha(&self) -> (L, L);

    /// `Lambda(w) |w.z|`: Smith's `Lambda` times the cosine, the projected area of the
    /// back-facing microsurface, which stays finite where `Lambda` diverges
    /// (`|w.z| -> 0`). 0 along the normal.
    fn lambda_cos(&self, w: Vec3<L>) -> L;

    /// `sigma(w) = |w.z| + 2 Lambda(w) |w.z|` (`z = |w.z|`), positive. Override when a
    /// closed form avoids the sum's work.
    #[inline(always)]
    fn sigma(&self, w: Vec3<L>, z: L) -> L {
        z + L::splat(2.0) * self.lambda_cos(w)
    }

    /// `P = G1(wo) D(h) / |cos_o| = 2 D(h) / B` of [`Self::pair`]. Override when a
    /// closed form is cheaper or better conditioned.
    #[inline(always)]
    fn pair_density(&self, v: &View<L>, h: Vec3<L>) -> L {
        L::splat(2.0) * self.d(h) / v.b
    }

    /// Lanes whose distribution is narrow enough to be treated as a delta.
    #[inline(always)]
    fn is_delta(&self) -> L::Mask {
        let (ax, ay) = self.alpha();
        ax.max(ay).lt(L::splat(DELTA_ALPHA))
    }

    /// Smith masking `G1(w) = 1 / (1 + Lambda(w)) = |w.z| / (|w.z| + Lambda |w.z|)`.
    #[inline(always)]
    fn g1(&self, w: Vec3<L>) -> L {
        let z = w.z.abs();
        z.safe_div(z + self.lambda_cos(w))
    }

    /// `G1(w) / |w.z| = 1 / (|w.z| + Lambda(w) |w.z|)`: finite as `|w.z| -> 0`, where
    /// `G1` vanishes like `|w.z|`.
    #[inline(always)]
    fn g1_over_cos(&self, w: Vec3<L>) -> L {
        L::one().safe_div(w.z.abs() + self.lambda_cos(w))
    }

    /// Height-correlated masking-shadowing `G2 = 1 / (1 + Lambda(wo) + Lambda(wi))`
    /// (Heitz 2014 eq. 99).
    #[inline(always)]
    fn g2(&self, wo: Vec3<L>, wi: Vec3<L>) -> L {
        wo.z.abs() * self.g2_over_cos_o(wo, wi)
    }

    /// `G2(wo, wi) / |wo.z|`, multiplied out by `|wo.z| |wi.z|` (so no `Lambda` diverges):
    /// `|cos_i| / (|cos_o cos_i| + |cos_i| Lambda_o |cos_o| + |cos_o| Lambda_i |cos_i|)`.
    /// Finite as `|wo.z| -> 0`.
    #[inline(always)]
    fn g2_over_cos_o(&self, wo: Vec3<L>, wi: Vec3<L>) -> L {
        let (zo, zi) = (wo.z.abs(), wi.z.abs());
        let denom = zo * zi + zi * self.lambda_cos(wo) + zo * self.lambda_cos(wi);
        zi.safe_div(denom)
    }

    /// The `wo`-side terms of a microfacet eval, computed once per `wo` (eval, and
    /// sample before its direction is known): see [`View`].
    #[inline(always)]
    fn view(&self, wo: Vec3<L>) -> View<L> {
        let z = wo.z.abs();
        let sigma = self.sigma(wo, z);
        View {
            z,
            sigma,
            b: z + sigma,
        }
    }

    /// The microfacet terms of a pair (`v` = [`Self::view`] of `wo`, unit half vector
    /// `h`, `wi`), as `(P, rho, ok)` with
    /// - `P = G1(wo) D(h) / |cos_o| = 2 D(h) / B`, `B = |cos_o| + sigma_o`
    ///   (`G1 = 1 / (1 + Lambda)` = `2 |z| / (|z| + sigma)`), so the VNDF reflection pdf
    ///   `D_wo(h) / (4 wo.h) = G1(wo) D(h) / (4 cos_o)` (Heitz 2018 eq. 17) is `P / 4`;
    /// - `rho = G2(wo, wi) / G1(wo) = B |cos_i| / A`, `A = |cos_i| sigma_o + |cos_o| sigma_i`,
    ///   from the height-correlated `G2 = 1 / (1 + Lambda_o + Lambda_i)` (Heitz 2014
    ///   eq. 99) multiplied out by `|cos_o cos_i|`: `G2 / |cos_o| = 2 |cos_i| / A`;
    /// - `ok`: the lanes where `A > 0` (it may underflow at denormal cosines),
    ///
    /// so that `D G2 / |cos_o| = P rho`.
    #[inline(always)]
    fn pair(&self, v: &View<L>, h: Vec3<L>, wi: Vec3<L>) -> (L, L, L::Mask) {
        let zi = wi.z.abs();
        let a = zi * v.sigma + v.z * self.sigma(wi, zi);
        (self.pair_density(v, h), v.b * zi / a, a.gt(L::zero()))
    }

    /// Density of visible normals `D_w(m) = G1(w) max(0, w.m) D(m) / |w.z|` (Heitz 2014
    /// eq. 38) for `w` flipped to the upper hemisphere as [`Ndf::sample`] flips it,
    /// through [`Self::g1_over_cos`] so that it stays finite at grazing `w`.
    #[inline(always)]
    fn pdf_visible(&self, w: Vec3<L>, m: Vec3<L>) -> L {
        let w = upper(w);
        self.g1_over_cos(w) * w.dot(m).max(L::zero()) * self.d(m)
    }
}

/// The `wo`-side terms of a microfacet eval ([`SmithNdf::view`]): `|cos_o|`,
/// `sigma_o = |cos_o| (1 + 2 Lambda(wo))` and `B = |cos_o| + sigma_o = 2 |cos_o| / G1(wo)`.
#[derive(Clone, Copy, Debug)]
pub struct View<L> {
    pub z: L,
    pub sigma: L,
    pub b: L,
}

/// `w` flipped to the upper hemisphere: visible normals are sampled from above.
#[inline(always)]
fn upper<L: Lane>(w: Vec3<L>) -> Vec3<L> {
    Vec3::select(w.z.lt(L::zero()), -w, w)
}

/// Burley 2012's mapping of the artist parameters `roughness` and `anisotropic` in
/// [0, 1] to `(alpha_x, alpha_y)`: `alpha = roughness^2`, stretched along the tangent by
/// `1 / sqrt(1 - 0.9 anisotropic)`, each floored at `min`.
#[inline(always)]
pub fn burley_alpha<L: Lane>(roughness: L, anisotropic: L, min: f32) -> (L, L) {
    let alpha = roughness.clamp(L::zero(), L::one()).sqr();
    let aspect = (L::one() - L::splat(0.9) * anisotropic.clamp(L::zero(), L::one())).sqrt();
    // Times the reciprocal: calls with the same `anisotropic` share one division.
    let inv_aspect = L::one() / aspect;
    let min = L::splat(min);
    ((alpha * inv_aspect).max(min), (alpha * aspect).max(min))
}

/// The Smith distributions a lobe can choose at run time, in choice order: each entry is
/// `Variant "choice name"`, where `Variant` names both the [`NdfKind`] variant and the
/// type (re-exported from this module, a struct of public `alpha_x` and `alpha_y`, from
/// which the dispatch builds it). Invokes `$then!` with the list, so that every
/// closed list over them (the kind enum, its dispatch, the albedo table files) is
/// generated from this one.
macro_rules! smith_ndfs {
    ($then:ident ! { $($args:tt)* }) => {
        $then! { { $($args)* } Ggx "ggx", Beckmann "beckmann" }
    };
}
pub(crate) use smith_ndfs;

macro_rules! declare_kinds {
    ({} $($variant:ident $name:literal),+) => {
        /// Which Smith distribution a lobe uses (the `distribution` parameter).
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum NdfKind {
            $($variant),+
        }

        impl NdfKind {
            /// Every kind, in choice order.
            pub const ALL: &'static [NdfKind] = &[$(NdfKind::$variant),+];
            /// The choice names of the `distribution` parameter, in choice order.
            pub const NAMES: &'static [&'static str] = &[$($name),+];

            /// The kind of choice index `choice`; a validated block holds one in range.
            pub fn from_choice(choice: usize) -> NdfKind {
                Self::ALL.get(choice).copied().unwrap_or(Self::ALL[0])
            }

            pub fn name(self) -> &'static str {
                Self::NAMES[self as usize]
            }
        }
    };
}
smith_ndfs!(declare_kinds! {});

/// `$body` with `$n` bound to `$dist`'s distribution as its own type.
macro_rules! dispatch {
    ({ $dist:expr, $n:ident => $body:expr } $($variant:ident $name:literal),+) => {
        match $dist.kind {
            $(NdfKind::$variant => {
                let $n = $variant {
                    alpha_x: $dist.alpha_x,
                    alpha_y: $dist.alpha_y,
                };
                $body
            })+
        }
    };
}

/// A Smith distribution chosen at run time, with per-lane alphas. Each call dispatches
/// on `kind`, which is the same for every lane of a lobe.
#[derive(Clone, Copy, Debug)]
pub struct Distribution<L> {
    pub kind: NdfKind,
    pub alpha_x: L,
    pub alpha_y: L,
}

impl<L: Lane> Distribution<L> {
    /// From the artist parameters `roughness` and `anisotropic` ([`burley_alpha`], floored
    /// at [`MIN_ALPHA`]).
    #[inline(always)]
    pub fn from_roughness(kind: NdfKind, roughness: L, anisotropic: L) -> Self {
        let (alpha_x, alpha_y) = burley_alpha(roughness, anisotropic, MIN_ALPHA);
        Self {
            kind,
            alpha_x,
            alpha_y,
        }
    }
}

impl<L: Lane> Ndf<L> for Distribution<L> {
    #[inline(always)]
    fn d(&self, m: Vec3<L>) -> L {
        smith_ndfs!(dispatch! { self, n => n.d(m) })
    }

    #[inline(always)]
    fn sample(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        smith_ndfs!(dispatch! { self, n => n.sample(w, u0, u1) })
    }

    #[inline(always)]
    fn sample_reflection(&self, w: Vec3<L>, u0: L, u1: L) -> Vec3<L> {
        smith_ndfs!(dispatch! { self, n => n.sample_reflection(w, u0, u1) })
    }

    #[inline(always)]
    fn pdf(&self, w: Vec3<L>, m: Vec3<L>) -> L {
        smith_ndfs!(dispatch! { self, n => n.pdf(w, m) })
    }
}

impl<L: Lane> SmithNdf<L> for Distribution<L> {
    #[inline(always)]
    fn alpha(&self) -> (L, L) {
        (self.alpha_x, self.alpha_y)
    }

    #[inline(always)]
    fn lambda_cos(&self, w: Vec3<L>) -> L {
        smith_ndfs!(dispatch! { self, n => n.lambda_cos(w) })
    }

    #[inline(always)]
    fn sigma(&self, w: Vec3<L>, z: L) -> L {
        smith_ndfs!(dispatch! { self, n => n.sigma(w, z) })
    }

    #[inline(always)]
    fn pair_density(&self, v: &View<L>, h: Vec3<L>) -> L {
        smith_ndfs!(dispatch! { self, n => n.pair_density(v, h) })
    }
}
