//! The stream path tracer: a tile's camera samples as a pool of [`POOL`] paths in flight,
//! traced a segment at a time for all of them — gather the rays of the live paths, find
//! their closest hits in one call ([`Scene::intersect_many`]), then advance each path by one
//! vertex — for any scene, camera, material, texture and light. It renders the path
//! tracer on CPUs without AVX2 (and with `--backend stream`); elsewhere the sixteen-lane
//! wavefront (`integrator::wavefront`) renders every scene the path tracer does.
//!
//! The maths of a vertex is [`PathState::step`], the same function that the one-path loop
//! [`super::path::li`] runs, so each sample's value is the same bits by construction; only
//! the order in which samples finish changes, and the film's fixed-point sums
//! ([`PixelSums`]) are exact in any order. A path that ends adds its value to its pixel and
//! its slot takes the tile's next camera sample, so the pool stays full until the tile's
//! samples run out, however long each path is (no depth bound, no compaction pass).
//!
//! Batching the rays is what lets intersection overlap the memory latency of several
//! traversals (interleaved, prefetched traversal in `intersect_many`) instead of one
//! traversal's dependent loads at a time: the argument of Laine, Karras and Aila, "Megakernels
//! Considered Harmful: Wavefront Path Tracing on GPUs" (HPG 2013), for splitting the path
//! loop into a trace stage and a shade stage over queues of paths, as pbrt-v4's wavefront
//! integrator does (`src/pbrt/wavefront/`). It also gathers the camera rays of consecutive
//! samples, which share a pinhole camera's eye, into packets that traverse the tree once for
//! up to sixteen rays (`Scene::intersect_packet`). With one light sample a vertex (the
//! default), the step hands back its shadow ray, and a round's shadow rays are traced
//! together too ([`Scene::occluded_many`]) before the paths that ended add their values,
//! those from the first vertices of consecutive samples (nearby points, towards the lights)
//! as packets of their own origins ([`Scene::occluded_origins`]); with several light
//! samples a vertex, they stay inside the step (traced as one packet a vertex,
//! [`super::nee`]).

use super::path::{PathState, Shadow};
use crate::accel::{RayPacket, PACKET};
use crate::camera::Camera;
use crate::film::PixelSums;
use crate::geometry::Ray;
use crate::render::{self, RenderSettings, RenderStats, TilePixel};
use crate::sampler::Sampler;
use crate::scene::{Interaction, Scene};
use glam::Vec3A;

/// Paths in flight per tile (and rays per [`Scene::intersect_many`] call). With interleaved
/// traversal, 256 and 512 rendered the gallery fastest (16 and 64 less so); with one ray
/// after another, the size makes no difference (docs/performance.md).
pub const POOL: usize = 256;

/// A path in flight: its state, its camera sample's random numbers and its pixel (index
/// into the tile's pixels).
struct Slot {
    path: PathState,
    sampler: Sampler,
    k: usize,
    /// Whether the path's ray is its camera ray (until the path's step at its hit).
    fresh: bool,
}

/// The tile's camera samples, pixel by pixel, each pixel's in index order.
struct Queue<'a> {
    pixels: &'a [TilePixel],
    k: usize,
    i: u32,
}

impl Iterator for Queue<'_> {
    type Item = (usize, u32);

    #[inline]
    fn next(&mut self) -> Option<(usize, u32)> {
        while let Some(p) = self.pixels.get(self.k) {
            if self.i < p.samples.1 {
                self.i += 1;
                return Some((self.k, self.i - 1));
            }
            self.k += 1;
            self.i = self.pixels.get(self.k).map_or(0, |p| p.samples.0);
        }
        None
    }
}

/// Renders the samples of a tile's pixels (`pixels[k].samples` into `sums[k]`) as a
/// stream (see the module documentation), with the same sums as one
/// [`super::path::li`] at a time.
pub(crate) fn render_tile(
    scene: &Scene,
    s: &RenderSettings,
    camera: &Camera,
    pixels: &[TilePixel],
    sums: &mut [PixelSums],
    stats: &mut RenderStats,
) {
    #[cfg(target_arch = "x86_64")]
    if super::has_x86_64_v3() {
        // SAFETY: the CPU has the features, checked just above.
        return unsafe { render_tile_v3(scene, s, camera, pixels, sums, stats) };
    }
    render_tile_portable(scene, s, camera, pixels, sums, stats)
}

/// [`render_tile`] compiled for x86-64-v3, as [`super::li`] is.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn render_tile_v3(
    scene: &Scene,
    s: &RenderSettings,
    camera: &Camera,
    pixels: &[TilePixel],
    sums: &mut [PixelSums],
    stats: &mut RenderStats,
) {
    render_tile_portable(scene, s, camera, pixels, sums, stats)
}

#[inline(always)]
fn render_tile_portable(
    scene: &Scene,
    s: &RenderSettings,
    camera: &Camera,
    pixels: &[TilePixel],
    sums: &mut [PixelSums],
    stats: &mut RenderStats,
) {
    let p = &s.params;
    let mut queue = Queue {
        pixels,
        k: 0,
        i: pixels.first().map_or(0, |p| p.samples.0),
    };
    let mut pool: Vec<Slot> = Vec::with_capacity(POOL);
    while pool.len() < POOL {
        match start(s, camera, &mut queue, sums, stats) {
            Some(slot) => pool.push(slot),
            None => break,
        }
    }
    let mut rays = Rays::default();
    let mut hits: Vec<Option<Interaction>> = vec![None; POOL];
    let mut shadows = Shadows::default();
    let mut ended: Vec<bool> = vec![false; POOL];
    while !pool.is_empty() {
        let hits = &mut hits[..pool.len()];
        rays.trace(scene, &mut pool, hits);
        shadows.clear();
        for (j, ((slot, hit), ended)) in pool.iter_mut().zip(hits).zip(&mut ended).enumerate() {
            let (alive, shadow) =
                slot.path
                    .step(scene, hit.as_ref(), &mut slot.sampler, p, &mut stats.rays);
            *ended = !alive;
            let first = std::mem::take(&mut slot.fresh);
            if let Some(s) = shadow {
                shadows.push(j, s, first);
            }
        }
        shadows.trace(scene, &mut pool);
        let mut live = pool.len();
        for (slot, _) in pool.iter_mut().zip(&ended).filter(|(_, &ended)| ended) {
            render::add_sample(&mut sums[slot.k], &pixels[slot.k], slot.path.l, stats);
            match start(s, camera, &mut queue, sums, stats) {
                Some(next) => *slot = next,
                None => {
                    // The queue is empty: this slot ends with its path (marked by k).
                    slot.k = usize::MAX;
                    live -= 1;
                }
            }
        }
        if live < pool.len() {
            pool.retain(|slot| slot.k != usize::MAX);
        }
    }
}

/// The rays of a round's paths, traced together: the camera rays that share an origin (a
/// pinhole camera's) in packets of up to sixteen, in slot order, so that each packet holds
/// consecutive camera samples (a pixel's, then its neighbours'), which traverse nearly the
/// same nodes ([`Scene::intersect_packet`]); the others in one call
/// ([`Scene::intersect_many`]).
#[derive(Default)]
struct Rays {
    /// The rays not in packets, and their slots.
    rays: Vec<Ray>,
    slots: Vec<usize>,
    hits: Vec<Option<Interaction>>,
}

impl Rays {
    /// The closest hit of each slot's ray, into `hits` by slot.
    #[inline(always)]
    fn trace(&mut self, scene: &Scene, pool: &mut [Slot], hits: &mut [Option<Interaction>]) {
        self.rays.clear();
        self.slots.clear();
        let mut packet = Packet::default();
        for (j, slot) in pool.iter_mut().enumerate() {
            let ray = slot.path.ray;
            if !slot.fresh {
                self.rays.push(ray);
                self.slots.push(j);
                continue;
            }
            if packet.n == PACKET || (packet.n > 0 && packet.pk.o != ray.o) {
                packet.trace(scene, hits, self);
            }
            packet.push(j, ray);
        }
        packet.trace(scene, hits, self);
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        scene.intersect_many(&self.rays, &mut self.hits);
        for (&j, hit) in self.slots.iter().zip(&self.hits) {
            hits[j] = *hit;
        }
    }
}

/// Camera rays from one origin being gathered, and their slots.
struct Packet {
    pk: RayPacket,
    slots: [usize; PACKET],
    n: usize,
}

impl Default for Packet {
    fn default() -> Packet {
        Packet {
            pk: RayPacket {
                o: Vec3A::ZERO,
                d: [[0.0; PACKET]; 3],
                t_max: [f32::INFINITY; PACKET],
            },
            slots: [0; PACKET],
            n: 0,
        }
    }
}

impl Packet {
    #[inline(always)]
    fn push(&mut self, slot: usize, ray: Ray) {
        let (pk, n) = (&mut self.pk, self.n);
        pk.o = ray.o;
        (pk.d[0][n], pk.d[1][n], pk.d[2][n]) = (ray.d.x, ray.d.y, ray.d.z);
        self.slots[n] = slot;
        self.n += 1;
    }

    /// Traces the packet's rays into `hits` by slot and empties it; a single ray joins
    /// `rest`'s, which its own traversal serves better.
    #[inline(always)]
    fn trace(&mut self, scene: &Scene, hits: &mut [Option<Interaction>], rest: &mut Rays) {
        match self.n {
            0 => {}
            1 => {
                rest.rays.push(self.pk.ray(0));
                rest.slots.push(self.slots[0]);
            }
            n => {
                let mut out = [None; PACKET];
                scene.intersect_packet(&self.pk, (1 << n) - 1, &mut out);
                for (&j, hit) in self.slots[..n].iter().zip(&out) {
                    hits[j] = *hit;
                }
            }
        }
        self.n = 0;
    }
}

/// A round's shadow rays: those from paths' first vertices apart (`first`), the others in
/// `rest`.
#[derive(Default)]
struct Shadows {
    first: ShadowRays,
    rest: ShadowRays,
}

/// Shadow rays, their slots, and the answers.
#[derive(Default)]
struct ShadowRays {
    slots: Vec<(usize, Shadow)>,
    rays: Vec<Ray>,
    t_max: Vec<f32>,
    occluded: Vec<bool>,
}

impl ShadowRays {
    fn clear(&mut self) {
        self.slots.clear();
        self.rays.clear();
        self.t_max.clear();
        self.occluded.clear();
        self.occluded.resize(POOL, false);
    }

    #[inline(always)]
    fn push(&mut self, slot: usize, s: Shadow) {
        self.rays.push(s.ray);
        self.t_max.push(s.t_max);
        self.slots.push((slot, s));
    }

    /// Gives each ray's answer to its slot's path.
    #[inline(always)]
    fn give(&self, pool: &mut [Slot]) {
        for ((j, s), &occluded) in self.slots.iter().zip(&self.occluded) {
            pool[*j].path.light(s, occluded);
        }
    }
}

impl Shadows {
    fn clear(&mut self) {
        self.first.clear();
        self.rest.clear();
    }

    /// A shadow ray of slot `slot`'s path, from its first vertex where `first`. (One to a
    /// light at infinity, whose directions are spread over the sphere, goes with the
    /// others.)
    #[inline(always)]
    fn push(&mut self, slot: usize, s: Shadow, first: bool) {
        match first && s.t_max.is_finite() {
            true => self.first.push(slot, s),
            false => self.rest.push(slot, s),
        }
    }

    /// Traces the rays and gives each its slot's path: those from first vertices, which
    /// consecutive slots' fresh paths left (consecutive samples of a pixel, from nearly
    /// one point towards the lights), sixteen to a packet ([`Scene::occluded_origins`]);
    /// the others together ([`Scene::occluded_many`]).
    #[inline(always)]
    fn trace(&mut self, scene: &Scene, pool: &mut [Slot]) {
        let f = &mut self.first;
        let n = f.rays.len();
        scene.occluded_origins(&f.rays, &f.t_max, &mut f.occluded[..n]);
        let r = &mut self.rest;
        let n = r.rays.len();
        scene.occluded_many(&r.rays, &r.t_max, &mut r.occluded[..n]);
        self.first.give(pool);
        self.rest.give(pool);
    }
}

/// The queue's next camera sample as a path (camera samples of a path that traces no
/// segment, `max_depth` 0, add their zero at once); None once the queue is empty.
#[inline(always)]
fn start(
    s: &RenderSettings,
    camera: &Camera,
    queue: &mut Queue,
    sums: &mut [PixelSums],
    stats: &mut RenderStats,
) -> Option<Slot> {
    loop {
        let (k, i) = queue.next()?;
        let (sampler, ray) = render::camera_sample(s, camera, &queue.pixels[k], i);
        match PathState::new(ray, &s.params) {
            Some(path) => {
                let fresh = true;
                return Some(Slot {
                    path,
                    sampler,
                    k,
                    fresh,
                });
            }
            None => render::add_sample(&mut sums[k], &queue.pixels[k], crate::Color::ZERO, stats),
        }
    }
}
