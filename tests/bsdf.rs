//! BSDFs: energy conservation, reciprocity, consistency of `sample` with `eval` and `pdf`,
//! chi-square goodness-of-fit of the samplers against their pdfs, the smooth dielectric
//! (Fresnel, Snell, total internal reflection, radiance scaling) and one- versus two-sided
//! materials. Everything works in the local shading frame (z = normal).

#[path = "common/stats.rs"]
mod stats;

use glam::{Vec2, Vec3A};
use mcrt::material::dielectric::fresnel_dielectric;
use mcrt::material::{Bsdf, Dielectric, Lambert, Material, Mirror, OrenNayar, TransportMode};
use mcrt::Color;
use stats::*;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn lambert(albedo: f32, two_sided: bool) -> Material {
    Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Color::splat(albedo),
        }),
        two_sided,
    )
}

fn oren_nayar(albedo: f32, sigma_deg: f32, two_sided: bool) -> Material {
    Material::new(
        Bsdf::OrenNayar(OrenNayar::new(Color::splat(albedo), sigma_deg.to_radians())),
        two_sided,
    )
}

fn flip(w: Vec3A) -> Vec3A {
    Vec3A::new(w.x, w.y, -w.z)
}

/// Directional albedo ∫ f(wo, wi) |cos θi| dωi by Monte Carlo with uniform sphere sampling
/// (independent of the BSDF's own sampler): X = 4π f |cos θi|, E[X] = albedo. Returns the
/// mean and its standard error.
fn albedo_mc(m: &Material, wo: Vec3A, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed);
    mean_and_stderr((0..n).map(|_| {
        let wi = rng.sphere();
        4.0 * PI * m.eval(wo, wi).x as f64 * wi.z.abs() as f64
    }))
}

/// Oren–Nayar's A and B (Oren and Nayar 1994, eq. 30; pbrt-v3 eq. 8.12), σ in radians.
fn on_ab(sigma: f64) -> (f64, f64) {
    let s2 = sigma * sigma;
    (1.0 - s2 / (2.0 * (s2 + 0.33)), 0.45 * s2 / (s2 + 0.09))
}

/// Number of standard errors allowed in the Monte Carlo comparisons below: with about a
/// hundred comparisons, P(|Z| > 5) ≈ 6e-7 each keeps false failures negligible.
const Z: f64 = 5.0;

// ---------------------------------------------------------------------------------------------
// Chi-square goodness of fit (the method of Mitsuba's and pbrt's `chi2` tests)
// ---------------------------------------------------------------------------------------------

/// The chi-square tests of the BSDF samplers below; the significance of each is
/// 0.01 / CHI2_TESTS (Bonferroni), so that a correct implementation fails any of them with
/// probability below 1 %.
const CHI2_TESTS: f64 = 18.0;
const ALPHA: f64 = 0.01 / CHI2_TESTS;

// ---------------------------------------------------------------------------------------------
// The chi-square machinery itself
// ---------------------------------------------------------------------------------------------

/// Q(a, x) against closed forms and table values: Q(1, x) = e^{−x}; for one degree of freedom
/// P(χ² ≥ s) = erfc(√(s/2)); the 1 % critical values of χ² for 10 and 100 degrees of freedom
/// are 23.209 and 135.807 (Abramowitz and Stegun, table 26.8).
#[test]
fn incomplete_gamma_matches_known_values() {
    for x in [0.01, 0.5, 1.0, 3.0, 10.0, 50.0] {
        assert!((gamma_q(1.0, x) - (-x).exp()).abs() < 1e-12);
    }
    // erfc(1) = 0.157299207050285 (A&S table 7.1): s = 2.
    assert!((chi2_pvalue(2.0, 1) - 0.157299207050285).abs() < 1e-10);
    assert!((chi2_pvalue(23.209, 10) - 0.01).abs() < 1e-5);
    assert!((chi2_pvalue(135.807, 100) - 0.01).abs() < 1e-5);
    // ln Γ(n) = ln (n−1)!
    assert!((ln_gamma(10.0) - (362880.0f64).ln()).abs() < 1e-10);
    assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-10);
}

/// The test must be able to fail: cosine-weighted samples tested against the uniform
/// hemisphere pdf 1/(2π), and uniform samples against the cosine pdf, are both rejected; a
/// correct uniform-sphere sampler against 1/(4π) is accepted.
#[test]
fn chi2_rejects_a_wrong_pdf() {
    let m = lambert(0.5, false);
    let wo = dir(30.0, 0.3);
    let uniform_hemi = |w: Vec3A| if w.z > 0.0 { 1.0 / (2.0 * PI) } else { 0.0 };
    let (stat, dof, p) = chi2_test(
        |rng| {
            m.sample(wo, 0.5, rng.u2(), TransportMode::Radiance)
                .map(|s| s.wi)
        },
        &uniform_hemi,
        1,
    );
    assert!(
        p < ALPHA,
        "cosine samples passed as uniform: χ² = {stat:.1}, dof {dof}, p = {p:e}"
    );
    let (stat, dof, p) = chi2_test(
        |rng| {
            let w = rng.sphere();
            Some(flip_up(w))
        },
        &|w| m.pdf(wo, w) as f64,
        2,
    );
    assert!(
        p < ALPHA,
        "uniform samples passed as cosine: χ² = {stat:.1}, dof {dof}, p = {p:e}"
    );
    let (stat, dof, p) = chi2_test(|rng| Some(rng.sphere()), &|_| 1.0 / (4.0 * PI), 3);
    assert!(
        p > ALPHA,
        "a correct sampler was rejected: χ² = {stat:.1}, dof {dof}, p = {p:e}"
    );
}

fn flip_up(w: Vec3A) -> Vec3A {
    Vec3A::new(w.x, w.y, w.z.abs())
}

// ---------------------------------------------------------------------------------------------
// Lambert and Oren–Nayar
// ---------------------------------------------------------------------------------------------

/// Outgoing directions used throughout: normal, oblique and grazing (θ up to 89.9°).
const WO_THETAS: [f64; 5] = [0.0, 30.0, 60.0, 85.0, 89.9];

/// ∫ f cos dω equals the albedo for Lambert (ρ/π · π = ρ), by a Monte Carlo estimate that
/// does not use the BSDF's sampler, within Z standard errors.
#[test]
fn lambert_conserves_energy() {
    for (k, &rho) in [0.3f32, 0.8, 1.0].iter().enumerate() {
        let m = lambert(rho, false);
        for (i, &theta) in WO_THETAS.iter().enumerate() {
            let (mean, se) = albedo_mc(&m, dir(theta, 1.0), 200_000, (10 * k + i) as u64);
            assert!(
                (mean - rho as f64).abs() < Z * se,
                "ρ {rho}, θo {theta}: {mean} ± {se}"
            );
        }
    }
}

/// Oren–Nayar with albedo 1 reflects at most all the light for σ = 0°, 20°, 45° at every
/// θo. Two exact values pin the estimate down: at normal incidence f = A/π for every wi
/// (sin θo = 0), so the albedo is A; at grazing incidence (θo → 90°: α = θo, β = θi) it is
/// A + (B/π)·∫cos⁺φ dφ·∫ tan θ cos θ sin θ dθ = A + B/2. With cos θo = 1e-4 instead of 0 the
/// albedo differs from that limit by at most 4(A + B)·cos θo (the strip θi > θo and the
/// missing part of the strip θi < θo each contribute at most 2(A + B)·cos θo).
#[test]
fn oren_nayar_conserves_energy() {
    for (k, &sigma) in [0.0f32, 20.0, 45.0].iter().enumerate() {
        let m = oren_nayar(1.0, sigma, false);
        let (a, b) = on_ab((sigma as f64).to_radians());
        for (i, &z) in [1.0f64, 0.9, 0.5, 0.2, 0.05, 1e-4].iter().enumerate() {
            let (mean, se) = albedo_mc(&m, dir_z(z, 0.7), 400_000, (100 + 10 * k + i) as u64);
            eprintln!(
                "Oren–Nayar σ {sigma}°, cos θo {z}: albedo {mean:.4} ± {se:.4} \
                 (A {a:.4}, A + B/2 {:.4})",
                a + b / 2.0
            );
            assert!(
                mean <= 1.0 + Z * se,
                "σ {sigma}°, cos θo {z}: albedo {mean} ± {se} > 1"
            );
            if z == 1.0 {
                assert!(
                    (mean - a).abs() < Z * se + 1e-5,
                    "σ {sigma}°: normal-incidence albedo {mean} ± {se}, A = {a}"
                );
            }
            if z == 1e-4 {
                let limit = a + b / 2.0;
                assert!(
                    (mean - limit).abs() < Z * se + 4.0 * (a + b) * z,
                    "σ {sigma}°: grazing albedo {mean} ± {se}, A + B/2 = {limit}"
                );
            }
        }
    }
}

/// Oren–Nayar's eval against an independent implementation of the formula in angles:
/// f = ρ/π (A + B max(0, cos(φi − φo)) sin α tan β), α = max(θi, θo), β = min(θi, θo).
#[test]
fn oren_nayar_matches_the_formula() {
    let mut rng = Rng::new(7);
    for &sigma in &[10.0f64, 20.0, 45.0, 80.0] {
        let m = oren_nayar(0.7, sigma as f32, false);
        let (a, b) = on_ab(sigma.to_radians());
        for _ in 0..5000 {
            let (wo, wi) = (flip_up(rng.sphere()), flip_up(rng.sphere()));
            let th = |w: Vec3A| (w.z as f64).clamp(-1.0, 1.0).acos();
            let ph = |w: Vec3A| (w.y as f64).atan2(w.x as f64);
            let (ti, to) = (th(wi), th(wo));
            if ti.cos() < 1e-3 || to.cos() < 1e-3 || ti.sin() < 1e-3 || to.sin() < 1e-3 {
                continue; // tan β and the azimuth are ill-conditioned there
            }
            let (alpha, beta) = (ti.max(to), ti.min(to));
            let f =
                0.7 / PI * (a + b * (ph(wi) - ph(wo)).cos().max(0.0) * alpha.sin() * beta.tan());
            let got = m.eval(wo, wi).x as f64;
            assert!(
                (got - f).abs() <= 1e-5 * f,
                "σ {sigma}: f({wo:?}, {wi:?}) = {got}, formula {f}"
            );
        }
    }
}

/// With σ = 0 (A = 1, B = 0) Oren–Nayar is Lambert.
#[test]
fn oren_nayar_with_zero_roughness_is_lambert() {
    let mut rng = Rng::new(8);
    let (on, l) = (oren_nayar(0.6, 0.0, true), lambert(0.6, true));
    for _ in 0..10_000 {
        let (wo, wi) = (rng.sphere(), rng.sphere());
        assert_eq!(on.eval(wo, wi), l.eval(wo, wi));
        assert_eq!(on.pdf(wo, wi), l.pdf(wo, wi));
    }
}

/// Helmholtz reciprocity f(wo, wi) = f(wi, wo), on random pairs in the upper hemisphere and,
/// for two-sided materials, in the lower one.
#[test]
fn reciprocity() {
    let mut rng = Rng::new(9);
    let materials = [
        lambert(0.5, true),
        oren_nayar(0.5, 20.0, true),
        oren_nayar(0.9, 45.0, true),
        oren_nayar(0.9, 80.0, true),
    ];
    for m in &materials {
        for _ in 0..20_000 {
            let (mut wo, mut wi) = (flip_up(rng.sphere()), flip_up(rng.sphere()));
            if rng.f() < 0.5 {
                (wo, wi) = (flip(wo), flip(wi));
            }
            let (a, b) = (m.eval(wo, wi).x, m.eval(wi, wo).x);
            assert!(
                (a - b).abs() <= 1e-6 * a.abs().max(b.abs()),
                "{m:?}: f({wo:?}, {wi:?}) = {a}, reversed {b}"
            );
        }
    }
}

/// `sample` agrees with `eval` and `pdf`: weight = f·|cos θi|/pdf, pdf = pdf(wo, wi), the
/// direction is a unit vector on wo's side (reflection only), and it is not specular.
#[test]
fn sample_is_consistent_with_eval_and_pdf() {
    let mut rng = Rng::new(10);
    let materials = [
        lambert(0.5, true),
        oren_nayar(0.8, 20.0, true),
        oren_nayar(0.8, 45.0, true),
    ];
    for m in &materials {
        let mut n = 0;
        for _ in 0..20_000 {
            let wo = rng.sphere();
            if wo.z == 0.0 {
                continue;
            }
            let u1 = rng.f();
            let Some(s) = m.sample(wo, u1, rng.u2(), TransportMode::Radiance) else {
                continue;
            };
            n += 1;
            assert!(!s.specular && s.eta == 1.0);
            assert!((s.wi.length() - 1.0).abs() < 1e-5);
            assert!(s.wi.z * wo.z > 0.0, "wi {:?} not on wo's side {wo:?}", s.wi);
            let pdf = m.pdf(wo, s.wi);
            assert!(
                (s.pdf - pdf).abs() <= 1e-5 * pdf,
                "{m:?}: pdf {} vs {pdf}",
                s.pdf
            );
            let expected = m.eval(wo, s.wi) * s.wi.z.abs() / pdf;
            assert!(
                (s.weight - expected).abs().max_element() <= 1e-5 * expected.max_element(),
                "{m:?}: weight {:?} vs {expected:?}",
                s.weight
            );
        }
        assert!(n > 19_900, "{m:?}: only {n} samples out of 20000");
    }
}

/// Chi-square tests of the cosine-weighted samplers of Lambert and Oren–Nayar against their
/// pdfs at normal, oblique and grazing wo, from above and (two-sided) from below.
#[test]
fn chi2_lambert_and_oren_nayar() {
    let cases: Vec<(Material, Vec3A)> = {
        let mut v = Vec::new();
        for &theta in &WO_THETAS {
            v.push((lambert(0.5, false), dir(theta, 0.4)));
            v.push((oren_nayar(0.5, 20.0, false), dir(theta, 1.1)));
            v.push((oren_nayar(0.5, 45.0, false), dir(theta, 2.3)));
        }
        v.push((lambert(0.5, true), flip(dir(40.0, 0.4))));
        v.push((oren_nayar(0.5, 30.0, true), flip(dir(70.0, 0.4))));
        v.push((oren_nayar(0.5, 30.0, true), flip(dir(89.0, 5.0))));
        v
    };
    assert_eq!(cases.len() as f64, CHI2_TESTS);
    let mut failures = Vec::new();
    for (k, (m, wo)) in cases.iter().enumerate() {
        let (stat, dof, p) = chi2_material(m, *wo, 1000 + k as u64);
        eprintln!(
            "{:?} wo.z {:.4}: χ² = {stat:.1}, dof {dof}, p = {p:.3}",
            m.bsdf, wo.z
        );
        if p < ALPHA {
            failures.push(format!(
                "{:?} at wo {wo:?}: χ² = {stat:.1}, dof {dof}, p = {p:e}",
                m.bsdf
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "rejected at significance {ALPHA:e}:\n{}",
        failures.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// Mirror and one-/two-sided materials
// ---------------------------------------------------------------------------------------------

#[test]
fn mirror_reflects() {
    let mut rng = Rng::new(11);
    let m = Material::new(
        Bsdf::Mirror(Mirror {
            reflectance: Color::new(0.9, 0.5, 0.1),
        }),
        true,
    );
    for _ in 0..1000 {
        let wo = rng.sphere();
        let s = m
            .sample(wo, rng.f(), rng.u2(), TransportMode::Radiance)
            .unwrap();
        assert_eq!(s.wi, Vec3A::new(-wo.x, -wo.y, wo.z));
        assert_eq!(s.weight, Color::new(0.9, 0.5, 0.1));
        assert!(s.specular && s.pdf == 0.0);
        assert_eq!(
            m.eval(wo, s.wi),
            Color::ZERO,
            "delta BSDFs evaluate to zero"
        );
        assert_eq!(m.pdf(wo, s.wi), 0.0);
    }
}

/// A one-sided material seen from behind (wo.z < 0) reflects nothing: zero eval and pdf, no
/// sample. A two-sided one reflects as if seen from the front, mirrored through the surface.
#[test]
fn one_and_two_sided_materials() {
    let mut rng = Rng::new(12);
    let pairs = [
        (lambert(0.5, false), lambert(0.5, true)),
        (oren_nayar(0.5, 30.0, false), oren_nayar(0.5, 30.0, true)),
        (
            Material::new(
                Bsdf::Mirror(Mirror {
                    reflectance: Color::ONE,
                }),
                false,
            ),
            Material::new(
                Bsdf::Mirror(Mirror {
                    reflectance: Color::ONE,
                }),
                true,
            ),
        ),
    ];
    for (one, two) in &pairs {
        for _ in 0..5000 {
            let wo = flip(flip_up(rng.sphere())); // below
            let wi = rng.sphere();
            if wo.z == 0.0 {
                continue;
            }
            let (u1, u2) = (rng.f(), rng.u2());
            assert_eq!(one.eval(wo, wi), Color::ZERO);
            assert_eq!(one.pdf(wo, wi), 0.0);
            assert!(one.sample(wo, u1, u2, TransportMode::Radiance).is_none());
            // Two-sided: everything mirrored through the surface.
            assert_eq!(two.eval(wo, wi), two.eval(flip(wo), flip(wi)));
            assert_eq!(two.pdf(wo, wi), two.pdf(flip(wo), flip(wi)));
            let (a, b) = (
                two.sample(wo, u1, u2, TransportMode::Radiance),
                two.sample(flip(wo), u1, u2, TransportMode::Radiance),
            );
            assert_eq!(a.is_some(), b.is_some());
            if let (Some(a), Some(b)) = (a, b) {
                assert_eq!(a.wi, flip(b.wi));
                assert!(a.wi.z < 0.0, "two-sided reflection from below stays below");
                assert_eq!((a.weight, a.pdf, a.specular), (b.weight, b.pdf, b.specular));
            }
            // Seen from the front, both are the same material.
            let wf = flip(wo);
            assert_eq!(one.eval(wf, wi), two.eval(wf, wi));
        }
    }
    // Dielectrics have two sides by nature and ignore the flag.
    let glass = Material::new(Bsdf::Dielectric(Dielectric::new(1.5)), false);
    assert!(glass
        .sample(
            dir(180.0 - 20.0, 0.0),
            0.99,
            Vec2::ZERO,
            TransportMode::Radiance
        )
        .is_some());
}

// ---------------------------------------------------------------------------------------------
// Smooth dielectric
// ---------------------------------------------------------------------------------------------

/// Textbook unpolarised Fresnel reflectance (Hecht, *Optics*, eqs. 4.42–4.43), in f64, for
/// light crossing from index n1 into n2 at incidence cos θi ≥ 0:
/// r_s = (n1 cos θi − n2 cos θt)/(n1 cos θi + n2 cos θt),
/// r_p = (n2 cos θi − n1 cos θt)/(n2 cos θi + n1 cos θt), R = (r_s² + r_p²)/2.
fn fresnel_textbook(cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The indices on wo's side and on the other side, for relative index `eta` (inside over
/// outside; the normal points outside).
fn indices(wo: Vec3A, eta: f64) -> (f64, f64) {
    if wo.z > 0.0 {
        (1.0, eta)
    } else {
        (eta, 1.0)
    }
}

#[test]
fn fresnel_matches_textbook_values() {
    // Normal incidence: ((n − 1)/(n + 1))², from either side.
    for eta in [1.5f32, 1.33, 2.4] {
        let r0 = ((eta as f64 - 1.0) / (eta as f64 + 1.0)).powi(2);
        assert!((fresnel_dielectric(1.0, eta) as f64 - r0).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, eta) as f64 - r0).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / eta) as f64 - r0).abs() < 1e-6);
    }
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-7);
    // Brewster's angle tan θB = n2/n1: r_p = 0, and with cos θi = 1/√(1+η²),
    // cos θt = η/√(1+η²), r_s = (1 − η²)/(1 + η²), so R = r_s²/2.
    for eta in [1.5f64, 1.33, 2.4] {
        let rb = 0.5 * ((1.0 - eta * eta) / (1.0 + eta * eta)).powi(2);
        let cos_out = 1.0 / (1.0 + eta * eta).sqrt(); // from outside, tan θB = η
        let cos_in = eta / (1.0 + eta * eta).sqrt(); // from inside, tan θB = 1/η
        assert!(
            (fresnel_dielectric(cos_out as f32, eta as f32) as f64 - rb).abs() < 1e-6,
            "η {eta}"
        );
        assert!(
            (fresnel_dielectric(-cos_in as f32, eta as f32) as f64 - rb).abs() < 1e-6,
            "η {eta}"
        );
    }
    // Everywhere else, against Hecht's equations. Near the critical angle R has an infinite
    // derivative in cos θi; the tolerance there follows from the f32 rounding of
    // sin²θt (δ ≈ 2u) through cos θt = √(1 − sin²θt): |dR| ≲ 4·δ/cos θt.
    for eta in [1.5f64, 1.0 / 1.5, 1.33, 2.4] {
        for k in 0..=2000 {
            let cos_i = -1.0 + 2.0 * k as f64 / 2000.0;
            let (n1, n2) = if cos_i >= 0.0 { (1.0, eta) } else { (eta, 1.0) };
            let cos_i = cos_i as f32 as f64;
            let r = fresnel_textbook(cos_i.abs(), n1, n2);
            let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i);
            let tol = 1e-6 + 8.0 * f32::EPSILON as f64 / (1.0 - sin2_t).max(1e-12).sqrt();
            let got = fresnel_dielectric(cos_i as f32, eta as f32) as f64;
            assert!(
                (got - r).abs() <= tol || (sin2_t - 1.0).abs() < 1e-6,
                "η {eta}, cos θi {cos_i}: {got} vs {r}"
            );
        }
    }
    // Total internal reflection beyond the critical angle sin θc = 1/1.5.
    let cos_c = (1.0f64 - 1.0 / 2.25).sqrt();
    for cos_i in [cos_c * 0.999, 0.5, 0.1, 0.0001] {
        assert_eq!(fresnel_dielectric(-cos_i as f32, 1.5), 1.0);
        assert_eq!(fresnel_dielectric(cos_i as f32, 1.0 / 1.5), 1.0);
    }
}

/// Sampling the dielectric: the fraction of reflections is the Fresnel reflectance (within
/// Z binomial standard deviations); reflections are mirror images with weight 1; refractions
/// obey Snell's law n_o sin θo = n_i sin θi, stay in the plane of incidence on the other side,
/// and carry weight (n_o/n_i)² = 1/η² with η = n_i/n_o = η_t/η_i in radiance mode (radiance
/// scales as n², Veach 1997 §5.2) and 1 in importance mode; beyond the critical angle
/// everything reflects.
#[test]
fn dielectric_sampling() {
    const N: usize = 40_000;
    let mut rng = Rng::new(13);
    for eta in [1.5f32, 1.0 / 1.5] {
        let m = Material::new(Bsdf::Dielectric(Dielectric::new(eta)), false);
        for side in [1.0f32, -1.0] {
            for theta in [0.0f64, 20.0, 40.0, 45.0, 60.0, 80.0, 89.0] {
                let mut wo = dir(theta, 0.3 + theta / 10.0);
                wo.z *= side;
                let (n_o, n_i) = indices(wo, eta as f64);
                let r = fresnel_textbook(wo.z.abs() as f64, n_o, n_i);
                let mut reflected = 0usize;
                for k in 0..N {
                    let mode = if k % 2 == 0 {
                        TransportMode::Radiance
                    } else {
                        TransportMode::Importance
                    };
                    let s = m
                        .sample(wo, rng.f(), rng.u2(), mode)
                        .expect("a dielectric always scatters");
                    assert!(s.specular && s.pdf == 0.0);
                    assert!((s.wi.length() - 1.0).abs() < 1e-5);
                    if s.wi.z * wo.z > 0.0 {
                        reflected += 1;
                        assert_eq!(s.wi, Vec3A::new(-wo.x, -wo.y, wo.z));
                        assert_eq!((s.weight, s.eta), (Color::ONE, 1.0));
                    } else {
                        // Snell's law (sines from the tangential components).
                        let sin_o = (wo.x as f64).hypot(wo.y as f64);
                        let sin_i = (s.wi.x as f64).hypot(s.wi.y as f64);
                        assert!(
                            (n_o * sin_o - n_i * sin_i).abs() < 2e-6 * n_o.max(n_i),
                            "θo {theta}: {n_o}·{sin_o} vs {n_i}·{sin_i}"
                        );
                        // In the plane of incidence, on the far side of the normal.
                        if sin_o > 1e-3 {
                            let cross = wo.x * s.wi.y - wo.y * s.wi.x;
                            assert!(
                                cross.abs() < 1e-5 && wo.x * s.wi.x + wo.y * s.wi.y < 0.0,
                                "wo {wo:?}, wi {:?}",
                                s.wi
                            );
                        }
                        assert!(((s.eta as f64) - n_i / n_o).abs() < 1e-6);
                        let expected = if mode == TransportMode::Radiance {
                            (n_o / n_i).powi(2)
                        } else {
                            1.0
                        };
                        assert!(
                            (s.weight.x as f64 - expected).abs() < 1e-6
                                && s.weight.x == s.weight.y
                                && s.weight.y == s.weight.z
                        );
                    }
                }
                let sd = (N as f64 * r * (1.0 - r)).sqrt();
                if r == 1.0 {
                    assert_eq!(
                        reflected, N,
                        "η {eta}, θo {theta} (side {side}): beyond the critical angle"
                    );
                } else {
                    // f32 rounding of F (≲ 1e-5) adds at most N·1e-5 ≈ 0.4 counts.
                    let mean = N as f64 * r;
                    assert!(
                        (reflected as f64 - mean).abs() <= Z * sd + 1.0,
                        "η {eta}, θo {theta}, side {side}: {reflected} reflections, \
                         expected {mean:.1} ± {sd:.1}"
                    );
                }
            }
        }
    }
}

/// Dielectrics are delta BSDFs: eval and pdf are zero, in either mode and on either side.
#[test]
fn dielectric_eval_and_pdf_are_zero() {
    let mut rng = Rng::new(14);
    let m = Material::new(Bsdf::Dielectric(Dielectric::new(1.5)), true);
    assert!(m.is_specular());
    for _ in 0..1000 {
        let (wo, wi) = (rng.sphere(), rng.sphere());
        assert_eq!(m.eval(wo, wi), Color::ZERO);
        assert_eq!(m.pdf(wo, wi), 0.0);
    }
}
