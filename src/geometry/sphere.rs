//! Analytic spheres, intersected with the numerically robust quadratic.

use super::ray::{gamma, Ray};
use crate::simd::{Float, Mask, Vector3, V3};
use glam::{Vec3A, Vec4};

#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
}

/// Texture coordinates of the point of a sphere with unit normal `n`: (φ/2π, θ/π), φ the
/// azimuth from +x in [0, 2π), θ the angle from +z (Mitsuba's sphere).
#[inline]
pub fn uv_of_normal(n: Vec3A) -> glam::Vec2 {
    let phi = n.y.atan2(n.x);
    let phi = if phi < 0.0 {
        phi + std::f32::consts::TAU
    } else {
        phi
    };
    glam::Vec2::new(
        phi / std::f32::consts::TAU,
        n.z.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
    )
}

impl Sphere {
    /// Nearest t in (0, t_max). The discriminant is computed as r² − |f − (f·d̂)d̂|², with
    /// f = o − c, which loses no precision when the ray starts far from a small sphere
    /// (Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing
    /// Gems, ch. 7, 2019); the roots then come from the stable form q = −b − sign(b)√Δ.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let r2 = self.radius * self.radius;
        let (hit, t) = intersect_lanes(self.center, r2, ray.o, ray.d, t_max);
        if !hit {
            return None;
        }
        Some(t)
    }

    /// Whether [`Sphere::intersect`] finds a hit for each of four rays from one origin `o`
    /// (directions `d` by axis, a lane per ray), as a bit mask: the same IEEE operations in
    /// the same order, lane by lane (glam's dot products sum (x + y) + z), so each bit is
    /// `intersect(..).is_some()` for its ray. For shadow-ray packets.
    #[inline(always)]
    pub fn occludes4(&self, o: Vec3A, d: [Vec4; 3], t_max: Vec4) -> u32 {
        let r2 = Vec4::splat(self.radius * self.radius);
        let (o, c) = (V3::broadcast(o), V3::broadcast(self.center));
        let d = V3::new(d[0], d[1], d[2]);
        intersect_lanes(c, r2, o, d, t_max).0.bitmask()
    }

    /// The hit point reprojected onto the surface, its outward unit normal and its error bound
    /// (pbrt-v4 §6.8.5: reprojection leaves an error of γ(5) of the coordinates' magnitude).
    #[inline]
    pub fn surface_point(&self, p_approx: Vec3A) -> (Vec3A, Vec3A, Vec3A) {
        surface_point(self.center, self.radius, p_approx)
    }

    pub fn area(&self) -> f32 {
        4.0 * std::f32::consts::PI * self.radius * self.radius
    }
}

/// [`Sphere::intersect`] over any lanes, for the sphere of `center` and squared radius `r2`:
/// the lanes that hit in (0, `t_max`), and there the nearer such root.
#[inline(always)]
pub fn intersect_lanes<V: Vector3>(
    center: V,
    r2: V::F,
    o: V,
    d: V,
    t_max: V::F,
) -> (Mask<V>, V::F) {
    let zero = V::F::zero();
    let f = o - center;
    let a = d.dot(d);
    let b = -f.dot(d);
    let l = f + d.scale(b / a);
    let disc = a * (r2 - l.dot(l));
    // A negative discriminant misses (a NaN one fails every comparison below).
    let real = !disc.lt(zero);
    if !V::F::any(real) {
        return (real, zero);
    }
    let sq = disc.sqrt();
    let c = f.dot(f) - r2;
    let q = b + sq.copysign(b);
    let (mut t0, mut t1) = (c / q, q / a);
    // q = 0: a ray through the centre from the centre itself; both roots are ±r/|d|.
    let centre = q.eq(zero);
    if V::F::any(centre) {
        t0 = V::F::select(centre, -sq / a, t0);
        t1 = V::F::select(centre, sq / a, t1);
    }
    let swap = t0.gt(t1);
    let (t0, t1) = (V::F::select(swap, t1, t0), V::F::select(swap, t0, t1));
    let first = t0.gt(zero) & t0.lt(t_max);
    let second = t1.gt(zero) & t1.lt(t_max);
    (real & (first | second), V::F::select(first, t0, t1))
}

/// [`Sphere::surface_point`] over any lanes, for the sphere of `center` and `radius`.
#[inline(always)]
pub fn surface_point<V: Vector3>(center: V, radius: V::F, p_approx: V) -> (V, V, V) {
    let n = (p_approx - center).normalize();
    let p = center + n.scale(radius);
    let err = (center.abs() + n.scale(radius).abs()).scale(V::F::splat(gamma(5)));
    (p, n, err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Sampler;

    /// Four rays at a time agree with one at a time, bit for bit: origins outside, on and
    /// inside the sphere, directions at it, grazing it (the discriminant's sign decides),
    /// through its centre (q = 0), unnormalised, and random limits.
    #[test]
    fn occludes4_matches_intersect() {
        let mut rng = Sampler::from_state(3, 5);
        let mut u = || rng.next_1d();
        let (mut hits, mut n) = (0, 0);
        for i in 0..20_000 {
            let s = Sphere {
                center: Vec3A::new(u() - 0.5, u() - 0.5, u() - 0.5) * 4.0,
                radius: 0.1 + u() * 2.0,
            };
            let dir = Vec3A::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            let o = match i % 4 {
                0 => s.center + dir * s.radius * (1.0 + 3.0 * u()),
                1 => s.center + dir * s.radius,
                2 => s.center + dir * s.radius * u(),
                _ => s.center,
            };
            let mut d = [Vec4::ZERO; 3];
            let mut t_max = [0.0f32; 4];
            for lane in 0..4 {
                let side = Vec3A::new(u() - 0.5, u() - 0.5, u() - 0.5)
                    .cross(dir)
                    .normalize();
                // Aim at points near the silhouette (grazing), on it and past it.
                let target = s.center + side * s.radius * (0.9 + 0.2 * u());
                let v = (target - o) * (0.5 + 2.0 * u());
                for (k, x) in v.to_array().into_iter().enumerate() {
                    d[k][lane] = x;
                }
                t_max[lane] = if u() < 0.5 { f32::INFINITY } else { 3.0 * u() };
            }
            let got = s.occludes4(o, d, Vec4::from_array(t_max));
            for (lane, &t) in t_max.iter().enumerate() {
                let ray = Ray::new(o, Vec3A::new(d[0][lane], d[1][lane], d[2][lane]));
                let want = s.intersect(&ray, t).is_some();
                assert_eq!(
                    got >> lane & 1 == 1,
                    want,
                    "sphere {s:?}, {ray:?}, t_max {t}"
                );
                hits += want as u32;
                n += 1;
            }
        }
        // Both answers occur often, so the comparison means something.
        assert!(hits > n / 10 && hits < n * 9 / 10, "{hits} of {n}");
    }
}
