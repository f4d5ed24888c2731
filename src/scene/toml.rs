//! The native scene format: TOML, documented in `docs/scene-format.md`.
//!
//! Every error names the file, line and column of the value at fault and what was expected.

use super::desc::{FileSettings, GeometryDesc, LightDesc, SceneDesc, ShapeDesc};
use super::obj::load_obj;
use super::ply::load_ply;
use super::SceneError;
use crate::camera::{CameraDesc, FovAxis};
use crate::geometry::mesh::TriangleMesh;
use crate::integrator::IntegratorKind;
use crate::material::conductor::{conductor_ior, conductor_names};
use crate::material::textured::slots::{self, MAIN_COLOR};
use crate::material::{
    Binding, Blend, Bsdf, Conductor, Dielectric, Lambert, Material, Microfacet, MicrofacetType,
    Mirror, OrenNayar, Plastic, RoughConductor, RoughDielectric, RoughPlastic, Slot,
    ThinDielectric, MAX_BLEND_DEPTH,
};
use crate::texture::{Bitmap, BitmapTexture, FilterType, Texture, UvTransform, WrapMode};
use crate::Color;
use glam::{Mat4, Vec2, Vec3};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use toml::Spanned;

mod instance;

type V3 = [f32; 3];

#[path = "toml_principled.rs"]
mod principled;

/// A colour: one number (grey) or three (linear RGB); where a material's main colour is
/// expected, also the name of a `[texture.NAME]`.
#[derive(Deserialize, Clone)]
#[serde(
    untagged,
    expecting = "expected a colour: a number, an array of three numbers [r, g, b], or (for a material's main colour) the name of a texture"
)]
enum ColorT {
    Grey(f32),
    Rgb(V3),
    Texture(String),
}

impl ColorT {
    fn color(&self) -> Option<Color> {
        match self {
            ColorT::Grey(g) => Some(Color::splat(*g)),
            ColorT::Rgb(c) => Some(Color::from_array(*c)),
            ColorT::Texture(_) => None,
        }
    }
}

/// A float parameter: a number, or the name of a texture read as a float (its luminance).
#[derive(Deserialize, Clone)]
#[serde(untagged, expecting = "expected a number or the name of a texture")]
enum FloatT {
    Num(f32),
    Texture(String),
}

/// The textures defined in the file: names and indices into `SceneDesc::textures`.
struct Textures<'a> {
    ids: BTreeMap<&'a str, u32>,
    list: &'a [Texture],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileT {
    render: Option<RenderT>,
    #[serde(default)]
    camera: Vec<Spanned<CameraT>>,
    #[serde(default)]
    texture: BTreeMap<String, Spanned<TextureT>>,
    #[serde(default)]
    material: BTreeMap<String, Spanned<MaterialT>>,
    #[serde(default)]
    shape: Vec<Spanned<ShapeT>>,
    #[serde(default)]
    light: Vec<Spanned<LightT>>,
    #[serde(default)]
    instance: Vec<Spanned<instance::InstanceT>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderT {
    width: Option<Spanned<u32>>,
    height: Option<Spanned<u32>>,
    spp: Option<Spanned<u32>>,
    seed: Option<u64>,
    integrator: Option<Spanned<String>>,
    max_depth: Option<Spanned<i64>>,
    shadow_rays: Option<Spanned<u32>>,
    rr_survival: Option<Spanned<f32>>,
    camera: Option<Spanned<String>>,
    sampler: Option<Spanned<String>>,
    rr_depth: Option<Spanned<u32>>,
    hide_emitters: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraT {
    name: Spanned<String>,
    #[serde(rename = "type")]
    kind: Spanned<String>,
    eye: Option<Spanned<V3>>,
    top_left: Option<Spanned<V3>>,
    top_right: Option<Spanned<V3>>,
    bottom_left: Option<Spanned<V3>>,
    bottom_right: Option<Spanned<V3>>,
    origin: Option<Spanned<V3>>,
    target: Option<Spanned<V3>>,
    up: Option<Spanned<V3>>,
    fov: Option<Spanned<f32>>,
    fov_axis: Option<Spanned<String>>,
    aperture_radius: Option<Spanned<f32>>,
    focus_distance: Option<Spanned<f32>>,
    view_width: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialT {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    albedo: Option<Spanned<ColorT>>,
    sigma: Option<Spanned<f32>>,
    reflectance: Option<Spanned<ColorT>>,
    specular: Option<Spanned<ColorT>>,
    ior: Option<Spanned<f32>>,
    ext_ior: Option<Spanned<f32>>,
    material: Option<Spanned<String>>,
    eta: Option<Spanned<ColorT>>,
    k: Option<Spanned<ColorT>>,
    alpha: Option<Spanned<FloatT>>,
    alpha_u: Option<Spanned<FloatT>>,
    alpha_v: Option<Spanned<FloatT>>,
    distribution: Option<Spanned<String>>,
    weight: Option<Spanned<FloatT>>,
    materials: Option<Spanned<Vec<String>>>,
    nonlinear: Option<Spanned<bool>>,
    two_sided: Option<Spanned<bool>>,
    // `principled` and `principledthin` (toml_principled.rs), with `eta` and `specular`.
    base_color: Option<Spanned<ColorT>>,
    roughness: Option<Spanned<f32>>,
    anisotropic: Option<Spanned<f32>>,
    metallic: Option<Spanned<f32>>,
    spec_trans: Option<Spanned<f32>>,
    spec_tint: Option<Spanned<f32>>,
    sheen: Option<Spanned<f32>>,
    sheen_tint: Option<Spanned<f32>>,
    flatness: Option<Spanned<f32>>,
    clearcoat: Option<Spanned<f32>>,
    clearcoat_gloss: Option<Spanned<f32>>,
    diff_trans: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TextureT {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    file: Option<Spanned<String>>,
    raw: Option<Spanned<bool>>,
    filter: Option<Spanned<String>>,
    wrap: Option<Spanned<String>>,
    color0: Option<Spanned<ColorT>>,
    color1: Option<Spanned<ColorT>>,
    uv_scale: Option<Spanned<[f32; 2]>>,
    uv_offset: Option<Spanned<[f32; 2]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightT {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    position: Option<Spanned<V3>>,
    intensity: Option<Spanned<ColorT>>,
    direction: Option<Spanned<V3>>,
    irradiance: Option<Spanned<ColorT>>,
    radiance: Option<Spanned<ColorT>>,
    cutoff_angle: Option<Spanned<f32>>,
    beam_width: Option<Spanned<f32>>,
    texture: Option<Spanned<String>>,
    up: Option<Spanned<V3>>,
    to_world: Option<Spanned<[[f32; 4]; 4]>>,
    file: Option<Spanned<String>>,
    scale: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeT {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    material: Option<Spanned<String>>,
    emission: Option<Spanned<ColorT>>,
    vertices: Option<Spanned<Vec<V3>>>,
    center: Option<Spanned<V3>>,
    radius: Option<Spanned<f32>>,
    normal: Option<Spanned<V3>>,
    p0: Option<Spanned<V3>>,
    p1: Option<Spanned<V3>>,
    file: Option<Spanned<String>>,
    positions: Option<Spanned<Vec<V3>>>,
    indices: Option<Spanned<Vec<[u32; 3]>>>,
    normals: Option<Spanned<Vec<V3>>>,
    uvs: Option<Spanned<Vec<[f32; 2]>>>,
    smooth: Option<Spanned<bool>>,
    /// The shape group the shape belongs to, instead of the scene.
    group: Option<Spanned<String>>,
}

/// Error helper bound to one file's text.
struct Ctx<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Ctx<'_> {
    fn err<T>(
        &self,
        span: std::ops::Range<usize>,
        msg: impl Into<String>,
    ) -> Result<T, SceneError> {
        Err(SceneError::at(self.path, self.text, span.start, msg))
    }
    fn need<'b, T>(
        &self,
        v: &'b Option<Spanned<T>>,
        key: &str,
        what: &str,
        at: &std::ops::Range<usize>,
    ) -> Result<&'b Spanned<T>, SceneError> {
        match v {
            Some(v) => Ok(v),
            None => self.err(at.clone(), format!("{what} needs '{key}'")),
        }
    }
    /// Rejects keys that do not belong to this kind of table.
    fn only(
        &self,
        present: &[(&str, Option<std::ops::Range<usize>>)],
        allowed: &[&str],
        what: &str,
    ) -> Result<(), SceneError> {
        for (key, span) in present {
            if let Some(span) = span {
                if !allowed.contains(key) {
                    return self.err(
                        span.clone(),
                        format!(
                            "'{key}' does not apply to {what} (its keys: {})",
                            list_or_none(allowed)
                        ),
                    );
                }
            }
        }
        Ok(())
    }
    fn finite3(&self, v: &Spanned<V3>, key: &str) -> Result<Vec3, SceneError> {
        if v.get_ref().iter().all(|c| c.is_finite()) {
            Ok(Vec3::from(*v.get_ref()))
        } else {
            self.err(v.span(), format!("'{key}' must be three finite numbers"))
        }
    }
    fn color(&self, v: &Spanned<ColorT>, key: &str, max: Option<f32>) -> Result<Color, SceneError> {
        let Some(c) = v.get_ref().color() else {
            return self.err(
                v.span(),
                format!("'{key}' must be a colour (a number or [r, g, b]), not a texture name"),
            );
        };
        match crate::texture::color_fault(c, max) {
            Some(f) => self.err(v.span(), format!("'{key}' {f}")),
            None => Ok(c),
        }
    }
}

impl Ctx<'_> {
    /// A material's main colour (a reflectance, at most 1): a colour, or a texture by name,
    /// whose mean stands for it where the BSDF needs one value.
    fn main_color(
        &self,
        v: &Spanned<ColorT>,
        key: &str,
        tex: &Textures,
    ) -> Result<(Color, Option<u32>), SceneError> {
        match v.get_ref() {
            ColorT::Texture(name) => match tex.ids.get(name.as_str()) {
                // A texture as a reflectance obeys the rule of a constant one, texel by texel.
                Some(&i) => match crate::texture::color_fault(
                    Color::splat(tex.list[i as usize].max()),
                    Some(1.0),
                ) {
                    Some(f) => self.err(
                        v.span(),
                        format!(
                            "'{key}': texture '{}' has values up to {}; a reflectance {f}",
                            crate::input::shorten(name),
                            tex.list[i as usize].max()
                        ),
                    ),
                    None => Ok((tex.list[i as usize].mean(), Some(i))),
                },
                None => {
                    let known: Vec<&str> = tex.ids.keys().copied().collect();
                    self.err(
                        v.span(),
                        format!(
                            "unknown texture '{}' in '{key}' (defined: {}); give a colour or the name of a [texture.NAME]",
                            crate::input::shorten(name),
                            list_or_none(&known)
                        ),
                    )
                }
            },
            _ => Ok((self.color(v, key, Some(1.0))?, None)),
        }
    }

    /// An index of refraction: finite and > 0.
    fn ior(&self, v: &Option<Spanned<f32>>, key: &str, default: f32) -> Result<f32, SceneError> {
        match v {
            None => Ok(default),
            Some(v) if v.get_ref().is_finite() && *v.get_ref() > 0.0 => Ok(*v.get_ref()),
            Some(v) => self.err(
                v.span(),
                format!("'{key}' must be a positive index of refraction"),
            ),
        }
    }

    /// The microfacet distribution: `distribution` ("ggx", the default, or "beckmann") and
    /// `alpha` or `alpha_u` and `alpha_v`, each a number or (where `slots` is given) a
    /// texture read as a float.
    fn roughness(
        &self,
        t: &MaterialT,
        at: &std::ops::Range<usize>,
        tex: &Textures,
        mut slots: Option<&mut Vec<Binding>>,
    ) -> Result<Microfacet, SceneError> {
        let kind = match &t.distribution {
            None => MicrofacetType::Ggx,
            Some(d) => match MicrofacetType::parse(d.get_ref()) {
                Some(k) => k,
                None => {
                    return self.err(
                        d.span(),
                        format!(
                            "unknown microfacet distribution '{}' (expected ggx or beckmann)",
                            d.get_ref()
                        ),
                    )
                }
            },
        };
        let mut check = |v: &Spanned<FloatT>, key: &str, slot: Slot| {
            let value = match (v.get_ref(), slots.as_deref_mut()) {
                (FloatT::Num(x), _) => *x,
                (FloatT::Texture(name), Some(slots)) => {
                    let i = self.texture_id(v.span(), name, key, tex)?;
                    slots.push(Binding { texture: i, slot });
                    return Ok(tex.list[i as usize].mean_1().max(1e-4));
                }
                (FloatT::Texture(_), None) => {
                    return self.err(
                        v.span(),
                        format!("'{key}' of a roughplastic cannot be a texture (its coating is tabulated for one roughness); give a number"),
                    )
                }
            };
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                self.err(
                    v.span(),
                    format!("'{key}' (microfacet roughness) must be a finite number > 0, such as 0.1 (rough) or 0.01 (nearly smooth)"),
                )
            }
        };
        let (au, av) = match (&t.alpha, &t.alpha_u, &t.alpha_v) {
            (Some(a), None, None) => {
                let a = check(a, "alpha", slots::ALPHA)?;
                (a, a)
            }
            (None, None, None) => (0.1, 0.1),
            (None, Some(u), Some(v)) => (
                check(u, "alpha_u", slots::ALPHA_U)?,
                check(v, "alpha_v", slots::ALPHA_V)?,
            ),
            (Some(a), _, _) => {
                return self.err(
                    a.span(),
                    "give either 'alpha' or 'alpha_u' and 'alpha_v', not both",
                )
            }
            (None, u, v) => {
                return self.err(
                    u.as_ref().or(v.as_ref()).map_or(at.clone(), |s| s.span()),
                    "anisotropic roughness needs both 'alpha_u' and 'alpha_v'",
                )
            }
        };
        Ok(Microfacet::new(kind, au, av))
    }

    /// The index of texture `name` (for the parameter `key`), or an error listing those
    /// defined.
    fn texture_id(
        &self,
        span: std::ops::Range<usize>,
        name: &str,
        key: &str,
        tex: &Textures,
    ) -> Result<u32, SceneError> {
        match tex.ids.get(name) {
            Some(&i) => Ok(i),
            None => {
                let known: Vec<&str> = tex.ids.keys().copied().collect();
                self.err(
                    span,
                    format!(
                        "unknown texture '{}' in '{key}' (defined: {}); give a number or the name of a [texture.NAME]",
                        crate::input::shorten(name),
                        list_or_none(&known)
                    ),
                )
            }
        }
    }
}

/// "a, b, c", or "none" for an empty list.
fn list_or_none(items: &[&str]) -> String {
    if items.is_empty() {
        "none".to_string()
    } else {
        items.join(", ")
    }
}

fn span_of<T>(v: &Option<Spanned<T>>) -> Option<std::ops::Range<usize>> {
    v.as_ref().map(|s| s.span())
}

/// Loads a native TOML scene.
pub fn load_toml(path: &Path) -> Result<SceneDesc, SceneError> {
    let text = crate::input::read_text(path)
        .map_err(|e| SceneError::new(path, None, format!("cannot read scene file: {e}")))?;
    parse_toml(path, &text)
}

/// Every number of a scene is read as an f32; TOML's are f64. A value beyond f32's range
/// would become infinite (and be refused as "must be positive" or "finite", which it was
/// not), one too small would become 0: this pass over the whole file refuses both, each at
/// its place, before the file is read into its tables.
struct F32Range;

impl<'de> Deserialize<'de> for F32Range {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(F32Range)
    }
}

impl<'de> serde::de::Visitor<'de> for F32Range {
    type Value = F32Range;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("any TOML value")
    }
    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<F32Range, E> {
        match super::text::f32_fault(v) {
            Some(f) => Err(E::custom(f)),
            None => Ok(F32Range),
        }
    }
    fn visit_i64<E>(self, _: i64) -> Result<F32Range, E> {
        Ok(F32Range)
    }
    fn visit_u64<E>(self, _: u64) -> Result<F32Range, E> {
        Ok(F32Range)
    }
    fn visit_bool<E>(self, _: bool) -> Result<F32Range, E> {
        Ok(F32Range)
    }
    fn visit_str<E>(self, _: &str) -> Result<F32Range, E> {
        Ok(F32Range)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<F32Range, A::Error> {
        while a.next_element::<F32Range>()?.is_some() {}
        Ok(F32Range)
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<F32Range, A::Error> {
        while a.next_key::<serde::de::IgnoredAny>()?.is_some() {
            a.next_value::<F32Range>()?;
        }
        Ok(F32Range)
    }
}

pub fn parse_toml(path: &Path, text: &str) -> Result<SceneDesc, SceneError> {
    let cx = Ctx { path, text };
    let toml_error = |e: toml::de::Error| {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(s) => SceneError::at(path, text, s.start, msg),
            None => SceneError::new(path, None, msg),
        }
    };
    toml::from_str::<F32Range>(text).map_err(toml_error)?;
    let file: FileT = toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(s) => SceneError::at(path, text, s.start, msg),
            None => SceneError::new(path, None, msg),
        }
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut desc = SceneDesc::default();

    if let Some(r) = &file.render {
        desc.settings = settings(&cx, r)?;
    }

    // Names seen (a set: many cameras stay linear).
    let mut camera_names = std::collections::HashSet::new();
    for cam in &file.camera {
        let c = cam.get_ref();
        let at = cam.span();
        let name = c.name.get_ref().clone();
        if !camera_names.insert(name.clone()) {
            return cx.err(
                c.name.span(),
                format!(
                    "a camera named '{}' is already defined",
                    crate::input::shorten(&name)
                ),
            );
        }
        let present = [
            ("eye", span_of(&c.eye)),
            ("top_left", span_of(&c.top_left)),
            ("top_right", span_of(&c.top_right)),
            ("bottom_left", span_of(&c.bottom_left)),
            ("bottom_right", span_of(&c.bottom_right)),
            ("origin", span_of(&c.origin)),
            ("target", span_of(&c.target)),
            ("up", span_of(&c.up)),
            ("fov", span_of(&c.fov)),
            ("fov_axis", span_of(&c.fov_axis)),
            ("aperture_radius", span_of(&c.aperture_radius)),
            ("focus_distance", span_of(&c.focus_distance)),
            ("view_width", span_of(&c.view_width)),
        ];
        let cd = match c.kind.get_ref().as_str() {
            "pinhole" => {
                let what = "a pinhole camera";
                cx.only(
                    &present,
                    &[
                        "eye",
                        "top_left",
                        "top_right",
                        "bottom_left",
                        "bottom_right",
                    ],
                    what,
                )?;
                CameraDesc::Pinhole {
                    eye: cx.finite3(cx.need(&c.eye, "eye", what, &at)?, "eye")?,
                    top_left: cx
                        .finite3(cx.need(&c.top_left, "top_left", what, &at)?, "top_left")?,
                    top_right: cx
                        .finite3(cx.need(&c.top_right, "top_right", what, &at)?, "top_right")?,
                    bottom_left: cx.finite3(
                        cx.need(&c.bottom_left, "bottom_left", what, &at)?,
                        "bottom_left",
                    )?,
                    bottom_right: c
                        .bottom_right
                        .as_ref()
                        .map(|v| cx.finite3(v, "bottom_right"))
                        .transpose()?,
                }
            }
            "perspective" | "thinlens" => {
                let thin = c.kind.get_ref() == "thinlens";
                let what = if thin {
                    "a thinlens camera"
                } else {
                    "a perspective camera"
                };
                let keys: &[&str] = if thin {
                    &[
                        "origin",
                        "target",
                        "up",
                        "fov",
                        "fov_axis",
                        "aperture_radius",
                        "focus_distance",
                    ]
                } else {
                    &["origin", "target", "up", "fov", "fov_axis"]
                };
                cx.only(&present, keys, what)?;
                let origin = cx.finite3(cx.need(&c.origin, "origin", what, &at)?, "origin")?;
                let target = cx.finite3(cx.need(&c.target, "target", what, &at)?, "target")?;
                let up = cx.finite3(cx.need(&c.up, "up", what, &at)?, "up")?;
                let fov = cx.need(&c.fov, "fov", what, &at)?;
                if !(fov.get_ref() > &0.0 && fov.get_ref() < &180.0) {
                    return cx.err(fov.span(), "'fov' must be between 0 and 180 degrees");
                }
                let fov_axis = match &c.fov_axis {
                    None => FovAxis::X,
                    Some(a) => FovAxis::parse(a.get_ref()).map_or_else(
                        || {
                            cx.err(
                                a.span(),
                                "'fov_axis' must be one of: x, y, diagonal, smaller, larger",
                            )
                        },
                        Ok,
                    )?,
                };
                let fov = *fov.get_ref();
                if thin {
                    let radius = cx.need(&c.aperture_radius, "aperture_radius", what, &at)?;
                    if !(*radius.get_ref() >= 0.0 && radius.get_ref().is_finite()) {
                        return cx.err(radius.span(), "'aperture_radius' must be a number ≥ 0");
                    }
                    let focus = cx.need(&c.focus_distance, "focus_distance", what, &at)?;
                    if !(*focus.get_ref() > 0.0 && focus.get_ref().is_finite()) {
                        return cx.err(focus.span(), "'focus_distance' must be a number > 0");
                    }
                    CameraDesc::ThinLens {
                        origin,
                        target,
                        up,
                        fov,
                        fov_axis,
                        aperture_radius: *radius.get_ref(),
                        focus_distance: *focus.get_ref(),
                    }
                } else {
                    CameraDesc::Perspective {
                        origin,
                        target,
                        up,
                        fov,
                        fov_axis,
                    }
                }
            }
            "orthographic" => {
                let what = "an orthographic camera";
                cx.only(&present, &["origin", "target", "up", "view_width"], what)?;
                let origin = cx.finite3(cx.need(&c.origin, "origin", what, &at)?, "origin")?;
                let target = cx.finite3(cx.need(&c.target, "target", what, &at)?, "target")?;
                let up = cx.finite3(cx.need(&c.up, "up", what, &at)?, "up")?;
                let w = cx.need(&c.view_width, "view_width", what, &at)?;
                if !(*w.get_ref() > 0.0 && w.get_ref().is_finite()) {
                    return cx.err(w.span(), "'view_width' must be a number > 0");
                }
                CameraDesc::orthographic_look_at(origin, target, up, *w.get_ref())
            }
            other => {
                return cx.err(
                    c.kind.span(),
                    format!(
                        "unknown camera type '{other}' (expected 'pinhole', 'perspective', \
                         'thinlens' or 'orthographic')"
                    ),
                )
            }
        };
        if let Err(e) = cd.validate() {
            return cx.err(at, format!("camera '{}' {e}", crate::input::shorten(&name)));
        }
        desc.cameras.push((name, cd));
    }

    for t in file.texture.values() {
        let tex = texture(&cx, t, base)?;
        desc.textures.push(tex);
    }
    let tex = Textures {
        ids: file
            .texture
            .keys()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i as u32))
            .collect(),
        list: &desc.textures,
    };
    // Materials in the order of their names (a blend names its parts).
    let material_ids: BTreeMap<&str, u32> = file
        .material
        .keys()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i as u32))
        .collect();
    for m in file.material.values() {
        let mat = material(&cx, m, &tex, &material_ids)?;
        desc.materials.push(mat);
    }
    check_blends(&cx, &file.material, &desc.materials)?;
    // Shapes without a material (lights, usually) reflect nothing.
    let mut black: Option<u32> = None;

    for shape in &file.shape {
        let s = shape.get_ref();
        let at = shape.span();
        let material = match &s.material {
            Some(m) => match material_ids.get(m.get_ref().as_str()) {
                Some(&id) => id,
                None => {
                    let known: Vec<&str> = material_ids.keys().copied().collect();
                    return cx.err(
                        m.span(),
                        format!(
                            "unknown material '{}' (defined: {})",
                            m.get_ref(),
                            list_or_none(&known)
                        ),
                    );
                }
            },
            None => *black.get_or_insert_with(|| {
                desc.materials.push(Material::new(Bsdf::Black, true));
                (desc.materials.len() - 1) as u32
            }),
        };
        let emission = match &s.emission {
            Some(e) => Some(match e.get_ref() {
                ColorT::Texture(name) => {
                    let i = cx.texture_id(e.span(), name, "emission", &tex)?;
                    desc.emission_textures.push((desc.shapes.len(), i));
                    tex.list[i as usize].mean()
                }
                _ => cx.color(e, "emission", None)?,
            }),
            None => None,
        };
        let present = [
            ("vertices", span_of(&s.vertices)),
            ("center", span_of(&s.center)),
            ("radius", span_of(&s.radius)),
            ("normal", span_of(&s.normal)),
            ("p0", span_of(&s.p0)),
            ("p1", span_of(&s.p1)),
            ("file", span_of(&s.file)),
            ("positions", span_of(&s.positions)),
            ("indices", span_of(&s.indices)),
            ("normals", span_of(&s.normals)),
            ("uvs", span_of(&s.uvs)),
            ("smooth", span_of(&s.smooth)),
        ];
        let geometry = match s.kind.get_ref().as_str() {
            kind @ ("triangle" | "quad") => {
                let n = if kind == "triangle" { 3 } else { 4 };
                let what = format!("a {kind}");
                cx.only(&present, &["vertices"], &what)?;
                let v = cx.need(&s.vertices, "vertices", &what, &at)?;
                if v.get_ref().len() != n {
                    return cx.err(
                        v.span(),
                        format!("{what} needs {n} vertices, found {}", v.get_ref().len()),
                    );
                }
                if !v.get_ref().iter().flatten().all(|c| c.is_finite()) {
                    return cx.err(v.span(), "vertices must be finite numbers");
                }
                let positions: Vec<Vec3> = v.get_ref().iter().map(|p| Vec3::from(*p)).collect();
                let indices = if n == 3 {
                    vec![[0, 1, 2]]
                } else {
                    vec![[0, 1, 2], [0, 2, 3]]
                };
                // A quad's corners get uv (0,0), (1,0), (1,1), (0,1), as Mitsuba's rectangle.
                let uvs = (n == 4).then(|| vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
                GeometryDesc::Mesh(TriangleMesh {
                    tangents: None,
                    positions,
                    normals: None,
                    uvs,
                    indices,
                })
            }
            "sphere" => {
                cx.only(&present, &["center", "radius"], "a sphere")?;
                let center =
                    cx.finite3(cx.need(&s.center, "center", "a sphere", &at)?, "center")?;
                let r = cx.need(&s.radius, "radius", "a sphere", &at)?;
                if !(r.get_ref().is_finite() && *r.get_ref() > 0.0) {
                    return cx.err(r.span(), "'radius' must be a positive number");
                }
                GeometryDesc::Sphere {
                    center,
                    radius: *r.get_ref(),
                }
            }
            "disk" => {
                let what = "a disk";
                cx.only(&present, &["center", "normal", "radius"], what)?;
                let center = cx.finite3(cx.need(&s.center, "center", what, &at)?, "center")?;
                let nv = cx.need(&s.normal, "normal", what, &at)?;
                let Some(n) = cx.finite3(nv, "normal")?.try_normalize() else {
                    return cx.err(nv.span(), "'normal' must not be zero");
                };
                let r = cx.need(&s.radius, "radius", what, &at)?;
                if !(r.get_ref().is_finite() && *r.get_ref() > 0.0) {
                    return cx.err(r.span(), "'radius' must be a positive number");
                }
                let r = *r.get_ref();
                // The unit disk's frame: x and y span the plane, z = x × y is the normal.
                let x = n.any_orthonormal_vector();
                let y = n.cross(x);
                let m = Mat4::from_cols(
                    (x * r).extend(0.0),
                    (y * r).extend(0.0),
                    n.extend(0.0),
                    center.extend(1.0),
                );
                let mut disk = TriangleMesh::unit_disk();
                disk.transform(&m);
                GeometryDesc::Mesh(disk)
            }
            "cylinder" => {
                let what = "a cylinder";
                cx.only(&present, &["p0", "p1", "radius"], what)?;
                let p0 = cx.finite3(cx.need(&s.p0, "p0", what, &at)?, "p0")?;
                let p1 = cx.finite3(cx.need(&s.p1, "p1", what, &at)?, "p1")?;
                let r = cx.need(&s.radius, "radius", what, &at)?;
                let m = crate::scene::cylinder::cylinder_transform(Mat4::IDENTITY, p0, p1, *r.get_ref())
                    .or_else(|why| cx.err(at.clone(), why))?;
                let mut mesh = crate::scene::cylinder::unit_cylinder();
                mesh.transform(&m);
                GeometryDesc::Mesh(mesh)
            }
            "mesh" => {
                cx.only(
                    &present,
                    &["file", "positions", "indices", "normals", "uvs", "smooth"],
                    "a mesh",
                )?;
                let mesh = match (&s.file, &s.positions) {
                    (Some(f), None) => {
                        if s.indices.is_some() || s.normals.is_some() || s.uvs.is_some() {
                            return cx.err(
                                f.span(),
                                "a mesh takes either 'file' or 'positions' and 'indices' (with optional 'normals' and 'uvs'), not both",
                            );
                        }
                        let p = base.join(f.get_ref());
                        let ext = p
                            .extension()
                            .and_then(|e| e.to_str())
                            .unwrap_or("")
                            .to_ascii_lowercase();
                        if ext != "obj" && ext != "ply" && ext != "serialized" {
                            return cx.err(
                                f.span(),
                                format!(
                                    "unsupported mesh file '{}' (expected an .obj or .ply file, \
                                     or Mitsuba's .serialized)",
                                    f.get_ref()
                                ),
                            );
                        }
                        if let Some(why) = crate::input::file_problem(&p) {
                            return cx.err(
                                f.span(),
                                format!(
                                    "mesh file '{}' {why} (looked for {})",
                                    crate::input::shorten(f.get_ref()),
                                    p.display()
                                ),
                            );
                        }
                        let mut m = if ext == "obj" {
                            let mut m = load_obj(&p)?;
                            m.flip_v();
                            m
                        } else if ext == "ply" {
                            load_ply(&p)?.into_triangle_mesh()
                        } else {
                            // The file's first mesh (Mitsuba's default shape_index).
                            crate::scene::serialized::load_serialized(&p, 0)?
                        };
                        match s.smooth.as_ref().map(|v| *v.get_ref()) {
                            Some(true) if m.normals.is_none() => m.recompute_vertex_normals(),
                            Some(false) => m.normals = None,
                            _ => {}
                        }
                        m
                    }
                    (None, Some(pos)) => {
                        let idx = cx.need(&s.indices, "indices", "a mesh with 'positions'", &at)?;
                        if !pos.get_ref().iter().flatten().all(|c| c.is_finite()) {
                            return cx.err(pos.span(), "positions must be finite numbers");
                        }
                        let n = pos.get_ref().len() as u32;
                        if let Some(bad) = idx.get_ref().iter().flatten().find(|&&i| i >= n) {
                            return cx.err(idx.span(), format!("index {bad} out of range: the mesh has {n} positions (indices start at 0)"));
                        }
                        let normals = match &s.normals {
                            Some(ns) if ns.get_ref().len() != pos.get_ref().len() => {
                                return cx.err(
                                    ns.span(),
                                    format!(
                                        "'normals' needs one normal per position ({}), found {}",
                                        n,
                                        ns.get_ref().len()
                                    ),
                                );
                            }
                            Some(ns) if !ns.get_ref().iter().flatten().all(|c| c.is_finite()) => {
                                return cx.err(ns.span(), "normals must be finite numbers");
                            }
                            Some(ns) => Some(
                                ns.get_ref()
                                    .iter()
                                    .map(|v| Vec3::from(*v).normalize_or_zero())
                                    .collect(),
                            ),
                            None => None,
                        };
                        let uvs = match &s.uvs {
                            Some(uv) if uv.get_ref().len() != pos.get_ref().len() => {
                                return cx.err(
                                    uv.span(),
                                    format!(
                                        "'uvs' needs one [u, v] per position ({}), found {}",
                                        n,
                                        uv.get_ref().len()
                                    ),
                                );
                            }
                            Some(uv) if !uv.get_ref().iter().flatten().all(|c| c.is_finite()) => {
                                return cx.err(uv.span(), "uvs must be finite numbers");
                            }
                            Some(uv) => Some(uv.get_ref().iter().map(|t| Vec2::from(*t)).collect()),
                            None => None,
                        };
                        let mut m = TriangleMesh {
                            tangents: None,
                            positions: pos.get_ref().iter().map(|p| Vec3::from(*p)).collect(),
                            normals,
                            uvs,
                            indices: idx.get_ref().clone(),
                        };
                        if let Some(sm) = &s.smooth {
                            if m.normals.is_some() {
                                return cx.err(
                                    sm.span(),
                                    "'smooth' does not apply to a mesh with 'normals' (the normals given are used)",
                                );
                            }
                            if *sm.get_ref() {
                                m.recompute_vertex_normals();
                            }
                        }
                        m
                    }
                    _ => {
                        return cx.err(
                            at,
                            "a mesh needs either 'file' or 'positions' and 'indices'",
                        )
                    }
                };
                GeometryDesc::Mesh(mesh)
            }
            other => {
                return cx.err(
                    s.kind.span(),
                    format!(
                    "unknown shape type '{other}' (expected triangle, quad, sphere, disk, cylinder or mesh)"
                ),
                )
            }
        };
        if let (Some(e), GeometryDesc::Mesh(m)) = (&s.emission, &geometry) {
            let area: f32 = m
                .indices
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
            if area.is_nan() || area <= 0.0 {
                return cx.err(e.span(), "an emitting shape must have a positive area");
            }
        }
        let shape = ShapeDesc {
            geometry,
            material,
            emission,
        };
        instance::add_shape(
            &cx,
            &mut desc.shapes,
            &mut desc.groups,
            s.group.as_ref(),
            shape,
        )?;
    }
    desc.instances = instance::instances(&cx, &desc.groups, &file.instance)?;
    for light in &file.light {
        desc.lights.push(light_desc(&cx, light, &tex, base)?);
    }
    if let Some(name) = &desc.settings.camera {
        if !desc.cameras.iter().any(|(n, _)| n == name) {
            let span = file
                .render
                .as_ref()
                .and_then(|r| r.camera.as_ref())
                .map(|c| c.span())
                .unwrap_or(0..0);
            let names: Vec<&str> = desc.cameras.iter().map(|(n, _)| n.as_str()).collect();
            return cx.err(
                span,
                format!(
                    "no camera named '{name}' (defined: {})",
                    list_or_none(&names)
                ),
            );
        }
    }
    Ok(desc)
}

fn settings(cx: &Ctx, r: &RenderT) -> Result<FileSettings, SceneError> {
    // Each count within its bound (crate::limits).
    let positive = |v: &Option<Spanned<u32>>, key: &str| -> Result<Option<u32>, SceneError> {
        use crate::limits::*;
        let max = match key {
            "width" | "height" => MAX_SIZE,
            "spp" => MAX_SPP,
            "shadow_rays" => MAX_SHADOW_RAYS,
            _ => MAX_RR_DEPTH,
        };
        match v {
            Some(v) => match check(&format!("'{key}'"), *v.get_ref() as u64, 1, max) {
                Ok(()) => Ok(Some(*v.get_ref())),
                Err(m) => cx.err(v.span(), m),
            },
            None => Ok(None),
        }
    };
    let integrator = match &r.integrator {
        None => None,
        Some(i) => Some(IntegratorKind::parse(i.get_ref()).map_or_else(
            || {
                cx.err(
                    i.span(),
                    format!(
                        "unknown integrator '{}' (expected 'path', 'direct', 'photon' or 'sppm')",
                        i.get_ref()
                    ),
                )
            },
            Ok,
        )?),
    };
    let max_depth = match &r.max_depth {
        None => None,
        Some(d) if *d.get_ref() == -1 => None,
        Some(d) if (0..=crate::limits::MAX_DEPTH as i64).contains(d.get_ref()) => {
            Some(*d.get_ref() as u32)
        }
        Some(d) => {
            return cx.err(
                d.span(),
                format!(
                    "'max_depth' must be -1 (unlimited) or a path length of 0 to {}",
                    crate::limits::MAX_DEPTH
                ),
            )
        }
    };
    let rr_survival = match &r.rr_survival {
        Some(p) if !(*p.get_ref() > 0.0 && *p.get_ref() <= crate::limits::MAX_RR_SURVIVAL) => {
            return cx.err(
                p.span(),
                format!(
                    "'rr_survival' must be a probability between 0 and 1 (exclusive), at most {}",
                    crate::limits::MAX_RR_SURVIVAL
                ),
            )
        }
        p => p.as_ref().map(|p| *p.get_ref()),
    };
    let sampler = match &r.sampler {
        None => None,
        Some(v) => Some(crate::sampler::SamplerKind::parse(v.get_ref()).map_or_else(
            || {
                cx.err(
                    v.span(),
                    format!(
                        "unknown sampler '{}' (expected 'sobol' or 'independent')",
                        v.get_ref()
                    ),
                )
            },
            Ok,
        )?),
    };
    Ok(FileSettings {
        sampler,
        width: positive(&r.width, "width")?,
        height: positive(&r.height, "height")?,
        spp: positive(&r.spp, "spp")?,
        seed: r.seed,
        integrator,
        max_depth,
        shadow_rays: positive(&r.shadow_rays, "shadow_rays")?,
        rr_survival,
        camera: r.camera.as_ref().map(|c| c.get_ref().clone()),
        rr_depth: positive(&r.rr_depth, "rr_depth")?,
        hide_emitters: r.hide_emitters,
        ..Default::default()
    })
}

fn material(
    cx: &Ctx,
    m: &Spanned<MaterialT>,
    tex: &Textures,
    ids: &BTreeMap<&str, u32>,
) -> Result<Material, SceneError> {
    let t = m.get_ref();
    let at = m.span();
    let present = [
        ("albedo", span_of(&t.albedo)),
        ("sigma", span_of(&t.sigma)),
        ("reflectance", span_of(&t.reflectance)),
        ("specular", span_of(&t.specular)),
        ("ior", span_of(&t.ior)),
        ("ext_ior", span_of(&t.ext_ior)),
        ("material", span_of(&t.material)),
        ("eta", span_of(&t.eta)),
        ("k", span_of(&t.k)),
        ("alpha", span_of(&t.alpha)),
        ("alpha_u", span_of(&t.alpha_u)),
        ("alpha_v", span_of(&t.alpha_v)),
        ("distribution", span_of(&t.distribution)),
        ("nonlinear", span_of(&t.nonlinear)),
        ("two_sided", span_of(&t.two_sided)),
        ("base_color", span_of(&t.base_color)),
        ("roughness", span_of(&t.roughness)),
        ("anisotropic", span_of(&t.anisotropic)),
        ("metallic", span_of(&t.metallic)),
        ("spec_trans", span_of(&t.spec_trans)),
        ("spec_tint", span_of(&t.spec_tint)),
        ("sheen", span_of(&t.sheen)),
        ("sheen_tint", span_of(&t.sheen_tint)),
        ("flatness", span_of(&t.flatness)),
        ("clearcoat", span_of(&t.clearcoat)),
        ("clearcoat_gloss", span_of(&t.clearcoat_gloss)),
        ("diff_trans", span_of(&t.diff_trans)),
        ("weight", span_of(&t.weight)),
        ("materials", span_of(&t.materials)),
    ];
    let kind = t.kind.get_ref().as_str();
    // Two-sided by default, except the principled BSDFs, which have back sides of their own.
    let two_sided = t
        .two_sided
        .as_ref()
        .map_or(!kind.starts_with("principled"), |v| *v.get_ref());
    let what = format!(
        "{} {kind} material",
        if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        }
    );
    // A main colour: required, or with a default.
    let main = |v: &Option<Spanned<ColorT>>, key: &str, default: Option<f32>| match (v, default) {
        (Some(v), _) => cx.main_color(v, key, tex),
        (None, Some(d)) => Ok((Color::splat(d), None)),
        (None, None) => cx.need(v, key, &what, &at).map(|_| unreachable!()),
    };
    let eta_of = |default: f32| -> Result<f32, SceneError> {
        Ok(cx.ior(&t.ior, "ior", default)? / cx.ior(&t.ext_ior, "ext_ior", 1.0)?)
    };
    let mut texture = None;
    let mut bindings = Vec::new();
    let bsdf = match kind {
        "blend" => {
            cx.only(&present, &["weight", "materials", "two_sided"], &what)?;
            blend(cx, t, &at, tex, ids, &mut bindings)?
        }
        "lambert" => {
            cx.only(&present, &["albedo", "two_sided"], &what)?;
            let (albedo, tx) = main(&t.albedo, "albedo", None)?;
            texture = tx;
            Bsdf::Lambert(Lambert { albedo })
        }
        "oren_nayar" => {
            cx.only(&present, &["albedo", "sigma", "two_sided"], &what)?;
            let (albedo, tx) = main(&t.albedo, "albedo", None)?;
            texture = tx;
            let sigma = cx.need(&t.sigma, "sigma", &what, &at)?;
            if !(sigma.get_ref().is_finite() && *sigma.get_ref() >= 0.0 && *sigma.get_ref() <= 90.0) {
                return cx.err(sigma.span(), "'sigma' (roughness, in degrees) must be between 0 and 90");
            }
            Bsdf::OrenNayar(OrenNayar::new(albedo, sigma.get_ref().to_radians()))
        }
        "mirror" => {
            cx.only(&present, &["reflectance", "two_sided"], &what)?;
            let (reflectance, tx) = main(&t.reflectance, "reflectance", Some(1.0))?;
            texture = tx;
            Bsdf::Mirror(Mirror { reflectance })
        }
        "dielectric" => {
            cx.only(&present, &["ior", "ext_ior"], &what)?;
            cx.need(&t.ior, "ior", &what, &at)?;
            Bsdf::Dielectric(Dielectric::new(eta_of(1.5046)?))
        }
        "thindielectric" => {
            cx.only(&present, &["ior", "ext_ior"], &what)?;
            Bsdf::ThinDielectric(ThinDielectric::new(eta_of(1.5046)?))
        }
        "roughdielectric" => {
            cx.only(&present, &["ior", "ext_ior", "alpha", "alpha_u", "alpha_v", "distribution"], &what)?;
            let distr = cx.roughness(t, &at, tex, Some(&mut bindings))?;
            Bsdf::RoughDielectric(RoughDielectric::new(distr, eta_of(1.5046)?))
        }
        "conductor" | "roughconductor" => {
            let rough = kind == "roughconductor";
            let mut keys = vec!["material", "eta", "k", "reflectance", "two_sided"];
            if rough {
                keys.extend(["alpha", "alpha_u", "alpha_v", "distribution"]);
            }
            cx.only(&present, &keys, &what)?;
            let (eta, k) = match (&t.material, &t.eta, &t.k) {
                (Some(name), None, None) => conductor_ior(name.get_ref()).map_or_else(
                    || {
                        cx.err(
                            name.span(),
                            format!(
                                "unknown conductor material '{}' (expected none or one of {})",
                                name.get_ref(),
                                conductor_names().collect::<Vec<_>>().join(", ")
                            ),
                        )
                    },
                    Ok,
                )?,
                (None, None, None) => (Color::ZERO, Color::ONE),
                (None, Some(eta), Some(k)) => (cx.color(eta, "eta", None)?, cx.color(k, "k", None)?),
                (Some(name), _, _) => {
                    return cx.err(name.span(), "give either 'material' or 'eta' and 'k', not both")
                }
                (None, eta, k) => {
                    let span = eta.as_ref().or(k.as_ref()).map_or(at.clone(), |v| v.span());
                    return cx.err(span, "a conductor's index of refraction needs both 'eta' and 'k' (or a named 'material')");
                }
            };
            let (r, tx) = main(&t.reflectance, "reflectance", Some(1.0))?;
            texture = tx;
            if rough {
                let distr = cx.roughness(t, &at, tex, Some(&mut bindings))?;
                Bsdf::RoughConductor(RoughConductor::new(distr, eta, k, r))
            } else if eta == Color::ZERO && k == Color::ONE {
                // material = "none": a perfect mirror (as Mitsuba's conductor).
                Bsdf::Mirror(Mirror { reflectance: r })
            } else {
                Bsdf::Conductor(Conductor::new(eta, k, r))
            }
        }
        "plastic" | "roughplastic" => {
            let rough = kind == "roughplastic";
            let mut keys = vec!["albedo", "specular", "ior", "ext_ior", "nonlinear", "two_sided"];
            if rough {
                keys.extend(["alpha", "distribution"]);
            }
            cx.only(&present, &keys, &what)?;
            let (d, tx) = main(&t.albedo, "albedo", Some(0.5))?;
            texture = tx;
            let (spec, spec_tx) = main(&t.specular, "specular", Some(1.0))?;
            bindings.extend(spec_tx.map(|texture| Binding {
                texture,
                slot: slots::PLASTIC_SPECULAR,
            }));
            let nonlinear = t.nonlinear.as_ref().is_some_and(|v| *v.get_ref());
            let eta = eta_of(1.49)?;
            if rough {
                let distr = cx.roughness(t, &at, tex, None)?;
                Bsdf::RoughPlastic(RoughPlastic::new(distr.kind, distr.alpha_u, eta, d, spec, nonlinear))
            } else {
                Bsdf::Plastic(Plastic::new(eta, d, spec, nonlinear))
            }
        }
        "black" => {
            cx.only(&present, &[], &what)?;
            Bsdf::Black
        }
        "principled" | "principledthin" => principled::bsdf(cx, t, kind, &present, &what, tex, &mut texture)?,
        other => return cx.err(t.kind.span(), format!("unknown material type '{other}' (expected lambert, oren_nayar, mirror, dielectric, thindielectric, roughdielectric, conductor, roughconductor, plastic, roughplastic, principled, principledthin, blend or black)")),
    };
    bindings.extend(texture.map(|texture| Binding {
        texture,
        slot: MAIN_COLOR,
    }));
    Ok(Material::new(bsdf, two_sided).with_slots(bindings))
}

/// A `blend` material: `weight` (a number in [0, 1] or a texture) of the second of its two
/// `materials` (names), 1 − weight of the first.
fn blend(
    cx: &Ctx,
    t: &MaterialT,
    at: &std::ops::Range<usize>,
    tex: &Textures,
    ids: &BTreeMap<&str, u32>,
    bindings: &mut Vec<Binding>,
) -> Result<Bsdf, SceneError> {
    let what = "a blend material";
    let names = cx.need(&t.materials, "materials", what, at)?;
    let [first, second] = names.get_ref().as_slice() else {
        return cx.err(
            names.span(),
            format!(
                "a blend mixes exactly two materials, ['first', 'second']; found {}",
                names.get_ref().len()
            ),
        );
    };
    let id = |name: &String| match ids.get(name.as_str()) {
        Some(&i) => Ok(i),
        None => {
            let known: Vec<&str> = ids.keys().copied().collect();
            cx.err(
                names.span(),
                format!(
                    "unknown material '{}' in 'materials' (defined: {})",
                    crate::input::shorten(name),
                    list_or_none(&known)
                ),
            )
        }
    };
    let (first, second) = (id(first)?, id(second)?);
    let w = cx.need(&t.weight, "weight", what, at)?;
    let weight = match w.get_ref() {
        FloatT::Num(x) if (0.0..=1.0).contains(x) => *x,
        FloatT::Num(x) => {
            return cx.err(
                w.span(),
                format!("'weight' must be between 0 and 1, got {x}"),
            )
        }
        FloatT::Texture(name) => {
            let i = cx.texture_id(w.span(), name, "weight", tex)?;
            bindings.push(Binding {
                texture: i,
                slot: crate::slot!(Float, Blend, |b, v| b.weight = v),
            });
            tex.list[i as usize].mean_1()
        }
    };
    Ok(Bsdf::Blend(Blend {
        weight,
        first,
        second,
    }))
}

/// Blends nest at most [`MAX_BLEND_DEPTH`] deep, and none contains itself.
fn check_blends(
    cx: &Ctx,
    named: &BTreeMap<String, Spanned<MaterialT>>,
    materials: &[Material],
) -> Result<(), SceneError> {
    // Depth of material i, or None beyond the bound (which a cycle always is).
    fn depth(materials: &[Material], i: u32, level: u32) -> Option<u32> {
        if level > MAX_BLEND_DEPTH {
            return None;
        }
        match materials[i as usize].bsdf {
            Bsdf::Blend(b) => {
                let d = depth(materials, b.first, level + 1)?.max(depth(
                    materials,
                    b.second,
                    level + 1,
                )?);
                Some(d + 1)
            }
            _ => Some(0),
        }
    }
    for (i, m) in named.values().enumerate() {
        if depth(materials, i as u32, 0).is_none_or(|d| d > MAX_BLEND_DEPTH) {
            return cx.err(
                m.span(),
                format!(
                    "this blend nests blends more than {MAX_BLEND_DEPTH} deep, or contains itself"
                ),
            );
        }
    }
    Ok(())
}

fn texture(cx: &Ctx, t: &Spanned<TextureT>, base: &Path) -> Result<Texture, SceneError> {
    let v = t.get_ref();
    let at = t.span();
    let present = [
        ("file", span_of(&v.file)),
        ("raw", span_of(&v.raw)),
        ("filter", span_of(&v.filter)),
        ("wrap", span_of(&v.wrap)),
        ("color0", span_of(&v.color0)),
        ("color1", span_of(&v.color1)),
        ("uv_scale", span_of(&v.uv_scale)),
        ("uv_offset", span_of(&v.uv_offset)),
    ];
    let finite2 = |x: &Option<Spanned<[f32; 2]>>, key: &str, default: Vec2| match x {
        None => Ok(default),
        Some(x) if x.get_ref().iter().all(|c| c.is_finite()) => Ok(Vec2::from(*x.get_ref())),
        Some(x) => cx.err(
            x.span(),
            format!("'{key}' must be two finite numbers [u, v]"),
        ),
    };
    // uv ↦ uv · uv_scale + uv_offset.
    let to_uv = UvTransform::translate(finite2(&v.uv_offset, "uv_offset", Vec2::ZERO)?).after(
        UvTransform::scale(finite2(&v.uv_scale, "uv_scale", Vec2::ONE)?),
    );
    match v.kind.get_ref().as_str() {
        "bitmap" => {
            let what = "a bitmap texture";
            cx.only(
                &present,
                &["file", "raw", "filter", "wrap", "uv_scale", "uv_offset"],
                what,
            )?;
            let f = cx.need(&v.file, "file", what, &at)?;
            let p = base.join(f.get_ref());
            if let Some(why) = crate::input::file_problem(&p) {
                return cx.err(
                    f.span(),
                    format!(
                        "texture file '{}' {why} (looked for {})",
                        crate::input::shorten(f.get_ref()),
                        p.display()
                    ),
                );
            }
            let raw = v.raw.as_ref().is_some_and(|r| *r.get_ref());
            let bitmap = match Bitmap::load(&p, raw) {
                Ok(b) => b,
                Err(e) => {
                    return cx.err(
                        f.span(),
                        format!("cannot load texture {}: {}", p.display(), e.message),
                    )
                }
            };
            let mut b = BitmapTexture::new(Arc::new(bitmap));
            if let Some(fl) = &v.filter {
                b.filter = FilterType::parse(fl.get_ref()).map_or_else(
                    || {
                        cx.err(
                            fl.span(),
                            format!(
                                "unknown filter '{}' (expected 'bilinear' or 'nearest')",
                                fl.get_ref()
                            ),
                        )
                    },
                    Ok,
                )?;
            }
            if let Some(w) = &v.wrap {
                b.wrap = WrapMode::parse(w.get_ref()).map_or_else(
                    || {
                        cx.err(
                            w.span(),
                            format!(
                                "unknown wrap mode '{}' (expected 'repeat', 'mirror' or 'clamp')",
                                w.get_ref()
                            ),
                        )
                    },
                    Ok,
                )?;
            }
            b.to_uv = to_uv;
            Ok(Texture::Bitmap(b))
        }
        "checkerboard" => {
            cx.only(
                &present,
                &["color0", "color1", "uv_scale", "uv_offset"],
                "a checkerboard texture",
            )?;
            let c = |x: &Option<Spanned<ColorT>>, key: &str, d: f32| {
                x.as_ref()
                    .map(|x| cx.color(x, key, Some(1.0)))
                    .transpose()
                    .map(|c| c.unwrap_or(Color::splat(d)))
            };
            Ok(Texture::Checkerboard {
                color0: c(&v.color0, "color0", 0.4)?,
                color1: c(&v.color1, "color1", 0.2)?,
                to_uv,
            })
        }
        other => cx.err(
            v.kind.span(),
            format!("unknown texture type '{other}' (expected 'bitmap' or 'checkerboard')"),
        ),
    }
}

fn light_desc(
    cx: &Ctx,
    l: &Spanned<LightT>,
    tex: &Textures,
    base: &Path,
) -> Result<LightDesc, SceneError> {
    let v = l.get_ref();
    let at = l.span();
    let present = [
        ("position", span_of(&v.position)),
        ("intensity", span_of(&v.intensity)),
        ("direction", span_of(&v.direction)),
        ("irradiance", span_of(&v.irradiance)),
        ("radiance", span_of(&v.radiance)),
        ("cutoff_angle", span_of(&v.cutoff_angle)),
        ("beam_width", span_of(&v.beam_width)),
        ("texture", span_of(&v.texture)),
        ("up", span_of(&v.up)),
        ("to_world", span_of(&v.to_world)),
        ("file", span_of(&v.file)),
        ("scale", span_of(&v.scale)),
    ];
    match v.kind.get_ref().as_str() {
        "point" => {
            let what = "a point light";
            cx.only(&present, &["position", "intensity"], what)?;
            Ok(LightDesc::Point {
                position: cx.finite3(cx.need(&v.position, "position", what, &at)?, "position")?,
                intensity: cx.color(cx.need(&v.intensity, "intensity", what, &at)?, "intensity", None)?,
            })
        }
        "directional" => {
            let what = "a directional light";
            cx.only(&present, &["direction", "irradiance"], what)?;
            let d = cx.need(&v.direction, "direction", what, &at)?;
            let Some(direction) = cx.finite3(d, "direction")?.try_normalize() else {
                return cx.err(d.span(), "'direction' must not be zero");
            };
            Ok(LightDesc::Directional {
                direction,
                irradiance: cx.color(cx.need(&v.irradiance, "irradiance", what, &at)?, "irradiance", None)?,
            })
        }
        kind @ ("constant" | "environment") => {
            let what = format!("{} {kind} light", if kind == "constant" { "a" } else { "an" });
            cx.only(&present, &["radiance"], &what)?;
            Ok(LightDesc::Constant {
                radiance: cx.color(cx.need(&v.radiance, "radiance", &what, &at)?, "radiance", None)?,
            })
        }
        "spot" => {
            cx.only(
                &present,
                &[
                    "position",
                    "direction",
                    "up",
                    "to_world",
                    "intensity",
                    "cutoff_angle",
                    "beam_width",
                    "texture",
                ],
                "a spot light",
            )?;
            spot_desc(cx, v, &at, tex)
        }
        "envmap" => {
            cx.only(&present, &["file", "scale", "to_world"], "an envmap light")?;
            envmap_desc(cx, v, &at, base)
        }
        other => cx.err(
            v.kind.span(),
            format!("unknown light type '{other}' (expected point, directional, spot, constant, environment or envmap)"),
        ),
    }
}

/// A `to_world` matrix: four rows of four finite numbers (as Mitsuba's `<matrix>`), whose
/// last row is (0, 0, 0, 1).
fn to_world(cx: &Ctx, m: &Spanned<[[f32; 4]; 4]>) -> Result<glam::Mat4, SceneError> {
    let rows = m.get_ref();
    if !rows.iter().flatten().all(|x| x.is_finite()) || rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return cx.err(
            m.span(),
            "'to_world' must be four rows of four finite numbers, the last [0, 0, 0, 1]",
        );
    }
    Ok(glam::Mat4::from_cols_array_2d(rows).transpose())
}

/// A spot light (Mitsuba's `spot`): its frame from `to_world`, or from `position`,
/// `direction` (the axis) and `up` (which turns a projected texture; default +y, or +z for
/// a vertical axis) as Mitsuba's `<lookat>` makes it.
fn spot_desc(
    cx: &Ctx,
    v: &LightT,
    at: &std::ops::Range<usize>,
    tex: &Textures,
) -> Result<LightDesc, SceneError> {
    let what = "a spot light";
    let to_world = match &v.to_world {
        Some(m) => {
            if let Some(k) = [
                ("position", &v.position),
                ("direction", &v.direction),
                ("up", &v.up),
            ]
            .iter()
            .find_map(|(k, x)| x.as_ref().map(|x| (k, x.span())))
            {
                return cx.err(k.1, format!("'{}' and 'to_world' exclude each other", k.0));
            }
            let m4 = to_world(cx, m)?;
            if let Some(f) = crate::light::spot::frame_fault(glam::Mat3::from_mat4(m4)) {
                return cx.err(m.span(), f);
            }
            m4
        }
        None => {
            let p = cx.finite3(cx.need(&v.position, "position", what, at)?, "position")?;
            let d = cx.need(&v.direction, "direction", what, at)?;
            let dir = cx.finite3(d, "direction")?;
            let Some(axis) = dir.try_normalize() else {
                return cx.err(d.span(), "'direction' must not be zero");
            };
            let up = match &v.up {
                Some(u) => cx.finite3(u, "up")?,
                None if axis.y.abs() > 0.999 => glam::Vec3::Z,
                None => glam::Vec3::Y,
            };
            match crate::scene::xml::lookat(p, p + axis, up) {
                Some(m) => m,
                None => {
                    let s = v.up.as_ref().map_or(d.span(), |u| u.span());
                    return cx.err(s, "'up' must not be zero or parallel to 'direction'");
                }
            }
        }
    };
    let intensity = match &v.intensity {
        Some(i) => cx.color(i, "intensity", None)?,
        None => Color::ONE,
    };
    let cutoff_angle = v.cutoff_angle.as_ref().map_or(20.0, |c| *c.get_ref());
    let beam_width = v
        .beam_width
        .as_ref()
        .map_or(cutoff_angle * 0.75, |b| *b.get_ref());
    if let Some(f) = crate::light::spot::angles_fault(cutoff_angle, beam_width) {
        let s = match (&v.cutoff_angle, &v.beam_width) {
            (Some(c), _) if f.starts_with("'cutoff") => c.span(),
            (_, Some(b)) if f.starts_with("'beam") => b.span(),
            _ => at.clone(),
        };
        return cx.err(s, f);
    }
    let texture = match &v.texture {
        None => None,
        Some(t) => match tex.ids.get(t.get_ref().as_str()) {
            Some(&i) => Some(i),
            None => {
                let known: Vec<&str> = tex.ids.keys().copied().collect();
                return cx.err(
                    t.span(),
                    format!(
                        "unknown texture '{}' (defined: {})",
                        crate::input::shorten(t.get_ref()),
                        list_or_none(&known)
                    ),
                );
            }
        },
    };
    Ok(LightDesc::Spot {
        to_world,
        intensity,
        cutoff_angle,
        beam_width,
        texture,
    })
}

/// An image environment (Mitsuba's `envmap`): `file` (OpenEXR, Radiance HDR or PNG), `scale`
/// (default 1, not negative) and `to_world` (a rotation).
fn envmap_desc(
    cx: &Ctx,
    v: &LightT,
    at: &std::ops::Range<usize>,
    base: &Path,
) -> Result<LightDesc, SceneError> {
    let f = cx.need(&v.file, "file", "an envmap light", at)?;
    let scale = match &v.scale {
        Some(s) if *s.get_ref() < 0.0 => {
            return cx.err(
                s.span(),
                format!("'scale' must not be negative, got {}", s.get_ref()),
            )
        }
        Some(s) => *s.get_ref(),
        None => 1.0,
    };
    let to_world = match &v.to_world {
        Some(m) => to_world(cx, m)?,
        None => glam::Mat4::IDENTITY,
    };
    let p = base.join(f.get_ref());
    if let Some(why) = crate::input::file_problem(&p) {
        return cx.err(
            f.span(),
            format!(
                "environment map '{}' {why} (looked for {})",
                crate::input::shorten(f.get_ref()),
                p.display()
            ),
        );
    }
    let image = match Bitmap::load(&p, false) {
        Ok(b) => b,
        Err(e) => {
            return cx.err(
                f.span(),
                format!("cannot load environment map {}: {}", p.display(), e.message),
            )
        }
    };
    let m3 = glam::Mat3::from_mat4(to_world);
    if let Some(fault) = crate::light::envmap::fault(image.width, image.height, m3) {
        let s = match &v.to_world {
            Some(m) if !fault.contains("pixels") => m.span(),
            _ => f.span(),
        };
        return cx.err(s, fault);
    }
    Ok(LightDesc::Envmap {
        image: Arc::new(image),
        scale,
        to_world,
    })
}
