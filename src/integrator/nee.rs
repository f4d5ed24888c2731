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
//! The shadow rays of a vertex share their origin where the samples leave the surface on
//! one side, and are then traced as packets of up to sixteen
//! ([`crate::accel::RayPacket`]). The wavefront computes the same samples sixteen vertices
//! at a time with this module's [`Lattice`] and the same operations in its lanes.

use crate::accel::{RayPacket, PACKET};
use crate::geometry::{Frame, Ray};
use crate::material::sampling::power_heuristic;
use crate::material::Material;
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

/// Δ in 32-bit fixed point; the sampler's numbers are multiples of 2⁻²⁴, so this is exact.
#[inline(always)]
pub(crate) fn fixed(x: f32) -> u32 {
    (x * 4_294_967_296.0) as u32
}

/// Back to [0, 1): the top 24 bits, exactly representable.
#[inline(always)]
pub(crate) fn unit(x: u32) -> f32 {
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
    let delta = sampler.next_3d();
    if n == 1 {
        one_sample(scene, si, frame, wo, material, delta, stats)
    } else {
        any_lights(scene, si, frame, wo, material, n, delta, stats)
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

/// The lattice of a vertex's `n` light samples: sample j's numbers are the point
/// (Δ + j·g) mod 1, computed in 32-bit fixed point (the module comment).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lattice {
    /// 2³²/n, the first generator in fixed point.
    step: u32,
}

impl Lattice {
    #[inline(always)]
    pub(crate) fn new(n: u32) -> Lattice {
        Lattice {
            step: (u32::MAX / n.max(1)).wrapping_add(1),
        }
    }

    /// j·g in fixed point, to be added to Δ's ([`fixed`]).
    #[inline(always)]
    pub(crate) fn offsets(&self, j: u32) -> [u32; 3] {
        [
            j.wrapping_mul(self.step),
            j.wrapping_mul(G1),
            j.wrapping_mul(G2),
        ]
    }

    /// Sample `j`'s numbers for Δ = `delta` (`fixed` in fixed point); sample 0's are Δ.
    #[inline(always)]
    pub(crate) fn point(&self, delta: [f32; 3], fixed: [u32; 3], j: u32) -> [f32; 3] {
        if j == 0 {
            return delta;
        }
        let g = self.offsets(j);
        std::array::from_fn(|d| unit(fixed[d].wrapping_add(g[d])))
    }
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
    let (lattice, fixed_delta) = (Lattice::new(n), delta.map(fixed));
    let mut i = 0;
    while i < n {
        let m = (n - i).min(BATCH as u32);
        let mut k = 0;
        for j in i..i + m {
            let u = lattice.point(delta, fixed_delta, j);
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
