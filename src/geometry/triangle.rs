//! Triangles and the Möller–Trumbore ray–triangle test.

use super::ray::{gamma, Ray};
use glam::Vec3A;

/// A triangle stored for intersection: one vertex and two edges (Möller and Trumbore,
/// "Fast, Minimum Storage Ray/Triangle Intersection", JGT 2(1), 1997).
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    pub v0: Vec3A,
    pub e1: Vec3A,
    pub e2: Vec3A,
}

impl Triangle {
    pub fn new(p0: Vec3A, p1: Vec3A, p2: Vec3A) -> Self {
        Triangle {
            v0: p0,
            e1: p1 - p0,
            e2: p2 - p0,
        }
    }

    #[inline]
    pub fn vertices(&self) -> [Vec3A; 3] {
        [self.v0, self.v0 + self.e1, self.v0 + self.e2]
    }

    /// Returns (t, u, v) of the nearest hit with t in (0, t_max); u and v are the barycentric
    /// weights of the second and third vertex. Hits on either face count.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let p = ray.d.cross(self.e2);
        let det = self.e1.dot(p);
        // A ray in the triangle's plane (det = 0) cannot hit it; tiny determinants are
        // kept, so thin triangles seen edge-on still work.
        if det == 0.0 {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = ray.o - self.v0;
        let u = s.dot(p) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = ray.d.dot(q) * inv_det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv_det;
        if t > 0.0 && t < t_max {
            Some((t, u, v))
        } else {
            None
        }
    }

    /// Unnormalised geometric normal (right-hand rule over v0, v1, v2).
    #[inline]
    pub fn normal_unnormalized(&self) -> Vec3A {
        self.e1.cross(self.e2)
    }

    pub fn area(&self) -> f32 {
        0.5 * self.normal_unnormalized().length()
    }

    /// The point with barycentric weights (1-u-v, u, v) and its floating-point error bound
    /// (pbrt-v4 §6.8.4: γ(7) times the sum of the magnitudes of the weighted vertices).
    #[inline]
    pub fn point(&self, u: f32, v: f32) -> (Vec3A, Vec3A) {
        let [p0, p1, p2] = self.vertices();
        let w = 1.0 - u - v;
        let p = p0 * w + p1 * u + p2 * v;
        let err = ((p0 * w).abs() + (p1 * u).abs() + (p2 * v).abs()) * gamma(7);
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
