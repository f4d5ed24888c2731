//! The build stage of the BVH: a binary tree over primitive bounds by the binned surface area
//! heuristic, collapsed into the eight-wide tree of [`super::wide`] that traversal uses.
//!
//! Build: Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", RT 2007
//! (binning centroids into 16 buckets per axis and sweeping for the cheapest split,
//! [`binned`]), with Embree's 32-byte primitive references (bounds with the index in the
//! spare lane), branch-free in-place partitioning, and a node array laid out in advance:
//! each reference carries the number of slots its subtree takes ([`Weight`]: a primitive's
//! leaf one, a cluster's own tree exactly as many nodes as it has), so a subtree over
//! references takes one slot fewer than the sum of theirs, the left child follows its
//! parent and the parent records where the right child starts. Subtrees built in parallel
//! write straight into their own parts of it, and each leaf writes its primitives' indices
//! into its own part of the final order. Large nodes choose their split from a fixed sample
//! of their primitives; small ones find the exact SAH split over lists sorted once per axis
//! ([`sweep`]). Inputs of [`CLUSTER_MIN`] primitives or more are built over clusters of
//! neighbours, each cluster's own tree below it ([`cluster`]), with no array of the
//! primitives' references (see [`build`]), and in two stages so that the binary tree never
//! exists whole: its top, collapsed at once, then each subtree below it built and collapsed
//! by one thread while its nodes are in the cache ([`fused`]). The result depends only on
//! the input, never on the thread count.

use super::{BuildTimes, WideBvh};
use crate::geometry::Aabb;
use glam::{BVec4A, Vec3A, Vec4};
use std::mem::MaybeUninit;

mod binned;
mod cluster;
mod fused;
mod sweep;
use binned::{binned_split, partition};
pub use cluster::CLUSTER_MIN;
use sweep::{sweep_node, SWEEP_MAX};

/// Selects the x, y and z lanes of a `Vec4`.
const XYZ: BVec4A = BVec4A::new(true, true, true, false);

/// A primitive's bounds, with its index in the spare lane of the lower corner (32 bytes).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct PrimRef {
    lo: Vec4,
    hi: Vec4,
}

impl PrimRef {
    /// A placeholder, overwritten before it is read.
    const EMPTY: PrimRef = PrimRef {
        lo: Vec4::ZERO,
        hi: Vec4::ZERO,
    };
    /// The caller's primitive `index`, with bounds `b`; a `costly` one (a sphere, whose test
    /// costs several triangles') is never merged into a leaf with others. (The flag rides in
    /// the upper corner's spare lane as 0 or 1, which no decision reads.)
    #[inline]
    pub fn new(b: &Aabb, index: u32, costly: bool) -> Self {
        PrimRef {
            lo: b.min.extend(f32::from_bits(index)),
            hi: b.max.extend(costly as u32 as f32),
        }
    }
    #[inline(always)]
    fn costly(&self) -> bool {
        self.hi.w != 0.0
    }
    /// A reference to a cluster of `prims` primitives (fewer than 16) whose own tree takes
    /// `slots` nodes (fewer than 16), both in the upper corner's spare lane as one small
    /// whole float: a normal number, unlike the index's bits.
    #[inline]
    fn cluster(b: &Aabb, index: u32, prims: u32, slots: u32) -> Self {
        debug_assert!(prims < 16 && slots < 16);
        PrimRef {
            lo: b.min.extend(f32::from_bits(index)),
            hi: b.max.extend((prims | slots << 4) as f32),
        }
    }
    /// A cluster's primitives and nodes, as [`Weight`].
    #[inline(always)]
    fn cluster_weight(&self) -> Weight {
        let w = self.hi.w as u64;
        weight(w & 15, w >> 4)
    }
    /// The lower corner, with the index lane cleared. The index's bits, read as an f32, are
    /// a subnormal number, and any arithmetic on one (the centroid sums, the extents of the
    /// surface areas) takes a microcode assist of about a hundred cycles on x86 CPUs: with
    /// the lane left in, the build over 10 M triangles took 2.2 times as long.
    #[inline(always)]
    fn lo(&self) -> Vec3A {
        Vec3A::from_vec4(Vec4::select(XYZ, self.lo, Vec4::ZERO))
    }
    #[inline(always)]
    fn hi(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.lo(),
            max: self.hi(),
        }
    }
    #[inline(always)]
    pub fn index(&self) -> u32 {
        self.lo.w.to_bits()
    }
    /// Twice the centroid (the factor ½ would change no decision).
    #[inline(always)]
    fn c2(&self) -> Vec3A {
        self.lo() + self.hi()
    }
}

/// One node of the binary tree (32 bytes). `count` holds the number of primitives under it
/// (the low 27 bits; there are fewer than 2²⁷), the number of leaves of its subtree up to 15
/// (bits 27 to 30) and [`LEAF_FLAG`] on leaves. A leaf holds the primitives
/// `first..first + prims()` of the order; an inner node's `first` is the distance from it to
/// its right child (its left child follows it). `first` holds, in its top bit, whether a
/// costly primitive lies under the node. The collapse reads from these what it needs of a
/// subtree (whether a small one becomes a leaf) without walking it.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct BvhNode {
    pub min: [f32; 3],
    first: u32,
    pub max: [f32; 3],
    count: u32,
}

pub const LEAF_FLAG: u32 = 1 << 31;
const PRIMS: u32 = (1 << 27) - 1;
const LEAVES_SHIFT: u32 = 27;
const COSTLY: u32 = 1 << 31;

impl BvhNode {
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count & LEAF_FLAG != 0
    }
    #[inline]
    pub fn prims(&self) -> u32 {
        self.count & PRIMS
    }
    /// The leaves of its subtree, counted up to 15.
    #[inline]
    pub fn leaves(&self) -> u32 {
        (self.count >> LEAVES_SHIFT) & 15
    }
    /// Whether a costly primitive (see `build`) lies under it.
    #[inline]
    pub fn costly(&self) -> bool {
        self.first & COSTLY != 0
    }
    /// Whether it is a stub: a node that stands for a subtree built elsewhere (see
    /// [`fused`]), with its bounds and primitives, the first of them in `first`, and no
    /// leaves recorded (every other inner node has at least two).
    #[inline]
    pub fn is_stub(&self) -> bool {
        !self.is_leaf() && self.leaves() == 0
    }
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3A::from_array(self.min),
            max: Vec3A::from_array(self.max),
        }
    }
}

/// What a node's parent records of its subtree: its leaves (up to 15), and whether a
/// costly primitive lies in it.
#[derive(Clone, Copy, Debug)]
#[must_use]
struct Sub {
    leaves: u32,
    costly: bool,
}

impl Sub {
    fn join(self, o: Sub) -> Sub {
        Sub {
            leaves: (self.leaves + o.leaves).min(15),
            costly: self.costly || o.costly,
        }
    }
}

/// Records `sub` in the inner node written at `node`, after its children were built.
fn finish(node: &mut MaybeUninit<BvhNode>, sub: Sub) -> Sub {
    // SAFETY: the node was written before its children were built.
    let n = unsafe { node.assume_init_mut() };
    n.count |= sub.leaves << LEAVES_SHIFT;
    if sub.costly {
        n.first |= COSTLY;
    }
    sub
}

/// The binary tree over fewer than [`CLUSTER_MIN`] primitives: node 0 is the root; an inner
/// node `i`'s children are `i + 1` and the node its `first` names. Each subtree takes a run
/// of slots of its own. Slots no node landed in (under a leaf of several primitives) stay
/// uninitialised and are never read.
pub struct Bvh {
    nodes: Vec<MaybeUninit<BvhNode>>,
    /// `order[i]` is the caller's index of the BVH's i-th primitive.
    pub order: Vec<u32>,
}

impl Bvh {
    /// The nodes, for the collapse and the tests.
    pub(crate) fn nodes(&self) -> Nodes<'_> {
        // SAFETY: the build writes the root and both children of every inner node it
        // writes, at exactly the indices this layout names (and makes no stubs).
        unsafe { Nodes::new(&self.nodes) }
    }
    /// The number of node slots.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }
}

/// Binary nodes as the build lays them out: node 0 is the root, an inner node `i`'s left
/// child is `i + 1` and its right child the node its `first` names. Stubs (see
/// [`BvhNode::is_stub`]) stand for subtrees laid out elsewhere and have no children here.
#[derive(Clone, Copy)]
pub(crate) struct Nodes<'a>(&'a [MaybeUninit<BvhNode>]);

impl<'a> Nodes<'a> {
    /// # Safety
    /// Node 0 and both children of every inner node written that is not a stub must be
    /// written (the nodes reachable from the root); only those are read.
    pub(crate) unsafe fn new(nodes: &'a [MaybeUninit<BvhNode>]) -> Self {
        Nodes(nodes)
    }
    /// Node `i`; `i` must be the root or a child of a node read through here.
    #[inline]
    pub(crate) fn node(&self, i: usize) -> &'a BvhNode {
        // SAFETY: see `new`.
        unsafe { self.0[i].assume_init_ref() }
    }
    /// Asks the cache for node `i` (a hint, for any `i`).
    #[inline(always)]
    pub(crate) fn prefetch(&self, i: usize) {
        if let Some(n) = self.0.get(i) {
            super::prefetch(n);
        }
    }
    /// The right child of inner node `i`.
    #[inline]
    pub(crate) fn right(&self, i: usize) -> usize {
        i + (self.node(i).first & !COSTLY) as usize
    }
    /// The primitives under node `i` (not a stub): the position of the first in the order,
    /// and their count. (An inner node's first primitive is its leftmost leaf's, which for
    /// the small subtrees the collapse asks about lies a node or two after it.)
    #[inline]
    pub(crate) fn prim_range(&self, i: usize) -> (u32, u32) {
        let mut k = i;
        while !self.node(k).is_leaf() {
            k += 1;
        }
        (self.node(k).first & !COSTLY, self.node(i).prims())
    }
}

const BINS: usize = 16;
/// Deepest a node may lie. Past `MAX_DEPTH - 32` nodes split at the object median, which
/// halves the count, so no path can exceed this for fewer than 2³² primitives; traversal
/// stacks are sized from it.
pub const MAX_DEPTH: usize = 80;
/// Leaves hold at most this many primitives.
const MAX_LEAF: usize = 8;

/// Cost of visiting a node relative to one primitive test. Measured with callgrind on the
/// TNCG15 room (32×32, 64 spp): 1.0 → 837 M instructions, 0.5 → 765 M, 0.25 and 0.125 the
/// same as 0.5; 2.0 → 1319 M. 0.5 is also pbrt-v4's value.
const TRAVERSAL_COST: f32 = 0.5;

/// Subtrees with more primitives than this are built in parallel (rayon::join).
const PARALLEL_MIN: usize = 1 << 14;
/// Nodes with more primitives than this choose their split from about `SAMPLES` of them, a
/// fixed stride apart.
const SAMPLE_MIN: usize = 1 << 11;
const SAMPLES: usize = 1 << 10;

/// Builds the BVH over the primitives `0..n`, whose references `prim` gives (it is asked
/// for each one several times, and must give the same answer each time): the binary SAH
/// tree over the primitives themselves, or over clusters of them when there are at least
/// [`CLUSTER_MIN`], collapsed into the eight-wide tree. Returns that tree and the order of the
/// primitives (`order[i]` is the caller's index of the tree's i-th primitive). Marks its
/// phases in `times`.
///
/// The references are asked for, not passed in an array, because an array of them is the
/// build's largest (32 bytes a primitive, twice over once sorted along the curve), and on
/// hosts that charge dearly for memory a process touches first (see docs/performance.md,
/// "Fresh memory on this VM") computing a triangle's bounds again from its three vertices
/// costs far less than storing them.
pub fn build<F>(n: usize, prim: F, times: &mut BuildTimes) -> (WideBvh, Vec<u32>)
where
    F: Fn(u32) -> PrimRef + Sync,
{
    assert!(n < 1 << 27, "too many primitives");
    if n >= CLUSTER_MIN {
        cluster::build(n, &prim, times)
    } else {
        let mut refs: Vec<PrimRef> = (0..n as u32).map(&prim).collect();
        times.mark("bounds");
        let bvh = build_sah(&mut refs);
        times.mark("binary SAH tree");
        let wide = WideBvh::from_binary(&bvh);
        times.mark("wide collapse");
        (wide, bvh.order)
    }
}

/// The binary SAH tree over the primitives `refs` (which it reorders).
fn build_sah(refs: &mut [PrimRef]) -> Bvh {
    let n = refs.len();
    let slots = (2 * n).max(1) - 1;
    let mut nodes: Vec<MaybeUninit<BvhNode>> = Vec::with_capacity(slots);
    // SAFETY: MaybeUninit needs no initialisation.
    unsafe { nodes.set_len(slots) };
    let mut order = vec![0; n];
    if n > 0 {
        let (b, cb) = bounds_of(refs);
        let _ = build_node(&Prims, &mut nodes, &mut order, refs, 0, 0, b, cb);
    }
    Bvh { nodes, order }
}

/// What the references of a build stand for: primitives, or clusters of them whose own
/// trees are built under the clusters' leaves ([`cluster`]).
trait Kind: Sync {
    /// Most references in one leaf.
    const MAX_LEAF: usize;
    /// Whether every reference stands for one primitive.
    const UNIT: bool;
    /// Depth below which the build splits at the object median (so that no path passes
    /// [`MAX_DEPTH`], leaving room for the trees under the leaves).
    const MEDIAN_DEPTH: usize;
    /// The primitives `r` stands for, and its nodes.
    fn weight(r: &PrimRef) -> Weight;
    /// Writes the subtree of a leaf over `refs` (at most `MAX_LEAF` of them, whose
    /// primitives are `first..first + order.len()` of the final order, `bounds` their
    /// bounds) into `nodes` (exactly the slots their weights name), and their primitives'
    /// indices, in the tree's order, into `order`; returns what its parent records of it.
    fn leaf(
        &self,
        nodes: &mut [MaybeUninit<BvhNode>],
        order: &mut [u32],
        refs: &[PrimRef],
        first: usize,
        depth: usize,
        bounds: &Aabb,
    ) -> Sub;
}

/// Primitives, at most [`MAX_LEAF`] to a leaf.
struct Prims;

impl Kind for Prims {
    const MAX_LEAF: usize = MAX_LEAF;
    const UNIT: bool = true;
    const MEDIAN_DEPTH: usize = MAX_DEPTH - 32;
    #[inline(always)]
    fn weight(_: &PrimRef) -> Weight {
        PRIM
    }
    #[inline]
    fn leaf(
        &self,
        nodes: &mut [MaybeUninit<BvhNode>],
        order: &mut [u32],
        refs: &[PrimRef],
        first: usize,
        _depth: usize,
        bounds: &Aabb,
    ) -> Sub {
        let mut costly = false;
        for (o, r) in order.iter_mut().zip(refs) {
            *o = r.index();
            costly |= r.costly();
        }
        let mut node = leaf(bounds, first, refs.len());
        if costly {
            node.first |= COSTLY;
        }
        nodes[0].write(node);
        Sub { leaves: 1, costly }
    }
}

/// What references stand for, summed: primitives in the low 32 bits, and in the high 32
/// the slots their subtrees take plus one each, so that the subtree over a set of
/// references takes [`slots_of`] their sum (a primitive's subtree is one leaf: two, and
/// the n − 1 inner nodes above n leaves make the sum minus one). The sums stay below
/// 2³² on both sides, as there are fewer than 2²⁷ primitives, each of whose subtrees
/// takes fewer than 16 slots.
pub(crate) type Weight = u64;

/// A weight of `prims` primitives whose subtree takes `slots` nodes.
#[inline(always)]
const fn weight(prims: u64, slots: u64) -> Weight {
    prims | (slots + 1) << 32
}
/// A primitive's weight: one primitive, one leaf.
const PRIM: Weight = weight(1, 1);

/// The primitives of a weight.
#[inline(always)]
fn prims_of(w: Weight) -> usize {
    w as u32 as usize
}
/// The slots of the subtree over references of total weight `w`.
#[inline(always)]
fn slots_of(w: Weight) -> usize {
    (w >> 32) as usize - 1
}

/// Bounds of the primitives and of their (doubled) centroids.
#[inline]
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let (b, cb, _) = bounds_weight_of(refs, |_| 0);
    (b, cb)
}

/// [`bounds_of`], and the references' total `weight`.
#[inline(always)]
fn bounds_weight_of(refs: &[PrimRef], weight: impl Fn(&PrimRef) -> Weight) -> (Aabb, Aabb, Weight) {
    let mut b = Aabb::EMPTY;
    let mut cb = Aabb::EMPTY;
    let mut w = 0;
    for r in refs {
        b.min = b.min.min(r.lo());
        b.max = b.max.max(r.hi());
        cb.grow_point(r.c2());
        w += weight(r);
    }
    (b, cb, w)
}

fn leaf(b: &Aabb, first: usize, count: usize) -> BvhNode {
    BvhNode {
        min: b.min.to_array(),
        first: first as u32,
        max: b.max.to_array(),
        count: count as u32 | LEAF_FLAG,
    }
}

/// An inner node over `count` primitives whose right child lies `right` slots after it.
fn inner(b: &Aabb, right: usize, count: usize) -> BvhNode {
    BvhNode {
        min: b.min.to_array(),
        first: right as u32,
        max: b.max.to_array(),
        count: count as u32,
    }
}

/// A stub over `count` primitives, the first of them at `first` in the order (see
/// [`BvhNode::is_stub`]).
fn stub(b: &Aabb, first: usize, count: usize) -> BvhNode {
    inner(b, first, count)
}

/// Writes the subtree over `refs` (standing for the primitives `first..first + order.len()`
/// of the final order) into `nodes`, its root at `nodes[0]`, and the primitives' indices in
/// the tree's order into `order`. `bounds` and `cbounds` are the bounds of the references
/// and of their doubled centroids.
#[allow(clippy::too_many_arguments)]
fn build_node<K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    refs: &mut [PrimRef],
    first: usize,
    depth: usize,
    bounds: Aabb,
    cbounds: Aabb,
) -> Sub {
    match step::<K>(refs, order.len(), depth, &bounds, &cbounds) {
        Step::Leaf => kind.leaf(nodes, order, refs, first, depth, &bounds),
        Step::Sweep => sweep_node(kind, nodes, order, refs, first, depth, &bounds),
        Step::Split(s) => interior(kind, nodes, order, refs, first, depth, &bounds, s),
    }
}

/// What becomes of a node: a leaf, a small node whose subtree the exact sweep builds, or an
/// inner node split as [`Split`] says.
enum Step {
    Leaf,
    Sweep,
    Split(Split),
}

/// A node's references split at `mid` (reordered so that those left of it go left): the
/// left side's weight, and both sides' bounds and centroid bounds.
struct Split {
    mid: usize,
    wl: Weight,
    l: (Aabb, Aabb),
    r: (Aabb, Aabb),
}

/// Decides the node over `refs` (standing for `w` primitives, at `depth`, with bounds
/// `bounds` and centroid bounds `cbounds`), and for a split reorders `refs` by side.
fn step<K: Kind>(
    refs: &mut [PrimRef],
    w: usize,
    depth: usize,
    bounds: &Aabb,
    cbounds: &Aabb,
) -> Step {
    let n = refs.len();
    if n == 1 {
        return Step::Leaf;
    }
    let cext = cbounds.extent();
    if depth >= K::MEDIAN_DEPTH || cext.max_element() <= 0.0 {
        if n <= K::MAX_LEAF {
            return Step::Leaf;
        }
        // Degenerate input (the SAH keeps peeling off few primitives, or all centroids
        // coincide): split at the object median along the widest centroid axis.
        let widest = widest_axis(cext);
        let mid = n / 2;
        refs.select_nth_unstable_by(mid, |a, b| a.c2()[widest].total_cmp(&b.c2()[widest]));
        return Step::Split(split_at::<K>(refs, mid));
    }
    if n <= SWEEP_MAX {
        return Step::Sweep;
    }
    let area = half_area(bounds.min, bounds.max).max(f32::MIN_POSITIVE);
    match binned_split(refs, cbounds, K::weight) {
        Some(s) if split_pays::<K>(n, w, area, s.cost) => {
            let (mid, wl, l, r) = partition(refs, s.cmin, s.scale, s.axis, s.limit, K::weight);
            if mid == 0 || mid == n {
                // Cannot happen (the sampled bins held references on both sides); kept so
                // that the node layout can never underflow.
                return Step::Split(split_at::<K>(refs, n / 2));
            }
            Step::Split(Split { mid, wl, l, r })
        }
        // (Without a split every centroid lies in one bin along every axis; rare but
        // possible with centroids a few ulps apart.)
        None if n > K::MAX_LEAF => Step::Split(split_at::<K>(refs, n / 2)),
        _ => Step::Leaf,
    }
}

/// Whether splitting a node of `n` references standing for `w` primitives, and of surface
/// `area`, whose children's SAH sum (primitives times area) is `children`, beats a leaf by
/// the SAH, or the node is too large for a leaf.
#[inline]
fn split_pays<K: Kind>(n: usize, w: usize, area: f32, children: f32) -> bool {
    n > K::MAX_LEAF || TRAVERSAL_COST + children / area < w as f32
}

/// Half the surface area of the box `lo..hi` (non-empty); the factor ½ changes no decision.
#[inline(always)]
fn half_area(lo: Vec3A, hi: Vec3A) -> f32 {
    let e = hi - lo;
    (e * Vec3A::new(e.y, e.z, e.x)).element_sum()
}

fn widest_axis(e: Vec3A) -> usize {
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

/// `refs` split at `mid` as they lie.
fn split_at<K: Kind>(refs: &[PrimRef], mid: usize) -> Split {
    let (l, r) = refs.split_at(mid);
    let (lb, lc, wl) = bounds_weight_of(l, K::weight);
    Split {
        mid,
        wl,
        l: (lb, lc),
        r: bounds_of(r),
    }
}

/// Writes an inner node over `refs`, split as `split` says, and builds its children (in
/// parallel when both are large).
#[allow(clippy::too_many_arguments)]
fn interior<K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    refs: &mut [PrimRef],
    first: usize,
    depth: usize,
    bounds: &Aabb,
    split: Split,
) -> Sub {
    let (head, [l, r]) = fused::children(nodes, order, refs, first, depth, bounds, split);
    // A child as `build_node` takes it.
    fn build<K: Kind>(kind: &K, (nodes, at, refs, order, _): fused::Child) -> Sub {
        build_node(
            kind, nodes, order, refs, at.first, at.depth, at.bounds, at.cbounds,
        )
    }
    let (a, b) = if l.3.len().min(r.3.len()) >= PARALLEL_MIN {
        rayon::join(|| build(kind, l), || build(kind, r))
    } else {
        (build(kind, l), build(kind, r))
    };
    finish(head, a.join(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The index rides in the lower corner's spare lane, whose bits read as a subnormal f32;
    /// the corners the build computes with must not carry it (see `PrimRef::lo`). (Only
    /// x86-64's `Vec3A` has a fourth lane.)
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn prim_ref_corners_leave_the_index_out() {
        let lanes = |v: Vec3A| Vec4::from(std::arch::x86_64::__m128::from(v)).to_array();
        let b = Aabb {
            min: Vec3A::new(-1.0, 2.0, 3.0),
            max: Vec3A::new(4.0, 5.0, 6.5),
        };
        for index in [1u32, 12_345, (1 << 27) - 1] {
            let r = PrimRef::new(&b, index, false);
            assert_eq!(r.index(), index);
            assert_eq!(lanes(r.lo()), [-1.0, 2.0, 3.0, 0.0]);
            assert_eq!(lanes(r.c2())[3], 0.0);
            assert_eq!(r.bounds().min, b.min);
        }
    }

    /// The partition keeps every primitive once, puts exactly those below the limit on the
    /// left, and returns both sides' bounds and centroid bounds.
    #[test]
    fn partition_splits_by_bin_and_bounds_each_side() {
        let mut x = 0x2545_f491u32;
        let mut f = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1 << 24) as f32
        };
        let refs: Vec<PrimRef> = (0..1000)
            .map(|i| {
                let c = Vec3A::new(f(), f(), f()) * 8.0;
                let h = Vec3A::new(f(), f(), f()) * 0.1;
                PrimRef::new(
                    &Aabb {
                        min: c - h,
                        max: c + h,
                    },
                    i,
                    i % 7 == 0,
                )
            })
            .collect();
        let (_, cb) = bounds_of(&refs);
        let scale = Vec3A::splat(16.0 * (1.0 - 1e-6)) / cb.extent();
        for axis in 0..3 {
            for limit in [1.0f32, 5.0, 15.0] {
                let mut v = refs.clone();
                let weight = |r: &PrimRef| weight(r.index() as u64 % 3 + 1, r.index() as u64 % 5);
                let (mid, wl, (lb, lc), (rb, rc)) =
                    partition(&mut v, cb.min, scale, axis, limit, weight);
                let left = |r: &PrimRef| ((r.c2() - cb.min) * scale)[axis] < limit;
                assert!(v[..mid].iter().all(left) && !v[mid..].iter().any(left));
                let w: Weight = v[..mid].iter().map(weight).sum();
                assert_eq!(wl, w);
                let mut seen: Vec<u32> = v.iter().map(PrimRef::index).collect();
                seen.sort();
                assert_eq!(seen, (0..1000).collect::<Vec<u32>>());
                for ((b, c), side) in [((lb, lc), &v[..mid]), ((rb, rc), &v[mid..])] {
                    let (eb, ec) = bounds_of(side);
                    assert_eq!(
                        (b.min, b.max, c.min, c.max),
                        (eb.min, eb.max, ec.min, ec.max)
                    );
                }
            }
        }
    }
}
