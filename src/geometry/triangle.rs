//! Triangles and the Möller–Trumbore ray–triangle test.

use super::ray::{gamma, Ray};
use glam::{DVec3, Vec3A};

/// A triangle stored by its vertices (Möller and Trumbore, "Fast, Minimum Storage
/// Ray/Triangle Intersection", JGT 2(1), 1997, derive the edges on the fly).
///
/// Vertices rather than precomputed edges: two triangles sharing an edge then share its exact
/// endpoints, which the watertightness fallback in [`Triangle::intersect`] relies on.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    pub p0: Vec3A,
    pub p1: Vec3A,
    pub p2: Vec3A,
}

/// Barycentric coordinates closer than this to an edge are recomputed in f64.
const EDGE_EPS: f32 = 1e-4;

impl Triangle {
    pub fn new(p0: Vec3A, p1: Vec3A, p2: Vec3A) -> Self {
        Triangle { p0, p1, p2 }
    }

    #[inline]
    pub fn vertices(&self) -> [Vec3A; 3] {
        [self.p0, self.p1, self.p2]
    }

    /// Returns (t, u, v) of the hit with t in (0, t_max); u and v are the barycentric weights
    /// of the second and third vertex. Hits on either face count.
    ///
    /// In f32, Möller–Trumbore evaluates an edge shared by two triangles with different
    /// expressions, so a ray through the edge can miss both (about 3 % of rays aimed at a
    /// quad's diagonal did). Near an edge the test is therefore repeated in f64 from the same
    /// f32 vertices: differences and products of f32 values are exact in f64, so both
    /// triangles see the edge on the same side except for rays within ~1e-16 of it.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let e1 = self.p1 - self.p0;
        let e2 = self.p2 - self.p0;
        let p = ray.d.cross(e2);
        let det = e1.dot(p);
        let inv_det = 1.0 / det;
        let s = ray.o - self.p0;
        let u = s.dot(p) * inv_det;
        let q = s.cross(e1);
        let v = ray.d.dot(q) * inv_det;
        // The fast path decides clear hits and misses; anything near an edge (or a ray nearly
        // in the triangle's plane, where inv_det is huge or infinite) goes to f64.
        if u.min(v).min(1.0 - u - v) > EDGE_EPS {
            let t = e2.dot(q) * inv_det;
            return (t > 0.0 && t < t_max).then_some((t, u, v));
        }
        if u < -EDGE_EPS || v < -EDGE_EPS || u + v > 1.0 + EDGE_EPS {
            return None;
        }
        self.intersect_f64(ray, t_max)
    }

    #[cold]
    fn intersect_f64(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let d = |v: Vec3A| DVec3::new(v.x as f64, v.y as f64, v.z as f64);
        let (p0, p1, p2) = (d(self.p0), d(self.p1), d(self.p2));
        let (o, dir) = (d(ray.o), d(ray.d));
        let (e1, e2) = (p1 - p0, p2 - p0);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let s = o - p0;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = (e2.dot(q) / det) as f32;
        (t > 0.0 && t < t_max).then_some((t, u as f32, v as f32))
    }

    /// Unnormalised geometric normal (right-hand rule over p0, p1, p2).
    #[inline]
    pub fn normal_unnormalized(&self) -> Vec3A {
        (self.p1 - self.p0).cross(self.p2 - self.p0)
    }

    pub fn area(&self) -> f32 {
        0.5 * self.normal_unnormalized().length()
    }

    /// The point with barycentric weights (1-u-v, u, v) and its floating-point error bound
    /// (pbrt-v4 §6.8.4: γ(7) times the sum of the magnitudes of the weighted vertices).
    #[inline]
    pub fn point(&self, u: f32, v: f32) -> (Vec3A, Vec3A) {
        let w = 1.0 - u - v;
        let p = self.p0 * w + self.p1 * u + self.p2 * v;
        let err = ((self.p0 * w).abs() + (self.p1 * u).abs() + (self.p2 * v).abs()) * gamma(7);
        (p, err)
    }

    /// Uniform point on the triangle from two uniform numbers (the square-root
    /// parameterisation, Shirley and Chiu 1997), returned as barycentric (u, v).
    #[inline]
    pub fn sample_uniform(u: glam::Vec2) -> (f32, f32) {
        let su = u.x.sqrt();
        (1.0 - su, u.y * su)
    }
}
