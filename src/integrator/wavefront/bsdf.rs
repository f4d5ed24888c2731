//! BSDF sampling, lane by lane: `Material::orient` and `Material::sample` for the
//! Lambertian, mirror, glass, rough conductor, rough dielectric and rough plastic BSDFs,
//! over the warps, Fresnel terms and BSDFs of [`crate::material`] instanced for the lanes.

use super::general::General;
use super::simd::{F, M, V3};
use super::LaneMask;
use crate::material::microfacet::Either;
use crate::material::rough_conductor::RoughConductor;
use crate::material::rough_plastic::Coated;
use crate::material::{dielectric, lambert, rough_dielectric, TransportMode};
use crate::simd::{Float, Vector3};

/// The lanes' BSDF samples (`Material::sample` in radiance mode).
pub struct Sample {
    /// Lanes with a sample (the others end their path).
    pub ok: M,
    /// Local direction, throughput weight, solid-angle pdf (0 for delta lobes), relative
    /// index of refraction crossed (1 for reflection).
    pub wi: V3,
    pub weight: V3,
    pub pdf: F,
    pub eta: F,
    /// Lanes whose sample is not a delta lobe's (MIS weighs the emitter it finds).
    pub glossy: M,
}

/// The rough lanes of a vertex, where any lane has one: those of rough conductors (`metal`),
/// of rough dielectrics (`glass`, of relative index `eta`, unit factors) and of rough
/// plastics (`plastic`, their BSDFs `coated` where any lane has one), and the conductors,
/// whose distribution serves all three.
pub struct Microfacets<'a> {
    pub metal: M,
    pub glass: M,
    pub plastic: M,
    pub conductor: RoughConductor<Either<F>, V3>,
    pub eta: F,
    pub coated: Option<Coated<'a, Either<F>, V3>>,
}

/// The BSDF samples of lanes with Lambertian (`lambert`), mirror (`mirror`), glass
/// (`glass`) and rough (`rough`, where any lane is) materials: `colour` the
/// albedo or reflectance, `eta` the glass's index, `oriented` and `side` what
/// `Material::orient` gives (glass: every lane, side 1).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn sample(
    wo: V3,
    [ux, uy, u1]: [F; 3],
    colour: V3,
    eta: F,
    (lambert, mirror, glass): (M, M, M),
    rough: Option<&Microfacets>,
    general: Option<&General>,
    oriented: M,
    side: F,
) -> Sample {
    let (zero, one) = (F::zero(), F::splat(1.0));
    // Lambertian: the cosine-weighted hemisphere on the side `wo` is on.
    let (h, h_pdf, h_ok): (V3, F, M) = lambert::sample(ux, uy);
    let lambert_ok = lambert & oriented & h_ok;
    let pdf = F::select(lambert, h_pdf, zero);
    // Mirror: `reflect_local` of wo on its side, then back (`Mirror::sample`).
    let mirrored = V3 {
        x: -wo.x,
        y: -wo.y,
        z: (wo.z * side) * side,
    };
    // Glass (`Dielectric::sample`): reflect with probability F, else refract.
    let (glass_wi, reflects, etap, glass_ok) = dielectric::sample(wo, eta, u1);
    let glass_ok = glass & glass_ok;
    let glass_reflects = glass & reflects;
    let scale = one / (etap * etap);
    let wi = V3::select(
        lambert,
        V3 {
            x: h.x,
            y: h.y,
            z: h.z * side,
        },
        V3::select(mirror, mirrored, glass_wi),
    );
    let weight = V3::select(
        lambert | mirror,
        colour,
        V3::select(
            glass_reflects,
            V3::splat([1.0; 3]),
            V3 {
                x: scale,
                y: scale,
                z: scale,
            },
        ),
    );
    let mut s = Sample {
        ok: lambert_ok | (mirror & oriented) | glass_ok,
        wi,
        weight,
        pdf,
        eta: F::select(glass & !reflects, etap, one),
        glossy: lambert,
    };
    if let Some(g) = general {
        let gs = g.sample(wo, [ux, uy, u1]);
        s.ok |= gs.ok;
        s.wi = V3::select(g.lanes, gs.wi, s.wi);
        s.weight = V3::select(g.lanes, gs.weight, s.weight);
        s.pdf = F::select(g.lanes, gs.pdf, s.pdf);
        s.eta = F::select(g.lanes, gs.eta, s.eta);
        s.glossy |= gs.glossy;
    }
    let Some(r) = rough else {
        return s;
    };
    s.glossy |= r.metal | r.glass | r.plastic;
    // Rough conductors on the side wo is on, and back (`Material::sample`'s flip).
    if r.metal.any() {
        let (wi, weight, pdf, ok) = r.conductor.sample_lanes(flip_z(wo, side), ux, uy);
        s.ok |= r.metal & oriented & ok;
        s.wi = V3::select(r.metal, flip_z(wi, side), s.wi);
        s.weight = V3::select(r.metal, weight, s.weight);
        s.pdf = F::select(r.metal, pdf, s.pdf);
    }
    // Rough plastics on the side wo is on, and back, as the conductors.
    if let Some(c) = &r.coated {
        let (wi, weight, pdf, ok) = c.sample_lanes(flip_z(wo, side), u1, ux, uy);
        s.ok |= r.plastic & oriented & ok;
        s.wi = V3::select(r.plastic, flip_z(wi, side), s.wi);
        s.weight = V3::select(r.plastic, weight, s.weight);
        s.pdf = F::select(r.plastic, pdf, s.pdf);
    }
    // Rough dielectrics, from either side.
    if r.glass.any() {
        let distr = &r.conductor.distr;
        let g = rough_dielectric::sample_lanes(distr, r.eta, wo, [u1, ux, uy], TransportMode::Radiance);
        let w = g.weight;
        s.ok |= r.glass & g.ok;
        s.wi = V3::select(r.glass, g.wi, s.wi);
        s.weight = V3::select(r.glass, V3 { x: w, y: w, z: w }, s.weight);
        s.pdf = F::select(r.glass, g.pdf, s.pdf);
        s.eta = F::select(r.glass, g.eta, s.eta);
    }
    s
}

/// `w` with its z times `side`: `Material`'s flip of a direction to the side the path is on
/// (x and y times one).
#[inline(always)]
pub fn flip_z(w: V3, side: F) -> V3 {
    V3 {
        x: w.x,
        y: w.y,
        z: w.z * side,
    }
}
