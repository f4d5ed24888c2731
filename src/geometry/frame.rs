//! Orthonormal shading frames: BSDFs work in a local frame whose z axis is the normal.

use crate::simd::{Float, Vector3};
use glam::Vec3A;

/// A frame of vectors `V`: glam's `Vec3A` for one path, or lanes of them
/// ([`crate::simd`]).
#[derive(Clone, Copy, Debug)]
pub struct Frame<V = Vec3A> {
    pub s: V,
    pub t: V,
    pub n: V,
}

impl<V: Vector3> Frame<V> {
    /// Builds a frame around the unit vector `n` without branches on its direction:
    /// Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017.
    #[inline(always)]
    pub fn from_normal(n: V) -> Self {
        let (x, y, z) = (n.x(), n.y(), n.z());
        let one = V::F::splat(1.0);
        let sign = one.copysign(z);
        let a = V::F::splat(-1.0) / (sign + z);
        let b = x * y * a;
        let s = V::new(one + sign * x * x * a, sign * b, -sign * x);
        let t = V::new(b, sign + y * y * a, -y);
        Frame { s, t, n }
    }
    #[inline(always)]
    pub fn to_local(&self, v: V) -> V {
        V::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    #[inline(always)]
    pub fn to_world(&self, v: V) -> V {
        self.s.scale(v.x()) + self.t.scale(v.y()) + self.n.scale(v.z())
    }
}
