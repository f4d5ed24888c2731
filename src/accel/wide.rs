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
    min_x: Vec4,
    max_x: Vec4,
    min_y: Vec4,
    max_y: Vec4,
    min_z: Vec4,
    max_z: Vec4,
    child: [ChildRef; 4],
}

#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    pub nodes: Vec<Node4>,
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
        self.nodes.push(Node4 {
            min_x: Vec4::splat(f32::INFINITY),
            max_x: Vec4::splat(f32::NEG_INFINITY),
            min_y: Vec4::splat(f32::INFINITY),
            max_y: Vec4::splat(f32::NEG_INFINITY),
            min_z: Vec4::splat(f32::INFINITY),
            max_z: Vec4::splat(f32::NEG_INFINITY),
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
            node.min_x[slot] = kb.min.x;
            node.max_x[slot] = kb.max.x;
            node.min_y[slot] = kb.min.y;
            node.max_y[slot] = kb.max.y;
            node.min_z[slot] = kb.min.z;
            node.max_z[slot] = kb.max.z;
            node.child[slot] = r;
        }
        index as ChildRef
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
                let node = &self.nodes[cur as usize];
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

    /// Any hit before `t_max`.
    #[inline]
    pub fn occluded<F: FnMut(usize, f32) -> bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut hit: F,
    ) -> bool {
        let r = RayBoxes::new(ray);
        let mut stack = Stack::new();
        let mut cur = self.root;
        loop {
            if cur == EMPTY {
            } else if cur & LEAF != 0 {
                let first = ((cur & !LEAF) >> 4) as usize;
                for p in first..first + (cur & 15) as usize {
                    if hit(p, t_max) {
                        return true;
                    }
                }
            } else {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = r.test(node, t_max);
                while mask != 0 {
                    let s = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push(node.child[s]);
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
/// axis which bound is near (so no per-box min/max of the two slab distances is needed).
struct RayBoxes {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    neg: [bool; 3],
}

impl RayBoxes {
    #[inline]
    fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip();
        RayBoxes {
            o: [
                Vec4::splat(ray.o.x),
                Vec4::splat(ray.o.y),
                Vec4::splat(ray.o.z),
            ],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            // The sign of the reciprocal, not of the direction: −0.0 < 0.0 is false, yet its
            // reciprocal is −∞, so the far bound is the minimum.
            neg: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
        }
    }

    /// Bit mask of the children whose boxes the ray enters before `t_max`, and their entry
    /// distances. The exit distance is rounded up by 2γ(3) so that rounding never loses a box
    /// (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013).
    #[inline(always)]
    fn test(&self, n: &Node4, t_max: f32) -> (u32, Vec4) {
        let pick = |neg: bool, lo: Vec4, hi: Vec4| if neg { (hi, lo) } else { (lo, hi) };
        let (nx, fx) = pick(self.neg[0], n.min_x, n.max_x);
        let (ny, fy) = pick(self.neg[1], n.min_y, n.max_y);
        let (nz, fz) = pick(self.neg[2], n.min_z, n.max_z);
        let tn_x = (nx - self.o[0]) * self.inv[0];
        let tn_y = (ny - self.o[1]) * self.inv[1];
        let tn_z = (nz - self.o[2]) * self.inv[2];
        let tf_x = (fx - self.o[0]) * self.inv[0];
        let tf_y = (fy - self.o[1]) * self.inv[1];
        let tf_z = (fz - self.o[2]) * self.inv[2];
        let tnear = tn_x.max(tn_y).max(tn_z).max(Vec4::ZERO);
        let tfar = tf_x.min(tf_y).min(tf_z).min(Vec4::splat(t_max)) * (1.0 + 2.0 * gamma(3));
        (tnear.cmple(tfar).bitmask(), tnear)
    }
}

/// The traversal stack. The binary tree is at most `bvh::MAX_DEPTH` deep, so a wide node
/// path is too, and each level leaves at most three siblings behind: 3 × MAX_DEPTH entries
/// suffice. Left uninitialised: zeroing it cost 4 % of all instructions per ray.
struct Stack {
    items: [std::mem::MaybeUninit<u32>; 3 * super::bvh::MAX_DEPTH],
    len: usize,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            items: [std::mem::MaybeUninit::uninit(); 3 * super::bvh::MAX_DEPTH],
            len: 0,
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
        Some(unsafe { self.items[self.len].assume_init() })
    }
}
