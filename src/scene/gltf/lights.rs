//! KHR_lights_punctual: point lights (intensity in candela, lm/sr), spot lights (candela,
//! with a cone about the node's −z; Mitsuba's `spot`, beam width = the inner cone angle,
//! cutoff = the outer) and directional lights (illuminance in lux, lm/m²,
//! travelling along the node's −z). mcrt's lights are radiometric (W/sr, W/m²); a lumen is
//! taken as 1/683 W, the luminous efficacy of 555 nm light that Blender's exporter assumes
//! ([`super::LUMENS_PER_WATT`]), so candela / 683 is W/sr and lux / 683 is W/m².

use super::{Loader, LUMENS_PER_WATT};
use crate::scene::desc::LightDesc;
use crate::scene::SceneError;
use crate::Color;
use glam::{Mat4, Quat, Vec3};

/// The radiometric value of a photometric `intensity` of colour `color`.
pub fn radiometric(color: [f32; 3], intensity: f32) -> Color {
    Color::from(color) * (intensity / LUMENS_PER_WATT)
}

pub fn add_light(
    l: &mut Loader,
    light: &::gltf::khr_lights_punctual::Light,
    world: &Mat4,
) -> Result<(), SceneError> {
    use ::gltf::khr_lights_punctual::Kind;
    let where_ = format!("KHR_lights_punctual.lights[{}]", light.index());
    let value = radiometric(light.color(), light.intensity());
    if !(value.is_finite() && value.min_element() >= 0.0) {
        return Err(l.err(format!(
            "{where_}: colour {:?} times intensity {} must be finite and not negative",
            light.color(),
            light.intensity()
        )));
    }
    if light.range().is_some() {
        l.note(format!(
            "{where_}: 'range' is ignored (lights fall off with the inverse square of the \
             distance, without a cut-off)"
        ));
    }
    let position = world.transform_point3(Vec3::ZERO);
    match light.kind() {
        Kind::Point => l.desc.lights.push(LightDesc::Point {
            position,
            intensity: value,
        }),
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let (inner, outer) = (inner_cone_angle.to_degrees(), outer_cone_angle.to_degrees());
            if let Some(f) = crate::light::spot::angles_fault(outer, inner) {
                return Err(l.err(format!(
                    "{where_}: cone angles inner {inner}°, outer {outer}°: {f}"
                )));
            }
            if inner < outer {
                l.note(format!(
                    "{where_}: the spot's edge fades linearly in the angle from {inner:.1}° to \
                     {outer:.1}° (Mitsuba's spot), not as the square of glTF's smooth step in \
                     the cosine"
                ));
            }
            let dir = world.transform_vector3(-Vec3::Z).normalize_or_zero();
            if dir == Vec3::ZERO {
                return Err(l.err(format!("{where_}: its node's transform has no direction")));
            }
            // Mitsuba's spot shines along its frame's +z.
            let to_world =
                Mat4::from_rotation_translation(Quat::from_rotation_arc(Vec3::Z, dir), position);
            l.desc.lights.push(LightDesc::Spot {
                to_world,
                intensity: value,
                cutoff_angle: outer,
                beam_width: inner,
                texture: None,
            })
        }
        Kind::Directional => {
            let direction = world.transform_vector3(-Vec3::Z).normalize_or_zero();
            if direction == Vec3::ZERO {
                return Err(l.err(format!("{where_}: its node's transform has no direction")));
            }
            l.desc.lights.push(LightDesc::Directional {
                direction,
                irradiance: value,
            })
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 683 cd of white light is 1 W/sr; the colour multiplies the intensity.
    #[test]
    fn candela_to_watts_per_steradian() {
        assert_eq!(radiometric([1.0; 3], 683.0), Color::ONE);
        assert_eq!(
            radiometric([0.5, 1.0, 0.0], 1366.0),
            Color::new(1.0, 2.0, 0.0)
        );
    }
}
