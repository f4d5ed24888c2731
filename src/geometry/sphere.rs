//! Analytic spheres, intersected with the numerically robust quadratic.

use super::ray::{gamma, Ray};
use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
}

impl Sphere {
    /// Nearest t in (0, t_max). The discriminant is computed as r² − |f − (f·d̂)d̂|², with
    /// f = o − c, which loses no precision when the ray starts far from a small sphere
    /// (Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing
    /// Gems, ch. 7, 2019); the roots then come from the stable form q = −b − sign(b)√Δ.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let f = ray.o - self.center;
        let a = ray.d.length_squared();
        let b = -f.dot(ray.d);
        let l = f + (b / a) * ray.d;
        let disc = a * (self.radius * self.radius - l.length_squared());
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        let c = f.length_squared() - self.radius * self.radius;
        let q = b + sq.copysign(b);
        let (mut t0, mut t1) = (c / q, q / a);
        if q == 0.0 {
            // Ray through the centre from the centre itself: both roots are ±r/|d|.
            t0 = -sq / a;
            t1 = sq / a;
        }
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > 0.0 && t0 < t_max {
            Some(t0)
        } else if t1 > 0.0 && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// The hit point reprojected onto the surface, its outward unit normal and its error bound
    /// (pbrt-v4 §6.8.5: reprojection leaves an error of γ(5) of the coordinates' magnitude).
    #[inline]
    pub fn surface_point(&self, p_approx: Vec3A) -> (Vec3A, Vec3A, Vec3A) {
        let n = (p_approx - self.center).normalize();
        let p = self.center + n * self.radius;
        let err = (self.center.abs() + (n * self.radius).abs()) * gamma(5);
        (p, n, err)
    }

    pub fn area(&self) -> f32 {
        4.0 * std::f32::consts::PI * self.radius * self.radius
    }
}
