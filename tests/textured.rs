//! Textured parameters end to end: Mitsuba XML parameters bound to textures change the
//! BSDF per hit (roughness, reflectances, dielectric factors), and textured area lights give
//! the same radiance to a light sample as to a ray that hits the sampled point.

use glam::{Vec2, Vec3A};
use mcrt::geometry::Ray;
use mcrt::material::{Bsdf, TransportMode};
use mcrt::scene::xml::{parse_xml, XmlOptions};
use mcrt::scene::{Interaction, Scene, SceneDesc};
use mcrt::Color;
use std::path::Path;

fn scene(body: &str) -> SceneDesc {
    let text = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    {body}
</scene>"#
    );
    // Relative file names resolve beside tests/data/mitsuba/features.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features/t.xml");
    parse_xml(&path, &text, &XmlOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// A hit at texture coordinates `uv` on material `m`.
fn hit(m: u32, uv: Vec2) -> Interaction {
    Interaction {
        p: Vec3A::ZERO,
        p_err: Vec3A::ZERO,
        ng: Vec3A::Z,
        ns: Vec3A::Z,
        ns_base: Vec3A::Z,
        t: 1.0,
        uv,
        material: m,
        light: mcrt::scene::NO_LIGHT,
    }
}

/// Every textured parameter of every BSDF reaches its field: the texture's value at the hit,
/// read as a colour or (roughness) as a float.
#[test]
fn xml_parameters_take_textures() {
    let d = scene(
        r#"<texture type="checkerboard" id="c">
            <rgb name="color0" value="0.9, 0.5, 0.1"/><rgb name="color1" value="0.2, 0.3, 0.4"/>
        </texture>
        <shape type="sphere"><bsdf type="roughconductor"><ref name="alpha" id="c"/><ref name="specular_reflectance" id="c"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughdielectric"><ref name="alpha_u" id="c"/><float name="alpha_v" value="0.2"/><ref name="specular_transmittance" id="c"/></bsdf></shape>
        <shape type="sphere"><bsdf type="thindielectric"><ref name="specular_reflectance" id="c"/></bsdf></shape>
        <shape type="sphere"><bsdf type="dielectric"><ref name="specular_transmittance" id="c"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughplastic"><ref name="diffuse_reflectance" id="c"/><ref name="specular_reflectance" id="c"/></bsdf></shape>
        <shape type="sphere"><bsdf type="conductor"><ref name="specular_reflectance" id="c"/></bsdf></shape>
        <shape type="sphere"><bsdf type="conductor"><ref name="eta" id="c"/><rgb name="k" value="2"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughconductor"><rgb name="eta" value="0.2"/><ref name="k" id="c"/></bsdf></shape>"#,
    );
    let s = Scene::build(d);
    let c0 = Color::new(0.9, 0.5, 0.1);
    let c1 = Color::new(0.2, 0.3, 0.4);
    let (m0, m1) = ((0.9 + 0.5 + 0.1) / 3.0, 0.3);
    // Cell (¼, ¼): colour lookups give color0, float lookups color1's mean; (¾, ¼) the reverse.
    for (uv, c, f) in [(Vec2::splat(0.25), c0, m1), (Vec2::new(0.75, 0.25), c1, m0)] {
        let at = |m: u32| s.material_at(&hit(m, uv)).bsdf;
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        match at(0) {
            Bsdf::RoughConductor(b) => {
                assert_eq!(b.specular_reflectance, c);
                assert!(close(b.distr.alpha_u, f) && close(b.distr.alpha_v, f));
            }
            b => panic!("{b:?}"),
        }
        match at(1) {
            Bsdf::RoughDielectric(b) => {
                assert_eq!(b.specular_transmittance, c);
                assert_eq!(b.specular_reflectance, Color::ONE);
                assert!(close(b.distr.alpha_u, f) && b.distr.alpha_v == 0.2);
            }
            b => panic!("{b:?}"),
        }
        match at(2) {
            Bsdf::ThinDielectric(b) => assert_eq!(b.specular_reflectance, c),
            b => panic!("{b:?}"),
        }
        match at(3) {
            Bsdf::Dielectric(b) => assert_eq!(b.specular_transmittance, c),
            b => panic!("{b:?}"),
        }
        match at(4) {
            Bsdf::RoughPlastic(b) => {
                assert_eq!(b.diffuse_reflectance, c);
                assert_eq!(b.specular_reflectance, c);
            }
            b => panic!("{b:?}"),
        }
        match at(5) {
            Bsdf::Mirror(b) => assert_eq!(b.reflectance, c),
            b => panic!("{b:?}"),
        }
        match at(6) {
            Bsdf::Conductor(b) => assert_eq!((b.eta, b.k), (c, Color::splat(2.0))),
            b => panic!("{b:?}"),
        }
        match at(7) {
            Bsdf::RoughConductor(b) => assert_eq!((b.eta, b.k), (Color::splat(0.2), c)),
            b => panic!("{b:?}"),
        }
    }
}

/// The dielectrics' factors scale what they reflect and what they transmit, and nothing
/// else: the sampled direction and pdf do not change.
#[test]
fn dielectric_factors_scale_their_lobes() {
    let d = scene(
        r#"<shape type="sphere"><bsdf type="dielectric"><rgb name="specular_reflectance" value="0.5, 0.4, 0.3"/><rgb name="specular_transmittance" value="0.1, 0.2, 0.9"/></bsdf></shape>
        <shape type="sphere"><bsdf type="dielectric"/></shape>
        <shape type="sphere"><bsdf type="roughdielectric"><rgb name="specular_reflectance" value="0.5, 0.4, 0.3"/><rgb name="specular_transmittance" value="0.1, 0.2, 0.9"/></bsdf></shape>
        <shape type="sphere"><bsdf type="roughdielectric"/></shape>
        <shape type="sphere"><bsdf type="thindielectric"><rgb name="specular_reflectance" value="0.5, 0.4, 0.3"/><rgb name="specular_transmittance" value="0.1, 0.2, 0.9"/></bsdf></shape>
        <shape type="sphere"><bsdf type="thindielectric"/></shape>"#,
    );
    let s = Scene::build(d);
    let (r, t) = (Color::new(0.5, 0.4, 0.3), Color::new(0.1, 0.2, 0.9));
    let wo = Vec3A::new(0.3, -0.2, 0.9).normalize();
    for pair in [(0, 1), (2, 3), (4, 5)] {
        let (a, b) = (
            s.material_at(&hit(pair.0, Vec2::ZERO)),
            s.material_at(&hit(pair.1, Vec2::ZERO)),
        );
        let (mut reflected, mut transmitted) = (0, 0);
        for k in 0..64 {
            let u1 = (k as f32 + 0.5) / 64.0;
            let u2 = Vec2::new(0.37, 0.61);
            let (Some(x), Some(y)) = (
                a.sample(wo, u1, u2, TransportMode::Radiance),
                b.sample(wo, u1, u2, TransportMode::Radiance),
            ) else {
                continue;
            };
            assert_eq!((x.wi, x.pdf), (y.wi, y.pdf));
            let f = if x.wi.z > 0.0 {
                reflected += 1;
                r
            } else {
                transmitted += 1;
                t
            };
            assert!((x.weight - y.weight * f).abs().max_element() < 1e-6);
            if !x.specular {
                let (fa, fb) = (a.eval(wo, x.wi), b.eval(wo, x.wi));
                assert!((fa - fb * f).abs().max_element() <= 1e-6 * fb.max_element());
            }
        }
        assert!(reflected > 0 && transmitted > 0, "{pair:?}");
    }
}

/// A light sample's radiance is the texture at the sampled point: a ray from the shading
/// point to it hits the light there, with the same texture coordinates and radiance, for a
/// rectangle (mesh uvs), an OBJ without uvs' triangle (barycentric) and a sphere.
#[test]
fn textured_light_samples_match_hits() {
    let d = scene(
        r#"<texture type="bitmap" id="glow"><string name="filename" value="glow.exr"/><string name="filter_type" value="nearest"/><boolean name="accel" value="false"/></texture>
        <shape type="rectangle">
            <transform name="to_world"><scale x="2" y="1"/><rotate x="1" angle="90"/><translate y="3"/></transform>
            <emitter type="area"><ref name="radiance" id="glow"/></emitter>
        </shape>
        <shape type="sphere">
            <point name="center" value="3, 1, 0"/><float name="radius" value="0.5"/>
            <emitter type="area"><ref name="radiance" id="glow"/></emitter>
        </shape>"#,
    );
    let lights_mean = d.textures[0].mean();
    let s = Scene::build(d);
    // Two triangles (not merged into a parallelogram: each maps its own uvs) and a sphere.
    assert_eq!(s.lights.lights.len(), 3);
    assert!(s.lights.lights.iter().all(|l| l.radiance == lights_mean));
    assert!(s.lights.single_planar().is_none());
    let mut rng = 12345u64;
    let mut next = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng >> 40) as f32) / (1u64 << 24) as f32
    };
    let (mut checked, mut distinct) = (0, std::collections::BTreeSet::new());
    for _ in 0..4000 {
        let p = Vec3A::new(next() * 2.0 - 1.0, 0.0, next() * 2.0 - 1.0);
        let Some(ls) = s.lights.sample(p, next(), Vec2::new(next(), next())) else {
            continue;
        };
        let ray = Ray::new(p, ls.wi);
        let Some(si) = s.intersect(&ray) else {
            continue;
        };
        if (si.p - ls.p).length() > 1e-3 || si.light == mcrt::scene::NO_LIGHT {
            continue; // hit something in front (the sphere hides part of itself)
        }
        let le = s.lights.le(si.light, si.ng, si.uv, -ls.wi);
        // Nearest lookups: away from texel edges the two agree exactly.
        let tol = 1e-4 * ls.le.max_element();
        if (le - ls.le).abs().max_element() > tol {
            // On a texel edge the hit's and the sample's uv may round apart.
            let u = si.uv * Vec2::new(4.0, 2.0);
            let frac = (u - u.floor()).min(Vec2::ONE - (u - u.floor()));
            assert!(
                frac.min_element() < 1e-3,
                "le {le:?} at hit uv {:?}, sample {:?}",
                si.uv,
                ls.le
            );
        }
        checked += 1;
        distinct.insert(format!("{:?}", ls.le));
    }
    assert!(checked > 1000, "{checked}");
    // The texture's texels, not one mean radiance.
    assert!(distinct.len() >= 6, "{distinct:?}");
}
