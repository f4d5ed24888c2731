//! Mitsuba 3's `spot` emitter (`src/emitters/spot.cpp`): a point light at the origin of its
//! `to_world` frame, shining along the frame's +z within a cone.
//!
//! The intensity in a direction θ off the axis is `intensity · falloff(θ) · texture(uv)`:
//! - falloff is 1 within `beam_width`, 0 beyond `cutoff_angle`, and between them falls
//!   **linearly in the angle**, `(cutoff − θ) / (cutoff − beam_width)` (spot.cpp's
//!   `falloff_curve`; Mitsuba 3.9 renders exactly this, checked against its `sample_direction`);
//! - the optional texture is projected as spot.cpp's `direction_to_uv` does, for the local
//!   direction (x, y, z): `uv = ½ + ½ (x, y) / (z · tan(cutoff))`, so the cone's cross-section
//!   at the cutoff touches the unit square's edges.

use crate::texture::Texture;
use crate::Color;
use glam::{Mat3A, Vec2, Vec3A};

/// A spot light, ready to evaluate.
#[derive(Clone, Debug)]
pub struct SpotLight {
    /// The light's position (the frame's origin).
    pub position: Vec3A,
    /// The frame's linear part (local to world) and its inverse.
    to_world: Mat3A,
    to_local: Mat3A,
    intensity: Color,
    /// Angles in radians and their cosines.
    cutoff: f32,
    cos_cutoff: f32,
    cos_beam: f32,
    /// 1 / (cutoff − beam_width); unused where the two are equal (no transition).
    inv_transition: f32,
    /// tan(cutoff): the projection's scale.
    uv_factor: f32,
    texture: Option<Texture>,
}

/// What is wrong with a spot light's angles (in degrees), if anything: the cutoff must lie in
/// (0, 90] (within a hemisphere, where the projection of a texture is defined; Mitsuba does not
/// check, and its `tan` turns negative past 90°) and the beam width in [0, cutoff].
pub fn angles_fault(cutoff_deg: f32, beam_deg: f32) -> Option<String> {
    if !(cutoff_deg > 0.0 && cutoff_deg <= 90.0) {
        return Some(format!(
            "'cutoff_angle' must be in (0, 90] degrees, got {cutoff_deg}"
        ));
    }
    if !(beam_deg >= 0.0 && beam_deg <= cutoff_deg) {
        return Some(format!(
            "'beam_width' must be in [0, cutoff_angle = {cutoff_deg}] degrees, got {beam_deg}"
        ));
    }
    None
}

/// What is wrong with a spot light's frame (the linear part of `to_world`), if anything: it
/// must be invertible.
pub fn frame_fault(to_world: glam::Mat3) -> Option<String> {
    let det = to_world.determinant();
    let ok = det.is_finite() && det != 0.0 && to_world.inverse().is_finite();
    (!ok).then(|| "the spot light's to_world transform is singular".to_string())
}

impl SpotLight {
    /// `to_world`: the frame's linear part (local +z is the axis); `position`: its origin.
    /// The readers check the angles ([`angles_fault`]) and the frame ([`frame_fault`]) first;
    /// here the angles are only clamped into range.
    pub fn new(
        position: Vec3A,
        to_world: glam::Mat3,
        intensity: Color,
        cutoff_deg: f32,
        beam_deg: f32,
        texture: Option<Texture>,
    ) -> SpotLight {
        let cutoff_deg = cutoff_deg.clamp(1e-3, 90.0);
        let beam_deg = beam_deg.clamp(0.0, cutoff_deg);
        let (cutoff, beam) = (cutoff_deg.to_radians(), beam_deg.to_radians());
        SpotLight {
            position,
            to_world: Mat3A::from(to_world),
            to_local: Mat3A::from(to_world.inverse()),
            intensity,
            cutoff,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam.cos(),
            inv_transition: 1.0 / (cutoff - beam),
            // In f64: at a cutoff of 90° the f32 tangent of π/2 rounds negative.
            uv_factor: (cutoff_deg as f64).to_radians().tan() as f32,
            texture,
        }
    }

    /// The falloff towards the local direction `d` (any length), in [0, 1].
    #[inline]
    fn falloff(&self, d: Vec3A) -> f32 {
        let cos_theta = d.normalize_or_zero().z;
        if cos_theta <= self.cos_cutoff {
            0.0
        } else if cos_theta >= self.cos_beam {
            1.0
        } else {
            ((self.cutoff - cos_theta.clamp(-1.0, 1.0).acos()) * self.inv_transition).max(0.0)
        }
    }

    /// Radiant intensity (W/sr) leaving the light in world direction `w` (any length).
    #[inline]
    pub fn intensity_towards(&self, w: Vec3A) -> Color {
        let d = self.to_local * w;
        let f = self.falloff(d);
        if f <= 0.0 {
            return Color::ZERO;
        }
        let i = self.intensity * f;
        match &self.texture {
            None => i,
            Some(t) => {
                let uv = Vec2::new(d.x, d.y) / (d.z * self.uv_factor) * 0.5 + 0.5;
                i * t.eval(uv)
            }
        }
    }

    /// Emitted power averaged over RGB, for choosing among lights: pbrt-v4's estimate for a
    /// spot light (`SpotLight::Phi`, which counts the transition at half), times the
    /// texture's mean.
    pub fn power(&self) -> f32 {
        let mean = |c: Color| (c.x + c.y + c.z) / 3.0;
        let solid_angle = 2.0
            * std::f32::consts::PI
            * ((1.0 - self.cos_beam) + 0.5 * (self.cos_beam - self.cos_cutoff));
        let tex = self.texture.as_ref().map_or(1.0, |t| mean(t.mean()));
        mean(self.intensity) * solid_angle * tex
    }

    /// The world direction of the light's axis (unit).
    pub fn axis(&self) -> Vec3A {
        (self.to_world * Vec3A::Z).normalize()
    }

    /// cos(cutoff_angle): no light leaves further off the axis (for a rotation frame).
    pub fn cos_cutoff(&self) -> f32 {
        self.cos_cutoff
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(cutoff: f32, beam: f32) -> SpotLight {
        SpotLight::new(
            Vec3A::ZERO,
            glam::Mat3::IDENTITY,
            Color::ONE,
            cutoff,
            beam,
            None,
        )
    }

    /// Mitsuba 3.9's values (its `sample_direction` from points at these angles off the
    /// axis of a spot with cutoff 20°, beam 10°): 1 inside the beam, linear in the angle
    /// between, 0 past the cutoff.
    #[test]
    fn falloff_is_linear_in_the_angle() {
        let s = spot(20.0, 10.0);
        for (deg, want) in [
            (0.0, 1.0),
            (5.0, 1.0),
            (10.0, 1.0),
            (12.0, 0.8),
            (15.0, 0.5),
            (18.0, 0.2),
            (19.9, 0.01),
            (20.5, 0.0),
            (120.0, 0.0),
        ] {
            let t = f32::to_radians(deg);
            let got = s.intensity_towards(Vec3A::new(t.sin(), 0.0, t.cos())).x;
            assert!((got - want).abs() < 2e-4, "{deg}°: {got} vs {want}");
        }
    }

    #[test]
    fn equal_beam_and_cutoff_is_a_hard_edge() {
        let s = spot(30.0, 30.0);
        let at = |deg: f32| {
            let t = deg.to_radians();
            s.intensity_towards(Vec3A::new(t.sin(), 0.0, t.cos())).x
        };
        assert_eq!(at(29.9), 1.0);
        assert_eq!(at(30.1), 0.0);
    }

    #[test]
    fn angles_and_frames_out_of_range_are_refused() {
        assert!(frame_fault(glam::Mat3::IDENTITY).is_none());
        assert!(frame_fault(glam::Mat3::from_diagonal(glam::Vec3::new(1.0, 0.0, 1.0))).is_some());
        assert!(angles_fault(20.0, 15.0).is_none());
        assert!(angles_fault(90.0, 0.0).is_none());
        for (c, b) in [
            (0.0, 0.0),
            (-5.0, 0.0),
            (91.0, 10.0),
            (20.0, 25.0),
            (20.0, -1.0),
        ] {
            assert!(angles_fault(c, b).is_some(), "{c} {b}");
        }
        assert!(angles_fault(f32::NAN, 1.0).is_some());
    }

    /// The texture's centre lies on the axis; uv (1, ½) at the cutoff along local +x.
    #[test]
    fn texture_projection() {
        use crate::texture::{Bitmap, BitmapTexture, FilterType};
        // 2×1 image: left half red, right half green, looked up nearest.
        let bm = Bitmap::from_pixels(2, 1, vec![Color::X, Color::Y]).unwrap();
        let mut t = BitmapTexture::new(std::sync::Arc::new(bm));
        t.filter = FilterType::Nearest;
        let s = SpotLight::new(
            Vec3A::ZERO,
            glam::Mat3::IDENTITY,
            Color::ONE,
            40.0,
            40.0,
            Some(Texture::Bitmap(t)),
        );
        let t = 30f32.to_radians();
        assert_eq!(
            s.intensity_towards(Vec3A::new(t.sin(), 0.0, t.cos())),
            Color::Y
        );
        assert_eq!(
            s.intensity_towards(Vec3A::new(-t.sin(), 0.0, t.cos())),
            Color::X
        );
    }
}
