//! The random numbers of sixteen camera samples, a lane each: lane i draws exactly the
//! numbers its sample's own [`Sampler`] would, request by request.
//!
//! - [`Pcg16`]: the independent sampler's PCG32 streams ([`crate::sampler::Pcg32`]) in
//!   SIMD: the 64-bit states in two registers of eight lanes (AVX-512DQ's 64-bit multiply),
//!   the 32-bit outputs gathered into one register of sixteen.
//! - [`Samplers16`]: any sampler (Owen-scrambled Sobol points), one `Sampler` a lane, each
//!   request answered lane by lane.

use super::simd::{F, M, U};
use crate::sampler::{Sampler, SamplerKind};
use std::arch::x86_64::*;

/// The numbers of sixteen camera samples.
pub trait LaneSampler {
    /// Lane `lane` starts camera sample `index` of `pixel` (`Sampler::for_sample`).
    fn start(&mut self, lane: usize, kind: SamplerKind, seed: u64, pixel: u64, index: u64);
    /// One request of two, three or four numbers (`Sampler::next_2d`, `next_3d`,
    /// `next_4d`) for each lane in `m`; the other lanes draw nothing (their values are
    /// meaningless).
    ///
    /// # Safety
    /// The CPU must have AVX-512F and AVX-512DQ.
    unsafe fn next<const N: usize>(&mut self, m: M) -> [F; N];
}

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

/// Sixteen PCG32 streams.
#[derive(Clone)]
pub struct Pcg16 {
    state: [u64; 16],
    inc: [u64; 16],
}

impl Pcg16 {
    pub fn new() -> Pcg16 {
        Pcg16 {
            state: [0; 16],
            inc: [1; 16],
        }
    }

    /// The next 32-bit output of each lane in `m`; the other lanes' streams do not move.
    #[inline(always)]
    unsafe fn next_u32(&mut self, m: M) -> U {
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

    /// The next number in [0, 1) of each lane in `m`, as `Pcg32::next_1d`: the top 24 bits
    /// times 2⁻²⁴.
    #[inline(always)]
    unsafe fn next_1d(&mut self, m: M) -> F {
        let x = self.next_u32(m);
        let top = U(_mm512_srli_epi32::<8>(x.0));
        top.to_f32() * F::splat(1.0 / (1u32 << 24) as f32)
    }
}

impl LaneSampler for Pcg16 {
    fn start(&mut self, lane: usize, kind: SamplerKind, seed: u64, pixel: u64, index: u64) {
        (self.state[lane], self.inc[lane]) =
            Sampler::for_sample(kind, seed, pixel, index).pcg_words();
    }

    /// The independent sampler's requests are its numbers one after the other.
    #[inline(always)]
    unsafe fn next<const N: usize>(&mut self, m: M) -> [F; N] {
        let mut out = [F::zero(); N];
        for x in &mut out {
            *x = self.next_1d(m);
        }
        out
    }
}

/// Sixteen `Sampler`s, for the samplers whose numbers are not lane arithmetic.
#[derive(Clone)]
pub struct Samplers16 {
    lanes: [Sampler; 16],
}

impl Samplers16 {
    pub fn new() -> Samplers16 {
        Samplers16 {
            lanes: std::array::from_fn(|_| Sampler::from_state(0, 0)),
        }
    }
}

impl LaneSampler for Samplers16 {
    fn start(&mut self, lane: usize, kind: SamplerKind, seed: u64, pixel: u64, index: u64) {
        self.lanes[lane] = Sampler::for_sample(kind, seed, pixel, index);
    }

    #[inline(always)]
    unsafe fn next<const N: usize>(&mut self, m: M) -> [F; N] {
        debug_assert!((2..=4).contains(&N));
        let mut v = [[0f32; 16]; N];
        let mut mm = m;
        while mm != 0 {
            let l = mm.trailing_zeros() as usize;
            mm &= mm - 1;
            let s = &mut self.lanes[l];
            match N {
                2 => {
                    let u = s.next_2d();
                    (v[0][l], v[1 % N][l]) = (u.x, u.y);
                }
                3 => {
                    let u = s.next_3d();
                    for (k, x) in u.into_iter().enumerate() {
                        v[k % N][l] = x;
                    }
                }
                _ => {
                    let u = s.next_4d();
                    for (k, x) in u.into_iter().enumerate() {
                        v[k % N][l] = x;
                    }
                }
            }
        }
        v.map(|a| F::load(&a))
    }
}
