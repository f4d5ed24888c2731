//! Textures: constant colors, bitmaps (PNG, OpenEXR) and a procedural checkerboard, with the
//! semantics of Mitsuba 3's `bitmap` and `checkerboard` plugins.
//!
//! # Texture coordinates
//!
//! A lookup first maps `uv` through the texture's `to_uv` affine transform (Mitsuba's
//! `transform_affine`). For bitmaps, `u` runs along a row from the left edge (u = 0) to the
//! right edge (u = 1) and `v` runs down the image from its **top** row (v = 0, the first row
//! stored in the file) to its bottom row (v = 1): there is no flip of v in the texture,
//! exactly as in Mitsuba 3, where the bitmap is a tensor of shape `[height, width, channels]`
//! indexed by `(v · height, u · width)` (drjit `Texture::eval_nonaccel`, used by
//! `BitmapTextureImpl::interpolate_3` in `src/textures/bitmap.cpp`). Mitsuba's mesh loaders flip
//! v instead, with their `flip_tex_coords` option: default true in `obj.cpp` (an OBJ `vt` with
//! v = 1 ends on the top row), default false in `ply.cpp`. A mesh loader that wants Mitsuba's
//! behaviour applies `v ↦ 1 − v` itself (OBJ), or nothing (PLY).
//!
//! Pixel (x, y) covers `[x/w, (x+1)/w] × [y/h, (y+1)/h]` and its centre is at
//! `((x + ½)/w, (y + ½)/h)`:
//! - `nearest`: the pixel `⌊u·w⌋, ⌊v·h⌋` (after wrapping);
//! - `bilinear` (default): `p = uv·(w, h) − ½`, the four pixels `⌊p⌋ + {0, 1}²` (each wrapped),
//!   weighted by `p − ⌊p⌋`; so pixel centres return the pixel exactly.
//!
//! Wrapping of integer pixel indices (drjit `Texture::wrap`): `repeat` is the Euclidean
//! remainder; `clamp` clamps to `[0, n − 1]`; `mirror` reflects about each edge, so that
//! indices −1 and n map to 0 and n − 1 (period 2n).

use crate::scene::SceneError;
use crate::Color;
use glam::{Affine2, Mat2, Mat3, Mat4, Vec2};
use std::path::Path;
use std::sync::Arc;

/// An affine map of texture coordinates (Mitsuba's `to_uv`), applied before every lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform(pub Affine2);

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform::IDENTITY
    }
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform(Affine2::IDENTITY);

    /// `uv ↦ s ∘ uv`.
    pub fn scale(s: Vec2) -> Self {
        UvTransform(Affine2::from_scale(s))
    }

    /// `uv ↦ uv + t`.
    pub fn translate(t: Vec2) -> Self {
        UvTransform(Affine2::from_translation(t))
    }

    /// From a 3×3 homogeneous matrix acting on `(u, v, 1)`; the last row is ignored, as in
    /// Mitsuba's `transform_affine`.
    pub fn from_mat3(m: Mat3) -> Self {
        UvTransform(Affine2::from_mat2_translation(
            Mat2::from_cols(m.x_axis.truncate(), m.y_axis.truncate()),
            m.z_axis.truncate(),
        ))
    }

    /// From a 4×4 matrix, as Mitsuba's `Transform4f::extract()` does: the upper-left 2×2
    /// block and the x, y translation (column 3); the z row and column are dropped.
    pub fn from_mat4(m: Mat4) -> Self {
        UvTransform(Affine2::from_mat2_translation(
            Mat2::from_cols(
                m.x_axis.truncate().truncate(),
                m.y_axis.truncate().truncate(),
            ),
            m.w_axis.truncate().truncate(),
        ))
    }

    /// `self` after `first`: `uv ↦ self(first(uv))`.
    pub fn after(self, first: UvTransform) -> Self {
        UvTransform(self.0 * first.0)
    }

    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.0.transform_point2(uv)
    }
}

/// How bitmap lookups between pixel centres are reconstructed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FilterType {
    #[default]
    Bilinear,
    Nearest,
}

/// How bitmap lookups outside [0, 1]² are mapped back into the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WrapMode {
    #[default]
    Repeat,
    Mirror,
    Clamp,
}

impl FilterType {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "bilinear" => Some(FilterType::Bilinear),
            "nearest" => Some(FilterType::Nearest),
            _ => None,
        }
    }
}

impl WrapMode {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "repeat" => Some(WrapMode::Repeat),
            "mirror" => Some(WrapMode::Mirror),
            "clamp" => Some(WrapMode::Clamp),
            _ => None,
        }
    }

    /// Wraps an integer pixel index into `[0, n)` (n ≥ 1).
    #[inline]
    pub(crate) fn wrap(self, i: i64, n: i64) -> usize {
        (match self {
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }) as usize
    }
}

/// The exact sRGB EOTF (IEC 61966-2-1): encoded value in [0, 1] to linear.
#[inline]
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The luminance Y of a linear sRGB colour, with Mitsuba's coefficients (`luminance()` in
/// include/mitsuba/core/spectrum.h): what a bitmap gives where a float is read.
#[inline]
pub fn luminance(c: Color) -> f32 {
    c.x * 0.212_671 + c.y * 0.715_160 + c.z * 0.072_169
}

/// What is wrong with a colour value, constant or texel, by the one rule they all obey:
/// finite and not negative, and for a reflectance (`max` = 1) at most `max` in every channel.
/// None when it is right. The message completes "'albedo' …" or "texture values …".
pub fn color_fault(c: Color, max: Option<f32>) -> Option<String> {
    if !c.is_finite() || c.min_element() < 0.0 {
        return Some("must be finite and not negative".into());
    }
    match max {
        Some(m) if c.max_element() > m => Some(format!(
            "must be at most {m} in every channel (a surface cannot reflect more light than \
             it receives)"
        )),
        _ => None,
    }
}

/// Largest decoded PNG accepted (bytes of 8- or 16-bit samples), against hostile headers.
const MAX_PNG_BYTES: usize = 1 << 30;

/// Image data of a bitmap texture: linear RGB (or raw values), row-major, row 0 = the top row
/// of the file. Grayscale images are stored as gray RGB; alpha is dropped (as Mitsuba does).
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    pub width: u32,
    pub height: u32,
    texels: Texels,
    mean: Color,
    /// The largest value of any channel of any pixel.
    max: f32,
    /// Every pixel grey (a one-channel image, or grey RGB): its float value is any channel.
    gray: bool,
}

/// How a bitmap holds its pixels. An 8-bit image keeps its bytes and decodes each channel
/// through a table of the 256 values (sRGB-decoded, or raw `i/255`) at every lookup, as
/// pbrt-v4's `Image` keeps `U256` pixels: the same floats as decoding them all at load, in
/// a quarter of the memory (3 bytes a texel, not 12), so four times as many texels share a
/// cache (a 512² terrain texture: 0.8 MB, not 3 MB).
#[derive(Clone, Debug, PartialEq)]
enum Texels {
    /// Linear floats (HDR and 16-bit images, and pixels made in memory).
    Float(Vec<Color>),
    /// Bytes, each channel's value `table[byte]`.
    Bytes {
        rgb: Vec<[u8; 3]>,
        table: Box<[f32; 256]>,
    },
}

impl Bitmap {
    /// A bitmap from linear pixel values (row-major, top row first). Errors when the size
    /// is zero or does not match the pixel count, or a pixel breaks [`color_fault`]'s rule.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Color>) -> Result<Bitmap, String> {
        Bitmap::new(width, height, Texels::Float(pixels))
    }

    /// A bitmap from 8-bit pixels (row-major, top row first), channel value `b` standing for
    /// `table[b]`; errors as [`Bitmap::from_pixels`].
    pub fn from_bytes(
        width: u32,
        height: u32,
        rgb: Vec<[u8; 3]>,
        table: [f32; 256],
    ) -> Result<Bitmap, String> {
        let table = Box::new(table);
        Bitmap::new(width, height, Texels::Bytes { rgb, table })
    }

    fn new(width: u32, height: u32, texels: Texels) -> Result<Bitmap, String> {
        if width == 0 || height == 0 {
            return Err(format!("empty image ({width}×{height})"));
        }
        let n = texels.len();
        if n as u64 != width as u64 * height as u64 {
            return Err(format!("{n} pixels given for a {width}×{height} image"));
        }
        let mut sum = glam::DVec3::ZERO;
        let mut max = 0f32;
        let mut gray = true;
        for i in 0..n {
            let p = texels.get(i);
            if let Some(f) = color_fault(p, None) {
                let (x, y) = (i as u64 % width as u64, i as u64 / width as u64);
                return Err(format!(
                    "pixel ({x}, {y}) is ({}, {}, {}): texture values {f}",
                    p.x, p.y, p.z
                ));
            }
            sum += p.as_dvec3();
            max = max.max(p.max_element());
            gray &= p.x == p.y && p.y == p.z;
        }
        let mean = (sum / n as f64).as_vec3();
        Ok(Bitmap {
            width,
            height,
            texels,
            mean,
            max,
            gray,
        })
    }

    /// Reads a PNG (8 or 16 bits; gray, gray+alpha, RGB, RGBA or palette), OpenEXR or
    /// Radiance HDR ([`crate::rgbe`]) file, recognized by its first bytes. Unless `raw`, PNG
    /// values are sRGB-decoded to linear; EXR and HDR values are linear and kept as they are. The file is read once
    /// ([`crate::input::read`]).
    pub fn load(path: &Path, raw: bool) -> Result<Bitmap, SceneError> {
        let err = |msg: String| SceneError::new(path, None, msg);
        let bytes =
            crate::input::read(path).map_err(|e| err(format!("cannot read texture: {e}")))?;
        Bitmap::decode(&bytes, raw).map_err(err)
    }

    /// Decodes a PNG or OpenEXR file's bytes (see [`Bitmap::load`]), checking the decoded
    /// size against the memory budget before it is allocated.
    pub fn decode(bytes: &[u8], raw: bool) -> Result<Bitmap, String> {
        if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            decode_png(bytes, raw)
        } else if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            let img = crate::image::decode_exr(bytes)
                .map_err(|e| format!("cannot read OpenEXR texture: {e}"))?;
            Bitmap::from_pixels(img.width, img.height, img.pixels)
        } else if crate::rgbe::is_rgbe(bytes) {
            let (w, h, pixels) = crate::rgbe::decode(bytes)
                .map_err(|e| format!("cannot read Radiance HDR image: {e}"))?;
            Bitmap::from_pixels(w, h, pixels)
        } else if bytes.len() < 8 {
            Err("not a PNG, OpenEXR or Radiance HDR image (file too short)".into())
        } else {
            Err("unsupported image format (expected PNG, OpenEXR or Radiance HDR)".into())
        }
    }

    /// Per-channel mean of the pixels.
    pub fn mean(&self) -> Color {
        self.mean
    }

    /// The largest value of any channel of any pixel.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// A pixel's value as a float (Mitsuba's `eval_1`): the value of a grey image, else the
    /// luminance.
    #[inline]
    fn float_of(&self, c: Color) -> f32 {
        if self.gray {
            c.x
        } else {
            luminance(c)
        }
    }

    /// Pixel `i` (row-major, top row first), linear.
    #[inline]
    pub fn pixel(&self, i: usize) -> Color {
        self.texels.get(i)
    }

    /// The pixels in order (row-major, top row first), linear.
    pub fn pixels(&self) -> impl ExactSizeIterator<Item = Color> + '_ {
        (0..self.texels.len()).map(|i| self.texels.get(i))
    }

    /// Bytes of the pixels.
    pub fn memory_bytes(&self) -> usize {
        match &self.texels {
            Texels::Float(v) => std::mem::size_of_val(&v[..]),
            Texels::Bytes { rgb, .. } => std::mem::size_of_val(&rgb[..]) + 256 * 4,
        }
    }

    #[inline]
    fn texel(&self, x: usize, y: usize) -> Color {
        self.pixel(y * self.width as usize + x)
    }

    /// Lookup at `uv` (already mapped by `to_uv`).
    pub fn lookup(&self, uv: Vec2, filter: FilterType, wrap: WrapMode) -> Color {
        let (w, h) = (self.width as i64, self.height as i64);
        let res = Vec2::new(self.width as f32, self.height as f32);
        match filter {
            FilterType::Nearest => {
                let p = (uv * res).floor();
                // `as` saturates (NaN gives 0): no overflow for any input.
                let x = wrap.wrap(p.x as i64, w);
                let y = wrap.wrap(p.y as i64, h);
                self.texel(x, y)
            }
            FilterType::Bilinear => {
                let p = uv * res - 0.5;
                let p0 = p.floor();
                let w1 = p - p0;
                let w0 = 1.0 - w1;
                let (xi, yi) = (p0.x as i64, p0.y as i64);
                let x0 = wrap.wrap(xi, w);
                let x1 = wrap.wrap(xi.saturating_add(1), w);
                let y0 = wrap.wrap(yi, h);
                let y1 = wrap.wrap(yi.saturating_add(1), h);
                // Accumulated in drjit's order: 00, 10, 01, 11.
                let mut out = self.texel(x0, y0) * (w0.x * w0.y);
                out += self.texel(x1, y0) * (w1.x * w0.y);
                out += self.texel(x0, y1) * (w0.x * w1.y);
                out += self.texel(x1, y1) * (w1.x * w1.y);
                out
            }
        }
    }
}

impl Texels {
    fn len(&self) -> usize {
        match self {
            Texels::Float(v) => v.len(),
            Texels::Bytes { rgb, .. } => rgb.len(),
        }
    }

    #[inline(always)]
    fn get(&self, i: usize) -> Color {
        match self {
            Texels::Float(v) => v[i],
            Texels::Bytes { rgb, table } => {
                let [r, g, b] = rgb[i];
                Color::new(table[r as usize], table[g as usize], table[b as usize])
            }
        }
    }
}

fn decode_png(bytes: &[u8], raw: bool) -> Result<Bitmap, String> {
    let mut decoder = png::Decoder::new_with_limits(
        std::io::Cursor::new(bytes),
        png::Limits {
            bytes: MAX_PNG_BYTES,
        },
    );
    // Palette → RGB(A), gray below 8 bits → 8 bits, tRNS → alpha; 16 bits stay 16 bits.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("cannot read PNG texture: {e}"))?;
    let size = reader.output_buffer_size();
    if size > MAX_PNG_BYTES {
        return Err(format!(
            "PNG texture too large ({size} bytes decoded, at most {MAX_PNG_BYTES})"
        ));
    }
    // The decoded samples and the pixels kept from them (bytes of 8-bit images, floats of
    // 16-bit ones: see `Texels`), both sized by the header.
    let (w, h) = reader.info().size();
    let pixels = w as u64 * h as u64;
    let kept = match reader.output_color_type().1 {
        png::BitDepth::Sixteen => std::mem::size_of::<Color>(),
        _ => 3,
    };
    crate::check_allocation((size as u64).saturating_add(pixels.saturating_mul(kept as u64)))
        .map_err(|e| format!("the PNG texture's header claims {w} × {h} pixels, which {e}"))?;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("cannot read PNG texture: {e}"))?;
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => {
            return Err("unsupported PNG format: palette image was not expanded".into())
        }
    };
    let bytes_per_sample = match info.bit_depth {
        png::BitDepth::Eight => 1,
        png::BitDepth::Sixteen => 2,
        d => return Err(format!("unsupported PNG bit depth {d:?} after expansion")),
    };
    let (w, h) = (info.width as usize, info.height as usize);
    let row_bytes = w * channels * bytes_per_sample;
    if info.line_size < row_bytes || buf.len() < info.line_size * h {
        return Err("PNG texture data is shorter than its size".into());
    }
    let decode = |v: f32| if raw { v } else { srgb_to_linear(v) };
    let rows = (0..h).map(|y| &buf[y * info.line_size..y * info.line_size + row_bytes]);
    if bytes_per_sample == 1 {
        // Grey replicated to RGB; alpha dropped.
        let rgb = rows
            .flat_map(|row| row.chunks_exact(channels))
            .map(|p| {
                if channels < 3 {
                    [p[0]; 3]
                } else {
                    [p[0], p[1], p[2]]
                }
            })
            .collect();
        let table = std::array::from_fn(|i| decode(i as f32 / 255.0));
        return Bitmap::from_bytes(info.width, info.height, rgb, table);
    }
    let sample =
        |p: &[u8], c: usize| decode(u16::from_be_bytes([p[2 * c], p[2 * c + 1]]) as f32 / 65535.0);
    let pixels = rows
        .flat_map(|row| row.chunks_exact(2 * channels))
        .map(|p| {
            if channels < 3 {
                Color::splat(sample(p, 0))
            } else {
                Color::new(sample(p, 0), sample(p, 1), sample(p, 2))
            }
        })
        .collect();
    Bitmap::from_pixels(info.width, info.height, pixels)
}

/// The mean of a colour's channels: Mitsuba's `eval_1` and `mean()` of a constant colour.
#[inline]
fn channel_mean(c: Color) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// A bitmap and how it is looked up; the image data is shared.
#[derive(Clone, Debug, PartialEq)]
pub struct BitmapTexture {
    pub bitmap: Arc<Bitmap>,
    pub filter: FilterType,
    pub wrap: WrapMode,
    pub to_uv: UvTransform,
}

impl BitmapTexture {
    /// Bilinear, repeating, identity `to_uv`: Mitsuba's defaults.
    pub fn new(bitmap: Arc<Bitmap>) -> Self {
        BitmapTexture {
            bitmap,
            filter: FilterType::default(),
            wrap: WrapMode::default(),
            to_uv: UvTransform::IDENTITY,
        }
    }
}

/// A color that varies over a surface's texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Constant(Color),
    Bitmap(BitmapTexture),
    /// Mitsuba's `checkerboard`: cells of half a unit in uv (after `to_uv`); `color0` where
    /// the fractional parts of u and v are both above ½ or both at most ½, else `color1`.
    Checkerboard {
        color0: Color,
        color1: Color,
        to_uv: UvTransform,
    },
}

impl Texture {
    /// Mitsuba's default checkerboard: `color0` = 0.4, `color1` = 0.2.
    pub fn default_checkerboard() -> Texture {
        Texture::Checkerboard {
            color0: Color::splat(0.4),
            color1: Color::splat(0.2),
            to_uv: UvTransform::IDENTITY,
        }
    }

    /// The texture's value at texture coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> Color {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.bitmap.lookup(b.to_uv.apply(uv), b.filter, b.wrap),
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                // checkerboard.cpp, eval()/eval_3(): mask = uv − floor(uv) > .5;
                // color0 where mask.x == mask.y. (Its eval_1 uses the opposite cells, a
                // legacy quirk of the monochrome path that is not followed here.)
                let p = to_uv.apply(uv);
                let m = (p - p.floor()).cmpgt(Vec2::splat(0.5));
                if m.x == m.y {
                    *color0
                } else {
                    *color1
                }
            }
        }
    }

    /// The texture's value at `uv` where a float is read (roughness, a blend weight), as
    /// Mitsuba's `eval_1`: a bitmap's luminance (its value, if grey), a constant's channel
    /// mean, and for the checkerboard the float of `color0` where the cells of
    /// [`Texture::eval`] hold `color1` and the reverse. (checkerboard.cpp's `eval_1` tests
    /// `mask.x != mask.y` for `color0` where `eval` tests `==`; followed here so that a
    /// checkerboard weight or roughness renders as in Mitsuba.)
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        match self {
            Texture::Constant(c) => channel_mean(*c),
            Texture::Bitmap(b) => {
                b.bitmap
                    .float_of(b.bitmap.lookup(b.to_uv.apply(uv), b.filter, b.wrap))
            }
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let p = to_uv.apply(uv);
                let m = (p - p.floor()).cmpgt(Vec2::splat(0.5));
                channel_mean(if m.x != m.y { *color0 } else { *color1 })
            }
        }
    }

    /// The average of [`Texture::eval_1`] over the texture (Mitsuba's `mean()`): a bitmap's
    /// mean luminance, a constant's channel mean, the checkerboard's two colours averaged.
    pub fn mean_1(&self) -> f32 {
        match self {
            Texture::Constant(c) => channel_mean(*c),
            Texture::Bitmap(b) => b.bitmap.float_of(b.bitmap.mean()),
            Texture::Checkerboard { color0, color1, .. } => {
                0.5 * (channel_mean(*color0) + channel_mean(*color1))
            }
        }
    }

    /// The average over the texture (per channel): the pixel mean for bitmaps (Mitsuba's
    /// `mean()` is the luminance of this), the mean of the two colors for the checkerboard.
    pub fn mean(&self) -> Color {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.bitmap.mean(),
            Texture::Checkerboard { color0, color1, .. } => 0.5 * (*color0 + *color1),
        }
    }

    /// The largest value of any channel the texture takes anywhere.
    pub fn max(&self) -> f32 {
        match self {
            Texture::Constant(c) => c.max_element(),
            Texture::Bitmap(b) => b.bitmap.max(),
            Texture::Checkerboard { color0, color1, .. } => {
                color0.max_element().max(color1.max_element())
            }
        }
    }

    /// True if the texture is the same everywhere.
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant(_))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn close(a: Color, b: Color, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    fn temp_file(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("mcrt-texture-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// A bitmap texture over the given pixels.
    fn tex(w: u32, h: u32, px: &[Color], filter: FilterType, wrap: WrapMode) -> Texture {
        Texture::Bitmap(BitmapTexture {
            bitmap: Arc::new(Bitmap::from_pixels(w, h, px.to_vec()).unwrap()),
            filter,
            wrap,
            to_uv: UvTransform::IDENTITY,
        })
    }

    fn gray(v: f32) -> Color {
        Color::splat(v)
    }

    #[test]
    fn srgb_decode_values() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert_eq!(srgb_to_linear(1.0), 1.0);
        assert_eq!(srgb_to_linear(0.04045), 0.04045 / 12.92);
        // Values from the exact formula, in f64.
        let exact = |v: f64| ((v + 0.055) / 1.055).powf(2.4);
        for v in [0.05f32, 0.2, 0.5, 128.0 / 255.0, 0.9] {
            let e = exact(v as f64) as f32;
            assert!((srgb_to_linear(v) - e).abs() <= 2e-7, "{v}");
        }
        assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
        assert!((srgb_to_linear(128.0 / 255.0) - 0.215_860_5).abs() < 1e-6);
        // Continuous at the junction.
        let below = 0.04045f32 / 12.92;
        let above = ((0.04045f64 + 0.055) / 1.055).powf(2.4) as f32;
        assert!((below - above).abs() < 1e-7);
    }

    #[test]
    fn bilinear_at_pixel_centres_and_between() {
        let px = [
            gray(0.0),
            gray(1.0),
            gray(2.0),
            gray(3.0),
            gray(4.0),
            gray(5.0),
        ];
        let (w, h) = (3u32, 2u32);
        let t = tex(w, h, &px, FilterType::Bilinear, WrapMode::Clamp);
        for y in 0..h {
            for x in 0..w {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                assert!(
                    close(t.eval(uv), px[(y * w + x) as usize], 1e-5),
                    "({x}, {y})"
                );
            }
        }
        // Halfway between the centres of pixels (0,0) and (1,0): u = 1/3, v = 1/4.
        assert!(close(t.eval(Vec2::new(1.0 / 3.0, 0.25)), gray(0.5), 1e-6));
        // The middle of four centres (0,0), (1,0), (0,1), (1,1).
        assert!(close(t.eval(Vec2::new(1.0 / 3.0, 0.5)), gray(2.0), 1e-6));
        // A quarter of the way from centre (1,0) to centre (2,0), and down to row 1.
        let uv = Vec2::new((1.5 + 0.25) / 3.0, (0.5 + 0.75) / 2.0);
        let expect = (1.0 * 0.75 + 2.0 * 0.25) * 0.25 + (4.0 * 0.75 + 5.0 * 0.25) * 0.75;
        assert!(close(t.eval(uv), gray(expect), 1e-5));
        // Clamp: the half pixel beyond the outer centres is flat.
        assert_eq!(t.eval(Vec2::new(0.0, 0.0)), gray(0.0));
        assert_eq!(t.eval(Vec2::new(1.0, 1.0)), gray(5.0));
    }

    #[test]
    fn bilinear_wraps_across_the_edge() {
        let px = [gray(0.0), gray(1.0), gray(2.0), gray(3.0)];
        // At uv = (0, 0) the four neighbours are the pixel corners (−1|0) × (−1|0).
        let rep = tex(2, 2, &px, FilterType::Bilinear, WrapMode::Repeat);
        assert!(close(rep.eval(Vec2::ZERO), gray(1.5), 1e-6));
        // On the left edge at row 0's centre: halfway between x = −1 (→ 1) and x = 0.
        assert!(close(rep.eval(Vec2::new(0.0, 0.25)), gray(0.5), 1e-6));
        let mir = tex(2, 2, &px, FilterType::Bilinear, WrapMode::Mirror);
        // Mirror: x = −1 → 0, so the edge is flat.
        assert!(close(mir.eval(Vec2::new(0.0, 0.25)), gray(0.0), 1e-6));
        assert!(close(mir.eval(Vec2::new(1.0, 0.75)), gray(3.0), 1e-6));
    }

    #[test]
    fn wrap_modes_nearest() {
        // One row of 4 pixels with values 0..3 (two rows, the second +10).
        let px: Vec<Color> = (0..8)
            .map(|i| gray((i % 4) as f32 + 10.0 * (i / 4) as f32))
            .collect();
        let at = |wrap: WrapMode, u: f32| {
            tex(4, 2, &px, FilterType::Nearest, wrap)
                .eval(Vec2::new(u, 0.25))
                .x
        };
        use WrapMode::*;
        // (u, repeat, mirror, clamp)
        let cases = [
            (0.1, 0.0, 0.0, 0.0),
            (0.99, 3.0, 3.0, 3.0),
            (-0.1, 3.0, 0.0, 0.0), // pixel −1
            (1.1, 0.0, 3.0, 3.0),  // pixel 4
            (1.9, 3.0, 0.0, 3.0),  // pixel 7
            (-0.9, 0.0, 3.0, 0.0), // pixel −4
            (-1.1, 3.0, 3.0, 0.0), // pixel −5
            (2.3, 1.0, 1.0, 3.0),  // pixel 9
            (-2.3, 2.0, 1.0, 0.0), // pixel −10
            (1.0, 0.0, 3.0, 3.0),  // exactly the right edge: pixel 4
            (0.0, 0.0, 0.0, 0.0),
        ];
        for (u, r, m, c) in cases {
            assert_eq!(at(Repeat, u), r, "repeat u = {u}");
            assert_eq!(at(Mirror, u), m, "mirror u = {u}");
            assert_eq!(at(Clamp, u), c, "clamp u = {u}");
        }
        // v too: row 1 below, row 0 above.
        let t = tex(4, 2, &px, FilterType::Nearest, Repeat);
        assert_eq!(t.eval(Vec2::new(0.1, 0.75)).x, 10.0);
        assert_eq!(t.eval(Vec2::new(0.1, -0.25)).x, 10.0);
        assert_eq!(t.eval(Vec2::new(0.1, 1.25)).x, 0.0);
    }

    #[test]
    fn no_panic_on_extreme_uvs() {
        let px = [gray(0.0), gray(1.0), gray(2.0), gray(3.0)];
        for filter in [FilterType::Nearest, FilterType::Bilinear] {
            for wrap in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
                let t = tex(2, 2, &px, filter, wrap);
                for u in [f32::MAX, f32::MIN, 1e30, -1e30, f32::INFINITY, f32::NAN] {
                    let _ = t.eval(Vec2::new(u, u));
                    let _ = t.eval(Vec2::new(0.3, u));
                }
            }
        }
    }

    #[test]
    fn v_is_not_flipped_row_zero_is_at_v_zero() {
        let red = Color::new(1.0, 0.0, 0.0);
        let blue = Color::new(0.0, 0.0, 1.0);
        // Row 0 (the top row of the file) red, row 1 blue.
        let t = tex(1, 2, &[red, blue], FilterType::Nearest, WrapMode::Repeat);
        assert_eq!(t.eval(Vec2::new(0.5, 0.1)), red);
        assert_eq!(t.eval(Vec2::new(0.5, 0.9)), blue);
        let t = tex(1, 2, &[red, blue], FilterType::Bilinear, WrapMode::Clamp);
        assert_eq!(t.eval(Vec2::new(0.5, 0.25)), red);
        assert_eq!(t.eval(Vec2::new(0.5, 0.75)), blue);
    }

    #[test]
    fn to_uv_transform() {
        let px: Vec<Color> = (0..4).map(|i| gray(i as f32)).collect();
        let mut t = BitmapTexture::new(Arc::new(Bitmap::from_pixels(4, 1, px).unwrap()));
        t.filter = FilterType::Nearest;
        // Scale by 2: u = 0.3 → 0.6 → pixel 2.
        t.to_uv = UvTransform::scale(Vec2::splat(2.0));
        assert_eq!(Texture::Bitmap(t.clone()).eval(Vec2::new(0.3, 0.5)).x, 2.0);
        // Then translate by 0.25: scale first, then translate (Mitsuba: translate ∘ scale
        // for <scale/><translate/>).
        t.to_uv = UvTransform::translate(Vec2::new(0.25, 0.0))
            .after(UvTransform::scale(Vec2::splat(2.0)));
        assert_eq!(Texture::Bitmap(t.clone()).eval(Vec2::new(0.3, 0.5)).x, 3.0);
        // The same from a 4×4 matrix with z entries, and from a 3×3 one.
        let m4 = Mat4::from_cols_array_2d(&[
            [2.0, 0.0, 7.0, 0.0],
            [0.0, 2.0, 7.0, 0.0],
            [7.0, 7.0, 7.0, 0.0],
            [0.25, 0.0, 7.0, 1.0],
        ]);
        assert_eq!(UvTransform::from_mat4(m4), t.to_uv);
        let m3 = Mat3::from_cols_array_2d(&[[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.25, 0.0, 1.0]]);
        assert_eq!(UvTransform::from_mat3(m3), t.to_uv);
        assert_eq!(t.to_uv.apply(Vec2::new(1.0, 1.0)), Vec2::new(2.25, 2.0));
    }

    #[test]
    fn checkerboard_cells() {
        let c0 = Color::new(1.0, 0.0, 0.0);
        let c1 = Color::new(0.0, 1.0, 0.0);
        let t = Texture::Checkerboard {
            color0: c0,
            color1: c1,
            to_uv: UvTransform::IDENTITY,
        };
        let at = |u: f32, v: f32| t.eval(Vec2::new(u, v));
        assert_eq!(at(0.25, 0.25), c0);
        assert_eq!(at(0.75, 0.25), c1);
        assert_eq!(at(0.25, 0.75), c1);
        assert_eq!(at(0.75, 0.75), c0);
        // ½ itself belongs to the lower half (strict >).
        assert_eq!(at(0.5, 0.25), c0);
        assert_eq!(at(0.5, 0.75), c1);
        // Periodic, negative coordinates by their fractional part.
        assert_eq!(at(1.25, 2.25), c0);
        assert_eq!(at(-0.25, 0.25), c1); // frac = 0.75
        assert_eq!(at(-0.25, -0.25), c0);
        // to_uv scales the pattern.
        let t = Texture::Checkerboard {
            color0: c0,
            color1: c1,
            to_uv: UvTransform::scale(Vec2::splat(2.0)),
        };
        assert_eq!(t.eval(Vec2::new(0.3, 0.1)), c1); // (0.6, 0.2)
        assert_eq!(t.eval(Vec2::new(0.3, 0.3)), c0); // (0.6, 0.6)
        assert_eq!(t.mean(), Color::new(0.5, 0.5, 0.0));
        let d = Texture::default_checkerboard();
        assert_eq!(d.eval(Vec2::splat(0.25)), gray(0.4));
        assert_eq!(d.eval(Vec2::new(0.75, 0.25)), gray(0.2));
        assert!(close(d.mean(), gray(0.3), 1e-7));
    }

    #[test]
    fn constant_and_means() {
        let c = Color::new(0.1, 0.2, 0.3);
        let t = Texture::Constant(c);
        assert_eq!(t.eval(Vec2::new(5.0, -3.0)), c);
        assert_eq!(t.mean(), c);
        assert!(t.is_constant());
        let px = [gray(0.0), Color::new(1.0, 2.0, 3.0)];
        let t = tex(2, 1, &px, FilterType::Bilinear, WrapMode::Repeat);
        assert_eq!(t.mean(), Color::new(0.5, 1.0, 1.5));
        assert!(!t.is_constant());
    }

    /// Floats from textures (Mitsuba's `eval_1` and `mean()`): a grey bitmap's value, an RGB
    /// one's luminance, a constant's channel mean, and the checkerboard's cells swapped.
    #[test]
    fn float_lookups_and_means() {
        let px = [gray(0.25), gray(0.75)];
        let t = tex(2, 1, &px, FilterType::Nearest, WrapMode::Clamp);
        assert_eq!(t.eval_1(Vec2::new(0.2, 0.5)), 0.25);
        assert_eq!(t.eval_1(Vec2::new(0.8, 0.5)), 0.75);
        assert_eq!(t.mean_1(), 0.5);
        let red = Color::new(1.0, 0.0, 0.0);
        let px = [red, Color::new(0.2, 0.4, 0.6)];
        let t = tex(2, 1, &px, FilterType::Nearest, WrapMode::Repeat);
        assert_eq!(t.eval_1(Vec2::new(0.2, 0.5)), 0.212_671);
        let y = 0.2 * 0.212_671 + 0.4 * 0.715_160 + 0.6 * 0.072_169;
        assert!((t.eval_1(Vec2::new(0.8, 0.5)) - y).abs() < 1e-7);
        assert!((t.mean_1() - 0.5 * (0.212_671 + y)).abs() < 1e-7);
        // Bilinear: the luminance of the interpolated colour (linear, so either order).
        let t = tex(2, 1, &px, FilterType::Bilinear, WrapMode::Clamp);
        assert!((t.eval_1(Vec2::new(0.5, 0.5)) - 0.5 * (0.212_671 + y)).abs() < 1e-6);
        let c = Texture::Constant(Color::new(0.1, 0.2, 0.6));
        assert!((c.eval_1(Vec2::ZERO) - 0.3).abs() < 1e-7 && c.mean_1() == c.eval_1(Vec2::ZERO));
        let k = Texture::Checkerboard {
            color0: gray(0.9),
            color1: Color::new(0.1, 0.2, 0.3),
            to_uv: UvTransform::IDENTITY,
        };
        // eval gives color0 at (¼, ¼); eval_1 gives color1's mean there.
        assert_eq!(k.eval(Vec2::splat(0.25)), gray(0.9));
        assert!((k.eval_1(Vec2::splat(0.25)) - 0.2).abs() < 1e-7);
        assert!((k.eval_1(Vec2::new(0.75, 0.25)) - 0.9).abs() < 1e-7);
        assert!((k.mean_1() - 0.55).abs() < 1e-7);
    }

    #[test]
    fn from_pixels_rejects_bad_sizes() {
        assert!(Bitmap::from_pixels(0, 1, vec![]).is_err());
        assert!(Bitmap::from_pixels(2, 2, vec![Color::ZERO; 3]).is_err());
    }

    // -----------------------------------------------------------------------------------------
    // Files
    // -----------------------------------------------------------------------------------------

    fn write_png(
        name: &str,
        w: u32,
        h: u32,
        color: png::ColorType,
        depth: png::BitDepth,
        data: &[u8],
        palette: Option<(&[u8], Option<&[u8]>)>,
    ) -> PathBuf {
        let p = temp_file(name);
        let f = std::fs::File::create(&p).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w, h);
        enc.set_color(color);
        enc.set_depth(depth);
        if let Some((plte, trns)) = palette {
            enc.set_palette(plte.to_vec());
            if let Some(t) = trns {
                enc.set_trns(t.to_vec());
            }
        }
        let mut wr = enc.write_header().unwrap();
        wr.write_image_data(data).unwrap();
        wr.finish().unwrap();
        p
    }

    fn s8(v: u8) -> f32 {
        srgb_to_linear(v as f32 / 255.0)
    }

    #[test]
    fn png_rgb8_round_trip() {
        use png::{BitDepth, ColorType};
        // 2×2: top row (255,0,0) (0,128,0); bottom row (0,0,64) (10,20,30).
        let data = [255, 0, 0, 0, 128, 0, 0, 0, 64, 10, 20, 30];
        let p = write_png(
            "rgb8.png",
            2,
            2,
            ColorType::Rgb,
            BitDepth::Eight,
            &data,
            None,
        );
        let b = Bitmap::load(&p, false).unwrap();
        assert_eq!((b.width, b.height), (2, 2));
        assert_eq!(b.pixel(0), Color::new(1.0, 0.0, 0.0));
        assert_eq!(b.pixel(1), Color::new(0.0, s8(128), 0.0));
        assert_eq!(b.pixel(2), Color::new(0.0, 0.0, s8(64)));
        assert_eq!(b.pixel(3), Color::new(s8(10), s8(20), s8(30)));
        let raw = Bitmap::load(&p, true).unwrap();
        assert_eq!(raw.pixel(1), Color::new(0.0, 128.0 / 255.0, 0.0));
        assert_eq!(raw.pixel(3), Color::new(10.0, 20.0, 30.0) / 255.0);
        // Looked up through a texture: the top-left pixel at small v.
        let t = Texture::Bitmap(BitmapTexture::new(Arc::new(b)));
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Color::new(1.0, 0.0, 0.0));
        assert_eq!(
            t.eval(Vec2::new(0.75, 0.75)),
            Color::new(s8(10), s8(20), s8(30))
        );
    }

    /// An 8-bit image keeps 3 bytes a texel, and reads as the same image stored as floats:
    /// every pixel, the mean and maximum, and lookups (both filters, every wrap), bit for bit.
    #[test]
    fn eight_bit_images_keep_their_bytes() {
        use png::{BitDepth, ColorType};
        let data: Vec<u8> = (0..18).map(|i| (i * 47 % 256) as u8).collect();
        let p = write_png(
            "rgb8-3x2.png",
            3,
            2,
            ColorType::Rgb,
            BitDepth::Eight,
            &data,
            None,
        );
        for raw in [false, true] {
            let b = Bitmap::load(&p, raw).unwrap();
            assert_eq!(b.memory_bytes(), 6 * 3 + 256 * 4);
            let f = Bitmap::from_pixels(3, 2, b.pixels().collect()).unwrap();
            assert_eq!(f.memory_bytes(), 6 * 12);
            for (i, c) in b.pixels().enumerate() {
                let want = |k: usize| {
                    let v = data[3 * i + k] as f32 / 255.0;
                    if raw {
                        v
                    } else {
                        srgb_to_linear(v)
                    }
                };
                assert_eq!(c, Color::new(want(0), want(1), want(2)));
            }
            assert_eq!((b.mean(), b.max()), (f.mean(), f.max()));
            for filter in [FilterType::Nearest, FilterType::Bilinear] {
                for wrap in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
                    for k in 0..400 {
                        let uv =
                            Vec2::new((k % 20) as f32 * 0.17 - 1.3, (k / 20) as f32 * 0.13 - 0.9);
                        let (x, y) = (b.lookup(uv, filter, wrap), f.lookup(uv, filter, wrap));
                        assert_eq!(
                            x.to_array().map(f32::to_bits),
                            y.to_array().map(f32::to_bits)
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn png_other_formats() {
        use png::{BitDepth, ColorType};
        // 16-bit gray, 1×2.
        let data = [0xff, 0xff, 0x80, 0x00];
        let p = write_png(
            "g16.png",
            1,
            2,
            ColorType::Grayscale,
            BitDepth::Sixteen,
            &data,
            None,
        );
        let b = Bitmap::load(&p, false).unwrap();
        assert_eq!(b.pixel(0), gray(1.0));
        assert_eq!(b.pixel(1), gray(srgb_to_linear(32768.0 / 65535.0)));
        let b = Bitmap::load(&p, true).unwrap();
        assert_eq!(b.pixel(1), gray(32768.0 / 65535.0));
        // 8-bit gray + alpha: alpha dropped.
        let data = [100, 7, 200, 255];
        let p = write_png(
            "ga8.png",
            2,
            1,
            ColorType::GrayscaleAlpha,
            BitDepth::Eight,
            &data,
            None,
        );
        let b = Bitmap::load(&p, false).unwrap();
        assert_eq!(
            b.pixels().collect::<Vec<_>>(),
            [gray(s8(100)), gray(s8(200))]
        );
        // 16-bit RGBA.
        let data = [0, 0, 0x80, 0x00, 0xff, 0xff, 0x12, 0x34];
        let p = write_png(
            "rgba16.png",
            1,
            1,
            ColorType::Rgba,
            BitDepth::Sixteen,
            &data,
            None,
        );
        let b = Bitmap::load(&p, true).unwrap();
        assert_eq!(b.pixel(0), Color::new(0.0, 32768.0 / 65535.0, 1.0));
        // 8-bit RGBA.
        let data = [1, 2, 3, 4];
        let p = write_png(
            "rgba8.png",
            1,
            1,
            ColorType::Rgba,
            BitDepth::Eight,
            &data,
            None,
        );
        let b = Bitmap::load(&p, false).unwrap();
        assert_eq!(b.pixel(0), Color::new(s8(1), s8(2), s8(3)));
        // Palette (2 bits per index) with transparency.
        let plte = [255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128];
        let trns = [255, 0];
        // Indices 3, 2, 1, 0 packed into one byte.
        let data = [0b11_10_01_00];
        let p = write_png(
            "pal.png",
            4,
            1,
            ColorType::Indexed,
            BitDepth::Two,
            &data,
            Some((&plte, Some(&trns))),
        );
        let b = Bitmap::load(&p, true).unwrap();
        let c = |r: u8, g: u8, bl: u8| Color::new(r as f32, g as f32, bl as f32) / 255.0;
        assert_eq!(
            b.pixels().collect::<Vec<_>>(),
            [c(128, 128, 128), c(0, 0, 255), c(0, 255, 0), c(255, 0, 0)]
        );
        // 1-bit gray.
        let data = [0b1010_0000];
        let p = write_png(
            "g1.png",
            3,
            1,
            ColorType::Grayscale,
            BitDepth::One,
            &data,
            None,
        );
        let b = Bitmap::load(&p, false).unwrap();
        assert_eq!(
            b.pixels().collect::<Vec<_>>(),
            [gray(1.0), gray(0.0), gray(1.0)]
        );
    }

    #[test]
    fn exr_round_trip_is_linear() {
        let mut img = crate::image::Image::new(2, 1);
        img.pixels = vec![Color::new(0.5, 2.0, 0.25), Color::new(0.0, 0.1, 10.0)];
        let p = temp_file("tex.exr");
        crate::image::write_image(&p, &img, &Default::default()).unwrap();
        for raw in [false, true] {
            let b = Bitmap::load(&p, raw).unwrap();
            assert_eq!(b.pixels().collect::<Vec<_>>(), img.pixels);
        }
    }

    #[test]
    fn load_errors() {
        let e = Bitmap::load(&temp_file("missing.png"), false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("missing.png") && e.contains("cannot read texture"),
            "{e}"
        );
        let p = temp_file("text.png");
        std::fs::write(&p, "hello, not an image").unwrap();
        let e = Bitmap::load(&p, false).unwrap_err().to_string();
        assert!(
            e.contains("text.png") && e.contains("unsupported image format"),
            "{e}"
        );
        let p = temp_file("tiny.png");
        std::fs::write(&p, "ab").unwrap();
        let e = Bitmap::load(&p, false).unwrap_err().to_string();
        assert!(e.contains("too short"), "{e}");
        // A truncated PNG.
        let data = [7u8; 64 * 64 * 3];
        let good = write_png(
            "full.png",
            64,
            64,
            png::ColorType::Rgb,
            png::BitDepth::Eight,
            &data,
            None,
        );
        let bytes = std::fs::read(&good).unwrap();
        let p = temp_file("cut.png");
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        let e = Bitmap::load(&p, false).unwrap_err().to_string();
        assert!(
            e.contains("cut.png") && e.contains("cannot read PNG"),
            "{e}"
        );
        // A PNG header claiming a huge image.
        let mut huge = bytes[..33].to_vec();
        huge[16..20].copy_from_slice(&100_000u32.to_be_bytes());
        huge[20..24].copy_from_slice(&100_000u32.to_be_bytes());
        // Fix the IHDR CRC so the decoder gets as far as the size check.
        let crc = crc32(&huge[12..29]);
        huge[29..33].copy_from_slice(&crc.to_be_bytes());
        let p = temp_file("huge.png");
        std::fs::write(&p, &huge).unwrap();
        let e = Bitmap::load(&p, false).unwrap_err().to_string();
        assert!(e.contains("huge.png"), "{e}");
        // An EXR magic with garbage after it.
        let p = temp_file("bad.exr");
        std::fs::write(&p, [0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0, 1, 2, 3]).unwrap();
        let e = Bitmap::load(&p, false).unwrap_err().to_string();
        assert!(e.contains("bad.exr") && e.contains("OpenEXR"), "{e}");
    }

    /// CRC-32 (IEEE), as PNG chunks use.
    fn crc32(data: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in data {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
}
