//! Smooth dielectric interface (glass): exact Fresnel reflectance, refraction by Snell's law,
//! total internal reflection. Reflection or refraction is chosen with probability F and 1 − F,
//! so the sample weight is 1 (times the radiance scaling of refraction), times Mitsuba's
//! `specular_reflectance` or `specular_transmittance` factor (1 for physical realism).

use super::mirror::reflect_local;
use super::{BsdfSample, TransportMode};
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
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0; // total internal reflection
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// Fresnel reflectance together with what refraction needs, as Mitsuba's `fresnel`:
/// returns (F, cos θt, η_it, η_ti), where cos θt is signed (on the far side of the interface
/// from `cos_i`), η_it is the relative index in the direction of travel and η_ti = 1/η_it.
/// `eta` is inside over outside; a negative `cos_i` means the light arrives from inside.
#[inline]
pub fn fresnel_refraction(cos_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let (eta_it, eta_ti) = if cos_i >= 0.0 {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    let cos_t = cos_t2.max(0.0).sqrt();
    let f = fresnel_dielectric(cos_i, eta);
    (f, if cos_i >= 0.0 { -cos_t } else { cos_t }, eta_it, eta_ti)
}

/// Refracts `wi` (pointing away from the surface) through the interface with local normal +z.
/// Returns the transmitted direction and the relative index η_t/η_i actually crossed.
#[inline]
pub fn refract_local(wi: Vec3A, eta: f32) -> Option<(Vec3A, f32)> {
    let (mut cos_i, mut eta, mut n) = (wi.z, eta, Vec3A::Z);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wi / eta + (cos_i / eta - cos_t) * n, eta))
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
        let f = fresnel_dielectric(wo.z, self.eta);
        if u < f {
            return Some(BsdfSample {
                wi: reflect_local(wo),
                weight: self.specular_reflectance,
                pdf: 0.0,
                specular: true,
                eta: 1.0,
            });
        }
        let (wi, etap) = refract_local(wo, self.eta)?;
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
