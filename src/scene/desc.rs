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
}

#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    pub settings: FileSettings,
    pub cameras: Vec<(String, CameraDesc)>,
    pub materials: Vec<Material>,
    pub shapes: Vec<ShapeDesc>,
}
