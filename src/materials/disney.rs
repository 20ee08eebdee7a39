//! `disney`: the principled BRDF of Burley 2012 ("Physically-Based Shading at Disney",
//! seed 003; formulas as restated in `shared/reference/formulas.md`), as four lobes
//! whose weights reproduce the 2012 sum
//! `f = ((1/pi) mix(Fd, ss, subsurface) base_color + Fsheen) (1 - metallic)
//!      + Gs Fs Ds + 0.25 clearcoat Gr Fr Dr`.
//!
//! Parameters (the 2012 names; every one in [0, 1]):
//! - `base_color` (rgb, default 0.82, 0.67, 0.16), `subsurface` (0), `metallic` (0),
//!   `specular` (0.5), `specular_tint` (0), `roughness` (0.5), `anisotropic` (0),
//!   `sheen` (0), `sheen_tint` (0.5), `clearcoat` (0), `clearcoat_gloss` (1).
//!
//! Slots, each emitted only where it can contribute:
//! - `disney_diffuse` (base_color, roughness, subsurface), weight `1 - metallic`; not
//!   emitted at metallic 1 or a black base color;
//! - `disney_sheen` (color 1), weight `(1 - metallic) sheen Csheen`; not at sheen 0;
//! - `disney_specular` (roughness, anisotropic, f0 = Cspec0), weight 1; always (its
//!   Schlick term reaches 1 at grazing whatever `Cspec0`);
//! - `disney_clearcoat` (gloss = clearcoat_gloss), weight `0.25 clearcoat`; not at
//!   clearcoat 0.
//!
//! With `Cdlum = 0.3 R + 0.6 G + 0.1 B` of the base color, `Ctint = base_color / Cdlum`
//! (1 where `Cdlum = 0`), `Cspec0 = mix(specular 0.08 mix(1, Ctint, specular_tint),
//! base_color, metallic)` and `Csheen = mix(1, Ctint, sheen_tint)`.

use super::{Context, Expansion, MaterialModel};
use crate::lobes::disney_clearcoat::DisneyClearcoat;
use crate::lobes::disney_diffuse::DisneyDiffuse;
use crate::lobes::disney_sheen::DisneySheen;
use crate::lobes::disney_specular::DisneySpecular;
use crate::lobes::{Params, VerifyCase};
use crate::math::{Lane, Mask, Rgb};
use crate::params::{ParamSpec, offset_of};

pub struct Disney;

/// Burley 2012's luminance approximation `Cdlum = 0.3 R + 0.6 G + 0.1 B`. (A function,
/// not a closure: a closure would lose the kernel's target features.)
#[inline(always)]
fn burley_luminance<L: Lane>(c: Rgb<L>) -> L {
    L::splat(0.3) * c.r + L::splat(0.6) * c.g + L::splat(0.1) * c.b
}

/// 2^64: takes the smallest denormal's luminance (0.1 of 1.4e-45) to a normal float.
const TINY_COLOR_SCALE: f32 = 18_446_744_073_709_551_616.0;

/// Slots, in [`Disney::Slots`] order.
pub const DIFFUSE: usize = 0;
pub const SHEEN: usize = 1;
pub const SPECULAR: usize = 2;
pub const CLEARCOAT: usize = 3;

const BASE_COLOR: usize = offset_of(Disney::PARAMS, 0);
const SUBSURFACE: usize = offset_of(Disney::PARAMS, 1);
const METALLIC: usize = offset_of(Disney::PARAMS, 2);
const SPECULAR_LEVEL: usize = offset_of(Disney::PARAMS, 3);
const SPECULAR_TINT: usize = offset_of(Disney::PARAMS, 4);
const ROUGHNESS: usize = offset_of(Disney::PARAMS, 5);
const ANISOTROPIC: usize = offset_of(Disney::PARAMS, 6);
const SHEEN_LEVEL: usize = offset_of(Disney::PARAMS, 7);
const SHEEN_TINT: usize = offset_of(Disney::PARAMS, 8);
const CLEARCOAT_LEVEL: usize = offset_of(Disney::PARAMS, 9);
const CLEARCOAT_GLOSS: usize = offset_of(Disney::PARAMS, 10);

impl MaterialModel for Disney {
    const NAME: &'static str = "disney";
    const SUMMARY: &'static str = "Disney principled BRDF (Burley 2012): diffuse with retro-reflection and subsurface, sheen, anisotropic GTR2 specular, GTR1 clearcoat";
    const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::rgb(
            "base_color",
            [0.82, 0.67, 0.16],
            0.0,
            1.0,
            "surface color: diffuse albedo, or specular color when metallic",
        ),
        ParamSpec::float(
            "subsurface",
            0.0,
            0.0,
            1.0,
            "blend of the diffuse toward the Hanrahan-Krueger-like subsurface shape",
        ),
        ParamSpec::float(
            "metallic",
            0.0,
            0.0,
            1.0,
            "0 dielectric, 1 metal (no diffuse or sheen)",
        ),
        ParamSpec::float(
            "specular",
            0.5,
            0.0,
            1.0,
            "normal-incidence reflectance 0.08 specular (0.5: 4%, IOR 1.5)",
        ),
        ParamSpec::float(
            "specular_tint",
            0.0,
            0.0,
            1.0,
            "tints the dielectric specular toward the base color",
        ),
        ParamSpec::float(
            "roughness",
            0.5,
            0.0,
            1.0,
            "diffuse retro-reflection and specular width (alpha = roughness^2)",
        ),
        ParamSpec::float(
            "anisotropic",
            0.0,
            0.0,
            1.0,
            "specular aspect sqrt(1 - 0.9 anisotropic), wider along the tangent",
        ),
        ParamSpec::float("sheen", 0.0, 0.0, 1.0, "grazing sheen for cloth"),
        ParamSpec::float(
            "sheen_tint",
            0.5,
            0.0,
            1.0,
            "tints the sheen toward the base color",
        ),
        ParamSpec::float("clearcoat", 0.0, 0.0, 1.0, "second, clear specular layer"),
        ParamSpec::float(
            "clearcoat_gloss",
            1.0,
            0.0,
            1.0,
            "clearcoat GTR1 alpha mix(0.1, 0.001, clearcoat_gloss)",
        ),
    ];
    type Slots = (DisneyDiffuse, DisneySheen, DisneySpecular, DisneyClearcoat);
    const VERIFY_CASES: &'static [VerifyCase] = &[
        VerifyCase {
            name: "all 0",
            set: &[
                ("base_color", 0.0),
                ("subsurface", 0.0),
                ("metallic", 0.0),
                ("specular", 0.0),
                ("specular_tint", 0.0),
                ("roughness", 0.0),
                ("anisotropic", 0.0),
                ("sheen", 0.0),
                ("sheen_tint", 0.0),
                ("clearcoat", 0.0),
                ("clearcoat_gloss", 0.0),
            ],
        },
        VerifyCase {
            name: "all 1",
            set: &[
                ("base_color", 1.0),
                ("subsurface", 1.0),
                ("metallic", 1.0),
                ("specular", 1.0),
                ("specular_tint", 1.0),
                ("roughness", 1.0),
                ("anisotropic", 1.0),
                ("sheen", 1.0),
                ("sheen_tint", 1.0),
                ("clearcoat", 1.0),
                ("clearcoat_gloss", 1.0),
            ],
        },
        VerifyCase {
            name: "roughness 0",
            set: &[("roughness", 0.0)],
        },
        VerifyCase {
            name: "roughness 1",
            set: &[("roughness", 1.0)],
        },
        VerifyCase {
            name: "anisotropic 1",
            set: &[("anisotropic", 1.0), ("roughness", 0.4)],
        },
        VerifyCase {
            name: "metallic 0.5",
            set: &[("metallic", 0.5)],
        },
        VerifyCase {
            name: "clearcoat 1 gloss 0",
            set: &[("clearcoat", 1.0), ("clearcoat_gloss", 0.0)],
        },
        VerifyCase {
            name: "clearcoat 1 gloss 1",
            set: &[("clearcoat", 1.0), ("clearcoat_gloss", 1.0)],
        },
        VerifyCase {
            name: "every lobe",
            set: &[
                ("subsurface", 0.5),
                ("metallic", 0.3),
                ("sheen", 1.0),
                ("clearcoat", 1.0),
                ("anisotropic", 0.5),
            ],
        },
    ];

    #[inline(always)]
    fn expand<L: Lane>(p: Params<'_, L>, _ctx: &Context<L>, out: &mut Expansion<L>) {
        let base = p.rgb(BASE_COLOR);
        let metallic = p.float(METALLIC);
        let roughness = p.float(ROUGHNESS);
        let dielectric = L::one() - metallic;
        let (zero, one) = (L::zero(), L::one());

        // Burley 2012's luminance approximation and hue. A color whose luminance is not
        // a normal float (every channel below about 1e-37) is scaled by 2^64 first
        // (exactly): its luminance's reciprocal would overflow, and a denormal
        // luminance would round its hue away.
        let (mut lum, mut hue) = (burley_luminance(base), base);
        let tiny = lum.lt(L::splat(f32::MIN_POSITIVE));
        if tiny.any() {
            let scale = L::select(tiny, L::splat(TINY_COLOR_SCALE), one);
            hue = base.map(
                #[inline(always)]
                |c| c * scale,
            );
            lum = burley_luminance(hue);
        }
        let has_hue = lum.gt(zero);
        let inv_lum = one / L::select(has_hue, lum, one);
        let tint = hue.map(
            #[inline(always)]
            |c| L::select(has_hue, c * inv_lum, one),
        );
        let mix = |a: Rgb<L>, b: Rgb<L>, t: L| {
            a.zip(
                b,
                #[inline(always)]
                |a, b| a + (b - a) * t,
            )
        };
        let white = Rgb::new(one, one, one);

        let diffuse = L::select(has_hue, dielectric, zero);
        out.weight[DIFFUSE] = Rgb::new(diffuse, diffuse, diffuse);
        let d = &mut out.params[DIFFUSE];
        (d[0], d[1], d[2]) = (base.r, base.g, base.b);
        (d[3], d[4]) = (roughness, p.float(SUBSURFACE));

        let sheen_tint = mix(white, tint, p.float(SHEEN_TINT));
        out.weight[SHEEN] = sheen_tint * (dielectric * p.float(SHEEN_LEVEL));
        out.params[SHEEN][..3].fill(one);

        let dielectric_f0 =
            mix(white, tint, p.float(SPECULAR_TINT)) * (L::splat(0.08) * p.float(SPECULAR_LEVEL));
        let f0 = mix(dielectric_f0, base, metallic).map(
            #[inline(always)]
            |c| c.clamp(zero, one),
        );
        out.weight[SPECULAR] = white;
        let s = &mut out.params[SPECULAR];
        (s[0], s[1]) = (roughness, p.float(ANISOTROPIC));
        (s[2], s[3], s[4]) = (f0.r, f0.g, f0.b);

        let coat = L::splat(0.25) * p.float(CLEARCOAT_LEVEL);
        out.weight[CLEARCOAT] = Rgb::new(coat, coat, coat);
        out.params[CLEARCOAT][0] = p.float(CLEARCOAT_GLOSS);
    }
}
