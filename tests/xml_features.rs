//! Mitsuba 3 XML feature scenes (tests/data/mitsuba/features): each exercises emitters, BSDFs,
//! textures and shapes of the importer, and is compared on block means with a Mitsuba 3
//! reference made by tools/mitsuba_ref.py (commands in tests/data/README.md).

mod common;

use common::*;
use mcrt::scene::desc::FileSettings;

/// z-score above which a block fails (a few hundred blocks in all: P(|Z| > 5) ≈ 6e-7 each).
const Z: f64 = 5.0;

/// Renders an XML feature scene at its own resolution with `spp` and compares 8×8 blocks
/// with the reference (made with `ref_spp`).
fn feature_matches_mitsuba(name: &str, spp: u32, ref_spp: u32) {
    let (scene, fs) = load(&format!("tests/data/mitsuba/features/{name}.xml"));
    let s = settings(
        &fs,
        FileSettings {
            spp: Some(spp),
            ..Default::default()
        },
    );
    let r = render_with(&scene, &s);
    let c = BlockComparison::new(&r, &reference(&format!("{name}.exr")), 8, ref_spp);
    eprintln!(
        "{name}: {} blocks, max z {:.2}, aggregate z {:.2}",
        c.mine.len(),
        c.max_z(),
        c.aggregate_z()
    );
    let out = c.outliers(Z);
    if !out.is_empty() {
        c.print();
    }
    assert!(out.is_empty(), "{name}: blocks beyond {Z} sigma: {out:?}");
    assert!(
        c.aggregate_z().abs() < Z,
        "{name}: biased overall, aggregate z {:.2}",
        c.aggregate_z()
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
