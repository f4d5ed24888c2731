//! Criterion micro-benchmarks of the renderer's heart: BVH build, ray traversal (coherent
//! camera rays and incoherent random rays), triangle and sphere tests, BSDF sampling, and one
//! small frame.
//!
//!     cargo bench --bench micro

#[path = "common.rs"]
mod common;

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use glam::{Vec2, Vec3, Vec3A};
use mcrt::geometry::{Ray, Sphere, Triangle};
use mcrt::material::{
    Bsdf, Dielectric, Lambert, Material, RoughConductor, RoughPlastic, TransportMode,
};
use mcrt::sampler::Pcg32;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;

fn rng_dir(r: &mut Pcg32) -> Vec3A {
    mcrt::material::sampling::square_to_uniform_sphere(Vec2::new(r.next_1d(), r.next_1d()))
}

fn bvh(c: &mut Criterion) {
    let mesh = common::subdivide(&common::bunny(), 5);
    let n = mesh.indices.len() as u64;
    let desc = common::bunny_scene(mesh);
    let mut g = c.benchmark_group("bvh");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n));
    g.bench_function("build 92k triangles", |b| {
        b.iter(|| Scene::build(black_box(desc.clone())))
    });
    g.finish();

    let scene = Scene::build(desc);
    let cam = scene.camera(None).unwrap().build(256, 256);
    let mut g = c.benchmark_group("traversal");
    g.throughput(Throughput::Elements(256 * 256));
    g.bench_function("coherent camera rays", |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for y in 0..256 {
                for x in 0..256 {
                    let ray = cam.generate_ray(x, y, Vec2::splat(0.5));
                    hits += scene.intersect(&ray).is_some() as u32;
                }
            }
            hits
        })
    });
    let mut r = Pcg32::new(7, 1);
    let rays: Vec<Ray> = (0..256 * 256)
        .map(|_| {
            let o = Vec3A::new(
                r.next_1d() * 10.0 - 5.0,
                r.next_1d() * 9.7,
                r.next_1d() * 7.5 - 3.7,
            );
            Ray::new(o, rng_dir(&mut r))
        })
        .collect();
    g.bench_function("incoherent rays inside the bunny's box", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|ray| scene.intersect(ray).is_some())
                .count()
        })
    });
    g.finish();
}

fn primitives(c: &mut Criterion) {
    let tri = Triangle::new(
        Vec3A::new(-1.0, -1.0, 0.0),
        Vec3A::new(1.0, -1.0, 0.0),
        Vec3A::new(0.0, 1.0, 0.0),
    );
    let sph = Sphere {
        center: Vec3A::ZERO,
        radius: 1.0,
    };
    let mut r = Pcg32::new(3, 1);
    let rays: Vec<Ray> = (0..1024)
        .map(|_| {
            let o = Vec3A::new(r.next_1d() - 0.5, r.next_1d() - 0.5, 3.0);
            let t = Vec3A::new(r.next_1d() * 2.4 - 1.2, r.next_1d() * 2.4 - 1.2, 0.0);
            Ray::new(o, (t - o).normalize())
        })
        .collect();
    let mut g = c.benchmark_group("intersect");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("triangle", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|ray| tri.intersect(ray, f32::INFINITY).is_some())
                .count()
        })
    });
    g.bench_function("sphere", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|ray| sph.intersect(ray, f32::INFINITY).is_some())
                .count()
        })
    });
    g.finish();
}

fn bsdfs(c: &mut Criterion) {
    let white = Vec3::splat(0.8);
    let materials = [
        ("lambert", Bsdf::Lambert(Lambert { albedo: white })),
        ("dielectric", Bsdf::Dielectric(Dielectric::new(1.5))),
        (
            "roughconductor",
            Bsdf::RoughConductor(RoughConductor::new(
                mcrt::material::Microfacet::ggx(0.2, 0.2),
                Vec3::new(0.2, 0.9, 1.1),
                Vec3::new(3.9, 2.4, 2.2),
                Vec3::ONE,
            )),
        ),
        (
            "roughplastic",
            Bsdf::RoughPlastic(RoughPlastic::new(
                mcrt::material::MicrofacetType::Ggx,
                0.2,
                1.49,
                white,
                Vec3::ONE,
                false,
            )),
        ),
    ];
    let mut r = Pcg32::new(5, 1);
    let wos: Vec<Vec3A> = (0..1024)
        .map(|_| {
            let d = rng_dir(&mut r);
            Vec3A::new(d.x, d.y, d.z.abs().max(0.05)).normalize()
        })
        .collect();
    let us: Vec<(f32, Vec2)> = (0..1024)
        .map(|_| (r.next_1d(), Vec2::new(r.next_1d(), r.next_1d())))
        .collect();
    let mut g = c.benchmark_group("bsdf sample");
    g.throughput(Throughput::Elements(1024));
    for (name, bsdf) in materials {
        let m = Material::new(bsdf, false);
        g.bench_function(name, |b| {
            b.iter(|| {
                wos.iter()
                    .zip(&us)
                    .filter_map(|(wo, (u1, u2))| m.sample(*wo, *u1, *u2, TransportMode::Radiance))
                    .count()
            })
        });
    }
    g.finish();
}

fn frame(c: &mut Criterion) {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let desc = mcrt::load_scene(&p).unwrap();
    let fs = desc.settings.clone();
    let scene = Scene::build(desc);
    let s = mcrt::resolve_settings(
        &fs,
        &FileSettings {
            width: Some(64),
            height: Some(64),
            spp: Some(4),
            ..Default::default()
        },
        None,
    )
    .unwrap();
    let mut g = c.benchmark_group("frame");
    g.sample_size(20);
    g.throughput(Throughput::Elements(64 * 64 * 4));
    g.bench_function("cornell box 64x64 4spp", |b| {
        b.iter(|| mcrt::render::render(&scene, &s, &|_| {}).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bvh, primitives, bsdfs, frame);
criterion_main!(benches);
