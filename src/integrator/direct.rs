//! Direct illumination: light emitted towards the camera plus one bounce of direct light at
//! the first non-specular surface, following mirrors and glass on the way there (the TNCG15
//! report's Figure 3.1). The direct light is estimated with shadow rays and one BSDF sample,
//! combined by MIS.

use super::{emitted, escaped, sample_lights, IntegratorParams, RayStats};
use crate::geometry::{Frame, Ray};
use crate::material::TransportMode;
use crate::sampler::Sampler;
use crate::scene::Scene;
use crate::Color;

/// Direct lighting ready for a scene.
pub struct DirectLighting<'a> {
    pub scene: &'a Scene,
    pub params: IntegratorParams,
}

impl super::Integrator for DirectLighting<'_> {
    #[inline]
    fn li(&self, ray: Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Color {
        super::li(self.scene, ray, sampler, &self.params, stats)
    }
}

/// Specular bounces followed before giving up (a ray trapped by total internal reflection).
const MAX_SPECULAR_CHAIN: u32 = 64;

pub fn li(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    let mut l = Color::ZERO;
    let mut beta = Color::ONE;
    let max_depth = p.max_depth.unwrap_or(u32::MAX);
    if max_depth == 0 {
        return Color::ZERO; // no segment at all: not even emitters are seen
    }
    let mut depth = 0u32;
    loop {
        stats.rays += 1;
        let hidden = depth == 0 && p.hide_emitters;
        let Some(si) = scene.intersect(&ray) else {
            if !hidden {
                l += beta * escaped(scene, ray.d, None, p.shadow_rays);
            }
            break;
        };
        if !hidden {
            l += beta * emitted(scene, &si, ray.d, None, p.shadow_rays);
        }
        if depth + 1 >= max_depth || depth >= MAX_SPECULAR_CHAIN {
            break;
        }
        let material = &scene.material_at(&si);
        if material.is_black() {
            break;
        }
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        let u1 = sampler.next_1d();
        let u2 = sampler.next_2d();
        if material.is_specular() && p.specular_chain {
            let Some(bs) = material.sample(wo, u1, u2, TransportMode::Radiance) else {
                break;
            };
            beta *= bs.weight;
            ray = si.spawn_ray(frame.to_world(bs.wi));
            depth += 1;
            continue;
        }
        // The first non-specular surface: light sampling plus one BSDF sample, by MIS.
        if !scene.lights.is_empty() {
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
        if let Some(bs) = material.sample(wo, u1, u2, TransportMode::Radiance) {
            let ray2 = si.spawn_ray(frame.to_world(bs.wi));
            stats.rays += 1;
            // A delta sample (a mirror, plastic's coating) cannot be found by light sampling:
            // it takes the emission with weight 1.
            let prev = (!bs.specular).then_some((si.p, bs.pdf));
            match scene.intersect(&ray2) {
                Some(si2) => {
                    l += beta * bs.weight * emitted(scene, &si2, ray2.d, prev, p.shadow_rays)
                }
                None => l += beta * bs.weight * escaped(scene, ray2.d, prev, p.shadow_rays),
            }
        }
        break;
    }
    l
}
