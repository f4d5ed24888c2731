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

//!
//! The maths is written once over lanes (`eval_lanes`, `pdf_lanes`, `sample_lanes`, of unit
//! factors: the callers apply them): one path's BSDF calls them with a [`Microfacet`], the
//! wavefront's lanes with a `microfacet::Either`.

use super::dielectric::{fresnel_dielectric_lanes, fresnel_refraction_lanes};
use super::microfacet::{reflect_about_lanes, Distribution, Microfacet};
use super::{BsdfSample, TransportMode};
use crate::simd::{Float, Mask, Vector3};
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
#[inline(always)]
fn half_vector<V: Vector3>(wo: V, wi: V, eta: V::F) -> (V, Mask<V>, V::F) {
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let reflect = (wo.z() * wi.z()).gt(zero);
    let eta = V::F::select(wo.z().gt(zero), eta, one / eta);
    let m = (wo + wi.scale(V::F::select(reflect, one, eta))).normalize();
    (V::select(m.z().lt(zero), -m, m), reflect, eta)
}

/// Lanes where x is finite.
#[inline(always)]
fn finite<T: Float>(x: T) -> T::Mask {
    x.abs().lt(T::splat(f32::INFINITY))
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
        let (v, reflect) = eval_lanes(&self.distr, self.eta, wo, wi, mode);
        if reflect {
            self.specular_reflectance * v
        } else {
            self.specular_transmittance * v
        }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        pdf_lanes(&self.distr, self.eta, wo, wi)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let s = sample_lanes(&self.distr, self.eta, wo, [u1, u2.x, u2.y], mode);
        if !s.ok {
            return None;
        }
        let factor = if s.reflect {
            self.specular_reflectance
        } else {
            self.specular_transmittance
        };
        Some(BsdfSample {
            wi: s.wi,
            weight: factor * s.weight,
            pdf: s.pdf,
            specular: false,
            eta: s.eta,
        })
    }
}

/// f(wo, wi) of unit factors in lanes, of relative index `eta` (inside over outside), and
/// the lanes where the pair reflects (whose factor is the reflectance; the others' the
/// transmittance). Zero where either direction is in the plane or the value is not finite.
#[inline(always)]
pub fn eval_lanes<V, D>(distr: &D, eta: V::F, wo: V, wi: V, mode: TransportMode) -> (V::F, Mask<V>)
where
    V: Vector3,
    D: Distribution<V>,
{
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let mut ok = !wo.z().eq(zero) & !wi.z().eq(zero);
    let (m, reflect, eta_p) = half_vector(wo, wi, eta);
    if !V::F::any(ok) {
        return (zero, reflect);
    }
    let d = distr.d(m);
    ok = ok & !d.eq(zero);
    if !V::F::any(ok) {
        return (zero, reflect);
    }
    let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
    let f = fresnel_dielectric_lanes(wo_m, eta);
    let g = distr.g1(wo, m) * distr.g1(wi, m);
    let r = f * d * g / (V::F::splat(4.0) * wo.z().abs() * wi.z().abs());
    let scale = match mode {
        TransportMode::Radiance => one / (eta_p * eta_p),
        TransportMode::Importance => one,
    };
    let denom = wo_m + eta_p * wi_m;
    let t = (scale * (one - f) * d * g * eta_p * eta_p * wo_m * wi_m
        / (wo.z() * wi.z() * denom * denom))
        .abs();
    let v = V::F::select(reflect, r, t);
    (V::F::select(ok & finite(v), v, zero), reflect)
}

/// The pdf of [`sample_lanes`] choosing `wi`, in lanes.
#[inline(always)]
pub fn pdf_lanes<V, D>(distr: &D, eta: V::F, wo: V, wi: V) -> V::F
where
    V: Vector3,
    D: Distribution<V>,
{
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let mut ok = !wo.z().eq(zero) & !wi.z().eq(zero);
    if !V::F::any(ok) {
        return zero;
    }
    let (m, reflect, eta_p) = half_vector(wo, wi, eta);
    let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
    // Micro- and macro-surface must agree on the side of each direction.
    ok = ok & !(wo_m * wo.z()).le(zero) & !(wi_m * wi.z()).le(zero);
    let denom = wo_m + eta_p * wi_m;
    let dm_dwi = V::F::select(
        reflect,
        one / (V::F::splat(4.0) * wi_m),
        eta_p * eta_p * wi_m / (denom * denom),
    );
    let wo_up = V::select(wo.z().gt(zero), wo, -wo);
    let f = fresnel_dielectric_lanes(wo_m, eta);
    let p = distr.pdf_visible(wo_up, m) * V::F::select(reflect, f, one - f) * dm_dwi.abs();
    V::F::select(ok & finite(p), p, zero)
}

/// A sample of [`sample_lanes`]: the direction, the weight f·|cos θi|/pdf of unit factors,
/// the pdf, the index crossed (1 where reflecting), the lanes that reflect and those with a
/// sample.
pub struct Sample<V: Vector3> {
    pub wi: V,
    pub weight: V::F,
    pub pdf: V::F,
    pub eta: V::F,
    pub reflect: Mask<V>,
    pub ok: Mask<V>,
}

/// A normal by the distribution of those visible from `wo` (turned to the upper side), then
/// reflection through it with probability F, else refraction: `u` the lobe's number and
/// the normal's two.
#[inline(always)]
pub fn sample_lanes<V, D>(
    distr: &D,
    eta: V::F,
    wo: V,
    [u1, ux, uy]: [V::F; 3],
    mode: TransportMode,
) -> Sample<V>
where
    V: Vector3,
    D: Distribution<V>,
{
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let mut ok = !wo.z().eq(zero);
    let none = Sample {
        wi: wo,
        weight: zero,
        pdf: zero,
        eta: one,
        reflect: ok,
        ok: !ok & ok,
    };
    if !V::F::any(ok) {
        return none;
    }
    let wo_up = V::select(wo.z().gt(zero), wo, -wo);
    let m = distr.sample_visible(wo_up, ux, uy);
    let pdf = distr.pdf_visible(wo_up, m);
    ok = ok & pdf.gt(zero);
    let wo_m = wo.dot(m);
    let (f, cos_t, eta_it, eta_ti) = fresnel_refraction_lanes(wo_m, eta);
    let reflect = u1.le(f);
    let reflected = reflect_about_lanes(wo, m);
    // Refraction through m (Walter et al. 2007, eq. 40).
    let refracted = m.scale(wo_m * eta_ti + cos_t) - wo.scale(eta_ti);
    let wi = V::select(reflect, reflected, refracted);
    let scale = match mode {
        TransportMode::Radiance => eta_ti * eta_ti,
        TransportMode::Importance => one,
    };
    let wi_m = refracted.dot(m);
    let denom = wo_m + eta_it * wi_m;
    let dm_dwi = V::F::select(
        reflect,
        one / (V::F::splat(4.0) * reflected.dot(m)),
        eta_it * eta_it * wi_m / (denom * denom),
    );
    // f·|cos θi|/pdf reduces to G1(wi, m) (times the radiance scale) for visible-normal
    // sampling: D, G1(wo), F and the Jacobian cancel.
    let weight = V::F::select(reflect, one, scale) * distr.g1(wi, m);
    let pdf = pdf * V::F::select(reflect, f, one - f) * dm_dwi.abs();
    // (NaN weights and pdfs fail the comparisons.)
    let ok = ok & weight.gt(zero) & finite(pdf) & pdf.gt(zero);
    Sample {
        wi,
        weight,
        pdf,
        eta: V::F::select(reflect, one, eta_it),
        reflect,
        ok,
    }
}
