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
//! ([`crate::accel::ShadowPacket`]). When the scene's only light is a triangle or a
//! parallelogram (`Lights::single_planar`, the case of most test scenes and of the TNCG15
//! room), the batch's samples, BSDF values and MIS weights are computed four lanes at a time
//! (glam's `Vec4`), with everything the samples share (the light choice, the light's offset,
//! the material's side, a Lambertian BSDF's colour) worked out once per vertex.

use crate::accel::{ShadowPacket, PACKET};
use crate::geometry::ray::{offset_ray_origin, SHADOW_EPSILON};
use crate::geometry::{sqrt4, Frame, Ray};
use crate::light::PlanarLight;
use crate::material::sampling::power_heuristic;
use crate::material::{Bsdf, Material};
use crate::scene::{Interaction, Scene};
use crate::Color;
use glam::{Vec3A, Vec4};
use std::f32::consts::{FRAC_1_PI, PI};
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
fn fixed(x: f32) -> u32 {
    (x * 4_294_967_296.0) as u32
}

/// Back to [0, 1): the top 24 bits, exactly representable.
#[inline(always)]
fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Next-event estimation at `si`: the direct light, weighted by MIS, divided by `n`.
#[inline]
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
    match scene.lights.single_planar() {
        // One sample gains nothing from lanes; it takes the general path, as it always did.
        Some(light) if n > 1 => {
            // What the BSDF is for every sample: a Lambertian one seen from a side it reflects
            // on is a constant colour times the cosine, with the cosine's pdf (its own
            // variant, without the arrays the others need); the others are evaluated sample
            // by sample.
            let planar = match &material.bsdf {
                Bsdf::Lambert(_) => match material.orient(wo) {
                    Some(_) => planar::<true>,
                    None => return Color::ZERO, // a one-sided surface seen from behind
                },
                _ => planar::<false>,
            };
            planar(scene, light, si, frame, wo, material, n, delta, stats)
        }
        _ if n == 1 => one_sample(scene, si, frame, wo, material, delta, stats),
        _ => any_lights(scene, si, frame, wo, material, n, delta, stats),
    }
}

/// One light sample (`n` = 1, the default): `any_lights` without its batch, its lattice and
/// its packets, which cost a vertex about a fifth of its light sampling (callgrind, Cornell
/// box). The sample is `any_lights`'s first, so the result is the same.
#[inline]
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

/// frac(j·(φ − 1)) for j < 256 (and three more, for loads of four), from `G1`: the lattice's
/// second coordinate, by table so that four lanes load it at once. Past 256 samples a vertex
/// reuses them (each sample stays uniform; only the set's spread suffers).
static LATTICE_V: [f32; 259] = {
    let mut t = [0.0; 259];
    let mut j = 0;
    while j < 259 {
        t[j] = ((j as u32 % 256).wrapping_mul(G1) >> 8) as f32 * (1.0 / 16_777_216.0);
        j += 1;
    }
    t
};

/// Lane masks of the four-bit numbers: lane l is 1 where bit l is set.
static VISIBLE_LANES: [Vec4; 16] = {
    let mut t = [Vec4::ZERO; 16];
    let mut b = 0;
    while b < 16 {
        t[b] = Vec4::new(bit(b, 0), bit(b, 1), bit(b, 2), bit(b, 3));
        b += 1;
    }
    t
};

const fn bit(b: usize, l: usize) -> f32 {
    ((b >> l) & 1) as f32
}

/// (Δ + offset) mod 1 for Δ and offsets in [0, 1): one subtraction, exact by Sterbenz's lemma.
#[inline(always)]
fn wrap(x: Vec4) -> Vec4 {
    Vec4::select(x.cmpge(Vec4::ONE), x - Vec4::ONE, x)
}

/// One light, planar: the batch four lanes at a time (glam's `Vec4`: SSE2 on x86-64). The
/// estimator is the general path's (`AreaLight::sample_point`, `Lights::sample`,
/// `Interaction::spawn_ray_to`, the power heuristic): the same points, rays and weights, the
/// weights' algebra rearranged to spare the divider (see the comments below), so the values
/// agree to rounding, not bit for bit.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn planar<const LAMBERT: bool>(
    scene: &Scene,
    light: &PlanarLight,
    si: &Interaction,
    frame: &Frame,
    wo: Vec3A,
    material: &Material,
    n: u32,
    delta: [f32; 3],
    stats: &mut RayStats,
) -> Color {
    // Lambertian: the albedo and the side `wo` is on (`sample_lights` checked it is lit).
    let (albedo, side) = match (&material.bsdf, material.orient(wo)) {
        (Bsdf::Lambert(b), Some(side)) => (b.albedo, side),
        _ => (Color::ZERO, 1.0),
    };
    let p = si.p;
    // The two possible ray origins, above and below the surface (`offset_ray_origin`).
    let origins = [
        offset_ray_origin(p, si.p_err, si.ng, si.ng),
        offset_ray_origin(p, si.p_err, si.ng, -si.ng),
    ];
    let sp = |v: Vec3A| [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)];
    let (a, b, c) = (sp(light.a), sp(light.b), sp(light.c));
    let (nl, off) = (sp(light.normal), sp(light.offset));
    let (ps, ns, ng) = (sp(p), sp(frame.n), sp(si.ng));
    let (o_above, o_below) = (sp(origins[0]), sp(origins[1]));
    let dot = |x: &[Vec4; 3], y: &[Vec4; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let (du, dv) = (Vec4::splat(delta[0]), Vec4::splat(delta[1]));
    let nf = n as f32;
    let (inv_n, area) = (Vec4::splat(1.0 / nf), Vec4::splat(light.area));
    let lane = Vec4::new(0.0, 1.0, 2.0, 3.0);
    let side = Vec4::splat(side);
    let mut acc = Vec4::ZERO;
    let mut sum = Color::ZERO;
    let mut i = 0;
    while i < n {
        let m = (n - i).min(BATCH as u32);
        let mut pk = ShadowPacket {
            o: origins[0],
            d: [[0.0; PACKET]; 3],
            t_max: [1.0 - SHADOW_EPSILON; PACKET],
        };
        let mut wi = [[0f32; BATCH]; 3];
        let (mut pdf, mut cos_s, mut weight_s) = ([0f32; BATCH], [0f32; BATCH], [0f32; BATCH]);
        // Lambertian weights, four lanes a vector.
        let mut weight = [Vec4::ZERO; BATCH / 4];
        // Bit l: sample i + l is usable, its ray leaves below the surface.
        let (mut ok, mut below) = (0u32, 0u32);
        for h in 0..m.div_ceil(4) as usize {
            let j = i + 4 * h as u32;
            let jv = Vec4::splat(j as f32) + lane;
            let u = wrap(du + jv * inv_n);
            let k = (j % 256) as usize;
            let v = wrap(dv + Vec4::from_slice(&LATTICE_V[k..k + 4]));
            // The point's weights: (1, u, v), or a triangle's (Triangle::sample_uniform).
            let (w0, w1, w2) = if light.triangle {
                let su = sqrt4(u);
                let (bu, bv) = (Vec4::ONE - su, v * su);
                (Vec4::ONE - bu - bv, bu, bv)
            } else {
                (Vec4::ONE, u, v)
            };
            let q: [Vec4; 3] = std::array::from_fn(|x| a[x] * w0 + b[x] * w1 + c[x] * w2);
            let d: [Vec4; 3] = std::array::from_fn(|x| q[x] - ps[x]);
            let dist2 = dot(&d, &d);
            let under = dot(&ng, &d).cmplt(Vec4::ZERO);
            let mut good = jv.cmplt(Vec4::splat(nf)) & dist2.cmpgt(Vec4::ZERO);
            // The divider, not the arithmetic, bounds this loop (divisions and square roots
            // issue one every few cycles and wait a dozen), so each lane pays as few as it can.
            if LAMBERT {
                // f·|cos| = (ρ/π)·c and p_bsdf = c/π, with c the cosine on the lit side (ρ/π
                // is applied to the sum), and p_light = r²/(cos_l·A). The power heuristic's
                // weight over p_light, c·(n·p_light)²/((n·p_light)² + p_bsdf²)/p_light, is
                // n²π²·t/(n²π² + t²) with t = c·cos_l·A/r² = (c·r)(cos_l·A·r)/(r²)²: no square
                // root, one division for 1/r² and one for the weight; finite, and 0 where t is
                // (a light seen edge-on), as the limit is.
                let a_l = -dot(&nl, &d) * area; // cos_l·A·r
                let a_s = dot(&ns, &d) * side; // c·r
                good &= a_l.cmpgt(Vec4::ZERO) & a_s.cmpgt(Vec4::ZERO);
                let inv = Vec4::ONE / dist2;
                let t = (a_l * a_s) * (inv * inv);
                let k = Vec4::splat(nf * nf * PI * PI);
                weight[h] = (k * t) / (k + t * t);
            } else {
                // The pdf is carried as its reciprocal x = 1/p_light = cos_l·A/r².
                let inv_r = Vec4::ONE / sqrt4(dist2);
                let w: [Vec4; 3] = std::array::from_fn(|x| d[x] * inv_r);
                let cos_l = -dot(&nl, &w);
                let x_l = cos_l * area * (inv_r * inv_r);
                good &= cos_l.cmpgt(Vec4::ZERO);
                (Vec4::ONE / x_l).write_to_slice(&mut pdf[4 * h..]);
                dot(&ns, &w).write_to_slice(&mut cos_s[4 * h..]);
                for x in 0..3 {
                    w[x].write_to_slice(&mut wi[x][4 * h..]);
                }
            }
            // The ray: from the origin on its side to the point pushed off the light towards
            // it (`offset_ray_origin` at both ends).
            let o: [Vec4; 3] = std::array::from_fn(|x| Vec4::select(under, o_below[x], o_above[x]));
            let back: [Vec4; 3] = std::array::from_fn(|x| o[x] - q[x]);
            let towards = dot(&back, &nl).cmplt(Vec4::ZERO);
            for x in 0..3 {
                let target = Vec4::select(towards, q[x] - off[x], q[x] + off[x]);
                (target - o[x]).write_to_slice(&mut pk.d[x][4 * h..]);
            }
            ok |= good.bitmask() << (4 * h);
            below |= under.bitmask() << (4 * h);
        }
        // Other BSDFs, sample by sample.
        let mut colour = [Color::ZERO; BATCH];
        if !LAMBERT {
            let mut mm = ok;
            while mm != 0 {
                let l = mm.trailing_zeros() as usize;
                mm &= mm - 1;
                let w = Vec3A::new(wi[0][l], wi[1][l], wi[2][l]);
                let local = Vec3A::new(w.dot(frame.s), w.dot(frame.t), cos_s[l]);
                let (f, bsdf_pdf) = material.eval_pdf(wo, local);
                let f = f * cos_s[l].abs();
                if f == Color::ZERO {
                    ok &= !(1 << l);
                }
                colour[l] = f;
                weight_s[l] = power_heuristic(nf * pdf[l], bsdf_pdf) / pdf[l];
            }
        }
        // The shadow rays, in up to two packets by the side of the surface they leave
        // (almost always one).
        let mut visible = 0;
        for (s, active) in [ok & !below, ok & below].into_iter().enumerate() {
            if active != 0 {
                pk.o = origins[s];
                stats.shadow_rays += active.count_ones() as u64;
                visible |= active & !scene.occluded_packet(&pk, active);
            }
        }
        // Contributions summed in a fixed order: Lambertian weights a vector at a time (no
        // chain of dependent scalar additions), the others sample by sample.
        if LAMBERT {
            for (h, wv) in weight.iter().enumerate().take(m.div_ceil(4) as usize) {
                let bits = visible >> (4 * h);
                let on = VISIBLE_LANES[(bits & 15) as usize];
                acc += Vec4::select(on.cmpne(Vec4::ZERO), *wv, Vec4::ZERO);
            }
        } else {
            while visible != 0 {
                let l = visible.trailing_zeros() as usize;
                visible &= visible - 1;
                sum += colour[l] * weight_s[l];
            }
        }
        i += m;
    }
    let sum = if LAMBERT {
        albedo * FRAC_1_PI * light.radiance * acc.element_sum()
    } else {
        sum * light.radiance
    };
    sum / nf
}
