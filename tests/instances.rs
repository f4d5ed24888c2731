//! Instancing (shape groups and instances, a two-level BVH): an instanced mesh is hit where
//! the same mesh flattened under the same transform is, with the same distance, normals,
//! texture coordinates and material; rays leaving an instanced surface do not hit it again;
//! shadow packets agree with single rays; a group's geometry is stored once.

use glam::{Affine3A, Mat4, Quat, Vec2, Vec3, Vec3A};
use mcrt::accel::{RayPacket, PACKET};
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::geometry::Ray;
use mcrt::material::{Bsdf, Lambert, Material};
use mcrt::sampler::Sampler;
use mcrt::scene::desc::{GeometryDesc, GroupDesc, InstanceDesc, SceneDesc, ShapeDesc};
use mcrt::scene::{Interaction, Scene};
use mcrt::texture::Texture;
use mcrt::Color;

struct Rng(Sampler);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(Sampler::from_state(seed, 0x1257 ^ seed))
    }
    fn f(&mut self) -> f32 {
        self.0.next_1d()
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    fn dir(&mut self) -> Vec3A {
        let z = 1.0 - 2.0 * self.f();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.f();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// A textured material (so that hits carry the mesh's texture coordinates) and a plain one.
fn materials() -> Vec<Material> {
    let mut textured = Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Color::splat(0.5),
        }),
        false,
    );
    textured.slots = vec![mcrt::material::Binding {
        texture: 0,
        slot: mcrt::material::textured::slots::MAIN_COLOR,
    }]
    .into();
    let plain = Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Color::splat(0.2),
        }),
        true,
    );
    vec![plain, textured]
}

/// A closed, convex, bumpy-free UV sphere of `2 · rings · segments` triangles (poles
/// included) with smooth normals and texture coordinates: a mesh with every attribute.
fn uv_sphere(rings: u32, segments: u32) -> TriangleMesh {
    let (mut positions, mut normals, mut uvs, mut indices) = (vec![], vec![], vec![], vec![]);
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            // (Exact poles: every pole vertex the same point.)
            let (sin, cos) = match r {
                0 => (0.0, 1.0),
                _ if r == rings => (0.0, -1.0),
                _ => theta.sin_cos(),
            };
            let n = Vec3::new(sin * phi.cos(), cos, sin * phi.sin());
            positions.push(n);
            normals.push(n);
            uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            // Outward winding; the poles' degenerate triangles are dropped by the build.
            indices.push([a, a + 1, b]);
            indices.push([a + 1, b + 1, b]);
        }
    }
    TriangleMesh {
        tangents: None,
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
    }
}

fn shape(mesh: TriangleMesh, material: u32) -> ShapeDesc {
    ShapeDesc {
        geometry: GeometryDesc::Mesh(mesh),
        material,
        emission: None,
    }
}

/// A group of `shapes` placed by each of `to_world`.
fn instanced(shapes: Vec<ShapeDesc>, to_world: &[Affine3A]) -> Scene {
    Scene::build(SceneDesc {
        materials: materials(),
        textures: vec![Texture::default_checkerboard()],
        groups: vec![GroupDesc {
            name: "g".into(),
            shapes,
        }],
        instances: to_world
            .iter()
            .map(|&m| InstanceDesc {
                group: 0,
                to_world: m,
            })
            .collect(),
        ..Default::default()
    })
}

/// The same shapes flattened: each mesh transformed as the loaders transform one.
fn flattened(shapes: Vec<ShapeDesc>, to_world: &[Affine3A]) -> Scene {
    let mut out = Vec::new();
    for m in to_world {
        for s in &shapes {
            let mut s = s.clone();
            if let GeometryDesc::Mesh(mesh) = &mut s.geometry {
                mesh.transform(&Mat4::from(*m));
            }
            out.push(s);
        }
    }
    Scene::build(SceneDesc {
        materials: materials(),
        textures: vec![Texture::default_checkerboard()],
        shapes: out,
        ..Default::default()
    })
}

/// Rotation, non-uniform scale (or uniform) and translation far from the origin.
fn placement(scale: Vec3, at: Vec3) -> Affine3A {
    Affine3A::from_scale_rotation_translation(
        scale,
        Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 0.9),
        at,
    )
}

/// Rays from around `center` (within `spread`) at points near it.
fn rays(rng: &mut Rng, center: Vec3A, spread: f32, n: usize) -> Vec<Ray> {
    (0..n)
        .map(|_| {
            let o = center + rng.dir() * (3.0 * spread);
            let target = center + rng.dir() * (spread * rng.f());
            Ray::new(o, (target - o) * rng.range(0.2, 3.0))
        })
        .collect()
}

/// How far apart two hits `a` and `b` of `ray` on the same surface may lie: a few times
/// their error bounds and the rounding of coordinates of magnitude `scale`, more along a
/// grazing ray (where a small error across the surface is a large one along the ray).
fn tolerance(ray: &Ray, a: &Interaction, b: &Interaction, scale: f32) -> f32 {
    let cos = ray.d.normalize().dot(b.ng).abs().max(0.05);
    (4.0 * (a.p_err + b.p_err).length() + 16.0 * f32::EPSILON * scale) / cos
}

/// `a` and `b`, hits of `ray`, agree: same distance and point ([`tolerance`]), same
/// geometric normal, shading normal (`ns_tol`), texture coordinates and material.
fn same_hit(
    ray: &Ray,
    a: &Interaction,
    b: &Interaction,
    scale: f32,
    ns_tol: f32,
) -> Result<(), String> {
    let tol = tolerance(ray, a, b, scale);
    let ok = (a.t - b.t).abs() * ray.d.length() <= tol
        && (a.p - b.p).length() <= tol
        && a.ng.dot(b.ng) > 1.0 - 1e-5
        && a.ns.dot(b.ns) > 1.0 - ns_tol
        && (a.uv - b.uv).abs().max_element() < 1e-4
        && a.material == b.material;
    if ok {
        Ok(())
    } else {
        Err(format!("instanced {a:?}\nflattened {b:?}"))
    }
}

/// Compares hits of many rays on both scenes; at most `edge_share` of the rays (those
/// through an edge, decided by rounding) may hit one and miss the other.
fn compare(inst: &Scene, flat: &Scene, rays: &[Ray], scale: f32, ns_tol: f32) {
    let (mut hits, mut differ) = (0, 0);
    for ray in rays {
        match (inst.intersect(ray), flat.intersect(ray)) {
            (Some(a), Some(b)) => {
                hits += 1;
                if let Err(e) = same_hit(ray, &a, &b, scale, ns_tol) {
                    // A ray through a shared edge may hit either triangle: the same point
                    // up to rounding, another normal; count it, not fail.
                    if (a.p - b.p).length() > tolerance(ray, &a, &b, scale) {
                        panic!("{e}");
                    }
                    if differ < 5 {
                        eprintln!("differ: {e}");
                    }
                    differ += 1;
                }
            }
            (None, None) => {}
            (a, b) => {
                if differ < 5 {
                    eprintln!("one hit: {a:?}\n{b:?}");
                }
                differ += 1
            }
        }
    }
    assert!(
        hits > rays.len() / 4,
        "only {hits} of {} rays hit",
        rays.len()
    );
    assert!(
        differ * 1000 <= rays.len(),
        "{differ} of {} rays disagree",
        rays.len()
    );
}

#[test]
fn instanced_mesh_hits_as_the_flattened_mesh_under_uniform_scale() {
    let m = [placement(Vec3::splat(2.5), Vec3::new(300.0, -40.0, 75.0))];
    let shapes = vec![shape(uv_sphere(24, 48), 1)];
    let (inst, flat) = (instanced(shapes.clone(), &m), flattened(shapes, &m));
    let mut rng = Rng::new(1);
    let rays = rays(&mut rng, Vec3A::new(300.0, -40.0, 75.0), 2.5, 20_000);
    compare(&inst, &flat, &rays, 300.0, 1e-4);
}

/// Under a non-uniform scale the shading normals differ slightly (the flattened mesh
/// normalises its vertex normals after the transform, the instance after interpolation);
/// everything else agrees. A mirroring instance keeps the file's orientation as a
/// flattened mesh does.
#[test]
fn instanced_mesh_hits_as_the_flattened_mesh_under_non_uniform_and_mirroring_scale() {
    for (k, scale) in [Vec3::new(0.5, 3.0, 1.5), Vec3::new(-1.0, 0.7, 2.0)]
        .into_iter()
        .enumerate()
    {
        let m = [placement(scale, Vec3::new(-12.0, 5.0, 9.0))];
        let shapes = vec![shape(uv_sphere(16, 32), 1), shape(uv_sphere(6, 6), 0)];
        let (inst, flat) = (instanced(shapes.clone(), &m), flattened(shapes, &m));
        let mut rng = Rng::new(2 + k as u64);
        let rays = rays(&mut rng, Vec3A::new(-12.0, 5.0, 9.0), 3.0, 20_000);
        compare(&inst, &flat, &rays, 12.0, 0.02);
    }
}

/// Many instances, overlapping: the nearest of all is found, as in the flattened scene, and
/// shadow rays (single and in packets) agree with it.
#[test]
fn many_overlapping_instances_agree_with_the_flattened_scene() {
    let mut rng = Rng::new(7);
    let m: Vec<Affine3A> = (0..60)
        .map(|_| {
            let s = rng.range(0.3, 1.2);
            Affine3A::from_scale_rotation_translation(
                Vec3::new(s, s * rng.range(0.5, 2.0), s),
                Quat::from_axis_angle(Vec3::from(rng.dir()), rng.range(0.0, 3.0)),
                Vec3::from(rng.dir() * rng.range(0.0, 4.0)),
            )
        })
        .collect();
    let shapes = vec![shape(uv_sphere(8, 12), 1)];
    let (inst, flat) = (instanced(shapes.clone(), &m), flattened(shapes, &m));
    let rays = rays(&mut rng, Vec3A::ZERO, 4.0, 10_000);
    compare(&inst, &flat, &rays, 4.0, 0.05);
    // Shadow rays to points along the ray: the instanced scene's single rays against the
    // flattened scene's, and packets against single rays.
    let mut differ = 0;
    for chunk in rays.chunks(PACKET) {
        let o = chunk[0].o;
        let mut pk = RayPacket {
            o,
            d: [[0.0; PACKET]; 3],
            t_max: [0.0; PACKET],
        };
        for (l, r) in chunk.iter().enumerate() {
            for a in 0..3 {
                pk.d[a][l] = r.d[a];
            }
            pk.t_max[l] = rng.range(0.0, 2.0);
        }
        let active = if chunk.len() == PACKET {
            u32::MAX >> (32 - PACKET)
        } else {
            (1 << chunk.len()) - 1
        };
        let single: u32 = (0..chunk.len())
            .map(|l| (inst.occluded(&pk.ray(l), pk.t_max[l]) as u32) << l)
            .sum();
        let flat_single: u32 = (0..chunk.len())
            .map(|l| (flat.occluded(&pk.ray(l), pk.t_max[l]) as u32) << l)
            .sum();
        for lanes in [1, 8, 16] {
            assert_eq!(inst.occluded_packet_with(&pk, active, lanes), single);
        }
        differ += (single ^ flat_single).count_ones();
    }
    assert!(
        differ <= 10,
        "{differ} shadow rays disagree with the flattened scene"
    );
}

/// Rays leaving an instanced convex surface (outward, from hits under a large translation
/// and a strong non-uniform scale) never hit it again, nor are shadow rays to points
/// outside blocked by it.
#[test]
fn rays_leaving_an_instanced_surface_do_not_hit_it_again() {
    for (k, (scale, at)) in [
        (Vec3::new(40.0, 0.05, 7.0), Vec3::new(1.0e4, -3.0e3, 2.0e4)),
        (Vec3::splat(1.0e-3), Vec3::new(0.5, 0.25, -0.75)),
        (Vec3::new(-3.0, 3.0, 3.0), Vec3::new(-700.0, 100.0, 0.0)),
    ]
    .into_iter()
    .enumerate()
    {
        let m = [placement(scale, at)];
        let scene = instanced(vec![shape(uv_sphere(20, 40), 0)], &m);
        let mut rng = Rng::new(100 + k as u64);
        let size = scale.abs().max_element();
        let (mut tested, mut again) = (0, 0);
        for ray in rays(&mut rng, Vec3A::from(at), size, 5_000) {
            let Some(si) = scene.intersect(&ray) else {
                continue;
            };
            // A direction on the outside of the closed convex mesh (the side its geometric
            // normal faces).
            let mut d = rng.dir();
            if d.dot(si.ng) < 0.0 {
                d = -d;
            }
            tested += 1;
            let leaving = si.spawn_ray(d);
            if scene.intersect(&leaving).is_some() {
                again += 1;
            }
            let far = si.p + d * (10.0 * size);
            let (shadow, t_max) = si.spawn_ray_to(far, Vec3A::ZERO, d);
            if scene.occluded(&shadow, t_max) {
                again += 1;
            }
        }
        assert!(tested > 1000, "only {tested} hits");
        assert_eq!(
            again, 0,
            "{again} of {tested} rays hit the surface they left ({k})"
        );
    }
}

/// Each group is stored once: n instances of a mesh take less memory than two flattened
/// copies of it (the issue's proof at a size CI runs in a second; the ignored test in
/// `instancing_memory` measures 10,000 instances of 100,000 triangles and the process's
/// peak memory).
#[test]
fn a_thousand_instances_take_less_memory_than_two_flattened_copies() {
    let mesh = uv_sphere(50, 100); // 10,000 triangles (9,900 after the poles' degenerate ones)
    let mut rng = Rng::new(9);
    let m: Vec<Affine3A> = (0..1000)
        .map(|_| {
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(rng.range(0.5, 1.0)),
                Quat::from_axis_angle(Vec3::from(rng.dir()), rng.range(0.0, 3.0)),
                Vec3::from(rng.dir() * rng.range(0.0, 100.0)),
            )
        })
        .collect();
    let inst = instanced(vec![shape(mesh.clone(), 0)], &m);
    let two = flattened(vec![shape(mesh, 0)], &m[..2]);
    let (bytes, two_bytes) = (inst.memory_bytes(), two.memory_bytes());
    eprintln!("1,000 instances: {bytes} bytes; two flattened copies: {two_bytes} bytes");
    assert!(bytes < two_bytes, "{bytes} >= {two_bytes}");
    assert_eq!(inst.prim_count() * 2, two.prim_count());
    let line = inst.instancing_summary().unwrap();
    assert!(line.contains("1000 instances"), "{line}");
}

/// The TOML format's groups and instances describe what the same XML does: the shapes of a
/// group stored once, instances with the same transforms (scale, then rotate, then
/// translate; or a matrix).
#[test]
fn toml_groups_and_instances_match_the_xml_ones() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features");
    let xml = mcrt::scene::xml::parse_xml(
        &dir.join("inline.xml"),
        r#"<scene version="3.0.0">
            <shape type="shapegroup" id="g">
                <shape type="sphere"><float name="radius" value="0.5"/></shape>
                <shape type="ply"><string name="filename" value="pyramid.ply"/></shape>
            </shape>
            <shape type="instance"><ref id="g"/>
                <transform name="to_world">
                    <scale x="2" y="1" z="0.5"/><rotate x="1" y="1" angle="30"/><translate x="3" z="-1"/>
                </transform>
            </shape>
            <shape type="instance"><ref id="g"/>
                <transform name="to_world"><matrix value="0 -1 0 1  1 0 0 2  0 0 1 3  0 0 0 1"/></transform>
            </shape>
            <shape type="sphere"/>
        </scene>"#,
        &Default::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let toml = mcrt::scene::toml::parse_toml(
        &dir.join("inline.toml"),
        r#"
            [[shape]]
            type = "sphere"
            center = [0, 0, 0]
            radius = 0.5
            group = "g"

            [[shape]]
            type = "mesh"
            file = "pyramid.ply"
            group = "g"
            smooth = true

            [[shape]]
            type = "sphere"
            center = [0, 0, 0]
            radius = 1

            [[instance]]
            group = "g"
            scale = [2, 1, 0.5]
            rotate = [1, 1, 0, 30]
            translate = [3, 0, -1]

            [[instance]]
            group = "g"
            matrix = [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3]]
        "#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for d in [&xml, &toml] {
        assert_eq!(d.shapes.len(), 1);
        assert_eq!(d.groups.len(), 1);
        assert_eq!(d.groups[0].shapes.len(), 2);
        assert_eq!(d.instances.len(), 2);
    }
    for (a, b) in xml.instances.iter().zip(&toml.instances) {
        assert_eq!(a.group, b.group);
        assert!(
            a.to_world.abs_diff_eq(b.to_world, 1e-5),
            "{:?} {:?}",
            a.to_world,
            b.to_world
        );
    }
}
