//! Cameras beyond the pinhole: the thin lens (its lens samples are uniform on the aperture,
//! and every ray of a film point meets at the plane of focus), the orthographic camera
//! (parallel rays from the image rectangle), the sampler dimensions each takes, and the
//! XML sensors' parameters and defaults (Mitsuba's focal length).

#[path = "common/stats.rs"]
mod stats;

use glam::{Vec2, Vec3, Vec3A};
use mcrt::camera::{CameraDesc, FovAxis};
use mcrt::sampler::{Sampler, SamplerKind};
use stats::chi2_pvalue;
use std::path::Path;

fn thin_lens(aperture_radius: f32, focus_distance: f32) -> CameraDesc {
    CameraDesc::ThinLens {
        origin: Vec3::new(1.0, 2.0, 3.0),
        target: Vec3::new(1.0, 2.0, 0.0),
        up: Vec3::Y,
        fov: 50.0,
        fov_axis: FovAxis::X,
        aperture_radius,
        focus_distance,
    }
}

/// Lens points of a thin lens are uniform on its aperture: a chi-square test over 16 rings
/// of equal area × 16 sectors of the disk of radius 0.5 around the eye, in the plane
/// z = 3 facing the view direction (−z).
#[test]
fn lens_samples_are_uniform_on_the_aperture() {
    let radius = 0.5;
    let cam = thin_lens(radius, 4.0).build(64, 48);
    let mut rng = Sampler::from_state(7, 11);
    let (rings, sectors, n) = (16usize, 16usize, 256_000usize);
    let mut counts = vec![0.0f64; rings * sectors];
    for _ in 0..n {
        let ray = cam.generate_ray_lens(20, 30, rng.next_2d(), rng.next_2d());
        let d = ray.o - Vec3A::new(1.0, 2.0, 3.0);
        assert!(d.z.abs() < 1e-6, "lens point off the lens plane: {d:?}");
        let r2 = (d.x * d.x + d.y * d.y) / (radius * radius);
        assert!(r2 <= 1.0 + 1e-5, "lens point outside the aperture: {d:?}");
        let ring = ((r2 as f64 * rings as f64) as usize).min(rings - 1);
        let phi = (d.y.atan2(d.x) as f64).rem_euclid(std::f64::consts::TAU);
        let sector = ((phi / std::f64::consts::TAU * sectors as f64) as usize).min(sectors - 1);
        counts[ring * sectors + sector] += 1.0;
    }
    let expected = n as f64 / (rings * sectors) as f64;
    let stat: f64 = counts
        .iter()
        .map(|c| (c - expected) * (c - expected) / expected)
        .sum();
    let p = chi2_pvalue(stat, rings * sectors - 1);
    assert!(p > 1e-4, "chi-square {stat:.1}, p = {p:.2e}");
}

/// All rays through one film point, whatever their lens sample, cross the plane of focus
/// (focus_distance ahead of the eye along the view direction) at one point, the one the
/// lens centre's ray crosses; the lens centre's ray is the perspective camera's.
#[test]
fn thin_lens_rays_meet_at_the_plane_of_focus() {
    let focus = 4.0;
    let cam = thin_lens(0.3, focus).build(64, 48);
    let pin = CameraDesc::Perspective {
        origin: Vec3::new(1.0, 2.0, 3.0),
        target: Vec3::new(1.0, 2.0, 0.0),
        up: Vec3::Y,
        fov: 50.0,
        fov_axis: FovAxis::X,
    }
    .build(64, 48);
    let mut rng = Sampler::from_state(3, 5);
    for _ in 0..200 {
        let (x, y, u) = (rng.next_u32() % 64, rng.next_u32() % 48, rng.next_2d());
        let centre = cam.generate_ray_lens(x, y, u, Vec2::splat(0.5));
        let pinhole = pin.generate_ray(x, y, u);
        assert!((centre.o - pinhole.o).length() < 1e-6);
        assert!((centre.d - pinhole.d).length() < 1e-5);
        // The plane of focus is z = 3 − focus (the camera looks along −z).
        let at = |r: mcrt::geometry::Ray| r.at((r.o.z - (3.0 - focus)) / -r.d.z);
        let f = at(centre);
        for _ in 0..8 {
            let ray = cam.generate_ray_lens(x, y, u, rng.next_2d());
            assert!((ray.d.length() - 1.0).abs() < 1e-5);
            assert!((at(ray) - f).length() < 1e-4, "{:?} vs {f:?}", at(ray));
        }
    }
}

/// An orthographic camera's rays are parallel, along its view direction, and leave the
/// image rectangle: its corners are the centre ± half_x ± half_y / aspect (half_x to the
/// image's left).
#[test]
fn orthographic_rays_are_parallel_from_the_image_rectangle() {
    let desc = CameraDesc::Orthographic {
        center: Vec3::new(0.0, 1.0, 5.0),
        half_x: Vec3::new(-2.0, 0.0, 0.0),
        half_y: Vec3::new(0.0, 2.0, 0.0),
        dir: Vec3::new(0.0, 0.0, -1.0),
    };
    desc.validate().unwrap();
    let cam = desc.build(80, 40);
    let tl = cam.generate_ray(0, 0, Vec2::ZERO);
    let br = cam.generate_ray(79, 39, Vec2::ONE);
    assert!(
        (tl.o - Vec3A::new(-2.0, 2.0, 5.0)).length() < 1e-6,
        "{:?}",
        tl.o
    );
    assert!(
        (br.o - Vec3A::new(2.0, 0.0, 5.0)).length() < 1e-5,
        "{:?}",
        br.o
    );
    let mut rng = Sampler::from_state(1, 2);
    for _ in 0..100 {
        let r = cam.sample_ray(rng.next_u32() % 80, rng.next_u32() % 40, &mut rng);
        assert_eq!(r.d, Vec3A::new(0.0, 0.0, -1.0));
        assert!(r.o.z == 5.0 && r.o.x.abs() <= 2.0 && (r.o.y - 1.0).abs() <= 1.0);
    }
    // project() inverts it: a point ahead of the image lands where its ray starts.
    let (s, t) = cam.project(Vec3A::new(1.0, 1.5, -3.0)).unwrap();
    assert!(
        (s - 0.75).abs() < 1e-6 && (t - 0.25).abs() < 1e-6,
        "{s} {t}"
    );
    assert!(cam.project(Vec3A::new(1.0, 1.5, 6.0)).is_none());
    // The TOML form: a view width and the look-at frame.
    let look = CameraDesc::orthographic_look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::Y, Vec3::Y, 4.0);
    let c2 = look.build(80, 40);
    assert_eq!(c2.generate_ray(0, 0, Vec2::ZERO).o, tl.o);
}

/// Only a thin lens draws a lens sample: a perspective camera's ray from `sample_ray` is
/// `generate_ray` with the sampler's first 2D request and leaves the sampler where that
/// leaves it (so pinhole images keep their bits); a thin lens takes the next request too.
#[test]
fn only_a_thin_lens_takes_more_sampler_dimensions() {
    let persp = CameraDesc::Perspective {
        origin: Vec3::ZERO,
        target: Vec3::Z,
        up: Vec3::Y,
        fov: 40.0,
        fov_axis: FovAxis::X,
    }
    .build(32, 32);
    let thin = thin_lens(0.2, 3.0).build(32, 32);
    for kind in [SamplerKind::Independent, SamplerKind::Sobol] {
        for i in 0..64u64 {
            let mut a = Sampler::for_sample(kind, 9, 77, i);
            let mut b = a.clone();
            let ra = persp.sample_ray(5, 7, &mut a);
            let rb = persp.generate_ray(5, 7, b.next_2d());
            assert_eq!((ra.o, ra.d), (rb.o, rb.d));
            assert_eq!(a.next_1d().to_bits(), b.next_1d().to_bits());
            let mut c = Sampler::for_sample(kind, 9, 77, i);
            let mut d = c.clone();
            let rc = thin.sample_ray(5, 7, &mut c);
            let (u, lens) = (d.next_2d(), d.next_2d());
            let rd = thin.generate_ray_lens(5, 7, u, lens);
            assert_eq!((rc.o, rc.d), (rd.o, rd.d));
            assert_eq!(c.next_1d().to_bits(), d.next_1d().to_bits());
        }
    }
}

fn xml_camera(sensor: &str) -> CameraDesc {
    let text = format!("<scene version=\"3.0.0\">{sensor}</scene>");
    let d = mcrt::scene::xml::parse_xml(Path::new("t.xml"), &text, &Default::default()).unwrap();
    d.cameras[0].1.clone()
}

/// A perspective sensor without `fov` has Mitsuba's focal length, 50 mm on a 36 × 24 mm
/// film, which spans the diagonal; `focal_length` sets another.
#[test]
fn perspective_without_fov_has_a_50mm_lens() {
    let fov_of = |focal: f64| 2.0 * (36f64.hypot(24.0) / (2.0 * focal)).atan().to_degrees();
    for (sensor, focal) in [
        ("<sensor type=\"perspective\"/>", 50.0),
        (
            "<sensor type=\"perspective\"><string name=\"focal_length\" value=\"35mm\"/></sensor>",
            35.0,
        ),
        (
            "<sensor type=\"thinlens\"><string name=\"focal_length\" value=\"85\"/>\
             <float name=\"aperture_radius\" value=\"0.1\"/></sensor>",
            85.0,
        ),
    ] {
        let (fov, fov_axis) = match xml_camera(sensor) {
            CameraDesc::Perspective { fov, fov_axis, .. }
            | CameraDesc::ThinLens { fov, fov_axis, .. } => (fov, fov_axis),
            c => panic!("{c:?}"),
        };
        assert_eq!(fov_axis, FovAxis::Diagonal);
        assert!((fov as f64 - fov_of(focal)).abs() < 1e-4, "{fov}");
    }
}

/// The thinlens sensor's parameters, and its focus at the far clip plane by default; the
/// orthographic sensor's extent from its to_world scale.
#[test]
fn xml_thinlens_and_orthographic_parameters() {
    match xml_camera(
        "<sensor type=\"thinlens\"><float name=\"fov\" value=\"30\"/>\
         <float name=\"aperture_radius\" value=\"0.2\"/><float name=\"far_clip\" value=\"500\"/>\
         </sensor>",
    ) {
        CameraDesc::ThinLens {
            aperture_radius,
            focus_distance,
            fov,
            ..
        } => assert_eq!((aperture_radius, focus_distance, fov), (0.2, 500.0, 30.0)),
        c => panic!("{c:?}"),
    }
    match xml_camera(
        "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale x=\"3\" y=\"2\"/>\
         <translate z=\"-4\"/></transform></sensor>",
    ) {
        CameraDesc::Orthographic {
            center,
            half_x,
            half_y,
            dir,
        } => {
            assert_eq!(center, Vec3::new(0.0, 0.0, 0.01 - 4.0));
            assert_eq!(
                (half_x, half_y, dir),
                (Vec3::X * 3.0, Vec3::Y * 2.0, Vec3::Z)
            );
        }
        c => panic!("{c:?}"),
    }
}

/// The TOML format's thinlens and orthographic cameras.
#[test]
fn toml_thinlens_and_orthographic_cameras() {
    let d = mcrt::scene::toml::parse_toml(
        Path::new("t.toml"),
        "[[camera]]\nname = \"lens\"\ntype = \"thinlens\"\norigin = [1, 2, 3]\n\
         target = [1, 2, 0]\nup = [0, 1, 0]\nfov = 50\naperture_radius = 0.3\n\
         focus_distance = 4\n\n[[camera]]\nname = \"plan\"\ntype = \"orthographic\"\n\
         origin = [0, 1, 5]\ntarget = [0, 1, 0]\nup = [0, 1, 0]\nview_width = 4\n",
    )
    .unwrap();
    let lens = d.cameras[0].1.build(64, 48);
    let want = thin_lens(0.3, 4.0).build(64, 48);
    let mut rng = Sampler::from_state(5, 6);
    for _ in 0..16 {
        let (u, l) = (rng.next_2d(), rng.next_2d());
        let (a, b) = (
            lens.generate_ray_lens(3, 4, u, l),
            want.generate_ray_lens(3, 4, u, l),
        );
        assert_eq!((a.o, a.d), (b.o, b.d));
    }
    let plan = d.cameras[1].1.build(80, 40);
    let tl = plan.generate_ray(0, 0, Vec2::ZERO);
    assert_eq!(tl.o, Vec3A::new(-2.0, 2.0, 5.0));
    assert_eq!(tl.d, Vec3A::new(0.0, 0.0, -1.0));
}

/// The wavefront takes the Cornell box with a thin lens or an orthographic camera too
/// (their rays made by each lane's `Camera`), and renders it with the path tracer's bits,
/// forced to either backend (`tests/wavefront.rs` compares every backend on more scenes).
#[cfg(target_arch = "x86_64")]
#[test]
fn the_wavefront_takes_lens_and_orthographic_cameras() {
    use mcrt::integrator::wavefront::Wavefront;
    use mcrt::render::Backend;
    use mcrt::scene::desc::FileSettings;
    use mcrt::scene::Scene;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let mut desc = mcrt::load_scene(&path).unwrap();
    let over = FileSettings {
        width: Some(16),
        height: Some(16),
        spp: Some(2),
        ..Default::default()
    };
    let s = mcrt::resolve_settings(&desc.settings, &over, None).unwrap();
    if Wavefront::new(&Scene::build(desc.clone()), &s).is_none() {
        eprintln!("this CPU has no wavefront backend: nothing to decline");
        return;
    }
    let eye = Vec3::new(0.0, 0.0, 3.9);
    for cam in [
        CameraDesc::ThinLens {
            origin: eye,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov: 40.0,
            fov_axis: FovAxis::X,
            aperture_radius: 0.1,
            focus_distance: 3.9,
        },
        CameraDesc::orthographic_look_at(eye, Vec3::ZERO, Vec3::Y, 2.0),
    ] {
        desc.cameras = vec![("main".into(), cam)];
        let scene = Scene::build(desc.clone());
        assert!(Wavefront::new(&scene, &s).is_some());
        let with = |backend| mcrt::render::RenderSettings {
            backend,
            ..s.clone()
        };
        let (one, _) = mcrt::render::render(&scene, &with(Backend::Scalar), &|_| {}).unwrap();
        let (wide, _) = mcrt::render::render(&scene, &s, &|_| {}).unwrap();
        assert!(one.sum_f64().iter().flatten().sum::<f64>() > 0.0, "lit");
        assert_eq!(wide.sum, one.sum, "the wavefront's film");
        if std::arch::is_x86_feature_detected!("avx512f") {
            let (avx2, _) = mcrt::render::render(&scene, &with(Backend::Avx2), &|_| {}).unwrap();
            assert_eq!(avx2.sum, one.sum, "the AVX2 backend's film");
        }
    }
}
