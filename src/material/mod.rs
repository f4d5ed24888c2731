//! Materials and their BSDFs.
//!
//! A closed enum, matched in the integrators' inner loops (no dynamic dispatch). All BSDFs
//! work in the local shading frame: z is the shading normal, `wo` points towards the viewer
//! (or the previous vertex) and `wi` towards the light; both are unit vectors.
//!
//! Parameters given by textures (colours, roughness, blend weights) are filled in per hit
//! by one mechanism, [`textured`]: a parameter is a field of the BSDF, and a texture bound
//! to it a [`Binding`] whose slot writes the texture's value there. Blends ([`blend`]) keep
//! their parts by material index and become a mixture at the hit.

pub mod blend;
pub mod conductor;
pub mod dielectric;
pub mod lambert;
pub mod microfacet;
pub mod mirror;
pub mod normal_map;
pub mod oren_nayar;
pub mod plastic;
pub mod principled;
pub mod principled_lobes;
pub mod principled_thin;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;
pub mod sampling;
pub mod textured;
pub mod thin_dielectric;

pub use blend::{Blend, MAX_BLEND_DEPTH};
pub use conductor::{conductor_ior, Conductor};
pub use dielectric::Dielectric;
pub use lambert::Lambert;
pub use microfacet::{Microfacet, MicrofacetType};
pub use mirror::Mirror;
pub use oren_nayar::OrenNayar;
pub use plastic::Plastic;
pub use principled::Principled;
pub use principled_thin::PrincipledThin;
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic::RoughPlastic;
pub use textured::{Binding, Slot};
pub use thin_dielectric::ThinDielectric;

use crate::Color;
use glam::{Vec2, Vec3A};

/// Whether a path carries radiance (from the camera) or importance (from the lights); only
/// refraction treats the two differently.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

/// The result of sampling a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3A,
    /// f(wo, wi)·|cos θi| / pdf: what the path throughput is multiplied by.
    pub weight: Color,
    /// Solid-angle pdf; 0 for delta (specular) samples.
    pub pdf: f32,
    pub specular: bool,
    /// Relative index of refraction crossed (1 for reflection).
    pub eta: f32,
}

#[derive(Clone, Copy, Debug)]
pub enum Bsdf {
    Lambert(Lambert),
    OrenNayar(OrenNayar),
    Mirror(Mirror),
    Dielectric(Dielectric),
    Conductor(Conductor),
    RoughConductor(RoughConductor),
    RoughDielectric(RoughDielectric),
    ThinDielectric(ThinDielectric),
    /// A delta lobe plus a diffuse one: not all-delta (`is_specular` is false).
    Plastic(Plastic),
    RoughPlastic(RoughPlastic),
    /// Mitsuba's `principled`: handles its own back side unless the material is two-sided.
    Principled(Principled),
    /// Mitsuba's `principledthin`: the same from both sides.
    PrincipledThin(PrincipledThin),
    /// Two BSDFs mixed by a weight, their parts by material index ([`blend`]): resolved per
    /// hit into [`Material::mix`]; as a BSDF of its own it reflects nothing.
    Blend(Blend),
    /// Absorbs everything (the back of a light, a black body).
    Black,
}

impl Bsdf {
    /// The microfacet distribution of a rough BSDF.
    pub fn microfacet(&self) -> Option<Microfacet> {
        match self {
            Bsdf::RoughConductor(b) => Some(b.distr),
            Bsdf::RoughDielectric(b) => Some(b.distr),
            Bsdf::RoughPlastic(b) => Some(b.distr),
            _ => None,
        }
    }
}

/// A BSDF and how it treats the back side of a surface.
///
/// A scene's materials hold constants and the bindings of their textured parameters; the
/// material at a hit ([`Material::at`]) holds the values there, and for a blend the mixture
/// of its parts.
#[derive(Clone, Debug)]
pub struct Material {
    pub bsdf: Bsdf,
    /// Reflective BSDFs on a one-sided material reflect nothing when seen from behind the
    /// geometric normal (Mitsuba's convention); two-sided ones reflect alike on both sides
    /// (pbrt's). Dielectrics have two sides by nature and ignore this.
    pub two_sided: bool,
    /// The textured parameters ([`textured`]); empty for a material of constants.
    pub slots: Box<[Binding]>,
    /// At a hit on a blend: its leaves and their weights ([`blend`]); the methods below
    /// then describe the mixture.
    pub mix: Option<Box<[blend::Part]>>,
    /// `normalmap`: an RGB texture of shading-frame normals ([`normal_map`]).
    pub normal_map: Option<u32>,
    /// `bumpmap`: a height texture and its scale ([`normal_map`]).
    pub bump: Option<normal_map::Bump>,
    /// `mask`: a texture whose value (clamped to [0, 1]) is the probability that a ray sees
    /// the surface at all ([`crate::scene::mask`]); None for opaque surfaces.
    pub opacity: Option<u32>,
    /// At a hit of a normal- or bump-mapped material ([`crate::scene::Scene::material_at`]):
    /// the unperturbed normal, which the BSDF's value and sampling weight depend on.
    pub perturbed: Option<normal_map::Perturbed>,
}

impl Material {
    pub fn new(bsdf: Bsdf, two_sided: bool) -> Self {
        Material {
            bsdf,
            two_sided,
            slots: Box::default(),
            mix: None,
            normal_map: None,
            bump: None,
            opacity: None,
            perturbed: None,
        }
    }

    /// Whether the material perturbs its shading normal (normal or bump map).
    #[inline]
    pub fn perturbs(&self) -> bool {
        self.normal_map.is_some() || self.bump.is_some()
    }

    /// Whether anything of the material varies with the texture coordinates of a hit.
    #[inline]
    pub fn reads_uv(&self) -> bool {
        self.varies() || self.perturbs() || self.opacity.is_some()
    }

    /// True when every scattering is a delta (mirror, glass, smooth metal, thin sheet): no
    /// light sampling there. Plastic mixes a delta lobe with a diffuse one and is not.
    #[inline]
    pub fn is_specular(&self) -> bool {
        if let Some(parts) = &self.mix {
            return parts.iter().all(|p| p.material.is_specular());
        }
        matches!(
            self.bsdf,
            Bsdf::Mirror(_) | Bsdf::Dielectric(_) | Bsdf::Conductor(_) | Bsdf::ThinDielectric(_)
        )
    }

    /// True for BSDFs that transmit as well as reflect (two-sided by nature), and the
    /// principled BSDF, which has a back side of its own unless wrapped in `twosided`.
    #[inline]
    fn is_transmissive(&self) -> bool {
        match self.bsdf {
            Bsdf::Dielectric(_)
            | Bsdf::RoughDielectric(_)
            | Bsdf::ThinDielectric(_)
            | Bsdf::PrincipledThin(_) => true,
            Bsdf::Principled(_) => !self.two_sided,
            _ => false,
        }
    }

    #[inline]
    pub fn is_black(&self) -> bool {
        matches!(self.bsdf, Bsdf::Black)
    }

    /// For reflective BSDFs, maps a direction pair seen from the back into the front
    /// hemisphere. Returns None when the one-sided surface is seen from behind.
    #[inline]
    pub(crate) fn orient(&self, wo: Vec3A) -> Option<f32> {
        if self.is_transmissive() {
            return Some(1.0);
        }
        if wo.z > 0.0 {
            Some(1.0)
        } else if wo.z < 0.0 && self.two_sided {
            Some(-1.0)
        } else {
            None
        }
    }

    /// f(wo, wi), without the cosine, for radiance transport (what the path tracer needs).
    /// Zero for delta BSDFs; for plastic, only its non-delta part.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        self.eval_mode(wo, wi, TransportMode::Radiance)
    }

    /// f(wo, wi) in either transport mode (only rough refraction tells them apart).
    #[inline]
    pub fn eval_mode(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Color {
        match &self.perturbed {
            None => self.eval_nested(wo, wi, mode),
            Some(p) => {
                let f = p.factor(wi);
                if f == 0.0 {
                    Color::ZERO
                } else {
                    f * self.eval_nested(wo, wi, mode)
                }
            }
        }
    }

    /// [`Material::eval_mode`] of the BSDF itself, in the (perturbed) shading frame.
    #[inline]
    fn eval_nested(&self, wo: Vec3A, wi: Vec3A, mode: TransportMode) -> Color {
        if let Some(parts) = &self.mix {
            return blend::eval_pdf(parts, wo, wi, mode).0;
        }
        if let Bsdf::RoughDielectric(b) = &self.bsdf {
            return b.eval(wo, wi, mode);
        }
        let Some(s) = self.orient(wo) else {
            return Color::ZERO;
        };
        let flip = Vec3A::new(1.0, 1.0, s);
        let (wo, wi) = (wo * flip, wi * flip);
        match &self.bsdf {
            Bsdf::Lambert(b) => b.eval(wo, wi),
            Bsdf::OrenNayar(b) => b.eval(wo, wi),
            Bsdf::RoughConductor(b) => b.eval(wo, wi),
            Bsdf::Plastic(b) => b.eval(wo, wi),
            Bsdf::RoughPlastic(b) => b.eval(wo, wi),
            Bsdf::Principled(b) => b.eval(wo, wi, mode),
            Bsdf::PrincipledThin(b) => b.eval(wo, wi),
            _ => Color::ZERO,
        }
    }

    /// f(wo, wi) for radiance transport and the pdf of sampling `wi`, with one orientation
    /// test and one match: what next-event estimation needs for each shadow ray.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3A, wi: Vec3A) -> (Color, f32) {
        match &self.perturbed {
            None => self.eval_pdf_nested(wo, wi),
            Some(p) => {
                let f = p.factor(wi);
                if f == 0.0 {
                    return (Color::ZERO, 0.0);
                }
                let (v, pdf) = self.eval_pdf_nested(wo, wi);
                (f * v, pdf)
            }
        }
    }

    #[inline(always)]
    fn eval_pdf_nested(&self, wo: Vec3A, wi: Vec3A) -> (Color, f32) {
        if let Some(parts) = &self.mix {
            return blend::eval_pdf(parts, wo, wi, TransportMode::Radiance);
        }
        if let Bsdf::RoughDielectric(b) = &self.bsdf {
            return (b.eval(wo, wi, TransportMode::Radiance), b.pdf(wo, wi));
        }
        let Some(s) = self.orient(wo) else {
            return (Color::ZERO, 0.0);
        };
        let flip = Vec3A::new(1.0, 1.0, s);
        let (wo, wi) = (wo * flip, wi * flip);
        match &self.bsdf {
            Bsdf::Lambert(b) => (b.eval(wo, wi), b.pdf(wo, wi)),
            Bsdf::OrenNayar(b) => (b.eval(wo, wi), b.pdf(wo, wi)),
            Bsdf::RoughConductor(b) => (b.eval(wo, wi), b.pdf(wo, wi)),
            Bsdf::Plastic(b) => (b.eval(wo, wi), b.pdf(wo, wi)),
            Bsdf::RoughPlastic(b) => b.eval_pdf(wo, wi),
            Bsdf::Principled(b) => {
                let (f, pdf) = b.eval_cos_pdf(wo, wi, TransportMode::Radiance);
                (if wi.z == 0.0 { f } else { f / wi.z.abs() }, pdf)
            }
            Bsdf::PrincipledThin(b) => (b.eval(wo, wi), b.pdf(wo, wi)),
            _ => (Color::ZERO, 0.0),
        }
    }

    /// Solid-angle pdf of sampling `wi` given `wo`. Zero for delta BSDFs.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match &self.perturbed {
            Some(p) if p.factor(wi) == 0.0 => 0.0,
            _ => self.pdf_nested(wo, wi),
        }
    }

    #[inline]
    fn pdf_nested(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if let Some(parts) = &self.mix {
            return blend::eval_pdf(parts, wo, wi, TransportMode::Radiance).1;
        }
        if let Bsdf::RoughDielectric(b) = &self.bsdf {
            return b.pdf(wo, wi);
        }
        let Some(s) = self.orient(wo) else { return 0.0 };
        let flip = Vec3A::new(1.0, 1.0, s);
        let (wo, wi) = (wo * flip, wi * flip);
        match &self.bsdf {
            Bsdf::Lambert(b) => b.pdf(wo, wi),
            Bsdf::OrenNayar(b) => b.pdf(wo, wi),
            Bsdf::RoughConductor(b) => b.pdf(wo, wi),
            Bsdf::Plastic(b) => b.pdf(wo, wi),
            Bsdf::RoughPlastic(b) => b.pdf(wo, wi),
            Bsdf::Principled(b) => b.pdf(wo, wi),
            Bsdf::PrincipledThin(b) => b.pdf(wo, wi),
            _ => 0.0,
        }
    }

    /// Samples wi. `u1` picks among lobes (reflection or refraction), `u2` the direction.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let mut bs = self.sample_nested(wo, u1, u2, mode)?;
        if let Some(p) = &self.perturbed {
            let f = p.factor(bs.wi);
            if f == 0.0 {
                return None;
            }
            bs.weight *= f;
        }
        Some(bs)
    }

    #[inline(always)]
    fn sample_nested(
        &self,
        wo: Vec3A,
        u1: f32,
        u2: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        if let Some(parts) = &self.mix {
            return blend::sample(parts, wo, u1, u2, mode);
        }
        let s = self.orient(wo)?;
        let flip = Vec3A::new(1.0, 1.0, s);
        let wo_f = wo * flip;
        let mut bs = match &self.bsdf {
            Bsdf::Lambert(b) => b.sample(wo_f, u2),
            Bsdf::OrenNayar(b) => b.sample(wo_f, u2),
            Bsdf::Mirror(b) => b.sample(wo_f),
            Bsdf::Dielectric(b) => return b.sample(wo, u1, mode),
            Bsdf::Conductor(b) => b.sample(wo_f),
            Bsdf::RoughConductor(b) => b.sample(wo_f, u2),
            Bsdf::RoughDielectric(b) => return b.sample(wo, u1, u2, mode),
            Bsdf::ThinDielectric(b) => return b.sample(wo, u1),
            Bsdf::Plastic(b) => b.sample(wo_f, u1, u2),
            Bsdf::RoughPlastic(b) => b.sample(wo_f, u1, u2),
            Bsdf::Principled(b) => b.sample(wo_f, u1, u2, mode),
            Bsdf::PrincipledThin(b) => b.sample(wo_f, u1, u2),
            Bsdf::Blend(_) | Bsdf::Black => None,
        }?;
        bs.wi *= flip;
        Some(bs)
    }

    /// The directional-hemispherical reflectance at normal incidence, roughly: the colour a
    /// denoiser or photon tracer takes as the surface's albedo.
    pub fn albedo(&self) -> Color {
        if let Some(parts) = &self.mix {
            return blend::albedo(parts);
        }
        match &self.bsdf {
            Bsdf::Lambert(b) => b.albedo,
            Bsdf::OrenNayar(b) => b.albedo,
            Bsdf::Mirror(b) => b.reflectance,
            Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_) | Bsdf::ThinDielectric(_) => Color::ONE,
            Bsdf::Conductor(b) => b.reflectance(1.0),
            Bsdf::RoughConductor(b) => {
                b.specular_reflectance * conductor::fresnel_conductor_rgb(1.0, b.eta, b.k)
            }
            // The coating's specular reflectance at normal incidence plus the base seen
            // through it.
            Bsdf::Plastic(b) => {
                let f0 = dielectric::fresnel_dielectric(1.0, b.eta);
                b.specular_reflectance * f0 + b.diffuse_reflectance * (1.0 - f0)
            }
            Bsdf::RoughPlastic(b) => {
                let f0 = dielectric::fresnel_dielectric(1.0, b.eta);
                b.specular_reflectance * f0 + b.diffuse_reflectance * (1.0 - f0)
            }
            // Mitsuba's `eval_diffuse_reflectance`.
            Bsdf::Principled(b) => b.base_color,
            Bsdf::PrincipledThin(b) => b.base_color,
            Bsdf::Blend(_) | Bsdf::Black => Color::ZERO,
        }
    }
}
