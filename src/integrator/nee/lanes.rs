//! The lane types the planar light batch ([`super::planar`]) is written over: glam's `Vec4`
//! (four lanes, SSE2 on x86-64, NEON on AArch64) and, on x86-64 CPUs that have it, the
//! eight-lane AVX vector of [`crate::simd::avx`]. Every operation is the IEEE one of the same name lane by lane
//! (no fused multiply-add, no approximations), so a lane's value does not depend on the
//! width it was computed at.

use crate::simd::Float;
use glam::{BVec4A, Vec4};

/// A vector of `N` f32 lanes ([`Float`]) that loads, stores and counts.
pub(super) trait Lanes: Float {
    const N: usize;
    /// Lanes `0..N` of `s`.
    fn load(s: &[f32]) -> Self;
    /// Into `s[0..N]`.
    fn store(self, s: &mut [f32]);
    /// 0, 1, …, N − 1.
    fn index() -> Self;
    /// Bit l set where lane l of `m` is.
    fn bits(m: Self::Mask) -> u32;
    /// The mask of the low `N` bits of `b`.
    fn mask_of(b: u32) -> Self::Mask;
    /// `acc` plus this vector's lanes four at a time, in lane order: the sums a `Vec4` loop
    /// over the same lanes would make, bit for bit.
    fn add_to(self, acc: Vec4) -> Vec4;
}

/// Lane masks of the four-bit numbers: lane l is set where bit l is.
static MASKS4: [BVec4A; 16] = {
    let mut t = [BVec4A::FALSE; 16];
    let mut b = 0;
    while b < 16 {
        t[b] = BVec4A::new(b & 1 != 0, b & 2 != 0, b & 4 != 0, b & 8 != 0);
        b += 1;
    }
    t
};

impl Lanes for Vec4 {
    const N: usize = 4;
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        Vec4::from_slice(s)
    }
    #[inline(always)]
    fn store(self, s: &mut [f32]) {
        self.write_to_slice(s)
    }
    #[inline(always)]
    fn index() -> Self {
        Vec4::new(0.0, 1.0, 2.0, 3.0)
    }
    #[inline(always)]
    fn bits(m: BVec4A) -> u32 {
        m.bitmask()
    }
    #[inline(always)]
    fn mask_of(b: u32) -> BVec4A {
        MASKS4[(b & 15) as usize]
    }
    #[inline(always)]
    fn add_to(self, acc: Vec4) -> Vec4 {
        acc + self
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use crate::simd::avx::F8;

/// Eight lanes in one AVX register: its methods use AVX instructions, so they may only run
/// inside a function compiled with `#[target_feature(enable = "avx")]` on a CPU that has AVX
/// (checked at run time by the caller); they are `inline(always)` so that they are compiled
/// into that function.
#[cfg(target_arch = "x86_64")]
impl Lanes for F8 {
    const N: usize = 8;
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        F8::load(s)
    }
    #[inline(always)]
    fn store(self, s: &mut [f32]) {
        F8::store(self, s)
    }
    #[inline(always)]
    fn index() -> Self {
        F8::load(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0])
    }
    #[inline(always)]
    fn bits(m: crate::simd::avx::M8) -> u32 {
        F8::bits(m)
    }
    #[inline(always)]
    fn mask_of(b: u32) -> crate::simd::avx::M8 {
        use std::arch::x86_64::*;
        // Each lane's bit tested in place: the integer bits compare as tiny non-zero floats
        // (AVX1 has no integer compare).
        // SAFETY: AVX, which the caller has (see above).
        unsafe {
            let bits = _mm256_castsi256_ps(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
            let word = _mm256_castsi256_ps(_mm256_set1_epi32((b & 255) as i32));
            crate::simd::avx::M8(_mm256_cmp_ps::<_CMP_NEQ_UQ>(
                _mm256_and_ps(word, bits),
                _mm256_setzero_ps(),
            ))
        }
    }
    #[inline(always)]
    fn add_to(self, acc: Vec4) -> Vec4 {
        use std::arch::x86_64::*;
        // SAFETY: AVX, as above.
        let (lo, hi) = unsafe {
            (
                _mm256_castps256_ps128(self.0),
                _mm256_extractf128_ps::<1>(self.0),
            )
        };
        (acc + Vec4::from(lo)) + Vec4::from(hi)
    }
}
