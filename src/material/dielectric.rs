//! Smooth dielectric interface (glass): exact Fresnel reflectance, refraction by Snell's law,
//! total internal reflection. Reflection or refraction is chosen with probability F and 1 − F,
//! so the sample weight is 1 (times the radiance scaling of refraction), times Mitsuba's
//! `specular_reflectance` or `specular_transmittance` factor (1 for physical realism).

use super::mirror::reflect_local;
use super::{BsdfSample, TransportMode};
use crate::simd::{Float, Mask, Vector3};
use crate::Color;
use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Dielectric {
    /// Relative index of refraction: inside over outside (the side the normal points to).
    pub eta: f32,
    /// Factors on the reflected and the refracted light.
    pub specular_reflectance: Color,
    pub specular_transmittance: Color,
}

/// Unpolarised Fresnel reflectance of a dielectric interface (pbrt-v4 §9.3.5,
/// `FrDielectric`). `cos_i` is measured against the normal on the outside, `eta` is
/// inside over outside; a negative `cos_i` means the light arrives from inside.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    fresnel_dielectric_lanes(cos_i, eta)
}

/// [`fresnel_dielectric`] over any lanes.
#[inline(always)]
pub fn fresnel_dielectric_lanes<T: Float>(cos_i: T, eta: T) -> T {
    let one = T::splat(1.0);
    // `f32::clamp(-1, 1)`, NaN kept.
    let c = T::select(cos_i.lt(-one), -one, cos_i);
    let c = T::select(c.gt(one), one, c);
    let inside = c.lt(T::zero());
    let eta = T::select(inside, one / eta, eta);
    let c = T::select(inside, -c, c);
    let sin2_i = one - c * c;
    let sin2_t = sin2_i / (eta * eta);
    let cos_t = (one - sin2_t).max_num(T::zero()).sqrt();
    let r_parl = (eta * c - cos_t) / (eta * c + cos_t);
    let r_perp = (c - eta * cos_t) / (c + eta * cos_t);
    let f = T::splat(0.5) * (r_parl * r_parl + r_perp * r_perp);
    // Total internal reflection.
    T::select(sin2_t.ge(one), one, f)
}

/// Fresnel reflectance together with what refraction needs, as Mitsuba's `fresnel`:
/// returns (F, cos θt, η_it, η_ti), where cos θt is signed (on the far side of the interface
/// from `cos_i`), η_it is the relative index in the direction of travel and η_ti = 1/η_it.
/// `eta` is inside over outside; a negative `cos_i` means the light arrives from inside.
#[inline]
pub fn fresnel_refraction(cos_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    fresnel_refraction_lanes(cos_i, eta)
}

/// [`fresnel_refraction`] over any lanes.
#[inline(always)]
pub fn fresnel_refraction_lanes<T: Float>(cos_i: T, eta: T) -> (T, T, T, T) {
    let (zero, one) = (T::zero(), T::splat(1.0));
    let outside = cos_i.ge(zero);
    let (eta_it, eta_ti) = (
        T::select(outside, eta, one / eta),
        T::select(outside, one / eta, eta),
    );
    let cos_t2 = one - (one - cos_i * cos_i) * eta_ti * eta_ti;
    let cos_t = cos_t2.max_num(zero).sqrt();
    let f = fresnel_dielectric_lanes(cos_i, eta);
    (f, T::select(outside, -cos_t, cos_t), eta_it, eta_ti)
}

/// Refracts `wi` (pointing away from the surface) through the interface with local normal +z.
/// Returns the transmitted direction and the relative index η_t/η_i actually crossed.
#[inline]
pub fn refract_local(wi: Vec3A, eta: f32) -> Option<(Vec3A, f32)> {
    let (w, eta, ok) = refract(wi, eta);
    if !ok {
        return None;
    }
    Some((w, eta))
}

/// [`refract_local`] over any lanes: the direction, the index crossed, and the lanes where
/// it exists (no total internal reflection).
#[inline(always)]
pub fn refract<V: Vector3>(wi: V, eta: V::F) -> (V, V::F, Mask<V>) {
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let inside = wi.z().lt(zero);
    let eta = V::F::select(inside, one / eta, eta);
    let cos_i = V::F::select(inside, -wi.z(), wi.z());
    // The normal, +z or −z (whose x and y are −0, as `-Vec3A::Z` has them).
    let nxy = V::F::select(inside, V::F::splat(-0.0), zero);
    let n = V::new(nxy, nxy, V::F::select(inside, -one, one));
    let sin2_i = (one - cos_i * cos_i).max_num(zero);
    let sin2_t = sin2_i / (eta * eta);
    let cos_t = (one - sin2_t).sqrt();
    let w = (-wi).div(eta) + n.scale(cos_i / eta - cos_t);
    (w, eta, !sin2_t.ge(one))
}

impl Dielectric {
    /// Glass of relative index `eta` with factors of 1.
    pub fn new(eta: f32) -> Self {
        Dielectric {
            eta,
            specular_reflectance: Color::ONE,
            specular_transmittance: Color::ONE,
        }
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u: f32, mode: TransportMode) -> Option<BsdfSample> {
        let (wi, reflects, etap, ok) = sample(wo, self.eta, u);
        if !ok {
            return None;
        }
        if reflects {
            return Some(BsdfSample {
                wi,
                weight: self.specular_reflectance,
                pdf: 0.0,
                specular: true,
                eta: 1.0,
            });
        }
        // Radiance is compressed into the smaller solid angle of the denser medium: it
        // scales by 1/η² across the interface (Veach 1997 §5.2; pbrt-v4 §9.5.2).
        let scale = match mode {
            TransportMode::Radiance => 1.0 / (etap * etap),
            TransportMode::Importance => 1.0,
        };
        Some(BsdfSample {
            wi,
            weight: self.specular_transmittance * scale,
            pdf: 0.0,
            specular: true,
            eta: etap,
        })
    }
}

/// [`Dielectric::sample`]'s choice over any lanes, `u` uniform: reflection with probability
/// F, else refraction. The direction, the lanes that reflect, the relative index crossed
/// where refracting, and the lanes with a sample (none where refraction would be total
/// internal reflection).
#[inline(always)]
pub fn sample<V: Vector3>(wo: V, eta: V::F, u: V::F) -> (V, Mask<V>, V::F, Mask<V>) {
    let reflects = u.lt(fresnel_dielectric_lanes(wo.z(), eta));
    let (refracted, etap, refracts) = refract(wo, eta);
    let wi = V::select(reflects, reflect_local(wo), refracted);
    (wi, reflects, etap, reflects | refracts)
}
