//! The build for large inputs: the primitives sorted along a Morton curve, neighbours on the
//! curve paired into clusters, and the binned SAH tree built over the clusters.
//!
//! After the bottom-up grouping of HLBVH (Garanzha, Pantaleoni and McAllister, "Simpler and
//! Faster HLBVH with Work Queues", HPG 2011), kept to the finest level: a cluster is a leaf
//! of at most [`CLUSTER_SIZE`] primitives, formed only where its box is no larger than its
//! primitives' boxes together (by surface area), so that it never spans a jump of the curve.
//! The Morton sort is linear (three radix passes over 8-byte keys); the SAH build, O(n log n)
//! and on large inputs bound by memory traffic (each level reads and rewrites every 32-byte
//! reference), then sees about 60 % of the references. Measured on the subdivided bunny
//! (`cargo bench --bench scale`): the tree's SAH cost rises 3 % at 1 M triangles; clusters
//! of up to four, faster still to build, cost 10 % (see docs/performance.md).

use super::{build_sah, Bvh, PrimRef};
use crate::accel::BuildTimes;
use crate::geometry::Aabb;
use glam::Vec3A;
use rayon::prelude::*;

/// Inputs of at least this many primitives are built over clusters.
pub const CLUSTER_MIN: usize = 1 << 15;
/// Most primitives in one cluster (a leaf).
const CLUSTER_SIZE: usize = 2;
/// A cluster's surface area may be at most this times the sum of its primitives'.
const CLUSTER_AREA: f32 = 1.0;
/// Clusters are formed in chunks of this many consecutive keys.
const CHUNK: usize = 1 << 16;
/// Bits of a Morton code (10 per axis) and of one radix pass.
const CODE_BITS: u32 = 30;
const RADIX_BITS: u32 = 10;

/// The tree over clusters of `refs` (which it leaves as they are); `order` lists the
/// primitives cluster by cluster in the tree's order.
pub(super) fn build(refs: &[PrimRef], times: &mut BuildTimes) -> Bvh {
    let keys = sorted_keys(refs);
    times.mark("Morton sort");
    // Clusters: runs of consecutive keys, formed in fixed chunks of the curve (so the result
    // depends on the input only, not on the threads).
    let parts: Vec<(Vec<u32>, Vec<Aabb>)> = keys
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| clusters_of(refs, chunk, (c * CHUNK) as u32))
        .collect();
    let mut starts = Vec::with_capacity(keys.len() / 2 + 2);
    let mut clusters = Vec::with_capacity(keys.len() / 2 + 1);
    for (s, b) in parts {
        starts.extend_from_slice(&s);
        for b in &b {
            clusters.push(PrimRef::new(b, clusters.len() as u32));
        }
    }
    starts.push(keys.len() as u32);
    let range = |c: usize| starts[c] as usize..starts[c + 1] as usize;
    times.mark("clusters");
    let mut bvh = build_sah::<1>(&mut clusters);
    times.mark("binary SAH tree");
    // Positions of the clusters' first primitives in the final order.
    let mut prim_start = Vec::with_capacity(bvh.order.len() + 1);
    let mut at = 0u32;
    for &c in &bvh.order {
        prim_start.push(at);
        at += starts[c as usize + 1] - starts[c as usize];
    }
    prim_start.push(at);
    bvh.order = bvh
        .order
        .par_iter()
        .with_min_len(1 << 12)
        .flat_map_iter(|&c| keys[range(c as usize)].iter().map(|&k| k as u32))
        .collect();
    bvh.prim_start = prim_start;
    times.mark("cluster order");
    bvh
}

/// The clusters of one chunk of the sorted keys, whose first key is the `base`-th: each
/// cluster's first position and its bounds. A cluster takes the next primitive while it has
/// fewer than `CLUSTER_SIZE` and its bounds' surface area stays within `CLUSTER_AREA` times
/// the sum of its primitives' (so it never spans a jump of the curve).
fn clusters_of(refs: &[PrimRef], chunk: &[u64], base: u32) -> (Vec<u32>, Vec<Aabb>) {
    let bounds = |k: u64| refs[k as u32 as usize].bounds();
    let (mut starts, mut out) = (vec![base], Vec::with_capacity(chunk.len() / 2 + 1));
    let mut cb = bounds(chunk[0]);
    let (mut sum, mut len) = (cb.surface_area(), 1);
    for (i, &k) in chunk.iter().enumerate().skip(1) {
        let b = bounds(k);
        let u = Aabb::union(&cb, &b);
        let a = b.surface_area();
        if len == CLUSTER_SIZE || u.surface_area() > CLUSTER_AREA * (sum + a) {
            starts.push(base + i as u32);
            out.push(cb);
            (cb, sum, len) = (b, a, 1);
        } else {
            (cb, sum, len) = (u, sum + a, len + 1);
        }
    }
    out.push(cb);
    (starts, out)
}

/// The primitives' keys (Morton code of the centroid in the high 32 bits, index in the low),
/// sorted. Keys are distinct, so the order is unique.
fn sorted_keys(refs: &[PrimRef]) -> Vec<u64> {
    let cb = refs
        .par_iter()
        .with_min_len(1 << 12)
        .map(|r| Aabb {
            min: r.c2(),
            max: r.c2(),
        })
        .reduce(|| Aabb::EMPTY, |a, b| Aabb::union(&a, &b));
    let ext = cb.extent();
    let steps = (1u32 << (CODE_BITS / 3)) as f32;
    let scale = Vec3A::select(
        ext.cmpgt(Vec3A::ZERO),
        Vec3A::splat(steps * (1.0 - 1e-6)) / ext,
        Vec3A::ZERO,
    );
    let mut keys: Vec<u64> = refs
        .par_iter()
        .with_min_len(1 << 12)
        .map(|r| {
            let q = ((r.c2() - cb.min) * scale).min(Vec3A::splat(steps - 1.0));
            let code = spread(q.x as u32) | spread(q.y as u32) << 1 | spread(q.z as u32) << 2;
            (code as u64) << 32 | r.index() as u64
        })
        .collect();
    radix_sort_high(&mut keys);
    keys
}

/// The low 10 bits of `x` moved to every third bit (bit i to bit 3i).
#[inline]
fn spread(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    x = (x | x << 2) & 0x0924_9249;
    x
}

/// Sorts keys by their high 32 bits (of which the low `CODE_BITS` are used), stably: an LSD
/// radix sort, three passes of `RADIX_BITS`, with all three histograms from one read.
fn radix_sort_high(keys: &mut Vec<u64>) {
    const PASSES: usize = (CODE_BITS / RADIX_BITS) as usize;
    const BUCKETS: usize = 1 << RADIX_BITS;
    let digit = |k: u64, p: usize| ((k >> (32 + RADIX_BITS as usize * p)) as usize) & (BUCKETS - 1);
    let mut hist = vec![[0u32; BUCKETS]; PASSES];
    for &k in keys.iter() {
        for (p, h) in hist.iter_mut().enumerate() {
            h[digit(k, p)] += 1;
        }
    }
    let mut tmp = vec![0u64; keys.len()];
    for (p, h) in hist.iter_mut().enumerate() {
        let mut sum = 0;
        for c in h.iter_mut() {
            (*c, sum) = (sum, sum + *c);
        }
        for &k in keys.iter() {
            let d = &mut h[digit(k, p)];
            tmp[*d as usize] = k;
            *d += 1;
        }
        std::mem::swap(keys, &mut tmp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_puts_bit_i_at_3i() {
        for i in 0..10 {
            assert_eq!(spread(1 << i), 1 << (3 * i));
        }
        assert_eq!(spread(0x3ff), 0x0924_9249);
        assert_eq!(spread(0x400), 0, "only 10 bits");
    }

    #[test]
    fn radix_sort_matches_a_comparison_sort() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut keys: Vec<u64> = (0..20_000u64)
            .map(|i| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                // Few distinct codes, so that ties (broken by the index) are common.
                ((x % 3000) << 32) | i
            })
            .collect();
        let mut expected = keys.clone();
        expected.sort();
        radix_sort_high(&mut keys);
        assert_eq!(keys, expected);
    }

    /// Every primitive in exactly one leaf, leaves of at most CLUSTER_SIZE, and every node's
    /// bounds holding its primitives' and its children's.
    #[test]
    fn clustered_tree_covers_every_primitive_once() {
        let mut x = 12345u32;
        let mut f = || {
            x = x.wrapping_mul(747796405).wrapping_add(2891336453);
            (x >> 8) as f32 / (1 << 24) as f32
        };
        let n = 5000;
        let boxes: Vec<Aabb> = (0..n)
            .map(|_| {
                let c = Vec3A::new(f(), f() * 3.0, f()) * 10.0;
                let h = Vec3A::new(f(), f(), f()) * 0.05;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect();
        let refs: Vec<PrimRef> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| PrimRef::new(b, i as u32))
            .collect();
        let bvh = build(&refs, &mut BuildTimes::start());
        let mut seen = vec![false; n];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = bvh.node(i);
            let (first, count) = bvh.prim_range(node);
            let nb = node.bounds();
            for &p in &bvh.order[first as usize..(first + count) as usize] {
                let b = &boxes[p as usize];
                assert!(nb.min.cmple(b.min).all() && nb.max.cmpge(b.max).all());
            }
            if node.is_leaf() {
                assert!((1..=CLUSTER_SIZE as u32).contains(&count));
                for &p in &bvh.order[first as usize..(first + count) as usize] {
                    assert!(!seen[p as usize], "primitive {p} twice");
                    seen[p as usize] = true;
                }
            } else {
                stack.extend([i + 1, bvh.right(i)]);
            }
        }
        assert!(seen.iter().all(|&s| s), "a primitive in no leaf");
    }
}
