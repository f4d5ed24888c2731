//! Shared helpers for the image-level tests: rendering a scene file through the library, and
//! comparing block means against a reference with tolerances derived from measured noise.
#![allow(dead_code)]

pub mod caustic;
pub mod cli;

use mcrt::image::{read_exr, Image};
use mcrt::render::RenderSettings;
use mcrt::sampler::SamplerKind;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use std::path::{Path, PathBuf};

pub fn project_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn reference(name: &str) -> Image {
    read_exr(&project_path(&format!("tests/data/refs/{name}"))).expect("reference image")
}

/// A rendered image with the estimated variance of each pixel mean.
pub struct Rendered {
    pub mean: Image,
    pub var: Image,
    pub spp: u32,
}

pub fn load(scene: &str) -> (Scene, FileSettings) {
    let desc = mcrt::load_scene(&project_path(scene)).expect("scene loads");
    let fs = desc.settings.clone();
    (Scene::build(desc), fs)
}

/// Render settings for tests. Unless `over` names a sampler, independent random numbers are
/// used: their per-pixel sample variance is an unbiased estimate of the error of the pixel
/// mean, which the tolerances are derived from (with Sobol points it overestimates it).
pub fn settings(file: &FileSettings, over: FileSettings) -> RenderSettings {
    let sampler = over.sampler.or(Some(SamplerKind::Independent));
    mcrt::resolve_settings(file, &FileSettings { sampler, ..over }, None).expect("settings")
}

pub fn render_with(scene: &Scene, s: &RenderSettings) -> Rendered {
    let (film, _) = mcrt::render::render(scene, s, &|_| {}).expect("render");
    Rendered {
        mean: film.image(),
        var: film.variance_of_mean(),
        spp: s.spp,
    }
}

/// Per-block comparison of `r` against `reference` (which may have a finer resolution by an
/// integer factor: with a box filter a pixel of `r` is exactly the mean of the reference's
/// pixels it covers). `ref_block` is the block edge in reference pixels.
pub struct BlockComparison {
    pub blocks_x: u32,
    pub blocks_y: u32,
    /// Luminance (RGB mean) of each block: mine, reference, and the standard deviation of
    /// the difference (mine's measured noise plus the reference's, estimated from mine).
    pub mine: Vec<f64>,
    pub reference: Vec<f64>,
    pub sigma: Vec<f64>,
}

impl BlockComparison {
    pub fn new(r: &Rendered, reference: &Image, ref_block: u32, ref_spp: u32) -> Self {
        let f = reference.width / r.mean.width;
        assert_eq!(reference.width, r.mean.width * f);
        assert_eq!(reference.height, r.mean.height * f);
        let bs = ref_block / f;
        let (bx, by) = (r.mean.width / bs, r.mean.height / bs);
        let mut c = BlockComparison {
            blocks_x: bx,
            blocks_y: by,
            mine: vec![],
            reference: vec![],
            sigma: vec![],
        };
        let lum = |p: [f64; 3]| (p[0] + p[1] + p[2]) / 3.0;
        for j in 0..by {
            for i in 0..bx {
                let m = lum(r.mean.block_mean(i, j, bs));
                let rf = lum(reference.block_mean(i, j, ref_block));
                // Variance of the block mean: Σ var(pixel mean) / n²; the luminance's standard
                // deviation is bounded by the mean of the channels' (they are correlated).
                let mut v = 0.0;
                for y in j * bs..(j + 1) * bs {
                    for x in i * bs..(i + 1) * bs {
                        let p = r.var.get(x, y);
                        let s = (p.x.max(0.0).sqrt() + p.y.max(0.0).sqrt() + p.z.max(0.0).sqrt())
                            as f64
                            / 3.0;
                        v += s * s;
                    }
                }
                let n = (bs * bs) as f64;
                let var_mine = v / (n * n);
                // The reference is the same estimator with more samples per block.
                let samples_mine = n * r.spp as f64;
                let samples_ref = (ref_block * ref_block) as f64 * ref_spp as f64;
                let var_ref = var_mine * samples_mine / samples_ref;
                c.mine.push(m);
                c.reference.push(rf);
                // Where there is no Monte Carlo noise at all (a constant environment seen
                // directly), what is left is float rounding: f32 sums and Mitsuba's RGB
                // pipeline differ in the last digits. Floor the noise at 1e-5 relative.
                let rounding = 1e-5 * rf.abs();
                c.sigma.push((var_mine + var_ref).sqrt().max(rounding));
            }
        }
        c
    }

    /// Blocks whose difference exceeds z standard deviations: (index, z-score).
    pub fn outliers(&self, z: f64) -> Vec<(usize, f64)> {
        (0..self.mine.len())
            .filter_map(|i| {
                let zi = (self.mine[i] - self.reference[i]).abs() / self.sigma[i].max(1e-12);
                (zi > z).then_some((i, zi))
            })
            .collect()
    }

    pub fn rel_err(&self, i: usize) -> f64 {
        (self.mine[i] - self.reference[i]).abs() / self.reference[i].max(1e-6)
    }

    pub fn max_z(&self) -> f64 {
        (0..self.mine.len())
            .map(|i| (self.mine[i] - self.reference[i]).abs() / self.sigma[i].max(1e-12))
            .fold(0.0, f64::max)
    }

    /// The blocks' z-scores summed and normalised: N(0, 1) when the images agree, so a small
    /// bias shared by all blocks, invisible in any one of them, shows here (256 blocks turn a
    /// 0.5 σ bias into 8 σ).
    pub fn aggregate_z(&self) -> f64 {
        let s: f64 = (0..self.mine.len())
            .map(|i| (self.mine[i] - self.reference[i]) / self.sigma[i].max(1e-12))
            .sum();
        s / (self.mine.len() as f64).sqrt()
    }

    pub fn print(&self) {
        for j in 0..self.blocks_y {
            let row: Vec<String> = (0..self.blocks_x)
                .map(|i| {
                    let k = (j * self.blocks_x + i) as usize;
                    format!(
                        "{:+5.1}",
                        100.0 * (self.mine[k] - self.reference[k]) / self.reference[k].max(1e-6)
                    )
                })
                .collect();
            eprintln!("{}", row.join(" "));
        }
    }
}

/// z-score above which a block fails: with a few hundred blocks, P(|Z| > 5) ≈ 6e-7 each.
pub const Z: f64 = 5.0;

impl BlockComparison {
    /// Every block within `Z` standard deviations of the measured noise, and the image as a
    /// whole unbiased (aggregate z within `Z`); prints the summary, and the blocks if any fail.
    pub fn assert_within_noise(&self, name: &str) {
        let out = self.outliers(Z);
        eprintln!(
            "{name}: {} blocks, max z {:.2}, aggregate z {:.2}, max rel err {:.2} %",
            self.mine.len(),
            self.max_z(),
            self.aggregate_z(),
            100.0
                * (0..self.mine.len())
                    .map(|i| self.rel_err(i))
                    .fold(0.0, f64::max)
        );
        if !out.is_empty() {
            self.print();
        }
        assert!(out.is_empty(), "{name}: blocks beyond {Z} sigma: {out:?}");
        assert!(
            self.aggregate_z().abs() < Z,
            "{name}: the image as a whole is biased: aggregate z {:.2}",
            self.aggregate_z()
        );
    }
}

/// Renders a scene file at its own resolution with `spp` and checks 8×8 blocks against the
/// reference `tests/data/refs/{reference}` (same resolution, made with `ref_spp`).
pub fn file_matches_reference(scene_file: &str, spp: u32, reference_file: &str, ref_spp: u32) {
    let (scene, fs) = load(scene_file);
    let s = settings(
        &fs,
        FileSettings {
            spp: Some(spp),
            ..Default::default()
        },
    );
    let r = render_with(&scene, &s);
    BlockComparison::new(&r, &reference(reference_file), 8, ref_spp)
        .assert_within_noise(scene_file);
}
