//! Sixteen rays against every primitive of a small scene, one primitive at a time: its
//! data broadcast, the rays in the lanes. The transpose of the blocks' test
//! ([`Flat::intersect`], one ray against sixteen triangles); the arithmetic of each (ray,
//! primitive) pair is the same, the one lane form of [`Triangle::intersect`]
//! ([`intersect_lanes_edges`]) and of [`Sphere::intersect`] ([`intersect_lanes`]), and so
//! are the rules that choose among hits: the spheres first, each bounded by the nearest so
//! far; then the triangles, bounded by the spheres' nearest; of equally near hits the
//! lowest primitive. So each ray gets the answers [`Flat::intersect`] and
//! [`Flat::occluded`] give it. Pairs near an edge are decided by the primitive's own test
//! (`Triangle::intersect` with its f64 fallback), as there.
//!
//! The rules are written here once, in lanes, for every batch of rays a small scene
//! traces: the wavefront's paths (`integrator::wavefront`, which keeps the answers in its
//! registers) and the stream's and the packets' rays ([`Flat::intersect_rays`]).
//!
//! [`Triangle::intersect`]: crate::geometry::Triangle::intersect
//! [`Sphere::intersect`]: crate::geometry::Sphere::intersect
//! [`intersect_lanes_edges`]: crate::geometry::triangle::intersect_lanes_edges

use super::{Flat, FLAT_MAX_SLOTS, RAYS};
use crate::geometry::sphere::intersect_lanes;
use crate::geometry::triangle::{intersect_lanes_edges, LaneHits};
use crate::geometry::{Ray, Triangle};
use crate::simd::{Float, Sixteen, Vector3, V3};
use glam::Vec3A;
use std::mem::MaybeUninit;

/// A sphere as the lanes test it: its centre, its radius squared (as `Sphere::intersect`
/// computes it) and its primitive index.
#[derive(Clone, Copy, Debug)]
pub struct Ball {
    pub center: Vec3A,
    pub r2: f32,
    pub prim: u32,
}

/// A triangle as the lanes test it, its data together: its first vertex and edges (as
/// [`TriangleBlock::new`] stores them), and its primitive index as an f32 (as [`Hits`]
/// holds it).
///
/// [`TriangleBlock::new`]: crate::geometry::triangle_block::TriangleBlock::new
#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    p0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    prim: f32,
}

impl Tri {
    /// Triangle `tri`, primitive `prim`.
    pub(super) fn new(prim: u32, tri: &Triangle) -> Tri {
        // The edges as `Triangle::intersect` subtracts them.
        let (e1, e2) = (tri.p1 - tri.p0, tri.p2 - tri.p0);
        Tri {
            p0: tri.p0.into(),
            e1: e1.into(),
            e2: e2.into(),
            prim: prim as f32,
        }
    }

    /// The rays in the lanes of `T` against the triangle ([`intersect_lanes_edges`]).
    #[inline(always)]
    fn test<T: Sixteen>(&self, o: V3<T>, d: V3<T>) -> LaneHits<T> {
        intersect_lanes_edges(
            V3::splat(self.p0),
            V3::splat(self.e1),
            V3::splat(self.e2),
            o,
            d,
        )
    }
}

/// The nearest hits of rays in the lanes of `T`: the lanes that hit something, those whose
/// hit is a sphere, and the primitive hit (a whole number in f32: exact, as a flat set holds
/// far fewer than 2²⁴), t, u and v (a sphere's u and v are 0). Where a lane hits nothing,
/// its numbers mean nothing.
pub struct Hits<T: Float> {
    pub hit: T::Mask,
    pub sphere: T::Mask,
    pub prim: T,
    pub t: T,
    pub u: T,
    pub v: T,
}

/// The (lanes, slot) pairs left to the primitives' own test, at most one entry a slot. The
/// list is left uninitialised: a batch rarely has any, and zeroing it for every batch took
/// 0.3 % of a Cornell box's instructions (callgrind).
struct Unsure {
    n: usize,
    list: [MaybeUninit<(u16, u8)>; FLAT_MAX_SLOTS],
}

impl Unsure {
    #[inline(always)]
    fn new() -> Unsure {
        Unsure {
            n: 0,
            list: [const { MaybeUninit::uninit() }; FLAT_MAX_SLOTS],
        }
    }

    /// The lanes `lanes` near an edge of triangle `slot`, if any.
    #[inline(always)]
    fn add(&mut self, lanes: u32, slot: usize) {
        const { assert!(RAYS <= 16, "a pair's lanes are kept in 16 bits") };
        if lanes != 0 {
            self.list[self.n].write((lanes as u16, slot as u8));
            self.n += 1;
        }
    }

    /// The pairs added, as (lanes, slot).
    fn pairs(&self) -> impl Iterator<Item = (u32, usize)> + '_ {
        // SAFETY: `add` wrote the first `n` entries.
        self.list[..self.n].iter().map(|e| {
            let (lanes, slot) = unsafe { e.assume_init() };
            (u32::from(lanes), usize::from(slot))
        })
    }
}

/// The rays of the lanes one by one, for the pairs near an edge.
struct Rays {
    o: [[f32; RAYS]; 3],
    d: [[f32; RAYS]; 3],
}

impl Rays {
    // (No closure: it would be compiled without the caller's target features.)
    #[inline(always)]
    fn of<T: Sixteen>(o: &V3<T>, d: &V3<T>) -> Rays {
        Rays {
            o: [o.x.to_array(), o.y.to_array(), o.z.to_array()],
            d: [d.x.to_array(), d.y.to_array(), d.z.to_array()],
        }
    }

    fn ray(&self, l: usize) -> Ray {
        let v = |a: &[[f32; RAYS]; 3]| Vec3A::new(a[0][l], a[1][l], a[2][l]);
        Ray::new(v(&self.o), v(&self.d))
    }
}

/// The triangles' nearest hits of the lanes as arrays, where the pairs near an edge join
/// them.
struct Nearest {
    hits: u32,
    prim: [f32; RAYS],
    t: [f32; RAYS],
    u: [f32; RAYS],
    v: [f32; RAYS],
}

impl Flat {
    /// The nearest hits of the rays (origins `o`, directions `d`, each up to infinity) in
    /// the lanes `active`, as [`Flat::intersect`] finds each. `hit(ray, prim, t_max)` is
    /// the primitive's own test (t, u, v of a hit in (0, `t_max`)), for the pairs near an
    /// edge. The caller is compiled with the features of `T`.
    #[inline(always)]
    pub fn closest_lanes<T: Sixteen, H>(
        &self,
        o: V3<T>,
        d: V3<T>,
        active: T::Mask,
        hit: H,
    ) -> Hits<T>
    where
        H: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        let (zero, inf) = (T::zero(), T::splat(f32::INFINITY));
        // The spheres first, each against the nearest hit so far (`Flat::nearest_sphere`).
        let (mut st, mut sprim, mut shit) = (inf, zero, T::from_bits(0));
        for b in &self.balls {
            let (h, t) = intersect_lanes(V3::broadcast(b.center), T::splat(b.r2), o, d, st);
            let h = h & active;
            st = T::select(h, t, st);
            sprim = T::select(h, T::splat(b.prim as f32), sprim);
            shit = shit | h;
        }
        // The triangles up to one ulp past the spheres' nearest, so that one as near is
        // seen (`Flat::triangle_bound`).
        let bound = T::select(shit, st.next_up(), inf);
        let (mut bt, mut bu, mut bv, mut bprim) = (bound, zero, zero, zero);
        let mut thit = T::from_bits(0);
        let mut unsure = Unsure::new();
        for (j, tri) in self.tris.iter().enumerate() {
            let r = tri.test(o, d);
            // Strictly nearer only: of equally near hits the first slot (the lowest
            // primitive) stays.
            let h = r.clear & r.t.gt(zero) & r.t.lt(bt) & active;
            bt = T::select(h, r.t, bt);
            bu = T::select(h, r.u, bu);
            bv = T::select(h, r.v, bv);
            bprim = T::select(h, T::splat(tri.prim), bprim);
            thit = thit | h;
            unsure.add(T::bits(r.unsure & active), j);
        }
        if unsure.n != 0 {
            let mut best = Nearest {
                hits: T::bits(thit),
                prim: bprim.to_array(),
                t: bt.to_array(),
                u: bu.to_array(),
                v: bv.to_array(),
            };
            let rays = Rays::of(&o, &d);
            self.settle_lanes(&rays, &unsure, &bound.to_array(), &mut best, hit);
            thit = T::from_bits(best.hits);
            (bprim, bt, bu, bv) = (
                T::load(&best.prim),
                T::load(&best.t),
                T::load(&best.u),
                T::load(&best.v),
            );
        }
        // A triangle's hit wins if nearer than the spheres', or as near and of a lower
        // primitive (`Flat::result`).
        let tri = thit & (!shit | bt.lt(st) | (bt.eq(st) & bprim.lt(sprim)));
        let sphere = shit & !tri;
        Hits {
            hit: tri | sphere,
            sphere,
            prim: T::select(tri, bprim, sprim),
            t: T::select(tri, bt, st),
            u: T::select(tri, bu, zero),
            v: T::select(tri, bv, zero),
        }
    }

    /// The lanes of `active` whose rays are blocked before their `t_max`, as
    /// [`Flat::occluded`] finds each; `hit` as for [`Flat::closest_lanes`].
    #[inline(always)]
    pub fn occluded_lanes<T: Sixteen, H>(
        &self,
        o: V3<T>,
        d: V3<T>,
        t_max: T,
        active: T::Mask,
        hit: H,
    ) -> T::Mask
    where
        H: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        let mut blocked = T::from_bits(0);
        for b in &self.balls {
            let (h, _) = intersect_lanes(V3::broadcast(b.center), T::splat(b.r2), o, d, t_max);
            blocked = blocked | (h & active);
        }
        let mut unsure = Unsure::new();
        let zero = T::zero();
        for (j, tri) in self.tris.iter().enumerate() {
            let r = tri.test(o, d);
            blocked = blocked | (r.clear & r.t.gt(zero) & r.t.lt(t_max) & active);
            unsure.add(T::bits(r.unsure & active), j);
        }
        if unsure.n == 0 {
            return blocked;
        }
        let rays = Rays::of(&o, &d);
        let more =
            self.settle_blocked_lanes(&rays, &unsure, &t_max.to_array(), T::bits(blocked), hit);
        blocked | T::from_bits(more)
    }

    /// The pairs near an edge, decided by `hit` before each lane's `bound` and kept where
    /// nearer than the lane's `best` (or as near and of a lower primitive).
    #[cold]
    #[inline(never)]
    fn settle_lanes<H>(
        &self,
        rays: &Rays,
        unsure: &Unsure,
        bound: &[f32; RAYS],
        best: &mut Nearest,
        mut hit: H,
    ) where
        H: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        for (lanes, j) in unsure.pairs() {
            let p = self.prims[j];
            for l in crate::simd::lanes_of(lanes) {
                let Some((t, u, v)) = hit(&rays.ray(l), p as usize, bound[l]) else {
                    continue;
                };
                if t < best.t[l] || (t == best.t[l] && (p as f32) < best.prim[l]) {
                    (best.t[l], best.u[l], best.v[l], best.prim[l]) = (t, u, v, p as f32);
                    best.hits |= 1 << l;
                }
            }
        }
    }

    /// The lanes, not yet `blocked`, that a pair near an edge blocks before their `t_max`
    /// by `hit`'s test, as bits.
    #[cold]
    #[inline(never)]
    fn settle_blocked_lanes<H>(
        &self,
        rays: &Rays,
        unsure: &Unsure,
        t_max: &[f32; RAYS],
        mut blocked: u32,
        mut hit: H,
    ) -> u32
    where
        H: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        let mut more = 0;
        for (lanes, j) in unsure.pairs() {
            let p = self.prims[j] as usize;
            for l in crate::simd::lanes_of(lanes & !blocked) {
                if hit(&rays.ray(l), p, t_max[l]).is_some() {
                    more |= 1 << l;
                    blocked |= 1 << l;
                }
            }
        }
        more
    }
}
