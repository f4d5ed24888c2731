//! Textured parameters: one mechanism for every BSDF parameter that may vary over a surface.
//!
//! A material's parameters are fields of its [`Bsdf`], filled with constants when the scene
//! is read. A parameter given by a texture is a [`Binding`]: the texture's index and a
//! [`Slot`], a plain function that writes a value into that field. At a hit,
//! [`Material::at`] copies the BSDF and runs each binding with the texture's value at the
//! hit's uv, so the integrators see an ordinary BSDF with constants; blends are resolved
//! there too ([`super::blend`]). A material without bindings or blends is copied as it is:
//! no per-hit work.
//!
//! A slot reads its texture as a colour ([`Slot::Color`], [`Texture::eval`]) or as a float
//! ([`Slot::Float`], [`Texture::eval_1`]: Mitsuba's `eval_1`, a bitmap's luminance). The
//! constant the BSDF is built with is the texture's mean ([`Texture::mean`] or
//! [`Texture::mean_1`]), so what a BSDF derives once from its parameters (plastic's
//! lobe-selection weight) takes the mean, as in Mitsuba.
//!
//! # Adding a textured parameter
//!
//! One line where the reader reads it: pass a slot, made by [`crate::slot!`] (the BSDF variant,
//! how the texture is read, the assignment) or one of [`slots`] (shared by the XML and TOML
//! readers, for fields several variants have), to the XML reader's `color_param` or
//! `float_param_opt` (src/scene/xml/params.rs), which binds a texture or returns the
//! constant:
//!
//! ```ignore
//! let r = self.color_param(&p, "specular_reflectance", 1.0, &mut slots,
//!     slot!(Color, RoughConductor, |b, v| b.specular_reflectance = v))?;
//! let w = self.float_param_opt(&p, "weight", &mut slots,
//!     slot!(Float, Blend, |b, v| b.weight = v))?;
//! ```
//!
//! and give the material its bindings (`Material::with_slots`). A value a slot writes must
//! leave the BSDF valid for any value the texture takes (clamp where the BSDF needs it).

use super::{normal_map, Bsdf, Material};
use crate::texture::Texture;
use crate::Color;
use glam::Vec2;

/// Where a texture's value goes: a function writing it into one field of a BSDF variant
/// (and doing nothing for other variants).
#[derive(Clone, Copy, Debug)]
pub enum Slot {
    /// Read as a colour ([`Texture::eval`]).
    Color(fn(&mut Bsdf, Color)),
    /// Read as a float ([`Texture::eval_1`]).
    Float(fn(&mut Bsdf, f32)),
}

/// A slot with the texture (an index into the scene's textures) that fills it.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub texture: u32,
    pub slot: Slot,
}

impl Binding {
    /// Writes the texture's value at `uv` into `bsdf`.
    #[inline]
    pub fn apply(&self, bsdf: &mut Bsdf, textures: &[Texture], uv: Vec2) {
        let t = &textures[self.texture as usize];
        match self.slot {
            Slot::Color(set) => set(bsdf, t.eval(uv)),
            Slot::Float(set) => set(bsdf, t.eval_1(uv)),
        }
    }
}

/// A [`Slot`] writing into a field of one [`Bsdf`] variant:
/// `slot!(Color | Float, Variant, |b, v| b.field = v)`, where `b` is the variant's struct
/// and `v` the texture's value (a `Color` or an `f32`).
#[macro_export]
macro_rules! slot {
    ($kind:ident, $variant:ident, |$b:ident, $v:ident| $body:expr) => {
        $crate::material::textured::Slot::$kind(|bsdf, $v| {
            if let $crate::material::Bsdf::$variant($b) = bsdf {
                $body;
            }
        })
    };
}

/// The slots of the parameters the scene readers bind, shared by them.
pub mod slots {
    use super::Slot;
    use crate::material::{Bsdf, Microfacet};

    /// The main colour of the BSDFs that have one (diffuse reflectance, or a metal's specular
    /// reflectance): what mcrt's TOML scenes may texture.
    pub const MAIN_COLOR: Slot = Slot::Color(|bsdf, c| match bsdf {
        Bsdf::Lambert(b) => b.albedo = c,
        Bsdf::OrenNayar(b) => b.albedo = c,
        Bsdf::Mirror(b) => b.reflectance = c,
        Bsdf::Conductor(b) => b.specular_reflectance = c,
        Bsdf::RoughConductor(b) => b.specular_reflectance = c,
        Bsdf::Plastic(b) => b.diffuse_reflectance = c,
        Bsdf::RoughPlastic(b) => b.diffuse_reflectance = c,
        Bsdf::Principled(b) => b.base_color = c,
        Bsdf::PrincipledThin(b) => b.base_color = c,
        _ => {}
    });

    /// Roughness slots of the rough conductor and dielectric (`alpha`, `alpha_u`, `alpha_v`).
    pub const ALPHA: Slot = Slot::Float(|bsdf, v| {
        if let Some(d) = distr_mut(bsdf) {
            d.set_alpha(v, v);
        }
    });
    pub const ALPHA_U: Slot = Slot::Float(|bsdf, v| {
        if let Some(d) = distr_mut(bsdf) {
            d.set_alpha_u(v);
        }
    });
    pub const ALPHA_V: Slot = Slot::Float(|bsdf, v| {
        if let Some(d) = distr_mut(bsdf) {
            d.set_alpha_v(v);
        }
    });

    fn distr_mut(bsdf: &mut Bsdf) -> Option<&mut Microfacet> {
        match bsdf {
            Bsdf::RoughConductor(b) => Some(&mut b.distr),
            Bsdf::RoughDielectric(b) => Some(&mut b.distr),
            _ => None,
        }
    }

    /// `specular_reflectance` of the conductors (a `conductor` of material "none" is a mirror).
    pub const CONDUCTOR_REFLECTANCE: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Mirror(b) => b.reflectance = v,
        Bsdf::Conductor(b) => b.specular_reflectance = v,
        Bsdf::RoughConductor(b) => b.specular_reflectance = v,
        _ => {}
    });

    /// A conductor's complex index of refraction η + ik (`eta`, `k`).
    pub const CONDUCTOR_ETA: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Conductor(b) => b.eta = v,
        Bsdf::RoughConductor(b) => b.eta = v,
        _ => {}
    });
    pub const CONDUCTOR_K: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Conductor(b) => b.k = v,
        Bsdf::RoughConductor(b) => b.k = v,
        _ => {}
    });

    /// `specular_reflectance` and `specular_transmittance` of the dielectrics.
    pub const DIELECTRIC_REFLECTANCE: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Dielectric(b) => b.specular_reflectance = v,
        Bsdf::ThinDielectric(b) => b.specular_reflectance = v,
        Bsdf::RoughDielectric(b) => b.specular_reflectance = v,
        _ => {}
    });
    pub const DIELECTRIC_TRANSMITTANCE: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Dielectric(b) => b.specular_transmittance = v,
        Bsdf::ThinDielectric(b) => b.specular_transmittance = v,
        Bsdf::RoughDielectric(b) => b.specular_transmittance = v,
        _ => {}
    });

    /// `diffuse_reflectance` and `specular_reflectance` of the plastics.
    pub const PLASTIC_DIFFUSE: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Plastic(b) => b.diffuse_reflectance = v,
        Bsdf::RoughPlastic(b) => b.diffuse_reflectance = v,
        _ => {}
    });
    pub const PLASTIC_SPECULAR: Slot = Slot::Color(|bsdf, v| match bsdf {
        Bsdf::Plastic(b) => b.specular_reflectance = v,
        Bsdf::RoughPlastic(b) => b.specular_reflectance = v,
        _ => {}
    });
}

impl Material {
    /// This material with `bindings` filling its textured parameters.
    pub fn with_slots(mut self, bindings: Vec<Binding>) -> Material {
        self.slots = bindings.into_boxed_slice();
        self
    }

    /// True when the BSDF differs from hit to hit: textured parameters, or a blend (whose
    /// parts may be textured and whose weight may be).
    #[inline]
    pub fn varies(&self) -> bool {
        !self.slots.is_empty() || matches!(self.bsdf, Bsdf::Blend(_))
    }

    /// The material at a hit with texture coordinates `uv`: its textured parameters
    /// evaluated there and its blends resolved into a mixture of their parts (`materials`
    /// and `textures`: the scene's), with the hit's `perturbed` normal (of a normal- or
    /// bump-mapped material). A material that does not vary is copied, built in one
    /// expression with `perturbed`: copied first and then given `perturbed`, it was stored
    /// in pieces and loaded back whole on its way to the caller, which the CPU's store
    /// forwarding cannot serve (about 1 % of the gallery's samples, `perf annotate`).
    #[inline]
    pub fn at(
        &self,
        materials: &[Material],
        textures: &[Texture],
        uv: Vec2,
        perturbed: Option<normal_map::Perturbed>,
    ) -> Material {
        if !self.varies() {
            return Material {
                slots: Box::default(),
                mix: None,
                perturbed,
                ..*self
            };
        }
        let mut m = self.resolve(materials, textures, uv);
        m.perturbed = perturbed;
        m
    }

    /// The BSDF with its textured parameters evaluated at `uv` (a blend unresolved).
    #[inline]
    pub(crate) fn bsdf_at(&self, textures: &[Texture], uv: Vec2) -> Bsdf {
        let mut bsdf = self.bsdf;
        for b in self.slots.iter() {
            b.apply(&mut bsdf, textures, uv);
        }
        bsdf
    }

    #[cold]
    fn resolve(&self, materials: &[Material], textures: &[Texture], uv: Vec2) -> Material {
        match self.bsdf_at(textures, uv) {
            Bsdf::Blend(blend) => {
                super::blend::resolve(blend, self.two_sided, materials, textures, uv)
            }
            bsdf => Material {
                bsdf,
                slots: Box::default(),
                mix: None,
                ..*self
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Lambert, Microfacet, MicrofacetType, RoughConductor};
    use crate::texture::UvTransform;

    fn checker(c0: f32, c1: f32) -> Texture {
        Texture::Checkerboard {
            color0: Color::splat(c0),
            color1: Color::splat(c1),
            to_uv: UvTransform::IDENTITY,
        }
    }

    /// A colour slot takes the texture's colour; a float slot its `eval_1` (the checkerboard's
    /// cells swapped, as Mitsuba's); the material without bindings is left alone.
    #[test]
    fn slots_fill_their_fields_per_hit() {
        let textures = vec![
            Texture::Checkerboard {
                color0: Color::new(0.9, 0.1, 0.1),
                color1: Color::new(0.1, 0.1, 0.9),
                to_uv: UvTransform::IDENTITY,
            },
            checker(0.5, 0.05),
        ];
        let base = Material::new(
            Bsdf::RoughConductor(RoughConductor::new(
                Microfacet::new(MicrofacetType::Ggx, 0.3, 0.3),
                Color::ZERO,
                Color::ONE,
                Color::ONE,
            )),
            false,
        );
        let m = base.clone().with_slots(vec![
            Binding {
                texture: 0,
                slot: slot!(Color, RoughConductor, |b, v| b.specular_reflectance = v),
            },
            Binding {
                texture: 1,
                slot: slot!(Float, RoughConductor, |b, v| b.distr.set_alpha(v, v)),
            },
        ]);
        assert!(m.varies() && !base.varies());
        let at = |u: f32, v: f32| match m.at(&[], &textures, Vec2::new(u, v), None).bsdf {
            Bsdf::RoughConductor(c) => (c.specular_reflectance, c.distr.alpha_u, c.distr.alpha_v),
            b => panic!("{b:?}"),
        };
        // Cell (¼, ¼): eval gives color0; eval_1 gives color1's float.
        assert_eq!(at(0.25, 0.25), (Color::new(0.9, 0.1, 0.1), 0.05, 0.05));
        assert_eq!(at(0.75, 0.25), (Color::new(0.1, 0.1, 0.9), 0.5, 0.5));
        // A material that does not vary comes back as it is.
        match base.at(&[], &textures, Vec2::new(0.75, 0.25), None).bsdf {
            Bsdf::RoughConductor(c) => assert_eq!(c.distr.alpha_u, 0.3),
            b => panic!("{b:?}"),
        }
        // A slot for another variant does nothing.
        let lambert = Material::new(
            Bsdf::Lambert(Lambert {
                albedo: Color::splat(0.2),
            }),
            false,
        )
        .with_slots(vec![Binding {
            texture: 0,
            slot: slot!(Color, RoughConductor, |b, v| b.specular_reflectance = v),
        }]);
        match lambert.at(&[], &textures, Vec2::ZERO, None).bsdf {
            Bsdf::Lambert(l) => assert_eq!(l.albedo, Color::splat(0.2)),
            b => panic!("{b:?}"),
        }
    }
}
