//! Orthonormal shading frames: BSDFs work in a local frame whose z axis is the normal.

use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3A,
    pub t: Vec3A,
    pub n: Vec3A,
}

impl Frame {
    /// Builds a frame around the unit vector `n` without branches on its direction:
    /// Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017.
    #[inline]
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}
