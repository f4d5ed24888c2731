//! The native scene format: TOML, documented in `docs/scene-format.md`.
//!
//! Every error names the file, line and column of the value at fault and what was expected.

use super::desc::{FileSettings, GeometryDesc, SceneDesc, ShapeDesc};
use super::obj::load_obj;
use super::SceneError;
use crate::camera::{CameraDesc, FovAxis};
use crate::geometry::mesh::TriangleMesh;
use crate::integrator::IntegratorKind;
use crate::material::{Bsdf, Dielectric, Lambert, Material, Mirror, OrenNayar};
use crate::Color;
use glam::{Vec2, Vec3};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

type V3 = [f32; 3];

/// A colour: one number (grey) or three (linear RGB).
#[derive(Deserialize, Clone, Copy)]
#[serde(
    untagged,
    expecting = "expected a colour: a number or an array of three numbers [r, g, b]"
)]
enum ColorT {
    Grey(f32),
    Rgb(V3),
}

impl ColorT {
    fn color(self) -> Color {
        match self {
            ColorT::Grey(g) => Color::splat(g),
            ColorT::Rgb(c) => Color::from_array(c),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileT {
    render: Option<RenderT>,
    #[serde(default)]
    camera: Vec<Spanned<CameraT>>,
    #[serde(default)]
    material: BTreeMap<String, Spanned<MaterialT>>,
    #[serde(default)]
    shape: Vec<Spanned<ShapeT>>,
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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialT {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    albedo: Option<Spanned<ColorT>>,
    sigma: Option<Spanned<f32>>,
    reflectance: Option<Spanned<ColorT>>,
    ior: Option<Spanned<f32>>,
    ext_ior: Option<Spanned<f32>>,
    two_sided: Option<Spanned<bool>>,
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
    file: Option<Spanned<String>>,
    positions: Option<Spanned<Vec<V3>>>,
    indices: Option<Spanned<Vec<[u32; 3]>>>,
    normals: Option<Spanned<Vec<V3>>>,
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
        let c = v.get_ref().color();
        if !c.is_finite() || c.min_element() < 0.0 {
            return self.err(v.span(), format!("'{key}' must be finite and not negative"));
        }
        if let Some(m) = max {
            if c.max_element() > m {
                return self.err(v.span(), format!("'{key}' must be at most {m} in every channel (a surface cannot reflect more light than it receives)"));
            }
        }
        Ok(c)
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
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(path, None, format!("cannot read scene file: {e}")))?;
    parse_toml(path, &text)
}

pub fn parse_toml(path: &Path, text: &str) -> Result<SceneDesc, SceneError> {
    let cx = Ctx { path, text };
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

    for cam in &file.camera {
        let c = cam.get_ref();
        let at = cam.span();
        let name = c.name.get_ref().clone();
        if desc.cameras.iter().any(|(n, _)| *n == name) {
            return cx.err(
                c.name.span(),
                format!("a camera named '{name}' is already defined"),
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
            "perspective" => {
                let what = "a perspective camera";
                cx.only(
                    &present,
                    &["origin", "target", "up", "fov", "fov_axis"],
                    what,
                )?;
                let origin = cx.finite3(cx.need(&c.origin, "origin", what, &at)?, "origin")?;
                let target = cx.finite3(cx.need(&c.target, "target", what, &at)?, "target")?;
                let up = cx.finite3(cx.need(&c.up, "up", what, &at)?, "up")?;
                let fov = cx.need(&c.fov, "fov", what, &at)?;
                if !(fov.get_ref() > &0.0 && fov.get_ref() < &180.0) {
                    return cx.err(fov.span(), "'fov' must be between 0 and 180 degrees");
                }
                let fwd = target - origin;
                if fwd.length_squared() == 0.0 || fwd.cross(up).length_squared() == 0.0 {
                    return cx.err(at, "'target' must differ from 'origin', and 'up' must not be parallel to the view direction");
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
                CameraDesc::Perspective {
                    origin,
                    target,
                    up,
                    fov: *fov.get_ref(),
                    fov_axis,
                }
            }
            other => {
                return cx.err(
                    c.kind.span(),
                    format!("unknown camera type '{other}' (expected 'pinhole' or 'perspective')"),
                )
            }
        };
        desc.cameras.push((name, cd));
    }

    let mut material_ids: BTreeMap<&str, u32> = BTreeMap::new();
    for (name, m) in &file.material {
        let mat = material(&cx, m)?;
        material_ids.insert(name.as_str(), desc.materials.len() as u32);
        desc.materials.push(mat);
    }
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
        let emission = s
            .emission
            .as_ref()
            .map(|e| cx.color(e, "emission", None))
            .transpose()?;
        let present = [
            ("vertices", span_of(&s.vertices)),
            ("center", span_of(&s.center)),
            ("radius", span_of(&s.radius)),
            ("file", span_of(&s.file)),
            ("positions", span_of(&s.positions)),
            ("indices", span_of(&s.indices)),
            ("normals", span_of(&s.normals)),
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
            "mesh" => {
                cx.only(
                    &present,
                    &["file", "positions", "indices", "normals"],
                    "a mesh",
                )?;
                let mesh = match (&s.file, &s.positions) {
                    (Some(f), None) => {
                        if s.indices.is_some() || s.normals.is_some() {
                            return cx.err(
                                f.span(),
                                "a mesh takes either 'file' or 'positions' and 'indices', not both",
                            );
                        }
                        let p = base.join(f.get_ref());
                        let ext = p
                            .extension()
                            .and_then(|e| e.to_str())
                            .unwrap_or("")
                            .to_ascii_lowercase();
                        if ext != "obj" {
                            return cx.err(
                                f.span(),
                                format!(
                                    "unsupported mesh file '{}' (expected an .obj file)",
                                    f.get_ref()
                                ),
                            );
                        }
                        if !p.is_file() {
                            return cx.err(
                                f.span(),
                                format!(
                                    "mesh file '{}' not found (looked for {})",
                                    f.get_ref(),
                                    p.display()
                                ),
                            );
                        }
                        let mut m = load_obj(&p)?;
                        m.flip_v();
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
                        TriangleMesh {
                            positions: pos.get_ref().iter().map(|p| Vec3::from(*p)).collect(),
                            normals,
                            uvs: None,
                            indices: idx.get_ref().clone(),
                        }
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
                        "unknown shape type '{other}' (expected triangle, quad, sphere or mesh)"
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
            if !(area > 0.0) {
                return cx.err(e.span(), "an emitting shape must have a positive area");
            }
        }
        desc.shapes.push(ShapeDesc {
            geometry,
            material,
            emission,
        });
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
    let positive = |v: &Option<Spanned<u32>>, key: &str| -> Result<Option<u32>, SceneError> {
        match v {
            Some(v) if *v.get_ref() == 0 => cx.err(v.span(), format!("'{key}' must be at least 1")),
            Some(v) => Ok(Some(*v.get_ref())),
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
        Some(d) if *d.get_ref() >= 0 && *d.get_ref() <= u32::MAX as i64 => {
            Some(*d.get_ref() as u32)
        }
        Some(d) => {
            return cx.err(
                d.span(),
                "'max_depth' must be -1 (unlimited) or a path length of 0 or more",
            )
        }
    };
    let rr_survival = match &r.rr_survival {
        Some(p) if !(*p.get_ref() > 0.0 && *p.get_ref() < 1.0) => {
            return cx.err(
                p.span(),
                "'rr_survival' must be a probability between 0 and 1 (exclusive)",
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
        ..Default::default()
    })
}

fn material(cx: &Ctx, m: &Spanned<MaterialT>) -> Result<Material, SceneError> {
    let t = m.get_ref();
    let at = m.span();
    let present = [
        ("albedo", span_of(&t.albedo)),
        ("sigma", span_of(&t.sigma)),
        ("reflectance", span_of(&t.reflectance)),
        ("ior", span_of(&t.ior)),
        ("ext_ior", span_of(&t.ext_ior)),
        ("two_sided", span_of(&t.two_sided)),
    ];
    let two_sided = t.two_sided.as_ref().is_none_or(|v| *v.get_ref());
    let bsdf = match t.kind.get_ref().as_str() {
        "lambert" => {
            cx.only(&present, &["albedo", "two_sided"], "a lambert material")?;
            Bsdf::Lambert(Lambert { albedo: cx.color(cx.need(&t.albedo, "albedo", "a lambert material", &at)?, "albedo", Some(1.0))? })
        }
        "oren_nayar" => {
            cx.only(&present, &["albedo", "sigma", "two_sided"], "an oren_nayar material")?;
            let albedo = cx.color(cx.need(&t.albedo, "albedo", "an oren_nayar material", &at)?, "albedo", Some(1.0))?;
            let sigma = cx.need(&t.sigma, "sigma", "an oren_nayar material", &at)?;
            if !(sigma.get_ref().is_finite() && *sigma.get_ref() >= 0.0 && *sigma.get_ref() <= 90.0) {
                return cx.err(sigma.span(), "'sigma' (roughness, in degrees) must be between 0 and 90");
            }
            Bsdf::OrenNayar(OrenNayar::new(albedo, sigma.get_ref().to_radians()))
        }
        "mirror" => {
            cx.only(&present, &["reflectance", "two_sided"], "a mirror material")?;
            let r = t.reflectance.as_ref().map(|r| cx.color(r, "reflectance", Some(1.0))).transpose()?.unwrap_or(Color::ONE);
            Bsdf::Mirror(Mirror { reflectance: r })
        }
        "dielectric" => {
            cx.only(&present, &["ior", "ext_ior"], "a dielectric material")?;
            let ior = cx.need(&t.ior, "ior", "a dielectric material", &at)?;
            let check = |v: &Spanned<f32>, key: &str| {
                if v.get_ref().is_finite() && *v.get_ref() > 0.0 {
                    Ok(*v.get_ref())
                } else {
                    cx.err(v.span(), format!("'{key}' must be a positive index of refraction"))
                }
            };
            let int = check(ior, "ior")?;
            let ext = t.ext_ior.as_ref().map(|v| check(v, "ext_ior")).transpose()?.unwrap_or(1.0);
            Bsdf::Dielectric(Dielectric { eta: int / ext })
        }
        "black" => {
            cx.only(&present, &[], "a black material")?;
            Bsdf::Black
        }
        other => return cx.err(t.kind.span(), format!("unknown material type '{other}' (expected lambert, oren_nayar, mirror, dielectric or black)")),
    };
    Ok(Material::new(bsdf, two_sided))
}
