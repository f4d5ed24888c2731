//! Mitsuba 3's `envmap` emitter (`src/emitters/envmap.cpp`): radiance arriving from
//! infinitely far away, from a latitude-longitude image.
//!
//! # Mapping (envmap.cpp's `uv_to_direction`, exactly)
//!
//! In the light's frame (y up), texture coordinates (u, v) are the direction
//! `(sin φ sin θ, cos θ, −cos φ sin θ)` with φ = 2πu and θ = πv: u = 0 looks along −z,
//! u = ¼ along +x, v = 0 is straight up (+y), v = 1 straight down. `to_world` turns the frame
//! (it must be a rotation: the readers refuse others).
//!
//! The radiance is bilinear between pixels as envmap.cpp's `eval_spectrum` reads them: the
//! image gets a periodic extra column (its first), a column's values sit at u = (x + ½)/W
//! (the half-texel shift) and a row's at v = y/(H − 1), so that the top row is the north pole
//! and the bottom row the south pole; times `scale`.
//!
//! # Sampling
//!
//! The bilinear cells (W across, H − 1 down) get a piecewise-constant density in (u, v)
//! proportional to the integral of luminance times sin θ over the cell (pbrt-v4's
//! `ImageInfiniteLight`; Mitsuba samples the same product with a bilinear warp): a cell is
//! chosen where it sends much light, and never where it sends none (its four corners black). A point uniform in the cell maps to a direction, and the density
//! converts to solid angle by dω = 2π² sin θ du dv (pbrt-v4 eq. 12.7 with Mitsuba's ranges).

use super::distribution::Distribution2D;
use crate::texture::Bitmap;
use crate::Color;
use glam::{Mat3, Mat3A, Vec2, Vec3A};
use std::f32::consts::PI;

use crate::texture::luminance;

/// An environment map, ready to evaluate and sample.
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: usize,
    height: usize,
    /// Radiance (the image times `scale`), row-major, top row first.
    data: Vec<Color>,
    to_world: Mat3A,
    to_local: Mat3A,
    dist: Distribution2D,
    /// Radiance averaged over the sphere of directions.
    mean: Color,
}

/// What is wrong with an environment map's image size or `to_world`, if anything: the image
/// must be at least 2 × 3 pixels (as Mitsuba requires) and the frame a rotation (with at most
/// a uniform scale, which is divided out).
pub fn fault(width: u32, height: u32, to_world: Mat3) -> Option<String> {
    if width < 2 || height < 3 {
        return Some(format!(
            "an environment map must be at least 2×3 pixels, this one is {width}×{height}"
        ));
    }
    let s = to_world.determinant().abs().cbrt();
    let r = to_world * (1.0 / s);
    if !(s.is_finite() && s > 0.0 && (r.transpose() * r).abs_diff_eq(Mat3::IDENTITY, 1e-4)) {
        return Some(
            "an environment map's to_world must be a rotation (a uniform scale is ignored)".into(),
        );
    }
    None
}

impl EnvMap {
    /// The map of `image` times `scale` (finite, not negative) in the frame `to_world`
    /// (checked by [`fault`] first; only its rotation is used).
    pub fn new(image: &Bitmap, scale: f32, to_world: Mat3) -> EnvMap {
        let (w, h) = (image.width as usize, image.height as usize);
        let data: Vec<Color> = image.pixels().map(|c| c * scale).collect();
        let s = to_world.determinant().abs().cbrt();
        let rot = if s.is_finite() && s > 0.0 {
            to_world * (1.0 / s)
        } else {
            Mat3::IDENTITY
        };
        // Cells between pixel centres: W across (the last wraps to the first column), H − 1
        // down.
        let (cw, ch) = (w, h.saturating_sub(1).max(1));
        let px = |x: usize, y: usize| data[y.min(h - 1) * w + x % w];
        let mut weights = vec![0.0f32; cw * ch];
        let mut total = glam::DVec3::ZERO;
        let dtheta = PI / ch as f32;
        for y in 0..ch {
            // The radiance is linear in θ between a cell's rows, L = L0 (1 − t) + L1 t with
            // t = (θ − θ0)/Δθ: ∫ L sin θ dθ = L0 a0 + L1 a1, with a1 = ∫ t sin θ dθ =
            // (sin θ1 − sin θ0)/Δθ − cos θ1 and a0 + a1 = cos θ0 − cos θ1.
            let (t0, t1) = (y as f32 * dtheta, (y + 1) as f32 * dtheta);
            let a1 = ((t1.sin() - t0.sin()) / dtheta - t1.cos()).max(0.0);
            let a0 = (t0.cos() - t1.cos() - a1).max(0.0);
            for x in 0..cw {
                // Across, the mean of the two columns is exact.
                let top = 0.5 * (px(x, y) + px(x + 1, y));
                let bottom = 0.5 * (px(x, y + 1) + px(x + 1, y + 1));
                let integral = top * a0 + bottom * a1;
                weights[y * cw + x] = luminance(integral);
                // Times the cell's width in φ.
                total += (integral * (2.0 * PI / cw as f32)).as_dvec3();
            }
        }
        EnvMap {
            width: w,
            height: h,
            dist: Distribution2D::new(&weights, cw, ch),
            mean: (total / (4.0 * std::f64::consts::PI)).as_vec3(),
            data,
            to_world: Mat3A::from(rot),
            to_local: Mat3A::from(rot.transpose()),
        }
    }

    /// Radiance averaged over all directions.
    pub fn mean(&self) -> Color {
        self.mean
    }

    /// The local direction of texture coordinates `uv`, and sin θ.
    #[inline]
    fn uv_to_direction(uv: Vec2) -> (Vec3A, f32) {
        let (sin_theta, cos_theta) = (uv.y * PI).sin_cos();
        let (sin_phi, cos_phi) = (uv.x * 2.0 * PI).sin_cos();
        (
            Vec3A::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta),
            sin_theta,
        )
    }

    /// Texture coordinates of a unit local direction (u in (−½, ½], v in [0, 1]).
    #[inline]
    fn direction_to_uv(d: Vec3A) -> Vec2 {
        Vec2::new(
            d.x.atan2(-d.z) * (0.5 / PI),
            d.y.clamp(-1.0, 1.0).acos() * (1.0 / PI),
        )
    }

    /// Bilinear lookup in pixel coordinates: x in [0, W) (periodic), y in [0, H − 1].
    #[inline]
    fn lookup(&self, x: f32, y: f32) -> Color {
        let (w, h) = (self.width, self.height);
        let x0 = (x.max(0.0) as usize).min(w - 1);
        let y0 = (y.max(0.0) as usize).min(h - 2);
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let x1 = (x0 + 1) % w;
        let row0 = y0 * w;
        let row1 = row0 + w;
        let top = self.data[row0 + x0] * (1.0 - fx) + self.data[row0 + x1] * fx;
        let bottom = self.data[row1 + x0] * (1.0 - fx) + self.data[row1 + x1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Pixel coordinates (x, y) of texture coordinates, as `eval_spectrum` shifts them.
    #[inline]
    fn uv_to_pixel(&self, uv: Vec2) -> Vec2 {
        let u = uv.x - 0.5 / self.width as f32;
        let x = (u - u.floor()) * self.width as f32;
        // u − ⌊u⌋ can round to 1.
        let x = if x >= self.width as f32 { 0.0 } else { x };
        Vec2::new(x, uv.y.clamp(0.0, 1.0) * (self.height - 1) as f32)
    }

    /// Radiance arriving from world direction `d` (any length; zero gives black).
    #[inline]
    pub fn eval(&self, d: Vec3A) -> Color {
        let Some(local) = (self.to_local * d).try_normalize() else {
            return Color::ZERO;
        };
        let p = self.uv_to_pixel(Self::direction_to_uv(local));
        self.lookup(p.x, p.y)
    }

    /// A world direction (unit), the radiance from it and its solid-angle density; None
    /// where the map is black.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3A, Color, f32)> {
        let (p, pdf_cells) = self.dist.sample(u)?;
        // Cell coordinates to texture coordinates: x + ½ texel across, rows as they are.
        let uv = Vec2::new(p.x + 0.5 / self.width as f32, p.y);
        let (local, sin_theta) = Self::uv_to_direction(uv);
        if sin_theta <= 0.0 || pdf_cells <= 0.0 {
            return None;
        }
        let pdf = pdf_cells / (2.0 * PI * PI * sin_theta);
        let x = p.x * self.width as f32;
        let le = self.lookup(x, p.y * (self.height - 1) as f32);
        Some(((self.to_world * local).normalize(), le, pdf))
    }

    /// The solid-angle density with which `sample` gives world direction `d` (unit).
    #[inline]
    pub fn pdf(&self, d: Vec3A) -> f32 {
        let Some(local) = (self.to_local * d).try_normalize() else {
            return 0.0;
        };
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        let pixel = self.uv_to_pixel(Self::direction_to_uv(local));
        let cell = Vec2::new(
            pixel.x / self.width as f32,
            pixel.y / (self.height - 1) as f32,
        );
        self.dist.pdf(cell) / (2.0 * PI * PI * sin_theta)
    }
}
