//! The pieces Mitsuba 3's `principled` and `principledthin` BSDFs share (Mitsuba's
//! src/bsdfs/principledhelpers.h), after Burley, "Physically Based Shading at Disney"
//! (SIGGRAPH 2012 course notes) and "Extending the Disney BRDF to a BSDF with Integrated
//! Subsurface Scattering" (SIGGRAPH 2015 course notes): Schlick's Fresnel and its tinted mix
//! with the dielectric one, the roughness-to-α map with anisotropy, the diffuse lobe with
//! retro-reflection and the "flatness" fake subsurface, the sheen, and the GTR1 distribution
//! of the clearcoat. Values are what Mitsuba's code computes, step for step, so that both
//! BSDFs match it pointwise (tests/bsdf_mitsuba.rs).

use super::microfacet::Microfacet;
use crate::Color;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

/// Schlick's weight (1 − cos θ)⁵, the argument clamped to [0, 1] (`schlick_weight`).
#[inline]
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel approximation F = R0 + (1 − R0)(1 − cos)⁵ per channel, with the cosine
/// on the denser side of the interface: the incident one when η_it > 1, the transmitted one
/// otherwise (`calc_schlick`; `eta` is inside over outside, `cos_i` signed as in
/// `fresnel_dielectric`).
#[inline]
pub fn schlick_fresnel(r0: Color, cos_i: f32, eta: f32) -> Color {
    let (eta_it, eta_ti) = if cos_i >= 0.0 {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti);
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    // Mitsuba's lerp(w, 1, R0).
    r0 + (Color::splat(w) - w * r0)
}

/// Normal-incidence reflectance of an interface of relative index η: ((η − 1)/(η + 1))².
#[inline]
pub fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Luminance of a linear sRGB colour (Mitsuba's `luminance` in its RGB variants: the Y row of
/// the sRGB-to-XYZ matrix).
#[inline]
pub fn luminance(c: Color) -> f32 {
    c.x * 0.212671 + c.y * 0.715160 + c.z * 0.072169
}

/// The base colour normalised to unit luminance (white when the base colour is black): the
/// hue that `spec_tint` and `sheen_tint` blend towards.
#[inline]
pub fn tint_color(base: Color) -> Color {
    let lum = luminance(base);
    if lum > 0.0 {
        base / lum
    } else {
        Color::ONE
    }
}

/// Mitsuba's `lerp(a, b, t)`: b·t + (a − a·t), exact at t = 0 and t = 1.
#[inline]
pub fn lerp(a: f32, b: f32, t: f32) -> f32 {
    b * t + (a - a * t)
}

#[inline]
fn lerp_color(a: Color, b: Color, t: f32) -> Color {
    b * t + (a - a * t)
}

/// The GGX distribution of the main specular lobes: α = roughness², stretched by the aspect
/// √(1 − 0.9·anisotropic) along the tangent and squeezed along the bitangent, at least 0.001
/// (Burley 2012, §5.4; `calc_dist_params`).
#[inline]
pub fn specular_distribution(roughness: f32, anisotropic: f32) -> Microfacet {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    Microfacet::ggx((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
}

/// The dielectric Fresnel term of the principled BSDF on the front side, blended with the
/// metal's Schlick term (R0 = base colour) and the tinted dielectric one (R0 = the tint colour
/// times R0(η)); from the back, only the dielectric term scaled by the transmission weight
/// (`principled_fresnel`).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn principled_fresnel(
    f_dielectric: f32,
    metallic: f32,
    spec_tint: f32,
    base: Color,
    cos_i: f32,
    front: bool,
    bsdf_weight: f32,
    eta: f32,
) -> Color {
    if !front {
        return Color::splat(bsdf_weight * f_dielectric);
    }
    let eta_it = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    let metal = metallic * schlick_fresnel(base, cos_i, eta);
    let r0_tint = tint_color(base) * schlick_r0(eta_it);
    let tinted = ((1.0 - metallic) * spec_tint) * schlick_fresnel(r0_tint, cos_i, eta);
    Color::splat((1.0 - metallic) * (1.0 - spec_tint) * f_dielectric) + (metal + tinted)
}

/// The thin BSDF's Fresnel term: the dielectric one blended towards the tinted Schlick term by
/// `spec_tint` (`thin_fresnel`).
#[inline]
pub fn thin_fresnel(f_dielectric: f32, spec_tint: f32, base: Color, cos_i: f32, eta: f32) -> Color {
    let tinted = schlick_fresnel(tint_color(base) * schlick_r0(eta), cos_i, eta);
    lerp_color(Color::splat(f_dielectric), tinted, spec_tint)
}

/// Burley's diffuse lobe without its ρ/π factor: the Lambertian part with Schlick-shaped
/// darkening at grazing angles, (1 − F_i/2)(1 − F_o/2), plus retro-reflection
/// R_r(F_o + F_i + F_o F_i (R_r − 1)), R_r = 2·roughness·cos²θ_d (Burley 2015, §3.1), blended
/// by `flatness` towards the fake subsurface term 1.25(F_ss(1/(cos θo + cos θi) − 0.5) + 0.5)
/// after Hanrahan and Krueger (Burley 2012, §5.3). `cos_o`, `cos_i` are |cos θ| of the two
/// directions, `cos_d` the cosine between the half vector and either.
#[inline]
pub fn diffuse_retro(cos_o: f32, cos_i: f32, cos_d: f32, roughness: f32, flatness: f32) -> f32 {
    let (fo, fi) = (schlick_weight(cos_o), schlick_weight(cos_i));
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * roughness * cos_d * cos_d;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    if flatness == 0.0 {
        return f_diff + f_retro;
    }
    let fss90 = rr / 2.0;
    let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
    let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
    lerp(f_diff + f_retro, f_ss, flatness)
}

/// The sheen lobe (without the lobe weights): Schlick's weight of θ_d, tinted towards the base
/// colour's hue by `sheen_tint` (Burley 2012, §5.3).
#[inline]
pub fn sheen(cos_d: f32, base: Color, sheen_tint: f32) -> Color {
    let c = lerp_color(Color::ONE, tint_color(base), sheen_tint);
    schlick_weight(cos_d.abs()) * c
}

/// Whether the microfacet `m` is seen from the side of the macro-surface each direction lies
/// on: `wo` and `wi` both in front of m (oriented towards `wo`'s side) for reflection, `wi`
/// behind it for transmission (`mac_mic_compatibility`).
#[inline]
pub fn compatible(m: Vec3A, wo: Vec3A, wi: Vec3A, cos_o: f32, reflection: bool) -> bool {
    let m = if cos_o < 0.0 { -m } else { m };
    wo.dot(m) > 0.0
        && if reflection {
            wi.dot(m) > 0.0
        } else {
            wi.dot(m) < 0.0
        }
}

/// The clearcoat's roughness: lerp(0.1, 0.001, clearcoat_gloss) (Burley 2012, §5.4).
#[inline]
pub fn clearcoat_alpha(gloss: f32) -> f32 {
    lerp(0.1, 0.001, gloss)
}

/// The clearcoat's shadowing–masking: Smith's separable G of GGX with α = 0.25 (Burley 2012,
/// §5.6, fixed roughness), as `clearcoat_G`.
#[inline]
pub fn clearcoat_g(wo: Vec3A, wi: Vec3A, h: Vec3A) -> f32 {
    Microfacet::ggx(0.25, 0.25).g(wo, wi, h)
}

/// Burley's "generalised Trowbridge–Reitz" distribution with γ = 1 (Burley 2012, eq. 4,
/// normalised): D(m) = (α² − 1)/(π ln α² (1 + (α² − 1) cos²θm)), isotropic, sampled by
/// normals (not visible normals), as Mitsuba's `GTR1Isotropic`.
#[derive(Clone, Copy, Debug)]
pub struct Gtr1 {
    pub alpha: f32,
}

impl Gtr1 {
    #[inline]
    pub fn d(&self, m: Vec3A) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let r = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c2));
        if r * m.z > 1e-20 {
            r
        } else {
            0.0
        }
    }

    /// Density of `sample` over normals: D(m) cos θm.
    #[inline]
    pub fn pdf(&self, m: Vec3A) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.d(m)
        }
    }

    /// Inverts the CDF of D cos θ in cos²θ: cos²θ = (1 − (α²)^(1−u))/(1 − α²) (Burley 2012,
    /// eq. 5).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3A {
        let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin_t = (1.0 - cos2).max(0.0).sqrt();
        let cos_t = cos2.max(0.0).sqrt();
        Vec3A::new(cos_phi * sin_t, sin_phi * sin_t, cos_t)
    }
}
