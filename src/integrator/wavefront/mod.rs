//! The path tracer sixteen paths at a time, on CPUs with AVX-512 or AVX2.
//!
//! [`super::path::li`] follows one path at a time: its arithmetic on three-component vectors
//! fills three lanes of a four-lane register, and its branches (which material, whether the
//! light sample counts, whether roulette ends the path) vary from path to path. Here sixteen
//! paths advance together, a lane each, in the manner of a wavefront renderer (Laine, Karras
//! and Aila, "Megakernels Considered Harmful: Wavefront Path Tracing on GPUs", HPG 2013;
//! Mitsuba 3's `llvm` variants): every step finds all sixteen rays' hits ([`Trace`]), shades
//! them, samples the light for all of them and traces their shadow rays ([`nee`]), samples
//! their BSDFs ([`bsdf`]) and plays their roulette ([`path`]), with the branches turned into
//! lane masks. A lane whose path ends takes the tile's next camera sample at the next step,
//! so the lanes stay full until the tile runs out of samples. With one light sample a
//! vertex, a tile keeps several groups of sixteen paths in flight (`lanes::POOL` by brute
//! force, `lanes::GROUPS` through the scene) and traces the shadow rays of each pool of
//! groups together, packed sixteen to a vector (each group's rays fill about half of one): a
//! step is [`Wavefront::front`] for every group, [`Wavefront::shadows`] for every pool, then
//! [`Wavefront::back`] for every group.
//!
//! The hits come one of two ways ([`Trace`]). Where the path tracer itself traces single rays
//! by brute force (`accel::flat`: at most 64 triangles and 4 spheres) and the triangles carry
//! no vertex normals, the lanes test all sixteen rays against each primitive in turn
//! (`Flat::closest_lanes`: the brute force's own rules, in lanes) and look up shading data
//! by primitive in tables of 64. Everywhere else the lanes' rays go to the scene's own
//! queries: the camera rays, which share the eye, in packets of sixteen
//! (`Scene::intersect_packet`), the others of all groups in one call
//! (`Scene::intersect_many`), both with `Scene::intersect`'s answers (the BVH, instances,
//! masks), and the lanes take each hit's point and normals from its `Interaction`, with the
//! shading data by material; the shadow rays go to `Scene::occluded_many` likewise.
//!
//! Each lane computes exactly what `path::li` computes for its camera sample: the same
//! numbers from the same sampler ([`rng`]), the same hits, and the same shading maths, which
//! is written once over the lane traits of [`crate::simd`] (frames, warps, Fresnel,
//! refraction, MIS, ray offsets, hit points, light samples, the Lambertian, glass, rough
//! conductor, rough dielectric and rough plastic BSDFs) and instanced here with sixteen
//! lanes, there with
//! one, or is the path tracer's own `Material` called a lane at a time ([`general`]). A
//! sample's value is therefore the same
//! bits whichever of the two renders it, and so is the image (the film's fixed-point sums do
//! not depend on the order samples arrive in): on any CPU, any thread count, any split into
//! passes or machines. `tests/wavefront.rs` compares the two on scenes that take every
//! branch (what is still the lanes' own: the brute-force traversal, the material dispatch by
//! masks, the roulette).
//!
//! The scenes it takes ([`Wavefront::new`]): any material, any lights, any camera (a
//! pinhole's rays made in the lanes, the others' by each lane's `Camera`), either sampler;
//! the `path` integrator with any number of light samples a vertex ([`nee`]). One planar
//! light (a triangle or a parallelogram of constant radiance) the lanes sample in their
//! registers; any other lights (several, spheres, meshes, textured, point, spot,
//! directional, environments) each lane asks of `Lights`, a lane at a time, with the path
//! tracer's own functions ([`lights`]), and those scenes are traced through the scene's
//! queries. The lanes shade in their registers the Lambertian, mirror, smooth glass, rough
//! conductor, rough glass (Beckmann or GGX, isotropic or not; glass of unit factors), rough
//! plastic (each lane reading its coating's table) and black materials, their colours
//! constant or textured (looked up at each hit as `Scene::material_at` does, so not with
//! brute force; a rough material's not), with no normal or bump map; every other material
//! (`GENERAL`: the smooth plastic, principled, Oren–Nayar, smooth conductors, blends, maps,
//! textured roughness and rough materials' textured colours) by calling each lane's
//! `Material` ([`general`]), which brute force takes where it is the same at every hit.
//! Other integrators, and any CPU without AVX2, BMI1, BMI2 and POPCNT, render with the
//! stream ([`super::stream`]) or `path::li`.
//!
//! The lanes' code is written once over a small SIMD type of sixteen lanes and compiled
//! twice ([`Backend`]): in one AVX-512 register ([`avx512`]) and in two AVX2 registers
//! ([`avx2`], for CPUs without AVX-512, where Mitsuba's `llvm` variants run eight lanes
//! wide too). Both compute every lane's IEEE operations in the scalar code's order, so the
//! same bits.

mod avx2;
mod avx512;

use crate::accel::flat::Flat;
use crate::camera::Camera;
use crate::film::PixelSums;
use crate::integrator::{IntegratorKind, RussianRoulette};
use crate::material::{Bsdf, MicrofacetType, RoughPlastic};
use crate::render::{self, RenderSettings, RenderStats, TilePixel};
use crate::sampler::SamplerKind;
use crate::scene::{Scene, META_EMITTER, META_MATERIAL, SPHERE};

/// Lanes as the lanes' state keeps them between steps and loops over them: bit i for lane i.
pub(crate) type Bits = u16;

/// A mask of sixteen lanes as the lanes' code reads it: its bits (bit i for lane i), and
/// from bits. The AVX-512 backend's masks are the bits themselves (`u16`, its `k`
/// registers); the AVX2 backend's are vector masks, which these convert.
pub(crate) trait LaneMask: Copy {
    fn bits(self) -> Bits;
    fn from_bits(bits: Bits) -> Self;
    /// Whether any lane is set.
    fn any(self) -> bool {
        self.bits() != 0
    }
    /// No lane set.
    #[inline(always)]
    fn none() -> Self {
        Self::from_bits(0)
    }
    /// How many lanes are set.
    #[inline(always)]
    fn count(self) -> u32 {
        self.bits().count_ones()
    }
}

impl LaneMask for Bits {
    #[inline(always)]
    fn bits(self) -> Bits {
        self
    }
    #[inline(always)]
    fn from_bits(bits: Bits) -> Bits {
        bits
    }
    #[inline(always)]
    fn any(self) -> bool {
        self != 0
    }
}

/// Most primitives the wavefront traces (by brute force, as `accel::flat` does).
pub const MAX_PRIMS: usize = 64;

/// `flags` of a primitive: its material's kind in the low three bits...
const KIND: u32 = 7;
const LAMBERT: u32 = 0;
const MIRROR: u32 = 1;
const GLASS: u32 = 2;
const BLACK: u32 = 3;
/// A rough conductor, a rough dielectric, any other material (its `Material` called a lane
/// at a time: [`general`]), a rough plastic...
const ROUGH: u32 = 4;
const ROUGH_GLASS: u32 = 5;
const GENERAL: u32 = 6;
const ROUGH_PLASTIC: u32 = 7;
/// ...whether it is two-sided, whether it emits, and whether a rough material's microfacets
/// are Beckmann's (else GGX).
const TWO_SIDED: u32 = 8;
const EMITTER: u32 = 16;
const BECKMANN: u32 = 32;

/// A scene prepared for sixteen paths at a time: how its rays are traced, and what shading
/// reads, per primitive in tables of 64 for lane lookups (brute force) or per material.
pub struct Wavefront<'a> {
    scene: &'a Scene,
    /// How the lanes find their hits.
    trace: Trace,
    /// With [`Trace::Scene`], each material's flags (`KIND`, `TWO_SIDED`; `EMITTER` comes
    /// from the hit's light), colour and η, by material index.
    materials: Vec<Shading>,
    /// With [`Trace::Lanes`], the scene's brute-force set, which the lanes trace.
    flat: Option<&'a Flat>,
    /// Triangles: vertices and unit geometric normal (also the shading normal: no vertex
    /// normals here). Spheres: centre (in `p0`) and radius.
    p0: [[f32; 64]; 3],
    p1: [[f32; 64]; 3],
    p2: [[f32; 64]; 3],
    ng: [[f32; 64]; 3],
    radius: [f32; 64],
    /// The material's colour (Lambertian albedo, mirror and rough conductor reflectance)
    /// and relative index of refraction (glass).
    colour: [[f32; 64]; 3],
    eta: [f32; 64],
    flags: [u32; 64],
    /// A rough conductor's roughness and complex index of refraction.
    rough: RoughTables,
    /// The rough plastics' coating transmittance tables, one after another (`Coat::first`).
    coatings: Vec<f32>,
    /// Each `GENERAL` material as every hit sees it, where that is the same at every hit
    /// (no texture, blend, normal or bump map), by material index.
    resolved: Vec<Option<crate::material::Material>>,
    /// The scene's light where it has one light, planar, which the lanes sample in their
    /// registers; None for any other lights, which each lane asks `Lights` for ([`lights`]).
    light: Option<Light>,
    max_depth: u32,
    rr: RussianRoulette,
    hide_emitters: bool,
    shadow_rays: u32,
    sampler: SamplerKind,
    seed: u64,
    width: u32,
    backend: Backend,
}

/// The instruction set the lanes run on: sixteen lanes in one AVX-512 register, or in two
/// AVX2 registers (the same arithmetic, lane for lane, so the same bits).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Backend {
    Avx512,
    Avx2,
}

impl Backend {
    /// The lanes the render settings ask for, if this CPU runs them: with
    /// [`render::Backend::Auto`] the best it has.
    fn detect(asked: render::Backend) -> Option<Backend> {
        let (avx512, avx2) = match asked {
            render::Backend::Auto => (true, true),
            render::Backend::Scalar | render::Backend::Stream => (false, false),
            render::Backend::Avx512 => (true, false),
            render::Backend::Avx2 => (false, true),
        };
        if avx512
            && crate::cpu::avx512()
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("bmi2")
        {
            Some(Backend::Avx512)
        } else if avx2
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            Some(Backend::Avx2)
        } else {
            None
        }
    }
}

/// How the lanes find their hits and answer their shadow rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Trace {
    /// Sixteen rays against every primitive in turn ([`trace`]), with shading data looked
    /// up by primitive: where the path tracer itself traces single rays by brute force
    /// (`accel::flat`) and the triangles carry no vertex normals.
    Lanes,
    /// Each lane's ray by the scene's own queries (`Scene::intersect`, `Scene::occluded`:
    /// the BVH, instances, masks), its hit's point and normals from the scene's
    /// `Interaction`, as the path tracer gets them: any other scene.
    Scene,
}

/// What the lanes read of a material: the flags of a primitive (`KIND`, `TWO_SIDED`), the
/// colour (Lambertian albedo, mirror and rough conductor reflectance), relative index of
/// refraction (glass) and a rough conductor's parameters; whether the colour is a
/// texture's, to be looked up at each hit ([`Trace::Scene`] only), and whether the material
/// is an opacity mask (which the scene's queries see through).
#[derive(Clone, Copy, Debug)]
struct Shading {
    flags: u32,
    colour: [f32; 3],
    eta: f32,
    rough: Rough,
    coat: Coat,
    textured: bool,
    masked: bool,
}

/// A rough conductor's roughness (as `Microfacet::new` clamps it) and complex index of
/// refraction η + ik; other materials' are never read (those of a smooth surface).
#[derive(Clone, Copy, Debug)]
struct Rough {
    alpha: [f32; 2],
    eta: [f32; 3],
    k: [f32; 3],
}

impl Rough {
    const NONE: Rough = Rough {
        alpha: [1.0; 2],
        eta: [0.0; 3],
        k: [1.0; 3],
    };
}

/// A rough plastic's coating (its roughness is its [`Rough`]'s, its η and diffuse
/// reflectance the material's `eta` and `colour`), as `rough_plastic::Coated` reads it;
/// other materials' are never read.
#[derive(Clone, Copy, Debug)]
struct Coat {
    specular: [f32; 3],
    nonlinear: bool,
    weight: f32,
    inv_eta2: f32,
    /// Where its transmittance table starts in [`Wavefront::coatings`]...
    first: f32,
    /// ...and that table, until it is placed there.
    table: &'static [f32],
    internal_reflectance: f32,
}

impl Coat {
    const NONE: Coat = Coat {
        specular: [0.0; 3],
        nonlinear: false,
        weight: 0.0,
        inv_eta2: 1.0,
        first: 0.0,
        table: &[],
        internal_reflectance: 0.0,
    };

    /// A rough plastic's, its table yet to be placed.
    fn of(b: &RoughPlastic) -> Coat {
        let c = b.coated();
        Coat {
            specular: c.specular_reflectance.into(),
            nonlinear: c.nonlinear,
            weight: c.specular_sampling_weight,
            inv_eta2: c.inv_eta2,
            first: 0.0,
            table: c.transmittance,
            internal_reflectance: c.internal_reflectance,
        }
    }
}

/// [`Rough`] by primitive, for [`Trace::Lanes`]' lookups.
struct RoughTables {
    alpha: [[f32; 64]; 2],
    eta: [[f32; 64]; 3],
    k: [[f32; 64]; 3],
}

impl RoughTables {
    fn set(&mut self, j: usize, r: &Rough) {
        for c in 0..3 {
            (self.eta[c][j], self.k[c][j]) = (r.eta[c], r.k[c]);
        }
        (self.alpha[0][j], self.alpha[1][j]) = (r.alpha[0], r.alpha[1]);
    }
}

impl Shading {
    /// The material as the lanes shade it: in their registers a Lambertian, a mirror, smooth
    /// or rough glass of unit factors, a rough conductor, or black, their colours constant
    /// or textured (not a rough material's or glass's), with no normal or bump map; any
    /// other as `GENERAL`, textured where anything of it varies from hit to hit.
    fn of(material: &crate::material::Material) -> Shading {
        let textured = !material.slots.is_empty();
        let general = Shading {
            flags: GENERAL,
            colour: [0.0; 3],
            eta: 1.0,
            rough: Rough::NONE,
            coat: Coat::NONE,
            textured: material.varies() || material.perturbs(),
            masked: material.opacity.is_some(),
        };
        let Some((kind, colour, eta)) = Self::bsdf(&material.bsdf) else {
            return general;
        };
        // (Glass's textured factors would not be the unit ones the lanes assume, and a
        // rough material's textured roughness is not looked up.)
        if material.perturbs()
            || textured && matches!(kind, GLASS | ROUGH | ROUGH_GLASS | ROUGH_PLASTIC)
        {
            return general;
        }
        let (rough, distr) = match &material.bsdf {
            Bsdf::RoughConductor(b) => (
                Rough {
                    alpha: [b.distr.alpha_u, b.distr.alpha_v],
                    eta: b.eta.into(),
                    k: b.k.into(),
                },
                Some(b.distr),
            ),
            Bsdf::RoughDielectric(b) => (
                Rough {
                    alpha: [b.distr.alpha_u, b.distr.alpha_v],
                    ..Rough::NONE
                },
                Some(b.distr),
            ),
            Bsdf::RoughPlastic(b) => (
                Rough {
                    alpha: [b.distr.alpha_u, b.distr.alpha_v],
                    ..Rough::NONE
                },
                Some(b.distr),
            ),
            _ => (Rough::NONE, None),
        };
        let coat = match &material.bsdf {
            Bsdf::RoughPlastic(b) => Coat::of(b),
            _ => Coat::NONE,
        };
        let two_sided = if material.two_sided { TWO_SIDED } else { 0 };
        let beckmann = match distr {
            Some(d) if d.kind == MicrofacetType::Beckmann => BECKMANN,
            _ => 0,
        };
        Shading {
            flags: kind | two_sided | beckmann,
            colour,
            eta,
            rough,
            coat,
            textured,
            masked: material.opacity.is_some(),
        }
    }

    /// The kind, colour and η of a BSDF the lanes shade (a blend is not one of them).
    #[inline(always)]
    fn bsdf(bsdf: &Bsdf) -> Option<(u32, [f32; 3], f32)> {
        let (kind, colour, eta) = match bsdf {
            Bsdf::Lambert(b) => (LAMBERT, b.albedo, 1.0),
            Bsdf::Mirror(b) => (MIRROR, b.reflectance, 1.0),
            Bsdf::RoughConductor(b) => (ROUGH, b.specular_reflectance, 1.0),
            Bsdf::RoughPlastic(b) => (ROUGH_PLASTIC, b.diffuse_reflectance, b.eta),
            // (Rough glass of factors other than 1 takes the scalar path.)
            Bsdf::RoughDielectric(b)
                if b.specular_reflectance == crate::Color::ONE
                    && b.specular_transmittance == crate::Color::ONE =>
            {
                (ROUGH_GLASS, crate::Color::ONE, b.eta)
            }
            Bsdf::Dielectric(b) => {
                // (Glass with factors other than 1 takes the scalar path.)
                if b.specular_reflectance != crate::Color::ONE
                    || b.specular_transmittance != crate::Color::ONE
                {
                    return None;
                }
                (GLASS, crate::Color::ONE, b.eta)
            }
            Bsdf::Black => (BLACK, crate::Color::ZERO, 1.0),
            _ => return None,
        };
        Some((kind, colour.into(), eta))
    }

    /// The colour at a hit with texture coordinates `uv` on `material` (this one's): its
    /// textured parameters evaluated there, as `Scene::material_at` evaluates them.
    #[inline(always)]
    fn colour_at(
        &self,
        material: &crate::material::Material,
        textures: &[crate::texture::Texture],
        uv: glam::Vec2,
    ) -> [f32; 3] {
        if !self.textured || self.flags & KIND == GENERAL {
            return self.colour;
        }
        Self::bsdf(&material.bsdf_at(textures, uv)).map_or(self.colour, |(_, c, _)| c)
    }
}

/// The rough plastics' coating tables one after another, each once (plastics of one
/// distribution, α and η share theirs), and each plastic's `Coat::first` set to where its
/// table starts.
fn place_coatings(materials: &mut [Shading]) -> Vec<f32> {
    let mut all = Vec::new();
    let mut placed: Vec<(*const f32, f32)> = Vec::new();
    for c in materials
        .iter_mut()
        .map(|m| &mut m.coat)
        .filter(|c| !c.table.is_empty())
    {
        let at = c.table.as_ptr();
        c.first = match placed.iter().find(|p| p.0 == at) {
            Some(&(_, first)) => first,
            None => {
                let first = all.len() as f32;
                all.extend_from_slice(c.table);
                placed.push((at, first));
                first
            }
        };
    }
    all
}

/// The scene's one light, as `Lights::sample` and `Lights::pdf` read it.
#[derive(Clone, Copy)]
struct Light {
    /// A point is `a + b·u + c·v` (parallelogram) or `a·w + b·u + c·v` (triangle).
    a: [f32; 3],
    b: [f32; 3],
    c: [f32; 3],
    triangle: bool,
    normal: [f32; 3],
    /// `offset_ray_origin`'s push off the light (`PlanarLight::offset`).
    offset: [f32; 3],
    area: f32,
    radiance: [f32; 3],
    /// Its probability in `Lights::pdf` (the distribution's, over the one light).
    pmf: f32,
}

impl<'a> Wavefront<'a> {
    /// The wavefront for rendering `scene` with `s`, if the scene, the settings and the CPU
    /// are ones it takes (see the module comment); None otherwise.
    pub fn new(scene: &'a Scene, s: &RenderSettings) -> Option<Wavefront<'a>> {
        let backend = Backend::detect(s.backend)?;
        let p = &s.params;
        // (No shadow ray at all is refused by the settings; through the library it would
        // make `sample_lights` divide by zero, which the lanes do not copy.)
        if p.kind != IntegratorKind::Path || p.max_depth == Some(0) || p.shadow_rays == 0 {
            return None;
        }
        let planar = scene.lights.single_planar();
        let mut materials: Vec<Shading> = scene.materials.iter().map(Shading::of).collect();
        let coatings = place_coatings(&mut materials);
        // (The lanes index the tables in f32, exact below 2²⁴.)
        if coatings.len() >= 1 << 24 {
            return None;
        }
        let resolved = (scene.materials.iter().zip(&materials))
            .map(|(m, sh)| {
                (sh.flags & KIND == GENERAL && !sh.textured)
                    .then(|| m.at(&scene.materials, &scene.textures, glam::Vec2::ZERO, None))
            })
            .collect();
        let mut w = Wavefront {
            scene,
            trace: Trace::Scene,
            materials,
            flat: None,
            p0: [[0.0; 64]; 3],
            p1: [[0.0; 64]; 3],
            p2: [[0.0; 64]; 3],
            ng: [[0.0; 64]; 3],
            radius: [0.0; 64],
            colour: [[0.0; 64]; 3],
            eta: [1.0; 64],
            flags: [0; 64],
            rough: RoughTables {
                alpha: [[1.0; 64]; 2],
                eta: [[0.0; 64]; 3],
                k: [[1.0; 64]; 3],
            },
            coatings,
            resolved,
            light: planar.map(|planar| Light {
                a: planar.a.into(),
                b: planar.b.into(),
                c: planar.c.into(),
                triangle: planar.triangle,
                normal: planar.normal.into(),
                offset: planar.offset.into(),
                area: planar.area,
                radiance: planar.radiance.into(),
                pmf: scene.lights.pmf(0),
            }),
            max_depth: p.max_depth.unwrap_or(u32::MAX),
            rr: p.rr,
            hide_emitters: p.hide_emitters,
            shadow_rays: p.shadow_rays,
            sampler: s.sampler,
            seed: s.seed,
            width: s.width,
            backend,
        };
        if w.fill_tables() {
            w.trace = Trace::Lanes;
            w.flat = scene.flat.as_deref();
        }
        Some(w)
    }

    /// Whether the lanes trace the scene by brute force ([`Trace::Lanes`]) rather than
    /// through its own queries: for the tests and benchmarks.
    pub fn is_brute_force(&self) -> bool {
        self.trace == Trace::Lanes
    }

    /// Fills the per-primitive tables that [`Trace::Lanes`] reads, if the scene is one it
    /// takes: one the path tracer traces by brute force too (`accel::flat`: at most
    /// [`MAX_PRIMS`] primitives), since elsewhere it uses the BVH, which for a grazing ray
    /// may skip a primitive brute force would test; with no vertex normals (the lanes shade
    /// with the face's), no textures, no instances, no emitting or inward-facing spheres, and
    /// one planar light (other lights read each hit's `Interaction`).
    fn fill_tables(&mut self) -> bool {
        let scene = self.scene;
        let n = scene.tris.len();
        if n == 0
            || self.light.is_none()
            || n > MAX_PRIMS
            || !scene.is_flat()
            || !scene.attrs.is_empty()
            || scene.instances.is_some()
        {
            return false;
        }
        for (j, &idx) in scene.tris.iter().enumerate() {
            let meta = scene.meta[j];
            let m = self.materials[(meta & META_MATERIAL) as usize];
            // (Brute force reads no texture coordinates and sees every surface.)
            if m.textured || m.masked {
                return false;
            }
            let mut flags = m.flags;
            for c in 0..3 {
                self.colour[c][j] = m.colour[c];
            }
            self.eta[j] = m.eta;
            self.rough.set(j, &m.rough);
            if idx[0] == SPHERE {
                // (Emitting spheres are lights of their own: no scene here has one.)
                if meta & META_EMITTER != 0 || scene.sphere_frames[idx[1] as usize].flip {
                    return false;
                }
                let sphere = scene.spheres[idx[1] as usize];
                for c in 0..3 {
                    self.p0[c][j] = sphere.center[c];
                }
                self.radius[j] = sphere.radius;
                self.flags[j] = flags;
                continue;
            }
            if meta & META_EMITTER != 0 {
                flags |= EMITTER;
            }
            self.flags[j] = flags;
            let tri = scene.triangle(idx);
            // As `Scene::interaction` computes it.
            let ng = tri.normal_unnormalized().normalize();
            for c in 0..3 {
                self.p0[c][j] = tri.p0[c];
                self.p1[c][j] = tri.p1[c];
                self.p2[c][j] = tri.p2[c];
                self.ng[c][j] = ng[c];
            }
        }
        true
    }

    /// Renders the samples of one tile's pixels into their sums: pixel k's samples
    /// `pixels[k].samples`, added to `sums[k]`.
    pub fn render_tile(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        assert_eq!(pixels.len(), sums.len());
        // SAFETY: `new` found the backend's features on this CPU.
        unsafe {
            match self.backend {
                Backend::Avx512 => avx512::Wavefront(self).render(camera, pixels, sums, stats),
                Backend::Avx2 => avx2::Wavefront(self).render(camera, pixels, sums, stats),
            }
        }
    }
}
