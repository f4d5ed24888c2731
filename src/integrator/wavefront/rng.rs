//! The random numbers of sixteen camera samples, a lane each: lane i draws exactly the
//! numbers its sample's own [`Sampler`] would, request by request.
//!
//! - [`Pcg16`]: the independent sampler's PCG32 streams ([`crate::sampler::Pcg32`]), as
//!   the lanes' backend steps them ([`pcg32`]).
//! - [`Samplers16`]: any sampler (Owen-scrambled Sobol points), one `Sampler` a lane, each
//!   request answered lane by lane.

use crate::simd::Float;
use super::simd::{pcg32, F, M, U};
use crate::sampler::{Sampler, SamplerKind};

/// The numbers of sixteen camera samples.
pub trait LaneSampler {
    /// Lane `lane` starts camera sample `index` of `pixel` (`Sampler::for_sample`).
    fn start(&mut self, lane: usize, kind: SamplerKind, seed: u64, pixel: u64, index: u64);
    /// One request of two, three or four numbers (`Sampler::next_2d`, `next_3d`,
    /// `next_4d`) for each lane in `m`; the other lanes draw nothing (their values are
    /// meaningless).
    ///
    /// # Safety
    /// The CPU must have the features of the lanes' backend (see `super::simd`).
    unsafe fn next<const N: usize>(&mut self, m: M) -> [F; N];
}

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
        pcg32(&mut self.state, &self.inc, m)
    }

    /// The next number in [0, 1) of each lane in `m`, as `Pcg32::next_1d`: the top 24 bits
    /// times 2⁻²⁴.
    #[inline(always)]
    unsafe fn next_1d(&mut self, m: M) -> F {
        let x = self.next_u32(m);
        x.shr::<8>().to_f32() * F::splat(1.0 / (1u32 << 24) as f32)
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
