//! `mcrt._mcrt`: the Python module of the mcrt renderer (the package `mcrt` re-exports it).
//!
//! Every function calls the library as the `mcrt` command does (`mcrt::session` sets a render
//! up for both), so `mcrt.render` returns the bits `mcrt render` writes to an EXR. Images cross
//! into Python as float32 NumPy arrays of shape (height, width, 3), row 0 at the top; numpy is
//! used through its Python API (no compiled dependency on its headers). Renders run on a worker
//! thread with the GIL released; the calling thread reports progress and checks for Ctrl-C,
//! which sets the render's cancel flag and raises `KeyboardInterrupt` once the workers stop.

use mcrt::aov::{self, Aov};
use mcrt::film::Film;
use mcrt::image::{Format, Image, ToneMap, WriteOptions};
use mcrt::integrator::{IntegratorKind, PhotonParams};
use mcrt::progressive::Budget;
use mcrt::render::RenderSettings;
use mcrt::sampler::SamplerKind;
use mcrt::scene::desc::FileSettings;
use mcrt::session::Request;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyUserWarning};
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes, PyDict, PyString, PyTuple};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

create_exception!(
    mcrt,
    Error,
    PyException,
    "Any error of mcrt; its message is the one the `mcrt` command prints."
);
create_exception!(
    mcrt,
    SceneError,
    Error,
    "A bad scene file: the message is `file:line:column: message` (as the command line's); \
     the attributes `path`, `line` and `column` hold the place (line and column None where the \
     error has no place in the file)."
);
create_exception!(
    mcrt,
    UsageError,
    Error,
    "A bad argument: a setting out of range, an unknown name, a wrong combination."
);
create_exception!(
    mcrt,
    ImageError,
    Error,
    "An image that cannot be read or written."
);
create_exception!(mcrt, RenderError, Error, "A failure while rendering.");

/// The Python exception for a library error, with the message the command line prints.
fn py_err(py: Python<'_>, e: mcrt::Error) -> PyErr {
    let msg = e.to_string();
    match e {
        mcrt::Error::Scene(se) => {
            let err = SceneError::new_err(msg);
            let v = err.value(py);
            let (line, column) = match se.location {
                Some((l, c)) => (Some(l), Some(c)),
                None => (None, None),
            };
            // Setting attributes on a fresh exception object cannot fail in practice; the
            // message carries the same facts if it did.
            let _ = v.setattr("path", se.path.to_string_lossy().into_owned());
            let _ = v.setattr("line", line);
            let _ = v.setattr("column", column);
            err
        }
        mcrt::Error::Usage(_) => UsageError::new_err(msg),
        mcrt::Error::Image(_) | mcrt::Error::Input(_) => ImageError::new_err(msg),
        mcrt::Error::Render(_) | mcrt::Error::Parts(_) | mcrt::Error::Denoise(_) => {
            RenderError::new_err(msg)
        }
    }
}

fn usage(msg: impl Into<String>) -> PyErr {
    UsageError::new_err(msg.into())
}

/// A scene read from a file and built (BVH, lights), ready to render any number of times.
#[pyclass(module = "mcrt", name = "Scene", frozen)]
struct PyScene {
    scene: Arc<mcrt::scene::Scene>,
    path: PathBuf,
    warnings: Vec<String>,
}

#[pymethods]
impl PyScene {
    /// The scene file's path.
    #[getter]
    fn path(&self) -> String {
        self.path.to_string_lossy().into_owned()
    }

    /// The cameras' names, in the file's order (`render(camera=...)` picks one).
    #[getter]
    fn cameras(&self) -> Vec<String> {
        self.scene.cameras.iter().map(|(n, _)| n.clone()).collect()
    }

    /// Warnings from reading the file (also issued as Python warnings by `load`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Image width, height and samples per pixel the file asks for (None where it does not).
    #[getter]
    fn width(&self) -> Option<u32> {
        self.scene.desc_settings.width
    }
    #[getter]
    fn height(&self) -> Option<u32> {
        self.scene.desc_settings.height
    }
    #[getter]
    fn spp(&self) -> Option<u32> {
        self.scene.desc_settings.spp
    }

    fn __repr__(&self) -> String {
        format!(
            "<mcrt.Scene {:?}: {} primitives, {} lights, cameras {:?}>",
            self.path.display().to_string(),
            self.scene.prim_count(),
            self.scene.lights.lights.len() + self.scene.lights.others.len(),
            self.cameras()
        )
    }
}

/// A Mitsuba `-D` value from a Python value: booleans as `true`/`false`, others by `str()`.
fn define_value(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(b) = v.extract::<bool>() {
        return Ok(if b { "true" } else { "false" }.into());
    }
    Ok(v.str()?.to_string())
}

/// Reads and builds a scene (GIL released).
fn load_scene(py: Python<'_>, path: PathBuf, opts: mcrt::LoadOptions) -> PyResult<PyScene> {
    let (scene, warnings) = py
        .detach(|| -> Result<_, mcrt::Error> {
            let desc = mcrt::load_scene_with(&path, &opts)?;
            let warnings = desc
                .warnings
                .iter()
                .map(|w| w.to_string())
                .collect::<Vec<_>>();
            Ok((mcrt::session::build(&path, desc)?, warnings))
        })
        .map_err(|e| py_err(py, e))?;
    for w in &warnings {
        let msg = std::ffi::CString::new(format!("{}: {w}", path.display()))
            .unwrap_or_else(|_| c"scene warning".into());
        PyErr::warn(py, &py.get_type::<PyUserWarning>(), &msg, 1)?;
    }
    Ok(PyScene {
        scene: Arc::new(scene),
        path,
        warnings,
    })
}

/// Reads a scene file and builds it: `.toml` (mcrt's format) or `.xml` (Mitsuba 3). Keyword
/// `params` set the parameters of a Mitsuba XML scene (its `<default>`s and `$name`s), as the
/// command line's `-D name=value`; booleans are written `true`/`false`, other values by
/// `str()`. `lenient=True` renders unsupported BSDFs of an XML scene as grey diffuse (each
/// listed in `Scene.warnings`) instead of failing. Raises `mcrt.SceneError` with
/// `file:line:column: message` for a bad file.
#[pyfunction]
#[pyo3(signature = (path, *, lenient=false, **params))]
fn load(
    py: Python<'_>,
    path: PathBuf,
    lenient: bool,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyScene> {
    let mut defines = Vec::new();
    if let Some(params) = params {
        for (k, v) in params.iter() {
            defines.push((k.extract::<String>()?, define_value(&v)?));
        }
    }
    load_scene(py, path, mcrt::LoadOptions { defines, lenient })
}

/// A duration from seconds (int or float) or text such as "90s", "10m", "250ms", checked as
/// the command's `--time` (a number is read as that many seconds).
fn duration(v: &Bound<'_, PyAny>) -> PyResult<Duration> {
    let text = match v.cast::<PyString>() {
        Ok(s) => s.to_string(),
        Err(_) => v.extract::<f64>()?.to_string(),
    };
    mcrt::progressive::parse_duration(&text).map_err(usage)
}

/// A list of AOV names from "albedo,normal" or ["albedo", "normal"].
fn aov_list(v: &Bound<'_, PyAny>) -> PyResult<Vec<Aov>> {
    let text = match v.cast::<PyString>() {
        Ok(s) => s.to_string(),
        Err(_) => v.extract::<Vec<String>>()?.join(","),
    };
    aov::parse_list(&text).map_err(usage)
}

/// The settings of a render, as `mcrt render` resolves them from its flags.
#[allow(clippy::too_many_arguments)]
fn request(
    spp: Option<u32>,
    width: Option<u32>,
    height: Option<u32>,
    seed: Option<u64>,
    integrator: Option<&str>,
    threads: Option<usize>,
    sampler: Option<&str>,
    max_depth: Option<i64>,
    shadow_rays: Option<u32>,
    camera: Option<String>,
) -> PyResult<Request> {
    let integrator = match integrator {
        None => None,
        Some(name) => Some(IntegratorKind::parse(name).ok_or_else(|| {
            usage(format!(
                "unknown integrator '{name}' (known: path, direct, photon, sppm)"
            ))
        })?),
    };
    let sampler = match sampler {
        None => None,
        Some(name) => Some(SamplerKind::parse(name).ok_or_else(|| {
            usage(format!(
                "unknown sampler '{name}' (known: independent, sobol)"
            ))
        })?),
    };
    let max_depth_limit = mcrt::session::max_depth(max_depth).map_err(|e| usage(e.to_string()))?;
    mcrt::session::check_threads(threads).map_err(|e| usage(e.to_string()))?;
    Ok(Request {
        over: FileSettings {
            width,
            height,
            spp,
            seed,
            integrator,
            max_depth: max_depth_limit,
            shadow_rays,
            camera,
            sampler,
            ..Default::default()
        },
        unlimited_depth: max_depth == Some(-1),
        threads,
        photon: PhotonParams::default(),
        backend: Default::default(),
    })
}

/// What the worker thread renders.
struct Job {
    scene: Arc<mcrt::scene::Scene>,
    settings: RenderSettings,
    /// None: `sppm`, rendered in one go.
    budget: Option<Budget>,
    aovs: Vec<Aov>,
}

/// The rendered image and AOV channels.
struct Output {
    image: Image,
    layers: Vec<(String, Vec<f32>)>,
}

impl Job {
    fn run(
        &self,
        cancel: &AtomicBool,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Output, mcrt::Error> {
        let (scene, s) = (&*self.scene, &self.settings);
        let Some(budget) = &self.budget else {
            let stop = || cancel.load(Ordering::SeqCst);
            let (film, _) = mcrt::render::render_until(scene, s, progress, &stop)?;
            return Ok(Output {
                image: film.image(),
                layers: Vec::new(),
            });
        };
        let guides = if self.aovs.iter().any(|a| a.needs_guides()) {
            Some(aov::render_guides(scene, s)?)
        } else {
            None
        };
        let (_, _, fw, fh) = s.window();
        let mut film = Film::new(fw, fh);
        let mut next = vec![0; fw as usize * fh as usize];
        // It stops early only when the caller set `cancel`, and then raises instead.
        mcrt::progressive::render_progressive::<mcrt::Error>(
            scene,
            s,
            &mut film,
            &mut next,
            budget,
            cancel,
            &mut |_, _| Ok(()),
            progress,
        )?;
        Ok(Output {
            image: film.image(),
            layers: aov::channels(&self.aovs, guides.as_ref(), &film),
        })
    }
}

/// Progress reports to a Python callable `f(done, total)` or a tqdm bar.
enum Reporter<'py> {
    None,
    Call(Bound<'py, PyAny>),
    Tqdm(Bound<'py, PyAny>, u64),
}

impl<'py> Reporter<'py> {
    fn new(
        py: Python<'py>,
        progress: Option<&Bound<'py, PyAny>>,
        total: Option<u64>,
    ) -> PyResult<Self> {
        let Some(p) = progress else {
            return Ok(Reporter::None);
        };
        if let Ok(flag) = p.extract::<bool>() {
            if !flag {
                return Ok(Reporter::None);
            }
            // progress=True: a tqdm bar where tqdm is installed, else nothing.
            let Ok(tqdm) = py.import("tqdm") else {
                return Ok(Reporter::None);
            };
            let kw = PyDict::new(py);
            kw.set_item("total", total)?;
            kw.set_item("unit", "sample")?;
            kw.set_item("unit_scale", true)?;
            let bar = tqdm.getattr("tqdm")?.call((), Some(&kw))?;
            return Ok(Reporter::Tqdm(bar, 0));
        }
        if !p.is_callable() {
            return Err(usage(
                "progress must be True, False, None or a callable f(done, total)",
            ));
        }
        Ok(Reporter::Call(p.clone()))
    }

    fn report(&mut self, done: u64, total: Option<u64>) -> PyResult<()> {
        match self {
            Reporter::None => Ok(()),
            Reporter::Call(f) => f.call1((done, total)).map(|_| ()),
            Reporter::Tqdm(bar, shown) => {
                if done > *shown {
                    bar.call_method1("update", (done - *shown,))?;
                    *shown = done;
                }
                Ok(())
            }
        }
    }

    fn close(&self) -> PyResult<()> {
        match self {
            Reporter::Tqdm(bar, _) => bar.call_method0("close").map(|_| ()),
            _ => Ok(()),
        }
    }
}

/// Runs the job on a worker thread with the GIL released; every 100 ms (and at the end) the
/// calling thread reports progress and checks for signals. Ctrl-C (or an exception from the
/// progress callback) sets the cancel flag: the workers stop after their current step of a
/// tile's samples and the exception is raised.
fn run_job(
    py: Python<'_>,
    job: &Job,
    reporter: &mut Reporter<'_>,
    total: Option<u64>,
) -> PyResult<Output> {
    let cancel = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let progress = |n: u64| {
        done.fetch_add(n, Ordering::Relaxed);
    };
    let mut pending: Option<PyErr> = None;
    let (tx, rx) = mpsc::channel();
    let result = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let r = job.run(&cancel, &progress);
            let _ = tx.send(());
            r
        });
        let mut rx = Some(rx);
        loop {
            let r = rx.take().expect("receiver");
            let (r, got) = py.detach(move || {
                let got = r.recv_timeout(Duration::from_millis(100));
                (r, got)
            });
            rx = Some(r);
            let finished = !matches!(got, Err(mpsc::RecvTimeoutError::Timeout));
            if pending.is_none() {
                let checked = py
                    .check_signals()
                    .and_then(|_| reporter.report(done.load(Ordering::Relaxed), total));
                if let Err(e) = checked {
                    cancel.store(true, Ordering::SeqCst);
                    pending = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        match worker.join() {
            Ok(r) => r,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    });
    let closed = reporter.close();
    if let Some(e) = pending {
        return Err(e);
    }
    closed?;
    result.map_err(|e| py_err(py, e))
}

/// Renders a scene (a `Scene` from `load`, or a scene file's path) and returns the image as a
/// float32 NumPy array of shape (height, width, 3), linear RGB, row 0 at the top: the same
/// bits as `mcrt render` writes to an EXR with the same settings and seed.
///
/// Each argument given wins over the scene file, as the command's flag of the same name:
/// `integrator` is "path", "direct", "photon" or "sppm"; `sampler` "independent" or "sobol";
/// `max_depth` -1 means unlimited; `time` is a budget in seconds (or text such as "90s") and
/// `target_noise` a relative standard error at which to stop (with either and no `spp` the
/// samples are unbounded); `adaptive` spends samples where the noise is above the target.
///
/// `aovs` ("albedo,normal" or a list of names among albedo, normal, emission, depth, variance,
/// spp)
/// makes it return a dict instead: "image" and one array per AOV, (height, width, 3) or, for
/// depth and spp, (height, width).
///
/// `progress` is a callable `f(done, total)` (samples; total None when unbounded), called
/// about ten times a second from the calling thread, or True for a tqdm bar where tqdm is
/// installed. `backend` ("auto", "scalar", "avx512", "avx2") and the photon integrators'
/// `photons`, `caustic_photons`, `gather_photons`, `final_gather`, `iterations`,
/// `photons_per_iteration` and `initial_radius` are the command's flags of the same names.
/// Ctrl-C stops the render within a tile (photon tracing between chunks, sppm
/// between iterations) and raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (scene, *, spp=None, width=None, height=None, seed=None, integrator=None, time=None, threads=None, sampler=None, max_depth=None, shadow_rays=None, camera=None, target_noise=None, adaptive=false, aovs=None, progress=None, backend=None, photons=None, caustic_photons=None, gather_photons=None, final_gather=None, iterations=None, photons_per_iteration=None, initial_radius=None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    spp: Option<u32>,
    width: Option<u32>,
    height: Option<u32>,
    seed: Option<u64>,
    integrator: Option<String>,
    time: Option<&Bound<'py, PyAny>>,
    threads: Option<usize>,
    sampler: Option<String>,
    max_depth: Option<i64>,
    shadow_rays: Option<u32>,
    camera: Option<String>,
    target_noise: Option<f64>,
    adaptive: bool,
    aovs: Option<&Bound<'py, PyAny>>,
    progress: Option<&Bound<'py, PyAny>>,
    backend: Option<String>,
    photons: Option<u64>,
    caustic_photons: Option<u64>,
    gather_photons: Option<u32>,
    final_gather: Option<u32>,
    iterations: Option<u32>,
    photons_per_iteration: Option<u64>,
    initial_radius: Option<f32>,
) -> PyResult<Bound<'py, PyAny>> {
    // The kernels ignore a cap they do not know (`mcrt::cpu`); refused here, as the CLI does.
    mcrt::cpu::max_isa().map_err(usage)?;
    let (arc, path) = match scene.cast::<PyScene>() {
        Ok(s) => (s.get().scene.clone(), s.get().path.clone()),
        Err(_) => {
            let path: PathBuf = scene.extract().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err("scene must be an mcrt.Scene or a path")
            })?;
            let s = load_scene(py, path, mcrt::LoadOptions::default())?;
            (s.scene, s.path)
        }
    };
    let mut req = request(
        spp,
        width,
        height,
        seed,
        integrator.as_deref(),
        threads,
        sampler.as_deref(),
        max_depth,
        shadow_rays,
        camera,
    )?;
    let d = PhotonParams::DEFAULT;
    req.photon = PhotonParams {
        photons: photons.unwrap_or(d.photons),
        caustic_photons: caustic_photons.unwrap_or(d.caustic_photons),
        gather_photons: gather_photons.unwrap_or(d.gather_photons),
        final_gather: final_gather.unwrap_or(d.final_gather),
        iterations: iterations.unwrap_or(d.iterations),
        photons_per_iteration: photons_per_iteration.unwrap_or(d.photons_per_iteration),
        initial_radius: initial_radius.or(d.initial_radius),
    };
    req.photon.check().map_err(usage)?;
    if let Some(name) = backend.as_deref() {
        req.backend = mcrt::render::Backend::parse(name).ok_or_else(|| {
            usage(format!(
                "unknown backend '{name}' (known: auto, scalar, avx512, avx2)"
            ))
        })?;
    }
    let time = time.map(duration).transpose()?;
    let aovs = aovs.map(aov_list).transpose()?.unwrap_or_default();
    let want_dict = !aovs.is_empty();
    let settings = mcrt::session::settings(&path, &arc.desc_settings, &arc.cameras, &req)
        .map_err(|e| py_err(py, e))?;
    let (_, _, fw, fh) = settings.window();
    let npix = fw as u64 * fh as u64;
    let (budget, total) = match settings.params.kind {
        IntegratorKind::Sppm => {
            if time.is_some() || target_noise.is_some() || adaptive || want_dict {
                return Err(usage(
                    "integrator sppm renders the whole image at once: time, target_noise, \
                     adaptive and aovs apply to path, direct and photon",
                ));
            }
            let passes = settings.params.photon.iterations;
            (None, Some(npix.saturating_mul(passes as u64)))
        }
        _ => {
            let b =
                mcrt::session::budget(&settings, spp.is_some(), time, target_noise, adaptive, None)
                    .map_err(|e| py_err(py, e))?;
            let total = b.spp.map(|n| npix.saturating_mul(n as u64));
            (Some(b), total)
        }
    };
    let job = Job {
        scene: arc,
        settings,
        budget,
        aovs: aovs.clone(),
    };
    let mut reporter = Reporter::new(py, progress, total)?;
    let out = run_job(py, &job, &mut reporter, total)?;
    let image = image_to_numpy(py, &out.image)?;
    if !want_dict {
        return Ok(image);
    }
    let dict = PyDict::new(py);
    dict.set_item("image", image)?;
    let mut layers = out.layers.into_iter();
    for a in &aovs {
        let n = a.channels().len();
        let chans: Vec<Vec<f32>> = layers.by_ref().take(n).map(|(_, v)| v).collect();
        let mut data = Vec::with_capacity(npix as usize * n);
        for i in 0..npix as usize {
            data.extend(chans.iter().map(|c| c[i]));
        }
        let shape: Vec<usize> = if n == 1 {
            vec![fh as usize, fw as usize]
        } else {
            vec![fh as usize, fw as usize, n]
        };
        dict.set_item(a.name(), to_numpy(py, &data, &shape)?)?;
    }
    Ok(dict.into_any())
}

/// A float32 NumPy array of `shape` holding `data` (copied once, into a bytearray that the
/// array owns, so the array is writable).
fn to_numpy<'py>(py: Python<'py>, data: &[f32], shape: &[usize]) -> PyResult<Bound<'py, PyAny>> {
    let mut bytes = Vec::with_capacity(data.len() * 4);
    for v in data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let buf = PyByteArray::new(py, &bytes);
    let np = py.import("numpy")?;
    let arr = np.call_method1("frombuffer", (buf, "<f4"))?;
    arr.call_method1("reshape", (PyTuple::new(py, shape)?,))
}

fn image_to_numpy<'py>(py: Python<'py>, img: &Image) -> PyResult<Bound<'py, PyAny>> {
    let data: Vec<f32> = img.pixels.iter().flat_map(|p| p.to_array()).collect();
    to_numpy(py, &data, &[img.height as usize, img.width as usize, 3])
}

/// An array-like as float32 values and its shape.
fn from_numpy(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<(Vec<f32>, Vec<usize>)> {
    let np = py.import("numpy")?;
    let arr = np.call_method1("ascontiguousarray", (obj, "<f4"))?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    let bytes = arr.call_method0("tobytes")?;
    let bytes = bytes.cast::<PyBytes>()?.as_bytes();
    let data = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok((data, shape))
}

/// An RGB image from an array of shape (height, width, 3).
fn image_from_numpy(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Image> {
    let (data, shape) = from_numpy(py, obj)?;
    let [h, w, 3] = shape[..] else {
        return Err(usage(format!(
            "{what} must have shape (height, width, 3), got {shape:?}"
        )));
    };
    if h == 0 || w == 0 || h > u32::MAX as usize || w > u32::MAX as usize {
        return Err(usage(format!(
            "{what} has no pixels or is too large: {shape:?}"
        )));
    }
    Ok(Image {
        width: w as u32,
        height: h as u32,
        pixels: data
            .chunks_exact(3)
            .map(|p| mcrt::Color::new(p[0], p[1], p[2]))
            .collect(),
    })
}

/// Writes an image of shape (height, width, 3) (linear RGB; any float dtype, converted to
/// float32) as the extension says: `.exr` (32-bit float, or 16-bit with `half=True`) or `.png`
/// (8-bit sRGB after `exposure` in stops and `tonemap` "clamp", "reinhard" or "aces"), as
/// `mcrt render` does; atomically (no half-written file at `path`). `aovs`, a dict such as
/// `render(..., aovs=...)` returns (its "image" entry is ignored), adds the AOV layers to an
/// EXR (`albedo.R`, `normal.X`, `depth.Z`, ...).
#[pyfunction]
#[pyo3(signature = (path, image, *, exposure=0.0, tonemap="clamp", half=false, aovs=None))]
fn write(
    py: Python<'_>,
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    exposure: f32,
    tonemap: &str,
    half: bool,
    aovs: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let img = image_from_numpy(py, image, "image")?;
    let tonemap = match tonemap {
        "clamp" => ToneMap::Clamp,
        "reinhard" => ToneMap::Reinhard,
        "aces" => ToneMap::Aces,
        t => {
            return Err(usage(format!(
                "unknown tone map '{t}' (known: clamp, reinhard, aces)"
            )))
        }
    };
    let mut layers = Vec::new();
    if let Some(aovs) = aovs {
        for (k, v) in aovs.iter() {
            let name: String = k.extract()?;
            if name == "image" {
                continue;
            }
            let a = aov::parse_list(&name).map_err(usage)?[0];
            let (data, shape) = from_numpy(py, &v)?;
            let n = a.channels().len();
            let (h, w) = (img.height as usize, img.width as usize);
            let ok = shape[..] == [h, w, n] || (n == 1 && shape[..] == [h, w]);
            if !ok {
                return Err(usage(format!(
                    "AOV '{name}' must have shape ({h}, {w}{}), got {shape:?}",
                    if n == 1 {
                        String::new()
                    } else {
                        format!(", {n}")
                    }
                )));
            }
            for (c, ch) in a.channels().iter().enumerate() {
                let v = data.iter().skip(c).step_by(n).copied().collect();
                layers.push((format!("{name}.{ch}"), v));
            }
        }
    }
    let opts = WriteOptions {
        exposure,
        tonemap,
        half,
    };
    py.detach(|| mcrt::image::write_image_with(&path, &img, &opts, &layers))
        .map_err(|e| py_err(py, e.into()))
}

/// Reads an RGB image: OpenEXR (its first RGB layer, as stored) or PNG (decoded from sRGB to
/// linear, as the renderer decodes textures).
fn read_image(path: &Path) -> Result<Image, mcrt::Error> {
    match Format::from_path(path)? {
        Format::Exr => Ok(mcrt::image::read_exr(path)?),
        Format::Png => {
            let b = mcrt::texture::Bitmap::load(path, false)
                .map_err(|e| mcrt::Error::Input(e.to_string()))?;
            Ok(Image {
                width: b.width,
                height: b.height,
                pixels: b.pixels().collect(),
            })
        }
    }
}

/// Reads an image as a float32 array of shape (height, width, 3), linear RGB: an `.exr` file's
/// RGB channels as stored, or a `.png` decoded from sRGB to linear (alpha dropped).
#[pyfunction]
fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let img = py.detach(|| read_image(&path)).map_err(|e| py_err(py, e))?;
    image_to_numpy(py, &img)
}

/// Error metrics of an image against a reference, as `mcrt compare` prints them.
#[pyclass(module = "mcrt", name = "Metrics", frozen, get_all)]
struct Metrics {
    /// Mean squared error over all pixels and channels.
    mse: f64,
    /// sqrt(mse).
    rmse: f64,
    /// mean((a−b)²/(b²+0.01)).
    rel_mse: f64,
    /// 10·log10(1/mse) dB (peak 1).
    psnr: f64,
    /// Largest absolute difference of any channel.
    max_abs: f64,
}

#[pymethods]
impl Metrics {
    fn __repr__(&self) -> String {
        format!(
            "Metrics(rmse={}, rel_mse={}, psnr={}, mse={}, max_abs={})",
            self.rmse, self.rel_mse, self.psnr, self.mse, self.max_abs
        )
    }
}

/// An image to compare: an `.exr` path (read as `mcrt compare` reads it) or an array.
fn compare_input(py: Python<'_>, v: &Bound<'_, PyAny>, what: &str) -> PyResult<(Image, String)> {
    if let Ok(p) = v.extract::<PathBuf>() {
        if Format::from_path(&p).ok() != Some(Format::Exr) {
            return Err(ImageError::new_err(format!(
                "{}: compare reads OpenEXR images (.exr)",
                p.display()
            )));
        }
        let img = py
            .detach(|| mcrt::image::read_exr(&p))
            .map_err(|e| ImageError::new_err(e.to_string()))?;
        return Ok((img, p.display().to_string()));
    }
    Ok((image_from_numpy(py, v, what)?, what.to_string()))
}

/// Compares image `a` with the reference `b` (each an `.exr` path or an array of shape
/// (height, width, 3)) over all pixels and channels: RMSE, relMSE, PSNR, as `mcrt compare`.
/// `diff`, a path, gets the false-colour difference map (white where equal, red where `a` is
/// brighter, blue where `b` is), pure red or blue at `diff_range` (default: the largest
/// difference of any pixel).
#[pyfunction]
#[pyo3(signature = (a, b, *, diff=None, diff_range=None))]
fn compare(
    py: Python<'_>,
    a: &Bound<'_, PyAny>,
    b: &Bound<'_, PyAny>,
    diff: Option<PathBuf>,
    diff_range: Option<f64>,
) -> PyResult<Metrics> {
    if let Some(r) = diff_range {
        if !(r > 0.0 && r.is_finite()) {
            return Err(usage(format!(
                "--diff-range must be a positive number, got {r}"
            )));
        }
    }
    let (img_a, name_a) = compare_input(py, a, "a")?;
    let (img_b, name_b) = compare_input(py, b, "b")?;
    let m = mcrt::compare::metrics(&img_a, &img_b)
        .map_err(|e| ImageError::new_err(format!("{name_a} and {name_b}: {e}")))?;
    if let Some(d) = diff {
        let range = diff_range.unwrap_or(if m.max_abs_mean > 0.0 {
            m.max_abs_mean
        } else {
            1.0
        });
        let img = mcrt::compare::diff_image(&img_a, &img_b, range);
        py.detach(|| mcrt::image::write_image(&d, &img, &WriteOptions::default()))
            .map_err(|e| py_err(py, e.into()))?;
    }
    Ok(Metrics {
        mse: m.mse,
        rmse: m.rmse,
        rel_mse: m.rel_mse,
        psnr: m.psnr,
        max_abs: m.max_abs,
    })
}

#[pymodule]
fn _mcrt(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PyScene>()?;
    m.add_class::<Metrics>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add("Error", py.get_type::<Error>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("UsageError", py.get_type::<UsageError>())?;
    m.add("ImageError", py.get_type::<ImageError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
