//! Closest hits of up to sixteen rays from one origin, as a pinhole camera's rays are
//! ([`Scene::intersect_packet`]), in one traversal of the tree for all of them
//! ([`crate::accel::WideBvh::closest_packet`]): each node is fetched once for the packet and
//! its children tested against all the lanes at once. The camera rays of a pixel's samples,
//! and of neighbouring pixels, enter nearly the same nodes, so a packet costs about what one
//! of its rays costs alone (Wald, Slusallek, Benthin and Wagner, "Interactive Rendering with
//! Coherent Ray Tracing", Eurographics 2001).
//!
//! Every answer is the same bits as [`Scene::intersect`]'s: each lane tests the boxes and the
//! primitives it reaches by the single ray's operations (`Scene::keep_nearer`, the tie rule
//! included), and its hit becomes an [`Interaction`] by the same code, instances and masks
//! included. A triangle is tested against the lanes that reach it sixteen at once (in one
//! AVX-512 register or two AVX ones) or four at a time ([`intersect_lanes`], the single
//! ray's test in lanes), as are the occlusion packets'.

use super::{take_nearer, Interaction, Scene, NO_HIT, SPHERE};
use crate::accel::{RayPacket, PACKET};
use crate::geometry::triangle::intersect_lanes;
use crate::geometry::{Ray, Triangle};
use crate::simd::{lanes_of, Vector3, V3};
use glam::{Vec3A, Vec4};

impl Scene {
    /// The closest hits of the lanes of `active` of `pk` into `out` by lane (the other lanes
    /// are left as they are): [`Scene::intersect`] of each lane's ray, the same bits, with
    /// the tree traversed once for all of them. The packet's `t_max` must be infinite, as
    /// `intersect`'s is.
    #[inline]
    pub fn intersect_packet(
        &self,
        pk: &RayPacket,
        active: u32,
        out: &mut [Option<Interaction>; PACKET],
    ) {
        self.intersect_packet_with(pk, active, PACKET, out);
    }

    /// [`Scene::intersect_packet`] with its box tests `lanes` (1, 8 or 16) rays at a time
    /// where the CPU allows (sixteen with AVX-512, eight with AVX; else one): the same
    /// answers each way, which the tests check by choosing.
    #[inline]
    pub fn intersect_packet_with(
        &self,
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        out: &mut [Option<Interaction>; PACKET],
    ) {
        debug_assert!(pk.t_max.iter().all(|&t| t == f32::INFINITY));
        let mut best = [NO_HIT; PACKET];
        let found = if self.is_flat() {
            // Brute force, faster than any tree for small scenes.
            self.flat_lanes(pk, active, &mut best)
        } else if self.masked {
            self.closest_lanes(pk, active, lanes, &mut best, |l, i, u, v, t| {
                self.seen(&pk.ray(l), i, u, v, t)
            })
        } else {
            self.closest_lanes(pk, active, lanes, &mut best, |_, _, _, _, _| true)
        };
        for l in lanes_of(active) {
            let hit = (found >> l & 1 != 0).then_some(best[l]);
            self.interaction_into(&pk.ray(l), hit, &mut out[l]);
        }
    }

    /// [`Scene::intersect_packet`]'s closest hits by brute force, into `best` by lane; returns
    /// the lanes with one. All sixteen rays at once where the scene has no masks
    /// ([`Flat::intersect_rays`]; an inactive lane repeats an active one's ray), else one by
    /// one.
    ///
    /// [`Flat::intersect_rays`]: crate::accel::flat::Flat::intersect_rays
    #[inline(always)]
    fn flat_lanes(
        &self,
        pk: &RayPacket,
        active: u32,
        best: &mut [(usize, f32, f32, f32); PACKET],
    ) -> u32 {
        let mut found = 0;
        #[cfg(target_arch = "x86_64")]
        if let (Some(f), false, true) = (&self.flat, self.masked, active != 0) {
            const _: () = assert!(PACKET == crate::accel::flat::RAYS);
            let first = active.trailing_zeros() as usize;
            let rays: [Ray; PACKET] =
                std::array::from_fn(|l| pk.ray(if active >> l & 1 != 0 { l } else { first }));
            let hits = f.intersect_rays(&rays, |ray, i, t| self.hit(ray, i, t));
            for l in lanes_of(active) {
                if let Some((i, t, u, v)) = hits[l] {
                    (best[l], found) = ((i, u, v, t), found | 1 << l);
                }
            }
            return found;
        }
        for l in lanes_of(active) {
            if let Some(hit) = self.closest(&pk.ray(l), f32::INFINITY) {
                (best[l], found) = (hit, found | 1 << l);
            }
        }
        found
    }

    /// `Scene::closest_kept` for the lanes of `active` of `pk` in one traversal: into `best`
    /// by lane, of the hits `keep` keeps (given the lane, primitive, u, v, t); returns the
    /// lanes with one.
    #[inline(always)]
    fn closest_lanes(
        &self,
        pk: &RayPacket,
        active: u32,
        lanes: usize,
        best: &mut [(usize, f32, f32, f32); PACKET],
        keep: impl Fn(usize, usize, f32, f32, f32) -> bool,
    ) -> u32 {
        let width = triangle_lanes(lanes);
        self.bvh
            .closest_packet_with(pk, active, lanes, |i, lanes, t_max| {
                let mut nearer = 0;
                let mut take = |l: usize, hit| {
                    let keep = |i, u, v, t| keep(l, i, u, v, t);
                    if let Some(t) = take_nearer(&mut best[l], i, hit, t_max[l], &keep) {
                        (t_max[l], nearer) = (t, nearer | 1 << l);
                    }
                };
                // SAFETY: the BVH's leaves name primitives below tris.len() (Scene::build).
                let idx = unsafe { *self.tris.get_unchecked(i) };
                if idx[0] == SPHERE || lanes.is_power_of_two() {
                    for l in lanes_of(lanes) {
                        if let Some(hit) = self.hit(&pk.ray(l), i, f32::INFINITY) {
                            take(l, hit);
                        }
                    }
                } else {
                    self.triangle_hits(idx, pk, None, lanes, width, take);
                }
                nearer
            })
    }

    /// The lanes of `lanes` whose rays primitive `i` blocks before their `t_max`: the rays
    /// of `pk`, or from `origins` in the directions of `pk`; `width` as for
    /// `Scene::triangle_hits`.
    #[inline(always)]
    pub(super) fn packet_hits(
        &self,
        pk: &RayPacket,
        origins: Option<&[[f32; PACKET]; 3]>,
        i: usize,
        lanes: u32,
        width: TriangleLanes,
    ) -> u32 {
        let ray = |l| ray_of(pk, origins, l);
        let each = |hit: &dyn Fn(usize) -> bool| {
            lanes_of(lanes).fold(0, |hits, l| hits | (hit(l) as u32) << l)
        };
        if self.masked && self.has_opacity(i) {
            return each(&|l| self.blocks_seen(&ray(l), i, pk.t_max[l]));
        }
        // SAFETY: the BVH's leaves name primitives below tris.len() (Scene::build).
        let idx = unsafe { *self.tris.get_unchecked(i) };
        match (idx[0] == SPHERE, origins) {
            (false, _) if !lanes.is_power_of_two() => {
                let mut hits = 0;
                self.triangle_hits(idx, pk, origins, lanes, width, |l, (t, _, _)| {
                    hits |= ((t < pk.t_max[l]) as u32) << l;
                });
                hits
            }
            (true, None) => {
                // Rays from one origin, four at a time.
                let sphere = &self.spheres[idx[1] as usize];
                let mut hits = 0;
                for h in (0..PACKET).step_by(4) {
                    let m = (lanes >> h) & 15;
                    if m != 0 {
                        let d = std::array::from_fn(|k| Vec4::from_slice(&pk.d[k][h..h + 4]));
                        let t_max = Vec4::from_slice(&pk.t_max[h..h + 4]);
                        hits |= (sphere.occludes4(pk.o, d, t_max) & m) << h;
                    }
                }
                hits
            }
            _ => each(&|l| self.hit(&ray(l), i, pk.t_max[l]).is_some()),
        }
    }

    /// Triangle `idx` (its vertex indices) against the rays of `lanes` (those of `pk`, or
    /// from `origins` in the directions of `pk`) by [`intersect_lanes`], `width` lanes at a
    /// time ([`triangle_lanes`]), and those it is unsure
    /// of one by one: `each(lane, (t, u, v))` gets the hit of every lane that has one up to
    /// infinity, [`Scene::hit`]'s answer (its order of lanes is not theirs).
    #[inline(always)]
    fn triangle_hits(
        &self,
        idx: [u32; 3],
        pk: &RayPacket,
        origins: Option<&[[f32; PACKET]; 3]>,
        lanes: u32,
        width: TriangleLanes,
        mut each: impl FnMut(usize, (f32, f32, f32)),
    ) {
        let p = idx.map(|k| self.vertex_fast(k));
        let tri = Triangle::new(p[0], p[1], p[2]);
        // Lanes `base + k` of a pass: its clear hits as they are, its unsure lanes to `tri`.
        let mut give = |base: usize, clear: u32, unsure: u32, tuv: [&[f32]; 3]| {
            for k in lanes_of(clear) {
                each(base + k, (tuv[0][k], tuv[1][k], tuv[2][k]));
            }
            for k in lanes_of(unsure) {
                let ray = ray_of(pk, origins, base + k);
                if let Some(hit) = tri.intersect(&ray, f32::INFINITY) {
                    each(base + k, hit);
                }
            }
        };
        #[cfg(target_arch = "x86_64")]
        if width != TriangleLanes::Four {
            // SAFETY: `triangle_lanes` chose the width for the CPU's features.
            let r = unsafe {
                match width {
                    TriangleLanes::Avx512 => sixteen_avx512(tri, pk, origins),
                    _ => sixteen_avx(tri, pk, origins),
                }
            };
            give(0, r.clear & lanes, r.unsure & lanes, [&r.t, &r.u, &r.v]);
            return;
        }
        let p = p.map(V3::<Vec4>::broadcast);
        // (Loaded in place: `pk.d.map` would copy the whole arrays first.)
        let four = |a: &[[f32; PACKET]; 3], h: usize| {
            V3::new(
                Vec4::from_slice(&a[0][h..h + 4]),
                Vec4::from_slice(&a[1][h..h + 4]),
                Vec4::from_slice(&a[2][h..h + 4]),
            )
        };
        let shared = V3::broadcast(pk.o);
        for h in (0..PACKET).step_by(4) {
            let m = (lanes >> h) & 15;
            if m == 0 {
                continue;
            }
            let o = origins.map_or(shared, |o| four(o, h));
            let r = intersect_lanes(p, o, four(&pk.d, h));
            let ahead = r.t.cmpgt(Vec4::ZERO) & r.t.cmplt(Vec4::INFINITY);
            let (clear, unsure) = ((r.clear & ahead).bitmask() & m, r.unsure.bitmask() & m);
            let tuv = [r.t.to_array(), r.u.to_array(), r.v.to_array()];
            give(h, clear, unsure, [&tuv[0], &tuv[1], &tuv[2]]);
        }
    }
}

/// How a packet tests its triangles ([`Scene::triangle_hits`]): sixteen lanes at once, in
/// one AVX-512 register or in two AVX ones, or four at a time.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum TriangleLanes {
    Four,
    #[cfg(target_arch = "x86_64")]
    Avx,
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

/// How a packet whose box tests take `lanes` lanes (1, 8 or 16) tests its triangles, chosen
/// once a packet: sixteen at once in AVX-512 where the box tests are sixteen wide and the CPU
/// may run it (`cpu::avx512`), in AVX where they take eight lanes or more and the CPU has
/// it, else four at a time. Tied to the box tests' width so that the tests, which choose
/// that width, reach every form on an AVX-512 host.
#[inline(always)]
pub(super) fn triangle_lanes(lanes: usize) -> TriangleLanes {
    #[cfg(target_arch = "x86_64")]
    {
        if lanes == PACKET && crate::cpu::avx512() {
            return TriangleLanes::Avx512;
        }
        if lanes >= 8 && std::arch::is_x86_feature_detected!("avx") {
            return TriangleLanes::Avx;
        }
    }
    let _ = lanes;
    TriangleLanes::Four
}

/// Lane `l`'s ray: of `pk`, or from `origins` in `pk`'s direction.
#[inline(always)]
fn ray_of(pk: &RayPacket, origins: Option<&[[f32; PACKET]; 3]>, l: usize) -> Ray {
    match origins {
        Some(o) => Ray::new(Vec3A::new(o[0][l], o[1][l], o[2][l]), pk.ray(l).d),
        None => pk.ray(l),
    }
}

/// [`intersect_lanes`] of all sixteen lanes of `pk` (or from `origins` in its directions)
/// against `tri` at once: distances and barycentrics by lane, the clear lanes that hit (0 <
/// t < ∞) and the unsure ones, as bits.
#[cfg(target_arch = "x86_64")]
struct SixteenHits {
    t: [f32; PACKET],
    u: [f32; PACKET],
    v: [f32; PACKET],
    clear: u32,
    unsure: u32,
}

/// [`SixteenHits`] in one AVX-512 register.
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn sixteen_avx512(
    tri: Triangle,
    pk: &RayPacket,
    origins: Option<&[[f32; PACKET]; 3]>,
) -> SixteenHits {
    sixteen::<crate::simd::avx512::F>(tri, pk, origins)
}

/// [`SixteenHits`] in two AVX registers.
///
/// # Safety
/// The CPU must have AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn sixteen_avx(
    tri: Triangle,
    pk: &RayPacket,
    origins: Option<&[[f32; PACKET]; 3]>,
) -> SixteenHits {
    sixteen::<crate::simd::avx2::F>(tri, pk, origins)
}

/// [`SixteenHits`] in the lanes of `T`, inlined into a caller compiled with their features.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn sixteen<T: crate::simd::Sixteen>(
    tri: Triangle,
    pk: &RayPacket,
    origins: Option<&[[f32; PACKET]; 3]>,
) -> SixteenHits {
    // (Written out: a closure would be compiled without the caller's features.)
    let p = [
        V3::<T>::broadcast(tri.p0),
        V3::broadcast(tri.p1),
        V3::broadcast(tri.p2),
    ];
    let o = match origins {
        Some(o) => V3::new(T::load(&o[0]), T::load(&o[1]), T::load(&o[2])),
        None => V3::broadcast(pk.o),
    };
    let d = V3::new(T::load(&pk.d[0]), T::load(&pk.d[1]), T::load(&pk.d[2]));
    let r = intersect_lanes(p, o, d);
    let ahead = r.t.gt(T::zero()) & r.t.lt(T::splat(f32::INFINITY));
    SixteenHits {
        t: r.t.to_array(),
        u: r.u.to_array(),
        v: r.v.to_array(),
        clear: T::bits(r.clear & ahead),
        unsure: T::bits(r.unsure),
    }
}
