//! Sixteen triangles tested against one ray at once: with AVX-512 in one pass, or with AVX
//! in two of eight lanes. The triangles of a small scene are tested this way by brute force
//! ([`crate::accel::flat`]). Embree's `Triangle8` and Wald, Benthin and Boulos ("Getting Rid
//! of Packets", RT 2008) test a leaf's triangles in the lanes of one register in the same
//! way. The first vertex and both edges are stored by axis, a lane per triangle, so a test
//! loads nine registers and runs the Möller–Trumbore arithmetic once for all lanes.
//!
//! Every lane computes exactly what [`Triangle::intersect`] computes for its triangle, with
//! the same IEEE operations in the same order: the edges `p1 − p0` and `p2 − p0` as it
//! subtracts them, glam's cross product component by component, dot products summed as
//! (x + y) + z, and one reciprocal of the determinant. No FMA is used; Rust never fuses on its
//! own. So a lane this test classes as a clear hit or a clear miss is one `intersect`
//! classes so, with the same t, u and v. A lane near an edge, or with a near-zero
//! determinant, is left to `intersect` itself, whose f64 test decides.

use super::{Ray, Triangle};
use std::arch::x86_64::*;

/// Triangles in one block.
pub const LANES: usize = 16;

/// Barycentric margin of the fast path, as in [`Triangle::intersect`].
const EDGE_EPS: f32 = 1e-4;

/// Sixteen triangles' first vertex and edges, by axis (576 bytes). Lanes without a
/// triangle hold NaN, which the test classes neither as a hit nor as a miss; the caller
/// masks them off.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct TriangleBlock {
    p0: [[f32; LANES]; 3],
    e1: [[f32; LANES]; 3],
    e2: [[f32; LANES]; 3],
}

impl TriangleBlock {
    /// A block of `tris` (at most [`LANES`]); the remaining lanes hold NaN.
    pub fn new(tris: &[Triangle]) -> Self {
        assert!(tris.len() <= LANES);
        let mut b = TriangleBlock {
            p0: [[f32::NAN; LANES]; 3],
            e1: [[f32::NAN; LANES]; 3],
            e2: [[f32::NAN; LANES]; 3],
        };
        for (lane, tri) in tris.iter().enumerate() {
            // The edges as `Triangle::intersect` subtracts them.
            let (e1, e2) = (tri.p1 - tri.p0, tri.p2 - tri.p0);
            for axis in 0..3 {
                b.p0[axis][lane] = tri.p0[axis];
                b.e1[axis][lane] = e1[axis];
                b.e2[axis][lane] = e2[axis];
            }
        }
        b
    }

    /// The block against `ray`, with AVX-512: the mask of lanes hit in (0, `t_max`) (lane
    /// by lane), the mask of lanes near an edge (to be decided by [`Triangle::intersect`]),
    /// and the lanes' t, u and v (meaningful where hit). `ray` holds the origin and
    /// direction splatted by axis ([`splat16`]).
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub unsafe fn test16(&self, ray: &[__m512; 6], t_max: __m512) -> (u32, u32, [__m512; 3]) {
        // SAFETY: each row holds sixteen f32 (the loads are unaligned ones).
        let ld = |a: &[[f32; LANES]; 3]| a.map(|r| unsafe { _mm512_loadu_ps(r.as_ptr()) });
        let (p0, e1, e2) = (ld(&self.p0), ld(&self.e1), ld(&self.e2));
        let (o, d) = ([ray[0], ray[1], ray[2]], [ray[3], ray[4], ray[5]]);
        let s: [__m512; 3] = std::array::from_fn(|a| _mm512_sub_ps(o[a], p0[a]));
        // glam's `Vec3A::cross`, component by component: x = a.y·b.z − b.y·a.z, and so on.
        let cross = |a: &[__m512; 3], b: &[__m512; 3]| {
            let m = |x, y| _mm512_mul_ps(x, y);
            [
                _mm512_sub_ps(m(a[1], b[2]), m(b[1], a[2])),
                _mm512_sub_ps(m(a[2], b[0]), m(b[2], a[0])),
                _mm512_sub_ps(m(a[0], b[1]), m(b[0], a[1])),
            ]
        };
        let dot = |a: &[__m512; 3], b: &[__m512; 3]| {
            let m = |x, y| _mm512_mul_ps(x, y);
            _mm512_add_ps(_mm512_add_ps(m(a[0], b[0]), m(a[1], b[1])), m(a[2], b[2]))
        };
        let p = cross(&d, &e2);
        let q = cross(&s, &e1);
        let one = _mm512_set1_ps(1.0);
        let inv_det = _mm512_div_ps(one, dot(&e1, &p));
        let u = _mm512_mul_ps(dot(&s, &p), inv_det);
        let v = _mm512_mul_ps(dot(&d, &q), inv_det);
        let w = _mm512_sub_ps(_mm512_sub_ps(one, u), v);
        let t = _mm512_mul_ps(dot(&e2, &q), inv_det);
        // u, v and w > ε (false for NaN), as `intersect`'s fast path.
        let eps = _mm512_set1_ps(EDGE_EPS);
        let neps = _mm512_set1_ps(-EDGE_EPS);
        let gt = |a, b| _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b);
        let lt = |a, b| _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b);
        let clear = gt(u, eps) & gt(v, eps) & gt(w, eps);
        let ahead = gt(t, _mm512_setzero_ps()) & lt(t, t_max);
        let out =
            lt(u, neps) | lt(v, neps) | gt(_mm512_add_ps(u, v), _mm512_set1_ps(1.0 + EDGE_EPS));
        let hit = (clear & ahead) as u32;
        let unsure = !(clear | out) as u32 & 0xffff;
        (hit, unsure, [t, u, v])
    }

    /// Lanes `8·half..8·half + 8` of the block against `ray`, with AVX: as
    /// [`TriangleBlock::test16`] for those eight lanes (bit 0 of the masks for the first),
    /// the hit lanes also as a vector mask (all ones where hit).
    /// `ray` holds the origin and direction splatted ([`splat8`]).
    ///
    /// # Safety
    /// The CPU must have AVX; `half` is 0 or 1.
    #[inline]
    #[target_feature(enable = "avx")]
    pub unsafe fn test8(
        &self,
        ray: &[__m256; 6],
        t_max: __m256,
        half: usize,
    ) -> (__m256, u32, [__m256; 3]) {
        debug_assert!(half < 2);
        let at = 8 * half;
        // SAFETY: each row holds sixteen f32, of which these eight.
        let ld = |a: &[[f32; LANES]; 3]| a.map(|r| unsafe { _mm256_loadu_ps(r.as_ptr().add(at)) });
        let (p0, e1, e2) = (ld(&self.p0), ld(&self.e1), ld(&self.e2));
        let (o, d) = ([ray[0], ray[1], ray[2]], [ray[3], ray[4], ray[5]]);
        let s: [__m256; 3] = std::array::from_fn(|a| _mm256_sub_ps(o[a], p0[a]));
        let cross = |a: &[__m256; 3], b: &[__m256; 3]| {
            let m = |x, y| _mm256_mul_ps(x, y);
            [
                _mm256_sub_ps(m(a[1], b[2]), m(b[1], a[2])),
                _mm256_sub_ps(m(a[2], b[0]), m(b[2], a[0])),
                _mm256_sub_ps(m(a[0], b[1]), m(b[0], a[1])),
            ]
        };
        let dot = |a: &[__m256; 3], b: &[__m256; 3]| {
            let m = |x, y| _mm256_mul_ps(x, y);
            _mm256_add_ps(_mm256_add_ps(m(a[0], b[0]), m(a[1], b[1])), m(a[2], b[2]))
        };
        let p = cross(&d, &e2);
        let q = cross(&s, &e1);
        let one = _mm256_set1_ps(1.0);
        let inv_det = _mm256_div_ps(one, dot(&e1, &p));
        let u = _mm256_mul_ps(dot(&s, &p), inv_det);
        let v = _mm256_mul_ps(dot(&d, &q), inv_det);
        let w = _mm256_sub_ps(_mm256_sub_ps(one, u), v);
        let t = _mm256_mul_ps(dot(&e2, &q), inv_det);
        let eps = _mm256_set1_ps(EDGE_EPS);
        let neps = _mm256_set1_ps(-EDGE_EPS);
        let gt = |a, b| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b);
        let lt = |a, b| _mm256_cmp_ps::<_CMP_LT_OQ>(a, b);
        let clear = _mm256_and_ps(_mm256_and_ps(gt(u, eps), gt(v, eps)), gt(w, eps));
        let ahead = _mm256_and_ps(gt(t, _mm256_setzero_ps()), lt(t, t_max));
        let out = _mm256_or_ps(
            _mm256_or_ps(lt(u, neps), lt(v, neps)),
            gt(_mm256_add_ps(u, v), _mm256_set1_ps(1.0 + EDGE_EPS)),
        );
        let hit = _mm256_and_ps(clear, ahead);
        let unsure = !(_mm256_movemask_ps(_mm256_or_ps(clear, out)) as u32) & 0xff;
        (hit, unsure, [t, u, v])
    }
}

/// A ray's origin and direction splatted by axis, for [`TriangleBlock::test16`].
///
/// # Safety
/// The CPU must have AVX-512F.
#[inline]
#[target_feature(enable = "avx512f")]
pub unsafe fn splat16(ray: &Ray) -> [__m512; 6] {
    let (o, d) = (ray.o, ray.d);
    [o.x, o.y, o.z, d.x, d.y, d.z].map(|x| _mm512_set1_ps(x))
}

/// A ray's origin and direction splatted by axis, for [`TriangleBlock::test8`].
///
/// # Safety
/// The CPU must have AVX.
#[inline]
#[target_feature(enable = "avx")]
pub unsafe fn splat8(ray: &Ray) -> [__m256; 6] {
    let (o, d) = (ray.o, ray.d);
    [o.x, o.y, o.z, d.x, d.y, d.z].map(|x| _mm256_set1_ps(x))
}
