//! TOML twins of the Mitsuba 3 XML feature scenes (tests/data/toml, written by
//! tools/toml_feature_scenes.py): the native format expresses the same emitters, BSDFs,
//! textures and shapes, checked twice: the loaded descriptions match the XML importer's, and
//! the renders match the same Mitsuba 3 references on 8×8 block means, as in
//! tests/xml_features.rs.

mod common;

use common::*;
use mcrt::camera::CameraDesc;
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::scene::desc::{GeometryDesc, SceneDesc};

fn desc(rel: &str) -> SceneDesc {
    mcrt::load_scene(&project_path(rel)).expect("scene loads")
}

/// Renders the scene `tests/data/toml/{name}.toml` and compares it with the reference `{name}.exr`.
fn twin_matches_mitsuba(name: &str, spp: u32, ref_spp: u32) {
    file_matches_reference(
        &format!("tests/data/toml/{name}.toml"),
        spp,
        &format!("{name}.exr"),
        ref_spp,
    );
}

#[test]
fn toml_point_directional_and_constant_lights_match_mitsuba() {
    twin_matches_mitsuba("lights", 256, 4096);
}

#[test]
fn toml_conductor_rough_and_thin_dielectric_and_plastic_match_mitsuba() {
    twin_matches_mitsuba("materials", 512, 4096);
}

#[test]
fn toml_textures_obj_and_ply_match_mitsuba() {
    twin_matches_mitsuba("textures", 256, 4096);
}

/// Textured roughness and plastic reflectances, blends (checkerboard and nested) and
/// textured area lights, written in the native format.
#[test]
fn toml_textured_parameters_and_blends_match_mitsuba() {
    twin_matches_mitsuba("textured-params", 256, 4096);
}

fn area(m: &TriangleMesh) -> f32 {
    m.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Area-weighted mean of the geometric normals, and the centroid of the vertices.
fn normal_and_centroid(m: &TriangleMesh) -> (glam::Vec3, glam::Vec3) {
    let n: glam::Vec3 = m
        .indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a)
        })
        .sum();
    let c = m.positions.iter().copied().sum::<glam::Vec3>() / m.positions.len() as f32;
    (n, c)
}

/// The TOML twin loads to the XML importer's description: settings, cameras, lights,
/// materials (BSDF, sides, texture), spheres, and meshes (area, orientation, centroid,
/// texture coordinates where the twin keeps the vertex order).
fn twin_matches_xml(name: &str) {
    let x = desc(&format!("tests/data/mitsuba/features/{name}.xml"));
    let t = desc(&format!("tests/data/toml/{name}.toml"));
    let (xs, ts) = (&x.settings, &t.settings);
    assert_eq!((xs.width, xs.height), (ts.width, ts.height), "{name}: size");
    assert_eq!(xs.integrator, ts.integrator, "{name}: integrator");
    assert_eq!(xs.max_depth, ts.max_depth, "{name}: max_depth");
    assert_eq!(
        xs.rr_depth.unwrap_or(5),
        ts.rr_depth.unwrap_or(5),
        "{name}: rr_depth"
    );
    assert_eq!(
        xs.hide_emitters.unwrap_or(false),
        ts.hide_emitters.unwrap_or(false),
        "{name}: hide_emitters"
    );
    // The same rays: eye, view direction, up in the image plane, field of view.
    let view = |c: &CameraDesc| match *c {
        CameraDesc::Perspective {
            origin,
            target,
            up,
            fov,
            fov_axis,
        } => {
            let d = (target - origin).normalize();
            let u = (up - d * up.dot(d)).normalize();
            (origin, d, u, fov, fov_axis)
        }
        _ => panic!("{name}: not a perspective camera"),
    };
    let (ca, cb) = (view(&x.cameras[0].1), view(&t.cameras[0].1));
    assert!(
        (ca.0 - cb.0).length() < 1e-5
            && (ca.1 - cb.1).length() < 1e-5
            && (ca.2 - cb.2).length() < 1e-5
            && ca.3 == cb.3
            && ca.4 == cb.4,
        "{name}: camera {ca:?} vs {cb:?}"
    );
    assert_eq!(
        format!("{:?}", x.lights),
        format!("{:?}", t.lights),
        "{name}: lights"
    );
    assert_eq!(x.shapes.len(), t.shapes.len(), "{name}: shape count");
    // Shapes in the same order in both files.
    for (i, (a, b)) in x.shapes.iter().zip(&t.shapes).enumerate() {
        let (ma, mb) = (
            &x.materials[a.material as usize],
            &t.materials[b.material as usize],
        );
        let lit = a.emission.is_some();
        assert_eq!(
            format!("{:?}", a.emission),
            format!("{:?}", b.emission),
            "{name}: shape {i} emission"
        );
        // Lights: Mitsuba's black diffuse against mcrt's black material.
        if !lit {
            assert_eq!(
                format!("{:?}", ma.bsdf),
                format!("{:?}", mb.bsdf),
                "{name}: shape {i} BSDF"
            );
            // Dielectrics have two sides whatever the flag says.
            if !format!("{:?}", ma.bsdf).contains("Dielectric") {
                assert_eq!(ma.two_sided, mb.two_sided, "{name}: shape {i} sides");
            }
            let textures = |m: &mcrt::material::Material, d: &mcrt::scene::SceneDesc| {
                m.slots
                    .iter()
                    .map(|b| d.textures[b.texture as usize].clone())
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                textures(ma, &x),
                textures(mb, &t),
                "{name}: shape {i} texture"
            );
        }
        match (&a.geometry, &b.geometry) {
            (
                GeometryDesc::Sphere { center, radius },
                GeometryDesc::Sphere {
                    center: c2,
                    radius: r2,
                },
            ) => {
                assert!(
                    (*center - *c2).length() < 1e-5 && (radius - r2).abs() < 1e-5,
                    "{name}: shape {i} sphere"
                );
            }
            (GeometryDesc::Mesh(ma), GeometryDesc::Mesh(mb)) => {
                assert_eq!(ma.indices.len(), mb.indices.len(), "{name}: shape {i}");
                let (aa, ab) = (area(ma), area(mb));
                assert!(
                    (aa - ab).abs() < 1e-4 * aa,
                    "{name}: shape {i} area {aa} vs {ab}"
                );
                let ((na, ca), (nb, cb)) = (normal_and_centroid(ma), normal_and_centroid(mb));
                assert!((na - nb).length() < 1e-4 * aa, "{name}: shape {i} facing");
                assert!((ca - cb).length() < 1e-4, "{name}: shape {i} centroid");
                assert_eq!(
                    ma.normals.is_some(),
                    mb.normals.is_some(),
                    "{name}: shape {i}"
                );
                // The disk's polygon may start at another angle; other meshes keep the order.
                if ma.indices.len() != 256 {
                    for (p, q) in ma.positions.iter().zip(&mb.positions) {
                        assert!((*p - *q).length() < 1e-5, "{name}: shape {i} vertex");
                    }
                    if ma.uvs.is_some() && mb.uvs.is_some() {
                        assert_eq!(ma.uvs, mb.uvs, "{name}: shape {i} uvs");
                    }
                }
            }
            _ => panic!("{name}: shape {i} has different kinds of geometry"),
        }
    }
}

#[test]
fn toml_lights_twin_describes_the_xml_scene() {
    twin_matches_xml("lights");
}

#[test]
fn toml_materials_twin_describes_the_xml_scene() {
    twin_matches_xml("materials");
}

#[test]
fn toml_textures_twin_describes_the_xml_scene() {
    twin_matches_xml("textures");
}

/// A TOML scene written next to the feature data (so that relative files resolve there).
fn parse(text: &str) -> SceneDesc {
    let path = project_path("tests/data/toml/inline.toml");
    mcrt::scene::toml::parse_toml(&path, text).unwrap_or_else(|e| panic!("{e}"))
}

fn mesh_of(d: &SceneDesc, i: usize) -> &TriangleMesh {
    match &d.shapes[i].geometry {
        GeometryDesc::Mesh(m) => m,
        _ => panic!("shape {i} is not a mesh"),
    }
}

#[test]
fn toml_render_rr_depth_and_hide_emitters() {
    let d = parse("[render]\nrr_depth = 3\nhide_emitters = true\n");
    assert_eq!(d.settings.rr_depth, Some(3));
    assert_eq!(d.settings.hide_emitters, Some(true));
    let d = parse("");
    assert_eq!(d.settings.rr_depth, None);
    assert_eq!(d.settings.hide_emitters, None);
}

#[test]
fn toml_smooth_computes_drops_or_keeps_normals() {
    let d = parse(
        "[[shape]]\ntype = \"mesh\"\nfile = \"pyramid.ply\"\n\n\
         [[shape]]\ntype = \"mesh\"\nfile = \"pyramid.ply\"\nsmooth = true\n\n\
         [[shape]]\ntype = \"mesh\"\nfile = \"quad.obj\"\n\n\
         [[shape]]\ntype = \"mesh\"\nfile = \"quad.obj\"\nsmooth = false\n\n\
         [[shape]]\ntype = \"mesh\"\npositions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nindices = [[0, 1, 2]]\nsmooth = true\n",
    );
    assert!(
        mesh_of(&d, 0).normals.is_none(),
        "PLY without normals: flat"
    );
    let mut smooth = mesh_of(&d, 0).clone();
    smooth.recompute_vertex_normals();
    assert_eq!(mesh_of(&d, 1).normals, smooth.normals, "smooth = true");
    assert!(mesh_of(&d, 2).normals.is_some(), "OBJ normals kept");
    assert!(
        mesh_of(&d, 3).normals.is_none(),
        "smooth = false drops them"
    );
    assert!(mesh_of(&d, 4).normals.is_some(), "inline smooth = true");
    // OBJ texture coordinates are flipped: vt (0, 0) becomes (0, 1).
    assert_eq!(
        mesh_of(&d, 2).uvs.as_ref().unwrap()[0],
        glam::Vec2::new(0.0, 1.0)
    );
}

#[test]
fn toml_defaults_of_the_new_materials_and_lights() {
    let d = parse(
        "[material.p]\ntype = \"plastic\"\n\n\
         [material.m]\ntype = \"conductor\"\n\n\
         [material.r]\ntype = \"roughconductor\"\nmaterial = \"Au\"\n\n\
         [[light]]\ntype = \"environment\"\nradiance = 0.5\n",
    );
    // BTreeMap order: m, p, r.
    let dbg: Vec<String> = d
        .materials
        .iter()
        .map(|m| format!("{:?}", m.bsdf))
        .collect();
    let plastic =
        mcrt::material::Plastic::new(1.49, mcrt::Color::splat(0.5), mcrt::Color::ONE, false);
    assert!(
        dbg[0].starts_with("Mirror"),
        "conductor 'none' is a mirror: {}",
        dbg[0]
    );
    assert_eq!(
        dbg[1],
        format!("{:?}", mcrt::material::Bsdf::Plastic(plastic))
    );
    let (eta, k) = mcrt::material::conductor::conductor_ior("Au").unwrap();
    let gold = mcrt::material::RoughConductor::new(
        mcrt::material::Microfacet::ggx(0.1, 0.1),
        eta,
        k,
        mcrt::Color::ONE,
    );
    assert_eq!(
        dbg[2],
        format!("{:?}", mcrt::material::Bsdf::RoughConductor(gold))
    );
    assert!(d
        .materials
        .iter()
        .all(|m| m.two_sided && m.slots.is_empty()));
    assert_eq!(
        format!("{:?}", d.lights),
        "[Constant { radiance: Vec3(0.5, 0.5, 0.5) }]"
    );
}

/// `distribution` picks the microfacet distribution of the rough materials; GGX without it
/// (mcrt's TOML default, unlike Mitsuba's XML).
#[test]
fn toml_microfacet_distribution() {
    use mcrt::material::MicrofacetType;
    let d = parse(
        "[material.a]\ntype = \"roughconductor\"\n\n\
         [material.b]\ntype = \"roughconductor\"\ndistribution = \"beckmann\"\nalpha_u = 0.1\nalpha_v = 0.3\n\n\
         [material.c]\ntype = \"roughdielectric\"\ndistribution = \"beckmann\"\n\n\
         [material.d]\ntype = \"roughplastic\"\ndistribution = \"beckmann\"\nalpha = 0.2\n\n\
         [material.e]\ntype = \"roughplastic\"\ndistribution = \"ggx\"\n",
    );
    let got: Vec<_> = d
        .materials
        .iter()
        .map(|m| {
            let distr = m
                .bsdf
                .microfacet()
                .unwrap_or_else(|| panic!("not rough: {:?}", m.bsdf));
            (distr.kind, distr.alpha_u, distr.alpha_v)
        })
        .collect();
    use MicrofacetType::{Beckmann, Ggx};
    assert_eq!(
        got,
        [
            (Ggx, 0.1, 0.1),
            (Beckmann, 0.1, 0.3),
            (Beckmann, 0.1, 0.1),
            (Beckmann, 0.2, 0.2),
            (Ggx, 0.1, 0.1),
        ]
    );
}

/// Spot lights by position, direction and up, and by a to_world matrix with a projected
/// texture: the Mitsuba reference of spot.xml.
#[test]
fn toml_spot_lights_match_mitsuba() {
    twin_matches_mitsuba("spot", 256, 4096);
}

/// An envmap light (Radiance HDR, scale, a to_world rotation): the Mitsuba reference of
/// envmap.xml.
#[test]
fn toml_envmap_light_matches_mitsuba() {
    twin_matches_mitsuba("envmap", 256, 4096);
}

#[test]
fn toml_principled_twin_describes_the_xml_scene() {
    twin_matches_xml("principled");
}

#[test]
fn toml_principled_matches_mitsuba() {
    twin_matches_mitsuba("principled", 512, 4096);
}
