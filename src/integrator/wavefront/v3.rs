//! Three-component vectors in sixteen lanes, over either backend's `F` (this file is a
//! module of `simd.rs` and of `simd_avx2.rs`). Each operation is written out component by
//! component rather than through closures, which would be compiled without the caller's
//! target features (see `simd_avx2.rs`).

use super::{F, M, U};
use crate::simd::{Float, Vector3};
use std::ops::{Add, Mul, Neg, Sub};

/// Three-component vectors in sixteen lanes, for `Vec3A` (points, directions) and `Color`
/// (`glam::Vec3`) alike: every operation is component by component but the dot and cross
/// products, which follow glam's order.
#[derive(Clone, Copy)]
pub struct V3 {
    pub x: F,
    pub y: F,
    pub z: F,
}

impl V3 {
    #[inline(always)]
    pub fn splat(v: [f32; 3]) -> V3 {
        V3 {
            x: F::splat(v[0]),
            y: F::splat(v[1]),
            z: F::splat(v[2]),
        }
    }
    #[inline(always)]
    pub fn zero() -> V3 {
        V3::splat([0.0; 3])
    }
    #[inline(always)]
    pub fn load(a: &[[f32; 16]; 3]) -> V3 {
        V3 {
            x: F::load(&a[0]),
            y: F::load(&a[1]),
            z: F::load(&a[2]),
        }
    }
    #[inline(always)]
    pub fn store(self, a: &mut [[f32; 16]; 3]) {
        self.x.store(&mut a[0]);
        self.y.store(&mut a[1]);
        self.z.store(&mut a[2]);
    }
    /// glam's `cross`: x = a.y·b.z − b.y·a.z, and so on.
    #[inline(always)]
    pub fn cross(self, o: V3) -> V3 {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }
    /// Lanes where all three components equal zero (`Vec3 == Vec3::ZERO`).
    #[inline(always)]
    pub fn is_zero(self) -> M {
        let z = F::zero();
        self.x.eq(z) & self.y.eq(z) & self.z.eq(z)
    }
    /// Lanes where all three components are finite.
    #[inline(always)]
    pub fn is_finite(self) -> M {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }
    /// `Vec3::max_element`: x.max(y.max(z)) with `f32::max`.
    #[inline(always)]
    pub fn max_element(self) -> F {
        self.x.max_num2(self.y.max_num2(self.z))
    }
    /// Lane i of each component's table.
    #[inline(always)]
    pub fn lookup64(table: &[[f32; 64]; 3], idx: U) -> V3 {
        V3 {
            x: F::lookup64(&table[0], idx),
            y: F::lookup64(&table[1], idx),
            z: F::lookup64(&table[2], idx),
        }
    }
}

impl Vector3 for V3 {
    type F = F;
    #[inline(always)]
    fn new(x: F, y: F, z: F) -> V3 {
        V3 { x, y, z }
    }
    #[inline(always)]
    fn x(self) -> F {
        self.x
    }
    #[inline(always)]
    fn y(self) -> F {
        self.y
    }
    #[inline(always)]
    fn z(self) -> F {
        self.z
    }
    /// glam's `dot`: (x·x' + y·y') + z·z'.
    #[inline(always)]
    fn dot(self, o: V3) -> F {
        (self.x * o.x + self.y * o.y) + self.z * o.z
    }
    #[inline(always)]
    fn scale(self, s: F) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    fn div(self, s: F) -> V3 {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
    #[inline(always)]
    fn select(m: M, a: V3, b: V3) -> V3 {
        V3 {
            x: F::select(m, a.x, b.x),
            y: F::select(m, a.y, b.y),
            z: F::select(m, a.z, b.z),
        }
    }
    /// glam's `normalize`: each component divided by the length.
    #[inline(always)]
    fn normalize(self) -> V3 {
        self.div(self.dot(self).sqrt())
    }
    #[inline(always)]
    fn abs(self) -> V3 {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }
}

impl Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}
impl Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}
impl Mul for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}
impl Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}
