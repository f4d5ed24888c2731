//! `principled` and `principledthin` materials of the TOML format: Mitsuba's parameter names
//! and defaults (`base_color` a colour or a texture's name; `eta` or `specular` as single
//! numbers), weights in [0, 1] and `diff_trans` in [0, 2]. A principled material has a back
//! side of its own (refraction out of the object; the thin one is the same from both sides),
//! so `two_sided` defaults to false for them, as in Mitsuba.

use super::{ColorT, Ctx, MaterialT, Textures};
use crate::material::{Bsdf, Principled, PrincipledThin};
use crate::scene::SceneError;
use std::ops::Range;
use toml::Spanned;

type Present<'a> = [(&'a str, Option<Range<usize>>)];

const THIN_KEYS: &[&str] = &[
    "base_color",
    "roughness",
    "anisotropic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "diff_trans",
    "eta",
    "two_sided",
];

const PRINCIPLED_KEYS: &[&str] = &[
    "base_color",
    "roughness",
    "anisotropic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "metallic",
    "clearcoat",
    "clearcoat_gloss",
    "eta",
    "specular",
    "two_sided",
];

/// A number and where it is.
type At = (Range<usize>, f32);

fn at(v: &Option<Spanned<f32>>) -> Option<At> {
    v.as_ref().map(|s| (s.span(), *s.get_ref()))
}

/// A weight in [0, hi], `default` when absent.
fn weight(cx: &Ctx, v: Option<At>, key: &str, default: f32, hi: f32) -> Result<f32, SceneError> {
    match v {
        None => Ok(default),
        Some((_, x)) if (0.0..=hi).contains(&x) => Ok(x),
        Some((span, x)) => cx.err(span, format!("'{key}' must be between 0 and {hi}, got {x}")),
    }
}

/// A single number given where the format's `ColorT` keys (`eta`, `specular`) are shared with
/// other materials.
fn number(cx: &Ctx, v: &Option<Spanned<ColorT>>, key: &str) -> Result<Option<At>, SceneError> {
    match v {
        None => Ok(None),
        Some(s) => match s.get_ref() {
            ColorT::Grey(x) => Ok(Some((s.span(), *x))),
            _ => cx.err(
                s.span(),
                format!("'{key}' of a principled material is a single number"),
            ),
        },
    }
}

/// The BSDF of a `principled` or `principledthin` material (`kind`); `texture` receives the
/// base colour's texture, if it has one.
pub(super) fn bsdf(
    cx: &Ctx,
    t: &MaterialT,
    kind: &str,
    present: &Present,
    what: &str,
    tex: &Textures,
    texture: &mut Option<u32>,
) -> Result<Bsdf, SceneError> {
    let thin = kind == "principledthin";
    cx.only(
        present,
        if thin { THIN_KEYS } else { PRINCIPLED_KEYS },
        what,
    )?;
    let base_color = match &t.base_color {
        Some(v) => {
            let (c, tx) = cx.main_color(v, "base_color", tex)?;
            *texture = tx;
            c
        }
        None => Principled::default().base_color,
    };
    let unit =
        |v: &Option<Spanned<f32>>, key: &str, default: f32| weight(cx, at(v), key, default, 1.0);
    let roughness = unit(&t.roughness, "roughness", 0.5)?;
    let anisotropic = unit(&t.anisotropic, "anisotropic", 0.0)?;
    let spec_trans = unit(&t.spec_trans, "spec_trans", 0.0)?;
    let spec_tint = unit(&t.spec_tint, "spec_tint", 0.0)?;
    let sheen = unit(&t.sheen, "sheen", 0.0)?;
    let sheen_tint = unit(&t.sheen_tint, "sheen_tint", 0.0)?;
    let flatness = unit(&t.flatness, "flatness", 0.0)?;
    let eta = number(cx, &t.eta, "eta")?;
    if let Some((span, e)) = &eta {
        if !(*e > 0.0) {
            return cx.err(span.clone(), format!("'eta' must be positive, got {e}"));
        }
    }
    let eta = eta.map(|(_, e)| e);
    if thin {
        return Ok(Bsdf::PrincipledThin(PrincipledThin {
            base_color,
            roughness,
            anisotropic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            diff_trans: weight(cx, at(&t.diff_trans), "diff_trans", 0.0, 2.0)?,
            eta: eta.unwrap_or(1.5),
            ..PrincipledThin::default()
        }));
    }
    let specular = number(cx, &t.specular, "specular")?;
    if let (Some(_), Some((span, _))) = (eta, &specular) {
        return cx.err(
            span.clone(),
            "give either 'eta' or 'specular' (they set the same index of refraction), not both",
        );
    }
    let specular = match specular {
        Some(s) => Some(weight(cx, Some(s), "specular", 0.5, 1.0)?),
        None => None,
    };
    Ok(Bsdf::Principled(Principled {
        base_color,
        roughness,
        anisotropic,
        metallic: unit(&t.metallic, "metallic", 0.0)?,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        flatness,
        clearcoat: unit(&t.clearcoat, "clearcoat", 0.0)?,
        clearcoat_gloss: unit(&t.clearcoat_gloss, "clearcoat_gloss", 0.0)?,
        eta: Principled::eta_of(eta, specular, t.spec_trans.is_some() && spec_trans != 0.0),
        ..Principled::default()
    }))
}
