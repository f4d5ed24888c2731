//! Rough conductors: the Cook–Torrance microfacet BRDF (Beckmann or GGX distribution),
//! f = F(wo·h)·D(h)·G(wo, wi, h) / (4 cos θo cos θi) (Walter et al., "Microfacet Models for
//! Refraction through Rough Surfaces", EGSR 2007, eq. 20), complex Fresnel, sampled by
//! visible normals; as Mitsuba 3's `roughconductor` with `sample_visible = true`.

use super::conductor::fresnel_conductor_rgb;
use super::microfacet::{reflect_about, Microfacet};
use super::BsdfSample;
use crate::Color;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug)]
pub struct RoughConductor {
    pub distr: Microfacet,
    pub eta: Color,
    pub k: Color,
    pub specular_reflectance: Color,
}

impl RoughConductor {
    pub fn new(distr: Microfacet, eta: Color, k: Color, specular_reflectance: Color) -> Self {
        RoughConductor {
            distr,
            eta,
            k,
            specular_reflectance,
        }
    }

    /// `wo.z > 0` is required for a non-zero result (one-sided; `Material` flips two-sided
    /// materials seen from behind).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.d(h);
        if d == 0.0 {
            return Color::ZERO;
        }
        let g = self.distr.g(wo, wi, h);
        let f = fresnel_conductor_rgb(wo.dot(h), self.eta, self.k);
        self.specular_reflectance * f * (d * g / (4.0 * wo.z * wi.z))
    }

    /// D_wo(h)/(4 wi·h) = D(h)·G1(wo, h)/(4 cos θo): the visible-normal density through the
    /// Jacobian of the reflection, |dh/dwi| = 1/(4 wi·h).
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.distr.d(h) * self.distr.g1(wo, h) / (4.0 * wo.z)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let m = self.distr.sample_visible(wo, u);
        let wi = reflect_about(wo, m);
        let wo_m = wo.dot(m);
        let pdf = self.distr.pdf_visible(wo, m) / (4.0 * wo_m);
        if pdf.is_nan() || pdf <= 0.0 || wi.z <= 0.0 {
            return None;
        }
        // f·cos θi/pdf = F·D·G/(4 cos θo)/(D·G1(wo)/(4 cos θo)) = F·G1(wi).
        let weight = self.specular_reflectance
            * fresnel_conductor_rgb(wo_m, self.eta, self.k)
            * self.distr.g1(wi, m);
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}
