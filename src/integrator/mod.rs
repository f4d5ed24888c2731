//! Integrators: estimators of the radiance arriving along a camera ray.
//!
//! - [`path`]: unidirectional path tracing with next-event estimation and multiple importance
//!   sampling, ended by Russian roulette (unbiased).
//! - [`direct`]: emission plus one bounce of direct light, seen through mirrors and glass.
//! - [`photon`]: Jensen's two-pass photon mapping (biased, consistent as the photon counts
//!   grow): direct light by shadow rays, caustics from a caustic map, indirect light by
//!   final gathering into a global map.
//! - [`sppm`]: stochastic progressive photon mapping (Hachisuka and Jensen 2009), its own
//!   whole-image driver ([`sppm::render_sppm`]).
//!
//! The path tracer's maths is one function, [`path::PathState::step`] (one vertex of one
//! path), which two drivers run: [`path::li`] one path at a time (`--backend scalar`) and
//! [`stream`], a pool of paths per tile whose rays are traced in batches (any scene). The
//! sixteen-lane [`wavefront`] follows it lane for lane on the small scenes it takes. The
//! render settings' backend chooses ([`crate::render::Backend`]); the image is the same bits
//! with each.
//!
//! # The seam
//!
//! The render loop ([`crate::render`]), the progressive driver, `--pass`, `--resume` and
//! `--time` all render through one interface, [`Integrator`]: an estimator made ready for one
//! scene and one set of render settings (its photon maps built, its backend chosen) that
//! fills a tile's pixels with samples. [`prepare`] is the one place that maps an
//! [`IntegratorKind`] to its integrator; a new integrator is a type implementing the trait
//! and an arm there. Each camera sample's value depends only on (seed, pixel, sample index),
//! which is what lets any split of the samples give the same film. SPPM's passes depend on
//! each other (each shrinks the radii of the last), so it is not an [`Integrator`] but a
//! whole-image driver; estimators that add to any pixel (light tracing, bidirectional
//! methods) splat into [`crate::film::Film::splat`].

pub mod direct;
mod nee;
pub mod path;
pub mod photon;
pub mod sppm;
pub mod stream;
#[cfg(target_arch = "x86_64")]
pub mod wavefront;

use crate::camera::Camera;
use crate::film::PixelSums;
use crate::geometry::Ray;
use crate::material::sampling::power_heuristic;
use crate::render::{Backend, RenderError, RenderSettings, RenderStats, TilePixel};
use crate::sampler::Sampler;
use crate::scene::{Interaction, Scene};
use crate::simd::{Float, Mask, Vector3};
use crate::Color;
use glam::Vec3A;
#[cfg(target_arch = "x86_64")]
pub(crate) use nee::Lattice;
pub(crate) use nee::{one_light, sample_lights};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    Path,
    Direct,
    Photon,
    Sppm,
}

impl IntegratorKind {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "path" => Some(IntegratorKind::Path),
            "direct" => Some(IntegratorKind::Direct),
            "photon" => Some(IntegratorKind::Photon),
            "sppm" => Some(IntegratorKind::Sppm),
            _ => None,
        }
    }
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Direct => "direct",
            IntegratorKind::Photon => "photon",
            IntegratorKind::Sppm => "sppm",
        }
    }
}

/// How paths end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RussianRoulette {
    /// Survive with probability min(max(throughput)·η², 0.95) from bounce `start` on (the
    /// throughput-based rule of Mitsuba 3 and pbrt-v4).
    Throughput { start: u32 },
    /// Survive every bounce with this fixed probability p: 1/(1 − p) bounces on average, as in
    /// the TNCG15 report.
    Fixed(f32),
}

impl RussianRoulette {
    /// The roulette after a vertex, over any lanes (written once for the one-path loop,
    /// [`path::PathState::step`], and the wavefront's lanes): the lanes whose path survives,
    /// and there its throughput `beta` divided by the survival probability. `eta2` is the
    /// η² gathered over refractions (the throughput rule undoes radiance scaling with it),
    /// `deep(start)` the lanes whose path has made at least `start` bounces (asked by the
    /// throughput rule only), `u` the vertex's roulette number.
    #[inline(always)]
    pub(crate) fn play<V: Vector3>(
        self,
        beta: V,
        eta2: V::F,
        deep: impl FnOnce(u32) -> Mask<V>,
        u: V::F,
    ) -> (Mask<V>, V) {
        match self {
            RussianRoulette::Fixed(q) => {
                let q = V::F::splat(q);
                (!u.ge(q), beta.div(q))
            }
            RussianRoulette::Throughput { start } => {
                let plays = deep(start);
                let q = (beta.max_element() * eta2).min_num(V::F::splat(0.95));
                (!(plays & u.ge(q)), V::select(plays, beta.div(q), beta))
            }
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct IntegratorParams {
    pub kind: IntegratorKind,
    /// Longest path in segments (Mitsuba's `max_depth`); None = unlimited.
    pub max_depth: Option<u32>,
    /// Shadow rays per non-specular vertex.
    pub shadow_rays: u32,
    pub rr: RussianRoulette,
    /// Emitters seen directly from the camera are black.
    pub hide_emitters: bool,
    /// `direct` follows mirrors and glass to the first non-specular surface.
    pub specular_chain: bool,
    /// Settings of the `photon` and `sppm` integrators.
    pub photon: PhotonParams,
}

/// Photon counts and search parameters of the photon-mapping integrators.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonParams {
    /// `photon`: photons emitted for the global map.
    pub photons: u64,
    /// `photon`: photons emitted for the caustic map (only those reaching a diffuse surface
    /// by mirrors and glass are kept).
    pub caustic_photons: u64,
    /// `photon`: photons in each radiance estimate (k nearest).
    pub gather_photons: u32,
    /// `photon`: final-gather rays per camera sample.
    pub final_gather: u32,
    /// `sppm`: photon passes (and camera passes).
    pub iterations: u32,
    /// `sppm`: photons emitted per pass.
    pub photons_per_iteration: u64,
    /// `sppm`: initial search radius (world units); None: 1/200 of the scene's diagonal.
    pub initial_radius: Option<f32>,
}

impl PhotonParams {
    /// The defaults (a constant, so the command's flags can show them).
    pub const DEFAULT: PhotonParams = PhotonParams {
        photons: 200_000,
        caustic_photons: 1_000_000,
        gather_photons: 64,
        final_gather: 8,
        iterations: 64,
        photons_per_iteration: 100_000,
        initial_radius: None,
    };

    /// Refuses counts beyond [`crate::limits`] and a radius that is not a positive number,
    /// naming the command's flag.
    pub fn check(&self) -> Result<(), String> {
        use crate::limits::*;
        for (flag, v, min, max) in [
            ("--photons", self.photons, 0, MAX_PHOTONS),
            ("--caustic-photons", self.caustic_photons, 0, MAX_PHOTONS),
            (
                "--gather-photons",
                self.gather_photons as u64,
                1,
                MAX_GATHER_PHOTONS,
            ),
            (
                "--final-gather",
                self.final_gather as u64,
                0,
                MAX_FINAL_GATHER,
            ),
            ("--iterations", self.iterations as u64, 1, MAX_ITERATIONS),
            (
                "--photons-per-iteration",
                self.photons_per_iteration,
                1,
                MAX_PHOTONS,
            ),
        ] {
            check(flag, v, min, max)?;
        }
        match self.initial_radius {
            Some(r) if !(r > 0.0 && r.is_finite()) => {
                Err(format!("--initial-radius must be positive, got {r}"))
            }
            _ => Ok(()),
        }
    }
}

impl Default for PhotonParams {
    fn default() -> Self {
        PhotonParams::DEFAULT
    }
}

impl Default for IntegratorParams {
    fn default() -> Self {
        IntegratorParams {
            kind: IntegratorKind::Path,
            max_depth: None,
            shadow_rays: 1,
            rr: RussianRoulette::Throughput { start: 5 },
            hide_emitters: false,
            specular_chain: true,
            photon: PhotonParams::default(),
        }
    }
}

/// An estimator of the radiance along camera rays, ready to render one scene with one set of
/// render settings (see the module documentation).
pub trait Integrator: Sync {
    /// Radiance along a camera ray, from the sample's own random stream.
    fn li(&self, ray: Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Color;

    /// Renders a tile's samples (`pixels[k].samples` of pixel k, added to `sums[k]`) some
    /// other way than one [`Integrator::li`] at a time, with the same values; false leaves
    /// them to the render loop, which calls `li` sample by sample.
    fn render_tile(
        &self,
        _camera: &Camera,
        _pixels: &[TilePixel],
        _sums: &mut [PixelSums],
        _stats: &mut RenderStats,
    ) -> bool {
        false
    }

    /// What making it ready took (photons stored, their memory and time), counted once in
    /// the render's statistics.
    fn setup_stats(&self) -> RenderStats {
        RenderStats::default()
    }
}

/// The integrator that `s` names, ready for `scene`: the one registry of integrators.
/// `--integrator sppm` has its own driver and is refused here. `stop` is asked during long
/// preparations (photon tracing); once it answers true, this ends with
/// [`RenderError::Interrupted`].
pub fn prepare<'a>(
    scene: &'a Scene,
    s: &'a RenderSettings,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Box<dyn Integrator + 'a>, RenderError> {
    Ok(match s.params.kind {
        IntegratorKind::Path => Box::new(path::PathTracer::new(scene, s)?),
        IntegratorKind::Direct => {
            no_lanes(s)?;
            Box::new(direct::DirectLighting {
                scene,
                params: s.params,
            })
        }
        IntegratorKind::Photon => {
            no_lanes(s)?;
            Box::new(photon::PhotonMapping::new(scene, s, stop)?)
        }
        IntegratorKind::Sppm => {
            return Err(RenderError::Unsupported(
                "sppm renders whole-image iterations of its own (render::render), not \
                 samples per pixel"
                    .into(),
            ))
        }
    })
}

/// Refuses a wide backend asked for an integrator that traces one path at a time.
fn no_lanes(s: &RenderSettings) -> Result<(), RenderError> {
    match s.backend {
        Backend::Auto | Backend::Scalar => Ok(()),
        b => Err(RenderError::Unsupported(format!(
            "--backend {} runs the path tracer only, not --integrator {}",
            b.name(),
            s.params.kind.name()
        ))),
    }
}

/// Rays traced, for the summary line.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayStats {
    pub rays: u64,
    pub shadow_rays: u64,
}

impl RayStats {
    pub fn add(&mut self, o: &RayStats) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
    }
}

/// Radiance along a camera ray by `path` or `direct` (what [`path::PathTracer`] and
/// [`direct::DirectLighting`] call). The photon-mapping integrators need their maps, which
/// [`prepare`] builds; they are not rendered here (a `kind` of theirs gives `path`).
///
/// Where the CPU has AVX2, FMA, BMI1/2 and LZCNT (x86-64-v3: Intel since 2013, AMD since
/// 2015), the whole path (traversal, intersection tests, BSDFs, light sampling: everything
/// `li_v3` inlines) runs as code compiled for them, chosen at run time, so one binary still
/// runs on any x86-64. The instructions are those of the portable code in VEX form, with
/// three operands and without the register copies SSE needs, and with the bit-manipulation
/// instructions for the masks: 5–12 % off the Cornell box's render time (docs/performance.md).
/// The answers are the same bits: Rust lets LLVM fuse no multiply and add into an FMA, nor
/// reorder any floating-point operation, whatever the target features (the test
/// `same_image_with_and_without_the_x86_64_v3_path` checks it).
#[inline]
pub fn li(
    scene: &Scene,
    ray: crate::geometry::Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    #[cfg(target_arch = "x86_64")]
    if has_x86_64_v3() {
        // SAFETY: the CPU has the features, checked just above.
        return unsafe { li_v3(scene, ray, sampler, p, stats) };
    }
    li_portable(scene, ray, sampler, p, stats)
}

/// Whether the CPU has what [`li_v3`] is compiled for: AVX2, FMA, BMI1/2 and LZCNT.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn has_x86_64_v3() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("lzcnt")
}

/// [`li`] compiled for x86-64-v3 (the callees it needs are `#[inline(always)]`, so that
/// they are compiled here with its features rather than called in their portable form).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn li_v3(
    scene: &Scene,
    ray: crate::geometry::Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    li_portable(scene, ray, sampler, p, stats)
}

/// [`li`] in its portable form whatever the CPU, for the test that compares both forms.
#[doc(hidden)]
#[inline(always)]
pub fn li_portable(
    scene: &Scene,
    ray: crate::geometry::Ray,
    sampler: &mut Sampler,
    p: &IntegratorParams,
    stats: &mut RayStats,
) -> Color {
    match p.kind {
        IntegratorKind::Path | IntegratorKind::Photon | IntegratorKind::Sppm => {
            path::li(scene, ray, sampler, p, stats)
        }
        IntegratorKind::Direct => direct::li(scene, ray, sampler, p, stats),
    }
}

/// Radiance of the environment along a ray `d` (unit) that left the scene, weighted against
/// light sampling as `emitted` is.
#[inline]
pub(crate) fn escaped(
    scene: &Scene,
    d: Vec3A,
    prev: Option<(Vec3A, f32)>,
    shadow_rays: u32,
) -> Color {
    let Some((le, light_pdf)) = scene.lights.environment(d) else {
        return Color::ZERO;
    };
    match prev {
        None => le,
        Some((_, bsdf_pdf)) => le * power_heuristic(bsdf_pdf, shadow_rays as f32 * light_pdf),
    }
}

/// Emission seen at `si` along `-d`, weighted against light sampling from the previous
/// vertex `prev` when the path got here by a non-specular BSDF sample with density `bsdf_pdf`.
#[inline]
pub(crate) fn emitted(
    scene: &Scene,
    si: &Interaction,
    d: Vec3A,
    prev: Option<(Vec3A, f32)>,
    shadow_rays: u32,
) -> Color {
    if si.light == crate::scene::NO_LIGHT {
        return Color::ZERO;
    }
    let le = scene.lights.le(si.light, si.ng, si.uv, -d);
    match prev {
        None => le,
        Some((p_prev, bsdf_pdf)) => {
            let light_pdf = scene.lights.pdf(si.light, p_prev, si.p, si.ng);
            le * power_heuristic(bsdf_pdf, shadow_rays as f32 * light_pdf)
        }
    }
}
