//! The perfect mirror: a delta BSDF that reflects a fraction `reflectance` of the light.

use super::BsdfSample;
use crate::simd::Vector3;
use crate::Color;
use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Mirror {
    pub reflectance: Color,
}

/// The mirror direction of `wo` about the local normal +z, over any lanes.
#[inline(always)]
pub fn reflect_local<V: Vector3>(wo: V) -> V {
    V::new(-wo.x(), -wo.y(), wo.z())
}

impl Mirror {
    #[inline]
    pub fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        Some(BsdfSample {
            wi: reflect_local(wo),
            weight: self.reflectance,
            pdf: 0.0,
            specular: true,
            eta: 1.0,
        })
    }
}
