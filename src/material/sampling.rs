//! Warping uniform numbers onto directions.

use crate::simd::{Float, Vector3};
use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

/// Concentric map of the square onto the unit disk (Shirley and Chiu, "A Low Distortion Map
/// Between Disk and Square", JGT 2(3), 1997).
#[inline]
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    // The one-lane form branches where `disk_concentric` selects: the same values, but the
    // selects made the scalar path 2–4 % slower (256² Cornell box and TNCG15 room, one
    // thread, alternating runs), so this form stays until a generic one compiles as well.
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (o.y / o.x));
        Vec2::new(o.x * c, o.x * s)
    } else {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (o.x / o.y));
        Vec2::new(o.y * s, o.y * c)
    }
}

/// [`square_to_disk_concentric`] over any lanes: (x, y) on the disk.
#[inline(always)]
pub fn disk_concentric<T: Float>(ux: T, uy: T) -> (T, T) {
    let (zero, one, two) = (T::zero(), T::splat(1.0), T::splat(2.0));
    let (ox, oy) = (two * ux - one, two * uy - one);
    let centre = ox.eq(zero) & oy.eq(zero);
    // θ = φ in the wedges around ±x and θ = π/2 − φ in those around ±y, with φ within
    // ±π/4 either way: sin and cos of φ (swapped for the second) by polynomials.
    let xmaj = ox.abs().gt(oy.abs());
    let r = T::select(xmaj, ox, oy);
    let ratio = T::select(xmaj, oy, ox) / r;
    let (s, c) = sin_cos_quarter_lanes(T::splat(FRAC_PI_4) * ratio);
    let x = T::select(centre, zero, r * T::select(xmaj, c, s));
    let y = T::select(centre, zero, r * T::select(xmaj, s, c));
    (x, y)
}

/// sin x and cos x for |x| ≤ π/4, within about an ulp: the minimax polynomials of Cephes'
/// `sinf` and `cosf` (Moshier, *Methods and Programs for Mathematical Functions*, 1989) for
/// that interval, without the argument reduction a library call pays for. The concentric map
/// calls it once a diffuse bounce, where libm's `sincosf` cost 3 % of a Cornell box render.
#[inline(always)]
pub fn sin_cos_quarter(x: f32) -> (f32, f32) {
    sin_cos_quarter_lanes(x)
}

/// [`sin_cos_quarter`] over any lanes.
#[inline(always)]
pub fn sin_cos_quarter_lanes<T: Float>(x: T) -> (T, T) {
    let k = T::splat;
    let z = x * x;
    let s = ((((k(-1.951_529_6e-4) * z + k(8.332_161e-3)) * z - k(1.666_665_5e-1)) * z) * x) + x;
    let c = ((((k(2.443_315_7e-5) * z - k(1.388_731_6e-3)) * z + k(4.166_664_6e-2)) * z) * z
        - k(0.5) * z)
        + k(1.0);
    (s, c)
}

/// Cosine-weighted hemisphere around +z (Malley's method): pdf = cos θ / π.
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

/// [`square_to_cosine_hemisphere`] over any lanes.
#[inline(always)]
pub fn cosine_hemisphere<V: Vector3>(ux: V::F, uy: V::F) -> V {
    let (x, y) = disk_concentric(ux, uy);
    let z = (V::F::splat(1.0) - (x * x + y * y))
        .max_num(V::F::zero())
        .sqrt();
    V::new(x, y, z)
}

#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cosine_hemisphere_pdf_lanes(cos_theta)
}

/// [`cosine_hemisphere_pdf`] over any lanes.
#[inline(always)]
pub fn cosine_hemisphere_pdf_lanes<T: Float>(cos_theta: T) -> T {
    cos_theta.max_num(T::zero()) * T::splat(FRAC_1_PI)
}

/// Uniform direction on the whole sphere: pdf = 1/(4π).
#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * std::f32::consts::PI * u.y).sin_cos();
    Vec3A::new(r * c, r * s, z)
}

/// Power heuristic with β = 2 (Veach, PhD thesis, 1997, eq. 9.13), with the sample counts
/// folded into the pdfs by the caller.
#[inline]
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    power_heuristic_lanes(f, g)
}

/// [`power_heuristic`] over any lanes.
#[inline(always)]
pub fn power_heuristic_lanes<T: Float>(f: T, g: T) -> T {
    let (f2, g2) = (f * f, g * g);
    let sum = f2 + g2;
    let r = T::select(sum.eq(T::zero()), T::zero(), f2 / sum);
    T::select(f2.abs().eq(T::splat(f32::INFINITY)), T::splat(1.0), r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomials against f64 sin and cos over the whole interval, densely: within
    /// 1.5 ulp of 1 (the largest value) everywhere.
    #[test]
    fn sin_cos_quarter_is_accurate() {
        let n = 100_000;
        let mut worst = 0.0f64;
        for i in 0..=n {
            let x =
                (-FRAC_PI_4 + 2.0 * FRAC_PI_4 * i as f32 / n as f32).clamp(-FRAC_PI_4, FRAC_PI_4);
            let (s, c) = sin_cos_quarter(x);
            let xd = x as f64;
            worst = worst
                .max((s as f64 - xd.sin()).abs())
                .max((c as f64 - xd.cos()).abs());
        }
        assert!(worst < 1.5 * f32::EPSILON as f64, "worst error {worst:e}");
    }

    /// The concentric map: the disk point has the radius and angle Shirley and Chiu's formula
    /// gives (evaluated in f64), for points of every wedge.
    #[test]
    fn concentric_map_matches_the_formula() {
        let mut rng = crate::sampler::Sampler::from_state(7, 1);
        for _ in 0..10_000 {
            let u = rng.next_2d();
            let d = square_to_disk_concentric(u);
            let (x, y) = (2.0 * u.x as f64 - 1.0, 2.0 * u.y as f64 - 1.0);
            let (r, t) = if x.abs() > y.abs() {
                (x, std::f64::consts::FRAC_PI_4 * (y / x))
            } else {
                (
                    y,
                    std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (x / y),
                )
            };
            let e = (d.x as f64 - r * t.cos())
                .abs()
                .max((d.y as f64 - r * t.sin()).abs());
            assert!(e < 4.0 * f32::EPSILON as f64, "{u:?}: {d:?} off by {e:e}");
        }
    }
}
