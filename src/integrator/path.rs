//! Path tracing with next-event estimation, MIS and Russian roulette (Kajiya 1986; Veach 1997
//! ch. 9; the structure follows pbrt-v4's `PathIntegrator` and Mitsuba 3's `path`).

use super::{emitted, escaped, one_light, sample_lights, IntegratorParams, RayStats};
use crate::camera::Camera;
use crate::film::PixelSums;
use crate::geometry::{Frame, Ray};
use crate::material::TransportMode;
use crate::render::{Backend, RenderError, RenderSettings, RenderStats, TilePixel};
use crate::sampler::Sampler;
use crate::scene::Interaction;
use crate::scene::Scene;
use crate::Color;
use glam::Vec3A;

/// The path tracer ready for a scene: one path at a time ([`li`]), a stream of paths per
/// tile ([`super::stream`]), or sixteen at a time where the settings' backend, the scene and
/// the CPU allow ([`super::wavefront`]), with the same values each way.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    /// Tiles that the wavefront does not take are rendered by the stream.
    stream: bool,
    #[cfg(target_arch = "x86_64")]
    wavefront: Option<super::wavefront::Wavefront<'a>>,
}

impl<'a> PathTracer<'a> {
    /// Refuses a wide backend that the CPU or the scene cannot run (`Auto` falls back).
    pub fn new(scene: &'a Scene, s: &'a RenderSettings) -> Result<Self, RenderError> {
        #[cfg(target_arch = "x86_64")]
        let wavefront = super::wavefront::Wavefront::new(scene, s);
        #[cfg(target_arch = "x86_64")]
        let lanes = wavefront.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        let lanes = false;
        if matches!(s.backend, Backend::Avx512 | Backend::Avx2) && !lanes {
            return Err(RenderError::Unsupported(format!(
                "--backend {} needs a CPU with it (and MCRT_MAX_ISA not below it), a scene the \
                 wavefront takes and settings it runs (see docs/performance.md); --backend \
                 auto picks what runs",
                s.backend.name()
            )));
        }
        Ok(PathTracer {
            scene,
            settings: s,
            stream: matches!(s.backend, Backend::Auto | Backend::Stream),
            #[cfg(target_arch = "x86_64")]
            wavefront,
        })
    }
}

impl super::Integrator for PathTracer<'_> {
    #[inline]
    fn li(&self, ray: Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Color {
        super::li(self.scene, ray, sampler, &self.settings.params, stats)
    }

    fn render_tile(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let Some(w) = self.wavefront.as_ref() {
            w.render_tile(camera, pixels, sums, stats);
            return true;
        }
        if self.stream {
            super::stream::render_tile(self.scene, self.settings, camera, pixels, sums, stats);
        }
        self.stream
    }
}

/// Radiance along a camera ray, one path at a time: the loop "intersect, step, trace the
/// step's shadow ray" over [`PathState::step`], which holds all of the path's maths (the
/// stream, [`super::stream`], runs the same function for many paths at a time, and traces
/// their shadow rays together).
#[inline(always)]
pub fn li(
    scene: &Scene,
    ray: Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    let Some(mut path) = PathState::new(ray, p) else {
        return Color::ZERO;
    };
    loop {
        let hit = scene.intersect(&path.ray);
        let (alive, shadow) = path.step(scene, hit.as_ref(), sampler, p, stats);
        if let Some(s) = shadow {
            path.light(&s, scene.occluded(&s.ray, s.t_max));
        }
        if !alive {
            return path.l;
        }
    }
}

/// The shadow ray of a vertex's light sample, left by [`PathState::step`] to its caller:
/// the segment that must be unobstructed up to `t_max` for the sample to add `l`
/// ([`PathState::light`]). Returned rather than traced so that the stream can trace the
/// shadow rays of all its paths in one call (`Scene::occluded_many`), which overlaps their
/// traversals' cache misses as `Scene::intersect_many` does the closest hits'.
#[derive(Clone, Copy, Debug)]
pub struct Shadow {
    pub ray: Ray,
    pub t_max: f32,
    /// The throughput at the vertex times the sample's contribution.
    l: Color,
}

/// A path between two segments: the ray to trace next and what the vertices so far left
/// (Kajiya 1986; Veach 1997 ch. 9; the structure follows pbrt-v4's `PathIntegrator` and
/// Mitsuba 3's `path`). Its random numbers come from the camera sample's [`Sampler`], which
/// the caller keeps beside it.
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    /// The segment to trace next.
    pub ray: Ray,
    /// Radiance gathered so far: the sample's value once [`PathState::step`] says the path
    /// ended.
    pub l: Color,
    /// Throughput.
    beta: Color,
    /// η² accumulated over refractions, to undo radiance scaling in the roulette test.
    eta2: f32,
    /// Previous vertex and BSDF pdf for MIS on emitter hits; None after a specular bounce.
    prev: Option<(Vec3A, f32)>,
    /// Segments traced so far, minus one.
    depth: u32,
}

impl PathState {
    /// A path starting along the camera ray `ray`; None where `max_depth` is 0 (no segment
    /// at all: not even emitters are seen, and the sample's value is zero).
    #[inline(always)]
    pub fn new(ray: Ray, p: &IntegratorParams) -> Option<PathState> {
        if p.max_depth == Some(0) {
            return None;
        }
        Some(PathState {
            ray,
            l: Color::ZERO,
            beta: Color::ONE,
            eta2: 1.0,
            prev: None,
            depth: 0,
        })
    }

    /// One vertex: takes `hit`, the closest hit of `self.ray` (None if it left the scene),
    /// adds what it sees and its next-event estimate to `self.l`, and either sets `self.ray`
    /// to the next segment and returns true, or ends the path and returns false. With one
    /// light sample a vertex, its shadow ray is returned instead of traced, and the caller
    /// passes its answer to [`PathState::light`] before the next step (the path's value is
    /// then complete even where this step ended it).
    #[inline(always)]
    pub fn step(
        &mut self,
        scene: &Scene,
        hit: Option<&Interaction>,
        sampler: &mut Sampler,
        p: &IntegratorParams,
        stats: &mut RayStats,
    ) -> (bool, Option<Shadow>) {
        stats.rays += 1;
        let ray = self.ray;
        let hidden = self.depth == 0 && p.hide_emitters;
        let Some(si) = hit else {
            if !hidden {
                self.l += self.beta * escaped(scene, ray.d, self.prev, p.shadow_rays);
            }
            return (false, None);
        };
        if !hidden {
            self.l += self.beta * emitted(scene, si, ray.d, self.prev, p.shadow_rays);
        }
        // A further vertex would make the path longer than max_depth segments.
        if self.depth + 1 >= p.max_depth.unwrap_or(u32::MAX) {
            return (false, None);
        }
        let material = &scene.material_at(si);
        if material.is_black() {
            return (false, None);
        }
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        // With one light sample, its shadow ray goes to the caller.
        let mut shadow = None;
        if !material.is_specular() && !scene.lights.is_empty() {
            let n = p.shadow_rays;
            if n == 1 {
                shadow =
                    one_light(scene, si, &frame, wo, material, sampler).map(|(ray, t_max, c)| {
                        stats.shadow_rays += 1;
                        let l = self.beta * c;
                        Shadow { ray, t_max, l }
                    });
            } else {
                let direct = sample_lights(scene, si, &frame, wo, material, n, sampler, stats);
                self.l += self.beta * direct;
            }
        }
        // One request for the direction (the best-stratified pair of a Sobol point), the
        // lobe choice and the roulette.
        let [ux, uy, u1, u_rr] = sampler.next_4d();
        let u2 = glam::Vec2::new(ux, uy);
        let Some(bs) = material.sample(wo, u1, u2, TransportMode::Radiance) else {
            return (false, shadow);
        };
        self.beta *= bs.weight;
        self.eta2 *= bs.eta * bs.eta;
        self.prev = if bs.specular {
            None
        } else {
            Some((si.p, bs.pdf))
        };
        let wi = frame.to_world(bs.wi);
        self.ray = si.spawn_ray(wi);
        self.depth += 1;
        let (survives, beta) =
            p.rr.play(self.beta, self.eta2, |start| self.depth >= start, u_rr);
        if !survives {
            return (false, shadow);
        }
        self.beta = beta;
        (self.beta != Color::ZERO, shadow)
    }

    /// Adds the light sample of `s` (from this path's last step) unless `occluded`.
    #[inline(always)]
    pub fn light(&mut self, s: &Shadow, occluded: bool) {
        if !occluded {
            self.l += s.l;
        }
    }
}
