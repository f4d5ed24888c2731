//! Mitsuba's sphere options beyond centre and radius: texture coordinates in the sphere's own
//! frame under a rotation, and `flip_normals`, also on an area emitter (a sphere that lights
//! its inside); and the cylinder's frame and texture coordinates.

mod common;

use common::*;
use glam::{Vec2, Vec3A};
use mcrt::geometry::Ray;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use std::path::Path;

/// A scene from XML shapes, read as if it lay beside the feature scenes (for `tex.png`).
fn scene(shapes: &str) -> Scene {
    let text = format!(
        "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"30\"/>\
         <transform name=\"to_world\"><lookat origin=\"0, 0, 3\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>\
         </transform><film type=\"hdrfilm\"><integer name=\"width\" value=\"64\"/>\
         <integer name=\"height\" value=\"64\"/></film></sensor>{shapes}</scene>"
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features/t.xml");
    let desc = mcrt::scene::xml::parse_xml(&path, &text, &Default::default()).unwrap();
    Scene::build(desc)
}

const TEXTURED: &str = "<bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\">\
                        <string name=\"filename\" value=\"tex.png\"/></texture></bsdf>";

/// Texture coordinates follow the sphere's frame: rotated 90° about z, the point in world
/// direction +y is the local +x (u = 0, v = 1/2), and world −x is local +y (u = 1/4).
/// Unrotated, world +y has u = 1/4. `flip_normals` turns the normal inwards.
#[test]
fn sphere_uv_follow_its_rotation_and_flip_turns_normals() {
    let hit = |s: &Scene, from: Vec3A| {
        s.intersect(&Ray::new(from * 5.0, -from))
            .expect("the ray hits the sphere")
    };
    let plain = scene(&format!("<shape type=\"sphere\">{TEXTURED}</shape>"));
    let si = hit(&plain, Vec3A::Y);
    assert!(
        (si.uv - Vec2::new(0.25, 0.5)).length() < 1e-5,
        "{:?}",
        si.uv
    );
    assert!((si.ng - Vec3A::Y).length() < 1e-5);
    let rotated = scene(&format!(
        "<shape type=\"sphere\"><transform name=\"to_world\"><rotate z=\"1\" angle=\"90\"/>\
         </transform><boolean name=\"flip_normals\" value=\"true\"/>{TEXTURED}</shape>"
    ));
    let si = hit(&rotated, Vec3A::Y);
    assert!(
        si.uv.x.min(1.0 - si.uv.x) < 1e-5 && (si.uv.y - 0.5).abs() < 1e-5,
        "{:?}",
        si.uv
    );
    assert!(
        (si.ng + Vec3A::Y).length() < 1e-5,
        "flipped normal {:?}",
        si.ng
    );
    assert_eq!(si.ns, si.ng);
    let si = hit(&rotated, -Vec3A::X);
    assert!(
        (si.uv - Vec2::new(0.25, 0.5)).length() < 1e-5,
        "{:?}",
        si.uv
    );
    // The pole: local +z stays world +z under a rotation about z (v = 0).
    let si = hit(&rotated, Vec3A::Z);
    assert!(si.uv.y < 1e-3, "{:?}", si.uv);
}

/// A cylinder's uv: u = φ/2π around its axis from the local frame's x axis, v from 0 at p0
/// to 1 at p1; normals point away from the axis.
#[test]
fn cylinder_uv_and_normals() {
    let s = scene(&format!(
        "<shape type=\"cylinder\"><point name=\"p0\" value=\"0, 0, -1\"/>\
         <point name=\"p1\" value=\"0, 0, 1\"/><float name=\"radius\" value=\"0.5\"/>\
         {TEXTURED}</shape>"
    ));
    // Along +z the local frame is the world's (Duff et al.'s frame of +z is x, y).
    for (dir, u) in [(Vec3A::X, 0.0), (Vec3A::Y, 0.25), (-Vec3A::X, 0.5)] {
        for z in [-0.5f32, 0.0, 0.75] {
            let from = dir * 5.0 + Vec3A::Z * z;
            let si = s.intersect(&Ray::new(from, -dir)).expect("hit");
            let du = (si.uv.x - u).abs().min((si.uv.x - u - 1.0).abs());
            assert!(du < 2e-3, "{dir:?} {z}: {:?}", si.uv);
            assert!((si.uv.y - (z + 1.0) / 2.0).abs() < 1e-4, "{:?}", si.uv);
            assert!((si.ns - dir).length() < 1e-3, "{:?}", si.ns);
            assert!((si.p.length_squared() - z * z - 0.25).abs() < 1e-3);
        }
    }
    // Open: a ray along the axis passes through.
    assert!(s.intersect(&Ray::new(Vec3A::Z * 5.0, -Vec3A::Z)).is_none());
}

/// A flipped sphere emitter (radiance 1, black) lights its inside: a diffuse sphere of
/// reflectance 1/2 at its centre, which sees it in every direction, has radiance 1/2, and
/// the emitter seen from inside has radiance 1. Light sampling must give the emitter inward
/// normals for next-event estimation to count (and MIS to weigh) its samples.
#[test]
fn flipped_sphere_emitter_lights_its_inside() {
    let s = scene(
        "<shape type=\"sphere\"><float name=\"radius\" value=\"6\"/>\
         <boolean name=\"flip_normals\" value=\"true\"/>\
         <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>\
         <emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\
         <shape type=\"sphere\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/>\
         </bsdf></shape>",
    );
    let fs = FileSettings::default();
    let r = render_with(
        &s,
        &settings(
            &fs,
            FileSettings {
                width: Some(64),
                height: Some(64),
                spp: Some(64),
                ..Default::default()
            },
        ),
    );
    let px = |x: u32, y: u32| {
        let c = r.mean.pixels[(y * r.mean.width + x) as usize];
        (c.x + c.y + c.z) as f64 / 3.0
    };
    // The centre 16 × 16 pixels see the inner sphere, the corners the emitter.
    let (mut centre, mut n) = (0.0, 0);
    for y in 24..40 {
        for x in 24..40 {
            centre += px(x, y);
            n += 1;
        }
    }
    let centre = centre / n as f64;
    assert!((centre - 0.5).abs() < 0.01, "inner sphere {centre}");
    for (x, y) in [(0, 0), (63, 0), (0, 63), (63, 63)] {
        assert!((px(x, y) - 1.0).abs() < 1e-6, "emitter {}", px(x, y));
    }
}

/// The TOML format's cylinder is the XML importer's, and its meshes may be serialized files
/// (the first mesh, as Mitsuba's default shape_index).
#[test]
fn toml_cylinder_and_serialized_mesh_are_the_xml_ones() {
    use mcrt::scene::GeometryDesc;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features");
    let toml = mcrt::scene::toml::parse_toml(
        &dir.join("t.toml"),
        "[[shape]]\ntype = \"cylinder\"\np0 = [1, 2, 3]\np1 = [2, 2, 5]\nradius = 0.3\n\n\
         [[shape]]\ntype = \"mesh\"\nfile = \"mesh.serialized\"\n",
    )
    .unwrap();
    let xml = mcrt::scene::xml::parse_xml(
        &dir.join("t.xml"),
        "<scene version=\"3.0.0\"><shape type=\"cylinder\"><point name=\"p0\" value=\"1, 2, 3\"/>\
         <point name=\"p1\" value=\"2, 2, 5\"/><float name=\"radius\" value=\"0.3\"/></shape>\
         <shape type=\"serialized\"><string name=\"filename\" value=\"mesh.serialized\"/>\
         <boolean name=\"face_normals\" value=\"true\"/></shape></scene>",
        &Default::default(),
    )
    .unwrap();
    for (a, b) in toml.shapes.iter().zip(&xml.shapes) {
        let (GeometryDesc::Mesh(a), GeometryDesc::Mesh(b)) = (&a.geometry, &b.geometry) else {
            panic!("meshes expected");
        };
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.indices, b.indices);
        assert_eq!(a.normals, b.normals);
    }
    let GeometryDesc::Mesh(tetra) = &toml.shapes[1].geometry else {
        unreachable!()
    };
    assert_eq!((tetra.positions.len(), tetra.indices.len()), (4, 4));
}
