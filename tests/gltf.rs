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

/// The scene's contents: the mesh used by two nodes is one shape group placed by two
/// instances (at the nodes' world matrices), the camera is named by its node and by itself,
/// and the aspect ratio sizes the image.
#[test]
fn scene_contents() {
    let desc = mcrt::load_scene(&project_path(SCENE)).unwrap();
    assert_eq!(desc.shapes.len(), 4, "floor, wall, glass, panel");
    assert_eq!(desc.groups.len(), 1, "the cube");
    assert_eq!(desc.groups[0].shapes.len(), 1);
    assert!(
        desc.groups[0].name.contains("cube"),
        "{}",
        desc.groups[0].name
    );
    assert_eq!(desc.instances.len(), 2, "CubeA and CubeB");
    assert!(desc.instances.iter().all(|i| i.group == 0));
    // CubeA: Group (translation (−0.4, 0, 0.2), scale 0.8) × CubeA (translation
    // (−0.6, 0.5, 0), 30° about +y): its origin lands at (−0.88, 0.4, 0.2).
    let o = desc.instances[0]
        .to_world
        .transform_point3(glam::Vec3::ZERO);
    assert!(
        (o - glam::Vec3::new(-0.88, 0.4, 0.2)).length() < 1e-5,
        "{o}"
    );
    let det = desc.instances[1].to_world.matrix3.determinant();
    assert!((det - 0.8f32.powi(3)).abs() < 1e-5, "{det}");
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

/// The glTF render against Mitsuba 3's renders of its twins.
///
/// twin-principled.xml places the meshes by world matrices that make_scene.py computes from
/// the specification, with Mitsuba's `principled` BSDF, which renders glTF materials
/// (docs/gltf.md): the render must equal it up to noise, so the axes, the camera, the
/// winding, the light units, the texture coordinates and KHR_texture_transform agree.
///
/// twin.xml renders the same materials with the rough conductor, dielectric and plastic
/// BSDFs of the earlier mapping: each block may differ from it by the BRDF difference,
/// measured between the two Mitsuba renders, plus noise; and the image as a whole by at
/// most 3 % (between the two Mitsuba renders: 1.5 % as a whole, median block 1.4 %, largest
/// 6.6 %, 2026-12-03).
#[test]
fn renders_like_its_mitsuba_twins() {
    let r = render_scene(256);
    let twin = BlockComparison::new(&r, &reference("gltf-twin-principled.exr"), 8, 4096);
    twin.assert_within_noise(SCENE);
    let pr = BlockComparison::new(&r, &reference("gltf-twin.exr"), 8, 4096);
    let n = twin.mine.len();
    for i in 0..n {
        let brdf = (twin.reference[i] - pr.reference[i]).abs();
        let noise = Z * (twin.sigma[i].powi(2) + pr.sigma[i].powi(2)).sqrt();
        let diff = (pr.mine[i] - pr.reference[i]).abs();
        assert!(
            diff <= brdf + noise,
            "block {i}: mcrt {:.4} vs the rough-BSDF twin {:.4}: beyond the BRDF difference {brdf:.4} \
             plus noise {noise:.4}",
            pr.mine[i],
            pr.reference[i]
        );
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let rel = (mean(&pr.mine) / mean(&pr.reference) - 1.0).abs();
    let median = {
        let mut d: Vec<f64> = (0..n)
            .filter(|&i| pr.reference[i] > 0.01)
            .map(|i| (pr.mine[i] / pr.reference[i] - 1.0).abs())
            .collect();
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    };
    eprintln!(
        "against the rough-BSDF twin: image mean {:.2} %, median block {:.2} %",
        100.0 * rel,
        100.0 * median
    );
    assert!(
        rel < 0.03,
        "the image mean differs from the rough-BSDF twin's by {:.2} %",
        100.0 * rel
    );
}

/// A one-triangle glTF with a camera and an emissive material; `camera` is the camera
/// object, `material` the material, `extra` more top-level members (each with a leading
/// comma) and `nodes` more nodes after the two (mesh, camera).
fn triangle(camera: &str, material: &str, nodes: &str, extra: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
 "scenes": [{{"nodes": [0, 1{roots}]}}],
 "nodes": [{{"mesh": 0}}, {{"name": "Cam", "camera": 0, "translation": [0, 0, 3]}}{nodes}],
 "cameras": [{camera}],
 "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
 "materials": [{material}],
 "buffers": [{{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=", "byteLength": 44}}],
 "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
 "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
               {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}]{extra}}}"#,
        roots = if nodes.is_empty() { "" } else { ", 2" },
    )
}

const PERSPECTIVE: &str = r#"{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}"#;
const EMISSIVE: &str = r#"{"emissiveFactor": [1, 1, 1]}"#;

fn parse(json: &str, lenient: bool) -> Result<mcrt::scene::SceneDesc, mcrt::scene::SceneError> {
    mcrt::scene::gltf::parse_gltf(std::path::Path::new("t.gltf"), json.as_bytes(), lenient)
}

/// An orthographic camera: parallel rays along −z; `xmag/ymag` sizes the image.
#[test]
fn orthographic_camera() {
    let cam = r#"{"type": "orthographic", "orthographic": {"xmag": 3, "ymag": 2, "znear": 0.5, "zfar": 100}}"#;
    let desc = parse(&triangle(cam, EMISSIVE, "", ""), false).unwrap();
    match &desc.cameras[0].1 {
        mcrt::camera::CameraDesc::Orthographic {
            center,
            half_x,
            half_y,
            dir,
        } => {
            assert_eq!(*dir, glam::Vec3::NEG_Z);
            assert_eq!(*center, glam::Vec3::new(0.0, 0.0, 2.5));
            assert_eq!(*half_x, glam::Vec3::new(-3.0, 0.0, 0.0));
            assert_eq!(*half_y, glam::Vec3::new(0.0, 3.0, 0.0));
        }
        c => panic!("not orthographic: {c:?}"),
    }
    assert_eq!(
        (desc.settings.width, desc.settings.height),
        (Some(512), Some(341))
    );
}

/// Approximations are refused by default, naming the first and counting the rest; with
/// `--lenient` each is one warning line. A spot light (default cone: 0° to 45°) is exact.
#[test]
fn approximations_refused_unless_lenient() {
    let mat = r#"{"emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"metallicFactor": 0.3},
        "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0},
                       "KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1]}}}"#;
    let lights = r#", "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "spot": {}, "intensity": 683}]}}"#;
    let node = r#", {"extensions": {"KHR_lights_punctual": {"light": 0}}}"#;
    let json = triangle(PERSPECTIVE, mat, node, lights);
    let err = parse(&json, false).unwrap_err().to_string();
    assert!(
        err.contains("the clearcoat layer is rendered as principled"),
        "{err}"
    );
    assert!(
        err.contains("(and 1 more)") && err.contains("--lenient"),
        "{err}"
    );
    let desc = parse(&json, true).unwrap();
    let approx: Vec<&String> = desc
        .warnings
        .iter()
        .filter(|w| w.contains("approximated:"))
        .collect();
    assert_eq!(approx.len(), 2, "{:?}", desc.warnings);
    assert!(approx.iter().any(|w| w.contains("sheen")));
    // The layers are principled's clearcoat and sheen (Blender's importer maps them so).
    let coated = desc.materials.iter().any(|m| {
        matches!(m.bsdf, mcrt::material::Bsdf::Principled(p)
            if p.clearcoat == 1.0 && p.clearcoat_gloss == 1.0 && p.sheen == 1.0)
    });
    assert!(coated, "{:?}", desc.materials);
    // The spot light is Mitsuba's spot; its edge's falloff is a note in both modes.
    assert!(desc.warnings.iter().any(|w| w.contains("fades linearly")));
    assert!(matches!(
        desc.lights[0],
        mcrt::scene::desc::LightDesc::Spot { cutoff_angle, beam_width, .. }
            if (cutoff_angle - 45.0).abs() < 1e-4 && beam_width == 0.0
    ));
}

/// A normal texture becomes the material's normal map (linear values, glTF's `scale` on x
/// and y); a material without one has none.
#[test]
fn normal_texture_is_a_normal_map() {
    let png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAIAAACQd1PeAAAADElEQVR4nGNoaPgPAAODAgAApfuJAAAAAElFTkSuQmCC";
    let mat = r#"{"emissiveFactor": [1, 1, 1], "normalTexture": {"index": 0, "scale": 0.5}}"#;
    let extra = format!(
        r#", "textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{png}"}}]"#
    );
    let desc = parse(&triangle(PERSPECTIVE, mat, "", &extra), false).unwrap();
    let t = desc.materials[0].normal_map.expect("a normal map") as usize;
    // The 1×1 image is (128, 128, 255): x, y near 0 stay there; z = 1.
    let c = desc.textures[t].eval(glam::Vec2::splat(0.5));
    assert!(
        (c.x - 0.5).abs() < 0.01 && (c.y - 0.5).abs() < 0.01 && c.z == 1.0,
        "{c}"
    );
    let plain = parse(&triangle(PERSPECTIVE, EMISSIVE, "", ""), false).unwrap();
    assert!(plain.materials[0].normal_map.is_none());
}

/// A mesh used by two nodes is instanced, unless it emits (groups may not) or a node mirrors
/// it (glTF reverses the winding there): then each node gets a copy.
#[test]
fn reused_meshes_are_instanced_unless_emissive_or_mirrored() {
    let light = r#", "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 683}]}}"#;
    let second = |t: &str| {
        format!(
            r#", {{"mesh": 0, {t}, "children": [3]}}, {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}}"#
        )
    };
    let moved = second(r#""translation": [2, 0, 0]"#);
    let desc = parse(&triangle(PERSPECTIVE, "{}", &moved, light), false).unwrap();
    assert_eq!((desc.shapes.len(), desc.groups.len()), (0, 1));
    let at: Vec<glam::Vec3> = desc
        .instances
        .iter()
        .map(|i| i.to_world.transform_point3(glam::Vec3::X))
        .collect();
    assert_eq!(at, [glam::Vec3::X, glam::Vec3::new(3.0, 0.0, 0.0)]);
    let mirrored = second(r#""scale": [-1, 1, 1]"#);
    let desc = parse(&triangle(PERSPECTIVE, "{}", &mirrored, light), false).unwrap();
    assert_eq!((desc.shapes.len(), desc.groups.len()), (2, 0));
    assert!(desc.instances.is_empty());
    let desc = parse(&triangle(PERSPECTIVE, EMISSIVE, &moved, light), false).unwrap();
    assert_eq!((desc.shapes.len(), desc.groups.len()), (2, 0));
    assert!(desc.shapes.iter().all(|s| s.emission.is_some()));
}

/// A 2×1 PNG: texels (51, 102, 204) and (255, 25, 0), sampled nearest, as glTF textures
/// 0 (`extra` members for [`triangle`]).
const TWO_TEXELS: &str = r#", "textures": [{"source": 0, "sampler": 0}], "samplers": [{"magFilter": 9728}],
 "images": [{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAABCAIAAAB7QOjdAAAAD0lEQVR4nGMwTjvzX5IBAAmWAn4aWbVmAAAAAElFTkSuQmCC"}]"#;

/// The uv of each texel of [`TWO_TEXELS`].
const TEXELS: [glam::Vec2; 2] = [glam::Vec2::new(0.25, 0.5), glam::Vec2::new(0.75, 0.5)];

/// metallicRoughnessTexture (B metalness, G roughness, linear) and KHR_materials_transmission's
/// texture (R) are bound to principled's `metallic`, `roughness` and `spec_trans` slots: at
/// a hit they take the texel's channel times the factor; the BSDF's constant is the mean.
#[test]
fn metallic_roughness_and_transmission_textures_are_exact() {
    let mat = r#"{"emissiveFactor": [1, 1, 1],
        "pbrMetallicRoughness": {"metallicFactor": 0.5, "metallicRoughnessTexture": {"index": 0}},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0, "transmissionTexture": {"index": 0}}}}"#;
    let desc = parse(&triangle(PERSPECTIVE, mat, "", TWO_TEXELS), false).unwrap();
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let principled = |m: &mcrt::material::Material| match &m.bsdf {
        mcrt::material::Bsdf::Principled(b) => {
            glam::Vec3::new(b.metallic, b.roughness, b.spec_trans)
        }
        b => panic!("not principled: {b:?}"),
    };
    let m = &desc.materials[0];
    // (metallic, roughness, spec_trans) at each texel.
    let want = [
        glam::Vec3::new(0.5 * 204.0 / 255.0, 102.0 / 255.0, 51.0 / 255.0),
        glam::Vec3::new(0.0, 25.0 / 255.0, 1.0),
    ];
    for (uv, w) in TEXELS.iter().zip(want) {
        let got = principled(&m.at(&desc.materials, &desc.textures, *uv, None));
        assert!(got.abs_diff_eq(w, 1e-5), "at {uv}: {got}, want {w}");
    }
    let c = principled(m);
    let mean = 0.5 * (want[0] + want[1]);
    assert!(c.abs_diff_eq(mean, 1e-5), "constants {c}, want {mean}");
}

/// An emissive texture makes the area light's radiance a texture (sRGB) times emissiveFactor
/// × emissive strength; the shape's emission is its mean.
#[test]
fn emissive_texture_is_the_lights_radiance() {
    let mat = r#"{"emissiveFactor": [1, 0.5, 1], "emissiveTexture": {"index": 0},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}}}"#;
    let desc = parse(&triangle(PERSPECTIVE, mat, "", TWO_TEXELS), false).unwrap();
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let [(0, t)] = desc.emission_textures[..] else {
        panic!("{:?}", desc.emission_textures)
    };
    let tex = &desc.textures[t as usize];
    let srgb = |c: f32| {
        let c = c / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let scale = mcrt::Color::new(2.0, 1.0, 2.0);
    for (uv, px) in TEXELS
        .iter()
        .zip([[51.0, 102.0, 204.0], [255.0, 25.0, 0.0]])
    {
        let want = scale * mcrt::Color::new(srgb(px[0]), srgb(px[1]), srgb(px[2]));
        let got = tex.eval(*uv);
        assert!(
            (got - want).abs().max_element() < 1e-3,
            "at {uv}: {got}, want {want}"
        );
    }
    assert_eq!(desc.shapes[0].emission, Some(tex.mean()));
}

/// Factors are checked, KHR_materials_specular's too, before they scale any texture.
#[test]
fn negative_specular_factor_is_refused() {
    let mat = r#"{"emissiveFactor": [1, 1, 1],
        "extensions": {"KHR_materials_specular": {"specularFactor": -1}}}"#;
    let err = parse(&triangle(PERSPECTIVE, mat, "", ""), true)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("specular") && err.contains("out of range"),
        "{err}"
    );
}

/// [`triangle`] with a TANGENT accessor: `data` is the base64 of its 44-byte buffer followed
/// by three VEC4 tangents, `node` more members of the mesh's node.
fn with_tangents(data: &str, node: &str, material: &str, extra: &str) -> String {
    triangle(PERSPECTIVE, material, "", extra)
        .replace(
            r#"base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=", "byteLength": 44"#,
            &format!(r#"base64,{data}", "byteLength": 92"#),
        )
        .replace(r#"{"POSITION": 0}"#, r#"{"POSITION": 0, "TANGENT": 2}"#)
        .replace(
            r#""byteOffset": 36, "byteLength": 6}"#,
            r#""byteOffset": 36, "byteLength": 6}, {"buffer": 0, "byteOffset": 44, "byteLength": 48}"#,
        )
        .replace(
            r#""type": "SCALAR"}]"#,
            r#""type": "SCALAR"}, {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"}]"#,
        )
        .replace(r#""nodes": [{"mesh": 0}"#, &format!(r#""nodes": [{{"mesh": 0{node}}}"#))
}

fn mesh_tangents(desc: &mcrt::scene::SceneDesc) -> Option<Vec<glam::Vec4>> {
    match &desc.shapes[0].geometry {
        mcrt::scene::desc::GeometryDesc::Mesh(m) => m.tangents.clone(),
        g => panic!("not a mesh: {g:?}"),
    }
}

/// TANGENT (glTF 2.0 §3.7.2.1) is read per vertex and carried to world space like a
/// direction, normalized, its bitangent sign w kept; a mirroring node flips w.
#[test]
fn tangents_are_read_and_transformed() {
    // Tangents (1, 0, 0, 1), (0, 1, 0, −1), (1, 1, 0, 1).
    let data = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAgD8AAAAAAACAvwAAgD8AAIA/AAAAAAAAgD8=";
    let load = |node: &str| {
        let desc = parse(&with_tangents(data, node, EMISSIVE, ""), false).unwrap();
        mesh_tangents(&desc).expect("tangents")
    };
    let close = |a: &[glam::Vec4], b: &[glam::Vec4]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (*x - *y).length() < 1e-6)
    };
    let s = 5f32.sqrt();
    let t = load(r#", "scale": [2, 1, 1]"#);
    let want = [
        glam::Vec4::new(1.0, 0.0, 0.0, 1.0),
        glam::Vec4::new(0.0, 1.0, 0.0, -1.0),
        glam::Vec4::new(2.0 / s, 1.0 / s, 0.0, 1.0),
    ];
    assert!(close(&t, &want), "{t:?}");
    let t = load(r#", "scale": [-1, 1, 1]"#);
    let h = 0.5f32.sqrt();
    let want = [
        glam::Vec4::new(-1.0, 0.0, 0.0, -1.0),
        glam::Vec4::new(0.0, 1.0, 0.0, 1.0),
        glam::Vec4::new(-h, h, 0.0, -1.0),
    ];
    assert!(close(&t, &want), "{t:?}");
    // Without TANGENT there are none.
    let desc = parse(&triangle(PERSPECTIVE, EMISSIVE, "", ""), false).unwrap();
    assert!(mesh_tangents(&desc).is_none());
}

/// At a hit, a normal texture tilted 45° towards +x of tangent space tilts the shading
/// normal towards dp/du = +x without TANGENT (no uvs: the barycentric partials, edge
/// p1 − p0), towards the vertex tangent +y with TANGENT (0, 1, 0, 1).
#[test]
fn normal_map_frame_follows_tangents_at_hits() {
    use mcrt::geometry::Ray;
    // A 1×1 PNG of (218, 128, 218): 2c − 1 ≈ (0.71, 0, 0.71).
    let png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAIAAACQd1PeAAAADElEQVR4nGO41XALAARsAjUQ4/RCAAAAAElFTkSuQmCC";
    let mat = r#"{"emissiveFactor": [1, 1, 1], "normalTexture": {"index": 0}}"#;
    let extra = format!(
        r#", "textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{png}"}}]"#
    );
    let data = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAAAAAAAAACAPwAAAAAAAIA/AAAAAAAAgD8AAAAAAACAPwAAAAAAAIA/AAAAAAAAgD8=";
    let shading_normal = |json: &str| {
        let scene = mcrt::scene::Scene::build(parse(json, false).unwrap());
        let ray = Ray::new(glam::Vec3A::new(0.25, 0.25, 3.0), glam::Vec3A::NEG_Z);
        scene.intersect(&ray).expect("a hit").ns
    };
    let h = 0.5f32.sqrt();
    let n = shading_normal(&triangle(PERSPECTIVE, mat, "", &extra));
    assert!((n - glam::Vec3A::new(h, 0.0, h)).length() < 0.01, "{n}");
    let n = shading_normal(&with_tangents(data, "", mat, &extra));
    assert!((n - glam::Vec3A::new(0.0, h, h)).length() < 0.01, "{n}");
}
