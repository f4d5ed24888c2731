//! The `mcrt` binary on bad and good input: bad input exits with status 2, names the file (and
//! the line and column of the value at fault) and what was expected, never panics and never
//! leaves a file at the output path; good input writes a valid image.

mod common;

use common::cli::*;
use std::path::{Path, PathBuf};
use std::process::Output;

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// A camera so that scenes under test fail on the line they are about, not for want of one.
const CAMERA: &str = r#"[[camera]]
name = "main"
type = "perspective"
origin = [0, 0, 5]
target = [0, 0, 0]
up = [0, 1, 0]
fov = 40
"#;

/// A scene file with an error: the camera above, then `body`.
fn bad_scene(tag: &str, body: &str, where_: Option<Loc>, expect: &[&str]) {
    let dir = TempDir::new(tag);
    let text = format!("{CAMERA}\n{body}");
    let scene = dir.write("scene.toml", &text);
    let out = dir.path().join("out.png");
    check_failure(&dir, &scene, &out, &[], &scene, Some(&text), where_, expect);
}

#[test]
fn toml_syntax_error() {
    bad_scene(
        "syntax",
        "[material.white\ntype = \"lambert\"\nalbedo = 0.5\n",
        Some(Loc {
            line_text: "[material.white",
            at: None,
        }),
        &["expected"],
    );
}

#[test]
fn unknown_key() {
    bad_scene(
        "unknown-key",
        "[material.white]\ntype = \"lambert\"\nalbedo = 0.5\ncolour = 0.5\n",
        loc("colour = 0.5", "colour"),
        &["colour", "expected one of", "albedo"],
    );
}

#[test]
fn unknown_key_for_the_type() {
    bad_scene(
        "foreign-key",
        "[[shape]]\ntype = \"quad\"\nvertices = [[0,0,0],[1,0,0],[1,1,0],[0,1,0]]\nradius = 1\n",
        loc("radius = 1", "1"),
        &["'radius' does not apply to a quad", "vertices"],
    );
}

#[test]
fn unknown_material() {
    bad_scene(
        "unknown-material",
        "[material.white]\ntype = \"lambert\"\nalbedo = 0.5\n\n[[shape]]\ntype = \"sphere\"\nmaterial = \"whte\"\ncenter = [0, 0, 0]\nradius = 1\n",
        loc("material = \"whte\"", "\"whte\""),
        &["unknown material 'whte'", "white"],
    );
}

#[test]
fn wrong_type() {
    bad_scene(
        "wrong-type",
        "[[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = \"one\"\n",
        loc("radius = \"one\"", "\"one\""),
        &["invalid type", "string", "expected"],
    );
}

#[test]
fn wrong_type_in_render() {
    bad_scene(
        "wrong-type-render",
        "[render]\nspp = 4\nwidth = \"big\"\n",
        loc("width = \"big\"", "\"big\""),
        &["invalid type", "expected"],
    );
}

#[test]
fn triangle_with_two_vertices() {
    bad_scene(
        "triangle-2",
        "[[shape]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0]]\n",
        loc("vertices = [[0, 0, 0], [1, 0, 0]]", "[[0"),
        &["needs 3 vertices, found 2"],
    );
}

#[test]
fn negative_radius() {
    bad_scene(
        "negative-radius",
        "[[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1.5\n",
        loc("radius = -1.5", "-1.5"),
        &["'radius' must be a positive number"],
    );
}

#[test]
fn nan_in_colour() {
    bad_scene(
        "nan-colour",
        "[material.white]\ntype = \"lambert\"\nalbedo = [0.5, nan, 0.5]\n",
        loc("albedo = [0.5, nan, 0.5]", "[0.5"),
        &["'albedo' must be finite"],
    );
}

#[test]
fn nan_in_emission() {
    bad_scene(
        "nan-emission",
        "[[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nemission = nan\n",
        loc("emission = nan", "nan"),
        &["'emission' must be finite"],
    );
}

#[test]
fn albedo_above_one() {
    bad_scene(
        "albedo",
        "[material.white]\ntype = \"lambert\"\nalbedo = [0.5, 1.2, 0.5]\n",
        loc("albedo = [0.5, 1.2, 0.5]", "[0.5"),
        &["'albedo' must be at most 1"],
    );
}

#[test]
fn mesh_index_out_of_range() {
    bad_scene(
        "mesh-index",
        "[[shape]]\ntype = \"mesh\"\npositions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nindices = [[0, 1, 3]]\n",
        loc("indices = [[0, 1, 3]]", "[[0"),
        &["index 3 out of range", "3 positions"],
    );
}

#[test]
fn missing_obj_file() {
    bad_scene(
        "missing-obj",
        "[[shape]]\ntype = \"mesh\"\nfile = \"meshes/missing.obj\"\n",
        loc("file = \"meshes/missing.obj\"", "\"meshes"),
        &["'meshes/missing.obj' not found"],
    );
}

#[test]
fn unknown_texture() {
    bad_scene(
        "unknown-texture",
        "[texture.checks]\ntype = \"checkerboard\"\n\n[material.floor]\ntype = \"lambert\"\nalbedo = \"chekcs\"\n",
        loc("albedo = \"chekcs\"", "\"chekcs\""),
        &["unknown texture 'chekcs'", "defined: checks"],
    );
}

#[test]
fn texture_name_where_a_colour_is_needed() {
    bad_scene(
        "texture-intensity",
        "[texture.checks]\ntype = \"checkerboard\"\n\n[[light]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = \"checks\"\n",
        loc("intensity = \"checks\"", "\"checks\""),
        &["'intensity' must be a colour", "not a texture"],
    );
}

#[test]
fn missing_texture_file() {
    bad_scene(
        "missing-texture",
        "[texture.wood]\ntype = \"bitmap\"\nfile = \"textures/wood.png\"\n",
        loc("file = \"textures/wood.png\"", "\"textures"),
        &["texture file 'textures/wood.png' not found"],
    );
}

#[test]
fn alpha_not_positive() {
    bad_scene(
        "alpha-zero",
        "[material.metal]\ntype = \"roughconductor\"\nmaterial = \"Cu\"\nalpha = 0\n",
        loc("alpha = 0", "0"),
        &["'alpha' (microfacet roughness) must be a finite number > 0"],
    );
    bad_scene(
        "alpha-negative",
        "[material.glass]\ntype = \"roughdielectric\"\nalpha_u = 0.1\nalpha_v = -0.2\n",
        loc("alpha_v = -0.2", "-0.2"),
        &["'alpha_v' (microfacet roughness) must be a finite number > 0"],
    );
}

#[test]
fn alpha_and_alpha_u_together() {
    bad_scene(
        "alpha-both",
        "[material.metal]\ntype = \"roughconductor\"\nalpha = 0.1\nalpha_u = 0.2\nalpha_v = 0.3\n",
        loc("alpha = 0.1", "0.1"),
        &["either 'alpha' or 'alpha_u' and 'alpha_v'"],
    );
}

#[test]
fn unknown_conductor_material() {
    bad_scene(
        "conductor-name",
        "[material.metal]\ntype = \"conductor\"\nmaterial = \"Gold\"\n",
        loc("material = \"Gold\"", "\"Gold\""),
        &["unknown conductor material 'Gold'", "none", "Au"],
    );
}

#[test]
fn plastic_specular_above_one() {
    bad_scene(
        "plastic-specular",
        "[material.red]\ntype = \"plastic\"\nalbedo = [0.7, 0.1, 0.1]\nspecular = 1.5\n",
        loc("specular = 1.5", "1.5"),
        &["'specular' must be at most 1"],
    );
}

#[test]
fn unknown_light_type() {
    bad_scene(
        "light-type",
        "[[light]]\ntype = \"projector\"\nposition = [0, 1, 0]\n",
        loc("type = \"projector\"", "\"projector\""),
        &[
            "unknown light type 'projector'",
            "point, directional, spot, constant",
        ],
    );
}

#[test]
fn directional_light_without_direction() {
    bad_scene(
        "light-direction",
        "[[light]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nirradiance = 1\n",
        loc("direction = [0, 0, 0]", "[0"),
        &["'direction' must not be zero"],
    );
}

#[test]
fn bad_rr_depth() {
    bad_scene(
        "rr-depth",
        "[render]\nrr_depth = 0\n",
        loc("rr_depth = 0", "0"),
        &["'rr_depth' must be at least 1"],
    );
}

#[test]
fn unsupported_mesh_file() {
    bad_scene(
        "mesh-ext",
        "[[shape]]\ntype = \"mesh\"\nfile = \"bunny.stl\"\n",
        loc("file = \"bunny.stl\"", "\"bunny"),
        &["expected an .obj or .ply file"],
    );
}

/// A scene that loads `mesh.obj` (written with `obj`); the error must point into the OBJ file.
fn bad_obj(tag: &str, obj: &str, where_: Loc, expect: &[&str]) {
    let dir = TempDir::new(tag);
    let text = format!("{CAMERA}\n[[shape]]\ntype = \"mesh\"\nfile = \"mesh.obj\"\n");
    let scene = dir.write("scene.toml", &text);
    let obj_path = dir.write("mesh.obj", obj);
    let out = dir.path().join("out.png");
    check_failure(
        &dir,
        &scene,
        &out,
        &[],
        &obj_path,
        Some(obj),
        Some(where_),
        expect,
    );
}

#[test]
fn obj_bad_number() {
    bad_obj(
        "obj-number",
        "# a triangle\nv 0 0 0\nv 1 0 0\nv 0 1.x 0\nf 1 2 3\n",
        Loc {
            line_text: "v 0 1.x 0",
            at: Some("1.x"),
        },
        &["expected a finite number", "'1.x'"],
    );
}

#[test]
fn obj_face_index_out_of_range() {
    bad_obj(
        "obj-index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n",
        Loc {
            line_text: "f 1 2 4",
            at: Some("4"),
        },
        &["vertex index 4 out of range", "3"],
    );
}

/// An unknown `--camera NAME` is reported against the scene file, with the names it defines.
#[test]
fn unknown_camera_flag_names_scene_file() {
    let dir = TempDir::new("camera-flag-file");
    let scene = scene_path("tncg15.toml");
    let out = dir.path().join("out.png");
    check_failure(
        &dir,
        &scene,
        &out,
        &["--camera", "eye3"],
        &scene,
        None,
        None,
        &["'eye3'", "eye1, eye2"],
    );
}

/// A scene without a camera is reported against its file.
#[test]
fn scene_without_camera_names_file() {
    let dir = TempDir::new("no-camera");
    let scene = dir.write(
        "scene.toml",
        "[[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
    );
    let out = dir.path().join("out.png");
    check_failure(&dir, &scene, &out, &[], &scene, None, None, &["camera"]);
}

#[test]
fn unknown_output_extension() {
    let dir = TempDir::new("out-ext");
    let out = dir.path().join("out.bmp");
    check_failure(
        &dir,
        &scene_path("tncg15.toml"),
        &out,
        &[],
        &out,
        None,
        None,
        &["unsupported image format", ".png", ".exr"],
    );
}

#[test]
fn output_in_missing_directory() {
    let dir = TempDir::new("out-dir");
    let out = dir.path().join("no").join("such").join("out.png");
    check_failure(
        &dir,
        &scene_path("tncg15.toml"),
        &out,
        &[],
        &out,
        None,
        None,
        &["does not exist"],
    );
}

#[test]
fn rr_survival_out_of_range() {
    let dir = TempDir::new("rr");
    let out = dir.path().join("out.png");
    check_failure(
        &dir,
        &scene_path("tncg15.toml"),
        &out,
        &["--rr-survival", "1.5"],
        Path::new("--rr-survival"),
        None,
        None,
        &["between 0 and 1", "1.5"],
    );
}

#[test]
fn zero_threads() {
    let dir = TempDir::new("threads");
    let out = dir.path().join("out.png");
    check_failure(
        &dir,
        &scene_path("tncg15.toml"),
        &out,
        &["--threads", "0"],
        Path::new("--threads"),
        None,
        None,
        &["at least 1"],
    );
}

#[test]
fn missing_scene_file() {
    let dir = TempDir::new("no-scene");
    let scene = dir.path().join("nope.toml");
    let out = dir.path().join("out.png");
    check_failure(
        &dir,
        &scene,
        &out,
        &[],
        &scene,
        None,
        None,
        &["cannot read scene file"],
    );
}

#[test]
fn unsupported_scene_extension() {
    let dir = TempDir::new("scene-ext");
    let scene = dir.write("scene.blend", "not a scene\n");
    let out = dir.path().join("out.png");
    check_failure(
        &dir,
        &scene,
        &out,
        &[],
        &scene,
        None,
        None,
        &["unsupported scene format", ".toml", ".xml"],
    );
}

const FLAGS: [&str; 15] = [
    "--spp",
    "--width",
    "--height",
    "--seed",
    "--threads",
    "--integrator",
    "--shadow-rays",
    "--rr-survival",
    "--max-depth",
    "--camera",
    "--quiet",
    "--output",
    "--exposure",
    "--tonemap",
    "--half",
];

#[test]
fn help() {
    let o = run(&["--help".as_ref()]);
    assert_eq!(o.status.code(), Some(0));
    let top = String::from_utf8_lossy(&o.stdout);
    assert!(
        top.contains("render"),
        "top-level help lists the render command:\n{top}"
    );

    let o = run(&["render".as_ref(), "--help".as_ref()]);
    assert_eq!(o.status.code(), Some(0));
    let help = String::from_utf8_lossy(&o.stdout);
    for f in FLAGS {
        assert!(
            help.contains(f),
            "render --help should mention {f}:\n{help}"
        );
    }
}

/// Renders scenes/tncg15.toml at 16×16, 2 spp, with `extra` flags; returns the process output.
fn tiny_render(out: &Path, extra: &[&str]) -> Output {
    let scene = scene_path("tncg15.toml");
    let mut args: Vec<&std::ffi::OsStr> = vec!["render".as_ref(), scene.as_os_str()];
    args.push("-o".as_ref());
    args.push(out.as_os_str());
    for a in ["--width", "16", "--height", "16", "--spp", "2"] {
        args.push(a.as_ref());
    }
    for a in extra {
        args.push(a.as_ref());
    }
    let o = run(&args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "render failed:\n{}",
        stderr_of(&o)
    );
    o
}

#[test]
fn tiny_render_png_and_exr() {
    let dir = TempDir::new("render");

    let png = dir.path().join("room.png");
    let o = tiny_render(&png, &[]);
    let err = stderr_of(&o);
    // stderr is a pipe here: the summary line, and no progress bar.
    assert!(err.contains("samples/s"), "summary line: {err:?}");
    assert!(err.contains("rays/s"), "summary line: {err:?}");
    assert_eq!(err.lines().count(), 1, "only the summary line: {err:?}");
    assert!(
        !err.contains('\r') && !err.contains('\u{1b}') && !err.contains("ETA"),
        "no progress bar when stderr is not a terminal: {err:?}"
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    assert_eq!((be(16), be(20)), (16, 16), "PNG size");
    assert_eq!((bytes[24], bytes[25]), (8, 2), "8-bit RGB");

    let exr = dir.path().join("room.exr");
    let o = tiny_render(&exr, &["--quiet"]);
    assert!(
        o.stderr.is_empty(),
        "--quiet prints nothing: {:?}",
        stderr_of(&o)
    );
    assert!(o.stdout.is_empty());
    let img = mcrt::image::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (16, 16));
    assert!(img
        .pixels
        .iter()
        .all(|p| p.is_finite() && p.min_element() >= 0.0));
    assert!(
        img.pixels.iter().any(|p| p.max_element() > 0.0),
        "the room is lit"
    );

    let half = dir.path().join("room-half.exr");
    tiny_render(&half, &["-q", "--half"]);
    let img_h = mcrt::image::read_exr(&half).unwrap();
    assert_eq!((img_h.width, img_h.height), (16, 16));
    for (a, b) in img.pixels.iter().zip(&img_h.pixels) {
        assert!(
            (*a - *b).abs().max_element() <= 1e-3 * a.max_element().max(1.0),
            "{a} vs {b}"
        );
    }

    // Nothing but the three images is left behind (no temporary files).
    assert_eq!(dir.listing(), vec!["room-half.exr", "room.exr", "room.png"]);
}

/// With Mitsuba's meaning of max_depth, a path of 0 segments carries no light: the image is
/// black, even where the light is seen directly.
#[test]
fn max_depth_zero_is_black() {
    let dir = TempDir::new("depth0");
    let exr = dir.path().join("d0.exr");
    tiny_render(&exr, &["-q", "--max-depth", "0"]);
    let img = mcrt::image::read_exr(&exr).unwrap();
    let lit = img.pixels.iter().filter(|p| p.max_element() > 0.0).count();
    assert_eq!(lit, 0, "max_depth 0 should give a black image");
}

/// Photon maps that would not fit in memory are refused before any photon is traced.
#[test]
fn photon_maps_beyond_memory_are_refused() {
    let dir = TempDir::new("photon-memory");
    let out = dir.path().join("out.png");
    let scene = scene_path("tncg15.toml");
    let o = run(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--integrator".as_ref(),
        "photon".as_ref(),
        "--photons".as_ref(),
        "1000000000".as_ref(),
    ]);
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for want in ["photon maps", "GiB", "fewer photons"] {
        assert!(err.contains(want), "{want:?} missing from:\n{err}");
    }
    assert!(!out.exists());
}

/// `MCRT_MAX_ISA=avx2` keeps AVX-512 code from running (`mcrt::cpu`): the image is the same
/// bits as uncapped (every kernel computes the same), `--backend avx512` is refused under it,
/// and a value outside the accepted ones is refused with status 2 and nothing written.
#[test]
fn max_isa_caps_the_kernels_not_the_image() {
    let dir = TempDir::new("max-isa");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/cornell-box.xml");
    let render = |cap: &str, name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let o = std::process::Command::new(BIN)
            .env("MCRT_MAX_ISA", cap)
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["--spp", "4", "--width", "48", "--height", "48", "-q"])
            .args(extra)
            .output()
            .expect("cannot run the mcrt binary");
        (o, out)
    };
    let (o, plain) = render("", "plain.exr", &[]);
    assert!(o.status.success(), "{}", stderr_of(&o));
    let (o, capped) = render("avx2", "avx2.exr", &[]);
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert_eq!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&capped).unwrap()
    );
    let (o, out) = render("avx2", "refused.exr", &["--backend", "avx512"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr_of(&o));
    assert!(stderr_of(&o).contains("MCRT_MAX_ISA"), "{}", stderr_of(&o));
    assert!(!out.exists());
    let (o, out) = render("sse", "bad.exr", &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr_of(&o));
    for want in ["MCRT_MAX_ISA", "\"sse\"", "avx512", "avx2"] {
        assert!(
            stderr_of(&o).contains(want),
            "{want:?} missing from:\n{}",
            stderr_of(&o)
        );
    }
    assert!(!out.exists());
}
