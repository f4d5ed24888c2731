//! White-furnace tests of the integrators: a closed box whose every surface is Lambertian
//! with albedo ρ and emits radiance Le. The rendering equation L = Le + ρ·(mean of L over the
//! hemisphere) has the constant solution L = Le/(1 − ρ) everywhere (the Neumann series
//! Le·Σ ρ^j); counting only paths of at most k segments gives Le·Σ_{j<k} ρ^j =
//! Le(1 − ρ^k)/(1 − ρ). Any bias in path sampling, next-event estimation, MIS weights, Russian
//! roulette or ray spawning shows up as a departure from that constant.
//!
//! Tolerances come from the measured noise (`Film::variance_of_mean`), never from a fixed
//! percentage:
//!
//! - Per pixel, σ is the root of the mean of `variance_of_mean` over the pixel's 5×5
//!   neighbourhood. A pixel's own estimate is not reliable here: Russian roulette makes the
//!   samples a mixture in which a few percent of paths survive to contribute much more, and a
//!   pixel that happened to draw few of them (k of an expected λ) has both a low mean and a
//!   small σ, so its self-normalised z ≈ (k − λ)/√k has a far heavier tail than a normal
//!   (measured: |z| up to 6.3 over 1024 pixels for a correct estimator). The per-sample
//!   variance varies slowly over the image, so the pooled estimate is accurate, and
//!   z ≈ (k − λ)/√λ then behaves.
//! - Every pixel must lie within Z_PIXEL σ; the image mean within Z_MEAN standard errors
//!   √(Σσ_i²)/N (pixels are independent: every sample has its own random stream).
//! - Fixed roulette with survival q < ρ multiplies the surviving throughput by ρ/q > 1 per
//!   bounce: the samples then have finite variance but an infinite third moment
//!   (Σ_k q^k (ρ/q)^{3k} diverges for ρ = 0.8, q = 0.7), so means of a few hundred samples
//!   stay skewed. That case is checked on 4×4-pixel blocks (4096 samples each) with the
//!   blocks' own σ.

use glam::Vec3;
use mcrt::camera::{CameraDesc, FovAxis};
use mcrt::film::Film;
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::material::{Bsdf, Lambert, Material};
use mcrt::render::RenderSettings;
use mcrt::sampler::SamplerKind;
use mcrt::scene::desc::{FileSettings, GeometryDesc, SceneDesc, ShapeDesc};
use mcrt::scene::Scene;
use mcrt::Color;

const SIZE: u32 = 32;
const SPP: u32 = 256;
/// Threshold per pixel or block. With 1024 pixels, a normal P(|Z| > 5.5) ≈ 4e-8 each gives
/// 4e-5 for the image; the margin over the Bonferroni value (≈ 4.4 for 1 % over 1024 pixels)
/// covers the residual skewness of means of roulette-terminated paths (measured over 12
/// seeds at 256 spp: largest pooled pixel |z| 4.7 with throughput RR, 3.9 with fixed RR and
/// q > ρ; largest block |z| 3.7 with q < ρ).
const Z_PIXEL: f64 = 5.5;
/// Image-mean threshold (a single test).
const Z_MEAN: f64 = 4.0;
/// Half-width of the neighbourhood over which pixel variances are pooled.
const POOL: i64 = 2;

/// How the image is compared with the expected constant.
#[derive(Clone, Copy)]
enum Unit {
    /// Every pixel, with σ pooled over its neighbourhood.
    Pixels,
    /// Blocks of b×b pixels; the variance of a block mean is Σσ_i²/b⁴.
    Blocks(u32),
}

/// The box [−1, 1]³ with 12 triangles wound so that the geometric normals face inward.
fn inward_box() -> TriangleMesh {
    let mut positions = Vec::new();
    for i in 0..8 {
        let s = |b: u32| if i & b != 0 { 1.0 } else { -1.0 };
        positions.push(Vec3::new(s(1), s(2), s(4)));
    }
    // Each face as a quad wound clockwise seen from outside (so its normal points in).
    let quads = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let mut indices = Vec::new();
    for q in quads {
        indices.push([q[0], q[1], q[2]]);
        indices.push([q[0], q[2], q[3]]);
    }
    TriangleMesh {
        tangents: None,
        positions,
        normals: None,
        uvs: None,
        indices,
    }
}

/// The furnace: the inward box (and optionally a sphere inside), every surface a one-sided
/// Lambertian of albedo ρ emitting Le from its front. One-sided materials and emitters also
/// check the orientation: a box wound the wrong way would render black.
fn furnace(rho: f32, le: f32, with_sphere: bool) -> Scene {
    let material = Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Color::splat(rho),
        }),
        false,
    );
    let mut shapes = vec![ShapeDesc {
        geometry: GeometryDesc::Mesh(inward_box()),
        material: 0,
        emission: Some(Color::splat(le)),
    }];
    if with_sphere {
        shapes.push(ShapeDesc {
            geometry: GeometryDesc::Sphere {
                center: Vec3::new(0.4, 0.3, -0.3),
                radius: 0.3,
            },
            material: 0,
            emission: Some(Color::splat(le)),
        });
    }
    // A wide view from off-centre towards the sphere's corner, so that pixels see walls,
    // edges, corners and (when present) the sphere at various angles.
    let camera = CameraDesc::Perspective {
        origin: Vec3::new(0.1, -0.2, 0.05),
        target: Vec3::new(0.4, 0.3, -0.3),
        up: Vec3::Z,
        fov: 100.0,
        fov_axis: FovAxis::X,
    };
    let desc = SceneDesc {
        cameras: vec![("main".into(), camera)],
        materials: vec![material],
        shapes,
        ..Default::default()
    };
    Scene::build(desc)
}

fn settings(over: FileSettings) -> RenderSettings {
    let base = FileSettings {
        width: Some(SIZE),
        height: Some(SIZE),
        spp: Some(SPP),
        seed: Some(1),
        // Independent samples: the per-pixel sample variance is then an unbiased estimate
        // of the variance of the mean (with stratified Sobol points it only bounds it).
        sampler: Some(SamplerKind::Independent),
        ..Default::default()
    };
    mcrt::resolve_settings(&base, &over, None).expect("valid settings")
}

/// Renders and checks every pixel (or block) and the image mean against `expected`.
fn check(name: &str, scene: &Scene, s: &RenderSettings, expected: f64, unit: Unit) {
    let (film, stats) = mcrt::render::render(scene, s, &|_| {}).expect("render");
    assert_eq!(stats.dropped, 0, "{name}: NaN or infinite samples");
    assert_eq!(stats.samples, (s.width * s.height * s.spp) as u64);
    if let Err(e) = compare(name, &film, expected, unit) {
        panic!("{e}");
    }
}

/// Compares a rendered furnace with the constant `expected`; Err describes the failure.
fn compare(name: &str, film: &Film, expected: f64, unit: Unit) -> Result<(), String> {
    let (w, h) = (film.width as i64, film.height as i64);
    let var: Vec<f64> = film
        .variance_of_mean()
        .pixels
        .iter()
        .map(|v| v.x as f64)
        .collect();
    let mean: Vec<f64> = (0..film.sum.len())
        .map(|i| {
            // A grey scene renders grey: the three channels follow the same computation.
            let s = film.sum[i];
            assert!(
                s[1] == s[0] && s[2] == s[0],
                "{name}: pixel {i} is not grey"
            );
            mcrt::film::sum_to_f64(s[0]) / film.count[i] as f64
        })
        .collect();
    let at = |x: i64, y: i64| (y * w + x) as usize;
    // (label, mean, σ) of each unit compared.
    let mut units = Vec::new();
    match unit {
        Unit::Pixels => {
            for y in 0..h {
                for x in 0..w {
                    let (mut v, mut n) = (0.0, 0.0);
                    for yy in (y - POOL).max(0)..=(y + POOL).min(h - 1) {
                        for xx in (x - POOL).max(0)..=(x + POOL).min(w - 1) {
                            v += var[at(xx, yy)];
                            n += 1.0;
                        }
                    }
                    units.push((format!("pixel ({x}, {y})"), mean[at(x, y)], (v / n).sqrt()));
                }
            }
        }
        Unit::Blocks(b) => {
            let b = b as i64;
            for by in 0..h / b {
                for bx in 0..w / b {
                    let (mut m, mut v) = (0.0, 0.0);
                    for y in by * b..(by + 1) * b {
                        for x in bx * b..(bx + 1) * b {
                            m += mean[at(x, y)];
                            v += var[at(x, y)];
                        }
                    }
                    let n = (b * b) as f64;
                    units.push((format!("block ({bx}, {by})"), m / n, v.sqrt() / n));
                }
            }
        }
    }
    let mut bad = Vec::new();
    let mut max_z = 0.0f64;
    for (label, m, sigma) in &units {
        // Zero-variance estimators (max_depth = 1) may differ from the exact answer by f32
        // rounding only.
        let tol = Z_PIXEL * sigma + 1e-5 * expected;
        if *sigma > 0.0 {
            max_z = max_z.max((m - expected).abs() / sigma);
        }
        if (m - expected).abs() > tol {
            bad.push(format!("{label}: {m:.5} ± {sigma:.5}"));
        }
    }
    let n_pix = mean.len() as f64;
    let img_mean = mean.iter().sum::<f64>() / n_pix;
    let img_se = var.iter().sum::<f64>().sqrt() / n_pix;
    eprintln!(
        "{name}: image mean {img_mean:.5} ± {img_se:.5}, expected {expected:.5}; \
         largest |z| over {} units {max_z:.2}",
        units.len()
    );
    if !bad.is_empty() {
        return Err(format!(
            "{name}: {} of {} units beyond {Z_PIXEL} σ of {expected}:\n{}",
            bad.len(),
            units.len(),
            bad.iter().take(20).cloned().collect::<Vec<_>>().join("\n")
        ));
    }
    if (img_mean - expected).abs() > Z_MEAN * img_se + 1e-5 * expected {
        return Err(format!(
            "{name}: image mean {img_mean} ± {img_se}, expected {expected}"
        ));
    }
    Ok(())
}

/// Le/(1 − ρ), or with at most k segments, Le(1 − ρ^k)/(1 − ρ).
fn furnace_radiance(rho: f64, le: f64, max_depth: Option<u32>) -> f64 {
    match max_depth {
        None => le / (1.0 - rho),
        Some(k) => le * (1.0 - rho.powi(k as i32)) / (1.0 - rho),
    }
}

/// The default path tracer (throughput-based Russian roulette from bounce 5), unlimited depth.
#[test]
fn furnace_default_roulette() {
    for (rho, le) in [(0.5f32, 1.0f32), (0.8, 0.5)] {
        let s = settings(FileSettings::default());
        assert_eq!(s.params.max_depth, None);
        check(
            &format!("ρ {rho}, throughput RR"),
            &furnace(rho, le, false),
            &s,
            furnace_radiance(rho as f64, le as f64, None),
            Unit::Pixels,
        );
    }
}

/// Fixed Russian roulette with survival 0.7 at every bounce (the TNCG15 report's rule):
/// unbiased whatever ρ, since surviving paths are reweighted by 1/0.7. With ρ = 0.8 > 0.7
/// the reweighted throughput grows along a path (see the module notes): 4×4 blocks.
#[test]
fn furnace_fixed_roulette() {
    for (rho, le, unit) in [(0.5f32, 1.0f32, Unit::Pixels), (0.8, 0.5, Unit::Blocks(4))] {
        let s = settings(FileSettings {
            rr_survival: Some(0.7),
            seed: Some(2),
            ..Default::default()
        });
        assert_eq!(s.params.rr, mcrt::integrator::RussianRoulette::Fixed(0.7));
        check(
            &format!("ρ {rho}, fixed RR 0.7"),
            &furnace(rho, le, false),
            &s,
            furnace_radiance(rho as f64, le as f64, None),
            unit,
        );
    }
}

/// Paths of at most k segments (Mitsuba's max_depth): Le(1 − ρ^k)/(1 − ρ). k = 1 is the
/// emission seen directly (Le exactly, no noise), k = 2 adds direct lighting (ρLe), k = 3
/// one more bounce.
#[test]
fn furnace_max_depth() {
    for (rho, le) in [(0.5f32, 1.0f32), (0.8, 0.5)] {
        for k in 1..=3 {
            let s = settings(FileSettings {
                max_depth: Some(k),
                seed: Some(3 + k as u64),
                ..Default::default()
            });
            check(
                &format!("ρ {rho}, max_depth {k}"),
                &furnace(rho, le, false),
                &s,
                furnace_radiance(rho as f64, le as f64, Some(k)),
                Unit::Pixels,
            );
        }
    }
}

/// The direct integrator (emission plus one bounce of direct light) sees Le(1 + ρ), the
/// same as the path tracer with two segments.
#[test]
fn furnace_direct_integrator() {
    let (rho, le) = (0.8f32, 0.5f32);
    let s = settings(FileSettings {
        integrator: Some(mcrt::integrator::IntegratorKind::Direct),
        seed: Some(9),
        ..Default::default()
    });
    check(
        "direct integrator",
        &furnace(rho, le, false),
        &s,
        furnace_radiance(rho as f64, le as f64, Some(2)),
        Unit::Pixels,
    );
}

/// A small emissive Lambertian sphere of the same ρ and Le inside the box changes nothing:
/// it is just more furnace wall (seen from outside, where its normals point). This also
/// exercises light sampling of a sphere, shadow rays past it, and MIS between the two lights.
#[test]
fn furnace_with_sphere_inside() {
    for (rho, le) in [(0.5f32, 1.0f32), (0.8, 0.5)] {
        let scene = furnace(rho, le, true);
        // The box's six faces (two triangles each) are six parallelogram lights.
        assert_eq!(scene.lights.lights.len(), 7);
        let s = settings(FileSettings {
            seed: Some(11),
            ..Default::default()
        });
        check(
            &format!("ρ {rho}, sphere inside"),
            &scene,
            &s,
            furnace_radiance(rho as f64, le as f64, None),
            Unit::Pixels,
        );
        let s = settings(FileSettings {
            max_depth: Some(3),
            seed: Some(12),
            ..Default::default()
        });
        check(
            &format!("ρ {rho}, sphere inside, max_depth 3"),
            &scene,
            &s,
            furnace_radiance(rho as f64, le as f64, Some(3)),
            Unit::Pixels,
        );
    }
}

/// Negative control, to show that the check has power: the furnace with ρ = 0.8 and
/// Le = 0.5 (answer 2.5) does not pass for an answer 1 % off. The image mean's standard
/// error is ≈ 0.0032 at this resolution and sample count, so 1 % (0.025) is ≈ 8σ.
#[test]
fn furnace_check_detects_a_one_percent_error() {
    let s = settings(FileSettings {
        seed: Some(13),
        ..Default::default()
    });
    let scene = furnace(0.8, 0.5, false);
    let (film, _) = mcrt::render::render(&scene, &s, &|_| {}).unwrap();
    let right = furnace_radiance(0.8, 0.5, None);
    for wrong in [0.99 * right, 1.01 * right] {
        assert!(
            compare("wrong answer", &film, wrong, Unit::Pixels).is_err(),
            "the check accepted {wrong} for a furnace whose answer is {right}"
        );
    }
    compare("right answer", &film, right, Unit::Pixels).unwrap();
}
