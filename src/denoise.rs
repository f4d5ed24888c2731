//! Denoising with Intel Open Image Denoise (OIDN) 2.x, loaded at run time.
//!
//! mcrt does not link OIDN: [`Oidn::load`] opens its shared library with `dlopen`
//! (`libloading`) from, in order,
//! 1. the directory `$OIDN_DIR` (or its `lib/` subdirectory),
//! 2. the directory of the `mcrt` binary (or `../lib` from there),
//! 3. the system's library search path (`LD_LIBRARY_PATH`, ldconfig).
//!
//! On Linux the PyPI package `pyoidn` ships the library and its CPU and GPU device modules;
//! [`INSTALL_HINT`] says how to point `OIDN_DIR` at them.
//!
//! The filter is OIDN's generic ray-tracing filter `RT` with `hdr` set (the image is linear
//! HDR radiance), guided by the albedo and normal layers of [`crate::aov`] (first
//! non-specular surface, averaged over the guide rays: OIDN's recommended auxiliary images).
//!
//! Emission that camera rays see directly (emitters and a constant environment on the first
//! segment) bypasses the filter: OIDN gets the image less the emission the render's own
//! samples added, and the pixel's integral of that emission is added back
//! ([`crate::aov::emission_split`]). Inside an emitter that emission has no Monte Carlo noise,
//! and it is usually far brighter than the rest of the image, where the network is least
//! accurate: denoising the Cornell box whole darkens its light by about 2% and leaves the
//! image's RMSE larger than the raw one's. On an emitter's edge its only noise is the
//! coverage, which the integral (a grid of rays) removes without the network's help. The
//! emission taken out of a pixel is at most the pixel's value per channel, so the image given
//! to OIDN is never negative. `mcrt denoise`, with no scene, uses the `emission` layer of
//! its input (if any) for both.
//!
//! Images go through OIDN buffers (`oidnNewBuffer`, `oidnWriteBuffer`, `oidnReadBuffer`),
//! which work on every device type OIDN picks (CPU, CUDA, HIP, SYCL), unlike shared host
//! pointers. API: the OIDN 2 documentation, "Open Image Denoise API" (C API, `oidn.h`).

use crate::aov::{emission_split, Guides};
use crate::film::Film;
use crate::image::Image;
use crate::render::RenderSettings;
use crate::scene::Scene;
use crate::Color;
use glam::Vec3A;
use libloading::Library;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::{Path, PathBuf};

/// The shared library's file name.
#[cfg(target_os = "linux")]
pub const LIBRARY: &str = "libOpenImageDenoise.so.2";
#[cfg(target_os = "macos")]
pub const LIBRARY: &str = "libOpenImageDenoise.2.dylib";
#[cfg(windows)]
pub const LIBRARY: &str = "OpenImageDenoise.dll";
#[cfg(not(any(target_os = "linux", target_os = "macos", windows)))]
pub const LIBRARY: &str = "libOpenImageDenoise.so.2";

/// How to install OIDN, for the error message when it is missing.
pub const INSTALL_HINT: &str = "install it with `pip install pyoidn` (its wheel ships \
libOpenImageDenoise.so.2) and point OIDN_DIR at the library:\n  \
export OIDN_DIR=\"$(python3 -c 'import importlib.util, pathlib; print(pathlib.Path(importlib.util.find_spec(\"pyoidn\").origin).parent / \"oidn\" / \"lib\")')\"\n\
or put libOpenImageDenoise.so.2 next to the mcrt binary or on the library path (LD_LIBRARY_PATH)";

/// OIDN_DEVICE_TYPE_DEFAULT: the fastest device present (a GPU, else the CPU).
const DEVICE_TYPE_DEFAULT: c_int = 0;
/// OIDN_ERROR_NONE.
const ERROR_NONE: c_int = 0;
/// OIDN_FORMAT_FLOAT3.
const FORMAT_FLOAT3: c_int = 3;

type Handle = *mut c_void;

/// The entry points of the OIDN 2 C API that mcrt uses (signatures from `oidn.h`).
#[derive(Clone, Copy)]
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    get_device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> c_int,
    get_device_int: unsafe extern "C" fn(Handle, *const c_char) -> c_int,
    new_buffer: unsafe extern "C" fn(Handle, usize) -> Handle,
    write_buffer: unsafe extern "C" fn(Handle, usize, usize, *const c_void),
    read_buffer: unsafe extern "C" fn(Handle, usize, usize, *mut c_void),
    release_buffer: unsafe extern "C" fn(Handle),
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    #[allow(clippy::type_complexity)]
    set_filter_image: unsafe extern "C" fn(
        Handle,
        *const c_char,
        Handle,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_filter_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// A loaded OIDN library with a committed device.
pub struct Oidn {
    api: Api,
    device: Handle,
    /// Where the library was found.
    pub path: PathBuf,
    /// OIDN's version, e.g. 20501 for 2.5.1.
    pub version: i32,
    // Dropped last: the function pointers above point into it.
    _lib: Library,
}

/// The places searched for the library, in order (see the module documentation).
pub fn candidates() -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) {
        let dir = PathBuf::from(dir);
        out.push(dir.join(LIBRARY));
        out.push(dir.join("lib").join(LIBRARY));
    }
    if let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        out.push(dir.join(LIBRARY));
        out.push(dir.join("..").join("lib").join(LIBRARY));
    }
    // A bare name: dlopen's own search.
    out.push(PathBuf::from(LIBRARY));
    out
}

impl Oidn {
    /// Finds and opens OIDN and creates its device; a message naming the places searched and
    /// how to install it when it is missing or unusable.
    pub fn load() -> Result<Oidn, String> {
        let mut tried = Vec::new();
        for path in candidates() {
            let bare = path.parent().is_none_or(|p| p.as_os_str().is_empty());
            if !bare && !path.exists() {
                tried.push(format!("{} (not there)", path.display()));
                continue;
            }
            // SAFETY: OIDN's initialisers only set up its own state.
            match unsafe { Library::new(&path) } {
                Ok(lib) => return Oidn::open(lib, path),
                Err(e) if bare => tried.push(format!("{LIBRARY} on the library path ({e})")),
                Err(e) => tried.push(format!("{} ({e})", path.display())),
            }
        }
        Err(format!(
            "--denoise needs Intel Open Image Denoise 2 ({LIBRARY}), which could not be loaded; \
             tried:\n  {}\nTo get it, {INSTALL_HINT}",
            tried.join("\n  ")
        ))
    }

    fn open(lib: Library, path: PathBuf) -> Result<Oidn, String> {
        fn sym<T: Copy>(lib: &Library, path: &Path, name: &str) -> Result<T, String> {
            // SAFETY: T is the function's type as declared in oidn.h.
            unsafe { lib.get::<T>(name.as_bytes()) }
                .map(|s| *s)
                .map_err(|e| {
                    format!(
                        "{}: not an Open Image Denoise 2 library (no {name}: {e})",
                        path.display()
                    )
                })
        }
        let api = Api {
            new_device: sym(&lib, &path, "oidnNewDevice")?,
            commit_device: sym(&lib, &path, "oidnCommitDevice")?,
            release_device: sym(&lib, &path, "oidnReleaseDevice")?,
            get_device_error: sym(&lib, &path, "oidnGetDeviceError")?,
            get_device_int: sym(&lib, &path, "oidnGetDeviceInt")?,
            new_buffer: sym(&lib, &path, "oidnNewBuffer")?,
            write_buffer: sym(&lib, &path, "oidnWriteBuffer")?,
            read_buffer: sym(&lib, &path, "oidnReadBuffer")?,
            release_buffer: sym(&lib, &path, "oidnReleaseBuffer")?,
            new_filter: sym(&lib, &path, "oidnNewFilter")?,
            set_filter_image: sym(&lib, &path, "oidnSetFilterImage")?,
            set_filter_bool: sym(&lib, &path, "oidnSetFilterBool")?,
            commit_filter: sym(&lib, &path, "oidnCommitFilter")?,
            execute_filter: sym(&lib, &path, "oidnExecuteFilter")?,
            release_filter: sym(&lib, &path, "oidnReleaseFilter")?,
        };
        // SAFETY: calls of the C API as documented; the device is released in Drop.
        let device = unsafe { (api.new_device)(DEVICE_TYPE_DEFAULT) };
        let mut oidn = Oidn {
            api,
            device,
            path,
            version: 0,
            _lib: lib,
        };
        if device.is_null() {
            return Err(format!(
                "{}: Open Image Denoise could not create a device",
                oidn.path.display()
            ));
        }
        unsafe { (api.commit_device)(device) };
        oidn.check("creating the device")?;
        oidn.version = unsafe { (api.get_device_int)(device, c"version".as_ptr()) };
        Ok(oidn)
    }

    /// The device's pending error, if any.
    fn check(&self, what: &str) -> Result<(), String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: the device is live; OIDN owns the message until the next call.
        let code = unsafe { (self.api.get_device_error)(self.device, &mut message) };
        if code == ERROR_NONE {
            return Ok(());
        }
        let text = if message.is_null() {
            String::from("no message")
        } else {
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Err(format!(
            "Open Image Denoise ({}) failed {what}: error {code}: {text}",
            self.path.display()
        ))
    }

    /// Denoises `color` with the albedo and normal guides of the same size (row-major).
    /// With `emission` = (taken, added), the directly seen emission `taken` is kept out of
    /// the filter and `added` put in its place (see the module documentation).
    pub fn denoise(
        &self,
        color: &Image,
        albedo: &[Color],
        normal: &[Vec3A],
        emission: Option<(&[Color], &[Color])>,
    ) -> Result<Image, String> {
        let n = color.pixels.len();
        let bad = |e: &[Color]| e.len() != n;
        if albedo.len() != n || normal.len() != n || emission.is_some_and(|(t, a)| bad(t) || bad(a))
        {
            return Err("the guide layers do not have the image's size".into());
        }
        let Some((taken, added)) = emission else {
            return self.filter(color, albedo, normal);
        };
        // Never more than the pixel holds (rounding), so that OIDN sees no negative value.
        let rest = Image {
            width: color.width,
            height: color.height,
            pixels: color
                .pixels
                .iter()
                .zip(taken)
                .map(|(c, t)| *c - t.min(*c).max(Color::ZERO))
                .collect(),
        };
        let mut out = self.filter(&rest, albedo, normal)?;
        for (o, a) in out.pixels.iter_mut().zip(added) {
            *o += *a;
        }
        Ok(out)
    }

    /// Runs the RT filter on `color`.
    fn filter(&self, color: &Image, albedo: &[Color], normal: &[Vec3A]) -> Result<Image, String> {
        let n = color.pixels.len();
        let (w, h) = (color.width as usize, color.height as usize);
        let flat = |it: &mut dyn Iterator<Item = [f32; 3]>| -> Vec<f32> { it.flatten().collect() };
        let inputs = [
            (
                "color",
                flat(&mut color.pixels.iter().map(|p| p.to_array())),
            ),
            ("albedo", flat(&mut albedo.iter().map(|p| p.to_array()))),
            ("normal", flat(&mut normal.iter().map(|p| p.to_array()))),
        ];
        let bytes = n * 3 * std::mem::size_of::<f32>();
        let api = self.api;
        // Every handle made here, released on every path out.
        let mut buffers: Vec<Handle> = Vec::new();
        let mut filter: Handle = std::ptr::null_mut();
        let result = (|| -> Result<Vec<f32>, String> {
            // SAFETY: calls of the C API as documented, on a live device; each buffer is
            // `bytes` long and each host slice holds exactly `bytes`.
            unsafe {
                filter = (api.new_filter)(self.device, c"RT".as_ptr());
                self.check("creating the RT filter")?;
                for (name, data) in &inputs {
                    let b = (api.new_buffer)(self.device, bytes);
                    self.check("allocating a buffer")?;
                    buffers.push(b);
                    (api.write_buffer)(b, 0, bytes, data.as_ptr().cast());
                    let cname = CString::new(*name).expect("no NUL");
                    (api.set_filter_image)(filter, cname.as_ptr(), b, FORMAT_FLOAT3, w, h, 0, 0, 0);
                }
                let out = (api.new_buffer)(self.device, bytes);
                self.check("allocating a buffer")?;
                buffers.push(out);
                (api.set_filter_image)(
                    filter,
                    c"output".as_ptr(),
                    out,
                    FORMAT_FLOAT3,
                    w,
                    h,
                    0,
                    0,
                    0,
                );
                (api.set_filter_bool)(filter, c"hdr".as_ptr(), true);
                (api.commit_filter)(filter);
                self.check("setting up the RT filter")?;
                (api.execute_filter)(filter);
                self.check("denoising")?;
                let mut result = vec![0f32; n * 3];
                (api.read_buffer)(out, 0, bytes, result.as_mut_ptr().cast());
                self.check("reading the result")?;
                Ok(result)
            }
        })();
        unsafe {
            for b in buffers {
                (api.release_buffer)(b);
            }
            if !filter.is_null() {
                (api.release_filter)(filter);
            }
        }
        let v = result?;
        Ok(Image {
            width: color.width,
            height: color.height,
            pixels: v
                .chunks_exact(3)
                .map(|c| Color::new(c[0], c[1], c[2]))
                .collect(),
        })
    }

    /// Denoises a render (`film`) with the guide layers of [`crate::aov::render_guides`],
    /// its directly seen emission kept out ([`crate::aov::emission_split`]).
    pub fn denoise_render(
        &self,
        scene: &Scene,
        s: &RenderSettings,
        film: &Film,
        guides: &Guides,
    ) -> Result<Image, crate::Error> {
        let (taken, added) = emission_split(scene, s, guides, film)?;
        let color = film.image();
        self.denoise(
            &color,
            &guides.albedo,
            &guides.normal,
            Some((&taken, &added)),
        )
        .map_err(crate::Error::Denoise)
    }
}

impl Drop for Oidn {
    fn drop(&mut self) {
        // SAFETY: the device was made by this library, which is still loaded.
        unsafe { (self.api.release_device)(self.device) };
    }
}

/// Where `--denoise` writes the raw image: OUTPUT's stem + `.raw` + its extension
/// (`out.exr` → `out.raw.exr`).
pub fn raw_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().unwrap_or_default().to_string_lossy();
    let name = match output.extension() {
        Some(ext) => format!("{stem}.raw.{}", ext.to_string_lossy()),
        None => format!("{stem}.raw"),
    };
    output.with_file_name(name)
}

/// An image with its albedo and normal guides, as `mcrt render --aov albedo,normal` writes
/// it: channels `R`, `G`, `B`, `albedo.R/G/B` and `normal.X/Y/Z`, and optionally
/// `emission.R/G/B` (`--aov albedo,normal,emission`).
pub struct GuidedImage {
    pub color: Image,
    pub albedo: Vec<Color>,
    pub normal: Vec<Vec3A>,
    pub emission: Option<Vec<Color>>,
}

/// Reads an EXR with the layers of [`GuidedImage`]; the message names what is missing.
pub fn read_guided_exr(path: &Path) -> Result<GuidedImage, String> {
    let shown = path.display();
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| format!("{shown}: cannot read as OpenEXR: {e}"))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| format!("{shown}: the file has no image"))?;
    // Refuse, before decoding, an image too large for the memory there is.
    let size = header.layer_size;
    let need = (size.width() as u64)
        .saturating_mul(size.height() as u64)
        .saturating_mul(header.channels.list.len() as u64)
        .saturating_mul(4 * 3);
    if let Some(have) = crate::available_memory() {
        if need > have {
            return Err(format!(
                "{shown}: a {} × {} image with {} channels needs more memory than is available",
                size.width(),
                size.height(),
                header.channels.list.len()
            ));
        }
    }
    let img = exr::prelude::read_all_flat_layers_from_file(path)
        .map_err(|e| format!("{shown}: cannot read as OpenEXR: {e}"))?;
    let layer = img
        .layer_data
        .first()
        .ok_or_else(|| format!("{shown}: the file has no image"))?;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channel = |name: &str| -> Result<Vec<f32>, String> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .map(|c| c.sample_data.values_as_f32().collect())
            .ok_or_else(|| {
                format!(
                    "{shown}: no channel '{name}' (denoising needs R, G, B, albedo.R/G/B and \
                     normal.X/Y/Z: render with --aov albedo,normal)"
                )
            })
    };
    let triple = |names: [&str; 3]| -> Result<Vec<[f32; 3]>, String> {
        let [a, b, c] = names.map(channel);
        let (a, b, c) = (a?, b?, c?);
        Ok((0..w * h).map(|i| [a[i], b[i], c[i]]).collect())
    };
    let color = triple(["R", "G", "B"])?;
    let albedo = triple(["albedo.R", "albedo.G", "albedo.B"])?;
    let normal = triple(["normal.X", "normal.Y", "normal.Z"])?;
    let has = |name: &str| layer.channel_data.list.iter().any(|c| c.name == *name);
    let emission = if has("emission.R") {
        Some(triple(["emission.R", "emission.G", "emission.B"])?)
    } else {
        None
    };
    Ok(GuidedImage {
        color: Image {
            width: w as u32,
            height: h as u32,
            pixels: color.into_iter().map(Color::from_array).collect(),
        },
        albedo: albedo.into_iter().map(Color::from_array).collect(),
        normal: normal.into_iter().map(Vec3A::from_array).collect(),
        emission: emission.map(|e| e.into_iter().map(Color::from_array).collect()),
    })
}
