//! A photon map: photons in a balanced kd-tree stored in place (Jensen 2001, §6.3): the
//! photons of a range are split at their median along the axis of largest extent, the median
//! photon is the node (its split axis lives in two bits of its flags) and the two halves of
//! the range are its subtrees. No pointers, no extra memory beyond the photons themselves.

use super::photon::Photon;
use glam::Vec3A;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    photons: Vec<Photon>,
}

/// A photon found by a query and its squared distance.
#[derive(Clone, Copy, Debug)]
pub struct Found {
    pub d2: f32,
    pub index: u32,
}

impl PartialEq for Found {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Found {}
impl PartialOrd for Found {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Found {
    // Ties broken by index, so that the k nearest are the same on every run.
    fn cmp(&self, o: &Self) -> Ordering {
        self.d2.total_cmp(&o.d2).then(self.index.cmp(&o.index))
    }
}

/// Below this many photons a range is split without recursion into threads.
const PAR_CUTOFF: usize = 1 << 15;

impl PhotonMap {
    /// Builds the tree (O(n log n), in parallel over subtrees). The result depends only on
    /// the photons and their order.
    pub fn build(mut photons: Vec<Photon>) -> PhotonMap {
        build_rec(&mut photons);
        PhotonMap { photons }
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }
    /// The photons, in tree order.
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }
    pub fn memory_bytes(&self) -> usize {
        self.photons.capacity() * std::mem::size_of::<Photon>()
    }

    /// The `k` nearest photons to `q` within distance² `r2_max` that pass `keep`, nearest
    /// first, in `out` (cleared); `heap` is scratch space.
    pub fn k_nearest(
        &self,
        q: Vec3A,
        k: usize,
        r2_max: f32,
        keep: &dyn Fn(&Photon) -> bool,
        heap: &mut BinaryHeap<Found>,
        out: &mut Vec<Found>,
    ) {
        heap.clear();
        out.clear();
        if k == 0 || self.photons.is_empty() {
            return;
        }
        let mut r2 = r2_max;
        self.knn_rec(0, self.photons.len(), q, k, &mut r2, keep, heap);
        out.extend(heap.drain());
        out.sort_unstable();
    }

    #[allow(clippy::too_many_arguments)]
    fn knn_rec(
        &self,
        lo: usize,
        hi: usize,
        q: Vec3A,
        k: usize,
        r2: &mut f32,
        keep: &dyn Fn(&Photon) -> bool,
        heap: &mut BinaryHeap<Found>,
    ) {
        if lo >= hi {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let ph = &self.photons[mid];
        let axis = ph.axis();
        // (Through an array: Vec3A's index by a variable is a match, a branch a node.)
        let d = q.to_array()[axis] - ph.p[axis];
        let (near, far) = if d < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.knn_rec(near.0, near.1, q, k, r2, keep, heap);
        let d2 = (ph.pos() - q).length_squared();
        if d2 < *r2 && keep(ph) {
            heap.push(Found {
                d2,
                index: mid as u32,
            });
            if heap.len() > k {
                heap.pop();
            }
            if heap.len() == k {
                *r2 = heap.peek().unwrap().d2;
            }
        }
        if d * d < *r2 {
            self.knn_rec(far.0, far.1, q, k, r2, keep, heap);
        }
    }

    /// Calls `f` for every photon within distance² `r2` of `q`.
    pub fn for_each_within(&self, q: Vec3A, r2: f32, f: &mut dyn FnMut(&Photon, f32)) {
        let mut stack = [(0usize, 0usize); 64];
        let mut sp = 0;
        if self.photons.is_empty() {
            return;
        }
        stack[0] = (0, self.photons.len());
        sp += 1;
        while sp > 0 {
            sp -= 1;
            let (lo, hi) = stack[sp];
            if lo >= hi {
                continue;
            }
            let mid = lo + (hi - lo) / 2;
            let ph = &self.photons[mid];
            let axis = ph.axis();
            let d = q.to_array()[axis] - ph.p[axis];
            let d2 = (ph.pos() - q).length_squared();
            if d2 < r2 {
                f(ph, d2);
            }
            if d <= 0.0 || d * d < r2 {
                stack[sp] = (lo, mid);
                sp += 1;
            }
            if d >= 0.0 || d * d < r2 {
                stack[sp] = (mid + 1, hi);
                sp += 1;
            }
        }
    }
}

fn build_rec(ph: &mut [Photon]) {
    if ph.is_empty() {
        return;
    }
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for p in ph.iter() {
        lo = lo.min(p.pos());
        hi = hi.max(p.pos());
    }
    let e = hi - lo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = ph.len() / 2;
    ph.select_nth_unstable_by(mid, |a, b| a.p[axis].total_cmp(&b.p[axis]));
    ph[mid].set_axis(axis);
    let (left, rest) = ph.split_at_mut(mid);
    let right = &mut rest[1..];
    if left.len() + right.len() > PAR_CUTOFF {
        rayon::join(|| build_rec(left), || build_rec(right));
    } else {
        build_rec(left);
        build_rec(right);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Pcg32;
    use crate::Color;

    #[test]
    fn knn_matches_brute_force() {
        let mut rng = Pcg32::new(1, 2);
        let photons: Vec<Photon> = (0..5000)
            .map(|_| {
                let p = Vec3A::new(rng.next_1d(), rng.next_1d(), rng.next_1d() * 0.1);
                Photon::new(p, Color::ONE, Vec3A::Z, 1 + rng.next_u32() % 3, false)
            })
            .collect();
        let map = PhotonMap::build(photons.clone());
        let (mut heap, mut out) = (BinaryHeap::new(), Vec::new());
        for _ in 0..50 {
            let q = Vec3A::new(rng.next_1d(), rng.next_1d(), 0.05);
            let keep = |p: &Photon| p.depth() < 3;
            map.k_nearest(q, 20, 0.04, &keep, &mut heap, &mut out);
            let mut brute: Vec<f32> = photons
                .iter()
                .filter(|p| keep(p))
                .map(|p| (p.pos() - q).length_squared())
                .filter(|&d| d < 0.04)
                .collect();
            brute.sort_by(f32::total_cmp);
            brute.truncate(20);
            let got: Vec<f32> = out.iter().map(|f| f.d2).collect();
            assert_eq!(got, brute);
            let mut n = 0;
            map.for_each_within(q, 0.01, &mut |_, _| n += 1);
            let b = photons
                .iter()
                .filter(|p| (p.pos() - q).length_squared() < 0.01)
                .count();
            assert_eq!(n, b);
        }
    }
}
