//! Occlusion of up to eight shadow rays from one origin in one traversal of the 4-wide BVH.
//!
//! Next-event estimation sends its shadow rays from one shading point to nearby points on
//! the lights, so the rays of one vertex visit nearly the same nodes. Traced together, each
//! node is fetched and its loop, stack and branches paid once for all of them, and each
//! child box is tested against all eight rays in one 8-lane AVX pass (rays in lanes, in the
//! manner of Wald, Slusallek, Benthin and Wagner, "Interactive Rendering with Coherent Ray
//! Tracing", Eurographics 2001, with the rays' lanes masked as in Benthin's packet
//! traversal). A ray found occluded leaves the mask; a subtree is entered only for the rays
//! that enter its box.
//!
//! The answers are exactly those of [`WideBvh::occluded`] for each ray on its own: every
//! box test computes the same IEEE operations on the same operands, in the same order
//! (`(slab − o) · (1/d)`, the near slab chosen by the sign of `1/d`, the same max/min
//! operand order), so a ray enters exactly the boxes it enters alone, and tests the same
//! primitives with the caller's own test. Whether a ray is occluded is a property of the
//! set of primitives it reaches, not of the order they are visited in. Without AVX (checked
//! at run time; the binary is built for plain x86-64) each ray is traced on its own.

use super::{WideBvh, EMPTY, LEAF, STACK};
use crate::geometry::{ray::gamma, Ray};
use glam::Vec3A;

/// Rays in a packet.
pub const PACKET: usize = 8;

/// Up to eight shadow rays that share their origin.
#[derive(Clone, Copy, Debug)]
pub struct ShadowPacket {
    pub o: Vec3A,
    /// The directions, by axis then lane.
    pub d: [[f32; PACKET]; 3],
    /// Per lane, the parametric distance up to which the ray must be unobstructed.
    pub t_max: [f32; PACKET],
}

impl ShadowPacket {
    /// Lane `lane` as a ray, bit for bit the one that was stored.
    #[inline(always)]
    pub fn ray(&self, lane: usize) -> Ray {
        Ray::new(
            self.o,
            Vec3A::new(self.d[0][lane], self.d[1][lane], self.d[2][lane]),
        )
    }
}

impl WideBvh {
    /// The lanes of `active` (bit i: lane i) whose rays hit something before their `t_max`.
    /// `hit(prim, lane)` tests primitive `prim` against lane `lane`'s ray and its `t_max`.
    #[inline]
    pub fn occluded_packet<F: FnMut(usize, usize) -> bool>(
        &self,
        pk: &ShadowPacket,
        active: u32,
        mut hit: F,
    ) -> u32 {
        debug_assert!(active < 1 << PACKET);
        if self.root == EMPTY || active == 0 {
            return 0;
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX, checked just above.
            return unsafe { avx::occluded(self, pk, active, &mut hit) };
        }
        self.occluded_each(pk, active, hit)
    }

    /// The same answers, each ray by the single-ray traversal: the fallback without AVX, and
    /// what the tests compare the packet traversal with.
    pub fn occluded_each<F: FnMut(usize, usize) -> bool>(
        &self,
        pk: &ShadowPacket,
        active: u32,
        mut hit: F,
    ) -> u32 {
        let mut occ = 0;
        let mut m = active;
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            if self.occluded(&pk.ray(lane), pk.t_max[lane], |p, _| hit(p, lane)) {
                occ |= 1 << lane;
            }
        }
        occ
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::*;
    use std::arch::x86_64::*;
    use std::mem::MaybeUninit;

    /// The packet traversal; see the module's comment for why its answers are the
    /// single-ray traversal's.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn occluded<F: FnMut(usize, usize) -> bool>(
        bvh: &WideBvh,
        pk: &ShadowPacket,
        active: u32,
        hit: &mut F,
    ) -> u32 {
        let load = |a: &[f32; PACKET]| _mm256_loadu_ps(a.as_ptr());
        let one = _mm256_set1_ps(1.0);
        // 1/d as `Vec3A::recip` computes it (a division, not an approximation).
        let inv = [
            _mm256_div_ps(one, load(&pk.d[0])),
            _mm256_div_ps(one, load(&pk.d[1])),
            _mm256_div_ps(one, load(&pk.d[2])),
        ];
        let t_max = load(&pk.t_max);
        let widen = _mm256_set1_ps(1.0 + 2.0 * gamma(3));
        let zero = _mm256_setzero_ps();
        let o = [
            _mm_set1_ps(pk.o.x),
            _mm_set1_ps(pk.o.y),
            _mm_set1_ps(pk.o.z),
        ];
        // (node, lanes that entered it); left uninitialised, entries are written before read.
        let mut stack = [const { MaybeUninit::<(u32, u32)>::uninit() }; STACK];
        let mut len = 0;
        let (mut cur, mut mask) = (bvh.root, active);
        let mut occ = 0u32;
        loop {
            if cur & LEAF != 0 {
                let first = ((cur & !LEAF) >> 4) as usize;
                for p in first..first + (cur & 15) as usize {
                    let mut m = mask;
                    while m != 0 {
                        let lane = m.trailing_zeros() as usize;
                        m &= m - 1;
                        if hit(p, lane) {
                            occ |= 1 << lane;
                        }
                    }
                    mask &= !occ;
                    if mask == 0 {
                        break;
                    }
                }
                if occ == active {
                    return occ;
                }
            } else {
                let node = bvh.node(cur);
                // The slabs relative to the origin, all four children at once: the single-ray
                // test's `slab − o`, which the origin shared by all lanes lets us share too.
                let mut rel = [[0f32; 4]; 6];
                for (s, r) in rel.iter_mut().enumerate() {
                    let b: __m128 = node.bounds[s].into();
                    _mm_storeu_ps(r.as_mut_ptr(), _mm_sub_ps(b, o[s / 2]));
                }
                let mut next = EMPTY;
                let mut next_mask = 0;
                for (c, &child) in node.child.iter().enumerate() {
                    if child == EMPTY {
                        continue;
                    }
                    // Per axis: the near and far slab of each lane by the sign of its 1/d
                    // (blendv takes the second operand where the sign bit is set), times 1/d.
                    let slabs = |a: usize| {
                        let lo = _mm256_set1_ps(rel[2 * a][c]);
                        let hi = _mm256_set1_ps(rel[2 * a + 1][c]);
                        (
                            _mm256_mul_ps(_mm256_blendv_ps(lo, hi, inv[a]), inv[a]),
                            _mm256_mul_ps(_mm256_blendv_ps(hi, lo, inv[a]), inv[a]),
                        )
                    };
                    let (tn_x, tf_x) = slabs(0);
                    let (tn_y, tf_y) = slabs(1);
                    let (tn_z, tf_z) = slabs(2);
                    // The operand order of `RayBoxes::test` (max/min return the second
                    // operand when either is NaN).
                    let tnear = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(tn_x, tn_y), tn_z), zero);
                    let tfar = _mm256_mul_ps(
                        _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(tf_x, tf_y), tf_z), t_max),
                        widen,
                    );
                    let m =
                        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar)) as u32 & mask;
                    if m == 0 {
                        continue;
                    }
                    if next == EMPTY {
                        (next, next_mask) = (child, m);
                    } else {
                        debug_assert!(len < STACK);
                        stack.get_unchecked_mut(len).write((child, m));
                        len += 1;
                    }
                }
                if next != EMPTY {
                    (cur, mask) = (next, next_mask);
                    continue;
                }
            }
            // The next entry with a lane not yet known to be occluded.
            loop {
                if len == 0 {
                    return occ;
                }
                len -= 1;
                let (c, m) = stack.get_unchecked(len).assume_init();
                if m & !occ != 0 {
                    (cur, mask) = (c, m & !occ);
                    break;
                }
            }
        }
    }
}
