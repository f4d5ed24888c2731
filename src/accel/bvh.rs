//! A bounding volume hierarchy built with the binned surface area heuristic and stored as a
//! flat array of 32-byte nodes in depth-first order.
//!
//! The BVH knows nothing about primitives beyond their bounds. It is the build stage: for
//! traversal it is collapsed into the 4-wide tree of [`super::wide`].
//!
//! Build: Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", RT 2007
//! (binning centroids into 16 buckets per axis and sweeping for the cheapest split).

use crate::geometry::Aabb;
use glam::Vec3A;

/// One node. Interior nodes have `count == 0`; their first child follows them in the array
/// and `offset` is the index of the second. Leaves hold `count` primitives from `offset` on.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct BvhNode {
    pub min: [f32; 3],
    pub offset: u32,
    pub max: [f32; 3],
    pub count: u16,
    pub axis: u16,
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// `order[i]` is the caller's index of the BVH's i-th primitive.
    pub order: Vec<u32>,
}

const BINS: usize = 16;
/// Deepest a node may lie. Past `MAX_DEPTH - 32` nodes split at the object median, which
/// halves the count, so no path can exceed this for fewer than 2³² primitives; traversal
/// stacks are sized from it.
pub const MAX_DEPTH: usize = 80;
const MAX_LEAF: usize = 8;
/// Cost of visiting a node relative to one primitive test. Measured with callgrind on the
/// TNCG15 room (32×32, 64 spp): 1.0 → 837 M instructions, 0.5 → 765 M, 0.25 and 0.125 the
/// same as 0.5; 2.0 → 1319 M. 0.5 is also pbrt-v4's value.
const TRAVERSAL_COST: f32 = 0.5;

struct BuildRef {
    bounds: Aabb,
    centroid: Vec3A,
    index: u32,
}

/// Subtrees with more primitives than this are built in parallel (rayon::join); below it the
/// recursion stays on one thread and writes into one node array.
const PARALLEL_MIN: usize = 1 << 14;

/// Per-axis bins of one node: primitive counts, primitive bounds and centroid bounds.
struct Bins {
    count: [[u32; BINS]; 3],
    bounds: [[Aabb; BINS]; 3],
    centroids: [[Aabb; BINS]; 3],
}

impl Bvh {
    /// Builds over the given primitive bounds.
    pub fn build(bounds: &[Aabb]) -> Bvh {
        use rayon::prelude::*;
        let mut refs: Vec<BuildRef> = bounds
            .par_iter()
            .enumerate()
            .map(|(i, b)| BuildRef {
                bounds: *b,
                centroid: b.centroid(),
                index: i as u32,
            })
            .collect();
        if refs.is_empty() {
            return Bvh {
                nodes: vec![BvhNode {
                    min: [f32::INFINITY; 3],
                    offset: 0,
                    max: [f32::NEG_INFINITY; 3],
                    count: 0,
                    axis: 0,
                }],
                // An empty leaf: traversal checks `order`.
                order: Vec::new(),
            };
        }
        let (b, cb) = bounds_of(&refs);
        let nodes = build_subtree(&mut refs, 0, 0, b, cb);
        Bvh {
            nodes,
            order: refs.iter().map(|r| r.index).collect(),
        }
    }

    pub fn bounds(&self) -> Aabb {
        let n = &self.nodes[0];
        Aabb {
            min: Vec3A::from_array(n.min),
            max: Vec3A::from_array(n.max),
        }
    }

    pub fn depth(&self) -> usize {
        fn rec(b: &Bvh, i: usize) -> usize {
            let n = &b.nodes[i];
            if n.count > 0 || b.order.is_empty() {
                1
            } else {
                1 + rec(b, i + 1).max(rec(b, n.offset as usize))
            }
        }
        rec(self, 0)
    }
}

/// Bounds of the primitives and of their centroids.
fn bounds_of(refs: &[BuildRef]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut cb = Aabb::EMPTY;
    for r in refs {
        b.grow(&r.bounds);
        cb.grow_point(r.centroid);
    }
    (b, cb)
}

/// Builds the subtree over `refs` (the primitives `first..first + refs.len()` of the final
/// order) into a node array of its own, whose inner nodes' offsets count from its start.
fn build_subtree(
    refs: &mut [BuildRef],
    first: usize,
    depth: usize,
    bounds: Aabb,
    cbounds: Aabb,
) -> Vec<BvhNode> {
    let mut nodes = Vec::with_capacity(2 * refs.len());
    build_node(&mut nodes, refs, first, depth, bounds, cbounds);
    nodes
}

fn leaf(b: &Aabb, first: usize, count: usize) -> BvhNode {
    BvhNode {
        min: b.min.to_array(),
        offset: first as u32,
        max: b.max.to_array(),
        count: count as u16,
        axis: 0,
    }
}

/// Appends the subtree over `refs` to `nodes`. `bounds` and `cbounds` are the bounds of the
/// primitives and of their centroids (the parent's bins give them without another pass).
fn build_node(
    nodes: &mut Vec<BvhNode>,
    refs: &mut [BuildRef],
    first: usize,
    depth: usize,
    bounds: Aabb,
    cbounds: Aabb,
) {
    let n = refs.len();
    if n == 1 {
        nodes.push(leaf(&bounds, first, n));
        return;
    }
    let cext = cbounds.extent();
    let widest = if cext.x >= cext.y && cext.x >= cext.z {
        0
    } else if cext.y >= cext.z {
        1
    } else {
        2
    };
    if depth >= MAX_DEPTH - 32 {
        // Degenerate input (the SAH keeps peeling off few primitives): split at the object
        // median along the widest centroid axis.
        let mid = n / 2;
        refs.select_nth_unstable_by(mid, |a, b| {
            a.centroid[widest].total_cmp(&b.centroid[widest])
        });
        return push_interior(nodes, refs, first, depth, &bounds, widest, mid, None);
    }
    // Bin the centroids along all three axes in one pass over the primitives.
    let scale = Vec3A::select(
        cext.cmpgt(Vec3A::ZERO),
        Vec3A::splat(BINS as f32 * (1.0 - 1e-6)) / cext,
        Vec3A::ZERO,
    );
    let bin_of = |c: Vec3A| {
        let b = ((c - cbounds.min) * scale)
            .as_uvec3()
            .min(glam::UVec3::splat(BINS as u32 - 1));
        [b.x as usize, b.y as usize, b.z as usize]
    };
    let mut bins = Bins {
        count: [[0; BINS]; 3],
        bounds: [[Aabb::EMPTY; BINS]; 3],
        centroids: [[Aabb::EMPTY; BINS]; 3],
    };
    for r in refs.iter() {
        let b = bin_of(r.centroid);
        #[allow(clippy::needless_range_loop)] // three parallel arrays indexed by axis
        for axis in 0..3 {
            bins.count[axis][b[axis]] += 1;
            bins.bounds[axis][b[axis]].grow(&r.bounds);
            bins.centroids[axis][b[axis]].grow_point(r.centroid);
        }
    }
    // Sweep each axis for the cheapest split (right-hand areas first, then from the left).
    let mut best: Option<(usize, usize, f32)> = None; // (axis, bin, cost)
    for axis in 0..3 {
        if cext[axis] <= 0.0 {
            continue;
        }
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in (1..BINS).rev() {
            acc.grow(&bins.bounds[axis][i]);
            cnt += bins.count[axis][i];
            right_area[i] = acc.surface_area();
            right_count[i] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in 0..BINS - 1 {
            acc.grow(&bins.bounds[axis][i]);
            cnt += bins.count[axis][i];
            if cnt == 0 || right_count[i + 1] == 0 {
                continue;
            }
            let cost =
                cnt as f32 * acc.surface_area() + right_count[i + 1] as f32 * right_area[i + 1];
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, i, cost));
            }
        }
    }
    let area = bounds.surface_area().max(f32::MIN_POSITIVE);
    let leaf_cost = n as f32;
    match best.map(|(axis, bin, cost)| (axis, bin, TRAVERSAL_COST + cost / area)) {
        Some((axis, bin, cost)) if cost < leaf_cost || n > MAX_LEAF => {
            let mid = partition(refs, |r| bin_of(r.centroid)[axis] <= bin);
            // The children's bounds are the unions of their bins'.
            let union = |range: std::ops::Range<usize>| {
                let (mut b, mut c) = (Aabb::EMPTY, Aabb::EMPTY);
                for i in range {
                    b.grow(&bins.bounds[axis][i]);
                    c.grow(&bins.centroids[axis][i]);
                }
                (b, c)
            };
            let left_count: u32 = bins.count[axis][..=bin].iter().sum();
            // (The partition falls back to a median split only if one side were empty, which
            // the sweep excludes; then the bins would not describe the children.)
            let children =
                (mid == left_count as usize).then(|| (union(0..bin + 1), union(bin + 1..BINS)));
            push_interior(nodes, refs, first, depth, &bounds, axis, mid, children);
        }
        // All centroids coincide: split the list in half so leaves stay small.
        None if n > MAX_LEAF => push_interior(nodes, refs, first, depth, &bounds, 0, n / 2, None),
        _ => nodes.push(leaf(&bounds, first, n)),
    }
}

/// Emits an inner node over `refs`, split at `mid` along `axis`, and builds its children
/// (in parallel when they are large). `children` gives their bounds and centroid bounds
/// when the split came from the bins.
#[allow(clippy::too_many_arguments)]
fn push_interior(
    nodes: &mut Vec<BvhNode>,
    refs: &mut [BuildRef],
    first: usize,
    depth: usize,
    bounds: &Aabb,
    axis: usize,
    mid: usize,
    children: Option<((Aabb, Aabb), (Aabb, Aabb))>,
) {
    let node_index = nodes.len();
    nodes.push(BvhNode {
        min: bounds.min.to_array(),
        offset: 0,
        max: bounds.max.to_array(),
        count: 0,
        axis: axis as u16,
    });
    let (left, right) = refs.split_at_mut(mid);
    let ((lb, lc), (rb, rc)) = children.unwrap_or_else(|| (bounds_of(left), bounds_of(right)));
    if left.len().min(right.len()) >= PARALLEL_MIN {
        let (l, r) = rayon::join(
            || build_subtree(left, first, depth + 1, lb, lc),
            || build_subtree(right, first + mid, depth + 1, rb, rc),
        );
        append(nodes, &l);
        nodes[node_index].offset = nodes.len() as u32;
        append(nodes, &r);
    } else {
        build_node(nodes, left, first, depth + 1, lb, lc);
        nodes[node_index].offset = nodes.len() as u32;
        build_node(nodes, right, first + mid, depth + 1, rb, rc);
    }
}

/// Appends a subtree built on its own, moving its inner nodes' child offsets to its place.
fn append(nodes: &mut Vec<BvhNode>, sub: &[BvhNode]) {
    let base = nodes.len() as u32;
    nodes.extend(sub.iter().map(|n| {
        let mut n = *n;
        if n.count == 0 {
            n.offset += base;
        }
        n
    }));
}

/// Stable-enough in-place partition; returns the number of elements satisfying `pred`,
/// falling back to a median split if every element lands on one side.
fn partition<F: Fn(&BuildRef) -> bool>(refs: &mut [BuildRef], pred: F) -> usize {
    let mut i = 0;
    for j in 0..refs.len() {
        if pred(&refs[j]) {
            refs.swap(i, j);
            i += 1;
        }
    }
    if i == 0 || i == refs.len() {
        refs.len() / 2
    } else {
        i
    }
}
