//! Scenes: the description read from a file, and the built scene the integrators trace.
//!
//! Data flows one way: a file is parsed into a [`SceneDesc`] (geometry, materials, cameras and
//! settings, independent of the format), which [`Scene::build`] turns into primitives, a BVH,
//! materials and lights.

pub mod build;
pub mod desc;
pub mod error;
pub mod obj;
pub mod ply;
pub mod text;
pub mod toml;
pub mod xml;

pub use desc::{GeometryDesc, SceneDesc, ShapeDesc};
pub use error::SceneError;

use crate::accel::WideBvh;
use crate::camera::CameraDesc;
use crate::geometry::ray::{offset_ray_origin, SHADOW_EPSILON};
use crate::geometry::{Ray, Sphere, Triangle};
use crate::light::Lights;
use crate::material::Material;
use glam::{Vec2, Vec3A};

pub const NO_LIGHT: u32 = u32::MAX;
pub const NO_NORMALS: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// A triangle and the index of its vertex normals in `Scene::normals` (or NO_NORMALS).
    Triangle(Triangle, u32),
    Sphere(Sphere),
}

#[derive(Clone, Copy, Debug)]
pub struct Primitive {
    pub shape: Shape,
    pub material: u32,
    /// Index into the lights if this primitive emits, else NO_LIGHT.
    pub light: u32,
}

/// A ray's hit on a surface, with everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct Interaction {
    pub p: Vec3A,
    /// Conservative bound on the floating-point error of `p`, per axis.
    pub p_err: Vec3A,
    /// Unit geometric normal, oriented as the geometry defines it (front side).
    pub ng: Vec3A,
    /// Unit shading normal, on the same side as `ng`.
    pub ns: Vec3A,
    pub t: f32,
    /// Texture coordinates: the mesh's, interpolated; barycentric (b1, b2) on a mesh without
    /// them; (φ/2π, θ/π) on a sphere (Mitsuba's conventions).
    pub uv: Vec2,
    pub material: u32,
    pub light: u32,
}

impl Interaction {
    /// A ray leaving this point in direction `d`, offset off the surface to `d`'s side.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3A) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_err, self.ng, d), d)
    }

    /// A shadow ray from this point to the point `p2` (normal `n2`, error `err2`); returns
    /// the ray and the parametric distance up to which it must be unobstructed.
    #[inline]
    pub fn spawn_ray_to(&self, p2: Vec3A, err2: Vec3A, n2: Vec3A) -> (Ray, f32) {
        let d0 = p2 - self.p;
        let o = offset_ray_origin(self.p, self.p_err, self.ng, d0);
        let target = offset_ray_origin(p2, err2, n2, o - p2);
        (Ray::new(o, target - o), 1.0 - SHADOW_EPSILON)
    }
}

pub struct Scene {
    /// Primitives in BVH order.
    pub prims: Vec<Primitive>,
    pub bvh: WideBvh,
    pub materials: Vec<Material>,
    pub lights: Lights,
    /// Vertex normals and texture coordinates of triangles whose mesh has either (the
    /// triangle's face normal, and barycentric uvs, stand in for what it lacks).
    pub normals: Vec<[Vec3A; 3]>,
    pub uvs: Vec<[Vec2; 3]>,
    pub textures: Vec<crate::texture::Texture>,
    pub cameras: Vec<(String, CameraDesc)>,
    pub desc_settings: desc::FileSettings,
}

impl Scene {
    /// Closest hit along the ray, if any.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        let mut best = (usize::MAX, 0.0f32, 0.0f32, 0.0f32);
        let prims = &self.prims;
        let found = self
            .bvh
            .intersect(ray, f32::INFINITY, |i, t_max| match &prims[i].shape {
                Shape::Triangle(tri, _) => tri.intersect(ray, t_max).map(|(t, u, v)| {
                    best = (i, u, v, t);
                    t
                }),
                Shape::Sphere(s) => s.intersect(ray, t_max).inspect(|&t| {
                    best = (i, 0.0, 0.0, t);
                }),
            });
        if !found {
            return None;
        }
        let (i, u, v, t) = best;
        Some(self.interaction(ray, i, u, v, t))
    }

    #[inline]
    fn interaction(&self, ray: &Ray, i: usize, u: f32, v: f32, t_hit: f32) -> Interaction {
        let prim = &self.prims[i];
        match &prim.shape {
            Shape::Triangle(tri, nidx) => {
                let (p, p_err) = tri.point(u, v);
                let ng = tri.normal_unnormalized().normalize();
                let ns = if *nidx != NO_NORMALS {
                    let [n0, n1, n2] = self.normals[*nidx as usize];
                    let n = (n0 * (1.0 - u - v) + n1 * u + n2 * v).normalize_or_zero();
                    // Keep the shading normal on the geometric normal's side.
                    if n == Vec3A::ZERO {
                        ng
                    } else if n.dot(ng) < 0.0 {
                        -n
                    } else {
                        n
                    }
                } else {
                    ng
                };
                let uv = if *nidx != NO_NORMALS {
                    let [t0, t1, t2] = self.uvs[*nidx as usize];
                    t0 * (1.0 - u - v) + t1 * u + t2 * v
                } else {
                    Vec2::new(u, v)
                };
                Interaction {
                    p,
                    p_err,
                    ng,
                    ns,
                    t: t_hit,
                    uv,
                    material: prim.material,
                    light: prim.light,
                }
            }
            Shape::Sphere(s) => {
                let (p, n, p_err) = s.surface_point(ray.at(t_hit));
                let phi = n.y.atan2(n.x);
                let phi = if phi < 0.0 {
                    phi + std::f32::consts::TAU
                } else {
                    phi
                };
                let uv = Vec2::new(
                    phi / std::f32::consts::TAU,
                    n.z.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
                );
                Interaction {
                    p,
                    p_err,
                    ng: n,
                    ns: n,
                    t: t_hit,
                    uv,
                    material: prim.material,
                    light: prim.light,
                }
            }
        }
    }

    /// True if anything blocks the ray before parametric distance `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let prims = &self.prims;
        self.bvh
            .occluded(ray, t_max, |i, t_max| match &prims[i].shape {
                Shape::Triangle(tri, _) => tri.intersect(ray, t_max).is_some(),
                Shape::Sphere(s) => s.intersect(ray, t_max).is_some(),
            })
    }

    /// Bytes held by the geometry the integrators trace: primitives, BVH nodes, vertex
    /// normals and texture coordinates (not materials, textures or lights).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.prims.len() * size_of::<Primitive>()
            + self.bvh.memory_bytes()
            + self.normals.len() * size_of::<[Vec3A; 3]>()
            + self.uvs.len() * size_of::<[Vec2; 3]>()
    }

    /// The material at a hit, its texture (if any) evaluated there.
    #[inline]
    pub fn material_at(&self, si: &Interaction) -> Material {
        let m = self.materials[si.material as usize];
        match m.texture {
            None => m,
            Some(t) => m.with_color(self.textures[t as usize].eval(si.uv)),
        }
    }

    pub fn camera(&self, name: Option<&str>) -> Option<&CameraDesc> {
        match name {
            None => self.cameras.first().map(|(_, c)| c),
            Some(n) => self.cameras.iter().find(|(k, _)| k == n).map(|(_, c)| c),
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.prims
            .iter()
            .filter(|p| matches!(p.shape, Shape::Triangle(..)))
            .count()
    }
}
