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
            let frame = &self.sphere_frames[idx[1] as usize];
            return sphere_uv(frame.local((ray.at(t) - s.center).normalize()));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{RayPacket, PACKET};
    use glam::Vec3A;

    /// A masked quad ([−1, 1]², z = 0) of opacity `opacity` (XML) in front of a larger
    /// opaque one (z = −1), both facing +z.
    fn scene(opacity: &str) -> Scene {
        let xml = format!(
            "<scene version=\"3.0.0\">\
             <shape type=\"rectangle\"><bsdf type=\"mask\">{opacity}<bsdf type=\"diffuse\"/>\
             </bsdf></shape>\
             <shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/>\
             <translate z=\"-1\"/></transform></shape></scene>"
        );
        let desc = crate::scene::xml::parse_xml(
            std::path::Path::new("mask.xml"),
            &xml,
            &Default::default(),
        )
        .unwrap();
        Scene::build(desc)
    }

    /// Rays from z = 5 to points spread over the quads (a fixed low-discrepancy set).
    fn rays(n: usize) -> impl Iterator<Item = Ray> {
        (0..n).map(move |k| {
            let x = (k as f32 + 0.5) / n as f32 * 1.8 - 0.9;
            let y = ((k as f32 * 0.618_034).fract()) * 1.8 - 0.9;
            let o = Vec3A::new(0.1, -0.2, 5.0);
            Ray::new(o, Vec3A::new(x, y, 0.0) - o)
        })
    }

    /// (Fraction of rays whose closest hit is the masked quad, fraction blocked before the
    /// opaque one, fraction blocked in packets.)
    fn seen_fractions(s: &Scene, n: usize) -> (f64, f64, f64) {
        let (mut front, mut blocked, mut packed) = (0, 0, 0);
        let all: Vec<Ray> = rays(n).collect();
        for r in &all {
            let si = s.intersect(r).expect("every ray hits a quad");
            front += (si.p.z.abs() < 1e-3) as u32;
            blocked += s.occluded(r, 1.1) as u32;
        }
        // The packets share an origin: all the rays above do.
        for chunk in all.chunks(PACKET) {
            let mut pk = RayPacket {
                o: chunk[0].o,
                d: [[0.0; PACKET]; 3],
                t_max: [0.0; PACKET],
            };
            for (l, r) in chunk.iter().enumerate() {
                for (c, v) in r.d.to_array().into_iter().enumerate() {
                    pk.d[c][l] = v;
                }
                pk.t_max[l] = 1.1;
            }
            let active = (1u32 << chunk.len()) - 1;
            packed += s.occluded_packet(&pk, active).count_ones();
        }
        let n = n as f64;
        (front as f64 / n, blocked as f64 / n, packed as f64 / n)
    }

    #[test]
    fn opacity_zero_is_invisible_and_one_opaque() {
        let s = scene("<float name=\"opacity\" value=\"0\"/>");
        assert!(s.masked);
        assert_eq!(seen_fractions(&s, 2000), (0.0, 0.0, 0.0));
        // Opacity 1 is no mask at all.
        let s = scene("<float name=\"opacity\" value=\"1\"/>");
        assert!(!s.masked);
        assert_eq!(seen_fractions(&s, 2000), (1.0, 1.0, 1.0));
    }

    #[test]
    fn opacity_is_the_fraction_of_rays_that_see_the_surface() {
        let s = scene("<float name=\"opacity\" value=\"0.3\"/>");
        let n = 20_000;
        let (front, blocked, packed) = seen_fractions(&s, n);
        // Binomial noise: σ = √(α(1 − α)/n) ≈ 0.0032; five of them.
        let tol = 5.0 * (0.3f64 * 0.7 / n as f64).sqrt();
        for f in [front, blocked, packed] {
            assert!((f - 0.3).abs() < tol, "{f} (tolerance {tol})");
        }
        // The same ray makes the same choice every time.
        let again = seen_fractions(&s, n);
        assert_eq!((front, blocked, packed), again);
    }

    #[test]
    fn hash_is_uniform() {
        let n = 100_000;
        let mut bins = [0u32; 10];
        for r in rays(n) {
            bins[(hash_unit(&r, 7) * 10.0) as usize] += 1;
        }
        // χ² with 9 degrees of freedom: 27.9 is its 0.999 quantile.
        let e = n as f64 / 10.0;
        let chi2: f64 = bins.iter().map(|&b| (b as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 27.9, "{bins:?}: χ² = {chi2}");
    }
}
