//! Opacity (Mitsuba 3's `mask` BSDF): a surface of opacity α is seen by a ray with
//! probability α, and passed through otherwise.
//!
//! As pbrt-v4 does for alpha textures (`GeometricPrimitive::Intersect`), the choice is made
//! where the ray meets the primitive, inside the BVH traversal: a rejected hit is no hit, so
//! the closest-hit search goes on behind it and a shadow ray is not blocked by it. The
//! choice is a hash of the ray and the primitive, not a sampler draw: the same ray always
//! makes the same choice, whatever the thread, pass or packet that traces it, and the
//! integrators need no change. In expectation this is Mitsuba's mask, whose BSDF is α times
//! the nested one plus a null (pass-through) lobe of weight 1 − α. (Unlike Mitsuba's null
//! lobe, passing does not count as a path vertex for `max_depth`.)
//!
//! Scenes without any opacity keep the unmasked traversal (`Scene::masked` is false); masked
//! scenes leave the brute-force set of [`crate::accel::flat`] and the wavefront, whose
//! kernels test triangles only.

use super::{sphere_uv, Scene, META_ATTRS, META_MATERIAL, SPHERE};
use crate::geometry::Ray;
use crate::material::normal_map::luminance;
use crate::sampler::mix64;
use glam::Vec2;

impl Scene {
    /// Whether primitive `i`'s material has an opacity.
    #[inline]
    pub(super) fn has_opacity(&self, i: usize) -> bool {
        let m = (self.meta[i] & META_MATERIAL) as usize;
        self.materials[m].opacity.is_some()
    }

    /// Whether `ray` sees its hit of primitive `i` at (u, v, t) (as [`Scene::hit`] returns
    /// them): always where the material has no opacity, else with probability α.
    #[inline]
    pub(super) fn seen(&self, ray: &Ray, i: usize, u: f32, v: f32, t: f32) -> bool {
        let meta = self.meta[i];
        let Some(tex) = self.materials[(meta & META_MATERIAL) as usize].opacity else {
            return true;
        };
        let alpha = opacity(self.textures[tex as usize].eval(self.hit_uv(ray, i, u, v, t)));
        alpha >= 1.0 || (alpha > 0.0 && hash_unit(ray, i) < alpha)
    }

    /// The texture coordinates of primitive `i`'s hit, as [`Scene::intersect`] gives them.
    fn hit_uv(&self, ray: &Ray, i: usize, u: f32, v: f32, t: f32) -> Vec2 {
        let idx = self.tris[i];
        if idx[0] == SPHERE {
            let s = &self.spheres[idx[1] as usize];
            return sphere_uv((ray.at(t) - s.center).normalize());
        }
        let uvs = if self.meta[i] & META_ATTRS != 0 {
            self.vertex_uvs(idx)
        } else {
            None
        };
        match uvs {
            Some([t0, t1, t2]) => t0 * (1.0 - u - v) + t1 * u + t2 * v,
            None => Vec2::new(u, v),
        }
    }
}

/// A texture value read as opacity: its luminance (Mitsuba's `eval_1`), clamped to [0, 1].
#[inline]
pub fn opacity(c: crate::Color) -> f32 {
    luminance(c).clamp(0.0, 1.0)
}

/// A number in [0, 1) from the bits of the ray's origin and direction and the primitive.
#[inline]
pub fn hash_unit(ray: &Ray, prim: usize) -> f32 {
    let b = |x: f32| x.to_bits() as u64;
    let mut h = mix64(b(ray.o.x) | b(ray.o.y) << 32);
    h = mix64(h ^ (b(ray.o.z) | b(ray.d.x) << 32));
    h = mix64(h ^ (b(ray.d.y) | b(ray.d.z) << 32));
    h = mix64(h ^ prim as u64);
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}
