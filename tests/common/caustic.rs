//! The caustic mask of the TNCG15 room's eye-1 view, shared by tests/reference.rs and
//! tests/photon.rs.
#![allow(dead_code)]

use glam::Vec2;
use mcrt::geometry::{Frame, Ray};
use mcrt::material::Bsdf;
use mcrt::scene::Scene;

/// Blocks of the eye-1 view that see the glass sphere's caustic: a camera ray, followed
/// through mirror and glass (both branches), reaches a diffuse point from which some point of
/// the light is seen through the glass sphere.
pub fn caustic_blocks(scene: &Scene, width: u32, block: u32) -> Vec<bool> {
    let cam = scene.camera(Some("eye1")).unwrap().build(width, width);
    let light = &scene.lights.lights;
    let lit_through_glass = |p: glam::Vec3A| {
        light.iter().any(|l| {
            (0..5).any(|i| {
                (0..5).any(|j| {
                    let (q, _, _) =
                        l.sample_point(Vec2::new((i as f32 + 0.5) / 5.0, (j as f32 + 0.5) / 5.0));
                    let ray = Ray::new(p, (q - p).normalize());
                    scene.intersect(&ray).is_some_and(|si| {
                        matches!(
                            scene.materials[si.material as usize].bsdf,
                            Bsdf::Dielectric(_)
                        )
                    })
                })
            })
        })
    };
    fn trace(scene: &Scene, ray: Ray, depth: u32, f: &dyn Fn(glam::Vec3A) -> bool) -> bool {
        let Some(si) = scene.intersect(&ray) else {
            return false;
        };
        let m = &scene.materials[si.material as usize];
        let frame = Frame::from_normal(si.ns);
        let wo = frame.to_local(-ray.d);
        match m.bsdf {
            Bsdf::Mirror(_) if depth < 6 => trace(
                scene,
                si.spawn_ray(frame.to_world(glam::Vec3A::new(-wo.x, -wo.y, wo.z))),
                depth + 1,
                f,
            ),
            Bsdf::Dielectric(d) if depth < 6 => {
                let refl = trace(
                    scene,
                    si.spawn_ray(frame.to_world(glam::Vec3A::new(-wo.x, -wo.y, wo.z))),
                    depth + 1,
                    f,
                );
                let refr =
                    mcrt::material::dielectric::refract_local(wo, d.eta).is_some_and(|(wi, _)| {
                        trace(scene, si.spawn_ray(frame.to_world(wi)), depth + 1, f)
                    });
                refl || refr
            }
            Bsdf::Lambert(_) | Bsdf::OrenNayar(_) => f(si.p),
            _ => false,
        }
    }
    let nb = width / block;
    let mut mask = vec![false; (nb * nb) as usize];
    for by in 0..nb {
        for bx in 0..nb {
            'block: for y in (by * block..(by + 1) * block).step_by(2) {
                for x in (bx * block..(bx + 1) * block).step_by(2) {
                    if trace(
                        scene,
                        cam.generate_ray(x, y, Vec2::splat(0.5)),
                        0,
                        &lit_through_glass,
                    ) {
                        mask[(by * nb + bx) as usize] = true;
                        break 'block;
                    }
                }
            }
        }
    }
    mask
}
