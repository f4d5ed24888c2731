//! Packets of rays from one origin (`Scene::intersect_packet`, a pinhole camera's rays)
//! find the same closest hits as single rays (`Scene::intersect`), bit for bit, with one,
//! eight and sixteen lanes a box test: on every feature scene (brute force and BVH), the
//! rooms, and the Cornell box with the Stanford bunny and two spheres; coherent packets (a
//! pixel's samples, a row of pixels), incoherent ones (directions over the sphere, along
//! axes) and partial ones.

use glam::{Vec2, Vec3A};
use mcrt::accel::{RayPacket, SingleRays, PACKET};
use mcrt::scene::{GeometryDesc, Scene, SceneDesc, ShapeDesc};
use std::path::Path;

/// A scene file of the repository (`$file`, where a scene asks for one: an environment
/// map).
fn file(rel: &str) -> SceneDesc {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    let opts = mcrt::LoadOptions {
        defines: vec![("file".into(), "sky.exr".into())],
        ..Default::default()
    };
    mcrt::load_scene_with(&path, &opts).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// A number in [0, 1) from `k` (SplitMix64's finaliser).
fn unit(k: u64) -> f32 {
    let mut z = k.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// Packets from the scene's camera position: each pixel's sixteen samples (coherent),
/// rows of sixteen pixels, and sixteen directions over the sphere (any signs, some
/// along an axis), with every lane active and with every other one. (A scene without a
/// camera is seen from its centre, its "pixels" spread over the sphere.)
fn packets(scene: &Scene) -> Vec<(RayPacket, u32)> {
    const RES: u32 = 12;
    let sphere = |s: f32, t: f32| {
        let (z, phi) = (1.0 - 2.0 * s, std::f32::consts::TAU * t);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    };
    type Pixel = Box<dyn Fn(u32, u32, Vec2) -> Vec3A>;
    let (o, pixel): (Vec3A, Pixel) = match scene.camera(None) {
        Some(cam) => {
            let cam = cam.build(RES, RES);
            let o = cam.generate_ray(0, 0, Vec2::splat(0.5)).o;
            (o, Box::new(move |x, y, u| cam.generate_ray(x, y, u).d))
        }
        None => {
            let b = scene.bounds().expect("a scene with something in it");
            let at = |x: u32, u: f32| (x as f32 + u) / RES as f32;
            (
                (b.min + b.max) * 0.5,
                Box::new(move |x, y, u| sphere(at(x, u.x), at(y, u.y))),
            )
        }
    };
    let packet = |d: &dyn Fn(usize) -> Vec3A| {
        let mut pk = RayPacket {
            o,
            d: [[0.0; PACKET]; 3],
            t_max: [f32::INFINITY; PACKET],
        };
        for l in 0..PACKET {
            let v = d(l);
            (pk.d[0][l], pk.d[1][l], pk.d[2][l]) = (v.x, v.y, v.z);
        }
        pk
    };
    let mut out = Vec::new();
    for y in 0..RES {
        for x in 0..RES {
            let k = u64::from(y * RES + x) << 8;
            let u = |l: usize| Vec2::new(unit(k + 2 * l as u64), unit(k + 2 * l as u64 + 1));
            out.push(packet(&|l| pixel(x, y, u(l))));
        }
        out.push(packet(&|l| {
            let x = (l as u32 * RES) / PACKET as u32;
            pixel(x, y, Vec2::splat(0.5))
        }));
        out.push(packet(&|l| {
            let k = (u64::from(y) << 16) + 2 * l as u64;
            match l {
                0 => Vec3A::X,
                1 => Vec3A::NEG_Z,
                _ => sphere(unit(k), unit(k + 1)),
            }
        }));
    }
    out.into_iter()
        .flat_map(|pk| [(pk, u32::from(u16::MAX)), (pk, 0x5555)])
        .collect()
}

/// Checks every packet's answers, with each lane count, against `Scene::intersect`'s.
fn check(scene: &Scene, what: &str) {
    if scene.bounds().is_none() {
        return; // (a file of BSDFs that others include: nothing to hit)
    }
    let packets = packets(scene);
    for lanes in [1, 8, 16] {
        for (pk, active) in &packets {
            let mut out = [None; PACKET];
            scene.intersect_packet_with(pk, *active, lanes, &mut out);
            for (l, got) in out.iter().enumerate() {
                let want = (active >> l & 1 != 0)
                    .then(|| scene.intersect(&pk.ray(l)))
                    .flatten();
                assert_eq!(
                    format!("{got:?}"),
                    format!("{want:?}"),
                    "{what}, {lanes} lanes, lane {l} of {pk:?}"
                );
            }
        }
    }
}

#[test]
fn packets_hit_what_single_rays_hit() {
    let mut files: Vec<String> = std::fs::read_dir(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features"),
    )
    .expect("the feature scenes")
    .map(|e| e.expect("an entry").path())
    .filter(|p| p.extension().is_some_and(|e| e == "xml"))
    .map(|p| {
        format!(
            "tests/data/mitsuba/features/{}",
            p.file_name().unwrap().to_string_lossy()
        )
    })
    .collect();
    files.sort();
    files.push("tests/data/mitsuba/cornell-box.xml".into());
    files.push("tests/data/mitsuba/hexroom/hexroom.xml".into());
    for f in &files {
        for rays in [SingleRays::Auto, SingleRays::Bvh] {
            check(&Scene::build_with(file(f), rays), &format!("{f}, {rays:?}"));
        }
    }
}

/// The Cornell box with the Stanford bunny (3 674 triangles) in it, and two spheres.
#[test]
fn packets_hit_a_mesh_as_single_rays_do() {
    let mut desc = file("tests/data/mitsuba/cornell-box.xml");
    let bunny = mcrt::scene::obj::load_obj(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data/bunny.obj"),
    )
    .expect("the bunny");
    let (lo, hi) = bunny.positions.iter().fold(
        (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let scale = 0.6 / (hi - lo).max_element();
    let mut mesh = bunny;
    for p in &mut mesh.positions {
        *p = (*p - (lo + hi) * 0.5) * scale + glam::Vec3::new(0.0, 0.3, 0.0);
    }
    let shape = |geometry| ShapeDesc {
        geometry,
        material: 0,
        emission: None,
    };
    desc.shapes.push(shape(GeometryDesc::Mesh(mesh)));
    for (c, r) in [
        (glam::Vec3::new(0.5, 0.2, 0.3), 0.2),
        (glam::Vec3::new(-0.5, 0.8, 0.0), 0.1),
    ] {
        desc.shapes.push(shape(GeometryDesc::Sphere {
            center: c,
            radius: r,
        }));
    }
    check(&Scene::build(desc), "bunny box");
}
