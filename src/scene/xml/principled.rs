//! Mitsuba's `principled` and `principledthin` BSDFs: their parameters, Mitsuba's defaults,
//! and the ranges its documentation gives (weights in [0, 1], `diff_trans` in [0, 2], a
//! positive `eta`, non-negative sampling rates), checked here so that a typo such as
//! `metallic = 2` is an error rather than a BSDF that creates energy.

use super::super::props::FloatSrc;
use super::{Builder, Props, Result};
use crate::material::{Binding, Bsdf, Principled, PrincipledThin, Slot};

/// The slot of a float field that both plugins have.
macro_rules! both {
    ($f:ident) => {
        Slot::Float(|bsdf, v| match bsdf {
            Bsdf::Principled(b) => b.$f = v,
            Bsdf::PrincipledThin(b) => b.$f = v,
            _ => {}
        })
    };
}

/// The slots of [`UNIT_WEIGHTS`], in its order.
const UNIT_SLOTS: [Slot; 7] = [
    both!(roughness),
    both!(anisotropic),
    both!(spec_trans),
    both!(spec_tint),
    both!(sheen),
    both!(sheen_tint),
    both!(flatness),
];
const METALLIC: Slot = crate::slot!(Float, Principled, |b, v| b.metallic = v);
const CLEARCOAT: Slot = crate::slot!(Float, Principled, |b, v| b.clearcoat = v);
const CLEARCOAT_GLOSS: Slot = crate::slot!(Float, Principled, |b, v| b.clearcoat_gloss = v);
const DIFF_TRANS: Slot = crate::slot!(Float, PrincipledThin, |b, v| b.diff_trans = v);

/// The weights of both plugins that must lie in [0, 1], with their defaults.
const UNIT_WEIGHTS: [(&str, f32); 7] = [
    ("roughness", 0.5),
    ("anisotropic", 0.0),
    ("spec_trans", 0.0),
    ("spec_tint", 0.0),
    ("sheen", 0.0),
    ("sheen_tint", 0.0),
    ("flatness", 0.0),
];

impl<'a> Builder<'a> {
    /// A float property within [0, hi].
    fn float_in(&self, p: &Props<'a>, name: &'static str, default: f32, hi: f32) -> Result<f32> {
        let v = p.float(name, default)?;
        if !(0.0..=hi).contains(&v) {
            let at = p.elem(name).unwrap_or(p.owner);
            return Err(self.doc.err_attr(
                at,
                "value",
                format!("'{name}' must be between 0 and {hi}, got {v}"),
            ));
        }
        Ok(v)
    }

    /// A weight as Mitsuba textures it: a number within [0, hi], or a texture (read as a
    /// float, Mitsuba's `eval_1`) bound to `slot`, whose mean stands for it until the hit.
    fn weight(
        &mut self,
        p: &Props<'a>,
        (name, default, hi): (&'static str, f32, f32),
        slots: &mut Vec<Binding>,
        slot: Slot,
    ) -> Result<f32> {
        if let Some(FloatSrc::Texture(_)) = p.float_src(name)? {
            let v = self.float_param_opt(p, name, slots, slot)?;
            return Ok(v.unwrap_or(default));
        }
        self.float_in(p, name, default, hi)
    }

    /// A sampling rate: any non-negative number, 1 by default.
    fn rate(&self, p: &Props<'a>, name: &'static str) -> Result<f32> {
        let v = p.float(name, 1.0)?;
        if v < 0.0 {
            let at = p.elem(name).unwrap_or(p.owner);
            return Err(self.doc.err_attr(
                at,
                "value",
                format!("'{name}' must not be negative, got {v}"),
            ));
        }
        Ok(v)
    }

    /// The BSDF of a `principled` or `principledthin` element; a base colour texture is
    /// bound in `slots`.
    pub(super) fn principled(
        &mut self,
        p: &Props<'a>,
        kind: &str,
        slots: &mut Vec<crate::material::Binding>,
    ) -> Result<Bsdf> {
        let main = crate::material::textured::slots::MAIN_COLOR;
        let base_color = self.color_param(p, "base_color", 0.5, slots, main)?;
        let mut w = [0.0f32; UNIT_WEIGHTS.len()];
        for ((v, (name, default)), slot) in w.iter_mut().zip(UNIT_WEIGHTS).zip(UNIT_SLOTS) {
            *v = self.weight(p, (name, default, 1.0), slots, slot)?;
        }
        let [roughness, anisotropic, spec_trans, spec_tint, sheen, sheen_tint, flatness] = w;
        let thin = kind == "principledthin";
        let [metallic, clearcoat, clearcoat_gloss, diff_trans] = if thin {
            [
                0.0,
                0.0,
                0.0,
                self.weight(p, ("diff_trans", 0.0, 2.0), slots, DIFF_TRANS)?,
            ]
        } else {
            [
                self.weight(p, ("metallic", 0.0, 1.0), slots, METALLIC)?,
                self.weight(p, ("clearcoat", 0.0, 1.0), slots, CLEARCOAT)?,
                self.weight(p, ("clearcoat_gloss", 0.0, 1.0), slots, CLEARCOAT_GLOSS)?,
                0.0,
            ]
        };
        let positive_eta = |eta: Option<f32>| -> Result<Option<f32>> {
            match eta {
                Some(e) if !(e > 0.0) => {
                    let at = p.elem("eta").unwrap_or(p.owner);
                    Err(self
                        .doc
                        .err_attr(at, "value", format!("'eta' must be positive, got {e}")))
                }
                e => Ok(e),
            }
        };
        let bsdf = if thin {
            Bsdf::PrincipledThin(PrincipledThin {
                base_color,
                roughness,
                anisotropic,
                spec_trans,
                spec_tint,
                sheen,
                sheen_tint,
                flatness,
                diff_trans,
                eta: positive_eta(p.float_opt("eta")?)?.unwrap_or(1.5),
                diffuse_reflectance_sampling_rate: self
                    .rate(p, "diffuse_reflectance_sampling_rate")?,
                specular_reflectance_sampling_rate: self
                    .rate(p, "specular_reflectance_sampling_rate")?,
                specular_transmittance_sampling_rate: self
                    .rate(p, "specular_transmittance_sampling_rate")?,
                diffuse_transmittance_sampling_rate: self
                    .rate(p, "diffuse_transmittance_sampling_rate")?,
            })
        } else {
            if p.has("eta") && p.has("specular") {
                let at = p.elem("specular").unwrap_or(p.owner);
                return Err(self.doc.err(
                    at,
                    "give either 'eta' or 'specular' (they set the same index of refraction), \
                     not both",
                ));
            }
            let eta = positive_eta(p.float_opt("eta")?)?;
            let specular = if p.has("specular") {
                Some(self.float_in(p, "specular", 0.5, 1.0)?)
            } else {
                None
            };
            // Mitsuba's `get_flag`: a `spec_trans` given and not 0.
            let has_spec_trans = p.has("spec_trans") && spec_trans != 0.0;
            Bsdf::Principled(Principled {
                base_color,
                roughness,
                anisotropic,
                metallic,
                spec_trans,
                spec_tint,
                sheen,
                sheen_tint,
                flatness,
                clearcoat,
                clearcoat_gloss,
                eta: Principled::eta_of(eta, specular, has_spec_trans),
                diffuse_reflectance_sampling_rate: self
                    .rate(p, "diffuse_reflectance_sampling_rate")?,
                main_specular_sampling_rate: self.rate(p, "main_specular_sampling_rate")?,
                clearcoat_sampling_rate: self.rate(p, "clearcoat_sampling_rate")?,
            })
        };
        Ok(bsdf)
    }
}
