//! Geometry: rays, shading frames, triangles (Möller–Trumbore), spheres and meshes.

pub mod frame;
pub mod mesh;
pub mod ray;
pub mod sphere;
pub mod triangle;
#[cfg(target_arch = "x86_64")]
pub mod triangle_block;

pub use frame::Frame;
pub use ray::Ray;
pub use sphere::Sphere;
pub use triangle::Triangle;

use glam::{Vec3A, Vec4};

/// The square root of each lane (glam's `Vec4` has none), correctly rounded as `f32::sqrt`
/// is: one SSE instruction on x86-64, the same values elsewhere.
#[inline(always)]
pub(crate) fn sqrt4(x: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE is part of x86-64.
        Vec4::from(unsafe { std::arch::x86_64::_mm_sqrt_ps(x.into()) })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        x.map(f32::sqrt)
    }
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug)]
pub struct Aabb {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline]
    pub fn from_points(pts: &[Vec3A]) -> Self {
        let mut b = Aabb::EMPTY;
        for &p in pts {
            b.grow_point(p);
        }
        b
    }
    #[inline]
    pub fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    #[inline]
    pub fn grow(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }
    #[inline]
    pub fn union(a: &Aabb, b: &Aabb) -> Aabb {
        Aabb {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
        }
    }
    #[inline]
    pub fn centroid(&self) -> Vec3A {
        (self.min + self.max) * 0.5
    }
    #[inline]
    pub fn extent(&self) -> Vec3A {
        (self.max - self.min).max(Vec3A::ZERO)
    }
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.min.x > self.max.x {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
}
