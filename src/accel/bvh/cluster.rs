//! The build for large inputs: the primitives sorted along a Morton curve, runs of
//! neighbours on the curve grouped into clusters, the binned SAH tree built over the
//! clusters (each counting for its primitives), and under each cluster a small tree over its
//! own primitives.
//!
//! After the bottom-up grouping of HLBVH (Garanzha, Pantaleoni and McAllister, "Simpler and
//! Faster HLBVH with Work Queues", HPG 2011), kept to the finest level, and the mini-trees of
//! Bonsai (Ganestam et al., "Bonsai: Rapid Bounding Volume Hierarchy Generation using Mini
//! Trees", JCGT 4(3), 2015): a cluster holds at most [`CLUSTER_SIZE`] consecutive primitives
//! and forms only where its box is no larger than its primitives' boxes together (by surface
//! area), so that it never spans a jump of the curve. The Morton sort is linear (three radix
//! passes over 8-byte keys). The SAH build over the clusters, O(n log n) and on large inputs
//! bound by memory traffic (each level reads and rewrites every 32-byte reference), sees
//! about a third of the references. Measured on the subdivided bunny (`cargo bench --bench
//! scale`, 940 k triangles, see docs/performance.md): the wide tree's SAH cost is 24.57,
//! against 24.9 for the binary SAH tree over clusters of at most two that were leaves, and
//! 24.84 with an exact SAH sweep under each cluster instead of [`run_tree`].
//!
//! Memory: at 10 M triangles the build's arrays are a large share of its time on hosts that
//! charge for memory a process touches first (docs/performance.md, "Fresh memory on this
//! VM"), so it keeps few: the primitives in curve order (4 bytes each, the low halves of
//! the sorted keys, kept in half of the sort's own buffer), the clusters' references, the
//! wide nodes and the order; the binary tree never exists whole ([`fused`]). A
//! primitive's bounds are asked of the caller again where they are needed (for its key,
//! when the clusters form, and when its cluster's tree is built) instead of being stored and
//! gathered along the curve (64 bytes a primitive); each cluster's tree is built once when
//! the cluster forms, to count its nodes, so that the node array holds no gaps.

use super::{
    finish, fused, half_area, inner, BvhNode, Kind, PrimRef, Prims, Sub, Weight, MAX_DEPTH,
};
use crate::accel::wide::{merges, WideBvh};
use crate::accel::{huge_pages, BuildTimes};
use crate::geometry::Aabb;
use glam::Vec3A;
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// Inputs of at least this many primitives are built over clusters.
pub const CLUSTER_MIN: usize = 1 << 15;
/// Most primitives in one cluster.
const CLUSTER_SIZE: usize = 8;
/// A cluster's surface area may be at most this times the sum of its primitives'.
const CLUSTER_AREA: f32 = 1.0;
/// Clusters are formed in chunks of this many consecutive keys.
const CHUNK: usize = 1 << 16;
/// Bits of a Morton code (10 per axis) and of one radix pass.
const CODE_BITS: u32 = 30;
const RADIX_BITS: u32 = 10;

/// The tree over the primitives `0..n` (`prim` gives each one's reference): clusters of
/// neighbours on the Morton curve, the binned SAH tree over the clusters (each counting for
/// its primitives), and below each cluster the SAH tree over its own primitives. Nodes count
/// primitives, as in a tree built over them directly. No array of the primitives'
/// references is kept: each phase asks `prim` again for those it needs (see [`super::build`]).
pub(super) fn build<F>(n: usize, prim: &F, times: &mut BuildTimes) -> (WideBvh, Vec<u32>)
where
    F: Fn(u32) -> PrimRef + Sync,
{
    let (keys, world) = sorted_keys(n, prim);
    times.mark("Morton sort");
    let merge_weight = crate::accel::wide::merge_weight(n, &world);
    // Clusters: runs of consecutive primitives, formed in fixed chunks of the curve (so the
    // result depends on the input only, not on the threads), each chunk's written into its
    // own stretch of a staging array with room for a cluster per primitive, of which the
    // memory is touched only where written (about a third) and given back to the system
    // once the clusters are gathered. (A vector per chunk came from the allocator's
    // thread arenas, which kept about 90 MB of it at 10 M triangles after it was freed.)
    let mut staging: Vec<MaybeUninit<PrimRef>> = huge_pages::sparse(n);
    // SAFETY: MaybeUninit needs no initialisation.
    unsafe { staging.set_len(n) };
    let counts: Vec<usize> = keys
        .par_chunks(CHUNK)
        .zip(staging.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (chunk, out))| clusters_of(chunk, (c * CHUNK) as u32, prim, merge_weight, out))
        .collect();
    let mut clusters = concatenate(&staging, &counts);
    drop(staging);
    times.mark("clusters");
    let kind = Clusters {
        keys: &keys,
        prim,
        merge_weight,
    };
    fused::build(&kind, &mut clusters, n, merge_weight, times)
}

/// Clusters of primitives: a leaf of the tree over them is one cluster, under which the
/// tree over its primitives is built.
struct Clusters<'a, F> {
    /// The primitives in Morton order: a cluster's reference holds the position of its
    /// first in its index lane.
    keys: &'a [u32],
    prim: &'a F,
    /// The wide collapse's merge weight: subtrees it would merge into one leaf are built
    /// as that leaf (see [`run_tree`]).
    merge_weight: f32,
}

impl<F: Fn(u32) -> PrimRef + Sync> Kind for Clusters<'_, F> {
    const MAX_LEAF: usize = 1;
    const UNIT: bool = false;
    /// Median splits from this depth halve the clusters, fewer than 2²⁷, so single ones lie
    /// at most 27 levels deeper, and a cluster's tree adds at most `CLUSTER_SIZE - 1`
    /// levels: no path passes `MAX_DEPTH`.
    const MEDIAN_DEPTH: usize = MAX_DEPTH - 32 - CLUSTER_SIZE;
    #[inline(always)]
    fn weight(r: &PrimRef) -> Weight {
        r.cluster_weight()
    }
    fn leaf(
        &self,
        nodes: &mut [MaybeUninit<BvhNode>],
        order: &mut [u32],
        refs: &[PrimRef],
        first: usize,
        _depth: usize,
        bounds: &Aabb,
    ) -> Sub {
        debug_assert_eq!(refs.len(), 1);
        let start = refs[0].index() as usize;
        // (The cluster's primitives are as many as its part of the order.)
        let keys = &self.keys[start..start + order.len()];
        let mut prims = [PrimRef::EMPTY; CLUSTER_SIZE];
        for (p, &k) in prims.iter_mut().zip(keys) {
            *p = (self.prim)(k);
        }
        let (sub, used) = run_tree(
            nodes,
            order,
            &prims[..keys.len()],
            first,
            bounds,
            self.merge_weight,
        );
        debug_assert_eq!(used, nodes.len());
        sub
    }
}

/// The tree over a cluster's primitives `prims`, in the order they lie along the Morton
/// curve: each node split into the prefix and suffix of its run that the SAH prefers, down
/// to single primitives (the wide collapse merges small subtrees into leaves again). Measured
/// on the subdivided bunny (`cargo bench --bench scale`, 940 k triangles) against the SAH
/// tree over each cluster's primitives by the exact sweep of [`super::sweep`] (whose leaves
/// may hold several): wide SAH cost 24.57 against 24.84, and a fifth of the instructions;
/// splitting each run in the middle instead gave 24.77.
///
/// The nodes are written one after the other from `nodes[0]`, each right child after its
/// left sibling's subtree; returns what the parent records, and the number of nodes. The
/// clusters are formed knowing that number ([`clusters_of`] builds each cluster's tree
/// once to count them), so the tree above lays the clusters' trees out without gaps.
fn run_tree(
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    prims: &[PrimRef],
    first: usize,
    bounds: &Aabb,
    merge_weight: f32,
) -> (Sub, usize) {
    let n = prims.len();
    if n == 1 {
        return (Prims.leaf(nodes, order, prims, first, 0, bounds), 1);
    }
    // A run of up to three primitives that the wide collapse would merge into one leaf
    // (`wide::merges`; split down to single primitives it would have a leaf each) is that
    // leaf already: the same wide tree, with fewer binary nodes written and read. Its
    // parent counts the leaves the run would have had, so that it is merged (or not)
    // just as before.
    if n <= 3
        && merges(
            n as u32,
            n as u32,
            prims.iter().any(PrimRef::costly),
            bounds,
            merge_weight,
        )
    {
        let _ = Prims.leaf(nodes, order, prims, first, 0, bounds);
        let sub = Sub {
            leaves: n as u32,
            costly: false,
        };
        return (sub, 1);
    }
    // Suffix bounds (kept for the right child), then the prefix sweep.
    let mut slo = [Vec3A::ZERO; CLUSTER_SIZE];
    let mut shi = [Vec3A::ZERO; CLUSTER_SIZE];
    let (mut lo, mut hi) = (prims[n - 1].lo(), prims[n - 1].hi());
    (slo[n - 1], shi[n - 1]) = (lo, hi);
    for k in (1..n - 1).rev() {
        lo = lo.min(prims[k].lo());
        hi = hi.max(prims[k].hi());
        (slo[k], shi[k]) = (lo, hi);
    }
    let (mut lo, mut hi) = (prims[0].lo(), prims[0].hi());
    // (split, its cost, the left bounds)
    let mut best = (1, f32::INFINITY, lo, hi);
    for k in 1..n {
        if k > 1 {
            lo = lo.min(prims[k - 1].lo());
            hi = hi.max(prims[k - 1].hi());
        }
        let cost = k as f32 * half_area(lo, hi) + (n - k) as f32 * half_area(slo[k], shi[k]);
        if cost < best.1 {
            best = (k, cost, lo, hi);
        }
    }
    let (k, _, llo, lhi) = best;
    let (head, rest) = nodes.split_first_mut().unwrap();
    let (lo, ro) = order.split_at_mut(k);
    let lb = Aabb { min: llo, max: lhi };
    let rb = Aabb {
        min: slo[k],
        max: shi[k],
    };
    let (a, l) = run_tree(rest, lo, &prims[..k], first, &lb, merge_weight);
    let (b, r) = run_tree(
        &mut rest[l..],
        ro,
        &prims[k..],
        first + k,
        &rb,
        merge_weight,
    );
    head.write(inner(bounds, 1 + l, n));
    (finish(head, a.join(b)), 1 + l + r)
}

/// The chunks' clusters one after the other: the first `counts[c]` of chunk c's stretch of
/// `staging` (copied in parallel, each chunk's to its own stretch).
fn concatenate(staging: &[MaybeUninit<PrimRef>], counts: &[usize]) -> Vec<PrimRef> {
    let count: usize = counts.iter().sum();
    let mut clusters: Vec<PrimRef> = huge_pages::with_capacity(count);
    let mut jobs = Vec::with_capacity(counts.len());
    let mut rest = &mut clusters.spare_capacity_mut()[..count];
    for (part, &c) in staging.chunks(CHUNK).zip(counts) {
        let (here, next) = std::mem::take(&mut rest).split_at_mut(c);
        rest = next;
        jobs.push((&part[..c], here));
    }
    jobs.into_par_iter().for_each(|(part, out)| {
        for (o, r) in out.iter_mut().zip(part) {
            // SAFETY: `clusters_of` wrote the first `counts[c]` of its stretch.
            o.write(unsafe { r.assume_init() });
        }
    });
    // SAFETY: the parts' stretches cover 0..count, and each was written whole.
    unsafe { clusters.set_len(count) };
    clusters
}

/// The clusters of one chunk of the sorted primitives, whose first is the `base`-th, written
/// into `out`; returns their number. Each is a reference with its primitives and nodes, and
/// the position of its first primitive in the curve's order in place of an index. A cluster
/// takes the next primitive while it has fewer than `CLUSTER_SIZE` and its bounds' surface
/// area stays within `CLUSTER_AREA` times the sum of its primitives' (so it never spans a
/// jump of the curve).
fn clusters_of<F>(
    chunk: &[u32],
    base: u32,
    prim: &F,
    merge_weight: f32,
    out: &mut [MaybeUninit<PrimRef>],
) -> usize
where
    F: Fn(u32) -> PrimRef,
{
    let mut first = base;
    // (At most one cluster a primitive, so `out` has room.)
    let mut count = 0;
    // The cluster's primitives, whose tree is built once here to count its nodes.
    let mut prims = [PrimRef::EMPTY; CLUSTER_SIZE];
    let mut scratch = [MaybeUninit::<BvhNode>::uninit(); 2 * CLUSTER_SIZE - 1];
    let mut scratch_order = [0u32; CLUSTER_SIZE];
    let mut close = |prims: &[PrimRef], cb: &Aabb, first: u32| {
        let len = prims.len();
        let (_, slots) = run_tree(
            &mut scratch,
            &mut scratch_order[..len],
            prims,
            0,
            cb,
            merge_weight,
        );
        PrimRef::cluster(cb, first, len as u32, slots as u32)
    };
    prims[0] = prim(chunk[0]);
    let mut cb = prims[0].bounds();
    let (mut sum, mut len) = (cb.surface_area(), 1);
    for (i, &k) in chunk.iter().enumerate().skip(1) {
        let r = prim(k);
        let b = r.bounds();
        let u = Aabb::union(&cb, &b);
        let a = b.surface_area();
        if len == CLUSTER_SIZE || u.surface_area() > CLUSTER_AREA * (sum + a) {
            out[count].write(close(&prims[..len], &cb, first));
            count += 1;
            first = base + i as u32;
            (cb, sum, len) = (b, a, 1);
        } else {
            (cb, sum, len) = (u, sum + a, len + 1);
        }
        prims[len - 1] = r;
    }
    out[count].write(close(&prims[..len], &cb, first));
    count + 1
}

/// The primitives sorted by their keys (Morton code of the centroid in the high 32 bits,
/// index in the low), and the bounds of all primitives. Keys are distinct, so the order is
/// unique.
fn sorted_keys<F>(n: usize, prim: &F) -> (Sorted, Aabb)
where
    F: Fn(u32) -> PrimRef + Sync,
{
    // (Minimum and maximum are exact, so any grouping of this reduction gives the same.)
    let (world, cb) = (0..n as u32)
        .into_par_iter()
        .with_min_len(1 << 12)
        .map(|i| {
            let r = prim(i);
            let c = r.c2();
            (r.bounds(), Aabb { min: c, max: c })
        })
        .reduce(
            || (Aabb::EMPTY, Aabb::EMPTY),
            |a, b| (Aabb::union(&a.0, &b.0), Aabb::union(&a.1, &b.1)),
        );
    let ext = cb.extent();
    let steps = (1u32 << (CODE_BITS / 3)) as f32;
    let scale = Vec3A::select(
        ext.cmpgt(Vec3A::ZERO),
        Vec3A::splat(steps * (1.0 - 1e-6)) / ext,
        Vec3A::ZERO,
    );
    let mut keys: Vec<u64> = huge_pages::with_capacity(n);
    (0..n as u32)
        .into_par_iter()
        .with_min_len(1 << 12)
        .map(|i| {
            let q = ((prim(i).c2() - cb.min) * scale).min(Vec3A::splat(steps - 1.0));
            let code = spread(q.x as u32) | spread(q.y as u32) << 1 | spread(q.z as u32) << 2;
            (code as u64) << 32 | i as u64
        })
        .collect_into_vec(&mut keys);
    (radix_sort_high(keys), world)
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

/// The primitives in curve order (the low halves of the sorted keys), as 4-byte indices in
/// the first half of the sort's spare buffer (see [`radix_sort_high`]).
pub(super) struct Sorted {
    buf: Vec<u64>,
    n: usize,
}

impl std::ops::Deref for Sorted {
    type Target = [u32];
    fn deref(&self) -> &[u32] {
        // SAFETY: the sort's last pass wrote the first `n` u32s of the buffer, which has room
        // for 2n (u64's alignment is more than u32's).
        unsafe { std::slice::from_raw_parts(self.buf.as_ptr() as *const u32, self.n) }
    }
}

/// Sorts keys by their high 32 bits (of which the low `CODE_BITS` are used), stably, and
/// returns their low halves: an LSD radix sort, three passes of `RADIX_BITS`. Each pass
/// splits the keys into blocks, counts each block's digits in parallel, and scatters the
/// blocks in parallel, each key to its digit's place after the keys of lower digits and of
/// the same digit in earlier blocks, so the result is the sequential pass's, whatever the
/// blocks or threads. The last pass writes only the low halves, into the first half of the
/// buffer the pass before read from; the keys' own buffer is then freed and the second half
/// of the other given back to the system (the build's fresh memory, see `super::build`).
fn radix_sort_high(mut keys: Vec<u64>) -> Sorted {
    const PASSES: usize = (CODE_BITS / RADIX_BITS) as usize;
    const BUCKETS: usize = 1 << RADIX_BITS;
    let n = keys.len();
    let block = n.div_ceil(4 * rayon::current_num_threads()).max(1 << 14);
    let mut tmp: Vec<u64> = huge_pages::with_capacity(n);
    for p in 0..PASSES {
        let shift = 32 + RADIX_BITS as usize * p;
        let digit = |k: u64| ((k >> shift) as usize) & (BUCKETS - 1);
        let counts: Vec<[u32; BUCKETS]> = keys
            .par_chunks(block)
            .map(|c| {
                let mut h = [0u32; BUCKETS];
                for &k in c {
                    h[digit(k)] += 1;
                }
                h
            })
            .collect();
        // Each block's first place for each digit.
        let mut places = counts.clone();
        let mut sum = 0;
        for d in 0..BUCKETS {
            for (b, c) in counts.iter().enumerate() {
                places[b][d] = sum;
                sum += c[d];
            }
        }
        let last = p == PASSES - 1;
        let out = Scatter(tmp.spare_capacity_mut().as_mut_ptr());
        keys.par_chunks(block)
            .zip(places)
            .for_each(|(c, mut place)| {
                let out = &out;
                for &k in c {
                    let d = &mut place[digit(k)];
                    // SAFETY: the places of (block, digit) run from the sums of the keys
                    // before them to that plus the block's count of the digit: the ranges
                    // tile 0..n, and each is written once, by this block only. (The last
                    // pass writes 4-byte halves, of which the buffer holds 2n.)
                    unsafe {
                        if last {
                            (out.0 as *mut u32).add(*d as usize).write(k as u32);
                        } else {
                            (*out.0.add(*d as usize)).write(k);
                        }
                    }
                    *d += 1;
                }
            });
        if last {
            break;
        }
        // SAFETY: the scatter wrote every place below n.
        unsafe { tmp.set_len(n) };
        std::mem::swap(&mut keys, &mut tmp);
        tmp.clear();
    }
    drop(keys);
    let half = tmp.as_ptr() as usize + 4 * n;
    // SAFETY: the second half of the buffer is never read (`Sorted` reads the first).
    unsafe { huge_pages::release(half, 4 * n) };
    Sorted { buf: tmp, n }
}

/// The output of a scatter, written at disjoint places from several threads.
struct Scatter(*mut std::mem::MaybeUninit<u64>);
// SAFETY: the threads write disjoint items (see `radix_sort_high`).
unsafe impl Sync for Scatter {}

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
        let keys: Vec<u64> = (0..20_000u64)
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
        let expected: Vec<u32> = expected.iter().map(|&k| k as u32).collect();
        assert_eq!(&radix_sort_high(keys)[..], &expected[..]);
    }

    /// Builds the tree over `boxes` (by [`build`], whatever their number) and checks it
    /// (see `WideBvh::check`).
    fn check_tree(boxes: &[Aabb]) {
        let n = boxes.len();
        let prim = |i: u32| PrimRef::new(&boxes[i as usize], i, false);
        let (wide, order) = build(n, &prim, &mut BuildTimes::start());
        let mut sorted = order.clone();
        sorted.sort();
        assert!(sorted.iter().enumerate().all(|(i, &p)| p == i as u32));
        let _ = wide.check(&order, |p| boxes[p as usize], super::super::MAX_LEAF as u32);
    }

    /// Random small boxes, their centres spread unevenly along the axes.
    fn random_boxes(n: usize, seed: u32) -> Vec<Aabb> {
        let mut x = seed;
        let mut f = || {
            x = x.wrapping_mul(747796405).wrapping_add(2891336453);
            (x >> 8) as f32 / (1 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3A::new(f(), f() * 3.0, f()) * 10.0;
                let h = Vec3A::new(f(), f(), f()) * 0.05;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect()
    }

    /// Fewer primitives than one subtree of the second stage (the root a stub), and enough
    /// for a top of a few hundred nodes.
    #[test]
    fn clustered_tree_covers_every_primitive_once() {
        check_tree(&random_boxes(5000, 12345));
        check_tree(&random_boxes(300_000, 777));
    }

    /// The second stage places the subtrees in their order whatever thread finishes first:
    /// built on one thread and on three, the trees are the same bit for bit.
    #[test]
    fn clustered_tree_is_the_same_on_any_thread_count() {
        let boxes = random_boxes(200_000, 4242);
        let prim = |i: u32| PrimRef::new(&boxes[i as usize], i, false);
        let trees: Vec<_> = [1, 3]
            .map(|threads| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let (wide, order) =
                    pool.install(|| build(boxes.len(), &prim, &mut BuildTimes::start()));
                (wide.bits(), order)
            })
            .into();
        assert!(trees[0] == trees[1], "the trees differ");
    }

    /// Degenerate inputs: every box the same (no centroid extent at all), and boxes a few
    /// ulps apart along a line, whose splits the SAH keeps peeling off one at a time.
    #[test]
    fn clustered_tree_of_degenerate_input_stays_shallow() {
        let b = Aabb {
            min: Vec3A::splat(1.0),
            max: Vec3A::splat(2.0),
        };
        check_tree(&vec![b; 40_000]);
        let line: Vec<Aabb> = (0..40_000)
            .map(|i| {
                let x = 1.0 + i as f32 * f32::EPSILON;
                Aabb {
                    min: Vec3A::new(x, 0.0, 0.0),
                    max: Vec3A::new(x, 1.0, 1.0),
                }
            })
            .collect();
        check_tree(&line);
    }
}
