//! Path tracing with next-event estimation, MIS and Russian roulette (Kajiya 1986; Veach 1997
//! ch. 9; the structure follows pbrt-v4's `PathIntegrator` and Mitsuba 3's `path`).

use super::{emitted, escaped, sample_lights, IntegratorParams, RayStats, RussianRoulette};
use crate::camera::Camera;
use crate::film::PixelSums;
use crate::geometry::{Frame, Ray};
use crate::material::TransportMode;
use crate::render::{Backend, RenderError, RenderSettings, RenderStats, TilePixel};
use crate::sampler::Sampler;
use crate::scene::Scene;
use crate::Color;

/// The path tracer ready for a scene: one path at a time, or sixteen at a time where the
/// settings' backend, the scene and the CPU allow ([`super::wavefront`]), with the same
/// values either way.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    params: IntegratorParams,
    #[cfg(target_arch = "x86_64")]
    wavefront: Option<super::wavefront::Wavefront<'a>>,
}

impl<'a> PathTracer<'a> {
    /// Refuses a wide backend that the CPU or the scene cannot run (`Auto` falls back).
    pub fn new(scene: &'a Scene, s: &RenderSettings) -> Result<Self, RenderError> {
        #[cfg(target_arch = "x86_64")]
        let wavefront = super::wavefront::Wavefront::new(scene, s);
        #[cfg(target_arch = "x86_64")]
        let lanes = wavefront.is_some();
        #[cfg(not(target_arch = "x86_64"))]
        let lanes = false;
        if matches!(s.backend, Backend::Avx512 | Backend::Avx2) && !lanes {
            return Err(RenderError::Unsupported(format!(
                "--backend {} needs a CPU with it, a scene the wavefront takes and settings it \
                 runs (see docs/performance.md); --backend auto picks what runs",
                s.backend.name()
            )));
        }
        Ok(PathTracer {
            scene,
            params: s.params,
            #[cfg(target_arch = "x86_64")]
            wavefront,
        })
    }
}

impl super::Integrator for PathTracer<'_> {
    #[inline]
    fn li(&self, ray: Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Color {
        super::li(self.scene, ray, sampler, &self.params, stats)
    }

    fn render_tile(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let Some(w) = self.wavefront.as_ref().filter(|_| camera.is_pinhole()) {
            w.render_tile(camera, pixels, sums, stats);
            return true;
        }
        let _ = (camera, pixels, sums, stats);
        false
    }
}

#[inline(always)]
pub fn li(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    let mut l = Color::ZERO;
    let mut beta = Color::ONE;
    // η² accumulated over refractions, to undo radiance scaling in the roulette test.
    let mut eta2 = 1.0f32;
    // Previous vertex and BSDF pdf for MIS on emitter hits; None after a specular bounce.
    let mut prev: Option<(glam::Vec3A, f32)> = None;
    let max_depth = p.max_depth.unwrap_or(u32::MAX);
    if max_depth == 0 {
        return Color::ZERO; // no segment at all: not even emitters are seen
    }
    let mut depth = 0u32; // segments traced so far, minus one
    loop {
        stats.rays += 1;
        let hidden = depth == 0 && p.hide_emitters;
        let Some(si) = scene.intersect(&ray) else {
            if !hidden {
                l += beta * escaped(scene, ray.d, prev, p.shadow_rays);
            }
            break;
        };
        if !hidden {
            l += beta * emitted(scene, &si, ray.d, prev, p.shadow_rays);
        }
        // A further vertex would make the path longer than max_depth segments.
        if depth + 1 >= max_depth {
            break;
        }
        let material = &scene.material_at(&si);
        if material.is_black() {
            break;
        }
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        if !material.is_specular() && !scene.lights.is_empty() {
            l += beta
                * sample_lights(
                    scene,
                    &si,
                    &frame,
                    wo,
                    material,
                    p.shadow_rays,
                    sampler,
                    stats,
                );
        }
        // One request for the direction (the best-stratified pair of a Sobol point), the
        // lobe choice and the roulette.
        let [ux, uy, u1, u_rr] = sampler.next_4d();
        let u2 = glam::Vec2::new(ux, uy);
        let Some(bs) = material.sample(wo, u1, u2, TransportMode::Radiance) else {
            break;
        };
        beta *= bs.weight;
        eta2 *= bs.eta * bs.eta;
        prev = if bs.specular {
            None
        } else {
            Some((si.p, bs.pdf))
        };
        let wi = frame.to_world(bs.wi);
        ray = si.spawn_ray(wi);
        depth += 1;
        match p.rr {
            RussianRoulette::Fixed(q) => {
                if u_rr >= q {
                    break;
                }
                beta /= q;
            }
            RussianRoulette::Throughput { start } => {
                if depth >= start {
                    let q = (beta.max_element() * eta2).min(0.95);
                    if u_rr >= q {
                        break;
                    }
                    beta /= q;
                }
            }
        }
        if beta == Color::ZERO {
            break;
        }
    }
    l
}
