//! Photon shooting: photons leave the lights in proportion to their power: area lights from
//! a point uniform on the light in a cosine-distributed direction, spot lights uniformly
//! within their cone, image environments from a disk facing a direction the map samples
//! (point, directional and constant lights emit none), and bounce with the path tracer's
//! BSDFs (importance transport); Russian roulette by the BSDF sample's weight (the albedo for
//! diffuse surfaces) keeps their power nearly constant. Photons are stored at non-specular
//! hits.
//!
//! Photon i draws its numbers from a PCG32 stream keyed by (seed, pass, i) and photons are
//! traced in parallel chunks collected in index order: the photons, and the maps built from
//! them, are the same bits on any number of threads.

use super::photon::Photon;
use crate::geometry::ray::offset_ray_origin;
use crate::geometry::{Frame, Ray};
use crate::light::distribution::Distribution1D;
use crate::light::OtherLight;
use crate::material::sampling::square_to_cosine_hemisphere;
use crate::material::TransportMode;
use crate::sampler::{mix64, Sampler};
use crate::scene::Scene;
use crate::Color;
use glam::Vec3A;
use rayon::prelude::*;

/// Which photons a pass keeps.
#[derive(Clone, Copy, Debug)]
pub struct TraceOptions {
    pub seed: u64,
    /// Distinguishes the random streams of different passes (global, caustic, SPPM
    /// iterations) under one seed.
    pub pass: u64,
    /// Longest photon path in segments (light to the last stored hit).
    pub max_depth: u32,
    /// Keep only photons whose path was specular since the light (and then stop).
    pub caustic_only: bool,
    /// Keep photons only from this many segments on (1: all; 2: not the direct ones).
    pub min_depth: u32,
    /// Also record shadow photons: the continuation of each photon's first segment through
    /// the surfaces behind the first hit.
    pub shadow: bool,
    /// Also record each stored photon's surface normal (on the side it arrived from), in
    /// `Traced::normals`: the global pass's irradiance points need it.
    pub normals: bool,
}

impl Default for TraceOptions {
    fn default() -> Self {
        TraceOptions {
            seed: 0,
            pass: 0,
            max_depth: u32::MAX,
            caustic_only: false,
            min_depth: 1,
            shadow: false,
            normals: false,
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct Traced {
    pub photons: Vec<Photon>,
    pub shadow: Vec<Photon>,
    /// With `TraceOptions::normals`: the normal at each of `photons`, same order.
    pub normals: Vec<glam::Vec3A>,
    /// Photons emitted (the powers are normalised by it).
    pub emitted: u64,
    pub rays: u64,
}

/// Photons traced per parallel work item.
const CHUNK: u64 = 4096;
/// Surfaces a shadow photon's ray passes through at most.
const MAX_SHADOW_HITS: u32 = 4;

/// The distribution over the lights photons leave, by power: the area lights, then the
/// others in `Lights::others` order, of which spots and image environments emit (the
/// others weigh 0); None without any.
pub fn light_distribution(scene: &Scene) -> Option<Distribution1D> {
    let (_, radius) = scene_sphere(scene);
    let powers: Vec<f32> = scene
        .lights
        .lights
        .iter()
        .map(|l| l.power())
        .chain(scene.lights.others.iter().map(|o| match o {
            OtherLight::Spot(_) | OtherLight::Envmap(_) => o.power(radius),
            _ => 0.0,
        }))
        .collect();
    let d = Distribution1D::new(&powers);
    (!d.is_empty()).then_some(d)
}

/// A sphere around the scene's primitives: centre and radius (a little larger than half the
/// bounds' diagonal, so that a photon from an environment starts outside everything).
fn scene_sphere(scene: &Scene) -> (Vec3A, f32) {
    match scene.bvh.bounds() {
        Some(b) => (
            0.5 * (b.min + b.max),
            (0.5 * (b.max - b.min).length() * 1.001).max(1e-3),
        ),
        None => (Vec3A::ZERO, 1.0),
    }
}

/// A photon's first ray and power (before the division by the photon count) from a light
/// that is not a surface, chosen with probability `pmf`; None when the sample carries
/// nothing.
fn emit_other(
    scene: &Scene,
    light: &OtherLight,
    pmf: f32,
    s: &mut Sampler,
) -> Option<(Ray, Color)> {
    match light {
        // A direction uniform in the cone of the cutoff around the axis (pdf 1/(2π(1 −
        // cos θmax))), weighted by the intensity the light sends along it.
        OtherLight::Spot(sp) => {
            let u = s.next_2d();
            let cos_max = sp.cos_cutoff();
            let cos_t = 1.0 - u.x * (1.0 - cos_max);
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let (sin_p, cos_p) = (2.0 * std::f32::consts::PI * u.y).sin_cos();
            let d = Frame::from_normal(sp.axis()).to_world(Vec3A::new(
                sin_t * cos_p,
                sin_t * sin_p,
                cos_t,
            ));
            let pdf = 1.0 / (2.0 * std::f32::consts::PI * (1.0 - cos_max));
            let i = sp.intensity_towards(d);
            (i != Color::ZERO).then(|| (Ray::new(sp.position, d), i / (pdf * pmf)))
        }
        // A direction by the map's own sampling, and a point uniform on a disk of the scene
        // sphere's radius facing it, outside the sphere: L·πR²/p(ω) (pbrt-v4's
        // `ImageInfiniteLight::SampleLe`).
        OtherLight::Envmap(e) => {
            let (wi, le, pdf) = e.sample(s.next_2d())?;
            let (centre, r) = scene_sphere(scene);
            let u = s.next_2d();
            let (rr, (sin_p, cos_p)) =
                (r * u.x.sqrt(), (2.0 * std::f32::consts::PI * u.y).sin_cos());
            let o = centre
                + wi * r
                + Frame::from_normal(wi).to_world(Vec3A::new(rr * cos_p, rr * sin_p, 0.0));
            let area = std::f32::consts::PI * r * r;
            Some((Ray::new(o, -wi), le * (area / (pdf * pmf))))
        }
        _ => None,
    }
}

/// Emits `n` photons and traces them through the scene.
pub fn trace_photons(scene: &Scene, n: u64, o: &TraceOptions) -> Traced {
    trace_photons_until(scene, n, o, &|| false).expect("never stopped")
}

/// [`trace_photons`], asking `stop` before each chunk of photons: None once it answers true
/// (a pass cut short would be biased, so nothing of it is kept).
pub fn trace_photons_until(
    scene: &Scene,
    n: u64,
    o: &TraceOptions,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<Traced> {
    let Some(dist) = light_distribution(scene) else {
        return Some(Traced {
            emitted: n,
            ..Default::default()
        });
    };
    let chunks = n.div_ceil(CHUNK);
    let parts: Vec<Option<Traced>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            if stop() {
                return None;
            }
            let mut t = Traced::default();
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                trace_one(scene, &dist, n, i, o, &mut t);
            }
            Some(t)
        })
        .collect();
    let parts: Vec<Traced> = parts.into_iter().collect::<Option<_>>()?;
    let total: usize = parts.iter().map(|t| t.photons.len()).sum();
    let total_shadow: usize = parts.iter().map(|t| t.shadow.len()).sum();
    let mut out = Traced {
        photons: Vec::with_capacity(total),
        shadow: Vec::with_capacity(total_shadow),
        normals: Vec::new(),
        emitted: n,
        rays: 0,
    };
    for p in parts {
        out.photons.extend_from_slice(&p.photons);
        out.shadow.extend_from_slice(&p.shadow);
        out.normals.extend_from_slice(&p.normals);
        out.rays += p.rays;
    }
    Some(out)
}

/// The random numbers of photon `i` of a pass.
pub fn photon_sampler(seed: u64, pass: u64, i: u64) -> Sampler {
    let key = mix64(mix64(seed ^ 0x5851_f42d_4c95_7f2d) ^ pass.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    Sampler::from_state(mix64(key ^ i.wrapping_mul(0xd1b5_4a32_d192_ed03)), key)
}

fn trace_one(
    scene: &Scene,
    dist: &Distribution1D,
    n: u64,
    i: u64,
    o: &TraceOptions,
    t: &mut Traced,
) {
    let mut s = photon_sampler(o.seed, o.pass, i);
    let Some((id, pmf)) = dist.sample_discrete(s.next_1d()) else {
        return;
    };
    let (mut ray, mut power) = match scene.lights.lights.get(id) {
        Some(light) => {
            let u = s.next_2d();
            let (p, nl, err) = light.sample_point(u);
            let d = Frame::from_normal(nl).to_world(square_to_cosine_hemisphere(s.next_2d()));
            // Le·cos / (pmf · 1/A · cos/π) / n
            let le = scene.lights.radiance_of_sample(id, u, nl);
            let power = le * (std::f32::consts::PI * light.area / (pmf * n as f32));
            (Ray::new(offset_ray_origin(p, err, nl, d), d), power)
        }
        None => {
            let other = &scene.lights.others[id - scene.lights.lights.len()];
            let Some((ray, power)) = emit_other(scene, other, pmf, &mut s) else {
                return;
            };
            (ray, power / n as f32)
        }
    };
    let mut depth = 1u32;
    let mut specular_path = true;
    loop {
        t.rays += 1;
        let Some(si) = scene.intersect(&ray) else {
            break;
        };
        if o.shadow && depth == 1 {
            let mut r = Ray::new(offset_ray_origin(si.p, si.p_err, si.ng, ray.d), ray.d);
            for _ in 0..MAX_SHADOW_HITS {
                t.rays += 1;
                let Some(h) = scene.intersect(&r) else { break };
                t.shadow.push(Photon::shadow(h.p, -ray.d));
                r = Ray::new(offset_ray_origin(h.p, h.p_err, h.ng, ray.d), ray.d);
            }
        }
        let material = scene.material_at(&si);
        if material.is_black() {
            break;
        }
        if !material.is_specular() {
            let caustic = specular_path && depth > 1;
            if depth >= o.min_depth && (!o.caustic_only || caustic) {
                t.photons
                    .push(Photon::new(si.p, power, -ray.d, depth, caustic));
                if o.normals {
                    let n = if si.ng.dot(ray.d) < 0.0 {
                        si.ng
                    } else {
                        -si.ng
                    };
                    t.normals.push(n);
                }
            }
            if o.caustic_only {
                break;
            }
            specular_path = false;
        }
        if depth >= o.max_depth {
            break;
        }
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        let u1 = s.next_1d();
        let u2 = s.next_2d();
        let Some(bs) = material.sample(wo, u1, u2, TransportMode::Importance) else {
            break;
        };
        // Russian roulette by the sample's weight: survivors keep (about) their power.
        let q = bs.weight.max_element().min(1.0);
        if q.is_nan() || q <= 0.0 || s.next_1d() >= q {
            break;
        }
        power *= bs.weight / q;
        ray = si.spawn_ray(frame.to_world(bs.wi));
        depth += 1;
    }
}

/// Total power of the scene's area lights per RGB channel (W).
pub fn light_power_rgb(scene: &Scene) -> Color {
    scene
        .lights
        .lights
        .iter()
        .map(|l| l.radiance * (std::f32::consts::PI * l.area))
        .sum()
}
