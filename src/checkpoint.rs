//! Checkpoints: the state of an unfinished render, to continue it with `--resume`.
//!
//! A checkpoint is a sums file ([`crate::parts`]) of pass 1/1 with one more u32 channel,
//! `next`: for each pixel, the number of samples rendered so far (its samples [0, next) are
//! in the sums; `count` can be smaller where NaN or infinite samples were dropped). Its
//! metadata says `spp` = the largest `next` and `samples=0..` the smallest, so a checkpoint in
//! which every pixel got the same number of samples is also a complete sums file that `mcrt
//! merge` accepts. Resuming continues every pixel from its own `next`; since a sample depends
//! only on (seed, pixel, index) and the sums are exact integers, an interrupted and resumed
//! render equals the uninterrupted one bit for bit.

use crate::film::Film;
use crate::image::ImageError;
use crate::parts::{self, Part, PartMeta, PartsError, Pass};
use crate::render::RenderSettings;
use std::path::{Path, PathBuf};

/// Name of the per-pixel sample-index channel.
pub const NEXT: &str = "next";

#[derive(Clone, Debug)]
pub struct Checkpoint {
    pub meta: PartMeta,
    pub film: Film,
    /// Samples rendered per pixel, row-major over the film.
    pub next: Vec<u32>,
}

/// The default checkpoint path of an output image: `DIR/STEM.checkpoint.exr`, with the stem
/// cut short and a hash of it added where that name would be too long for the file system
/// ([`crate::image::fit_file_name`]).
pub fn default_path(output: &Path) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(crate::image::fit_file_name("", &stem, ".checkpoint.exr"))
}

impl Checkpoint {
    /// A checkpoint of `film`/`next`, rendered with settings `s` from the scene file whose
    /// bytes are `scene_bytes` (`extra` as for [`PartMeta::new`]).
    pub fn new(
        scene: &Path,
        scene_bytes: &[u8],
        extra: &str,
        s: &RenderSettings,
        film: Film,
        next: Vec<u32>,
    ) -> Checkpoint {
        let lo = next.iter().copied().min().unwrap_or(0);
        let hi = next.iter().copied().max().unwrap_or(0);
        let mut meta = PartMeta::new(scene, scene_bytes, extra, s, Pass { k: 1, n: 1 });
        meta.spp = hi;
        meta.first = 0;
        meta.count = lo;
        Checkpoint { meta, film, next }
    }

    /// Checks that this checkpoint continues the render described by `now` (the metadata
    /// [`Checkpoint::new`] would give the resuming render): same mcrt version, scene file
    /// bytes, settings, image size, crop and seed. The spp may differ.
    pub fn check_matches(&self, path: &Path, now: &PartMeta) -> Result<(), PartsError> {
        let m = &self.meta;
        let differ = |what: &str, a: String, b: String| {
            PartsError::Mismatch(format!(
                "{}: the checkpoint is of another render: {what} {} in the checkpoint, {} now",
                path.display(),
                crate::input::shorten(&a),
                crate::input::shorten(&b)
            ))
        };
        if m.version != now.version {
            return Err(differ(
                "mcrt version",
                m.version.clone(),
                now.version.clone(),
            ));
        }
        if m.scene_hash != now.scene_hash {
            return Err(differ(
                "scene file",
                format!("{} (hash {})", m.scene, m.scene_hash),
                format!("{} (hash {})", now.scene, now.scene_hash),
            ));
        }
        if (m.width, m.height, m.crop) != (now.width, now.height, now.crop) {
            let size = |m: &PartMeta| match m.crop {
                Some([x, y, w, h]) => format!("{} × {} crop {x},{y},{w},{h}", m.width, m.height),
                None => format!("{} × {}", m.width, m.height),
            };
            return Err(differ("image size", size(m), size(now)));
        }
        if m.seed != now.seed {
            return Err(differ("seed", m.seed.to_string(), now.seed.to_string()));
        }
        if m.settings != now.settings {
            let (a, b) = parts::settings_difference(&m.settings, &now.settings);
            return Err(differ("settings", a, b));
        }
        Ok(())
    }
}

/// Writes a checkpoint atomically (temporary file + rename).
pub fn write_checkpoint(path: &Path, c: &Checkpoint) -> Result<(), ImageError> {
    let part = Part {
        meta: c.meta.clone(),
        film: c.film.clone(),
    };
    parts::write_part_with(path, &part, &[(NEXT, &c.next)])
}

/// Checks a checkpoint's counts against each other: no pixel counts more samples than it
/// rendered (`next`), and `next` spans exactly the samples the metadata says (its largest
/// value is `spp`, its smallest the end of `samples=0..`), so the spp checked against
/// `--spp` on resuming is the one the pixels hold. (The checksum has already tied the
/// channels to the metadata; this catches a checkpoint whose parts disagree as written.)
fn check_counts(part: &Part, next: &[u32]) -> Result<(), String> {
    if next.iter().zip(&part.film.count).any(|(n, c)| c > n) {
        return Err("a pixel's count exceeds its samples rendered".into());
    }
    let m = &part.meta;
    let lo = next.iter().copied().min().unwrap_or(0);
    let hi = next.iter().copied().max().unwrap_or(0);
    if m.pass != (Pass { k: 1, n: 1 }) || m.first != 0 || (lo, hi) != (m.count, m.spp) {
        return Err(format!(
            "its 'next' channel holds {lo} to {hi} samples per pixel, but its metadata says \
             pass {} with {} spp, samples {}..{}",
            m.pass,
            m.spp,
            m.first,
            m.first + m.count
        ));
    }
    Ok(())
}

/// Reads a checkpoint written by [`write_checkpoint`] (once, through
/// [`crate::input::read`]).
pub fn read_checkpoint(path: &Path) -> Result<Checkpoint, PartsError> {
    let err = |message: String| PartsError::Read {
        path: path.to_path_buf(),
        message,
    };
    let bytes = crate::input::read(path).map_err(err)?;
    decode_checkpoint(&bytes).map_err(err)
}

/// Decodes a checkpoint's bytes: a sums file ([`parts::decode_part`]) with a `next` channel
/// whose counts agree with its film and metadata.
pub fn decode_checkpoint(bytes: &[u8]) -> Result<Checkpoint, String> {
    let (part, mut more) = parts::decode_part(bytes, &[NEXT]).map_err(|message| {
        if message.contains("no channel 'next'") {
            "not a checkpoint (no 'next' channel): a sums file of `--pass`?".into()
        } else {
            message
        }
    })?;
    let next = more.remove(0);
    check_counts(&part, &next)?;
    Ok(Checkpoint {
        meta: part.meta,
        film: part.film,
        next,
    })
}
