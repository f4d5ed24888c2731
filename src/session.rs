//! Setting up one render from a caller's request, shared by the `mcrt render` command and the
//! Python module so that both render the same image, bit for bit, from the same request: the
//! settings (flags over the scene file over the defaults, [`crate::resolve_settings`]), the
//! checks made before anything is built (memory, camera, scene limits), and the budget of the
//! progressive passes.

use crate::camera::CameraDesc;
use crate::integrator::PhotonParams;
use crate::progressive::Budget;
use crate::render::{Backend, RenderSettings};
use crate::scene::desc::FileSettings;
use crate::scene::{Scene, SceneDesc, SceneError};
use crate::Error;
use std::path::Path;
use std::time::Duration;

/// What a caller asks for beyond the scene file (the flags of `mcrt render`).
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// Settings given by the caller; each wins over the scene file's.
    pub over: FileSettings,
    /// `--max-depth -1`: unlimited path length, also over a limit in the scene file.
    pub unlimited_depth: bool,
    /// Worker threads (None: one per core).
    pub threads: Option<usize>,
    pub photon: PhotonParams,
    /// How the path tracer runs (the image does not depend on it).
    pub backend: Backend,
}

/// The render settings for a scene file at `path` with settings `file` and `cameras`: the
/// request over the file over the defaults. Checked before anything is allocated: the film
/// fits in memory, and the camera asked for exists.
pub fn settings(
    path: &Path,
    file: &FileSettings,
    cameras: &[(String, CameraDesc)],
    req: &Request,
) -> Result<RenderSettings, Error> {
    let mut file = file.clone();
    if req.unlimited_depth {
        file.max_depth = None;
    }
    let mut settings = crate::resolve_settings(&file, &req.over, req.threads)?;
    settings.params.photon = req.photon;
    settings.backend = req.backend;
    crate::check_memory(&settings).map_err(|e| match (req.over.width, req.over.height) {
        // The size came from the scene file: say so.
        (None, None) => Error::Scene(SceneError::new(path, None, e.to_string())),
        _ => e,
    })?;
    let names: Vec<&str> = cameras.iter().map(|(n, _)| n.as_str()).collect();
    if names.is_empty() {
        return Err(SceneError::new(
            path,
            None,
            "the scene defines no camera (add a [[camera]] table, or a <sensor> in Mitsuba XML)",
        )
        .into());
    }
    if let Some(name) = &settings.camera {
        if !names.contains(&name.as_str()) {
            return Err(SceneError::new(
                path,
                None,
                format!("no camera named '{name}' (defined: {})", names.join(", ")),
            )
            .into());
        }
    }
    Ok(settings)
}

/// Builds the scene read from `path` (BVH, lights), after checking the limits of its
/// description.
pub fn build(path: &Path, desc: SceneDesc) -> Result<Scene, Error> {
    desc.check_limits()
        .map_err(|e| SceneError::new(path, None, e))?;
    Ok(Scene::build(desc))
}

/// `--max-depth`: absent or -1 is unlimited (None), otherwise a limit of at least 0.
pub fn max_depth(flag: Option<i64>) -> Result<Option<u32>, Error> {
    match flag {
        None | Some(-1) => Ok(None),
        Some(d) if (0..=u32::MAX as i64).contains(&d) => Ok(Some(d as u32)),
        Some(d) => Err(Error::Usage(format!(
            "--max-depth must be -1 (unlimited) or at least 0, got {d}"
        ))),
    }
}

/// `--threads`: at least one.
pub fn check_threads(threads: Option<usize>) -> Result<(), Error> {
    match threads {
        Some(0) => Err(Error::Usage("--threads must be at least 1".into())),
        _ => Ok(()),
    }
}

/// Refuses a `--target-noise` that is not a positive number (checked before the scene is
/// loaded, and again with the budget).
pub fn check_target_noise(target_noise: Option<f64>) -> Result<(), Error> {
    match target_noise {
        Some(e) if !(e > 0.0 && e.is_finite()) => Err(Error::Usage(format!(
            "--target-noise must be a positive number, got {e}"
        ))),
        _ => Ok(()),
    }
}

/// The budget of the progressive passes: at most `settings.spp` samples per pixel, except that
/// with a time or noise target and no sample count given (`spp_given` false) the samples are
/// unbounded (the scene file's spp is then ignored).
pub fn budget(
    settings: &RenderSettings,
    spp_given: bool,
    time: Option<Duration>,
    target_noise: Option<f64>,
    adaptive: bool,
    max_pass: Option<Duration>,
) -> Result<Budget, Error> {
    check_target_noise(target_noise)?;
    Ok(Budget {
        spp: if (time.is_some() || target_noise.is_some()) && !spp_given {
            None
        } else {
            Some(settings.spp)
        },
        time,
        target_noise,
        adaptive,
        max_pass,
    })
}
