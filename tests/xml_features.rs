//! Mitsuba 3 XML feature scenes (tests/data/mitsuba/features): each exercises emitters, BSDFs,
//! textures and shapes of the importer, and is compared on block means with a Mitsuba 3
//! reference made by tools/mitsuba_ref.py (commands in tests/data/README.md).

mod common;

use common::*;

/// Renders the scene `tests/data/mitsuba/features/{name}.xml` and compares it with the reference `{name}.exr`.
fn feature_matches_mitsuba(name: &str, spp: u32, ref_spp: u32) {
    file_matches_reference(
        &format!("tests/data/mitsuba/features/{name}.xml"),
        spp,
        &format!("{name}.exr"),
        ref_spp,
    );
}

#[test]
fn point_directional_and_constant_emitters() {
    feature_matches_mitsuba("lights", 256, 4096);
}

#[test]
fn conductor_rough_and_thin_dielectric_and_plastic_bsdfs() {
    feature_matches_mitsuba("materials", 512, 4096);
}

#[test]
fn textures_meshes_and_includes() {
    feature_matches_mitsuba("textures", 256, 4096);
}

/// The rough BSDFs without `distribution`: Mitsuba's default, Beckmann.
#[test]
fn beckmann_rough_bsdfs_by_default() {
    feature_matches_mitsuba("beckmann", 512, 4096);
}

/// Textures on float and colour parameters (roughness from a raw PNG with clamp wrap, a
/// checkerboard blend weight, plastic reflectances), nested blends and textured area lights
/// (a rectangle and a sphere).
#[test]
fn textured_parameters_blends_and_emission() {
    feature_matches_mitsuba("textured-params", 256, 4096);
}

/// `spot`: default and given beam widths (linear falloff between beam and cutoff), a
/// projected PNG texture, frames by lookat and by rotations.
#[test]
fn spot_emitters() {
    feature_matches_mitsuba("spot", 256, 4096);
}

/// `envmap` from a Radiance HDR file: scale, a to_world rotation, the background seen
/// directly and in a mirror, diffuse and rough plastic shapes lit by it (importance sampled,
/// with MIS against BSDF sampling).
#[test]
fn envmap_emitter_hdr() {
    feature_matches_mitsuba("envmap", 256, 4096);
}

/// The same scene with the OpenEXR copy of the map (the same values): the same reference.
#[test]
fn envmap_emitter_exr() {
    let opts = mcrt::LoadOptions {
        defines: vec![("file".into(), "sky.exr".into())],
        ..Default::default()
    };
    let path = project_path("tests/data/mitsuba/features/envmap.xml");
    let desc = mcrt::load_scene_with(&path, &opts).expect("scene loads");
    let fs = desc.settings.clone();
    let scene = mcrt::scene::Scene::build(desc);
    let s = settings(
        &fs,
        mcrt::scene::desc::FileSettings {
            spp: Some(128),
            ..Default::default()
        },
    );
    let r = render_with(&scene, &s);
    BlockComparison::new(&r, &reference("envmap.exr"), 8, 4096)
        .assert_within_noise("envmap.xml (EXR)");
}

/// `normalmap` on a rectangle, `bumpmap` on a sphere, and a `mask` with a bitmap opacity in
/// front of an area light (shadow rays through it).
#[test]
fn normal_bump_maps_and_masks() {
    feature_matches_mitsuba("maps-mask", 512, 4096);
}

/// A thinlens sensor: defocus in front of and behind the plane of focus.
#[test]
fn thinlens_sensor_defocus() {
    feature_matches_mitsuba("cameras", 256, 4096);
}

/// An orthographic sensor whose to_world scale sets the view's extent.
#[test]
fn orthographic_sensor() {
    feature_matches_mitsuba("orthographic", 256, 4096);
}

/// An open cylinder, a sphere with flip_normals, a rotated textured sphere and a serialized
/// mesh.
#[test]
fn cylinder_flipped_and_rotated_spheres_serialized_mesh() {
    feature_matches_mitsuba("shapes", 256, 4096);
}

/// The envmap scene by `direct` (Mitsuba's: one emitter and one BSDF sample by MIS).
#[test]
fn envmap_emitter_direct_integrator() {
    feature_matches_mitsuba("envmap-direct", 256, 4096);
}

/// Mitsuba's principled BSDF (defaults, anisotropic metal, rough glass, clearcoat and sheen,
/// every parameter at once, flatness with a textured base colour) and principledthin.
#[test]
fn principled_bsdfs() {
    feature_matches_mitsuba("principled", 512, 4096);
}

/// Shape groups placed by instances under rotations, non-uniform and mirroring scales.
#[test]
fn shapegroups_and_instances() {
    feature_matches_mitsuba("instances", 256, 4096);
}
