//! The Oren–Nayar BSDF for rough diffuse surfaces, in its qualitative form (Oren and Nayar,
//! "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994, eq. 30; as in pbrt-v3
//! §8.4.2): f = ρ/π · (A + B·max(0, cos(φi − φo))·sin α·tan β), α = max(θi, θo),
//! β = min(θi, θo), A = 1 − σ²/(2(σ² + 0.33)), B = 0.45σ²/(σ² + 0.09), σ in radians.
//! Sampled cosine-weighted, like Lambert.

use super::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use super::BsdfSample;
use crate::Color;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct OrenNayar {
    pub albedo: Color,
    a: f32,
    b: f32,
}

impl OrenNayar {
    /// `sigma`: the standard deviation of the facet slope angle, in radians.
    pub fn new(albedo: Color, sigma: f32) -> Self {
        let s2 = sigma * sigma;
        OrenNayar {
            albedo,
            a: 1.0 - s2 / (2.0 * (s2 + 0.33)),
            b: 0.45 * s2 / (s2 + 0.09),
        }
    }

    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Color::ZERO;
        }
        let sin_i = (1.0 - wi.z * wi.z).max(0.0).sqrt();
        let sin_o = (1.0 - wo.z * wo.z).max(0.0).sqrt();
        // cos(φi − φo) from the projections on the tangent plane.
        let max_cos = if sin_i > 1e-4 && sin_o > 1e-4 {
            ((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_o)).max(0.0)
        } else {
            0.0
        };
        // α is the larger angle, so sin α comes from the smaller cosine; tan β from the larger.
        let (sin_alpha, tan_beta) = if wi.z > wo.z {
            (sin_o, sin_i / wi.z)
        } else {
            (sin_i, sin_o / wo.z)
        };
        self.albedo * (FRAC_1_PI * (self.a + self.b * max_cos * sin_alpha * tan_beta))
    }
    #[inline]
    pub fn pdf(&self, _wo: Vec3A, wi: Vec3A) -> f32 {
        cosine_hemisphere_pdf(wi.z)
    }
    #[inline]
    pub fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        let wi = square_to_cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = cosine_hemisphere_pdf(wi.z);
        let weight = self.eval(wo, wi) * (wi.z / pdf);
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}
