//! Agreement with Mitsuba 3: converged references (tests/data/refs, made with
//! tools/mitsuba_ref.py, see tests/data/README.md) against mcrt renders of the native scenes,
//! compared on 16×16-pixel block means with tolerances derived from the measured noise.

mod common;

use common::caustic::caustic_blocks;
use common::*;
use glam::{Vec2, Vec3};
use mcrt::camera::{CameraDesc, FovAxis};
use mcrt::render::RenderSettings;
use mcrt::scene::desc::FileSettings;

/// Renders a scene file's camera at 128×128 and 256 spp and checks it against a 256×256
/// reference made with `ref_spp` samples.
fn matches_mitsuba(
    scene_file: &str,
    camera: Option<&str>,
    reference_file: &str,
    ref_spp: u32,
) -> RenderSettings {
    let (scene, fs) = load(scene_file);
    let over = FileSettings {
        width: Some(128),
        height: Some(128),
        spp: Some(256),
        camera: camera.map(String::from),
        ..Default::default()
    };
    let s = settings(&fs, over);
    let r = render_with(&scene, &s);
    BlockComparison::new(&r, &reference(reference_file), 16, ref_spp)
        .assert_within_noise(&format!("{scene_file} {}", camera.unwrap_or("")));
    s
}

#[test]
fn mitsuba_xml_cornell_box_matches_mitsuba() {
    let s = matches_mitsuba(
        "tests/data/mitsuba/cornell-box.xml",
        None,
        "cornell-box.exr",
        8192,
    );
    assert_eq!(s.params.max_depth, Some(8), "max_depth read from the XML");
}

#[test]
fn mitsuba_xml_hexroom_matches_mitsuba() {
    let s = matches_mitsuba(
        "tests/data/mitsuba/hexroom/hexroom.xml",
        None,
        "hexroom-eye1.exr",
        16384,
    );
    assert_eq!(s.params.max_depth, None, "max_depth -1 is unlimited");
}

#[test]
fn tncg15_eye1_matches_mitsuba() {
    matches_mitsuba(
        "scenes/tncg15.toml",
        Some("eye1"),
        "hexroom-eye1.exr",
        16384,
    );
}

#[test]
fn tncg15_eye2_matches_mitsuba() {
    matches_mitsuba("scenes/tncg15.toml", Some("eye2"), "hexroom-eye2.exr", 4096);
}

#[test]
fn cornell_box_matches_mitsuba() {
    let s = matches_mitsuba("scenes/cornell-box.toml", None, "cornell-box.exr", 8192);
    assert_eq!(
        s.params.max_depth,
        Some(8),
        "the scene file carries Mitsuba's max_depth"
    );
}

/// The course's camera (eye + image-plane corners) and the look-at camera with a field of
/// view must generate the same rays for both eyes of the TNCG15 room: eye 1 is a 90° view
/// from (−1,0,0), eye 2 a 2·atan(1/2) view from (−2,0,0), both through the plane x = 0 with
/// corners (0, ±1, ±1).
#[test]
fn pinhole_cameras_equal_lookat_cameras() {
    let (scene, _) = load("scenes/tncg15.toml");
    for (name, eye_x, fov) in [
        ("eye1", -1.0f32, 90.0f32),
        ("eye2", -2.0, 2.0 * 0.5f32.atan().to_degrees()),
    ] {
        let pin = scene.camera(Some(name)).unwrap().build(64, 64);
        let look = CameraDesc::Perspective {
            origin: Vec3::new(eye_x, 0.0, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            fov,
            fov_axis: FovAxis::X,
        }
        .build(64, 64);
        for y in 0..64 {
            for x in 0..64 {
                for u in [Vec2::ZERO, Vec2::splat(0.5), Vec2::new(0.999, 0.25)] {
                    let (a, b) = (pin.generate_ray(x, y, u), look.generate_ray(x, y, u));
                    assert!(
                        (a.o - b.o).length() < 1e-6 && (a.d - b.d).length() < 1e-5,
                        "{name} pixel {x},{y}: {:?} vs {:?}",
                        a,
                        b
                    );
                }
            }
        }
        // The top-left pixel looks up and to the left (+y, +z), as the scene description says.
        let d = pin.generate_ray(0, 0, Vec2::ZERO).d;
        assert!(
            d.y > 0.0 && d.z > 0.0 && d.x > 0.0,
            "{name}: top-left ray {d:?}"
        );
        // The image-plane corner hit by the top-left ray is (0, 1, 1).
        let t = -pin.eye().x / d.x;
        let p = pin.eye() + d * t;
        assert!(
            (p - glam::Vec3A::new(0.0, 1.0, 1.0)).length() < 1e-5,
            "{name}: corner {p:?}"
        );
    }
}

/// Renders eye 1 at 256×256 with `spp` and compares with the reference: every block within
/// 5σ of the measured noise; returns the comparison, the caustic mask and the worst relative
/// error outside the caustic.
fn tncg15_full_resolution(spp: u32) -> (BlockComparison, Vec<bool>, f64) {
    let (scene, fs) = load("scenes/tncg15.toml");
    let over = FileSettings {
        width: Some(256),
        height: Some(256),
        spp: Some(spp),
        camera: Some("eye1".into()),
        ..Default::default()
    };
    let r = render_with(&scene, &settings(&fs, over));
    let c = BlockComparison::new(&r, &reference("hexroom-eye1.exr"), 16, 16384);
    let mask = caustic_blocks(&scene, 256, 16);
    for i in (0..c.mine.len()).filter(|&i| c.rel_err(i) > 0.015) {
        let d = c.mine[i] - c.reference[i];
        eprintln!(
            "block ({}, {}): {:+.2} %, z {:+.2}, relative sigma {:.2} %, caustic {}",
            i % 16,
            i / 16,
            100.0 * d / c.reference[i],
            d / c.sigma[i],
            100.0 * c.sigma[i] / c.reference[i],
            mask[i]
        );
    }
    c.assert_within_noise(&format!("tncg15 eye1 {spp} spp"));
    let worst = (0..c.mine.len())
        .filter(|&i| !mask[i])
        .map(|i| c.rel_err(i))
        .fold(0.0, f64::max);
    let over2 = (0..c.mine.len())
        .filter(|&i| !mask[i] && c.rel_err(i) > 0.02)
        .count();
    eprintln!(
        "{spp} spp: {} caustic blocks; outside them worst {:.2} %, {over2} blocks over 2 %",
        mask.iter().filter(|&&m| m).count(),
        100.0 * worst
    );
    (c, mask, worst)
}

/// The bar at 1024 spp: every block within noise. At 1024 spp the measured noise of a
/// 16×16 block here is about 1 % (the same as Mitsuba's: its reference's 0.1–0.3 % at 16384
/// spp is 0.4–1.2 % at 1024), so 2 % is a 2σ criterion that a few of the 200 non-caustic
/// blocks miss by chance (Mitsuba 3's own 1024-spp render misses it on six, see
/// `other_renderer_against_the_2_percent_bar`); the test prints them. About a minute on two cores:
/// `cargo test --release --test reference -- --ignored`.
#[test]
#[ignore]
fn tncg15_1024spp_within_noise() {
    tncg15_full_resolution(1024);
}

/// The 2 % criterion where it is a 4σ one: at 4096 spp, every block outside the glass
/// sphere's caustic within 2 % of Mitsuba 3. About five minutes on two cores.
#[test]
#[ignore]
fn tncg15_4096spp_within_2_percent() {
    let (_, _, worst) = tncg15_full_resolution(4096);
    assert!(
        worst < 0.02,
        "a block outside the caustic is off by {:.2} %",
        100.0 * worst
    );
}

/// The caustic mask itself must find the caustic: the floor under the glass sphere, away
/// from the light, and nothing in the top half of the image (walls and ceiling far from it).
#[test]
fn caustic_mask_is_where_the_caustic_is() {
    let (scene, _) = load("scenes/tncg15.toml");
    let mask = caustic_blocks(&scene, 256, 16);
    let n = mask.iter().filter(|&&m| m).count();
    assert!(n > 0 && n < 64, "{n} caustic blocks");
    // Floor point below the glass sphere, on the side away from the light: (6, 2.5, −5),
    // projected through eye 1 onto x = 0: (y, z) = (2.5/7, −5/7) → block (5, 13).
    assert!(mask[13 * 16 + 5], "block (5, 13) holds the caustic");
}

/// The 2 % bar applied to another renderer's image of eye 1 (256×256), given by the path in
/// `MCRT_OTHER_EXR`: how many blocks outside the caustic are off by more than 2 %. Mitsuba 3
/// itself at 1024 spp (`python3 tools/mitsuba_ref.py tests/data/mitsuba/hexroom/hexroom.xml
/// mi.exr 1024 --seed 1000`) has six such blocks, worst 2.9 %: at 1024 spp the bar is a
/// 2σ criterion for any unbiased path tracer. Run with
/// `MCRT_OTHER_EXR=mi.exr cargo test --release --test reference -- --ignored other_renderer`.
#[test]
#[ignore]
fn other_renderer_against_the_2_percent_bar() {
    let Ok(path) = std::env::var("MCRT_OTHER_EXR") else {
        panic!("set MCRT_OTHER_EXR to a 256×256 EXR of eye 1");
    };
    let (scene, _) = load("scenes/tncg15.toml");
    let mask = caustic_blocks(&scene, 256, 16);
    let other = mcrt::image::read_exr(std::path::Path::new(&path)).expect("readable EXR");
    let r = reference("hexroom-eye1.exr");
    assert_eq!((other.width, other.height), (256, 256));
    let (mut worst, mut over) = (0.0f64, 0);
    for by in 0..16 {
        for bx in 0..16 {
            let (a, b) = (other.block_mean(bx, by, 16), r.block_mean(bx, by, 16));
            let e = ((a[0] + a[1] + a[2]) / (b[0] + b[1] + b[2]) - 1.0).abs();
            if !mask[(by * 16 + bx) as usize] {
                worst = worst.max(e);
                if e > 0.02 {
                    over += 1;
                    eprintln!("block ({bx}, {by}): {:.2} %", 100.0 * e);
                }
            }
        }
    }
    eprintln!(
        "outside the caustic: worst {:.2} %, {over} blocks over 2 %",
        100.0 * worst
    );
}
