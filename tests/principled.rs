//! The principled BSDFs (Mitsuba's `principled` and `principledthin`): chi-square tests of
//! their samplers against their pdfs for many parameter sets and from both sides, the special
//! cases that are other BSDFs (a white metal is the rough conductor of Fresnel 1, a white
//! spec_trans = 1 the rough dielectric), energy (analytic albedos of the diffuse lobe and of
//! diffuse transmission; no gain where the model conserves energy; sampled and uniformly
//! estimated albedos agree), and a rendered white furnace. Pointwise agreement with Mitsuba
//! itself is in tests/bsdf_mitsuba.rs, the feature scene in tests/xml_features.rs.

#[path = "common/stats.rs"]
mod stats;

use glam::{Vec3, Vec3A};
use mcrt::material::principled_lobes::specular_distribution;
use mcrt::material::{
    Bsdf, Material, Principled, PrincipledThin, RoughConductor, RoughDielectric, TransportMode,
};
use mcrt::Color;
use stats::*;

/// Monte Carlo comparisons allow Z standard errors (P(|Z| > 5) ≈ 6e-7 each).
const Z: f64 = 5.0;

fn principled(p: Principled) -> Material {
    Material::new(Bsdf::Principled(p), false)
}

fn thin(p: PrincipledThin) -> Material {
    Material::new(Bsdf::PrincipledThin(p), false)
}

fn flip(w: Vec3A) -> Vec3A {
    Vec3A::new(w.x, w.y, -w.z)
}

const P: Principled = Principled {
    base_color: Vec3::new(0.5, 0.5, 0.5),
    roughness: 0.5,
    anisotropic: 0.0,
    metallic: 0.0,
    spec_trans: 0.0,
    spec_tint: 0.0,
    sheen: 0.0,
    sheen_tint: 0.0,
    flatness: 0.0,
    clearcoat: 0.0,
    clearcoat_gloss: 0.0,
    eta: 1.5,
    diffuse_reflectance_sampling_rate: 1.0,
    main_specular_sampling_rate: 1.0,
    clearcoat_sampling_rate: 1.0,
};

const T: PrincipledThin = PrincipledThin {
    base_color: Vec3::new(0.5, 0.5, 0.5),
    roughness: 0.5,
    anisotropic: 0.0,
    spec_trans: 0.0,
    spec_tint: 0.0,
    sheen: 0.0,
    sheen_tint: 0.0,
    flatness: 0.0,
    diff_trans: 0.0,
    eta: 1.5,
    diffuse_reflectance_sampling_rate: 1.0,
    specular_reflectance_sampling_rate: 1.0,
    specular_transmittance_sampling_rate: 1.0,
    diffuse_transmittance_sampling_rate: 1.0,
};

/// Every parameter at once (the example of Mitsuba's documentation, coloured).
const ALL: Principled = Principled {
    base_color: Vec3::new(0.9, 0.7, 0.4),
    metallic: 0.7,
    roughness: 0.35,
    spec_tint: 0.4,
    anisotropic: 0.5,
    sheen: 0.3,
    sheen_tint: 0.2,
    clearcoat: 0.6,
    clearcoat_gloss: 0.3,
    spec_trans: 0.4,
    flatness: 0.3,
    ..P
};

#[test]
fn defaults_are_mitsubas() {
    assert_eq!(Principled::default(), P);
    assert_eq!(PrincipledThin::default(), T);
    // specular 0.5 ↔ η = 1.5; the guards for transmission.
    assert!((Principled::eta_of(None, None, false) - 1.5).abs() < 1e-6);
    assert_eq!(Principled::eta_of(Some(1.0), None, true), 1.001);
    assert_eq!(Principled::eta_of(Some(1.0), None, false), 1.0);
    assert_eq!(Principled::eta_of(None, Some(0.0), false), 1.0);
    assert!(Principled::eta_of(None, Some(0.0), true) > 1.0);
}

// ---------------------------------------------------------------------------------------------
// Chi-square
// ---------------------------------------------------------------------------------------------

/// The chi-square tests of this file (Bonferroni: a correct implementation fails any of them
/// with probability below 1 %).
const CHI2_TESTS: f64 = 30.0;
const ALPHA: f64 = 0.01 / CHI2_TESTS;
/// Simpson subdivisions per histogram cell for the expected counts of peaked lobes.
const FINE: usize = 32;

/// [`material_chi2`] at this file's subdivision.
fn chi2(sampler: &Material, pdf_of: &Material, wo: Vec3A, seed: u64) -> (f64, usize, f64) {
    material_chi2(sampler, pdf_of, wo, seed, FINE)
}

fn chi2_cases(cases: &[(&str, Material, Vec3A)], seed: u64) {
    let mut failures = Vec::new();
    for (k, (name, m, wo)) in cases.iter().enumerate() {
        let (stat, dof, p) = chi2(m, m, *wo, seed + k as u64);
        eprintln!("{name} wo {wo:?}: χ² = {stat:.1}, dof {dof}, p = {p:.3}");
        if p < ALPHA {
            failures.push(format!(
                "{name} wo {wo:?}: χ² = {stat:.1}, dof {dof}, p = {p:e}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn chi2_principled() {
    let metal = principled(Principled {
        base_color: Color::new(0.9, 0.6, 0.3),
        metallic: 1.0,
        anisotropic: 0.6,
        ..P
    });
    let glass = principled(Principled {
        spec_trans: 1.0,
        roughness: 0.6,
        ..P
    });
    let coat = principled(Principled {
        clearcoat: 1.0,
        roughness: 0.8,
        metallic: 0.2,
        sheen: 0.5,
        ..P
    });
    let low_eta = principled(Principled {
        eta: 0.8,
        spec_trans: 0.5,
        roughness: 0.6,
        ..P
    });
    let rates = principled(Principled {
        spec_trans: 0.3,
        clearcoat: 0.5,
        clearcoat_gloss: 0.2,
        main_specular_sampling_rate: 0.5,
        clearcoat_sampling_rate: 3.0,
        ..P
    });
    let mut two_sided = principled(Principled {
        metallic: 0.5,
        clearcoat: 0.5,
        ..P
    });
    two_sided.two_sided = true;
    let cases = [
        ("default", principled(P), dir(0.0, 0.3)),
        ("default", principled(P), dir(45.0, 0.3)),
        ("default", principled(P), dir(80.0, 0.3)),
        ("metal", metal.clone(), dir(30.0, 1.0)),
        ("metal", metal.clone(), dir(70.0, 2.0)),
        ("glass", glass.clone(), dir(30.0, 0.5)),
        ("glass", glass.clone(), dir(65.0, 0.5)),
        ("glass inside", glass.clone(), flip(dir(40.0, 0.5))),
        ("clearcoat", coat.clone(), dir(20.0, 0.1)),
        ("clearcoat", coat.clone(), dir(60.0, 0.1)),
        ("all", principled(ALL), dir(45.0, 0.8)),
        ("all inside", principled(ALL), flip(dir(30.0, 0.8))),
        ("eta 0.8", low_eta.clone(), dir(40.0, 0.2)),
        ("eta 0.8 inside", low_eta.clone(), flip(dir(40.0, 0.2))),
        ("rates", rates.clone(), dir(50.0, 0.4)),
        (
            "two-sided from behind",
            two_sided.clone(),
            flip(dir(50.0, 0.4)),
        ),
    ];
    chi2_cases(&cases, 100);
}

#[test]
fn chi2_principled_thin() {
    let all = thin(PrincipledThin {
        base_color: Color::new(0.3, 0.7, 0.2),
        spec_trans: 0.5,
        diff_trans: 0.6,
        eta: 1.3,
        anisotropic: 0.3,
        sheen: 0.4,
        flatness: 0.4,
        ..T
    });
    let leaf = thin(PrincipledThin {
        diff_trans: 1.5,
        roughness: 0.6,
        ..T
    });
    let glass = thin(PrincipledThin {
        spec_trans: 0.9,
        eta: 1.6,
        diff_trans: 0.4,
        specular_reflectance_sampling_rate: 0.7,
        ..T
    });
    let cases = [
        ("thin all", all.clone(), dir(30.0, 0.6)),
        ("thin all from behind", all.clone(), flip(dir(60.0, 0.6))),
        ("thin leaf", leaf.clone(), dir(45.0, 1.1)),
        ("thin glass", glass.clone(), dir(30.0, 2.1)),
        (
            "thin glass from behind",
            glass.clone(),
            flip(dir(50.0, 2.1)),
        ),
        ("thin default", thin(T), dir(75.0, 0.0)),
    ];
    chi2_cases(&cases, 200);
}

/// The test can fail: samples tested against the pdf of slightly different parameters (the
/// clearcoat's gloss, the transmission weight, the thin sheet's diffuse transmission) are
/// rejected.
#[test]
fn chi2_rejects_wrong_principled_pdfs() {
    let pairs = [
        (
            principled(Principled {
                clearcoat: 1.0,
                clearcoat_gloss: 0.0,
                metallic: 1.0,
                roughness: 0.9,
                ..P
            }),
            principled(Principled {
                clearcoat: 1.0,
                clearcoat_gloss: 0.3,
                metallic: 1.0,
                roughness: 0.9,
                ..P
            }),
        ),
        (
            principled(Principled {
                spec_trans: 0.5,
                ..P
            }),
            principled(Principled {
                spec_trans: 0.6,
                ..P
            }),
        ),
        (
            thin(PrincipledThin {
                diff_trans: 0.6,
                ..T
            }),
            thin(PrincipledThin {
                diff_trans: 0.7,
                ..T
            }),
        ),
    ];
    for (k, (sampler, wrong)) in pairs.iter().enumerate() {
        let (stat, dof, p) = chi2(sampler, wrong, dir(40.0, 0.3), 300 + k as u64);
        assert!(
            p < ALPHA,
            "case {k} passed a wrong pdf: χ² = {stat:.1}, dof {dof}, p = {p:e}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Special cases that are other BSDFs
// ---------------------------------------------------------------------------------------------

/// |a − b| ≤ rel·max(|a|, |b|) + abs.
fn close(a: f32, b: f32, rel: f32, abs: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

fn random_pairs(n: usize, seed: u64, both_sides: bool) -> Vec<(Vec3A, Vec3A)> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let (mut a, mut b) = (rng.sphere(), rng.sphere());
            if !both_sides {
                a.z = a.z.abs();
                b.z = b.z.abs();
            }
            (a, b)
        })
        .collect()
}

/// A white metal (metallic 1, base colour 1: Schlick's F = 1) is the rough conductor of
/// Fresnel reflectance 1 with the principled α: the same f and pdf (seen from the front).
#[test]
fn white_metal_is_a_perfect_rough_conductor() {
    for (r, a) in [(0.3f32, 0.0f32), (0.6, 0.7), (0.05, 0.2)] {
        let p = principled(Principled {
            base_color: Color::ONE,
            metallic: 1.0,
            roughness: r,
            anisotropic: a,
            ..P
        });
        let c = Material::new(
            Bsdf::RoughConductor(RoughConductor::new(
                specular_distribution(r, a),
                Color::ZERO,
                Color::ONE,
                Color::ONE,
            )),
            false,
        );
        for (wo, wi) in random_pairs(2000, 1, false) {
            let (fp, fc) = (p.eval(wo, wi), c.eval(wo, wi));
            let (pp, pc) = (p.pdf(wo, wi), c.pdf(wo, wi));
            assert!(
                (0..3).all(|k| close(fp[k], fc[k], 1e-4, 1e-6)) && close(pp, pc, 1e-4, 1e-6),
                "r {r} a {a} wo {wo:?} wi {wi:?}: f {fp:?} vs {fc:?}, pdf {pp} vs {pc}"
            );
        }
    }
}

/// A white spec_trans = 1 principled BSDF is the GGX rough dielectric: the same f in both
/// transport modes and the same pdf, from both sides.
#[test]
fn white_transmission_is_a_rough_dielectric() {
    for (r, eta) in [(0.4f32, 1.5f32), (0.7, 1.33), (0.3, 1.0 / 1.5)] {
        let p = principled(Principled {
            base_color: Color::ONE,
            spec_trans: 1.0,
            roughness: r,
            eta,
            ..P
        });
        let d = Material::new(
            Bsdf::RoughDielectric(RoughDielectric::new(specular_distribution(r, 0.0), eta)),
            false,
        );
        for (wo, wi) in random_pairs(2000, 2, true) {
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let (fp, fd) = (p.eval_mode(wo, wi, mode), d.eval_mode(wo, wi, mode));
                assert!(
                    (0..3).all(|k| close(fp[k], fd[k], 1e-4, 1e-6)),
                    "r {r} η {eta} wo {wo:?} wi {wi:?} {mode:?}: f {fp:?} vs {fd:?}"
                );
            }
            let (pp, pd) = (p.pdf(wo, wi), d.pdf(wo, wi));
            assert!(
                close(pp, pd, 1e-4, 1e-6),
                "r {r} η {eta} wo {wo:?} wi {wi:?}: pdf {pp} vs {pd}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Energy
// ---------------------------------------------------------------------------------------------

/// The albedo of `m` at `wo`: both estimates agree and equal `expected` (when given) within Z
/// standard errors (plus f32 rounding, or 1 % where the lobe is `peaked`: GGX's masking at
/// α = 0.0025 and the rounding of nearly delta lobes), or stay at most 1 (when `conserving`).
/// Peaked lobes are estimated by their sampler only: uniform sampling cannot find them.
fn check_albedo(
    name: &str,
    m: &Material,
    wo: Vec3A,
    mode: TransportMode,
    expected: Option<f64>,
    conserving: bool,
    peaked: bool,
) {
    let [(u, su), (s, ss)] = albedos(m, wo, mode, 200_000, (wo.z.to_bits() as u64) ^ 77);
    eprintln!(
        "{name} wo.z {:.3}: albedo {u:.4} ± {su:.4} (uniform), {s:.4} ± {ss:.4} (sampled)",
        wo.z
    );
    let mut estimates = vec![(s, ss)];
    if !peaked {
        assert!(
            (u - s).abs() <= Z * (su * su + ss * ss).sqrt(),
            "{name} wo {wo:?}: uniform {u} ± {su} vs sampled {s} ± {ss}"
        );
        estimates.push((u, su));
    }
    let slack = if peaked { 0.01 } else { 1e-6 };
    for (a, se) in estimates {
        if let Some(e) = expected {
            assert!(
                (a - e).abs() <= Z * se + slack,
                "{name} wo {wo:?}: albedo {a} ± {se}, expected {e}"
            );
        }
        if conserving {
            assert!(a <= 1.0 + Z * se, "{name} wo {wo:?}: albedo {a} ± {se} > 1");
        }
    }
}

/// With specular 0 (η = 1: no specular reflection) and roughness 0 (no retro-reflection), the
/// principled BSDF is Burley's diffuse f = ρ/π (1 − F_o/2)(1 − F_i/2), F = (1 − cos θ)⁵, whose
/// albedo is ρ(1 − F_o/2)(1 − 1/42) (∫₀¹ (1 − μ)⁵ 2μ dμ = 1/21). The thin sheet's diffuse lobe
/// is the same; its diffuse transmission (diff_trans = 2) is Lambertian: albedo 1 exactly, and
/// diff_trans = 1 splits the two halves.
#[test]
fn diffuse_albedo_is_analytic() {
    let burley = |mu: f64| (1.0 - 0.5 * (1.0 - mu).powi(5)) * (41.0 / 42.0);
    let p = principled(Principled {
        base_color: Color::ONE,
        roughness: 0.0,
        eta: Principled::eta_of(None, Some(0.0), false),
        ..P
    });
    let t = |dt: f32| {
        thin(PrincipledThin {
            base_color: Color::ONE,
            roughness: 0.0,
            diff_trans: dt,
            ..T
        })
    };
    for mu in [1.0f64, 0.7, 0.3, 0.05] {
        let wo = dir_z(mu, 0.4);
        let b = burley(mu);
        let r = TransportMode::Radiance;
        check_albedo("principled diffuse", &p, wo, r, Some(b), true, false);
        check_albedo("thin diffuse", &t(0.0), wo, r, Some(b), true, false);
        check_albedo(
            "thin half",
            &t(1.0),
            flip(wo),
            r,
            Some(0.5 * b + 0.5),
            true,
            false,
        );
        check_albedo("thin transmission", &t(2.0), wo, r, Some(1.0), true, false);
    }
}

/// No energy gain where the model conserves energy: a white metal, white transmission
/// (importance transport: radiance mode scales refraction by 1/η²), the thin sheet's
/// specular pair when both use the same distribution (η = 27/13: 0.65η − 0.35 = 1), at most
/// 1 and close to 1 when nearly smooth; elsewhere (Burley's diffuse gains energy at grazing
/// angles by design) the two estimates agree.
#[test]
fn energy() {
    let white = Color::ONE;
    for (k, theta) in [0.0, 45.0, 80.0].into_iter().enumerate() {
        let wo = dir(theta, 0.9 + k as f64);
        for r in [0.05f32, 0.4, 0.8] {
            let peaked = r < 0.1;
            let nearly_one = (peaked && theta < 60.0).then_some(1.0);
            let metal = principled(Principled {
                base_color: white,
                metallic: 1.0,
                roughness: r,
                anisotropic: 0.5,
                ..P
            });
            let (rad, imp) = (TransportMode::Radiance, TransportMode::Importance);
            check_albedo("white metal", &metal, wo, rad, nearly_one, true, peaked);
            let glass = principled(Principled {
                base_color: white,
                spec_trans: 1.0,
                roughness: r,
                ..P
            });
            for w in [wo, flip(wo)] {
                check_albedo("white glass", &glass, w, imp, None, true, peaked);
            }
            let sheet = thin(PrincipledThin {
                base_color: white,
                spec_trans: 1.0,
                roughness: r,
                eta: 27.0 / 13.0,
                ..T
            });
            check_albedo("thin specular", &sheet, wo, rad, nearly_one, true, peaked);
        }
        for (name, m) in [
            ("default", principled(P)),
            ("all", principled(ALL)),
            (
                "clearcoat and sheen",
                principled(Principled {
                    clearcoat: 1.0,
                    clearcoat_gloss: 0.9,
                    sheen: 1.0,
                    sheen_tint: 0.5,
                    base_color: Color::new(0.4, 0.3, 0.2),
                    ..P
                }),
            ),
            (
                "thin",
                thin(PrincipledThin {
                    spec_trans: 0.4,
                    diff_trans: 0.8,
                    sheen: 0.5,
                    flatness: 0.5,
                    ..T
                }),
            ),
        ] {
            for w in [wo, flip(wo)] {
                check_albedo(name, &m, w, TransportMode::Radiance, None, false, false);
            }
        }
    }
}

/// f(wo, wi) = f(wi, wo) for reflection off the front (all lobes but the refraction, which
/// is not symmetric in radiance transport).
#[test]
fn reflection_is_reciprocal() {
    for m in [principled(P), principled(ALL), thin(T)] {
        for (wo, wi) in random_pairs(1000, 3, false) {
            let (a, b) = (m.eval(wo, wi), m.eval(wi, wo));
            assert!(
                (0..3).all(|k| close(a[k], b[k], 1e-4, 1e-6)),
                "{:?} wo {wo:?} wi {wi:?}: {a:?} vs {b:?}",
                m.bsdf
            );
        }
    }
}

/// `sample` agrees with `eval` and `pdf`: weight = f·|cos θi|/pdf, pdf = pdf(wo, wi).
#[test]
fn sample_is_consistent_with_eval_and_pdf() {
    let mut rng = Rng::new(9);
    for m in [principled(P), principled(ALL), thin(T)] {
        for _ in 0..2000 {
            let wo = rng.sphere();
            let u1 = rng.f();
            let Some(s) = m.sample(wo, u1, rng.u2(), TransportMode::Radiance) else {
                continue;
            };
            let (f, pdf) = (m.eval(wo, s.wi), m.pdf(wo, s.wi));
            let w = f * s.wi.z.abs() / pdf;
            assert!(close(pdf, s.pdf, 1e-5, 0.0), "{pdf} vs {}", s.pdf);
            assert!((0..3).all(|k| close(w[k], s.weight[k], 1e-4, 1e-6)));
            assert!(!s.specular);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// A rendered white furnace
// ---------------------------------------------------------------------------------------------

/// Renders a unit sphere of material `m` filling a 16×16 view (half-angle `half_fov`°, from
/// 4 units away) under a uniform white environment of radiance 1: each pixel is then the
/// albedo the sphere shows from that direction, interreflections inside included. Returns
/// each pixel's mean and standard error (first channel).
fn furnace(m: Material, half_fov: f32) -> Vec<(f64, f64)> {
    use mcrt::camera::{CameraDesc, FovAxis};
    use mcrt::scene::desc::{FileSettings, GeometryDesc, LightDesc, SceneDesc, ShapeDesc};
    let desc = SceneDesc {
        cameras: vec![(
            "main".into(),
            CameraDesc::Perspective {
                origin: Vec3::new(0.0, 0.0, 4.0),
                target: Vec3::ZERO,
                up: Vec3::Y,
                fov: 2.0 * half_fov,
                fov_axis: FovAxis::X,
            },
        )],
        materials: vec![m],
        shapes: vec![ShapeDesc {
            geometry: GeometryDesc::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            },
            material: 0,
            emission: None,
        }],
        lights: vec![LightDesc::Constant {
            radiance: Color::ONE,
        }],
        ..Default::default()
    };
    let scene = mcrt::scene::Scene::build(desc);
    let fs = FileSettings {
        width: Some(16),
        height: Some(16),
        spp: Some(256),
        seed: Some(3),
        max_depth: Some(64),
        sampler: Some(mcrt::sampler::SamplerKind::Independent),
        ..Default::default()
    };
    let s = mcrt::resolve_settings(&fs, &FileSettings::default(), None).expect("settings");
    let (film, stats) = mcrt::render::render(&scene, &s, &|_| {}).expect("render");
    assert_eq!(stats.dropped, 0, "NaN or infinite samples");
    let var = film.variance_of_mean();
    (0..film.sum.len())
        .map(|i| {
            let mean = mcrt::film::sum_to_f64(film.sum[i][0]) / film.count[i] as f64;
            (mean, (var.pixels[i].x as f64).sqrt())
        })
        .collect()
}

/// No pixel brighter than the environment (energy-conserving parameters: a white metal and
/// white glass, nearly smooth, where the sphere must look almost exactly like the furnace, and
/// rough); Burley's diffuse head-on (a narrow view: cos θ > 0.99) shows its analytic albedo
/// ρ·41/42 (see `diffuse_albedo_is_analytic`).
#[test]
fn white_furnace() {
    let white = Color::ONE;
    for (name, m, lowest) in [
        (
            "smooth white metal",
            Principled {
                base_color: white,
                metallic: 1.0,
                roughness: 0.05,
                ..P
            },
            0.99,
        ),
        (
            "smooth white glass",
            Principled {
                base_color: white,
                spec_trans: 1.0,
                roughness: 0.05,
                ..P
            },
            0.97,
        ),
        (
            "rough white metal",
            Principled {
                base_color: white,
                metallic: 1.0,
                roughness: 0.6,
                ..P
            },
            0.0,
        ),
        (
            "rough white glass",
            Principled {
                base_color: white,
                spec_trans: 1.0,
                roughness: 0.6,
                ..P
            },
            0.0,
        ),
    ] {
        let px = furnace(principled(m), 14.0);
        let mean = px.iter().map(|p| p.0).sum::<f64>() / px.len() as f64;
        eprintln!("{name}: image mean {mean:.4}");
        for (i, (v, se)) in px.iter().enumerate() {
            assert!(
                *v <= 1.0 + Z * se + 1e-4,
                "{name}: pixel {i} is {v} ± {se}, brighter than the furnace"
            );
        }
        assert!(mean >= lowest, "{name}: image mean {mean} < {lowest}");
    }
    let rho = 0.8;
    let diffuse = Principled {
        base_color: Color::splat(rho as f32),
        roughness: 0.0,
        eta: 1.0,
        ..P
    };
    let expected = rho * 41.0 / 42.0;
    for (i, (v, se)) in furnace(principled(diffuse), 1.0).iter().enumerate() {
        // cos θ > 0.99 over the view: (1 − cos θ)⁵/2 < 1e-10 of the albedo.
        assert!(
            (v - expected).abs() <= Z * se + 1e-4,
            "diffuse: pixel {i} is {v} ± {se}, expected {expected}"
        );
    }
}
