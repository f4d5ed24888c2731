//! Sixteen lanes in two AVX2 registers (lanes 0–7 in the first, 8–15 in the second), with
//! the same operations as the AVX-512 backend (`simd.rs`), for CPUs without AVX-512: the
//! f32 lanes and masks of [`crate::simd::avx2`] (shared with the small scenes' brute force)
//! and what only the wavefront does with them (gathers, compressed stores, table lookups,
//! the masks as bits where code reads them, `LaneMask::bits`), u32 lanes and sixteen PCG32
//! streams. Each the IEEE operation the scalar code performs on one lane (no FMA, no
//! reciprocal approximations), so a lane computes the same bits on either backend.
//!
//! As in `simd.rs`, these are `#[inline(always)]` safe functions that run AVX2
//! instructions, sound only because nothing outside this private module tree calls them:
//! every call is made inside a function compiled for AVX2 (`lanes_fn!` in `avx2.rs`), which
//! runs only where `Backend::detect` found the features.

use super::super::LaneMask;
use crate::sampler::Uint;
use crate::simd::avx::{F8, M8};
use crate::simd::avx2::both;
pub use crate::simd::avx2::{F, M};
use crate::simd::Float;
use std::arch::x86_64::*;
use std::ops::{BitAnd, BitOr, BitXor};

/// Sixteen u32 lanes.
#[derive(Clone, Copy)]
pub struct U(pub [__m256i; 2]);

// SAFETY (all the `unsafe` blocks of this module): the intrinsics need AVX2, which every
// caller has checked for (see the module comment); they touch no memory but the arrays
// they are given.

/// Two halves' comparison results as a mask.
#[inline(always)]
fn mask_of(c: [__m256; 2]) -> M {
    M([M8(c[0]), M8(c[1])])
}

/// Half `h` of `m` as integer lanes.
#[inline(always)]
fn lanes_of(m: M, h: usize) -> __m256i {
    unsafe { _mm256_castps_si256(m.0[h].0) }
}

impl LaneMask for M {
    #[inline(always)]
    fn bits(self) -> u16 {
        unsafe {
            (_mm256_movemask_ps(self.0[0].0) as u32 | (_mm256_movemask_ps(self.0[1].0) as u32) << 8)
                as u16
        }
    }
    #[inline(always)]
    fn from_bits(m: u16) -> M {
        <F as crate::simd::Sixteen>::from_bits(m.into())
    }
    #[inline(always)]
    fn any(self) -> bool {
        F::any(self)
    }
}

impl F {
    #[inline(always)]
    pub fn is_nan(self) -> M {
        mask_of(both!(h => unsafe { _mm256_cmp_ps::<_CMP_UNORD_Q>(self.0[h].0, self.0[h].0) }))
    }
    /// Lanes where x is finite (neither infinite nor NaN).
    #[inline(always)]
    pub fn is_finite(self) -> M {
        // |x| < ∞ is false for ∞ and NaN.
        self.abs().lt(F::splat(f32::INFINITY))
    }
    /// `a[at..at + 16]`.
    #[inline(always)]
    pub fn load_at(a: &[f32], at: usize) -> F {
        let a: &[f32; 16] = a[at..at + 16].try_into().unwrap();
        F::load(a)
    }
    /// The lanes of `m`, in order, written to `a[at..]`; the rest of `a[at..at + 16]` is
    /// overwritten with zeros.
    #[inline(always)]
    pub fn compress_to(self, m: u16, a: &mut [f32], at: usize) {
        let a: &mut [f32; 16] = (&mut a[at..at + 16]).try_into().unwrap();
        let x = self.to_array();
        let mut n = 0;
        let mut mm = m;
        while mm != 0 {
            a[n] = x[mm.trailing_zeros() as usize];
            mm &= mm - 1;
            n += 1;
        }
        a[n..].fill(0.0);
    }
    /// Lane i of `table` for the index in lane i (below 64), gathered.
    #[inline(always)]
    pub fn lookup64(table: &[f32; 64], idx: U) -> F {
        F(both!(h => unsafe {
            // (An index below 64 reads inside the table.)
            F8(_mm256_i32gather_ps::<4>(table.as_ptr(), _mm256_and_si256(idx.0[h], _mm256_set1_epi32(63))))
        }))
    }
}

impl U {
    #[inline(always)]
    pub fn splat(x: u32) -> U {
        U([unsafe { _mm256_set1_epi32(x as i32) }; 2])
    }
    #[inline(always)]
    pub fn load(a: &[u32; 16]) -> U {
        U(both!(h => unsafe { _mm256_loadu_si256(a.as_ptr().add(8 * h) as *const _) }))
    }
    #[inline(always)]
    pub fn store(self, a: &mut [u32; 16]) {
        unsafe {
            _mm256_storeu_si256(a.as_mut_ptr() as *mut _, self.0[0]);
            _mm256_storeu_si256(a.as_mut_ptr().add(8) as *mut _, self.0[1]);
        }
    }
    #[inline(always)]
    pub fn select(m: M, a: U, b: U) -> U {
        U(both!(h => unsafe { _mm256_blendv_epi8(b.0[h], a.0[h], lanes_of(m, h)) }))
    }
    #[inline(always)]
    pub fn add(self, o: U) -> U {
        U(both!(h => unsafe { _mm256_add_epi32(self.0[h], o.0[h]) }))
    }
    /// Unsigned `x >= o`: max(x, o) == x.
    #[inline(always)]
    pub fn ge(self, o: U) -> M {
        mask_of(both!(h => unsafe {
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_max_epu32(self.0[h], o.0[h]), self.0[h]))
        }))
    }
    /// Unsigned `x < o`.
    #[inline(always)]
    pub fn lt(self, o: U) -> M {
        !self.ge(o)
    }
    /// Unsigned `x == o`.
    #[inline(always)]
    pub fn eq(self, o: U) -> M {
        mask_of(both!(h => unsafe { _mm256_castsi256_ps(_mm256_cmpeq_epi32(self.0[h], o.0[h])) }))
    }
    /// Lanes whose bits under `mask` equal `value`.
    #[inline(always)]
    pub fn masked_eq(self, mask: u32, value: u32) -> M {
        (self & U::splat(mask)).eq(U::splat(value))
    }
    /// Lanes with any of `bits` set.
    #[inline(always)]
    pub fn any(self, bits: u32) -> M {
        !(self & U::splat(bits)).eq(U::splat(0))
    }
    /// Lane i of `table` for the index in lane i (below 64), gathered.
    #[inline(always)]
    pub fn lookup64(table: &[u32; 64], idx: U) -> U {
        U(both!(h => unsafe {
            // (An index below 64 reads inside the table.)
            _mm256_i32gather_epi32::<4>(
                table.as_ptr() as *const i32,
                _mm256_and_si256(idx.0[h], _mm256_set1_epi32(63)),
            )
        }))
    }
    /// Each lane shifted right by `K` bits.
    #[inline(always)]
    pub fn shr<const K: u32>(self) -> U {
        U(both!(h => unsafe { _mm256_srl_epi32(self.0[h], _mm_cvtsi32_si128(K as i32)) }))
    }
    /// The lanes as f32 (exact below 2^24; every caller's lanes are below 2^31, where the
    /// signed conversion is the unsigned one).
    #[inline(always)]
    pub fn to_f32(self) -> F {
        F(both!(h => F8(unsafe { _mm256_cvtepi32_ps(self.0[h]) })))
    }
    /// The whole numbers of `f`'s lanes (below 2^31), rounded toward zero.
    #[inline(always)]
    pub fn of_f32(f: F) -> U {
        U(both!(h => unsafe { _mm256_cvttps_epi32(f.0[h].0) }))
    }
}

impl BitAnd for U {
    type Output = U;
    #[inline(always)]
    fn bitand(self, o: U) -> U {
        U(both!(h => unsafe { _mm256_and_si256(self.0[h], o.0[h]) }))
    }
}
impl BitOr for U {
    type Output = U;
    #[inline(always)]
    fn bitor(self, o: U) -> U {
        U(both!(h => unsafe { _mm256_or_si256(self.0[h], o.0[h]) }))
    }
}
impl BitXor for U {
    type Output = U;
    #[inline(always)]
    fn bitxor(self, o: U) -> U {
        U(both!(h => unsafe { _mm256_xor_si256(self.0[h], o.0[h]) }))
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
        U(both!(h => unsafe { _mm256_mullo_epi32(self.0[h], o.0[h]) }))
    }
    #[inline(always)]
    fn shr<const K: u32>(self) -> U {
        U::shr::<K>(self)
    }
    #[inline(always)]
    fn shl<const K: u32>(self) -> U {
        U(both!(h => unsafe { _mm256_sll_epi32(self.0[h], _mm_cvtsi32_si128(K as i32)) }))
    }
}

impl U {
    /// `table[idx]` in each lane of `m` (zero in the others).
    ///
    /// # Safety
    /// Every index of the lanes of `m` must be below `table.len()`.
    #[inline(always)]
    pub unsafe fn gather(table: &[u32], idx: U, m: M) -> U {
        U(both!(h => _mm256_mask_i32gather_epi32::<4>(
            _mm256_setzero_si256(),
            table.as_ptr() as *const i32,
            idx.0[h],
            lanes_of(m, h),
        )))
    }
    /// The lanes' bits as f32.
    #[inline(always)]
    pub fn to_bits_f32(self) -> F {
        F(both!(h => F8(unsafe { _mm256_castsi256_ps(self.0[h]) })))
    }
}

#[path = "v3.rs"]
mod v3;
pub use v3::V3;

/// The next output of sixteen PCG32 streams ([`crate::sampler::Pcg32`]), of each lane in
/// `m`; the other lanes' streams do not move. Four 64-bit states a register: AVX2 has no
/// 64-bit multiply, so the state's product is built from three 32-bit ones (lo·lo, and
/// hi·lo + lo·hi shifted up), the same bits modulo 2⁶⁴; the 32-bit outputs are rotated in
/// place and gathered. (Lane by lane, with scalar 64-bit multiplies, it cost 6 % more of
/// the TNCG15 room's instructions with independent numbers.)
#[inline(always)]
pub fn pcg32(state: &mut [u64; 16], inc: &[u64; 16], m: M) -> U {
    unsafe {
        let mult = _mm256_set1_epi64x(crate::sampler::PCG_MULT as i64);
        let mult_hi = _mm256_srli_epi64::<32>(mult);
        let low = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
        let mut out = [_mm_setzero_si128(); 4];
        for (q, out) in out.iter_mut().enumerate() {
            let at = 4 * q;
            let old = _mm256_loadu_si256(state.as_ptr().add(at) as *const _);
            let inc = _mm256_loadu_si256(inc.as_ptr().add(at) as *const _);
            let lo = _mm256_mul_epu32(old, mult);
            let cross = _mm256_add_epi64(
                _mm256_mul_epu32(_mm256_srli_epi64::<32>(old), mult),
                _mm256_mul_epu32(old, mult_hi),
            );
            let new = _mm256_add_epi64(_mm256_add_epi64(lo, _mm256_slli_epi64::<32>(cross)), inc);
            // This quarter's four lanes of `m`, each widened to 64 bits.
            let half = _mm256_castps_si256(m.0[q / 2].0);
            let four = if q % 2 == 0 {
                _mm256_castsi256_si128(half)
            } else {
                _mm256_extracti128_si256::<1>(half)
            };
            _mm256_maskstore_epi64(
                state.as_mut_ptr().add(at) as *mut i64,
                _mm256_cvtepi32_epi64(four),
                new,
            );
            // ((old >> 18) ^ old) >> 27, truncated, rotated right by old >> 59: in the low
            // 32 bits of each 64-bit lane (a shift by 32 or more gives 0, so a rotation by 0
            // is x | 0), then the low halves gathered.
            let x = _mm256_srli_epi64::<27>(_mm256_xor_si256(_mm256_srli_epi64::<18>(old), old));
            let rot = _mm256_srli_epi64::<59>(old);
            let r = _mm256_or_si256(
                _mm256_srlv_epi32(x, rot),
                _mm256_sllv_epi32(x, _mm256_sub_epi32(_mm256_set1_epi32(32), rot)),
            );
            *out = _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(r, low));
        }
        U([
            _mm256_set_m128i(out[1], out[0]),
            _mm256_set_m128i(out[3], out[2]),
        ])
    }
}
