//! Images in memory and on disk: linear RGB, written as OpenEXR (linear half or float) or as
//! 8-bit sRGB PNG after exposure and a tone map. Files are written to a temporary name in the
//! same directory and renamed, so no half-written image ever stands at the output path.

use crate::Color;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first, linear RGB.
    pub pixels: Vec<Color>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ToneMap {
    /// Clamp to [0, 1].
    #[default]
    Clamp,
    /// Reinhard, L/(1 + L) per channel.
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve ("ACES Filmic Tone Mapping Curve", 2016).
    Aces,
}

#[derive(Clone, Copy, Debug)]
pub struct WriteOptions {
    /// Exposure in stops: pixel values are multiplied by 2^exposure before tone mapping
    /// (PNG only).
    pub exposure: f32,
    pub tonemap: ToneMap,
    /// Write EXR as 16-bit half floats instead of 32-bit floats.
    pub half: bool,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            exposure: 0.0,
            tonemap: ToneMap::Clamp,
            half: false,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Exr,
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: unsupported image format (use a .png or .exr file name)")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: the directory {dir} does not exist")]
    NoDirectory { path: PathBuf, dir: PathBuf },
    #[error("{path}: cannot write here: {source}")]
    NotWritable {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
}

impl Format {
    pub fn from_path(path: &Path) -> Result<Format, ImageError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            _ => Err(ImageError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

impl Image {
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![Color::ZERO; width as usize * height as usize],
        }
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Color {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean over the block of `bs`×`bs` pixels at block coordinates (bx, by), in f64.
    pub fn block_mean(&self, bx: u32, by: u32, bs: u32) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for y in by * bs..((by + 1) * bs).min(self.height) {
            for x in bx * bs..((bx + 1) * bs).min(self.width) {
                let p = self.get(x, y);
                for c in 0..3 {
                    s[c] += p[c] as f64;
                }
            }
        }
        let n = (bs * bs) as f64;
        s.map(|v| v / n)
    }

    /// 8-bit sRGB bytes after exposure and tone mapping.
    pub fn to_srgb8(&self, opts: &WriteOptions) -> Vec<u8> {
        let scale = 2f32.powf(opts.exposure);
        let mut out = Vec::with_capacity(self.pixels.len() * 3);
        for p in &self.pixels {
            let v = *p * scale;
            let t = match opts.tonemap {
                ToneMap::Clamp => v,
                ToneMap::Reinhard => v / (Color::ONE + v.max(Color::ZERO)),
                ToneMap::Aces => {
                    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
                    let v = v.max(Color::ZERO);
                    (v * (a * v + b)) / (v * (c * v + d) + e)
                }
            };
            for ch in 0..3 {
                out.push((linear_to_srgb(t[ch]) * 255.0 + 0.5) as u8);
            }
        }
        out
    }
}

/// The sRGB transfer function (IEC 61966-2-1), on [0, 1] after clamping; NaN maps to 0.
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Checks, before a long render, that an image can be written at `path`: the format is known,
/// the name is a file's (not `DIR/`), the directory exists and a file can be created in it,
/// and what stands at `path` already, if anything, is a regular file that may be written
/// (not a directory, a device, an immutable or a read-only file). Removes the temporaries of
/// earlier runs for this path that were killed while writing ([`clean_stale_temps`]).
pub fn check_output_path(path: &Path) -> Result<Format, ImageError> {
    let refuse = |why: &str| ImageError::NotWritable {
        path: path.to_path_buf(),
        source: std::io::Error::other(why.to_string()),
    };
    if path.as_os_str().as_encoded_bytes().ends_with(b"/") {
        return Err(refuse(
            "the name ends with '/': it names a directory, not an image file",
        ));
    }
    let format = Format::from_path(path)?;
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(ImageError::NoDirectory {
            path: path.to_path_buf(),
            dir,
        });
    }
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => return Err(refuse("it is a directory")),
        Ok(m) if !m.is_file() => return Err(refuse("it is not a regular file")),
        Ok(_) => {
            // Opening for writing without truncating changes nothing, and fails for an
            // immutable or read-only file that the rename at the end would fail on or
            // silently replace.
            if let Err(source) = std::fs::OpenOptions::new().write(true).open(path) {
                return Err(ImageError::NotWritable {
                    path: path.to_path_buf(),
                    source,
                });
            }
        }
        Err(_) => {}
    }
    clean_stale_temps(path);
    let probe = temp_path(path);
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(format)
        }
        Err(source) => Err(ImageError::NotWritable {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// Whether two paths name the same file: the same device and inode where both exist, else
/// the same canonical directory and file name.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return (x.dev(), x.ino()) == (y.dev(), y.ino());
        }
    }
    let resolve = |p: &Path| {
        let dir = parent_dir(p);
        (
            dir.canonicalize().unwrap_or(dir),
            p.file_name().map(|n| n.to_owned()),
        )
    };
    resolve(a) == resolve(b)
}

/// Longest file name most file systems take (NAME_MAX), in bytes.
const NAME_MAX: usize = 255;

/// `prefix + name + suffix`, or, where that is longer than [`NAME_MAX`], `name` cut short and
/// followed by a hash of the whole of it (so different long names stay different).
pub fn fit_file_name(prefix: &str, name: &str, suffix: &str) -> String {
    let whole = format!("{prefix}{name}{suffix}");
    if whole.len() <= NAME_MAX {
        return whole;
    }
    // FNV-1a: stable across runs, so a later run finds the same name.
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    });
    let tag = format!("~{hash:016x}");
    let mut keep = NAME_MAX.saturating_sub(prefix.len() + tag.len() + suffix.len());
    while keep > 0 && !name.is_char_boundary(keep) {
        keep -= 1;
    }
    format!("{prefix}{}{tag}{suffix}", &name[..keep.min(name.len())])
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The part of a temporary's name before its process id: `.NAME.` (shortened where the
/// whole would be too long a file name).
fn temp_prefix(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // Room for the longest process id (u32) and ".tmp".
    let long = fit_file_name(".", &name, ".4294967295.tmp");
    format!("{}.", long.trim_end_matches(".4294967295.tmp"))
}

/// The temporary file an image is written to before the rename: `DIR/.NAME.PID.tmp`.
fn temp_path(path: &Path) -> PathBuf {
    parent_dir(path).join(format!("{}{}.tmp", temp_prefix(path), std::process::id()))
}

/// Removes the temporaries `.NAME.PID.tmp` of `path` whose process no longer runs (killed
/// while writing, e.g. by SIGKILL). Only where the running processes can be listed
/// (/proc); others' temporaries are left alone.
pub fn clean_stale_temps(path: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let prefix = temp_prefix(path);
    let Ok(entries) = std::fs::read_dir(parent_dir(path)) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|n| n.strip_suffix(".tmp"))
            .and_then(|n| n.parse::<u32>().ok())
        else {
            continue;
        };
        let alive = Path::new("/proc").join(pid.to_string()).exists();
        if !alive && e.file_type().is_ok_and(|t| t.is_file()) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Writes the image in the format the extension names, atomically (temporary file + rename).
pub fn write_image(path: &Path, img: &Image, opts: &WriteOptions) -> Result<(), ImageError> {
    let format = Format::from_path(path)?;
    write_atomic(path, |tmp| match format {
        Format::Png => write_png(tmp, img, opts),
        Format::Exr => write_exr(tmp, img, opts.half),
    })
}

/// Writes an EXR image with extra channels (name, one f32 per pixel, e.g. `albedo.R`) beside
/// its `R`, `G`, `B`, atomically. Without extra channels it is [`write_image`].
pub fn write_image_with(
    path: &Path,
    img: &Image,
    opts: &WriteOptions,
    extra: &[(String, Vec<f32>)],
) -> Result<(), ImageError> {
    if extra.is_empty() {
        return write_image(path, img, opts);
    }
    if Format::from_path(path)? != Format::Exr {
        return Err(ImageError::Io {
            path: path.to_path_buf(),
            message: "extra layers need an .exr image".into(),
        });
    }
    write_atomic(path, |tmp| write_exr_layers(tmp, img, opts.half, extra))
}

fn write_exr_layers(
    path: &Path,
    img: &Image,
    half: bool,
    extra: &[(String, Vec<f32>)],
) -> Result<(), String> {
    use exr::prelude::*;
    let (w, h) = (img.width as usize, img.height as usize);
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let v = img.pixels.iter().map(|p| p[c]);
        let samples = if half {
            FlatSamples::F16(v.map(f16::from_f32).collect())
        } else {
            FlatSamples::F32(v.collect())
        };
        channels.push(AnyChannel::new(*name, samples));
    }
    for (name, v) in extra {
        if v.len() != w * h {
            return Err(format!("layer {name} does not have the image's size"));
        }
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(v.clone())));
    }
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    exr::image::Image::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| e.to_string())
}

/// Writes a file atomically: `write` fills a temporary file in the same directory, which is
/// then renamed to `path` (and removed if anything fails).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), ImageError> {
    let tmp = temp_path(path);
    let io = |message: String| ImageError::Io {
        path: path.to_path_buf(),
        message,
    };
    if let Err(message) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(message));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e.to_string())
    })
}

fn write_png(path: &Path, img: &Image, opts: &WriteOptions) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    encode_png(std::io::BufWriter::new(file), img, opts)
}

/// Encodes the image as an 8-bit sRGB PNG (exposure and tone map applied) into `w`.
pub fn encode_png(w: impl std::io::Write, img: &Image, opts: &WriteOptions) -> Result<(), String> {
    let mut enc = png::Encoder::new(w, img.width, img.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer
        .write_image_data(&img.to_srgb8(opts))
        .map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

fn write_exr(path: &Path, img: &Image, half: bool) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    encode_exr(std::io::BufWriter::new(file), img, half)
}

/// Encodes the image as a linear RGB OpenEXR file into `w`.
pub fn encode_exr(
    w: impl std::io::Write + std::io::Seek,
    img: &Image,
    half: bool,
) -> Result<(), String> {
    use exr::prelude::*;
    let mut out = w;
    let (w, h) = (img.width as usize, img.height as usize);
    let get = |x: usize, y: usize| img.pixels[y * w + x];
    // RLE in 64² tiles (the crate's fast default), stored in increasing order: the tiles are
    // compressed in parallel, and with the default's unspecified order they were written as
    // they finished, so two writes of one image differed in their bytes.
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    let r = if half {
        let channels = SpecificChannels::rgb(|Vec2(x, y)| {
            let p = get(x, y);
            (f16::from_f32(p.x), f16::from_f32(p.y), f16::from_f32(p.z))
        });
        Image::from_encoded_channels((w, h), encoding, channels)
            .write()
            .to_buffered(&mut out)
    } else {
        let channels = SpecificChannels::rgb(|Vec2(x, y)| {
            let p = get(x, y);
            (p.x, p.y, p.z)
        });
        Image::from_encoded_channels((w, h), encoding, channels)
            .write()
            .to_buffered(&mut out)
    };
    r.map_err(|e| e.to_string())?;
    out.flush().map_err(|e| e.to_string())
}

/// Reads the first RGB(A) layer of an OpenEXR file as linear RGB: the file is read once
/// ([`crate::input::read`]) and decoded by [`decode_exr`].
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let io = |message: String| ImageError::Io {
        path: path.to_path_buf(),
        message,
    };
    let bytes = crate::input::read(path).map_err(io)?;
    decode_exr(&bytes).map_err(io)
}

/// Decodes the first RGB(A) layer of an OpenEXR file's bytes as linear RGB, once
/// [`check_exr_memory`] has found that its size fits in memory.
pub fn decode_exr(bytes: &[u8]) -> Result<Image, String> {
    use exr::prelude::*;
    check_exr_memory(bytes, std::mem::size_of::<Color>() as u64)?;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| self::Image::new(res.width() as u32, res.height() as u32),
            |img: &mut self::Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let i = pos.y() * img.width as usize + pos.x();
                img.pixels[i] = Color::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    Ok(img.layer_data.channel_data.pixels)
}

/// Reads an OpenEXR file's headers and checks, before anything the size of its pixels is
/// allocated, that decoding its largest layer fits in memory ([`crate::check_allocation`]):
/// the decoder's samples of every channel plus `per_pixel` bytes a pixel for the caller's
/// copy, and the decoder's working memory, two copies of a decompressed block for each
/// thread decoding at once. A header may claim any size (a 313-byte file can claim
/// 100000 × 100000 pixels, one scanline block of a ZIP file 16 lines of any width).
pub fn check_exr_memory(bytes: &[u8], per_pixel: u64) -> Result<(), String> {
    use exr::meta::BlockDescription;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| e.to_string())?;
    let threads = rayon::current_num_threads() as u64;
    let mut largest = (0u64, 0usize, 0usize);
    for h in meta.headers.iter() {
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        let pixels = (w as u64).saturating_mul(ht as u64);
        let samples: u64 = h
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u64)
            .sum();
        let block = match h.blocks {
            BlockDescription::Tiles(t) => {
                (t.tile_size.width() as u64).saturating_mul(t.tile_size.height() as u64)
            }
            BlockDescription::ScanLines => {
                (h.compression.scan_lines_per_block() as u64).saturating_mul(w as u64)
            }
        }
        .min(pixels);
        let working = block.saturating_mul(samples).saturating_mul(2 * threads);
        let need = pixels
            .saturating_mul(samples.saturating_add(per_pixel))
            .saturating_add(working);
        if need > largest.0 {
            largest = (need, w, ht);
        }
    }
    let (need, w, h) = largest;
    crate::check_allocation(need)
        .map_err(|e| format!("its header claims {w} × {h} pixels, which {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An EXR file's bytes depend only on the image: tiles compressed in parallel are still
    /// stored in one order (a noisy 512² image, many tiles, written several times), and the
    /// file reads back as the image.
    #[test]
    fn exr_bytes_are_deterministic() {
        let mut img = Image::new(512, 512);
        let mut s = crate::sampler::Sampler::from_state(1, 2);
        for p in &mut img.pixels {
            *p = Color::new(s.next_1d(), s.next_1d() * 4.0, s.next_1d() * 0.1);
        }
        let dir = std::env::temp_dir().join(format!("mcrt-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes: Vec<Vec<u8>> = (0..6)
            .map(|i| {
                let path = dir.join(format!("{i}.exr"));
                write_image(&path, &img, &WriteOptions::default()).unwrap();
                std::fs::read(&path).unwrap()
            })
            .collect();
        let back = read_exr(&dir.join("0.exr")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(bytes.iter().all(|b| *b == bytes[0]), "writes differ");
        assert_eq!(back.pixels, img.pixels);
    }
}
