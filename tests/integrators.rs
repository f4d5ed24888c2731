//! Integrator behaviour beyond agreement with Mitsuba: the options of the path integrator and
//! the direct integrator, each checked against an independent estimate with the measured noise.

mod common;

use common::*;
use mcrt::integrator::IntegratorKind;
use mcrt::render::RenderSettings;
use mcrt::scene::desc::FileSettings;

/// Two renders of the same quantity: every 8×8 block and the whole image agree within 5 σ
/// of their combined measured noise.
fn assert_same(a: &Rendered, b: &Rendered, what: &str) {
    let bs = 8;
    let (nx, ny) = (a.mean.width / bs, a.mean.height / bs);
    let lum = |p: [f64; 3]| (p[0] + p[1] + p[2]) / 3.0;
    let block_var = |r: &Rendered, i: u32, j: u32| {
        let mut v = 0.0;
        for y in j * bs..(j + 1) * bs {
            for x in i * bs..(i + 1) * bs {
                let p = r.var.get(x, y);
                let s = (p.x.sqrt() + p.y.sqrt() + p.z.sqrt()) as f64 / 3.0;
                v += s * s;
            }
        }
        v / ((bs * bs) as f64).powi(2)
    };
    let mut zsum = 0.0;
    let mut zmax: f64 = 0.0;
    for j in 0..ny {
        for i in 0..nx {
            let d = lum(a.mean.block_mean(i, j, bs)) - lum(b.mean.block_mean(i, j, bs));
            let s = (block_var(a, i, j) + block_var(b, i, j)).sqrt().max(1e-9);
            zsum += d / s;
            zmax = zmax.max((d / s).abs());
        }
    }
    let zagg = zsum / ((nx * ny) as f64).sqrt();
    eprintln!("{what}: max block z {zmax:.2}, aggregate z {zagg:.2}");
    assert!(zmax < 5.0, "{what}: a block differs by {zmax:.1} sigma");
    assert!(
        zagg.abs() < 5.0,
        "{what}: images differ overall by {zagg:.1} sigma"
    );
}

fn cornell(over: FileSettings) -> (mcrt::scene::Scene, RenderSettings) {
    let (scene, fs) = load("scenes/cornell-box.toml");
    let s = settings(
        &fs,
        FileSettings {
            width: Some(64),
            height: Some(64),
            ..over
        },
    );
    (scene, s)
}

/// Without mirrors or glass, "emission plus one bounce of direct light" is exactly the path
/// integrator limited to two segments.
#[test]
fn direct_equals_path_with_two_segments_on_diffuse_scene() {
    let (scene, d) = cornell(FileSettings {
        spp: Some(64),
        integrator: Some(IntegratorKind::Direct),
        ..Default::default()
    });
    let (_, mut p) = cornell(FileSettings {
        spp: Some(64),
        seed: Some(7),
        ..Default::default()
    });
    p.params.max_depth = Some(2);
    assert_same(
        &render_with(&scene, &d),
        &render_with(&scene, &p),
        "direct vs path max_depth 2",
    );
}

/// The direct integrator follows the mirror wall and the glass sphere: with them, it sees more
/// than the path integrator limited to two segments, which stops at the mirror.
#[test]
fn direct_sees_through_mirror_and_glass() {
    let (scene, fs) = load("scenes/tncg15.toml");
    let over = FileSettings {
        width: Some(32),
        height: Some(32),
        spp: Some(16),
        ..Default::default()
    };
    let mut d = settings(
        &fs,
        FileSettings {
            integrator: Some(IntegratorKind::Direct),
            ..over.clone()
        },
    );
    let mut p = settings(&fs, over);
    p.params.max_depth = Some(2);
    d.threads = None;
    let (a, b) = (render_with(&scene, &d), render_with(&scene, &p));
    // Pixel looking at the mirror wall (back right, wall 4) near the image centre-right row:
    // the ray from eye 1 through (0, −0.45, 0) reaches x≈12 on the mirror.
    let (x, y) = (23, 16);
    let (da, pb) = (a.mean.get(x, y), b.mean.get(x, y));
    assert!(
        pb.max_element() < 1e-6,
        "path with 2 segments stops at the mirror: {pb:?}"
    );
    assert!(
        da.max_element() > 0.05,
        "direct lights what the mirror shows: {da:?}"
    );
}

/// More shadow rays per vertex change the noise, not the answer; with MIS the estimate stays
/// unbiased for any count.
#[test]
fn shadow_ray_count_is_unbiased() {
    let (scene, one) = cornell(FileSettings {
        spp: Some(64),
        ..Default::default()
    });
    let (_, ten) = cornell(FileSettings {
        spp: Some(16),
        shadow_rays: Some(10),
        seed: Some(3),
        ..Default::default()
    });
    assert_same(
        &render_with(&scene, &one),
        &render_with(&scene, &ten),
        "1 vs 10 shadow rays",
    );
}

/// A fixed survival probability p gives the report's "1/(1 − p) reflections on average" and
/// the same image as throughput-based roulette.
#[test]
fn fixed_roulette_is_unbiased_and_sets_path_length() {
    let (scene, fs) = load("scenes/tncg15.toml");
    let over = FileSettings {
        width: Some(64),
        height: Some(64),
        ..Default::default()
    };
    let thr = settings(
        &fs,
        FileSettings {
            spp: Some(64),
            ..over.clone()
        },
    );
    let fix = settings(
        &fs,
        FileSettings {
            spp: Some(64),
            rr_survival: Some(0.75),
            seed: Some(11),
            ..over.clone()
        },
    );
    assert_same(
        &render_with(&scene, &thr),
        &render_with(&scene, &fix),
        "throughput vs fixed roulette",
    );
    // Rays per sample: the camera ray plus K extensions, K geometric with mean p/(1 − p) = 3,
    // cut short only where a path hits the light or escapes (the room is closed). The mean of
    // N samples has standard error σ/√N with σ² = p/(1 − p)² = 12.
    let (_, stats) = mcrt::render::render(&scene, &fix, &|_| {}).unwrap();
    let n = stats.samples as f64;
    let rays_per_sample = stats.rays.rays as f64 / n;
    let se = (12.0f64 / n).sqrt();
    eprintln!("rays per sample {rays_per_sample:.4} (≤ 4, se {se:.4})");
    assert!(rays_per_sample < 4.0 + 5.0 * se, "{rays_per_sample}");
    // Paths that hit the light end early: a few per cent of vertices see the small light.
    assert!(rays_per_sample > 3.6, "{rays_per_sample}");
}

/// max_depth 1: only emitters seen directly; the light's pixels show its radiance exactly.
#[test]
fn max_depth_one_shows_only_emitters() {
    let (scene, fs) = load("scenes/tncg15.toml");
    let mut s = settings(
        &fs,
        FileSettings {
            width: Some(64),
            height: Some(64),
            spp: Some(4),
            ..Default::default()
        },
    );
    s.params.max_depth = Some(1);
    let r = render_with(&scene, &s);
    let mut lit = 0;
    for p in &r.mean.pixels {
        assert!(
            p.max_element() == 0.0 || (p.min_element() > 0.0 && p.max_element() <= 25.0 + 1e-3),
            "{p:?}"
        );
        if p.min_element() == 25.0 {
            lit += 1;
        }
    }
    // The light, 2×2 at height 4.99 seen from (−1, 0, 0), covers ≈ (2/6)·(1/6)/(2·2)·64² ≈ 57
    // fully covered pixels around the top centre.
    assert!((30..120).contains(&lit), "{lit} pixels fully on the light");
}
