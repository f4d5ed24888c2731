//! Rays and robust spawning of secondary rays.
//!
//! Secondary rays must not re-hit the surface they leave, at any scene scale. Following
//! pbrt-v4 (Pharr, Jakob, Humphreys, *Physically Based Rendering*, 4th ed., §6.8.6), every hit
//! point carries a conservative bound on its floating-point error; a new ray starts at the hit
//! point pushed along the geometric normal by that bound (so the offset scales with the
//! magnitude of the coordinates, never a fixed epsilon), then rounded away from the surface.

use crate::simd::{Float, Vector3};
use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3A,
    pub d: Vec3A,
}

impl Ray {
    #[inline]
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        Ray { o, d }
    }
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.o + self.d * t
    }
}

/// γ(n) = nε/(1−nε), the bound on relative error of n floating-point operations
/// (pbrt-v4 eq. 6.11, Higham 2002).
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

/// pbrt-v4 `OffsetRayOrigin`: moves `p` (with error bound `p_err`) off the surface with
/// geometric normal `n` to the side that `w` points to.
///
/// pbrt pushes `p` by the bound's projection d = |n|·p_err along n and then rounds each
/// coordinate one ulp away from the surface, so that rounding `p + offset` cannot pull the
/// origin back into the error region. Here the push is 2d instead, with no rounding step
/// (branch-free, and this runs for every shadow ray): rounding the sum moves the point by at
/// most half an ulp per coordinate, at most γ(1)·Σ|nᵢ||pᵢ| along n, while every shape's
/// bound has d ≥ γ(5)·Σ|nᵢ||pᵢ| (triangles γ(7), spheres γ(5)), so the extra d covers it.
#[inline(always)]
pub fn offset_ray_origin<V: Vector3>(p: V, p_err: V, n: V, w: V) -> V {
    offset_by(p, offset_push(n, p_err), n, w)
}

/// [`offset_ray_origin`]'s push off the surface: n·2(|n|·p_err).
#[inline(always)]
pub fn offset_push<V: Vector3>(n: V, p_err: V) -> V {
    n.scale(V::F::splat(2.0) * n.abs().dot(p_err))
}

/// [`offset_ray_origin`] with its push `off`: `p` moved to the side of `n` that `w` points to.
#[inline(always)]
pub fn offset_by<V: Vector3>(p: V, off: V, n: V, w: V) -> V {
    V::select(w.dot(n).lt(V::F::zero()), p - off, p + off)
}

/// Fraction of a shadow ray's length left unchecked at its far end, so the ray does not
/// report the light's own surface as a blocker (pbrt-v4's `ShadowEpsilon`).
pub const SHADOW_EPSILON: f32 = 1e-4;
