//! Up to sixteen rays from one origin in one traversal of the eight-wide BVH: occlusion of a
//! vertex's shadow rays ([`WideBvh::occluded_packet`]) and the closest hits of a pinhole
//! camera's rays ([`WideBvh::closest_packet`]); and occlusion of sixteen rays of their own
//! origins, the shadow rays of a pixel's samples from their first vertices
//! (`WideBvh::occluded_origins`).
//!
//! Next-event estimation sends its shadow rays from one shading point to nearby points on
//! the lights, and a pixel's camera samples leave the eye in nearly one direction, so such
//! rays visit nearly the same nodes. Traced together, each node is fetched and its loop,
//! stack and branches paid once for all of them, and each child box is tested against eight
//! rays per 8-lane AVX instruction, or all sixteen per AVX-512 instruction where the CPU has
//! it (rays in lanes, in the manner of Wald, Slusallek, Benthin and Wagner, "Interactive
//! Rendering with Coherent Ray Tracing", Eurographics 2001, with a mask of active rays). A
//! ray found occluded leaves the mask; a subtree is entered only for the rays that enter its
//! box. Before the exact tests a node's eight children are culled against the packet's
//! interval of directions (interval arithmetic culling, as in Boulos et al., "Packet-based
//! Whitted and Distribution Ray Tracing", Graphics Interface 2007), see `avx::Coherent`. The
//! two traversals differ in what they seek ([`avx::Walk`]) and share the rest.
//!
//! The answers are exactly those of [`WideBvh::occluded`] and [`WideBvh::intersect`] for
//! each ray on its own: every box test computes the same IEEE operations on the same
//! operands, in the same order (`(slab − o) · (1/d)`, the near slab chosen by the sign of
//! `1/d`, the same max/min operand order), so a ray enters exactly the boxes it would enter
//! alone with the same `t_max`, and tests the primitives there with the caller's own test.
//! Whether a ray is occluded is a property of the set of primitives it reaches, and its
//! closest hit (of equally near ones, the lowest primitive's) one of the primitives it
//! reaches before it, not of the order they are visited in. Without AVX (checked at run
//! time; the binary is built for plain x86-64) each ray is traced on its own; with AVX-512
//! (also checked at run time) the box tests take all sixteen lanes in one register, with the
//! same operations lane by lane, so the answers do not depend on the CPU either.

use super::{Node, WideBvh, EMPTY, LEAF, STACK, WIDEN, WIDTH};
use crate::geometry::Ray;
use glam::Vec3A;

/// Rays in a packet.
pub const PACKET: usize = 16;

/// AVX registers (eight lanes each) per packet quantity.
#[cfg(target_arch = "x86_64")]
const HALVES: usize = PACKET / 8;

/// Up to sixteen rays that share their origin: a vertex's shadow rays (sixteen: the ten of
/// the TNCG15 report's Figure 3.3 in one traversal), or a pinhole camera's rays.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket {
    pub o: Vec3A,
    /// The directions, by axis then lane.
    pub d: [[f32; PACKET]; 3],
    /// Per lane, the parametric distance up to which the ray must be unobstructed.
    pub t_max: [f32; PACKET],
}

impl RayPacket {
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
    /// `hit(prim, lanes)` tests primitive `prim` against the rays of `lanes` and returns
    /// those it blocks; each lane's answer must be that of the lane's ray on its own.
    #[inline]
    pub fn occluded_packet<F: FnMut(usize, u32) -> u32>(
        &self,
        pk: &RayPacket,
        active: u32,
        hit: F,
    ) -> u32 {
        self.occluded_packet_with(pk, active, PACKET, hit)
    }

    /// [`Self::occluded_packet`] with its box tests `lanes` rays at a time, as
    /// [`Self::closest_packet_with`] chooses them.
    #[inline]
    pub(crate) fn occluded_packet_with<F: FnMut(usize, u32) -> u32>(
        &self,
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        hit: F,
    ) -> u32 {
        self.occluded_lanes(pk, None, active, lanes, hit)
    }

    /// [`Self::occluded_packet_with`] for rays of their own origins (`o`, by axis then lane;
    /// `pk.o` is not read), as the shadow rays of a pixel's samples from their first
    /// vertices are: nearby origins, directions to the lights. Each box test subtracts each
    /// lane's origin, as its ray's own test does, so the answers are again each ray's on its
    /// own; no interval of directions culls the children first.
    #[inline]
    pub(crate) fn occluded_origins<F: FnMut(usize, u32) -> u32>(
        &self,
        o: &[[f32; PACKET]; 3],
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        hit: F,
    ) -> u32 {
        self.occluded_lanes(pk, Some(o), active, lanes, hit)
    }

    /// Both of the above: the lanes' rays from `pk`, or from `origins` in the directions
    /// of `pk`.
    #[inline(always)]
    fn occluded_lanes<F: FnMut(usize, u32) -> u32>(
        &self,
        pk: &RayPacket,
        origins: Option<&[[f32; PACKET]; 3]>,
        active: u32,
        lanes: usize,
        mut hit: F,
    ) -> u32 {
        debug_assert!(active < 1 << PACKET && matches!(lanes, 1 | 8 | PACKET));
        if self.root == EMPTY || active == 0 {
            return 0;
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(wide) = avx::width(lanes) {
            let w = &mut avx::Occlusion(&mut hit);
            // SAFETY: `avx::width` checked the CPU's AVX, and AVX-512 where `wide`.
            return unsafe { avx::run(self, pk, origins, active, wide, w) };
        }
        // Without AVX, each ray by the single-ray traversal: the same answers.
        let mut occ = 0;
        for lane in crate::simd::lanes_of(active) {
            let mut ray = pk.ray(lane);
            if let Some(o) = origins {
                ray.o = Vec3A::new(o[0][lane], o[1][lane], o[2][lane]);
            }
            if self.occluded(&ray, pk.t_max[lane], |p, _| hit(p, 1 << lane) != 0) {
                occ |= 1 << lane;
            }
        }
        occ
    }

    /// The closest hits of the lanes of `active`: `hit(prim, lanes, t_max)` tests primitive
    /// `prim` against the rays of `lanes`, lowers `t_max` (by lane, from the packet's) of
    /// those whose nearest hit it becomes, and returns them, each lane's answer that of its
    /// ray on its own; returns the lanes that found one. The lanes' hits are those of
    /// [`WideBvh::intersect`] for each ray on its own (see `avx::Closest`).
    #[inline]
    pub fn closest_packet<F: FnMut(usize, u32, &mut [f32; PACKET]) -> u32>(
        &self,
        pk: &RayPacket,
        active: u32,
        hit: F,
    ) -> u32 {
        self.closest_packet_with(pk, active, PACKET, hit)
    }

    /// [`Self::closest_packet`] with its box tests `lanes` rays at a time: sixteen where
    /// `lanes` is 16 and the CPU has AVX-512, else eight where `lanes` is at least 8 and the
    /// CPU has AVX, else each ray on its own (the same answers each way, which the tests
    /// check; `Scene::occluded_packet_with` lets them choose).
    #[inline]
    pub(crate) fn closest_packet_with<F: FnMut(usize, u32, &mut [f32; PACKET]) -> u32>(
        &self,
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        mut hit: F,
    ) -> u32 {
        debug_assert!(active < 1 << PACKET && matches!(lanes, 1 | 8 | PACKET));
        if self.root == EMPTY || active == 0 {
            return 0;
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(wide) = avx::width(lanes) {
            let mut walk = avx::Closest {
                hit: &mut hit,
                t_max: pk.t_max,
            };
            // SAFETY: `avx::width` checked the CPU's AVX, and AVX-512 where `wide`.
            return unsafe { avx::run(self, pk, None, active, wide, &mut walk) };
        }
        self.closest_each(pk, active, hit)
    }

    /// The same answers, each ray by the single-ray traversal: the fallback without AVX.
    fn closest_each<F: FnMut(usize, u32, &mut [f32; PACKET]) -> u32>(
        &self,
        pk: &RayPacket,
        active: u32,
        mut hit: F,
    ) -> u32 {
        let mut t_max = pk.t_max;
        let mut found = 0;
        for lane in crate::simd::lanes_of(active) {
            let ray = pk.ray(lane);
            if self.intersect(&ray, t_max[lane], |p, t| {
                t_max[lane] = t;
                (hit(p, 1 << lane, &mut t_max) != 0).then_some(t_max[lane])
            }) {
                found |= 1 << lane;
            }
        }
        found
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::*;
    use std::arch::x86_64::*;
    use std::mem::MaybeUninit;

    /// What every box test of a packet needs, in registers.
    pub(super) struct Lanes {
        /// 1/d as `Vec3A::recip` computes it (a division, not an approximation).
        inv: [[__m256; HALVES]; 3],
        t_max: [__m256; HALVES],
        /// The origin, splatted for the eight children of a node (zero where each lane has
        /// its own).
        o: [__m256; 3],
        /// Each lane's origin (packets of kind `ORIGINS` only).
        lane_o: [[__m256; HALVES]; 3],
    }

    /// The sixteen lanes' reciprocal directions, `t_max` and origins (kind `ORIGINS` only)
    /// in AVX-512 registers.
    pub(super) struct Lanes16 {
        inv: [__m512; 3],
        t_max: __m512,
        lane_o: [__m512; 3],
    }

    impl Lanes {
        /// Each lane's `t_max` from `t` (after a closest-hit search lowered some), in both
        /// widths.
        #[inline(always)]
        unsafe fn set_t_max<const WIDE: bool>(
            &mut self,
            l16: Option<&mut Lanes16>,
            t: &[f32; PACKET],
        ) {
            for h in 0..HALVES {
                self.t_max[h] = _mm256_loadu_ps(t[8 * h..].as_ptr());
            }
            if WIDE {
                l16.unwrap_unchecked().t_max = _mm512_loadu_ps(t.as_ptr());
            }
        }

        /// The lanes whose `t_max`, widened as the box test widens it, is not below `near`:
        /// those that still reach a box they entered at `near`. (The registers hold the
        /// walk's `t_max`: [`Lanes::set_t_max`] follows every leaf that lowered one.)
        #[inline(always)]
        unsafe fn reaching<const WIDE: bool>(&self, l16: Option<&Lanes16>, near: f32) -> u32 {
            if WIDE {
                let far = _mm512_mul_ps(l16.unwrap_unchecked().t_max, _mm512_set1_ps(WIDEN));
                return u32::from(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(_mm512_set1_ps(near), far));
            }
            let mut m = 0;
            for h in 0..HALVES {
                let far = _mm256_mul_ps(self.t_max[h], _mm256_set1_ps(WIDEN));
                let le = _mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_set1_ps(near), far);
                m |= (_mm256_movemask_ps(le) as u32) << (8 * h);
            }
            m
        }
    }

    /// A traversal of a packet through the tree (which answer it seeks, and what it does at
    /// nodes and leaves), run by [`run`] for the packet's kind and width.
    pub(super) trait Walk {
        /// Walks the tree for the lanes of `active`, of kind `KIND` (see [`Coherent`]), eight
        /// lanes at a time or, with `WIDE` (and `l16`), sixteen; returns a mask of lanes
        /// (the walk's answer). Inlined into [`run8`] and [`run16`], whose target features
        /// its intrinsics are compiled with.
        unsafe fn walk<const KIND: u8, const WIDE: bool>(
            &mut self,
            bvh: &WideBvh,
            l: &mut Lanes,
            l16: Option<&mut Lanes16>,
            coh: &Coherent,
            active: u32,
        ) -> u32;
    }

    /// How a packet whose box tests may take `lanes` rays at a time (1, 8 or 16) runs here:
    /// `Some(true)` sixteen at a time (the CPU may run AVX-512: `crate::cpu`), `Some(false)`
    /// eight (AVX), `None` each ray on its own. One place for both walks' choice.
    #[inline]
    pub(super) fn width(lanes: usize) -> Option<bool> {
        (lanes >= 8 && std::arch::is_x86_feature_detected!("avx"))
            .then(|| lanes >= PACKET && crate::cpu::avx512())
    }

    /// Runs `w` for the lanes of `active` of `pk`, sixteen lanes at a time where `wide`
    /// (the CPU has AVX-512), else eight; with `origins`, each lane from its own origin
    /// (`pk.o` unread).
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn run<W: Walk>(
        bvh: &WideBvh,
        pk: &RayPacket,
        origins: Option<&[[f32; PACKET]; 3]>,
        active: u32,
        wide: bool,
        w: &mut W,
    ) -> u32 {
        let load = |a: &[f32; PACKET]| -> [__m256; HALVES] {
            std::array::from_fn(|h| _mm256_loadu_ps(a[8 * h..].as_ptr()))
        };
        let one = _mm256_set1_ps(1.0);
        let zero = [[_mm256_setzero_ps(); HALVES]; 3];
        let mut lanes = Lanes {
            inv: pk.d.map(|d| load(&d).map(|v| _mm256_div_ps(one, v))),
            t_max: load(&pk.t_max),
            // `slab − 0` is `slab`, bit for bit: the lanes subtract their own origins.
            o: match origins {
                Some(_) => [_mm256_setzero_ps(); 3],
                None => [pk.o.x, pk.o.y, pk.o.z].map(|x| _mm256_set1_ps(x)),
            },
            lane_o: origins.map_or(zero, |o| o.map(|a| load(&a))),
        };
        // (Rays of their own origins are not culled by intervals first: with the origins'
        // interval too, that culling cost more than it saved on the shadow rays of a
        // pixel's first vertices.)
        let c = match origins {
            Some(_) => None,
            None => Coherent::new(&lanes, active),
        };
        let kind = match &c {
            Some(c) if c.one_sign => COHERENT,
            Some(_) => FINITE,
            None if origins.is_some() => ORIGINS,
            None => ANY,
        };
        let c = c.unwrap_or_else(Coherent::none);
        let l = &mut lanes;
        match (kind, wide) {
            (COHERENT, false) => run8::<COHERENT, W>(bvh, l, &c, active, w),
            (FINITE, false) => run8::<FINITE, W>(bvh, l, &c, active, w),
            (ORIGINS, false) => run8::<ORIGINS, W>(bvh, l, &c, active, w),
            (_, false) => run8::<ANY, W>(bvh, l, &c, active, w),
            (COHERENT, true) => run16::<COHERENT, W>(bvh, l, pk, origins, &c, active, w),
            (FINITE, true) => run16::<FINITE, W>(bvh, l, pk, origins, &c, active, w),
            (ORIGINS, true) => run16::<ORIGINS, W>(bvh, l, pk, origins, &c, active, w),
            (_, true) => run16::<ANY, W>(bvh, l, pk, origins, &c, active, w),
        }
    }

    /// [`run`] with AVX: each child box against the rays eight at a time.
    #[target_feature(enable = "avx")]
    unsafe fn run8<const KIND: u8, W: Walk>(
        bvh: &WideBvh,
        l: &mut Lanes,
        coh: &Coherent,
        active: u32,
        w: &mut W,
    ) -> u32 {
        w.walk::<KIND, false>(bvh, l, None, coh, active)
    }

    /// [`run`] with AVX-512: each child box against all sixteen rays at once.
    #[target_feature(enable = "avx,avx512f")]
    unsafe fn run16<const KIND: u8, W: Walk>(
        bvh: &WideBvh,
        l: &mut Lanes,
        pk: &RayPacket,
        origins: Option<&[[f32; PACKET]; 3]>,
        coh: &Coherent,
        active: u32,
        w: &mut W,
    ) -> u32 {
        let one = _mm512_set1_ps(1.0);
        let mut l16 = Lanes16 {
            // The same division as the eight-lane `inv`, lane for lane.
            inv: pk
                .d
                .map(|d| _mm512_div_ps(one, _mm512_loadu_ps(d.as_ptr()))),
            t_max: _mm512_loadu_ps(pk.t_max.as_ptr()),
            lane_o: match origins {
                Some(o) => o.map(|a| _mm512_loadu_ps(a.as_ptr())),
                None => [_mm512_setzero_ps(); 3],
            },
        };
        w.walk::<KIND, true>(bvh, l, Some(&mut l16), coh, active)
    }

    /// The occlusion traversal: `hit(prim, lanes)` tests a primitive against the rays of
    /// `lanes` and returns those it blocks; the walk returns the lanes blocked.
    pub(super) struct Occlusion<F>(pub F);

    impl<F: FnMut(usize, u32) -> u32> Walk for Occlusion<F> {
        #[inline(always)]
        unsafe fn walk<const KIND: u8, const WIDE: bool>(
            &mut self,
            bvh: &WideBvh,
            l: &mut Lanes,
            l16: Option<&mut Lanes16>,
            coh: &Coherent,
            active: u32,
        ) -> u32 {
            let l16 = l16.map(|l16| &*l16);
            // (node, lanes that entered it); left uninitialised, entries are written before
            // read.
            let mut stack = [const { MaybeUninit::<(u32, u32)>::uninit() }; STACK];
            let mut len = 0;
            let (mut cur, mut mask) = (bvh.root, active);
            let mut occ = 0u32;
            loop {
                if cur & LEAF != 0 {
                    let first = ((cur & !LEAF) >> 4) as usize;
                    for p in first..first + (cur & 15) as usize {
                        occ |= (self.0)(p, mask);
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
                    let (rel, mut cand, all) = relative::<KIND>(node, l, coh);
                    let mut next = EMPTY;
                    let mut next_mask = 0;
                    while cand != 0 {
                        let c = cand.trailing_zeros() as usize;
                        cand &= cand - 1;
                        let child = node.child[c];
                        if child == EMPTY {
                            continue;
                        }
                        let m = if all & (1 << c) != 0 {
                            // Entered by every active lane: no lane's own test can fail.
                            mask
                        } else {
                            enter::<KIND, WIDE, false>(l, l16, &rel, c, mask).0
                        };
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

    /// The closest-hit traversal: `hit(prim, lanes, t_max)` tests a primitive against the
    /// rays of `lanes`, lowers the `t_max` of those whose nearest hit it becomes, and returns
    /// them; the walk returns the lanes with a hit. `t_max` starts as the packet's.
    ///
    /// A node's children are visited nearest first, by the smallest entry distance of the
    /// lanes that enter each; a postponed child is resumed by the lanes whose `t_max` is not
    /// below that distance (widened as the box test widens it), the others having found a
    /// nearer hit. Each lane enters only boxes it enters on its own with its current `t_max`
    /// (its own test, see the module's comment), and tests only primitives there; its nearest
    /// hit, of equally near ones the lowest primitive's (`Scene::keep_nearer`), does not
    /// depend on the order of the visits, so it is the single ray's.
    pub(super) struct Closest<F> {
        pub hit: F,
        pub t_max: [f32; PACKET],
    }

    impl<F: FnMut(usize, u32, &mut [f32; PACKET]) -> u32> Walk for Closest<F> {
        #[inline(always)]
        unsafe fn walk<const KIND: u8, const WIDE: bool>(
            &mut self,
            bvh: &WideBvh,
            l: &mut Lanes,
            mut l16: Option<&mut Lanes16>,
            coh: &Coherent,
            active: u32,
        ) -> u32 {
            // (node, lanes that entered it, their smallest entry distance); left
            // uninitialised, entries are written before read.
            let mut stack = [const { MaybeUninit::<(u32, u32, f32)>::uninit() }; STACK];
            let mut len = 0;
            let (mut cur, mut mask) = (bvh.root, active);
            let mut found = 0u32;
            loop {
                if cur & LEAF != 0 {
                    let first = ((cur & !LEAF) >> 4) as usize;
                    let mut nearer = 0;
                    for p in first..first + (cur & 15) as usize {
                        nearer |= (self.hit)(p, mask, &mut self.t_max);
                    }
                    if nearer != 0 {
                        found |= nearer;
                        l.set_t_max::<WIDE>(l16.as_deref_mut(), &self.t_max);
                    }
                } else {
                    let node = bvh.node(cur);
                    // (Every child is tested lane by lane: the entry distances order them.)
                    let (rel, mut cand, _) = relative::<KIND>(node, l, coh);
                    let mut entered = [(0u32, 0u32, 0f32); WIDTH];
                    let mut n = 0;
                    while cand != 0 {
                        let c = cand.trailing_zeros() as usize;
                        cand &= cand - 1;
                        let child = node.child[c];
                        if child == EMPTY {
                            continue;
                        }
                        let (m, near) = enter::<KIND, WIDE, true>(l, l16.as_deref(), &rel, c, mask);
                        if m == 0 {
                            continue;
                        }
                        // Insertion by entry distance, nearest first.
                        let mut k = n;
                        while k > 0 && entered[k - 1].2 > near {
                            entered[k] = entered[k - 1];
                            k -= 1;
                        }
                        entered[k] = (child, m, near);
                        n += 1;
                    }
                    if n > 0 {
                        for &e in entered[1..n].iter().rev() {
                            debug_assert!(len < STACK);
                            stack.get_unchecked_mut(len).write(e);
                            len += 1;
                        }
                        (cur, mask) = (entered[0].0, entered[0].1);
                        continue;
                    }
                }
                // The next postponed child that a lane still enters before its nearest hit.
                loop {
                    if len == 0 {
                        return found;
                    }
                    len -= 1;
                    let (c, m, near) = stack.get_unchecked(len).assume_init();
                    let resume = m & l.reaching::<WIDE>(l16.as_deref(), near);
                    if resume != 0 {
                        (cur, mask) = (c, resume);
                        break;
                    }
                }
            }
        }
    }

    /// A node's slabs relative to the packet's origin, all eight children at once: the
    /// single-ray test's `slab − o`, which the origin shared by all lanes lets us share too;
    /// and the children that some lane may enter, and that every active lane enters. A
    /// coherent packet needs only each axis's near and far slab (the same for all its lanes)
    /// and first culls the children no lane enters; any other needs both slabs, and a packet
    /// of finite directions culls with both. (Rays of their own origins get the slabs
    /// themselves, `l.o` being zero, and `enter` subtracts each lane's origin.)
    #[inline(always)]
    unsafe fn relative<const KIND: u8>(
        node: &Node,
        l: &Lanes,
        coh: &Coherent,
    ) -> ([[f32; WIDTH]; 6], u32, u32) {
        let slab = |s: usize| -> __m256 {
            debug_assert!(s < 6);
            // SAFETY: slab indices are below 6 (`Coherent::new`, or 0..6 below); a node's
            // bounds are 32-byte aligned.
            _mm256_load_ps(node.bounds.get_unchecked(s).as_ptr())
        };
        let mut rel = [[0f32; WIDTH]; 6];
        let mut cand = (1 << WIDTH) - 1;
        // Children every active lane surely enters (coherent packets only).
        let mut all = 0;
        if KIND == COHERENT {
            let near: [__m256; 3] =
                std::array::from_fn(|a| _mm256_sub_ps(slab(coh.near[a]), l.o[a]));
            let far: [__m256; 3] = std::array::from_fn(|a| _mm256_sub_ps(slab(coh.far[a]), l.o[a]));
            (cand, all) = coh.children(&near, &far);
            for a in 0..3 {
                _mm256_storeu_ps(rel[2 * a].as_mut_ptr(), near[a]);
                _mm256_storeu_ps(rel[2 * a + 1].as_mut_ptr(), far[a]);
            }
        } else {
            let both: [__m256; 6] = std::array::from_fn(|s| _mm256_sub_ps(slab(s), l.o[s / 2]));
            if KIND == FINITE {
                cand = coh.children_finite(&both);
            }
            for (r, v) in rel.iter_mut().zip(both) {
                _mm256_storeu_ps(r.as_mut_ptr(), v);
            }
        }
        (rel, cand, all)
    }

    /// Kinds of packet, by their active lanes' reciprocal directions: on each axis finite and
    /// of one sign, finite, or any; and of rays each from its own origin, of any directions.
    const COHERENT: u8 = 2;
    const FINITE: u8 = 1;
    const ANY: u8 = 0;
    const ORIGINS: u8 = 3;

    /// The lanes of `mask` whose rays enter child `c` of a node (its slabs minus the origin
    /// in `rel`, as [`relative`] lays them out), each by its own test, and where `NEAR` the
    /// smallest of their entry distances (else ∞). For a packet of kind `KIND`, sixteen lanes
    /// at a time with `WIDE` (and `l16`), else eight.
    #[inline(always)]
    unsafe fn enter<const KIND: u8, const WIDE: bool, const NEAR: bool>(
        l: &Lanes,
        l16: Option<&Lanes16>,
        rel: &[[f32; WIDTH]; 6],
        c: usize,
        mask: u32,
    ) -> (u32, f32) {
        // The smallest lane of an eight-lane register (the others ∞), as a number.
        let min8 = |v: __m256| {
            let v = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
            let v = _mm_min_ps(v, _mm_movehl_ps(v, v));
            _mm_cvtss_f32(_mm_min_ss(v, _mm_movehdup_ps(v)))
        };
        if WIDE {
            // The eight-lane test below, on all sixteen lanes at once: the same operations in
            // the same order (AVX-512's max and min return the second operand on a NaN as
            // AVX's do; the blend takes `hi` where the sign bit of 1/d is set, as blendv does).
            let l16 = l16.unwrap_unchecked();
            // Each lane's `slab − o` where the lanes have their own origins.
            let own = |s: f32, a: usize| {
                let s = _mm512_set1_ps(s);
                if KIND == ORIGINS {
                    _mm512_sub_ps(s, l16.lane_o[a])
                } else {
                    s
                }
            };
            let lo: [__m512; 3] = std::array::from_fn(|a| own(rel[2 * a][c], a));
            let hi: [__m512; 3] = std::array::from_fn(|a| own(rel[2 * a + 1][c], a));
            let slabs = |a: usize| {
                let inv = l16.inv[a];
                if KIND == COHERENT {
                    (_mm512_mul_ps(lo[a], inv), _mm512_mul_ps(hi[a], inv))
                } else {
                    let neg =
                        _mm512_cmplt_epi32_mask(_mm512_castps_si512(inv), _mm512_setzero_si512());
                    (
                        _mm512_mul_ps(_mm512_mask_blend_ps(neg, lo[a], hi[a]), inv),
                        _mm512_mul_ps(_mm512_mask_blend_ps(neg, hi[a], lo[a]), inv),
                    )
                }
            };
            let (tn_x, tf_x) = slabs(0);
            let (tn_y, tf_y) = slabs(1);
            let (tn_z, tf_z) = slabs(2);
            let tnear = _mm512_max_ps(
                _mm512_max_ps(_mm512_max_ps(tn_x, tn_y), tn_z),
                _mm512_setzero_ps(),
            );
            let tfar = _mm512_mul_ps(
                _mm512_min_ps(_mm512_min_ps(_mm512_min_ps(tf_x, tf_y), tf_z), l16.t_max),
                _mm512_set1_ps(WIDEN),
            );
            let enter = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(tnear, tfar) & mask as u16;
            let mut near = f32::INFINITY;
            if NEAR {
                let v = _mm512_mask_blend_ps(enter, _mm512_set1_ps(f32::INFINITY), tnear);
                let hi = _mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v));
                near = min8(_mm256_min_ps(
                    _mm512_castps512_ps256(v),
                    _mm256_castpd_ps(hi),
                ));
            }
            return (u32::from(enter), near);
        }
        // Per axis, the entry and exit distance of each lane: its near and far slab times its
        // 1/d. In a coherent packet `rel` holds them already; else each lane picks them by the
        // sign of its 1/d (blendv takes the second operand where the sign bit is set). Eight
        // lanes at a time, skipping eights with no lane in the mask.
        let lo: [__m256; 3] = std::array::from_fn(|a| _mm256_set1_ps(rel[2 * a][c]));
        let hi: [__m256; 3] = std::array::from_fn(|a| _mm256_set1_ps(rel[2 * a + 1][c]));
        let mut m = 0;
        let inf = _mm256_set1_ps(f32::INFINITY);
        let mut near = inf;
        for h in 0..HALVES {
            if (mask >> (8 * h)) & 0xff == 0 {
                continue;
            }
            let slabs = |a: usize| {
                let inv = l.inv[a][h];
                let (lo, hi) = if KIND == ORIGINS {
                    let o = l.lane_o[a][h];
                    (_mm256_sub_ps(lo[a], o), _mm256_sub_ps(hi[a], o))
                } else {
                    (lo[a], hi[a])
                };
                if KIND == COHERENT {
                    (_mm256_mul_ps(lo, inv), _mm256_mul_ps(hi, inv))
                } else {
                    (
                        _mm256_mul_ps(_mm256_blendv_ps(lo, hi, inv), inv),
                        _mm256_mul_ps(_mm256_blendv_ps(hi, lo, inv), inv),
                    )
                }
            };
            let (tn_x, tf_x) = slabs(0);
            let (tn_y, tf_y) = slabs(1);
            let (tn_z, tf_z) = slabs(2);
            // The operand order of `RayBoxes::test` (max/min return the second operand when
            // either is NaN).
            let tnear = _mm256_max_ps(
                _mm256_max_ps(_mm256_max_ps(tn_x, tn_y), tn_z),
                _mm256_setzero_ps(),
            );
            let tfar = _mm256_mul_ps(
                _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(tf_x, tf_y), tf_z), l.t_max[h]),
                _mm256_set1_ps(WIDEN),
            );
            let enter = _mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar);
            let bits = (_mm256_movemask_ps(enter) as u32) << (8 * h) & mask;
            m |= bits;
            if NEAR && bits != 0 {
                let lanes = lanes8(bits >> (8 * h));
                near = _mm256_min_ps(near, _mm256_blendv_ps(inf, tnear, lanes));
            }
        }
        (m, if NEAR { min8(near) } else { f32::INFINITY })
    }

    /// The lanes of the low eight bits of `bits` as an AVX mask (lane l set where bit l
    /// is): each lane's bit tested in place, the integer bits compared as tiny non-zero
    /// floats (AVX1 has no integer compare).
    #[inline(always)]
    unsafe fn lanes8(bits: u32) -> __m256 {
        let word = _mm256_castsi256_ps(_mm256_set1_epi32(bits as i32));
        let one = _mm256_castsi256_ps(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
        _mm256_cmp_ps::<_CMP_NEQ_UQ>(_mm256_and_ps(word, one), _mm256_setzero_ps())
    }

    /// A packet whose active lanes have finite reciprocal directions, taken as one ray with
    /// an interval of reciprocal directions per axis, for a test of a node's eight children
    /// at once that rejects those no lane enters before the exact test of each lane against
    /// the others. Where on each axis the 1/d are of one sign too (most of next-event
    /// estimation's packets: rays from a point to a small light), all lanes use the same near
    /// and far slab per axis, and the test needs only those (it rejected three children in
    /// four in the TNCG15 room, with four-wide nodes); otherwise it takes both slabs
    /// (`children_finite`: about a quarter of the room's packets, from points within the
    /// light's extent along x or y).
    ///
    /// That test never rejects a box a lane enters: a rounded product x·(1/d) is monotonic in
    /// 1/d, so its smallest and largest values over the lanes are those at the smallest and
    /// largest 1/d; the bounds of the lanes' entry and exit distances so obtained pass
    /// through the same max/min/widening as each lane's (monotonic too), so a lane with
    /// entry ≤ exit makes the bounds pass.
    pub(super) struct Coherent {
        /// On every axis, the active lanes' 1/d have one sign (else only finite).
        one_sign: bool,
        near: [usize; 3],
        far: [usize; 3],
        /// The smallest and largest 1/d of the active lanes, splatted.
        lo: [__m256; 3],
        hi: [__m256; 3],
        /// The largest and the smallest `t_max`.
        t_max: __m256,
        t_min: __m256,
    }

    impl Coherent {
        fn none() -> Coherent {
            // SAFETY: zero bits are a valid `__m256` (no AVX instruction is needed to make
            // one); never read (the general traversal ignores it).
            let z: __m256 = unsafe { std::mem::zeroed() };
            Coherent {
                one_sign: false,
                near: [0, 2, 4],
                far: [1, 3, 5],
                lo: [z; 3],
                hi: [z; 3],
                t_max: z,
                t_min: z,
            }
        }

        #[inline]
        #[target_feature(enable = "avx")]
        fn new(l: &Lanes, active: u32) -> Option<Coherent> {
            // The active lanes as masks, eight at a time.
            // SAFETY: the CPU has AVX (this function's feature).
            let on: [__m256; HALVES] =
                std::array::from_fn(|h| unsafe { lanes8(active >> (8 * h)) });
            let (inf, ninf) = (
                _mm256_set1_ps(f32::INFINITY),
                _mm256_set1_ps(f32::NEG_INFINITY),
            );
            // The active lanes' minimum (or maximum) of `v`, in all four lanes of the result.
            let reduce = |v: &[__m256; HALVES], max: bool| {
                let fill = if max { ninf } else { inf };
                let f8 = |x, y| {
                    if max {
                        _mm256_max_ps(x, y)
                    } else {
                        _mm256_min_ps(x, y)
                    }
                };
                let mut w = _mm256_blendv_ps(fill, v[0], on[0]);
                for h in 1..HALVES {
                    w = f8(w, _mm256_blendv_ps(fill, v[h], on[h]));
                }
                let f = |x, y| {
                    if max {
                        _mm_max_ps(x, y)
                    } else {
                        _mm_min_ps(x, y)
                    }
                };
                let w = f(_mm256_castps256_ps128(w), _mm256_extractf128_ps::<1>(w));
                let w = f(w, _mm_shuffle_ps::<0b01_00_11_10>(w, w));
                f(w, _mm_shuffle_ps::<0b10_11_00_01>(w, w))
            };
            let lo = l.inv.map(|v| reduce(&v, false));
            let hi = l.inv.map(|v| reduce(&v, true));
            // One sign and finite on every axis: 0 < lo or hi < 0, and both below ∞ in
            // magnitude (NaN fails every test).
            let (zero, big) = (_mm_setzero_ps(), _mm_set1_ps(f32::MAX));
            let abs = |v: __m128| _mm_andnot_ps(_mm_set1_ps(-0.0), v);
            let (mut finite, mut one_sign) = (0b1111, 0b1111);
            for a in 0..3 {
                let sign = _mm_or_ps(_mm_cmplt_ps(zero, lo[a]), _mm_cmplt_ps(hi[a], zero));
                let fin = _mm_and_ps(_mm_cmple_ps(abs(lo[a]), big), _mm_cmple_ps(abs(hi[a]), big));
                finite &= _mm_movemask_ps(fin);
                one_sign &= _mm_movemask_ps(sign);
            }
            if finite != 0b1111 {
                return None;
            }
            let neg: [usize; 3] = std::array::from_fn(|a| (_mm_cvtss_f32(hi[a]) < 0.0) as usize);
            // For the eight children of a node.
            let eight = |v: __m128| _mm256_set_m128(v, v);
            Some(Coherent {
                one_sign: one_sign == 0b1111,
                near: std::array::from_fn(|a| 2 * a + neg[a]),
                far: std::array::from_fn(|a| 2 * a + 1 - neg[a]),
                lo: lo.map(eight),
                hi: hi.map(eight),
                t_max: eight(reduce(&l.t_max, true)),
                t_min: eight(reduce(&l.t_max, false)),
            })
        }

        /// Bit c: child c may be entered by some lane, for finite 1/d of any signs (`both`:
        /// the node's six slabs minus the origin, lower then upper per axis).
        ///
        /// A lane's entry and exit distances on an axis are the smaller and the larger of
        /// its two slab products `s·(1/d)`; each product, rounded, is monotonic in 1/d, so
        /// over the lanes it lies between its values at the smallest and the largest 1/d.
        /// The smallest of the four products bounds every lane's entry from below, the
        /// largest every lane's exit from above, with the same max/min/widening after.
        #[inline]
        #[target_feature(enable = "avx")]
        fn children_finite(&self, both: &[__m256; 6]) -> u32 {
            let mut tn = [_mm256_setzero_ps(); 3];
            let mut tf = [_mm256_setzero_ps(); 3];
            for a in 0..3 {
                let (s0, s1) = (both[2 * a], both[2 * a + 1]);
                let p = [
                    _mm256_mul_ps(s0, self.lo[a]),
                    _mm256_mul_ps(s0, self.hi[a]),
                    _mm256_mul_ps(s1, self.lo[a]),
                    _mm256_mul_ps(s1, self.hi[a]),
                ];
                tn[a] = _mm256_min_ps(_mm256_min_ps(p[0], p[1]), _mm256_min_ps(p[2], p[3]));
                tf[a] = _mm256_max_ps(_mm256_max_ps(p[0], p[1]), _mm256_max_ps(p[2], p[3]));
            }
            let tnear = _mm256_max_ps(
                _mm256_max_ps(_mm256_max_ps(tn[0], tn[1]), tn[2]),
                _mm256_setzero_ps(),
            );
            let tfar = _mm256_mul_ps(
                _mm256_min_ps(
                    _mm256_min_ps(_mm256_min_ps(tf[0], tf[1]), tf[2]),
                    self.t_max,
                ),
                _mm256_set1_ps(WIDEN),
            );
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar)) as u32
        }

        /// Bits c: child c may be entered by some lane, and child c is entered by every
        /// active lane (`near`, `far`: the node's near and far slabs minus the origin).
        ///
        /// The second is the first's bounds the other way round: the largest entry and the
        /// smallest exit distance any lane can have; where even those meet, each lane's own
        /// entry and exit distances, which lie between the bounds, meet too.
        #[inline]
        #[target_feature(enable = "avx")]
        fn children(&self, near: &[__m256; 3], far: &[__m256; 3]) -> (u32, u32) {
            let mut tn = [_mm256_setzero_ps(); 3];
            let mut tf = [_mm256_setzero_ps(); 3];
            let mut tn_hi = [_mm256_setzero_ps(); 3];
            let mut tf_lo = [_mm256_setzero_ps(); 3];
            for a in 0..3 {
                let (n, f) = (near[a], far[a]);
                let (n_lo, n_hi) = (_mm256_mul_ps(n, self.lo[a]), _mm256_mul_ps(n, self.hi[a]));
                let (f_lo, f_hi) = (_mm256_mul_ps(f, self.lo[a]), _mm256_mul_ps(f, self.hi[a]));
                tn[a] = _mm256_min_ps(n_lo, n_hi);
                tn_hi[a] = _mm256_max_ps(n_lo, n_hi);
                tf[a] = _mm256_max_ps(f_lo, f_hi);
                tf_lo[a] = _mm256_min_ps(f_lo, f_hi);
            }
            let widen = _mm256_set1_ps(WIDEN);
            let zero = _mm256_setzero_ps();
            let max3 = |t: [__m256; 3]| {
                _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(t[0], t[1]), t[2]), zero)
            };
            let min3 = |t: [__m256; 3], t_max| {
                _mm256_mul_ps(
                    _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(t[0], t[1]), t[2]), t_max),
                    widen,
                )
            };
            let some = _mm256_cmp_ps::<_CMP_LE_OQ>(max3(tn), min3(tf, self.t_max));
            let every = _mm256_cmp_ps::<_CMP_LE_OQ>(max3(tn_hi), min3(tf_lo, self.t_min));
            (
                _mm256_movemask_ps(some) as u32,
                _mm256_movemask_ps(every) as u32,
            )
        }
    }
}
