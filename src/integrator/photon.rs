//! Jensen's two-pass photon mapping ("Global Illumination Using Photon Maps", 1996; "Realistic
//! Image Synthesis Using Photon Mapping", 2001, ch. 9). The camera ray follows mirrors and
//! glass by recursion (one branch sampled per bounce) to the first non-specular surface, where
//! the radiance is split into
//! - direct light, by shadow rays to the lights, skipped where the nearby shadow photons say
//!   the point is fully lit (no shadow rays: visible) or fully in shadow (zero);
//! - caustics (light reaching the point by mirrors and glass only), from the caustic map: the
//!   k nearest photons with a cone filter;
//! - the rest of the indirect light, by final gathering: BSDF-sampled rays whose first
//!   non-specular hit takes its reflected radiance from the global map: on Lambertian
//!   surfaces ρ/π times the nearest precomputed irradiance point's E (Christensen 1999),
//!   one nearest-neighbour lookup instead of a k-nearest estimate.
//!
//! Biased (density estimation blurs), consistent as the photon counts grow.

use super::{IntegratorParams, RayStats};
use crate::geometry::{Frame, Ray};
use crate::material::{Material, TransportMode};
use crate::photon::{
    precomputed_radiance, radiance_estimate, visibility, PhotonMaps, ShadingPoint, Visibility,
};
use crate::render::{RenderError, RenderSettings, RenderStats};
use crate::sampler::Sampler;
use crate::scene::{Interaction, Scene};
use crate::Color;

/// Specular bounces followed before giving up.
const MAX_SPECULAR_CHAIN: u32 = 32;
/// Photons consulted by the shadow-photon test.
const SHADOW_K: usize = 16;

/// The maps and the search radii, built once per render.
pub struct PhotonContext {
    pub maps: PhotonMaps,
    /// Largest search radius of the global, caustic and shadow-photon estimates.
    pub r_global: f32,
    pub r_caustic: f32,
    pub r_shadow: f32,
    /// The shadow-photon test is valid only when every light is an area light.
    pub use_shadow_photons: bool,
}

impl PhotonContext {
    pub fn new(scene: &Scene, maps: PhotonMaps) -> Self {
        let d = crate::photon::scene_diagonal(scene);
        PhotonContext {
            maps,
            r_global: crate::photon::GLOBAL_RADIUS * d,
            r_caustic: 0.05 * d,
            r_shadow: 0.02 * d,
            use_shadow_photons: scene.lights.others.is_empty(),
        }
    }
}

/// Photon mapping ready for a scene: its maps traced and built (deterministically from the
/// seed, so every pass, machine and resumed render sees the same maps).
pub struct PhotonMapping<'a> {
    scene: &'a Scene,
    params: IntegratorParams,
    ctx: PhotonContext,
}

impl<'a> PhotonMapping<'a> {
    /// Ends with [`RenderError::Interrupted`] if `stop` answers true before the maps are built.
    pub fn new(
        scene: &'a Scene,
        s: &RenderSettings,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<Self, RenderError> {
        crate::render::camera_for(scene, s)?;
        let maps = crate::render::with_threads(s, || {
            PhotonMaps::build_until(scene, &s.params, s.seed, stop)
        })?
        .ok_or(RenderError::Interrupted)?;
        Ok(PhotonMapping {
            scene,
            params: s.params,
            ctx: PhotonContext::new(scene, maps),
        })
    }
}

impl super::Integrator for PhotonMapping<'_> {
    fn li(&self, ray: Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Color {
        li(self.scene, &self.ctx, ray, sampler, &self.params, stats)
    }

    fn setup_stats(&self) -> RenderStats {
        let maps = &self.ctx.maps;
        RenderStats {
            photons_stored: (maps.global.len() + maps.caustic.len() + maps.shadow.len()) as u64,
            photon_bytes: maps.memory_bytes() as u64,
            photon_time: maps.build_time,
            elapsed: maps.build_time,
            rays: RayStats {
                rays: maps.rays,
                shadow_rays: 0,
            },
            ..Default::default()
        }
    }
}

/// Direct light at a non-specular point by `n` light samples (no MIS: emission found by
/// BSDF sampling is never counted by this integrator), with visibility known or tested.
#[allow(clippy::too_many_arguments)]
pub(crate) fn direct_light(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: glam::Vec3A,
    material: &Material,
    n: u32,
    vis: Visibility,
    sampler: &mut Sampler,
    stats: &mut RayStats,
) -> Color {
    if vis == Visibility::Shadowed {
        return Color::ZERO;
    }
    let mut sum = Color::ZERO;
    for _ in 0..n {
        let u_sel = sampler.next_1d();
        let u = sampler.next_2d();
        let Some(ls) = scene.lights.sample(si.p, u_sel, u) else {
            continue;
        };
        let wi = frame.to_local(ls.wi);
        let f = material.eval(wo, wi) * wi.z.abs();
        if f == Color::ZERO || ls.pdf.is_nan() || ls.pdf <= 0.0 {
            continue;
        }
        if vis == Visibility::Unknown {
            let (ray, t_max) = si.spawn_ray_to_light(&ls);
            stats.shadow_rays += 1;
            if scene.occluded(&ray, t_max) {
                continue;
            }
        }
        sum += f * ls.le / ls.pdf;
    }
    sum / n as f32
}

/// Follows a ray through mirrors and glass to the first non-specular surface; returns it,
/// its material, the throughput and the segments traced. `on_hit` sees every surface hit,
/// and None where the ray leaves the scene.
fn follow_specular(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    stats: &mut RayStats,
    max_segments: u32,
    mut on_hit: impl FnMut(Option<&Interaction>, &Ray, Color),
) -> Option<(Interaction, Material, Ray, Color, u32)> {
    let mut beta = Color::ONE;
    let mut segs = 0u32;
    loop {
        stats.rays += 1;
        segs += 1;
        let Some(si) = scene.intersect(&ray) else {
            on_hit(None, &ray, beta);
            return None;
        };
        on_hit(Some(&si), &ray, beta);
        let material = scene.material_at(&si);
        if material.is_black() {
            return None;
        }
        if !material.is_specular() {
            return Some((si, material, ray, beta, segs));
        }
        if segs >= max_segments || segs > MAX_SPECULAR_CHAIN {
            return None;
        }
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        let u1 = sampler.next_1d();
        let u2 = sampler.next_2d();
        let bs = material.sample(wo, u1, u2, TransportMode::Radiance)?;
        beta *= bs.weight;
        if beta == Color::ZERO {
            return None;
        }
        ray = si.spawn_ray(frame.to_world(bs.wi));
    }
}

pub fn li(
    scene: &Scene,
    ctx: &PhotonContext,
    ray: Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    let max_depth = p.max_depth.unwrap_or(u32::MAX);
    if max_depth == 0 {
        return Color::ZERO;
    }
    let pp = &p.photon;
    let k = pp.gather_photons.max(1) as usize;
    let mut l = Color::ZERO;
    // Emission seen directly or through mirrors and glass.
    let hidden_first = p.hide_emitters;
    let mut first = true;
    // (and the environment, where the ray leaves the scene, also after mirrors and glass).
    let hit = follow_specular(scene, ray, sampler, stats, max_depth, |si, r, beta| {
        if !(first && hidden_first) {
            l += beta
                * match si {
                    Some(si) => super::emitted(scene, si, r.d, None, p.shadow_rays),
                    None => super::escaped(scene, r.d, None, p.shadow_rays),
                };
        }
        first = false;
    });
    let Some((si, material, ray, beta, s)) = hit else {
        return l;
    };
    if s >= max_depth {
        return l;
    }
    let frame = Frame::from_normal(si.ns);
    let wo = frame.to_local(-ray.d);
    let sp = ShadingPoint {
        si: &si,
        frame: &frame,
        wo,
        wo_world: -ray.d,
        material: &material,
    };
    // Direct light.
    if !scene.lights.is_empty() {
        let vis = if ctx.use_shadow_photons {
            visibility(&ctx.maps.shadow, &sp, SHADOW_K, ctx.r_shadow)
        } else {
            Visibility::Unknown
        };
        l += beta
            * direct_light(
                scene,
                &si,
                &frame,
                wo,
                &material,
                p.shadow_rays,
                vis,
                sampler,
                stats,
            );
    }
    // Caustics.
    l += beta * radiance_estimate(&ctx.maps.caustic, &sp, k, ctx.r_caustic, max_depth - s);
    // Indirect light by final gathering.
    let n = pp.final_gather;
    if n > 0 && !ctx.maps.global.is_empty() && max_depth - s >= 2 {
        let mut sum = Color::ZERO;
        for _ in 0..n {
            let u1 = sampler.next_1d();
            let u2 = sampler.next_2d();
            let Some(bs) = material.sample(wo, u1, u2, TransportMode::Radiance) else {
                continue;
            };
            let gray = si.spawn_ray(frame.to_world(bs.wi));
            let Some((y, my, gray, gbeta, g)) =
                follow_specular(scene, gray, sampler, stats, max_depth - s, |_, _, _| {})
            else {
                continue;
            };
            if s + g >= max_depth {
                continue;
            }
            let fy = Frame::from_normal(y.ns);
            let spy = ShadingPoint {
                si: &y,
                frame: &fy,
                wo: fy.to_local(-gray.d),
                wo_world: -gray.d,
                material: &my,
            };
            let depth_left = max_depth - s - g;
            let lo = if depth_left >= crate::photon::photon::MAX_DEPTH {
                precomputed_radiance(&ctx.maps.irradiance, &spy, ctx.r_global)
            } else {
                None
            };
            let lo = lo.unwrap_or_else(|| {
                radiance_estimate(&ctx.maps.global, &spy, k, ctx.r_global, depth_left)
            });
            sum += bs.weight * gbeta * lo;
        }
        l += beta * sum / n as f32;
    }
    l
}
