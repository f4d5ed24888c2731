//! Numerical robustness: a scene scaled by 1e-3 or 1e4 renders the same image as at scale 1
//! (ray offsets scale with the scene, no fixed epsilon), for a diffuse box and for the TNCG15
//! room with its glass sphere and mirror.

mod common;

use common::*;
use glam::{Mat4, Vec3};
use mcrt::camera::CameraDesc;
use mcrt::scene::desc::FileSettings;
use mcrt::scene::{GeometryDesc, Scene, SceneDesc};

fn scaled(mut d: SceneDesc, s: f32) -> SceneDesc {
    for shape in &mut d.shapes {
        match &mut shape.geometry {
            GeometryDesc::Mesh(m) => m.transform(&Mat4::from_scale(Vec3::splat(s))),
            GeometryDesc::Sphere { center, radius }
            | GeometryDesc::OrientedSphere { center, radius, .. } => {
                *center *= s;
                *radius *= s;
            }
        }
    }
    for (_, cam) in &mut d.cameras {
        match cam {
            CameraDesc::Pinhole {
                eye,
                top_left,
                top_right,
                bottom_left,
                bottom_right,
            } => {
                *eye *= s;
                *top_left *= s;
                *top_right *= s;
                *bottom_left *= s;
                if let Some(b) = bottom_right {
                    *b *= s;
                }
            }
            CameraDesc::Perspective { origin, target, .. } => {
                *origin *= s;
                *target *= s;
            }
            CameraDesc::ThinLens {
                origin,
                target,
                aperture_radius,
                focus_distance,
                ..
            } => {
                *origin *= s;
                *target *= s;
                *aperture_radius *= s;
                *focus_distance *= s;
            }
            CameraDesc::Orthographic {
                center,
                half_x,
                half_y,
                ..
            } => {
                *center *= s;
                *half_x *= s;
                *half_y *= s;
            }
        }
    }
    d
}

fn same_image_at_every_scale(file: &str, camera: Option<&str>) {
    let desc = mcrt::load_scene(&project_path(file)).unwrap();
    let fs = desc.settings.clone();
    let s = settings(
        &fs,
        FileSettings {
            width: Some(64),
            height: Some(64),
            spp: Some(64),
            camera: camera.map(String::from),
            ..Default::default()
        },
    );
    let base = render_with(&Scene::build(desc.clone()), &s);
    for scale in [1e-3f32, 1e4] {
        let r = render_with(&Scene::build(scaled(desc.clone(), scale)), &s);
        // Radiance does not depend on scale. Compare 8×8 blocks with the noise of both.
        let (mut worst, mut sum_a, mut sum_b) = (0.0f64, 0.0, 0.0);
        for by in 0..8 {
            for bx in 0..8 {
                let lum = |p: [f64; 3]| (p[0] + p[1] + p[2]) / 3.0;
                let a = lum(base.mean.block_mean(bx, by, 8));
                let b = lum(r.mean.block_mean(bx, by, 8));
                let var = |img: &mcrt::image::Image| {
                    let v = img.block_mean(bx, by, 8);
                    (v[0] + v[1] + v[2]) / 3.0 / 64.0
                };
                let sigma = (var(&base.var) + var(&r.var)).sqrt().max(1e-6 * a.abs());
                worst = worst.max((a - b).abs() / sigma);
                sum_a += a;
                sum_b += b;
            }
        }
        eprintln!("{file} at scale {scale}: worst block z {worst:.2}, image means {sum_a:.4} / {sum_b:.4}");
        assert!(
            worst < 5.0,
            "{file} at scale {scale}: a block is off by {worst:.2} sigma"
        );
        assert!(sum_b > 0.0);
    }
}

#[test]
fn cornell_box_at_every_scale() {
    same_image_at_every_scale("scenes/cornell-box.toml", None);
}

#[test]
fn tncg15_room_with_glass_and_mirror_at_every_scale() {
    same_image_at_every_scale("scenes/tncg15.toml", Some("eye1"));
}
