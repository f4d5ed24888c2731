//! The split of a large node: its references' centroids binned along each axis and the
//! bins swept for the cheapest split by the SAH (Wald, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies", RT 2007), and the in-place partition by that split.

use super::{
    bounds_of, bounds_weight_of, half_area, prims_of, PrimRef, Weight, BINS, SAMPLES, SAMPLE_MIN,
};
use crate::geometry::Aabb;
use glam::Vec3A;

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

/// A split found by binning: the references whose doubled centroid `c` has
/// `(c - cmin) * scale < limit` along `axis` go left (see [`partition`]).
#[derive(Clone, Copy, Debug)]
pub struct Split {
    pub axis: usize,
    pub limit: f32,
    pub cmin: Vec3A,
    pub scale: Vec3A,
    /// The children's SAH sum (weight times half area), scaled from the sample to the node.
    pub cost: f32,
}

/// The cheapest split of `refs` by the binned SAH (Wald 2007): their doubled centroids binned
/// along all three axes in one pass (over a fixed sample of a large node; fewer bins for
/// fewer references), each bin's bounds and weight swept from both ends. `weight` is what a
/// reference stands for; its primitives (1 for a primitive, its primitive count for a
/// cluster) count in the SAH. `cbounds` bounds the doubled centroids. `None` where no bin
/// boundary has references on both sides (every centroid in one bin along every axis).
#[inline]
pub fn binned_split(
    refs: &[PrimRef],
    cbounds: &Aabb,
    weight: impl Fn(&PrimRef) -> Weight,
) -> Option<Split> {
    if refs.len() <= 64 {
        binned_split_with::<8>(refs, cbounds, weight)
    } else {
        binned_split_with::<BINS>(refs, cbounds, weight)
    }
}

/// [`binned_split`] with `NB` bins.
#[inline]
fn binned_split_with<const NB: usize>(
    refs: &[PrimRef],
    cbounds: &Aabb,
    weight: impl Fn(&PrimRef) -> Weight,
) -> Option<Split> {
    let n = refs.len();
    let cext = cbounds.extent();
    let nb = NB;
    let scale = Vec3A::select(
        cext.cmpgt(Vec3A::ZERO),
        Vec3A::splat(nb as f32 * (1.0 - 1e-6)) / cext,
        Vec3A::ZERO,
    );
    let cmin = cbounds.min;
    let last = (nb - 1) as f32;
    let stride = if n > SAMPLE_MIN { n / SAMPLES } else { 1 };
    // Two sets of bins, for even and odd references: neighbours often share a bin, and one
    // set would make each update wait for the previous one's store.
    let mut count = [[[0u32; NB]; 3]; 2];
    let mut bins = [[[Aabb::EMPTY; NB]; 3]; 2];
    let mut sampled = 0u64;
    for (k, r) in refs.iter().step_by(stride).enumerate() {
        let set = k & 1;
        let (lo, hi) = (r.lo(), r.hi());
        let b = bin3((lo + hi - cmin) * scale, last);
        let w = prims_of(weight(r)) as u32;
        for axis in 0..3 {
            count[set][axis][b[axis]] += w;
            let bb = &mut bins[set][axis][b[axis]];
            bb.min = bb.min.min(lo);
            bb.max = bb.max.max(hi);
        }
        sampled += w as u64;
    }
    let total: u64 = if stride > 1 {
        refs.iter().map(|r| prims_of(weight(r)) as u64).sum()
    } else {
        sampled
    };
    // Sweep each axis for the cheapest split (right-hand areas first, then from the left).
    let mut best: Option<(usize, usize, f32)> = None; // (axis, bin, cost)
    for axis in 0..3 {
        if cext[axis] <= 0.0 {
            continue;
        }
        let [(c0, b0), (c1, b1)] = [0, 1].map(|s| (&count[s][axis], &bins[s][axis]));
        let mut right_area = [0.0f32; NB];
        let mut right_count = [0u32; NB];
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
    let (axis, bin, cost) = best?;
    let share = if stride > 1 {
        sampled as f32 / total as f32
    } else {
        1.0
    };
    Some(Split {
        axis,
        limit: (bin + 1) as f32,
        cmin,
        scale,
        cost: cost / share,
    })
}

/// In-place partition of `refs`: to the left those whose doubled centroid `c` has
/// `(c - cmin) * scale < limit` along `axis` (that is, those in bins below `limit`; a NaN
/// goes right, as `bin3` clamps it to the last bin); returns the split index and the bounds
/// and centroid bounds of both sides. Neither side is empty when the split came from bins
/// holding primitives on both sides. Also returns the left side's total `weight`.
///
/// Branch-free (Lomuto's scheme with the swap made unconditional, as in Edelkamp and Weiß,
/// "BlockQuicksort", ESA 2016, and pdqsort): which side a primitive goes to is a coin flip
/// the branch predictor loses half the time, and Hoare's scheme paid a misprediction for
/// every other primitive of every level of the tree.
pub fn partition(
    refs: &mut [PrimRef],
    cmin: Vec3A,
    scale: Vec3A,
    axis: usize,
    limit: f32,
    weight: impl Fn(&PrimRef) -> Weight,
) -> (usize, Weight, (Aabb, Aabb), (Aabb, Aabb)) {
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
    // side's or the other's by selects inside the loop cost more than this pass. The left
    // side's weight in the same pass.
    let (l, r) = refs.split_at(j);
    let (lb, lc, wl) = bounds_weight_of(l, weight);
    (j, wl, (lb, lc), bounds_of(r))
}
