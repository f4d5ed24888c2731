//! The scene description: what a scene file says, independent of its format.

use crate::camera::CameraDesc;
use crate::geometry::mesh::TriangleMesh;
use crate::material::Material;
use crate::Color;
use glam::Vec3;

#[derive(Clone, Debug)]
pub enum GeometryDesc {
    Mesh(TriangleMesh),
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// A sphere with a frame of its own (Mitsuba's, set by `to_world`): `rotation` takes its
    /// local axes, in which texture coordinates are (φ/2π, θ/π), to the world's; `flip`
    /// turns its normals inwards (`flip_normals`).
    OrientedSphere {
        center: Vec3,
        radius: f32,
        rotation: glam::Mat3,
        flip: bool,
    },
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
    /// Mitsuba's `spot` ([`crate::light::spot`]): at the origin of `to_world`, along its +z.
    Spot {
        to_world: glam::Mat4,
        intensity: Color,
        /// Degrees.
        cutoff_angle: f32,
        beam_width: f32,
        /// Index into `SceneDesc::textures` of the projected texture.
        texture: Option<u32>,
    },
    /// Mitsuba's `envmap` ([`crate::light::envmap`]): a latitude-longitude image times
    /// `scale`, turned by `to_world` (a rotation).
    Envmap {
        image: std::sync::Arc<crate::texture::Bitmap>,
        scale: f32,
        to_world: glam::Mat4,
    },
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
    /// (shape index, texture) of the area lights whose radiance is a texture, by shape;
    /// their `ShapeDesc::emission` is the texture's mean.
    pub emission_textures: Vec<(usize, u32)>,
    /// Things the loader accepted but rendered differently, one line each with file:line:col.
    pub warnings: Vec<String>,
    /// Shapes stored once and placed by `instances` (see [`super::instance`]).
    pub groups: Vec<GroupDesc>,
    pub instances: Vec<InstanceDesc>,
}

/// Shapes stored, and their BVH built, once, whatever the number of instances that place
/// them; never rendered by themselves (Mitsuba's `shapegroup`). Their shapes may not emit.
#[derive(Clone, Debug, Default)]
pub struct GroupDesc {
    pub name: String,
    pub shapes: Vec<ShapeDesc>,
}

/// One placement of a group (Mitsuba's `instance`): `to_world` maps the group's object space
/// to the world; it must be invertible.
#[derive(Clone, Copy, Debug)]
pub struct InstanceDesc {
    /// Index into `SceneDesc::groups`.
    pub group: u32,
    pub to_world: glam::Affine3A,
}

/// Most primitives (triangles and spheres) a scene may hold: the BVH's leaves name a
/// primitive in 27 bits.
pub const MAX_PRIMITIVES: usize = (1 << 27) - 1;

impl SceneDesc {
    /// What [`crate::scene::Scene::build`] cannot represent, if the scene exceeds it: more
    /// than [`MAX_PRIMITIVES`] triangles and spheres, vertices past 32-bit indices, or more
    /// materials than a primitive's 30 bits of material index. (Checked before the build,
    /// which would otherwise stop on an assertion.)
    pub fn check_limits(&self) -> Result<(), String> {
        let (prims, vertices) = shape_counts(&self.shapes);
        check_counts(prims, vertices, self.materials.len())?;
        super::instance::check_limits(self)
    }
}

/// The primitives (triangles and spheres) and vertices of `shapes`.
pub(super) fn shape_counts(shapes: &[ShapeDesc]) -> (usize, usize) {
    let (mut prims, mut vertices) = (0usize, 0usize);
    for s in shapes {
        match &s.geometry {
            GeometryDesc::Mesh(m) => {
                prims += m.indices.len();
                vertices += m.positions.len();
            }
            GeometryDesc::Sphere { .. } | GeometryDesc::OrientedSphere { .. } => prims += 1,
        }
    }
    (prims, vertices)
}

/// [`SceneDesc::check_limits`] on the counts.
pub(super) fn check_counts(prims: usize, vertices: usize, materials: usize) -> Result<(), String> {
    if prims > MAX_PRIMITIVES {
        return Err(format!(
            "the scene has {prims} triangles and spheres; mcrt renders at most {MAX_PRIMITIVES}"
        ));
    }
    if vertices >= u32::MAX as usize {
        return Err(format!(
            "the scene's meshes have {vertices} vertices; mcrt renders at most {}",
            u32::MAX - 1
        ));
    }
    let most = super::META_MATERIAL as usize;
    if materials > most {
        return Err(format!(
            "the scene has {materials} materials; mcrt renders at most {most}"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The limits are those `Scene::build` asserts: the largest scene within them passes,
    /// one more of anything is refused with a message that names it.
    #[test]
    fn limits_are_the_builds() {
        let most = (
            MAX_PRIMITIVES,
            u32::MAX as usize - 1,
            super::super::META_MATERIAL as usize,
        );
        assert_eq!(check_counts(most.0, most.1, most.2), Ok(()));
        let err = |r: Result<(), String>| r.unwrap_err();
        assert!(err(check_counts(most.0 + 1, 3, 1)).contains("triangles and spheres"));
        assert!(err(check_counts(1, most.1 + 1, 1)).contains("vertices"));
        assert!(err(check_counts(1, 3, most.2 + 1)).contains("materials"));
        assert_eq!(SceneDesc::default().check_limits(), Ok(()));
    }
}
