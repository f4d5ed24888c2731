//! A tile's samples through the lanes: the groups of sixteen paths, their state between
//! steps, and the loop that feeds them camera samples and steps them.

use super::rng::LaneSampler;
use crate::simd::{lanes_of, Float, Vector3};
use super::simd::{F, M, U, V3};
use super::{Bits, LaneMask, Trace, Wavefront};
use crate::accel::{RayPacket, PACKET};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::scene::Interaction;
use glam::Vec3A;
use crate::film::PixelSums;
use crate::render::{RenderStats, TilePixel};

/// The state of the sixteen paths, a lane each, between steps.
pub(super) struct Lanes<S> {
    pub(super) o: [[f32; 16]; 3],
    pub(super) d: [[f32; 16]; 3],
    pub(super) beta: [[f32; 16]; 3],
    pub(super) l: [[f32; 16]; 3],
    /// η² accumulated over refractions (for the roulette).
    pub(super) eta2: [f32; 16],
    pub(super) prev_p: [[f32; 16]; 3],
    pub(super) prev_pdf: [f32; 16],
    pub(super) depth: [u32; 16],
    /// The tile pixel (index into `pixels`) of each lane's sample.
    pub(super) pixel: [u32; 16],
    pub(super) rng: S,
    /// Lanes holding a path.
    pub(super) active: Bits,
    /// Lanes whose path got to its vertex by a non-specular BSDF sample (for MIS on
    /// emitter hits).
    pub(super) has_prev: Bits,
    /// Lanes whose path ended at the last step, their samples not yet on the film.
    pub(super) done: Bits,
    /// Lanes whose ray is their camera ray from a pinhole, not yet traced (from the
    /// camera's eye).
    pub(super) fresh: Bits,
    /// The shadow rays of the last step's light samples, waiting to be traced.
    pub(super) shadow: Shadows,
    /// With `Trace::Scene`, the active lanes' hits, found for all groups at once before
    /// their steps (`Wavefront::trace_groups`).
    pub(super) hits: [Option<Interaction>; 16],
}

/// A group's shadow rays between `front` and `back` (one light sample a vertex).
pub(super) struct Shadows {
    /// The lanes that sampled the light, those whose sample needs a shadow ray, and of
    /// those the ones blocked (set by `shadows`).
    pub(super) nee: Bits,
    pub(super) lanes: Bits,
    pub(super) blocked: Bits,
    pub(super) o: [[f32; 16]; 3],
    pub(super) d: [[f32; 16]; 3],
    /// How far each ray must be clear (1 − `SHADOW_EPSILON` to a point, ∞ to a light at
    /// infinity).
    pub(super) t_max: [f32; 16],
    /// What `l += β·lit` adds: β times the contribution where the ray is clear, β·0 where
    /// it is blocked or there is no ray.
    pub(super) lit: [[f32; 16]; 3],
    pub(super) dark: [[f32; 16]; 3],
}

/// Groups of sixteen lanes whose shadow rays are traced together. Each group's light
/// samples leave shadow rays in about half its lanes (the others' paths end, or their sample
/// lies behind the surface: 58 % of them carry one in the Cornell box), so each group alone
/// would trace vectors half full; four groups' rays pack into about three (and their answers
/// into a u64). Measured on the Cornell box by brute force (256², 64 spp, one thread, three
/// rounds alternating): 1.45–1.72 s against 1.59–1.85 s for one group; two groups were no
/// faster, six or eight no faster than four. Brute force keeps this many groups in flight.
pub(super) const POOL: usize = 4;

/// Groups of sixteen lanes a tile keeps in flight through the scene's queries
/// ([`Trace::Scene`]): all their closest hits go to `Scene::intersect_many` in one call,
/// whose interleaved traversals overlap more cache misses with more rays (the gallery, one
/// thread, 256², 32 spp, three rounds alternating: 0.90–0.91 M samples/s with four groups,
/// 0.92–0.94 with sixteen, the stream's 256 paths a tile 0.86–0.91; the bunny box level).
pub(super) const GROUPS: usize = 16;

impl Wavefront<'_> {
    lanes_fn! {
    pub(super) unsafe fn run<S: LaneSampler + Clone>(
        &self,
        rng: S,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        let lanes = || Lanes {
            o: [[0.0; 16]; 3],
            d: [[0.0; 16]; 3],
            beta: [[0.0; 16]; 3],
            l: [[0.0; 16]; 3],
            eta2: [1.0; 16],
            prev_p: [[0.0; 16]; 3],
            prev_pdf: [0.0; 16],
            depth: [0; 16],
            pixel: [0; 16],
            rng: rng.clone(),
            active: 0,
            has_prev: 0,
            done: 0,
            fresh: 0,
            shadow: Shadows {
                nee: 0,
                lanes: 0,
                blocked: 0,
                o: [[0.0; 16]; 3],
                d: [[0.0; 16]; 3],
                t_max: [0.0; 16],
                lit: [[0.0; 16]; 3],
                dark: [[0.0; 16]; 3],
            },
            hits: [None; 16],
        };
        // Through the scene, many groups' closest hits in flight. By brute force, a pool of
        // groups' shadow rays packed together; several light samples a vertex are traced as
        // each lane's packets, in `front`: nothing to pool, so one group. (Only the groups
        // used are made: each is a few kilobytes, which a tile's start would otherwise copy
        // for nothing.)
        let n = match self.trace {
            Trace::Scene => GROUPS,
            Trace::Lanes if self.shadow_rays > 1 => 1,
            Trace::Lanes => POOL,
        };
        let mut all: Vec<Lanes<S>> = (0..n).map(|_| lanes()).collect();
        let groups = &mut all[..];
        // The next camera sample: pixel k, sample i.
        let (mut k, mut i) = (0usize, pixels.first().map_or(0, |p| p.samples.0));
        let (mut px, mut py) = ([0f32; 16], [0f32; 16]);
        let mut rays = Vec::with_capacity(16 * GROUPS);
        let mut hits = Vec::with_capacity(16 * GROUPS);
        loop {
            for st in groups.iter_mut() {
                // Free lanes take the next samples.
                let mut fresh: Bits = 0;
                let mut free = !st.active;
                while free != 0 {
                    while k < pixels.len() && i >= pixels[k].samples.1 {
                        k += 1;
                        i = pixels.get(k).map_or(0, |p| p.samples.0);
                    }
                    if k == pixels.len() {
                        break;
                    }
                    let l = free.trailing_zeros() as usize;
                    free &= free - 1;
                    let pix = &pixels[k];
                    let pixel = pix.gy as u64 * self.width as u64 + pix.gx as u64;
                    st.rng.start(l, self.sampler, self.seed, pixel, i as u64);
                    st.pixel[l] = k as u32;
                    (px[l], py[l]) = (pix.gx as f32, pix.gy as f32);
                    fresh |= 1 << l;
                    i += 1;
                }
                if fresh != 0 {
                    self.start(camera, st, fresh, &px, &py);
                }
            }
            if groups.iter().all(|st| st.active == 0) {
                break;
            }
            if self.trace == Trace::Scene {
                self.trace_groups(groups, &mut rays, &mut hits);
            }
            for st in groups.iter_mut().filter(|st| st.active != 0) {
                self.front(st, stats);
            }
            for pool in groups.chunks_mut(POOL) {
                self.shadows(pool, &mut rays);
            }
            for st in groups.iter_mut() {
                self.back(st, pixels, sums, stats);
            }
        }
    }
    }

    /// The closest hits of every group's active lanes ([`Trace::Scene`]), into each group's
    /// `hits`: the camera rays, which share the eye, in packets of sixteen
    /// (`Scene::intersect_packet`; the groups' fresh lanes hold consecutive camera samples),
    /// and the other rays of all groups together (`Scene::intersect_many`, which interleaves
    /// them where the scene outgrows the cache).
    fn trace_groups<S>(
        &self,
        groups: &mut [Lanes<S>],
        rays: &mut Vec<Ray>,
        hits: &mut Vec<Option<Interaction>>,
    ) {
        // The camera rays, by group and lane (a single one is better served by its own
        // traversal), and the lanes of each group that the packets leave.
        let mut fresh = [(0, 0); 16 * GROUPS];
        let mut n = 0;
        for (g, st) in groups.iter().enumerate() {
            for l in lanes_of(u32::from(st.fresh & st.active)) {
                fresh[n] = (g, l);
                n += 1;
            }
        }
        let mut rest: [Bits; GROUPS] =
            std::array::from_fn(|g| groups.get(g).map_or(0, |st| st.active));
        if n > 1 {
            for chunk in fresh[..n].chunks(PACKET) {
                self.trace_packet(groups, chunk);
            }
            for (rest, st) in rest.iter_mut().zip(groups.iter()) {
                *rest &= !st.fresh;
            }
        }
        rays.clear();
        for (st, &rest) in groups.iter().zip(&rest) {
            let (o, d) = (&st.o, &st.d);
            rays.extend(lanes_of(u32::from(rest)).map(|l| {
                Ray::new(
                    Vec3A::new(o[0][l], o[1][l], o[2][l]),
                    Vec3A::new(d[0][l], d[1][l], d[2][l]),
                )
            }));
        }
        hits.clear();
        hits.resize(rays.len(), None);
        self.scene.intersect_many(rays, hits);
        let mut next = hits.iter();
        for (st, &rest) in groups.iter_mut().zip(&rest) {
            for l in lanes_of(u32::from(rest)) {
                st.hits[l] = *next.next().expect("one hit per ray");
            }
            st.fresh = 0;
        }
    }

    /// The closest hits of the camera rays of `chunk` (up to sixteen (group, lane) pairs,
    /// the rays from one origin) in one packet, into their groups' `hits`.
    fn trace_packet<S>(&self, groups: &mut [Lanes<S>], chunk: &[(usize, usize)]) {
        let origin = |(g, l): (usize, usize)| {
            let o = &groups[g].o;
            Vec3A::new(o[0][l], o[1][l], o[2][l])
        };
        debug_assert!(chunk.iter().all(|&gl| origin(gl) == origin(chunk[0])));
        let mut pk = RayPacket {
            o: origin(chunk[0]),
            d: [[0.0; PACKET]; 3],
            t_max: [f32::INFINITY; PACKET],
        };
        for (k, &(g, l)) in chunk.iter().enumerate() {
            for a in 0..3 {
                pk.d[a][k] = groups[g].d[a][l];
            }
        }
        let mut out = [None; PACKET];
        self.scene.intersect_packet(&pk, (1 << chunk.len()) - 1, &mut out);
        for (&(g, l), hit) in chunk.iter().zip(out) {
            groups[g].hits[l] = hit;
        }
    }

    lanes_fn! {
    /// Camera rays for the lanes of `fresh` (`Camera::sample_ray`: the pixel offset the
    /// sample's first request, a thin lens's point the second), and their paths' initial
    /// state. A pinhole's rays are made in the lanes and marked fresh: they share the eye,
    /// so `trace_groups` traces them as packets. Other cameras' are each lane's
    /// `Camera::generate_ray` or `generate_ray_lens`.
    #[inline]
    unsafe fn start<S: LaneSampler + Clone>(
        &self,
        cam: &Camera,
        st: &mut Lanes<S>,
        bits: Bits,
        px: &[f32; 16],
        py: &[f32; 16],
    ) {
        let fresh = M::from_bits(bits);
        let [ux, uy] = st.rng.next::<2>(fresh);
        let (o, d) = if cam.is_pinhole() {
            let s = (F::load(px) + ux) / F::splat(cam.width as f32);
            let t = (F::load(py) + uy) / F::splat(cam.height as f32);
            let p: V3 = cam.plane_point_lanes(s, t);
            let eye = V3::broadcast(cam.eye);
            st.fresh |= bits;
            (eye, (p - eye).normalize())
        } else {
            // (No closures here: they would be compiled without the lanes' features.)
            let lens = if cam.samples_lens() {
                let [lx, ly] = st.rng.next::<2>(fresh);
                Some((lx.to_array(), ly.to_array()))
            } else {
                None
            };
            let (ux, uy) = (ux.to_array(), uy.to_array());
            let (mut o, mut d) = ([[0f32; 16]; 3], [[0f32; 16]; 3]);
            for l in lanes_of(u32::from(bits)) {
                let (x, y, u) = (px[l] as u32, py[l] as u32, glam::Vec2::new(ux[l], uy[l]));
                let ray = match &lens {
                    Some((lx, ly)) => {
                        cam.generate_ray_lens(x, y, u, glam::Vec2::new(lx[l], ly[l]))
                    }
                    None => cam.generate_ray(x, y, u),
                };
                let (ro, rd) = (ray.o.to_array(), ray.d.to_array());
                for a in 0..3 {
                    (o[a][l], d[a][l]) = (ro[a], rd[a]);
                }
            }
            (V3::load(&o), V3::load(&d))
        };
        let keep = |a: &mut [[f32; 16]; 3], x: V3| V3::select(fresh, x, V3::load(a)).store(a);
        keep(&mut st.o, o);
        keep(&mut st.d, d);
        keep(&mut st.beta, V3::splat([1.0; 3]));
        keep(&mut st.l, V3::zero());
        F::select(fresh, F::splat(1.0), F::load(&st.eta2)).store(&mut st.eta2);
        U::select(fresh, U::splat(0), U::load(&st.depth)).store(&mut st.depth);
        st.has_prev &= !bits;
        st.active |= bits;
    }
    }
}

