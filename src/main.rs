//! The `mcrt` command line: parses flags and calls the library.

use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use mcrt::checkpoint::{self, Checkpoint};
use mcrt::film::Film;
use mcrt::image::{
    check_output_path, write_image, write_image_with, Format, ToneMap, WriteOptions,
};
use mcrt::integrator::IntegratorKind;
use mcrt::parts::{self, Pass};
use mcrt::progressive::Stop;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::{Scene, SceneError};
use mcrt::Error;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

#[derive(Parser)]
#[command(name = "mcrt", version, about = "A physically based Monte Carlo ray tracer", long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (.png: 8-bit sRGB, tone mapped; .exr: linear RGB).
    Render(Box<RenderArgs>),
    /// Merge the sums files of `render --pass K/N` into the image of a single render.
    ///
    /// Give all N passes, once each, in any order. They must come from the same scene file,
    /// settings, seed, spp and mcrt version (checked: exit status 2 otherwise); the image is
    /// then the one a single `mcrt render` writes, bit for bit.
    Merge(MergeArgs),
    /// Compare image A with a reference B: RMSE, relMSE, PSNR and a difference image.
    ///
    /// Over all pixels and channels of two .exr images of the same size: RMSE =
    /// sqrt(mean((A−B)²)), relMSE = mean((A−B)²/(B²+0.01)), PSNR = 10·log10(1/MSE) dB (peak
    /// 1).
    Compare(CompareArgs),
    /// Trace the photon maps of the `photon` integrator and draw the stored photons over a
    /// dimmed direct-light render: global photons blue, caustic photons orange.
    Photons(PhotonsArgs),
    /// Denoise an EXR rendered with `--aov albedo,normal,emission` with Intel Open Image Denoise (its
    /// RT filter, guided by the albedo and normal layers; see README, "Denoising").
    Denoise(DenoiseArgs),
}

/// The photon-mapping integrators' defaults, which the flags show.
const PHOTON_DEFAULTS: mcrt::integrator::PhotonParams = mcrt::integrator::PhotonParams::DEFAULT;

/// Settings of the photon-mapping integrators.
#[derive(clap::Args, Clone)]
struct PhotonArgs {
    /// photon: photons emitted for the global map.
    #[arg(long, value_name = "N", default_value_t = PHOTON_DEFAULTS.photons)]
    photons: u64,
    /// photon: photons emitted for the caustic map (those that reach a diffuse surface by
    /// mirrors and glass only are kept).
    #[arg(long, value_name = "N", default_value_t = PHOTON_DEFAULTS.caustic_photons)]
    caustic_photons: u64,
    /// photon: photons in each radiance estimate (k nearest, cone filter).
    #[arg(long, value_name = "K", default_value_t = PHOTON_DEFAULTS.gather_photons)]
    gather_photons: u32,
    /// photon: final-gather rays per camera sample (0: the global map seen directly).
    #[arg(long, value_name = "N", default_value_t = PHOTON_DEFAULTS.final_gather)]
    final_gather: u32,
    /// sppm: iterations (camera pass plus photon pass each).
    #[arg(long, value_name = "N", default_value_t = PHOTON_DEFAULTS.iterations)]
    iterations: u32,
    /// sppm: photons emitted per iteration.
    #[arg(long, value_name = "N", default_value_t = PHOTON_DEFAULTS.photons_per_iteration)]
    photons_per_iteration: u64,
    /// sppm: initial search radius in scene units (default: 1/200 of the scene's diagonal).
    #[arg(long, value_name = "R")]
    initial_radius: Option<f32>,
}

impl PhotonArgs {
    fn params(&self) -> Result<mcrt::integrator::PhotonParams, Error> {
        let p = mcrt::integrator::PhotonParams {
            photons: self.photons,
            caustic_photons: self.caustic_photons,
            gather_photons: self.gather_photons,
            final_gather: self.final_gather,
            iterations: self.iterations,
            photons_per_iteration: self.photons_per_iteration,
            initial_radius: self.initial_radius,
        };
        p.check().map_err(Error::Usage)?;
        Ok(p)
    }
}

#[derive(clap::Args)]
struct PhotonsArgs {
    /// Scene file (.toml or Mitsuba .xml).
    scene: PathBuf,
    /// Output image (.png or .exr).
    #[arg(short, long, default_value = "photons.png")]
    output: PathBuf,
    /// Set a parameter of a Mitsuba XML scene.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Image width in pixels.
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    height: Option<u32>,
    /// Samples per pixel of the background render.
    #[arg(long, default_value_t = 4)]
    spp: u32,
    /// Seed of the photon and camera streams.
    #[arg(long)]
    seed: Option<u64>,
    /// Camera, by name.
    #[arg(long)]
    camera: Option<String>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    photon: PhotonArgs,
}

#[derive(Clone, Copy, ValueEnum)]
enum IntegratorArg {
    /// Path tracing with next-event estimation, MIS and Russian roulette.
    Path,
    /// Emission plus one bounce of direct light, through mirrors and glass.
    Direct,
    /// Photon mapping (Jensen): shadow rays, caustic map, final gathering into a global map.
    Photon,
    /// Stochastic progressive photon mapping: converges as --iterations grows.
    Sppm,
}

#[derive(Clone, Copy, ValueEnum)]
enum SamplerArg {
    /// Owen-scrambled Sobol points, one sequence per pixel (lower error).
    Sobol,
    /// Independent random numbers.
    Independent,
}

#[derive(Clone, Copy, ValueEnum)]
enum ToneMapArg {
    Clamp,
    Reinhard,
    Aces,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file: .toml (mcrt's format, see docs/scene-format.md), .xml (Mitsuba 3) or
    /// .gltf/.glb (glTF 2.0, see docs/gltf.md).
    scene: PathBuf,
    /// Set a parameter of a Mitsuba XML scene (its <default> or $name), as Mitsuba's -D.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Render unsupported BSDFs of an XML scene as grey diffuse, and approximate what mcrt
    /// lacks in a glTF scene, listing each, instead of failing.
    #[arg(long)]
    lenient: bool,
    /// Output image; the extension picks the format (.png or .exr). Default: SCENE's name with .png.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Image width in pixels.
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    height: Option<u32>,
    /// Seed of the random streams: the same seed and spp give the same image.
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: one per core). The image does not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Integrator.
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    /// Shadow rays per non-specular path vertex.
    #[arg(long)]
    shadow_rays: Option<u32>,
    /// Fixed Russian-roulette survival probability P (1/(1-P) bounces on average); by default
    /// the survival probability follows the path throughput.
    #[arg(long, value_name = "P")]
    rr_survival: Option<f32>,
    /// Longest path in segments (1: emitters seen directly, 2: direct light, ...); -1 or
    /// absent: unlimited.
    #[arg(long, allow_negative_numbers = true)]
    max_depth: Option<i64>,
    /// Sample generator (default: independent).
    #[arg(long, value_enum)]
    sampler: Option<SamplerArg>,
    /// Camera to render, by name (default: the scene's, else its first).
    #[arg(long)]
    camera: Option<String>,
    /// How the path tracer runs: auto (the fastest the CPU and scene allow), scalar (one path
    /// at a time), stream (a pool of paths per tile, rays traced in batches), avx512 or avx2
    /// (sixteen at a time; refused where unavailable). The image does not depend on it.
    #[arg(long, value_name = "auto|scalar|stream|avx512|avx2", value_parser = parse_backend)]
    backend: Option<mcrt::render::Backend>,
    #[command(flatten)]
    image: ImageArgs,
    /// Render only pass K of N (1-based): samples [⌊(K−1)·spp/N⌋, ⌊K·spp/N⌋) of every pixel,
    /// written as a sums file (-o must be .exr) for `mcrt merge`.
    #[arg(long, value_name = "K/N", conflicts_with_all = ["time", "target_noise", "write_partial", "checkpoint", "resume", "aov"])]
    pass: Option<mcrt::parts::Pass>,
    /// Time budget (90s, 10m, 2h, 250ms, or seconds): render progressive passes until it is
    /// spent. Without --spp the sample count is unbounded (the scene file's spp is ignored).
    #[arg(long, value_name = "DURATION", value_parser = mcrt::progressive::parse_duration)]
    time: Option<std::time::Duration>,
    /// Stop when the estimated relative standard error of the image falls to E (e.g. 0.01;
    /// see README, "Long renders"). Without --spp the sample count is unbounded.
    #[arg(long, value_name = "E")]
    target_noise: Option<f64>,
    /// With --target-noise: after the first estimate, spend further samples only on pixels
    /// whose error is still above the target.
    #[arg(long, requires = "target_noise")]
    adaptive: bool,
    /// Rewrite the output image (atomically) at most this often while rendering.
    #[arg(long, value_name = "DURATION", value_parser = mcrt::progressive::parse_duration)]
    write_partial: Option<std::time::Duration>,
    /// Where to write the checkpoint (default: OUTPUT's stem + .checkpoint.exr). Given, it is
    /// also written with every partial image and at the end; otherwise only on interruption.
    #[arg(long, value_name = "PATH.exr")]
    checkpoint: Option<PathBuf>,
    /// Continue the render saved in this checkpoint (same scene, settings and seed; --spp may
    /// be larger).
    #[arg(long, value_name = "CHECKPOINT.exr")]
    resume: Option<PathBuf>,
    /// Extra layers of the output EXR, comma-separated: albedo, normal, emission, depth,
    /// variance, spp (for denoisers; see README, "AOVs"). -o must be .exr.
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    quiet: bool,
    /// Serve a live preview of the render at ADDR (default 127.0.0.1:0, a free port on
    /// loopback; the URL is printed): the image after each pass, with a stop button.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:0", conflicts_with = "pass")]
    preview: Option<String>,
    /// Denoise the image (and each --write-partial image) with Intel Open Image Denoise,
    /// guided by albedo and normal; the raw image goes to OUTPUT's stem + .raw + extension.
    #[arg(long, conflicts_with = "pass")]
    denoise: bool,
    #[command(flatten)]
    photon: PhotonArgs,
}

#[derive(clap::Args)]
struct ImageArgs {
    /// Exposure in stops for PNG output (pixel values times 2^EV), from -64 to 64.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    exposure: f32,
    /// Tone map for PNG output.
    #[arg(long, value_enum, default_value = "clamp")]
    tonemap: ToneMapArg,
    /// Write EXR as 16-bit half floats.
    #[arg(long)]
    half: bool,
}

impl ImageArgs {
    fn options(&self) -> WriteOptions {
        WriteOptions {
            exposure: self.exposure,
            tonemap: match self.tonemap {
                ToneMapArg::Clamp => ToneMap::Clamp,
                ToneMapArg::Reinhard => ToneMap::Reinhard,
                ToneMapArg::Aces => ToneMap::Aces,
            },
            half: self.half,
        }
    }
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The sums files of passes 1/N … N/N, in any order.
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,
    /// Output image (.png or .exr).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the merged sums (a sums file of pass 1/1) here (.exr).
    #[arg(long, value_name = "SUMS.exr")]
    keep_sums: Option<PathBuf>,
    #[command(flatten)]
    image: ImageArgs,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// The image under test (.exr).
    a: PathBuf,
    /// The reference (.exr).
    b: PathBuf,
    /// Write a false-colour map of the per-pixel difference (mean over channels of A − B):
    /// white where equal, red where A is brighter, blue where B is (.png or .exr).
    #[arg(long, value_name = "IMAGE")]
    diff: Option<PathBuf>,
    /// The difference at which the map is pure red or blue (default: the largest difference
    /// of any pixel).
    #[arg(long, value_name = "D")]
    diff_range: Option<f64>,
}

/// `--exposure`: a finite number of stops within ±[`mcrt::limits::MAX_EXPOSURE`] (NaN would
/// write a black image, infinity a white or black one).
fn parse_exposure(text: &str) -> Result<f32, String> {
    let max = mcrt::limits::MAX_EXPOSURE;
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= max => Ok(v),
        Ok(v) => Err(format!(
            "expected a finite number of stops from -{max} to {max}, got {v}"
        )),
        Err(_) => Err(format!("expected a number of stops, got '{text}'")),
    }
}

/// Exit status after an interrupted render (128 + SIGINT, as shells report it).
const INTERRUPTED: i32 = 130;

/// Set by SIGINT or SIGTERM while rendering: the render stops within a few samples per
/// thread, writes what it has and exits with [`INTERRUPTED`].
static CANCEL: AtomicBool = AtomicBool::new(false);

/// True until the render begins: a signal while the scene loads ends the process at once,
/// writing nothing (an existing output stays as it was).
static LOADING: AtomicBool = AtomicBool::new(true);

/// Signals closer together than this count as one: `timeout` and a terminal's Ctrl-C signal
/// the whole process group, so one request can arrive twice at once.
const SIGNAL_BURST: std::time::Duration = std::time::Duration::from_millis(500);

fn main() {
    let cli = Cli::parse();
    // The kernels read the cap (`mcrt::cpu`) where they first run; a value they would
    // ignore is refused here.
    let result = mcrt::cpu::max_isa()
        .map_err(mcrt::Error::Usage)
        .and_then(|_| match cli.command {
            Command::Render(args) => render(*args),
            Command::Merge(args) => merge(args).map(|_| 0),
            Command::Compare(args) => compare(args).map(|_| 0),
            Command::Photons(args) => photons(args).map(|_| 0),
            Command::Denoise(args) => denoise(args).map(|_| 0),
        });
    match result {
        Ok(0) => {}
        Ok(code) => std::process::exit(code),
        Err(e) => {
            // User strings in the message (a name, a value) are cut short.
            eprintln!(
                "error: {}",
                mcrt::scene::error::shorten_message(&e.to_string())
            );
            std::process::exit(e.exit_code());
        }
    }
}

/// Catches SIGINT, SIGTERM and SIGHUP (the handler runs on its own thread). While the scene
/// loads ([`LOADING`]), a signal exits at once with status 130 and nothing written. While
/// rendering, the first sets [`CANCEL`] (the render writes its image, and a checkpoint where
/// it has one, and exits with 130); further signals within [`SIGNAL_BURST`] of it are the same
/// request; a later one exits at once.
fn catch_signals() {
    static FIRST: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    let _ = ctrlc::set_handler(|| {
        if LOADING.load(Ordering::SeqCst) {
            eprintln!("interrupted while loading the scene: nothing written");
            std::process::exit(INTERRUPTED);
        }
        let first = *FIRST.get_or_init(Instant::now);
        CANCEL.store(true, Ordering::SeqCst);
        if first.elapsed() > SIGNAL_BURST {
            eprintln!("interrupted again: exiting without saving");
            std::process::exit(INTERRUPTED);
        }
    });
}

/// The scene is loaded: from now on a signal stops the render instead of the process.
fn start_rendering() {
    LOADING.store(false, Ordering::SeqCst);
}

/// Renders; returns the exit status (0, or 130 when interrupted).
fn render(a: RenderArgs) -> Result<i32, Error> {
    let output = a.output.clone().unwrap_or_else(|| {
        PathBuf::from(a.scene.file_stem().unwrap_or_default()).with_extension("png")
    });
    // Fail on a bad output path now, not after a long render.
    let format = check_output_path(&output)?;
    if a.pass.is_some() && format != Format::Exr {
        return Err(Error::Usage(format!(
            "{}: --pass writes a sums file, which must be .exr",
            output.display()
        )));
    }
    let max_depth = mcrt::session::max_depth(a.max_depth)?;
    mcrt::session::check_threads(a.threads)?;
    mcrt::session::check_target_noise(a.target_noise)?;
    let aovs = match &a.aov {
        Some(list) => mcrt::aov::parse_list(list).map_err(Error::Usage)?,
        None => Vec::new(),
    };
    if !aovs.is_empty() && format != Format::Exr {
        return Err(Error::Usage(format!(
            "{}: --aov writes extra layers of an OpenEXR image; use an .exr output",
            output.display()
        )));
    }
    let checkpoint_path = a
        .checkpoint
        .clone()
        .unwrap_or_else(|| mcrt::checkpoint::default_path(&output));
    if a.pass.is_none() {
        if check_output_path(&checkpoint_path)? != Format::Exr {
            return Err(Error::Usage(format!(
                "{}: a checkpoint is a sums file, which must be .exr",
                checkpoint_path.display()
            )));
        }
        distinct_files(&[("-o", &output), ("--checkpoint", &checkpoint_path)])?;
        catch_signals();
    }
    if let Some(r) = &a.resume {
        distinct_files(&[("-o", &output), ("--resume", r)])?;
    }
    let denoiser = load_denoiser(&a, &output)?;
    let preview = start_preview(&a)?;
    let t_load = Instant::now();
    let load = mcrt::LoadOptions {
        defines: parse_defines(&a.define)?,
        lenient: a.lenient,
    };
    // Read once: the checkpoint's hash is of the bytes the scene was parsed from.
    let (desc, scene_bytes) = mcrt::load_scene_source(&a.scene, &load)?;
    for w in &desc.warnings {
        eprintln!("warning: {}", mcrt::scene::error::shorten_message(w));
    }
    let over = FileSettings {
        width: a.width,
        height: a.height,
        spp: a.spp,
        seed: a.seed,
        integrator: a.integrator.map(|i| match i {
            IntegratorArg::Path => IntegratorKind::Path,
            IntegratorArg::Direct => IntegratorKind::Direct,
            IntegratorArg::Photon => IntegratorKind::Photon,
            IntegratorArg::Sppm => IntegratorKind::Sppm,
        }),
        max_depth,
        shadow_rays: a.shadow_rays,
        rr_survival: a.rr_survival,
        camera: a.camera.clone(),
        sampler: a.sampler.map(|s| match s {
            SamplerArg::Sobol => mcrt::sampler::SamplerKind::Sobol,
            SamplerArg::Independent => mcrt::sampler::SamplerKind::Independent,
        }),
        ..Default::default()
    };
    let request = mcrt::session::Request {
        over,
        // With --max-depth -1 the flag must also override a limit in the file.
        unlimited_depth: a.max_depth == Some(-1),
        threads: a.threads,
        photon: a.photon.params()?,
        backend: a.backend.unwrap_or_default(),
    };
    let settings = mcrt::session::settings(&a.scene, &desc.settings, &desc.cameras, &request)?;
    let scene = mcrt::session::build(&a.scene, desc)?;
    let load_time = t_load.elapsed();
    if let Some(line) = scene.instancing_summary().filter(|_| !a.quiet) {
        eprintln!("{line}");
    }

    let (_, _, fw, fh) = settings.window();
    let npix = fw as u64 * fh as u64;
    let extra = format!("defines={:?} lenient={}", a.define, a.lenient);
    start_rendering();
    if settings.params.kind == IntegratorKind::Sppm {
        return render_sppm(&a, &scene, &settings, &output, load_time);
    }
    if let Some(pass) = a.pass {
        return render_pass(
            &a,
            &scene,
            &settings,
            pass,
            &output,
            &scene_bytes,
            &extra,
            load_time,
        );
    }
    // Budgets: with --time or --target-noise, only --spp bounds the samples.
    let budget = mcrt::session::budget(
        &settings,
        a.spp.is_some(),
        a.time,
        a.target_noise,
        a.adaptive,
        match (&preview, a.write_partial) {
            (Some(_), Some(w)) => Some(w.min(mcrt::preview::MAX_PASS)),
            (Some(_), None) => Some(mcrt::preview::MAX_PASS),
            (None, w) => w,
        },
    )?;
    let (mut film, mut next) = match &a.resume {
        None => (Film::new(fw, fh), vec![0; npix as usize]),
        Some(path) => {
            let c = checkpoint::read_checkpoint(path)?;
            let now = Checkpoint::new(
                &a.scene,
                &scene_bytes,
                &extra,
                &settings,
                Film::new(0, 0),
                vec![],
            );
            c.check_matches(path, &now.meta)?;
            if let Some(cap) = budget.spp {
                if c.meta.spp > cap {
                    return Err(Error::Usage(format!(
                        "{}: the checkpoint already holds {} samples per pixel, more than the {cap} asked for (--spp)",
                        path.display(),
                        c.meta.spp
                    )));
                }
            }
            (c.film, c.next)
        }
    };
    let resumed_from = next.iter().copied().min().unwrap_or(0);
    let show = !a.quiet && std::io::stderr().is_terminal();
    let bar = if !show {
        ProgressBar::hidden()
    } else if let Some(cap) = budget.spp {
        let done: u64 = next.iter().map(|&n| n as u64).sum();
        let b = ProgressBar::new(npix * cap as u64);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}%  {human_pos}/{human_len} samples  {per_sec}  ETA {eta}")
                .unwrap(),
        );
        b.set_position(done);
        b
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {human_pos} samples  {per_sec}  {msg}",
            )
            .unwrap(),
        );
        b
    };
    let opts = a.image.options();
    let guides = if aovs.iter().any(|v| v.needs_guides()) || denoiser.is_some() {
        Some(mcrt::aov::render_guides(&scene, &settings)?)
    } else {
        None
    };
    let save_checkpoint = |film: &Film, next: &[u32]| -> Result<(), Error> {
        let c = Checkpoint::new(
            &a.scene,
            &scene_bytes,
            &extra,
            &settings,
            film.clone(),
            next.to_vec(),
        );
        checkpoint::write_checkpoint(&checkpoint_path, &c)?;
        Ok(())
    };
    let write_output = |film: &Film| -> Result<(), Error> {
        let layers = mcrt::aov::channels(&aovs, guides.as_ref(), film);
        match &denoiser {
            None => write_image_with(&output, &film.image(), &opts, &layers)?,
            Some((oidn, raw)) => write_denoised(
                oidn,
                (&output, raw),
                (&scene, &settings),
                film,
                guides.as_ref(),
                &opts,
                &layers,
            )?,
        }
        Ok(())
    };
    let mut last_partial = Instant::now();
    let mut after_pass = |film: &Film, next: &[u32]| -> Result<(), Error> {
        if let Some(p) = &preview {
            p.publish(film, next, budget.spp);
        }
        if let Some(every) = a.write_partial {
            if last_partial.elapsed() >= every && !CANCEL.load(Ordering::SeqCst) {
                write_output(film)?;
                if a.checkpoint.is_some() {
                    save_checkpoint(film, next)?;
                }
                last_partial = Instant::now();
            }
        }
        Ok(())
    };
    let outcome = match mcrt::progressive::render_progressive(
        &scene,
        &settings,
        &mut film,
        &mut next,
        &budget,
        &CANCEL,
        &mut after_pass,
        &|n| bar.inc(n),
    ) {
        // Interrupted while the photon maps were traced: the render ends as any interrupted
        // one, with its (empty) image and a checkpoint that resumes from the start.
        Err(Error::Render(mcrt::render::RenderError::Interrupted))
            if CANCEL.load(Ordering::SeqCst) =>
        {
            mcrt::progressive::Outcome {
                stop: Stop::Interrupted,
                stats: Default::default(),
                passes: 0,
                noise: None,
            }
        }
        // The time budget spent before the first sample: an image of nothing would pass
        // for a result, so nothing is written.
        Err(Error::Render(mcrt::render::RenderError::Interrupted)) => {
            bar.finish_and_clear();
            return Err(Error::Usage(
                "the time budget (--time) was spent while the photon maps were built, before \
                 the first sample; nothing written: give more time or fewer photons"
                    .into(),
            ));
        }
        r => r?,
    };
    bar.finish_and_clear();
    if let Some(p) = &preview {
        p.set_state(mcrt::preview::State::Done);
    }
    let interrupted = outcome.stop == Stop::Interrupted;
    write_output(&film)?;
    if interrupted || a.checkpoint.is_some() {
        save_checkpoint(&film, &next)?;
    }
    let stats = &outcome.stats;
    if !a.quiet {
        let secs = stats.elapsed.as_secs_f64().max(1e-9);
        let rays = stats.rays.rays + stats.rays.shadow_rays;
        let (lo, hi) = (
            next.iter().copied().min().unwrap_or(0),
            next.iter().copied().max().unwrap_or(0),
        );
        let spp = if lo == hi {
            format!("{lo} spp")
        } else {
            format!(
                "{lo}–{hi} spp (mean {:.1})",
                next.iter().map(|&n| n as f64).sum::<f64>() / npix.max(1) as f64
            )
        };
        eprintln!(
            "{}: {}x{} at {spp}{} ({}, {} primitives, {} lights, loaded in {:.2} s) in {:.2} s, {} pass{}: {:.2} M samples/s, {:.2} M rays/s ({:.2} M shadow rays/s); stopped: {}{}",
            output.display(),
            fw,
            fh,
            if a.resume.is_some() { format!(", resumed from {resumed_from} spp") } else { String::new() },
            settings.params.kind.name(),
            scene.prim_count(),
            scene.lights.lights.len() + scene.lights.others.len(),
            load_time.as_secs_f64(),
            secs,
            outcome.passes,
            if outcome.passes == 1 { "" } else { "es" },
            stats.samples as f64 / secs / 1e6,
            rays as f64 / secs / 1e6,
            stats.rays.shadow_rays as f64 / secs / 1e6,
            outcome.stop,
            match (outcome.noise, outcome.stop) {
                (Some(e), Stop::Spp | Stop::Time | Stop::Interrupted) => format!(" (relative error {e:.4})"),
                _ => String::new(),
            }
        );
        print_photon_stats(stats);
        if interrupted || a.checkpoint.is_some() {
            eprintln!(
                "checkpoint: {} (continue with --resume {})",
                checkpoint_path.display(),
                checkpoint_path.display()
            );
        }
        warn_dropped(stats);
    }
    Ok(if interrupted { INTERRUPTED } else { 0 })
}

fn print_photon_stats(stats: &mcrt::render::RenderStats) {
    if stats.photons_stored > 0 {
        eprintln!(
            "photon maps: {} photons stored ({:.1} MB, {} bytes each), traced and built in {:.2} s",
            stats.photons_stored,
            stats.photon_bytes as f64 / 1e6,
            std::mem::size_of::<mcrt::photon::Photon>(),
            stats.photon_time.as_secs_f64()
        );
    }
}

fn parse_backend(s: &str) -> Result<mcrt::render::Backend, String> {
    mcrt::render::Backend::parse(s)
        .ok_or_else(|| format!("expected auto, scalar, stream, avx512 or avx2, got '{s}'"))
}

fn warn_dropped(stats: &mcrt::render::RenderStats) {
    if stats.dropped > 0 {
        let (x, y) = stats.first_dropped.unwrap_or_default();
        eprintln!(
            "warning: {} samples were NaN or infinite and were dropped (first at pixel {x}, {y})",
            stats.dropped
        );
    }
}

/// `--pass K/N`: one share of the samples, written as a sums file.
#[allow(clippy::too_many_arguments)]
fn render_pass(
    a: &RenderArgs,
    scene: &Scene,
    settings: &mcrt::render::RenderSettings,
    pass: Pass,
    output: &std::path::Path,
    scene_bytes: &[u8],
    extra: &str,
    load_time: std::time::Duration,
) -> Result<i32, Error> {
    let (_, _, fw, fh) = settings.window();
    let total = fw as u64 * fh as u64 * pass.share(settings.spp).1 as u64;
    let show = !a.quiet && std::io::stderr().is_terminal();
    let bar = if show {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}%  {human_pos}/{human_len} samples  {per_sec}  ETA {eta}")
                .unwrap(),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    let (film, stats) = parts::render_pass(scene, settings, pass, &|n| bar.inc(n))?;
    bar.finish_and_clear();
    let meta = parts::PartMeta::new(&a.scene, scene_bytes, extra, settings, pass);
    parts::write_part(output, &parts::Part { meta, film })?;
    if !a.quiet {
        let secs = stats.elapsed.as_secs_f64().max(1e-9);
        let rays = stats.rays.rays + stats.rays.shadow_rays;
        let (first, count) = pass.share(settings.spp);
        eprintln!(
            "{}: {}x{} at {} spp, pass {pass}: samples {first}..{} ({}, {} primitives, {} lights, loaded in {:.2} s) in {:.2} s: {:.2} M samples/s, {:.2} M rays/s ({:.2} M shadow rays/s)",
            output.display(),
            fw,
            fh,
            settings.spp,
            first + count,
            settings.params.kind.name(),
            scene.prim_count(),
            scene.lights.lights.len() + scene.lights.others.len(),
            load_time.as_secs_f64(),
            secs,
            stats.samples as f64 / secs / 1e6,
            rays as f64 / secs / 1e6,
            stats.rays.shadow_rays as f64 / secs / 1e6,
        );
        print_photon_stats(&stats);
        warn_dropped(&stats);
    }
    Ok(0)
}

/// Refuses two of the named paths that are the same file (an output written over another
/// output, or over an input still needed).
fn distinct_files(paths: &[(&str, &std::path::Path)]) -> Result<(), Error> {
    for (i, (fa, pa)) in paths.iter().enumerate() {
        for (fb, pb) in &paths[i + 1..] {
            if mcrt::image::same_file(pa, pb) {
                return Err(Error::Usage(format!(
                    "{fa} {} and {fb} {} are the same file; give them different names",
                    pa.display(),
                    pb.display()
                )));
            }
        }
    }
    Ok(())
}

fn merge(a: MergeArgs) -> Result<(), Error> {
    check_output_path(&a.output)?;
    let mut named: Vec<(&str, &std::path::Path)> = vec![("-o", &a.output)];
    if let Some(k) = &a.keep_sums {
        named.push(("--keep-sums", k));
    }
    let outputs = named.len();
    named.extend(a.parts.iter().map(|p| ("part", p.as_path())));
    // Outputs against each other and against the parts (a part given twice is merge's to
    // report).
    for i in 0..outputs {
        for &other in &named[i + 1..] {
            distinct_files(&[named[i], other])?;
        }
    }
    if let Some(k) = &a.keep_sums {
        if check_output_path(k)? != Format::Exr {
            return Err(Error::Usage(format!(
                "{}: --keep-sums writes a sums file, which must be .exr",
                k.display()
            )));
        }
    }
    // One part in memory at a time.
    let mut merger = parts::Merger::default();
    for p in &a.parts {
        merger.add(p, &parts::read_part(p)?)?;
    }
    let merged = merger.finish()?;
    write_image(&a.output, &merged.film.image(), &a.image.options())?;
    if let Some(k) = &a.keep_sums {
        parts::write_part(k, &merged)?;
    }
    Ok(())
}

fn compare(a: CompareArgs) -> Result<(), Error> {
    if let Some(d) = &a.diff {
        check_output_path(d)?;
        distinct_files(&[("--diff", d), ("A", &a.a)])?;
        distinct_files(&[("--diff", d), ("B", &a.b)])?;
    }
    if let Some(r) = a.diff_range {
        if !(r > 0.0 && r.is_finite()) {
            return Err(Error::Usage(format!(
                "--diff-range must be a positive number, got {r}"
            )));
        }
    }
    let read = |p: &PathBuf| -> Result<mcrt::image::Image, Error> {
        if Format::from_path(p).ok() != Some(Format::Exr) {
            return Err(Error::Input(format!(
                "{}: compare reads OpenEXR images (.exr)",
                p.display()
            )));
        }
        mcrt::image::read_exr(p).map_err(|e| Error::Input(e.to_string()))
    };
    let (img_a, img_b) = (read(&a.a)?, read(&a.b)?);
    let m = mcrt::compare::metrics(&img_a, &img_b)
        .map_err(|e| Error::Input(format!("{} and {}: {e}", a.a.display(), a.b.display())))?;
    println!("RMSE   {}", m.rmse);
    println!("relMSE {}", m.rel_mse);
    println!("PSNR   {} dB", m.psnr);
    if let Some(d) = &a.diff {
        let range = a.diff_range.unwrap_or(if m.max_abs_mean > 0.0 {
            m.max_abs_mean
        } else {
            1.0
        });
        let img = mcrt::compare::diff_image(&img_a, &img_b, range);
        write_image(d, &img, &WriteOptions::default())?;
        eprintln!(
            "{}: white = equal, red = A brighter by {range} or more, blue = B brighter",
            d.display()
        );
    }
    Ok(())
}

/// `sppm`: each iteration shrinks the radii the next one uses, so it renders in one go (no
/// sample passes, budgets, checkpoints or AOVs).
fn render_sppm(
    a: &RenderArgs,
    scene: &Scene,
    settings: &mcrt::render::RenderSettings,
    output: &std::path::Path,
    load_time: std::time::Duration,
) -> Result<i32, Error> {
    if a.pass.is_some()
        || a.time.is_some()
        || a.target_noise.is_some()
        || a.resume.is_some()
        || a.write_partial.is_some()
        || a.aov.is_some()
        || a.preview.is_some()
        || a.denoise
        || a.backend.is_some_and(|b| b != mcrt::render::Backend::Auto)
    {
        return Err(Error::Usage(
            "--integrator sppm renders the whole image at once, one path at a time: --pass, \
             --time, --target-noise, --resume, --write-partial, --aov, --preview, --denoise \
             and --backend apply to path, direct and photon"
                .into(),
        ));
    }
    let (_, _, fw, fh) = settings.window();
    let passes = settings.params.photon.iterations;
    let show = !a.quiet && std::io::stderr().is_terminal();
    let bar = if show {
        let b = ProgressBar::new(fw as u64 * fh as u64 * passes as u64);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}%  {human_pos}/{human_len} samples  {per_sec}  ETA {eta}")
                .unwrap(),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    let stop = || CANCEL.load(Ordering::SeqCst);
    let (film, stats) = mcrt::render::render_until(scene, settings, &|n| bar.inc(n), &stop)?;
    bar.finish_and_clear();
    write_image(output, &film.image(), &a.image.options())?;
    if stats.interrupted {
        // No checkpoint: each iteration's radii depend on all the iterations before it.
        eprintln!(
            "{}: interrupted; the image holds what was rendered ({} samples)",
            output.display(),
            stats.samples
        );
        return Ok(INTERRUPTED);
    }
    if !a.quiet {
        let secs = stats.elapsed.as_secs_f64().max(1e-9);
        let rays = stats.rays.rays + stats.rays.shadow_rays;
        eprintln!(
            "{}: {}x{} at {} iterations ({}, {} primitives, {} lights, loaded in {:.2} s) in {:.2} s: {:.2} M samples/s, {:.2} M rays/s ({:.2} M shadow rays/s)",
            output.display(),
            fw,
            fh,
            passes,
            settings.params.kind.name(),
            scene.prim_count(),
            scene.lights.lights.len() + scene.lights.others.len(),
            load_time.as_secs_f64(),
            secs,
            stats.samples as f64 / secs / 1e6,
            rays as f64 / secs / 1e6,
            stats.rays.shadow_rays as f64 / secs / 1e6,
        );
        print_photon_stats(&stats);
        warn_dropped(&stats);
    }
    Ok(0)
}

/// `-D NAME=VALUE` flags as (name, value) pairs.
fn parse_defines(flags: &[String]) -> Result<Vec<(String, String)>, Error> {
    flags
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) => Ok((k.to_string(), v.to_string())),
            None => Err(Error::Usage(format!("-D expects NAME=VALUE, got '{d}'"))),
        })
        .collect()
}

fn photons(a: PhotonsArgs) -> Result<(), Error> {
    check_output_path(&a.output)?;
    if a.threads == Some(0) {
        return Err(Error::Usage("--threads must be at least 1".into()));
    }
    let load = mcrt::LoadOptions {
        defines: parse_defines(&a.define)?,
        lenient: false,
    };
    let desc = mcrt::load_scene_with(&a.scene, &load)?;
    let over = FileSettings {
        width: a.width,
        height: a.height,
        spp: Some(a.spp),
        seed: a.seed,
        camera: a.camera.clone(),
        ..Default::default()
    };
    let mut settings = mcrt::resolve_settings(&desc.settings, &over, a.threads)?;
    settings.params.photon = a.photon.params()?;
    mcrt::check_memory(&settings)?;
    desc.check_limits()
        .map_err(|e| SceneError::new(&a.scene, None, e))?;
    let scene = Scene::build(desc);
    let s = &settings;
    let maps = mcrt::render::with_threads(s, || {
        mcrt::photon::PhotonMaps::build(&scene, &s.params, s.seed)
    })?;
    let img = mcrt::render::with_threads(s, || {
        mcrt::photon::visualize::draw_photons(&scene, s, &maps)
    })??;
    write_image(&a.output, &img, &WriteOptions::default())?;
    eprintln!(
        "{}: {} global photons (blue), {} caustic photons (orange), {} shadow-test photons; {:.1} MB, traced and built in {:.2} s",
        a.output.display(),
        maps.global.len(),
        maps.caustic.len(),
        maps.shadow.len(),
        maps.memory_bytes() as f64 / 1e6,
        maps.build_time.as_secs_f64()
    );
    Ok(())
}

/// `--denoise`: OIDN, loaded now so that a missing library stops the command before any
/// rendering, and the path of the raw image (checked now too).
fn load_denoiser(
    a: &RenderArgs,
    output: &std::path::Path,
) -> Result<Option<(mcrt::denoise::Oidn, PathBuf)>, Error> {
    if !a.denoise {
        return Ok(None);
    }
    let raw = mcrt::denoise::raw_path(output);
    check_output_path(&raw)?;
    let oidn = mcrt::denoise::Oidn::load().map_err(Error::Usage)?;
    Ok(Some((oidn, raw)))
}

/// Writes the denoised image to `output` and the raw one to `raw`, both with `layers`.
fn write_denoised(
    oidn: &mcrt::denoise::Oidn,
    (output, raw): (&std::path::Path, &std::path::Path),
    (scene, settings): (&Scene, &mcrt::render::RenderSettings),
    film: &Film,
    guides: Option<&mcrt::aov::Guides>,
    opts: &WriteOptions,
    layers: &[(String, Vec<f32>)],
) -> Result<(), Error> {
    let guides = guides.expect("--denoise renders the guides");
    let clean = oidn.denoise_render(scene, settings, film, guides)?;
    write_image_with(raw, &film.image(), opts, layers)?;
    write_image_with(output, &clean, opts, layers)?;
    Ok(())
}

/// `--preview`: starts the server and prints its URL.
fn start_preview(a: &RenderArgs) -> Result<Option<mcrt::preview::Preview>, Error> {
    let Some(addr) = &a.preview else {
        return Ok(None);
    };
    let p = mcrt::preview::Preview::start(addr, &CANCEL).map_err(Error::Usage)?;
    eprintln!("preview: {}", p.url());
    Ok(Some(p))
}

#[derive(clap::Args)]
struct DenoiseArgs {
    /// An EXR with channels R, G, B, albedo.R/G/B and normal.X/Y/Z, and optionally
    /// emission.R/G/B (`mcrt render --aov albedo,normal,emission -o IN.exr`).
    input: PathBuf,
    /// The denoised image (.png or .exr).
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    image: ImageArgs,
}

fn denoise(a: DenoiseArgs) -> Result<(), Error> {
    check_output_path(&a.output)?;
    let input = mcrt::denoise::read_guided_exr(&a.input).map_err(Error::Input)?;
    let oidn = mcrt::denoise::Oidn::load().map_err(Error::Usage)?;
    let clean = oidn
        .denoise(
            &input.color,
            &input.albedo,
            &input.normal,
            input.emission.as_deref().map(|e| (e, e)),
        )
        .map_err(Error::Denoise)?;
    write_image(&a.output, &clean, &a.image.options())?;
    Ok(())
}
