//! Sixteen f32 lanes in one AVX-512 register ([`F`]), a [`Float`] of the lane types: each
//! operation the IEEE operation the scalar code performs on one lane (no FMA, no reciprocal
//! approximations), so a lane computes the bits that `f32` computes.
//!
//! The operator impls and methods are `#[inline(always)]` functions without target features
//! that call the intrinsics; inlined into functions compiled for AVX-512F and AVX-512DQ, they
//! become single instructions. (A closure is compiled without its caller's features, and
//! where it is not inlined its intrinsics are calls.) They are safe functions that run
//! AVX-512 instructions, which is sound only because this module is the crate's own and
//! every use of it is made inside such a function, which runs only where the CPU was found
//! to have the features: the wavefront's (`lanes_fn!` in
//! `integrator/wavefront/avx512.rs`, after `Backend::detect`) and the packets' triangle test
//! (`scene/packet.rs`, after `cpu::avx512`). The wavefront adds the operations only it needs
//! (`integrator/wavefront/simd.rs`).

use super::{Float, Sixteen};
use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

// SAFETY (all the `unsafe` blocks of this module): the intrinsics need AVX-512F, which every
// caller has checked for (see the module comment); they touch no memory but the arrays they
// are given.

/// A mask of lanes, bit i for lane i.
pub type M = u16;

/// Sixteen f32 lanes.
#[derive(Clone, Copy)]
pub struct F(pub __m512);

impl F {
    #[inline(always)]
    pub fn load(a: &[f32; 16]) -> F {
        F(unsafe { _mm512_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    pub fn store(self, a: &mut [f32; 16]) {
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), self.0) }
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
        m != 0
    }
    #[inline(always)]
    fn splat(x: f32) -> F {
        F(unsafe { _mm512_set1_ps(x) })
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        F(unsafe { _mm512_sqrt_ps(self.0) })
    }
    /// |x|: the sign bit cleared, as `f32::abs` and glam's `abs`.
    #[inline(always)]
    fn abs(self) -> F {
        F(unsafe {
            _mm512_castsi512_ps(_mm512_and_si512(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(0x7fff_ffff),
            ))
        })
    }
    /// `f32::max` against a number `o` that is not NaN: `o` where `self` is NaN (x86's
    /// `maxps` gives its second operand where either is NaN). (Where the two are zeros of
    /// opposite signs either may come out, as for `f32::max`; no caller tells them apart.)
    #[inline(always)]
    fn max_num(self, o: F) -> F {
        F(unsafe { _mm512_max_ps(self.0, o.0) })
    }
    /// `f32::min` against a number `o` that is not NaN: `o` where `self` is NaN.
    #[inline(always)]
    fn min_num(self, o: F) -> F {
        F(unsafe { _mm512_min_ps(self.0, o.0) })
    }
    /// `x < o`, false for NaN.
    #[inline(always)]
    fn lt(self, o: F) -> M {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0) }
    }
    /// `x <= o`, false for NaN.
    #[inline(always)]
    fn le(self, o: F) -> M {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0) }
    }
    /// `x > o`, false for NaN.
    #[inline(always)]
    fn gt(self, o: F) -> M {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, o.0) }
    }
    /// `x >= o`, false for NaN.
    #[inline(always)]
    fn ge(self, o: F) -> M {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GE_OQ>(self.0, o.0) }
    }
    /// `x == o`, false for NaN.
    #[inline(always)]
    fn eq(self, o: F) -> M {
        unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self.0, o.0) }
    }
    /// `a` where `m`, else `b`.
    #[inline(always)]
    fn select(m: M, a: F, b: F) -> F {
        F(unsafe { _mm512_mask_blend_ps(m, b.0, a.0) })
    }
    /// `self.copysign(sign)`: the magnitude of `self` with the sign bit of `sign`.
    #[inline(always)]
    fn copysign(self, sign: F) -> F {
        unsafe {
            let s = _mm512_and_si512(_mm512_castps_si512(sign.0), _mm512_set1_epi32(i32::MIN));
            F(_mm512_castsi512_ps(_mm512_or_si512(
                s,
                _mm512_castps_si512(self.abs().0),
            )))
        }
    }
    /// (n + 127)·2²³, exact in f32, is as an integer the bits of 2ⁿ.
    #[inline(always)]
    fn pow2i(self) -> F {
        F(unsafe {
            let biased = _mm512_add_ps(self.0, _mm512_set1_ps(127.0));
            _mm512_castsi512_ps(_mm512_cvtps_epi32(_mm512_mul_ps(
                biased,
                _mm512_set1_ps(8_388_608.0),
            )))
        })
    }
    #[inline(always)]
    fn frexp(self) -> (F, F) {
        unsafe {
            let b = _mm512_castps_si512(self.0);
            let fraction = _mm512_and_si512(b, _mm512_set1_epi32(0x007f_ffff));
            let m = _mm512_or_si512(fraction, _mm512_set1_epi32(0x3f80_0000));
            let field =
                _mm512_srli_epi32::<23>(_mm512_and_si512(b, _mm512_set1_epi32(0x7f80_0000)));
            let e = _mm512_sub_ps(_mm512_cvtepi32_ps(field), _mm512_set1_ps(127.0));
            (F(_mm512_castsi512_ps(m)), F(e))
        }
    }
    #[inline(always)]
    fn trunc(self) -> F {
        F(unsafe { _mm512_roundscale_ps::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(self.0) })
    }
    /// One gather; NaN (converted to `i32::MIN`) and negatives clamped to 0, as `as usize`
    /// takes them.
    #[inline(always)]
    fn gather(table: &[f32], index: F) -> F {
        let last = i32::try_from(table.len()).expect("a table below 2^31 entries") - 1;
        assert!(last >= 0, "an empty table");
        unsafe {
            let i = _mm512_cvttps_epi32(index.0);
            let i = _mm512_min_epi32(
                _mm512_max_epi32(i, _mm512_setzero_si512()),
                _mm512_set1_epi32(last),
            );
            // SAFETY: every index is in 0..table.len().
            F(_mm512_i32gather_ps::<4>(i, table.as_ptr()))
        }
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
        m.into()
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> M {
        bits as M
    }
    #[inline(always)]
    fn next_up(self) -> F {
        unsafe {
            F(_mm512_castsi512_ps(_mm512_add_epi32(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(1),
            )))
        }
    }
    #[inline(always)]
    fn iota(first: f32) -> F {
        let i = unsafe {
            _mm512_setr_ps(
                0., 1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 13., 14., 15.,
            )
        };
        F(i) + F::splat(first)
    }
    #[inline(always)]
    fn min_by_key(t: F, key: F) -> (f32, f32) {
        unsafe {
            let least = _mm512_reduce_min_ps(t.0);
            let at = _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(t.0, _mm512_set1_ps(least));
            (least, _mm512_mask_reduce_min_ps(at, key.0))
        }
    }
}

impl Add for F {
    type Output = F;
    #[inline(always)]
    fn add(self, o: F) -> F {
        F(unsafe { _mm512_add_ps(self.0, o.0) })
    }
}
impl Sub for F {
    type Output = F;
    #[inline(always)]
    fn sub(self, o: F) -> F {
        F(unsafe { _mm512_sub_ps(self.0, o.0) })
    }
}
impl Mul for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, o: F) -> F {
        F(unsafe { _mm512_mul_ps(self.0, o.0) })
    }
}
impl Div for F {
    type Output = F;
    #[inline(always)]
    fn div(self, o: F) -> F {
        F(unsafe { _mm512_div_ps(self.0, o.0) })
    }
}
impl Neg for F {
    type Output = F;
    /// The sign bit flipped, as Rust's `-x` and glam's `neg`.
    #[inline(always)]
    fn neg(self) -> F {
        F(unsafe {
            _mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(i32::MIN),
            ))
        })
    }
}
