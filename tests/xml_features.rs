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

/// `spot`: default and given beam widths (linear falloff between beam and cutoff), a
/// projected PNG texture, frames by lookat and by rotations.
#[test]
fn spot_emitters() {
    feature_matches_mitsuba("spot", 256, 4096);
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
