//! Shared by the benchmarks: the Stanford bunny (benches/data/bunny.obj, from the npm package
//! `bunny`, public domain), subdivided to any triangle count, in a scene with a camera and
//! lights.
#![allow(dead_code)]

use glam::Vec3;
use mcrt::camera::{CameraDesc, FovAxis};
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::material::{Bsdf, Lambert, Material};
use mcrt::scene::desc::{LightDesc, SceneDesc};
use mcrt::scene::{GeometryDesc, ShapeDesc};
use std::path::Path;

pub fn bunny() -> TriangleMesh {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data/bunny.obj");
    mcrt::scene::obj::load_obj(&p).expect("benches/data/bunny.obj")
}

/// Each triangle split into k² triangles of the same plane (the shape is unchanged, so the
/// image is the same at every count).
pub fn subdivide(m: &TriangleMesh, k: u32) -> TriangleMesh {
    let mut positions = Vec::with_capacity(m.indices.len() * ((k + 1) * (k + 2) / 2) as usize);
    let mut indices = Vec::with_capacity(m.indices.len() * (k * k) as usize);
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        // Vertex (i, j) = a + (b − a)·i/k + (c − a)·j/k for i + j ≤ k, row j after row j − 1.
        let mut row_start = [0u32; 1024];
        for j in 0..=k {
            row_start[j as usize] = positions.len() as u32;
            for i in 0..=(k - j) {
                let (u, v) = (i as f32 / k as f32, j as f32 / k as f32);
                positions.push(a + (b - a) * u + (c - a) * v);
            }
        }
        let p = |i: u32, j: u32| row_start[j as usize] + i;
        for j in 0..k {
            for i in 0..(k - j) {
                indices.push([p(i, j), p(i + 1, j), p(i, j + 1)]);
                if i + 1 < k - j {
                    indices.push([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)]);
                }
            }
        }
    }
    TriangleMesh {
        tangents: None,
        positions,
        normals: None,
        uvs: None,
        indices,
    }
}

/// The bunny (10 units wide, 9.7 tall, y up), seen from the front, under a constant sky and a
/// directional sun.
pub fn bunny_scene(mesh: TriangleMesh) -> SceneDesc {
    let mut d = SceneDesc::default();
    d.materials.push(Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Vec3::splat(0.7),
        }),
        true,
    ));
    d.shapes.push(ShapeDesc {
        geometry: GeometryDesc::Mesh(mesh),
        material: 0,
        emission: None,
    });
    d.cameras.push((
        "front".into(),
        CameraDesc::Perspective {
            origin: Vec3::new(0.0, 6.0, 22.0),
            target: Vec3::new(0.0, 4.8, 0.0),
            up: Vec3::Y,
            fov: 35.0,
            fov_axis: FovAxis::X,
        },
    ));
    d.lights.push(LightDesc::Constant {
        radiance: Vec3::splat(0.5),
    });
    d.lights.push(LightDesc::Directional {
        direction: Vec3::new(-1.0, -1.0, -2.0),
        irradiance: Vec3::splat(2.0),
    });
    d
}
