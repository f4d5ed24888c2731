//! `Scene::intersect_many` (several rays' traversals interleaved) gives for every ray the same
//! bits as `Scene::intersect`, in every field of the interaction, and `Scene::occluded_many`
//! the answers of `Scene::occluded`: on a mesh with vertex
//! normals and texture coordinates, spheres, a masked scene, instanced scenes, an empty scene,
//! a small scene traced by brute force, and a grid of duplicated triangles where rays through
//! shared edges and vertices meet equally near hits; with random rays, rays that miss,
//! axis-parallel rays and the rays of paths; in batches of every length around the numbers
//! of rays in flight.

use glam::{Affine3A, Quat, Vec2, Vec3, Vec3A};
use mcrt::accel::SingleRays;
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::geometry::Ray;
use mcrt::material::{Bsdf, Lambert, Material};
use mcrt::sampler::Sampler;
use mcrt::scene::desc::{GeometryDesc, GroupDesc, InstanceDesc, SceneDesc, ShapeDesc};
use mcrt::scene::{Interaction, Scene};
use mcrt::texture::Texture;
use mcrt::Color;
use std::path::Path;

struct Rng(Sampler);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(Sampler::from_state(seed, 0x3a17 ^ seed))
    }
    fn f(&mut self) -> f32 {
        self.0.next_1d()
    }
    fn dir(&mut self) -> Vec3A {
        let z = 1.0 - 2.0 * self.f();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.f();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// A plain material and a textured one (so that hits carry the mesh's texture coordinates).
fn materials() -> Vec<Material> {
    let lambert = |a: f32| {
        Bsdf::Lambert(Lambert {
            albedo: Color::splat(a),
        })
    };
    let mut textured = Material::new(lambert(0.5), false);
    textured.slots = vec![mcrt::material::Binding {
        texture: 0,
        slot: mcrt::material::textured::slots::MAIN_COLOR,
    }]
    .into();
    vec![Material::new(lambert(0.2), true), textured]
}

/// The Stanford bunny with smooth vertex normals and texture coordinates.
fn bunny() -> TriangleMesh {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data/bunny.obj");
    let mut m = mcrt::scene::obj::load_obj(&p).expect("benches/data/bunny.obj");
    let mut normals = vec![Vec3::ZERO; m.positions.len()];
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    m.uvs = Some(
        m.positions
            .iter()
            .map(|p| Vec2::new(p.x, p.y) * 0.37)
            .collect(),
    );
    m.normals = Some(normals.iter().map(|n| n.normalize_or_zero()).collect());
    m
}

fn shape(geometry: GeometryDesc, material: u32) -> ShapeDesc {
    ShapeDesc {
        geometry,
        material,
        emission: None,
    }
}

fn scene(shapes: Vec<ShapeDesc>) -> Scene {
    Scene::build(SceneDesc {
        materials: materials(),
        textures: vec![Texture::default_checkerboard()],
        shapes,
        ..Default::default()
    })
}

/// `n` spheres scattered over a 20-unit cube, every third textured.
fn spheres(rng: &mut Rng, n: usize) -> Vec<ShapeDesc> {
    (0..n)
        .map(|k| {
            let center = Vec3::from(rng.dir()) * 10.0 * rng.f();
            let radius = 0.2 + rng.f();
            shape(GeometryDesc::Sphere { center, radius }, (k % 3 == 0) as u32)
        })
        .collect()
}

/// An `n` × `n` grid of unit squares in z = 0, two triangles each, every triangle twice (a
/// second copy with its own vertices), so that every hit is as near as another primitive's.
fn twice_gridded(n: u32) -> TriangleMesh {
    let mut positions = Vec::new();
    for copy in 0..2 {
        for y in 0..=n {
            for x in 0..=n {
                let _ = copy;
                positions.push(Vec3::new(x as f32, y as f32, 0.0));
            }
        }
    }
    let v = |copy: u32, x: u32, y: u32| copy * (n + 1) * (n + 1) + y * (n + 1) + x;
    let mut indices = Vec::new();
    for y in 0..n {
        for x in 0..n {
            for copy in 0..2 {
                indices.push([v(copy, x, y), v(copy, x + 1, y), v(copy, x + 1, y + 1)]);
                indices.push([v(copy, x, y), v(copy, x + 1, y + 1), v(copy, x, y + 1)]);
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

/// `count` rays at an `n` × `n` grid of unit squares in z = 0 (`twice_gridded`) from all
/// around it: through its vertices, along its edges' lines and across its diagonals.
fn grid_rays(rng: &mut Rng, n: u32, count: usize) -> Vec<Ray> {
    (0..count)
        .map(|k| {
            let (x, y) = ((k as u32 * 7) % (n + 1), (k as u32 * 13 / 5) % (n + 1));
            let (x, y) = match k % 3 {
                0 => (x as f32, y as f32),
                1 => (x as f32 + 0.5, y as f32),
                _ => (x as f32 + 0.25, y as f32 + 0.25),
            };
            let o = Vec3A::new(x, y, 0.0) + rng.dir() * 5.0;
            Ray::new(o, Vec3A::new(x, y, 0.0) - o)
        })
        .collect()
}

/// Rays at the scene from all around its bounds (towards points inside, so most hit), rays
/// pointing away (which miss), axis-parallel rays (zero and negative-zero direction
/// components), and a path's rays: from hits, cosine-distributed about the shading normal.
fn rays(scene: &Scene, rng: &mut Rng, n: usize) -> Vec<Ray> {
    let (c, r) = match scene.bounds() {
        Some(b) => (
            (b.min + b.max) * 0.5,
            (b.max - b.min).length().max(1.0) * 0.5,
        ),
        None => (Vec3A::ZERO, 1.0),
    };
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let o = c + rng.dir() * (2.0 * r);
        let target = c + rng.dir() * (r * rng.f());
        out.push(match out.len() % 8 {
            // Away from the scene.
            0 => Ray::new(o, o - c),
            // Axis-parallel, one axis, with signed zeros in the others.
            1 => {
                let mut d = Vec3A::new(0.0, -0.0, 0.0);
                let axis = (rng.f() * 3.0) as usize % 3;
                d[axis] = if rng.f() < 0.5 { 1.0 } else { -2.0 };
                Ray::new(target - d * (3.0 * r), d)
            }
            _ => Ray::new(o, (target - o) * (0.25 + rng.f())),
        });
    }
    // Each second ray replaced by one leaving the first's hit, as a path's bounce does.
    for k in (0..n - 1).step_by(2) {
        if let Some(si) = scene.intersect(&out[k]) {
            let nrm = if si.ns.dot(out[k].d) > 0.0 {
                -si.ns
            } else {
                si.ns
            };
            let (a, b) = nrm.any_orthonormal_pair();
            let (u1, phi) = (rng.f(), std::f32::consts::TAU * rng.f());
            let s = u1.sqrt();
            let d = a * (s * phi.cos()) + b * (s * phi.sin()) + nrm * (1.0 - u1).sqrt();
            out[k + 1] = si.spawn_ray(d);
        }
    }
    out
}

/// Every field of an answer, as bits.
fn bits(h: &Option<Interaction>) -> Option<Vec<u32>> {
    h.as_ref().map(|s| {
        let mut b = Vec::new();
        for v in [s.p, s.p_err, s.ng, s.ns, s.ns_base] {
            b.extend(v.to_array().map(f32::to_bits));
        }
        b.extend([s.t, s.uv.x, s.uv.y].map(f32::to_bits));
        b.extend([s.material, s.light]);
        b
    })
}

/// Checks `intersect_many` (and each number of rays in flight) against `intersect` on
/// batches of 0, 1, K − 1, K, K + 1 and 1000 rays taken from `rays`; returns how many of
/// the rays hit something.
fn check(scene: &Scene, rays: &[Ray]) -> usize {
    let want: Vec<_> = rays.iter().map(|r| bits(&scene.intersect(r))).collect();
    type Many = fn(&Scene, &[Ray], &mut [Option<Interaction>]);
    let variants: [(usize, Many); 6] = [
        (mcrt::scene::stream::STREAM, Scene::intersect_many),
        (2, Scene::intersect_many_k::<2>),
        (4, Scene::intersect_many_k::<4>),
        (8, Scene::intersect_many_k::<8>),
        (16, Scene::intersect_many_k::<16>),
        (32, Scene::intersect_many_k::<32>),
    ];
    for (k, many) in variants {
        let mut at = 0;
        for len in [0, 1, k - 1, k, k + 1, 1000] {
            let len = len.min(rays.len());
            let from = if at + len <= rays.len() { at } else { 0 };
            let batch = &rays[from..from + len];
            let mut out = vec![None; len];
            many(scene, batch, &mut out);
            for (j, o) in out.iter().enumerate() {
                assert_eq!(
                    bits(o),
                    want[from + j],
                    "K = {k}, batch of {len}: ray {} ({:?}) differs",
                    from + j,
                    batch[j]
                );
            }
            at = from + len;
        }
    }
    check_occluded(scene, rays);
    want.iter().filter(|w| w.is_some()).count()
}

/// Checks `occluded_many` (and each number of rays in flight) against `occluded`, with
/// distances around each ray's closest hit (half, equal, just beyond, infinite, 1).
fn check_occluded(scene: &Scene, rays: &[Ray]) {
    let t_max: Vec<f32> = rays
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let t = scene.intersect(r).map_or(10.0, |s| s.t);
            [t * 0.5, t, t * 1.0001, f32::INFINITY, 1.0][k % 5]
        })
        .collect();
    let want: Vec<bool> = rays
        .iter()
        .zip(&t_max)
        .map(|(r, &t)| scene.occluded(r, t))
        .collect();
    type Many = fn(&Scene, &[Ray], &[f32], &mut [bool]);
    let variants: [(usize, Many); 4] = [
        (mcrt::scene::stream::STREAM, Scene::occluded_many),
        (2, Scene::occluded_many_k::<2>),
        (8, Scene::occluded_many_k::<8>),
        (32, Scene::occluded_many_k::<32>),
    ];
    for (k, many) in variants {
        for len in [0, 1, k - 1, k, k + 1, 1000] {
            let len = len.min(rays.len());
            let mut out = vec![false; len];
            many(scene, &rays[..len], &t_max[..len], &mut out);
            assert_eq!(out, want[..len], "occlusion, K = {k}, batch of {len}");
        }
    }
    // Both answers occur wherever a ray hits something (half of those stop short of it).
    let blocked = want.iter().filter(|&&b| b).count();
    if rays.iter().any(|r| scene.intersect(r).is_some()) {
        assert!(
            blocked > 0 && blocked < want.len(),
            "{blocked} of {} blocked",
            want.len()
        );
    }
}

/// At least a fifth and at most nineteen twentieths of `n` rays hit: both cases are tested.
fn mixed(hits: usize, n: usize) {
    assert!(
        hits * 5 >= n && hits * 20 <= n * 19,
        "{hits} hits of {n} rays"
    );
}

const N: usize = 1200;

#[test]
fn a_mesh_with_normals_and_uvs_and_spheres() {
    let mut rng = Rng::new(1);
    let mut shapes = vec![shape(GeometryDesc::Mesh(bunny()), 1)];
    shapes.extend(spheres(&mut rng, 12));
    let s = scene(shapes);
    let r = rays(&s, &mut rng, N);
    mixed(check(&s, &r), N);
}

#[test]
fn spheres_alone() {
    let mut rng = Rng::new(2);
    let s = scene(spheres(&mut rng, 300));
    let r = rays(&s, &mut rng, N);
    mixed(check(&s, &r), N);
}

#[test]
fn equally_near_hits_keep_the_lowest_primitive() {
    let n = 24;
    let s = scene(vec![shape(GeometryDesc::Mesh(twice_gridded(n)), 0)]);
    let r = grid_rays(&mut Rng::new(3), n, N);
    let hits = check(&s, &r);
    assert!(hits * 10 >= N * 9, "{hits} of {N} rays hit the grid");
}

#[test]
fn a_masked_scene() {
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data/bunny.obj");
    let xml = format!(
        "<scene version=\"3.0.0\">\
         <shape type=\"obj\"><string name=\"filename\" value=\"{}\"/>\
         <bsdf type=\"mask\"><float name=\"opacity\" value=\"0.5\"/><bsdf type=\"diffuse\"/>\
         </bsdf></shape>\
         <shape type=\"sphere\"><point name=\"center\" x=\"1\" y=\"1\" z=\"1\"/>\
         <float name=\"radius\" value=\"1.5\"/></shape>\
         <shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"8\"/>\
         <translate z=\"-3\"/></transform></shape></scene>",
        bunny.display()
    );
    let desc =
        mcrt::scene::xml::parse_xml(Path::new("mask.xml"), &xml, &Default::default()).unwrap();
    let s = Scene::build(desc);
    let mut rng = Rng::new(4);
    let r = rays(&s, &mut rng, N);
    mixed(check(&s, &r), N);
}

/// Bunnies placed by `n` instances, with or without primitives of the scene's own.
fn instanced(n: usize, own: bool) -> Scene {
    let mut rng = Rng::new(5);
    let to_world = (0..n).map(|_| {
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.5 + rng.f()),
            Quat::from_axis_angle(Vec3::from(rng.dir()), 3.0 * rng.f()),
            Vec3::from(rng.dir()) * 8.0,
        )
    });
    let instances = to_world
        .map(|to_world| InstanceDesc { group: 0, to_world })
        .collect();
    let mut shapes = Vec::new();
    if own {
        shapes.push(shape(GeometryDesc::Mesh(bunny()), 0));
        shapes.extend(spheres(&mut rng, 5));
    }
    Scene::build(SceneDesc {
        materials: materials(),
        textures: vec![Texture::default_checkerboard()],
        shapes,
        groups: vec![GroupDesc {
            name: "g".into(),
            shapes: vec![shape(GeometryDesc::Mesh(bunny()), 1)],
        }],
        instances,
        ..Default::default()
    })
}

#[test]
fn instanced_scenes() {
    for own in [true, false] {
        let s = instanced(7, own);
        let mut rng = Rng::new(6);
        let r = rays(&s, &mut rng, N);
        mixed(check(&s, &r), N);
    }
}

#[test]
fn an_empty_scene_and_rays_that_miss() {
    let s = scene(Vec::new());
    let mut rng = Rng::new(7);
    let r = rays(&s, &mut rng, N);
    assert_eq!(check(&s, &r), 0);
    let s = scene(vec![shape(GeometryDesc::Mesh(bunny()), 0)]);
    let c = s.bounds().map(|b| (b.min + b.max) * 0.5).unwrap();
    let away: Vec<Ray> = (0..N)
        .map(|_| {
            let d = rng.dir();
            Ray::new(c + d * 50.0, d)
        })
        .collect();
    assert_eq!(check(&s, &away), 0);
}

#[test]
fn small_scenes_by_brute_force_and_through_the_bvh() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/cornell-box.xml");
    let s = Scene::build(mcrt::load_scene(&p).unwrap());
    let mut rng = Rng::new(8);
    let r = rays(&s, &mut rng, N);
    let hits = check(&s, &r);
    mixed(hits, N);
    let bvh = Scene::build_with(mcrt::load_scene(&p).unwrap(), SingleRays::Bvh);
    assert!(!bvh.is_flat());
    assert_eq!(check(&bvh, &r), hits);
}

/// Brute force's sixteen rays at a time (`Flat::intersect_rays` and `occluded_rays`, which
/// `intersect_many` and `occluded_many` take where single rays go by brute force), with each
/// kernel the CPU runs: two copies of a small grid in two materials (every hit on the grid
/// as near as the other copy's, which the lower primitive must win) with spheres among
/// them, some cutting the grid; rays from all around, and rays aimed at the grid's vertices
/// and edges (whose lanes the fast test leaves to the triangles' own).
#[cfg(target_arch = "x86_64")]
#[test]
fn small_scenes_in_lanes_with_each_kernel() {
    use mcrt::accel::flat::Kernel;
    let sphere = |c: [f32; 3], radius: f32| {
        shape(
            GeometryDesc::Sphere {
                center: Vec3::from(c),
                radius,
            },
            0,
        )
    };
    let n = 3;
    // One copy of the doubled grid: its first copy's triangles.
    let grid = || {
        let mut m = twice_gridded(n);
        m.indices.retain(|t| t[0] < (n + 1) * (n + 1));
        m
    };
    let mut ran = 0;
    for kernel in [Kernel::Avx512, Kernel::Avx] {
        if !kernel.available() {
            eprintln!("{kernel:?}: not on this CPU");
            continue;
        }
        let shapes = vec![
            shape(GeometryDesc::Mesh(grid()), 0),
            shape(GeometryDesc::Mesh(grid()), 1),
            sphere([0.5, 0.5, 0.0], 0.3),
            sphere([2.0, 1.0, 0.4], 0.5),
            sphere([1.0, 2.5, -0.2], 0.4),
        ];
        let desc = SceneDesc {
            materials: materials(),
            textures: vec![Texture::default_checkerboard()],
            shapes,
            ..Default::default()
        };
        let s = Scene::build_with(desc, SingleRays::Flat(kernel));
        assert!(s.is_flat(), "{kernel:?}");
        let mut rng = Rng::new(9);
        let mut r = rays(&s, &mut rng, N / 2);
        r.extend(grid_rays(&mut rng, n, N / 2));
        mixed(check(&s, &r), N);
        ran += 1;
    }
    assert!(ran > 0 || !std::arch::is_x86_feature_detected!("avx"));
}
