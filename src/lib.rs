//! mcrt: a physically based Monte Carlo ray tracer.
//!
//! The library loads a scene ([`load_scene`]), renders it ([`render::render`]) and writes
//! images ([`image::write_image`]). Data flows one way: file → [`scene::SceneDesc`] →
//! [`scene::Scene`] (primitives, BVH, materials, lights, cameras) → integrator over image
//! tiles → [`film::Film`] → image file.

pub mod accel;
pub mod camera;
pub mod film;
pub mod geometry;
pub mod image;
pub mod integrator;
pub mod light;
pub mod material;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod texture;

use integrator::{IntegratorKind, IntegratorParams, RussianRoulette};
use render::RenderSettings;
use scene::desc::FileSettings;
use scene::{SceneDesc, SceneError};
use std::path::Path;

/// Linear RGB radiance or reflectance.
pub type Color = glam::Vec3;

/// Everything that can go wrong, by kind: bad input (a scene file, a flag, an output path)
/// versus a failure while rendering or writing.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{0}")]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Image(#[from] image::ImageError),
    #[error("{0}")]
    Render(#[from] render::RenderError),
    #[error("{0}")]
    Usage(String),
}

impl Error {
    /// Process exit status: 2 for bad input, 1 for anything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Scene(_)
            | Error::Usage(_)
            | Error::Render(render::RenderError::NoCamera(..))
            | Error::Render(render::RenderError::NoCameras) => 2,
            Error::Image(
                image::ImageError::UnknownFormat { .. }
                | image::ImageError::NoDirectory { .. }
                | image::ImageError::NotWritable { .. },
            ) => 2,
            _ => 1,
        }
    }
}

/// Reads a scene file; the format follows the extension (`.toml`: mcrt's own format).
pub fn load_scene(path: &Path) -> Result<SceneDesc, Error> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("toml") => Ok(scene::toml::load_toml(path)?),
        _ => Err(Error::Scene(SceneError::new(
            path,
            None,
            "unsupported scene format (expected a .toml file)",
        ))),
    }
}

/// Default image size and sample count when neither the scene nor a flag gives one.
pub const DEFAULT_SIZE: u32 = 512;
pub const DEFAULT_SPP: u32 = 16;

/// Resolves the render settings: each flag (`over`) wins over the scene file (`file`), which
/// wins over the defaults.
pub fn resolve_settings(
    file: &FileSettings,
    over: &FileSettings,
    threads: Option<usize>,
) -> Result<RenderSettings, Error> {
    let width = over.width.or(file.width).unwrap_or(DEFAULT_SIZE);
    let height = over.height.or(file.height).unwrap_or(DEFAULT_SIZE);
    let spp = over.spp.or(file.spp).unwrap_or(DEFAULT_SPP);
    if width == 0 || height == 0 || spp == 0 {
        return Err(Error::Usage(
            "width, height and spp must be at least 1".into(),
        ));
    }
    let shadow_rays = over.shadow_rays.or(file.shadow_rays).unwrap_or(1);
    if shadow_rays == 0 {
        return Err(Error::Usage("--shadow-rays must be at least 1".into()));
    }
    let rr = match over.rr_survival.or(file.rr_survival) {
        Some(p) if !(p > 0.0 && p < 1.0) => {
            return Err(Error::Usage(format!(
                "--rr-survival must be between 0 and 1 (exclusive), got {p}"
            )))
        }
        Some(p) => RussianRoulette::Fixed(p),
        None => RussianRoulette::Throughput { start: 5 },
    };
    Ok(RenderSettings {
        width,
        height,
        spp,
        seed: over.seed.or(file.seed).unwrap_or(0),
        camera: over.camera.clone().or_else(|| file.camera.clone()),
        params: IntegratorParams {
            kind: over
                .integrator
                .or(file.integrator)
                .unwrap_or(IntegratorKind::Path),
            max_depth: over.max_depth.or(file.max_depth),
            shadow_rays,
            rr,
        },
        sampler: over.sampler.or(file.sampler).unwrap_or_default(),
        threads,
    })
}
