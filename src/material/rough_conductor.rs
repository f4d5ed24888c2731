//! Rough conductors: the Cook–Torrance microfacet BRDF (Beckmann or GGX distribution),
//! f = F(wo·h)·D(h)·G(wo, wi, h) / (4 cos θo cos θi) (Walter et al., "Microfacet Models for
//! Refraction through Rough Surfaces", EGSR 2007, eq. 20), complex Fresnel, sampled by
//! visible normals; as Mitsuba 3's `roughconductor` with `sample_visible = true`.
//!
//! The maths is written once over lanes ([`RoughConductor::eval_lanes`], `pdf_lanes`,
//! `sample_lanes`): one path's BSDF is `RoughConductor` (a [`Microfacet`] of either kind
//! and colours), sixteen paths' the wavefront's `RoughConductor<Ggx<F>, V3<F>>`.

use super::conductor::fresnel_conductor_rgb_lanes;
use super::microfacet::{reflect_about_lanes, Distribution, Microfacet};
use super::BsdfSample;
use crate::simd::{Float, Mask, Vector3};
use crate::Color;
use glam::{Vec2, Vec3A};

/// A rough conductor: its distribution `D` and its colours `C` (per channel: the real and
/// imaginary parts of the index of refraction, and a factor on the reflection).
#[derive(Clone, Copy, Debug)]
pub struct RoughConductor<D = Microfacet, C = Color> {
    pub distr: D,
    pub eta: C,
    pub k: C,
    pub specular_reflectance: C,
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
        self.eval_lanes(wo, wi)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        self.pdf_lanes(wo, wi)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u: Vec2) -> Option<BsdfSample> {
        let (wi, weight, pdf, ok) = self.sample_lanes(wo, u.x, u.y);
        ok.then_some(BsdfSample {
            wi,
            weight,
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}

impl<D, C: Vector3> RoughConductor<D, C> {
    /// f(wo, wi) in lanes: zero unless both directions are above the surface.
    #[inline(always)]
    pub fn eval_lanes<V>(&self, wo: V, wi: V) -> C
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let zero = C::F::zero();
        let none = C::new(zero, zero, zero);
        let mut ok = !wo.z().le(zero) & !wi.z().le(zero);
        if !C::F::any(ok) {
            return none;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.d(h);
        ok = ok & !d.eq(zero);
        if !C::F::any(ok) {
            return none;
        }
        let g = self.distr.g1(wo, h) * self.distr.g1(wi, h);
        let f = fresnel_conductor_rgb_lanes(wo.dot(h), self.eta, self.k);
        let v = (self.specular_reflectance * f).scale(d * g / (C::F::splat(4.0) * wo.z() * wi.z()));
        C::select(ok, v, none)
    }

    /// D_wo(h)/(4 wi·h) = D(h)·G1(wo, h)/(4 cos θo): the visible-normal density through the
    /// Jacobian of the reflection, |dh/dwi| = 1/(4 wi·h).
    #[inline(always)]
    pub fn pdf_lanes<V>(&self, wo: V, wi: V) -> C::F
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let zero = C::F::zero();
        let ok = !wo.z().le(zero) & !wi.z().le(zero);
        if !C::F::any(ok) {
            return zero;
        }
        let h = (wo + wi).normalize();
        let pdf = self.distr.d(h) * self.distr.g1(wo, h) / (C::F::splat(4.0) * wo.z());
        C::F::select(ok, pdf, zero)
    }

    /// A direction by the normals visible from `wo`, for the numbers (`ux`, `uy`): the
    /// direction, the weight f·cos θi/pdf, the pdf, and the lanes where there is a sample.
    #[inline(always)]
    pub fn sample_lanes<V>(&self, wo: V, ux: C::F, uy: C::F) -> (V, C, C::F, Mask<V>)
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let zero = C::F::zero();
        let above = !wo.z().le(zero);
        if !C::F::any(above) {
            return (wo, C::new(zero, zero, zero), zero, above);
        }
        let m = self.distr.sample_visible(wo, ux, uy);
        let wi = reflect_about_lanes(wo, m);
        let wo_m = wo.dot(m);
        let pdf = self.distr.pdf_visible(wo, m) / (C::F::splat(4.0) * wo_m);
        // (A NaN pdf has no sample.)
        let ok = above & pdf.gt(zero) & !wi.z().le(zero);
        // f·cos θi/pdf = F·D·G/(4 cos θo)/(D·G1(wo)/(4 cos θo)) = F·G1(wi).
        let weight = (self.specular_reflectance
            * fresnel_conductor_rgb_lanes(wo_m, self.eta, self.k))
        .scale(self.distr.g1(wi, m));
        (wi, weight, pdf, ok)
    }
}
