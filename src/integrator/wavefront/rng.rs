//! The independent sampler's PCG32 streams ([`crate::sampler::Pcg32`]), one per lane: the
//! 64-bit states in two registers of eight lanes (AVX-512DQ's 64-bit multiply), the 32-bit
//! outputs gathered into one register of sixteen. Lane i draws exactly the numbers its
//! camera sample's own `Sampler` would, in the same order.

use super::simd::{F, M, U};
use std::arch::x86_64::*;

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

/// Sixteen PCG32 streams.
pub struct Rng16 {
    pub state: [u64; 16],
    pub inc: [u64; 16],
}

impl Rng16 {
    pub fn new() -> Rng16 {
        Rng16 {
            state: [0; 16],
            inc: [1; 16],
        }
    }

    /// The next 32-bit output of each lane in `m`; the other lanes' streams do not move
    /// (their outputs are meaningless).
    ///
    /// # Safety
    /// The CPU must have AVX-512F and AVX-512DQ.
    #[inline(always)]
    pub unsafe fn next_u32(&mut self, m: M) -> U {
        let mult = _mm512_set1_epi64(PCG_MULT as i64);
        let mut out = [_mm256_setzero_si256(); 2];
        for (half, out) in out.iter_mut().enumerate() {
            let at = 8 * half;
            let old = _mm512_loadu_si512(self.state.as_ptr().add(at) as *const _);
            let inc = _mm512_loadu_si512(self.inc.as_ptr().add(at) as *const _);
            let new = _mm512_add_epi64(_mm512_mullo_epi64(old, mult), inc);
            let lanes = (m >> at) as u8;
            _mm512_mask_storeu_epi64(self.state.as_mut_ptr().add(at) as *mut _, lanes, new);
            // ((old >> 18) ^ old) >> 27, truncated, rotated right by old >> 59.
            let xorshifted =
                _mm512_srli_epi64::<27>(_mm512_xor_si512(_mm512_srli_epi64::<18>(old), old));
            let rot = _mm512_srli_epi64::<59>(old);
            // The rotation of the low 32 bits, in 64-bit lanes: rotate the 32-bit halves,
            // then keep the low one.
            let r = _mm512_rorv_epi32(xorshifted, rot);
            *out = _mm512_cvtepi64_epi32(r);
        }
        U(_mm512_inserti64x4::<1>(
            _mm512_castsi256_si512(out[0]),
            out[1],
        ))
    }

    /// The next uniform number in [0, 1) of each lane in `m`, as `Pcg32::next_1d`: the top
    /// 24 bits times 2⁻²⁴.
    ///
    /// # Safety
    /// As [`Rng16::next_u32`].
    #[inline(always)]
    pub unsafe fn next_1d(&mut self, m: M) -> F {
        let x = self.next_u32(m);
        let top = U(_mm512_srli_epi32::<8>(x.0));
        top.to_f32() * F::splat(1.0 / (1u32 << 24) as f32)
    }
}
