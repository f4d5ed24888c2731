//! Closest hits of a batch of independent rays ([`Scene::intersect_many`]), their BVH
//! traversals interleaved so that their cache misses overlap
//! ([`crate::accel::WideBvh::intersect_stream`]).
//!
//! Every answer is the same bits as [`Scene::intersect`]'s: each ray's traversal repeats the
//! same step function with the same primitive test (`Scene::keep_nearer`, the tie rule
//! included), and its hit becomes an [`Interaction`] by the same code. Scenes small enough for
//! brute force ([`crate::accel::flat`]) have no miss to hide (their few primitives sit in the
//! L1 cache): a batch's rays go sixteen at a time in the lanes, each triangle against all of
//! them (`Flat::intersect_rays`), with the single ray's answers. With instances, the
//! scene's own primitives are traversed together and the instances (the top-level tree and
//! the groups' trees) one ray at a time.

use super::{Interaction, Scene, NO_HIT};
use crate::accel::prefetch;
use crate::geometry::Ray;

/// Rays in flight in [`Scene::intersect_many`] (see docs/performance.md for the
/// measurement that chose it).
pub const STREAM: usize = 8;

/// Bytes of the CPU's level-2 cache (of the first CPU, as Linux reports it), 1 MiB where it
/// is not known.
fn l2_bytes() -> usize {
    static L2: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *L2.get_or_init(|| {
        let dir = std::path::Path::new("/sys/devices/system/cpu/cpu0/cache");
        let read = |i: usize, f: &str| std::fs::read_to_string(dir.join(format!("index{i}/{f}")));
        (0..8)
            .filter(|&i| read(i, "level").is_ok_and(|l| l.trim() == "2"))
            .find_map(|i| {
                let size = read(i, "size").ok()?;
                let kib: usize = size.trim().strip_suffix('K')?.parse().ok()?;
                Some(kib << 10)
            })
            .unwrap_or(1 << 20)
    })
}

impl Scene {
    /// Whether [`Scene::intersect_many`] interleaves its rays: where what a traversal reads
    /// (the tree's nodes, the primitives' vertex indices and positions) exceeds the level-2
    /// cache, so that node loads miss it. Where it fits, there is no miss to hide, and the
    /// interleaving's cost (about a quarter more instructions, and branches that the
    /// predictor sees mixed from several rays) made it slower: see docs/performance.md.
    pub fn streams(&self) -> bool {
        use std::mem::size_of_val;
        let bytes = self.bvh.memory_bytes()
            + size_of_val(&self.tris[..])
            + size_of_val(&self.positions[..]);
        bytes > l2_bytes()
    }

    /// [`Scene::intersect_many`] with `K` rays in flight (`K` ≤ 1: one by one), for the
    /// tests and benchmarks, which compare the choices.
    #[doc(hidden)]
    #[inline(always)]
    pub fn intersect_many_k<const K: usize>(&self, rays: &[Ray], out: &mut [Option<Interaction>]) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        if K > 1 && self.intersect_many_flat(rays, out) {
            return;
        }
        if K <= 1 || self.is_flat() {
            for (ray, o) in rays.iter().zip(out.iter_mut()) {
                self.interaction_into(ray, self.closest(ray, f32::INFINITY), o);
            }
            return;
        }
        let done = |k: usize, found: bool, best: &(usize, f32, f32, f32)| {
            let ray = &rays[k];
            let hit = found.then_some(*best);
            self.interaction_into(ray, hit, &mut out[k]);
        };
        if self.masked {
            self.closest_stream::<K>(rays, |ray, i, u, v, t| self.seen(ray, i, u, v, t), done);
        } else {
            self.closest_stream::<K>(rays, |_, _, _, _, _| true, done);
        }
    }

    /// `Scene::closest_kept` of each ray up to infinity, `K` in flight; `done(k, found,
    /// best)` gets each ray's answer as its traversal ends.
    #[inline(always)]
    fn closest_stream<const K: usize>(
        &self,
        rays: &[Ray],
        keep: impl Fn(&Ray, usize, f32, f32, f32) -> bool,
        done: impl FnMut(usize, bool, &(usize, f32, f32, f32)),
    ) {
        self.bvh.intersect_stream::<K, _>(
            rays,
            f32::INFINITY,
            NO_HIT,
            #[inline(always)]
            |k, best, i, t_max| {
                let ray = &rays[k];
                self.keep_nearer(ray, best, i, t_max, &|i, u, v, t| keep(ray, i, u, v, t))
            },
            #[inline(always)]
            |first, count| self.prefetch_prims(first, count),
            done,
        );
    }

    /// Occlusion of several rays: `out[k]` is [`Scene::occluded`]`(&rays[k], t_max[k])`,
    /// their traversals interleaved as [`Scene::intersect_many`]'s are. Panics if the slices'
    /// lengths differ.
    pub fn occluded_many(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        #[cfg(target_arch = "x86_64")]
        if crate::integrator::has_x86_64_v3() {
            // SAFETY: the CPU has the features, checked just above.
            return unsafe { self.occluded_many_v3(rays, t_max, out) };
        }
        self.occluded_many_portable(rays, t_max, out);
    }

    /// [`Scene::occluded_many`] compiled for x86-64-v3, as `intersect_many_v3` is (its
    /// callers' features do not pass to it).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn occluded_many_v3(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        self.occluded_many_portable(rays, t_max, out);
    }

    #[inline(always)]
    fn occluded_many_portable(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        if self.occluded_many_flat(rays, t_max, out) {
            return;
        }
        if self.streams() {
            self.occluded_many_k::<STREAM>(rays, t_max, out);
        } else {
            self.occluded_many_k::<1>(rays, t_max, out);
        }
    }

    /// [`Scene::occluded_many`] with `K` rays in flight (`K` ≤ 1: one by one), for the tests
    /// and benchmarks.
    #[doc(hidden)]
    #[inline(always)]
    pub fn occluded_many_k<const K: usize>(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) {
        assert!(
            rays.len() == t_max.len() && rays.len() == out.len(),
            "one distance and one output per ray"
        );
        if K > 1 && self.occluded_many_flat(rays, t_max, out) {
            return;
        }
        if K <= 1 || self.is_flat() {
            for ((ray, &t), o) in rays.iter().zip(t_max).zip(out.iter_mut()) {
                *o = self.occluded(ray, t);
            }
            return;
        }
        let done = |k: usize, blocked: bool| {
            out[k] = blocked
                || (self.instances.as_ref()).is_some_and(|inst| inst.occluded(&rays[k], t_max[k]));
        };
        let leaf = |first, count| self.prefetch_prims(first, count);
        if self.masked {
            self.bvh.occluded_stream::<K>(
                rays,
                t_max,
                |k, i, t| self.blocks_seen(&rays[k], i, t),
                leaf,
                done,
            );
        } else {
            self.bvh.occluded_stream::<K>(
                rays,
                t_max,
                #[inline(always)]
                |k, i, t| self.hit(&rays[k], i, t).is_some(),
                leaf,
                done,
            );
        }
    }

    /// Where single rays go by brute force ([`crate::accel::flat`]), the closest hits of
    /// `rays` sixteen at a time, the rays in the lanes ([`Flat::intersect_rays`]; the last
    /// few one by one), each [`Scene::intersect`]'s, and true; false, with nothing written,
    /// elsewhere. (A batch affords what a single ray cannot: on the Cornell box the lanes'
    /// brute force was 1.7× the single rays' in the wavefront.)
    ///
    /// [`Flat::intersect_rays`]: crate::accel::flat::Flat::intersect_rays
    #[inline(always)]
    pub(super) fn intersect_many_flat(
        &self,
        rays: &[Ray],
        out: &mut [Option<Interaction>],
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let (Some(f), false) = (&self.flat, self.masked) {
            use crate::accel::flat::RAYS;
            assert_eq!(rays.len(), out.len(), "one output per ray");
            let mut rs = rays.chunks_exact(RAYS);
            let mut os = out.chunks_exact_mut(RAYS);
            for (r, o) in (&mut rs).zip(&mut os) {
                let r: &[Ray; RAYS] = r.try_into().expect("a chunk of RAYS");
                let hits = f.intersect_rays(r, |ray, i, t| self.hit(ray, i, t));
                for (k, (ray, o)) in r.iter().zip(o.iter_mut()).enumerate() {
                    self.interaction_into(ray, hits[k].map(|(i, t, u, v)| (i, u, v, t)), o);
                }
            }
            for (ray, o) in rs.remainder().iter().zip(os.into_remainder()) {
                self.interaction_into(ray, self.closest(ray, f32::INFINITY), o);
            }
            return true;
        }
        let _ = (rays, out);
        false
    }

    /// [`Scene::intersect_many_flat`] for occlusion: [`Scene::occluded`] of each ray.
    #[inline(always)]
    fn occluded_many_flat(&self, rays: &[Ray], t_max: &[f32], out: &mut [bool]) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let (Some(f), false) = (&self.flat, self.masked) {
            use crate::accel::flat::RAYS;
            assert!(
                rays.len() == t_max.len() && rays.len() == out.len(),
                "one distance and one output per ray"
            );
            let mut rs = rays.chunks_exact(RAYS);
            let mut ts = t_max.chunks_exact(RAYS);
            let mut os = out.chunks_exact_mut(RAYS);
            for ((r, t), o) in (&mut rs).zip(&mut ts).zip(&mut os) {
                let r: &[Ray; RAYS] = r.try_into().expect("a chunk of RAYS");
                let t: &[f32; RAYS] = t.try_into().expect("a chunk of RAYS");
                let blocked = f.occluded_rays(r, t, |ray, i, t| self.hit(ray, i, t));
                for (k, o) in o.iter_mut().enumerate() {
                    *o = blocked >> k & 1 != 0
                        || (self.instances.as_ref()).is_some_and(|inst| inst.occluded(&r[k], t[k]));
                }
            }
            let rest = rs.remainder().iter().zip(ts.remainder());
            for ((ray, &t), o) in rest.zip(os.into_remainder()) {
                *o = self.occluded(ray, t);
            }
            return true;
        }
        let _ = (rays, t_max, out);
        false
    }

    /// Prefetches the vertex indices of primitives `first..first + count` (BVH order), what
    /// a leaf's tests read first.
    #[inline(always)]
    fn prefetch_prims(&self, first: usize, count: usize) {
        let prims = &self.tris[first..first + count];
        let p = prims.as_ptr() as *const u8;
        let len = std::mem::size_of_val(prims);
        let mut off = 0;
        while off < len {
            // SAFETY: `off` < `len`: inside the slice.
            prefetch(unsafe { &*p.add(off) });
            off += 64;
        }
        // SAFETY: a leaf holds at least one primitive, so `len` > 0.
        prefetch(unsafe { &*p.add(len - 1) });
    }
}
