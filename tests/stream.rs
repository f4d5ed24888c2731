//! The stream path tracer (`--backend stream`, `integrator::stream`: a pool of paths per tile
//! whose rays are traced in batches) renders the same film as one path at a time
//! (`--backend scalar`), bit for bit: the same fixed-point sums, sample counts, ray counts and
//! dropped samples, on scenes that take every branch of a path — meshes with normals and uvs,
//! textures, rough and smooth BSDFs (principled, blend, thin and rough dielectrics), masks,
//! bump and normal maps, instances, an environment map, point, spot, directional and area
//! lights; pinhole, thin-lens and orthographic cameras; hidden emitters; max_depth 1, 2 and
//! unlimited; both roulettes; several shadow rays; both samplers — on one and two threads, in
//! crops and in passes.

mod common;

use common::cli::{TempDir, BIN};
use mcrt::film::{Film, PixelSums};
use mcrt::integrator::{prepare, IntegratorKind};
use mcrt::render::{render, render_samples, Backend, RenderSettings, RenderStats, TilePixel};
use mcrt::sampler::SamplerKind;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use std::path::Path;

fn load(rel: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    Scene::build(mcrt::load_scene(&path).unwrap_or_else(|e| panic!("{rel}: {e}")))
}

fn feature(name: &str) -> Scene {
    load(&format!("tests/data/mitsuba/features/{name}.xml"))
}

/// Small renders (odd sizes, so tiles are partial; more samples per tile than the pool has
/// paths, so slots are refilled) with `over` on top.
fn settings(scene: &Scene, over: FileSettings, threads: usize) -> RenderSettings {
    let over = FileSettings {
        width: over.width.or(Some(21)),
        height: over.height.or(Some(13)),
        spp: over.spp.or(Some(3)),
        seed: over.seed.or(Some(5)),
        ..over
    };
    mcrt::resolve_settings(&scene.desc_settings, &over, Some(threads)).unwrap()
}

fn with_backend(s: &RenderSettings, backend: Backend) -> RenderSettings {
    RenderSettings {
        backend,
        ..s.clone()
    }
}

/// Everything the film and the statistics hold, for a bit-for-bit comparison.
fn assert_same(a: &(Film, RenderStats), b: &(Film, RenderStats), what: &str) {
    assert!(a.0.sum == b.0.sum, "{what}: Σ L differs");
    assert!(a.0.sum_sq == b.0.sum_sq, "{what}: Σ L² differs");
    assert_eq!(a.0.count, b.0.count, "{what}: sample counts differ");
    assert_eq!(a.1.samples, b.1.samples, "{what}: samples");
    assert_eq!(
        (a.1.rays.rays, a.1.rays.shadow_rays),
        (b.1.rays.rays, b.1.rays.shadow_rays),
        "{what}: ray counts"
    );
    assert_eq!(
        (a.1.dropped, a.1.first_dropped),
        (b.1.dropped, b.1.first_dropped),
        "{what}: dropped samples"
    );
}

/// Renders `scene` with `s` as a stream on `threads` threads and one path at a time on two,
/// compares them, and checks that the image is not empty (a black render would compare
/// equal whatever the stream did).
fn stream_equals_scalar(scene: &Scene, s: &RenderSettings, what: &str) {
    let scalar = render(scene, &with_backend(s, Backend::Scalar), &|_| {}).unwrap();
    let stream = render(scene, &with_backend(s, Backend::Stream), &|_| {}).unwrap();
    assert_same(&stream, &scalar, what);
    let lit = stream.0.sum.iter().flatten().filter(|&&v| v != 0).count();
    assert!(
        lit > 0,
        "{what}: the image is black, the test compares nothing"
    );
}

fn over() -> FileSettings {
    FileSettings::default()
}

/// The stream takes every tile it is given (else the comparisons below would compare the
/// scalar loop with itself) with `--backend stream`, and `auto` takes them too (with the
/// wavefront, or the stream where the CPU has no AVX2); `scalar` leaves the tiles to the
/// render loop.
#[test]
fn the_stream_takes_the_tiles() {
    // Two light samples a vertex under two lights.
    let scene = feature("cameras");
    let mut s = settings(&scene, over(), 1);
    s.params.shadow_rays = 2;
    let pixels: Vec<TilePixel> = (0..4)
        .map(|x| TilePixel {
            x,
            y: 0,
            gx: x,
            gy: 0,
            samples: (0, 2),
        })
        .collect();
    for (backend, takes) in [
        (Backend::Stream, true),
        (Backend::Auto, true),
        (Backend::Scalar, false),
    ] {
        let s = with_backend(&s, backend);
        let integrator = prepare(&scene, &s, &|| false).unwrap();
        let camera = mcrt::render::camera_for(&scene, &s).unwrap();
        let mut sums = vec![PixelSums::default(); pixels.len()];
        let mut stats = RenderStats::default();
        let took = integrator.render_tile(&camera, &pixels, &mut sums, &mut stats);
        assert_eq!(took, takes, "{backend:?}");
        if takes {
            assert!(
                sums.iter().all(|p| p.count == 2),
                "{backend:?}: two samples each"
            );
            assert!(
                stats.rays.rays >= 8,
                "{backend:?}: a ray per sample at least"
            );
        }
    }
}

/// Every feature scene, as its file sets it up (its depth, lights, camera).
#[test]
fn every_feature_scene() {
    for name in [
        "beckmann",
        "cameras",
        "envmap",
        "instances",
        "lights",
        "maps-mask",
        "materials",
        "orthographic",
        "principled",
        "principled-textured",
        "shapes",
        "spot",
        "textured-params",
        "textures",
    ] {
        let scene = feature(name);
        stream_equals_scalar(&scene, &settings(&scene, over(), 2), name);
    }
}

/// The two test rooms (smooth glass and mirror; Lambert walls), which `auto` gives to the
/// wavefront but `--backend stream` to the stream, and the glTF-free Cornell box from XML.
#[test]
fn rooms() {
    for rel in [
        "scenes/cornell-box.toml",
        "scenes/tncg15.toml",
        "tests/data/mitsuba/cornell-box.xml",
    ] {
        let scene = load(rel);
        stream_equals_scalar(&scene, &settings(&scene, over(), 2), rel);
    }
}

/// Path lengths, roulettes, shadow rays, samplers and hidden emitters, on scenes with rough
/// and smooth BSDFs, blends, principled and textures.
#[test]
fn integrator_settings() {
    let variants: Vec<(&str, FileSettings)> = vec![
        (
            "max_depth 2, hidden emitters",
            FileSettings {
                max_depth: Some(2),
                hide_emitters: Some(true),
                ..over()
            },
        ),
        (
            "max_depth 1",
            FileSettings {
                max_depth: Some(1),
                ..over()
            },
        ),
        (
            "max_depth 2, sobol",
            FileSettings {
                max_depth: Some(2),
                sampler: Some(SamplerKind::Sobol),
                ..over()
            },
        ),
        (
            "unlimited, fixed roulette, 3 shadow rays",
            FileSettings {
                rr_survival: Some(0.7),
                shadow_rays: Some(3),
                ..over()
            },
        ),
        (
            "unlimited, throughput roulette from depth 1, sobol, hidden emitters",
            FileSettings {
                rr_depth: Some(1),
                sampler: Some(SamplerKind::Sobol),
                hide_emitters: Some(true),
                ..over()
            },
        ),
    ];
    for name in ["materials", "textured-params", "principled-textured"] {
        let scene = feature(name);
        for (what, o) in &variants {
            stream_equals_scalar(
                &scene,
                &variant(&scene, what, o),
                &format!("{name}: {what}"),
            );
        }
    }
    let scene = load("scenes/cornell-box.toml");
    for (what, o) in &variants {
        let s = variant(&scene, what, o);
        stream_equals_scalar(&scene, &s, &format!("cornell-box: {what}"));
    }
}

/// The settings of a variant named `what`: an "unlimited" one has no max_depth, whatever
/// the scene's file sets.
fn variant(scene: &Scene, what: &str, o: &FileSettings) -> RenderSettings {
    let mut s = settings(scene, o.clone(), 2);
    if what.starts_with("unlimited") {
        s.params.max_depth = None;
    }
    s
}

/// One thread or two, the same bits.
#[test]
fn one_and_two_threads() {
    for name in ["envmap", "cameras"] {
        let scene = feature(name);
        let one = render(
            &scene,
            &with_backend(&settings(&scene, over(), 1), Backend::Stream),
            &|_| {},
        )
        .unwrap();
        let two = render(
            &scene,
            &with_backend(&settings(&scene, over(), 2), Backend::Scalar),
            &|_| {},
        )
        .unwrap();
        assert_same(&one, &two, name);
    }
}

/// Samples split into uneven passes (what `--pass`, `--resume` and `--time` do) and a crop
/// give the same film as one scalar pass.
#[test]
fn passes_and_crops() {
    for name in ["instances", "spot", "orthographic"] {
        let scene = feature(name);
        let s = settings(
            &scene,
            FileSettings {
                spp: Some(7),
                ..over()
            },
            2,
        );
        let once = render(&scene, &with_backend(&s, Backend::Scalar), &|_| {}).unwrap();
        let stream = with_backend(&s, Backend::Stream);
        let mut film = Film::new(s.width, s.height);
        let mut stats = RenderStats::default();
        for (first, count) in [(0, 1), (1, 4), (5, 2)] {
            stats.add(&render_samples(&scene, &stream, &mut film, first, count, &|_| {}).unwrap());
        }
        assert_same(&(film, stats), &once, &format!("{name}: passes"));

        let crop = RenderSettings {
            crop: Some([3, 2, 11, 7]),
            ..s.clone()
        };
        stream_equals_scalar(&scene, &crop, &format!("{name}: crop"));
    }
}

/// The stream runs the path tracer only: `direct` and `photon` refuse it, as they refuse the
/// wide backends.
#[test]
fn other_integrators_refuse_it() {
    let scene = feature("materials");
    for kind in [IntegratorKind::Direct, IntegratorKind::Photon] {
        let s = settings(
            &scene,
            FileSettings {
                integrator: Some(kind),
                ..over()
            },
            1,
        );
        let e = prepare(&scene, &with_backend(&s, Backend::Stream), &|| false)
            .err()
            .unwrap_or_else(|| panic!("{kind:?} takes --backend stream"));
        assert!(e.to_string().contains("--backend stream"), "{e}");
    }
}

/// From the command line: a render checkpointed at 3 spp and resumed to 7 with
/// `--backend stream` (a thin-lens camera, so `auto` takes the stream too) gives the image of
/// one scalar render at 7 spp, bit for bit.
#[test]
fn checkpoint_and_resume_from_the_command_line() {
    let dir = TempDir::new("stream-resume");
    let scene =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features/cameras.xml");
    let render = |out: &Path, extra: &[&str]| {
        let o = std::process::Command::new(BIN)
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(out)
            .args([
                "--width",
                "19",
                "--height",
                "11",
                "--threads",
                "2",
                "--seed",
                "3",
                "-q",
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        mcrt::image::read_exr(out).unwrap()
    };
    let ckpt = dir.path().join("state.exr");
    let ckpt_arg = ckpt.to_str().unwrap();
    let first = dir.path().join("first.exr");
    render(
        &first,
        &[
            "--spp",
            "3",
            "--backend",
            "stream",
            "--checkpoint",
            ckpt_arg,
        ],
    );
    let resumed = render(
        &dir.path().join("resumed.exr"),
        &["--spp", "7", "--backend", "stream", "--resume", ckpt_arg],
    );
    let once = render(
        &dir.path().join("once.exr"),
        &["--spp", "7", "--backend", "scalar"],
    );
    let bits = |img: &mcrt::image::Image| -> Vec<[u32; 3]> {
        img.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert!(
        bits(&resumed) == bits(&once),
        "resumed stream differs from one scalar render"
    );
    assert!(
        once.pixels.iter().any(|p| p.max_element() > 0.0),
        "a black image"
    );
}
