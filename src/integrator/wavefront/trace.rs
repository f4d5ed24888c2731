//! Sixteen rays against every primitive of a small scene, one primitive at a time: its
//! data broadcast, the rays in the lanes. The transpose of [`crate::accel::flat`], which
//! tests one ray against sixteen triangles; the arithmetic of each (ray, primitive) pair is
//! the same, the one lane form of [`Triangle::intersect`] ([`intersect_lanes_edges`]) and
//! of [`Sphere::intersect`] ([`intersect_lanes`]), and so are the rules that
//! choose among hits (the spheres first, each bounded by the nearest so far; then the
//! triangles, bounded by the spheres' nearest; of equally near hits the lowest primitive).
//! So each ray gets the hit `Scene::intersect` gives it and the answer `Scene::occluded`
//! gives it, in the scenes it traces by brute force (those `Wavefront::new` takes).
//! Triangle pairs near an edge are decided by the scene's own test (`Triangle::intersect`
//! with its f64 fallback), as there.
//!
//! [`Triangle::intersect`]: crate::geometry::Triangle::intersect
//! [`Sphere::intersect`]: crate::geometry::Sphere::intersect

use crate::simd::Float;
use super::simd::{F, M, U, V3};
use super::{Ball, LaneMask, Tri};
use crate::geometry::sphere::intersect_lanes;
use crate::geometry::triangle::{intersect_lanes_edges, LaneHits};
use crate::geometry::Ray;
use crate::scene::Scene;

/// The rays' nearest hits: the lanes hit, those whose hit is a sphere, the primitive hit,
/// and t, u and v (a sphere's u and v are 0).
pub struct Hits {
    pub hit: M,
    pub sphere: M,
    pub prim: U,
    pub t: F,
    pub u: F,
    pub v: F,
}

/// The (lanes, slot) pairs left to the scene's own test, at most one entry per slot.
struct Unsure {
    n: usize,
    list: [(u16, u16); 64],
}

impl Unsure {
    fn new() -> Unsure {
        Unsure {
            n: 0,
            list: [(0, 0); 64],
        }
    }
}

/// The rays against `tri`: `Triangle::intersect`'s fast path in lanes.
#[inline(always)]
fn test(tri: &Tri, o: V3, d: V3) -> LaneHits<F> {
    let (p0, e1, e2) = (V3::splat(tri.p0), V3::splat(tri.e1), V3::splat(tri.e2));
    intersect_lanes_edges(p0, e1, e2, o, d)
}

/// The ray of lane `l`.
#[inline(always)]
fn ray_of(o: &[[f32; 16]; 3], d: &[[f32; 16]; 3], l: usize) -> Ray {
    Ray::new(
        glam::Vec3A::new(o[0][l], o[1][l], o[2][l]),
        glam::Vec3A::new(d[0][l], d[1][l], d[2][l]),
    )
}

lanes_fn! {
/// The nearest hits of the rays in lanes `active` (no bound, as `Scene::intersect`).
///
/// # Safety
/// The CPU must have AVX-512F.
#[inline]
pub unsafe fn closest(
    scene: &Scene,
    tris: &[Tri],
    balls: &[Ball],
    o: V3,
    d: V3,
    active: M,
) -> Hits {
    let inf = F::splat(f32::INFINITY);
    // The spheres first, each against the nearest hit so far (`Flat::nearest_sphere`).
    let (mut st, mut sprim, mut shit) = (inf, U::splat(u32::MAX), M::none());
    for b in balls {
        let (h, t) = intersect_lanes(V3::splat(b.center), F::splat(b.r2), o, d, st);
        let h = h & active;
        st = F::select(h, t, st);
        sprim = U::select(h, U::splat(b.prim), sprim);
        shit |= h;
    }
    // The triangles up to one ulp past the spheres' nearest, so that one as near is seen.
    let bound = F::select(shit, st.next_up(), inf);
    let mut bt = bound;
    let (mut bu, mut bv) = (F::zero(), F::zero());
    // (`Wavefront::new` lists the triangles in primitive order: the lower primitive of two
    // is the earlier slot.)
    let mut bprim = U::splat(u32::MAX);
    let mut thit = M::none();
    let mut unsure = Unsure::new();
    let zero = F::zero();
    for (j, tri) in tris.iter().enumerate() {
        let LaneHits {
            t,
            u,
            v,
            clear,
            unsure: near_edge,
        } = test(tri, o, d);
        // Strictly nearer only: of equally near hits the first slot stays.
        let hit = clear & t.gt(zero) & t.lt(bt) & active;
        bt = F::select(hit, t, bt);
        bu = F::select(hit, u, bu);
        bv = F::select(hit, v, bv);
        bprim = U::select(hit, U::splat(tri.prim), bprim);
        thit |= hit;
        let uns = near_edge & active;
        if uns.any() {
            unsure.list[unsure.n] = (uns.bits(), j as u16);
            unsure.n += 1;
        }
    }
    if unsure.n != 0 {
        settle(
            scene,
            tris,
            &o,
            &d,
            &unsure,
            bound,
            (&mut thit, &mut bprim, &mut bt, &mut bu, &mut bv),
        );
    }
    // A triangle's hit wins if nearer than the spheres', or as near and of a lower
    // primitive (`Flat::result`).
    let tri = thit & (!shit | bt.lt(st) | (bt.eq(st) & bprim.lt(sprim)));
    let sphere = shit & !tri;
    Hits {
        hit: tri | sphere,
        sphere,
        prim: U::select(tri, bprim, sprim),
        t: F::select(tri, bt, st),
        u: F::select(tri, bu, zero),
        v: F::select(tri, bv, zero),
    }
}
}

lanes_fn! {
/// The pairs near an edge, decided by the scene's test before the lane's `bound` and kept
/// where nearer than the lane's triangle hit (or as near and of a lower primitive).
#[cold]
#[inline(never)]
unsafe fn settle(
    scene: &Scene,
    tris: &[Tri],
    o: &V3,
    d: &V3,
    unsure: &Unsure,
    bound: F,
    (hit, prim, t, u, v): (&mut M, &mut U, &mut F, &mut F, &mut F),
) {
    let (mut oa, mut da) = ([[0f32; 16]; 3], [[0f32; 16]; 3]);
    o.store(&mut oa);
    d.store(&mut da);
    let bound = bound.to_array();
    let (mut ta, mut ua, mut va) = (t.to_array(), u.to_array(), v.to_array());
    let mut pa = [0u32; 16];
    prim.store(&mut pa);
    let mut hits = hit.bits();
    for &(lanes, j) in &unsure.list[..unsure.n] {
        let mut m = lanes;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let ray = ray_of(&oa, &da, l);
            let p = tris[j as usize].prim;
            if let Some((tt, uu, vv)) = scene.hit(&ray, p as usize, bound[l]) {
                if tt < ta[l] || (tt == ta[l] && p < pa[l]) {
                    (ta[l], ua[l], va[l], pa[l]) = (tt, uu, vv, p);
                    hits |= 1 << l;
                }
            }
        }
    }
    *hit = M::from_bits(hits);
    *t = F::load(&ta);
    *u = F::load(&ua);
    *v = F::load(&va);
    *prim = U::load(&pa);
}
}

lanes_fn! {
/// The lanes of `active` whose rays are blocked before `t_max` (`Scene::occluded`).
///
/// # Safety
/// The CPU must have AVX-512F.
#[inline]
pub unsafe fn occluded(
    scene: &Scene,
    tris: &[Tri],
    balls: &[Ball],
    o: V3,
    d: V3,
    t_max: F,
    active: M,
) -> M {
    let mut blocked = M::none();
    for b in balls {
        blocked |= intersect_lanes(V3::splat(b.center), F::splat(b.r2), o, d, t_max).0 & active;
    }
    let mut unsure = Unsure::new();
    let zero = F::zero();
    for (j, tri) in tris.iter().enumerate() {
        let r = test(tri, o, d);
        blocked |= r.clear & r.t.gt(zero) & r.t.lt(t_max) & active;
        let uns = r.unsure & active;
        if uns.any() {
            unsure.list[unsure.n] = (uns.bits(), j as u16);
            unsure.n += 1;
        }
    }
    if unsure.n != 0 {
        blocked |= settle_occluded(scene, tris, &o, &d, t_max, &unsure, blocked);
    }
    blocked
}
}

lanes_fn! {
/// The lanes, not yet `blocked`, that a pair near an edge blocks by the scene's test.
#[cold]
#[inline(never)]
unsafe fn settle_occluded(
    scene: &Scene,
    tris: &[Tri],
    o: &V3,
    d: &V3,
    t_max: F,
    unsure: &Unsure,
    blocked: M,
) -> M {
    let mut blocked = blocked.bits();
    let (mut oa, mut da) = ([[0f32; 16]; 3], [[0f32; 16]; 3]);
    o.store(&mut oa);
    d.store(&mut da);
    let tm = t_max.to_array();
    let mut more = 0;
    for &(lanes, j) in &unsure.list[..unsure.n] {
        let mut m = lanes & !blocked;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let ray = ray_of(&oa, &da, l);
            if scene
                .hit(&ray, tris[j as usize].prim as usize, tm[l])
                .is_some()
            {
                more |= 1 << l;
                blocked |= 1 << l;
            }
        }
    }
    M::from_bits(more)
}
}
