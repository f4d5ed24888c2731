//! The scene description: what a scene file says, independent of its format.

use crate::camera::CameraDesc;
use crate::geometry::mesh::TriangleMesh;
use crate::material::Material;
use crate::Color;
use glam::Vec3;

#[derive(Clone, Debug)]
pub enum GeometryDesc {
    Mesh(TriangleMesh),
    Sphere { center: Vec3, radius: f32 },
}

#[derive(Clone, Debug)]
pub struct ShapeDesc {
    pub geometry: GeometryDesc,
    /// Index into `SceneDesc::materials`.
    pub material: u32,
    /// Radiance emitted from the front side, if the shape is an area light.
    pub emission: Option<Color>,
}

/// Render settings a scene file may give; command-line flags override each one.
#[derive(Clone, Debug, Default)]
pub struct FileSettings {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub seed: Option<u64>,
    pub integrator: Option<crate::integrator::IntegratorKind>,
    /// Mitsuba's meaning: 1 = emitters seen directly, 2 = direct light, …; None = unlimited.
    pub max_depth: Option<u32>,
    pub shadow_rays: Option<u32>,
    pub rr_survival: Option<f32>,
    pub camera: Option<String>,
    pub sampler: Option<crate::sampler::SamplerKind>,
    /// Russian roulette from this path depth on (Mitsuba's `rr_depth`).
    pub rr_depth: Option<u32>,
    /// Emitters seen directly by the camera render black (Mitsuba's `hide_emitters`).
    pub hide_emitters: Option<bool>,
    /// Whether `direct` follows mirrors and glass to the first diffuse surface (mcrt's
    /// default) or stops at the first surface (Mitsuba's `direct`).
    pub specular_chain: Option<bool>,
    /// Render only this window of the image: x, y, width, height (Mitsuba's crop).
    pub crop: Option<[u32; 4]>,
}

/// Lights that are not shapes.
#[derive(Clone, Debug)]
pub enum LightDesc {
    /// Radiant intensity I (W/sr) in every direction from a point.
    Point { position: Vec3, intensity: Color },
    /// Irradiance E arriving along `direction` (the way the light travels) from infinitely
    /// far away.
    Directional { direction: Vec3, irradiance: Color },
    /// Constant radiance arriving from every direction (a uniform environment).
    Constant { radiance: Color },
}

#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    pub settings: FileSettings,
    pub cameras: Vec<(String, CameraDesc)>,
    pub materials: Vec<Material>,
    pub shapes: Vec<ShapeDesc>,
    pub lights: Vec<LightDesc>,
    /// Textures that materials refer to by index.
    pub textures: Vec<crate::texture::Texture>,
    /// Things the loader accepted but rendered differently, one line each with file:line:col.
    pub warnings: Vec<String>,
}
