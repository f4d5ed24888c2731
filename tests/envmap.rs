//! The `envmap` emitter: Mitsuba's latitude-longitude convention, its importance sampling
//! (chi-square against its pdf, the pdf's integral), the estimate of its power, and the
//! light's use through `Lights` (environment lookup and light samples agree).

#[path = "common/stats.rs"]
mod stats;

use glam::{Mat3, Vec2, Vec3A};
use mcrt::light::envmap::{fault, EnvMap};
use mcrt::light::{Lights, OtherLight};
use mcrt::texture::Bitmap;
use mcrt::Color;
use stats::*;
use std::f64::consts::PI;

/// A non-uniform 8×6 map: a bright sun-like pixel, a dark band, colour gradients and a black
/// column (whose cells still get samples where a neighbour is lit).
fn image() -> Bitmap {
    let (w, h) = (8u32, 6u32);
    let px = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            match (x, y) {
                (5, 2) => Color::new(60.0, 50.0, 40.0),
                (_, 4) => Color::splat(0.01),
                (2, _) => Color::ZERO,
                _ => Color::new(0.2 + 0.1 * x as f32, 0.5, 0.1 + 0.2 * y as f32),
            }
        })
        .collect();
    Bitmap::from_pixels(w, h, px).unwrap()
}

/// Mitsuba's direction of texture coordinates (u, v), written out independently of the
/// crate: φ = 2πu, θ = πv, (sin φ sin θ, cos θ, −cos φ sin θ).
fn direction(u: f64, v: f64) -> Vec3A {
    let (t, p) = (v * PI, u * 2.0 * PI);
    Vec3A::new(
        (p.sin() * t.sin()) as f32,
        t.cos() as f32,
        (-p.cos() * t.sin()) as f32,
    )
}

/// Each pixel's value is the radiance from its centre's direction, (x + ½)/W across and
/// y/(H − 1) down (checked against Mitsuba 3.9's `eval` on a 4×3 image: −z reads between
/// the last and first columns, +x between the first and second), and between centres the
/// lookup is bilinear.
#[test]
fn latitude_longitude_convention() {
    let img = image();
    let env = EnvMap::new(&img, 2.0, Mat3::IDENTITY);
    let (w, h) = (img.width as usize, img.height as usize);
    for y in 1..h - 1 {
        for x in 0..w {
            let d = direction((x as f64 + 0.5) / w as f64, y as f64 / (h - 1) as f64);
            let got = env.eval(d);
            let want = img.pixel(y * w + x) * 2.0;
            assert!((got - want).abs().max_element() <= 1e-4 * want.max_element().max(1.0));
        }
    }
    // Half-way between columns 7 and 0 of row 1: straight along −z at v = 1/5.
    let d = direction(0.0, 0.2);
    let want = (img.pixel(w + 7) + img.pixel(w)) * 0.5 * 2.0;
    assert!((env.eval(d) - want).abs().max_element() < 1e-4);
    // A rotation: the map turned by 90° about y sees along +x what it saw along −z.
    let rot = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let turned = EnvMap::new(&img, 2.0, rot);
    let a = env.eval(Vec3A::new(0.3, 0.4, -0.8));
    let b = turned.eval(Vec3A::from(rot * glam::Vec3::new(0.3, 0.4, -0.8)));
    assert!((a - b).abs().max_element() < 1e-4, "{a} {b}");
}

/// Sampled directions, binned by the texture coordinates the test computes itself, follow
/// the solid-angle pdf: the expected count of a bin is ∫ pdf dω with dω = 2π² sin θ du dv. The bins (7 × 9) do not line up with the map's cells. The map is turned, so
/// the test also covers `to_world`.
#[test]
fn chi2_sampling_matches_pdf() {
    let rot = Mat3::from_rotation_x(0.7) * Mat3::from_rotation_y(-1.9);
    let env = EnvMap::new(&image(), 1.0, rot);
    let to_local = rot.transpose();
    let (bu, bv) = (7usize, 9usize);
    let uv_of = |d: Vec3A| {
        let l = glam::Vec3::from(d);
        let l = to_local * l;
        let mut u = (l.x as f64).atan2(-(l.z as f64)) / (2.0 * PI);
        if u < 0.0 {
            u += 1.0;
        }
        (u, (l.y as f64).clamp(-1.0, 1.0).acos() / PI)
    };
    let bin = |u: f64, v: f64| {
        let i = ((u * bu as f64) as usize).min(bu - 1);
        let j = ((v * bv as f64) as usize).min(bv - 1);
        j * bu + i
    };
    let mut rng = Rng::new(7);
    let n = 1_000_000usize;
    let mut observed = vec![0.0f64; bu * bv];
    for _ in 0..n {
        if let Some((d, _, pdf)) = env.sample(rng.u2()) {
            assert!(pdf > 0.0 && (d.length() - 1.0).abs() < 1e-4);
            let (u, v) = uv_of(d);
            observed[bin(u, v)] += 1.0;
        }
    }
    // Expected: pdf · sin θ is constant on each of the map's cells (8 columns from u = 1/16,
    // 5 rows), so the integral over each piece between bin and cell edges is exact.
    let mut us: Vec<f64> = (0..=bu).map(|i| i as f64 / bu as f64).collect();
    us.extend((0..8).map(|k| (k as f64 + 0.5) / 8.0));
    let mut vs: Vec<f64> = (0..=bv).map(|j| j as f64 / bv as f64).collect();
    vs.extend((0..=5).map(|k| k as f64 / 5.0));
    for e in [&mut us, &mut vs] {
        e.sort_by(|a, b| a.partial_cmp(b).unwrap());
        e.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    }
    let mut expected = vec![0.0f64; bu * bv];
    for v in vs.windows(2) {
        for u in us.windows(2) {
            let (um, vm) = (0.5 * (u[0] + u[1]), 0.5 * (v[0] + v[1]));
            let d = Vec3A::from(rot * glam::Vec3::from(direction(um, vm)));
            let area = (u[1] - u[0]) * (v[1] - v[0]);
            let g = env.pdf(d) as f64 * 2.0 * PI * PI * (vm * PI).sin();
            expected[bin(um, vm)] += g * area * n as f64;
        }
    }
    let total: f64 = expected.iter().sum::<f64>() / n as f64;
    assert!((total - 1.0).abs() < 2e-3, "the pdf integrates to {total}");
    let mut stat = 0.0;
    let mut cells = 0;
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            assert!(*o <= 20.0, "{o} samples where {e} were expected");
            continue;
        }
        stat += (o - e).powi(2) / e;
        cells += 1;
    }
    let p = chi2_pvalue(stat, cells - 1);
    assert!(p > 0.01, "χ² = {stat:.1} over {cells} cells, p = {p:e}");
}

/// The test above can fail: samples of a different map (another bright pixel) are rejected
/// against this map's pdf.
#[test]
fn chi2_rejects_another_maps_samples() {
    let env = EnvMap::new(&image(), 1.0, Mat3::IDENTITY);
    let mut other: Vec<_> = image().pixels().collect();
    other.swap(2 * 8 + 5, 3 * 8 + 1);
    let other = EnvMap::new(
        &Bitmap::from_pixels(8, 6, other).unwrap(),
        1.0,
        Mat3::IDENTITY,
    );
    let (stat, dof, p) = chi2_test_k(
        |rng| other.sample(rng.u2()).map(|s| s.0),
        &|d| env.pdf(d) as f64,
        3,
        32,
    );
    assert!(p < 1e-6, "χ² = {stat:.1}, dof {dof}, p = {p:e}");
}

/// The solid-angle pdf integrates to one over the sphere (midpoint rule in (z, φ), the
/// map's poles turned onto the x axis so that they are no grid line), and the sample's
/// density is `pdf` of its direction.
#[test]
fn pdf_integrates_to_one() {
    let rot = Mat3::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let env = EnvMap::new(&image(), 3.0, rot);
    let (nz, nphi) = (1024usize, 2048usize);
    let mut sum = 0.0f64;
    for i in 0..nz {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
        for j in 0..nphi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
            sum += env.pdf(dir_z(z, phi)) as f64;
        }
    }
    sum *= (2.0 / nz as f64) * (2.0 * PI / nphi as f64);
    assert!((sum - 1.0).abs() < 5e-3, "∫ pdf dω = {sum}");
    let mut rng = Rng::new(3);
    for _ in 0..2000 {
        let (d, le, pdf) = env.sample(rng.u2()).unwrap();
        let back = env.pdf(d);
        assert!((pdf - back).abs() <= 1e-3 * pdf, "{pdf} vs {back}");
        assert!((le - env.eval(d)).abs().max_element() <= 1e-3 * le.max_element().max(1e-3));
    }
}

/// E[Le / pdf] over the samples is ∫ Le dω, which a fine quadrature of `eval` gives too and
/// which `mean` estimates (4π times it).
#[test]
fn sampling_estimates_the_integral() {
    let env = EnvMap::new(&image(), 1.0, Mat3::IDENTITY);
    let mut rng = Rng::new(11);
    let n = 400_000;
    let (est, err) = mean_and_stderr((0..n).map(|_| {
        env.sample(rng.u2())
            .map_or(0.0, |(_, le, pdf)| (le.x / pdf) as f64)
    }));
    let (nu, nv) = (1024usize, 1024usize);
    let mut quad = 0.0f64;
    for j in 0..nv {
        let v = (j as f64 + 0.5) / nv as f64;
        for i in 0..nu {
            let u = (i as f64 + 0.5) / nu as f64;
            quad += env.eval(direction(u, v)).x as f64 * (v * PI).sin();
        }
    }
    quad *= 2.0 * PI * PI / (nu * nv) as f64;
    assert!(
        (est - quad).abs() < 5.0 * err + 1e-3 * quad,
        "{est} ± {err} vs {quad}"
    );
    let mean = env.mean().x as f64 * 4.0 * PI;
    assert!((mean - quad).abs() < 5e-3 * quad, "{mean} vs {quad}");
}

/// Through `Lights`: the environment seen by an escaping ray is the map's radiance, with the
/// light-sampling density its pdf times the probability of choosing it.
#[test]
fn lights_see_the_map() {
    let env = std::sync::Arc::new(EnvMap::new(&image(), 1.0, Mat3::IDENTITY));
    let point = OtherLight::Point {
        p: Vec3A::new(0.0, 5.0, 0.0),
        intensity: Color::splat(30.0),
    };
    let lights = Lights::with_others(
        Vec::new(),
        vec![point, OtherLight::Envmap(env.clone())],
        2.0,
    );
    let mut rng = Rng::new(5);
    let mut seen = 0;
    for _ in 0..2000 {
        let Some(s) = lights.sample(Vec3A::ZERO, rng.f(), rng.u2()) else {
            continue;
        };
        if s.delta {
            continue;
        }
        seen += 1;
        assert!(s.infinite);
        let (le, pdf) = lights.environment(s.wi).unwrap();
        assert!((le - s.le).abs().max_element() <= 1e-3 * le.max_element().max(1e-3));
        assert!((pdf - s.pdf).abs() <= 1e-3 * pdf, "{pdf} vs {}", s.pdf);
        assert!(
            pdf < env.pdf(s.wi),
            "the choice of the light is in the density"
        );
    }
    assert!(seen > 100);
}

#[test]
fn small_images_and_skewed_frames_are_refused() {
    assert!(fault(8, 6, Mat3::IDENTITY).is_none());
    assert!(fault(8, 6, Mat3::from_rotation_x(1.0) * 3.0).is_none());
    assert!(fault(1, 6, Mat3::IDENTITY).unwrap().contains("2×3"));
    assert!(fault(8, 2, Mat3::IDENTITY).unwrap().contains("2×3"));
    let skew = Mat3::from_cols(glam::Vec3::X, glam::Vec3::new(0.5, 1.0, 0.0), glam::Vec3::Z);
    assert!(fault(8, 6, skew).unwrap().contains("rotation"));
    assert!(fault(8, 6, Mat3::from_diagonal(glam::Vec3::new(1.0, 2.0, 1.0))).is_some());
    assert!(fault(8, 6, Mat3::ZERO).is_some());
}

/// A Radiance HDR file decodes to the same map as its pixels (through `Bitmap::decode`).
#[test]
fn hdr_files_load_as_bitmaps() {
    let img = image();
    let bytes = mcrt::rgbe::encode(img.width, img.height, &img.pixels().collect::<Vec<_>>());
    let back = Bitmap::decode(&bytes, false).unwrap();
    assert_eq!((back.width, back.height), (8, 6));
    for (a, b) in img.pixels().zip(back.pixels()) {
        assert!((a - b).abs().max_element() <= a.max_element() / 100.0 + 1e-6);
    }
    let _ = Vec2::ZERO;
}

/// Photons leave spot and envmap lights with their power: the first hits on what catches
/// every photon carry, in sum, the spot's emitted power I · 2π ∫ falloff(θ) sin θ dθ, and
/// for an environment around a sphere of radius r, π r² ∫ L dω. (Within 5 standard errors
/// of the photons' powers.)
#[test]
fn photons_carry_the_power_of_spot_and_envmap() {
    use mcrt::photon::trace::{trace_photons, TraceOptions};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let sky = root.join("tests/data/mitsuba/features/sky.hdr");
    let load = |text: &str| {
        let desc = mcrt::scene::toml::parse_toml(&root.join("photons.toml"), text).unwrap();
        mcrt::scene::Scene::build(desc)
    };
    let first_hits = |scene: &mcrt::scene::Scene| {
        let n = 200_000;
        let t = trace_photons(scene, n, &TraceOptions::default());
        // Each photon's contribution to the sum, the ones that hit nothing (or were
        // dropped) as 0.
        let direct: Vec<f64> = t
            .photons
            .iter()
            .filter(|p| p.depth() == 1)
            .map(|p| p.power().x as f64 * n as f64)
            .collect();
        let missing = n as usize - direct.len();
        mean_and_stderr(direct.into_iter().chain(std::iter::repeat_n(0.0, missing)))
    };
    // A spot 1 above a floor that catches its whole cone (cutoff 30°, beam 10°).
    let spot = load(
        "[material.m]\ntype = \"lambert\"\nalbedo = 0.5\n\n[[shape]]\ntype = \"quad\"\n\
         material = \"m\"\nvertices = [[-5, 0, 5], [5, 0, 5], [5, 0, -5], [-5, 0, -5]]\n\n\
         [[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n\
         intensity = 3\ncutoff_angle = 30\nbeam_width = 10\n",
    );
    let (got, err) = first_hits(&spot);
    let (c, b) = (30f64.to_radians(), 10f64.to_radians());
    let m = 100_000;
    let want: f64 = 3.0
        * 2.0
        * PI
        * (0..m)
            .map(|k| {
                let t = c * (k as f64 + 0.5) / m as f64;
                let f = if t <= b { 1.0 } else { (c - t) / (c - b) };
                f * t.sin() * c / m as f64
            })
            .sum::<f64>();
    assert!(
        (got - want).abs() < 5.0 * err + 1e-3 * want,
        "spot: {got} ± {err} vs {want}"
    );
    // A sphere of radius 0.5 under the sky.
    let env = load(&format!(
        "[material.m]\ntype = \"lambert\"\nalbedo = 0.5\n\n[[shape]]\ntype = \"sphere\"\n\
         material = \"m\"\ncenter = [0, 0, 0]\nradius = 0.5\n\n[[light]]\n\
         type = \"envmap\"\nfile = {:?}\nscale = 2\n",
        sky.display().to_string()
    ));
    let (got, err) = first_hits(&env);
    let img = Bitmap::load(&sky, false).unwrap();
    let map = EnvMap::new(&img, 2.0, Mat3::IDENTITY);
    let want = PI * 0.25 * 4.0 * PI * map.mean().x as f64;
    assert!(
        (got - want).abs() < 5.0 * err + 5e-3 * want,
        "envmap: {got} ± {err} vs {want}"
    );
}

/// `photon` and `sppm` render the spot and envmap feature scenes as Mitsuba's path tracer
/// does: the whole image's mean within 2 % and 16×16-pixel block means within 12 % (16 spp;
/// the photon estimates' bias and noise). Without photons from those lights the indirect
/// light, and with it a tenth of the image or more, would be missing.
#[test]
fn photon_integrators_render_spot_and_envmap() {
    use mcrt::integrator::IntegratorKind;
    use mcrt::scene::desc::FileSettings;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for name in ["spot", "envmap"] {
        let desc = mcrt::load_scene(&root.join(format!("tests/data/mitsuba/features/{name}.xml")))
            .unwrap();
        let fs = desc.settings.clone();
        let scene = mcrt::scene::Scene::build(desc);
        let reference =
            mcrt::image::read_exr(&root.join(format!("tests/data/refs/{name}.exr"))).unwrap();
        for integrator in [IntegratorKind::Photon, IntegratorKind::Sppm] {
            let over = FileSettings {
                integrator: Some(integrator),
                spp: Some(16),
                ..Default::default()
            };
            let s = mcrt::resolve_settings(&fs, &over, None).unwrap();
            let (film, _) = mcrt::render::render(&scene, &s, &|_| {}).unwrap();
            let img = film.image();
            let lum = |b: [f64; 3]| (b[0] + b[1] + b[2]) / 3.0;
            let (bx, by) = (img.width / 16, img.height / 16);
            let mut sum = (0.0, 0.0);
            for y in 0..by {
                for x in 0..bx {
                    let (a, r) = (
                        lum(img.block_mean(x, y, 16)),
                        lum(reference.block_mean(x, y, 16)),
                    );
                    sum = (sum.0 + a, sum.1 + r);
                    assert!(
                        (a - r).abs() <= 0.12 * r.max(0.01),
                        "{name} by {integrator:?}: block ({x}, {y}) {a} vs {r}"
                    );
                }
            }
            assert!(
                (sum.0 - sum.1).abs() <= 0.02 * sum.1,
                "{name} by {integrator:?}: mean {} vs {}",
                sum.0,
                sum.1
            );
        }
    }
}

/// Radiance HDR files with random bytes changed (header and data) and cut at random lengths
/// decode or are refused, never panic; an accepted one has as many pixels as it claims. (A
/// cheap stand-in for the `texture` fuzz target, whose corpus holds these files too.)
#[test]
fn mutated_hdr_files_never_panic() {
    let img = image();
    let good = mcrt::rgbe::encode(img.width, img.height, &img.pixels().collect::<Vec<_>>());
    let mut rng = Rng::new(17);
    let mut accepted = 0;
    for _ in 0..20_000 {
        let mut b = good.clone();
        for _ in 0..1 + (rng.f() * 4.0) as usize {
            let i = (rng.f() * b.len() as f32) as usize % b.len();
            b[i] = (rng.f() * 256.0) as u8;
        }
        if rng.f() < 0.3 {
            b.truncate((rng.f() * b.len() as f32) as usize);
        }
        if let Ok((w, h, px)) = mcrt::rgbe::decode(&b) {
            assert_eq!(px.len() as u64, w as u64 * h as u64);
            assert!(px.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
            accepted += 1;
        }
    }
    // Most changes hit pixel data, which stays decodable.
    assert!(accepted > 1000, "{accepted}");
}
