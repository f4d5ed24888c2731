//! Smooth plastic: a diffuse base under a smooth dielectric coating, as Mitsuba 3's
//! `plastic` (after Weidlich and Wilkie, "Arbitrarily Layered Micro-Facet Surfaces",
//! GRAPHITE 2007, and Mitsuba 0.6's documentation of the model). A delta reflection of
//! Fresnel weight F(θo) off the coating, plus the diffuse base seen through it:
//!
//!   f_d = ρ'/π · (1 − F(θo))(1 − F(θi)) / η²,  ρ' = ρ / (1 − F_dr)  (ρ' = ρ/(1 − ρ F_dr)
//!   with `nonlinear`),
//!
//! where F_dr is the diffuse internal reflectance of the coating (`fresnel_diffuse_reflectance`
//! of 1/η) and 1/η² the radiance compression into the coating. The delta lobe is sampled with
//! probability F(θo)·w / (F(θo)·w + (1 − F(θo))·(1 − w)), w = s̄/(d̄ + s̄) from the mean
//! specular and diffuse reflectances; the diffuse lobe is sampled cosine-weighted.
//!
//! `eval` and `pdf` describe only the diffuse lobe (with its selection probability folded
//! into the pdf); delta samples come out of `sample` with `specular = true` and pdf 0.

use super::dielectric::fresnel_dielectric;
use super::mirror::reflect_local;
use super::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use super::BsdfSample;
use crate::Color;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// The diffuse Fresnel reflectance F_dr(η) = 2 ∫ F(cos θ, η) cos θ sin θ dθ of a dielectric
/// interface with relative index η, by Mitsuba's fits: Egan and Hilgeman (1973) for η < 1,
/// d'Eon and Irving, "A Quantized-Diffusion Model for Rendering Translucent Materials",
/// SIGGRAPH 2011, eq. 12 (after Grosjean), for η ≥ 1.
#[inline]
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * (eta * eta) + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let inv = 1.0 / eta;
        let inv2 = inv * inv;
        let inv3 = inv2 * inv;
        let inv4 = inv3 * inv;
        let inv5 = inv4 * inv;
        0.919317 - 3.4793 * inv + 6.75335 * inv2 - 7.80989 * inv3 + 4.98554 * inv4 - 1.36881 * inv5
    }
}

/// The mean of a colour's channels (what Mitsuba's `Texture::mean()` gives for a constant RGB
/// reflectance in the RGB variants).
#[inline]
pub(crate) fn mean(c: Color) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

#[derive(Clone, Copy, Debug)]
pub struct Plastic {
    /// Index of the coating over that of the outside (`int_ior / ext_ior`).
    pub eta: f32,
    pub diffuse_reflectance: Color,
    pub specular_reflectance: Color,
    /// Account for the colour shift of multiple scattering inside the coating.
    pub nonlinear: bool,
    /// Probability weight w of the specular lobe, s̄/(d̄ + s̄), from the reflectances given to
    /// the constructor. A caller that substitutes textured reflectances per hit keeps this
    /// (Mitsuba computes it from the textures' means, not per hit).
    pub specular_sampling_weight: f32,
    /// F_dr(1/η), the diffuse reflectance of the coating from inside.
    fdr_int: f32,
    inv_eta2: f32,
}

impl Plastic {
    pub fn new(eta: f32, diffuse: Color, specular: Color, nonlinear: bool) -> Self {
        let (d, s) = (mean(diffuse), mean(specular));
        Plastic {
            eta,
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            nonlinear,
            specular_sampling_weight: s / (d + s),
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
            inv_eta2: 1.0 / (eta * eta),
        }
    }

    /// Probability of choosing the delta lobe at incidence cos θo with reflectance F(θo).
    #[inline]
    fn prob_specular(&self, f_o: f32) -> f32 {
        let w = self.specular_sampling_weight;
        let ps = f_o * w;
        let pd = (1.0 - f_o) * (1.0 - w);
        ps / (ps + pd)
    }

    /// ρ' = ρ/(1 − F_dr) or ρ/(1 − ρ F_dr).
    #[inline]
    fn base(&self) -> Color {
        let d = self.diffuse_reflectance;
        if self.nonlinear {
            d / (Color::ONE - d * self.fdr_int)
        } else {
            d / (1.0 - self.fdr_int)
        }
    }

    /// The diffuse lobe (wo.z > 0 required).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        let f_i = fresnel_dielectric(wi.z, self.eta);
        self.base() * (FRAC_1_PI * self.inv_eta2 * (1.0 - f_o) * (1.0 - f_i))
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        cosine_hemisphere_pdf(wi.z) * (1.0 - self.prob_specular(f_o))
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        let ps = self.prob_specular(f_o);
        if u1 < ps {
            return Some(BsdfSample {
                wi: reflect_local(wo),
                weight: self.specular_reflectance * (f_o / ps),
                pdf: 0.0,
                specular: true,
                eta: 1.0,
            });
        }
        let wi = square_to_cosine_hemisphere(u2);
        if wi.z <= 0.0 {
            return None;
        }
        let pd = 1.0 - ps;
        let f_i = fresnel_dielectric(wi.z, self.eta);
        // f·cos/pdf = ρ'/π·(1 − F_o)(1 − F_i)/η² · cos / (pd·cos/π).
        let weight = self.base() * (self.inv_eta2 * (1.0 - f_o) * (1.0 - f_i) / pd);
        Some(BsdfSample {
            wi,
            weight,
            pdf: cosine_hemisphere_pdf(wi.z) * pd,
            specular: false,
            eta: 1.0,
        })
    }
}
