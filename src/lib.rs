//! mcrt: a physically based Monte Carlo ray tracer.
//!
//! The library loads a scene ([`load_scene`]), renders it ([`render::render`]) and writes
//! images ([`image::write_image`]). Data flows one way: file → [`scene::SceneDesc`] →
//! [`scene::Scene`] (primitives, BVH, materials, lights, cameras) → integrator over image
//! tiles → [`film::Film`] → image file.

// `!(x > 0.0)` is used on purpose: it refuses NaN together with the non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod aov;
pub mod camera;
pub mod checkpoint;
pub mod compare;
pub mod denoise;
pub mod film;
pub mod geometry;
pub mod image;
pub mod integrator;
pub mod light;
pub mod material;
pub mod parts;
pub mod photon;
pub mod preview;
pub mod progressive;
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
    Parts(#[from] parts::PartsError),
    #[error("{0}")]
    Usage(String),
    /// An input file (not a scene) that cannot be used.
    #[error("{0}")]
    Input(String),
    /// Open Image Denoise failed on an image.
    #[error("{0}")]
    Denoise(String),
}

impl Error {
    /// Process exit status: 2 for bad input, 1 for anything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Scene(_)
            | Error::Usage(_)
            | Error::Parts(_)
            | Error::Input(_)
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

/// Options for reading a scene file.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `-D name=value`: parameters of a Mitsuba XML scene.
    pub defines: Vec<(String, String)>,
    /// Render unsupported parts of an XML scene approximately instead of refusing them.
    pub lenient: bool,
}

/// Reads a scene file; the format follows the extension (`.toml`: mcrt's own format; `.xml`:
/// Mitsuba 3).
pub fn load_scene(path: &Path) -> Result<SceneDesc, Error> {
    load_scene_with(path, &LoadOptions::default())
}

pub fn load_scene_with(path: &Path, opts: &LoadOptions) -> Result<SceneDesc, Error> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("toml") => {
            if !opts.defines.is_empty() {
                return Err(Error::Usage(
                    "-D parameters apply to Mitsuba XML scenes, not to .toml ones".into(),
                ));
            }
            Ok(scene::toml::load_toml(path)?)
        }
        Some("xml") => Ok(scene::xml::load_xml(
            path,
            &scene::xml::XmlOptions {
                defines: opts.defines.clone(),
                lenient: opts.lenient,
            },
        )?),
        _ => Err(Error::Scene(SceneError::new(
            path,
            None,
            "unsupported scene format (expected a .toml file or a Mitsuba 3 .xml file)",
        ))),
    }
}

/// Bytes of memory a render needs beyond the scene: the film (fixed-point sums and sums of
/// squares, counts) and the f32 RGB image written from it.
pub fn render_memory(s: &RenderSettings) -> u64 {
    let (_, _, w, h) = s.window();
    let per_pixel = 2 * std::mem::size_of::<[i128; 3]>() + std::mem::size_of::<u32>() + 12;
    let film = w as u64 * h as u64 * per_pixel as u64;
    film.saturating_add(photon_memory(s))
}

/// Bytes the photon maps may take: each emitted photon can be stored at every diffuse
/// bounce; budget `PHOTON_BOUNCES` stored photons (and a shadow photon) per emitted one.
fn photon_memory(s: &RenderSettings) -> u64 {
    const PHOTON_BOUNCES: u64 = 8;
    let bytes = std::mem::size_of::<photon::Photon>() as u64;
    let p = &s.params.photon;
    let emitted = match s.params.kind {
        IntegratorKind::Photon => p.photons.saturating_add(p.caustic_photons),
        IntegratorKind::Sppm => p.photons_per_iteration,
        _ => 0,
    };
    emitted.saturating_mul((PHOTON_BOUNCES + 1) * bytes)
}

/// Memory the system can still give, from /proc/meminfo (None where that is unknown).
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Refuses a render whose film would not fit in memory, before anything is allocated.
pub fn check_memory(s: &RenderSettings) -> Result<(), Error> {
    let need = render_memory(s);
    if let Some(have) = available_memory() {
        if need > have {
            let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
            let (_, _, w, h) = s.window();
            return Err(Error::Usage(format!(
                "a {w} × {h} image needs up to {:.1} GiB for its film and photon maps, but only \
                 {:.1} GiB of memory is available; render a smaller image (--width, --height), \
                 a crop, or with fewer photons",
                gib(need),
                gib(have)
            )));
        }
    }
    Ok(())
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
        None => RussianRoulette::Throughput {
            start: over.rr_depth.or(file.rr_depth).unwrap_or(5),
        },
    };
    let crop = match over.crop {
        Some(c) => Some(c),
        None if over.width.is_some() || over.height.is_some() => None,
        None => file.crop,
    };
    if let Some([x, y, w, h]) = crop {
        if w == 0 || h == 0 || x + w > width || y + h > height {
            return Err(Error::Usage(format!(
                "the crop window ({x}, {y}) + ({w} × {h}) does not fit in the {width} × {height} image"
            )));
        }
    }
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
            hide_emitters: over.hide_emitters.or(file.hide_emitters).unwrap_or(false),
            specular_chain: over.specular_chain.or(file.specular_chain).unwrap_or(true),
            photon: Default::default(),
        },
        // A crop window from the file belongs to the file's image size.
        crop,
        sampler: over.sampler.or(file.sampler).unwrap_or_default(),
        threads,
    })
}
