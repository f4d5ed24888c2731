//! The subtree of a small node by exact SAH sweeps (Wald, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies", RT 2007, §3: the full sweep over presorted lists). The
//! references are sorted along each axis once; children take their parent's sorted lists
//! filtered (stable), so no level sorts again.

use super::{
    finish, half_area, inner, prims_of, slots_of, split_pays, BvhNode, Kind, PrimRef, Sub, Weight,
    PRIM,
};
use crate::geometry::Aabb;
use glam::Vec3A;
use std::mem::MaybeUninit;

/// Nodes of at most this many references find the exact SAH split instead of binning, whose
/// fixed cost dominates at this size.
pub const SWEEP_MAX: usize = 12;

/// The references of a small node, copied out once: their bounds and weights.
struct Small<'a> {
    lo: [Vec3A; SWEEP_MAX],
    hi: [Vec3A; SWEEP_MAX],
    weight: [Weight; SWEEP_MAX],
    refs: &'a [PrimRef],
}

/// Lists of a node's references (positions in `Small`) sorted by centroid along each axis.
type Sorted = [[u8; SWEEP_MAX]; 3];

/// Writes the subtree over `refs` (at most [`SWEEP_MAX`]) as `build_node` does.
pub fn sweep_node<K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    refs: &[PrimRef],
    first: usize,
    depth: usize,
    bounds: &Aabb,
) -> Sub {
    let n = refs.len();
    let mut s = Small {
        lo: [Vec3A::ZERO; SWEEP_MAX],
        hi: [Vec3A::ZERO; SWEEP_MAX],
        weight: [PRIM; SWEEP_MAX],
        refs,
    };
    for (i, r) in refs.iter().enumerate() {
        s.lo[i] = r.lo();
        s.hi[i] = r.hi();
        if !K::UNIT {
            s.weight[i] = K::weight(r);
        }
    }
    let mut ord: Sorted = [[0u8; SWEEP_MAX]; 3];
    // (Two references need only one list: both splits of either order are the same.)
    let axes = if n == 2 { 1 } else { 3 };
    for (axis, o) in ord.iter_mut().enumerate().take(axes) {
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
    let at = Place {
        first,
        depth,
        lo: bounds.min,
        hi: bounds.max,
    };
    small_node(kind, nodes, order, &s, &ord, n, at)
}

/// Where a node of the small subtree goes: its first primitive's position in the final
/// order, its depth and its bounds.
#[derive(Clone, Copy)]
struct Place {
    first: usize,
    depth: usize,
    lo: Vec3A,
    hi: Vec3A,
}

/// One node of [`sweep_node`]'s subtree: `ord[axis][..n]` are its references sorted along
/// each axis.
fn small_node<K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    s: &Small,
    ord: &Sorted,
    n: usize,
    at: Place,
) -> Sub {
    let leaf = |nodes: &mut [MaybeUninit<BvhNode>], order: &mut [u32]| {
        let bounds = Aabb {
            min: at.lo,
            max: at.hi,
        };
        let list = &ord[0][..n];
        if n == 1 {
            let r = std::slice::from_ref(&s.refs[list[0] as usize]);
            return kind.leaf(nodes, order, r, at.first, at.depth, &bounds);
        }
        let mut refs = [s.refs[0]; SWEEP_MAX];
        for (r, &i) in refs.iter_mut().zip(list) {
            *r = s.refs[i as usize];
        }
        kind.leaf(nodes, order, &refs[..n], at.first, at.depth, &bounds)
    };
    if n == 1 {
        return leaf(nodes, order);
    }
    let w = order.len();
    if n == 2 {
        // Every sweep finds the one split: one reference on each side.
        let (a, b) = (ord[0][0] as usize, ord[0][1] as usize);
        let wa = if K::UNIT { 1 } else { prims_of(s.weight[a]) };
        let cost =
            wa as f32 * half_area(s.lo[a], s.hi[a]) + (w - wa) as f32 * half_area(s.lo[b], s.hi[b]);
        let area = half_area(at.lo, at.hi).max(f32::MIN_POSITIVE);
        if n <= K::MAX_LEAF && !split_pays::<K>(n, w, area, cost) {
            return leaf(nodes, order);
        }
        let bounds = Aabb {
            min: at.lo,
            max: at.hi,
        };
        let sa = slots_of(s.weight[a]);
        let (head, rest) = nodes.split_first_mut().unwrap();
        head.write(inner(&bounds, 1 + sa, w));
        let (ln, rn) = rest.split_at_mut(sa);
        let (lo, ro) = order.split_at_mut(wa);
        let one = |i: usize, first: usize| Place {
            first,
            depth: at.depth + 1,
            lo: s.lo[i],
            hi: s.hi[i],
        };
        let a = small_node(
            kind,
            ln,
            lo,
            s,
            &[[a as u8; SWEEP_MAX]; 3],
            1,
            one(a, at.first),
        );
        let b = small_node(
            kind,
            rn,
            ro,
            s,
            &[[b as u8; SWEEP_MAX]; 3],
            1,
            one(b, at.first + wa),
        );
        return finish(head, a.join(b));
    }
    // The cheapest split along each axis, (left count, left weight, cost), the three axes'
    // sweeps interleaved (each is a chain of dependent minimums and maximums). (For
    // primitives the weight is summed as for clusters, as it lays out the nodes, but the
    // SAH counts k.)
    let mut right_area = [[0f32; 3]; SWEEP_MAX];
    let at_k = |k: usize| [0, 1, 2].map(|a| ord[a][k] as usize);
    let last = at_k(n - 1);
    let (mut alo, mut ahi) = (last.map(|i| s.lo[i]), last.map(|i| s.hi[i]));
    for a in 0..3 {
        right_area[n - 1][a] = half_area(alo[a], ahi[a]);
    }
    for k in (1..n - 1).rev() {
        let i = at_k(k);
        for a in 0..3 {
            alo[a] = alo[a].min(s.lo[i[a]]);
            ahi[a] = ahi[a].max(s.hi[i[a]]);
            right_area[k][a] = half_area(alo[a], ahi[a]);
        }
    }
    let head = at_k(0);
    let (mut alo, mut ahi) = (head.map(|i| s.lo[i]), head.map(|i| s.hi[i]));
    let mut wl = head.map(|i| s.weight[i]);
    let mut best_on = [(n / 2, 0, f32::INFINITY); 3];
    for (k, ra) in right_area.iter().enumerate().take(n).skip(1) {
        let i = at_k(k - 1);
        for a in 0..3 {
            if k > 1 {
                alo[a] = alo[a].min(s.lo[i[a]]);
                ahi[a] = ahi[a].max(s.hi[i[a]]);
                wl[a] += s.weight[i[a]];
            }
            let pl = if K::UNIT { k } else { prims_of(wl[a]) };
            let cost = pl as f32 * half_area(alo[a], ahi[a]) + (w - pl) as f32 * ra[a];
            if cost < best_on[a].2 {
                best_on[a] = (k, wl[a], cost);
            }
        }
    }
    // The cheapest of the three (the first axis on a tie).
    let mut best = (0, n / 2, 0, f32::INFINITY);
    for (a, &(k, wl, cost)) in best_on.iter().enumerate() {
        if cost < best.3 {
            best = (a, k, wl, cost);
        }
    }
    let (axis, mid, wl, cost) = best;
    let area = half_area(at.lo, at.hi).max(f32::MIN_POSITIVE);
    if n <= K::MAX_LEAF && !split_pays::<K>(n, w, area, cost) {
        return leaf(nodes, order);
    }
    if cost.is_nan() || cost == f32::INFINITY {
        // (A cost that is not finite, from non-finite bounds, splits in the middle; the
        // sweep recorded no weight for it.)
        return split_middle(kind, nodes, order, s, ord, n, at, axis);
    }
    children(kind, nodes, order, s, ord, n, at, axis, mid, wl)
}

/// Splits the node in the middle of its list along `axis`.
#[allow(clippy::too_many_arguments)]
fn split_middle<K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    s: &Small,
    ord: &Sorted,
    n: usize,
    at: Place,
    axis: usize,
) -> Sub {
    let mid = n / 2;
    let wl = ord[axis][..mid].iter().map(|&i| s.weight[i as usize]).sum();
    children(kind, nodes, order, s, ord, n, at, axis, mid, wl)
}

/// Writes the inner node split after the first `mid` references of its list along `axis`
/// (of weight `wl`), and builds both children.
#[allow(clippy::too_many_arguments)]
fn children<K: Kind>(
    kind: &K,
    nodes: &mut [MaybeUninit<BvhNode>],
    order: &mut [u32],
    s: &Small,
    ord: &Sorted,
    n: usize,
    at: Place,
    axis: usize,
    mid: usize,
    wl: Weight,
) -> Sub {
    // Children's sorted lists: each axis's list filtered by side, order kept. Branch-free
    // (each index is written to both lists, and one of the two ends advances): the side is
    // unpredictable, and the branch cost a misprediction every other reference.
    let mut left = [false; SWEEP_MAX];
    for &i in &ord[axis][..mid] {
        left[i as usize] = true;
    }
    let mut lord: Sorted = [[0u8; SWEEP_MAX]; 3];
    let mut rord: Sorted = [[0u8; SWEEP_MAX]; 3];
    for a in 0..3 {
        let (mut l, mut r) = (0, 0);
        for &i in &ord[a][..n] {
            let goes_left = left[i as usize] as usize;
            // (l ≤ mid and r ≤ n − mid, and both are below n ≤ SWEEP_MAX until the last
            // reference has been written.)
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
    let bounds = Aabb {
        min: at.lo,
        max: at.hi,
    };
    let (sl, wl) = (slots_of(wl), prims_of(wl));
    let (head, rest) = nodes.split_first_mut().unwrap();
    head.write(inner(&bounds, 1 + sl, order.len()));
    let (ln, rn) = rest.split_at_mut(sl);
    let (lo, ro) = order.split_at_mut(wl);
    let depth = at.depth + 1;
    let left_at = Place {
        first: at.first,
        depth,
        lo: llo,
        hi: lhi,
    };
    let right_at = Place {
        first: at.first + wl,
        depth,
        lo: rlo,
        hi: rhi,
    };
    let a = small_node(kind, ln, lo, s, &lord, mid, left_at);
    let b = small_node(kind, rn, ro, s, &rord, n - mid, right_at);
    finish(head, a.join(b))
}
