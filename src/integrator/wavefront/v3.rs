//! What the wavefront adds to [`crate::simd::V3`] over either backend's `F` (this file is a
//! module of `simd.rs` and of `simd_avx2.rs`): loads, stores and table lookups.

use super::{F, M, U};

/// Three-component vectors in sixteen lanes.
pub type V3 = crate::simd::V3<F>;

impl V3 {
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
    /// The lanes, by component.
    #[inline(always)]
    pub fn to_arrays(self) -> [[f32; 16]; 3] {
        let mut a = [[0.0; 16]; 3];
        self.store(&mut a);
        a
    }
    /// Lanes where all three components are finite.
    #[inline(always)]
    pub fn is_finite(self) -> M {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
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
