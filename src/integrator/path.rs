//! Path tracing with next-event estimation, MIS and Russian roulette (Kajiya 1986; Veach 1997
//! ch. 9; the structure follows pbrt-v4's `PathIntegrator` and Mitsuba 3's `path`).

use super::{emitted, escaped, sample_lights, IntegratorParams, RayStats, RussianRoulette};
use crate::geometry::{Frame, Ray};
use crate::material::TransportMode;
use crate::sampler::Sampler;
use crate::scene::Scene;
use crate::Color;

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
                l += beta * escaped(scene, prev, p.shadow_rays);
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
