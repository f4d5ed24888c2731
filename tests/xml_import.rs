//! The Mitsuba 3 XML importer: document features (defaults, -D, includes, references),
//! transforms, and clean failures (file:line:col, status 2, nothing written) on what it does
//! not support. Image agreement with Mitsuba is in reference.rs and xml_features.rs.

mod common;

use common::cli::*;
use glam::Vec3;
use mcrt::scene::desc::{FileSettings, GeometryDesc};
use mcrt::scene::SceneDesc;
use mcrt::LoadOptions;
use std::path::Path;

const SENSOR: &str = r#"<sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>"#;

fn scene_xml(body: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<scene version=\"3.0.0\">\n    {SENSOR}\n{body}\n</scene>\n")
}

fn load_with(path: &Path, defines: &[(&str, &str)]) -> Result<SceneDesc, mcrt::Error> {
    mcrt::load_scene_with(
        path,
        &LoadOptions {
            defines: defines
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            lenient: false,
        },
    )
}

/// An XML scene that must fail: status 2 and a message at the line of `line_text`, column
/// of `at`, containing each of `expect`.
fn bad_xml(tag: &str, body: &str, line_text: &'static str, at: &'static str, expect: &[&str]) {
    let dir = TempDir::new(tag);
    let text = scene_xml(body);
    let scene = dir.write("scene.xml", &text);
    let out = dir.path().join("out.exr");
    check_failure(
        &dir,
        &scene,
        &out,
        &[],
        &scene,
        Some(&text),
        loc(line_text, at),
        expect,
    );
}

#[test]
fn unknown_bsdf_names_what_is_supported() {
    bad_xml(
        "xml-bsdf",
        r#"<shape type="sphere"><bsdf type="hair"/></shape>"#,
        "<bsdf type=\"hair\"/>",
        "hair",
        &["bsdf 'hair' is not supported", "diffuse", "--lenient"],
    );
}

#[test]
fn lenient_renders_unknown_bsdfs_grey_and_says_so() {
    let dir = TempDir::new("xml-lenient");
    let scene = dir.write(
        "scene.xml",
        &scene_xml(
            r#"<shape type="sphere"><bsdf type="hair"/></shape>
            <shape type="sphere"><point name="center" value="1, 0, 0"/><bsdf type="roughconductor"/></shape>
            <emitter type="constant"/>"#,
        ),
    );
    let out = dir.path().join("out.exr");
    let o = run(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--lenient".as_ref(),
        "--spp".as_ref(),
        "2".as_ref(),
    ]);
    let err = stderr_of(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("bsdf 'hair' replaced by grey diffuse"),
        "{err}"
    );
    // Beckmann (the roughconductor's default) is rendered as such: no stand-in, no warning.
    assert_eq!(err.matches("--lenient").count(), 1, "{err}");
    assert!(out.exists());
}

#[test]
fn misspelt_property_is_an_error() {
    bad_xml(
        "xml-prop",
        r#"<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectence" value="0.5"/></bsdf></shape>"#,
        "<rgb name=\"reflectence\"",
        "<rgb",
        &["no parameter 'reflectence'", "supported: reflectance"],
    );
}

#[test]
fn wrong_property_type_is_an_error() {
    bad_xml(
        "xml-type",
        r#"<shape type="sphere"><string name="radius" value="big"/></shape>"#,
        "<string name=\"radius\"",
        "<string",
        &["'radius'", "must be a <float>"],
    );
}

#[test]
fn unknown_shape_and_emitter() {
    bad_xml(
        "xml-shape",
        r#"<shape type="sdfgrid"/>"#,
        "sdfgrid",
        "sdfgrid",
        &["shape 'sdfgrid' is not supported", "ply"],
    );
    bad_xml(
        "xml-emitter",
        r#"<emitter type="projector"/>"#,
        "projector",
        "projector",
        &["emitter 'projector' is not supported", "spot and envmap"],
    );
}

#[test]
fn malformed_xml_gives_line_and_column() {
    bad_xml(
        "xml-syntax",
        "<shape type=\"sphere\">\n<float name=\"radius\" value=\"1\">\n</shape>",
        "</shape>",
        "</shape>",
        &["malformed XML"],
    );
}

#[test]
fn undefined_parameter_and_missing_reference() {
    bad_xml(
        "xml-param",
        r#"<shape type="sphere"><float name="radius" value="$size"/></shape>"#,
        "$size",
        "$size",
        &["undefined parameter '$size'", "-D size="],
    );
    bad_xml(
        "xml-ref",
        r#"<shape type="sphere"><ref id="nothing"/></shape>"#,
        "nothing",
        "nothing",
        &["no object has id 'nothing'"],
    );
}

#[test]
fn defaults_are_overridden_by_dash_d() {
    let dir = TempDir::new("xml-defaults");
    let text = r#"<scene version="3.0.0">
    <default name="res" value="32"/>
    <default name="r" value="0.5"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film>
    </sensor>
    <shape type="sphere"><float name="radius" value="$r"/></shape>
</scene>"#;
    let scene = dir.write("scene.xml", text);
    let d = load_with(&scene, &[]).unwrap();
    assert_eq!(d.settings.width, Some(32));
    let d = load_with(&scene, &[("res", "16"), ("r", "2")]).unwrap();
    assert_eq!(d.settings.width, Some(16));
    match &d.shapes[0].geometry {
        GeometryDesc::Sphere { radius, .. } => assert_eq!(*radius, 2.0),
        g => panic!("{g:?}"),
    }
}

#[test]
fn includes_share_ids_and_cycles_are_refused() {
    let dir = TempDir::new("xml-include");
    dir.write(
        "materials.xml",
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf></scene>"#,
    );
    let scene = dir.write(
        "scene.xml",
        &scene_xml(
            r#"<include filename="materials.xml"/>
            <shape type="sphere"><ref id="red"/></shape>"#,
        ),
    );
    let d = load_with(&scene, &[]).unwrap();
    assert_eq!(d.materials.len(), 1);
    assert_eq!(d.materials[0].albedo(), Vec3::new(0.8, 0.1, 0.1));

    let a = dir.write(
        "a.xml",
        r#"<scene version="3.0.0"><include filename="b.xml"/></scene>"#,
    );
    dir.write(
        "b.xml",
        r#"<scene version="3.0.0"><include filename="a.xml"/></scene>"#,
    );
    let e = load_with(&a, &[]).unwrap_err().to_string();
    assert!(e.contains("include cycle"), "{e}");
    assert!(
        e.contains("b.xml:1:"),
        "the error points at the include: {e}"
    );
}

/// Transforms compose in Mitsuba's order (each after the ones above it), and the rectangle,
/// cube and lookat conventions match Mitsuba's.
#[test]
fn transforms_compose_in_mitsuba_order() {
    let dir = TempDir::new("xml-transform");
    let scene = dir.write(
        "scene.xml",
        &scene_xml(
            r#"<shape type="rectangle">
                <transform name="to_world">
                    <scale x="2" y="3" z="1"/>
                    <rotate x="1" angle="90"/>
                    <translate x="10"/>
                </transform>
            </shape>
            <shape type="cube">
                <transform name="to_world">
                    <matrix value="1 0 0 5  0 1 0 0  0 0 1 0  0 0 0 1"/>
                </transform>
            </shape>"#,
        ),
    );
    let d = load_with(&scene, &[]).unwrap();
    let GeometryDesc::Mesh(rect) = &d.shapes[0].geometry else {
        panic!()
    };
    // (1, 1, 0) → scale (2, 3, 0) → rotate 90° about x: (2, 0, 3) → translate (12, 0, 3).
    let p = rect.positions[2];
    assert!((p - Vec3::new(12.0, 0.0, 3.0)).length() < 1e-5, "{p:?}");
    // The rectangle's front (+z locally) now faces −y.
    let [a, b, c] = rect.indices[0].map(|i| rect.positions[i as usize]);
    let n = (b - a).cross(c - a).normalize();
    assert!((n - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-5, "{n:?}");
    let GeometryDesc::Mesh(cube) = &d.shapes[1].geometry else {
        panic!()
    };
    assert_eq!(cube.indices.len(), 12);
    let centre: Vec3 = cube.positions.iter().sum::<Vec3>() / cube.positions.len() as f32;
    assert!((centre - Vec3::new(5.0, 0.0, 0.0)).length() < 1e-5);
    // Every face points away from the centre.
    for t in &cube.indices {
        let [a, b, c] = t.map(|i| cube.positions[i as usize]);
        assert!((b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) > 0.0);
    }
}

/// A crop window renders exactly the pixels of the full image it covers.
#[test]
fn crop_window_equals_the_full_image_there() {
    let dir = TempDir::new("xml-crop");
    let body = r#"<shape type="sphere"><bsdf type="diffuse"/></shape>
        <emitter type="constant"/>"#;
    let full = dir.write("full.xml", &scene_xml(body));
    let crop_text = scene_xml(body).replace(
        r#"<integer name="height" value="8"/>"#,
        r#"<integer name="height" value="8"/>
            <integer name="crop_offset_x" value="2"/><integer name="crop_offset_y" value="3"/>
            <integer name="crop_width" value="4"/><integer name="crop_height" value="5"/>"#,
    );
    let crop = dir.write("crop.xml", &crop_text);
    let render = |p: &Path| {
        let desc = load_with(p, &[]).unwrap();
        let fs = desc.settings.clone();
        let scene = mcrt::scene::Scene::build(desc);
        let s = mcrt::resolve_settings(
            &fs,
            &FileSettings {
                spp: Some(4),
                ..Default::default()
            },
            None,
        )
        .unwrap();
        mcrt::render::render(&scene, &s, &|_| {}).unwrap().0.image()
    };
    let a = render(&full);
    let b = render(&crop);
    assert_eq!((b.width, b.height), (4, 5));
    for y in 0..5 {
        for x in 0..4 {
            assert_eq!(b.get(x, y), a.get(x + 2, y + 3), "pixel ({x}, {y})");
        }
    }
}

/// The microfacet distribution of each rough BSDF of `body`, in order.
fn distributions(tag: &str, body: &str) -> Vec<(mcrt::material::MicrofacetType, f32, f32)> {
    let dir = TempDir::new(tag);
    let scene = dir.write("scene.xml", &scene_xml(body));
    let d = load_with(&scene, &[]).unwrap();
    d.materials
        .iter()
        .map(|m| {
            let distr = m
                .bsdf
                .microfacet()
                .unwrap_or_else(|| panic!("not rough: {:?}", m.bsdf));
            (distr.kind, distr.alpha_u, distr.alpha_v)
        })
        .collect()
}

/// As in Mitsuba, rough BSDFs without `distribution` are Beckmann; `ggx` and `beckmann` are
/// accepted in any case, with `alpha` or `alpha_u` and `alpha_v`.
#[test]
fn rough_bsdfs_default_to_beckmann() {
    use mcrt::material::MicrofacetType::{Beckmann, Ggx};
    let got = distributions(
        "xml-beckmann",
        r#"<shape type="sphere"><bsdf type="roughconductor"/></shape>
        <shape type="sphere"><bsdf type="roughdielectric"><float name="alpha" value="0.3"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughplastic"><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughconductor"><string name="distribution" value="GGX"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughdielectric"><string name="distribution" value="beckmann"/>
            <float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.4"/></bsdf></shape>"#,
    );
    assert_eq!(
        got,
        vec![
            (Beckmann, 0.1, 0.1),
            (Beckmann, 0.3, 0.3),
            (Beckmann, 0.2, 0.2),
            (Ggx, 0.1, 0.1),
            (Beckmann, 0.1, 0.4),
        ]
    );
}

#[test]
fn unknown_distribution_is_an_error_at_its_value() {
    bad_xml(
        "xml-distribution",
        r#"<shape type="sphere"><bsdf type="roughplastic"><string name="distribution" value="phong"/></bsdf></shape>"#,
        "<string name=\"distribution\" value=\"phong\"/>",
        "phong",
        &["distribution 'phong': expected beckmann or ggx"],
    );
}
