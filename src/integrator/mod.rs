//! Integrators: estimators of the radiance arriving along a camera ray.
//!
//! - [`path`]: unidirectional path tracing with next-event estimation and multiple importance
//!   sampling, ended by Russian roulette (unbiased).
//! - [`direct`]: emission plus one bounce of direct light, seen through mirrors and glass.
//! - [`photon`]: Jensen's two-pass photon mapping (biased, consistent as the photon counts
//!   grow): direct light by shadow rays, caustics from a caustic map, indirect light by
//!   final gathering into a global map.
//! - [`sppm`]: stochastic progressive photon mapping (Hachisuka and Jensen 2009), its own
//!   whole-image driver ([`sppm::render_sppm`]).

pub mod direct;
pub mod path;
pub mod photon;
pub mod sppm;

use crate::accel::{ShadowPacket, PACKET};
use crate::geometry::{Frame, Ray};
use crate::material::sampling::power_heuristic;
use crate::material::Material;
use crate::sampler::Sampler;
use crate::scene::{Interaction, Scene};
use crate::Color;
use glam::Vec3A;
use std::mem::MaybeUninit;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    Path,
    Direct,
    Photon,
    Sppm,
}

impl IntegratorKind {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "path" => Some(IntegratorKind::Path),
            "direct" => Some(IntegratorKind::Direct),
            "photon" => Some(IntegratorKind::Photon),
            "sppm" => Some(IntegratorKind::Sppm),
            _ => None,
        }
    }
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Direct => "direct",
            IntegratorKind::Photon => "photon",
            IntegratorKind::Sppm => "sppm",
        }
    }
}

/// How paths end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RussianRoulette {
    /// Survive with probability min(max(throughput)·η², 0.95) from bounce `start` on (the
    /// throughput-based rule of Mitsuba 3 and pbrt-v4).
    Throughput { start: u32 },
    /// Survive every bounce with this fixed probability p: 1/(1 − p) bounces on average, as in
    /// the TNCG15 report.
    Fixed(f32),
}

#[derive(Clone, Copy, Debug)]
pub struct IntegratorParams {
    pub kind: IntegratorKind,
    /// Longest path in segments (Mitsuba's `max_depth`); None = unlimited.
    pub max_depth: Option<u32>,
    /// Shadow rays per non-specular vertex.
    pub shadow_rays: u32,
    pub rr: RussianRoulette,
    /// Emitters seen directly from the camera are black.
    pub hide_emitters: bool,
    /// `direct` follows mirrors and glass to the first non-specular surface.
    pub specular_chain: bool,
    /// Settings of the `photon` and `sppm` integrators.
    pub photon: PhotonParams,
}

/// Photon counts and search parameters of the photon-mapping integrators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonParams {
    /// `photon`: photons emitted for the global map.
    pub photons: u64,
    /// `photon`: photons emitted for the caustic map (only those reaching a diffuse surface
    /// by mirrors and glass are kept).
    pub caustic_photons: u64,
    /// `photon`: photons in each radiance estimate (k nearest).
    pub gather_photons: u32,
    /// `photon`: final-gather rays per camera sample.
    pub final_gather: u32,
    /// `sppm`: photon passes (and camera passes).
    pub iterations: u32,
    /// `sppm`: photons emitted per pass.
    pub photons_per_iteration: u64,
    /// `sppm`: initial search radius (world units); None: 1/200 of the scene's diagonal.
    pub initial_radius: Option<f32>,
}

impl Default for PhotonParams {
    fn default() -> Self {
        PhotonParams {
            photons: 200_000,
            caustic_photons: 1_000_000,
            gather_photons: 64,
            final_gather: 8,
            iterations: 64,
            photons_per_iteration: 100_000,
            initial_radius: None,
        }
    }
}

impl Default for IntegratorParams {
    fn default() -> Self {
        IntegratorParams {
            kind: IntegratorKind::Path,
            max_depth: None,
            shadow_rays: 1,
            rr: RussianRoulette::Throughput { start: 5 },
            hide_emitters: false,
            specular_chain: true,
            photon: PhotonParams::default(),
        }
    }
}

/// Rays traced, for the summary line.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayStats {
    pub rays: u64,
    pub shadow_rays: u64,
}

impl RayStats {
    pub fn add(&mut self, o: &RayStats) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
    }
}

/// Radiance along a camera ray, by the chosen integrator. The photon-mapping integrators
/// need their maps (built by [`crate::render::render`]); here they fall back to `path`.
#[inline]
pub fn li(
    scene: &Scene,
    ray: crate::geometry::Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    match p.kind {
        IntegratorKind::Path | IntegratorKind::Photon | IntegratorKind::Sppm => {
            path::li(scene, ray, sampler, p, stats)
        }
        IntegratorKind::Direct => direct::li(scene, ray, sampler, p, stats),
    }
}

/// Next-event estimation at a non-specular vertex: `n` shadow rays to points chosen on the
/// lights, each weighted against BSDF sampling by the power heuristic. With n light samples
/// and one BSDF sample, Veach's multi-sample estimator (thesis eq. 9.10) gives each light
/// sample the weight w = (n·p_light)² / ((n·p_light)² + p_bsdf²) and divides the sum by n.
///
/// The samples are taken in batches: first every light sample of the batch and its
/// unoccluded contribution (chains of square roots and divisions that the processor can
/// overlap when they do not wait on each other), then the shadow rays. Random numbers are
/// drawn, and contributions summed, in the same order as one sample at a time would.
#[inline]
#[allow(clippy::too_many_arguments)] // the hot path: plain arguments, no context struct
pub(crate) fn sample_lights(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    n: u32,
    sampler: &mut Sampler,
    stats: &mut RayStats,
) -> Color {
    const BATCH: u32 = 8;
    let mut sum = Color::ZERO;
    // Left uninitialised: entry k is written before it is read.
    let mut pending = [const { MaybeUninit::<(Ray, f32, Color)>::uninit() }; BATCH as usize];
    let mut left = n;
    while left > 0 {
        let m = left.min(BATCH);
        left -= m;
        let mut k = 0;
        for _ in 0..m {
            let [ux, uy, u_sel] = sampler.next_3d();
            let u = glam::Vec2::new(ux, uy);
            let Some(ls) = scene.lights.sample(si.p, u_sel, u) else {
                continue;
            };
            let wi = frame.to_local(ls.wi);
            let (f, bsdf_pdf) = material.eval_pdf(wo, wi);
            let f = f * wi.z.abs();
            if f == Color::ZERO {
                continue;
            }
            let (ray, t_max) = if ls.infinite {
                (si.spawn_ray(ls.wi), f32::INFINITY)
            } else {
                si.spawn_ray_to(ls.p, ls.p_err, ls.n)
            };
            let w = if ls.delta {
                1.0
            } else {
                power_heuristic(n as f32 * ls.pdf, bsdf_pdf)
            };
            pending[k].write((ray, t_max, f * ls.le * (w / ls.pdf)));
            k += 1;
        }
        stats.shadow_rays += k as u64;
        // SAFETY: the first k entries were written above.
        let pending = unsafe { &*(&pending[..k] as *const _ as *const [(Ray, f32, Color)]) };
        let o = pending.first().map(|p| p.0.o);
        if k > 1 && pending.iter().all(|p| Some(p.0.o) == o) {
            let mut pk = ShadowPacket {
                o: o.unwrap_or_default(),
                d: [[0.0; PACKET]; 3],
                t_max: [0.0; PACKET],
            };
            for (lane, (ray, t_max, _)) in pending.iter().enumerate() {
                (pk.d[0][lane], pk.d[1][lane], pk.d[2][lane]) = (ray.d.x, ray.d.y, ray.d.z);
                pk.t_max[lane] = *t_max;
            }
            let occ = scene.occluded_packet(&pk, (1 << k) - 1);
            for (lane, (_, _, contribution)) in pending.iter().enumerate() {
                if occ & (1 << lane) == 0 {
                    sum += *contribution;
                }
            }
        } else {
            for (ray, t_max, contribution) in pending {
                if !scene.occluded(ray, *t_max) {
                    sum += *contribution;
                }
            }
        }
    }
    sum / n as f32
}

/// Radiance of the environment along a ray `d` that left the scene, weighted against light
/// sampling as `emitted` is.
#[inline]
pub(crate) fn escaped(scene: &Scene, prev: Option<(Vec3A, f32)>, shadow_rays: u32) -> Color {
    let Some((le, light_pdf)) = scene.lights.environment() else {
        return Color::ZERO;
    };
    match prev {
        None => le,
        Some((_, bsdf_pdf)) => le * power_heuristic(bsdf_pdf, shadow_rays as f32 * light_pdf),
    }
}

/// Emission seen at `si` along `-d`, weighted against light sampling from the previous
/// vertex `prev` when the path got here by a non-specular BSDF sample with density `bsdf_pdf`.
#[inline]
pub(crate) fn emitted(
    scene: &Scene,
    si: &Interaction,
    d: Vec3A,
    prev: Option<(Vec3A, f32)>,
    shadow_rays: u32,
) -> Color {
    if si.light == crate::scene::NO_LIGHT {
        return Color::ZERO;
    }
    let le = scene.lights.le(si.light, si.ng, -d);
    match prev {
        None => le,
        Some((p_prev, bsdf_pdf)) => {
            let light_pdf = scene.lights.pdf(si.light, p_prev, si.p, si.ng);
            le * power_heuristic(bsdf_pdf, shadow_rays as f32 * light_pdf)
        }
    }
}
