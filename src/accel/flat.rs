//! Brute force for small scenes: every triangle tested against a single ray, sixteen at a
//! time ([`TriangleBlock`]), and the few spheres one by one. No hierarchy at all. Batches of
//! sixteen rays take the transpose, each primitive against the rays in the lanes (`rays.rs`).
//!
//! Why: in a room of a few dozen triangles the BVH's work per ray is small, but it is
//! branchy. Each node test and each triangle's early exit is a branch whose outcome varies
//! from ray to ray, and a misprediction costs more than the arithmetic it skips. The block
//! loops here have no such branch. `cargo bench --bench flat` (docs/performance.md) timed
//! the Cornell box's bounce rays at 168 ns a closest hit through the 4-wide BVH and 98 ns
//! by brute force with AVX-512, and 151 ns with AVX. A path tracer's coherent camera rays
//! gain less. Brute force grows with the triangle count and the tree does not, so it is
//! used only up to [`FLAT_MAX_TRIANGLES`] triangles ([`FLAT_MAX_TRIANGLES_AVX`] with AVX
//! alone) and [`FLAT_MAX_SPHERES`] spheres, on x86-64 CPUs with AVX. The BVH is still
//! built: the shadow-ray packets trace it.
//!
//! The answers are those of the primitives' own tests: the nearest hit, and of equally near
//! ones the primitive of the lowest index. The BVH's traversal keeps the same rule
//! (`Scene::intersect`), so both give the same hits. The one exception is that the tree
//! never tests a primitive whose box its conservative box test rules out. That happens
//! only where the f32 test's t for a grazing ray lies farther out than the widened box
//! allows, and only when it would have been the nearest hit. The images are therefore the
//! same bits whichever of the two traces them (`tests/intersect.rs` compares every hit of
//! the example scenes both ways), whichever kernel the CPU runs (AVX-512 or AVX, which give
//! the same bits), and whether the integrator runs its portable or its x86-64-v3 code.

use crate::geometry::triangle_block::{TriangleBlock, LANES};
use crate::geometry::{Ray, Sphere, Triangle};
use crate::simd::{avx2, avx512, Sixteen, Vector3, V3};

mod rays;
use rays::Tri;
pub use rays::{Ball, Hits};

/// Most triangles traced by brute force with AVX-512. `cargo bench --bench flat` found it
/// faster than the BVH at every size up to this one (docs/performance.md).
pub const FLAT_MAX_TRIANGLES: usize = 64;
/// Most triangles traced by brute force with AVX only (two passes of eight lanes a block).
/// In `cargo bench --bench flat` it beat the BVH at every size measured: by 10 % on the
/// Cornell box's 36 triangles, 26 % on the TNCG15 room's 26 and 19 % on 52 random ones
/// (docs/performance.md). It was 32 until the wavefront ran on AVX2 (2026-12-03): the
/// wavefront takes only scenes traced by brute force (so that its hits are the path
/// tracer's), and the Cornell box has 36.
pub const FLAT_MAX_TRIANGLES_AVX: usize = 64;
/// Most triangles a flat set can hold: the lanes near an edge are gathered in one 64-bit mask.
pub const FLAT_MAX_SLOTS: usize = 64;
/// Most spheres traced by brute force (each costs a test of its own for every ray).
pub const FLAT_MAX_SPHERES: usize = 4;

/// The SIMD code that tests the blocks: one pass of sixteen lanes, or two of eight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    Avx512,
    Avx,
}

impl Kernel {
    /// Whether this CPU runs the kernel.
    pub fn available(self) -> bool {
        match self {
            Kernel::Avx512 => crate::cpu::avx512(),
            Kernel::Avx => std::arch::is_x86_feature_detected!("avx"),
        }
    }
}

/// The primitives of a small scene, for brute-force tests of single rays.
#[derive(Clone, Debug)]
pub struct Flat {
    blocks: Vec<TriangleBlock>,
    /// The scene's primitive index of each triangle, block by block, lane by lane.
    prims: Vec<u32>,
    /// The spheres, with the scene's primitive indices, in the order of those.
    balls: Vec<Ball>,
    /// The triangles again, each one's data together, for the rays in lanes (`rays.rs`).
    tris: Vec<Tri>,
    kernel: Kernel,
}

impl Flat {
    /// The flat set over `triangles` (primitive index and triangle, in the scene's order)
    /// and `spheres` (likewise); None where the scene is too large for brute force
    /// or the CPU lacks AVX.
    pub fn new(triangles: &[(u32, Triangle)], spheres: &[(u32, Sphere)]) -> Option<Flat> {
        let kernel = detect()?;
        let most = match kernel {
            Kernel::Avx512 => FLAT_MAX_TRIANGLES,
            Kernel::Avx => FLAT_MAX_TRIANGLES_AVX,
        };
        if triangles.len() > most || spheres.len() > FLAT_MAX_SPHERES {
            return None;
        }
        Self::with_kernel(triangles, spheres, kernel)
    }

    /// The flat set with `kernel`, whatever the scene's size (up to [`FLAT_MAX_SLOTS`]
    /// triangles); None where the CPU does not run `kernel`, or there is nothing to test.
    pub fn with_kernel(
        triangles: &[(u32, Triangle)],
        spheres: &[(u32, Sphere)],
        kernel: Kernel,
    ) -> Option<Flat> {
        assert!(triangles.len() <= FLAT_MAX_SLOTS);
        if !kernel.available() || (triangles.is_empty() && spheres.is_empty()) {
            return None;
        }
        let blocks = triangles
            .chunks(LANES)
            .map(|c| TriangleBlock::new(&c.iter().map(|&(_, t)| t).collect::<Vec<_>>()))
            .collect();
        Some(Flat {
            blocks,
            prims: triangles.iter().map(|&(p, _)| p).collect(),
            tris: triangles.iter().map(|(p, t)| Tri::new(*p, t)).collect(),
            balls: spheres
                .iter()
                .map(|&(prim, s)| Ball {
                    center: s.center,
                    r2: s.radius * s.radius,
                    prim,
                })
                .collect(),
            kernel,
        })
    }

    /// Whether the set holds spheres.
    pub fn has_spheres(&self) -> bool {
        !self.balls.is_empty()
    }

    /// Bytes of the blocks and index lists.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&self.blocks[..])
            + std::mem::size_of_val(&self.prims[..])
            + std::mem::size_of_val(&self.balls[..])
            + std::mem::size_of_val(&self.tris[..])
    }

    /// The lanes of block `k` that hold triangles.
    #[inline(always)]
    fn lanes(&self, k: usize) -> u32 {
        let n = (self.prims.len() - k * LANES).min(LANES);
        (1u32 << n) - 1
    }

    /// The nearest hit before `t_max` as (primitive, t, u, v). `hit(prim, t_max)` is the
    /// primitive's own test (t, u, v of a hit in (0, t_max)): it decides the spheres and
    /// the lanes near an edge.
    #[inline(always)]
    pub fn intersect<F>(&self, ray: &Ray, t_max: f32, hit: F) -> Option<(usize, f32, f32, f32)>
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        // SAFETY: the kernel was chosen for the CPU's features (`detect`).
        unsafe {
            match self.kernel {
                Kernel::Avx512 => self.intersect16(ray, t_max, hit),
                Kernel::Avx => self.intersect8(ray, t_max, hit),
            }
        }
    }

    /// Whether anything blocks the ray before `t_max`; `hit` as for [`Flat::intersect`].
    #[inline(always)]
    pub fn occluded<F>(&self, ray: &Ray, t_max: f32, hit: F) -> bool
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        // SAFETY: as above.
        unsafe {
            match self.kernel {
                Kernel::Avx512 => self.occluded16(ray, t_max, hit),
                Kernel::Avx => self.occluded8(ray, t_max, hit),
            }
        }
    }

    /// The spheres' nearest hit before `t_max`, as (primitive, t, u, v), or
    /// (`usize::MAX`, `t_max`, 0, 0) where none is hit. (The spheres are listed by
    /// primitive, so of equally near ones the first is the lowest.)
    #[inline(always)]
    fn nearest_sphere<F>(&self, t_max: f32, hit: &mut F) -> (usize, f32, f32, f32)
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        let mut best = (usize::MAX, t_max, 0.0, 0.0);
        for b in &self.balls {
            if let Some((t, u, v)) = hit(b.prim as usize, best.1) {
                best = (b.prim as usize, t, u, v);
            }
        }
        best
    }

    /// The triangles' lanes near an edge (bit `16·block + lane` of `unsure`), decided by
    /// `hit` before `t_max`, against `best`, the nearest clear hit as (slot, t, u, v): the
    /// nearest of them all, and of equally near ones the first slot.
    #[inline(always)]
    fn settle<F>(
        &self,
        mut unsure: u64,
        t_max: f32,
        mut best: (usize, f32, f32, f32),
        hit: &mut F,
    ) -> (usize, f32, f32, f32)
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        while unsure != 0 {
            let slot = unsure.trailing_zeros() as usize;
            unsure &= unsure - 1;
            if let Some((t, u, v)) = hit(self.prims[slot] as usize, t_max) {
                if t < best.1 || (t == best.1 && slot < best.0) {
                    best = (slot, t, u, v);
                }
            }
        }
        best
    }

    /// The bound the triangles' hits must lie below, given the spheres' nearest: one ulp
    /// past it, so that a triangle exactly as near (of a lower index) is still seen.
    #[inline(always)]
    fn triangle_bound(sphere: &(usize, f32, f32, f32), t_max: f32) -> f32 {
        if sphere.0 == usize::MAX {
            t_max
        } else {
            sphere.1.next_up()
        }
    }

    /// The nearest hit of the spheres' and the triangles' (slot `best.0`), of equally near
    /// ones the lower primitive.
    #[inline(always)]
    fn result(
        &self,
        sphere: (usize, f32, f32, f32),
        best: (usize, f32, f32, f32),
    ) -> Option<(usize, f32, f32, f32)> {
        if best.0 != usize::MAX {
            let tri = (self.prims[best.0] as usize, best.1, best.2, best.3);
            if sphere.0 == usize::MAX || tri.1 < sphere.1 || (tri.1 == sphere.1 && tri.0 < sphere.0)
            {
                return Some(tri);
            }
        }
        (sphere.0 != usize::MAX).then_some(sphere)
    }

    // The block loops below carry no branch on the rays' answers: each lane keeps the
    // nearest hit it has seen (a later block's only where strictly nearer, so of equal ones
    // the first), and the lanes are reduced once at the end. Every block's arithmetic is
    // then independent of the one before, and the CPU overlaps their divisions (the
    // latency a block waits on) rather than waiting on a mispredicted branch per block.

    /// # Safety
    /// The CPU must have AVX-512F.
    // Not inlined: a call per ray costs nothing next to the blocks, and the caller's
    // hot loop (the path, compiled for x86-64-v3) keeps its registers.
    #[inline(never)]
    #[target_feature(enable = "avx,avx512f")]
    unsafe fn intersect16<F>(&self, ray: &Ray, t_max: f32, hit: F) -> Option<(usize, f32, f32, f32)>
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.nearest::<avx512::F, F>(ray, t_max, hit)
    }

    /// # Safety
    /// The CPU must have AVX.
    // (Not inlined, as `intersect16`.)
    #[inline(never)]
    #[target_feature(enable = "avx")]
    unsafe fn intersect8<F>(&self, ray: &Ray, t_max: f32, hit: F) -> Option<(usize, f32, f32, f32)>
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.nearest::<avx2::F, F>(ray, t_max, hit)
    }

    /// [`Flat::intersect`] in the lanes of `T`, compiled into a caller with its features.
    #[inline(always)]
    fn nearest<T: Sixteen, F>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut hit: F,
    ) -> Option<(usize, f32, f32, f32)>
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        let sphere = self.nearest_sphere(t_max, &mut hit);
        let t_max = Self::triangle_bound(&sphere, t_max);
        let (o, d) = (V3::<T>::broadcast(ray.o), V3::broadcast(ray.d));
        let (mut bt, mut bu, mut bv) = (T::splat(t_max), T::zero(), T::zero());
        // Each lane's slot (16·block + lane) as an f32 (exact: fewer than 2²⁴), selected as
        // the distances are.
        let mut bslot = T::zero();
        let mut unsure_all = 0u64;
        for (k, b) in self.blocks.iter().enumerate() {
            let (hits, unsure, [t, u, v]) = b.test(o, d, bt);
            // (Lanes past the last triangle hold NaN and are never hit; only their
            // `unsure` bits need masking.)
            unsure_all |= u64::from(T::bits(unsure) & self.lanes(k)) << (LANES * k);
            bt = T::select(hits, t, bt);
            bu = T::select(hits, u, bu);
            bv = T::select(hits, v, bv);
            bslot = T::select(hits, T::iota((LANES * k) as f32), bslot);
        }
        let mut best = (usize::MAX, t_max, 0.0, 0.0);
        let (t, slot) = T::min_by_key(bt, bslot);
        if t < t_max {
            let slot = slot as usize;
            best = (
                slot,
                t,
                bu.to_array()[slot % LANES],
                bv.to_array()[slot % LANES],
            );
        }
        if unsure_all != 0 {
            best = self.settle(unsure_all, t_max, best, &mut hit);
        }
        self.result(sphere, best)
    }

    /// # Safety
    /// The CPU must have AVX-512F.
    // (Not inlined, as `intersect16`.)
    #[inline(never)]
    #[target_feature(enable = "avx,avx512f")]
    unsafe fn occluded16<F>(&self, ray: &Ray, t_max: f32, hit: F) -> bool
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.blocked::<avx512::F, F>(ray, t_max, hit)
    }

    /// # Safety
    /// The CPU must have AVX.
    // (Not inlined, as `intersect16`.)
    #[inline(never)]
    #[target_feature(enable = "avx")]
    unsafe fn occluded8<F>(&self, ray: &Ray, t_max: f32, hit: F) -> bool
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.blocked::<avx2::F, F>(ray, t_max, hit)
    }

    /// [`Flat::occluded`] in the lanes of `T`, compiled into a caller with its features.
    #[inline(always)]
    fn blocked<T: Sixteen, F>(&self, ray: &Ray, t_max: f32, mut hit: F) -> bool
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        if self
            .balls
            .iter()
            .any(|b| hit(b.prim as usize, t_max).is_some())
        {
            return true;
        }
        let (o, d) = (V3::<T>::broadcast(ray.o), V3::broadcast(ray.d));
        let tm = T::splat(t_max);
        let (mut any, mut unsure_all) = (0u32, 0u64);
        for (k, b) in self.blocks.iter().enumerate() {
            let (hits, unsure, _) = b.test(o, d, tm);
            any |= T::bits(hits);
            unsure_all |= u64::from(T::bits(unsure) & self.lanes(k)) << (LANES * k);
        }
        any != 0 || self.any_unsure(unsure_all, t_max, &mut hit)
    }

    /// [`Flat::intersect`] of sixteen rays at once, each up to infinity, the same answers:
    /// the rays in the lanes and each primitive broadcast in turn ([`Flat::closest_lanes`]),
    /// which a batch of rays (`Scene::intersect_many`) affords. `hit(ray, prim, t_max)` is
    /// the primitive's own test: it decides the lanes near an edge.
    #[inline(always)]
    pub fn intersect_rays<F>(
        &self,
        rays: &[Ray; RAYS],
        hit: F,
    ) -> [Option<(usize, f32, f32, f32)>; RAYS]
    where
        F: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        // SAFETY: the kernel was chosen for the CPU's features (`detect`).
        unsafe {
            match self.kernel {
                Kernel::Avx512 => self.intersect_rays16(rays, hit),
                Kernel::Avx => self.intersect_rays8(rays, hit),
            }
        }
    }

    /// [`Flat::occluded`] of sixteen rays at once (ray k before `t_max[k]`), as bits (bit k
    /// for ray k); `hit` as for [`Flat::intersect_rays`].
    #[inline(always)]
    pub fn occluded_rays<F>(&self, rays: &[Ray; RAYS], t_max: &[f32; RAYS], hit: F) -> u32
    where
        F: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        // SAFETY: as above.
        unsafe {
            match self.kernel {
                Kernel::Avx512 => self.occluded_rays16(rays, t_max, hit),
                Kernel::Avx => self.occluded_rays8(rays, t_max, hit),
            }
        }
    }

    /// # Safety
    /// The CPU must have AVX-512F.
    #[inline(never)]
    #[target_feature(enable = "avx,avx512f")]
    unsafe fn intersect_rays16<F>(
        &self,
        rays: &[Ray; RAYS],
        hit: F,
    ) -> [Option<(usize, f32, f32, f32)>; RAYS]
    where
        F: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.nearest_of_rays::<avx512::F, F>(rays, hit)
    }

    /// # Safety
    /// The CPU must have AVX.
    #[inline(never)]
    #[target_feature(enable = "avx")]
    unsafe fn intersect_rays8<F>(
        &self,
        rays: &[Ray; RAYS],
        hit: F,
    ) -> [Option<(usize, f32, f32, f32)>; RAYS]
    where
        F: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.nearest_of_rays::<avx2::F, F>(rays, hit)
    }

    /// # Safety
    /// The CPU must have AVX-512F.
    #[inline(never)]
    #[target_feature(enable = "avx,avx512f")]
    unsafe fn occluded_rays16<F>(&self, rays: &[Ray; RAYS], t_max: &[f32; RAYS], hit: F) -> u32
    where
        F: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.blocked_rays::<avx512::F, F>(rays, t_max, hit)
    }

    /// # Safety
    /// The CPU must have AVX.
    #[inline(never)]
    #[target_feature(enable = "avx")]
    unsafe fn occluded_rays8<F>(&self, rays: &[Ray; RAYS], t_max: &[f32; RAYS], hit: F) -> u32
    where
        F: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        self.blocked_rays::<avx2::F, F>(rays, t_max, hit)
    }

    /// [`Flat::intersect_rays`] in the lanes of `T` ([`Flat::closest_lanes`]).
    #[inline(always)]
    fn nearest_of_rays<T: Sixteen, H>(
        &self,
        rays: &[Ray; RAYS],
        hit: H,
    ) -> [Option<(usize, f32, f32, f32)>; RAYS]
    where
        H: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        let (o, d) = rays_in_lanes::<T>(rays);
        let h = self.closest_lanes(o, d, T::from_bits(u32::MAX), hit);
        let hits = T::bits(h.hit);
        let (prim, t, u, v) = (
            h.prim.to_array(),
            h.t.to_array(),
            h.u.to_array(),
            h.v.to_array(),
        );
        std::array::from_fn(|k| (hits >> k & 1 != 0).then(|| (prim[k] as usize, t[k], u[k], v[k])))
    }

    /// [`Flat::occluded_rays`] in the lanes of `T` ([`Flat::occluded_lanes`]).
    #[inline(always)]
    fn blocked_rays<T: Sixteen, H>(&self, rays: &[Ray; RAYS], t_max: &[f32; RAYS], hit: H) -> u32
    where
        H: FnMut(&Ray, usize, f32) -> Option<(f32, f32, f32)>,
    {
        let (o, d) = rays_in_lanes::<T>(rays);
        T::bits(self.occluded_lanes(o, d, T::load(t_max), T::from_bits(u32::MAX), hit))
    }

    /// Whether any of the triangles' lanes near an edge (bit `16·block + lane` of
    /// `unsure`), decided by `hit`, blocks the ray before `t_max`.
    #[inline(always)]
    fn any_unsure<F>(&self, mut unsure: u64, t_max: f32, hit: &mut F) -> bool
    where
        F: FnMut(usize, f32) -> Option<(f32, f32, f32)>,
    {
        while unsure != 0 {
            let slot = unsure.trailing_zeros() as usize;
            unsure &= unsure - 1;
            if hit(self.prims[slot] as usize, t_max).is_some() {
                return true;
            }
        }
        false
    }
}

/// Rays in one batch of [`Flat::intersect_rays`] and [`Flat::occluded_rays`].
pub const RAYS: usize = 16;

/// The origins and directions of `rays` in the lanes of `T`.
#[inline(always)]
fn rays_in_lanes<T: Sixteen>(rays: &[Ray; RAYS]) -> (V3<T>, V3<T>) {
    let (mut o, mut d) = ([[0f32; RAYS]; 3], [[0f32; RAYS]; 3]);
    for (k, ray) in rays.iter().enumerate() {
        // (Arrays: a vector's index with a variable is a match.)
        let (ro, rd) = (ray.o.to_array(), ray.d.to_array());
        for a in 0..3 {
            o[a][k] = ro[a];
            d[a][k] = rd[a];
        }
    }
    // (Not a closure: a closure is compiled without its caller's target features.)
    let (o0, o1, o2) = (T::load(&o[0]), T::load(&o[1]), T::load(&o[2]));
    let (d0, d1, d2) = (T::load(&d[0]), T::load(&d[1]), T::load(&d[2]));
    (V3::new(o0, o1, o2), V3::new(d0, d1, d2))
}

/// The widest kernel the CPU runs, if any.
fn detect() -> Option<Kernel> {
    [Kernel::Avx512, Kernel::Avx]
        .into_iter()
        .find(|k| k.available())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Sphere;
    use glam::Vec3A;

    #[derive(Clone, Copy)]
    enum Prim {
        Tri(Triangle),
        Ball(Sphere),
    }

    /// The nearest hit by each primitive's own test, in index order, kept only where nearer:
    /// the answer `Flat` must give.
    fn reference(prims: &[Prim], ray: &Ray, t_max: f32) -> Option<(usize, f32, f32, f32)> {
        let mut best: Option<(usize, f32, f32, f32)> = None;
        for (i, p) in prims.iter().enumerate() {
            let bound = best.map_or(t_max, |b| b.1);
            if let Some((t, u, v)) = test(p, ray, bound) {
                best = Some((i, t, u, v));
            }
        }
        best
    }

    /// The flat set of `prims` with kernel `k`.
    fn flat_of(prims: &[Prim], k: Kernel) -> Flat {
        let (mut triangles, mut spheres) = (Vec::new(), Vec::new());
        for (i, p) in prims.iter().enumerate() {
            match *p {
                Prim::Tri(t) => triangles.push((i as u32, t)),
                Prim::Ball(s) => spheres.push((i as u32, s)),
            }
        }
        Flat::with_kernel(&triangles, &spheres, k).unwrap()
    }

    fn test(p: &Prim, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        match p {
            Prim::Tri(t) => t.intersect(ray, t_max),
            Prim::Ball(s) => s.intersect(ray, t_max).map(|t| (t, 0.0, 0.0)),
        }
    }

    /// A sphere and two triangles hit at exactly the same distance, in every order of the
    /// three (the ray along +z from the origin meets the sphere and both triangles at t = 1
    /// exactly; it runs along an edge of the second triangle, whose lane is then left to
    /// its own test): the lowest primitive wins, and nothing counts at or beyond `t_max`.
    #[test]
    fn spheres_and_triangles_tie_by_index() {
        let ray = Ray::new(Vec3A::ZERO, Vec3A::Z);
        let sphere = Prim::Ball(Sphere {
            center: Vec3A::new(0.0, 0.0, 2.0),
            radius: 1.0,
        });
        let v = |x: f32, y: f32| Vec3A::new(x, y, 1.0);
        let big = Prim::Tri(Triangle::new(v(-4.0, -4.0), v(4.0, -4.0), v(0.0, 4.0)));
        let edge = Prim::Tri(Triangle::new(v(0.0, -1.0), v(0.0, 1.0), v(2.0, 0.0)));
        for p in [&sphere, &big, &edge] {
            assert_eq!(
                test(p, &ray, f32::INFINITY).map(|h| h.0),
                Some(1.0),
                "not a tie"
            );
        }
        let orders = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for order in orders {
            // The three among filler triangles far off the ray.
            let far = |k: f32| {
                Prim::Tri(Triangle::new(
                    v(10.0 + k, 10.0),
                    v(11.0 + k, 10.0),
                    v(10.0 + k, 11.0),
                ))
            };
            let mut prims = vec![far(0.0), far(2.0)];
            for (slot, &which) in order.iter().enumerate() {
                prims.insert(2 * slot, [sphere, big, edge][which]);
            }
            for k in [Kernel::Avx512, Kernel::Avx]
                .into_iter()
                .filter(|k| k.available())
            {
                let f = flat_of(&prims, k);
                for t_max in [f32::INFINITY, 2.0, 1.0f32.next_up(), 1.0] {
                    let hit = |i: usize, t: f32| test(&prims[i], &ray, t);
                    let got = f.intersect(&ray, t_max, hit).map(|h| (h.0, h.1));
                    let want = (t_max > 1.0).then(|| {
                        (
                            prims
                                .iter()
                                .position(|p| test(p, &ray, t_max).is_some())
                                .unwrap(),
                            1.0,
                        )
                    });
                    assert_eq!(got, want, "{k:?}, order {order:?}, t_max {t_max}");
                    assert_eq!(f.occluded(&ray, t_max, hit), t_max > 1.0);
                    // The same in lanes (`rays.rs`), each lane's ray the same.
                    let find = |ray: &Ray, i: usize, t: f32| test(&prims[i], ray, t);
                    let blocked = f.occluded_rays(&[ray; RAYS], &[t_max; RAYS], find);
                    assert_eq!(blocked, if t_max > 1.0 { 0xffff } else { 0 });
                    if t_max == f32::INFINITY {
                        let lanes = f.intersect_rays(&[ray; RAYS], find);
                        assert!(lanes.iter().all(|h| h.map(|h| (h.0, h.1)) == want), "{k:?}");
                    }
                }
            }
        }
    }

    /// Both kernels against the reference, bit for bit, on sets of up to 64 triangles (a grid
    /// of coplanar quads, whose shared edges give hits exactly as near as each other, and
    /// random triangles, some slivers, some twice) with up to four spheres among them, and rays aimed at
    /// the insides, edges and vertices of triangles and past them.
    #[test]
    fn kernels_give_the_primitives_own_answers() {
        let kernels: Vec<Kernel> = [Kernel::Avx512, Kernel::Avx]
            .into_iter()
            .filter(|k| k.available())
            .collect();
        if kernels.is_empty() {
            return;
        }
        let mut state = 0x853c_49e6_748f_ea9bu64;
        let mut r = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut hits, mut ties, mut blocked, mut unblocked) = (0, 0, 0, 0);
        for case in 0..400 {
            let n = 1 + case % FLAT_MAX_SLOTS;
            let mut tris = Vec::new();
            // A grid of k × k quads in the plane z = 0.
            let k = 1 + case % 4;
            for (i, j) in (0..k).flat_map(|i| (0..k).map(move |j| (i, j))) {
                let p =
                    |a: usize, b: usize| Vec3A::new(a as f32 / k as f32, b as f32 / k as f32, 0.0);
                tris.push(Triangle::new(p(i, j), p(i + 1, j), p(i + 1, j + 1)));
                tris.push(Triangle::new(p(i, j), p(i + 1, j + 1), p(i, j + 1)));
            }
            // Over the grid, in its plane, a triangle of twice the area 16: with the grid's
            // quads (of twice the area 1/k², a power of two for k = 1, 2, 4), rays of dyadic
            // origin and direction give every triangle of the plane exactly the same t, so a
            // lane near a grid edge ties with the big triangle's lane, far from its edges.
            if k != 3 {
                let big = Triangle::new(
                    Vec3A::new(-1.0, -1.0, 0.0),
                    Vec3A::new(3.0, -1.0, 0.0),
                    Vec3A::new(-1.0, 3.0, 0.0),
                );
                if case % 2 == 0 {
                    tris.insert(0, big);
                } else {
                    tris.push(big);
                }
            }
            tris.truncate(n);
            while tris.len() < n {
                let mut v = || Vec3A::new(r(), r(), r()) * 2.0 - 1.0;
                let (a, b, c) = (v(), v(), v());
                tris.push(match tris.len() % 7 {
                    3 => Triangle::new(a, b, a + (c - a) * 1e-3),
                    // The same triangle twice (a doubled wall): hits exactly as near, far
                    // from any edge, in two lanes.
                    5 => tris[(r() * tris.len() as f32) as usize],
                    _ => Triangle::new(a, b, c),
                });
            }
            // Spheres at random places in the primitive order.
            let mut prims: Vec<Prim> = tris.iter().copied().map(Prim::Tri).collect();
            for _ in 0..case % (FLAT_MAX_SPHERES + 1) {
                let at = (r() * prims.len() as f32) as usize;
                let c = Vec3A::new(r(), r(), r()) * 2.0 - 1.0;
                prims.insert(
                    at,
                    Prim::Ball(Sphere {
                        center: c,
                        radius: 0.05 + 0.3 * r(),
                    }),
                );
            }
            let sets: Vec<Flat> = kernels.iter().map(|&k| flat_of(&prims, k)).collect();
            let key = |h: Option<(usize, f32, f32, f32)>| {
                h.map(|(i, t, u, v)| (i, t.to_bits(), u.to_bits(), v.to_bits()))
            };
            let mut batch = Vec::new();
            for ray_case in 0..200 {
                let aim = tris[(r() * tris.len() as f32) as usize];
                let (a, b) = (r(), r());
                let (a, b) = match ray_case % 5 {
                    0 => (a, 0.0),
                    1 => (0.0, 0.0),
                    2 => (a, 1.0 - a),
                    3 => (a * 1.4 - 0.2, b * 1.4 - 0.2),
                    _ => (a * 0.5, b * 0.5),
                };
                let target = aim.p0 + (aim.p1 - aim.p0) * a + (aim.p2 - aim.p0) * b;
                let o = Vec3A::new(r(), r(), r()) * 6.0 - 3.0;
                let ray = if ray_case % 4 == 3 {
                    // Dyadic, at a point of a grid line (see above).
                    let q = |x: f32, steps: f32| (x * steps).floor() / steps;
                    let o = Vec3A::new(
                        q(r(), 8.0) * 2.0 - 1.0,
                        q(r(), 8.0) * 2.0 - 1.0,
                        1.0 + q(r(), 4.0),
                    );
                    let line = (r() * (k + 1) as f32).floor() / k as f32;
                    let along = q(r(), 16.0);
                    let target = if r() < 0.5 {
                        Vec3A::new(line, along, 0.0)
                    } else {
                        Vec3A::new(along, line, 0.0)
                    };
                    Ray::new(o, target - o)
                } else {
                    Ray::new(o, target - o)
                };
                let t_max = if ray_case % 3 == 0 {
                    0.5 + r()
                } else {
                    f32::INFINITY
                };
                let want = reference(&prims, &ray, t_max);
                if let Some((i, t, ..)) = want {
                    hits += 1;
                    ties += prims[i + 1..]
                        .iter()
                        .any(|p| test(p, &ray, t.next_up()).is_some_and(|h| h.0 == t))
                        as u32;
                }
                let occluded = prims.iter().any(|p| test(p, &ray, t_max).is_some());
                if occluded {
                    blocked += 1;
                } else {
                    unblocked += 1;
                }
                for (f, k) in sets.iter().zip(&kernels) {
                    let hit = |i: usize, t: f32| test(&prims[i], &ray, t);
                    assert_eq!(
                        key(f.intersect(&ray, t_max, hit)),
                        key(want),
                        "{k:?}, case {case}, ray {ray_case}"
                    );
                    assert_eq!(
                        f.occluded(&ray, t_max, hit),
                        occluded,
                        "{k:?}, case {case}, ray {ray_case}"
                    );
                }
                batch.push((ray, t_max));
            }
            // Sixteen rays at a time, in the lanes (`rays.rs`): the same answers.
            for rays in batch.chunks_exact(RAYS) {
                let t_max: [f32; RAYS] = std::array::from_fn(|k| rays[k].1);
                let rays: [Ray; RAYS] = std::array::from_fn(|k| rays[k].0);
                let find = |ray: &Ray, i: usize, t: f32| test(&prims[i], ray, t);
                for (f, k) in sets.iter().zip(&kernels) {
                    let got = f.intersect_rays(&rays, find);
                    let blocked = f.occluded_rays(&rays, &t_max, find);
                    for (j, ray) in rays.iter().enumerate() {
                        let want = reference(&prims, ray, f32::INFINITY);
                        assert_eq!(key(got[j]), key(want), "{k:?}, case {case}, lane {j}");
                        let occluded = prims.iter().any(|p| test(p, ray, t_max[j]).is_some());
                        assert_eq!(blocked >> j & 1 != 0, occluded, "{k:?}, case {case}");
                    }
                }
            }
        }
        // Each kind of answer came up often enough to have been checked.
        assert!(
            hits > 10_000 && blocked > 10_000 && unblocked > 10_000,
            "{hits} {blocked} {unblocked}"
        );
        eprintln!("hits {hits}, ties {ties}");
        assert!(ties > 50, "only {ties} ties");
    }
}
