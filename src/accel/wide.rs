//! A 4-wide BVH: the binary SAH tree collapsed so that each node holds the boxes of up to
//! four children in structure-of-arrays form, tested against a ray in one SIMD pass (glam's
//! `Vec4` is SSE2 on x86-64 and NEON on AArch64, with a scalar fallback elsewhere).
//!
//! Collapsing follows Wald et al., "Getting Rid of Packets: Efficient SIMD Single-Ray
//! Traversal using Multi-branching BVHs", RT 2008: a node adopts its children's children,
//! largest surface area first, until it has four. Leaves stay as in the binary tree.

mod packet;

use super::bvh::Bvh;
use crate::geometry::{ray::gamma, Aabb, Ray};
use glam::Vec4;
pub use packet::{ShadowPacket, PACKET};

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

/// Fringe merging (a subtree with at most three leaves, whose own wide node would be
/// underfull, becomes one leaf): only in trees over at least `MERGE_MIN_PRIMS` primitives,
/// only for at most `MERGE_MAX` primitives, none of them costly to test (spheres), and only
/// where the subtree's surface area is below `MERGE_AREA` times the root's per primitive.
/// A merged leaf costs a test of each of its primitives where the wide node it replaces
/// cost one box test and tests of the primitives whose boxes the ray enters. It is what
/// brings the subdivided bunny's nodes from 49 to about 21 bytes a triangle (the memory
/// target); measured with callgrind it costs the 92 k-triangle bunny 5 % of its render
/// instructions (wall time within noise, the tree being 2.3× smaller), and would cost the
/// TNCG15 room, whose floor and ceiling fans it merges, 33 % (hence the size limits).
const MERGE_MIN_PRIMS: usize = 4096;
const MERGE_MAX: u32 = 4;
const MERGE_AREA: f32 = 12.0;

/// The weight of fringe merging in a tree over `n` primitives within `root` (0: none).
pub(crate) fn merge_weight(n: usize, root: &Aabb) -> f32 {
    if n < MERGE_MIN_PRIMS {
        0.0
    } else {
        n as f32 / (MERGE_AREA * root.surface_area())
    }
}

/// Whether a subtree over `prims` primitives in `leaves` leaves (some `costly`) within
/// `bounds` becomes one leaf, in a tree of merge weight `weight` (see [`merge_weight`]).
#[inline]
pub(crate) fn merges(prims: u32, leaves: u32, costly: bool, bounds: &Aabb, weight: f32) -> bool {
    weight != 0.0
        && prims <= MERGE_MAX
        && leaves <= 3
        && !costly
        && bounds.surface_area() * weight < 1.0
}

/// The top of the tree, down to subtrees over at most this many primitives, and at most a
/// sixty-fourth of the tree, is collapsed sequentially, and those subtrees in parallel (see
/// `Collapse::top`): enough of them for the threads to share the work evenly.
const PARALLEL_MIN: u32 = 1 << 15;
const PARALLEL_SHARE: u32 = 64;

/// What the collapse needs besides the binary tree.
struct Collapse<'a> {
    b: &'a Bvh,
    /// Fringe subtrees whose surface area times this is below 1 become leaves (0: none).
    merge_weight: f32,
    /// Subtrees over at most this many primitives are collapsed as one parallel task.
    parallel_min: u32,
}

impl WideBvh {
    /// Collapses a binary BVH; primitive indices keep the binary tree's order.
    pub fn from_binary(b: &Bvh) -> WideBvh {
        let mut w = WideBvh {
            nodes: Vec::new(),
            root: EMPTY,
            bounds: None,
        };
        if b.is_empty() {
            return w;
        }
        let root = b.node(0);
        w.bounds = Some(root.bounds());
        let n = b.order.len();
        let c = Collapse {
            b,
            merge_weight: merge_weight(n, &root.bounds()),
            parallel_min: PARALLEL_MIN.max(root.prims() / PARALLEL_SHARE),
        };
        if root.is_leaf() {
            let (first, count) = b.prim_range(0);
            w.root = leaf_ref(first, count);
        } else {
            w.nodes = c.top();
            w.root = 0;
        }
        w
    }

    /// Inner node `i`, without a bounds check: inner child references are made by the
    /// collapse (`subtree`) and always name a node of `nodes`.
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

    /// The tree's expected cost for a ray that meets its root, by the surface area heuristic
    /// (MacDonald and Booth 1990): the surface area of each wide node (one four-box test)
    /// and of each leaf times its primitives, over the root's. A measure of tree quality
    /// that does not depend on timing; the `scale` benchmark prints it.
    pub fn sah_cost(&self) -> f64 {
        let Some(root) = self.bounds else { return 0.0 };
        let area = |b: &Aabb| b.surface_area() as f64;
        let mut cost = 0.0;
        let mut stack = vec![(self.root, area(&root))];
        while let Some((c, a)) = stack.pop() {
            if c == EMPTY {
                continue;
            }
            if c & LEAF != 0 {
                cost += a * (c & 15) as f64;
                continue;
            }
            cost += a;
            let n = self.node(c);
            for slot in 0..4 {
                let b = Aabb {
                    min: glam::Vec3A::new(n.bounds[0][slot], n.bounds[2][slot], n.bounds[4][slot]),
                    max: glam::Vec3A::new(n.bounds[1][slot], n.bounds[3][slot], n.bounds[5][slot]),
                };
                stack.push((n.child[slot], area(&b)));
            }
        }
        cost / area(&root)
    }

    /// Closest hit. `hit(prim, t_max)` tests the primitive `prim` (in the BVH's order) and
    /// returns its distance if nearer than `t_max`; the caller keeps whatever else it needs.
    /// The closure is monomorphised, so the caller's primitive enum is matched inline, with
    /// no dynamic dispatch per ray.
    ///
    /// Children are visited nearest entry first, and the stack keeps each postponed child's
    /// entry distance: one popped after a hit nearer than its box is dropped unopened, so a
    /// wall behind the hit costs no node or triangle tests (Wald et al. 2008 do the same).
    #[inline(always)]
    pub fn intersect<F: FnMut(usize, f32) -> Option<f32>>(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut hit: F,
    ) -> bool {
        if self.root == EMPTY {
            return false;
        }
        let r = RayBoxes::new(ray);
        let mut stack = Stack::<(u32, f32)>::new();
        let mut cur = self.root;
        let mut found = false;
        loop {
            // Empty child slots have empty boxes and are never entered, so only the root can
            // be EMPTY, and it was checked above.
            if cur & LEAF != 0 {
                let first = ((cur & !LEAF) >> 4) as usize;
                for p in first..first + (cur & 15) as usize {
                    if let Some(t) = hit(p, t_max) {
                        t_max = t;
                        found = true;
                    }
                }
            } else {
                let node = self.node(cur);
                let (mut mask, tnear) = r.test(node, t_max);
                if mask != 0 {
                    let t = tnear.to_array();
                    let a = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = node.child[a];
                        continue;
                    }
                    let b = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        // Two children, the commonest case: the nearer next, the other kept.
                        let (near, far) = if t[a] <= t[b] { (a, b) } else { (b, a) };
                        stack.push((node.child[far], t[far]));
                        cur = node.child[near];
                        continue;
                    }
                    // Three or four: sorted by entry distance, farthest pushed first.
                    let mut order = [(0f32, 0u32); 4];
                    order[0] = (t[a], node.child[a]);
                    order[1] = (t[b], node.child[b]);
                    let mut n = 2;
                    while mask != 0 {
                        let s = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        order[n] = (t[s], node.child[s]);
                        n += 1;
                    }
                    for i in 1..n {
                        let mut j = i;
                        while j > 0 && order[j - 1].0 < order[j].0 {
                            order.swap(j - 1, j);
                            j -= 1;
                        }
                    }
                    for &(tc, c) in &order[..n - 1] {
                        stack.push((c, tc));
                    }
                    cur = order[n - 1].1;
                    continue;
                }
            }
            // The next postponed child whose box the ray still enters before the nearest
            // hit (widened as `RayBoxes::test` widens it, so no box the test would enter is
            // dropped).
            loop {
                match stack.pop() {
                    Some((c, tc)) if tc <= t_max * WIDEN => {
                        cur = c;
                        break;
                    }
                    Some(_) => {}
                    None => return found,
                }
            }
        }
    }

    /// Any hit before `t_max`. Order does not matter here: the first hit child is visited
    /// next and the others are pushed as they come.
    #[inline(always)]
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
        let mut stack = Stack::<u32>::new();
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

impl Collapse<'_> {
    /// Whether inner node `k` becomes a leaf: it has at most three leaves under it (its own
    /// wide node would be underfull), at most `MERGE_MAX` primitives, none costly (see
    /// `bvh::build`), and a small surface area. (The build records the leaves and the
    /// costly primitive in the node, so only it is read.)
    fn fringe(&self, k: usize) -> bool {
        let n = self.b.node(k);
        merges(
            n.prims(),
            n.leaves(),
            n.costly(),
            &n.bounds(),
            self.merge_weight,
        )
    }

    /// The wide nodes of the whole tree (root inner), its root first. The top, down to
    /// subtrees over at most `parallel_min` primitives, is collapsed here; those subtrees
    /// are collapsed in parallel, in a fixed order after the top's nodes (the layout
    /// depends on the tree alone, not on the threads). Each subtree's wide nodes are
    /// counted first, so that it is collapsed straight into its own stretch of the tree's
    /// array: counting costs a walk of the binary tree, where an array per subtree, copied
    /// into the tree's, cost as much memory again as the tree's nodes, and fresh memory is
    /// what the build spends most on (see docs/performance.md, "Fresh memory on this VM").
    fn top(&self) -> Vec<Node4> {
        let mut top = Vec::new();
        // (wide node, slot, binary node) of each subtree left to the parallel collapse
        let mut tasks = Vec::new();
        self.collapse_top(0, &mut top, &mut tasks);
        use rayon::prelude::*;
        let counts: Vec<usize> = tasks.par_iter().map(|&(_, _, k)| self.count(k)).collect();
        let total = top.len() + counts.iter().sum::<usize>();
        let mut out: Vec<Node4> = super::huge_pages::with_capacity(total);
        let mut jobs = Vec::with_capacity(tasks.len());
        let mut base = top.len();
        let mut rest = &mut out.spare_capacity_mut()[top.len()..total];
        for (&(w, slot, k), &count) in tasks.iter().zip(&counts) {
            top[w].child[slot] = base as ChildRef;
            let (here, next) = std::mem::take(&mut rest).split_at_mut(count);
            rest = next;
            jobs.push((k, here, base as ChildRef));
            base += count;
        }
        jobs.into_par_iter().for_each(|(k, buf, base)| {
            let mut stretch = Stretch { buf, len: 0, base };
            self.collapse(k, &mut stretch);
            // (`set_len` below relies on this.)
            assert_eq!(
                stretch.len,
                stretch.buf.len(),
                "count and collapse disagree"
            );
        });
        // SAFETY: the jobs wrote every slot from top.len() to total (asserted above), and
        // top fills the rest.
        unsafe {
            std::ptr::copy_nonoverlapping(top.as_ptr(), out.as_mut_ptr(), top.len());
            out.set_len(total);
        }
        out
    }

    /// The sequential top of [`Self::top`]: appends the wide node for binary inner node `i`
    /// to `out`, and recurses into its inner children over more than `parallel_min`
    /// primitives; the others go to `tasks`.
    fn collapse_top(&self, i: usize, out: &mut Vec<Node4>, tasks: &mut Vec<(usize, usize, usize)>) {
        let (node, kids) = self.node(i);
        let index = out.len();
        out.push(node);
        for (slot, &(k, area)) in kids.iter().enumerate() {
            if area < 0.0 {
                continue;
            }
            if self.b.node(k).prims() > self.parallel_min {
                let r = out.len() as ChildRef;
                out[index].child[slot] = r;
                self.collapse_top(k, out, tasks);
            } else {
                tasks.push((index, slot, k));
            }
        }
    }

    /// The number of wide nodes of the subtree under binary inner node `i`.
    fn count(&self, i: usize) -> usize {
        let kids = self.kids(i);
        1 + kids
            .iter()
            .filter(|&&(_, area)| area >= 0.0)
            .map(|&(k, _)| self.count(k))
            .sum::<usize>()
    }

    /// Appends the wide node for binary inner node `i` and its subtree to `out`; returns
    /// its index.
    fn collapse(&self, i: usize, out: &mut Stretch) -> ChildRef {
        let (node, kids) = self.node(i);
        let index = out.push(node);
        for (slot, &(k, area)) in kids.iter().enumerate() {
            if area >= 0.0 {
                let r = self.collapse(k, out);
                out.node_mut(index).child[slot] = r;
            }
        }
        index
    }

    /// The wide node for binary inner node `i`, its inner children's references left
    /// `EMPTY`, and its children (see [`Self::kids`]).
    #[inline]
    fn node(&self, i: usize) -> (Node4, ArrayVec4) {
        let b = self.b;
        let ArrayVec4 { kids, len } = self.kids(i);
        let (lo, hi) = (Vec4::splat(f32::INFINITY), Vec4::splat(f32::NEG_INFINITY));
        let mut node = Node4 {
            bounds: [lo, hi, lo, hi, lo, hi],
            child: [EMPTY; 4],
        };
        for (slot, &(k, area)) in kids[..len].iter().enumerate() {
            let kn = b.node(k);
            for axis in 0..3 {
                node.bounds[2 * axis][slot] = kn.min[axis];
                node.bounds[2 * axis + 1][slot] = kn.max[axis];
            }
            if area < 0.0 {
                let (first, count) = b.prim_range(k);
                node.child[slot] = leaf_ref(first, count);
            }
        }
        (node, ArrayVec4 { kids, len })
    }

    /// The children of the wide node for binary inner node `i`: (binary node, its surface
    /// area, or −1 for a leaf).
    #[inline]
    fn kids(&self, i: usize) -> ArrayVec4 {
        let b = self.b;
        let kid = |k: usize| {
            let n = b.node(k);
            let inner = !n.is_leaf() && !self.fringe(k);
            if inner {
                // Its right child lies far from it in the array and is read next, when
                // this node is opened or becomes a wide node itself: asked for now, the
                // cache miss overlaps this node's other work. (The left child follows it.)
                b.prefetch(b.right(k));
            }
            (
                k,
                if inner {
                    n.bounds().surface_area()
                } else {
                    -1.0
                },
            )
        };
        let mut kids = [kid(i + 1), kid(b.right(i)), (0, 0.0), (0, 0.0)];
        let mut len = 2;
        while len < 4 {
            // Open the inner child with the largest surface area.
            let mut best = None;
            for (pos, &(_, area)) in kids[..len].iter().enumerate() {
                if area >= 0.0 && best.is_none_or(|(_, a)| area > a) {
                    best = Some((pos, area));
                }
            }
            let Some((pos, _)) = best else { break };
            let k = kids[pos].0;
            kids[pos] = kid(k + 1);
            kids[len] = kid(b.right(k));
            len += 1;
        }
        ArrayVec4 { kids, len }
    }
}

/// A subtree's stretch of the wide tree's array, filled from its start; `base` is the
/// index of its first slot in the whole array.
struct Stretch<'a> {
    buf: &'a mut [std::mem::MaybeUninit<Node4>],
    len: usize,
    base: ChildRef,
}

impl Stretch<'_> {
    /// Writes `node` in the next slot (panics past the end); returns its index in the whole
    /// array.
    fn push(&mut self, node: Node4) -> ChildRef {
        self.buf[self.len].write(node);
        self.len += 1;
        self.base + (self.len - 1) as ChildRef
    }
    /// The node at index `i` of the whole array, which `push` returned.
    fn node_mut(&mut self, i: ChildRef) -> &mut Node4 {
        let k = (i - self.base) as usize;
        assert!(k < self.len);
        // SAFETY: slots below `len` were written by `push`.
        unsafe { self.buf[k].assume_init_mut() }
    }
}

/// Up to four children of a wide node, as [`Collapse::node`] gives them.
struct ArrayVec4 {
    kids: [(usize, f32); 4],
    len: usize,
}

impl ArrayVec4 {
    fn iter(&self) -> std::slice::Iter<'_, (usize, f32)> {
        self.kids[..self.len].iter()
    }
}

/// The factor by which a box's exit distance is widened: 1 + 2γ(3) (see `RayBoxes::test`).
const WIDEN: f32 = 1.0 + 2.0 * gamma(3);

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
        let tfar = tf_x.min(tf_y).min(tf_z).min(Vec4::splat(t_max)) * WIDEN;
        (tnear.cmple(tfar).bitmask(), tnear)
    }
}

/// The traversal stack (of child references, with their entry distances for the closest
/// hit). The binary tree is at most `bvh::MAX_DEPTH` deep, so a wide node path is too, and
/// each level leaves at most three siblings behind: 3 × MAX_DEPTH entries suffice. Left
/// uninitialised: zeroing it cost 4 % of all instructions per ray.
struct Stack<T: Copy> {
    items: [std::mem::MaybeUninit<T>; STACK],
    len: usize,
}

const STACK: usize = 3 * super::bvh::MAX_DEPTH;

impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn new() -> Self {
        // Built in place from an uninitialised whole: initialising `len` as a field next to
        // the uninitialised items let LLVM merge both into one memset of the whole stack.
        let mut s = std::mem::MaybeUninit::<Stack<T>>::uninit();
        // SAFETY: `len` is written before use; the items are MaybeUninit and need nothing.
        unsafe {
            std::ptr::addr_of_mut!((*s.as_mut_ptr()).len).write(0);
            s.assume_init()
        }
    }
    #[inline(always)]
    fn push(&mut self, v: T) {
        self.items[self.len] = std::mem::MaybeUninit::new(v);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below `len` was written by `push`.
        Some(unsafe { self.items.get_unchecked(self.len).assume_init() })
    }
}
