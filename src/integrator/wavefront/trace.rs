//! Sixteen rays against every triangle of a small scene, one triangle at a time: the
//! triangle's vertex and edges broadcast, the rays in the lanes. The transpose of
//! [`crate::accel::flat`], which tests one ray against sixteen triangles; the arithmetic of
//! each (ray, triangle) pair is the same, operation for operation ([`TriangleBlock`]'s, which
//! is [`Triangle::intersect`]'s), so each ray gets the hit `Scene::intersect` gives it: the
//! nearest, and of equally near ones the lowest primitive. Pairs near an edge are decided by
//! the scene's own test (`Triangle::intersect` with its f64 fallback), as there.
//!
//! [`TriangleBlock`]: crate::geometry::triangle_block::TriangleBlock
//! [`Triangle::intersect`]: crate::geometry::Triangle::intersect

use super::simd::{F, M, U, V3};
use crate::geometry::Ray;
use crate::scene::Scene;

/// Barycentric margin of the fast path, as in `Triangle::intersect`.
const EDGE_EPS: f32 = 1e-4;

/// A triangle's first vertex and edges `p1 − p0`, `p2 − p0` (as `Triangle::intersect`
/// subtracts them), and its primitive index.
#[derive(Clone, Copy, Debug)]
pub struct Tri {
    pub p0: [f32; 3],
    pub e1: [f32; 3],
    pub e2: [f32; 3],
    pub prim: u32,
}

/// The rays' nearest hits: the lanes hit, and their slot (index into the triangle list),
/// t, u and v.
pub struct Hits {
    pub hit: M,
    pub slot: U,
    pub t: F,
    pub u: F,
    pub v: F,
}

/// The (lane, slot) pairs left to the scene's own test, at most one entry per slot.
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

/// Per ray, the pair's quantities of Möller–Trumbore: (u, v, w, t) and the lanes it
/// classes clear (u, v, w > ε) and out (u or v < −ε, or u + v > 1 + ε).
#[inline(always)]
fn test(tri: &Tri, o: &V3, d: &V3) -> (F, F, F, M, M) {
    let (p0, e1, e2) = (V3::splat(tri.p0), V3::splat(tri.e1), V3::splat(tri.e2));
    let s = *o - p0;
    let p = d.cross(e2);
    let q = s.cross(e1);
    let one = F::splat(1.0);
    let inv_det = one / e1.dot(p);
    let u = s.dot(p) * inv_det;
    let v = d.dot(q) * inv_det;
    let w = (one - u) - v;
    let t = e2.dot(q) * inv_det;
    let (eps, neps) = (F::splat(EDGE_EPS), F::splat(-EDGE_EPS));
    let clear = u.gt(eps) & v.gt(eps) & w.gt(eps);
    let out = u.lt(neps) | v.lt(neps) | (u + v).gt(F::splat(1.0 + EDGE_EPS));
    (u, v, t, clear, out)
}

/// The ray of lane `l`.
#[inline(always)]
fn ray_of(o: &[[f32; 16]; 3], d: &[[f32; 16]; 3], l: usize) -> Ray {
    Ray::new(
        glam::Vec3A::new(o[0][l], o[1][l], o[2][l]),
        glam::Vec3A::new(d[0][l], d[1][l], d[2][l]),
    )
}

/// The nearest hits of the rays in lanes `active` (no bound: `Scene::intersect`'s).
///
/// # Safety
/// The CPU must have AVX-512F.
#[inline]
#[target_feature(enable = "avx512f")]
pub unsafe fn closest(scene: &Scene, tris: &[Tri], o: V3, d: V3, active: M) -> Hits {
    let mut bt = F::splat(f32::INFINITY);
    let (mut bu, mut bv) = (F::zero(), F::zero());
    let mut bslot = U::splat(u32::MAX);
    let mut unsure = Unsure::new();
    let zero = F::zero();
    for (j, tri) in tris.iter().enumerate() {
        let (u, v, t, clear, out) = test(tri, &o, &d);
        // Strictly nearer only: of equally near hits the first slot stays.
        let hit = clear & t.gt(zero) & t.lt(bt) & active;
        bt = F::select(hit, t, bt);
        bu = F::select(hit, u, bu);
        bv = F::select(hit, v, bv);
        bslot = U::select(hit, U::splat(j as u32), bslot);
        let uns = !(clear | out) & active;
        if uns != 0 {
            unsure.list[unsure.n] = (uns, j as u16);
            unsure.n += 1;
        }
    }
    let mut h = Hits {
        hit: bt.lt(F::splat(f32::INFINITY)) & active,
        slot: bslot,
        t: bt,
        u: bu,
        v: bv,
    };
    if unsure.n != 0 {
        settle(scene, tris, &o, &d, &unsure, &mut h);
    }
    h
}

/// The pairs near an edge, decided by the scene's test and kept where nearer than the
/// lane's hit (or as near and of a lower slot).
#[cold]
#[inline(never)]
#[target_feature(enable = "avx512f")]
unsafe fn settle(scene: &Scene, tris: &[Tri], o: &V3, d: &V3, unsure: &Unsure, h: &mut Hits) {
    let (mut oa, mut da) = ([[0f32; 16]; 3], [[0f32; 16]; 3]);
    o.store(&mut oa);
    d.store(&mut da);
    let (mut t, mut u, mut v) = (h.t.to_array(), h.u.to_array(), h.v.to_array());
    let mut slot = [0u32; 16];
    h.slot.store(&mut slot);
    for &(lanes, j) in &unsure.list[..unsure.n] {
        let mut m = lanes;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let ray = ray_of(&oa, &da, l);
            let prim = tris[j as usize].prim as usize;
            if let Some((tt, uu, vv)) = scene.hit(&ray, prim, f32::INFINITY) {
                let nearer = tt < t[l] || (tt == t[l] && (j as u32) < slot[l]);
                if nearer {
                    (t[l], u[l], v[l], slot[l]) = (tt, uu, vv, j as u32);
                    h.hit |= 1 << l;
                }
            }
        }
    }
    h.t = F::load(&t);
    h.u = F::load(&u);
    h.v = F::load(&v);
    h.slot = U::load(&slot);
}

/// The lanes of `active` whose rays are blocked before `t_max` (`Scene::occluded`).
///
/// # Safety
/// The CPU must have AVX-512F.
#[inline]
#[target_feature(enable = "avx512f")]
pub unsafe fn occluded(scene: &Scene, tris: &[Tri], o: V3, d: V3, t_max: F, active: M) -> M {
    let mut blocked: M = 0;
    let mut unsure = Unsure::new();
    let zero = F::zero();
    for (j, tri) in tris.iter().enumerate() {
        let (_, _, t, clear, out) = test(tri, &o, &d);
        blocked |= clear & t.gt(zero) & t.lt(t_max) & active;
        let uns = !(clear | out) & active;
        if uns != 0 {
            unsure.list[unsure.n] = (uns, j as u16);
            unsure.n += 1;
        }
    }
    if unsure.n != 0 {
        blocked |= settle_occluded(scene, tris, &o, &d, t_max, &unsure, blocked);
    }
    blocked
}

/// The lanes, not yet `blocked`, that a pair near an edge blocks by the scene's test.
#[cold]
#[inline(never)]
#[target_feature(enable = "avx512f")]
unsafe fn settle_occluded(
    scene: &Scene,
    tris: &[Tri],
    o: &V3,
    d: &V3,
    t_max: F,
    unsure: &Unsure,
    mut blocked: M,
) -> M {
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
    more
}
