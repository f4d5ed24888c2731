//! The random numbers of sixteen camera samples, a lane each: lane i draws exactly the
//! numbers its sample's own [`Sampler`] would, request by request.
//!
//! - [`Pcg16`]: the independent sampler's PCG32 streams ([`crate::sampler::Pcg32`]), as
//!   the lanes' backend steps them ([`pcg32`]).
//! - [`Sobol16`]: the Sobol sampler's Owen-scrambled points, scrambled in the lanes, with
//!   the PCG32 streams beside them.

use crate::simd::Float;
use super::simd::{pcg32, F, M, U};
use super::{Bits, LaneMask};
use crate::sampler::{scrambled, shuffled, sobol4_tables, Uint, DIM_HASH, SCRAMBLE_4D};
use crate::sampler::SOBOL_DIMS;
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

/// Sixteen camera samples' Owen-scrambled Sobol points, computed in the lanes with the
/// sampler's own maths (`crate::sampler`'s `shuffled` and `scrambled`, written once over
/// integer lanes), and each lane's PCG32 stream for what the sampler draws from it (the
/// requests past its Sobol dimensions, the samples past its Sobol indices).
#[derive(Clone)]
pub struct Sobol16 {
    index: [u32; 16],
    seed: [u32; 16],
    /// Requests made so far.
    dim: [u32; 16],
    /// Lanes whose sample draws Sobol points at all.
    sobol: Bits,
    pcg: Pcg16,
}

impl Sobol16 {
    pub fn new() -> Sobol16 {
        Sobol16 {
            index: [0; 16],
            seed: [0; 16],
            dim: [0; 16],
            sobol: 0,
            pcg: Pcg16::new(),
        }
    }
}

impl LaneSampler for Sobol16 {
    fn start(&mut self, lane: usize, kind: SamplerKind, seed: u64, pixel: u64, index: u64) {
        let s = Sampler::for_sample(kind, seed, pixel, index);
        (self.pcg.state[lane], self.pcg.inc[lane]) = s.pcg_words();
        match s.sobol_words() {
            Some((i, seed, dim)) => {
                (self.index[lane], self.seed[lane], self.dim[lane]) = (i, seed, dim);
                self.sobol |= 1 << lane;
            }
            None => self.sobol &= !(1 << lane),
        }
    }

    /// `Sampler::next_2d`, `next_3d` and `next_4d`: with Sobol points, dimensions 0 to N − 1
    /// of the request's own scrambled sequence (`sobol_4d`), else N PCG32 numbers.
    #[inline(always)]
    unsafe fn next<const N: usize>(&mut self, m: M) -> [F; N] {
        let dim = U::load(&self.dim);
        let s = m & M::from_bits(self.sobol) & dim.lt(U::splat(SOBOL_DIMS));
        let mut out = [F::zero(); N];
        // (`s` lies in `m`.)
        let rest = m & !s;
        if rest.any() {
            out = self.pcg.next::<N>(rest);
        }
        if !s.any() {
            return out;
        }
        let (idx, seed) = shuffled(
            U::load(&self.seed),
            U::gather(&DIM_HASH, dim, s),
            U::load(&self.index),
        );
        // `sobol_rev_fast`: the tables of the index's top two bytes, four words an entry.
        let t = sobol4_tables();
        let (t0, t1) = (t[0].as_flattened(), t[1].as_flattened());
        let hi = idx.shr::<24>().shl::<2>();
        let lo = (idx.shr::<16>() & U::splat(0xff)).shl::<2>();
        for (d, x) in out.iter_mut().enumerate() {
            let at = U::splat(d as u32);
            let sobol = U::gather(t0, hi.add(at), s) ^ U::gather(t1, lo.add(at), s);
            let n = scrambled(sobol, seed, U::splat(SCRAMBLE_4D[d]));
            // `to_unit`: the top 23 bits as the mantissa of a float in [1, 2), minus one.
            let f = (n.shr::<9>() | U::splat(0x3f80_0000)).to_bits_f32() - F::splat(1.0);
            *x = F::select(s, f, *x);
        }
        U::select(s, dim.add(U::splat(1)), dim).store(&mut self.dim);
        out
    }
}
