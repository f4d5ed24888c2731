//! The wavefront (sixteen paths at a time, `mcrt::integrator::wavefront`) against the path
//! tracer one path at a time, on the scenes it takes: the same renders both ways, the same
//! film (checked), alternating, on one thread and on all.
//!
//!     cargo bench --bench wavefront            (five rounds)
//!     cargo bench --bench wavefront -- 9       (nine rounds)
//!
//! Each row renders the scene at 128×128 (Figure 3.3's settings at 250×250) once per
//! round each way, the two ways alternating; it prints the fastest and the median round of
//! each and the ratio of the medians. (x86-64 with AVX2 and BMI2, and AVX-512 where the CPU
//! has it; elsewhere the wavefront never runs and there is nothing to compare.)

fn main() {
    #[cfg(target_arch = "x86_64")]
    x86::main();
    #[cfg(not(target_arch = "x86_64"))]
    println!("the wavefront is x86-64 code: nothing to compare here");
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use mcrt::film::Film;
    use mcrt::integrator::RussianRoulette;
    use mcrt::render::{render, RenderSettings};
    use mcrt::sampler::SamplerKind;
    use mcrt::scene::desc::FileSettings;
    use mcrt::scene::Scene;
    use std::path::Path;
    use std::time::Instant;

    fn load(file: &str) -> Scene {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        Scene::build(mcrt::load_scene(&p).expect("scene"))
    }

    fn time(scene: &Scene, s: &RenderSettings) -> (f64, Film) {
        let t = Instant::now();
        let (film, _) = render(scene, s, &|_| {}).expect("render");
        (t.elapsed().as_secs_f64(), film)
    }

    fn median(mut v: Vec<f64>) -> f64 {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }

    pub fn main() {
        let rounds: usize = std::env::args()
            .skip(1)
            .find_map(|a| a.parse().ok())
            .unwrap_or(5);
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        println!("| scene | threads | one at a time (s, min / median) | wavefront (s, min / median) | speed-up (medians) |");
        println!("|---|---|---|---|---|");
        type Case = (
            &'static str,
            &'static str,
            u32,
            u32,
            u32,
            Option<f32>,
            SamplerKind,
        );
        let cases: [Case; 4] = [
            (
                "Cornell box, depth 8",
                "scenes/cornell-box.toml",
                128,
                64,
                1,
                None,
                SamplerKind::Independent,
            ),
            (
                "TNCG15 room",
                "scenes/tncg15.toml",
                128,
                64,
                1,
                None,
                SamplerKind::Independent,
            ),
            (
                "TNCG15 room, Sobol",
                "scenes/tncg15.toml",
                128,
                64,
                1,
                None,
                SamplerKind::Sobol,
            ),
            (
                "Figure 3.3 (250², 5 spp, 10 shadow rays)",
                "scenes/tncg15.toml",
                250,
                5,
                10,
                Some(0.75),
                SamplerKind::Independent,
            ),
        ];
        for (name, file, size, spp, shadow_rays, rr, sampler) in cases {
            for threads in [1, cores] {
                let wide = load(file);
                let over = FileSettings {
                    width: Some(size),
                    height: Some(size),
                    spp: Some(spp),
                    sampler: Some(sampler),
                    ..Default::default()
                };
                let mut s = mcrt::resolve_settings(&wide.desc_settings, &over, Some(threads))
                    .expect("settings");
                s.params.shadow_rays = shadow_rays;
                if let Some(q) = rr {
                    s.params.rr = RussianRoulette::Fixed(q);
                }
                let scalar = mcrt::render::RenderSettings {
                    backend: mcrt::render::Backend::Scalar,
                    ..s.clone()
                };
                if mcrt::integrator::wavefront::Wavefront::new(&wide, &s).is_none() {
                    println!("| {name} | {threads} | – | not taken on this CPU | – |");
                    continue;
                }
                let (mut a, mut b) = (Vec::new(), Vec::new());
                for _ in 0..rounds {
                    let (ta, fa) = time(&wide, &scalar);
                    let (tb, fb) = time(&wide, &s);
                    assert!(fa == fb, "{name}: the films differ");
                    a.push(ta);
                    b.push(tb);
                }
                let (ma, mb) = (median(a.clone()), median(b.clone()));
                let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
                println!(
                    "| {name} | {threads} | {:.3} / {ma:.3} | {:.3} / {mb:.3} | {:.2}× |",
                    min(&a),
                    min(&b),
                    ma / mb
                );
            }
        }
    }
}
