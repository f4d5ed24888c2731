//! Mitsuba's `principled` and `principledthin` BSDFs: their parameters, Mitsuba's defaults,
//! and the ranges its documentation gives (weights in [0, 1], `diff_trans` in [0, 2], a
//! positive `eta`, non-negative sampling rates), checked here so that a typo such as
//! `metallic = 2` is an error rather than a BSDF that creates energy.

use super::{Builder, Props, Result};
use crate::material::{Bsdf, Principled, PrincipledThin};

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
        for (slot, (name, default)) in w.iter_mut().zip(UNIT_WEIGHTS) {
            *slot = self.float_in(p, name, default, 1.0)?;
        }
        let [roughness, anisotropic, spec_trans, spec_tint, sheen, sheen_tint, flatness] = w;
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
        let bsdf = if kind == "principledthin" {
            Bsdf::PrincipledThin(PrincipledThin {
                base_color,
                roughness,
                anisotropic,
                spec_trans,
                spec_tint,
                sheen,
                sheen_tint,
                flatness,
                diff_trans: self.float_in(p, "diff_trans", 0.0, 2.0)?,
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
                metallic: self.float_in(p, "metallic", 0.0, 1.0)?,
                spec_trans,
                spec_tint,
                sheen,
                sheen_tint,
                flatness,
                clearcoat: self.float_in(p, "clearcoat", 0.0, 1.0)?,
                clearcoat_gloss: self.float_in(p, "clearcoat_gloss", 0.0, 1.0)?,
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
