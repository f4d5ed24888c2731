//! Random numbers for the estimators.
//!
//! Every camera sample's numbers derive only from (seed, pixel, sample index), so an image
//! does not depend on how pixels are scheduled over threads or machines: the same seed and
//! sample count give the same bits on any thread count.

use glam::Vec2;
use std::ops::{BitAnd, BitOr, BitXor};

/// SplitMix64 finaliser (Steele et al., "Fast Splittable Pseudorandom Number Generators",
/// OOPSLA 2014): a bijective 64-bit mix used to derive independent stream states.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Which numbers drive the estimators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points (Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4),
    /// 2020, via the `sobol_burley` crate), padded: each 1D or 2D request of a camera sample
    /// draws from its own scrambled sequence, so a pixel's samples are stratified in each.
    /// On the TNCG15 room it lowers the 16×16 block error by about 10 % at equal spp but costs
    /// 41 % more instructions (callgrind), so it is not the default.
    Sobol,
    /// Independent uniform numbers (PCG32), the default. Their per-pixel sample variance is an
    /// honest estimate of the error, which the statistical tests rely on.
    #[default]
    Independent,
}

impl SamplerKind {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "sobol" => Some(SamplerKind::Sobol),
            "independent" => Some(SamplerKind::Independent),
            _ => None,
        }
    }
}

/// 1D or 2D requests of a camera sample drawn from Sobol sequences; later ones (deep path
/// vertices, where stratification no longer pays for its cost) use PCG32. 32 covers the
/// camera and the first vertices with a few shadow rays each.
pub(crate) const SOBOL_DIMS: u32 = 32;
/// Sample indices the Sobol sequence covers; further samples of a pixel are independent.
const SOBOL_SAMPLES: u64 = 1 << 16;

/// The random numbers of one camera sample.
#[derive(Clone, Debug)]
pub struct Sampler {
    rng: Pcg32,
    sobol: bool,
    index: u32,
    seed: u32,
    dim: u32,
}

impl Sampler {
    /// The numbers for camera sample `index` of pixel `pixel` under `seed`.
    #[inline]
    pub fn for_sample(kind: SamplerKind, seed: u64, pixel: u64, index: u64) -> Sampler {
        let a = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let b = mix64(a ^ pixel.wrapping_mul(0xd1b5_4a32_d192_ed03));
        let c = mix64(b ^ index.wrapping_mul(0x8cb9_2ba7_2f3d_8dd7));
        Sampler {
            rng: Pcg32::new(c, b),
            sobol: kind == SamplerKind::Sobol && index < SOBOL_SAMPLES,
            index: index as u32,
            seed: (b >> 32) as u32 ^ b as u32,
            dim: 0,
        }
    }

    /// Independent numbers from two words (tests, photon tracing).
    #[inline]
    pub fn from_state(state: u64, stream: u64) -> Sampler {
        Sampler {
            rng: Pcg32::new(state, stream),
            sobol: false,
            index: 0,
            seed: 0,
            dim: 0,
        }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.rng.next_u32()
    }

    /// The PCG32 stream's state and increment, for the wavefront's lanes, which continue
    /// the stream where this sampler would (the independent sampler only).
    #[inline]
    pub(crate) fn pcg_words(&self) -> (u64, u64) {
        (self.rng.state, self.rng.inc)
    }

    /// Uniform in [0, 1).
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        if self.sobol && self.dim < SOBOL_DIMS {
            self.sobol_1d()
        } else {
            self.rng.next_1d()
        }
    }

    /// A uniform point of [0, 1)². With Sobol, every request draws dimensions 0 and 1 of its
    /// own scrambled sequence (index shuffled and bits scrambled by a per-request seed): the
    /// pixel's samples of that request form a (0, 2)-sequence, well stratified in 2D, and
    /// independent of every other request's (pbrt-v4's padded Sobol sampler).
    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        if self.sobol && self.dim < SOBOL_DIMS {
            self.sobol_2d()
        } else {
            let x = self.rng.next_1d();
            Vec2::new(x, self.rng.next_1d())
        }
    }

    /// Four uniform numbers of one request: with Sobol, one 4D point of the request's own
    /// scrambled sequence (dimensions 0–3, computed four lanes at once), so that a BSDF
    /// sample and its roulette, or a light choice and the point on it, cost one request.
    #[inline(always)]
    pub fn next_4d(&mut self) -> [f32; 4] {
        if self.sobol && self.dim < SOBOL_DIMS {
            self.sobol_4d()
        } else {
            let a = self.rng.next_1d();
            let b = self.rng.next_1d();
            let c = self.rng.next_1d();
            [a, b, c, self.rng.next_1d()]
        }
    }

    /// Three uniform numbers of one request: `next_4d` without its last (with independent
    /// numbers, one fewer is drawn).
    #[inline(always)]
    pub fn next_3d(&mut self) -> [f32; 3] {
        if self.sobol && self.dim < SOBOL_DIMS {
            let [a, b, c, _] = self.sobol_4d();
            [a, b, c]
        } else {
            let a = self.rng.next_1d();
            let b = self.rng.next_1d();
            [a, b, self.rng.next_1d()]
        }
    }

    // The Sobol paths stay out of line, so that the independent path inlines into the
    // integrators' loops (a call per random number cost 10 % of all instructions).
    #[inline(never)]
    fn sobol_1d(&mut self) -> f32 {
        let (idx, seed) = self.shuffled_index();
        to_unit(scrambled(sobol_rev_fast(idx, 0), seed, SCRAMBLE_4D[0]))
    }

    #[inline(never)]
    fn sobol_2d(&mut self) -> Vec2 {
        let (idx, seed) = self.shuffled_index();
        let x = scrambled(sobol_rev_fast(idx, 0), seed, SCRAMBLE_4D[0]);
        let y = scrambled(sobol_rev_fast(idx, 1), seed, SCRAMBLE_4D[1]);
        Vec2::new(to_unit(x), to_unit(y))
    }

    #[inline(never)]
    fn sobol_4d(&mut self) -> [f32; 4] {
        let (idx, seed) = self.shuffled_index();
        let t = sobol4_tables();
        let (a, b) = (
            t[0][(idx >> 24) as usize],
            t[1][((idx >> 16) & 0xff) as usize],
        );
        let sobol = std::array::from_fn(|d| a[d] ^ b[d]);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("sse4.1") {
            // SAFETY: the CPU has SSE4.1 (and so SSSE3), checked just above.
            return unsafe { sse41::scramble_4d(sobol, seed) };
        }
        scramble_4d(sobol, seed)
    }

    /// This request's shuffled sample index and seed ([`shuffled`]).
    #[inline]
    fn shuffled_index(&mut self) -> (u32, u32) {
        let dim = self.dim as usize;
        self.dim += 1;
        shuffled(self.seed, DIM_HASH[dim], self.index)
    }

    /// With Sobol points, the sample's index and seed and the requests it has made (for
    /// the wavefront's lanes, which continue its requests); None for independent numbers.
    #[inline]
    pub(crate) fn sobol_words(&self) -> Option<(u32, u32, u32)> {
        self.sobol.then_some((self.index, self.seed, self.dim))
    }
}

/// Unsigned 32-bit integer lanes, `u32` or a SIMD vector of them, for the Sobol points'
/// scrambling written once ([`hash`], [`owen_scramble_rev`], [`Uint::reverse_bits`]) for one
/// camera sample here and sixteen in the wavefront's lanes
/// (`integrator::wavefront::rng::Sobol16`). Every operation wraps, lane by lane.
pub(crate) trait Uint:
    Copy + BitXor<Output = Self> + BitOr<Output = Self> + BitAnd<Output = Self>
{
    fn splat(x: u32) -> Self;
    fn wrapping_add(self, o: Self) -> Self;
    fn wrapping_mul(self, o: Self) -> Self;
    fn shr<const K: u32>(self) -> Self;
    fn shl<const K: u32>(self) -> Self;
    /// The bits of each lane in reverse order (`u32::reverse_bits`); lane types with a
    /// faster way than [`reverse_bits_by_swaps`] give their own.
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        reverse_bits_by_swaps(self)
    }
}

impl Uint for u32 {
    #[inline(always)]
    fn splat(x: u32) -> u32 {
        x
    }
    #[inline(always)]
    fn wrapping_add(self, o: u32) -> u32 {
        u32::wrapping_add(self, o)
    }
    #[inline(always)]
    fn wrapping_mul(self, o: u32) -> u32 {
        u32::wrapping_mul(self, o)
    }
    #[inline(always)]
    fn shr<const K: u32>(self) -> u32 {
        self >> K
    }
    #[inline(always)]
    fn shl<const K: u32>(self) -> u32 {
        self << K
    }
    #[inline(always)]
    fn reverse_bits(self) -> u32 {
        u32::reverse_bits(self)
    }
}

/// Burley's integer hash (`sobol_burley::parts::hash`).
#[inline(always)]
pub(crate) fn hash<U: Uint>(n: U) -> U {
    let mut n = n ^ U::splat(0xe6fe_3beb); // so that zero does not map to zero
    n = n ^ n.shr::<16>();
    n = n.wrapping_mul(U::splat(0x7feb_352d));
    n = n ^ n.shr::<15>();
    n = n.wrapping_mul(U::splat(0x846c_a68b));
    n ^ n.shr::<16>()
}

/// Owen scrambling of a bit-reversed number by a hash-based permutation (Burley 2020, §3;
/// `sobol_burley::parts::owen_scramble_rev`).
#[inline(always)]
pub(crate) fn owen_scramble_rev<U: Uint>(n: U, scramble: U) -> U {
    let mut n = n ^ n.wrapping_mul(U::splat(0x3d20_adea));
    n = n.wrapping_add(scramble);
    n = n.wrapping_mul(scramble.shr::<16>() | U::splat(1));
    n = n ^ n.wrapping_mul(U::splat(0x0552_6c56));
    n ^ n.wrapping_mul(U::splat(0x53a2_2864))
}

/// The bits of each lane in reverse order (`u32::reverse_bits`): neighbours, pairs,
/// nibbles, bytes and halves swapped.
#[inline(always)]
pub(crate) fn reverse_bits_by_swaps<U: Uint>(n: U) -> U {
    let m = |lo: u32| U::splat(lo);
    let n = (n.shr::<1>() & m(0x5555_5555)) | (n & m(0x5555_5555)).shl::<1>();
    let n = (n.shr::<2>() & m(0x3333_3333)) | (n & m(0x3333_3333)).shl::<2>();
    let n = (n.shr::<4>() & m(0x0f0f_0f0f)) | (n & m(0x0f0f_0f0f)).shl::<4>();
    let n = (n.shr::<8>() & m(0x00ff_00ff)) | (n & m(0x00ff_00ff)).shl::<8>();
    n.shr::<16>() | n.shl::<16>()
}

/// Request `dim`'s seed for a camera sample of seed `seed`, and the sample's index within
/// the request's sequence: its bit-reversed `index`, Owen-scrambled with that seed (a
/// random permutation of the pixel's samples that keeps power-of-two prefixes
/// stratified), of which only the top 16 bits are used (2^16 samples at most).
#[inline(always)]
pub(crate) fn shuffled<U: Uint>(seed: U, dim_hash: U, index: U) -> (U, U) {
    let seed = hash(seed ^ dim_hash);
    let idx = owen_scramble_rev(index.reverse_bits(), hash(seed ^ U::splat(0x79c6_8e4a)));
    (idx & U::splat(0xffff_0000), seed)
}

/// A coordinate of a request's Sobol point: `sobol` (the reversed coordinate,
/// [`sobol_rev_fast`]) scrambled by the request's `seed` mixed with the dimension's constant
/// `k` (of [`SCRAMBLE_4D`]), bits in order. The uniform number is [`to_unit`] of it.
#[inline(always)]
pub(crate) fn scrambled<U: Uint>(sobol: U, seed: U, k: U) -> U {
    owen_scramble_rev(sobol, hash(seed ^ k)).reverse_bits()
}

/// A number's top 23 bits as a float in [0, 1) (`sobol_burley::parts::u32_to_f32_norm`).
#[inline(always)]
pub(crate) fn to_unit(n: u32) -> f32 {
    f32::from_bits((n >> 9) | 0x3f80_0000) - 1.0
}

/// hash(d + 0x9e3779b9) for every Sobol request d: the per-request seed mixes it in.
pub(crate) const DIM_HASH: [u32; SOBOL_DIMS as usize] = {
    let mut t = [0; SOBOL_DIMS as usize];
    let mut d = 0;
    while d < SOBOL_DIMS as usize {
        t[d] = hash_const((d as u32).wrapping_add(0x9e37_79b9));
        d += 1;
    }
    t
};

/// `sobol_burley::parts::hash`, as a const fn for the table above.
const fn hash_const(mut n: u32) -> u32 {
    n ^= 0xe6fe_3beb;
    n ^= n >> 16;
    n = n.wrapping_mul(0x7feb_352d);
    n ^= n >> 15;
    n = n.wrapping_mul(0x846c_a68b);
    n ^= n >> 16;
    n
}

/// `sobol_rev(i, d)` for d < 4 by two table lookups: Sobol points are linear over GF(2) in
/// the index bits, so the top two bytes of the index (all that 2^16 samples use) contribute
/// independently. The crate walks the set bits one by one, the dearest part of a sample.
#[inline(always)]
pub(crate) fn sobol_rev_fast(i: u32, d: usize) -> u32 {
    let t = sobol4_tables();
    t[0][(i >> 24) as usize][d] ^ t[1][((i >> 16) & 0xff) as usize][d]
}

/// Owen-scrambles the four reversed Sobol coordinates of a request with seed `seed` (one
/// hashed scramble per dimension, [`scrambled`]) and maps them to [0, 1).
fn scramble_4d(sobol: [u32; 4], seed: u32) -> [f32; 4] {
    std::array::from_fn(|d| to_unit(scrambled(sobol[d], seed, SCRAMBLE_4D[d])))
}

/// The constants that make each dimension's scramble of a request its own.
pub(crate) const SCRAMBLE_4D: [u32; 4] = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8];

/// `scramble_4d` four lanes at once in an SSE register, with SSE4.1's 32-bit multiply and
/// SSSE3's byte shuffle for the bit reversal (chosen at run time, so the binary still runs on
/// any x86-64): the same bits, in about a third of the instructions.
#[cfg(target_arch = "x86_64")]
mod sse41 {
    use super::{scrambled, to_unit, Uint, SCRAMBLE_4D};
    use std::arch::x86_64::*;
    use std::ops::{BitAnd, BitOr, BitXor};

    /// Four u32 lanes. (SAFETY of the `unsafe` blocks: SSE2 is part of x86-64; the SSE4.1
    /// and SSSE3 intrinsics run only inside `scramble_4d`, whose caller checked for them.)
    #[derive(Clone, Copy)]
    struct I4(__m128i);

    impl BitAnd for I4 {
        type Output = I4;
        #[inline(always)]
        fn bitand(self, o: I4) -> I4 {
            I4(unsafe { _mm_and_si128(self.0, o.0) })
        }
    }
    impl BitOr for I4 {
        type Output = I4;
        #[inline(always)]
        fn bitor(self, o: I4) -> I4 {
            I4(unsafe { _mm_or_si128(self.0, o.0) })
        }
    }
    impl BitXor for I4 {
        type Output = I4;
        #[inline(always)]
        fn bitxor(self, o: I4) -> I4 {
            I4(unsafe { _mm_xor_si128(self.0, o.0) })
        }
    }

    impl Uint for I4 {
        #[inline(always)]
        fn splat(x: u32) -> I4 {
            I4(unsafe { _mm_set1_epi32(x as i32) })
        }
        #[inline(always)]
        fn wrapping_add(self, o: I4) -> I4 {
            I4(unsafe { _mm_add_epi32(self.0, o.0) })
        }
        #[inline(always)]
        fn wrapping_mul(self, o: I4) -> I4 {
            I4(unsafe { _mm_mullo_epi32(self.0, o.0) })
        }
        #[inline(always)]
        fn shr<const K: u32>(self) -> I4 {
            I4(unsafe { _mm_srl_epi32(self.0, _mm_cvtsi32_si128(K as i32)) })
        }
        #[inline(always)]
        fn shl<const K: u32>(self) -> I4 {
            I4(unsafe { _mm_sll_epi32(self.0, _mm_cvtsi32_si128(K as i32)) })
        }
        /// The bytes of each lane by one shuffle, the bits of each byte by a lookup of its
        /// two nibbles, reversed and swapped.
        #[inline(always)]
        fn reverse_bits(self) -> I4 {
            unsafe {
                let n = _mm_shuffle_epi8(
                    self.0,
                    _mm_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12),
                );
                let rev_nibble =
                    _mm_setr_epi8(0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15);
                let low = _mm_set1_epi8(0x0f);
                let lo = _mm_and_si128(n, low);
                let hi = _mm_and_si128(_mm_srli_epi16::<4>(n), low);
                I4(_mm_or_si128(
                    _mm_slli_epi16::<4>(_mm_shuffle_epi8(rev_nibble, lo)),
                    _mm_shuffle_epi8(rev_nibble, hi),
                ))
            }
        }
    }

    #[target_feature(enable = "sse4.1,ssse3")]
    pub unsafe fn scramble_4d(sobol: [u32; 4], seed: u32) -> [f32; 4] {
        let load = |a: [u32; 4]| I4(_mm_loadu_si128(a.as_ptr() as *const __m128i));
        let n = scrambled(load(sobol), I4::splat(seed), load(SCRAMBLE_4D));
        let mut out = [0u32; 4];
        _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, n.0);
        out.map(to_unit)
    }
}

/// Sobol dimensions 0–3 (reversed) of each value of the index's top byte, `[0]`, and of its
/// second byte, `[1]`: the index's contribution is the XOR of the two.
pub(crate) fn sobol4_tables() -> &'static [[[u32; 4]; 256]; 2] {
    static TABLES: std::sync::OnceLock<[[[u32; 4]; 256]; 2]> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        let byte = |shift: u32| {
            std::array::from_fn(|b| {
                std::array::from_fn(|d| {
                    sobol_burley::parts::sobol_rev((b as u32) << shift, d as u32)
                })
            })
        };
        [byte(24), byte(16)]
    })
}

/// PCG32 (O'Neill, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
/// Algorithms for Random Number Generation", 2014): 64-bit state, 32-bit output.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

pub(crate) const PCG_MULT: u64 = 6_364_136_223_846_793_005;

impl Pcg32 {
    #[inline]
    pub fn new(state: u64, stream: u64) -> Pcg32 {
        let mut s = Pcg32 {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scrambling written once over `Uint` lanes gives the `sobol_burley` crate's bits
    /// (Burley's reference code): its hash, its Owen scramble, its bit reversal (the swap
    /// network the wide lanes use, against `u32::reverse_bits`) and its mapping to [0, 1).
    #[test]
    fn scrambling_matches_the_crate() {
        use sobol_burley::parts;
        let mut x = 3u64;
        for _ in 0..100_000 {
            x = mix64(x);
            let (a, b) = (x as u32, (x >> 32) as u32);
            assert_eq!(hash(a), parts::hash(a));
            assert_eq!(owen_scramble_rev(a, b), parts::owen_scramble_rev(a, b));
            assert_eq!(reverse_bits_by_swaps(a), a.reverse_bits());
            assert_eq!(to_unit(a).to_bits(), parts::u32_to_f32_norm(a).to_bits());
        }
    }

    /// The table-driven Sobol dimensions and the precomputed hashes are the crate's own
    /// functions, for every sample index the sampler uses.
    #[test]
    fn fast_sobol_matches_the_crate() {
        for i in 0..(1u32 << 16) {
            let rev = i.reverse_bits();
            for d in 0..4 {
                let want = sobol_burley::parts::sobol_rev(rev, d as u32);
                assert_eq!(sobol_rev_fast(rev, d), want, "index {i}, dimension {d}");
            }
        }
        for d in 0..SOBOL_DIMS {
            assert_eq!(DIM_HASH[d as usize], hash(d.wrapping_add(0x9e37_79b9)));
        }
        let t = sobol4_tables();
        for i in (0..(1u32 << 16)).step_by(7) {
            let rev = i.reverse_bits();
            let want: [u32; 4] = sobol_burley::parts::sobol_int4_rev(rev, 0).into();
            let got: [u32; 4] = std::array::from_fn(|d| {
                t[0][(rev >> 24) as usize][d] ^ t[1][((rev >> 16) & 0xff) as usize][d]
            });
            assert_eq!(got, want, "index {i}");
        }
    }

    /// The SSE4.1 scramble gives the bits of sobol_burley's own.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn sse41_scramble_matches() {
        if !std::arch::is_x86_feature_detected!("sse4.1") {
            return;
        }
        let mut x = 7u64;
        for _ in 0..200_000 {
            x = mix64(x);
            let sobol = [
                x as u32,
                (x >> 32) as u32,
                (x >> 7) as u32,
                (x >> 19) as u32,
            ];
            let seed = (x >> 13) as u32;
            let fast = unsafe { sse41::scramble_4d(sobol, seed) };
            assert_eq!(
                fast.map(f32::to_bits),
                scramble_4d(sobol, seed).map(f32::to_bits)
            );
        }
    }
}
