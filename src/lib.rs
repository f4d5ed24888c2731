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
pub mod cpu;
pub mod denoise;
pub mod film;
pub mod geometry;
pub mod image;
pub mod input;
pub mod integrator;
pub mod light;
pub mod limits;
pub mod material;
pub mod parts;
pub mod photon;
pub mod preview;
pub mod progressive;
pub mod render;
pub mod rgbe;
pub mod sampler;
pub mod scene;
pub mod session;
pub mod simd;
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
            | Error::Render(render::RenderError::NoCameras)
            | Error::Render(render::RenderError::Unsupported(_)) => 2,
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
/// Mitsuba 3; `.gltf`, `.glb`: glTF 2.0).
pub fn load_scene(path: &Path) -> Result<SceneDesc, Error> {
    load_scene_with(path, &LoadOptions::default())
}

pub fn load_scene_with(path: &Path, opts: &LoadOptions) -> Result<SceneDesc, Error> {
    Ok(load_scene_source(path, opts)?.0)
}

/// [`load_scene_with`], also giving the scene file's bytes (read once: a checkpoint hashes
/// the very bytes the scene was parsed from).
pub fn load_scene_source(path: &Path, opts: &LoadOptions) -> Result<(SceneDesc, Vec<u8>), Error> {
    let format = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if !matches!(format.as_deref(), Some("toml" | "xml" | "gltf" | "glb")) {
        return Err(Error::Scene(SceneError::new(
            path,
            None,
            "unsupported scene format (expected a .toml file, a Mitsuba 3 .xml file, or a \
             glTF 2.0 .gltf or .glb file)",
        )));
    }
    if format.as_deref() == Some("toml") && !opts.defines.is_empty() {
        return Err(Error::Usage(
            "-D parameters apply to Mitsuba XML scenes, not to .toml ones".into(),
        ));
    }
    let bytes = input::read(path)
        .map_err(|e| SceneError::new(path, None, format!("cannot read scene file: {e}")))?;
    if matches!(format.as_deref(), Some("gltf" | "glb")) {
        if !opts.defines.is_empty() {
            return Err(Error::Usage(
                "-D parameters apply to Mitsuba XML scenes, not to glTF ones".into(),
            ));
        }
        return Ok((scene::gltf::parse_gltf(path, &bytes, opts.lenient)?, bytes));
    }
    let text = input::as_text(&bytes)
        .map_err(|e| SceneError::new(path, None, format!("cannot read scene file: {e}")))?;
    let desc = if format.as_deref() == Some("toml") {
        scene::toml::parse_toml(path, text)?
    } else {
        let xml = scene::xml::XmlOptions {
            defines: opts.defines.clone(),
            lenient: opts.lenient,
        };
        scene::xml::parse_xml(path, text, &xml)?
    };
    Ok((desc, bytes))
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

/// Memory this process can still take: the least of the system's available memory
/// (`MemAvailable` in /proc/meminfo), the address space left under `RLIMIT_AS` (`ulimit -v`)
/// and what the cgroup's `memory.max` leaves (None where none of these is known).
pub fn available_memory() -> Option<u64> {
    [meminfo_available(), address_space_left(), cgroup_left()]
        .into_iter()
        .flatten()
        .min()
}

fn meminfo_available() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// `RLIMIT_AS` less the address space already mapped (`VmSize`): an allocation beyond it
/// fails, and Rust aborts on a failed allocation.
#[cfg(target_os = "linux")]
fn address_space_left() -> Option<u64> {
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one rlimit through a valid pointer.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut lim) } != 0
        || lim.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmSize:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(lim.rlim_cur.saturating_sub(kb * 1024))
}

#[cfg(not(target_os = "linux"))]
fn address_space_left() -> Option<u64> {
    None
}

/// The cgroup v2 limit less its current use, where the process's cgroup is mounted at
/// /sys/fs/cgroup (as in a container).
fn cgroup_left() -> Option<u64> {
    let read = |f: &str| -> Option<u64> {
        std::fs::read_to_string(format!("/sys/fs/cgroup/{f}"))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    Some(read("memory.max")?.saturating_sub(read("memory.current")?))
}

/// A byte count for messages: bytes below 1 MiB, else MiB or GiB with one decimal.
pub fn bytes_text(b: u64) -> String {
    const MIB: f64 = (1u64 << 20) as f64;
    match b {
        b if b < 1 << 20 => format!("{b} bytes"),
        b if b < 1 << 30 => format!("{:.1} MiB", b as f64 / MIB),
        b => format!("{:.1} GiB", b as f64 / MIB / 1024.0),
    }
}

/// The memory budget every allocation sized by an input (a file's header, a count) is
/// checked against before it is made: Err says how much is needed and how much is
/// available, for the caller to put after what needs it.
pub fn check_allocation(bytes: u64) -> Result<(), String> {
    match available_memory() {
        Some(have) if bytes > have => Err(format!(
            "needs {} of memory, but only {} is available",
            bytes_text(bytes),
            bytes_text(have)
        )),
        _ => Ok(()),
    }
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
    let shadow_rays = over.shadow_rays.or(file.shadow_rays).unwrap_or(1);
    let rr_depth = over.rr_depth.or(file.rr_depth).unwrap_or(5);
    let max_depth = over.max_depth.or(file.max_depth);
    // Every count within its bound (limits.rs), named by its flag where a flag gave it.
    let bound = |flag: &str, given: bool, v: u64, min: u64, max: u64| {
        let name = if given {
            flag.to_string()
        } else {
            format!(
                "the scene's {}",
                flag.trim_start_matches("--").replace('-', "_")
            )
        };
        limits::check(&name, v, min, max).map_err(Error::Usage)
    };
    use limits::*;
    bound("--width", over.width.is_some(), width as u64, 1, MAX_SIZE)?;
    bound(
        "--height",
        over.height.is_some(),
        height as u64,
        1,
        MAX_SIZE,
    )?;
    bound("--spp", over.spp.is_some(), spp as u64, 1, MAX_SPP)?;
    let shadow_flag = over.shadow_rays.is_some();
    bound(
        "--shadow-rays",
        shadow_flag,
        shadow_rays as u64,
        1,
        MAX_SHADOW_RAYS,
    )?;
    bound(
        "--rr-depth",
        over.rr_depth.is_some(),
        rr_depth as u64,
        1,
        MAX_RR_DEPTH,
    )?;
    if let Some(d) = max_depth {
        bound(
            "--max-depth",
            over.max_depth.is_some(),
            d as u64,
            0,
            limits::MAX_DEPTH,
        )?;
    }
    if let Some(t) = threads {
        bound("--threads", true, t as u64, 1, MAX_THREADS)?;
    }
    let rr = match over.rr_survival.or(file.rr_survival) {
        Some(p) if !(p > 0.0 && p <= MAX_RR_SURVIVAL) => {
            let name = match over.rr_survival {
                Some(_) => "--rr-survival",
                None => "the scene's rr_survival",
            };
            return Err(Error::Usage(format!(
                "{name} must be between 0 and 1 (exclusive) and at most {MAX_RR_SURVIVAL}, \
                 got {p}"
            )));
        }
        Some(p) => RussianRoulette::Fixed(p),
        None => RussianRoulette::Throughput { start: rr_depth },
    };
    let crop = match over.crop {
        Some(c) => Some(c),
        None if over.width.is_some() || over.height.is_some() => None,
        None => file.crop,
    };
    if let Some([x, y, w, h]) = crop {
        // Checked sums: a window past u32::MAX does not fit either.
        let fits = |o: u32, n: u32, size: u32| n > 0 && o.checked_add(n).is_some_and(|e| e <= size);
        if !(fits(x, w, width) && fits(y, h, height)) {
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
            max_depth,
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
        backend: Default::default(),
    })
}
