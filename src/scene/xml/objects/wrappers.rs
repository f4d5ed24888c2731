//! Mitsuba's BSDFs that wrap one nested BSDF and change where it is seen: `normalmap`,
//! `bumpmap` (the shading normal; [`crate::material::normal_map`]) and `mask` (opacity;
//! [`crate::scene::mask`]). The nested BSDF becomes the material; the wrapper adds its
//! texture to it.

use super::{Builder, Document, Elem, Props, Result};
use crate::material::normal_map::{luminance, Bump};
use crate::material::Material;
use crate::scene::xml::props::ColorSrc;
use crate::texture::Texture;
use crate::Color;

impl<'a> Builder<'a> {
    /// The material of a `normalmap`, `bumpmap` or `mask` element `e` (properties `p`).
    pub(super) fn wrapper(
        &mut self,
        e: &'a Elem,
        p: &Props<'a>,
        kind: &str,
        two_sided: bool,
    ) -> Result<Material> {
        let inner = self.nested_bsdf(e, p, kind)?;
        let mut normal_map = None;
        let mut bump = None;
        let mut opacity = None;
        match kind {
            "normalmap" => {
                let ColorSrc::Texture(t) = p.color_src("normalmap", Color::ZERO)? else {
                    return Err(self.doc.err(
                        p.elem("normalmap").unwrap_or(e),
                        "normalmap needs a texture named 'normalmap' (a bitmap of normals, \
                         raw=\"true\")",
                    ));
                };
                normal_map = Some(self.texture(t)?);
            }
            "bumpmap" => {
                let texture = self.bump_texture(e, p)?;
                let scale = p.float("scale", 1.0)?;
                if !scale.is_finite() {
                    return Err(self.doc.err(
                        p.elem("scale").unwrap_or(e),
                        format!("bumpmap scale must be finite, got {scale}"),
                    ));
                }
                bump = Some(Bump { texture, scale });
            }
            _ => opacity = self.opacity(e, p)?,
        }
        if kind != "mask" {
            // Mitsuba's defaults, the only behaviour mcrt has.
            for flag in ["flip_invalid_normals", "use_shadowing_function"] {
                if !p.bool(flag, true)? {
                    return Err(self.doc.err(
                        p.elem(flag).unwrap_or(e),
                        format!(
                            "{kind} {flag}=false is not supported (only Mitsuba's default, true)"
                        ),
                    ));
                }
            }
        }
        p.finish()?;
        let mut m = self.bsdf(inner, two_sided)?;
        if (m.perturbs() && kind != "mask") || (m.opacity.is_some() && kind == "mask") {
            return Err(self.doc.err(
                inner,
                format!(
                    "a {kind} around a BSDF that already has {} is not supported",
                    if kind == "mask" {
                        "an opacity (mask)"
                    } else {
                        "a normal or bump map"
                    }
                ),
            ));
        }
        if normal_map.is_some() || bump.is_some() {
            (m.normal_map, m.bump) = (normal_map, bump);
        }
        if opacity.is_some() {
            m.opacity = opacity;
        }
        Ok(m)
    }

    /// The one nested `<bsdf>` of a wrapper (a bumpmap may also hold its texture unnamed).
    fn nested_bsdf(&self, e: &'a Elem, p: &Props<'a>, kind: &str) -> Result<&'a Elem> {
        let mut bsdfs = Vec::new();
        for &o in &p.objects {
            match o.tag.as_str() {
                "bsdf" => bsdfs.push(o),
                "texture" if kind == "bumpmap" => {}
                tag => {
                    return Err(self.doc.err(
                        o,
                        format!("<{tag}> cannot be nested in a {kind}; it takes one <bsdf>"),
                    ))
                }
            }
        }
        match bsdfs[..] {
            [b] => Ok(b),
            _ => Err(self.doc.err(
                e,
                format!(
                    "{kind} needs exactly one nested <bsdf>, found {}",
                    bsdfs.len()
                ),
            )),
        }
    }

    /// A bumpmap's height texture: its one `<texture>`, named or not (Mitsuba takes it by
    /// type).
    fn bump_texture(&mut self, e: &'a Elem, p: &Props<'a>) -> Result<u32> {
        let mut ts: Vec<&'a Elem> = p.textures_any_name();
        ts.extend(p.objects.iter().copied().filter(|o| o.tag == "texture"));
        match ts[..] {
            [t] => self.texture(t),
            _ => Err(self.doc.err(
                e,
                format!(
                    "bumpmap needs exactly one nested <texture> (the height), found {}",
                    ts.len()
                ),
            )),
        }
    }

    /// A mask's `opacity` (default 0.5): a texture, or a constant in [0, 1] (None for 1:
    /// opaque, as without a mask).
    fn opacity(&mut self, e: &'a Elem, p: &Props<'a>) -> Result<Option<u32>> {
        let c = match p.color_src("opacity", Color::splat(0.5))? {
            ColorSrc::Texture(t) => return self.texture(t).map(Some),
            ColorSrc::Const(c) => c,
        };
        if c.max_element() > 1.0 {
            return Err(bad_opacity(self.doc, p.elem("opacity").unwrap_or(e), c));
        }
        let a = luminance(c);
        if a >= 1.0 {
            return Ok(None);
        }
        self.desc.textures.push(Texture::Constant(Color::splat(a)));
        Ok(Some((self.desc.textures.len() - 1) as u32))
    }
}

fn bad_opacity(doc: &Document, at: &Elem, c: Color) -> crate::scene::SceneError {
    let v = if c.x == c.y && c.y == c.z {
        format!("{}", c.x)
    } else {
        format!("({}, {}, {})", c.x, c.y, c.z)
    };
    doc.err(at, format!("mask opacity must lie in [0, 1], got {v}"))
}
