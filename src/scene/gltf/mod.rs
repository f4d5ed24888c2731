//! glTF 2.0 scenes (`.gltf` with embedded or external buffers, and binary `.glb`), read into
//! the same [`SceneDesc`] as the TOML and Mitsuba XML loaders produce.
//!
//! The JSON and GLB container are parsed and validated by the `gltf` crate (references
//! between objects, enum values); everything that reads bytes (buffers, accessors, images)
//! is done here with bounds checks, so that a bad file is an error, never a panic.
//! Conventions (glTF 2.0 specification, §3.4 "Coordinate System and Units"): right-handed,
//! +y up, metres; a camera looks down its node's −z with +y up; column vectors, node
//! matrices are `T·R·S`; texture coordinate (0, 0) is the image's top-left corner, as in
//! mcrt's textures (see [`crate::texture`]). See docs/gltf.md for what maps to what.

mod accessors;
mod buffers;
mod cameras;
mod lights;
mod materials;
mod meshes;
mod nodes;

use super::desc::{LightDesc, SceneDesc};
use super::SceneError;
use crate::Color;
use std::path::Path;

/// Extensions mcrt reads (fully or approximately); a file that requires any other is refused.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
];

/// The W per lm of 555 nm light, the photometric-to-radiometric factor mcrt uses for
/// KHR_lights_punctual's candela and lux (as Blender's glTF exporter does, `PBR_WATTS_TO_LUMENS`).
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Radiance of the environment a light-less scene gets with `--lenient`.
pub const DEFAULT_ENVIRONMENT: f32 = 1.0;

/// The loading state shared by the concept modules.
pub(super) struct Loader<'a> {
    pub path: &'a Path,
    pub doc: &'a ::gltf::Document,
    pub buffers: Vec<Vec<u8>>,
    pub desc: SceneDesc,
    /// Things rendered differently from what the file says (refused unless `--lenient`).
    pub approximations: Vec<String>,
    pub lenient: bool,
    pub images: std::collections::HashMap<(usize, bool), std::sync::Arc<crate::texture::Bitmap>>,
    /// Each glTF material's mcrt material and emission (None: the default material).
    pub material_cache:
        std::collections::HashMap<Option<usize>, (u32, Option<materials::Emission>)>,
    /// Triangles and vertices read so far (a shape group's once).
    pub triangles: usize,
    pub vertices: usize,
    /// How many nodes that can place an instance use each mesh (see [`meshes`]).
    pub mesh_uses: std::collections::HashMap<usize, usize>,
    /// Each reused mesh's shape group (None: it emits, and is copied instead).
    pub mesh_groups: std::collections::HashMap<usize, Option<u32>>,
}

impl Loader<'_> {
    pub fn err(&self, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.path, None, msg)
    }

    /// Records something mcrt renders differently from what the file says.
    pub fn approximate(&mut self, what: String) {
        if !self.approximations.contains(&what) {
            self.approximations.push(what);
        }
    }

    /// Records a remark that is not an approximation (printed as a warning in every mode).
    pub fn note(&mut self, what: String) {
        let w = format!("{}: {what}", self.path.display());
        if !self.desc.warnings.contains(&w) {
            self.desc.warnings.push(w);
        }
    }
}

/// Reads a glTF 2.0 scene from `bytes`, the contents of `path` (`.gltf` JSON or `.glb`);
/// external buffers and images are read relative to `path`. Without `lenient`, anything mcrt
/// would render differently from what the file says is refused, naming it; with it, each
/// approximation becomes one warning line.
pub fn parse_gltf(path: &Path, bytes: &[u8], lenient: bool) -> Result<SceneDesc, SceneError> {
    let (doc, blob) = open(path, bytes)?;
    let buffers = buffers::load(path, &doc, blob)?;
    let mut l = Loader {
        path,
        doc: &doc,
        buffers,
        desc: SceneDesc::default(),
        approximations: Vec::new(),
        lenient,
        images: Default::default(),
        material_cache: Default::default(),
        triangles: 0,
        vertices: 0,
        mesh_uses: Default::default(),
        mesh_groups: Default::default(),
    };
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| l.err("the file has no scene (its 'scenes' array is empty)"))?;
    let placed = nodes::flatten(&l, &scene)?;
    meshes::count_uses(&mut l, &placed);
    for p in &placed {
        if let Some(mesh) = p.node.mesh() {
            meshes::place_mesh(&mut l, &mesh, &p.world)?;
        }
        if let Some(cam) = p.node.camera() {
            cameras::add_camera(&mut l, &p.node, &cam, &p.world)?;
        }
        if let Some(light) = p.node.light() {
            lights::add_light(&mut l, &light, &p.world)?;
        }
    }
    finish(l)
}

/// The checks after everything is read: a camera, a light, and the approximations.
fn finish(mut l: Loader) -> Result<SceneDesc, SceneError> {
    if l.desc.cameras.is_empty() {
        return Err(l.err(
            "the scene has no camera (glTF cameras are nodes with a 'camera'; in Blender, \
             add a camera and tick Include > Cameras when exporting)",
        ));
    }
    let emitters = l.desc.shapes.iter().any(|s| s.emission.is_some());
    if l.desc.lights.is_empty() && !emitters {
        let msg = format!(
            "the scene has no light: no KHR_lights_punctual light and no emissive material \
             (in Blender, tick Include > Punctual Lights when exporting, or give a material \
             an emission); --lenient lights it with a uniform white environment of \
             radiance {DEFAULT_ENVIRONMENT}"
        );
        if !l.lenient {
            return Err(l.err(msg));
        }
        l.desc.lights.push(LightDesc::Constant {
            radiance: Color::splat(DEFAULT_ENVIRONMENT),
        });
        l.approximations.push(format!(
            "the scene has no light: lit by a uniform white environment of radiance \
             {DEFAULT_ENVIRONMENT}"
        ));
    }
    if !l.lenient {
        if let Some(first) = l.approximations.first() {
            let more = match l.approximations.len() {
                1 => String::new(),
                n => format!(" (and {} more)", n - 1),
            };
            return Err(l.err(format!(
                "{first}{more}; --lenient renders the scene anyway and lists each approximation"
            )));
        }
    }
    let path = l.path.display().to_string();
    for a in std::mem::take(&mut l.approximations) {
        l.desc.warnings.push(format!("{path}: approximated: {a}"));
    }
    Ok(l.desc)
}

/// Parses and validates the JSON (and the GLB container), refusing required extensions mcrt
/// does not read. Returns the document and the GLB's binary chunk.
fn open(path: &Path, bytes: &[u8]) -> Result<(::gltf::Document, Option<Vec<u8>>), SceneError> {
    let err = |loc, msg: String| SceneError::new(path, loc, msg);
    let glb = bytes.starts_with(b"glTF");
    if glb {
        buffers::check_glb_header(bytes).map_err(|m| err(None, m))?;
    }
    let g = ::gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| match e {
        ::gltf::Error::Deserialize(j) if !glb => {
            // serde_json ends its message with the place, which the error already gives.
            let place = format!(" at line {} column {}", j.line(), j.column());
            let msg = j.to_string();
            let msg = msg.strip_suffix(&place).unwrap_or(&msg).to_string();
            err(
                Some((j.line(), j.column())),
                format!("invalid glTF JSON: {msg}"),
            )
        }
        ::gltf::Error::Deserialize(j) => {
            err(None, format!("invalid JSON in the GLB's JSON chunk: {j}"))
        }
        ::gltf::Error::Binary(b) => err(None, format!("invalid GLB container: {b}")),
        e => err(None, format!("cannot read the glTF file: {e}")),
    })?;
    let mut root = g.document.into_json();
    if !root.asset.version.starts_with("2.") {
        return Err(err(
            None,
            format!(
                "asset.version is '{}': mcrt reads glTF 2.x",
                crate::input::shorten(&root.asset.version)
            ),
        ));
    }
    for ext in &root.extensions_required {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(err(
                None,
                format!(
                    "the file requires the extension '{}', which mcrt does not support \
                     (supported: {}); in Blender, export without compression",
                    crate::input::shorten(ext),
                    SUPPORTED_EXTENSIONS.join(", ")
                ),
            ));
        }
    }
    // Checked above; the crate's own list is narrower (it knows no quantization).
    root.extensions_required.clear();
    check_attribute_indices(&root).map_err(|m| err(None, m))?;
    let doc = ::gltf::Document::from_json(root).map_err(|e| match e {
        ::gltf::Error::Validation(v) => err(None, validation_message(&v)),
        e => err(None, format!("invalid glTF: {e}")),
    })?;
    Ok((doc, g.blob))
}

/// Refuses an attribute naming an accessor that does not exist: the crate's validation of a
/// primitive indexes the accessors by the POSITION attribute before checking it (gltf-json
/// 1.4.1, mesh.rs), and would panic (found by the fuzz target).
fn check_attribute_indices(root: &::gltf::json::Root) -> Result<(), String> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= n {
                    let name = match semantic {
                        ::gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        _ => "an attribute".into(),
                    };
                    return Err(format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes.{name} refers to \
                         accessors[{}], which does not exist ({n} accessors)",
                        index.value()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The validation errors, by JSON path: the first three, and how many more.
fn validation_message(v: &[(::gltf::json::Path, ::gltf::json::validation::Error)]) -> String {
    use ::gltf::json::validation::Error as E;
    let each: Vec<String> = v
        .iter()
        .take(3)
        .map(|(p, e)| {
            let what = match e {
                E::IndexOutOfBounds => {
                    "refers to an object that does not exist (index out of range)"
                }
                E::Invalid => "has an invalid value",
                E::Missing => "is missing",
                E::Oversize => "is too large",
                E::Unsupported => "is not supported",
            };
            format!("{} {what}", p.as_str())
        })
        .collect();
    let more = if v.len() > 3 {
        format!(" (and {} more)", v.len() - 3)
    } else {
        String::new()
    };
    format!("invalid glTF: {}{more}", each.join("; "))
}
