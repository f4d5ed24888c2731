//! Turning Mitsuba objects (sensor, integrator, BSDFs, shapes, emitters) into a scene
//! description.

use super::document::{Document, Elem};
use super::props::{ColorSrc, Ids, Props, Result};
use crate::geometry::mesh::TriangleMesh;
use crate::integrator::IntegratorKind;
use crate::limits;
use crate::material::conductor::{conductor_ior, conductor_names};
use crate::material::textured::slots;
use crate::material::{
    Bsdf, Conductor, Dielectric, Lambert, Material, Mirror, Plastic, RoughConductor,
    RoughDielectric, RoughPlastic, ThinDielectric,
};
use crate::scene::desc::{GeometryDesc, LightDesc, SceneDesc, ShapeDesc};
use crate::scene::obj::load_obj;
use crate::scene::ply::load_ply;
use crate::slot;
use crate::texture::{Bitmap, BitmapTexture, FilterType, Texture, UvTransform, WrapMode};
use crate::Color;
use glam::{Mat4, Vec2, Vec3};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

#[path = "principled.rs"]
mod principled;
mod wrappers;

pub(super) struct Builder<'a> {
    pub(super) doc: &'a Document,
    ids: Ids<'a>,
    lenient: bool,
    pub(super) desc: SceneDesc,
    /// Material index of each BSDF element already converted (shared through `<ref>`).
    materials: HashMap<*const Elem, u32>,
    textures: HashMap<*const Elem, u32>,
    default_material: Option<u32>,
    /// The BSDF elements being converted, outermost first (a `<ref>` cycle is an error).
    converting: Vec<*const Elem>,
    /// Index in `desc.groups` of each shape group element already built.
    groups: HashMap<*const Elem, u32>,
}

#[path = "instance.rs"]
mod instance;

pub fn build(doc: &Document, lenient: bool) -> Result<SceneDesc> {
    let mut b = Builder {
        doc,
        ids: Ids::collect(doc)?,
        lenient,
        desc: SceneDesc::default(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        default_material: None,
        converting: Vec::new(),
        groups: HashMap::new(),
    };
    let scene = Props::new(doc, &b.ids, &doc.root)?;
    let mut sensors = 0;
    for &obj in &scene.objects {
        match obj.tag.as_str() {
            "sensor" => {
                b.sensor(obj, sensors)?;
                sensors += 1;
            }
            "integrator" => b.integrator(obj)?,
            "shape" => b.shape(obj)?,
            "emitter" => b.emitter(obj)?,
            // Declared for later reference by id.
            "bsdf" | "texture" => {
                if obj.attr("id").is_none() {
                    return Err(doc.err(obj, format!("a top-level <{}> needs an id", obj.tag)));
                }
            }
            tag => {
                return Err(doc.err(
                    obj,
                    format!(
                        "<{tag}> is not supported in mcrt (supported at the top level: sensor, \
                         integrator, shape, emitter, bsdf, texture)"
                    ),
                ))
            }
        }
    }
    scene.finish()?;
    Ok(b.desc)
}

impl<'a> Builder<'a> {
    fn props(&self, e: &'a Elem) -> Result<Props<'a>> {
        Props::new(self.doc, &self.ids, e)
    }

    fn warn(&mut self, e: &Elem, msg: impl Into<String>) {
        let w = format!(
            "{}:{}:{}: {}",
            self.doc.files[e.file].display(),
            e.pos.0,
            e.pos.1,
            msg.into()
        );
        self.desc.warnings.push(w);
    }

    fn path_of(&self, e: &Elem, name: &str) -> PathBuf {
        self.doc.files[e.file]
            .parent()
            .unwrap_or(std::path::Path::new("."))
            .join(name)
    }

    fn bounded(&self, e: &Elem, what: &str, v: i64, min: u64, max: u64) -> Result<u32> {
        bounded(self.doc, e, what, v, min, max)
    }

    fn sensor(&mut self, e: &'a Elem, index: usize) -> Result<()> {
        let p = self.props(e)?;
        let kind = p.kind()?;
        let camera = super::sensor::camera(&p, e, kind)?.ok_or_else(|| {
            self.doc.err_attr(
                e,
                "type",
                format!(
                    "sensor '{kind}' is not supported; mcrt has {}",
                    super::sensor::SENSORS
                ),
            )
        })?;
        let name = e.attr("id").map(str::to_string).unwrap_or_else(|| {
            if index == 0 {
                "default".into()
            } else {
                format!("sensor{index}")
            }
        });
        self.desc.cameras.push((name, camera));
        for &obj in &p.objects {
            match obj.tag.as_str() {
                "film" if index == 0 => self.film(obj)?,
                "sampler" if index == 0 => self.sampler(obj)?,
                "film" | "sampler" => {}
                tag => {
                    return Err(self
                        .doc
                        .err(obj, format!("<{tag}> cannot be nested in a <sensor>")))
                }
            }
        }
        p.finish()
    }

    fn film(&mut self, e: &'a Elem) -> Result<()> {
        let p = self.props(e)?;
        let kind = p.kind()?;
        if kind != "hdrfilm" {
            return Err(self.doc.err_attr(
                e,
                "type",
                format!("film '{kind}' is not supported; mcrt has 'hdrfilm'"),
            ));
        }
        let positive = |name: &'static str, v: i64| -> Result<u32> {
            self.bounded(e, &format!("film {name}"), v, 1, limits::MAX_SIZE)
        };
        // Mitsuba's defaults.
        let w = positive("width", p.int("width", 768)?)?;
        let h = positive("height", p.int("height", 576)?)?;
        self.desc.settings.width = Some(w);
        self.desc.settings.height = Some(h);
        let cx = p.int("crop_offset_x", 0)?;
        let cy = p.int("crop_offset_y", 0)?;
        let cw = p.int("crop_width", (w as i64).saturating_sub(cx))?;
        let ch = p.int("crop_height", (h as i64).saturating_sub(cy))?;
        // Checked sums: huge offsets and sizes must not wrap around into a fit.
        let fits = |o: i64, n: i64, size: u32| {
            o >= 0 && n >= 1 && o.checked_add(n).is_some_and(|end| end <= size as i64)
        };
        if !(fits(cx, cw, w) && fits(cy, ch, h)) {
            return Err(self.doc.err(
                e,
                format!(
                    "the crop window ({cx}, {cy}) + ({cw} × {ch}) does not fit in the {w} × {h} \
                     film"
                ),
            ));
        }
        if (cx, cy, cw, ch) != (0, 0, w as i64, h as i64) {
            self.desc.settings.crop = Some([cx as u32, cy as u32, cw as u32, ch as u32]);
        }
        // Output details the extension of `-o` decides in mcrt.
        for name in [
            "pixel_format",
            "component_format",
            "file_format",
            "banner",
            "sample_border",
        ] {
            p.ignore(name);
        }
        for &obj in &p.objects {
            if obj.tag != "rfilter" {
                return Err(self
                    .doc
                    .err(obj, format!("<{}> cannot be nested in a <film>", obj.tag)));
            }
            let f = self.props(obj)?;
            let kind = f.kind()?;
            if kind != "box" {
                self.warn(
                    obj,
                    format!("rfilter '{kind}' is rendered with mcrt's box filter"),
                );
            }
            for name in ["radius", "stddev", "lobes", "B", "C"] {
                f.ignore(name);
            }
            f.finish()?;
        }
        p.finish()
    }

    fn sampler(&mut self, e: &'a Elem) -> Result<()> {
        let p = self.props(e)?;
        p.kind()?; // any type: mcrt's own sampler is used
        let spp = p.int("sample_count", 4)?;
        let spp = self.bounded(e, "sample_count", spp, 1, limits::MAX_SPP)?;
        self.desc.settings.spp = Some(spp);
        let seed = p.int("seed", 0)?;
        self.desc.settings.seed = Some(seed as u64);
        for name in ["jitter", "scramble_seed", "pixel_format", "dimension"] {
            p.ignore(name);
        }
        p.finish()
    }

    fn integrator(&mut self, e: &'a Elem) -> Result<()> {
        let p = self.props(e)?;
        let kind = p.kind()?;
        let s = &mut self.desc.settings;
        match kind {
            // Without participating media (not supported), volpath is path.
            "path" | "volpath" => {
                s.integrator = Some(IntegratorKind::Path);
                let rr = p.int("rr_depth", 5)?;
                s.rr_depth = Some(bounded(
                    self.doc,
                    e,
                    "rr_depth",
                    rr,
                    1,
                    limits::MAX_RR_DEPTH,
                )?);
            }
            "direct" => {
                s.integrator = Some(IntegratorKind::Direct);
                // Mitsuba's direct integrator stops at the first surface: it does not follow
                // mirrors and glass as mcrt's native `direct` does.
                s.specular_chain = Some(false);
                let n = p.int("emitter_samples", p.int("shadow_samples", 1)?)?;
                let n = bounded(
                    self.doc,
                    e,
                    "emitter_samples",
                    n,
                    1,
                    limits::MAX_SHADOW_RAYS,
                )?;
                s.shadow_rays = Some(n);
                if p.int("bsdf_samples", 1)? != 1 {
                    return Err(self
                        .doc
                        .err(e, "mcrt's direct integrator takes one BSDF sample"));
                }
            }
            _ => {
                return Err(self.doc.err_attr(
                    e,
                    "type",
                    format!("integrator '{kind}' is not supported; mcrt has 'path' and 'direct'"),
                ))
            }
        }
        let d = p.int("max_depth", -1)?;
        s.max_depth = match d {
            -1 => None,
            d if (0..=limits::MAX_DEPTH as i64).contains(&d) => Some(d as u32),
            d => {
                return Err(self.doc.err(
                    e,
                    format!(
                        "max_depth must be -1 or between 0 and {}, got {d}",
                        limits::MAX_DEPTH
                    ),
                ))
            }
        };
        let hide = p.bool("hide_emitters", false)?;
        self.desc.settings.hide_emitters = Some(hide);
        p.finish()
    }

    /// The material index of a BSDF element (converted once, shared by reference).
    pub(super) fn material(&mut self, e: &'a Elem) -> Result<u32> {
        if let Some(&i) = self.materials.get(&(e as *const Elem)) {
            return Ok(i);
        }
        let m = self.bsdf(e, false)?;
        self.desc.materials.push(m);
        let i = (self.desc.materials.len() - 1) as u32;
        self.materials.insert(e as *const Elem, i);
        Ok(i)
    }

    fn default_material(&mut self) -> u32 {
        *self.default_material.get_or_insert_with(|| {
            // Mitsuba gives shapes without a BSDF a grey diffuse one.
            self.desc.materials.push(Material::new(
                Bsdf::Lambert(Lambert {
                    albedo: Color::splat(0.5),
                }),
                false,
            ));
            (self.desc.materials.len() - 1) as u32
        })
    }

    /// The index of a texture element (converted once, shared by reference).
    pub(super) fn texture(&mut self, e: &'a Elem) -> Result<u32> {
        if let Some(&i) = self.textures.get(&(e as *const Elem)) {
            return Ok(i);
        }
        let p = self.props(e)?;
        let kind = p.kind()?;
        let to_uv = UvTransform::from_mat4(p.transform("to_uv")?);
        let tex = match kind {
            "bitmap" => {
                let name = p
                    .string_opt("filename")?
                    .ok_or_else(|| self.doc.err(e, "a bitmap texture needs a 'filename'"))?;
                let raw = p.bool("raw", false)?;
                let path = self.path_of(e, name);
                if let Some(why) = crate::input::file_problem(&path) {
                    return Err(self.doc.err(
                        e,
                        format!(
                            "texture file '{}' {why} (looked for {})",
                            crate::input::shorten(name),
                            path.display()
                        ),
                    ));
                }
                let bitmap = Bitmap::load(&path, raw).map_err(|mut err| {
                    // Name the texture element too: the image file itself has no line.
                    err.message = format!(
                        "{} (texture at {}:{}:{})",
                        err.message,
                        self.doc.files[e.file].display(),
                        e.pos.0,
                        e.pos.1
                    );
                    err
                })?;
                let mut b = BitmapTexture::new(Arc::new(bitmap));
                let f = p.string("filter_type", "bilinear")?;
                b.filter = FilterType::parse(f).ok_or_else(|| {
                    self.doc.err(
                        e,
                        format!("filter_type '{f}': expected bilinear or nearest"),
                    )
                })?;
                let w = p.string("wrap_mode", "repeat")?;
                b.wrap = WrapMode::parse(w).ok_or_else(|| {
                    self.doc.err(
                        e,
                        format!("wrap_mode '{w}': expected repeat, mirror or clamp"),
                    )
                })?;
                b.to_uv = to_uv;
                // Storage precision, and CUDA's hardware lookups: no effect on the values.
                p.ignore("format");
                p.ignore("accel");
                Texture::Bitmap(b)
            }
            "checkerboard" => Texture::Checkerboard {
                color0: p.color("color0", Color::splat(0.4))?,
                color1: p.color("color1", Color::splat(0.2))?,
                to_uv,
            },
            _ => {
                return Err(self.doc.err_attr(
                    e,
                    "type",
                    format!("texture '{kind}' is not supported; mcrt has bitmap and checkerboard"),
                ))
            }
        };
        p.finish()?;
        self.desc.textures.push(tex);
        let i = (self.desc.textures.len() - 1) as u32;
        self.textures.insert(e as *const Elem, i);
        Ok(i)
    }

    /// A conductor's complex index of refraction: a named `material`, or `eta` and `k`.
    /// (`eta` and `k` may be textures, bound through `slots`.)
    fn conductor_ior(
        &mut self,
        p: &Props<'a>,
        slots: &mut Vec<crate::material::Binding>,
    ) -> Result<(Color, Color)> {
        let e = p.owner;
        let named = p.string_opt("material")?;
        if p.has("eta") || p.has("k") {
            if named.is_some() {
                return Err(self
                    .doc
                    .err(e, "give either 'material' or 'eta' and 'k', not both"));
            }
            let eta = self.color_param(p, "eta", 0.0, slots, slots::CONDUCTOR_ETA)?;
            let k = self.color_param(p, "k", 1.0, slots, slots::CONDUCTOR_K)?;
            return Ok((eta, k));
        }
        let name = named.unwrap_or("none");
        conductor_ior(name).ok_or_else(|| {
            self.doc.err(
                e,
                format!(
                    "unknown conductor material '{name}'; expected none or one of {}",
                    conductor_names().collect::<Vec<_>>().join(", ")
                ),
            )
        })
    }

    fn bsdf(&mut self, e: &'a Elem, two_sided: bool) -> Result<Material> {
        if self.converting.contains(&(e as *const Elem)) {
            return Err(self
                .doc
                .err(e, "this BSDF contains itself (through a <ref> to it)"));
        }
        self.converting.push(e as *const Elem);
        let m = self.bsdf_inner(e, two_sided);
        self.converting.pop();
        m
    }

    fn bsdf_inner(&mut self, e: &'a Elem, two_sided: bool) -> Result<Material> {
        let p = self.props(e)?;
        let kind = p.kind()?;
        let mut slots = Vec::new();
        let bsdf = match kind {
            "twosided" => {
                let inner: Vec<&Elem> = p
                    .objects
                    .iter()
                    .copied()
                    .filter(|o| o.tag == "bsdf")
                    .collect();
                if inner.len() != 1 || p.objects.len() != 1 {
                    return Err(self.doc.err(
                        e,
                        "twosided needs exactly one nested BSDF (different front and back BSDFs \
                         are not supported)",
                    ));
                }
                p.finish()?;
                return self.bsdf(inner[0], true);
            }
            "blendbsdf" => self.blend(&p, &mut slots)?,
            "normalmap" | "bumpmap" | "mask" => return self.wrapper(e, &p, kind, two_sided),
            "diffuse" => {
                let lambert = slot!(Color, Lambert, |b, v| b.albedo = v);
                let c = self.color_param(&p, "reflectance", 0.5, &mut slots, lambert)?;
                Bsdf::Lambert(Lambert { albedo: c })
            }
            "dielectric" | "thindielectric" | "roughdielectric" => {
                let eta = ior(&p, "int_ior", 1.5046)? / ior(&p, "ext_ior", 1.000277)?;
                let (r, t) = (
                    slots::DIELECTRIC_REFLECTANCE,
                    slots::DIELECTRIC_TRANSMITTANCE,
                );
                let r = self.color_param(&p, "specular_reflectance", 1.0, &mut slots, r)?;
                let t = self.color_param(&p, "specular_transmittance", 1.0, &mut slots, t)?;
                match kind {
                    "dielectric" => Bsdf::Dielectric(Dielectric {
                        eta,
                        specular_reflectance: r,
                        specular_transmittance: t,
                    }),
                    "thindielectric" => Bsdf::ThinDielectric(ThinDielectric {
                        specular_reflectance: r,
                        specular_transmittance: t,
                        ..ThinDielectric::new(eta)
                    }),
                    _ => Bsdf::RoughDielectric(RoughDielectric {
                        specular_reflectance: r,
                        specular_transmittance: t,
                        ..RoughDielectric::new(self.roughness(&p, Some(&mut slots))?, eta)
                    }),
                }
            }
            "conductor" | "roughconductor" => {
                let (eta, k) = self.conductor_ior(&p, &mut slots)?;
                let textured_ior = !slots.is_empty();
                let r = slots::CONDUCTOR_REFLECTANCE;
                let r = self.color_param(&p, "specular_reflectance", 1.0, &mut slots, r)?;
                if kind == "conductor" {
                    // `material = "none"` is η = 0, k = 1: Fresnel reflectance 1, a mirror.
                    if eta == Color::ZERO && k == Color::ONE && !textured_ior {
                        Bsdf::Mirror(Mirror { reflectance: r })
                    } else {
                        Bsdf::Conductor(Conductor::new(eta, k, r))
                    }
                } else {
                    let distr = self.roughness(&p, Some(&mut slots))?;
                    Bsdf::RoughConductor(RoughConductor::new(distr, eta, k, r))
                }
            }
            "plastic" | "roughplastic" => {
                let eta = ior(&p, "int_ior", 1.49)? / ior(&p, "ext_ior", 1.000277)?;
                let (d, s) = (slots::PLASTIC_DIFFUSE, slots::PLASTIC_SPECULAR);
                let d = self.color_param(&p, "diffuse_reflectance", 0.5, &mut slots, d)?;
                let s = self.color_param(&p, "specular_reflectance", 1.0, &mut slots, s)?;
                let nonlinear = p.bool("nonlinear", false)?;
                if kind == "plastic" {
                    Bsdf::Plastic(Plastic::new(eta, d, s, nonlinear))
                } else {
                    let m = self.roughness(&p, None)?;
                    if m.alpha_u != m.alpha_v {
                        return Err(self.doc.err(e, "roughplastic is isotropic: give 'alpha'"));
                    }
                    Bsdf::RoughPlastic(RoughPlastic::new(m.kind, m.alpha_u, eta, d, s, nonlinear))
                }
            }
            "principled" | "principledthin" => self.principled(&p, kind, &mut slots)?,
            _ => {
                if self.lenient {
                    self.warn(
                        e,
                        format!("bsdf '{kind}' replaced by grey diffuse (--lenient)"),
                    );
                    return Ok(Material::new(
                        Bsdf::Lambert(Lambert {
                            albedo: Color::splat(0.5),
                        }),
                        two_sided,
                    ));
                }
                return Err(self.doc.err_attr(
                    e,
                    "type",
                    format!(
                        "bsdf '{kind}' is not supported; mcrt has diffuse, dielectric, \
                         thindielectric, roughdielectric, conductor, roughconductor, plastic, \
                         roughplastic, principled, principledthin, blendbsdf, twosided, normalmap, bumpmap \
                         and mask (--lenient renders it grey diffuse)"
                    ),
                ));
            }
        };
        p.finish()?;
        Ok(Material::new(bsdf, two_sided).with_slots(slots))
    }

    fn shape(&mut self, e: &'a Elem) -> Result<()> {
        let p = self.props(e)?;
        let kind = p.kind()?;
        if let Some(done) = self.instancing(e, &p, kind) {
            return done;
        }
        let m = p.transform("to_world")?;
        let flip = p.bool("flip_normals", false)?;
        let geometry = match kind {
            "rectangle" => GeometryDesc::Mesh(mesh(
                &[[-1., -1., 0.], [1., -1., 0.], [1., 1., 0.], [-1., 1., 0.]],
                &[[0, 1, 2], [0, 2, 3]],
                m,
                flip,
            )),
            "cube" => GeometryDesc::Mesh(cube(m, flip)),
            "disk" => GeometryDesc::Mesh(disk(m, flip)),
            "cylinder" => {
                let p0 = p.vec3_opt("p0")?.unwrap_or(Vec3::ZERO);
                let p1 = p.vec3_opt("p1")?.unwrap_or(Vec3::Z);
                let r = p.float("radius", 1.0)?;
                let to_world = crate::scene::cylinder::cylinder_transform(m, p0, p1, r)
                    .map_err(|why| self.doc.err(e, why))?;
                let mut mesh = crate::scene::cylinder::unit_cylinder();
                mesh.transform(&to_world);
                if flip {
                    flip_mesh(&mut mesh);
                }
                if self.lenient {
                    self.warn(
                        e,
                        format!(
                            "cylinder traced as a mesh of {} quads with exact normals \
                             (--lenient)",
                            crate::scene::cylinder::SEGMENTS
                        ),
                    );
                }
                GeometryDesc::Mesh(mesh)
            }
            "sphere" => {
                let c = p.vec3_opt("center")?.unwrap_or(Vec3::ZERO);
                let r = p.float("radius", 1.0)?;
                if !(r > 0.0) {
                    return Err(self
                        .doc
                        .err(e, format!("sphere radius must be positive, got {r}")));
                }
                let full = m * Mat4::from_translation(c) * Mat4::from_scale(Vec3::splat(r));
                let cols = [
                    full.x_axis.truncate(),
                    full.y_axis.truncate(),
                    full.z_axis.truncate(),
                ];
                let s = cols[0].length();
                if cols.iter().any(|c| (c.length() - s).abs() > 1e-4 * s)
                    || cols[0].dot(cols[1]).abs() > 1e-4 * s * s
                    || cols[1].dot(cols[2]).abs() > 1e-4 * s * s
                    || cols[0].dot(cols[2]).abs() > 1e-4 * s * s
                {
                    return Err(self.doc.err(
                        e,
                        "a sphere's to_world may only translate, rotate and scale uniformly",
                    ));
                }
                // The rotation of the sphere's frame: its unit axes (the columns over the
                // scale); identity for spheres that only move and scale.
                let rotation = glam::Mat3::from_cols(cols[0] / s, cols[1] / s, cols[2] / s);
                let center = full.transform_point3(Vec3::ZERO);
                if rotation == glam::Mat3::IDENTITY && !flip {
                    GeometryDesc::Sphere { center, radius: s }
                } else {
                    GeometryDesc::OrientedSphere {
                        center,
                        radius: s,
                        rotation,
                        flip,
                    }
                }
            }
            "obj" | "ply" | "serialized" => {
                let name = p.string_opt("filename")?.ok_or_else(|| {
                    self.doc
                        .err(e, format!("a {kind} shape needs a 'filename'"))
                })?;
                let path = self.path_of(e, name);
                if let Some(why) = crate::input::file_problem(&path) {
                    return Err(self.doc.err(
                        e,
                        format!(
                            "mesh file '{}' {why} (looked for {})",
                            crate::input::shorten(name),
                            path.display()
                        ),
                    ));
                }
                let mut mesh = if kind == "obj" {
                    let mut m = load_obj(&path)?;
                    if p.bool("flip_tex_coords", true)? {
                        m.flip_v();
                    }
                    m
                } else if kind == "ply" {
                    load_ply(&path)?.into_triangle_mesh()
                } else {
                    let index = p.int("shape_index", 0)?;
                    let index = u32::try_from(index).map_err(|_| {
                        self.doc
                            .err(e, format!("shape_index must be ≥ 0, got {index}"))
                    })?;
                    crate::scene::serialized::load_serialized(&path, index)
                        .map_err(|err| self.doc.err(e, err.to_string()))?
                };
                if mesh.indices.is_empty() {
                    return Err(self
                        .doc
                        .err(e, format!("'{}' holds no triangles", path.display())));
                }
                if p.bool("face_normals", false)? {
                    mesh.normals = None;
                } else if mesh.normals.is_none() {
                    // Mitsuba shades meshes without normals smoothly.
                    mesh.recompute_vertex_normals();
                }
                mesh.transform(&m);
                if flip {
                    flip_mesh(&mut mesh);
                }
                GeometryDesc::Mesh(mesh)
            }
            _ => {
                return Err(self.doc.err_attr(
                    e,
                    "type",
                    format!(
                        "shape '{kind}' is not supported; mcrt has obj, ply, serialized, \
                         rectangle, cube, sphere, disk, cylinder, shapegroup and instance"
                    ),
                ))
            }
        };
        let mut material = None;
        let mut emission = None;
        for &obj in &p.objects {
            match obj.tag.as_str() {
                "bsdf" => {
                    if material.is_some() {
                        return Err(self.doc.err(obj, "a shape has one BSDF"));
                    }
                    material = Some(self.material(obj)?);
                }
                "emitter" => {
                    let ep = self.props(obj)?;
                    let k = ep.kind()?;
                    if k != "area" {
                        return Err(self.doc.err_attr(
                            obj,
                            "type",
                            format!("emitter '{k}' cannot be attached to a shape; use 'area'"),
                        ));
                    }
                    emission = Some(match ep.color_src("radiance", Color::ONE)? {
                        ColorSrc::Const(c) => c,
                        ColorSrc::Texture(t) => {
                            let t = self.texture(t)?;
                            let shape = self.desc.shapes.len();
                            self.desc.emission_textures.push((shape, t));
                            self.desc.textures[t as usize].mean()
                        }
                    });
                    ep.finish()?;
                }
                tag => {
                    return Err(self
                        .doc
                        .err(obj, format!("<{tag}> cannot be nested in a <shape>")))
                }
            }
        }
        if let (Some(_), GeometryDesc::Mesh(m)) = (&emission, &geometry) {
            let area: f32 = m
                .indices
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
            if !(area > 0.0 && area.is_finite()) {
                return Err(self.doc.err(e, "an area emitter's shape must have a positive, finite area (this one is degenerate)"));
            }
        }
        let material = match material {
            Some(m) => m,
            None => self.default_material(),
        };
        p.finish()?;
        self.desc.shapes.push(ShapeDesc {
            geometry,
            material,
            emission,
        });
        Ok(())
    }

    fn emitter(&mut self, e: &'a Elem) -> Result<()> {
        let p = self.props(e)?;
        let kind = p.kind()?;
        let light = match kind {
            "point" => {
                let m = p.transform("to_world")?;
                let pos = p.vec3_opt("position")?.unwrap_or(Vec3::ZERO);
                LightDesc::Point {
                    position: m.transform_point3(pos),
                    intensity: p.color("intensity", Color::ONE)?,
                }
            }
            "directional" => {
                let m = p.transform("to_world")?;
                let d = p.vec3_opt("direction")?.unwrap_or(Vec3::Z);
                let d = m.transform_vector3(d).try_normalize().ok_or_else(|| self.doc.err(e, "the direction is zero"))?;
                LightDesc::Directional {
                    direction: d,
                    irradiance: p.color("irradiance", Color::ONE)?,
                }
            }
            "constant" => LightDesc::Constant {
                radiance: p.color("radiance", Color::ONE)?,
            },
            "spot" => super::emitters::spot(self.doc, e, &p, &mut |t| self.texture(t))?,
            "envmap" => super::emitters::envmap(self.doc, e, &p)?,
            "area" => return Err(self.doc.err(e, "an area emitter must be nested in a <shape>")),
            _ => {
                return Err(self.doc.err_attr(
                    e,
                    "type",
                    format!("emitter '{kind}' is not supported; mcrt has area, point, directional, constant, spot and envmap"),
                ))
            }
        };
        p.finish()?;
        self.desc.lights.push(light);
        Ok(())
    }
}

/// A mesh from local vertices and triangles, moved to the world by `m`.
fn mesh(v: &[[f32; 3]], idx: &[[u32; 3]], m: Mat4, flip: bool) -> TriangleMesh {
    let mut mesh = TriangleMesh {
        tangents: None,
        positions: v.iter().map(|p| Vec3::from_array(*p)).collect(),
        normals: None,
        // Planar texture coordinates over [−1, 1]² (Mitsuba's rectangle; the disk and the
        // cube's faces approximate Mitsuba's own maps).
        uvs: Some(
            v.iter()
                .map(|p| Vec2::new(0.5 * p[0] + 0.5, 0.5 * p[1] + 0.5))
                .collect(),
        ),
        indices: idx.to_vec(),
    };

    mesh.transform(&m);
    if flip {
        flip_mesh(&mut mesh);
    }
    mesh
}

fn flip_mesh(mesh: &mut TriangleMesh) {
    for t in &mut mesh.indices {
        t.swap(1, 2);
    }
    if let Some(ns) = &mut mesh.normals {
        for n in ns {
            *n = -*n;
        }
    }
}

/// Mitsuba's `cube`: [−1, 1]³ with outward faces.
fn cube(m: Mat4, flip: bool) -> TriangleMesh {
    let mut v = Vec::new();
    let mut idx = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0f32; 3];
            n[axis] = sign;
            let n = Vec3::from_array(n);
            // Tangents with u × v = n.
            let u = Vec3::from_array({
                let mut a = [0.0; 3];
                a[(axis + 1) % 3] = 1.0;
                a
            });
            let w = n.cross(u);
            let base = v.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                v.push((n + u * a + w * b).to_array());
            }
            idx.push([base, base + 1, base + 2]);
            idx.push([base, base + 2, base + 3]);
        }
    }
    let mut cube = mesh(&v, &idx, m, flip);
    // Each face spans the unit square of texture space.
    let face = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
    cube.uvs = Some((0..v.len()).map(|i| face[i % 4]).collect());
    cube
}

/// Mitsuba's `disk`: the unit disk in the xy plane, facing +z, as a polygon of equal area.
fn disk(m: Mat4, flip: bool) -> TriangleMesh {
    let mut disk = TriangleMesh::unit_disk();
    disk.transform(&m);
    if flip {
        flip_mesh(&mut disk);
    }
    disk
}

/// An index of refraction: a number or one of Mitsuba's named materials.
fn ior(p: &Props, name: &'static str, default: f32) -> Result<f32> {
    if !p.has(name) {
        return Ok(default);
    }
    if let Some(s) = p.string_opt(name).ok().flatten() {
        return named_ior(s).ok_or_else(|| {
            p.doc.err(
                p.owner,
                format!(
                    "{name}: unknown material '{s}'; give a number or one of {}",
                    IORS.iter().map(|i| i.0).collect::<Vec<_>>().join(", ")
                ),
            )
        });
    }
    let v = p.float(name, default)?;
    if !(v > 0.0) {
        return Err(p
            .doc
            .err(p.owner, format!("{name} must be positive, got {v}")));
    }
    Ok(v)
}

/// Mitsuba 3's table of named indices of refraction (include/mitsuba/core/... `ior.h`).
const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

fn named_ior(s: &str) -> Option<f32> {
    let s = s.trim().to_ascii_lowercase();
    IORS.iter().find(|(n, _)| *n == s).map(|i| i.1)
}

/// An integer property within [min, max] (crate::limits), as u32.
fn bounded(doc: &Document, e: &Elem, what: &str, v: i64, min: u64, max: u64) -> Result<u32> {
    if v < 0 {
        return Err(doc.err(e, format!("{what} must be at least {min}, got {v}")));
    }
    crate::limits::check(what, v as u64, min, max).map_err(|m| doc.err(e, m))?;
    Ok(v as u32)
}
