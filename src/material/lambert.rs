//! The Lambertian (ideal diffuse) BSDF: f = ρ/π.

use super::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use super::BsdfSample;
use crate::Color;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct Lambert {
    pub albedo: Color,
}

impl Lambert {
    /// `wo` and `wi` are in the local frame with `wo.z > 0`.
    #[inline]
    pub fn eval(&self, _wo: Vec3A, wi: Vec3A) -> Color {
        if wi.z <= 0.0 {
            return Color::ZERO;
        }
        self.albedo * FRAC_1_PI
    }
    #[inline]
    pub fn pdf(&self, _wo: Vec3A, wi: Vec3A) -> f32 {
        cosine_hemisphere_pdf(wi.z)
    }
    #[inline]
    pub fn sample(&self, _wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        let wi = square_to_cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        // f·cos/pdf = (ρ/π)·cos/(cos/π) = ρ.
        Some(BsdfSample {
            wi,
            weight: self.albedo,
            pdf: cosine_hemisphere_pdf(wi.z),
            specular: false,
            eta: 1.0,
        })
    }
}
