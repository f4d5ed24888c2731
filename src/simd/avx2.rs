//! Sixteen f32 lanes in two AVX registers ([`F`]: lanes 0–7 in the first, 8–15 in the
//! second, each an [`F8`]), a [`Float`] of the lane types for CPUs without AVX-512, with the
//! operations of [`super::avx512`]: each [`F8`]'s on both halves, the IEEE operation the
//! scalar code performs on one lane (no FMA, no reciprocal approximations), so a lane
//! computes the bits that `f32` computes. A lane mask ([`M`]) is a vector mask (all ones in
//! a set lane), as the comparisons give it and `blendv` takes it. Kept as bits, every comparison had taken two `movemask`s and a pack,
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

use super::avx::{F8, M8};
use super::{Float, Sixteen};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitAndAssign, BitOr, BitOrAssign, Div, Mul, Neg, Not, Sub};

/// A mask of lanes: all ones in each lane set, all zeros in the others.
#[derive(Clone, Copy)]
pub struct M(pub [M8; 2]);

/// Sixteen f32 lanes.
#[derive(Clone, Copy)]
pub struct F(pub [F8; 2]);

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
        M(both!(h => self.0[h] & o.0[h]))
    }
}
impl BitOr for M {
    type Output = M;
    #[inline(always)]
    fn bitor(self, o: M) -> M {
        M(both!(h => self.0[h] | o.0[h]))
    }
}
impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        M(both!(h => !self.0[h]))
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
        F(both!(h => F8::load(&a[8 * h..])))
    }
    #[inline(always)]
    pub fn store(self, a: &mut [f32; 16]) {
        let (lo, hi) = a.split_at_mut(8);
        self.0[0].store(lo);
        self.0[1].store(hi);
    }
    #[inline(always)]
    pub fn to_array(self) -> [f32; 16] {
        let mut a = [0.0; 16];
        self.store(&mut a);
        a
    }
}

/// Every operation [`F8`]'s on each half.
impl Float for F {
    type Mask = M;
    #[inline(always)]
    fn any(m: M) -> bool {
        F8::any(m.0[0] | m.0[1])
    }
    #[inline(always)]
    fn splat(x: f32) -> F {
        F([F8::splat(x); 2])
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        F(both!(h => self.0[h].sqrt()))
    }
    #[inline(always)]
    fn abs(self) -> F {
        F(both!(h => self.0[h].abs()))
    }
    #[inline(always)]
    fn max_num(self, o: F) -> F {
        F(both!(h => self.0[h].max_num(o.0[h])))
    }
    #[inline(always)]
    fn min_num(self, o: F) -> F {
        F(both!(h => self.0[h].min_num(o.0[h])))
    }
    #[inline(always)]
    fn lt(self, o: F) -> M {
        M(both!(h => self.0[h].lt(o.0[h])))
    }
    #[inline(always)]
    fn le(self, o: F) -> M {
        M(both!(h => self.0[h].le(o.0[h])))
    }
    #[inline(always)]
    fn gt(self, o: F) -> M {
        M(both!(h => self.0[h].gt(o.0[h])))
    }
    #[inline(always)]
    fn ge(self, o: F) -> M {
        M(both!(h => self.0[h].ge(o.0[h])))
    }
    #[inline(always)]
    fn eq(self, o: F) -> M {
        M(both!(h => self.0[h].eq(o.0[h])))
    }
    #[inline(always)]
    fn select(m: M, a: F, b: F) -> F {
        F(both!(h => F8::select(m.0[h], a.0[h], b.0[h])))
    }
    #[inline(always)]
    fn copysign(self, sign: F) -> F {
        F(both!(h => self.0[h].copysign(sign.0[h])))
    }
    #[inline(always)]
    fn pow2i(self) -> F {
        F(both!(h => self.0[h].pow2i()))
    }
    #[inline(always)]
    fn frexp(self) -> (F, F) {
        let [(m0, e0), (m1, e1)] = both!(h => self.0[h].frexp());
        (F([m0, m1]), F([e0, e1]))
    }
    #[inline(always)]
    fn trunc(self) -> F {
        F(both!(h => self.0[h].trunc()))
    }
    #[inline(always)]
    fn gather(table: &[f32], index: F) -> F {
        F(both!(h => F8::gather(table, index.0[h])))
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
        F8::bits(m.0[0]) | F8::bits(m.0[1]) << 8
    }
    /// All ones in the lanes whose bit is set.
    #[inline(always)]
    fn from_bits(bits: u32) -> M {
        M(both!(h => unsafe {
            let each = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let b = _mm256_set1_epi32(((bits >> (8 * h)) & 0xff) as i32);
            M8(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(b, each), each)))
        }))
    }
    #[inline(always)]
    fn next_up(self) -> F {
        F(both!(h => unsafe {
            F8(_mm256_castsi256_ps(_mm256_add_epi32(
                _mm256_castps_si256(self.0[h].0),
                _mm256_set1_epi32(1),
            )))
        }))
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
        F(both!(h => F8(unsafe { _mm256_add_ps(i[h], f) })))
    }
    /// Halved three times: each lane against the lane half a register away.
    #[inline(always)]
    fn min_by_key(t: F, key: F) -> (f32, f32) {
        unsafe {
            let (t, k) = least(t.0[0].0, key.0[0].0, t.0[1].0, key.0[1].0);
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
        F(both!(h => self.0[h] + o.0[h]))
    }
}
impl Sub for F {
    type Output = F;
    #[inline(always)]
    fn sub(self, o: F) -> F {
        F(both!(h => self.0[h] - o.0[h]))
    }
}
impl Mul for F {
    type Output = F;
    #[inline(always)]
    fn mul(self, o: F) -> F {
        F(both!(h => self.0[h] * o.0[h]))
    }
}
impl Div for F {
    type Output = F;
    #[inline(always)]
    fn div(self, o: F) -> F {
        F(both!(h => self.0[h] / o.0[h]))
    }
}
impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        F(both!(h => -self.0[h]))
    }
}
