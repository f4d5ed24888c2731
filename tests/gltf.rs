//! glTF 2.0 scenes (tests/data/gltf, written by make_scene.py): the three encodings of the
//! scene load alike, and the render agrees with Mitsuba 3's render of the scene's XML twin.
//! See docs/gltf.md.

mod common;

use common::*;
use mcrt::scene::desc::FileSettings;

const SCENE: &str = "tests/data/gltf/scene.gltf";

/// The description without its warnings (which name the file).
fn described(rel: &str) -> String {
    let mut desc = mcrt::load_scene(&project_path(rel)).expect("scene loads");
    desc.warnings.clear();
    format!("{desc:?}")
}

/// `.gltf` with an external buffer and image, `.gltf` with data: URIs and `.glb` with the
/// image in its binary chunk describe the same scene.
#[test]
fn gltf_glb_and_embedded_load_the_same_scene() {
    let a = described(SCENE);
    assert_eq!(a, described("tests/data/gltf/scene.glb"));
    assert_eq!(a, described("tests/data/gltf/scene_embedded.gltf"));
}

/// The scene's contents: the mesh used by two nodes is copied, the camera is named by its
/// node and by itself, and the aspect ratio sizes the image.
#[test]
fn scene_contents() {
    let desc = mcrt::load_scene(&project_path(SCENE)).unwrap();
    assert_eq!(desc.shapes.len(), 6, "floor, wall, two cubes, glass, panel");
    let names: Vec<&str> = desc.cameras.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["MainCam", "Lens"]);
    assert_eq!(
        (desc.settings.width, desc.settings.height),
        (Some(512), Some(341))
    );
    assert_eq!(desc.lights.len(), 1);
    assert_eq!(
        desc.shapes.iter().filter(|s| s.emission.is_some()).count(),
        1
    );
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
}

fn render_scene(spp: u32) -> Rendered {
    let (scene, fs) = load(SCENE);
    let s = settings(
        &fs,
        FileSettings {
            spp: Some(spp),
            width: Some(96),
            height: Some(64),
            ..Default::default()
        },
    );
    render_with(&scene, &s)
}

/// The glTF render against Mitsuba 3's render of twin.xml, whose meshes are placed by world
/// matrices make_scene.py computes from the specification and whose BSDFs are those
/// docs/gltf.md maps glTF materials to: equal up to noise, so the axes, the camera, the
/// winding, the light units, the texture coordinates and KHR_texture_transform agree.
#[test]
fn renders_like_its_mitsuba_twin() {
    let r = render_scene(256);
    BlockComparison::new(&r, &reference("gltf-twin.exr"), 8, 4096).assert_within_noise(SCENE);
}
