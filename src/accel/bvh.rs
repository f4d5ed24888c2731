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

impl Bvh {
    /// Builds over the given primitive bounds.
    pub fn build(bounds: &[Aabb]) -> Bvh {
        let mut refs: Vec<BuildRef> = bounds
            .iter()
            .enumerate()
            .map(|(i, b)| BuildRef {
                bounds: *b,
                centroid: b.centroid(),
                index: i as u32,
            })
            .collect();
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(bounds.len().max(1) * 2),
            order: Vec::new(),
        };
        if refs.is_empty() {
            bvh.nodes.push(BvhNode {
                min: [f32::INFINITY; 3],
                offset: 0,
                max: [f32::NEG_INFINITY; 3],
                count: 0,
                axis: 0,
            });
            // An empty leaf: mark with count 0 but no children; traversal checks `order`.
            return bvh;
        }
        bvh.build_node(&mut refs, 0, 0);
        bvh.order = refs.iter().map(|r| r.index).collect();
        bvh
    }

    pub fn bounds(&self) -> Aabb {
        let n = &self.nodes[0];
        Aabb {
            min: Vec3A::from_array(n.min),
            max: Vec3A::from_array(n.max),
        }
    }

    fn push_leaf(&mut self, b: &Aabb, first: usize, count: usize) {
        self.nodes.push(BvhNode {
            min: b.min.to_array(),
            offset: first as u32,
            max: b.max.to_array(),
            count: count as u16,
            axis: 0,
        });
    }

    fn build_node(&mut self, refs: &mut [BuildRef], first: usize, depth: usize) -> usize {
        let node_index = self.nodes.len();
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for r in refs.iter() {
            bounds.grow(&r.bounds);
            cbounds.grow_point(r.centroid);
        }
        let n = refs.len();
        if n == 1 {
            self.push_leaf(&bounds, first, n);
            return node_index;
        }
        let cext = cbounds.extent();
        if depth >= MAX_DEPTH - 32 {
            // Degenerate input (the SAH keeps peeling off few primitives): split at the
            // object median along the widest centroid axis.
            let axis = if cext.x >= cext.y && cext.x >= cext.z {
                0
            } else if cext.y >= cext.z {
                1
            } else {
                2
            };
            let mid = n / 2;
            refs.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            return self.push_interior(refs, first, depth, &bounds, axis, mid);
        }
        // Find the cheapest binned split over all three axes.
        let mut best: Option<(usize, usize, f32)> = None; // (axis, bin, cost)
        for axis in 0..3 {
            if cext[axis] <= 0.0 {
                continue;
            }
            let mut counts = [0usize; BINS];
            let mut bb = [Aabb::EMPTY; BINS];
            let k = BINS as f32 * (1.0 - 1e-6) / cext[axis];
            for r in refs.iter() {
                let b = (((r.centroid[axis] - cbounds.min[axis]) * k) as usize).min(BINS - 1);
                counts[b] += 1;
                bb[b].grow(&r.bounds);
            }
            // Sweep from the right to get the right-hand areas, then from the left.
            let mut right_area = [0.0f32; BINS];
            let mut right_count = [0usize; BINS];
            let mut acc = Aabb::EMPTY;
            let mut cnt = 0;
            for i in (1..BINS).rev() {
                acc.grow(&bb[i]);
                cnt += counts[i];
                right_area[i] = acc.surface_area();
                right_count[i] = cnt;
            }
            let mut acc = Aabb::EMPTY;
            let mut cnt = 0;
            for i in 0..BINS - 1 {
                acc.grow(&bb[i]);
                cnt += counts[i];
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
        let split = best.map(|(axis, bin, cost)| (axis, bin, TRAVERSAL_COST + cost / area));
        let (axis, mid) = match split {
            Some((axis, bin, cost)) if cost < leaf_cost || n > MAX_LEAF => {
                let k = BINS as f32 * (1.0 - 1e-6) / cext[axis];
                let lo = cbounds.min[axis];
                let mid = partition(refs, |r| {
                    (((r.centroid[axis] - lo) * k) as usize).min(BINS - 1) <= bin
                });
                (axis, mid)
            }
            None if n > MAX_LEAF => {
                // All centroids coincide: split the list in half so leaves stay small.
                (0, n / 2)
            }
            _ => {
                self.push_leaf(&bounds, first, n);
                return node_index;
            }
        };
        self.push_interior(refs, first, depth, &bounds, axis, mid)
    }

    /// Emits an inner node over `refs`, split at `mid` along `axis`, and builds its children.
    fn push_interior(
        &mut self,
        refs: &mut [BuildRef],
        first: usize,
        depth: usize,
        bounds: &Aabb,
        axis: usize,
        mid: usize,
    ) -> usize {
        let node_index = self.nodes.len();
        self.nodes.push(BvhNode {
            min: bounds.min.to_array(),
            offset: 0,
            max: bounds.max.to_array(),
            count: 0,
            axis: axis as u16,
        });
        let (left, right) = refs.split_at_mut(mid);
        self.build_node(left, first, depth + 1);
        let second = self.build_node(right, first + mid, depth + 1);
        self.nodes[node_index].offset = second as u32;
        node_index
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
