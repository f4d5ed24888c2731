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
//! - `depth.Z`: the distance from the camera to the first surface hit (along the camera ray,
//!   not the z-depth); the mean over the samples that hit, +∞ where none does.
//! - `variance.R/G/B`: the estimated variance of each pixel's mean, s²/n
//!   ([`Film::variance_of_mean`]).
//! - `spp.Y`: the samples in each pixel's mean (with `--adaptive` they differ).
//!
//! Albedo, normal and depth are averaged over [`GUIDE_SPP`] camera rays per pixel: the first
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
    Depth,
    Variance,
    Spp,
}

impl Aov {
    pub const ALL: [Aov; 5] = [
        Aov::Albedo,
        Aov::Normal,
        Aov::Depth,
        Aov::Variance,
        Aov::Spp,
    ];

    pub fn name(&self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Variance => "variance",
            Aov::Spp => "spp",
        }
    }

    /// The layer's channels in the EXR (`LAYER.CHANNEL`), in order, as [`channels`] writes
    /// them.
    pub fn channels(&self) -> &'static [&'static str] {
        match self {
            Aov::Albedo | Aov::Variance => &["R", "G", "B"],
            Aov::Normal => &["X", "Y", "Z"],
            Aov::Depth => &["Z"],
            Aov::Spp => &["Y"],
        }
    }

    /// Whether the layer needs the guide rays of [`render_guides`].
    pub fn needs_guides(&self) -> bool {
        matches!(self, Aov::Albedo | Aov::Normal | Aov::Depth)
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
                format!("unknown AOV '{name}' (known: albedo, normal, depth, variance, spp)")
            })?;
        if out.contains(&aov) {
            return Err(format!("AOV '{name}' is given twice"));
        }
        out.push(aov);
    }
    Ok(out)
}

/// Albedo, normal and depth per pixel of the film, row-major.
#[derive(Clone, Debug)]
pub struct Guides {
    pub albedo: Vec<Color>,
    pub normal: Vec<Vec3A>,
    pub depth: Vec<f32>,
}

/// Traces the guide rays ([`GUIDE_SPP`] per pixel) of the film window.
pub fn render_guides(scene: &Scene, s: &RenderSettings) -> Result<Guides, RenderError> {
    let camera = camera_for(scene, s)?;
    let (ox, oy, fw, fh) = s.window();
    let rows: Vec<Vec<(Color, Vec3A, f32)>> = with_threads(s, || {
        (0..fh)
            .into_par_iter()
            .map(|y| {
                (0..fw)
                    .map(|x| {
                        let (gx, gy) = (x + ox, y + oy);
                        let pixel = gy as u64 * s.width as u64 + gx as u64;
                        // Sums in f64: exact for the 16 values of a flat surface.
                        let (mut albedo, mut normal) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
                        let (mut depth, mut hits) = (0.0f64, 0u32);
                        for i in 0..GUIDE_SPP {
                            let mut sampler =
                                Sampler::for_sample(s.sampler, s.seed, pixel, i as u64);
                            let mut ray = camera.generate_ray(gx, gy, sampler.next_2d());
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
                            d,
                        )
                    })
                    .collect()
            })
            .collect()
    })?;
    let flat: Vec<(Color, Vec3A, f32)> = rows.into_iter().flatten().collect();
    Ok(Guides {
        albedo: flat.iter().map(|p| p.0).collect(),
        normal: flat.iter().map(|p| p.1).collect(),
        depth: flat.iter().map(|p| p.2).collect(),
    })
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
