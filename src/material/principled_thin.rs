//! Mitsuba 3's `principledthin` BSDF: the principled BSDF of a surface without thickness
//! (leaves, paper, cloth) after Burley 2015, §4 ("thin-surface BSDF"), as Mitsuba implements
//! it (src/bsdfs/principledthin.cpp), lobe for lobe:
//!
//! - weight spec_trans: a GGX reflection (α from roughness and anisotropic) with the dielectric
//!   Fresnel term of `eta` blended towards the tinted Schlick term by `spec_tint`, and a
//!   "transmission" that reflects about a microfacet of the distribution with roughness scaled
//!   by 0.65·η − 0.35 (Burley 2015, fig. 15) and mirrors the result through the sheet, without
//!   bending (coloured by base_color, weighted by 1 − F);
//! - weight (1 − spec_trans)(1 − diff_trans/2): Burley's diffuse with retro-reflection,
//!   `flatness` and sheen (`principled_lobes`);
//! - weight (1 − spec_trans)·diff_trans/2: Lambertian transmission of base_color
//!   (`diff_trans` runs from 0 to 2, as Burley's).
//!
//! The sheet is the same from both sides: wo below the surface is handled by mirroring both
//! directions. Sampling picks the GGX reflection, the mirrored transmission, the cosine
//! hemisphere above or below with probabilities spec_trans/2 times each specular rate, and
//! (1 − spec_trans)(1 − diff_trans/2), (1 − spec_trans)·diff_trans/2 times the diffuse rates.

use super::dielectric::fresnel_dielectric;
use super::microfacet::{reflect_about, Microfacet};
use super::principled_lobes::{
    compatible, diffuse_retro, sheen, specular_distribution, thin_fresnel,
};
use super::sampling::square_to_cosine_hemisphere;
use super::BsdfSample;
use crate::Color;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// The parameters of Mitsuba's `principledthin` plugin (its names; all in [0, 1] except
/// `diff_trans` in [0, 2], `eta` and the sampling rates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledThin {
    pub base_color: Color,
    pub roughness: f32,
    pub anisotropic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    /// Diffuse transmission, 0 (all diffuse reflection) to 2 (all transmission).
    pub diff_trans: f32,
    /// Index of refraction of the sheet (relative to the medium on both sides).
    pub eta: f32,
    pub diffuse_reflectance_sampling_rate: f32,
    pub specular_reflectance_sampling_rate: f32,
    pub specular_transmittance_sampling_rate: f32,
    pub diffuse_transmittance_sampling_rate: f32,
}

impl Default for PrincipledThin {
    /// Mitsuba's defaults: base colour 0.5, roughness 0.5, η = 1.5, every other weight 0,
    /// sampling rates 1.
    fn default() -> Self {
        PrincipledThin {
            base_color: Color::splat(0.5),
            roughness: 0.5,
            anisotropic: 0.0,
            spec_trans: 0.0,
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            diff_trans: 0.0,
            eta: 1.5,
            diffuse_reflectance_sampling_rate: 1.0,
            specular_reflectance_sampling_rate: 1.0,
            specular_transmittance_sampling_rate: 1.0,
            diffuse_transmittance_sampling_rate: 1.0,
        }
    }
}

/// wo and wi mirrored so that wo is above the sheet.
#[inline]
fn to_front(wo: Vec3A, wi: Vec3A) -> (Vec3A, Vec3A) {
    if wo.z < 0.0 {
        (-wo, -wi)
    } else {
        (wo, wi)
    }
}

impl PrincipledThin {
    #[inline]
    fn reflect_distr(&self) -> Microfacet {
        specular_distribution(self.roughness, self.anisotropic)
    }

    /// The transmission's distribution: roughness scaled by 0.65·η − 0.35 (Burley 2015,
    /// fig. 15).
    #[inline]
    fn transmit_distr(&self) -> Microfacet {
        specular_distribution((0.65 * self.eta - 0.35) * self.roughness, self.anisotropic)
    }

    /// Probabilities of (specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission); None when all are zero.
    #[inline]
    fn probabilities(&self) -> Option<[f32; 4]> {
        let (st, dt) = (self.spec_trans, self.diff_trans / 2.0);
        let p = [
            st * self.specular_reflectance_sampling_rate / 2.0,
            st * self.specular_transmittance_sampling_rate / 2.0,
            self.diffuse_reflectance_sampling_rate * (1.0 - st) * (1.0 - dt),
            self.diffuse_transmittance_sampling_rate * (1.0 - st) * dt,
        ];
        let total = p.iter().sum::<f32>();
        (total > 0.0).then(|| p.map(|x| x / total))
    }

    /// The half vector of wo and wi mirrored above the sheet (wo above).
    #[inline]
    fn half_vector(wo: Vec3A, wi: Vec3A) -> Vec3A {
        (wo + Vec3A::new(wi.x, wi.y, wi.z.abs())).normalize()
    }

    /// f(wo, wi)·|cos θi| (Mitsuba's `eval`).
    #[inline]
    pub fn eval_cos(&self, wo: Vec3A, wi: Vec3A) -> Color {
        if wo.z == 0.0 {
            return Color::ZERO;
        }
        let (wo, wi) = to_front(wo, wi);
        let (cos_o, cos_i) = (wo.z, wi.z);
        let (reflect, refract) = (cos_i > 0.0, cos_i < 0.0);
        let h = Self::half_vector(wo, wi);
        let (st, dt) = (self.spec_trans, self.diff_trans / 2.0);
        let base = self.base_color;
        let mut value = Color::ZERO;
        if st > 0.0 {
            let f = fresnel_dielectric(wo.dot(h), self.eta);
            if reflect && compatible(h, wo, wi, cos_o, true) {
                let distr = self.reflect_distr();
                let ft = thin_fresnel(f, self.spec_tint, base, wo.dot(h), self.eta);
                let dg = distr.d(h) * distr.g(wo, wi, h);
                value += ft * (st * dg / (4.0 * cos_o));
            }
            if refract && compatible(h, wo, wi, cos_o, false) {
                let distr = self.transmit_distr();
                let dg = distr.d(h) * distr.g(wo, wi, h);
                value += base * (st * (1.0 - f) * dg / (4.0 * cos_o));
            }
        }
        if reflect && st < 1.0 && dt < 1.0 {
            let cos_d = h.dot(wi);
            let fd = diffuse_retro(cos_i, cos_o, cos_d, self.roughness, self.flatness);
            value += base * ((1.0 - st) * cos_i * FRAC_1_PI * (1.0 - dt) * fd);
            if self.sheen > 0.0 {
                value += sheen(cos_d, base, self.sheen_tint)
                    * (self.sheen * (1.0 - st) * (1.0 - dt) * cos_i);
            }
        }
        if refract && st < 1.0 && dt > 0.0 {
            value += base * ((1.0 - st) * dt * FRAC_1_PI * -cos_i);
        }
        value
    }

    /// f(wo, wi) (without the cosine).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        if wi.z == 0.0 {
            return Color::ZERO;
        }
        self.eval_cos(wo, wi) / wi.z.abs()
    }

    /// The solid-angle density of `sample` (Mitsuba's `pdf`).
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        let Some([p_sr, p_st, p_dr, p_dt]) = self.probabilities() else {
            return 0.0;
        };
        let (wo, wi) = to_front(wo, wi);
        let cos_i = wi.z;
        let (reflect, refract) = (cos_i > 0.0, cos_i < 0.0);
        let mut pdf = 0.0;
        if self.spec_trans > 0.0 {
            let h = Self::half_vector(wo, wi);
            // Reflection and the mirrored transmission alike: dh/dwi of a reflection.
            let dh_dwi = (1.0 / (4.0 * Vec3A::new(wi.x, wi.y, cos_i.abs()).dot(h))).abs();
            if reflect && compatible(h, wo, wi, wo.z, true) {
                pdf += p_sr * self.reflect_distr().pdf_visible(wo, h) * dh_dwi;
            }
            if refract && compatible(h, wo, wi, wo.z, false) {
                pdf += p_st * self.transmit_distr().pdf_visible(wo, h) * dh_dwi;
            }
        }
        if reflect {
            pdf += p_dr * cos_i * FRAC_1_PI;
        }
        if refract && self.diff_trans > 0.0 {
            pdf += p_dt * -cos_i * FRAC_1_PI;
        }
        pdf
    }

    /// Samples wi: `u1` picks the lobe, `u2` the direction (Mitsuba's `sample`).
    #[inline]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let [p_sr, p_st, p_dr, _] = self.probabilities()?;
        let s = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let wo_f = wo * s;
        let wi = if u1 < p_sr {
            let m = self.reflect_distr().sample_visible(wo_f, u2);
            let wi = reflect_about(wo_f, m);
            if !(wi.z > 0.0 && compatible(m, wo_f, wi, wo_f.z, true)) {
                return None;
            }
            wi
        } else if u1 < p_sr + p_st {
            let m = self.transmit_distr().sample_visible(wo_f, u2);
            let r = reflect_about(wo_f, m);
            let wi = Vec3A::new(r.x, r.y, -r.z);
            if !(wi.z < 0.0 && compatible(m, wo_f, wi, wo_f.z, false)) {
                return None;
            }
            wi
        } else if u1 < p_sr + p_st + p_dr {
            square_to_cosine_hemisphere(u2)
        } else if self.diff_trans > 0.0 {
            -square_to_cosine_hemisphere(u2)
        } else {
            return None;
        };
        let wi = wi * s;
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.eval_cos(wo, wi) / pdf,
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}
