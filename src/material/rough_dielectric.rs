//! Rough dielectric interfaces (frosted glass): the microfacet BSDF of Walter et al.,
//! "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007, with the Beckmann
//! or GGX distribution, reflection (eq. 20) and transmission (eq. 21), sampled by visible
//! normals; as Mitsuba 3's `roughdielectric` with `sample_visible = true`.
//!
//! For wo on the side with index n_o and η = n_i/n_o the index ratio in the direction of
//! travel, the generalised half vector is h = ±(wo + η wi)/‖wo + η wi‖ (eq. 16), oriented
//! with the macro-normal, and
//! - reflection: f_r = F(wo·h)·D(h)·G(wo, wi, h) / (4 |cos θo| |cos θi|),
//! - transmission: f_t = |wo·h| |wi·h| η² (1 − F)·D·G / (|cos θo| |cos θi| (wo·h + η wi·h)²),
//!   times 1/η² when radiance is transported (Veach 1997 §5.2; the term Mitsuba adds, as the
//!   smooth `Dielectric` does).
//!
//! The reflection or the refraction through the sampled microfacet is chosen with
//! probability F and 1 − F. Mitsuba's `specular_reflectance` and `specular_transmittance`
//! scale the two (1 for physical realism).

use super::dielectric::{fresnel_dielectric, fresnel_refraction};
use super::microfacet::{reflect_about, Microfacet};
use super::{BsdfSample, TransportMode};
use crate::Color;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric {
    pub distr: Microfacet,
    /// Relative index of refraction: inside over outside (the side the normal points to).
    pub eta: f32,
    /// Factors on the reflected and the refracted light.
    pub specular_reflectance: Color,
    pub specular_transmittance: Color,
}

/// The generalised half vector of `wo` and `wi` on the upper hemisphere, whether the pair
/// reflects, and η (index ratio in the direction of travel, n_i/n_o).
#[inline]
fn half_vector(wo: Vec3A, wi: Vec3A, eta: f32) -> (Vec3A, bool, f32) {
    let reflect = wo.z * wi.z > 0.0;
    let eta = if wo.z > 0.0 { eta } else { 1.0 / eta };
    let m = (wo + wi * if reflect { 1.0 } else { eta }).normalize();
    (if m.z < 0.0 { -m } else { m }, reflect, eta)
}

impl RoughDielectric {
    pub fn new(distr: Microfacet, eta: f32) -> Self {
        RoughDielectric {
            distr,
            eta,
            specular_reflectance: Color::ONE,
            specular_transmittance: Color::ONE,
        }
    }

    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Color {
        if wo.z == 0.0 || wi.z == 0.0 {
            return Color::ZERO;
        }
        let (m, reflect, eta) = half_vector(wo, wi, self.eta);
        let d = self.distr.d(m);
        if d == 0.0 {
            return Color::ZERO;
        }
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        let f = fresnel_dielectric(wo_m, self.eta);
        let g = self.distr.g(wo, wi, m);
        let v = if reflect {
            f * d * g / (4.0 * wo.z.abs() * wi.z.abs())
        } else {
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (eta * eta),
                TransportMode::Importance => 1.0,
            };
            let denom = wo_m + eta * wi_m;
            (scale * (1.0 - f) * d * g * eta * eta * wo_m * wi_m / (wo.z * wi.z * denom * denom))
                .abs()
        };
        if !v.is_finite() {
            Color::ZERO
        } else if reflect {
            self.specular_reflectance * v
        } else {
            self.specular_transmittance * v
        }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let (m, reflect, eta) = half_vector(wo, wi, self.eta);
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        // Micro- and macro-surface must agree on the side of each direction.
        if wo_m * wo.z <= 0.0 || wi_m * wi.z <= 0.0 {
            return 0.0;
        }
        let dm_dwi = if reflect {
            1.0 / (4.0 * wi_m)
        } else {
            let denom = wo_m + eta * wi_m;
            eta * eta * wi_m / (denom * denom)
        };
        let wo_up = if wo.z > 0.0 { wo } else { -wo };
        let f = fresnel_dielectric(wo_m, self.eta);
        let p = self.distr.pdf_visible(wo_up, m) * if reflect { f } else { 1.0 - f } * dm_dwi.abs();
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wo_up = if wo.z > 0.0 { wo } else { -wo };
        let m = self.distr.sample_visible(wo_up, u2);
        let mut pdf = self.distr.pdf_visible(wo_up, m);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let wo_m = wo.dot(m);
        let (f, cos_t, eta_it, eta_ti) = fresnel_refraction(wo_m, self.eta);
        let reflect = u1 <= f;
        let (wi, mut weight, eta, dm_dwi) = if reflect {
            let wi = reflect_about(wo, m);
            pdf *= f;
            (wi, 1.0, 1.0, 1.0 / (4.0 * wi.dot(m)))
        } else {
            // Refraction through m (Walter et al. 2007, eq. 40).
            let wi = m * (wo_m * eta_ti + cos_t) - wo * eta_ti;
            pdf *= 1.0 - f;
            let scale = match mode {
                TransportMode::Radiance => eta_ti * eta_ti,
                TransportMode::Importance => 1.0,
            };
            let wi_m = wi.dot(m);
            let denom = wo_m + eta_it * wi_m;
            (wi, scale, eta_it, eta_it * eta_it * wi_m / (denom * denom))
        };
        // f·|cos θi|/pdf reduces to G1(wi, m) (times the radiance scale) for visible-normal
        // sampling: D, G1(wo), F and the Jacobian cancel.
        weight *= self.distr.g1(wi, m);
        pdf *= dm_dwi.abs();
        if weight.is_nan() || weight <= 0.0 || !pdf.is_finite() || pdf <= 0.0 {
            return None;
        }
        let factor = if reflect {
            self.specular_reflectance
        } else {
            self.specular_transmittance
        };
        Some(BsdfSample {
            wi,
            weight: factor * weight,
            pdf,
            specular: false,
            eta,
        })
    }
}
