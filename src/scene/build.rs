//! Turning a scene description into the scene the integrators trace: indexed triangles and
//! spheres in BVH order, materials, and one area light per emissive triangle or sphere.

use super::{
    desc::GeometryDesc, desc::LightDesc, MeshAttrs, Scene, SceneDesc, SphereFrame, META_ATTRS,
    META_EMITTER, META_MATERIAL, SPHERE,
};
use crate::accel::bvh::{self, PrimRef};
use crate::accel::{huge_pages, BuildTimes, SingleRays};
use crate::geometry::{Aabb, Sphere, Triangle};
use crate::light::{AreaLight, LightShape, Lights, OtherLight};
use glam::Vec3A;
use rayon::prelude::*;

impl Scene {
    /// The scene the integrators trace, from its description, its single rays answered as
    /// [`SingleRays::Auto`] chooses. Panics on a description beyond what it can represent;
    /// [`SceneDesc::check_limits`] tells those apart first, with a message (the CLI checks
    /// before it builds).
    pub fn build(desc: SceneDesc) -> Scene {
        Scene::build_with(desc, SingleRays::Auto)
    }

    /// [`Scene::build`] with its single rays answered as `single_rays` says.
    pub fn build_with(mut desc: SceneDesc, single_rays: SingleRays) -> Scene {
        let mut times = BuildTimes::start();
        let instances = super::instance::build(&mut desc, &mut times);
        let masked = desc.materials.iter().any(|m| m.opacity.is_some());
        // Primitives in the description's order: vertex indices (or a sphere), material and
        // flags, and bounds.
        let mut tris: Vec<[u32; 3]> = Vec::new();
        let mut meta: Vec<u32> = Vec::new();
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        let mut tangents = Vec::new();
        let mut attrs = Vec::new();
        let mut spheres = Vec::new();
        let mut sphere_frames = Vec::new();
        let mut lights = Vec::new();
        // (primitive, light) of the emitting primitives, by primitive.
        let mut emitting: Vec<(u32, u32)> = Vec::new();
        // (Shapes are taken by value: the first mesh's arrays become the scene's, uncopied.)
        for (index, shape) in std::mem::take(&mut desc.shapes).into_iter().enumerate() {
            let emission_texture = desc
                .emission_textures
                .iter()
                .find(|&&(s, _)| s == index)
                .map(|&(_, t)| t);
            let emission = shape
                .emission
                .filter(|e| e.max_element() > 0.0 || emission_texture.is_some());
            assert!(shape.material <= META_MATERIAL, "too many materials");
            let mut m = shape.material;
            if emission.is_some() {
                m |= META_EMITTER;
            }
            // (centre, radius, frame) of a sphere, pushed after the match.
            let mut sphere = None;
            match shape.geometry {
                GeometryDesc::Mesh(mut mesh) => {
                    mesh.drop_flat_normals();
                    let base = positions.len() as u32;
                    assert!(
                        positions.len() + mesh.positions.len() < SPHERE as usize,
                        "too many vertices"
                    );
                    // Texture coordinates matter only under a texture: without one the hit
                    // skips the search for its mesh's attributes (which cost a ray in the
                    // Cornell box, whose quads all have them, 45 instructions).
                    // (A normal or bump map needs the flag for its partials, with or
                    // without texture coordinates.)
                    let mat = desc.materials.get(shape.material as usize);
                    let textured =
                        emission_texture.is_some() || mat.is_some_and(|mat| mat.reads_uv());
                    let perturbs = mat.is_some_and(|mat| mat.perturbs());
                    if mesh.normals.is_some() || (mesh.uvs.is_some() && textured) || perturbs {
                        m |= META_ATTRS;
                        attrs.push(MeshAttrs {
                            first_vertex: base,
                            normals: mesh.normals.as_ref().map_or(u32::MAX, |ns| {
                                normals.extend_from_slice(ns);
                                (normals.len() - ns.len()) as u32
                            }),
                            uvs: mesh
                                .uvs
                                .as_ref()
                                .filter(|_| textured)
                                .map_or(u32::MAX, |ts| {
                                    uvs.extend_from_slice(ts);
                                    (uvs.len() - ts.len()) as u32
                                }),
                            // Only a normal map's tangent frame reads them.
                            tangents: mesh
                                .tangents
                                .as_ref()
                                .filter(|_| mat.is_some_and(|mat| mat.normal_map.is_some()))
                                .map_or(u32::MAX, |ts| {
                                    tangents.extend_from_slice(ts);
                                    (tangents.len() - ts.len()) as u32
                                }),
                        });
                    }
                    let vertex = |i: u32| Vec3A::from(mesh.positions[i as usize]);
                    // Degenerate triangles can never be hit and cannot emit; drop them. (The
                    // first mesh, without any, keeps its own array: no copy.)
                    let has_area = |idx: &[u32; 3]| {
                        let [a, b, c] = idx.map(vertex);
                        Triangle::new(a, b, c).has_area()
                    };
                    let kept: Vec<[u32; 3]> = if base == 0
                        && mesh.indices.par_iter().with_min_len(1 << 12).all(has_area)
                    {
                        mesh.indices
                    } else {
                        mesh.indices
                            .par_iter()
                            .with_min_len(1 << 12)
                            .filter(|idx| has_area(idx))
                            .map(|idx| idx.map(|i| i + base))
                            .collect()
                    };
                    if let Some(e) = emission {
                        let kept_tris: Vec<Triangle> = kept
                            .iter()
                            .map(|idx| {
                                let [a, b, c] = idx.map(|i| vertex(i - base));
                                Triangle::new(a, b, c)
                            })
                            .collect();
                        let ids: Vec<u32> = match emission_texture {
                            None => mesh_lights(&kept_tris, e, &mut lights).collect(),
                            Some(t) => {
                                // Barycentric coordinates stand in for missing uvs, as at a hit.
                                let uv = |i: u32| {
                                    mesh.uvs
                                        .as_ref()
                                        .map_or(glam::Vec2::ZERO, |u| u[(i - base) as usize])
                                };
                                let corners = [glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y];
                                kept.iter()
                                    .zip(&kept_tris)
                                    .map(|(idx, tri)| {
                                        let uvs = match mesh.uvs {
                                            Some(_) => idx.map(uv),
                                            None => corners,
                                        };
                                        lights.push(
                                            AreaLight::new(LightShape::Triangle(*tri), e)
                                                .with_texture(t, uvs),
                                        );
                                        (lights.len() - 1) as u32
                                    })
                                    .collect()
                            }
                        };
                        for (k, light) in ids.into_iter().enumerate() {
                            emitting.push(((tris.len() + k) as u32, light));
                        }
                    }
                    meta.resize(meta.len() + kept.len(), m);
                    if tris.is_empty() {
                        tris = kept;
                    } else {
                        tris.extend_from_slice(&kept);
                    }
                    if positions.is_empty() {
                        positions = mesh.positions;
                    } else {
                        positions.extend_from_slice(&mesh.positions);
                    }
                }
                GeometryDesc::Sphere { center, radius } => {
                    sphere = Some((center, radius, SphereFrame::default()));
                }
                GeometryDesc::OrientedSphere {
                    center,
                    radius,
                    rotation,
                    flip,
                } => {
                    let frame = SphereFrame {
                        to_local: (rotation != glam::Mat3::IDENTITY)
                            .then(|| glam::Mat3A::from(rotation.transpose())),
                        flip,
                    };
                    sphere = Some((center, radius, frame));
                }
            }
            if let Some((center, radius, frame)) = sphere {
                let s = Sphere {
                    center: center.into(),
                    radius,
                };
                if let Some(e) = emission {
                    let mut light = AreaLight::new(LightShape::Sphere(s), e);
                    if let Some(t) = emission_texture {
                        light = light.with_texture(t, light.uvs);
                    }
                    lights.push(if frame.flip { light.inward() } else { light });
                    emitting.push((tris.len() as u32, (lights.len() - 1) as u32));
                }
                tris.push([SPHERE, spheres.len() as u32, 0]);
                meta.push(m);
                spheres.push(s);
                sphere_frames.push(frame);
            }
        }
        assert!(tris.len() < 1 << 27, "too many primitives");
        let bounds_of = |idx: &[u32; 3]| {
            if idx[0] == SPHERE {
                let s: &Sphere = &spheres[idx[1] as usize];
                let r = Vec3A::splat(s.radius);
                Aabb {
                    min: s.center - r,
                    max: s.center + r,
                }
            } else {
                Aabb::from_points(&idx.map(|i| Vec3A::from(positions[i as usize])))
            }
        };
        times.mark("primitives");
        let prim = |i: u32| {
            let idx = &tris[i as usize];
            PrimRef::new(&bounds_of(idx), i, idx[0] == SPHERE)
        };
        let (wide, order) = bvh::build(tris.len(), prim, &mut times);
        let bounds =
            super::instance::union(wide.bounds(), instances.as_ref().and_then(|i| i.bounds()));
        let radius = bounds.map_or(1.0, |world| 0.5 * (world.max - world.min).length());
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
                LightDesc::Spot {
                    to_world,
                    intensity,
                    cutoff_angle,
                    beam_width,
                    texture,
                } => OtherLight::Spot(Box::new(crate::light::spot::SpotLight::new(
                    to_world.w_axis.truncate().into(),
                    glam::Mat3::from_mat4(to_world),
                    intensity,
                    cutoff_angle,
                    beam_width,
                    texture.and_then(|t| desc.textures.get(t as usize).cloned()),
                ))),
                LightDesc::Envmap {
                    ref image,
                    scale,
                    to_world,
                } => OtherLight::Envmap(std::sync::Arc::new(crate::light::envmap::EnvMap::new(
                    image,
                    scale,
                    glam::Mat3::from_mat4(to_world),
                ))),
            })
            .collect();
        // The padding vertex that `Scene::vertex_fast` may read past the last one.
        positions.push(glam::Vec3::ZERO);
        // Each old array is freed as soon as its reordered copy is made, so that the next
        // copy reuses memory the build has touched already (see `bvh::build` on fresh
        // memory).
        let tris = permuted(tris, &order);
        let meta = permuted(meta, &order);
        times.mark("reorder");
        #[cfg(target_arch = "x86_64")]
        let flat = match single_rays {
            SingleRays::Auto => flat(&tris, &positions, &spheres),
            SingleRays::Bvh => None,
            SingleRays::Flat(k) => flat_with(&tris, &positions, &spheres, Some(k)),
        }
        .filter(|_| !masked);
        #[cfg(not(target_arch = "x86_64"))]
        let _ = single_rays;
        // `emitting` is sorted by primitive.
        let emitters = if emitting.is_empty() {
            Vec::new()
        } else {
            order
                .par_iter()
                .enumerate()
                .with_min_len(1 << 12)
                .filter(|&(i, _)| meta[i] & META_EMITTER != 0)
                .map(|(i, p)| {
                    let k = emitting.binary_search_by_key(p, |&(q, _)| q).unwrap();
                    (i as u32, emitting[k].1)
                })
                .collect()
        };
        times.mark("materials and emitters");
        Scene {
            build_times: times,
            tris,
            meta,
            positions,
            spheres,
            sphere_frames,
            #[cfg(target_arch = "x86_64")]
            flat,
            emitters,
            normals,
            uvs,
            tangents,
            attrs,
            bvh: wide,
            materials: desc.materials,
            lights: Lights::with_others(lights, others, radius).with_textures(
                if desc.emission_textures.is_empty() {
                    Vec::new()
                } else {
                    desc.textures.clone()
                },
            ),
            textures: desc.textures,
            cameras: desc.cameras,
            desc_settings: desc.settings,
            instances,
            masked,
        }
    }
}

/// The area lights of an emissive mesh's (non-degenerate) triangles, pushed to `lights`, and
/// the light of each triangle. Consecutive triangles that form a parallelogram (a quad split
/// along a diagonal, as OBJ, PLY and Mitsuba's rectangles give them) share one parallelogram
/// light.
fn mesh_lights(
    tris: &[Triangle],
    e: crate::Color,
    lights: &mut Vec<AreaLight>,
) -> impl Iterator<Item = u32> {
    let mut ids = Vec::with_capacity(tris.len());
    let mut k = 0;
    while k < tris.len() {
        let pair = tris
            .get(k + 1)
            .and_then(|t2| AreaLight::parallelogram(&tris[k], t2, e));
        let id = lights.len() as u32;
        match pair {
            Some(l) => {
                lights.push(l);
                ids.extend([id, id]);
                k += 2;
            }
            None => {
                lights.push(AreaLight::new(LightShape::Triangle(tris[k]), e));
                ids.push(id);
                k += 1;
            }
        }
    }
    ids.into_iter()
}

/// The brute-force set of a small scene's primitives `tris` (in BVH order), if it is small
/// enough and the CPU has AVX ([`crate::accel::flat`]).
#[cfg(target_arch = "x86_64")]
fn flat(
    tris: &[[u32; 3]],
    positions: &[glam::Vec3],
    spheres: &[Sphere],
) -> Option<Box<crate::accel::flat::Flat>> {
    use crate::accel::flat::{FLAT_MAX_SPHERES, FLAT_MAX_TRIANGLES};
    if tris.len() > FLAT_MAX_TRIANGLES + FLAT_MAX_SPHERES {
        return None;
    }
    flat_with(tris, positions, spheres, None)
}

/// The flat set of `tris` with `kernel` (whatever the size, up to the set's capacity of
/// [`crate::accel::flat::FLAT_MAX_SLOTS`] triangles; None beyond it), or the one its size
/// and the CPU choose.
#[cfg(target_arch = "x86_64")]
fn flat_with(
    tris: &[[u32; 3]],
    positions: &[glam::Vec3],
    spheres: &[Sphere],
    kernel: Option<crate::accel::flat::Kernel>,
) -> Option<Box<crate::accel::flat::Flat>> {
    use crate::accel::flat::Flat;
    let vertex = |i: u32| Vec3A::from(positions[i as usize]);
    let (balls, triangles): (Vec<_>, Vec<_>) =
        (0..tris.len() as u32).partition(|&i| tris[i as usize][0] == SPHERE);
    let balls: Vec<(u32, Sphere)> = balls
        .into_iter()
        .map(|i| (i, spheres[tris[i as usize][1] as usize]))
        .collect();
    let triangles: Vec<(u32, Triangle)> = triangles
        .into_iter()
        .map(|i| {
            let [a, b, c] = tris[i as usize];
            (i, Triangle::new(vertex(a), vertex(b), vertex(c)))
        })
        .collect();
    if triangles.len() > crate::accel::flat::FLAT_MAX_SLOTS {
        return None;
    }
    match kernel {
        Some(k) => Flat::with_kernel(&triangles, &balls, k),
        None => Flat::new(&triangles, &balls),
    }
    .map(Box::new)
}

/// `v` in the BVH's `order` (item i is `v[order[i]]`).
fn permuted<T: Copy + Send + Sync>(v: Vec<T>, order: &[u32]) -> Vec<T> {
    let mut out = huge_pages::with_capacity(order.len());
    order
        .par_iter()
        .with_min_len(1 << 12)
        .map(|&i| v[i as usize])
        .collect_into_vec(&mut out);
    out
}
