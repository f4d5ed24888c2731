//! Sixteen f32 lanes in two AVX registers ([`F`]: lanes 0–7 in the first, 8–15 in the
//! second), a [`Float`] of the lane types for CPUs without AVX-512, with the operations of
//! [`super::avx512`]: each the IEEE operation the scalar code performs on one lane (no FMA,
//! no reciprocal approximations), so a lane computes the bits that `f32` computes. A lane
//! mask ([`M`]) is a vector mask (all ones in a set lane), as the comparisons give it and
//! `blendv` takes it. Kept as bits, every comparison had taken two `movemask`s and a pack,
//! and every select a broadcast, an `and` and a compare a half, all on the dependency chains
//! of the primitive tests (see docs/performance.md).
//!
//! As in `avx512`, these are `#[inline(always)]` safe functions that run AVX instructions,
//! sound only because this module is the crate's own and every use of it is made inside a
//! function compiled for AVX (or more) that runs only where the CPU was found to have it:
//! the wavefront's (`lanes_fn!` in `integrator/wavefront/avx2.rs`, after `Backend::detect`),
//! which adds what only it needs (`integrator/wavefront/simd_avx2.rs`: u32 lanes, gathers,
//! PCG32, with AVX2), and the small scenes' brute force (`accel::flat`, after its kernel's
//! detection).

use super::{Float, Sixteen};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitAndAssign, BitOr, BitOrAssign, Div, Mul, Neg, Not, Sub};

/// A mask of lanes: all ones in each lane set, all zeros in the others.
#[derive(Clone, Copy)]
pub struct M(pub [__m256; 2]);

/// Sixteen f32 lanes.
#[derive(Clone, Copy)]
pub struct F(pub [__m256; 2]);

// SAFETY (all the `unsafe` blocks of this module): the intrinsics need AVX, which every
// caller has checked for (see the module comment); they touch no memory but the arrays
// they are given.

/// `[e with h = 0, e with h = 1]`: each half's result, written out rather than through a
/// closure, which would be compiled without the caller's target features and so call the
/// intrinsics rather than inline them.
macro_rules! both {
    ($h:ident => $e:expr) => {
        [
            {
                let $h = 0usize;
                $e
            },
            {
                let $h = 1usize;
                $e
            },
        ]
    };
}
pub(crate) use both;

impl BitAnd for M {
    type Output = M;
    #[inline(always)]
    fn bitand(self, o: M) -> M {
        M(both!(h => unsafe { _mm256_and_ps(self.0[h], o.0[h]) }))
    }
}
impl BitOr for M {
    type Output = M;
    #[inline(always)]
    fn bitor(self, o: M) -> M {
        M(both!(h => unsafe { _mm256_or_ps(self.0[h], o.0[h]) }))
    }
}
impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        M(both!(h => unsafe {
            _mm256_xor_ps(self.0[h], _mm256_castsi256_ps(_mm256_set1_epi32(-1)))
        }))
    }
}
impl BitAndAssign for M {
    #[inline(always)]
    fn bitand_assign(&mut self, o: M) {
        *self = *self & o;
    }
}
impl BitOrAssign for M {
    #[inline(always)]
    fn bitor_assign(&mut self, o: M) {
        *self = *self | o;
    }
}

impl F {
    #[inline(always)]
    pub fn load(a: &[f32; 16]) -> F {
        F(both!(h => unsafe { _mm256_loadu_ps(a.as_ptr().add(8 * h)) }))
    }
    #[inline(always)]
    pub fn store(self, a: &mut [f32; 16]) {
        unsafe {
            _mm256_storeu_ps(a.as_mut_ptr(), self.0[0]);
            _mm256_storeu_ps(a.as_mut_ptr().add(8), self.0[1]);
        }
    }
    #[inline(always)]
    pub fn to_array(self) -> [f32; 16] {
        let mut a = [0.0; 16];
        self.store(&mut a);
        a
    }
}

impl Float for F {
    type Mask = M;
    #[inline(always)]
    fn any(m: M) -> bool {
        unsafe {
            let o = _mm256_or_ps(m.0[0], m.0[1]);
            _mm256_testz_ps(o, o) == 0
        }
    }
    #[inline(always)]
    fn splat(x: f32) -> F {
        F([unsafe { _mm256_set1_ps(x) }; 2])
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        F(both!(h => unsafe { _mm256_sqrt_ps(self.0[h]) }))
    }
    /// |x|: the sign bit cleared, as `f32::abs` and glam's `abs`.
    #[inline(always)]
    fn abs(self) -> F {
        F(both!(h => unsafe {
            _mm256_and_ps(self.0[h], _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff)))
        }))
    }
    /// `f32::max` against a number `o` that is not NaN: `o` where `self` is NaN (x86's
    /// `maxps` gives its second operand where either is NaN).
    #[inline(always)]
    fn max_num(self, o: F) -> F {
        F(both!(h => unsafe { _mm256_max_ps(self.0[h], o.0[h]) }))
    }
    /// `f32::min` against a number `o` that is not NaN: `o` where `self` is NaN.
    #[inline(always)]
    fn min_num(self, o: F) -> F {
        F(both!(h => unsafe { _mm256_min_ps(self.0[h], o.0[h]) }))
    }
    /// `x < o`, false for NaN.
    #[inline(always)]
    fn lt(self, o: F) -> M {
        M(both!(h => unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0[h], o.0[h]) }))
    }
    /// `x <= o`, false for NaN.
    #[inline(always)]
    fn le(self, o: F) -> M {
        M(both!(h => unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0[h], o.0[h]) }))
    }
    /// `x > o`, false for NaN.
    #[inline(always)]
    fn gt(self, o: F) -> M {
        M(both!(h => unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0[h], o.0[h]) }))
    }
    /// `x >= o`, false for NaN.
    #[inline(always)]
    fn ge(self, o: F) -> M {
        M(both!(h => unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(self.0[h], o.0[h]) }))
    }
    /// `x == o`, false for NaN.
    #[inline(always)]
    fn eq(self, o: F) -> M {
        M(both!(h => unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self.0[h], o.0[h]) }))
    }
    /// `a` where `m`, else `b`.
    #[inline(always)]
    fn select(m: M, a: F, b: F) -> F {
        F(both!(h => unsafe { _mm256_blendv_ps(b.0[h], a.0[h], m.0[h]) }))
    }
    /// `self.copysign(sign)`: the magnitude of `self` with the sign bit of `sign`.
    #[inline(always)]
    fn copysign(self, sign: F) -> F {
        let m = self.abs();
        F(both!(h => unsafe {
            let bit = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MIN));
            _mm256_or_ps(m.0[h], _mm256_and_ps(sign.0[h], bit))
        }))
    }
    /// (n + 127)·2²³, exact in f32, is as an integer the bits of 2ⁿ (AVX's conversions
    /// and float arithmetic: no AVX2 integer instruction).
    #[inline(always)]
    fn pow2i(self) -> F {
        F(both!(h => unsafe {
            let biased = _mm256_add_ps(self.0[h], _mm256_set1_ps(127.0));
            _mm256_castsi256_ps(_mm256_cvtps_epi32(_mm256_mul_ps(
                biased,
                _mm256_set1_ps(8_388_608.0),
            )))
        }))
    }
    /// The fields masked out with AVX's float `and`; the exponent field, as an integer,
    /// converted exactly and scaled down by 2²³.
    #[inline(always)]
    fn frexp(self) -> (F, F) {
        let m = F(both!(h => unsafe {
            let fraction = _mm256_castsi256_ps(_mm256_set1_epi32(0x007f_ffff));
            _mm256_or_ps(_mm256_and_ps(self.0[h], fraction), _mm256_set1_ps(1.0))
        }));
        let e = F(both!(h => unsafe {
            let field = _mm256_castsi256_ps(_mm256_set1_epi32(0x7f80_0000));
            let biased = _mm256_cvtepi32_ps(_mm256_castps_si256(_mm256_and_ps(self.0[h], field)));
            _mm256_sub_ps(
                _mm256_mul_ps(biased, _mm256_set1_ps(1.0 / 8_388_608.0)),
                _mm256_set1_ps(127.0),
            )
        }));
        (m, e)
    }
}

impl Sixteen for F {
    #[inline(always)]
    fn load(a: &[f32; 16]) -> F {
        F::load(a)
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 16] {
        F::to_array(self)
    }
    #[inline(always)]
    fn bits(m: M) -> u32 {
        unsafe { _mm256_movemask_ps(m.0[0]) as u32 | (_mm256_movemask_ps(m.0[1]) as u32) << 8 }
    }
    #[inline(always)]
    fn iota(first: f32) -> F {
        let f = unsafe { _mm256_set1_ps(first) };
        let i = unsafe {
            [
                _mm256_setr_ps(0., 1., 2., 3., 4., 5., 6., 7.),
                _mm256_setr_ps(8., 9., 10., 11., 12., 13., 14., 15.),
            ]
        };
        F(both!(h => unsafe { _mm256_add_ps(i[h], f) }))
    }
    /// Halved three times: each lane against the lane half a register away.
    #[inline(always)]
    fn min_by_key(t: F, key: F) -> (f32, f32) {
        unsafe {
            let (t, k) = least(t.0[0], key.0[0], t.0[1], key.0[1]);
            let (t, k) = least(
                t,
                k,
                _mm256_permute2f128_ps::<1>(t, t),
                _mm256_permute2f128_ps::<1>(k, k),
            );
            let (t, k) = least(
                t,
                k,
                _mm256_permute_ps::<0b01_00_11_10>(t),
                _mm256_permute_ps::<0b01_00_11_10>(k),
            );
            let (t, k) = least(
                t,
                k,
                _mm256_permute_ps::<0b10_11_00_01>(t),
                _mm256_permute_ps::<0b10_11_00_01>(k),
            );
            (_mm256_cvtss_f32(t), _mm256_cvtss_f32(k))
        }
    }
}

/// Lane by lane, the lesser t of (t0, k0) and (t1, k1) and its key; of equal t, the lesser
/// key.
#[inline(always)]
fn least(t0: __m256, k0: __m256, t1: __m256, k1: __m256) -> (__m256, __m256) {
    unsafe {
        let first = _mm256_cmp_ps::<_CMP_LT_OQ>(t1, t0);
        let tie = _mm256_cmp_ps::<_CMP_EQ_OQ>(t1, t0);
        let k = _mm256_blendv_ps(k0, k1, first);
        (
            _mm256_min_ps(t0, t1),
            _mm256_blendv_ps(k, _mm256_min_ps(k0, k1), tie),
        )
    }
}

impl Add for F {
    type Output = F;
    #[inline(always)]
    fn add(self, o: F) -> F {
        F(both!(h => unsafe { _mm256_add_ps(self.0[h], o.0[h]) }))
    }
}
impl Sub for F {
    type Output = F;
    #[inline(always)]
    fn sub(self, o: F) -> F {
        F(both!(h => unsafe { _mm256_sub_ps(self.0[h], o.0[h]) }))
    }
}
impl Mul for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, o: F) -> F {
        F(both!(h => unsafe { _mm256_mul_ps(self.0[h], o.0[h]) }))
    }
}
impl Div for F {
    type Output = F;
    #[inline(always)]
    fn div(self, o: F) -> F {
        F(both!(h => unsafe { _mm256_div_ps(self.0[h], o.0[h]) }))
    }
}
impl Neg for F {
    type Output = F;
    /// The sign bit flipped, as Rust's `-x` and glam's `neg`.
    #[inline(always)]
    fn neg(self) -> F {
        F(both!(h => unsafe {
            _mm256_xor_ps(self.0[h], _mm256_castsi256_ps(_mm256_set1_epi32(i32::MIN)))
        }))
    }
}
