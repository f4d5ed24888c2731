//! Turning a scene description into the scene the integrators trace: primitives in BVH order,
//! materials, and one area light per emissive triangle or sphere.

use super::{
    desc::GeometryDesc, desc::LightDesc, Primitive, Scene, SceneDesc, Shape, NO_LIGHT, NO_NORMALS,
};
use crate::accel::{Bvh, WideBvh};
use crate::geometry::{Aabb, Sphere, Triangle};
use crate::light::{AreaLight, LightShape, Lights, OtherLight};
use glam::{Vec2, Vec3A};

impl Scene {
    pub fn build(desc: SceneDesc) -> Scene {
        let mut prims = Vec::new();
        let mut bounds = Vec::new();
        let mut lights = Vec::new();
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        for shape in &desc.shapes {
            let emission = shape.emission.filter(|e| e.max_element() > 0.0);
            match &shape.geometry {
                GeometryDesc::Mesh(mesh) => {
                    let mesh_lights = match emission {
                        Some(e) => mesh_lights(mesh, e, &mut lights),
                        None => Vec::new(),
                    };
                    for (k, idx) in mesh.indices.iter().enumerate() {
                        let [a, b, c] = idx.map(|i| Vec3A::from(mesh.positions[i as usize]));
                        let tri = Triangle::new(a, b, c);
                        let area = tri.area();
                        // Degenerate triangles can never be hit and cannot emit; drop them.
                        if !(area > 0.0) {
                            continue;
                        }
                        let nidx = if mesh.normals.is_some() || mesh.uvs.is_some() {
                            let n = tri.normal_unnormalized().normalize();
                            normals.push(match &mesh.normals {
                                Some(ns) => idx.map(|i| Vec3A::from(ns[i as usize])),
                                None => [n; 3],
                            });
                            uvs.push(match &mesh.uvs {
                                Some(ts) => idx.map(|i| ts[i as usize]),
                                None => [Vec2::ZERO, Vec2::X, Vec2::Y],
                            });
                            (normals.len() - 1) as u32
                        } else {
                            NO_NORMALS
                        };
                        let light = mesh_lights.get(k).copied().unwrap_or(NO_LIGHT);
                        bounds.push(Aabb::from_points(&[a, b, c]));
                        prims.push(Primitive {
                            shape: Shape::Triangle(tri, nidx),
                            material: shape.material,
                            light,
                        });
                    }
                }
                GeometryDesc::Sphere { center, radius } => {
                    let s = Sphere {
                        center: (*center).into(),
                        radius: *radius,
                    };
                    let light = match emission {
                        Some(e) => {
                            lights.push(AreaLight::new(LightShape::Sphere(s), e));
                            (lights.len() - 1) as u32
                        }
                        None => NO_LIGHT,
                    };
                    let r = Vec3A::splat(*radius);
                    bounds.push(Aabb {
                        min: s.center - r,
                        max: s.center + r,
                    });
                    prims.push(Primitive {
                        shape: Shape::Sphere(s),
                        material: shape.material,
                        light,
                    });
                }
            }
        }
        let mut world = Aabb::EMPTY;
        for b in &bounds {
            world = Aabb::union(&world, b);
        }
        let radius = if bounds.is_empty() {
            1.0
        } else {
            0.5 * (world.max - world.min).length()
        };
        let others = desc
            .lights
            .iter()
            .map(|l| match *l {
                LightDesc::Point {
                    position,
                    intensity,
                } => OtherLight::Point {
                    p: position.into(),
                    intensity,
                },
                LightDesc::Directional {
                    direction,
                    irradiance,
                } => OtherLight::Directional {
                    dir: Vec3A::from(direction).normalize(),
                    irradiance,
                },
                LightDesc::Constant { radiance } => OtherLight::Constant { radiance },
            })
            .collect();
        let bvh = Bvh::build(&bounds);
        let prims = bvh.order.iter().map(|&i| prims[i as usize]).collect();
        Scene {
            prims,
            bvh: WideBvh::from_binary(&bvh),
            materials: desc.materials,
            lights: Lights::with_others(lights, others, radius),
            normals,
            uvs,
            textures: desc.textures,
            cameras: desc.cameras,
            desc_settings: desc.settings,
        }
    }
}

/// The area lights of an emissive mesh, and the light of each of its triangles (NO_LIGHT for
/// degenerate ones). Consecutive triangles that form a parallelogram (a quad split along a
/// diagonal, as OBJ, PLY and Mitsuba's rectangles give them) share one parallelogram light.
fn mesh_lights(
    mesh: &crate::geometry::mesh::TriangleMesh,
    e: crate::Color,
    lights: &mut Vec<AreaLight>,
) -> Vec<u32> {
    let tri = |k: usize| {
        let [a, b, c] = mesh.indices[k].map(|i| Vec3A::from(mesh.positions[i as usize]));
        Triangle::new(a, b, c)
    };
    let n = mesh.indices.len();
    let mut ids = vec![NO_LIGHT; n];
    let mut k = 0;
    while k < n {
        let t = tri(k);
        if !(t.area() > 0.0) {
            k += 1;
            continue;
        }
        if k + 1 < n {
            let t2 = tri(k + 1);
            if let Some(l) = AreaLight::parallelogram(&t, &t2, e).filter(|_| t2.area() > 0.0) {
                lights.push(l);
                ids[k] = (lights.len() - 1) as u32;
                ids[k + 1] = ids[k];
                k += 2;
                continue;
            }
        }
        lights.push(AreaLight::new(LightShape::Triangle(t), e));
        ids[k] = (lights.len() - 1) as u32;
        k += 1;
    }
    ids
}
