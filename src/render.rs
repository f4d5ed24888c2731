//! The render loop: image tiles in parallel (rayon), each pixel's samples in order, each
//! sample with its own random stream, so the image is the same on any number of threads.

use crate::film::{Film, PixelSums};
use crate::integrator::{self, Integrator, IntegratorKind, IntegratorParams, RayStats};
use crate::sampler::{Sampler, SamplerKind};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Tile edge in pixels: small enough to balance two to many cores, large enough that the
/// per-tile bookkeeping vanishes.
pub const TILE: u32 = 16;

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    pub camera: Option<String>,
    pub params: IntegratorParams,
    pub sampler: SamplerKind,
    /// Worker threads; None = one per core.
    pub threads: Option<usize>,
    /// Render only this window (x, y, width, height) of the width × height image.
    pub crop: Option<[u32; 4]>,
    /// How the samples are computed; the image does not depend on it.
    pub backend: Backend,
}

/// How the path tracer's samples run: an execution policy of the render, not a property of
/// the scene. Every backend gives the same bits ([`crate::integrator::wavefront`] follows
/// the scalar path's operations lane for lane), so it is not part of a checkpoint's
/// settings: a render may be resumed on another machine with another backend.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// The fastest that the CPU, the scene and the integrator allow: the wavefront where it
    /// takes the scene and camera, else the stream.
    #[default]
    Auto,
    /// One path at a time.
    Scalar,
    /// Sixteen paths at a time in one AVX-512 register; refused where the CPU or the scene
    /// cannot.
    Avx512,
    /// Sixteen paths at a time in two AVX2 registers; refused likewise.
    Avx2,
    /// A pool of paths per tile whose rays are traced in batches
    /// ([`crate::integrator::stream`]): any scene, camera and CPU.
    Stream,
}

impl Backend {
    pub fn parse(s: &str) -> Option<Backend> {
        Some(match s {
            "auto" => Backend::Auto,
            "scalar" => Backend::Scalar,
            "avx512" => Backend::Avx512,
            "avx2" => Backend::Avx2,
            "stream" => Backend::Stream,
            _ => return None,
        })
    }

    pub fn name(&self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Scalar => "scalar",
            Backend::Avx512 => "avx512",
            Backend::Avx2 => "avx2",
            Backend::Stream => "stream",
        }
    }
}

impl RenderSettings {
    /// The film's size and its offset in the full image.
    pub fn window(&self) -> (u32, u32, u32, u32) {
        match self.crop {
            Some([x, y, w, h]) => (x, y, w, h),
            None => (0, 0, self.width, self.height),
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub elapsed: Duration,
    pub samples: u64,
    pub rays: RayStats,
    /// Samples that came out NaN or infinite and were dropped, and the first such pixel.
    pub dropped: u64,
    pub first_dropped: Option<(u32, u32)>,
    /// `photon`: photons stored in the maps, their memory and the time to trace and build.
    pub photons_stored: u64,
    pub photon_bytes: u64,
    pub photon_time: Duration,
    /// Tiles skipped because the render was told to stop ([`render_ranges`]).
    pub skipped_tiles: u64,
    /// The render was told to stop before it rendered every sample it was asked for.
    pub interrupted: bool,
}

impl RenderStats {
    /// Adds the counts of a later call (elapsed times add up).
    pub fn add(&mut self, o: &RenderStats) {
        self.elapsed += o.elapsed;
        self.samples += o.samples;
        self.rays.add(&o.rays);
        self.dropped += o.dropped;
        if self.first_dropped.is_none() {
            self.first_dropped = o.first_dropped;
        }
        self.skipped_tiles += o.skipped_tiles;
        self.interrupted |= o.interrupted;
        self.photons_stored += o.photons_stored;
        self.photon_bytes += o.photon_bytes;
        self.photon_time += o.photon_time;
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("no camera named '{0}' in the scene (it has: {1})")]
    NoCamera(String, String),
    #[error("the scene has no camera")]
    NoCameras,
    #[error("{0}")]
    Threads(String),
    /// An integrator or backend that cannot render these settings.
    #[error("{0}")]
    Unsupported(String),
    /// Told to stop while the integrator was being made ready (photon maps).
    #[error("interrupted before rendering began")]
    Interrupted,
}

/// The camera the settings name, built for the image size.
pub fn camera_for(scene: &Scene, s: &RenderSettings) -> Result<crate::camera::Camera, RenderError> {
    let cam_desc = match (&s.camera, scene.camera(s.camera.as_deref())) {
        (_, Some(c)) => c,
        (Some(name), None) => {
            let names: Vec<&str> = scene.cameras.iter().map(|(n, _)| n.as_str()).collect();
            return Err(RenderError::NoCamera(name.clone(), names.join(", ")));
        }
        (None, None) => return Err(RenderError::NoCameras),
    };
    Ok(cam_desc.build(s.width, s.height))
}

/// Renders samples [first, first + count) of every pixel into `film`.
pub fn render_samples(
    scene: &Scene,
    s: &RenderSettings,
    film: &mut Film,
    first: u32,
    count: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderStats, RenderError> {
    let integrator = integrator::prepare(scene, s, &|| false)?;
    let mut next = vec![first; film.count.len()];
    let until = |_| first + count;
    let mut stats = integrator.setup_stats();
    stats.add(&render_ranges(
        &*integrator,
        scene,
        s,
        film,
        &mut next,
        &until,
        &|| false,
        progress,
    )?);
    Ok(stats)
}

/// Runs `work` on `s.threads` worker threads (or rayon's global pool).
pub fn with_threads<R: Send>(
    s: &RenderSettings,
    work: impl FnOnce() -> R + Send,
) -> Result<R, RenderError> {
    match s.threads {
        Some(t) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| RenderError::Threads(e.to_string()))?
            .install(work)),
        None => Ok(work()),
    }
}

/// Renders the samples of a tile's pixels into their sums (`sums[k]` for `pixels[k]`): all
/// at once where the integrator can, else one [`Integrator::li`] at a time.
fn render_tile(
    integrator: &dyn Integrator,
    s: &RenderSettings,
    camera: &crate::camera::Camera,
    pixels: &[TilePixel],
    sums: &mut [PixelSums],
    stats: &mut RenderStats,
) {
    if integrator.render_tile(camera, pixels, sums, stats) {
        return;
    }
    for (p, px) in pixels.iter().zip(sums) {
        for i in p.samples.0..p.samples.1 {
            let (mut sampler, ray) = camera_sample(s, camera, p, i);
            let l = integrator.li(ray, &mut sampler, &mut stats.rays);
            add_sample(px, p, l, stats);
        }
    }
}

/// Camera sample `i` of pixel `p`: its random numbers and its ray (what every way of
/// rendering a tile starts a sample with).
#[inline(always)]
pub(crate) fn camera_sample(
    s: &RenderSettings,
    camera: &crate::camera::Camera,
    p: &TilePixel,
    i: u32,
) -> (Sampler, crate::geometry::Ray) {
    // Random numbers follow the pixel of the full image, so a crop renders the same
    // values as the whole image does there.
    let pixel = p.gy as u64 * s.width as u64 + p.gx as u64;
    let mut sampler = Sampler::for_sample(s.sampler, s.seed, pixel, i as u64);
    let ray = camera.sample_ray(p.gx, p.gy, &mut sampler);
    (sampler, ray)
}

/// Adds a sample's value `l` to its pixel's sums, or drops it if it is not finite (counted,
/// with the first such pixel in scan order, whatever order the samples came in).
#[inline(always)]
pub(crate) fn add_sample(
    px: &mut PixelSums,
    p: &TilePixel,
    l: crate::Color,
    stats: &mut RenderStats,
) {
    if l.is_finite() {
        px.add(l);
    } else {
        stats.dropped += 1;
        if stats.first_dropped.is_none_or(|q| (p.y, p.x) < (q.1, q.0)) {
            stats.first_dropped = Some((p.x, p.y));
        }
    }
}

/// A pixel of a tile: its coordinates in the film and in the full image, and the samples
/// to render (indices `samples.0..samples.1`).
#[derive(Clone, Copy, Debug)]
pub struct TilePixel {
    pub x: u32,
    pub y: u32,
    pub gx: u32,
    pub gy: u32,
    pub samples: (u32, u32),
}

/// Renders, for each pixel i of the film (row-major), samples [next[i], until(i)) and sets
/// next[i] = until(i) (nothing where until(i) ≤ next[i]). Each pixel's samples are added in
/// index order to its running sums, and a sample's value depends only on (seed, pixel, index),
/// so the film after any sequence of calls that leaves pixel i at next[i] = n holds exactly
/// samples [0, n) of it, bit for bit, however they were split.
///
/// `stop` is asked before each tile and between steps of a tile's samples
/// ([`render_tile_steps`]): once it returns true, the tiles not yet started are skipped
/// (`stats.skipped_tiles` counts them) and started ones end after their current step, so an
/// abandoned call leaves the film and `next` consistent — every pixel holds a prefix of its
/// sample sequence.
///
/// The image's tiles are rendered in parallel, each tile's samples by `integrator`.
#[allow(clippy::too_many_arguments)]
pub fn render_ranges(
    integrator: &dyn Integrator,
    scene: &Scene,
    s: &RenderSettings,
    film: &mut Film,
    next: &mut [u32],
    until: &(dyn Fn(usize) -> u32 + Sync),
    stop: &(dyn Fn() -> bool + Sync),
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RenderStats, RenderError> {
    let camera = camera_for(scene, s)?;
    let (ox, oy, fw, fh) = s.window();
    assert_eq!(next.len(), fw as usize * fh as usize);
    assert_eq!((film.width, film.height), (fw, fh));
    let tiles_x = fw.div_ceil(TILE);
    let tiles_y = fh.div_ceil(TILE);
    let start = Instant::now();
    let shared = Mutex::new((film, next, RenderStats::default()));
    let work = || {
        (0..tiles_x * tiles_y).into_par_iter().for_each(|t| {
            let (tx, ty) = (t % tiles_x, t / tiles_x);
            let (x0, y0) = (tx * TILE, ty * TILE);
            let (x1, y1) = ((x0 + TILE).min(fw), (y0 + TILE).min(fh));
            let index = |x: u32, y: u32| (y * fw + x) as usize;
            if stop() {
                let mut g = shared.lock().unwrap();
                g.2.skipped_tiles += 1;
                g.2.interrupted = true;
                return;
            }
            // Continue each pixel's running sums from the film, so that rendering samples in
            // several passes adds them in exactly the order one pass would: the result is the
            // same bits however the samples are split (tiles never share pixels).
            let (mut sums, ranges): (Vec<PixelSums>, Vec<(u32, u32)>) = {
                let g = shared.lock().unwrap();
                (y0..y1)
                    .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                    .map(|(x, y)| {
                        let i = index(x, y);
                        let a = g.1[i];
                        (g.0.pixel(x, y), (a, until(i).max(a)))
                    })
                    .unzip()
            };
            let mut stats = RenderStats::default();
            let mut pixels: Vec<TilePixel> = (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .zip(&ranges)
                .map(|((x, y), &samples)| TilePixel {
                    x,
                    y,
                    gx: x + ox,
                    gy: y + oy,
                    samples,
                })
                .collect();
            // Each pixel reached `done[k]`: its end unless the render was told to stop.
            let done = render_tile_steps(
                integrator,
                s,
                &camera,
                &mut pixels,
                &mut sums,
                &mut stats,
                stop,
            );
            let ranges: Vec<(u32, u32)> =
                ranges.iter().zip(&done).map(|(r, &d)| (r.0, d)).collect();
            let n: u64 = ranges.iter().map(|&(a, b)| (b - a) as u64).sum();
            {
                let mut g = shared.lock().unwrap();
                let (film, next, total) = &mut *g;
                let mut k = 0;
                for y in y0..y1 {
                    for x in x0..x1 {
                        film.set_pixel(x, y, &sums[k]);
                        next[index(x, y)] = ranges[k].1;
                        k += 1;
                    }
                }
                total.samples += n;
                total.interrupted |= stats.interrupted;
                total.rays.add(&stats.rays);
                total.dropped += stats.dropped;
                // Keep the first dropped pixel in scan order, whatever the thread timing.
                if let Some(p) = stats.first_dropped {
                    if total.first_dropped.is_none_or(|q| (p.1, p.0) < (q.1, q.0)) {
                        total.first_dropped = Some(p);
                    }
                }
            }
            progress(n);
        });
    };
    with_threads(s, work)?;
    let (_, _, mut stats) = shared.into_inner().unwrap();
    stats.elapsed = start.elapsed();
    Ok(stats)
}

/// Samples per call of [`render_tile`] when one sample casts one shadow ray: between
/// two calls the render asks whether to stop, so a stop takes effect within about this much
/// work per thread (milliseconds), however many samples a pixel has. Large enough that the
/// wavefront's lanes drain at the end of a call rarely (a 16 × 16 tile at 16 spp is one call).
const STEP_SAMPLES: u64 = 4096;

/// Samples per step: [`STEP_SAMPLES`] divided by the shadow and final-gather rays a sample
/// casts at each vertex, so a step takes about as long with 1 or 1024 of them.
fn step_samples(s: &RenderSettings) -> u64 {
    let p = &s.params;
    let mut per_vertex = p.shadow_rays.max(1) as u64;
    if p.kind == IntegratorKind::Photon {
        per_vertex += p.photon.final_gather as u64;
    }
    (STEP_SAMPLES / per_vertex).max(1)
}

/// Renders a tile's pixels (samples `pixels[k].samples` into `sums[k]`) in steps of about
/// [`step_samples`] samples, a few samples of a group of pixels each, asking `stop` before
/// each step. Every pixel's samples are still added in index order, so the sums are the same
/// bits as in one call. Returns, for each pixel, the end of the samples it rendered: its
/// range's end, or less if `stop` answered true (then `stats.interrupted` is set).
fn render_tile_steps(
    integrator: &dyn Integrator,
    s: &RenderSettings,
    camera: &crate::camera::Camera,
    pixels: &mut [TilePixel],
    sums: &mut [PixelSums],
    stats: &mut RenderStats,
    stop: &(dyn Fn() -> bool + Sync),
) -> Vec<u32> {
    let step = step_samples(s);
    let npix = pixels.len().max(1) as u64;
    // Samples per pixel and pixels per step.
    let per_pixel = (step / npix).clamp(1, u32::MAX as u64) as u32;
    let group = (step / per_pixel as u64).clamp(1, npix) as usize;
    let ends: Vec<u32> = pixels.iter().map(|p| p.samples.1).collect();
    let mut done: Vec<u32> = pixels.iter().map(|p| p.samples.0).collect();
    while done.iter().zip(&ends).any(|(d, e)| d < e) {
        for start in (0..pixels.len()).step_by(group) {
            let end = (start + group).min(pixels.len());
            if (start..end).all(|k| done[k] >= ends[k]) {
                continue;
            }
            if stop() {
                stats.interrupted = true;
                return done;
            }
            for k in start..end {
                let to = done[k].saturating_add(per_pixel).min(ends[k]);
                pixels[k].samples = (done[k], to);
            }
            render_tile(
                integrator,
                s,
                camera,
                &pixels[start..end],
                &mut sums[start..end],
                stats,
            );
            for k in start..end {
                done[k] = pixels[k].samples.1;
            }
        }
    }
    done
}

/// Renders the whole image at `s.spp` samples per pixel (`sppm`: `iterations` passes).
pub fn render(
    scene: &Scene,
    s: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Film, RenderStats), RenderError> {
    render_until(scene, s, progress, &|| false)
}

/// [`render`], asking `stop` while it works (between steps of a tile's samples, photon
/// chunks and SPPM iterations). Once it answers true the render ends soon with what it has:
/// every pixel holds a prefix of its samples (none where the photon maps were not finished),
/// and `stats.interrupted` is set.
pub fn render_until(
    scene: &Scene,
    s: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Film, RenderStats), RenderError> {
    let (_, _, w, h) = s.window();
    let mut film = Film::new(w, h);
    if s.params.kind == IntegratorKind::Sppm {
        return integrator::sppm::render_sppm_until(
            scene,
            s,
            progress,
            &mut |_, _| {},
            &|_| false,
            stop,
        );
    }
    let integrator = match integrator::prepare(scene, s, stop) {
        Err(RenderError::Interrupted) => {
            let stats = RenderStats {
                interrupted: true,
                ..Default::default()
            };
            return Ok((film, stats));
        }
        r => r?,
    };
    let mut next = vec![0; film.count.len()];
    let mut stats = integrator.setup_stats();
    stats.add(&render_ranges(
        &*integrator,
        scene,
        s,
        &mut film,
        &mut next,
        &|_| s.spp,
        stop,
        progress,
    )?);
    Ok((film, stats))
}
