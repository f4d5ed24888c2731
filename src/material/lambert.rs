//! The Lambertian (ideal diffuse) BSDF: f = ρ/π.

use super::sampling::{
    cosine_hemisphere, cosine_hemisphere_pdf, cosine_hemisphere_pdf_lanes,
    square_to_cosine_hemisphere,
};
use super::BsdfSample;
use crate::simd::{Float, Mask, Vector3};
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
        eval(self.albedo, wi.z)
    }
    #[inline]
    pub fn pdf(&self, _wo: Vec3A, wi: Vec3A) -> f32 {
        cosine_hemisphere_pdf(wi.z)
    }
    #[inline]
    pub fn sample(&self, _wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        let wi = square_to_cosine_hemisphere(u);
        let (pdf, ok) = (cosine_hemisphere_pdf(wi.z), !wi.z.le(0.0));
        // f·cos/pdf = (ρ/π)·cos/(cos/π) = ρ. (`then_some` compiles to fewer instructions
        // here than an early return.)
        ok.then_some(BsdfSample {
            wi,
            weight: self.albedo,
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}

/// [`Lambert::eval`] over any lanes, of albedo ρ and cos θi `cos_i`: ρ/π above the surface.
#[inline(always)]
pub fn eval<C: Vector3>(albedo: C, cos_i: C::F) -> C {
    let zero = C::F::zero();
    let f = albedo.scale(C::F::splat(FRAC_1_PI));
    C::select(cos_i.le(zero), C::new(zero, zero, zero), f)
}

/// [`Lambert::sample`] over any lanes: the direction, its pdf, and the lanes where it is
/// above the surface (the others have no sample).
#[inline(always)]
pub fn sample<V: Vector3>(ux: V::F, uy: V::F) -> (V, V::F, Mask<V>) {
    let wi: V = cosine_hemisphere(ux, uy);
    (
        wi,
        cosine_hemisphere_pdf_lanes(wi.z()),
        !wi.z().le(V::F::zero()),
    )
}
