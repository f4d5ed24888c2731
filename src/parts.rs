//! Rendering on many machines: `mcrt render --pass K/N` renders the K-th of N disjoint shares
//! of every pixel's samples and writes a *sums file*; `mcrt merge` adds the sums files up.
//!
//! # Shares
//!
//! Pass K of N (1-based) renders samples [⌊(K−1)·spp/N⌋, ⌊K·spp/N⌋) of every pixel: contiguous
//! ranges that cover [0, spp) once, as even as possible (sizes differ by at most one, the
//! larger ones last when N does not divide spp). Each sample has its own random stream (it
//! depends on the seed, the pixel and the sample index only), so a pass renders exactly the
//! samples a single render would.
//!
//! # Bit-exact merging
//!
//! The film's sums are fixed-point integers ([`crate::film`]): every sample is rounded once to
//! the fixed-point grid, then sums are integer additions, which do not depend on grouping or
//! order. A sums file stores its pass's integers exactly (each i128 as four u32 channels), so
//! the merge of all N passes has the very sums, counts and therefore image bits of one render
//! of all spp samples. (Floating-point sums could not promise that: a single render adds the
//! samples one by one, a merge adds per-pass subtotals, and f64 addition is not associative.)
//!
//! # Sums files
//!
//! An OpenEXR file (ZIP-compressed scanlines), one layer `mcrt-sums` of the film's size with
//! channels
//! - `R`, `G`, `B` (f32): the pass's own mean image, for viewing only;
//! - `sum.{R,G,B}.w{0..3}` (u32): Σ L of the pass, an i128 in units of 2^-64 split into 32-bit
//!   words, least significant first (two's complement);
//! - `sumsq.{R,G,B}.w{0..3}` (u32): Σ L², an i128 in units of 2^-48;
//! - `count` (u32): samples that reached the pixel (NaN and infinite samples are dropped);
//! - `splat.{R,G,B}.w{0..3}` (u32), only where the film has splats ([`Film::splat`]): their
//!   Σ, as `sum`;
//!
//! and a text attribute `mcrtSums` of `key=value` lines ([`PartMeta`]): mcrt's version, the
//! scene file and a hash of its bytes, the settings, the seed, spp, the image size and crop,
//! and which pass of how many it holds, so that `merge` can check that the parts belong
//! together and cover every pass once; then `splat_paths=N` where the film traced paths that
//! splat, and `checksum=` over every integer channel (and the path count), so that a file
//! changed after it was written is refused. A merged film written with `--keep-sums` is the sums
//! file of pass 1/1.

use crate::film::Film;
use crate::image::{write_atomic, ImageError};
use crate::render::{render_samples, RenderError, RenderSettings, RenderStats};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// Format tag of the sums files this version reads and writes (2: with a checksum).
pub const FORMAT: &str = "mcrt-sums 2";
/// The most passes a render can be split into (`--pass K/N`, N ≤ this): far more machines
/// than a render farm has, and a bound on what a sums file's `pass` may claim.
pub const MAX_PASSES: u32 = 1 << 16;
/// Name of the EXR attribute holding the metadata.
pub const ATTRIBUTE: &str = "mcrtSums";
const LAYER: &str = "mcrt-sums";

/// Pass K of N, 1 ≤ K ≤ N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pass {
    pub k: u32,
    pub n: u32,
}

impl std::str::FromStr for Pass {
    type Err = String;
    fn from_str(s: &str) -> Result<Pass, String> {
        let bad = || {
            format!(
                "expected K/N with 1 ≤ K ≤ N (e.g. 3/8), got '{}'",
                crate::input::shorten(s)
            )
        };
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k: u32 = k.trim().parse().map_err(|_| bad())?;
        let n: u32 = n.trim().parse().map_err(|_| bad())?;
        if k == 0 || k > n {
            return Err(bad());
        }
        if n > MAX_PASSES {
            return Err(format!(
                "at most {MAX_PASSES} passes, got '{}'",
                crate::input::shorten(s)
            ));
        }
        Ok(Pass { k, n })
    }
}

impl std::fmt::Display for Pass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

impl Pass {
    /// The samples of this pass: (first, count) of [0, spp).
    pub fn share(&self, spp: u32) -> (u32, u32) {
        let at = |k: u32| (k as u64 * spp as u64 / self.n as u64) as u32;
        let (a, b) = (at(self.k - 1), at(self.k));
        (a, b - a)
    }
}

/// Renders pass `pass` of the image into a fresh film.
pub fn render_pass(
    scene: &Scene,
    s: &RenderSettings,
    pass: Pass,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Film, RenderStats), RenderError> {
    let (_, _, w, h) = s.window();
    let mut film = Film::new(w, h);
    let (first, count) = pass.share(s.spp);
    let stats = render_samples(scene, s, &mut film, first, count, progress)?;
    Ok((film, stats))
}

/// 64-bit FNV-1a of a file's bytes: identifies the scene a part was rendered from.
pub fn hash_bytes(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// What a sums file holds, and what must agree between the parts of one render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartMeta {
    /// The mcrt version that rendered it.
    pub version: String,
    /// The scene file as given on the command line (not compared: machines may mount it at
    /// different paths).
    pub scene: String,
    /// [`hash_bytes`] of the scene file, as 16 hex digits. (Files the scene includes or
    /// references are not hashed.)
    pub scene_hash: String,
    /// Everything else that shapes the samples: camera, sampler, integrator parameters,
    /// -D defines, lenient.
    pub settings: String,
    pub width: u32,
    pub height: u32,
    pub crop: Option<[u32; 4]>,
    pub seed: u64,
    pub spp: u32,
    pub pass: Pass,
    /// The samples it holds: [first, first + count).
    pub first: u32,
    pub count: u32,
}

impl PartMeta {
    /// The metadata of pass `pass` of a render with settings `s` of the scene file whose
    /// bytes are `scene_bytes`; `extra` adds load options that change the scene (defines).
    pub fn new(
        scene: &Path,
        scene_bytes: &[u8],
        extra: &str,
        s: &RenderSettings,
        pass: Pass,
    ) -> PartMeta {
        let (first, count) = pass.share(s.spp);
        PartMeta {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.display().to_string(),
            scene_hash: format!("{:016x}", hash_bytes(scene_bytes)),
            settings: format!(
                "camera={:?} sampler={:?} {:?} {extra}",
                s.camera, s.sampler, s.params
            ),
            width: s.width,
            height: s.height,
            crop: s.crop,
            seed: s.seed,
            spp: s.spp,
            pass,
            first,
            count,
        }
    }

    /// The film's size: the crop window's, else the image's.
    pub fn film_size(&self) -> (u32, u32) {
        match self.crop {
            Some([_, _, w, h]) => (w, h),
            None => (self.width, self.height),
        }
    }

    fn crop_text(&self) -> String {
        match self.crop {
            Some([x, y, w, h]) => format!("{x},{y},{w},{h}"),
            None => "none".into(),
        }
    }

    pub fn to_text(&self) -> String {
        format!(
            "format={FORMAT}\nversion={}\nscene={}\nscene_hash={}\nsettings={}\nwidth={}\nheight={}\ncrop={}\nseed={}\nspp={}\npass={}\nsamples={}..{}\n",
            self.version,
            self.scene.replace('\n', " "),
            self.scene_hash,
            self.settings.replace('\n', " "),
            self.width,
            self.height,
            self.crop_text(),
            self.seed,
            self.spp,
            self.pass,
            self.first,
            self.first + self.count,
        )
    }

    pub fn from_text(text: &str) -> Result<PartMeta, String> {
        let get = |key: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(key)?.strip_prefix('='))
                .ok_or_else(|| format!("the metadata lacks '{key}'"))
        };
        let num = |key: &str| -> Result<u64, String> {
            get(key)?
                .parse()
                .map_err(|_| format!("bad '{key}' in the metadata"))
        };
        let format = get("format")?;
        if format != FORMAT {
            return Err(format!(
                "sums file format '{format}', this mcrt reads '{FORMAT}'"
            ));
        }
        let crop = match get("crop")? {
            "none" => None,
            c => {
                let v: Vec<u32> = c
                    .split(',')
                    .map(|x| {
                        x.parse()
                            .map_err(|_| "bad 'crop' in the metadata".to_string())
                    })
                    .collect::<Result<_, _>>()?;
                Some(<[u32; 4]>::try_from(v).map_err(|_| "bad 'crop' in the metadata")?)
            }
        };
        let pass: Pass = get("pass")?.parse()?;
        let (first, end) = get("samples")?
            .split_once("..")
            .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)))
            .filter(|(a, b)| a <= b)
            .ok_or("bad 'samples' in the metadata")?;
        let u32_of = |key: &str| -> Result<u32, String> {
            u32::try_from(num(key)?).map_err(|_| format!("bad '{key}' in the metadata"))
        };
        Ok(PartMeta {
            version: get("version")?.to_string(),
            scene: get("scene")?.to_string(),
            scene_hash: get("scene_hash")?.to_string(),
            settings: get("settings")?.to_string(),
            width: u32_of("width")?,
            height: u32_of("height")?,
            crop,
            seed: num("seed")?,
            spp: u32_of("spp")?,
            pass,
            first,
            count: end - first,
        })
    }
}

/// A sums file in memory.
#[derive(Clone, Debug)]
pub struct Part {
    pub meta: PartMeta,
    pub film: Film,
}

#[derive(Debug, thiserror::Error)]
pub enum PartsError {
    #[error("{path}: cannot read this sums file: {message}")]
    Read { path: PathBuf, message: String },
    #[error("{0}")]
    Mismatch(String),
}

const QUANTITIES: [&str; 2] = ["sum", "sumsq"];
const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// Writes a sums file atomically (temporary file + rename).
pub fn write_part(path: &Path, part: &Part) -> Result<(), ImageError> {
    write_part_with(path, part, &[])
}

/// Writes a sums file with extra u32 channels (name, one value per pixel), atomically.
pub fn write_part_with(
    path: &Path,
    part: &Part,
    extra: &[(&str, &[u32])],
) -> Result<(), ImageError> {
    write_atomic(path, |tmp| write_part_exr(tmp, part, extra))
}

/// The names of a sums file's integer channels: the sums' words, `count`, the splats' words
/// if the film has splats, then `extra`.
fn integer_channels(extra: &[&str], splats: bool) -> Vec<String> {
    let mut names = Vec::with_capacity(QUANTITIES.len() * CHANNELS.len() * 4 + 1 + extra.len());
    let words = |names: &mut Vec<String>, qname: &str| {
        for cname in CHANNELS {
            for word in 0..4 {
                names.push(format!("{qname}.{cname}.w{word}"));
            }
        }
    };
    for qname in QUANTITIES {
        words(&mut names, qname);
    }
    names.push("count".into());
    if splats {
        words(&mut names, SPLAT);
    }
    names.extend(extra.iter().map(|s| s.to_string()));
    names
}

/// The channels' name prefix of a film's splats ([`Film::splat`]); their path count is the
/// metadata's `splat_paths`, which the checksum covers too.
const SPLAT: &str = "splat";

/// An i128 per pixel and channel as four u32 words per channel (least significant first).
fn push_words(ints: &mut Vec<Vec<u32>>, data: &[[i128; 3]]) {
    for c in 0..CHANNELS.len() {
        for word in 0..4 {
            ints.push(
                data.iter()
                    .map(|p| ((p[c] as u128) >> (32 * word)) as u32)
                    .collect(),
            );
        }
    }
}

/// [`push_words`] read back.
fn read_words<'a>(
    words: &mut impl Iterator<Item = &'a &'a [u32]>,
    data: &mut [[i128; 3]],
) -> Result<(), String> {
    for c in 0..CHANNELS.len() {
        for word in 0..4 {
            let v = words.next().ok_or("missing sums channel")?;
            for (p, &x) in data.iter_mut().zip(v.iter()) {
                p[c] = (p[c] as u128 | (x as u128) << (32 * word)) as i128;
            }
        }
    }
    Ok(())
}

/// The [`checksum`] of integer channels (name, values) and of the splats' path count.
fn checksum_of<'a>(
    channels: impl IntoIterator<Item = (&'a str, &'a [u32])>,
    splat_paths: u64,
) -> u64 {
    let paths = [splat_paths as u32, (splat_paths >> 32) as u32];
    let mut all: Vec<(&str, &[u32])> = channels.into_iter().collect();
    if splat_paths > 0 {
        all.push(("splat_paths", &paths[..]));
    }
    checksum(all)
}

/// The checksum a sums file carries (`checksum=` in its metadata) of all its integer
/// channels, taken in the order of their names (whichever of them a reader asks for, so a
/// checkpoint is also a sums file): FNV-1a (64-bit) over each name's bytes and each value as
/// one word. A file whose sums, counts or `next` were changed after it was written (a forged
/// or damaged checkpoint) no longer matches it.
pub fn checksum<'a>(channels: impl IntoIterator<Item = (&'a str, &'a [u32])>) -> u64 {
    const PRIME: u64 = 0x0100_0000_01b3;
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut sorted: Vec<(&str, &[u32])> = channels.into_iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(b.0));
    for (name, values) in sorted {
        for &b in name.as_bytes() {
            h = (h ^ b as u64).wrapping_mul(PRIME);
        }
        for &v in values {
            h = (h ^ v as u64).wrapping_mul(PRIME);
        }
    }
    h
}

fn write_part_exr(path: &Path, part: &Part, extra: &[(&str, &[u32])]) -> Result<(), String> {
    use exr::prelude::*;
    let f = &part.film;
    let (w, h) = (f.width as usize, f.height as usize);
    if part.meta.film_size() != (f.width, f.height) {
        return Err("the film does not have the size of its metadata".into());
    }
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let img = f.image();
    for (c, name) in CHANNELS.iter().enumerate() {
        let v: Vec<f32> = img.pixels.iter().map(|p| p[c]).collect();
        channels.push(AnyChannel::new(*name, FlatSamples::F32(v)));
    }
    let mut ints: Vec<Vec<u32>> = Vec::new();
    push_words(&mut ints, &f.sum);
    push_words(&mut ints, &f.sum_sq);
    ints.push(f.count.clone());
    let splats = !f.splat.is_empty();
    if splats {
        push_words(&mut ints, &f.splat);
    }
    for (name, v) in extra {
        if v.len() != w * h {
            return Err(format!("channel '{name}' does not have the film's size"));
        }
        ints.push(v.to_vec());
    }
    let extra_names: Vec<&str> = extra.iter().map(|(n, _)| *n).collect();
    let names = integer_channels(&extra_names, splats);
    let sum = checksum_of(
        names
            .iter()
            .map(|n| n.as_str())
            .zip(ints.iter().map(|v| &v[..])),
        f.splat_paths,
    );
    for (name, v) in names.iter().zip(ints) {
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::U32(v)));
    }
    let mut attrs = LayerAttributes::named(LAYER);
    let paths = match f.splat_paths {
        0 => String::new(),
        n => format!("splat_paths={n}\n"),
    };
    let text = format!("{}{paths}checksum={sum:016x}\n", part.meta.to_text());
    attrs.other.insert(
        Text::from(ATTRIBUTE),
        AttributeValue::Text(Text::from_slice_unchecked(text.as_bytes())),
    );
    let layer = Layer::new(
        (w, h),
        attrs,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    Image::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| e.to_string())
}

/// Reads a sums file written by [`write_part`] (once, through [`crate::input::read`]).
pub fn read_part(path: &Path) -> std::result::Result<Part, PartsError> {
    let bytes = crate::input::read(path).map_err(|message| PartsError::Read {
        path: path.to_path_buf(),
        message,
    })?;
    decode_sums(&bytes).map_err(|message| PartsError::Read {
        path: path.to_path_buf(),
        message,
    })
}

/// Decodes a sums file's bytes: beyond [`decode_part`]'s checks, no pixel counts more
/// samples than the pass holds.
pub fn decode_sums(bytes: &[u8]) -> std::result::Result<Part, String> {
    let part = decode_part(bytes, &[])?.0;
    if let Some(i) = part.film.count.iter().position(|&c| c > part.meta.count) {
        let w = part.film.width.max(1) as usize;
        return Err(format!(
            "pixel ({}, {}) counts {} samples, but the pass holds {}",
            i % w,
            i / w,
            part.film.count[i],
            part.meta.count
        ));
    }
    Ok(part)
}

/// Bytes a pixel of a sums file takes in memory once read: its film and its channels' copy.
fn part_bytes_per_pixel(extra: usize) -> u64 {
    // Sums, sums of squares and splats (which a film may have).
    let film = 3 * std::mem::size_of::<[i128; 3]>() + std::mem::size_of::<u32>();
    (film + 4 * extra) as u64
}

/// Reads a sums file and the extra u32 channels `extra` (each required). The file is read
/// once, its size checked against the memory budget before it is decoded, and its channels
/// against the checksum in its metadata.
pub fn read_part_with(
    path: &Path,
    extra: &[&str],
) -> std::result::Result<(Part, Vec<Vec<u32>>), PartsError> {
    let err = |message: String| PartsError::Read {
        path: path.to_path_buf(),
        message,
    };
    let bytes = crate::input::read(path).map_err(err)?;
    decode_part(&bytes, extra).map_err(err)
}

/// Decodes the bytes of a sums file (see [`read_part_with`]); Err says what is wrong.
pub fn decode_part(
    bytes: &[u8],
    extra: &[&str],
) -> std::result::Result<(Part, Vec<Vec<u32>>), String> {
    use exr::prelude::*;
    crate::image::check_exr_memory(bytes, part_bytes_per_pixel(extra.len()))?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let layer = &image.layer_data;
    let text = layer
        .attributes
        .other
        .get(ATTRIBUTE.as_bytes())
        .ok_or_else(|| {
            format!("no '{ATTRIBUTE}' attribute (not written by 'mcrt render --pass')")
        })?;
    let AttributeValue::Text(text) = text else {
        return Err(format!("the '{ATTRIBUTE}' attribute is not text"));
    };
    let text = String::from_utf8_lossy(text.bytes());
    let meta = PartMeta::from_text(&text)?;
    let (w, h) = (layer.size.width(), layer.size.height());
    if (w, h) != (meta.film_size().0 as usize, meta.film_size().1 as usize) {
        return Err(format!(
            "the layer is {w} × {h} pixels but the metadata says {} × {}",
            meta.film_size().0,
            meta.film_size().1
        ));
    }
    let channel = |name: &str| -> std::result::Result<&[u32], String> {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .ok_or_else(|| format!("no channel '{name}'"))?;
        match &ch.sample_data {
            FlatSamples::U32(v) if v.len() == w * h => Ok(v),
            _ => Err(format!("channel '{name}' is not u32")),
        }
    };
    let splats = channel(&format!("{SPLAT}.R.w0")).is_ok();
    let splat_paths: u64 = match text.lines().find_map(|l| l.strip_prefix("splat_paths=")) {
        Some(n) => n
            .parse()
            .map_err(|_| format!("bad splat_paths '{}'", crate::input::shorten(n)))?,
        None => 0,
    };
    let names = integer_channels(extra, splats);
    let ints = names
        .iter()
        .map(|n| channel(n))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let stated = text
        .lines()
        .find_map(|l| l.strip_prefix("checksum="))
        .ok_or("the metadata lacks 'checksum'")?;
    let all = layer
        .channel_data
        .list
        .iter()
        .filter_map(|c| match &c.sample_data {
            FlatSamples::U32(v) => {
                Some((std::str::from_utf8(c.name.bytes()).unwrap_or(""), &v[..]))
            }
            _ => None,
        });
    let sum = checksum_of(all, splat_paths);
    if u64::from_str_radix(stated, 16).ok() != Some(sum) {
        return Err(format!(
            "its channels do not match their checksum ({} in the metadata, {sum:016x} \
             computed): the file was changed or damaged after it was written",
            crate::input::shorten(stated)
        ));
    }
    let mut film = Film::new(w as u32, h as u32);
    let mut words = ints.iter();
    read_words(&mut words, &mut film.sum)?;
    read_words(&mut words, &mut film.sum_sq)?;
    film.count
        .copy_from_slice(words.next().ok_or("missing count channel")?);
    if splats {
        film.splat = vec![[0; 3]; film.sum.len()];
        read_words(&mut words, &mut film.splat)?;
    }
    // Paths count even when none of them splatted anything.
    film.splat_paths = splat_paths;
    let more = words.map(|v| v.to_vec()).collect();
    Ok((Part { meta, film }, more))
}

/// Merges the parts of one render: checks that they agree (scene, settings, seed, spp, size,
/// number of passes) and hold every pass exactly once, and adds their sums. The result is
/// pass 1/1: the film of a single render of all spp samples, bit for bit.
pub fn merge(parts: &[(PathBuf, Part)]) -> Result<Part, PartsError> {
    let mut m = Merger::default();
    for (p, part) in parts {
        m.add(p, part)?;
    }
    m.finish()
}

/// A merge in progress, one part at a time ([`merge`]): it holds one film and the passes
/// seen, never state sized by a part's claimed number of passes, so `mcrt merge` needs the
/// memory of two films however many parts it is given.
#[derive(Default)]
pub struct Merger {
    first: Option<(PathBuf, PartMeta)>,
    film: Option<Film>,
    seen: std::collections::BTreeMap<u32, PathBuf>,
}

impl Merger {
    /// Checks `part` (read from `p`) against the first part and the passes seen, and adds it.
    pub fn add(&mut self, p: &Path, part: &Part) -> Result<(), PartsError> {
        let (p0, m0) = self
            .first
            .get_or_insert_with(|| (p.to_path_buf(), part.meta.clone()));
        check_same_render(p0, m0, p, &part.meta)?;
        if let Some(q) = self.seen.get(&part.meta.pass.k) {
            return Err(PartsError::Mismatch(format!(
                "pass {} is given twice: {} and {}",
                part.meta.pass,
                q.display(),
                p.display()
            )));
        }
        self.seen.insert(part.meta.pass.k, p.to_path_buf());
        match &mut self.film {
            None => self.film = Some(part.film.clone()),
            Some(f) => f.add_film(&part.film),
        }
        Ok(())
    }

    /// The merged part, once every pass has been added.
    pub fn finish(self) -> Result<Part, PartsError> {
        let (Some((_, m0)), Some(film)) = (self.first, self.film) else {
            return Err(PartsError::Mismatch("no parts to merge".into()));
        };
        let n = m0.pass.n;
        let given = self.seen.len() as u32;
        if given < n {
            // The first few missing passes, found by walking the passes given.
            const SHOWN: usize = 10;
            let mut missing = Vec::new();
            let mut k = 1;
            for &g in self.seen.keys().chain(std::iter::once(&(n + 1))) {
                while k < g && missing.len() < SHOWN {
                    missing.push(format!("{k}/{n}"));
                    k += 1;
                }
                k = g + 1;
            }
            let more = (n - given) as usize - missing.len();
            return Err(PartsError::Mismatch(format!(
                "the parts do not cover all {n} passes: missing pass{} {}{} (given {given} of {n})",
                if n - given > 1 { "es" } else { "" },
                missing.join(", "),
                if more > 0 {
                    format!(" and {more} more")
                } else {
                    String::new()
                }
            )));
        }
        let pass = Pass { k: 1, n: 1 };
        let (f, c) = pass.share(m0.spp);
        let meta = PartMeta {
            pass,
            first: f,
            count: c,
            ..m0
        };
        Ok(Part { meta, film })
    }
}

/// Checks that the part `m` (file `p`) and the first part `m0` (file `p0`) are parts of one
/// render, and that `m` holds its pass's samples.
fn check_same_render(p0: &Path, m0: &PartMeta, p: &Path, m: &PartMeta) -> Result<(), PartsError> {
    let differ = |what: &str, a: String, b: String| {
        PartsError::Mismatch(format!(
            "{} and {} are not parts of the same render: {what} {} versus {}",
            p0.display(),
            p.display(),
            crate::input::shorten(&a),
            crate::input::shorten(&b)
        ))
    };
    if m.version != m0.version {
        return Err(differ(
            "mcrt version",
            m0.version.clone(),
            m.version.clone(),
        ));
    }
    if m.scene_hash != m0.scene_hash {
        return Err(differ(
            "scene file",
            format!("{} (hash {})", m0.scene, m0.scene_hash),
            format!("{} (hash {})", m.scene, m.scene_hash),
        ));
    }
    if (m.width, m.height) != (m0.width, m0.height) {
        return Err(differ(
            "image size",
            format!("{} × {}", m0.width, m0.height),
            format!("{} × {}", m.width, m.height),
        ));
    }
    if m.crop != m0.crop {
        return Err(differ("crop", m0.crop_text(), m.crop_text()));
    }
    if m.seed != m0.seed {
        return Err(differ("seed", m0.seed.to_string(), m.seed.to_string()));
    }
    if m.spp != m0.spp {
        return Err(differ("spp", m0.spp.to_string(), m.spp.to_string()));
    }
    if m.settings != m0.settings {
        let (a, b) = settings_difference(&m0.settings, &m.settings);
        return Err(differ("settings", a, b));
    }
    if m.pass.n != m0.pass.n {
        return Err(differ(
            "number of passes",
            m0.pass.n.to_string(),
            m.pass.n.to_string(),
        ));
    }
    if (m.first, m.count) != m.pass.share(m.spp) {
        return Err(PartsError::Mismatch(format!(
            "{}: pass {} of {} spp should hold samples {:?}, it holds {}..{}",
            p.display(),
            m.pass,
            m.spp,
            m.pass.share(m.spp),
            m.first,
            m.first + m.count
        )));
    }
    Ok(())
}

/// Where two settings strings first differ: the setting there (`name: value` or
/// `name=value`), from each. Settings strings are long (every integrator parameter); a
/// mismatch names the one that differs rather than printing both whole.
pub fn settings_difference(a: &str, b: &str) -> (String, String) {
    let at = a
        .char_indices()
        .zip(b.chars())
        .find(|((_, x), y)| x != y)
        .map_or(a.len().min(b.len()), |((i, _), _)| i);
    // The setting starts after the last separator before the difference: ", " or "{ "
    // inside the parameters' Debug text, " " before a top-level `key=value`. The two
    // strings agree up to there.
    let head = &a[..at];
    let mut start = 0;
    for sep in [", ", "{ "] {
        if let Some(i) = head.rfind(sep) {
            start = start.max(i + sep.len());
        }
    }
    for (i, _) in head.match_indices(' ') {
        if starts_with_key(&a[i + 1..]) {
            start = start.max(i + 1);
        }
    }
    let field = |s: &str| -> String {
        let rest = &s[start.min(s.len())..];
        let mut end = [", ", " }"]
            .iter()
            .filter_map(|sep| rest.find(sep))
            .min()
            .unwrap_or(rest.len());
        if let Some(i) = rest[..end]
            .match_indices(' ')
            .map(|(i, _)| i)
            .find(|&i| starts_with_key(&rest[i + 1..]))
        {
            end = i;
        }
        match &rest[..end] {
            "" => "(nothing)".into(),
            f => f.to_string(),
        }
    };
    (field(a), field(b))
}

/// Whether `s` starts with a top-level `key=`.
fn starts_with_key(s: &str) -> bool {
    let key = s
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .next()
        .unwrap_or("");
    !key.is_empty() && s[key.len()..].starts_with('=')
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A film's splats survive a sums file bit for bit, and their path count is under the
    /// checksum: a file whose `splat_paths` was changed is refused.
    #[test]
    fn splats_round_trip_through_sums_files() {
        let (w, h) = (3u32, 2u32);
        let mut s = crate::render::RenderSettings {
            width: w,
            height: h,
            spp: 2,
            seed: 1,
            camera: None,
            params: Default::default(),
            sampler: Default::default(),
            threads: None,
            crop: None,
            backend: Default::default(),
        };
        s.params.shadow_rays = 1;
        let meta = PartMeta::new(Path::new("x.toml"), b"scene", "", &s, Pass { k: 1, n: 1 });
        let mut film = Film::new(w, h);
        let mut px = crate::film::PixelSums::default();
        px.add(crate::Color::new(0.5, 1.0, 2.0));
        film.set_pixel(1, 1, &px);
        let mut splats = crate::film::Splats::default();
        splats.add(2, 0, w, crate::Color::new(3.0, -1e-7, 1e9));
        splats.paths = 7 << 33;
        film.add_splats(&splats);
        let dir = std::env::temp_dir().join(format!("mcrt-splat-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.exr");
        let part = Part { meta, film };
        write_part(&path, &part).unwrap();
        let back = read_part(&path).unwrap();
        assert!(back.film == part.film, "splats lost in the sums file");
        // The same bytes with another path count in the metadata.
        let mut bytes = std::fs::read(&path).unwrap();
        let at = bytes
            .windows(12)
            .position(|w| w == b"splat_paths=")
            .unwrap();
        bytes[at + 12] = if bytes[at + 12] == b'1' { b'2' } else { b'1' };
        let err = decode_part(&bytes, &[]).map(|_| ()).unwrap_err();
        assert!(err.contains("checksum"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_differing_setting_is_named() {
        let a = "camera=None sampler=Sobol IntegratorParams { kind: Path, shadow_rays: 1, rr: Fixed(0.5) } defines=[] lenient=false";
        let b = "camera=None sampler=Sobol IntegratorParams { kind: Path, shadow_rays: 4, rr: Fixed(0.5) } defines=[] lenient=false";
        assert_eq!(
            settings_difference(a, b),
            ("shadow_rays: 1".into(), "shadow_rays: 4".into())
        );
        let c = a.replace("camera=None", "camera=Some(\"top\")");
        assert_eq!(
            settings_difference(a, &c),
            ("camera=None".into(), "camera=Some(\"top\")".into())
        );
        let d = a.replace("lenient=false", "lenient=true");
        assert_eq!(
            settings_difference(a, &d),
            ("lenient=false".into(), "lenient=true".into())
        );
    }

    #[test]
    fn pass_count_is_bounded() {
        assert!("1/4000000000".parse::<Pass>().is_err());
        assert!(format!("1/{}", MAX_PASSES + 1).parse::<Pass>().is_err());
        assert!(format!("1/{MAX_PASSES}").parse::<Pass>().is_ok());
    }
}
