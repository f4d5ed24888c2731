//! Eight f32 lanes in one AVX register ([`F8`]) and their masks ([`M8`]: all ones in a set
//! lane, as the comparisons give it and `blendv` takes it): a [`Float`] of the lane types,
//! each operation the IEEE one the scalar code performs on one lane (no FMA, no reciprocal
//! approximations), so a lane computes the bits that `f32` computes. The sixteen lanes of
//! CPUs without AVX-512 are two of it ([`super::avx2`]).
//!
//! These are `#[inline(always)]` safe functions that run AVX instructions, sound only
//! because this module is the crate's own and every use of it is made inside a function
//! compiled for AVX (or more) that runs only where the CPU was found to have it.

use super::Float;
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Eight f32 lanes.
#[derive(Clone, Copy)]
pub struct F8(pub __m256);

/// A mask of eight lanes: all ones in each lane set, all zeros in the others.
#[derive(Clone, Copy)]
pub struct M8(pub __m256);

// SAFETY (all the `unsafe` blocks of this module): the intrinsics need AVX, which every
// caller has checked for (see the module comment); loads and stores check their slice's
// length first.

macro_rules! binary {
    ($t:ident, $tr:ident, $f:ident, $op:ident) => {
        impl $tr for $t {
            type Output = $t;
            #[inline(always)]
            fn $f(self, o: $t) -> $t {
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

/// Each lane's sign bit alone.
#[inline(always)]
fn sign_bits() -> __m256 {
    unsafe { _mm256_set1_ps(-0.0) }
}

impl Neg for F8 {
    type Output = F8;
    /// The sign bit flipped, as Rust's `-x` and glam's `neg`.
    #[inline(always)]
    fn neg(self) -> F8 {
        F8(unsafe { _mm256_xor_ps(self.0, sign_bits()) })
    }
}

impl Not for M8 {
    type Output = M8;
    #[inline(always)]
    fn not(self) -> M8 {
        M8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
    }
}

impl F8 {
    /// Lanes `0..8` of `s`.
    #[inline(always)]
    pub fn load(s: &[f32]) -> F8 {
        let s = &s[..8];
        F8(unsafe { _mm256_loadu_ps(s.as_ptr()) })
    }
    /// Into `s[0..8]`.
    #[inline(always)]
    pub fn store(self, s: &mut [f32]) {
        let s = &mut s[..8];
        unsafe { _mm256_storeu_ps(s.as_mut_ptr(), self.0) }
    }
    /// Bit l set where lane l of `m` is.
    #[inline(always)]
    pub fn bits(m: M8) -> u32 {
        unsafe { _mm256_movemask_ps(m.0) as u32 }
    }
}

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
    /// |x|: the sign bit cleared, as `f32::abs` and glam's `abs`.
    #[inline(always)]
    fn abs(self) -> Self {
        F8(unsafe { _mm256_andnot_ps(sign_bits(), self.0) })
    }
    /// `f32::max` against a number `o` that is not NaN: `o` where `self` is NaN (x86's
    /// `maxps` gives its second operand where either is NaN).
    #[inline(always)]
    fn max_num(self, o: Self) -> Self {
        F8(unsafe { _mm256_max_ps(self.0, o.0) })
    }
    /// `f32::min` against a number `o` that is not NaN: `o` where `self` is NaN.
    #[inline(always)]
    fn min_num(self, o: Self) -> Self {
        F8(unsafe { _mm256_min_ps(self.0, o.0) })
    }
    /// The magnitude of `self` with the sign bit of `sign`.
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        let s = sign_bits();
        F8(unsafe { _mm256_or_ps(_mm256_and_ps(sign.0, s), _mm256_andnot_ps(s, self.0)) })
    }
    // Ordered, non-signalling comparisons: false where either operand is NaN, as SSE's
    // `cmpltps` and friends.
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
    /// `a` where `m`, else `b` (blendv takes its second operand where the mask's sign bit
    /// is set).
    #[inline(always)]
    fn select(m: M8, a: Self, b: Self) -> Self {
        F8(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
    }
    #[inline(always)]
    fn any(m: M8) -> bool {
        unsafe { _mm256_testz_ps(m.0, m.0) == 0 }
    }
    /// (n + 127)·2²³, exact in f32, is as an integer the bits of 2ⁿ (AVX's conversions and
    /// float arithmetic: no AVX2 integer instruction).
    #[inline(always)]
    fn pow2i(self) -> Self {
        F8(unsafe {
            let biased = _mm256_add_ps(self.0, _mm256_set1_ps(127.0));
            _mm256_castsi256_ps(_mm256_cvtps_epi32(_mm256_mul_ps(
                biased,
                _mm256_set1_ps(8_388_608.0),
            )))
        })
    }
    /// The fields masked out with AVX's float `and`; the exponent field, as an integer,
    /// converted exactly and scaled down by 2²³.
    #[inline(always)]
    fn frexp(self) -> (Self, Self) {
        unsafe {
            let fraction = _mm256_castsi256_ps(_mm256_set1_epi32(0x007f_ffff));
            let m = _mm256_or_ps(_mm256_and_ps(self.0, fraction), _mm256_set1_ps(1.0));
            let field = _mm256_castsi256_ps(_mm256_set1_epi32(0x7f80_0000));
            let biased = _mm256_cvtepi32_ps(_mm256_castps_si256(_mm256_and_ps(self.0, field)));
            let e = _mm256_sub_ps(
                _mm256_mul_ps(biased, _mm256_set1_ps(1.0 / 8_388_608.0)),
                _mm256_set1_ps(127.0),
            );
            (F8(m), F8(e))
        }
    }
    #[inline(always)]
    fn trunc(self) -> Self {
        F8(unsafe { _mm256_round_ps::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(self.0) })
    }
    /// Lane by lane (AVX has no gather).
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        let mut a = [0.0; 8];
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), index.0) };
        let a = a.map(|i| f32::gather(table, i));
        F8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
}
