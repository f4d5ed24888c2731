//! BSDF parameters that may be textures, and `blendbsdf`: each parameter Mitsuba 3 reads
//! with `get_texture` / `get_unbounded_texture` is a constant or a texture here too, bound
//! to its field by a [`Slot`] ([`crate::material::textured`]).

use super::document::Elem;
use super::objects::Builder;
use super::props::{ColorSrc, FloatSrc, Props, Result};
use crate::material::textured::slots::{ALPHA, ALPHA_U, ALPHA_V};
use crate::material::{Binding, Blend, Bsdf, Microfacet, MicrofacetType, Slot, MAX_BLEND_DEPTH};
use crate::Color;

impl<'a> Builder<'a> {
    /// A colour parameter: a constant, or a texture bound to `slot` (pushed to `slots`);
    /// returns the constant, or the texture's mean for what the BSDF derives from it.
    pub(super) fn color_param(
        &mut self,
        p: &Props<'a>,
        name: &'static str,
        default: f32,
        slots: &mut Vec<Binding>,
        slot: Slot,
    ) -> Result<Color> {
        match p.color_src(name, Color::splat(default))? {
            ColorSrc::Const(c) => Ok(c),
            ColorSrc::Texture(t) => {
                let texture = self.texture(t)?;
                slots.push(Binding { texture, slot });
                Ok(self.desc.textures[texture as usize].mean())
            }
        }
    }

    /// A float parameter, if given: a constant, or a texture read as a float (Mitsuba's
    /// `eval_1`) bound to `slot`; returns the constant or the texture's mean.
    pub(super) fn float_param_opt(
        &mut self,
        p: &Props<'a>,
        name: &'static str,
        slots: &mut Vec<Binding>,
        slot: Slot,
    ) -> Result<Option<f32>> {
        match p.float_src(name)? {
            None => Ok(None),
            Some(FloatSrc::Const(v)) => Ok(Some(v)),
            Some(FloatSrc::Texture(t)) => {
                let texture = self.texture(t)?;
                slots.push(Binding { texture, slot });
                Ok(Some(self.desc.textures[texture as usize].mean_1()))
            }
        }
    }

    /// The microfacet distribution: `distribution` (`beckmann`, Mitsuba's default, or
    /// `ggx`, in any case) and `alpha`, or `alpha_u` and `alpha_v`. Where `slots` is given
    /// (rough conductor and dielectric) each may be a texture; roughplastic's may not, as in
    /// Mitsuba, which tabulates its coating for one α.
    pub(super) fn roughness(
        &mut self,
        p: &Props<'a>,
        slots: Option<&mut Vec<Binding>>,
    ) -> Result<Microfacet> {
        let e = p.owner;
        let kind = match p.string_opt("distribution")? {
            None => MicrofacetType::Beckmann,
            Some(d) => MicrofacetType::parse(d).ok_or_else(|| {
                let at = p.elem("distribution").unwrap_or(e);
                self.doc.err_attr(
                    at,
                    "value",
                    format!("distribution '{d}': expected beckmann or ggx"),
                )
            })?,
        };
        p.ignore("sample_visible");
        let (a, au, av) = match slots {
            Some(slots) => {
                let a = self.float_param_opt(p, "alpha", slots, ALPHA)?;
                let au = self.float_param_opt(p, "alpha_u", slots, ALPHA_U)?;
                let av = self.float_param_opt(p, "alpha_v", slots, ALPHA_V)?;
                (a, au, av)
            }
            None => {
                for name in ["alpha", "alpha_u", "alpha_v"] {
                    if let Some(t) = p.elem(name).filter(|t| t.tag == "texture") {
                        return Err(self.doc.err(
                            t,
                            format!(
                                "'{name}' of a {} cannot be a texture (Mitsuba tabulates its \
                                 coating for one roughness); give a <float>",
                                p.kind()?
                            ),
                        ));
                    }
                }
                (
                    p.float_opt("alpha")?,
                    p.float_opt("alpha_u")?,
                    p.float_opt("alpha_v")?,
                )
            }
        };
        let a = a.unwrap_or(0.1);
        let (au, av) = (au.unwrap_or(a), av.unwrap_or(a));
        for (n, v) in [("alpha", a), ("alpha_u", au), ("alpha_v", av)] {
            if !(v > 0.0) {
                return Err(self.doc.err(e, format!("{n} must be positive, got {v}")));
            }
        }
        Ok(Microfacet::new(kind, au, av))
    }

    /// `blendbsdf`: a `weight` (float or texture, in [0, 1]) and exactly two nested BSDFs,
    /// nested blends at most [`MAX_BLEND_DEPTH`] deep.
    pub(super) fn blend(&mut self, p: &Props<'a>, slots: &mut Vec<Binding>) -> Result<Bsdf> {
        let e = p.owner;
        let parts: Vec<&'a Elem> = p.objects.clone();
        if parts.len() != 2 || parts.iter().any(|o| o.tag != "bsdf") {
            return Err(self.doc.err(
                e,
                format!(
                    "blendbsdf needs exactly two nested BSDFs, found {} nested object{}",
                    parts.len(),
                    if parts.len() == 1 { "" } else { "s" }
                ),
            ));
        }
        let weight_slot = crate::slot!(Float, Blend, |b, v| b.weight = v);
        let weight = self
            .float_param_opt(p, "weight", slots, weight_slot)?
            .ok_or_else(|| {
                self.doc
                    .err(e, "a blendbsdf needs a 'weight' (float or texture)")
            })?;
        if !(0.0..=1.0).contains(&weight) {
            let at = p.elem("weight").unwrap_or(e);
            return Err(self.doc.err_attr(
                at,
                "value",
                format!("'weight' must be between 0 and 1, got {weight}"),
            ));
        }
        let first = self.material(parts[0])?;
        let second = self.material(parts[1])?;
        let depth = 1 + self.blend_depth(first).max(self.blend_depth(second));
        if depth > MAX_BLEND_DEPTH {
            return Err(self.doc.err(
                e,
                format!(
                    "blendbsdfs are nested {depth} deep here; mcrt allows at most \
                     {MAX_BLEND_DEPTH}"
                ),
            ));
        }
        Ok(Bsdf::Blend(Blend {
            weight,
            first,
            second,
        }))
    }

    /// How many blends deep material `i` is (0 for a plain BSDF).
    fn blend_depth(&self, i: u32) -> u32 {
        match self.desc.materials[i as usize].bsdf {
            Bsdf::Blend(b) => 1 + self.blend_depth(b.first).max(self.blend_depth(b.second)),
            _ => 0,
        }
    }
}
