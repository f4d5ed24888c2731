//! A 4-wide BVH: the binary SAH tree collapsed so that each node holds the boxes of up to
//! four children in structure-of-arrays form, tested against a ray in one SIMD pass (glam's
//! `Vec4` is SSE2 on x86-64 and NEON on AArch64, with a scalar fallback elsewhere).
//!
//! Collapsing follows Wald et al., "Getting Rid of Packets: Efficient SIMD Single-Ray
//! Traversal using Multi-branching BVHs", RT 2008: a node adopts its children's children,
//! largest surface area first, until it has four. Leaves stay as in the binary tree.

use super::bvh::Bvh;
use crate::geometry::{ray::gamma, Aabb, Ray};
use glam::{Vec3A, Vec4};

/// A child reference: an inner node index, or a leaf (high bit set) packing the first
/// primitive (27 bits) and the primitive count (4 bits).
type ChildRef = u32;
const LEAF: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;

#[inline]
fn leaf_ref(first: u32, count: u32) -> ChildRef {
    debug_assert!(count > 0 && count < 16 && first < (1 << 27));
    LEAF | (first << 4) | count
}

/// One 4-wide node: 6 × 16 bytes of child bounds and 4 child references (112 bytes).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Node4 {
    /// The four children's min x, max x, min y, max y, min z, max z: slab `2·axis` is the
    /// lower bound, `2·axis + 1` the upper, so a ray picks its near and far slab per axis by
    /// index (no selects per node).
    bounds: [Vec4; 6],
    child: [ChildRef; 4],
}

#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    nodes: Vec<Node4>,
    /// The root: an inner node, a single leaf, or EMPTY.
    root: ChildRef,
    bounds: Option<Aabb>,
}

impl WideBvh {
    /// Collapses a binary BVH; primitive indices keep the binary tree's order.
    pub fn from_binary(b: &Bvh) -> WideBvh {
        let mut w = WideBvh {
            nodes: Vec::with_capacity(b.nodes.len() / 2 + 1),
            root: EMPTY,
            bounds: None,
        };
        if b.order.is_empty() {
            return w;
        }
        w.bounds = Some(b.bounds());
        let root = &b.nodes[0];
        w.root = if root.count > 0 {
            leaf_ref(root.offset, root.count as u32)
        } else {
            w.collapse(b, 0)
        };
        w
    }

    fn bounds_of(b: &Bvh, i: usize) -> Aabb {
        let n = &b.nodes[i];
        Aabb {
            min: Vec3A::from_array(n.min),
            max: Vec3A::from_array(n.max),
        }
    }

    /// Builds the wide node for binary inner node `i`; returns its index.
    fn collapse(&mut self, b: &Bvh, i: usize) -> ChildRef {
        let n = &b.nodes[i];
        let mut kids: Vec<usize> = vec![i + 1, n.offset as usize];
        while kids.len() < 4 {
            // Open the inner child with the largest surface area.
            let best = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| b.nodes[k].count == 0)
                .max_by(|a, c| {
                    Self::bounds_of(b, *a.1)
                        .surface_area()
                        .total_cmp(&Self::bounds_of(b, *c.1).surface_area())
                });
            let Some((pos, &k)) = best else { break };
            kids.swap_remove(pos);
            kids.push(k + 1);
            kids.push(b.nodes[k].offset as usize);
        }
        let index = self.nodes.len();
        let (lo, hi) = (Vec4::splat(f32::INFINITY), Vec4::splat(f32::NEG_INFINITY));
        self.nodes.push(Node4 {
            bounds: [lo, hi, lo, hi, lo, hi],
            child: [EMPTY; 4],
        });
        for (slot, &k) in kids.iter().enumerate() {
            let kb = Self::bounds_of(b, k);
            let kn = &b.nodes[k];
            let r = if kn.count > 0 {
                leaf_ref(kn.offset, kn.count as u32)
            } else {
                self.collapse(b, k)
            };
            let node = &mut self.nodes[index];
            for axis in 0..3 {
                node.bounds[2 * axis][slot] = kb.min[axis];
                node.bounds[2 * axis + 1][slot] = kb.max[axis];
            }
            node.child[slot] = r;
        }
        index as ChildRef
    }

    /// Inner node `i`, without a bounds check: child references are made by `collapse` and
    /// always name a node it pushed.
    #[inline(always)]
    fn node(&self, i: ChildRef) -> &Node4 {
        debug_assert!((i as usize) < self.nodes.len());
        // SAFETY: see above; `nodes` is never shrunk after the build.
        unsafe { self.nodes.get_unchecked(i as usize) }
    }

    /// Bytes of the nodes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node4>()
    }

    pub fn bounds(&self) -> Option<Aabb> {
        self.bounds
    }

    /// Closest hit. `hit(prim, t_max)` tests the primitive `prim` (in the BVH's order) and
    /// returns its distance if nearer than `t_max`; the caller keeps whatever else it needs.
    /// The closure is monomorphised, so the caller's primitive enum is matched inline, with
    /// no dynamic dispatch per ray.
    #[inline]
    pub fn intersect<F: FnMut(usize, f32) -> Option<f32>>(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut hit: F,
    ) -> bool {
        let r = RayBoxes::new(ray);
        let mut stack = Stack::new();
        let mut cur = self.root;
        let mut found = false;
        loop {
            if cur == EMPTY {
            } else if cur & LEAF != 0 {
                let first = ((cur & !LEAF) >> 4) as usize;
                for p in first..first + (cur & 15) as usize {
                    if let Some(t) = hit(p, t_max) {
                        t_max = t;
                        found = true;
                    }
                }
            } else {
                let node = self.node(cur);
                let (mask, tnear) = r.test(node, t_max);
                if mask != 0 {
                    // Push the hit children farthest first, so the nearest is visited next.
                    let mut order = [(0f32, 0u32); 4];
                    let mut n = 0;
                    let t = tnear.to_array();
                    let mut m = mask;
                    while m != 0 {
                        let s = m.trailing_zeros() as usize;
                        m &= m - 1;
                        order[n] = (t[s], node.child[s]);
                        n += 1;
                    }
                    if n == 1 {
                        cur = order[0].1;
                        continue;
                    }
                    // Insertion sort of at most four entries, farthest first.
                    for i in 1..n {
                        let mut j = i;
                        while j > 0 && order[j - 1].0 < order[j].0 {
                            order.swap(j - 1, j);
                            j -= 1;
                        }
                    }
                    for &(_, c) in &order[..n - 1] {
                        stack.push(c);
                    }
                    cur = order[n - 1].1;
                    continue;
                }
            }
            match stack.pop() {
                Some(c) => cur = c,
                None => return found,
            }
        }
    }

    /// Any hit before `t_max`. Order does not matter here: the first hit child is visited
    /// next and the others are pushed as they come.
    #[inline]
    pub fn occluded<F: FnMut(usize, f32) -> bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut hit: F,
    ) -> bool {
        if self.root == EMPTY {
            return false;
        }
        let r = RayBoxes::new(ray);
        let mut stack = Stack::new();
        let mut cur = self.root;
        loop {
            // Empty child slots have empty boxes and are never entered, so only the root can
            // be EMPTY, and it was checked above.
            if cur & LEAF != 0 {
                let first = ((cur & !LEAF) >> 4) as usize;
                for p in first..first + (cur & 15) as usize {
                    if hit(p, t_max) {
                        return true;
                    }
                }
            } else {
                let node = self.node(cur);
                let (mut mask, _) = r.test(node, t_max);
                if mask != 0 {
                    cur = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        stack.push(node.child[mask.trailing_zeros() as usize]);
                        mask &= mask - 1;
                    }
                    continue;
                }
            }
            match stack.pop() {
                Some(c) => cur = c,
                None => return false,
            }
        }
    }
}

/// A ray prepared for 4-wide slab tests: the origin and inverse direction splatted, and per
/// axis the index of the near slab in `Node4::bounds` (so no per-box min/max of the two slab
/// distances is needed).
struct RayBoxes {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    /// `2·axis`, plus one where the ray runs towards −axis (the upper bound is then near);
    /// and the far slab of each axis.
    near: [usize; 3],
    far: [usize; 3],
}

impl RayBoxes {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip();
        // The sign of the reciprocal, not of the direction: −0.0 < 0.0 is false, yet its
        // reciprocal is −∞, so the far bound is the minimum.
        let neg = |v: f32| (v < 0.0) as usize;
        RayBoxes {
            o: [
                Vec4::splat(ray.o.x),
                Vec4::splat(ray.o.y),
                Vec4::splat(ray.o.z),
            ],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [neg(inv.x), 2 + neg(inv.y), 4 + neg(inv.z)],
            far: [1 - neg(inv.x), 3 - neg(inv.y), 5 - neg(inv.z)],
        }
    }

    /// Bit mask of the children whose boxes the ray enters before `t_max`, and their entry
    /// distances. The exit distance is rounded up by 2γ(3) so that rounding never loses a box
    /// (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013).
    #[inline(always)]
    fn test(&self, n: &Node4, t_max: f32) -> (u32, Vec4) {
        let slab = |i: usize| {
            debug_assert!(i < 6);
            // SAFETY: `near` and `far` hold indices below 6, set in `new`.
            unsafe { *n.bounds.get_unchecked(i) }
        };
        let tn_x = (slab(self.near[0]) - self.o[0]) * self.inv[0];
        let tn_y = (slab(self.near[1]) - self.o[1]) * self.inv[1];
        let tn_z = (slab(self.near[2]) - self.o[2]) * self.inv[2];
        let tf_x = (slab(self.far[0]) - self.o[0]) * self.inv[0];
        let tf_y = (slab(self.far[1]) - self.o[1]) * self.inv[1];
        let tf_z = (slab(self.far[2]) - self.o[2]) * self.inv[2];
        let tnear = tn_x.max(tn_y).max(tn_z).max(Vec4::ZERO);
        let tfar = tf_x.min(tf_y).min(tf_z).min(Vec4::splat(t_max)) * (1.0 + 2.0 * gamma(3));
        (tnear.cmple(tfar).bitmask(), tnear)
    }
}

/// The traversal stack. The binary tree is at most `bvh::MAX_DEPTH` deep, so a wide node
/// path is too, and each level leaves at most three siblings behind: 3 × MAX_DEPTH entries
/// suffice. Left uninitialised: zeroing it cost 4 % of all instructions per ray.
struct Stack {
    items: [std::mem::MaybeUninit<u32>; STACK],
    len: usize,
}

const STACK: usize = 3 * super::bvh::MAX_DEPTH;

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        // Built in place from an uninitialised whole: initialising `len` as a field next to
        // the uninitialised items let LLVM merge both into one memset of the whole stack.
        let mut s = std::mem::MaybeUninit::<Stack>::uninit();
        // SAFETY: `len` is written before use; the items are MaybeUninit and need nothing.
        unsafe {
            std::ptr::addr_of_mut!((*s.as_mut_ptr()).len).write(0);
            s.assume_init()
        }
    }
    #[inline(always)]
    fn push(&mut self, v: u32) {
        self.items[self.len] = std::mem::MaybeUninit::new(v);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<u32> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below `len` was written by `push`.
        Some(unsafe { self.items.get_unchecked(self.len).assume_init() })
    }
}
