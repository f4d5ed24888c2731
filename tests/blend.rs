//! `blendbsdf`: the mixture a blend resolves to at a hit (f and pdf the weighted sums of its
//! parts', nested blends flattened), consistency of its `sample` with `eval` and `pdf`, and
//! chi-square tests of its sampling against its pdf (the harness of tests/bsdf.rs).

#[path = "common/stats.rs"]
mod stats;

use glam::{Vec2, Vec3A};
use mcrt::material::{
    Binding, Blend, Bsdf, Lambert, Material, Microfacet, MicrofacetType, Plastic, RoughConductor,
    RoughDielectric, RoughPlastic, TransportMode,
};
use mcrt::texture::{Texture, UvTransform};
use mcrt::Color;
use stats::*;

const CHI2_CASES: f64 = 8.0;
const ALPHA: f64 = 0.01 / CHI2_CASES;

/// The parts the blends below refer to by index.
fn parts() -> Vec<Material> {
    let ggx = |a: f32| Microfacet::new(MicrofacetType::Ggx, a, a);
    let beckmann = |a: f32| Microfacet::new(MicrofacetType::Beckmann, a, a);
    vec![
        // 0
        Material::new(
            Bsdf::Lambert(Lambert {
                albedo: Color::new(0.8, 0.5, 0.2),
            }),
            false,
        ),
        // 1
        Material::new(
            Bsdf::RoughConductor(RoughConductor::new(
                ggx(0.15),
                Color::new(0.2, 0.9, 1.1),
                Color::new(3.9, 2.4, 2.2),
                Color::ONE,
            )),
            false,
        ),
        // 2
        Material::new(
            Bsdf::RoughDielectric(RoughDielectric::new(beckmann(0.3), 1.5)),
            false,
        ),
        // 3
        Material::new(
            Bsdf::RoughPlastic(RoughPlastic::new(
                MicrofacetType::Ggx,
                0.2,
                1.5,
                Color::new(0.1, 0.6, 0.3),
                Color::ONE,
                false,
            )),
            false,
        ),
        // 4: a delta lobe and a diffuse one
        Material::new(
            Bsdf::Plastic(Plastic::new(1.5, Color::splat(0.5), Color::ONE, false)),
            false,
        ),
    ]
}

fn blend(weight: f32, first: u32, second: u32, two_sided: bool) -> Material {
    Material::new(
        Bsdf::Blend(Blend {
            weight,
            first,
            second,
        }),
        two_sided,
    )
}

/// The scene's materials: the parts, then the blends; returns them and the blends' indices.
fn scene() -> (Vec<Material>, Vec<u32>) {
    let mut m = parts();
    let n = m.len() as u32;
    m.extend([
        blend(0.3, 0, 1, false),        // n: diffuse + metal
        blend(0.6, 2, 3, true),         // n+1: glass + rough plastic, two-sided
        blend(0.25, n, 3, false),       // n+2: nested: (diffuse + metal) + plastic
        blend(0.5, 4, 1, false),        // n+3: smooth plastic (delta) + metal
        blend(0.7, n + 2, n + 1, true), // n+4: three levels
    ]);
    (m, (n..n + 5).collect())
}

fn at(materials: &[Material], i: u32) -> Material {
    materials[i as usize].at(materials, &[], Vec2::ZERO, None)
}

/// The mixture of a resolved blend is the weighted sum of its parts, recursively: f and
/// pdf at random directions in both transport modes, and the albedo.
#[test]
fn mixture_is_the_weighted_sum_of_the_parts() {
    let (ms, blends) = scene();
    let n = blends[0];
    // (blend, [(part, weight)]) expanded by hand.
    let expect: Vec<(u32, Vec<(u32, f32)>)> = vec![
        (n, vec![(0, 0.7), (1, 0.3)]),
        (n + 2, vec![(0, 0.75 * 0.7), (1, 0.75 * 0.3), (3, 0.25)]),
        (n + 3, vec![(4, 0.5), (1, 0.5)]),
    ];
    let mut rng = Rng::new(7);
    for (b, leaves) in &expect {
        let m = at(&ms, *b);
        assert_eq!(m.mix.as_ref().map(|p| p.len()), Some(leaves.len()));
        for _ in 0..2000 {
            let (wo, wi) = (rng.sphere(), rng.sphere());
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let f: Color = leaves
                    .iter()
                    .map(|&(i, w)| ms[i as usize].eval_mode(wo, wi, mode) * w)
                    .sum();
                let got = m.eval_mode(wo, wi, mode);
                assert!(
                    (got - f).abs().max_element() <= 1e-5 * f.max_element() + 1e-7,
                    "blend {b}: f {got:?} vs {f:?}"
                );
            }
            let pdf: f32 = leaves
                .iter()
                .map(|&(i, w)| ms[i as usize].pdf(wo, wi) * w)
                .sum();
            assert!((m.pdf(wo, wi) - pdf).abs() <= 1e-5 * pdf + 1e-7);
            let (f, p) = m.eval_pdf(wo, wi);
            assert_eq!((f, p), (m.eval(wo, wi), m.pdf(wo, wi)));
        }
        let albedo: Color = leaves
            .iter()
            .map(|&(i, w)| ms[i as usize].albedo() * w)
            .sum();
        assert!((m.albedo() - albedo).abs().max_element() < 1e-6);
        assert!(!m.is_specular() && !m.is_black());
    }
}

/// A weight of 0 or 1 leaves one part, without a mixture; a two-sided blend makes its parts
/// two-sided.
#[test]
fn extreme_weights_and_sides() {
    let (mut ms, _) = scene();
    let n = ms.len() as u32;
    ms.push(blend(0.0, 0, 1, false));
    ms.push(blend(1.0, 0, 1, true));
    let zero = at(&ms, n);
    assert!(zero.mix.is_none() && matches!(zero.bsdf, Bsdf::Lambert(_)) && !zero.two_sided);
    let one = at(&ms, n + 1);
    assert!(one.mix.is_none() && matches!(one.bsdf, Bsdf::RoughConductor(_)) && one.two_sided);
    // Seen from below, the one-sided blend reflects nothing and the two-sided one does.
    let (wo, wi) = (dir(180.0 - 30.0, 0.3), dir(180.0 - 50.0, 2.0));
    let (ms2, blends) = scene();
    assert_eq!(at(&ms2, blends[0]).eval(wo, wi), Color::ZERO);
    let mut two = blend(0.3, 0, 1, true);
    two.two_sided = true;
    let mut ms3 = ms2.clone();
    ms3.push(two);
    let m = at(&ms3, ms3.len() as u32 - 1);
    assert!(m.eval(wo, wi).max_element() > 0.0);
    let up = at(&ms2, blends[0]);
    let flip = |w: Vec3A| Vec3A::new(w.x, w.y, -w.z);
    assert!(
        (m.eval(wo, wi) - up.eval(flip(wo), flip(wi)))
            .abs()
            .max_element()
            < 1e-6
    );
}

/// A textured weight: the blend's weight per hit is the texture's float there.
#[test]
fn textured_weight() {
    let (mut ms, _) = scene();
    let n = ms.len() as u32;
    let textures = vec![Texture::Checkerboard {
        color0: Color::splat(0.2),
        color1: Color::splat(0.9),
        to_uv: UvTransform::IDENTITY,
    }];
    let weight = mcrt::slot!(Float, Blend, |b, v| b.weight = v);
    ms.push(blend(0.55, 0, 1, false).with_slots(vec![Binding {
        texture: 0,
        slot: weight,
    }]));
    let (wo, wi) = (dir(20.0, 0.0), dir(35.0, 3.0));
    let (f0, f1) = (ms[0].eval(wo, wi), ms[1].eval(wo, wi));
    // eval_1 of the checkerboard: color1 in the cell (¼, ¼), color0 in (¾, ¼).
    for (uv, w) in [(Vec2::splat(0.25), 0.9), (Vec2::new(0.75, 0.25), 0.2)] {
        let m = ms[n as usize].at(&ms, &textures, uv, None);
        let f = f0 * (1.0 - w) + f1 * w;
        assert!((m.eval(wo, wi) - f).abs().max_element() < 1e-6, "{uv}");
    }
}

/// `sample` agrees with `eval` and `pdf` of the whole mixture for non-delta samples; delta
/// samples (smooth plastic's coating) carry that part's own weight.
#[test]
fn sample_is_consistent_with_eval_and_pdf() {
    let (ms, blends) = scene();
    let mut rng = Rng::new(11);
    for &b in &blends {
        let m = at(&ms, b);
        let (mut n, mut delta) = (0, 0);
        for k in 0..20_000 {
            let mode = if k % 2 == 0 {
                TransportMode::Radiance
            } else {
                TransportMode::Importance
            };
            let wo = rng.sphere();
            let u1 = rng.f();
            let Some(s) = m.sample(wo, u1, rng.u2(), mode) else {
                continue;
            };
            assert!((s.wi.length() - 1.0).abs() < 1e-4);
            if s.specular {
                // Only the smooth plastic has a delta lobe (tested on its own below).
                assert_eq!(s.pdf, 0.0);
                assert!(s.weight.max_element() > 0.0);
                delta += 1;
                continue;
            }
            n += 1;
            let pdf = m.pdf(wo, s.wi);
            assert!(
                (s.pdf - pdf).abs() <= 1e-3 * pdf,
                "blend {b}: pdf {} vs {pdf}",
                s.pdf
            );
            let expected = m.eval_mode(wo, s.wi, mode) * s.wi.z.abs() / pdf;
            assert!(
                (s.weight - expected).abs().max_element() <= 1e-3 * expected.max_element() + 1e-7,
                "blend {b} {mode:?}: weight {:?} vs {expected:?}",
                s.weight
            );
        }
        assert!(n > 5_000, "blend {b}: {n} samples");
        assert_eq!(
            delta > 0,
            b == blends[3],
            "blend {b}: {delta} delta samples"
        );
    }
}

/// Delta samples of a blend: the coating's reflection of the smooth plastic, with the
/// plastic's own weight, chosen with the plastic's share times its own probability.
#[test]
fn delta_samples_keep_their_part_weight() {
    let (ms, blends) = scene();
    let m = at(&ms, blends[3]);
    let plastic = &ms[4];
    let wo = dir(40.0, 1.0);
    let mut rng = Rng::new(3);
    let (mut delta, total) = (0usize, 200_000usize);
    for _ in 0..total {
        let u1 = rng.f();
        let u2 = rng.u2();
        if let Some(s) = m.sample(wo, u1, u2, TransportMode::Radiance) {
            if s.specular {
                delta += 1;
                // The plastic sampled on its own with u1 rescaled into its half.
                let own = plastic
                    .sample(wo, (u1 / 0.5).min(0.999_999), u2, TransportMode::Radiance)
                    .unwrap();
                assert!(own.specular);
                assert!((own.weight - s.weight).abs().max_element() < 1e-5);
            }
        }
    }
    // P(delta) = ½ · P_plastic(delta at wo).
    let mut p_own = 0usize;
    let mut rng = Rng::new(5);
    for _ in 0..total {
        let u1 = rng.f();
        if plastic
            .sample(wo, u1, rng.u2(), TransportMode::Radiance)
            .is_some_and(|s| s.specular)
        {
            p_own += 1;
        }
    }
    let (a, b) = (
        delta as f64 / total as f64,
        0.5 * p_own as f64 / total as f64,
    );
    let sd = (a * (1.0 - a) / total as f64).sqrt() + (b * (1.0 - b) / total as f64).sqrt();
    assert!((a - b).abs() < 5.0 * sd, "{a} vs {b}");
}

/// Chi-square tests of the blends' sampling (non-delta samples) against their pdfs, from
/// above and below.
#[test]
fn chi2_blends() {
    let (ms, blends) = scene();
    let cases: Vec<(u32, Vec3A)> = vec![
        (blends[0], dir(30.0, 0.4)),
        (blends[0], dir(75.0, 2.0)),
        (blends[1], dir(40.0, 1.0)),
        (blends[1], dir(180.0 - 50.0, 0.5)),
        (blends[2], dir(10.0, 0.2)),
        (blends[3], dir(60.0, 1.7)),
        (blends[4], dir(20.0, 0.9)),
        (blends[4], dir(180.0 - 65.0, 4.0)),
    ];
    assert_eq!(cases.len() as f64, CHI2_CASES);
    let mut failures = Vec::new();
    for (k, &(b, wo)) in cases.iter().enumerate() {
        let m = at(&ms, b);
        let (stat, dof, p) = chi2_test_k(
            |rng| {
                let u1 = rng.f();
                m.sample(wo, u1, rng.u2(), TransportMode::Radiance)
                    .filter(|s| !s.specular)
                    .map(|s| s.wi)
            },
            &|wi| m.pdf(wo, wi) as f64,
            500 + k as u64,
            128,
        );
        eprintln!("blend {b} wo {wo:?}: χ² = {stat:.1}, dof {dof}, p = {p:.3}");
        if p < ALPHA {
            failures.push(format!(
                "blend {b} at wo {wo:?}: χ² = {stat:.1}, dof {dof}, p = {p:e}"
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "rejected at significance {ALPHA:e}:\n{}",
        failures.join("\n")
    );
}

/// The test can fail: a mixture sampled with the wrong weights is rejected.
#[test]
fn chi2_rejects_wrong_weights() {
    let (ms, blends) = scene();
    let m = at(&ms, blends[0]);
    let wo = dir(30.0, 0.4);
    let mut ms2 = ms.clone();
    ms2[blends[0] as usize] = blend(0.5, 0, 1, false);
    let other = at(&ms2, blends[0]);
    let (stat, dof, p) = chi2_test_k(
        |rng| {
            let u1 = rng.f();
            other
                .sample(wo, u1, rng.u2(), TransportMode::Radiance)
                .map(|s| s.wi)
        },
        &|wi| m.pdf(wo, wi) as f64,
        77,
        32,
    );
    assert!(p < 1e-6, "χ² = {stat:.1}, dof {dof}, p = {p}");
}
