//! Sixteen lanes in one AVX-512 register, with the operations the wavefront needs: the f32
//! lanes of [`crate::simd::avx512`] (shared with the packets' triangle test) and what only
//! the wavefront does with them (gathers, compressed stores, table lookups), u32 lanes and
//! sixteen PCG32 streams. Each the IEEE operation the scalar code performs on one lane: no
//! FMA, no reciprocal approximations, sums in the order glam writes them. So a lane computes
//! the bits the scalar path computes for its path.
//!
//! The operator impls and methods are `#[inline(always)]` functions without target features
//! that call the intrinsics; inlined into the wavefront's functions compiled for AVX-512
//! (`lanes_fn!` in `avx512.rs`), they become single instructions. (A closure is compiled
//! without its caller's features, and where it is not inlined its intrinsics are calls:
//! `crate::simd::avx2` writes its two halves out for that reason.) They are safe functions that
//! run AVX-512 instructions, which is sound only because nothing outside this private module
//! tree calls them: every value of these types, and every call of the wavefront's helpers
//! built on them (`bsdf`, `nee`, `path`), is made inside such a function, which runs only
//! where `Backend::detect` found the features. `simd_avx2.rs` is the same interface on AVX2.

use crate::sampler::Uint;
pub use crate::simd::avx512::{F, M};
use crate::simd::Float;
use std::arch::x86_64::*;
use std::ops::{BitAnd, BitOr, BitXor};

/// Sixteen u32 lanes.
#[derive(Clone, Copy)]
pub struct U(pub __m512i);

// SAFETY (all the `unsafe` blocks of this module): the intrinsics need AVX-512F (and DQ where
// noted), which every caller has checked for (see the module comment); they touch no memory
// but the arrays they are given.

impl F {
    #[inline(always)]
    pub fn is_nan(self) -> M {
        unsafe { _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(self.0, self.0) }
    }
    /// Lanes where x is finite (neither infinite nor NaN).
    #[inline(always)]
    pub fn is_finite(self) -> M {
        // |x| < ∞ is false for ∞ and NaN.
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.abs().0, _mm512_set1_ps(f32::INFINITY)) }
    }
    /// `a[at..at + 16]`.
    #[inline(always)]
    pub fn load_at(a: &[f32], at: usize) -> F {
        assert!(at + 16 <= a.len());
        F(unsafe { _mm512_loadu_ps(a.as_ptr().add(at)) })
    }
    /// The lanes of `m`, in order, written to `a[at..]`; the rest of `a[at..at + 16]` is
    /// overwritten with zeros. (Compressed in a register and stored whole: the store to
    /// memory that compresses is microcoded and slow on AMD's Zen 4.)
    #[inline(always)]
    pub fn compress_to(self, m: M, a: &mut [f32], at: usize) {
        assert!(at + 16 <= a.len());
        unsafe { _mm512_storeu_ps(a.as_mut_ptr().add(at), _mm512_maskz_compress_ps(m, self.0)) }
    }
    /// Lane i of `table` for the index in lane i (below 64), by two two-register
    /// permutations and a blend on the index's bit 5.
    #[inline(always)]
    pub fn lookup64(table: &[f32; 64], idx: U) -> F {
        unsafe {
            let t: [__m512; 4] =
                std::array::from_fn(|k| _mm512_loadu_ps(table.as_ptr().add(16 * k)));
            let lo = _mm512_permutex2var_ps(t[0], idx.0, t[1]);
            let hi = _mm512_permutex2var_ps(t[2], idx.0, t[3]);
            let upper = _mm512_test_epi32_mask(idx.0, _mm512_set1_epi32(32));
            F(_mm512_mask_blend_ps(upper, lo, hi))
        }
    }
}

impl U {
    #[inline(always)]
    pub fn splat(x: u32) -> U {
        U(unsafe { _mm512_set1_epi32(x as i32) })
    }
    #[inline(always)]
    pub fn load(a: &[u32; 16]) -> U {
        U(unsafe { _mm512_loadu_si512(a.as_ptr() as *const _) })
    }
    #[inline(always)]
    pub fn store(self, a: &mut [u32; 16]) {
        unsafe { _mm512_storeu_si512(a.as_mut_ptr() as *mut _, self.0) }
    }
    #[inline(always)]
    pub fn select(m: M, a: U, b: U) -> U {
        U(unsafe { _mm512_mask_blend_epi32(m, b.0, a.0) })
    }
    #[inline(always)]
    pub fn add(self, o: U) -> U {
        U(unsafe { _mm512_add_epi32(self.0, o.0) })
    }
    /// Unsigned `x >= o`.
    #[inline(always)]
    pub fn ge(self, o: U) -> M {
        unsafe { _mm512_cmpge_epu32_mask(self.0, o.0) }
    }
    /// Unsigned `x < o`.
    #[inline(always)]
    pub fn lt(self, o: U) -> M {
        unsafe { _mm512_cmplt_epu32_mask(self.0, o.0) }
    }
    /// Unsigned `x == o`.
    #[inline(always)]
    pub fn eq(self, o: U) -> M {
        unsafe { _mm512_cmpeq_epu32_mask(self.0, o.0) }
    }
    /// Lanes whose bits under `mask` equal `value`.
    #[inline(always)]
    pub fn masked_eq(self, mask: u32, value: u32) -> M {
        unsafe {
            _mm512_cmpeq_epu32_mask(
                _mm512_and_si512(self.0, _mm512_set1_epi32(mask as i32)),
                _mm512_set1_epi32(value as i32),
            )
        }
    }
    /// Lanes with any of `bits` set.
    #[inline(always)]
    pub fn any(self, bits: u32) -> M {
        unsafe { _mm512_test_epi32_mask(self.0, _mm512_set1_epi32(bits as i32)) }
    }
    /// Lane i of `table` for the index in lane i (below 64).
    #[inline(always)]
    pub fn lookup64(table: &[u32; 64], idx: U) -> U {
        // SAFETY: the same bits through the float permutation.
        let t: &[f32; 64] = unsafe { &*(table as *const [u32; 64] as *const [f32; 64]) };
        U(unsafe { _mm512_castps_si512(F::lookup64(t, idx).0) })
    }
    /// Each lane shifted right by `K` bits.
    #[inline(always)]
    pub fn shr<const K: u32>(self) -> U {
        U(unsafe { _mm512_srli_epi32::<K>(self.0) })
    }
    /// The lanes as f32 (exact below 2^24).
    #[inline(always)]
    pub fn to_f32(self) -> F {
        F(unsafe { _mm512_cvtepu32_ps(self.0) })
    }
    /// The whole numbers of `f`'s lanes (below 2^31), rounded toward zero.
    #[inline(always)]
    pub fn of_f32(f: F) -> U {
        U(unsafe { _mm512_cvttps_epi32(f.0) })
    }
}

impl BitAnd for U {
    type Output = U;
    #[inline(always)]
    fn bitand(self, o: U) -> U {
        U(unsafe { _mm512_and_si512(self.0, o.0) })
    }
}
impl BitOr for U {
    type Output = U;
    #[inline(always)]
    fn bitor(self, o: U) -> U {
        U(unsafe { _mm512_or_si512(self.0, o.0) })
    }
}
impl BitXor for U {
    type Output = U;
    #[inline(always)]
    fn bitxor(self, o: U) -> U {
        U(unsafe { _mm512_xor_si512(self.0, o.0) })
    }
}

impl Uint for U {
    #[inline(always)]
    fn splat(x: u32) -> U {
        U::splat(x)
    }
    #[inline(always)]
    fn wrapping_add(self, o: U) -> U {
        self.add(o)
    }
    #[inline(always)]
    fn wrapping_mul(self, o: U) -> U {
        U(unsafe { _mm512_mullo_epi32(self.0, o.0) })
    }
    #[inline(always)]
    fn shr<const K: u32>(self) -> U {
        U::shr::<K>(self)
    }
    #[inline(always)]
    fn shl<const K: u32>(self) -> U {
        U(unsafe { _mm512_slli_epi32::<K>(self.0) })
    }
}

impl U {
    /// `table[idx]` in each lane of `m` (zero in the others).
    ///
    /// # Safety
    /// Every index of the lanes of `m` must be below `table.len()`.
    #[inline(always)]
    pub unsafe fn gather(table: &[u32], idx: U, m: M) -> U {
        U(_mm512_mask_i32gather_epi32::<4>(
            _mm512_setzero_si512(),
            m,
            idx.0,
            table.as_ptr() as *const _,
        ))
    }
    /// The lanes' bits as f32.
    #[inline(always)]
    pub fn to_bits_f32(self) -> F {
        F(unsafe { _mm512_castsi512_ps(self.0) })
    }
}

#[path = "v3.rs"]
mod v3;
pub use v3::V3;

/// The next output of sixteen PCG32 streams ([`crate::sampler::Pcg32`]), of each lane in
/// `m`; the other lanes' streams do not move. The 64-bit states in two registers of eight
/// lanes (AVX-512DQ's 64-bit multiply), the 32-bit outputs gathered into one of sixteen.
#[inline(always)]
pub fn pcg32(state: &mut [u64; 16], inc: &[u64; 16], m: M) -> U {
    unsafe {
        let mult = _mm512_set1_epi64(crate::sampler::PCG_MULT as i64);
        let mut out = [_mm256_setzero_si256(); 2];
        for (half, out) in out.iter_mut().enumerate() {
            let at = 8 * half;
            let old = _mm512_loadu_si512(state.as_ptr().add(at) as *const _);
            let inc = _mm512_loadu_si512(inc.as_ptr().add(at) as *const _);
            let new = _mm512_add_epi64(_mm512_mullo_epi64(old, mult), inc);
            let lanes = (m >> at) as u8;
            _mm512_mask_storeu_epi64(state.as_mut_ptr().add(at) as *mut _, lanes, new);
            // ((old >> 18) ^ old) >> 27, truncated, rotated right by old >> 59.
            let xorshifted =
                _mm512_srli_epi64::<27>(_mm512_xor_si512(_mm512_srli_epi64::<18>(old), old));
            let rot = _mm512_srli_epi64::<59>(old);
            // Rotating each 32-bit half of the 64-bit lanes rotates the low one, which is
            // the truncated value, by `rot` (the high one by 0); then keep the low halves.
            let r = _mm512_rorv_epi32(xorshifted, rot);
            *out = _mm512_cvtepi64_epi32(r);
        }
        U(_mm512_inserti64x4::<1>(
            _mm512_castsi256_si512(out[0]),
            out[1],
        ))
    }
}
