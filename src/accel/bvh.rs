//! The build stage of the BVH: a binary tree over primitive bounds by the binned surface area
//! heuristic, collapsed into the 4-wide tree of [`super::wide`] that traversal uses.
//!
//! Build: Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", RT 2007
//! (binning centroids into 16 buckets per axis and sweeping for the cheapest split), with
//! Embree's 32-byte primitive references (bounds with the index in the spare lane), in-place
//! partitioning that also gathers the children's bounds, and a node array laid out in advance
//! (a subtree over n primitives takes at most 2n − 1 slots: the left child follows its parent
//! and the right child starts 2·n_left slots after it), so subtrees built in parallel write
//! straight into their own parts of it. Large nodes choose their split from a fixed sample of
//! their primitives; small ones find the exact SAH split over lists sorted once per axis.
//! Inputs of [`CLUSTER_MIN`] primitives or more are built over pairs of neighbours
//! ([`cluster`]). The result depends only on the input, never on the thread count.

use super::BuildTimes;
use crate::geometry::Aabb;
use glam::{BVec4A, Vec3A, Vec4};
use std::mem::MaybeUninit;

mod cluster;
pub use cluster::CLUSTER_MIN;

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
    #[inline]
    pub fn new(b: &Aabb, index: u32) -> Self {
        PrimRef {
            lo: b.min.extend(f32::from_bits(index)),
            hi: b.max.extend(0.0),
        }
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

/// One node of the binary tree (32 bytes). `count` is the number of primitives under it,
/// with [`LEAF_FLAG`] set on leaves, which hold the primitives `first..first + count`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct BvhNode {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

pub const LEAF_FLAG: u32 = 1 << 31;

impl BvhNode {
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count & LEAF_FLAG != 0
    }
    #[inline]
    pub fn prims(&self) -> u32 {
        self.count & !LEAF_FLAG
    }
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3A::from_array(self.min),
            max: Vec3A::from_array(self.max),
        }
    }
}

/// The binary tree: node 0 is the root; an inner node `i`'s children are `i + 1` and
/// `i + 2 · prims(i + 1)`. Slots no node landed in stay uninitialised and are never read.
pub struct Bvh {
    nodes: Vec<MaybeUninit<BvhNode>>,
    /// `order[i]` is the caller's index of the BVH's i-th primitive.
    pub order: Vec<u32>,
    /// For a tree built over clusters ([`CLUSTER_MIN`]): nodes count clusters, and the
    /// `j`-th cluster's primitives are `order[prim_start[j]..prim_start[j + 1]]`. Empty
    /// when nodes count primitives.
    prim_start: Vec<u32>,
}

impl Bvh {
    /// Node `i`; `i` must be the root or a child of a node read through here.
    #[inline]
    pub fn node(&self, i: usize) -> &BvhNode {
        // SAFETY: the build writes the root and both children of every inner node it writes,
        // at exactly the indices this layout names; only those are read.
        unsafe { self.nodes[i].assume_init_ref() }
    }
    #[inline]
    pub fn right(&self, i: usize) -> usize {
        i + 2 * self.node(i + 1).prims() as usize
    }
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }
    /// The primitives under node `n` (which must be a node of this tree): the position of
    /// the first in `order`, and their count.
    #[inline]
    pub fn prim_range(&self, n: &BvhNode) -> (u32, u32) {
        if self.prim_start.is_empty() {
            (n.first, n.prims())
        } else {
            let (a, b) = (n.first as usize, (n.first + n.prims()) as usize);
            (self.prim_start[a], self.prim_start[b] - self.prim_start[a])
        }
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

/// Builds the binary tree over `refs`, which it may reorder: over the primitives
/// themselves, or over clusters of them when there are at least [`CLUSTER_MIN`].
/// Marks its phases in `times`.
pub fn build(refs: &mut [PrimRef], times: &mut BuildTimes) -> Bvh {
    if refs.len() >= CLUSTER_MIN {
        cluster::build(refs, times)
    } else {
        let bvh = build_sah::<MAX_LEAF>(refs);
        times.mark("binary SAH tree");
        bvh
    }
}

/// The binary SAH tree over `refs` (reordered), with leaves of at most `L` of them.
fn build_sah<const L: usize>(refs: &mut [PrimRef]) -> Bvh {
    let n = refs.len();
    let mut nodes: Vec<MaybeUninit<BvhNode>> = Vec::with_capacity((2 * n).max(1));
    // SAFETY: MaybeUninit needs no initialisation.
    unsafe { nodes.set_len((2 * n).max(1)) };
    if n > 0 {
        let (b, cb) = bounds_of(refs);
        build_node::<L>(&mut nodes, refs, 0, 0, b, cb);
    }
    Bvh {
        nodes,
        order: refs.iter().map(|r| r.index()).collect(),
        prim_start: Vec::new(),
    }
}

/// Bounds of the primitives and of their (doubled) centroids.
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut cb = Aabb::EMPTY;
    for r in refs {
        b.min = b.min.min(r.lo());
        b.max = b.max.max(r.hi());
        cb.grow_point(r.c2());
    }
    (b, cb)
}

fn leaf(b: &Aabb, first: usize, count: usize) -> BvhNode {
    BvhNode {
        min: b.min.to_array(),
        first: first as u32,
        max: b.max.to_array(),
        count: count as u32 | LEAF_FLAG,
    }
}

/// Bin indices of a scaled centroid offset (non-negative), clamped to `last`.
#[inline(always)]
fn bin3(v: Vec3A, last: f32) -> [usize; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86-64.
        unsafe {
            let v = _mm_min_ps(v.into(), _mm_set1_ps(last));
            let i = _mm_cvttps_epi32(v);
            let mut out = [0i32; 4];
            _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, i);
            [out[0] as usize, out[1] as usize, out[2] as usize]
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let b = v.min(Vec3A::splat(last));
        [b.x as usize, b.y as usize, b.z as usize]
    }
}

/// Writes the subtree over `refs` (the primitives `first..first + refs.len()` of the final
/// order) into `nodes`, its root at `nodes[0]`. `bounds` and `cbounds` are the bounds of the
/// primitives and of their doubled centroids.
fn build_node<const L: usize>(
    nodes: &mut [MaybeUninit<BvhNode>],
    refs: &mut [PrimRef],
    first: usize,
    depth: usize,
    bounds: Aabb,
    cbounds: Aabb,
) {
    let n = refs.len();
    if n == 1 {
        nodes[0].write(leaf(&bounds, first, n));
        return;
    }
    let cext = cbounds.extent();
    if depth >= MAX_DEPTH - 32 || cext.max_element() <= 0.0 {
        if n <= L {
            nodes[0].write(leaf(&bounds, first, n));
            return;
        }
        // Degenerate input (the SAH keeps peeling off few primitives, or all centroids
        // coincide): split at the object median along the widest centroid axis.
        let widest = widest_axis(cext);
        let mid = n / 2;
        refs.select_nth_unstable_by(mid, |a, b| a.c2()[widest].total_cmp(&b.c2()[widest]));
        let (l, r) = refs.split_at(mid);
        let (lb, lc) = bounds_of(l);
        let (rb, rc) = bounds_of(r);
        return interior::<L>(nodes, refs, first, depth, &bounds, mid, (lb, lc), (rb, rc));
    }
    if n <= SWEEP_MAX {
        return sweep_node::<L>(nodes, refs, first, &bounds);
    }
    // Bin the centroids along all three axes in one pass (over a sample of a large node);
    // fewer bins for fewer primitives.
    let nb = if n <= 64 { 8 } else { BINS };
    let scale = Vec3A::select(
        cext.cmpgt(Vec3A::ZERO),
        Vec3A::splat(nb as f32 * (1.0 - 1e-6)) / cext,
        Vec3A::ZERO,
    );
    let cmin = cbounds.min;
    let last = (nb - 1) as f32;
    let stride = if n > SAMPLE_MIN { n / SAMPLES } else { 1 };
    // Two sets of bins, for even and odd primitives: neighbours often share a bin, and one
    // set would make each update wait for the previous one's store.
    let mut count = [[[0u32; BINS]; 3]; 2];
    let mut bins = [[[Aabb::EMPTY; BINS]; 3]; 2];
    let mut samples = 0;
    for (k, r) in refs.iter().step_by(stride).enumerate() {
        let set = k & 1;
        let (lo, hi) = (r.lo(), r.hi());
        let b = bin3((lo + hi - cmin) * scale, last);
        for axis in 0..3 {
            count[set][axis][b[axis]] += 1;
            let bb = &mut bins[set][axis][b[axis]];
            bb.min = bb.min.min(lo);
            bb.max = bb.max.max(hi);
        }
        samples += 1;
    }
    // Sweep each axis for the cheapest split (right-hand areas first, then from the left).
    let mut best: Option<(usize, usize, f32)> = None; // (axis, bin, cost)
    for axis in 0..3 {
        if cext[axis] <= 0.0 {
            continue;
        }
        let [(c0, b0), (c1, b1)] = [0, 1].map(|s| (&count[s][axis], &bins[s][axis]));
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in (1..nb).rev() {
            acc.grow(&b0[i]);
            acc.grow(&b1[i]);
            cnt += c0[i] + c1[i];
            right_area[i] = half_area(acc.min, acc.max);
            right_count[i] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in 0..nb - 1 {
            acc.grow(&b0[i]);
            acc.grow(&b1[i]);
            cnt += c0[i] + c1[i];
            if cnt == 0 || right_count[i + 1] == 0 {
                continue;
            }
            let cost = cnt as f32 * half_area(acc.min, acc.max)
                + right_count[i + 1] as f32 * right_area[i + 1];
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, i, cost));
            }
        }
    }
    let area = half_area(bounds.min, bounds.max).max(f32::MIN_POSITIVE);
    let sampled = samples as f32 / n as f32;
    match best {
        Some((axis, bin, cost)) if split_pays::<L>(n, area, cost / sampled) => {
            let (mid, l, r) = partition(refs, cmin, scale, axis, (bin + 1) as f32);
            if mid == 0 || mid == n {
                // Cannot happen (the sampled bins held primitives on both sides); kept so
                // that the node layout can never underflow.
                return interior_median::<L>(nodes, refs, first, depth, &bounds);
            }
            interior::<L>(nodes, refs, first, depth, &bounds, mid, l, r)
        }
        // (Without a split every centroid lies in one bin along every axis; rare but
        // possible with centroids a few ulps apart.)
        None if n > L => interior_median::<L>(nodes, refs, first, depth, &bounds),
        _ => {
            nodes[0].write(leaf(&bounds, first, n));
        }
    }
}

/// Whether splitting a node of `n` primitives and surface `area`, whose children's SAH sum
/// (count times area) is `children`, beats a leaf by the SAH, or the node is too large for
/// a leaf.
#[inline]
fn split_pays<const L: usize>(n: usize, area: f32, children: f32) -> bool {
    n > L || TRAVERSAL_COST + children / area < n as f32
}

/// Nodes of at most this many primitives find the exact SAH split (the primitives sorted
/// along each axis) instead of binning, whose fixed cost dominates at this size.
const SWEEP_MAX: usize = 12;

/// Half the surface area of the box `lo..hi` (non-empty); the factor ½ changes no decision.
#[inline(always)]
fn half_area(lo: Vec3A, hi: Vec3A) -> f32 {
    let e = hi - lo;
    (e * Vec3A::new(e.y, e.z, e.x)).element_sum()
}

/// The primitives of a small node, copied out once: bounds, and the order of their doubled
/// centroids along each axis.
struct Small {
    lo: [Vec3A; SWEEP_MAX],
    hi: [Vec3A; SWEEP_MAX],
}

/// The whole subtree of a small node by exact SAH sweeps (Wald, "On fast Construction of
/// SAH-based Bounding Volume Hierarchies", 2007, §3: the full sweep over presorted lists).
/// The primitives are sorted along each axis once; children take their parent's sorted
/// lists filtered (stable), so no level sorts again.
fn sweep_node<const L: usize>(
    nodes: &mut [MaybeUninit<BvhNode>],
    refs: &mut [PrimRef],
    first: usize,
    bounds: &Aabb,
) {
    let n = refs.len();
    let mut s = Small {
        lo: [Vec3A::ZERO; SWEEP_MAX],
        hi: [Vec3A::ZERO; SWEEP_MAX],
    };
    for (i, r) in refs.iter().enumerate() {
        s.lo[i] = r.lo();
        s.hi[i] = r.hi();
    }
    let mut ord = [[0u8; SWEEP_MAX]; 3];
    for (axis, o) in ord.iter_mut().enumerate() {
        // Insertion sort by centroid, stable (ties keep their order: deterministic).
        let mut key = [0f32; SWEEP_MAX];
        for i in 0..n {
            let c = s.lo[i][axis] + s.hi[i][axis];
            let mut j = i;
            while j > 0 && key[j - 1] > c {
                key[j] = key[j - 1];
                o[j] = o[j - 1];
                j -= 1;
            }
            key[j] = c;
            o[j] = i as u8;
        }
    }
    let mut out = [0u8; SWEEP_MAX];
    let mut out_len = 0;
    small_node::<L>(
        nodes,
        &s,
        &ord,
        n,
        first,
        bounds.min,
        bounds.max,
        &mut out,
        &mut out_len,
    );
    let mut tmp = [refs[0]; SWEEP_MAX];
    tmp[..n].copy_from_slice(refs);
    for (r, &o) in refs.iter_mut().zip(&out[..n]) {
        *r = tmp[o as usize];
    }
}

/// One node of [`sweep_node`]'s subtree: `ord[axis][..n]` are its primitives sorted along
/// each axis. Leaves append their primitives to `out`, in the order the tree lists them.
#[allow(clippy::too_many_arguments)]
fn small_node<const L: usize>(
    nodes: &mut [MaybeUninit<BvhNode>],
    s: &Small,
    ord: &[[u8; SWEEP_MAX]; 3],
    n: usize,
    first: usize,
    lo: Vec3A,
    hi: Vec3A,
    out: &mut [u8; SWEEP_MAX],
    out_len: &mut usize,
) {
    let emit_leaf =
        |nodes: &mut [MaybeUninit<BvhNode>], out: &mut [u8; SWEEP_MAX], out_len: &mut usize| {
            nodes[0].write(leaf(&Aabb { min: lo, max: hi }, first, n));
            out[*out_len..*out_len + n].copy_from_slice(&ord[0][..n]);
            *out_len += n;
        };
    if n == 1 {
        return emit_leaf(nodes, out, out_len);
    }
    // The cheapest split over all three axes: (axis, left count, cost).
    let mut best = (0, n / 2, f32::INFINITY);
    let mut right_area = [0f32; SWEEP_MAX];
    for (axis, o) in ord.iter().enumerate() {
        let (mut alo, mut ahi) = (s.lo[o[n - 1] as usize], s.hi[o[n - 1] as usize]);
        right_area[n - 1] = half_area(alo, ahi);
        for k in (1..n - 1).rev() {
            alo = alo.min(s.lo[o[k] as usize]);
            ahi = ahi.max(s.hi[o[k] as usize]);
            right_area[k] = half_area(alo, ahi);
        }
        let (mut alo, mut ahi) = (s.lo[o[0] as usize], s.hi[o[0] as usize]);
        for k in 1..n {
            if k > 1 {
                alo = alo.min(s.lo[o[k - 1] as usize]);
                ahi = ahi.max(s.hi[o[k - 1] as usize]);
            }
            let cost = k as f32 * half_area(alo, ahi) + (n - k) as f32 * right_area[k];
            if cost < best.2 {
                best = (axis, k, cost);
            }
        }
    }
    let (axis, mid, cost) = best;
    let area = half_area(lo, hi).max(f32::MIN_POSITIVE);
    // (A cost that is not finite, from non-finite bounds, splits in the middle.)
    if n <= L && !split_pays::<L>(n, area, cost) {
        return emit_leaf(nodes, out, out_len);
    }
    // Children's sorted lists: each axis's list filtered by side, order kept. Branch-free
    // (each index is written to both lists, and one of the two ends advances): the side is
    // unpredictable, and the branch cost a misprediction every other primitive.
    let mut left = [false; SWEEP_MAX];
    for &i in &ord[axis][..mid] {
        left[i as usize] = true;
    }
    let mut lord = [[0u8; SWEEP_MAX]; 3];
    let mut rord = [[0u8; SWEEP_MAX]; 3];
    for a in 0..3 {
        let (mut l, mut r) = (0, 0);
        for &i in &ord[a][..n] {
            let goes_left = left[i as usize] as usize;
            // (l ≤ mid and r ≤ n − mid, and both are below n ≤ SWEEP_MAX until the last
            // primitive has been written.)
            lord[a][l % SWEEP_MAX] = i;
            rord[a][r % SWEEP_MAX] = i;
            l += goes_left;
            r += 1 - goes_left;
        }
    }
    let bounds_of = |o: &[u8]| {
        let (mut a, mut b) = (s.lo[o[0] as usize], s.hi[o[0] as usize]);
        for &i in &o[1..] {
            a = a.min(s.lo[i as usize]);
            b = b.max(s.hi[i as usize]);
        }
        (a, b)
    };
    let (llo, lhi) = bounds_of(&lord[0][..mid]);
    let (rlo, rhi) = bounds_of(&rord[0][..n - mid]);
    nodes[0].write(BvhNode {
        min: lo.to_array(),
        first: first as u32,
        max: hi.to_array(),
        count: n as u32,
    });
    let (ln, rn) = nodes[1..].split_at_mut(2 * mid - 1);
    small_node::<L>(ln, s, &lord, mid, first, llo, lhi, out, out_len);
    small_node::<L>(rn, s, &rord, n - mid, first + mid, rlo, rhi, out, out_len);
}

/// An inner node split in the middle of `refs` as they lie.
fn interior_median<const L: usize>(
    nodes: &mut [MaybeUninit<BvhNode>],
    refs: &mut [PrimRef],
    first: usize,
    depth: usize,
    bounds: &Aabb,
) {
    let mid = refs.len() / 2;
    let (l, r) = refs.split_at(mid);
    let (lb, lc) = bounds_of(l);
    let (rb, rc) = bounds_of(r);
    interior::<L>(nodes, refs, first, depth, bounds, mid, (lb, lc), (rb, rc))
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

/// Writes an inner node over `refs`, split at `mid`, and builds its children (in parallel
/// when both are large).
#[allow(clippy::too_many_arguments)]
fn interior<const L: usize>(
    nodes: &mut [MaybeUninit<BvhNode>],
    refs: &mut [PrimRef],
    first: usize,
    depth: usize,
    bounds: &Aabb,
    mid: usize,
    (lb, lc): (Aabb, Aabb),
    (rb, rc): (Aabb, Aabb),
) {
    nodes[0].write(BvhNode {
        min: bounds.min.to_array(),
        first: first as u32,
        max: bounds.max.to_array(),
        count: refs.len() as u32,
    });
    let (left, right) = refs.split_at_mut(mid);
    let (ln, rn) = nodes[1..].split_at_mut(2 * mid - 1);
    if left.len().min(right.len()) >= PARALLEL_MIN {
        rayon::join(
            || build_node::<L>(ln, left, first, depth + 1, lb, lc),
            || build_node::<L>(rn, right, first + mid, depth + 1, rb, rc),
        );
    } else {
        build_node::<L>(ln, left, first, depth + 1, lb, lc);
        build_node::<L>(rn, right, first + mid, depth + 1, rb, rc);
    }
}

/// In-place partition of `refs`: to the left those whose doubled centroid `c` has
/// `(c - cmin) * scale < limit` along `axis` (that is, those in bins below `limit`; a NaN
/// goes right, as `bin3` clamps it to the last bin); returns the split index and the bounds
/// and centroid bounds of both sides. Neither side is empty when the split came from bins
/// holding primitives on both sides.
///
/// Branch-free (Lomuto's scheme with the swap made unconditional, as in Edelkamp and Weiß,
/// "BlockQuicksort", ESA 2016, and pdqsort): which side a primitive goes to is a coin flip
/// the branch predictor loses half the time, and Hoare's scheme paid a misprediction for
/// every other primitive of every level of the tree.
fn partition(
    refs: &mut [PrimRef],
    cmin: Vec3A,
    scale: Vec3A,
    axis: usize,
    limit: f32,
) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    let limit = Vec3A::splat(limit);
    let bit = 1 << axis;
    let n = refs.len();
    let mut j = 0;
    for i in 0..n {
        // SAFETY: j <= i < n.
        unsafe {
            let r = *refs.get_unchecked(i);
            let left = ((r.c2() - cmin) * scale).cmplt(limit).bitmask() & bit != 0;
            *refs.get_unchecked_mut(i) = *refs.get_unchecked(j);
            *refs.get_unchecked_mut(j) = r;
            j += left as usize;
        }
    }
    // The sides' bounds in a second pass (the primitives are in cache now): growing one
    // side's or the other's by selects inside the loop cost more than this pass.
    let (l, r) = refs.split_at(j);
    (j, bounds_of(l), bounds_of(r))
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
            let r = PrimRef::new(&b, index);
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
                )
            })
            .collect();
        let (_, cb) = bounds_of(&refs);
        let scale = Vec3A::splat(16.0 * (1.0 - 1e-6)) / cb.extent();
        for axis in 0..3 {
            for limit in [1.0f32, 5.0, 15.0] {
                let mut v = refs.clone();
                let (mid, (lb, lc), (rb, rc)) = partition(&mut v, cb.min, scale, axis, limit);
                let left = |r: &PrimRef| ((r.c2() - cb.min) * scale)[axis] < limit;
                assert!(v[..mid].iter().all(left) && !v[mid..].iter().any(left));
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
