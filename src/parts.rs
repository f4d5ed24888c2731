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
//!
//! and a text attribute `mcrtSums` of `key=value` lines ([`PartMeta`]): mcrt's version, the
//! scene file and a hash of its bytes, the settings, the seed, spp, the image size and crop,
//! and which pass of how many it holds, so that `merge` can check that the parts belong
//! together and cover every pass once. A merged film written with `--keep-sums` is the sums
//! file of pass 1/1.

use crate::film::Film;
use crate::image::{write_atomic, ImageError};
use crate::render::{render_samples, RenderError, RenderSettings, RenderStats};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// Format tag of the sums files this version reads and writes.
pub const FORMAT: &str = "mcrt-sums 1";
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
        let bad = || format!("expected K/N with 1 ≤ K ≤ N (e.g. 3/8), got '{s}'");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k: u32 = k.trim().parse().map_err(|_| bad())?;
        let n: u32 = n.trim().parse().map_err(|_| bad())?;
        if k == 0 || k > n {
            return Err(bad());
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
    for (q, qname) in QUANTITIES.iter().enumerate() {
        let data = if q == 0 { &f.sum } else { &f.sum_sq };
        for (c, cname) in CHANNELS.iter().enumerate() {
            for word in 0..4 {
                let v: Vec<u32> = data
                    .iter()
                    .map(|p| ((p[c] as u128) >> (32 * word)) as u32)
                    .collect();
                channels.push(AnyChannel::new(
                    format!("{qname}.{cname}.w{word}").as_str(),
                    FlatSamples::U32(v),
                ));
            }
        }
    }
    channels.push(AnyChannel::new("count", FlatSamples::U32(f.count.clone())));
    for (name, v) in extra {
        if v.len() != w * h {
            return Err(format!("channel '{name}' does not have the film's size"));
        }
        channels.push(AnyChannel::new(*name, FlatSamples::U32(v.to_vec())));
    }
    let mut attrs = LayerAttributes::named(LAYER);
    attrs.other.insert(
        Text::from(ATTRIBUTE),
        AttributeValue::Text(Text::from_slice_unchecked(part.meta.to_text().as_bytes())),
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

/// Reads a sums file written by [`write_part`].
pub fn read_part(path: &Path) -> std::result::Result<Part, PartsError> {
    Ok(read_part_with(path, &[])?.0)
}

/// Reads a sums file and the extra u32 channels `extra` (each required).
pub fn read_part_with(
    path: &Path,
    extra: &[&str],
) -> std::result::Result<(Part, Vec<Vec<u32>>), PartsError> {
    use exr::prelude::*;
    let err = |message: String| PartsError::Read {
        path: path.to_path_buf(),
        message,
    };
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| err(e.to_string()))?;
    let layer = &image.layer_data;
    let text = layer
        .attributes
        .other
        .get(ATTRIBUTE.as_bytes())
        .ok_or_else(|| {
            err(format!(
                "no '{ATTRIBUTE}' attribute (not written by 'mcrt render --pass')"
            ))
        })?;
    let AttributeValue::Text(text) = text else {
        return Err(err(format!("the '{ATTRIBUTE}' attribute is not text")));
    };
    let meta = PartMeta::from_text(&String::from_utf8_lossy(text.bytes())).map_err(err)?;
    let (w, h) = (layer.size.width(), layer.size.height());
    if (w, h) != (meta.film_size().0 as usize, meta.film_size().1 as usize) {
        return Err(err(format!(
            "the layer is {w} × {h} pixels but the metadata says {} × {}",
            meta.film_size().0,
            meta.film_size().1
        )));
    }
    let channel = |name: &str| -> std::result::Result<&Vec<u32>, PartsError> {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .ok_or_else(|| err(format!("no channel '{name}'")))?;
        match &ch.sample_data {
            FlatSamples::U32(v) if v.len() == w * h => Ok(v),
            _ => Err(err(format!("channel '{name}' is not u32"))),
        }
    };
    let mut film = Film::new(w as u32, h as u32);
    for (q, qname) in QUANTITIES.iter().enumerate() {
        for (c, cname) in CHANNELS.iter().enumerate() {
            for word in 0..4 {
                let v = channel(&format!("{qname}.{cname}.w{word}"))?;
                let data = if q == 0 {
                    &mut film.sum
                } else {
                    &mut film.sum_sq
                };
                for (p, &x) in data.iter_mut().zip(v) {
                    p[c] = (p[c] as u128 | (x as u128) << (32 * word)) as i128;
                }
            }
        }
    }
    film.count.copy_from_slice(channel("count")?);
    let mut more = Vec::with_capacity(extra.len());
    for name in extra {
        more.push(channel(name)?.clone());
    }
    Ok((Part { meta, film }, more))
}

/// Merges the parts of one render: checks that they agree (scene, settings, seed, spp, size,
/// number of passes) and hold every pass exactly once, and adds their sums. The result is
/// pass 1/1: the film of a single render of all spp samples, bit for bit.
pub fn merge(parts: &[(PathBuf, Part)]) -> Result<Part, PartsError> {
    let Some((p0, first)) = parts.first() else {
        return Err(PartsError::Mismatch("no parts to merge".into()));
    };
    let m0 = &first.meta;
    for (p, part) in parts {
        let m = &part.meta;
        let differ = |what: &str, a: String, b: String| {
            PartsError::Mismatch(format!(
                "{} and {} are not parts of the same render: {what} {a} versus {b}",
                p0.display(),
                p.display()
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
            return Err(differ("settings", m0.settings.clone(), m.settings.clone()));
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
    }
    let n = m0.pass.n as usize;
    let mut seen: Vec<Option<&PathBuf>> = vec![None; n];
    for (p, part) in parts {
        let k = part.meta.pass.k as usize - 1;
        if let Some(q) = seen[k] {
            return Err(PartsError::Mismatch(format!(
                "pass {} is given twice: {} and {}",
                part.meta.pass,
                q.display(),
                p.display()
            )));
        }
        seen[k] = Some(p);
    }
    let missing: Vec<String> = (0..n)
        .filter(|&k| seen[k].is_none())
        .map(|k| format!("{}/{n}", k + 1))
        .collect();
    if !missing.is_empty() {
        return Err(PartsError::Mismatch(format!(
            "the parts do not cover all {n} passes: missing pass{} {} (given {} of {n})",
            if missing.len() > 1 { "es" } else { "" },
            missing.join(", "),
            n - missing.len()
        )));
    }
    let mut film = first.film.clone();
    for (_, part) in &parts[1..] {
        film.add_film(&part.film);
    }
    let pass = Pass { k: 1, n: 1 };
    let (f, c) = pass.share(m0.spp);
    let meta = PartMeta {
        pass,
        first: f,
        count: c,
        ..m0.clone()
    };
    Ok(Part { meta, film })
}
