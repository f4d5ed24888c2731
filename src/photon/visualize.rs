//! `mcrt photons`: the stored photons drawn over a dimmed direct-light render of the scene,
//! global photons in blue, caustic photons in orange (each a dot where it is visible from
//! the camera).

use super::PhotonMaps;
use crate::image::Image;
use crate::integrator::IntegratorKind;
use crate::render::{RenderError, RenderSettings};
use crate::scene::Scene;
use crate::Color;
use glam::Vec3A;

pub const GLOBAL_COLOR: Color = Color::new(0.15, 0.45, 1.0);
pub const CAUSTIC_COLOR: Color = Color::new(1.0, 0.55, 0.05);
/// The background render is scaled by this.
const DIM: f32 = 0.35;

/// Draws the photons of `maps` over the scene as seen by the settings' camera.
pub fn draw_photons(
    scene: &Scene,
    s: &RenderSettings,
    maps: &PhotonMaps,
) -> Result<Image, RenderError> {
    let mut bg = s.clone();
    bg.params.kind = IntegratorKind::Direct;
    let (film, _) = crate::render::render(scene, &bg, &|_| {})?;
    let mut img = film.image();
    for p in img.pixels.iter_mut() {
        *p *= DIM;
    }
    let camera = crate::render::camera_for(scene, s)?;
    let (ox, oy, w, h) = s.window();
    let eye = camera.eye();
    let mut splat = |p: Vec3A, c: Color| {
        let Some((sx, sy)) = camera.project(p) else {
            return;
        };
        let (x, y) = (
            (sx * s.width as f32).floor() as i64 - ox as i64,
            (sy * s.height as f32).floor() as i64 - oy as i64,
        );
        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
            return;
        }
        let ray = crate::geometry::Ray::new(eye, p - eye);
        if scene.occluded(&ray, 0.999) {
            return;
        }
        img.pixels[(y as u32 * w + x as u32) as usize] = c;
    };
    for ph in maps.global.photons() {
        if !ph.is_caustic() {
            splat(ph.pos(), GLOBAL_COLOR);
        }
    }
    for ph in maps.caustic.photons() {
        splat(ph.pos(), CAUSTIC_COLOR);
    }
    Ok(img)
}
