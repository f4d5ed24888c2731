//! `Scene::intersect` one ray at a time against `Scene::intersect_many` with K rays in flight,
//! on the rays a path tracer traces: the camera rays of a 64×64 image at 4 samples a pixel
//! (`--res`, `--spp`; a pixel's samples consecutive, as the renderers trace them),
//! then three bounces, each ray leaving its hit in a cosine-distributed direction about the
//! shading normal (on the side it came from), in batches of the size the stream path tracer
//! hands over; and `Scene::occluded` against `Scene::occluded_many` on a shadow ray from
//! each hit. Also the camera rays as the renderers' packets of sixteen
//! (`Scene::intersect_packet`), and shadow rays from the camera rays' hits towards one small
//! region, eight in flight against sixteen consecutive ones a packet of their own origins
//! (`Scene::occluded_origins`, as the renderers trace those of paths' first vertices).
//!
//! cargo bench --bench intersect_many -- [SCENE.xml ...] [--bunny N ...] [--batch N] [--rounds N]
//!                                        [--res N] [--spp N] [--dump DIR] [--set NAME]
//!                                        [--shuffle] [--repeat N]
//!
//! (`--bunny N`: the benchmarks' bunny with each triangle split into N², 3 674·N² triangles.
//! The closest-hit sets are `camera`, `bounces` (all three) and `first` (the first bounce
//! alone); `--set NAME` times that one only. `--shuffle` traces each set in a fixed random
//! order, what the rays' coherence is worth; `--repeat N` traces each sixteen consecutive
//! rays N times over, so that all but the first run from warm caches.)
//!
//! Defaults: bench/out/scenes/gallery.xml and bench/out/scenes/bunny-box.xml (written by
//! `python3 bench/make_scenes.py`), batches of 256, 7 rounds. The variants run alternately,
//! each round in a new order, and each figure is the minimum over the rounds (the machine is
//! shared), with the spread (max/min) beside it. Every batch's answers are checked equal to
//! the one-at-a-time ones, bit for bit, before anything is timed. `--only VARIANT` traces
//! with that variant only (or `packets`, the camera packets), once (`valgrind --tool=callgrind
//! --toggle-collect='*intersect_many::time*'`). `--dump DIR` also writes each scene's rays to
//! `DIR/STEM-{camera,bounces,first,shadow}.f32` (seven little-endian `f32` a ray: origin,
//! direction, end distance; unshuffled, unrepeated), for `bench/embree_rays.py`, which times Mitsuba 3's Embree on the
//! same rays.

mod common;

use glam::{Vec2, Vec3A};
use mcrt::accel::{RayPacket, PACKET};
use mcrt::geometry::Ray;
use mcrt::scene::{Interaction, Scene};
use std::path::Path;
use std::time::Instant;

const BOUNCES: usize = 3;

/// A 64-bit hash (SplitMix64's finaliser) as a number in [0, 1).
fn unit(seed: u64) -> f32 {
    let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// The rays of each depth: the camera's, then each bounce's; and shadow rays with their
/// distances, one from each hit towards a point drawn uniformly in the scene's bounds (as
/// a light sample's, the segment's end not reached: 1 − 10⁻⁴).
fn path_rays(scene: &Scene, res: u32, spp: u32) -> (Vec<Vec<Ray>>, Vec<Ray>, Vec<f32>) {
    let cam = scene.camera(None).expect("a camera").build(res, res);
    let mut levels = vec![Vec::new()];
    let (mut shadow, mut shadow_t) = (Vec::new(), Vec::new());
    let bb = scene.bounds().expect("a scene with something in it");
    for y in 0..res {
        for x in 0..res {
            for s in 0..spp {
                let id = (((y * res + x) * spp + s) as u64) << 8;
                levels[0].push(cam.generate_ray(x, y, Vec2::new(unit(id), unit(id + 1))));
            }
        }
    }
    for depth in 0..BOUNCES {
        let mut next = Vec::new();
        for (k, ray) in levels[depth].iter().enumerate() {
            let Some(si) = scene.intersect(ray) else {
                continue;
            };
            let id = ((k as u64) << 8) + 2 + 2 * depth as u64;
            let (u1, u2) = (unit(id), unit(id + 1));
            let n = if si.ns.dot(ray.d) > 0.0 {
                -si.ns
            } else {
                si.ns
            };
            let (a, b) = n.any_orthonormal_pair();
            let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let d = a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt();
            next.push(si.spawn_ray(d));
            let u = Vec3A::new(unit(id + 100), unit(id + 101), unit(id + 102));
            shadow.push(si.spawn_ray(bb.min + (bb.max - bb.min) * u - si.p));
            shadow_t.push(1.0 - 1e-4);
        }
        levels.push(next);
    }
    (levels, shadow, shadow_t)
}

/// All fields of an answer, as bits.
fn bits(h: &Option<Interaction>) -> Option<Vec<u32>> {
    h.as_ref().map(|s| {
        let mut b = Vec::new();
        for v in [s.p, s.p_err, s.ng, s.ns, s.ns_base] {
            b.extend(v.to_array().map(f32::to_bits));
        }
        b.extend([
            s.t.to_bits(),
            s.uv.x.to_bits(),
            s.uv.y.to_bits(),
            s.material,
            s.light,
        ]);
        b
    })
}

/// Rays as seven little-endian `f32` each: origin, direction, end distance.
fn write_rays(path: &Path, rays: &[Ray], t_max: &[f32]) {
    let mut bytes = Vec::with_capacity(rays.len() * 28);
    for (r, t) in rays.iter().zip(t_max) {
        for v in r.o.to_array().into_iter().chain(r.d.to_array()).chain([*t]) {
            bytes.extend(v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// Rays that share their origin, sixteen at a time through `Scene::intersect_packet`.
fn packets(s: &Scene, rays: &[Ray], out: &mut [Option<Interaction>]) {
    for (rs, os) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
        let mut pk = RayPacket {
            o: rs[0].o,
            d: [[0.0; PACKET]; 3],
            t_max: [f32::INFINITY; PACKET],
        };
        for (l, r) in rs.iter().enumerate() {
            assert_eq!(r.o, pk.o, "packets need rays from one origin");
            (pk.d[0][l], pk.d[1][l], pk.d[2][l]) = (r.d.x, r.d.y, r.d.z);
        }
        let mut hits = [None; PACKET];
        s.intersect_packet(&pk, (1u32 << rs.len()) - 1, &mut hits);
        os.clone_from_slice(&hits[..rs.len()]);
    }
}

type Trace = fn(&Scene, &[Ray], &mut [Option<Interaction>]);

fn one_by_one(s: &Scene, rays: &[Ray], out: &mut [Option<Interaction>]) {
    for (r, o) in rays.iter().zip(out) {
        *o = s.intersect(r);
    }
}

/// The ways to trace: one by one, `K` rays in flight (compiled for plain x86-64), and
/// `auto`, what a render calls (`intersect_many`: x86-64-v3 where the CPU has it, and
/// interleaved where the scene exceeds the level-2 cache).
const VARIANTS: [(&str, Trace); 6] = [
    ("1", one_by_one),
    ("auto", |s, r, o| s.intersect_many(r, o)),
    ("4", |s, r, o| s.intersect_many_k::<4>(r, o)),
    ("8", |s, r, o| s.intersect_many_k::<8>(r, o)),
    ("16", |s, r, o| s.intersect_many_k::<16>(r, o)),
    ("32", |s, r, o| s.intersect_many_k::<32>(r, o)),
];

/// Seconds to trace `rays` in batches of `batch` with `f` (not inlined, for callgrind's
/// `--toggle-collect='*intersect_many::time*'`).
#[inline(never)]
fn time(
    scene: &Scene,
    rays: &[Ray],
    batch: usize,
    f: Trace,
    out: &mut [Option<Interaction>],
) -> f64 {
    let t = Instant::now();
    for (r, o) in rays.chunks(batch).zip(out.chunks_mut(batch)) {
        f(scene, r, o);
    }
    std::hint::black_box(&out);
    t.elapsed().as_secs_f64()
}

fn main() {
    let mut scenes = Vec::new();
    let (mut batch, mut rounds) = (256usize, 7usize);
    let (mut res, mut spp) = (64u32, 4u32);
    // `--only NAME`: that variant once, no checks (for `valgrind --tool=callgrind`).
    let mut only = None;
    let mut dump = None;
    let (mut shuffle, mut repeat, mut only_set) = (false, 1usize, None);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--batch" => batch = args.next().and_then(|v| v.parse().ok()).expect("--batch N"),
            "--rounds" => {
                rounds = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--rounds N")
            }
            "--res" => res = args.next().and_then(|v| v.parse().ok()).expect("--res N"),
            "--spp" => spp = args.next().and_then(|v| v.parse().ok()).expect("--spp N"),
            "--only" => only = Some(args.next().expect("--only VARIANT")),
            "--dump" => dump = Some(args.next().expect("--dump DIR")),
            "--shuffle" => shuffle = true,
            "--repeat" => {
                repeat = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--repeat N")
            }
            "--set" => {
                let name = args.next().expect("--set camera|bounces|first");
                assert!(
                    ["camera", "bounces", "first"].contains(&name.as_str()),
                    "--set {name}: not camera, bounces or first"
                );
                only_set = Some(name);
            }
            "--bunny" => scenes.push(format!("bunny:{}", args.next().expect("--bunny N"))),
            "--bench" => {}
            _ => scenes.push(a),
        }
    }
    if scenes.is_empty() {
        scenes = ["gallery", "bunny-box"]
            .map(|s| format!("{}/bench/out/scenes/{s}.xml", env!("CARGO_MANIFEST_DIR")))
            .to_vec();
    }
    for path in &scenes {
        let desc = match path.strip_prefix("bunny:") {
            // The benchmarks' bunny, each triangle split into N² (`--bunny N`).
            Some(n) => common::bunny_scene(common::subdivide(
                &common::bunny(),
                n.parse().expect("--bunny N"),
            )),
            None => mcrt::load_scene_with(Path::new(path), &mcrt::LoadOptions::default())
                .unwrap_or_else(|e| panic!("{path}: {e} (run python3 bench/make_scenes.py)")),
        };
        let scene = Scene::build(desc);
        let (levels, shadow, shadow_t) = path_rays(&scene, res, spp);
        let mut sets = [
            ("camera", levels[0].clone()),
            ("bounces", levels[1..].concat()),
            // The first bounce alone: a pixel's samples leave from nearly one point.
            ("first", levels[1].clone()),
        ];
        if let Some(dir) = &dump {
            let stem = Path::new(path)
                .file_stem()
                .map_or("bunny".into(), |s| s.to_string_lossy());
            let infinite = |rays: &[Ray]| vec![f32::INFINITY; rays.len()];
            for (name, rays, t) in [
                ("camera", &sets[0].1, infinite(&sets[0].1)),
                ("bounces", &sets[1].1, infinite(&sets[1].1)),
                ("first", &sets[2].1, infinite(&sets[2].1)),
                ("shadow", &shadow, shadow_t.clone()),
            ] {
                write_rays(&Path::new(dir).join(format!("{stem}-{name}.f32")), rays, &t);
            }
        }
        if repeat > 1 {
            // Each sixteen consecutive rays traced `repeat` times over: all but the first
            // time from warm caches, so that a ray's time is its instructions' and not its
            // misses'.
            for (_, rays) in &mut sets {
                *rays = rays
                    .chunks(PACKET)
                    .flat_map(|c| std::iter::repeat_n(c, repeat).flatten().copied())
                    .collect();
            }
        }
        if shuffle {
            // The same rays in no order (a fixed permutation): what their order is worth.
            for (_, rays) in &mut sets {
                for i in (1..rays.len()).rev() {
                    let j = (unit(i as u64 ^ 0x5eed) * (i + 1) as f32) as usize;
                    rays.swap(i, j.min(i));
                }
            }
        }
        println!(
            "{path}: {} triangles, {:.1} MB, streams: {}, batches of {batch}, {rounds} rounds",
            scene.triangle_count(),
            scene.memory_bytes() as f64 / 1e6,
            scene.streams()
        );
        for (name, rays) in &sets {
            if only_set.as_ref().is_some_and(|s| s != name) {
                continue;
            }
            if let Some(v) = &only {
                // `packets`: the camera rays as the renderers' packets of sixteen.
                let (f, b) = match VARIANTS.iter().find(|(n, _)| n == v) {
                    Some(&(_, f)) => (f, batch),
                    None if v == "packets" => (packets as Trace, PACKET),
                    None => panic!("--only {v}: not a variant (1, auto, 4, 8, 16, 32, packets)"),
                };
                let mut out = vec![None; rays.len()];
                let t = time(&scene, rays, b, f, &mut out);
                println!(
                    "  {name}: {} rays, {v}: {:.1} ns/ray",
                    rays.len(),
                    t * 1e9 / rays.len() as f64
                );
                continue;
            }
            let mut want = vec![None; rays.len()];
            one_by_one(&scene, rays, &mut want);
            let want: Vec<_> = want.iter().map(bits).collect();
            let mut out = vec![None; rays.len()];
            for (vname, f) in &VARIANTS[1..] {
                time(&scene, rays, batch, *f, &mut out);
                let got: Vec<_> = out.iter().map(bits).collect();
                assert!(got == want, "{vname}: answers differ from one by one");
            }
            let mut best = vec![f64::INFINITY; VARIANTS.len()];
            let mut worst = vec![0f64; VARIANTS.len()];
            for round in 0..rounds {
                for j in 0..VARIANTS.len() {
                    let v = (j + round) % VARIANTS.len();
                    let t = time(&scene, rays, batch, VARIANTS[v].1, &mut out);
                    best[v] = best[v].min(t);
                    worst[v] = worst[v].max(t);
                }
            }
            let hits = want.iter().filter(|h| h.is_some()).count();
            println!("  {name}: {} rays ({hits} hit)", rays.len());
            if *name == "camera" {
                // A pinhole camera's rays share their origin: the render traces them in
                // packets of sixteen consecutive samples.
                packets(&scene, rays, &mut out);
                let got: Vec<_> = out.iter().map(bits).collect();
                assert!(got == want, "packets: answers differ from one by one");
                let t = (0..rounds)
                    .map(|_| time(&scene, rays, PACKET, packets, &mut out))
                    .fold(f64::INFINITY, f64::min);
                println!("    packets: {:7.1} ns/ray", t * 1e9 / rays.len() as f64);
            }
            for (v, (vname, _)) in VARIANTS.iter().enumerate() {
                println!(
                    "    K = {vname:>2}: {:7.1} ns/ray (spread {:.2}), one by one / this {:.3}",
                    best[v] * 1e9 / rays.len() as f64,
                    worst[v] / best[v],
                    best[0] / best[v],
                );
            }
        }
        shadows(&scene, &shadow, &shadow_t, batch, rounds, only.as_deref());
        if only.is_none() {
            first_vertex_shadows(&scene, &levels[0], rounds);
        }
    }
}

type Occlusion = fn(&Scene, &[Ray], &[f32], &mut [bool]);

fn occluded_one_by_one(s: &Scene, rays: &[Ray], t: &[f32], out: &mut [bool]) {
    for ((r, &t), o) in rays.iter().zip(t).zip(out) {
        *o = s.occluded(r, t);
    }
}

const SHADOW_VARIANTS: [(&str, Occlusion); 6] = [
    ("1", occluded_one_by_one),
    ("auto", |s, r, t, o| s.occluded_many(r, t, o)),
    ("4", |s, r, t, o| s.occluded_many_k::<4>(r, t, o)),
    ("8", |s, r, t, o| s.occluded_many_k::<8>(r, t, o)),
    ("16", |s, r, t, o| s.occluded_many_k::<16>(r, t, o)),
    ("32", |s, r, t, o| s.occluded_many_k::<32>(r, t, o)),
];

/// Seconds to trace shadow rays in batches of `batch` with `f`.
#[inline(never)]
fn time_shadows(scene: &Scene, rays: &[Ray], t: &[f32], batch: usize, f: Occlusion) -> f64 {
    let mut out = vec![false; rays.len()];
    let start = Instant::now();
    for ((r, t), o) in rays
        .chunks(batch)
        .zip(t.chunks(batch))
        .zip(out.chunks_mut(batch))
    {
        f(scene, r, t, o);
    }
    std::hint::black_box(&out);
    start.elapsed().as_secs_f64()
}

/// The shadow rays one by one against `occluded_many_k` (answers checked equal first).
fn shadows(
    scene: &Scene,
    rays: &[Ray],
    t: &[f32],
    batch: usize,
    rounds: usize,
    only: Option<&str>,
) {
    if let Some(v) = only {
        // (The camera packets have no shadow variant.)
        let Some(&(_, f)) = SHADOW_VARIANTS.iter().find(|(n, _)| *n == v) else {
            return;
        };
        let s = time_shadows(scene, rays, t, batch, f);
        println!(
            "  shadow: {} rays, {v}: {:.1} ns/ray",
            rays.len(),
            s * 1e9 / rays.len() as f64
        );
        return;
    }
    let mut want = vec![false; rays.len()];
    occluded_one_by_one(scene, rays, t, &mut want);
    for (vname, f) in &SHADOW_VARIANTS[1..] {
        let mut out = vec![false; rays.len()];
        f(scene, rays, t, &mut out);
        assert!(
            out == want,
            "shadow rays, {vname}: answers differ from one by one"
        );
    }
    let mut best = [f64::INFINITY; SHADOW_VARIANTS.len()];
    let mut worst = [0f64; SHADOW_VARIANTS.len()];
    for round in 0..rounds {
        for j in 0..SHADOW_VARIANTS.len() {
            let v = (j + round) % SHADOW_VARIANTS.len();
            let s = time_shadows(scene, rays, t, batch, SHADOW_VARIANTS[v].1);
            best[v] = best[v].min(s);
            worst[v] = worst[v].max(s);
        }
    }
    let blocked = want.iter().filter(|&&b| b).count();
    println!("  shadow: {} rays ({blocked} blocked)", rays.len());
    for (v, (vname, _)) in SHADOW_VARIANTS.iter().enumerate() {
        println!(
            "    K = {vname:>2}: {:7.1} ns/ray (spread {:.2}), one by one / this {:.3}",
            best[v] * 1e9 / rays.len() as f64,
            worst[v] / best[v],
            best[0] / best[v],
        );
    }
}

/// Shadow rays as next-event estimation sends them from the first vertices of a pixel's
/// samples: from the camera rays' hits towards a small region at the top of the scene (a
/// light), sixteen consecutive rays (a pixel's samples at `--spp 16`) as one packet of rays
/// of their own origins (`Scene::occluded_origins`) against the same rays eight in flight.
fn first_vertex_shadows(scene: &Scene, camera: &[Ray], rounds: usize) {
    let bb = scene.bounds().expect("a scene with something in it");
    let target = bb.min + (bb.max - bb.min) * Vec3A::new(0.5, 0.9, 0.5);
    let r = (bb.max - bb.min).length() * 0.02;
    let mut rays = Vec::new();
    for (k, ray) in camera.iter().enumerate() {
        if let Some(si) = scene.intersect(ray) {
            let j = Vec3A::new(
                unit(k as u64 * 3 + 7),
                unit(k as u64 * 3 + 8),
                unit(k as u64 * 3 + 9),
            );
            rays.push(si.spawn_ray(target + (j - 0.5) * r - si.p));
        }
    }
    let t = vec![1.0 - 1e-4; rays.len()];
    let mut want = vec![false; rays.len()];
    occluded_one_by_one(scene, &rays, &t, &mut want);
    let mut got = vec![false; rays.len()];
    let packets = |got: &mut [bool]| {
        let start = Instant::now();
        scene.occluded_origins(&rays, &t, got);
        start.elapsed().as_secs_f64()
    };
    packets(&mut got);
    assert!(
        got == want,
        "own-origin packets: answers differ from one by one"
    );
    let tp = (0..rounds)
        .map(|_| packets(&mut got))
        .fold(f64::INFINITY, f64::min);
    let many = |s: &Scene, r: &[Ray], t: &[f32], o: &mut [bool]| s.occluded_many(r, t, o);
    let ti = (0..rounds)
        .map(|_| time_shadows(scene, &rays, &t, 256, many))
        .fold(f64::INFINITY, f64::min);
    let blocked = want.iter().filter(|&&b| b).count();
    println!(
        "  first-vertex shadow rays: {} rays ({blocked} blocked), occluded_many {:.1} ns/ray, \
         packets of own origins {:.1} ns/ray",
        rays.len(),
        ti * 1e9 / rays.len() as f64,
        tp * 1e9 / rays.len() as f64
    );
}
