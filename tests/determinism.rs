//! Images depend only on the scene, the settings and the seed: not on the number of threads,
//! and not on whether the samples were rendered in one pass or several.

use mcrt::film::Film;
use mcrt::integrator::IntegratorKind;
use mcrt::render::{render, render_samples, RenderSettings};
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use std::path::Path;

const SIZE: u32 = 48;
const SPP: u32 = 8;

fn tncg15() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tncg15.toml");
    Scene::build(mcrt::load_scene(&path).unwrap())
}

fn settings(
    scene: &Scene,
    kind: IntegratorKind,
    seed: u64,
    threads: Option<usize>,
) -> RenderSettings {
    let over = FileSettings {
        width: Some(SIZE),
        height: Some(SIZE),
        spp: Some(SPP),
        seed: Some(seed),
        integrator: Some(kind),
        ..Default::default()
    };
    mcrt::resolve_settings(&scene.desc_settings, &over, threads).unwrap()
}

/// The film's exact (fixed-point) sums.
fn bits(v: &[[i128; 3]]) -> Vec<[i128; 3]> {
    v.to_vec()
}

fn image_bits(f: &Film) -> Vec<[u32; 3]> {
    f.image()
        .pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

fn assert_lit(f: &Film) {
    assert!(f.count.iter().all(|&n| n == SPP));
    let total: f64 = f.sum_f64().iter().flatten().sum();
    assert!(total.is_finite() && total > 0.0, "the room is lit: {total}");
}

#[test]
fn same_image_on_one_and_two_threads() {
    let scene = tncg15();
    for kind in [IntegratorKind::Path, IntegratorKind::Direct] {
        let (f1, s1) = render(&scene, &settings(&scene, kind, 7, Some(1)), &|_| {}).unwrap();
        let (f2, s2) = render(&scene, &settings(&scene, kind, 7, Some(2)), &|_| {}).unwrap();
        assert_lit(&f1);
        assert!(
            bits(&f1.sum) == bits(&f2.sum),
            "{kind:?}: Σ L differs between 1 and 2 threads"
        );
        assert!(
            bits(&f1.sum_sq) == bits(&f2.sum_sq),
            "{kind:?}: Σ L² differs"
        );
        assert_eq!(f1.count, f2.count);
        assert!(image_bits(&f1) == image_bits(&f2));
        assert_eq!(s1.samples, s2.samples);
        assert_eq!(s1.samples, (SIZE * SIZE * SPP) as u64);
        assert_eq!(
            (s1.rays.rays, s1.rays.shadow_rays),
            (s2.rays.rays, s2.rays.shadow_rays)
        );
        assert_eq!(
            (s1.dropped, s1.first_dropped),
            (s2.dropped, s2.first_dropped)
        );
    }
}

#[test]
fn other_seed_other_image() {
    let scene = tncg15();
    for kind in [IntegratorKind::Path, IntegratorKind::Direct] {
        let (a, _) = render(&scene, &settings(&scene, kind, 0, Some(2)), &|_| {}).unwrap();
        let (b, _) = render(&scene, &settings(&scene, kind, 1, Some(2)), &|_| {}).unwrap();
        assert_lit(&a);
        assert_lit(&b);
        let differ = a.sum.iter().zip(&b.sum).filter(|(p, q)| p != q).count();
        // Most pixels see a noisy estimate; a handful (pure emitter, pure background) may not.
        assert!(
            differ > (SIZE * SIZE / 2) as usize,
            "{kind:?}: only {differ} of {} pixels differ between seeds 0 and 1",
            SIZE * SIZE
        );
    }
}

/// Samples [0, 4) then [4, 8) into one film give the film of samples [0, 8) at once, bit for
/// bit: each pixel's fixed-point sums take the same f32 samples.
#[test]
fn two_passes_equal_one() {
    let scene = tncg15();
    for kind in [IntegratorKind::Path, IntegratorKind::Direct] {
        let s = settings(&scene, kind, 3, Some(2));
        let (once, _) = render(&scene, &s, &|_| {}).unwrap();
        let mut twice = Film::new(SIZE, SIZE);
        let a = render_samples(&scene, &s, &mut twice, 0, SPP / 2, &|_| {}).unwrap();
        let b = render_samples(&scene, &s, &mut twice, SPP / 2, SPP / 2, &|_| {}).unwrap();
        assert_eq!(a.samples + b.samples, (SIZE * SIZE * SPP) as u64);
        assert_lit(&once);
        assert_eq!(once.count, twice.count);
        assert!(
            image_bits(&once) == image_bits(&twice),
            "{kind:?}: the image of two passes differs from one pass"
        );
        // Each pass continues the pixels' running sums, so the sums are the same bits too.
        let bits = |f: &Film| {
            f.sum
                .iter()
                .chain(&f.sum_sq)
                .flatten()
                .copied()
                .collect::<Vec<i128>>()
        };
        assert!(
            bits(&once) == bits(&twice),
            "{kind:?}: the film sums of two passes differ from one pass"
        );
    }
}

/// The integrator compiled for x86-64-v3, which `integrator::li` chooses at run time where
/// the CPU has AVX2 and FMA, gives the portable code's film bit for bit: the TNCG15 room with
/// ten shadow rays (the lattice's samples, their packets) and the Cornell box with one
/// (single shadow rays, one-sided BSDFs). On a CPU without those features both are the
/// portable code, and the test checks nothing new.
#[test]
fn same_image_with_and_without_the_x86_64_v3_path() {
    use mcrt::geometry::Ray;
    use mcrt::integrator::{Integrator, IntegratorParams, RayStats};
    use mcrt::sampler::Sampler;
    /// The path tracer in its portable form whatever the CPU.
    struct Portable<'a>(&'a Scene, IntegratorParams);
    impl Integrator for Portable<'_> {
        fn li(&self, ray: Ray, sampler: &mut Sampler, stats: &mut RayStats) -> mcrt::Color {
            mcrt::integrator::li_portable(self.0, ray, sampler, &self.1, stats)
        }
    }
    for (file, shadow_rays) in [("scenes/tncg15.toml", 10), ("scenes/cornell-box.toml", 1)] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let scene = Scene::build(mcrt::load_scene(&path).unwrap());
        let mut s = settings(&scene, IntegratorKind::Path, 5, Some(2));
        s.params.shadow_rays = shadow_rays;
        // One path at a time both ways: the wavefront is not what this test compares.
        s.backend = mcrt::render::Backend::Scalar;
        let mut chosen = Film::new(SIZE, SIZE);
        render_samples(&scene, &s, &mut chosen, 0, SPP, &|_| {}).unwrap();
        let mut other = Film::new(SIZE, SIZE);
        let mut next = vec![0; (SIZE * SIZE) as usize];
        let portable = Portable(&scene, s.params);
        let until = |_| SPP;
        mcrt::render::render_ranges(
            &portable,
            &scene,
            &s,
            &mut other,
            &mut next,
            &until,
            &|| false,
            &|_| {},
        )
        .unwrap();
        assert_lit(&chosen);
        assert!(
            bits(&chosen.sum) == bits(&other.sum) && bits(&chosen.sum_sq) == bits(&other.sum_sq),
            "{file}: the x86-64-v3 code's film differs from the portable code's"
        );
    }
}

/// Masks decide by a hash of the ray, normal and bump maps perturb at the hit: the feature
/// scene of both gives the same bits on one and two threads.
#[test]
fn masked_and_mapped_scene_same_on_one_and_two_threads() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features/maps-mask.xml");
    let scene = Scene::build(mcrt::load_scene(&path).unwrap());
    for kind in [IntegratorKind::Path, IntegratorKind::Direct] {
        let (f1, _) = render(&scene, &settings(&scene, kind, 5, Some(1)), &|_| {}).unwrap();
        let (f2, _) = render(&scene, &settings(&scene, kind, 5, Some(2)), &|_| {}).unwrap();
        assert_lit(&f1);
        assert!(bits(&f1.sum) == bits(&f2.sum), "{kind:?}: Σ L differs");
        assert!(image_bits(&f1) == image_bits(&f2));
    }
}
