//! Scale: the same view of the bunny at about 10 k, 100 k, 1 M and 10 M triangles (each
//! triangle of the 3674-triangle bunny split into k² coplanar ones, generated here and never
//! stored), with the BVH build rate, the memory a triangle costs and the render rate.
//!
//!     cargo bench --bench scale            (all four sizes; about a minute and 2 GB at 10 M)
//!     cargo bench --bench scale -- 1000000 (sizes up to this count)
//!     cargo bench --bench scale -- 1000000 --build-only  (no renders)
//!     cargo bench --bench scale -- --phases  (also the wall time of each build phase, and
//!                                             the build's peak memory on Linux)
//!     cargo bench --bench scale -- --builds 5  (the fastest of five builds of each size)

#[path = "common.rs"]
mod common;

use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use std::time::Instant;

/// A build: its wall time, the scene, the resident memory before and at most during it
/// (bytes, where the OS tells), and its user and system CPU time (seconds).
type Build = (f64, Scene, Option<(u64, u64)>, (f64, f64));

fn main() {
    let max: u64 = std::env::args()
        .skip(1)
        .zip(std::env::args())
        .find_map(|(a, before)| a.parse().ok().filter(|_| before != "--builds"))
        .unwrap_or(u64::MAX);
    // `--build-only`: builds without rendering (for instruction counts of the build).
    let build_only = std::env::args().any(|a| a == "--build-only");
    let phases = std::env::args().any(|a| a == "--phases");
    let args: Vec<String> = std::env::args().collect();
    let builds: usize = args
        .iter()
        .position(|a| a == "--builds")
        .and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(1);
    let mut phase_lines = Vec::new();
    let base = common::bunny();
    println!(
        "| triangles | build (s) | build (M tri/s) | bytes/triangle | SAH cost | samples/s (M) | vs 10 k |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut first_rate = None;
    for k in [2u32, 5, 16, 52] {
        let n = base.indices.len() as u64 * (k * k) as u64;
        if n > max {
            break;
        }
        let mesh = common::subdivide(&base, k);
        let desc = common::bunny_scene(mesh);
        // (The copy is the benchmark's, so that `desc` can be dropped after the build; it is
        // not part of the build.) With `--builds K`, the fastest of K builds counts.
        let mut fastest: Option<Build> = None;
        for _ in 0..builds.max(1) {
            let copy = desc.clone();
            let start = reset_peak_rss();
            let cpu = cpu_times();
            let t = Instant::now();
            let scene = Scene::build(copy);
            let build = t.elapsed().as_secs_f64();
            let cpu_after = cpu_times();
            let cpu = (cpu_after.0 - cpu.0, cpu_after.1 - cpu.1);
            let peak = start.zip(peak_rss());
            if fastest.as_ref().is_none_or(|(b, ..)| build < *b) {
                fastest = Some((build, scene, peak, cpu));
            }
        }
        let (build, scene, peak, cpu) = fastest.unwrap();
        let bytes = scene.memory_bytes() as f64 / scene.prim_count() as f64;
        phase_lines.push(format!(
            "{} triangles: {}; CPU time {:.3} s user, {:.3} s system{}",
            scene.prim_count(),
            scene.build_times.summary(),
            cpu.0,
            cpu.1,
            peak.map_or(String::new(), |(s, p)| format!(
                "; resident memory {} MB before, at most {} MB during the build",
                s >> 20,
                p >> 20
            ))
        ));
        if build_only {
            println!(
                "| {} | {:.2} | {:.2} | {:.0} | {:.2} | – | – |",
                scene.prim_count(),
                build,
                scene.prim_count() as f64 / build / 1e6,
                bytes,
                scene.bvh.sah_cost()
            );
            continue;
        }
        let fs = FileSettings::default();
        let s = mcrt::resolve_settings(
            &fs,
            &FileSettings {
                width: Some(256),
                height: Some(256),
                spp: Some(8),
                ..Default::default()
            },
            None,
        )
        .unwrap();
        let (_, stats) = mcrt::render::render(&scene, &s, &|_| {}).unwrap();
        let rate = stats.samples as f64 / stats.elapsed.as_secs_f64();
        let first = *first_rate.get_or_insert(rate);
        println!(
            "| {} | {:.2} | {:.2} | {:.0} | {:.2} | {:.2} | {:.2}× slower |",
            scene.prim_count(),
            build,
            scene.prim_count() as f64 / build / 1e6,
            bytes,
            scene.bvh.sah_cost(),
            rate / 1e6,
            first / rate
        );
        drop(desc);
    }
    if phases {
        println!();
        for l in phase_lines {
            println!("{l}");
        }
    }
}

/// Resets the process's peak resident memory to its current size (Linux: `clear_refs`), and
/// returns that size in bytes; None where the kernel offers no such thing.
fn reset_peak_rss() -> Option<u64> {
    std::fs::write("/proc/self/clear_refs", "5").ok()?;
    status_bytes("VmRSS:")
}

/// The process's peak resident memory in bytes since the last reset (Linux).
fn peak_rss() -> Option<u64> {
    status_bytes("VmHWM:")
}

fn status_bytes(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line[field.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb << 10)
}

/// The process's user and system CPU time so far, in seconds (both threads' together).
fn cpu_times() -> (f64, f64) {
    // SAFETY: getrusage writes the struct it is given, which is plain data.
    let u = unsafe {
        let mut u: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_SELF, &mut u);
        u
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    (secs(u.ru_utime), secs(u.ru_stime))
}
