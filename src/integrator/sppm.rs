//! Stochastic progressive photon mapping (Hachisuka and Jensen, "Stochastic Progressive
//! Photon Mapping", SIGGRAPH Asia 2009; the bookkeeping of pbrt-v3's `SPPMIntegrator`).
//!
//! Each iteration traces one camera path per pixel through mirrors and glass to a visible
//! point on the first non-specular surface (adding emission on the way and direct light there
//! by shadow rays), then traces a photon pass and gathers, at each visible point, the photons
//! within the pixel's radius. Per pixel, with N photons counted so far and M new ones:
//! N' = N + αM, R'² = R²·N'/(N + M), τ' = (τ + β·Σ f·Φ)·R'²/R², α = 2/3; the pixel is
//! L = Σ L_direct / I + τ / (I·π·R²) after I iterations. The radius shrinks to zero while the
//! photon count inside it grows: the estimate converges to the right image.
//!
//! Deterministic: pixel p's camera numbers in iteration i are camera sample i of pixel p
//! (`Sampler::for_sample`), the photon pass of iteration i is stream i + 2 of the seed.

use super::RayStats;
use crate::film::Film;
use crate::geometry::{Frame, Ray};
use crate::material::{Material, TransportMode};
use crate::photon::{photon::MAX_DEPTH, trace_photons_until, PhotonMap, TraceOptions};
use crate::render::{RenderError, RenderSettings, RenderStats};
use crate::sampler::Sampler;
use crate::scene::{Interaction, Scene};
use crate::Color;
use glam::Vec3A;
use rayon::prelude::*;
use std::time::Instant;

const ALPHA: f32 = 2.0 / 3.0;
const MAX_SPECULAR_CHAIN: u32 = 32;

#[derive(Clone, Debug)]
struct VisiblePoint {
    si: Interaction,
    material: Material,
    /// Towards the camera, world.
    wo: Vec3A,
    beta: Color,
    /// Photon path segments allowed here (max_depth minus the camera path's).
    max_photon_depth: u32,
}

#[derive(Clone, Debug)]
struct PixelState {
    r2: f32,
    n: f32,
    tau: Color,
    ld: Color,
    /// This iteration's direct light, added to `ld` when its photon pass is done.
    ld_it: Color,
    vp: Option<VisiblePoint>,
}

/// Default initial radius: 1/200 of the scene's bounding-box diagonal.
pub fn default_radius(scene: &Scene) -> f32 {
    0.005 * crate::photon::scene_diagonal(scene)
}

/// Renders the image with SPPM. `on_iteration(i, image)` is called after each iteration with
/// the current estimate when `snapshot` says so (for convergence plots).
pub fn render_sppm(
    scene: &Scene,
    s: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
    on_iteration: &mut (dyn FnMut(u32, &crate::image::Image) + Send),
    snapshot: &(dyn Fn(u32) -> bool + Sync),
) -> Result<(Film, RenderStats), RenderError> {
    render_sppm_until(scene, s, progress, on_iteration, snapshot, &|| false)
}

/// [`render_sppm`], asking `stop` before each iteration and while tracing photons: once it
/// answers true the image holds the iterations completed (`stats.interrupted` set).
pub fn render_sppm_until(
    scene: &Scene,
    s: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
    on_iteration: &mut (dyn FnMut(u32, &crate::image::Image) + Send),
    snapshot: &(dyn Fn(u32) -> bool + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Film, RenderStats), RenderError> {
    let camera = crate::render::camera_for(scene, s)?;
    let (ox, oy, fw, fh) = s.window();
    let pp = &s.params.photon;
    let r0 = pp.initial_radius.unwrap_or_else(|| default_radius(scene));
    let max_depth = s.params.max_depth.unwrap_or(u32::MAX);
    let start = Instant::now();
    let mut pixels = vec![
        PixelState {
            r2: r0 * r0,
            n: 0.0,
            tau: Color::ZERO,
            ld: Color::ZERO,
            ld_it: Color::ZERO,
            vp: None,
        };
        fw as usize * fh as usize
    ];
    let mut stats = RenderStats::default();
    let iterations = pp.iterations.max(1);
    let mut done = 0;
    let mut run = |pixels: &mut Vec<PixelState>, stats: &mut RenderStats| {
        for it in 0..iterations {
            if stop() {
                stats.interrupted = true;
                return;
            }
            // Camera pass.
            let rays: RayStats = pixels
                .par_chunks_mut(fw as usize)
                .enumerate()
                .map(|(y, row)| {
                    let mut st = RayStats::default();
                    for (x, px) in row.iter_mut().enumerate() {
                        let (gx, gy) = (x as u32 + ox, y as u32 + oy);
                        let pixel = gy as u64 * s.width as u64 + gx as u64;
                        let mut sampler = Sampler::for_sample(s.sampler, s.seed, pixel, it as u64);
                        let ray = camera.sample_ray(gx, gy, &mut sampler);
                        let (ld, vp) = camera_path(scene, ray, &mut sampler, s, max_depth, &mut st);
                        px.ld_it = if ld.is_finite() { ld } else { Color::ZERO };
                        px.vp = vp;
                    }
                    st
                })
                .reduce(RayStats::default, |mut a, b| {
                    a.add(&b);
                    a
                });
            stats.rays.add(&rays);
            // Photon pass: direct light is the camera pass's, so photons count from their
            // second segment on.
            let Some(traced) = trace_photons_until(
                scene,
                pp.photons_per_iteration,
                &TraceOptions {
                    seed: s.seed,
                    pass: 2 + it as u64,
                    max_depth: max_depth.saturating_sub(1).max(1),
                    min_depth: 2,
                    ..Default::default()
                },
                stop,
            ) else {
                stats.interrupted = true;
                return;
            };
            stats.rays.rays += traced.rays;
            let map = PhotonMap::build(traced.photons);
            // Gather and update.
            pixels.par_chunks_mut(fw as usize).for_each(|row| {
                for px in row.iter_mut() {
                    px.ld += px.ld_it;
                    let Some(vp) = px.vp.take() else { continue };
                    let (phi, m) = gather(&map, &vp, px.r2);
                    if m > 0 {
                        let n_new = px.n + ALPHA * m as f32;
                        let r2_new = px.r2 * n_new / (px.n + m as f32);
                        px.tau = (px.tau + vp.beta * phi) * (r2_new / px.r2);
                        px.n = n_new;
                        px.r2 = r2_new;
                    }
                }
            });
            progress(fw as u64 * fh as u64);
            done = it + 1;
            if snapshot(it + 1) {
                on_iteration(it + 1, &image_of(pixels, fw, fh, it + 1).image());
            }
        }
    };
    match s.threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .map_err(|e| RenderError::Threads(e.to_string()))?
            .install(|| run(&mut pixels, &mut stats)),
        None => run(&mut pixels, &mut stats),
    }
    stats.elapsed = start.elapsed();
    stats.samples = fw as u64 * fh as u64 * done as u64;
    let film = match done {
        0 => Film::new(fw, fh),
        _ => image_of(&pixels, fw, fh, done),
    };
    Ok((film, stats))
}

/// The current estimate as a film (one "sample" a pixel).
fn image_of(pixels: &[PixelState], w: u32, h: u32, iterations: u32) -> Film {
    let mut film = Film::new(w, h);
    let k = 1.0 / iterations as f64;
    for (i, px) in pixels.iter().enumerate() {
        let l =
            px.ld.as_dvec3() * k + px.tau.as_dvec3() * (k / (std::f64::consts::PI * px.r2 as f64));
        film.sum[i] = l.to_array().map(crate::film::fixed_sum);
        film.sum_sq[i] = (l * l).to_array().map(crate::film::fixed_sq);
        film.count[i] = 1;
    }
    film
}

/// Σ f·Φ over the photons within the radius, and their count.
fn gather(map: &PhotonMap, vp: &VisiblePoint, r2: f32) -> (Color, u32) {
    let frame = Frame::from_normal(vp.si.ns);
    let wo = frame.to_local(vp.wo);
    let side = vp.wo.dot(vp.si.ng) > 0.0;
    let all = vp.max_photon_depth >= MAX_DEPTH;
    let mut phi = Color::ZERO;
    let mut m = 0u32;
    map.for_each_within(vp.si.p, r2, &mut |ph, _| {
        if !(all || ph.depth() <= vp.max_photon_depth) {
            return;
        }
        let wi = ph.wi();
        if (wi.dot(vp.si.ng) > 0.0) != side
            || !crate::photon::on_surface(vp.si.p, vp.si.ng, ph.pos())
        {
            return;
        }
        phi += vp.material.eval(wo, frame.to_local(wi)) * ph.power();
        m += 1;
    });
    (phi, m)
}

/// One camera path: emission seen through mirrors and glass, and at the first non-specular
/// surface its direct light and the visible point.
fn camera_path(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    s: &RenderSettings,
    max_depth: u32,
    stats: &mut RayStats,
) -> (Color, Option<VisiblePoint>) {
    let p = &s.params;
    let mut l = Color::ZERO;
    let mut beta = Color::ONE;
    let mut segs = 0u32;
    if max_depth == 0 {
        return (l, None);
    }
    loop {
        stats.rays += 1;
        segs += 1;
        let Some(si) = scene.intersect(&ray) else {
            if !(segs == 1 && p.hide_emitters) {
                l += beta * super::escaped(scene, ray.d, None, p.shadow_rays);
            }
            return (l, None);
        };
        if !(segs == 1 && p.hide_emitters) {
            l += beta * super::emitted(scene, &si, ray.d, None, p.shadow_rays);
        }
        if segs >= max_depth || segs > MAX_SPECULAR_CHAIN {
            return (l, None);
        }
        let material = scene.material_at(&si);
        if material.is_black() {
            return (l, None);
        }
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        if !material.is_specular() {
            if !scene.lights.is_empty() {
                l += beta
                    * super::photon::direct_light(
                        scene,
                        &si,
                        &frame,
                        wo,
                        &material,
                        p.shadow_rays,
                        crate::photon::Visibility::Unknown,
                        sampler,
                        stats,
                    );
            }
            let vp = VisiblePoint {
                si,
                material,
                wo: -ray.d,
                beta,
                max_photon_depth: max_depth - segs,
            };
            return (l, Some(vp));
        }
        let u1 = sampler.next_1d();
        let u2 = sampler.next_2d();
        let Some(bs) = material.sample(wo, u1, u2, TransportMode::Radiance) else {
            return (l, None);
        };
        beta *= bs.weight;
        if beta == Color::ZERO {
            return (l, None);
        }
        ray = si.spawn_ray(frame.to_world(bs.wi));
    }
}
