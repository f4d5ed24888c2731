//! The wavefront (sixteen paths at a time, `integrator::wavefront`) renders the same film as
//! the path tracer one path at a time, bit for bit: the same fixed-point sums, sample counts,
//! ray counts and dropped samples, on scenes that take every branch of a path (emitters
//! seen directly, through BSDF samples and hidden; one-sided surfaces seen from behind;
//! black bodies; rays that leave the scene; samples that overflow; both kinds of planar
//! light; both roulettes; every path length), on odd image sizes, crops and split passes.
//!
//! Both of its backends are compared where the CPU has them: AVX-512, and AVX2 (which a CPU
//! with AVX-512 runs when the render settings force it, `Backend::Avx2`). On a CPU
//! without AVX2 and BMI2 the wavefront never runs and there is nothing to compare; the tests
//! say so and pass. (The wavefront is x86-64 code; elsewhere there is nothing here.)
#![cfg(target_arch = "x86_64")]

use mcrt::film::Film;
use mcrt::integrator::wavefront::Wavefront;
use mcrt::render::{render, render_samples, Backend, RenderSettings, RenderStats};
use mcrt::scene::desc::FileSettings;
use mcrt::scene::Scene;
use std::path::Path;

fn cpu_runs_it() -> bool {
    let ok = std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("popcnt");
    if !ok {
        eprintln!("this CPU lacks AVX2, BMI1, BMI2 or POPCNT: the wavefront never runs");
    }
    ok
}

/// Whether the CPU runs the AVX-512 backend (and `MCRT_MAX_ISA` does not cap it), so that
/// the AVX2 one is compared as well.
fn cpu_has_avx512() -> bool {
    mcrt::cpu::avx512()
        && std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("bmi2")
}

fn scene_from(text: &str) -> Scene {
    let desc = mcrt::scene::toml::parse_toml(Path::new("test.toml"), text).expect("scene parses");
    Scene::build(desc)
}

/// `text` (whose first table is `[render]`), with `hide_emitters = true` if `hide`.
fn hiding_emitters(text: &str, hide: bool) -> String {
    if hide {
        text.replacen("[render]", "[render]\nhide_emitters = true", 1)
    } else {
        text.to_string()
    }
}

fn cornell() -> Scene {
    cornell_with(mcrt::accel::SingleRays::Auto)
}

/// The Cornell box with its single rays answered as `single_rays` says.
fn cornell_with(single_rays: mcrt::accel::SingleRays) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    Scene::build_with(mcrt::load_scene(&path).unwrap(), single_rays)
}

fn settings(scene: &Scene, over: FileSettings) -> RenderSettings {
    mcrt::resolve_settings(&scene.desc_settings, &over, Some(2)).unwrap()
}

/// `s` with its backend forced.
fn with_backend(s: &RenderSettings, backend: Backend) -> RenderSettings {
    RenderSettings {
        backend,
        ..s.clone()
    }
}

/// Renders `scene` with `s` both ways and compares everything the film and the statistics
/// hold. `scene` must be one the wavefront takes.
fn same_both_ways(scene: Scene, s: &RenderSettings, what: &str) -> (Film, RenderStats) {
    assert!(
        Wavefront::new(&scene, s).is_some(),
        "{what}: the wavefront does not take this scene, so the test would compare nothing"
    );
    let (wide, ws) = render(&scene, s, &|_| {}).unwrap();
    if cpu_has_avx512() {
        // The AVX2 backend too, against the same film.
        let avx2 = with_backend(s, Backend::Avx2);
        assert!(
            Wavefront::new(&scene, &avx2).is_some(),
            "{what}: AVX2 takes it"
        );
        let (narrow, ns) = render(&scene, &avx2, &|_| {}).unwrap();
        same_film(
            &narrow,
            &ns,
            &wide,
            &ws,
            &format!("{what}, AVX2 against AVX-512"),
        );
    }
    let scalar = with_backend(s, Backend::Scalar);
    assert!(Wavefront::new(&scene, &scalar).is_none());
    let (one, os) = render(&scene, &scalar, &|_| {}).unwrap();
    same_film(&wide, &ws, &one, &os, what);
    (wide, ws)
}

/// Asserts that two renders' films and statistics hold the same.
fn same_film(wide: &Film, ws: &RenderStats, one: &Film, os: &RenderStats, what: &str) {
    assert_eq!(wide.count, one.count, "{what}: sample counts");
    let differ = wide
        .sum
        .iter()
        .zip(&one.sum)
        .chain(wide.sum_sq.iter().zip(&one.sum_sq))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differ, 0, "{what}: {differ} pixel sums differ");
    assert_eq!(
        (ws.samples, ws.rays.rays, ws.rays.shadow_rays),
        (os.samples, os.rays.rays, os.rays.shadow_rays),
        "{what}: samples and rays"
    );
    assert_eq!(
        (ws.dropped, ws.first_dropped),
        (os.dropped, os.first_dropped),
        "{what}: dropped samples"
    );
}

/// The Cornell box (one-sided Lambertian walls, a white parallelogram light that reflects
/// too) at every path length and with both roulettes.
#[test]
fn cornell_box_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    let cases: [(&str, Option<u32>, RussianRoulette); 6] = [
        ("default", Some(8), RussianRoulette::Throughput { start: 5 }),
        (
            "max depth 1",
            Some(1),
            RussianRoulette::Throughput { start: 5 },
        ),
        (
            "max depth 2",
            Some(2),
            RussianRoulette::Throughput { start: 5 },
        ),
        ("unlimited", None, RussianRoulette::Throughput { start: 5 }),
        ("fixed roulette", None, RussianRoulette::Fixed(0.6)),
        (
            "roulette from 1",
            Some(8),
            RussianRoulette::Throughput { start: 1 },
        ),
    ];
    for (what, max_depth, rr) in cases {
        let scene = cornell();
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(40),
                height: Some(40),
                spp: Some(6),
                seed: Some(11),
                ..Default::default()
            },
        );
        s.params.max_depth = max_depth;
        s.params.rr = rr;
        let (film, stats) = same_both_ways(scene, &s, what);
        assert!(
            stats.rays.shadow_rays > 0 || what == "max depth 1",
            "{what}"
        );
        let total: f64 = film.sum_f64().iter().flatten().sum();
        assert!(total > 0.0, "{what}: the box is lit");
    }
}

/// A closed room seen from inside: two-sided and one-sided walls (one of them turned
/// away, so seen from behind), a black block, a two-sided card, a triangle light facing
/// down; emitters hidden from the camera or not.
const ROOM: &str = r#"
[render]
max_depth = 6

[[camera]]
name = "main"
type = "perspective"
origin = [0, 1, 2.6]
target = [0, 1.6, 0]
up = [0, 1, 0]
fov = 70

[material.two]
type = "lambert"
albedo = [0.8, 0.7, 0.6]
two_sided = true

[material.one]
type = "lambert"
albedo = [0.3, 0.6, 0.9]
two_sided = false

[material.dark]
type = "lambert"
albedo = [0.0, 0.0, 0.0]

[material.black]
type = "black"

# floor, ceiling, back wall, left and right walls (facing in), front wall behind the camera
[[shape]]
type = "quad"
material = "two"
vertices = [[-2, 0, 3], [2, 0, 3], [2, 0, -2], [-2, 0, -2]]
[[shape]]
type = "quad"
material = "one"
vertices = [[-2, 2.5, -2], [2, 2.5, -2], [2, 2.5, 3], [-2, 2.5, 3]]
[[shape]]
type = "quad"
material = "one"
vertices = [[-2, 0, -2], [2, 0, -2], [2, 2.5, -2], [-2, 2.5, -2]]
[[shape]]
type = "quad"
material = "two"
vertices = [[-2, 0, 3], [-2, 0, -2], [-2, 2.5, -2], [-2, 2.5, 3]]
# the right wall faces out: the camera sees its back
[[shape]]
type = "quad"
material = "one"
vertices = [[2, 0, 3], [2, 0, -2], [2, 2.5, -2], [2, 2.5, 3]]
[[shape]]
type = "quad"
material = "one"
vertices = [[2, 0, 3], [-2, 0, 3], [-2, 2.5, 3], [2, 2.5, 3]]

# a black block and a dark card, and a two-sided card seen edge-on and from both sides
[[shape]]
type = "mesh"
material = "black"
positions = [[-1.2, 0, -1], [-0.6, 0, -1], [-0.6, 0, -0.4], [-1.2, 0, -0.4], [-0.9, 0.9, -0.7]]
indices = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
[[shape]]
type = "triangle"
material = "dark"
vertices = [[1.5, 0, -1.5], [1.9, 0, -1.0], [1.7, 1.2, -1.2]]
[[shape]]
type = "quad"
material = "two"
vertices = [[0.2, 0.1, -0.5], [1.2, 0.1, 0.3], [1.2, 1.4, 0.3], [0.2, 1.4, -0.5]]

# the light: one triangle under the ceiling, facing down
[[shape]]
type = "triangle"
emission = [14, 12, 9]
vertices = [[-0.5, 2.45, -0.5], [0.6, 2.45, 0.4], [-0.3, 2.45, 0.7]]
"#;

#[test]
fn closed_room_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    for (hide, rr, seed) in [(false, None, 1), (true, None, 2), (false, Some(0.7), 3)] {
        let scene = scene_from(&hiding_emitters(ROOM, hide));
        let s = settings(
            &scene,
            FileSettings {
                width: Some(37),
                height: Some(23),
                spp: Some(5),
                seed: Some(seed),
                rr_survival: rr,
                ..Default::default()
            },
        );
        assert_eq!(s.params.hide_emitters, hide);
        let what = format!("room, hide {hide}, roulette {rr:?}");
        let (film, _) = same_both_ways(scene, &s, &what);
        assert!(
            film.sum_f64().iter().flatten().sum::<f64>() > 0.0,
            "{what}: lit"
        );
    }
}

/// An open scene: a floor under a parallelogram light and an overhanging one-sided board,
/// the camera looking past them at nothing (rays leave the scene), the light seen from
/// above (its back) and from below.
const OPEN: &str = r#"
[render]
max_depth = -1

[[camera]]
name = "main"
type = "perspective"
origin = [0, 1.5, 4]
target = [0, 0.6, 0]
up = [0, 1, 0]
fov = 60

[material.floor]
type = "lambert"
albedo = [0.7, 0.7, 0.7]
two_sided = false

[material.board]
type = "lambert"
albedo = [0.9, 0.2, 0.2]
two_sided = false

[[shape]]
type = "quad"
material = "floor"
vertices = [[-1.5, 0, 1.5], [1.5, 0, 1.5], [1.5, 0, -1.5], [-1.5, 0, -1.5]]
[[shape]]
type = "quad"
material = "board"
vertices = [[-1, 0.6, 0.3], [1, 0.6, 0.3], [1, 1.6, -0.4], [-1, 1.6, -0.4]]
[[shape]]
type = "quad"
emission = [6, 6, 6]
vertices = [[-0.4, 1.2, -0.4], [-0.4, 1.2, 0.4], [0.4, 1.2, 0.4], [0.4, 1.2, -0.4]]
"#;

#[test]
fn open_scene_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let scene = scene_from(OPEN);
    let s = settings(
        &scene,
        FileSettings {
            width: Some(33),
            height: Some(31),
            spp: Some(7),
            seed: Some(4),
            ..Default::default()
        },
    );
    same_both_ways(scene, &s, "open scene");
}

/// A light so bright that samples overflow to infinity: they are dropped, and the first
/// such pixel is the same either way.
#[test]
fn overflowing_samples_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let text = OPEN.replace("emission = [6, 6, 6]", "emission = [3.3e38, 1, 1]");
    let scene = scene_from(&text);
    let s = settings(
        &scene,
        FileSettings {
            width: Some(24),
            height: Some(24),
            spp: Some(4),
            seed: Some(9),
            ..Default::default()
        },
    );
    let (_, stats) = same_both_ways(scene, &s, "overflow");
    assert!(stats.dropped > 0, "some samples overflow");
}

/// A crop of the image, rendered in two passes of uneven size, gives the same film as the
/// path tracer's one pass.
#[test]
fn crop_and_passes_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let scene = cornell();
    let mut s = settings(
        &scene,
        FileSettings {
            width: Some(64),
            height: Some(48),
            spp: Some(5),
            seed: Some(21),
            ..Default::default()
        },
    );
    s.crop = Some([13, 7, 35, 29]);
    assert!(Wavefront::new(&scene, &s).is_some());
    let mut wide = Film::new(35, 29);
    render_samples(&scene, &s, &mut wide, 0, 2, &|_| {}).unwrap();
    render_samples(&scene, &s, &mut wide, 2, 3, &|_| {}).unwrap();
    let scalar = with_backend(&s, Backend::Scalar);
    let mut one = Film::new(35, 29);
    render_samples(&scene, &scalar, &mut one, 0, 5, &|_| {}).unwrap();
    assert_eq!(wide, one);
}

/// Sobol points in the lanes across the sampler's limits: samples on both sides of its
/// last Sobol index (2^16; later samples draw PCG32 numbers only) and paths long enough to
/// outrun its Sobol requests (32; later requests draw PCG32 numbers), in one pass each way.
#[test]
fn sobol_limits_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    let scene = scene_from(SPECULAR);
    let mut s = settings(
        &scene,
        FileSettings {
            width: Some(23),
            height: Some(19),
            seed: Some(77),
            ..Default::default()
        },
    );
    s.sampler = mcrt::sampler::SamplerKind::Sobol;
    s.params.max_depth = Some(40);
    s.params.rr = RussianRoulette::Fixed(0.97);
    assert!(Wavefront::new(&scene, &s).is_some());
    let (first, count) = ((1 << 16) - 3, 6);
    let mut wide = Film::new(23, 19);
    render_samples(&scene, &s, &mut wide, first, count, &|_| {}).unwrap();
    let scalar = with_backend(&s, Backend::Scalar);
    let mut one = Film::new(23, 19);
    render_samples(&scene, &scalar, &mut one, first, count, &|_| {}).unwrap();
    assert_eq!(wide, one);
    if cpu_has_avx512() {
        let mut narrow = Film::new(23, 19);
        let avx2 = with_backend(&s, Backend::Avx2);
        render_samples(&scene, &avx2, &mut narrow, first, count, &|_| {}).unwrap();
        assert_eq!(narrow, one, "AVX2");
    }
}

/// The TNCG15 room (two spheres, one diffuse and one of glass, a mirror wall, two-sided
/// walls, a parallelogram light) from both eyes: one shadow ray and the throughput
/// roulette; ten shadow rays and the fixed roulette of the report's Figure 3.3; Sobol points.
#[test]
fn tncg15_room_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    use mcrt::sampler::SamplerKind;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tncg15.toml");
    let cases = [
        ("eye1", 1, None, SamplerKind::Independent),
        ("eye2", 10, Some(0.75), SamplerKind::Independent),
        ("eye1", 3, None, SamplerKind::Sobol),
        ("eye2", 1, Some(0.5), SamplerKind::Sobol),
    ];
    for (k, (camera, shadow_rays, rr, sampler)) in cases.into_iter().enumerate() {
        let scene = Scene::build(mcrt::load_scene(&path).unwrap());
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(36),
                height: Some(36),
                spp: Some(4),
                seed: Some(k as u64),
                camera: Some(camera.into()),
                sampler: Some(sampler),
                ..Default::default()
            },
        );
        s.params.shadow_rays = shadow_rays;
        if let Some(q) = rr {
            s.params.rr = RussianRoulette::Fixed(q);
        }
        let what = format!("TNCG15 {camera}, {shadow_rays} shadow rays, {rr:?}, {sampler:?}");
        let (film, stats) = same_both_ways(scene, &s, &what);
        assert!(stats.rays.shadow_rays > 0, "{what}");
        assert!(
            film.sum_f64().iter().flatten().sum::<f64>() > 0.0,
            "{what}: lit"
        );
    }
}

/// Several shadow rays a vertex (the vertex's lattice) from a triangle light and from a
/// parallelogram, with one-sided walls seen from behind; and Sobol points.
#[test]
fn shadow_ray_batches_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::sampler::SamplerKind;
    for (what, text, n, sampler) in [
        ("room, triangle light", ROOM, 5, SamplerKind::Independent),
        ("room, Sobol", ROOM, 2, SamplerKind::Sobol),
        (
            "open, parallelogram light",
            OPEN,
            7,
            SamplerKind::Independent,
        ),
        ("open, Sobol", OPEN, 1, SamplerKind::Sobol),
    ] {
        let scene = scene_from(text);
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(29),
                height: Some(27),
                spp: Some(3),
                seed: Some(n as u64),
                sampler: Some(sampler),
                ..Default::default()
            },
        );
        s.params.shadow_rays = n;
        let (_, stats) = same_both_ways(scene, &s, what);
        assert!(stats.rays.shadow_rays > 0, "{what}");
    }
}

/// Mirrors seen from both sides (one-sided and two-sided), glass spheres seen from outside
/// and inside (total internal reflection), a sphere that touches a wall, spheres that
/// overlap.
const SPECULAR: &str = r#"
[render]
max_depth = 12

[[camera]]
name = "main"
type = "perspective"
origin = [0, 1.2, 2.8]
target = [0, 0.9, 0]
up = [0, 1, 0]
fov = 75

[material.white]
type = "lambert"
albedo = [0.8, 0.8, 0.8]
[material.mirror1]
type = "mirror"
reflectance = [0.9, 0.8, 0.7]
two_sided = false
[material.mirror2]
type = "mirror"
reflectance = [0.6, 0.9, 0.9]
[material.glass]
type = "dielectric"
ior = 1.5
[material.dense]
type = "dielectric"
ior = 2.4
ext_ior = 1.2

[[shape]]
type = "quad"
material = "white"
vertices = [[-2, 0, 3], [2, 0, 3], [2, 0, -2], [-2, 0, -2]]
[[shape]]
type = "quad"
material = "white"
vertices = [[-2, 2.5, -2], [2, 2.5, -2], [2, 2.5, 3], [-2, 2.5, 3]]
[[shape]]
type = "quad"
material = "mirror1"
vertices = [[-2, 0, -2], [2, 0, -2], [2, 2.5, -2], [-2, 2.5, -2]]
# a one-sided mirror facing away from the camera, and a two-sided one at an angle
[[shape]]
type = "quad"
material = "mirror1"
vertices = [[-1.6, 0.2, 0.5], [-1.6, 1.5, 0.5], [-0.8, 1.5, 0.9], [-0.8, 0.2, 0.9]]
[[shape]]
type = "quad"
material = "mirror2"
vertices = [[1.0, 0.2, -0.5], [1.8, 0.2, 0.2], [1.8, 1.6, 0.2], [1.0, 1.6, -0.5]]
[[shape]]
type = "quad"
material = "white"
vertices = [[-2, 0, 3], [-2, 0, -2], [-2, 2.5, -2], [-2, 2.5, 3]]
[[shape]]
type = "sphere"
material = "glass"
center = [0.3, 0.6, 0.2]
radius = 0.6
[[shape]]
type = "sphere"
material = "dense"
center = [-0.7, 0.45, -1.0]
radius = 0.45
[[shape]]
type = "sphere"
material = "white"
center = [-0.2, 0.45, -1.1]
radius = 0.4
[[shape]]
type = "sphere"
material = "mirror2"
center = [1.5, 0.3, -1.7]
radius = 0.3
[[shape]]
type = "quad"
emission = [10, 9, 8]
vertices = [[-0.5, 2.45, -0.5], [0.5, 2.45, -0.5], [0.5, 2.45, 0.5], [-0.5, 2.45, 0.5]]
"#;

#[test]
fn mirrors_and_glass_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    for (k, (n, rr, hide)) in [
        (1, None, false),
        (4, Some(0.8), false),
        (1, None, true),
        (2, Some(0.6), true),
    ]
    .into_iter()
    .enumerate()
    {
        let scene = scene_from(&hiding_emitters(SPECULAR, hide));
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(41),
                height: Some(33),
                spp: Some(4),
                seed: Some(30 + k as u64),
                ..Default::default()
            },
        );
        s.params.shadow_rays = n;
        if let Some(q) = rr {
            s.params.rr = RussianRoulette::Fixed(q);
        }
        let what = format!("mirrors and glass, {n} shadow rays, {rr:?}, hide {hide}");
        same_both_ways(scene, &s, &what);
    }
}

/// [`SPECULAR`] with its mirrors rough conductors: the one-sided one gold, anisotropic, of
/// GGX microfacets; the two-sided one of a given index, tinted, of Beckmann's; and its dense
/// glass rough (GGX, between two media).
fn rough_materials() -> String {
    let text = SPECULAR
        .replace(
            "[material.mirror1]\ntype = \"mirror\"\nreflectance = [0.9, 0.8, 0.7]",
            "[material.mirror1]\ntype = \"roughconductor\"\nmaterial = \"Au\"\nalpha_u = 0.05\nalpha_v = 0.4",
        )
        .replace(
            "[material.mirror2]\ntype = \"mirror\"\nreflectance = [0.6, 0.9, 0.9]",
            "[material.mirror2]\ntype = \"roughconductor\"\neta = [0.2, 0.9, 1.1]\nk = [3.9, 2.4, 2.2]\nreflectance = [0.9, 0.7, 0.9]\nalpha = 0.25\ndistribution = \"beckmann\"",
        )
        .replace(
            "[material.dense]\ntype = \"dielectric\"",
            "[material.dense]\ntype = \"roughdielectric\"\nalpha = 0.3",
        );
    assert!(
        text.contains("alpha_u") && text.contains("alpha = 0.25") && text.contains("alpha = 0.3")
    );
    text
}

/// Rough conductors (Beckmann and GGX, in one vector's lanes together or not; isotropic and
/// anisotropic, one- and two-sided, seen from behind) and rough glass,
/// by brute force and through the scene's own queries, with hidden emitters and both
/// roulettes: their light samples, BSDF samples and MIS as one path at a time computes them.
#[test]
fn rough_materials_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let smooth = rough_materials() + &smooth_ball([0.0, 1.7, -1.2], 0.3, "mirror2", 6, 10);
    cases_both_ways(
        "rough materials",
        [
            (rough_materials(), true, false, None),
            (rough_materials(), true, true, Some(0.6)),
            (smooth, false, false, None),
        ],
        70,
    );
}

/// Each of `cases` (scene text, whether brute force traces it, hidden emitters, a fixed
/// roulette's survival) rendered at 39×31, 4 spp, seed `seed` + its index, both ways; each
/// image lit.
fn cases_both_ways<const N: usize>(
    what: &str,
    cases: [(String, bool, bool, Option<f32>); N],
    seed: u64,
) {
    use mcrt::integrator::RussianRoulette;
    for (k, (text, brute, hide, rr)) in cases.into_iter().enumerate() {
        let scene = scene_from(&hiding_emitters(&text, hide));
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(39),
                height: Some(31),
                spp: Some(4),
                seed: Some(seed + k as u64),
                ..Default::default()
            },
        );
        if let Some(q) = rr {
            s.params.rr = RussianRoulette::Fixed(q);
        }
        let w = Wavefront::new(&scene, &s);
        assert!(
            w.is_some_and(|w| w.is_brute_force() == brute),
            "{what}: case {k}"
        );
        let what = format!("{what}, brute force {brute}, hide {hide}, {rr:?}");
        let (film, _) = same_both_ways(scene, &s, &what);
        assert!(
            film.sum_f64().iter().flatten().sum::<f64>() > 0.0,
            "{what}: lit"
        );
    }
}

/// [`SPECULAR`] with its mirrors and glass in materials the lanes shade through each lane's
/// `Material`: both `mirror1` quads (one facing away) a one-sided Beckmann rough plastic,
/// `mirror2` a two-sided plastic, the clear glass ball a principled BSDF with transmission,
/// clearcoat and sheen, the dense one a thin dielectric; the walls stay Lambertian, in the
/// lanes' own registers.
fn general_materials() -> String {
    let swap = |text: String, from: &str, to: &str| {
        assert!(text.contains(from), "SPECULAR holds {from}");
        text.replace(from, to)
    };
    let text = swap(
        SPECULAR.to_string(),
        "[material.mirror1]\ntype = \"mirror\"\nreflectance = [0.9, 0.8, 0.7]",
        "[material.mirror1]\ntype = \"roughplastic\"\nalbedo = [0.7, 0.3, 0.2]\nalpha = 0.2\ndistribution = \"beckmann\"",
    );
    let text = swap(
        text,
        "[material.mirror2]\ntype = \"mirror\"\nreflectance = [0.6, 0.9, 0.9]",
        "[material.mirror2]\ntype = \"plastic\"\nalbedo = [0.2, 0.5, 0.7]\ntwo_sided = true",
    );
    let text = swap(
        text,
        "[material.glass]\ntype = \"dielectric\"\nior = 1.5",
        "[material.glass]\ntype = \"principled\"\nbase_color = [0.8, 0.7, 0.6]\nroughness = 0.3\nmetallic = 0.2\nspec_trans = 0.6\nclearcoat = 0.5\nsheen = 0.3",
    );
    swap(
        text,
        "[material.dense]\ntype = \"dielectric\"\nior = 2.4\next_ior = 1.2",
        "[material.dense]\ntype = \"thindielectric\"\nior = 1.6",
    )
}

/// Materials that the lanes shade by calling each lane's `Material` (plastics, principled,
/// a thin dielectric; through the scene also a blend of Oren–Nayar and a smooth conductor,
/// textured roughness and a textured plastic), among Lambertian walls in the lanes' own
/// registers, by brute force and through the scene's queries, with hidden emitters and
/// both roulettes: the same film as one path at a time.
#[test]
fn general_materials_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let through = general_materials()
        .replace(
            "[material.dense]\ntype = \"thindielectric\"\nior = 1.6",
            "[material.clay]\ntype = \"oren_nayar\"\nalbedo = [0.6, 0.5, 0.4]\nsigma = 25\n\
             [material.gold]\ntype = \"conductor\"\nmaterial = \"Au\"\n\
             [material.dense]\ntype = \"blend\"\nmaterials = [\"clay\", \"gold\"]\nweight = 0.4\n\
             [texture.checks]\ntype = \"checkerboard\"\ncolor0 = [0.05, 0.05, 0.05]\ncolor1 = [0.4, 0.4, 0.4]\nuv_scale = [4, 4]\n\
             [material.brushed]\ntype = \"roughconductor\"\nmaterial = \"Cu\"\nalpha = \"checks\"\n\
             [material.tiles]\ntype = \"plastic\"\nalbedo = \"checks\"",
        )
        .replace(
            "[[shape]]\ntype = \"quad\"\nmaterial = \"white\"\nvertices = [[-2, 0, 3], [-2, 0, -2]",
            "[[shape]]\ntype = \"quad\"\nmaterial = \"tiles\"\nvertices = [[-2, 0, 3], [-2, 0, -2]",
        )
        + &smooth_ball([0.0, 1.7, -1.2], 0.3, "brushed", 6, 10);
    assert!(through.contains("\"tiles\"\nvertices") && through.contains("\"blend\""));
    cases_both_ways(
        "general materials",
        [
            (general_materials(), true, false, None),
            (general_materials(), true, true, Some(0.6)),
            (through.clone(), false, false, None),
            (through, false, true, Some(0.7)),
        ],
        90,
    );
}

/// Rough plastics, which the lanes shade in their registers (`rough_plastic::Coated`), each
/// lane reading its material's coating table: the walls a GGX one, `mirror1` a one-sided
/// Beckmann one of another η, `mirror2` a two-sided nonlinear GGX one with a specular
/// factor (three tables), by brute force and through the scene (where a smooth mesh ball is
/// a fourth, with a textured albedo, which the lanes leave to its `Material`): the same film
/// as one path at a time.
#[test]
fn rough_plastics_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let mut text = SPECULAR.to_string();
    for (from, to) in [
        (
            "[material.white]\ntype = \"lambert\"",
            "[material.white]\ntype = \"roughplastic\"\nalpha = 0.3\ndistribution = \"ggx\"",
        ),
        (
            "[material.mirror1]\ntype = \"mirror\"\nreflectance = [0.9, 0.8, 0.7]",
            "[material.mirror1]\ntype = \"roughplastic\"\nalbedo = [0.7, 0.3, 0.2]\nalpha = 0.15\ndistribution = \"beckmann\"\nior = 1.7",
        ),
        (
            "[material.mirror2]\ntype = \"mirror\"\nreflectance = [0.6, 0.9, 0.9]",
            "[material.mirror2]\ntype = \"roughplastic\"\nalbedo = [0.2, 0.5, 0.7]\nspecular = [0.9, 0.6, 0.4]\nalpha = 0.5\nnonlinear = true\ntwo_sided = true",
        ),
    ] {
        assert!(text.contains(from), "SPECULAR holds {from}");
        text = text.replacen(from, to, 1);
    }
    let through = text.clone()
        + "[texture.checks]\ntype = \"checkerboard\"\ncolor0 = [0.05, 0.05, 0.05]\n\
           color1 = [0.6, 0.4, 0.3]\nuv_scale = [4, 4]\n\
           [material.tiles]\ntype = \"roughplastic\"\nalbedo = \"checks\"\nalpha = 0.2\n"
        + &smooth_ball([0.0, 1.7, -1.2], 0.3, "tiles", 6, 10);
    cases_both_ways(
        "rough plastics",
        [
            (text.clone(), true, false, None),
            (text, true, true, Some(0.6)),
            (through.clone(), false, false, None),
            (through, false, true, Some(0.7)),
        ],
        170,
    );
}

/// A thin lens's and an orthographic camera's rays, made by each lane's `Camera` (a thin
/// lens's from a second pair of numbers), by brute force ([`SPECULAR`]) and through the
/// scene (with a smooth mesh ball): the same film as one path at a time.
#[test]
fn cameras_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let perspective = "type = \"perspective\"\norigin = [0, 1.2, 2.8]\ntarget = [0, 0.9, 0]\nup = [0, 1, 0]\nfov = 75";
    assert!(SPECULAR.contains(perspective));
    let lens = "type = \"thinlens\"\norigin = [0, 1.2, 2.8]\ntarget = [0, 0.9, 0]\nup = [0, 1, 0]\nfov = 75\naperture_radius = 0.15\nfocus_distance = 2.5";
    let ortho = "type = \"orthographic\"\norigin = [0, 1.2, 2.8]\ntarget = [0, 0.9, 0]\nup = [0, 1, 0]\nview_width = 3.5";
    let ball = smooth_ball([0.0, 1.7, -1.2], 0.3, "white", 6, 10);
    for (k, (camera, brute)) in [(lens, true), (ortho, true), (lens, false), (ortho, false)]
        .into_iter()
        .enumerate()
    {
        let mut text = SPECULAR.replace(perspective, camera);
        if !brute {
            text += &ball;
        }
        let scene = scene_from(&text);
        let s = settings(
            &scene,
            FileSettings {
                width: Some(37),
                height: Some(29),
                spp: Some(4),
                seed: Some(130 + k as u64),
                ..Default::default()
            },
        );
        let w = Wavefront::new(&scene, &s);
        assert!(w.is_some_and(|w| w.is_brute_force() == brute), "case {k}");
        let what = format!("camera {}, brute force {brute}", &camera[..20]);
        let (film, _) = same_both_ways(scene, &s, &what);
        assert!(
            film.sum_f64().iter().flatten().sum::<f64>() > 0.0,
            "{what}: lit"
        );
    }
}

/// The feature scenes of `tests/data/toml` (point, spot, directional, sphere, disk, mesh and
/// textured area lights, constant and bitmap environments; every BSDF, textured parameters,
/// blends), which the lanes render through the scene's queries, asking `Lights` lane by lane
/// where there is more than one planar light: the same film as one path at a time, with
/// hidden emitters, a fixed roulette and short paths too.
#[test]
fn feature_scenes_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    for (k, path) in feature_scenes().iter().enumerate() {
        let scene = Scene::build(mcrt::load_scene(path).unwrap());
        let hide = k % 2 == 1;
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(29),
                height: Some(23),
                spp: Some(4),
                seed: Some(110 + k as u64),
                hide_emitters: Some(hide),
                ..Default::default()
            },
        );
        s.params.max_depth = Some([3, 12][k % 2]);
        if k % 3 == 0 {
            s.params.rr = RussianRoulette::Fixed(0.7);
        }
        let w = Wavefront::new(&scene, &s);
        assert!(w.is_some_and(|w| !w.is_brute_force()), "{}", path.display());
        let what = format!("{}, hide {hide}", path.display());
        let (film, _) = same_both_ways(scene, &s, &what);
        assert!(
            film.sum_f64().iter().flatten().sum::<f64>() > 0.0,
            "{what}: lit"
        );
    }
}

/// The feature scenes of `tests/data/toml`, by name.
fn feature_scenes() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/toml");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 7, "the feature scenes are there");
    names
}

/// Several light samples a vertex (the vertex's lattice, each sample's shadow ray traced):
/// under the feature scenes' lights (2, 3 and 17 samples, across a packet of 16), and under
/// one planar light with rough conductors, rough glass and the general materials by brute
/// force and through the scene; hidden emitters and a fixed roulette on some: the same film
/// and shadow-ray count as one path at a time.
#[test]
fn several_light_samples_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    let mut cases: Vec<(String, Scene, bool)> = feature_scenes()
        .iter()
        .map(|p| {
            let scene = Scene::build(mcrt::load_scene(p).unwrap());
            (p.display().to_string(), scene, false)
        })
        .collect();
    let ball = smooth_ball([0.0, 1.7, -1.2], 0.3, "white", 6, 10);
    for (what, text, brute) in [
        ("rough", rough_materials(), true),
        ("general", general_materials(), true),
        ("general, a mesh ball", general_materials() + &ball, false),
    ] {
        cases.push((what.to_string(), scene_from(&text), brute));
    }
    for (k, (what, scene, brute)) in cases.into_iter().enumerate() {
        let hide = k % 2 == 1;
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(23),
                height: Some(19),
                spp: Some(2),
                seed: Some(150 + k as u64),
                hide_emitters: Some(hide),
                ..Default::default()
            },
        );
        s.params.shadow_rays = [2, 17, 3][k % 3];
        s.params.max_depth = Some(6);
        if k % 4 == 0 {
            s.params.rr = RussianRoulette::Fixed(0.7);
        }
        let w = Wavefront::new(&scene, &s);
        assert!(w.is_some_and(|w| w.is_brute_force() == brute), "{what}");
        let what = format!(
            "{what}, {} light samples, hide {hide}",
            s.params.shadow_rays
        );
        let (film, stats) = same_both_ways(scene, &s, &what);
        assert!(stats.rays.shadow_rays > 0, "{what}");
        assert!(
            film.sum_f64().iter().flatten().sum::<f64>() > 0.0,
            "{what}: lit"
        );
    }
}

/// A sphere of radius `r` at `c` as a mesh of `2·rings·segments` triangles with smooth
/// vertex normals (the sphere's), in `material`.
fn smooth_ball(c: [f32; 3], r: f32, material: &str, rings: usize, segments: usize) -> String {
    let mut normals = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            normals.push([
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ]);
        }
    }
    let at = |i: usize, j: usize| i * (segments + 1) + j;
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            indices.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            indices.push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    let list = |v: Vec<String>| v.join(", ");
    let p = normals.iter().map(|n| {
        format!(
            "[{}, {}, {}]",
            c[0] + r * n[0],
            c[1] + r * n[1],
            c[2] + r * n[2]
        )
    });
    let n = normals
        .iter()
        .map(|n| format!("[{}, {}, {}]", n[0], n[1], n[2]));
    let idx = indices
        .iter()
        .map(|t| format!("[{}, {}, {}]", t[0], t[1], t[2]));
    format!(
        "[[shape]]\ntype = \"mesh\"\nmaterial = \"{material}\"\npositions = [{}]\nnormals = [{}]\nindices = [{}]\n",
        list(p.collect()),
        list(n.collect()),
        list(idx.collect())
    )
}

/// Scenes that brute force does not take (hundreds of triangles, smooth vertex normals,
/// the BVH), traced by the lanes through the scene's own queries: the same film as one
/// path at a time, with mirrors, glass, one and several shadow rays and both roulettes.
#[test]
fn traced_through_the_scene_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    use mcrt::integrator::RussianRoulette;
    let text = SPECULAR.to_string()
        + &smooth_ball([0.9, 1.2, -0.6], 0.35, "glass", 8, 12)
        + &smooth_ball([-1.1, 1.3, -0.4], 0.3, "white", 6, 10)
        + &smooth_ball([0.0, 1.7, -1.2], 0.3, "mirror2", 6, 10);
    for (k, (n, rr, hide)) in [(1, None, false), (3, Some(0.7), true)]
        .into_iter()
        .enumerate()
    {
        let scene = scene_from(&hiding_emitters(&text, hide));
        assert!(scene.triangle_count() > 300 && !scene.is_flat());
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(37),
                height: Some(29),
                spp: Some(4),
                seed: Some(50 + k as u64),
                ..Default::default()
            },
        );
        s.params.shadow_rays = n;
        if let Some(q) = rr {
            s.params.rr = RussianRoulette::Fixed(q);
        }
        let w = Wavefront::new(&scene, &s);
        assert!(w.is_none_or(|w| !w.is_brute_force()));
        same_both_ways(
            scene,
            &s,
            &format!("smooth meshes, {n} shadow rays, {rr:?}"),
        );
    }
    // Textured Lambertian and mirror colours (looked up at each hit).
    let text = SPECULAR
        .replace(
            "[material.white]\ntype = \"lambert\"\nalbedo = [0.8, 0.8, 0.8]",
            "[texture.checks]\ntype = \"checkerboard\"\ncolor0 = [0.8, 0.7, 0.2]\ncolor1 = [0.1, 0.3, 0.6]\nuv_scale = [5, 3]\n[material.white]\ntype = \"lambert\"\nalbedo = \"checks\"",
        )
        .replace(
            "[material.mirror2]\ntype = \"mirror\"\nreflectance = [0.6, 0.9, 0.9]",
            "[texture.stripes]\ntype = \"checkerboard\"\ncolor0 = [0.9, 0.9, 0.9]\ncolor1 = [0.3, 0.6, 0.3]\nuv_scale = [8, 1]\n[material.mirror2]\ntype = \"mirror\"\nreflectance = \"stripes\"",
        );
    let scene = scene_from(&text);
    let s = settings(
        &scene,
        FileSettings {
            width: Some(33),
            height: Some(25),
            spp: Some(4),
            ..Default::default()
        },
    );
    let w = Wavefront::new(&scene, &s);
    assert!(w.is_some_and(|w| !w.is_brute_force()), "textures");
    same_both_ways(scene, &s, "textured colours");
    // Instances of a group (a smooth glass ball and a white one), rotated, scaled, mirrored.
    let grouped = |ball: String| ball.replacen("[[shape]]\n", "[[shape]]\ngroup = \"balls\"\n", 1);
    let text = SPECULAR.to_string()
        + &grouped(smooth_ball([0.0, 0.0, 0.0], 0.2, "glass", 6, 10))
        + &grouped(smooth_ball([0.3, 0.1, 0.0], 0.1, "white", 4, 8))
        + "[[instance]]\ngroup = \"balls\"\ntranslate = [0.9, 1.3, -0.5]\n"
        + "[[instance]]\ngroup = \"balls\"\nscale = [1.5, 0.8, 1.2]\nrotate = [0, 1, 1, 40]\ntranslate = [-1.0, 1.4, -0.8]\n"
        + "[[instance]]\ngroup = \"balls\"\nscale = [-1, 1, 1]\ntranslate = [0.2, 1.9, -1.3]\n";
    let scene = scene_from(&text);
    assert!(
        scene.instancing_summary().is_some(),
        "the scene has instances"
    );
    let s = settings(
        &scene,
        FileSettings {
            width: Some(31),
            height: Some(27),
            spp: Some(4),
            ..Default::default()
        },
    );
    same_both_ways(scene, &s, "instances");
    // The Cornell box through its BVH rather than by brute force, at every path length.
    for depth in [1, 2, 5] {
        let scene = cornell_with(mcrt::accel::SingleRays::Bvh);
        let mut s = settings(
            &scene,
            FileSettings {
                width: Some(24),
                height: Some(24),
                spp: Some(3),
                ..Default::default()
            },
        );
        s.params.max_depth = Some(depth);
        same_both_ways(
            scene,
            &s,
            &format!("Cornell box through the BVH, depth {depth}"),
        );
    }
}

/// The feature scene `maps-mask.xml`: an opacity mask (Mitsuba's `mask` with a bitmap
/// opacity of 1, 0.5 and 0) in front of a light, which the scene's queries see through for
/// camera and shadow rays alike, a normal-mapped rectangle and a bump-mapped sphere (whose
/// `Material`s the lanes call), two area lights and an environment.
#[test]
fn masks_and_maps_traced_through_the_scene_both_ways() {
    if !cpu_runs_it() {
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/features");
    let scene = Scene::build(mcrt::load_scene(&dir.join("maps-mask.xml")).unwrap());
    assert!(scene.materials.iter().any(|m| m.opacity.is_some()));
    assert!(scene.materials.iter().any(|m| m.normal_map.is_some()));
    assert!(scene.materials.iter().any(|m| m.bump.is_some()));
    let s = settings(
        &scene,
        FileSettings {
            width: Some(48),
            height: Some(24),
            spp: Some(4),
            ..Default::default()
        },
    );
    let w = Wavefront::new(&scene, &s);
    assert!(w.is_some_and(|w| !w.is_brute_force()), "the masked scene");
    same_both_ways(scene, &s, "an opacity mask, normal and bump maps");
}

/// Scenes and settings the wavefront does not take render one path at a time.
#[test]
fn declines_what_it_does_not_do() {
    if !cpu_runs_it() {
        return;
    }
    let scene = cornell();
    let base = settings(&scene, FileSettings::default());
    assert!(Wavefront::new(&scene, &base).is_some());
    let mut s = base.clone();
    s.params.kind = mcrt::integrator::IntegratorKind::Direct;
    assert!(
        Wavefront::new(&scene, &s).is_none(),
        "the direct integrator"
    );
    let mut s = base.clone();
    s.params.max_depth = Some(0);
    assert!(Wavefront::new(&scene, &s).is_none(), "no path at all");
    let mut s = base.clone();
    s.params.shadow_rays = 0;
    assert!(Wavefront::new(&scene, &s).is_none(), "no shadow ray");
    // What brute force does not take, the lanes trace through the scene's own queries.
    let through_scene = |what: &str, scene: &Scene| {
        let s = settings(scene, FileSettings::default());
        let w = Wavefront::new(scene, &s);
        assert!(w.is_some_and(|w| !w.is_brute_force()), "{what}");
    };
    // A second light, a sphere light: through the scene, also with several shadow rays a
    // vertex; rough and general materials by brute force either way.
    let two_lights = OPEN.to_string()
        + r#"
[[shape]]
type = "triangle"
emission = [1, 1, 1]
vertices = [[2, 0.1, 0], [2, 0.1, 1], [2, 1, 0]]
"#;
    let sphere_light = OPEN.replace(
        "type = \"quad\"\nemission = [6, 6, 6]\nvertices = [[-0.4, 1.2, -0.4], [-0.4, 1.2, 0.4], [0.4, 1.2, 0.4], [0.4, 1.2, -0.4]]",
        "type = \"sphere\"\nemission = [6, 6, 6]\ncenter = [0, 1.2, 0]\nradius = 0.2",
    );
    assert!(sphere_light.contains("radius = 0.2"));
    for (what, text, brute) in [
        ("two lights", two_lights, false),
        ("a sphere light", sphere_light, false),
        ("rough conductors", rough_materials(), true),
        ("general materials", general_materials(), true),
    ] {
        let scene = scene_from(&text);
        let mut s = settings(&scene, FileSettings::default());
        let w = Wavefront::new(&scene, &s);
        assert!(w.is_some_and(|w| w.is_brute_force() == brute), "{what}");
        s.params.shadow_rays = 2;
        let w = Wavefront::new(&scene, &s);
        assert!(
            w.is_some_and(|w| w.is_brute_force() == brute),
            "{what}, two shadow rays"
        );
    }
    through_scene(
        "a texture",
        &scene_from(&OPEN.replace(
            "[material.board]\ntype = \"lambert\"\nalbedo = [0.9, 0.2, 0.2]",
            "[texture.checks]\ntype = \"checkerboard\"\ncolor0 = [0.1, 0.1, 0.1]\ncolor1 = [0.9, 0.9, 0.9]\n[material.board]\ntype = \"lambert\"\nalbedo = \"checks\"",
        )),
    );
    through_scene(
        "the BVH traces",
        &cornell_with(mcrt::accel::SingleRays::Bvh),
    );
    let mesh = |normals: &str| {
        OPEN.to_string()
            + r#"
[[shape]]
type = "mesh"
material = "floor"
positions = [[-1, 0.1, 0], [1, 0.1, 0], [0, 0.1, 1]]
indices = [[0, 1, 2]]
"# + normals
    };
    through_scene(
        "vertex normals",
        &scene_from(&mesh("normals = [[0, 1, 0], [0.1, 1, 0], [0, 1, 0]]\n")),
    );
    // Vertex normals that are the face's own (on either side) are dropped when the scene is
    // built, so such a mesh is flat and taken.
    let scene = scene_from(&mesh("normals = [[0, 1, 0], [0, 1, 0], [0, 1, 0]]\n"));
    let s = settings(&scene, FileSettings::default());
    let w = Wavefront::new(&scene, &s);
    assert!(w.is_some_and(|w| w.is_brute_force()), "face normals");
    // Over 64 primitives.
    let many: String = (0..40)
        .map(|i| {
            let x = i as f32 * 0.05;
            format!(
                "[[shape]]\ntype = \"quad\"\nmaterial = \"floor\"\nvertices = [[{x}, 0.1, 0], [{x}, 0.1, 0.02], [{x}, 0.2, 0.02], [{x}, 0.2, 0]]\n"
            )
        })
        .collect();
    through_scene("many primitives", &scene_from(&(OPEN.to_string() + &many)));
    // Five spheres: more than brute force takes (four are taken).
    let ball = |i: usize| {
        format!(
            "[[shape]]\ntype = \"sphere\"\nmaterial = \"floor\"\ncenter = [{}, 0.3, 0]\nradius = 0.1\n",
            i as f32 * 0.3 - 0.6
        )
    };
    through_scene(
        "five spheres",
        &scene_from(&(OPEN.to_string() + &(0..5).map(ball).collect::<String>())),
    );
    let scene = scene_from(&(OPEN.to_string() + &(0..4).map(ball).collect::<String>()));
    let s = settings(&scene, FileSettings::default());
    let w = Wavefront::new(&scene, &s);
    assert!(w.is_some_and(|w| w.is_brute_force()), "four spheres");
}
