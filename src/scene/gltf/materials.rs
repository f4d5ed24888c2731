//! Materials (glTF 2.0 §3.9 and Appendix B) and their textures.
//!
//! glTF's metallic-roughness model mixes a metal (a GGX microfacet reflection whose Fresnel
//! term goes from the base colour at normal incidence to white) and a dielectric (GGX
//! reflection with the Fresnel term of `ior` over a diffuse base, or refraction where
//! KHR_materials_transmission says so) by `metallic`. [`bsdf_for`] is the one place that maps
//! it onto mcrt's BSDFs; docs/gltf.md says how each choice differs from Appendix B.

use super::Loader;
use crate::material::textured::{slots, Binding, Slot};
use crate::material::{Bsdf, Material, Principled};
use crate::scene::SceneError;
use crate::texture::{Bitmap, BitmapTexture, FilterType, Texture, UvTransform, WrapMode};
use crate::Color;
use std::sync::Arc;

/// A glTF material's parameters; where a texture varies one, its mean (the constant the
/// BSDF is built with, [`crate::material::textured`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbr {
    pub base: Color,
    pub metallic: f32,
    pub roughness: f32,
    pub ior: f32,
    pub transmission: f32,
    /// KHR_materials_specular: the dielectric's specular strength and colour.
    pub specular: Color,
    /// KHR_materials_clearcoat: the coat's weight and roughness.
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    /// KHR_materials_sheen: the largest component of sheenColorFactor.
    pub sheen: f32,
}

impl Default for Pbr {
    /// glTF's defaults (§5.19, §5.22): white, fully metallic, fully rough, ior 1.5.
    fn default() -> Self {
        Pbr {
            base: Color::ONE,
            metallic: 1.0,
            roughness: 1.0,
            ior: 1.5,
            transmission: 0.0,
            specular: Color::ONE,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            sheen: 0.0,
        }
    }
}

/// The mcrt BSDF that renders a glTF material: Mitsuba's `principled` (the Disney BSDF),
/// whose base colour, metallic, roughness, `spec_trans` and η are glTF's base colour,
/// metallic, roughness, transmission and ior (docs/gltf.md compares it with Appendix B).
/// KHR_materials_clearcoat and _sheen go onto principled's clearcoat (weight, gloss = 1 −
/// roughness) and sheen (weight; untinted), as Blender's glTF importer maps them onto its
/// Principled BSDF: approximations, since those lobes are not glTF's (GTR1 at a quarter
/// strength, Burley's sheen instead of the Charlie distribution).
pub fn bsdf_for(p: &Pbr) -> Bsdf {
    Bsdf::Principled(Principled {
        base_color: p.base,
        roughness: p.roughness,
        metallic: p.metallic,
        spec_trans: p.transmission,
        clearcoat: p.clearcoat,
        clearcoat_gloss: 1.0 - p.clearcoat_roughness,
        sheen: p.sheen,
        eta: Principled::eta_of(Some(p.ior), None, p.transmission != 0.0),
        ..Principled::default()
    })
}

/// What an emissive material emits: the radiance, or its mean where `texture` (an index
/// into the scene's textures, `SceneDesc::emission_textures`) gives it over the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    pub radiance: Color,
    pub texture: Option<u32>,
}

/// How a texture's pixels p become the values a slot reads.
#[derive(Clone, Copy, Debug)]
enum Map {
    /// p·mul + add, clamped at 0.
    Affine(Color, Color),
    /// One channel (0 = R, 1 = G, 2 = B) times a factor, clamped to [0, 1], as a grey image,
    /// which a float slot reads exactly (`Texture::eval_1` of a grey bitmap is its value).
    Channel(usize, f32),
}

impl Map {
    fn apply(self, p: Color) -> Color {
        match self {
            Map::Affine(mul, add) => (p * mul + add).max(Color::ZERO),
            Map::Channel(c, f) => Color::splat((p[c] * f).clamp(0.0, 1.0)),
        }
    }
}

/// The slots of the principled parameters glTF textures: glTF's metalness, roughness and
/// transmission are principled's `metallic`, `roughness` and `spec_trans` ([`bsdf_for`]).
const METALLIC: Slot = crate::slot!(Float, Principled, |b, v| b.metallic = v);
const ROUGHNESS: Slot = crate::slot!(Float, Principled, |b, v| b.roughness = v);
const SPEC_TRANS: Slot = crate::slot!(Float, Principled, |b, v| b.spec_trans = v);

impl Loader<'_> {
    /// The mcrt material (index into the scene's) and the emission of a glTF material, made
    /// once per material.
    pub fn material(
        &mut self,
        m: &::gltf::Material,
    ) -> Result<(u32, Option<Emission>), SceneError> {
        if let Some(&done) = self.material_cache.get(&m.index()) {
            return Ok(done);
        }
        let what = match (m.index(), m.name()) {
            (Some(i), Some(n)) => format!("materials[{i}] ('{}')", crate::input::shorten(n)),
            (Some(i), None) => format!("materials[{i}]"),
            (None, _) => "the default material".to_string(),
        };
        let (pbr, slots) = self.pbr(m, &what)?;
        let mut mat = Material::new(bsdf_for(&pbr), m.double_sided());
        mat.slots = slots.into_boxed_slice();
        if let Some(n) = m.normal_texture() {
            mat.normal_map = self.normal_texture(&n, &what)?;
        }
        let emission = self.emission(m, &what)?;
        let index = self.desc.materials.len() as u32;
        self.desc.materials.push(mat);
        self.material_cache.insert(m.index(), (index, emission));
        Ok((index, emission))
    }

    /// The material's parameters (textured ones at their means), and the bindings of its
    /// textures: the base colour, metalness (B), roughness (G) and transmission (R).
    fn pbr(&mut self, m: &::gltf::Material, what: &str) -> Result<(Pbr, Vec<Binding>), SceneError> {
        let mr = m.pbr_metallic_roughness();
        let f = mr.base_color_factor();
        let mut p = Pbr {
            base: Color::new(f[0], f[1], f[2]),
            metallic: mr.metallic_factor(),
            roughness: mr.roughness_factor(),
            ior: m.ior().unwrap_or(1.5),
            ..Pbr::default()
        };
        if let Some(t) = m.transmission() {
            p.transmission = t.transmission_factor();
        }
        if let Some(s) = m.specular() {
            p.specular = Color::from(s.specular_color_factor()) * s.specular_factor();
            if s.specular_texture().is_some() || s.specular_color_texture().is_some() {
                self.approximate(format!("{what}: the specular textures are ignored"));
            }
        }
        let ext = |name: &str, key: &str| extension_factor(m, name, key);
        p.clearcoat = ext("KHR_materials_clearcoat", "clearcoatFactor");
        p.clearcoat_roughness = ext("KHR_materials_clearcoat", "clearcoatRoughnessFactor");
        p.sheen = ext("KHR_materials_sheen", "sheenColorFactor");
        // Factors are checked before they scale textures.
        self.check_pbr(&p, what)?;
        let mut slots = Vec::new();
        let mut bind = |l: &mut Self, info: Option<::gltf::texture::Info>, map, slot, name| {
            let Some(info) = info else {
                return Ok(None);
            };
            let w = format!("{what}.{name}");
            let raw = !matches!(slot, Slot::Color(_));
            let Some(texture) = l.texture(&info, raw, map, &w)? else {
                return Ok(None);
            };
            slots.push(Binding { texture, slot });
            Ok::<_, SceneError>(Some(l.desc.textures[texture as usize].mean()))
        };
        let base = Map::Affine(p.base, Color::ZERO);
        let tex = mr.base_color_texture();
        if let Some(mean) = bind(self, tex, base, slots::MAIN_COLOR, "baseColorTexture")? {
            p.base = mean;
        }
        // B is metalness, G roughness (§3.9.2); each multiplies its factor.
        let (metal, rough) = (Map::Channel(2, p.metallic), Map::Channel(1, p.roughness));
        let tex = mr.metallic_roughness_texture();
        let name = "metallicRoughnessTexture";
        if let Some(mean) = bind(self, tex.clone(), metal, METALLIC, name)? {
            p.metallic = mean.x;
        }
        if let Some(mean) = bind(self, tex, rough, ROUGHNESS, name)? {
            p.roughness = mean.x;
        }
        // KHR_materials_transmission: R times transmissionFactor.
        if let Some(t) = m.transmission() {
            let map = Map::Channel(0, p.transmission);
            let tex = t.transmission_texture();
            let name = "KHR_materials_transmission.transmissionTexture";
            if let Some(mean) = bind(self, tex, map, SPEC_TRANS, name)? {
                p.transmission = mean.x;
            }
        }
        self.note_unsupported(m, &p, what);
        Ok((p, slots))
    }

    /// Refuses parameters outside their ranges (glTF 2.0 §5.19, §5.22).
    fn check_pbr(&self, p: &Pbr, what: &str) -> Result<(), SceneError> {
        let unit = |v: f32| (0.0..=1.0).contains(&v);
        let bad = if !(p.base.is_finite() && p.base.min_element() >= 0.0) {
            Some(format!("baseColorFactor {:?}", p.base.to_array()))
        } else if !unit(p.metallic) {
            Some(format!("metallicFactor {}", p.metallic))
        } else if !unit(p.roughness) {
            Some(format!("roughnessFactor {}", p.roughness))
        } else if !unit(p.transmission) {
            Some(format!("transmissionFactor {}", p.transmission))
        } else if !(p.ior >= 1.0 && p.ior.is_finite()) {
            Some(format!("ior {} (must be at least 1)", p.ior))
        } else if !unit(p.clearcoat) {
            Some(format!("clearcoatFactor {}", p.clearcoat))
        } else if !unit(p.clearcoat_roughness) {
            Some(format!(
                "clearcoatRoughnessFactor {}",
                p.clearcoat_roughness
            ))
        } else if !unit(p.sheen) {
            Some(format!("sheenColorFactor {}", p.sheen))
        } else if !(p.specular.is_finite() && p.specular.min_element() >= 0.0) {
            Some(format!("specular {:?}", p.specular.to_array()))
        } else {
            None
        };
        match bad {
            Some(b) => Err(self.err(format!("{what}: {b} is out of range"))),
            None => Ok(()),
        }
    }

    /// Approximations and notes for what [`bsdf_for`] cannot express.
    fn note_unsupported(&mut self, m: &::gltf::Material, p: &Pbr, what: &str) {
        if p.specular != Color::ONE {
            self.approximate(format!(
                "{what}: KHR_materials_specular is ignored (principled's specular follows ior)"
            ));
        }
        if m.occlusion_texture().is_some() {
            self.note(format!(
                "{what}: the occlusion texture is ignored (a path tracer computes occlusion)"
            ));
        }
        if m.alpha_mode() != ::gltf::material::AlphaMode::Opaque {
            self.approximate(format!(
                "{what}: alphaMode {:?} is rendered opaque",
                m.alpha_mode()
            ));
        }
        if p.clearcoat > 0.0 {
            self.approximate(format!(
                "{what}: the clearcoat layer is rendered as principled's clearcoat (GTR1)"
            ));
        }
        if p.sheen > 0.0 {
            self.approximate(format!(
                "{what}: the sheen layer is rendered as principled's untinted sheen"
            ));
        }
    }
}

/// A material extension's number, or the largest entry of its array (a colour); 0 where
/// absent or not a number (the extensions' defaults for the factors read here).
fn extension_factor(m: &::gltf::Material, ext: &str, key: &str) -> f32 {
    m.extension_value(ext)
        .and_then(|v| v.get(key))
        .map(|v| match v {
            ::gltf::json::Value::Number(n) => n.as_f64().unwrap_or(0.0) as f32,
            ::gltf::json::Value::Array(a) => a
                .iter()
                .filter_map(|x| x.as_f64())
                .fold(0.0f32, |s, x| s.max(x as f32)),
            _ => 0.0,
        })
        .unwrap_or(0.0)
}

impl Loader<'_> {
    /// Emitted radiance: emissiveFactor × KHR_materials_emissive_strength, times the
    /// emissive texture (sRGB) where there is one; None for black.
    fn emission(
        &mut self,
        m: &::gltf::Material,
        what: &str,
    ) -> Result<Option<Emission>, SceneError> {
        let strength = m.emissive_strength().unwrap_or(1.0);
        let e = Color::from(m.emissive_factor()) * strength;
        if !(e.is_finite() && e.min_element() >= 0.0) {
            return Err(self.err(format!(
                "{what}: emissiveFactor {:?} times emissive strength {strength} must be finite \
                 and not negative",
                m.emissive_factor()
            )));
        }
        if e == Color::ZERO {
            return Ok(None);
        }
        let mut emission = Emission {
            radiance: e,
            texture: None,
        };
        if let Some(info) = m.emissive_texture() {
            let w = format!("{what}.emissiveTexture");
            let map = Map::Affine(e, Color::ZERO);
            if let Some(t) = self.texture(&info, false, map, &w)? {
                emission = Emission {
                    radiance: self.desc.textures[t as usize].mean(),
                    texture: Some(t),
                };
            }
        }
        if m.double_sided() {
            self.note(format!(
                "{what}: emissive and double-sided: mcrt's area lights emit from the front \
                 side only"
            ));
        }
        Ok((emission.radiance != Color::ZERO).then_some(emission))
    }

    /// The decoded image of a texture (cached), or None with an approximation for a format
    /// mcrt does not decode (JPEG, WebP, KTX2).
    fn bitmap(
        &mut self,
        tex: &::gltf::Texture,
        raw: bool,
        what: &str,
    ) -> Result<Option<Arc<Bitmap>>, SceneError> {
        let img = tex.source();
        let key = (img.index(), raw);
        if let Some(b) = self.images.get(&key) {
            return Ok(Some(b.clone()));
        }
        // From the JSON: the crate's `Image::source` unwraps a missing mimeType or uri.
        let json = &self.doc.as_json().images[img.index()];
        let bytes = match (&json.buffer_view, &json.uri) {
            (Some(v), _) => {
                let view = self.doc.views().nth(v.value()).ok_or_else(|| {
                    self.err(format!(
                        "images[{}]: no bufferViews[{}]",
                        img.index(),
                        v.value()
                    ))
                })?;
                self.view_bytes(&view)?.to_vec()
            }
            (None, Some(uri)) => super::buffers::read_uri(self.path, uri)
                .map_err(|e| self.err(format!("images[{}]: {e}", img.index())))?,
            (None, None) => {
                return Err(self.err(format!(
                    "images[{}] has neither a uri nor a bufferView",
                    img.index()
                )))
            }
        };
        if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
            self.approximate(format!(
                "{what}: images[{}] is a JPEG, which mcrt does not decode: the texture is \
                 ignored (in Blender, export images as PNG)",
                img.index()
            ));
            return Ok(None);
        }
        let b = Arc::new(
            Bitmap::decode(&bytes, raw)
                .map_err(|e| self.err(format!("images[{}] ({what}): {e}", img.index())))?,
        );
        self.images.insert(key, b.clone());
        Ok(Some(b))
    }

    /// The normal texture as Mitsuba's `normalmap` reads one: linear values c, the normal
    /// 2c − 1 in the frame (dp/du, n × dp/du, n), which is glTF's tangent space (+x along
    /// increasing u, +y towards the image's top, i.e. decreasing v) where the tangents follow
    /// the texture coordinates (a primitive's TANGENT replaces dp/du, its w the bitangent's
    /// sign: [`crate::material::normal_map::HitGeometry::with_tangent`]); glTF's `scale` multiplies x and y.
    fn normal_texture(
        &mut self,
        n: &::gltf::material::NormalTexture,
        what: &str,
    ) -> Result<Option<u32>, SceneError> {
        let s = n.scale();
        if !(s.is_finite() && (0.0..=1.0).contains(&s.abs())) {
            self.approximate(format!(
                "{what}.normalTexture: scale {s} is clamped to [-1, 1]"
            ));
        }
        let s = if s.is_finite() {
            s.clamp(-1.0, 1.0)
        } else {
            1.0
        };
        // c ↦ ((2c − 1)·(s, s, 1) + 1)/2, which stays in [0, 1] for |s| ≤ 1.
        let map = (
            Color::new(s, s, 1.0),
            Color::new(0.5 - 0.5 * s, 0.5 - 0.5 * s, 0.0),
        );
        if n.tex_coord() != 0 {
            self.approximate(format!(
                "{what}.normalTexture: texture coordinates TEXCOORD_{} are read as TEXCOORD_0",
                n.tex_coord()
            ));
        }
        let tex = n.texture();
        let w = format!("{what}.normalTexture");
        let Some(bitmap) = self.bitmap(&tex, true, &w)? else {
            return Ok(None);
        };
        let bitmap = self.mapped(bitmap, Map::Affine(map.0, map.1), &w)?;
        self.push_texture(&tex, bitmap, UvTransform::IDENTITY, &w);
        Ok(Some(self.desc.textures.len() as u32 - 1))
    }

    /// The bitmap with each pixel mapped by `map`.
    fn mapped(&self, bitmap: Arc<Bitmap>, map: Map, what: &str) -> Result<Arc<Bitmap>, SceneError> {
        if matches!(map, Map::Affine(m, a) if m == Color::ONE && a == Color::ZERO) {
            return Ok(bitmap);
        }
        let px = bitmap.pixels().map(|p| map.apply(p)).collect();
        Ok(Arc::new(
            Bitmap::from_pixels(bitmap.width, bitmap.height, px)
                .map_err(|e| self.err(format!("{what}: {e}")))?,
        ))
    }

    /// A texture: the image (linear if `raw`, else sRGB) mapped by `map`, with the
    /// sampler's filter and wrap mode and the KHR_texture_transform; its index in the scene's
    /// textures, None where the image cannot be decoded (an approximation).
    fn texture(
        &mut self,
        info: &::gltf::texture::Info,
        raw: bool,
        map: Map,
        what: &str,
    ) -> Result<Option<u32>, SceneError> {
        let tex = info.texture();
        let Some(bitmap) = self.bitmap(&tex, raw, what)? else {
            return Ok(None);
        };
        let bitmap = self.mapped(bitmap, map, what)?;
        let mut set = info.tex_coord();
        let mut to_uv = UvTransform::IDENTITY;
        if let Some(t) = info.texture_transform() {
            to_uv = uv_transform(t.offset(), t.rotation(), t.scale());
            set = t.tex_coord().unwrap_or(set);
        }
        if set != 0 {
            self.approximate(format!(
                "{what}: texture coordinates TEXCOORD_{set} are read as TEXCOORD_0"
            ));
        }
        self.push_texture(&tex, bitmap, to_uv, what);
        Ok(Some(self.desc.textures.len() as u32 - 1))
    }

    /// Adds a bitmap texture with the glTF texture's sampler.
    fn push_texture(
        &mut self,
        tex: &::gltf::Texture,
        bitmap: Arc<Bitmap>,
        to_uv: UvTransform,
        what: &str,
    ) {
        let sampler = tex.sampler();
        let wrap = |w: ::gltf::texture::WrappingMode| match w {
            ::gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
            ::gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
            ::gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
        };
        if sampler.wrap_s() != sampler.wrap_t() {
            self.approximate(format!(
                "{what}: wrapS {:?} differs from wrapT {:?}; both wrap as wrapS",
                sampler.wrap_s(),
                sampler.wrap_t()
            ));
        }
        let filter = match sampler.mag_filter() {
            Some(::gltf::texture::MagFilter::Nearest) => FilterType::Nearest,
            _ => FilterType::Bilinear,
        };
        self.desc.textures.push(Texture::Bitmap(BitmapTexture {
            bitmap,
            filter,
            wrap: wrap(sampler.wrap_s()),
            to_uv,
        }));
    }
}

/// KHR_texture_transform: uv ↦ T·R·S·uv, with R the GLSL `mat3(cos, sin, 0, −sin, cos, 0,
/// 0, 0, 1)` of the extension's specification (column-major: columns (cos, sin) and
/// (−sin, cos)).
pub fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
    UvTransform(glam::Affine2::from_scale_angle_translation(
        scale.into(),
        rotation,
        offset.into(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    /// The extension's example: offset, then rotation, then scale, as the specification's
    /// matrix product applies them (scale first).
    #[test]
    fn texture_transform_matches_the_spec_matrix() {
        let (o, r, s) = ([0.5, -0.25], 0.3f32, [2.0, 3.0]);
        let t = uv_transform(o, r, s);
        let uv = Vec2::new(0.2, 0.7);
        // mat3 columns as written in the specification.
        let (c, sn) = (r.cos(), r.sin());
        let scaled = Vec2::new(uv.x * s[0], uv.y * s[1]);
        let rotated = Vec2::new(c * scaled.x - sn * scaled.y, sn * scaled.x + c * scaled.y);
        let want = rotated + Vec2::from(o);
        assert!((t.apply(uv) - want).length() < 1e-6);
    }

    #[test]
    fn mapping_onto_principled() {
        let p = Pbr {
            base: Color::new(0.8, 0.5, 0.2),
            metallic: 0.3,
            roughness: 0.6,
            ior: 1.4,
            transmission: 0.7,
            specular: Color::ONE,
            clearcoat: 0.5,
            clearcoat_roughness: 0.2,
            sheen: 0.4,
        };
        let Bsdf::Principled(b) = bsdf_for(&p) else {
            panic!("not principled")
        };
        assert_eq!(b.base_color, p.base);
        assert_eq!(
            (b.metallic, b.roughness, b.spec_trans, b.eta),
            (0.3, 0.6, 0.7, 1.4)
        );
        assert_eq!((b.clearcoat, b.clearcoat_gloss), (0.5, 0.8));
        assert_eq!((b.sheen, b.sheen_tint, b.anisotropic), (0.4, 0.0, 0.0));
    }
}
