//! Photon mapping: the photon record, the power bookkeeping of photon tracing, determinism,
//! and the `photon` and `sppm` integrators against the Mitsuba reference of the Cornell box.

mod common;

use common::*;
use mcrt::integrator::{IntegratorKind, PhotonParams};
use mcrt::photon::{trace_photons, Photon, PhotonMaps, TraceOptions};
use mcrt::scene::desc::FileSettings;
use mcrt::Color;

#[test]
fn photon_is_at_most_32_bytes() {
    let size = std::mem::size_of::<Photon>();
    assert!(size <= 32, "{size} bytes");
    // Ten million photons in under 500 MB.
    assert!(10_000_000 * size < 500_000_000);
}

/// A closed box (the Cornell box's walls plus a front wall, no inner blocks), so that every
/// photon that leaves the light lands somewhere.
const CLOSED_BOX: &str = r#"
[render]
width = 16
height = 16
[[camera]]
name = "main"
type = "perspective"
origin = [0, 0, 0.9]
target = [0, 0, 0]
up = [0, 1, 0]
fov = 60
[material.white]
type = "lambert"
albedo = [0.8, 0.6, 0.5]
[material.green]
type = "lambert"
albedo = [0.1, 0.4, 0.1]
[material.red]
type = "lambert"
albedo = [0.6, 0.05, 0.05]
[material.grey]
type = "lambert"
albedo = [0.3, 0.3, 0.3]
[[shape]]
type = "quad"
material = "white"
emission = [18, 14, 7]
vertices = [[-0.23, 0.99, -0.18], [0.23, 0.99, -0.18], [0.23, 0.99, 0.2], [-0.23, 0.99, 0.2]]
[[shape]]
type = "quad"
material = "white"
vertices = [[-1, -1, 1], [1, -1, 1], [1, -1, -1], [-1, -1, -1]]
[[shape]]
type = "quad"
material = "white"
vertices = [[-1, 1, -1], [1, 1, -1], [1, 1, 1], [-1, 1, 1]]
[[shape]]
type = "quad"
material = "white"
vertices = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]
[[shape]]
type = "quad"
material = "green"
vertices = [[1, -1, -1], [1, -1, 1], [1, 1, 1], [1, 1, -1]]
[[shape]]
type = "quad"
material = "red"
vertices = [[-1, -1, 1], [-1, -1, -1], [-1, 1, -1], [-1, 1, 1]]
[[shape]]
type = "quad"
material = "grey"
vertices = [[-1, -1, 1], [-1, 1, 1], [1, 1, 1], [1, -1, 1]]
"#;

fn closed_box() -> mcrt::scene::Scene {
    let path = std::env::temp_dir().join(format!("mcrt-closed-box-{}.toml", std::process::id()));
    std::fs::write(&path, CLOSED_BOX).unwrap();
    let desc = mcrt::load_scene(&path).expect("closed box loads");
    let _ = std::fs::remove_file(&path);
    mcrt::scene::Scene::build(desc)
}

/// The albedo of the closed box's surface under a photon, from where it lies.
fn box_albedo(p: &Photon) -> Color {
    let [x, y, z] = p.p;
    let near = |a: f32, b: f32| (a - b).abs() < 1e-3;
    if near(x, 1.0) {
        Color::new(0.1, 0.4, 0.1)
    } else if near(x, -1.0) {
        Color::new(0.6, 0.05, 0.05)
    } else if near(z, 1.0) {
        Color::splat(0.3)
    } else {
        // floor, ceiling, back wall and the light's front: white
        assert!(
            near(y, -1.0) || near(y, 1.0) || near(y, 0.99) || near(z, -1.0),
            "{:?}",
            p.p
        );
        Color::new(0.8, 0.6, 0.5)
    }
}

/// Power bookkeeping: the direct photons carry the light's power exactly (every photon lands
/// in the closed box), and the photons stored after the first bounce carry that power times
/// the albedo where it landed. Per direct photon i the second-bounce contribution is
/// X_i = Φ_i·ρ_i/q_i with probability q_i = max(ρ_i) (Russian roulette) and 0 otherwise, so
/// E[Σ X] = Σ Φ_i·ρ_i and Var[Σ X] = Σ (Φ_i·ρ_i)²·(1/q_i − 1): the test allows 5σ.
#[test]
fn first_bounce_flux_equals_light_power_times_albedo() {
    let scene = closed_box();
    let n = 200_000;
    let t = trace_photons(&scene, n, &TraceOptions::default());
    let power = mcrt::photon::trace::light_power_rgb(&scene);
    let sum = |d: u32| -> glam::DVec3 {
        t.photons
            .iter()
            .filter(|p| p.depth() == d)
            .map(|p| p.power().as_dvec3())
            .sum()
    };
    let d1 = sum(1);
    let direct = t.photons.iter().filter(|p| p.depth() == 1).count();
    assert_eq!(direct as u64, n, "every photon lands once");
    let rel = (d1 - power.as_dvec3()).abs() / power.as_dvec3();
    assert!(
        rel.max_element() < 1e-4,
        "direct flux {d1} vs light power {power}"
    );
    let (mut expect, mut var) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
    for p in t.photons.iter().filter(|p| p.depth() == 1) {
        let rho = box_albedo(p);
        let q = rho.max_element() as f64;
        let x = (p.power() * rho).as_dvec3();
        expect += x;
        var += x * x * (1.0 / q - 1.0);
    }
    let d2 = sum(2);
    let var = glam::DVec3::new(var.x.sqrt(), var.y.sqrt(), var.z.sqrt());
    let z = (d2 - expect).abs() / var;
    eprintln!(
        "light power {power}, direct {d1}, second bounce {d2}, expected {expect} (σ {}), z {z}, mean albedo {}",
        var,
        expect / d1
    );
    assert!(z.max_element() < 5.0, "second-bounce flux off by {z} σ");
}

fn photon_settings(
    kind: IntegratorKind,
    size: u32,
    spp: u32,
    pp: PhotonParams,
) -> (mcrt::scene::Scene, mcrt::render::RenderSettings) {
    let (scene, fs) = load("scenes/cornell-box.toml");
    let mut s = settings(
        &fs,
        FileSettings {
            width: Some(size),
            height: Some(size),
            spp: Some(spp),
            integrator: Some(kind),
            // Stratified pixel positions: the light's edges would otherwise dominate the
            // noise of the block means that contain it.
            sampler: Some(mcrt::sampler::SamplerKind::Sobol),
            ..Default::default()
        },
    );
    s.params.photon = pp;
    (scene, s)
}

/// The photon maps and the images are the same bits on one and two threads.
#[test]
fn photon_maps_and_images_are_deterministic() {
    let pp = PhotonParams {
        photons: 20_000,
        caustic_photons: 20_000,
        final_gather: 2,
        iterations: 2,
        photons_per_iteration: 5_000,
        ..Default::default()
    };
    for kind in [IntegratorKind::Photon, IntegratorKind::Sppm] {
        let (scene, mut s) = photon_settings(kind, 32, 2, pp);
        let mut images = vec![];
        for t in [1, 2] {
            s.threads = Some(t);
            let maps =
                mcrt::render::with_threads(&s, || PhotonMaps::build(&scene, &s.params, s.seed))
                    .unwrap();
            let (film, _) = mcrt::render::render(&scene, &s, &|_| {}).unwrap();
            images.push((
                maps.global.photons().to_vec(),
                maps.shadow.photons().to_vec(),
                film.image().pixels,
            ));
        }
        assert!(images[0] == images[1], "{kind:?}: 1 and 2 threads differ");
    }
}

/// Block means (16×16 blocks of a 64×64 image, 16 blocks; each covers 64×64 pixels of the
/// 256×256, 8192-spp reference) relative to the reference.
fn block_errors(r: &Rendered) -> Vec<f64> {
    let c = BlockComparison::new(r, &reference("cornell-box.exr"), 64, 8192);
    c.print();
    (0..c.mine.len()).map(|i| c.rel_err(i)).collect()
}

/// The `photon` integrator (biased) within 3 % of the Mitsuba path-traced reference on every
/// block mean. The final-gather noise of a block mean, measured from the per-pixel variance
/// over 256 pixels × 16 samples × 16 gather rays, is about 0.3 %, so 3 % is the bias budget.
/// The largest relative error of a Cornell-box block mean (64×64) rendered by `kind`.
fn worst_cornell_block(kind: IntegratorKind, spp: u32, pp: PhotonParams) -> f64 {
    let (scene, s) = photon_settings(kind, 64, spp, pp);
    let worst = block_errors(&render_with(&scene, &s))
        .into_iter()
        .fold(0.0, f64::max);
    eprintln!("{}: worst block {:.2} %", kind.name(), 100.0 * worst);
    worst
}

#[test]
fn photon_cornell_box_within_3_percent() {
    let pp = PhotonParams {
        photons: 200_000,
        caustic_photons: 0,
        gather_photons: 32,
        final_gather: 8,
        ..Default::default()
    };
    let worst = worst_cornell_block(IntegratorKind::Photon, 8, pp);
    assert!(worst < 0.03, "worst block off by {:.2} %", 100.0 * worst);
}

/// `sppm` within 2 % of the reference on every block mean. 64 iterations of 100 000 photons
/// from a radius of 0.03 (the box is 2 wide); over the settings tried (radius 0.017 to 0.03,
/// 64 to 256 iterations, 1.6 to 6.4 million photons in all) the worst block was 1.1 to 1.5 %
/// once at least 6 million photons were traced, 2.8 to 6.9 % with 1.3 million (the noise of
/// the photons, shared by neighbouring pixels, does not average out over a block).
#[test]
fn sppm_cornell_box_within_2_percent() {
    let pp = PhotonParams {
        iterations: 64,
        photons_per_iteration: 100_000,
        initial_radius: Some(0.03),
        ..Default::default()
    };
    let worst = worst_cornell_block(IntegratorKind::Sppm, 1, pp);
    assert!(worst < 0.02, "worst block off by {:.2} %", 100.0 * worst);
}

/// The `photon` integrator on the TNCG15 room (eye 1, 64×64, 16×16-pixel blocks: 16 block
/// means, each 64×64 pixels of the 16384-spp reference) outside the blocks that see the glass
/// sphere's caustic or the sphere itself: every block mean within 5 %.
///
/// The bias bound: at 32 spp and 4 gather rays every such block was within 3 % of the
/// reference (the ceiling's corners 2–3 % dark: the density estimates, from the precomputed
/// irradiance points and k = 64, lose light where their disc reaches past a wall; without the
/// precomputation 1 %), and a 1024-spp path-traced image was within 1.9 %; 5 % leaves room
/// for the final gather's noise at 16 spp.
/// The glass sphere's blocks are left out: they hold the light's reflection in the sphere, a
/// few pixels at radiance 25 hit by a few percent of the camera samples, whose block mean is
/// ±20 % at 16 spp for `path` and `photon` alike (camera noise, not bias). The whole-image
/// RMSE of 0.17 reported for `photon` at 16 independent samples a pixel was this camera
/// noise at the glints and the light's edges (`path` at 16 spp: 0.27), not a bias: with
/// 64 Sobol samples a pixel `photon` reaches 0.022, as `path` does at 1024.
#[test]
fn photon_tncg15_blocks_within_5_percent() {
    let (scene, fs) = load("scenes/tncg15.toml");
    let size = 64;
    let mut s = settings(
        &fs,
        FileSettings {
            width: Some(size),
            height: Some(size),
            spp: Some(16),
            camera: Some("eye1".into()),
            integrator: Some(IntegratorKind::Photon),
            sampler: Some(mcrt::sampler::SamplerKind::Sobol),
            ..Default::default()
        },
    );
    s.params.photon = PhotonParams {
        photons: 200_000,
        caustic_photons: 1_000_000,
        final_gather: 4,
        ..Default::default()
    };
    let r = render_with(&scene, &s);
    let c = BlockComparison::new(&r, &reference("hexroom-eye1.exr"), 64, 16384);
    c.print();
    // Blocks of 16 pixels at 64×64 that hold a caustic block (8 pixels at 128×128).
    let mask = common::caustic::caustic_blocks(&scene, 128, 8);
    let mut worst = 0.0f64;
    for i in 0..c.mine.len() {
        let (bx, by) = (i as u32 % c.blocks_x, i as u32 / c.blocks_x);
        let caustic =
            (0..4).any(|dy| (0..4).any(|dx| mask[((by * 4 + dy) * 16 + bx * 4 + dx) as usize]));
        if caustic {
            continue;
        }
        worst = worst.max(c.rel_err(i));
    }
    eprintln!(
        "photon TNCG15: worst block outside the caustic {:.2} %",
        100.0 * worst
    );
    assert!(worst < 0.05, "worst block off by {:.2} %", 100.0 * worst);
}

/// RMSE over RGB of `img` against `reference` (twice its resolution: each of its pixels is the
/// mean of 2×2 reference pixels) over the pixels where `mask` (blocks of `block` pixels of
/// `img`) is set, or everywhere.
fn rmse(
    img: &mcrt::image::Image,
    reference: &mcrt::image::Image,
    mask: Option<(&[bool], u32)>,
) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0u64);
    let nb = img.width / mask.map_or(1, |m| m.1);
    for y in 0..img.height {
        for x in 0..img.width {
            if let Some((m, b)) = mask {
                if !m[((y / b) * nb + x / b) as usize] {
                    continue;
                }
            }
            let r = (reference.get(2 * x, 2 * y)
                + reference.get(2 * x + 1, 2 * y)
                + reference.get(2 * x, 2 * y + 1)
                + reference.get(2 * x + 1, 2 * y + 1))
                * 0.25;
            let d = (img.get(x, y) - r).as_dvec3();
            sum += d.length_squared() / 3.0;
            n += 1;
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

/// A log-log SVG plot of (x, y) points.
fn svg_plot(points: &[(f64, f64)], xlabel: &str, ylabel: &str, title: &str) -> String {
    let (w, h, m) = (560.0, 380.0, 60.0);
    let lx: Vec<f64> = points.iter().map(|p| p.0.log10()).collect();
    let ly: Vec<f64> = points.iter().map(|p| p.1.log10()).collect();
    let (x0, x1) = (
        lx.iter().cloned().fold(f64::MAX, f64::min),
        lx.iter().cloned().fold(f64::MIN, f64::max),
    );
    let (y0, y1) = (
        ly.iter().cloned().fold(f64::MAX, f64::min).floor(),
        ly.iter().cloned().fold(f64::MIN, f64::max).ceil(),
    );
    let px = |v: f64| m + (v - x0) / (x1 - x0).max(1e-9) * (w - 1.5 * m);
    let py = |v: f64| h - m - (v - y0) / (y1 - y0).max(1e-9) * (h - 1.7 * m);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{title}</text>\n",
        w / 2.0
    );
    s += &format!(
        "<line x1=\"{m}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n",
        h - m,
        w - 0.5 * m,
        h - m
    );
    s += &format!(
        "<line x1=\"{m}\" y1=\"{}\" x2=\"{m}\" y2=\"{}\" stroke=\"black\"/>\n",
        h - m,
        0.7 * m
    );
    for (i, (x, y)) in points.iter().enumerate() {
        s += &format!(
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
            px(lx[i]),
            h - m + 16.0,
            x
        );
        s += &format!(
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3\" fill=\"#1f77b4\"/>\n",
            px(lx[i]),
            py(ly[i])
        );
        s += &format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\">{:.4}</text>\n",
            px(lx[i]) + 4.0,
            py(ly[i]) - 6.0,
            y
        );
    }
    let pts: Vec<String> = (0..points.len())
        .map(|i| format!("{:.1},{:.1}", px(lx[i]), py(ly[i])))
        .collect();
    s += &format!(
        "<polyline points=\"{}\" fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"2\"/>\n",
        pts.join(" ")
    );
    let mut e = y0;
    while e <= y1 + 1e-9 {
        s += &format!(
            "<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{}</text>\n",
            m - 6.0,
            py(e) + 4.0,
            e
        );
        e += 1.0;
    }
    s += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{xlabel} (log)</text>\n",
        w / 2.0,
        h - 15.0
    );
    s += &format!("<text x=\"15\" y=\"{}\" transform=\"rotate(-90 15 {})\" text-anchor=\"middle\">{ylabel} (log)</text>\n</svg>\n", h / 2.0, h / 2.0);
    s
}

/// The proof of the photon-mapping issue on the TNCG15 room (eye 1, 128×128, against the
/// 16384-spp Mitsuba reference): in the caustic blocks under the glass sphere, `photon` and
/// `sppm` against `path` at equal render time; and sppm's whole-image RMSE as iterations grow.
/// All three with Sobol camera samples. Writes docs/photon-sppm-convergence.svg and
/// target/photon-caustic.md. About half a minute on two cores: `bench/photon_caustic.sh`
/// (last run: ratio 0.47 for photon, 0.38 for sppm; docs/photon-mapping.md).
#[test]
#[ignore]
fn caustic_rmse_at_equal_time() {
    use std::fmt::Write;
    use std::time::Instant;
    let (scene, fs) = load("scenes/tncg15.toml");
    let refimg = reference("hexroom-eye1.exr");
    let size = 128;
    let mask = common::caustic::caustic_blocks(&scene, size, 8);
    let base = |kind| {
        let mut s = settings(
            &fs,
            FileSettings {
                width: Some(size),
                height: Some(size),
                spp: Some(16),
                camera: Some("eye1".into()),
                integrator: Some(kind),
                // The same stratified camera samples for all three: the light's edges and its
                // reflections in the glass sphere converge with the camera samples alone.
                sampler: Some(mcrt::sampler::SamplerKind::Sobol),
                ..Default::default()
            },
        );
        if kind == IntegratorKind::Photon {
            s.spp = 64;
        }
        s.params.photon = PhotonParams {
            photons: 200_000,
            caustic_photons: 1_000_000,
            gather_photons: 32,
            final_gather: 1,
            iterations: 64,
            photons_per_iteration: 100_000,
            initial_radius: None,
        };
        s
    };
    let mut md = String::new();
    let caustic = |img: &mcrt::image::Image| rmse(img, &refimg, Some((&mask, 8)));
    let whole = |img: &mcrt::image::Image| rmse(img, &refimg, None);
    // photon
    let s = base(IntegratorKind::Photon);
    let t = Instant::now();
    let (film, _) = mcrt::render::render(&scene, &s, &|_| {}).unwrap();
    let t_photon = t.elapsed().as_secs_f64();
    let img = film.image();
    let (pc, pw) = (caustic(&img), whole(&img));
    // sppm with snapshots
    let s = base(IntegratorKind::Sppm);
    let mut snaps: Vec<(u32, f64, f64, f64)> = vec![];
    let t = Instant::now();
    let (film, _) = mcrt::integrator::sppm::render_sppm(
        &scene,
        &s,
        &|_| {},
        &mut |i, img| snaps.push((i, t.elapsed().as_secs_f64(), whole(img), caustic(img))),
        &|i| i.is_power_of_two(),
    )
    .unwrap();
    let t_sppm = t.elapsed().as_secs_f64();
    let img = film.image();
    let (sc, sw) = (caustic(&img), whole(&img));
    // path, one sample per pixel a pass, until both times are reached
    let s = base(IntegratorKind::Path);
    let mut film = mcrt::film::Film::new(size, size);
    let t = Instant::now();
    let path_at = |target: f64, film: &mut mcrt::film::Film, spp: &mut u32| {
        while t.elapsed().as_secs_f64() < target {
            mcrt::render::render_samples(&scene, &s, film, *spp, 1, &|_| {}).unwrap();
            *spp += 1;
        }
        let img = film.image();
        (caustic(&img), whole(&img), *spp)
    };
    let mut spp = 0;
    let (first, second) = if t_photon <= t_sppm {
        (t_photon, t_sppm)
    } else {
        (t_sppm, t_photon)
    };
    let a = path_at(first, &mut film, &mut spp);
    let b = path_at(second, &mut film, &mut spp);
    let (path_p, path_s) = if t_photon <= t_sppm { (a, b) } else { (b, a) };
    writeln!(md, "| integrator | time (s) | caustic RMSE | path at equal time (spp) | path caustic RMSE | ratio | whole-image RMSE |").unwrap();
    writeln!(md, "|---|---|---|---|---|---|---|").unwrap();
    writeln!(
        md,
        "| photon | {t_photon:.2} | {pc:.4} | {} | {:.4} | {:.2} | {pw:.4} (path {:.4}) |",
        path_p.2,
        path_p.0,
        pc / path_p.0,
        path_p.1
    )
    .unwrap();
    writeln!(
        md,
        "| sppm | {t_sppm:.2} | {sc:.4} | {} | {:.4} | {:.2} | {sw:.4} (path {:.4}) |",
        path_s.2,
        path_s.0,
        sc / path_s.0,
        path_s.1
    )
    .unwrap();
    writeln!(
        md,
        "\n| sppm iterations | time (s) | whole-image RMSE | caustic RMSE |\n|---|---|---|---|"
    )
    .unwrap();
    for (i, t, w, c) in &snaps {
        writeln!(md, "| {i} | {t:.2} | {w:.4} | {c:.4} |").unwrap();
    }
    eprintln!("{md}");
    let pts: Vec<(f64, f64)> = snaps.iter().map(|s| (s.0 as f64, s.2)).collect();
    std::fs::write(
        project_path("docs/photon-sppm-convergence.svg"),
        svg_plot(
            &pts,
            "iterations",
            "RMSE",
            "SPPM on the TNCG15 room (eye 1, 128×128): whole-image RMSE vs the reference",
        ),
    )
    .unwrap();
    std::fs::create_dir_all(project_path("target")).unwrap();
    std::fs::write(project_path("target/photon-caustic.md"), &md).unwrap();
    assert!(
        pc < 0.5 * path_p.0,
        "photon caustic RMSE {pc} vs path {}",
        path_p.0
    );
    assert!(
        sc < 0.5 * path_s.0,
        "sppm caustic RMSE {sc} vs path {}",
        path_s.0
    );
    for w in snaps.windows(2) {
        assert!(
            w[1].2 < w[0].2,
            "sppm RMSE rose from {} to {} iterations",
            w[0].0,
            w[1].0
        );
    }
}
