//! The lane types the planar light batch ([`super::planar`]) is written over: glam's `Vec4`
//! (four lanes, SSE2 on x86-64, NEON on AArch64) and, on x86-64 CPUs that have it, an
//! eight-lane AVX vector. Every operation is the IEEE one of the same name lane by lane
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
pub(super) use avx::F8;

#[cfg(target_arch = "x86_64")]
mod avx {
    //! Eight lanes in one AVX register. Its methods use AVX instructions, so they may only
    //! run inside a function compiled with `#[target_feature(enable = "avx")]` on a CPU that
    //! has AVX (checked at run time by the caller); they are `inline(always)` so that they
    //! are compiled into that function.
    use super::Lanes;
    use crate::simd::Float;
    use glam::Vec4;
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

    #[derive(Clone, Copy)]
    pub struct F8(__m256);

    #[derive(Clone, Copy)]
    pub struct M8(__m256);

    macro_rules! binary {
        ($t:ident, $tr:ident, $f:ident, $op:ident) => {
            impl $tr for $t {
                type Output = $t;
                #[inline(always)]
                fn $f(self, o: $t) -> $t {
                    // SAFETY: see the module's comment.
                    $t(unsafe { $op(self.0, o.0) })
                }
            }
        };
    }
    binary!(F8, Add, add, _mm256_add_ps);
    binary!(F8, Sub, sub, _mm256_sub_ps);
    binary!(F8, Mul, mul, _mm256_mul_ps);
    binary!(F8, Div, div, _mm256_div_ps);
    binary!(M8, BitAnd, bitand, _mm256_and_ps);
    binary!(M8, BitOr, bitor, _mm256_or_ps);

    /// The sign bit of each lane.
    #[inline(always)]
    fn sign_bits() -> __m256 {
        // SAFETY: see the module's comment.
        unsafe { _mm256_set1_ps(-0.0) }
    }

    impl Neg for F8 {
        type Output = F8;
        #[inline(always)]
        fn neg(self) -> F8 {
            // SAFETY: see the module's comment.
            F8(unsafe { _mm256_xor_ps(self.0, sign_bits()) })
        }
    }

    impl Not for M8 {
        type Output = M8;
        #[inline(always)]
        fn not(self) -> M8 {
            // SAFETY: see the module's comment.
            M8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
        }
    }

    // SAFETY (every `unsafe` below): see the module's comment; loads and stores check their
    // slice's length first.
    impl Float for F8 {
        type Mask = M8;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            F8(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            F8(unsafe { _mm256_sqrt_ps(self.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            F8(unsafe { _mm256_andnot_ps(sign_bits(), self.0) })
        }
        #[inline(always)]
        fn max_num(self, o: Self) -> Self {
            F8(unsafe { _mm256_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn min_num(self, o: Self) -> Self {
            F8(unsafe { _mm256_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn copysign(self, sign: Self) -> Self {
            let s = sign_bits();
            F8(unsafe { _mm256_or_ps(_mm256_and_ps(sign.0, s), _mm256_andnot_ps(s, self.0)) })
        }
        // Ordered, non-signalling comparisons: false where either operand is NaN, as
        // SSE's `cmpltps` and friends.
        #[inline(always)]
        fn lt(self, o: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn gt(self, o: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn ge(self, o: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn eq(self, o: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn select(m: M8, a: Self, b: Self) -> Self {
            // blendv takes its second operand where the mask's sign bit is set.
            F8(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
        }
        #[inline(always)]
        fn any(m: M8) -> bool {
            unsafe { _mm256_movemask_ps(m.0) != 0 }
        }
        // (Only exp and log use these two, and the light batch calls neither.)
        #[inline(always)]
        fn pow2i(self) -> Self {
            let mut a = [0.0; 8];
            self.store(&mut a);
            F8::load(&a.map(f32::pow2i))
        }
        #[inline(always)]
        fn frexp(self) -> (Self, Self) {
            let mut a = [0.0; 8];
            self.store(&mut a);
            let p = a.map(f32::frexp);
            (F8::load(&p.map(|p| p.0)), F8::load(&p.map(|p| p.1)))
        }
    }

    impl Lanes for F8 {
        const N: usize = 8;
        #[inline(always)]
        fn load(s: &[f32]) -> Self {
            let s = &s[..8];
            F8(unsafe { _mm256_loadu_ps(s.as_ptr()) })
        }
        #[inline(always)]
        fn store(self, s: &mut [f32]) {
            let s = &mut s[..8];
            unsafe { _mm256_storeu_ps(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn index() -> Self {
            F8(unsafe { _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0) })
        }
        #[inline(always)]
        fn bits(m: M8) -> u32 {
            unsafe { _mm256_movemask_ps(m.0) as u32 }
        }
        #[inline(always)]
        fn mask_of(b: u32) -> M8 {
            // Each lane's bit tested in place: the integer bits compare as tiny non-zero
            // floats (AVX1 has no integer compare).
            unsafe {
                let bits = _mm256_castsi256_ps(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
                let word = _mm256_castsi256_ps(_mm256_set1_epi32((b & 255) as i32));
                M8(_mm256_cmp_ps::<_CMP_NEQ_UQ>(
                    _mm256_and_ps(word, bits),
                    _mm256_setzero_ps(),
                ))
            }
        }
        #[inline(always)]
        fn add_to(self, acc: Vec4) -> Vec4 {
            let (lo, hi) = unsafe {
                (
                    _mm256_castps256_ps128(self.0),
                    _mm256_extractf128_ps::<1>(self.0),
                )
            };
            (acc + Vec4::from(lo)) + Vec4::from(hi)
        }
    }
}
