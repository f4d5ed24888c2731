//! Next-event estimation: `n` shadow rays from a non-specular vertex to points chosen on the
//! lights, each weighted against BSDF sampling by the power heuristic. With n light samples
//! and one BSDF sample, Veach's multi-sample estimator (thesis eq. 9.10) gives each light
//! sample the weight w = (n·p_light)² / ((n·p_light)² + p_bsdf²) and divides the sum by n.
//!
//! The n samples of a vertex come from one uniform point Δ (one sampler request) and a
//! rank-1 lattice rotated by it (Cranley and Patterson, "Randomization of Number Theoretic
//! Methods for Multiple Integration", SIAM J. Numer. Anal. 13(6), 1976): sample i uses
//! (Δ + i·g) mod 1 with g = (1/n, φ − 1, 1/ρ) (φ the golden ratio, ρ the plastic number), a
//! Fibonacci-like lattice in the two dimensions that pick the point on a light. Each sample
//! is uniform on its own, since Δ is, so each term of the estimator has the expectation it
//! had with independent samples and the sum stays unbiased; the samples of a vertex cover
//! the light evenly rather than clump, which lowers the variance, and they cost one request
//! instead of n. With n = 1 the only sample is Δ itself, as before.
//!
//! The shadow rays of a vertex share their origin and are traced as packets of up to sixteen
//! ([`crate::accel::RayPacket`]). When the scene's only light is a triangle or a
//! parallelogram (`Lights::single_planar`, the case of most test scenes and of the TNCG15
//! room), the batch's samples, BSDF values and MIS weights are computed eight or four lanes at
//! a time ([`planar`]), with everything the samples share (the light's offset, the material's
//! side, a Lambertian BSDF's colour) worked out once per vertex.

mod lanes;
mod planar;

#[cfg(target_arch = "x86_64")]
pub(super) use planar::{lambert_weight, shadow_dir, wrap};

use crate::accel::{RayPacket, PACKET};
use crate::geometry::{Frame, Ray};
use crate::material::sampling::power_heuristic;
use crate::material::{Bsdf, Material};
use crate::scene::{Interaction, Scene};
use crate::Color;
use glam::Vec3A;
use std::mem::MaybeUninit;

use super::RayStats;

/// Samples per batch: one packet of shadow rays.
const BATCH: usize = PACKET;

/// The lattice's generators for the second and third dimensions in 32-bit fixed point:
/// 2³²·(φ − 1) and 2³²/ρ, ρ = 1.3247… the plastic number (Roberts' R2 sequence).
const G1: u32 = 0x9e37_79b9;
const G2: u32 = 0xc13f_a9a9;

/// The lattice's second coordinate for sample `j` of a vertex: frac(j·(φ − 1)) to 24 bits,
/// repeating after 256 samples (as the batch's table has it).
#[inline]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // (read by the wavefront)
pub(crate) fn lattice_v(j: u32) -> f32 {
    ((j % 256).wrapping_mul(G1) >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Δ in 32-bit fixed point; the sampler's numbers are multiples of 2⁻²⁴, so this is exact.
#[inline(always)]
fn fixed(x: f32) -> u32 {
    (x * 4_294_967_296.0) as u32
}

/// Back to [0, 1): the top 24 bits, exactly representable.
#[inline(always)]
fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Next-event estimation at `si`: the direct light, weighted by MIS, divided by `n`.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the hot path: plain arguments, no context struct
pub(crate) fn sample_lights(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    n: u32,
    sampler: &mut crate::sampler::Sampler,
    stats: &mut RayStats,
) -> Color {
    sample_lights_at(scene, si, frame, wo, material, n, sampler.next_3d(), stats)
}

/// [`sample_lights`] for the sampler's numbers `delta` (the wavefront's lanes draw their
/// own).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample_lights_at(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    n: u32,
    delta: [f32; 3],
    stats: &mut RayStats,
) -> Color {
    match scene.lights.single_planar() {
        // One sample gains nothing from lanes; it takes the general path, as it always did.
        Some(light) if n > 1 => {
            // What the BSDF is for every sample: a Lambertian one seen from a side it reflects
            // on is a constant colour times the cosine, with the cosine's pdf (its own
            // variant, without the arrays the others need); the others are evaluated sample
            // by sample.
            let planar = match &material.bsdf {
                // (A normal or bump map's factor varies with the light's direction.)
                Bsdf::Lambert(_) if material.perturbed.is_none() => match material.orient(wo) {
                    Some(_) => planar::planar::<true>,
                    None => return Color::ZERO, // a one-sided surface seen from behind
                },
                _ => planar::planar::<false>,
            };
            let vertex = planar::Vertex {
                scene,
                light,
                si,
                frame,
                wo,
                material,
                n,
                delta,
            };
            planar(&vertex, stats)
        }
        _ if n == 1 => one_sample(scene, si, frame, wo, material, delta, stats),
        _ => any_lights(scene, si, frame, wo, material, n, delta, stats),
    }
}

/// [`sample_lights`] with one light sample (`n` = 1, the default), its shadow ray left to the
/// caller: the ray, the distance it must be clear to, and the sample's contribution if it is
/// (None where it contributes nothing whatever the ray finds). The numbers are
/// [`one_sample`]'s.
#[inline(always)]
pub(crate) fn one_light(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    sampler: &mut crate::sampler::Sampler,
) -> Option<(Ray, f32, Color)> {
    light_sample(scene, si, frame, wo, material, 1, sampler.next_3d())
}

/// One light sample (`n` = 1, the default): `any_lights` without its batch, its lattice and
/// its packets, which cost a vertex about a fifth of its light sampling (callgrind, Cornell
/// box). The sample is `any_lights`'s first, so the result is the same.
#[inline(always)]
fn one_sample(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    delta: [f32; 3],
    stats: &mut RayStats,
) -> Color {
    let Some((ray, t_max, contribution)) = light_sample(scene, si, frame, wo, material, 1, delta)
    else {
        return Color::ZERO;
    };
    stats.shadow_rays += 1;
    if scene.occluded(&ray, t_max) {
        Color::ZERO
    } else {
        contribution
    }
}

/// Light sample `u` (two numbers for the point, one for the light) of `n` at `si`: its
/// shadow ray, the distance the ray must be clear to, and its contribution if it is (the
/// BSDF value and cosine times the emitted radiance, weighted by MIS against BSDF sampling,
/// over the light pdf); None where it contributes nothing whatever the shadow ray finds.
#[inline(always)]
fn light_sample(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    n: u32,
    [ux, uy, u_sel]: [f32; 3],
) -> Option<(Ray, f32, Color)> {
    let ls = scene.lights.sample(si.p, u_sel, glam::Vec2::new(ux, uy))?;
    let wi = frame.to_local(ls.wi);
    let (f, bsdf_pdf) = material.eval_pdf(wo, wi);
    let f = f * wi.z.abs();
    if f == Color::ZERO {
        return None;
    }
    let (ray, t_max) = si.spawn_ray_to_light(&ls);
    let w = if ls.delta {
        1.0
    } else {
        power_heuristic(n as f32 * ls.pdf, bsdf_pdf)
    };
    Some((ray, t_max, f * ls.le * (w / ls.pdf)))
}

/// Any lights: each sample by `Lights::sample` and `Material::eval_pdf`, in batches (first
/// every light sample of the batch, whose square roots and divisions can overlap, then the
/// shadow rays).
#[inline]
#[allow(clippy::too_many_arguments)]
fn any_lights(
    scene: &Scene,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    n: u32,
    delta: [f32; 3],
    stats: &mut RayStats,
) -> Color {
    let mut sum = Color::ZERO;
    // Left uninitialised: entry k is written before it is read.
    let mut pending = [const { MaybeUninit::<(Ray, f32, Color)>::uninit() }; BATCH];
    let fixed_delta = delta.map(fixed);
    let step = (u32::MAX / n.max(1)).wrapping_add(1);
    let mut i = 0;
    while i < n {
        let m = (n - i).min(BATCH as u32);
        let mut k = 0;
        for j in i..i + m {
            let u = if j == 0 {
                delta
            } else {
                let g = [j.wrapping_mul(step), j.wrapping_mul(G1), j.wrapping_mul(G2)];
                std::array::from_fn(|d| unit(fixed_delta[d].wrapping_add(g[d])))
            };
            let Some(sample) = light_sample(scene, si, frame, wo, material, n, u) else {
                continue;
            };
            pending[k].write(sample);
            k += 1;
        }
        i += m;
        stats.shadow_rays += k as u64;
        // SAFETY: the first k entries were written above.
        let pending = unsafe { &*(&pending[..k] as *const _ as *const [(Ray, f32, Color)]) };
        let o = pending.first().map(|p| p.0.o);
        if k > 1 && pending.iter().all(|p| Some(p.0.o) == o) {
            let mut pk = RayPacket {
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
