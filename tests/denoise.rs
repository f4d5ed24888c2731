//! `--denoise` and `mcrt denoise`: Intel Open Image Denoise, loaded at run time.
//!
//! The tests that run OIDN skip (with a notice) where it cannot be loaded, unless
//! `MCRT_REQUIRE_OIDN=1` is set, as `.ci/run` does after installing it (`pip install pyoidn`,
//! `OIDN_DIR`), where they fail instead.

mod common;

use common::cli::*;
use common::{project_path, reference};
use mcrt::compare::metrics;
use mcrt::image::read_exr;
use std::ffi::OsStr;
use std::process::Command;

/// Whether OIDN loads here; prints why a test is skipped when it does not.
fn have_oidn(test: &str) -> bool {
    match mcrt::denoise::Oidn::load() {
        Ok(_) => true,
        Err(e) if std::env::var_os("MCRT_REQUIRE_OIDN").is_some_and(|v| v == "1") => {
            panic!("MCRT_REQUIRE_OIDN=1 but OIDN does not load: {e}")
        }
        Err(_) => {
            eprintln!(
                "notice: {test} skipped: Open Image Denoise not found (pip install pyoidn and set \
                 OIDN_DIR, see README, \"Denoising\")"
            );
            false
        }
    }
}

fn render(args: &[&OsStr]) -> std::process::Output {
    let mut all: Vec<&OsStr> = vec!["render".as_ref()];
    all.extend_from_slice(args);
    run(&all)
}

fn ok(o: &std::process::Output, what: &str) {
    assert!(o.status.success(), "{what}: {}", stderr_of(o));
}

/// The proof of issue 26: the Cornell box at 16 spp, denoised, has less than a third of the
/// raw image's RMSE against the converged reference (Mitsuba 3, 8192 spp, the same 256²
/// view as tests/reference.rs uses).
#[test]
fn denoised_cornell_box_has_a_third_of_the_error() {
    if !have_oidn("denoised_cornell_box_has_a_third_of_the_error") {
        return;
    }
    let dir = TempDir::new("denoise-box");
    let out = dir.path().join("box.exr");
    let scene = project_path("scenes/cornell-box.toml");
    let o = render(&[
        scene.as_os_str(),
        "--spp".as_ref(),
        "16".as_ref(),
        "--seed".as_ref(),
        "1".as_ref(),
        "--denoise".as_ref(),
        "--aov".as_ref(),
        "albedo,normal,emission".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    ok(&o, "render --denoise");
    // The subcommand on the raw image and its layers, without the scene: the emission on
    // the light's edges is the guide rays' (coverage noise left), so it does less well.
    let cmd = dir.path().join("cmd.exr");
    let raw_path = dir.path().join("box.raw.exr");
    let o = run(&[
        "denoise".as_ref(),
        raw_path.as_os_str(),
        "-o".as_ref(),
        cmd.as_os_str(),
    ]);
    ok(&o, "mcrt denoise");
    let reference = reference("cornell-box.exr");
    let raw = read_exr(&dir.path().join("box.raw.exr")).expect("the raw image");
    let clean = read_exr(&out).expect("the denoised image");
    let e_raw = metrics(&raw, &reference).unwrap().rmse;
    let e_clean = metrics(&clean, &reference).unwrap().rmse;
    let e_cmd = metrics(&read_exr(&cmd).unwrap(), &reference).unwrap().rmse;
    eprintln!(
        "Cornell box 256² at 16 spp against the reference: RMSE raw {e_raw:.5}, denoised \
         {e_clean:.5} (ratio {:.3}); mcrt denoise on the raw EXR {e_cmd:.5}",
        e_clean / e_raw
    );
    assert!(e_clean < e_raw / 3.0, "raw {e_raw}, denoised {e_clean}");
    assert!(
        e_clean < e_cmd && e_cmd < e_raw,
        "raw {e_raw}, mcrt denoise {e_cmd}"
    );
    if let Some(keep) = std::env::var_os("MCRT_DENOISE_KEEP") {
        let keep = std::path::Path::new(&keep);
        std::fs::create_dir_all(keep).unwrap();
        for name in ["box.exr", "box.raw.exr", "cmd.exr"] {
            std::fs::copy(dir.path().join(name), keep.join(name)).unwrap();
        }
    }
}

/// The raw output of `--denoise` is the plain render; `mcrt denoise` with and without the
/// emission layer, to EXR and PNG.
#[test]
fn denoise_raw_output_and_subcommand() {
    if !have_oidn("denoise_raw_output_and_subcommand") {
        return;
    }
    let dir = TempDir::new("denoise-cmd");
    let scene = project_path("scenes/cornell-box.toml");
    let common = ["--spp", "4", "--width", "48", "--height", "40"];
    let with = |out: &std::path::Path, extra: &[&str]| {
        let mut args: Vec<&OsStr> = vec![scene.as_os_str()];
        args.extend(common.iter().map(OsStr::new));
        args.extend(extra.iter().map(OsStr::new));
        args.extend(["-o".as_ref(), out.as_os_str()]);
        let o = render(&args);
        ok(&o, &format!("render {extra:?}"));
    };
    let plain = dir.path().join("plain.exr");
    with(&plain, &["--aov", "albedo,normal,emission"]);
    let flagged = dir.path().join("flagged.exr");
    with(&flagged, &["--denoise"]);
    let no_emission = dir.path().join("no-emission.exr");
    with(&no_emission, &["--aov", "albedo,normal"]);
    let cmd_out = dir.path().join("cmd.exr");
    let cmd_whole = dir.path().join("cmd-whole.exr");
    for (input, output) in [(&plain, &cmd_out), (&no_emission, &cmd_whole)] {
        let o = run(&[
            "denoise".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            output.as_os_str(),
        ]);
        ok(&o, "mcrt denoise");
    }
    let image = |p: &std::path::Path| read_exr(p).unwrap();
    let raw = image(&dir.path().join("flagged.raw.exr"));
    assert!(
        raw.pixels == image(&plain).pixels,
        "the raw image is not the plain render"
    );
    let rmse =
        |a: &std::path::Path, b: &std::path::Path| metrics(&image(a), &image(b)).unwrap().rmse;
    assert!(rmse(&plain, &flagged) > 0.0, "denoising changed nothing");
    assert!(rmse(&plain, &cmd_out) > 0.0, "mcrt denoise changed nothing");
    // Without the emission layer the whole image goes through the filter.
    assert!(
        rmse(&cmd_whole, &cmd_out) > 0.0,
        "the emission layer is ignored"
    );
    // A PNG output of the subcommand.
    let png = dir.path().join("cmd.png");
    let o = run(&[
        "denoise".as_ref(),
        plain.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
    ]);
    ok(&o, "mcrt denoise to PNG");
    assert!(png.exists());
}

/// Runs mcrt with OIDN out of reach (OIDN_DIR empty, no library path).
fn without_oidn(args: &[&OsStr]) -> Option<std::process::Output> {
    let empty = TempDir::new("no-oidn");
    let o = Command::new(BIN)
        .args(args)
        .env("OIDN_DIR", empty.path())
        .env("LD_LIBRARY_PATH", empty.path())
        .output()
        .unwrap();
    // A system-wide install (ldconfig) cannot be hidden: nothing to check then.
    if o.status.success() {
        eprintln!("notice: OIDN is installed system-wide; the missing-library check is skipped");
        return None;
    }
    Some(o)
}

/// Without OIDN, `--denoise` stops before rendering: exit 2, how to install it, nothing
/// written.
#[test]
fn denoise_without_oidn_is_refused_before_rendering() {
    let dir = TempDir::new("denoise-missing");
    let out = dir.path().join("x.png");
    let scene = project_path("scenes/cornell-box.toml");
    // Far more samples than could render in the test's time.
    let Some(o) = without_oidn(&[
        "render".as_ref(),
        scene.as_os_str(),
        "--spp".as_ref(),
        "100000000".as_ref(),
        "--denoise".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]) else {
        return;
    };
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("libOpenImageDenoise"), "{err}");
    assert!(err.contains("pip install pyoidn"), "{err}");
    assert!(err.contains("OIDN_DIR"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(dir.listing().is_empty(), "{:?}", dir.listing());
}

/// `mcrt denoise` on an EXR without the guide layers names what is missing (exit 2).
#[test]
fn denoise_subcommand_needs_the_guide_layers() {
    let dir = TempDir::new("denoise-layers");
    let input = dir.path().join("in.exr");
    let img = mcrt::image::Image::new(8, 8);
    mcrt::image::write_image(&input, &img, &Default::default()).unwrap();
    let out = dir.path().join("out.exr");
    let o = run(&[
        "denoise".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("albedo.R") && err.contains("--aov albedo,normal"),
        "{err}"
    );
    assert!(!out.exists());
    let missing = dir.path().join("missing.exr");
    let o = run(&[
        "denoise".as_ref(),
        missing.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr_of(&o));
}

/// The emission guide: the Cornell box's light where camera rays see it (its radiance inside,
/// part of it on its edges), nothing elsewhere, and nothing with `hide_emitters`.
#[test]
fn emission_guide_is_the_directly_seen_light() {
    let (scene, fs) = common::load("scenes/cornell-box.toml");
    let over = mcrt::scene::desc::FileSettings {
        width: Some(64),
        height: Some(64),
        ..Default::default()
    };
    let mut s = common::settings(&fs, over);
    let g = mcrt::aov::render_guides(&scene, &s).unwrap();
    let le = glam::Vec3::new(18.387, 13.9873, 6.75357);
    let full = g.emission.iter().filter(|&&e| e == le).count();
    let partial = g
        .emission
        .iter()
        .filter(|e| e.x > 0.0 && e.x < le.x)
        .count();
    let zero = g
        .emission
        .iter()
        .filter(|e| **e == glam::Vec3::ZERO)
        .count();
    assert!(full >= 10, "{full} pixels see only the light");
    assert!(partial >= 10, "{partial} pixels on its edges");
    assert_eq!(full + partial + zero, 64 * 64);
    s.params.hide_emitters = true;
    let hidden = mcrt::aov::render_guides(&scene, &s).unwrap();
    assert!(hidden.emission.iter().all(|e| *e == glam::Vec3::ZERO));
    // The other guides do not depend on it.
    assert_eq!(hidden.albedo, g.albedo);
}
