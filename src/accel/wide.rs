//! An eight-wide BVH: the binary SAH tree collapsed so that each node holds the boxes of up
//! to eight children in structure-of-arrays form, tested against a ray in one pass: one
//! eight-lane AVX register where the CPU has AVX, else two four-lane passes (glam's `Vec4`:
//! SSE2 on x86-64, NEON on AArch64, scalar elsewhere), the same operations lane by lane.
//!
//! Collapsing follows Wald et al., "Getting Rid of Packets: Efficient SIMD Single-Ray
//! Traversal using Multi-branching BVHs", RT 2008: a node adopts its children's children,
//! largest surface area first, until it has eight. Leaves stay as in the binary tree.
//! Eight, not four, as Embree's `BVH8` for AVX CPUs: a ray visits about half as many nodes,
//! each one box test of eight children and one stack step. Measured with callgrind on the
//! bunny box's first-bounce rays (AVX2 code), 453 instructions a closest hit against 575
//! through four-wide nodes, and a fifth less time a ray on the bunny box and on the gallery
//! (docs/performance.md).

/// One step of the closest-hit traversal: the box test of node `$cur`'s children (the
/// nearest entered becomes `$cur`, the others are pushed on `$stack` with their entry
/// distances, farthest first, then `$next`), or the tests of leaf `$cur`'s primitives by
/// `$hit` (each hit nearer than `$t_max` becomes `$t_max`, and sets `$found`); then, where no
/// child was entered, the next postponed child that the ray still enters before its nearest
/// hit becomes `$cur` (then `$next`), or with none left, `$done`. Written once for the
/// single ray's loop ([`WideBvh::intersect`], where `$next` continues the loop) and for one
/// ray's turn among several ([`stream::Closest::step`], where it returns).
///
/// `$mixed` (a constant) says whether the steps of several rays interleave: the branch
/// predictor then sees their decisions mixed, and the choice between one entered child
/// and two, a third of which it mispredicted (callgrind's branch simulation, the gallery's
/// rays eight in flight), is made without a branch. A single ray's history predicts it
/// well enough that the branchless form, which costs more instructions, was slower there
/// (bunny box, rays one by one: +7 % time a ray).
macro_rules! closest_step {
    ($bvh:expr, $r:expr, $stack:expr, $cur:expr, $t_max:expr, $found:expr, $hit:expr,
     $mixed:expr, $next:block, $done:block) => {{
        // Empty child slots have empty boxes and are never entered, so only the root can be
        // EMPTY, and the callers check it.
        if $cur & LEAF != 0 {
            let first = (($cur & !LEAF) >> 4) as usize;
            for p in first..first + ($cur & 15) as usize {
                if let Some(t) = $hit(p, $t_max) {
                    $t_max = t;
                    $found = true;
                }
            }
        } else {
            let node = $bvh.node($cur);
            let (mut mask, t) = $r.test(node, $t_max);
            if mask != 0 {
                let a = lowest(mask);
                mask &= mask - 1;
                if !$mixed && mask == 0 {
                    $cur = node.child[a];
                    $next
                }
                let two = mask != 0;
                let b = lowest(mask);
                mask &= mask.wrapping_sub(1);
                if mask == 0 {
                    // One child or two (96 % of the nodes entered, with four-wide nodes): the
                    // nearer becomes `$cur`, the other (where there is one) is pushed.
                    if $mixed {
                        let swap = two & !(t[a] <= t[b]);
                        let (near, far) = if swap { (b, a) } else { (a, b) };
                        $stack.push_if((node.child[far], t[far]), two);
                        $cur = node.child[near];
                        $next
                    }
                    let (near, far) = if t[a] <= t[b] { (a, b) } else { (b, a) };
                    $stack.push((node.child[far], t[far]));
                    $cur = node.child[near];
                    $next
                }
                // Three or more: sorted by entry distance, farthest pushed first.
                let mut k = [u64::MAX; WIDTH];
                k[0] = child_key(t[a], node.child[a]);
                k[1] = child_key(t[b], node.child[b]);
                let mut n = 2;
                while mask != 0 {
                    let c = lowest(mask);
                    mask &= mask - 1;
                    // (n < WIDTH here: the mask has at most WIDTH bits. The `&` tells the
                    // compiler so, and saves the bounds check.)
                    k[n & (WIDTH - 1)] = child_key(t[c], node.child[c]);
                    n += 1;
                }
                sort_keys(&mut k, n);
                for &key in k[1..n].iter().rev() {
                    $stack.push(child_of_key(key));
                }
                $cur = child_of_key(k[0]).0;
                $next
            }
        }
        // The next postponed child whose box the ray still enters before the nearest hit
        // (widened as `RayBoxes::test` widens it, so no box the test would enter is dropped).
        loop {
            match $stack.pop() {
                Some((c, tc)) if tc <= $t_max * WIDEN => {
                    $cur = c;
                    $next
                }
                Some(_) => {}
                None => $done,
            }
        }
    }};
}

/// The child slot of the lowest bit set in a box test's `mask`, or 0 where none is: a slot
/// index either way, so that the branchless steps may read a child by it unconditionally
/// (what they read for an empty mask goes unused).
#[inline(always)]
fn lowest(mask: u32) -> usize {
    (mask.trailing_zeros() & (WIDTH as u32 - 1)) as usize
}

/// A child and its entry distance as one key that orders as the distance: entry distances
/// are non-negative (`RayBoxes::test` takes them from 0 up, and a NaN lane becomes 0), and
/// non-negative floats order as their bits.
#[inline(always)]
fn child_key(t: f32, child: ChildRef) -> u64 {
    (u64::from(t.to_bits()) << 32) | u64::from(child)
}

/// [`child_key`]'s child and entry distance, as the closest-hit stack holds them.
#[inline(always)]
fn child_of_key(k: u64) -> (ChildRef, f32) {
    (k as u32, f32::from_bits((k >> 32) as u32))
}

/// Sorts the first `n` keys of `k` (the rest `u64::MAX`), ascending, by a sorting network
/// (Knuth, TAOCP vol. 3, §5.3.4): each compare-exchange a compare and two conditional
/// moves, where an insertion sort branched on every comparison. Five of them for four keys
/// or fewer (most nodes with three entered children), nineteen (Batcher's merge exchange)
/// for up to eight. (Of equally distant children either order gives the same closest hit:
/// see `Scene::keep_nearer`.)
#[inline(always)]
fn sort_keys(k: &mut [u64; WIDTH], n: usize) {
    const FOUR: [(usize, usize); 5] = [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)];
    const EIGHT: [(usize, usize); 19] = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (1, 2),
        (5, 6),
        (0, 4),
        (3, 7),
        (1, 5),
        (2, 6),
        (1, 4),
        (3, 6),
        (2, 4),
        (3, 5),
        (3, 4),
    ];
    let pairs: &[(usize, usize)] = if n <= 4 { &FOUR } else { &EIGHT };
    for &(i, j) in pairs {
        let (lo, hi) = (k[i].min(k[j]), k[i].max(k[j]));
        k[i] = lo;
        k[j] = hi;
    }
}

/// One step of the occlusion traversal: the box test of node `$cur`'s children (the first
/// entered becomes `$cur`, the others are pushed on `$stack`, then `$next`), or the tests of
/// leaf `$cur`'s primitives by `$hit` (`$blocked` at the first hit); then, where no child
/// was entered, the next postponed child becomes `$cur` (then `$next`), or with none left,
/// `$done`. Written once for [`WideBvh::occluded`] and [`stream::Any`]'s step; `$mixed` as
/// for `closest_step!` (where rays interleave, the entered children are pushed without a
/// branch a child: a loop over them mispredicted its exit a third of the time).
macro_rules! any_step {
    ($bvh:expr, $r:expr, $stack:expr, $cur:expr, $t_max:expr, $hit:expr, $mixed:expr,
     $next:block, $blocked:block, $done:block) => {{
        // Empty child slots have empty boxes and are never entered, so only the root can be
        // EMPTY, and the callers check it.
        if $cur & LEAF != 0 {
            let first = (($cur & !LEAF) >> 4) as usize;
            for p in first..first + ($cur & 15) as usize {
                if $hit(p, $t_max) $blocked
            }
        } else {
            let node = $bvh.node($cur);
            let (mut mask, _) = $r.test(node, $t_max);
            if mask != 0 {
                $cur = node.child[lowest(mask)];
                mask &= mask - 1;
                if $mixed {
                    // All seven slots written, the entered ones counted.
                    let n = mask.count_ones() as usize;
                    let mut rest = [0; WIDTH - 1];
                    for r in &mut rest {
                        *r = node.child[lowest(mask)];
                        mask &= mask.wrapping_sub(1);
                    }
                    $stack.push_n(rest, n);
                    $next
                }
                while mask != 0 {
                    $stack.push(node.child[lowest(mask)]);
                    mask &= mask - 1;
                }
                $next
            }
        }
        match $stack.pop() {
            Some(c) => {
                $cur = c;
                $next
            }
            None => $done,
        }
    }};
}

mod packet;
mod stream;

use super::bvh::{Bvh, Nodes};
use crate::geometry::{ray::gamma, Aabb, Ray};
use glam::Vec4;
pub use packet::{RayPacket, PACKET};

/// Children of a wide node.
pub(crate) const WIDTH: usize = 8;

/// A child reference: an inner node index, or a leaf (high bit set) packing the first
/// primitive (27 bits) and the primitive count (4 bits).
pub(crate) type ChildRef = u32;
const LEAF: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;

#[inline]
fn leaf_ref(first: u32, count: u32) -> ChildRef {
    debug_assert!(count > 0 && count < 16 && first < (1 << 27));
    LEAF | (first << 4) | count
}

/// One wide node: 6 × 32 bytes of child bounds and 8 child references (224 bytes).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Node {
    /// The eight children's min x, max x, min y, max y, min z, max z: slab `2·axis` is the
    /// lower bound, `2·axis + 1` the upper, so a ray picks its near and far slab per axis by
    /// index (no selects per node). An empty slot's box is empty (+∞ to −∞), and no ray
    /// enters it.
    bounds: [[f32; WIDTH]; 6],
    child: [ChildRef; WIDTH],
}

impl Node {
    /// A node with every slot empty.
    fn empty() -> Node {
        let (lo, hi) = ([f32::INFINITY; WIDTH], [f32::NEG_INFINITY; WIDTH]);
        Node {
            bounds: [lo, hi, lo, hi, lo, hi],
            child: [EMPTY; WIDTH],
        }
    }
    /// The box of child `slot` (empty for an empty slot).
    fn child_box(&self, slot: usize) -> Aabb {
        let b = &self.bounds;
        Aabb {
            min: glam::Vec3A::new(b[0][slot], b[2][slot], b[4][slot]),
            max: glam::Vec3A::new(b[1][slot], b[3][slot], b[5][slot]),
        }
    }

    /// This node as it lies in a tree whose nodes were collapsed on their own, counted from
    /// 0, and then placed from index `base` on: its inner children's references moved by
    /// `base`.
    #[inline]
    pub(crate) fn rebased(mut self, base: u32) -> Node {
        for c in &mut self.child {
            *c = rebased(*c, base);
        }
        self
    }
    /// Sets child `slot`'s reference.
    pub(crate) fn set_child(&mut self, slot: usize, r: ChildRef) {
        self.child[slot] = r;
    }
}

/// A child reference `r` of a subtree collapsed on its own, placed from index `base` on.
#[inline]
pub(crate) fn rebased(r: ChildRef, base: u32) -> ChildRef {
    if r == EMPTY || r & LEAF != 0 {
        r
    } else {
        r + base
    }
}

#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    nodes: Vec<Node>,
    /// The root: an inner node, a single leaf, or EMPTY.
    root: ChildRef,
    bounds: Option<Aabb>,
}

/// Fringe merging (a subtree with at most `MERGE_LEAVES` leaves, whose own wide node would
/// be underfull, becomes one leaf): only in trees over at least `MERGE_MIN_PRIMS`
/// primitives, only for at most `MERGE_MAX` primitives, none of them costly to test
/// (spheres), and only where the subtree's surface area is below `MERGE_AREA` times the
/// root's per primitive. A merged leaf costs a test of each of its primitives where the wide
/// node it replaces cost one box test and tests of the primitives whose boxes the ray
/// enters. It keeps the tree within the memory target: with four-wide nodes it merged up to
/// four primitives in up to three leaves, and cost the 92 k-triangle bunny 5 % of its render
/// instructions (callgrind; wall time within noise, the tree 2.3× smaller); with eight-wide
/// nodes those limits left the subdivided bunny at 59–65 bytes a triangle in all (`cargo
/// bench --bench scale`, 15 k to 10 M triangles), six primitives in five leaves at 51–59,
/// at the same render rates (eight in seven: 50–57, 1–5 % slower). It would cost the TNCG15
/// room, whose floor and ceiling fans it merges, 33 % (hence the size limits).
const MERGE_MIN_PRIMS: usize = 4096;
pub(crate) const MERGE_MAX: u32 = 6;
const MERGE_LEAVES: u32 = 5;
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
        && leaves <= MERGE_LEAVES
        && !costly
        && bounds.surface_area() * weight < 1.0
}

/// What the collapse reads: the binary nodes, and the tree's merge weight (fringe subtrees
/// whose surface area times it is below 1 become leaves; 0: none).
pub(crate) struct Collapse<'a> {
    b: Nodes<'a>,
    merge_weight: f32,
    /// The stubs a wide node would have opened (see [`Self::wanted`]).
    wanted: std::cell::RefCell<Vec<usize>>,
}

/// A child slot of a wide node that the collapse left `EMPTY` for its caller, as it stands
/// for a stub (a subtree collapsed elsewhere): the wide node (its index in the collapse's
/// output), the slot, and the stub's binary node.
pub(crate) type External = (usize, usize, usize);

/// [`Kids`]' mark for a child that is a leaf of the wide tree; inner children carry
/// their surface area.
const LEAF_KID: f32 = -1.0;

impl WideBvh {
    /// Collapses a binary BVH; primitive indices keep the binary tree's order.
    pub fn from_binary(b: &Bvh) -> WideBvh {
        if b.is_empty() {
            return WideBvh {
                nodes: Vec::new(),
                root: EMPTY,
                bounds: None,
            };
        }
        let nodes = b.nodes();
        let bounds = nodes.node(0).bounds();
        let c = Collapse::new(nodes, merge_weight(b.order.len(), &bounds));
        let mut out = Vec::new();
        let root = c.subtree(0, &mut out, &mut Vec::new());
        WideBvh {
            nodes: out,
            root,
            bounds: Some(bounds),
        }
    }

    /// The tree of `nodes`, its root `root` (a node's index, or a leaf), within `bounds`.
    pub(crate) fn from_parts(nodes: Vec<Node>, root: ChildRef, bounds: Aabb) -> WideBvh {
        WideBvh {
            nodes,
            root,
            bounds: Some(bounds),
        }
    }

    /// Inner node `i`, without a bounds check: inner child references are made by the
    /// collapse (`subtree`) and always name a node of `nodes`.
    #[inline(always)]
    fn node(&self, i: ChildRef) -> &Node {
        debug_assert!((i as usize) < self.nodes.len());
        // SAFETY: see above; `nodes` is never shrunk after the build.
        unsafe { self.nodes.get_unchecked(i as usize) }
    }

    /// Bytes of the nodes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
    }

    pub fn bounds(&self) -> Option<Aabb> {
        self.bounds
    }

    /// The tree's expected cost for a ray that meets its root, by the surface area heuristic
    /// (MacDonald and Booth 1990): the surface area of each wide node (one eight-box test)
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
            for slot in 0..WIDTH {
                stack.push((n.child[slot], area(&n.child_box(slot))));
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
    /// Each turn of the loop is `closest_step!`, written once for this loop and for
    /// [`Closest::step`], which [`WideBvh::intersect_stream`] takes a step at a time for each
    /// of several rays. (A loop of `Closest::step` calls made single rays 4 % more
    /// instructions: the macro keeps this loop's code as it was.)
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
        let mut items = [std::mem::MaybeUninit::uninit(); STACK];
        let mut stack = LocalStack::<(u32, f32)>::new(&mut items);
        let mut cur = self.root;
        let mut found = false;
        'trav: loop {
            closest_step!(
                self,
                r,
                stack,
                cur,
                t_max,
                found,
                hit,
                false,
                { continue 'trav },
                { return found }
            )
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
        let mut items = [std::mem::MaybeUninit::uninit(); STACK];
        let mut stack = LocalStack::<u32>::new(&mut items);
        let mut cur = self.root;
        'trav: loop {
            any_step!(
                self,
                r,
                stack,
                cur,
                t_max,
                hit,
                false,
                { continue 'trav },
                { return true },
                { return false }
            )
        }
    }
}

impl<'a> Collapse<'a> {
    pub(crate) fn new(b: Nodes<'a>, merge_weight: f32) -> Self {
        Collapse {
            b,
            merge_weight,
            wanted: Default::default(),
        }
    }

    /// The stubs that the collapse so far would have opened, as a collapse of the whole
    /// binary tree would: where there are any, the wide nodes it wrote are not that
    /// collapse's, and the caller must build the stubs' children and collapse again.
    pub(crate) fn wanted(self) -> Vec<usize> {
        self.wanted.into_inner()
    }

    /// Whether inner node `k` becomes a leaf: it has at most `MERGE_LEAVES` leaves under it
    /// (its own wide node would be underfull), at most `MERGE_MAX` primitives, none costly (see
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

    /// The reference to the subtree under binary node `i` (not a stub): a leaf, or the wide
    /// node appended to `out` for it, its subtree after it, each node's index its position
    /// in `out`. Children that are stubs (subtrees collapsed elsewhere) are left `EMPTY` and
    /// listed in `ext`.
    pub(crate) fn subtree(
        &self,
        i: usize,
        out: &mut Vec<Node>,
        ext: &mut Vec<External>,
    ) -> ChildRef {
        debug_assert!(!self.b.node(i).is_stub());
        if self.b.node(i).is_leaf() || self.fringe(i) {
            let (first, count) = self.b.prim_range(i);
            leaf_ref(first, count)
        } else {
            self.collapse(i, out, ext)
        }
    }

    /// Appends the wide node for binary inner node `i` and its subtree to `out` (depth
    /// first, each node before its children); returns its index.
    fn collapse(&self, i: usize, out: &mut Vec<Node>, ext: &mut Vec<External>) -> ChildRef {
        let (node, kids) = self.node(i);
        let index = out.len();
        out.push(node);
        for (slot, &(k, area)) in kids.iter().enumerate() {
            if area >= 0.0 {
                if self.b.node(k).is_stub() {
                    ext.push((index, slot, k));
                } else {
                    let r = self.collapse(k, out, ext);
                    out[index].child[slot] = r;
                }
            }
        }
        index as ChildRef
    }

    /// The wide node for binary inner node `i`, its inner children's references left
    /// `EMPTY`, and its children (see [`Self::kids`]).
    #[inline]
    fn node(&self, i: usize) -> (Node, Kids) {
        let b = self.b;
        let Kids { kids, len } = self.kids(i);
        let mut node = Node::empty();
        for (slot, &(k, area)) in kids[..len].iter().enumerate() {
            let kn = b.node(k);
            for axis in 0..3 {
                node.bounds[2 * axis][slot] = kn.min[axis];
                node.bounds[2 * axis + 1][slot] = kn.max[axis];
            }
            if area == LEAF_KID {
                let (first, count) = b.prim_range(k);
                node.child[slot] = leaf_ref(first, count);
            }
        }
        (node, Kids { kids, len })
    }

    /// The children of the wide node for binary inner node `i`: (binary node, its surface
    /// area, or `LEAF_KID` for a leaf). A stub it would open is listed in `wanted`, and
    /// left as it is.
    #[inline]
    fn kids(&self, i: usize) -> Kids {
        let b = self.b;
        let kid = |k: usize| {
            let n = b.node(k);
            if n.is_stub() {
                // (A stub is an inner node, never a fringe one: see `BvhNode::is_stub`.)
                return (k, n.bounds().surface_area());
            }
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
                    LEAF_KID
                },
            )
        };
        let mut kids = [(0, 0.0); WIDTH];
        (kids[0], kids[1]) = (kid(i + 1), kid(b.right(i)));
        let mut len = 2;
        while len < WIDTH {
            // Open the inner child with the largest surface area.
            let mut best = None;
            for (pos, &(_, area)) in kids[..len].iter().enumerate() {
                if area >= 0.0 && best.is_none_or(|(_, a)| area > a) {
                    best = Some((pos, area));
                }
            }
            let Some((pos, _)) = best else { break };
            let k = kids[pos].0;
            if b.node(k).is_stub() {
                // Its children are not built yet: the caller builds them and collapses
                // again (see `Collapse::wanted`).
                self.wanted.borrow_mut().push(k);
                break;
            }
            kids[pos] = kid(k + 1);
            kids[len] = kid(b.right(k));
            len += 1;
        }
        Kids { kids, len }
    }
}

/// Up to eight children of a wide node, as [`Collapse::node`] gives them.
struct Kids {
    kids: [(usize, f32); WIDTH],
    len: usize,
}

impl Kids {
    fn iter(&self) -> std::slice::Iter<'_, (usize, f32)> {
        self.kids[..self.len].iter()
    }
}

/// The factor by which a box's exit distance is widened: 1 + 2γ(3) (see `RayBoxes::test`).
const WIDEN: f32 = 1.0 + 2.0 * gamma(3);

/// A ray prepared for the slab tests of a wide node's children: the origin and inverse
/// direction splatted, and per axis the byte offset of the near slab in a [`Node`] (so no
/// per-box min/max of the two slab distances is needed).
#[derive(Clone, Copy)]
struct RayBoxes {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    /// Slab `2·axis`, plus one where the ray runs towards −axis (the upper bound is then
    /// near), and the far slab of each axis, as byte offsets: a traversal that keeps its ray
    /// in memory ([`stream`]) reads each and adds it to the node's address, with no shift.
    near: [usize; 3],
    far: [usize; 3],
    /// Whether the CPU has AVX, so that [`RayBoxes::test`] takes eight lanes at once.
    #[cfg(target_arch = "x86_64")]
    avx: bool,
}

/// Byte offset of slab `i` in a [`Node`].
const fn slab_offset(i: usize) -> usize {
    i * std::mem::size_of::<[f32; WIDTH]>()
}

impl RayBoxes {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip();
        // The sign of the reciprocal, not of the direction: −0.0 < 0.0 is false, yet its
        // reciprocal is −∞, so the far bound is the minimum.
        let neg = |v: f32| (v < 0.0) as usize;
        let near = [neg(inv.x), 2 + neg(inv.y), 4 + neg(inv.z)].map(slab_offset);
        RayBoxes {
            o: [
                Vec4::splat(ray.o.x),
                Vec4::splat(ray.o.y),
                Vec4::splat(ray.o.z),
            ],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near,
            // The other slab of each axis: the index's lowest bit flipped.
            far: near.map(|off| off ^ slab_offset(1)),
            #[cfg(target_arch = "x86_64")]
            avx: std::arch::is_x86_feature_detected!("avx"),
        }
    }

    /// Bit mask of the children whose boxes the ray enters before `t_max`, and their entry
    /// distances. The exit distance is rounded up by 2γ(3) so that rounding never loses a box
    /// (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013).
    ///
    /// With AVX in one pass of eight lanes. That code is inlined where the caller is compiled
    /// with AVX (the renderer's x86-64-v3 paths, such as `Scene::closest_v3`) and called
    /// elsewhere; both forms compute the same operations lane by lane, so the same bits.
    #[inline(always)]
    fn test(&self, n: &Node, t_max: f32) -> (u32, [f32; WIDTH]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx {
            // SAFETY: `avx` says the CPU has AVX.
            return unsafe { self.test_avx(n, t_max) };
        }
        let mut mask = 0;
        let mut t = [0.0; WIDTH];
        for half in 0..WIDTH / 4 {
            let slab = |off: usize| {
                let off = off + 16 * half;
                debug_assert!(off < std::mem::size_of_val(&n.bounds) && off.is_multiple_of(16));
                // SAFETY: `near` and `far` hold the offsets of slabs 0 to 5, set in `new`,
                // and `half` is below 2; a `Node` and its `bounds` (its first field,
                // `repr(C)`) are 32-byte aligned.
                unsafe { *((n.bounds.as_ptr() as *const u8).add(off) as *const Vec4) }
            };
            let tn_x = (slab(self.near[0]) - self.o[0]) * self.inv[0];
            let tn_y = (slab(self.near[1]) - self.o[1]) * self.inv[1];
            let tn_z = (slab(self.near[2]) - self.o[2]) * self.inv[2];
            let tf_x = (slab(self.far[0]) - self.o[0]) * self.inv[0];
            let tf_y = (slab(self.far[1]) - self.o[1]) * self.inv[1];
            let tf_z = (slab(self.far[2]) - self.o[2]) * self.inv[2];
            let tnear = tn_x.max(tn_y).max(tn_z).max(Vec4::ZERO);
            let tfar = tf_x.min(tf_y).min(tf_z).min(Vec4::splat(t_max)) * WIDEN;
            mask |= tnear.cmple(tfar).bitmask() << (4 * half);
            t[4 * half..4 * half + 4].copy_from_slice(&tnear.to_array());
        }
        (mask, t)
    }

    /// [`RayBoxes::test`] in one pass of eight AVX lanes: the same operations in the same
    /// order as the two four-lane passes (and as the packets' box tests, `wide::packet`).
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    unsafe fn test_avx(&self, n: &Node, t_max: f32) -> (u32, [f32; WIDTH]) {
        use std::arch::x86_64::*;
        let base = n.bounds.as_ptr() as *const u8;
        // (Written out, not as a closure: a closure is not compiled with this function's
        // features, and its intrinsics would become calls.)
        let o = [
            _mm256_broadcast_ss(&self.o[0].x),
            _mm256_broadcast_ss(&self.o[1].x),
            _mm256_broadcast_ss(&self.o[2].x),
        ];
        let inv = [
            _mm256_broadcast_ss(&self.inv[0].x),
            _mm256_broadcast_ss(&self.inv[1].x),
            _mm256_broadcast_ss(&self.inv[2].x),
        ];
        // The distances to slab `$off` (a byte offset) along axis `$a`.
        macro_rules! slab {
            ($off:expr, $a:expr) => {
                // SAFETY: `near` and `far` hold the offsets of slabs 0 to 5, set in `new`; a
                // `Node` and its `bounds` are 32-byte aligned.
                _mm256_mul_ps(
                    _mm256_sub_ps(_mm256_load_ps(base.add($off) as *const f32), o[$a]),
                    inv[$a],
                )
            };
        }
        let (tn_x, tn_y, tn_z) = (
            slab!(self.near[0], 0),
            slab!(self.near[1], 1),
            slab!(self.near[2], 2),
        );
        let (tf_x, tf_y, tf_z) = (
            slab!(self.far[0], 0),
            slab!(self.far[1], 1),
            slab!(self.far[2], 2),
        );
        // The operand order of the four-lane passes (max and min return the second operand
        // where either is NaN, in SSE and AVX alike).
        let tnear = _mm256_max_ps(
            _mm256_max_ps(_mm256_max_ps(tn_x, tn_y), tn_z),
            _mm256_setzero_ps(),
        );
        let tfar = _mm256_mul_ps(
            _mm256_min_ps(
                _mm256_min_ps(_mm256_min_ps(tf_x, tf_y), tf_z),
                _mm256_set1_ps(t_max),
            ),
            _mm256_set1_ps(WIDEN),
        );
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar)) as u32;
        let mut t = [0.0; WIDTH];
        _mm256_storeu_ps(t.as_mut_ptr(), tnear);
        (mask, t)
    }
}

/// The traversal stack (of child references, with their entry distances for the closest
/// hit). The binary tree is at most `bvh::MAX_DEPTH` deep, so a wide node path is too, and
/// each level leaves at most seven siblings behind: 7 × MAX_DEPTH entries suffice. Left
/// uninitialised: zeroing it cost 4 % of all instructions per ray. This form holds its
/// items, for the traversals in flight of [`stream`]; a single ray's loop has a
/// [`LocalStack`].
struct Stack<T: Copy> {
    items: Items<T>,
    len: usize,
}

/// The items of a traversal stack.
type Items<T> = [std::mem::MaybeUninit<T>; STACK];

const STACK: usize = (WIDTH - 1) * super::bvh::MAX_DEPTH;

impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn push(&mut self, v: T) {
        push_n(&mut self.items, &mut self.len, [v], 1);
    }
    #[inline(always)]
    fn push_if(&mut self, v: T, keep: bool) {
        push_n(&mut self.items, &mut self.len, [v], keep as usize);
    }
    #[inline(always)]
    fn push_n<const N: usize>(&mut self, v: [T; N], n: usize) {
        push_n(&mut self.items, &mut self.len, v, n);
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        pop(&self.items, &mut self.len)
    }
}

/// A single ray's traversal stack, its items in an array of their own: next to an array
/// indexed at run time, as in [`Stack`], the length stayed in memory (LLVM's scalar
/// replacement does not split an aggregate accessed at a variable offset), a load and a
/// store at every push and pop; here it lives in a register.
struct LocalStack<'a, T: Copy> {
    items: &'a mut Items<T>,
    len: usize,
}

impl<'a, T: Copy> LocalStack<'a, T> {
    #[inline(always)]
    /// An empty stack on `items` (uninitialised: see [`Stack`]).
    fn new(items: &'a mut Items<T>) -> Self {
        LocalStack { items, len: 0 }
    }
    #[inline(always)]
    fn push(&mut self, v: T) {
        push_n(self.items, &mut self.len, [v], 1);
    }
    #[inline(always)]
    fn push_if(&mut self, v: T, keep: bool) {
        push_n(self.items, &mut self.len, [v], keep as usize);
    }
    #[inline(always)]
    fn push_n<const N: usize>(&mut self, v: [T; N], n: usize) {
        push_n(self.items, &mut self.len, v, n);
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        pop(self.items, &mut self.len)
    }
}

/// Pushes the first `n` of `v` (`n` ≤ N) on the stack of `items` below `len`, without a
/// branch on `n`: all N are written, those past the first `n` above the new top, where the
/// next push overwrites them. There is room: a node is opened with at most seven entries
/// for each level above it on the stack, so below 7 × (MAX_DEPTH − 1), and N ≤ 7.
#[inline(always)]
fn push_n<T: Copy, const N: usize>(items: &mut Items<T>, len: &mut usize, v: [T; N], n: usize) {
    debug_assert!(n <= N);
    for (slot, v) in items[*len..*len + N].iter_mut().zip(v) {
        *slot = std::mem::MaybeUninit::new(v);
    }
    *len += n;
}

/// Pops the top of the stack of `items` below `len`, if any.
#[inline(always)]
fn pop<T: Copy>(items: &Items<T>, len: &mut usize) -> Option<T> {
    if *len == 0 {
        return None;
    }
    *len -= 1;
    // SAFETY: every slot below `len` was written by `push`.
    Some(unsafe { items.get_unchecked(*len).assume_init() })
}

#[cfg(test)]
impl WideBvh {
    /// Checks the tree over primitives whose bounds `bounds_of` gives (by the caller's
    /// index; `order` as the build returned it), and panics where it fails: every node of
    /// the array reached exactly once from the root, each with at least two children; every
    /// primitive in exactly one leaf of at most `max_leaf`; every child's box inside its
    /// parent's and holding its primitives; no path deeper than `bvh::MAX_DEPTH`. Returns
    /// the leaves' primitive counts.
    pub(crate) fn check(
        &self,
        order: &[u32],
        bounds_of: impl Fn(u32) -> Aabb,
        max_leaf: u32,
    ) -> Vec<u32> {
        let root = self.bounds.expect("a tree over primitives has bounds");
        let inside = |a: &Aabb, b: &Aabb| a.min.cmpge(b.min).all() && a.max.cmple(b.max).all();
        let mut seen = vec![false; order.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut leaves = Vec::new();
        let mut stack = vec![(self.root, root, 1usize)];
        while let Some((c, b, depth)) = stack.pop() {
            assert!(depth <= super::bvh::MAX_DEPTH, "a path {depth} nodes deep");
            if c & LEAF != 0 {
                let (first, count) = ((c & !LEAF) >> 4, c & 15);
                assert!((1..=max_leaf).contains(&count), "a leaf of {count}");
                leaves.push(count);
                for pos in first..first + count {
                    let p = pos as usize;
                    assert!(!seen[p], "position {p} in two leaves");
                    seen[p] = true;
                    assert!(
                        inside(&bounds_of(order[p]), &b),
                        "a primitive outside its leaf"
                    );
                }
                continue;
            }
            let i = c as usize;
            assert!(!reached[i], "node {i} reached twice");
            reached[i] = true;
            let n = &self.nodes[i];
            let mut kids = 0;
            for slot in 0..WIDTH {
                if n.child[slot] == EMPTY {
                    continue;
                }
                kids += 1;
                let kb = n.child_box(slot);
                assert!(inside(&kb, &b), "a child's box outside its parent's");
                stack.push((n.child[slot], kb, depth + 1));
            }
            assert!(kids >= 2, "node {i} has {kids} children");
        }
        assert!(seen.iter().all(|&s| s), "a primitive in no leaf");
        assert!(reached.iter().all(|&r| r), "a node the root does not reach");
        leaves
    }

    /// The nodes' bits and the root, to compare two trees bit for bit.
    pub(crate) fn bits(&self) -> (Vec<u32>, ChildRef) {
        let mut bits = Vec::new();
        for n in &self.nodes {
            for v in &n.bounds {
                bits.extend(v.map(f32::to_bits));
            }
            bits.extend(n.child);
        }
        (bits, self.root)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sort_keys` sorts every count of keys from 0 to 8: by the 0-1 principle (Knuth, TAOCP
    /// vol. 3, §5.3.4, exercise 6) a comparator network that sorts every sequence of zeros and
    /// ones sorts every sequence; here each 0-1 sequence of length n, padded with `u64::MAX`.
    #[test]
    fn sort_keys_sorts_every_count() {
        for n in 0..=WIDTH {
            for bits in 0u32..1 << n {
                let mut k = [u64::MAX; WIDTH];
                for (i, key) in k[..n].iter_mut().enumerate() {
                    *key = u64::from(bits >> i & 1);
                }
                let mut want = k;
                want.sort_unstable();
                sort_keys(&mut k, n);
                assert_eq!(k, want, "{n} keys {bits:b}");
            }
        }
    }

    /// The box test's two forms, eight AVX lanes and two four-lane passes (what CPUs
    /// without AVX run), give the same mask and entry distances, bit for bit, on random
    /// boxes (some slots empty, some boxes flat) and rays (some parallel to an axis, with
    /// +0 or −0 components), and the same as each box tested on its own in scalar code.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn box_test_forms_agree() {
        if !std::arch::is_x86_feature_detected!("avx") {
            return;
        }
        let mut state = 7u64;
        let mut next = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            (crate::sampler::mix64(state) >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut entered = 0;
        for _ in 0..4000 {
            let mut node = Node::empty();
            for slot in 0..WIDTH {
                if next() < 0.15 {
                    continue;
                }
                for axis in 0..3 {
                    let a = next() * 4.0 - 2.0;
                    let w = if next() < 0.1 { 0.0 } else { next() * 2.0 };
                    node.bounds[2 * axis][slot] = a;
                    node.bounds[2 * axis + 1][slot] = a + w;
                }
            }
            let o = glam::Vec3A::new(next(), next(), next()) * 6.0 - 3.0;
            // Towards a point among the boxes, some components zero.
            let mut d = (glam::Vec3A::new(next(), next(), next()) * 2.0 - 1.0 - o).to_array();
            for v in &mut d {
                match (next() * 10.0) as u32 {
                    0 => *v = 0.0,
                    1 => *v = -0.0,
                    _ => {}
                }
            }
            let d = glam::Vec3A::from(d);
            let ray = Ray::new(o, d);
            let t_max = if next() < 0.5 {
                f32::INFINITY
            } else {
                next() * 5.0
            };
            let mut r = RayBoxes::new(&ray);
            // SAFETY: checked above.
            let wide = unsafe { r.test_avx(&node, t_max) };
            r.avx = false;
            let halves = r.test(&node, t_max);
            assert_eq!(wide.0, halves.0);
            assert_eq!(wide.1.map(f32::to_bits), halves.1.map(f32::to_bits));
            let inv = ray.d.recip();
            for slot in 0..WIDTH {
                // As `maxps`/`minps`: the second operand where either is NaN.
                let max = |a: f32, b: f32| if a > b { a } else { b };
                let min = |a: f32, b: f32| if a < b { a } else { b };
                let (mut tn, mut tf) = ([0.0f32; 3], [0.0f32; 3]);
                for axis in 0..3 {
                    let (lo, hi) = (node.bounds[2 * axis][slot], node.bounds[2 * axis + 1][slot]);
                    let (o, i) = (ray.o[axis], inv[axis]);
                    let (near, far) = if i < 0.0 { (hi, lo) } else { (lo, hi) };
                    tn[axis] = (near - o) * i;
                    tf[axis] = (far - o) * i;
                }
                let tn = max(max(max(tn[0], tn[1]), tn[2]), 0.0);
                let tf = min(min(min(tf[0], tf[1]), tf[2]), t_max) * WIDEN;
                let enters = tn <= tf;
                assert_eq!(wide.1[slot].to_bits(), tn.to_bits(), "slot {slot}");
                assert_eq!(wide.0 >> slot & 1 == 1, enters, "slot {slot}");
                entered += enters as u32;
            }
        }
        assert!(entered > 1000, "{entered} boxes entered");
    }
}
