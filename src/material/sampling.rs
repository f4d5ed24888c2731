//! Warping uniform numbers onto directions.

use glam::{Vec2, Vec3A};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4};

/// Concentric map of the square onto the unit disk (Shirley and Chiu, "A Low Distortion Map
/// Between Disk and Square", JGT 2(3), 1997).
#[inline]
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    let (s, c) = theta.sin_cos();
    Vec2::new(r * c, r * s)
}

/// Cosine-weighted hemisphere around +z (Malley's method): pdf = cos θ / π.
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
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
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() {
        return 1.0;
    }
    if f2 + g2 == 0.0 {
        0.0
    } else {
        f2 / (f2 + g2)
    }
}
