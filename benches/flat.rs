//! Brute force against the BVH for single rays in small scenes (`mcrt::accel::flat`): the
//! time of a closest hit and of an occlusion test, for the example scenes and for rooms of
//! 12 to 64 triangles, some with spheres.
//!
//!     cargo bench --bench flat
//!
//! A closed box of 12 triangles, with random triangles inside it for the rest of the count,
//! and random rays from points inside it in random directions (each occlusion test ends
//! halfway to the nearest hit, or at a random distance). The BVH, and brute force with each
//! kernel the CPU runs, trace the same rays one after the other, five rounds alternating;
//! the table gives the fastest round of each. (x86-64 only.)

use glam::{Vec2, Vec3, Vec3A};
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::geometry::Ray;
use mcrt::material::{Bsdf, Lambert, Material};
use mcrt::sampler::Pcg32;
use mcrt::scene::desc::SceneDesc;
use mcrt::scene::{GeometryDesc, Scene, ShapeDesc};
use std::hint::black_box;
use std::time::Instant;

/// The box [−1, 1]³ (12 triangles) and `n − 12` random triangles of about a fifth of its
/// width inside it.
fn room(n: usize, r: &mut Pcg32) -> SceneDesc {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let corner = |i: u32| {
        Vec3::new(
            [-1.0, 1.0][(i & 1) as usize],
            [-1.0, 1.0][(i >> 1 & 1) as usize],
            [-1.0, 1.0][(i >> 2) as usize],
        )
    };
    positions.extend((0..8).map(corner));
    for f in [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ] {
        indices.push([f[0], f[1], f[2]]);
        indices.push([f[0], f[2], f[3]]);
    }
    let mut p = || Vec3::new(r.next_1d(), r.next_1d(), r.next_1d()) * 1.6 - 0.8;
    for _ in 12..n {
        let c = p();
        let k = positions.len() as u32;
        for _ in 0..3 {
            let q = p();
            positions.push(c + (q - c) * 0.25);
        }
        indices.push([k, k + 1, k + 2]);
    }
    let mut d = SceneDesc::default();
    d.materials.push(Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Vec3::splat(0.5),
        }),
        true,
    ));
    d.shapes.push(ShapeDesc {
        geometry: GeometryDesc::Mesh(TriangleMesh {
            tangents: None,
            positions,
            normals: None,
            uvs: None,
            indices,
        }),
        material: 0,
        emission: None,
    });
    d
}

fn main() {
    #[cfg(target_arch = "x86_64")]
    run();
}

/// `n` rays from random points inside `[lo, hi]` in random directions, each with the end of
/// its occlusion test (half of them blocked).
fn rays_inside(s: &Scene, lo: Vec3A, hi: Vec3A, n: usize, r: &mut Pcg32) -> Vec<(Ray, f32)> {
    (0..n)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3A::new(r.next_1d(), r.next_1d(), r.next_1d());
            let ray = Ray::new(o, sphere_dir(r));
            shadow_end(s, ray, r)
        })
        .collect()
}

/// `n` rays from points on the surfaces (where random rays from `o` hit), into the
/// hemisphere they were reached from: the rays of a path tracer's bounces.
fn rays_bouncing(s: &Scene, o: Vec3A, n: usize, r: &mut Pcg32) -> Vec<(Ray, f32)> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let ray = Ray::new(o, sphere_dir(r));
        let Some(h) = s.intersect(&ray) else { continue };
        let ng = if h.ng.dot(ray.d) < 0.0 { h.ng } else { -h.ng };
        let d = sphere_dir(r);
        let d = if d.dot(ng) < 0.0 { -d } else { d };
        out.push(shadow_end(s, Ray::new(h.p + ng * 1e-3, d), r));
    }
    out
}

fn sphere_dir(r: &mut Pcg32) -> Vec3A {
    mcrt::material::sampling::square_to_uniform_sphere(Vec2::new(r.next_1d(), r.next_1d()))
}

/// The ray with the end of its occlusion test: half of them blocked (halfway to the nearest
/// hit), half not (past it, or at 10 where nothing is hit).
fn shadow_end(s: &Scene, ray: Ray, r: &mut Pcg32) -> (Ray, f32) {
    let t = s.intersect(&ray).map_or(10.0, |h| h.t);
    (ray, t * if r.next_1d() < 0.5 { 0.5 } else { 1.5 })
}

/// Nanoseconds a closest hit and an occlusion test take, for the BVH and brute force with
/// each kernel the CPU runs (the fastest of five rounds, alternating).
#[cfg(target_arch = "x86_64")]
fn row(label: &str, desc: &SceneDesc, mut rays: impl FnMut(&Scene) -> Vec<(Ray, f32)>) {
    use mcrt::accel::flat::Kernel;
    use mcrt::accel::SingleRays;
    let bvh = Scene::build_with(desc.clone(), SingleRays::Bvh);
    let kernels: Vec<(Kernel, Scene)> = [Kernel::Avx, Kernel::Avx512]
        .into_iter()
        .filter(|k| k.available())
        .map(|k| (k, Scene::build_with(desc.clone(), SingleRays::Flat(k))))
        .collect();
    let rays = rays(&bvh);
    let time = |s: &Scene| {
        let t0 = Instant::now();
        let mut acc = 0.0f32;
        for (ray, _) in &rays {
            acc += s.intersect(ray).map_or(0.0, |h| h.t);
        }
        let closest = t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        let mut blocked = 0u32;
        for (ray, t) in &rays {
            blocked += s.occluded(ray, *t) as u32;
        }
        black_box((acc, blocked));
        let per = |s: f64| s * 1e9 / rays.len() as f64;
        (per(closest), per(t0.elapsed().as_secs_f64()))
    };
    let mut best = vec![(f64::MAX, f64::MAX); 1 + kernels.len()];
    for _ in 0..5 {
        for (i, s) in std::iter::once(&bvh)
            .chain(kernels.iter().map(|(_, s)| s))
            .enumerate()
        {
            let (c, o) = time(s);
            best[i] = (best[i].0.min(c), best[i].1.min(o));
        }
    }
    let mut line = format!("| {label} | {:.1} | {:.1} |", best[0].0, best[0].1);
    for k in [Kernel::Avx, Kernel::Avx512] {
        match kernels.iter().position(|(q, _)| *q == k) {
            Some(j) => line += &format!(" {:.1} | {:.1} |", best[j + 1].0, best[j + 1].1),
            None => line += " – | – |",
        }
    }
    println!("{line}");
}

#[cfg(target_arch = "x86_64")]
fn run() {
    let mut r = Pcg32::new(11, 3);
    println!("| scene | BVH closest (ns) | BVH occluded (ns) | AVX closest | AVX occluded | AVX-512 closest | AVX-512 occluded |");
    println!("|---|---|---|---|---|---|---|");
    const RAYS: usize = 1 << 16;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, file) in [
        ("Cornell box", "scenes/cornell-box.toml"),
        ("TNCG15 room", "scenes/tncg15.toml"),
    ] {
        let desc = mcrt::load_scene(&root.join(file)).expect(file);
        let s = Scene::build(desc.clone());
        let b = s.bvh.bounds().expect("a scene with geometry");
        let n = s.prim_count();
        let mut r2 = Pcg32::new(5, 9);
        row(&format!("{name} ({n} primitives), bounces"), &desc, |s| {
            rays_bouncing(s, b.centroid(), RAYS, &mut r2)
        });
    }
    for n in [12, 16, 24, 32, 40, 48, 64] {
        let desc = room(n, &mut r);
        let mut r2 = Pcg32::new(n as u64, 1);
        row(
            &format!("box and {} random triangles, rays from inside", n - 12),
            &desc,
            |s| rays_inside(s, Vec3A::splat(-0.9), Vec3A::splat(0.9), RAYS, &mut r2),
        );
    }
    // Spheres: each is tested for every ray by brute force.
    for k in [1, 2, 4] {
        let mut desc = room(32, &mut r);
        for _ in 0..k {
            let c = Vec3::new(r.next_1d(), r.next_1d(), r.next_1d()) * 1.2 - 0.6;
            desc.shapes.push(ShapeDesc {
                geometry: GeometryDesc::Sphere {
                    center: c,
                    radius: 0.1 + 0.2 * r.next_1d(),
                },
                material: 0,
                emission: None,
            });
        }
        let mut r2 = Pcg32::new(100 + k as u64, 1);
        row(
            &format!("box, 20 random triangles and {k} spheres, rays from inside"),
            &desc,
            |s| rays_inside(s, Vec3A::splat(-0.9), Vec3A::splat(0.9), RAYS, &mut r2),
        );
    }
}
