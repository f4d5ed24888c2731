//! A thin dielectric sheet (a window pane): light is reflected about the normal or passes
//! straight through (wi = −wo, no refraction: the two parallel interfaces cancel the bending),
//! as Mitsuba 3's `thindielectric`. With the single-interface Fresnel reflectance R, the
//! inter-reflections inside the sheet sum to R' = R + T²R/(1 − R²) = 2R/(1 + R) with
//! T = 1 − R (a geometric series; see Mitsuba's plugin documentation). Reflection or
//! transmission is chosen with probability R' and 1 − R', so the weight is 1 (times
//! Mitsuba's `specular_reflectance` or `specular_transmittance` factor).

use super::dielectric::fresnel_dielectric;
use super::mirror::reflect_local;
use super::BsdfSample;
use crate::Color;
use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct ThinDielectric {
    /// Index of the sheet over that of the surrounding medium.
    pub eta: f32,
    /// Factors on the reflected and the transmitted light.
    pub specular_reflectance: Color,
    pub specular_transmittance: Color,
}

impl ThinDielectric {
    pub fn new(eta: f32) -> Self {
        ThinDielectric {
            eta,
            specular_reflectance: Color::ONE,
            specular_transmittance: Color::ONE,
        }
    }

    /// The total reflectance R' of the sheet at incidence |cos θ|.
    #[inline]
    pub fn reflectance(&self, cos_i: f32) -> f32 {
        let r = fresnel_dielectric(cos_i.abs(), self.eta);
        r * 2.0 / (1.0 + r)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u: f32) -> Option<BsdfSample> {
        let r = self.reflectance(wo.z);
        let (wi, weight) = if u <= r {
            (reflect_local(wo), self.specular_reflectance)
        } else {
            (-wo, self.specular_transmittance)
        };
        Some(BsdfSample {
            wi,
            weight,
            pdf: 0.0,
            specular: true,
            eta: 1.0,
        })
    }
}
