//! Photon mapping (Jensen 2001): photons traced from the lights ([`trace`]), stored compactly
//! ([`photon::Photon`], 24 bytes) in kd-trees ([`map::PhotonMap`]), and density estimation
//! of the reflected radiance from them ([`radiance_estimate`]). Used by the `photon` and
//! `sppm` integrators and the `photons` visualisation.

pub mod map;
#[allow(clippy::module_inception)]
pub mod photon;
pub mod trace;
pub mod visualize;

pub use map::{Found, PhotonMap};
pub use photon::Photon;
pub use trace::{trace_photons, trace_photons_until, TraceOptions, Traced};

use crate::geometry::Frame;
use crate::integrator::IntegratorParams;
use crate::material::Material;
use crate::scene::{Interaction, Scene};
use crate::Color;
use glam::Vec3A;
use std::cell::RefCell;
use std::collections::BinaryHeap;
use std::time::{Duration, Instant};

/// The maps of Jensen's two-pass method.
#[derive(Clone, Debug, Default)]
pub struct PhotonMaps {
    /// Every non-specular hit of the global pass.
    pub global: PhotonMap,
    /// Photons whose path since the light was specular only (LS+D), from the caustic pass.
    pub caustic: PhotonMap,
    /// The global pass's direct photons (lit) and shadow photons: where both are found near
    /// a point, it is in a penumbra; where only one kind, fully lit or fully in shadow.
    pub shadow: PhotonMap,
    /// Precomputed irradiance (Christensen, "Faster Photon Map Global Illumination", 1999)
    /// at every [`IRRADIANCE_STRIDE`]th global photon: its "power" is the irradiance E there
    /// (W/m², from the global map's k nearest photons), its direction the surface normal on
    /// the lit side. A final-gather ray that ends on a diffuse surface takes ρ/π·E from the
    /// nearest one instead of a k-nearest search of its own.
    pub irradiance: PhotonMap,
    /// Emitted photons of the global and caustic passes.
    pub emitted_global: u64,
    pub emitted_caustic: u64,
    pub rays: u64,
    pub build_time: Duration,
}

impl PhotonMaps {
    /// Traces the global and caustic passes and builds the three maps. `max_depth` (path
    /// segments, camera included) bounds the photon paths: a photon used at the end of a
    /// camera path of s segments may have at most max_depth − s.
    pub fn build(scene: &Scene, params: &IntegratorParams, seed: u64) -> PhotonMaps {
        Self::build_until(scene, params, seed, &|| false).expect("never stopped")
    }

    /// [`PhotonMaps::build`], asking `stop` while tracing: None once it answers true.
    pub fn build_until(
        scene: &Scene,
        params: &IntegratorParams,
        seed: u64,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<PhotonMaps> {
        let t0 = Instant::now();
        let md = params.max_depth.unwrap_or(u32::MAX);
        let pp = &params.photon;
        let global = trace_photons_until(
            scene,
            pp.photons,
            &TraceOptions {
                seed,
                pass: 0,
                // The camera path and the final-gather ray take at least two segments.
                max_depth: md.saturating_sub(2).max(1),
                shadow: true,
                normals: true,
                ..Default::default()
            },
            stop,
        )?;
        let caustic = trace_photons_until(
            scene,
            pp.caustic_photons,
            &TraceOptions {
                seed,
                pass: 1,
                max_depth: md.saturating_sub(1).max(1),
                caustic_only: true,
                ..Default::default()
            },
            stop,
        )?;
        let mut vis: Vec<Photon> = global
            .photons
            .iter()
            .filter(|p| p.depth() == 1)
            .copied()
            .collect();
        vis.extend_from_slice(&global.shadow);
        let candidates: Vec<(Vec3A, Vec3A)> = global
            .photons
            .iter()
            .zip(&global.normals)
            .step_by(IRRADIANCE_STRIDE)
            .map(|(ph, n)| (ph.pos(), *n))
            .collect();
        let global_map = PhotonMap::build(global.photons);
        let r_global = GLOBAL_RADIUS * scene_diagonal(scene);
        let k = pp.gather_photons.max(1) as usize;
        let irr: Vec<Photon> = {
            use rayon::prelude::*;
            candidates
                .par_iter()
                .map(|&(p, n)| {
                    let e = irradiance_estimate(&global_map, p, n, k, r_global);
                    Photon::new(p, e, n, 1, false)
                })
                .collect()
        };
        Some(PhotonMaps {
            irradiance: PhotonMap::build(irr),
            global: global_map,
            caustic: PhotonMap::build(caustic.photons),
            shadow: PhotonMap::build(vis),
            emitted_global: global.emitted,
            emitted_caustic: caustic.emitted,
            rays: global.rays + caustic.rays,
            build_time: t0.elapsed(),
        })
    }

    pub fn memory_bytes(&self) -> usize {
        self.global.memory_bytes()
            + self.caustic.memory_bytes()
            + self.shadow.memory_bytes()
            + self.irradiance.memory_bytes()
    }
}

/// One global photon in this many gets a precomputed irradiance point.
pub const IRRADIANCE_STRIDE: usize = 8;
/// Largest search radius of the global map's estimates, as a fraction of the scene diagonal.
pub const GLOBAL_RADIUS: f32 = 0.1;

/// Irradiance at `p` (normal `n`, on the side photons arrive from) from the `k` nearest
/// photons of `map` within `r_max` that arrived on that side and lie near the tangent
/// plane, with a cone filter: E = Σ Φ·(1 − d/r) / ((1/3)·π·r²).
///
/// `p` is the position of one of the map's photons: that photon is left out (the k nearest
/// after it are used). Counted, it would sit at the centre of every estimate with the cone's
/// full weight, where an independent photon's weight is 1/3 on average: the irradiance
/// would be too high by about 2/k (+6 % at k = 32 on the TNCG15 room, measured).
pub fn irradiance_estimate(map: &PhotonMap, p: Vec3A, n: Vec3A, k: usize, r_max: f32) -> Color {
    let keep = |ph: &Photon| ph.wi().dot(n) > 0.0 && on_surface(p, n, ph.pos());
    SCRATCH.with(|s| {
        let (heap, out) = &mut *s.borrow_mut();
        map.k_nearest(p, k + 1, r_max * r_max, &keep, heap, out);
        // The photon itself: the nearest, at distance 0.
        if out.first().is_some_and(|f| f.d2 == 0.0) {
            out.remove(0);
        } else {
            out.truncate(k);
        }
        let Some(r2) = gather_radius2(out, k, r_max) else {
            return Color::ZERO;
        };
        let r = r2.sqrt();
        let mut sum = Color::ZERO;
        for f in out.iter() {
            sum += map.photons()[f.index as usize].power() * (1.0 - f.d2.sqrt() / r);
        }
        sum / ((1.0 / 3.0) * std::f32::consts::PI * r2)
    })
}

/// Reflected radiance at a Lambertian point from the nearest precomputed irradiance point
/// (within `r_max`, normal within about 25° of the point's, on the same side): ρ/π·E. None
/// where there is none, or the material is not Lambertian or is normal-mapped (the caller
/// falls back to [`radiance_estimate`]).
pub fn precomputed_radiance(map: &PhotonMap, sp: &ShadingPoint, r_max: f32) -> Option<Color> {
    // (A normal or bump map's factor varies with the photon's direction: no shortcut.)
    if map.is_empty()
        || !matches!(sp.material.bsdf, crate::material::Bsdf::Lambert(_))
        || sp.material.perturbed.is_some()
    {
        return None;
    }
    let ng = sp.si.ng;
    let n = if sp.wo_world.dot(ng) >= 0.0 { ng } else { -ng };
    let keep = |ph: &Photon| ph.wi().dot(n) > 0.9 && on_surface(sp.si.p, n, ph.pos());
    SCRATCH.with(|s| {
        let (heap, out) = &mut *s.borrow_mut();
        map.k_nearest(sp.si.p, 1, r_max * r_max, &keep, heap, out);
        let f = out.first()?;
        let e = map.photons()[f.index as usize].power();
        // Lambertian: f is ρ/π for any pair of directions on the same side.
        let wi = Vec3A::new(0.0, 0.0, sp.wo.z.signum());
        Some(sp.material.eval(sp.wo, wi) * e)
    })
}

/// Bounding-box diagonal of the scene (sets default search radii).
pub fn scene_diagonal(scene: &Scene) -> f32 {
    scene
        .bounds()
        .map(|b| b.extent().length())
        .filter(|d| d.is_finite() && *d > 0.0)
        .unwrap_or(1.0)
}

/// Whether a photon at `q` lies within about 11° of the tangent plane at `p` (normal `n`):
/// photons on a perpendicular surface nearby (a corner) are not counted, those on the same
/// plane or a gently curved surface are.
#[inline]
pub fn on_surface(p: Vec3A, n: Vec3A, q: Vec3A) -> bool {
    let d = q - p;
    d.dot(n).abs() <= 0.2 * d.length() + 1e-4 * (1.0 + p.abs().max_element())
}

thread_local! {
    static SCRATCH: RefCell<(BinaryHeap<Found>, Vec<Found>)> =
        const { RefCell::new((BinaryHeap::new(), Vec::new())) };
}

/// Where a radiance estimate is made.
pub struct ShadingPoint<'a> {
    pub si: &'a Interaction,
    pub frame: &'a Frame,
    /// Towards the viewer, local frame.
    pub wo: Vec3A,
    /// Towards the viewer, world.
    pub wo_world: Vec3A,
    pub material: &'a Material,
}

impl ShadingPoint<'_> {
    /// Whether a photon may have landed on this surface: it arrived on the side the viewer
    /// sees, and lies near the tangent plane ([`on_surface`]).
    #[inline]
    pub fn same_side(&self, ph: &Photon) -> bool {
        let ng = self.si.ng;
        (ph.wi().dot(ng) > 0.0) == (self.wo_world.dot(ng) > 0.0)
            && on_surface(self.si.p, ng, ph.pos())
    }
}

/// Reflected radiance at `sp` towards the viewer from the `k` nearest photons within
/// `r_max` whose path length is at most `max_depth`, with a cone filter (Jensen 2001, eq.
/// 7.8, k = 1): L = Σ f·Φ·(1 − d/r) / ((1 − 2/3)·π·r²).
pub fn radiance_estimate(
    map: &PhotonMap,
    sp: &ShadingPoint,
    k: usize,
    r_max: f32,
    max_depth: u32,
) -> Color {
    if map.is_empty() || max_depth == 0 {
        return Color::ZERO;
    }
    let all = max_depth >= photon::MAX_DEPTH;
    let keep = |ph: &Photon| (all || ph.depth() <= max_depth) && sp.same_side(ph);
    SCRATCH.with(|s| {
        let (heap, out) = &mut *s.borrow_mut();
        map.k_nearest(sp.si.p, k, r_max * r_max, &keep, heap, out);
        let Some(r2) = gather_radius2(out, k, r_max) else {
            return Color::ZERO;
        };
        let r = r2.sqrt();
        let mut sum = Color::ZERO;
        for f in out.iter() {
            let ph = &map.photons()[f.index as usize];
            let wi = sp.frame.to_local(ph.wi());
            let w = 1.0 - f.d2.sqrt() / r;
            sum += sp.material.eval(sp.wo, wi) * ph.power() * w;
        }
        sum / ((1.0 / 3.0) * std::f32::consts::PI * r2)
    })
}

/// What the shadow photons near a point say about its direct light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    Lit,
    Shadowed,
    Unknown,
}

/// Jensen's shadow-photon test: the nearest direct and shadow photons around `sp`; all lit,
/// all in shadow, or mixed (or too few to tell).
pub fn visibility(map: &PhotonMap, sp: &ShadingPoint, k: usize, r_max: f32) -> Visibility {
    if map.is_empty() {
        return Visibility::Unknown;
    }
    let keep = |ph: &Photon| sp.same_side(ph);
    SCRATCH.with(|s| {
        let (heap, out) = &mut *s.borrow_mut();
        map.k_nearest(sp.si.p, k, r_max * r_max, &keep, heap, out);
        if out.len() < k {
            return Visibility::Unknown;
        }
        let shadow = out
            .iter()
            .filter(|f| map.photons()[f.index as usize].is_shadow())
            .count();
        if shadow == 0 {
            Visibility::Lit
        } else if shadow == out.len() {
            Visibility::Shadowed
        } else {
            Visibility::Unknown
        }
    })
}

/// The squared radius of a k-nearest gather: the k-th photon's distance when k were found,
/// else the search radius; None when nothing usable was found.
fn gather_radius2(found: &[map::Found], k: usize, r_max: f32) -> Option<f32> {
    let r2 = match found.len() {
        0 => return None,
        n if n == k => found[n - 1].d2,
        _ => r_max * r_max,
    };
    (r2 > 0.0).then_some(r2) // false for NaN too
}
