//! AOVs (arbitrary output variables): extra layers of the output EXR for denoisers (Open Image
//! Denoise, OptiX) and compositing, with `--aov albedo,normal,depth,variance,spp`.
//!
//! Layers (channels named `LAYER.CHANNEL`, OpenEXR's layer convention; 32-bit float even with
//! `--half`):
//! - `albedo.R/G/B`: the reflectance ([`crate::material::Material::albedo`], textures
//!   evaluated) of the first non-specular surface the camera ray reaches. As Open Image Denoise
//!   recommends, delta surfaces (mirror, smooth glass, smooth metal, thin glass) are followed
//!   along a sampled direction, up to [`MAX_SPECULAR`] of them, multiplying by their own
//!   albedo (glass: 1). Misses: 0.
//! - `normal.X/Y/Z`: the world-space shading normal at that same surface, turned towards the
//!   ray that reached it. Misses: (0, 0, 0), the null vector OIDN takes as "no surface".
//! - `emission.R/G/B`: the radiance emitted towards the camera by the surface (or the
//!   constant environment) each camera ray reaches first, as the path and direct integrators
//!   add it on the ray's first segment (none with `hide_emitters` or `max_depth` 0). It has no
//!   Monte Carlo noise but the pixel coverage, so [`crate::denoise`] keeps it out of the
//!   denoiser.
//! - `depth.Z`: the distance from the camera to the first surface hit (along the camera ray,
//!   not the z-depth); the mean over the samples that hit, +∞ where none does.
//! - `variance.R/G/B`: the estimated variance of each pixel's mean, s²/n
//!   ([`Film::variance_of_mean`]).
//! - `spp.Y`: the samples in each pixel's mean (with `--adaptive` they differ).
//!
//! Albedo, normal, emission and depth are averaged over [`GUIDE_SPP`] camera rays per pixel: the first
//! samples' own rays (same seed, pixel and sample index), traced only to the first
//! non-specular hit. They do not depend on how long the render runs, so a partial image, an
//! interrupted and a resumed render all carry the same guide layers.

use crate::film::Film;
use crate::geometry::Frame;
use crate::material::TransportMode;
use crate::render::{camera_for, with_threads, RenderError, RenderSettings};
use crate::sampler::Sampler;
use crate::scene::Scene;
use crate::Color;
use glam::Vec3A;
use rayon::prelude::*;

/// Camera rays per pixel for the albedo, normal and depth layers.
pub const GUIDE_SPP: u32 = 16;
/// Delta surfaces followed to find the albedo and normal.
pub const MAX_SPECULAR: u32 = 8;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aov {
    Albedo,
    Normal,
    Emission,
    Depth,
    Variance,
    Spp,
}

impl Aov {
    pub const ALL: [Aov; 6] = [
        Aov::Albedo,
        Aov::Normal,
        Aov::Emission,
        Aov::Depth,
        Aov::Variance,
        Aov::Spp,
    ];

    pub fn name(&self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Emission => "emission",
            Aov::Depth => "depth",
            Aov::Variance => "variance",
            Aov::Spp => "spp",
        }
    }

    /// The layer's channels in the EXR (`LAYER.CHANNEL`), in order, as [`channels`] writes
    /// them.
    pub fn channels(&self) -> &'static [&'static str] {
        match self {
            Aov::Albedo | Aov::Emission | Aov::Variance => &["R", "G", "B"],
            Aov::Normal => &["X", "Y", "Z"],
            Aov::Depth => &["Z"],
            Aov::Spp => &["Y"],
        }
    }

    /// Whether the layer needs the guide rays of [`render_guides`].
    pub fn needs_guides(&self) -> bool {
        matches!(self, Aov::Albedo | Aov::Normal | Aov::Emission | Aov::Depth)
    }
}

/// Parses a comma-separated list of AOV names (each at most once).
pub fn parse_list(text: &str) -> Result<Vec<Aov>, String> {
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim) {
        let aov = Aov::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .ok_or_else(|| {
                format!(
                    "unknown AOV '{name}' (known: albedo, normal, emission, depth, variance, spp)"
                )
            })?;
        if out.contains(&aov) {
            return Err(format!("AOV '{name}' is given twice"));
        }
        out.push(aov);
    }
    Ok(out)
}

/// Albedo, normal, emission and depth per pixel of the film, row-major.
#[derive(Clone, Debug)]
pub struct Guides {
    pub albedo: Vec<Color>,
    pub normal: Vec<Vec3A>,
    pub emission: Vec<Color>,
    /// Whether the guide rays of the pixel saw different emission (an emitter's edge).
    pub emission_edge: Vec<bool>,
    pub depth: Vec<f32>,
}

/// One pixel's guides: albedo, normal, emission, whether the emission varied, depth.
type GuidePixel = (Color, Vec3A, Color, bool, f32);

/// Traces the guide rays ([`GUIDE_SPP`] per pixel) of the film window.
pub fn render_guides(scene: &Scene, s: &RenderSettings) -> Result<Guides, RenderError> {
    let camera = camera_for(scene, s)?;
    let (ox, oy, fw, fh) = s.window();
    // As the integrators see emitters on the first segment (path.rs, direct.rs).
    let sees_emitters = !s.params.hide_emitters && s.params.max_depth != Some(0);
    let rows: Vec<Vec<GuidePixel>> = with_threads(s, || {
        (0..fh)
            .into_par_iter()
            .map(|y| {
                (0..fw)
                    .map(|x| {
                        let (gx, gy) = (x + ox, y + oy);
                        let pixel = gy as u64 * s.width as u64 + gx as u64;
                        // Sums in f64: exact for the 16 values of a flat surface.
                        let (mut albedo, mut normal) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
                        let mut emission = glam::DVec3::ZERO;
                        let (mut first_le, mut edge) = (None, false);
                        let (mut depth, mut hits) = (0.0f64, 0u32);
                        for i in 0..GUIDE_SPP {
                            let mut sampler =
                                Sampler::for_sample(s.sampler, s.seed, pixel, i as u64);
                            let mut ray = camera.sample_ray(gx, gy, &mut sampler);
                            let le = if sees_emitters {
                                seen_emission(scene, &ray)
                            } else {
                                Color::ZERO
                            };
                            first_le.get_or_insert(le);
                            edge |= first_le != Some(le);
                            emission += le.as_dvec3();
                            let mut tint = Color::ONE;
                            for bounce in 0..=MAX_SPECULAR {
                                let Some(si) = scene.intersect(&ray) else {
                                    break;
                                };
                                if bounce == 0 {
                                    depth += si.t as f64;
                                    hits += 1;
                                }
                                let m = scene.material_at(&si);
                                if !m.is_specular() || bounce == MAX_SPECULAR {
                                    albedo += (tint * m.albedo()).as_dvec3();
                                    let n = if si.ns.dot(ray.d) > 0.0 {
                                        -si.ns
                                    } else {
                                        si.ns
                                    };
                                    normal += n.as_dvec3();
                                    break;
                                }
                                tint *= m.albedo();
                                let frame = Frame::from_normal(si.ns);
                                let wo = frame.to_local(-ray.d);
                                let u1 = sampler.next_1d();
                                let u2 = sampler.next_2d();
                                let Some(bs) = m.sample(wo, u1, u2, TransportMode::Radiance) else {
                                    break;
                                };
                                ray = si.spawn_ray(frame.to_world(bs.wi));
                            }
                        }
                        let k = 1.0 / GUIDE_SPP as f64;
                        let d = if hits > 0 {
                            (depth / hits as f64) as f32
                        } else {
                            f32::INFINITY
                        };
                        (
                            (albedo * k).as_vec3(),
                            Vec3A::from((normal * k).as_vec3()),
                            (emission * k).as_vec3(),
                            edge,
                            d,
                        )
                    })
                    .collect()
            })
            .collect()
    })?;
    let flat: Vec<GuidePixel> = rows.into_iter().flatten().collect();
    Ok(Guides {
        albedo: flat.iter().map(|p| p.0).collect(),
        normal: flat.iter().map(|p| p.1).collect(),
        emission: flat.iter().map(|p| p.2).collect(),
        emission_edge: flat.iter().map(|p| p.3).collect(),
        depth: flat.iter().map(|p| p.4).collect(),
    })
}

/// The radiance emitted towards the camera by what `ray` (a camera ray) reaches first, as the
/// path and direct integrators add it on the first segment (`emitted` and `escaped` with no
/// previous vertex: no MIS weight).
fn seen_emission(scene: &Scene, ray: &crate::geometry::Ray) -> Color {
    match scene.intersect(ray) {
        Some(si) if si.light != crate::scene::NO_LIGHT => {
            scene.lights.le(si.light, si.ng, si.uv, -ray.d)
        }
        Some(_) => Color::ZERO,
        None => scene
            .lights
            .environment(ray.d)
            .map_or(Color::ZERO, |(le, _)| le),
    }
}

/// Ray positions per pixel of the quadrature in [`emission_split`]: a Fibonacci lattice of
/// F(14) = 377 points, with F(13) = 233 as its generator. Its points have distinct x and
/// distinct y coordinates, so the covered fraction of a pixel crossed by an axis-aligned edge
/// is found to within 1/377 (a 16 × 16 grid: only to 1/16), and edges of other slopes within
/// O(log N / N) (the lattice's discrepancy; Niederreiter, "Random Number Generation and
/// Quasi-Monte Carlo Methods", 1992, ch. 5).
pub const EMISSION_POINTS: u32 = 377;
const EMISSION_GENERATOR: u32 = 233;

/// The directly seen emission of each pixel twice, for [`crate::denoise`]: (what the render's
/// own samples added, the pixel's integral of it). Where the guide rays of the pixel and of its
/// eight neighbours all saw the same emission (inside an emitter, or none), both are the guide
/// value. On an emitter's edge (which may cross a pixel that all of its own guide rays missed
/// or hit, so the neighbours are asked too), the
/// first is the mean over the camera rays of the pixel's samples [0, count) (the same rays as
/// the render's: same seed, pixel and index), the second the mean over a grid of
/// [`EMISSION_POINTS`] ray positions in the pixel (the box filter the samples estimate), which
/// has no coverage noise left. The cost is one primary ray per sample of edge pixels only.
pub fn emission_split(
    scene: &Scene,
    s: &RenderSettings,
    guides: &Guides,
    film: &Film,
) -> Result<(Vec<Color>, Vec<Color>), RenderError> {
    let camera = camera_for(scene, s)?;
    let (ox, oy, fw, fh) = s.window();
    let edge = |i: usize| {
        let (x, y) = ((i as u32 % fw) as i64, (i as u32 / fw) as i64);
        let e = guides.emission[i];
        guides.emission_edge[i]
            || (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (xx, yy) = (x + dx, y + dy);
                    xx >= 0
                        && yy >= 0
                        && xx < fw as i64
                        && yy < fh as i64
                        && guides.emission[(yy * fw as i64 + xx) as usize] != e
                })
            })
    };
    let sees_emitters = !s.params.hide_emitters && s.params.max_depth != Some(0);
    let pairs: Vec<(Color, Color)> = with_threads(s, || {
        (0..guides.emission.len())
            .into_par_iter()
            .map(|i| {
                let e = guides.emission[i];
                if !sees_emitters || !edge(i) {
                    return (e, e);
                }
                let (gx, gy) = (i as u32 % fw + ox, i as u32 / fw + oy);
                let pixel = gy as u64 * s.width as u64 + gx as u64;
                let n = film.count[i];
                let mut own = glam::DVec3::ZERO;
                for k in 0..n {
                    let mut sampler = Sampler::for_sample(s.sampler, s.seed, pixel, k as u64);
                    let ray = camera.sample_ray(gx, gy, &mut sampler);
                    own += seen_emission(scene, &ray).as_dvec3();
                }
                let m = EMISSION_POINTS;
                let mut grid = glam::DVec3::ZERO;
                for k in 0..m {
                    let u = glam::Vec2::new(
                        (k as f32 + 0.5) / m as f32,
                        ((k * EMISSION_GENERATOR % m) as f32 + 0.5) / m as f32,
                    );
                    grid += seen_emission(scene, &camera.generate_ray(gx, gy, u)).as_dvec3();
                }
                (
                    (own / n.max(1) as f64).as_vec3(),
                    (grid / m as f64).as_vec3(),
                )
            })
            .collect()
    })?;
    Ok(pairs.into_iter().unzip())
}

/// The extra channels for `aovs`: (name, one value per pixel). `guides` must be given when
/// any AOV needs them.
pub fn channels(aovs: &[Aov], guides: Option<&Guides>, film: &Film) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    let guides = || guides.expect("guide layers rendered");
    for aov in aovs {
        match aov {
            Aov::Albedo => {
                for (c, ch) in ["R", "G", "B"].iter().enumerate() {
                    let v = guides().albedo.iter().map(|p| p[c]).collect();
                    out.push((format!("albedo.{ch}"), v));
                }
            }
            Aov::Normal => {
                for (c, ch) in ["X", "Y", "Z"].iter().enumerate() {
                    let v = guides().normal.iter().map(|p| p[c]).collect();
                    out.push((format!("normal.{ch}"), v));
                }
            }
            Aov::Emission => {
                for (c, ch) in ["R", "G", "B"].iter().enumerate() {
                    let v = guides().emission.iter().map(|p| p[c]).collect();
                    out.push((format!("emission.{ch}"), v));
                }
            }
            Aov::Depth => out.push(("depth.Z".into(), guides().depth.clone())),
            Aov::Variance => {
                let var = film.variance_of_mean();
                for (c, ch) in ["R", "G", "B"].iter().enumerate() {
                    let v = var.pixels.iter().map(|p| p[c]).collect();
                    out.push((format!("variance.{ch}"), v));
                }
            }
            Aov::Spp => out.push((
                "spp.Y".into(),
                film.count.iter().map(|&n| n as f32).collect(),
            )),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`Aov::channels`] names the channels [`channels`] writes, in order.
    #[test]
    fn channel_names_match_the_layers() {
        let film = Film::new(2, 1);
        let guides = Guides {
            albedo: vec![Color::ZERO; 2],
            normal: vec![Vec3A::ZERO; 2],
            emission: vec![Color::ZERO; 2],
            emission_edge: vec![false; 2],
            depth: vec![0.0; 2],
        };
        for aov in Aov::ALL {
            let names: Vec<String> = channels(&[aov], Some(&guides), &film)
                .into_iter()
                .map(|(n, v)| {
                    assert_eq!(v.len(), 2);
                    n
                })
                .collect();
            let want: Vec<String> = aov
                .channels()
                .iter()
                .map(|c| format!("{}.{c}", aov.name()))
                .collect();
            assert_eq!(names, want);
        }
    }
}
