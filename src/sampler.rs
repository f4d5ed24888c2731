//! Random numbers for the estimators.
//!
//! Every camera sample owns a stream derived only from (seed, pixel, sample index), so an
//! image does not depend on how pixels are scheduled over threads or machines: the same seed
//! and sample count give the same bits on any thread count.

use glam::Vec2;

/// SplitMix64 finaliser (Steele et al., "Fast Splittable Pseudorandom Number Generators",
/// OOPSLA 2014): a bijective 64-bit mix used to derive independent stream states.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// PCG32 (O'Neill, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
/// Algorithms for Random Number Generation", 2014): 64-bit state, 32-bit output.
#[derive(Clone, Debug)]
pub struct Sampler {
    state: u64,
    inc: u64,
}

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

impl Sampler {
    /// A stream for camera sample `index` of pixel `pixel` under `seed`.
    #[inline]
    pub fn for_sample(seed: u64, pixel: u64, index: u64) -> Sampler {
        let a = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let b = mix64(a ^ pixel.wrapping_mul(0xd1b5_4a32_d192_ed03));
        let c = mix64(b ^ index.wrapping_mul(0x8cb9_2ba7_2f3d_8dd7));
        Sampler::from_state(c, b)
    }

    /// A general stream from two words (used by tests and by photon tracing).
    #[inline]
    pub fn from_state(state: u64, stream: u64) -> Sampler {
        let mut s = Sampler {
            state: 0,
            inc: (stream << 1) | 1,
        };
        s.next_u32();
        s.state = s.state.wrapping_add(state);
        s.next_u32();
        s
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1): the top 24 bits, so 1.0 can never come out.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}
