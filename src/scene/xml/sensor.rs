//! Mitsuba 3's sensors as cameras: `perspective`, `thinlens` and `orthographic`, with their
//! parameter names, defaults and checks (src/sensors/{perspective,thinlens,orthographic}.cpp,
//! and `ProjectiveCamera` and `parse_fov` in src/render/sensor.cpp).

use super::document::Elem;
use super::props::{Props, Result};
use crate::camera::{CameraDesc, FovAxis};
use glam::{Mat4, Vec3};

/// The sensor types mcrt renders, for the message that refuses another.
pub(super) const SENSORS: &str = "perspective, thinlens and orthographic";

/// The camera of a `<sensor>` of type `kind`, or None if mcrt has no such sensor.
pub(super) fn camera(p: &Props, e: &Elem, kind: &str) -> Result<Option<CameraDesc>> {
    if !matches!(kind, "perspective" | "thinlens" | "orthographic") {
        return Ok(None);
    }
    let m = p.transform("to_world")?;
    let (near, far) = clip_planes(p, e)?;
    let camera = if kind == "orthographic" {
        CameraDesc::Orthographic {
            center: m.transform_point3(Vec3::new(0.0, 0.0, near)),
            half_x: m.transform_vector3(Vec3::X),
            half_y: m.transform_vector3(Vec3::Y),
            dir: m.transform_vector3(Vec3::Z).normalize_or_zero(),
        }
    } else {
        let (fov, fov_axis) = field_of_view(p, e)?;
        let (origin, target, up) = look_at(m);
        if kind == "perspective" {
            CameraDesc::Perspective {
                origin,
                target,
                up,
                fov,
                fov_axis,
            }
        } else {
            // Required in Mitsuba (no default); the focus defaults to the far clip plane.
            let aperture_radius = p
                .float_opt("aperture_radius")?
                .ok_or_else(|| p.doc.err(e, "a thinlens sensor needs an 'aperture_radius'"))?;
            let focus_distance = p.float("focus_distance", far)?;
            CameraDesc::ThinLens {
                origin,
                target,
                up,
                fov,
                fov_axis,
                aperture_radius,
                focus_distance,
            }
        }
    };
    camera.validate().map_err(|why| {
        p.doc.err(
            e,
            format!("the {kind} sensor is degenerate: the camera {why}"),
        )
    })?;
    Ok(Some(camera))
}

/// `near_clip` and `far_clip` (Mitsuba's defaults 0.01 and 10⁴), checked as Mitsuba checks
/// them. Only the orthographic camera's rays start at the near plane (as Mitsuba's, which
/// place their origin there); the others start at the eye and run on past the far plane,
/// which changes nothing where the geometry lies between them.
fn clip_planes(p: &Props, e: &Elem) -> Result<(f32, f32)> {
    let near = p.float("near_clip", 1e-2)?;
    let far = p.float("far_clip", 1e4)?;
    if !(near > 0.0 && near.is_finite()) {
        return Err(p.doc.err(
            e,
            format!("near_clip must be greater than zero, got {near}"),
        ));
    }
    if !(near < far) {
        return Err(p.doc.err(
            e,
            format!("near_clip ({near}) must be smaller than far_clip ({far})"),
        ));
    }
    Ok((near, far))
}

/// Origin, target (one unit ahead) and up of a camera-to-world transform (camera space looks
/// along +z with +y up, as Mitsuba's).
fn look_at(m: Mat4) -> (Vec3, Vec3, Vec3) {
    let origin = m.transform_point3(Vec3::ZERO);
    let dir = m.transform_vector3(Vec3::Z);
    let up = m.transform_vector3(Vec3::Y);
    (
        origin,
        origin + dir.normalize_or_zero(),
        up.normalize_or_zero(),
    )
}

/// The field of view in degrees and its axis: `fov` and `fov_axis`, or else `focal_length`
/// ("50mm" by default) on a 36 × 24 mm film, which spans the diagonal (Mitsuba's
/// `parse_fov`).
fn field_of_view(p: &Props, e: &Elem) -> Result<(f32, FovAxis)> {
    let fov = p.float_opt("fov")?;
    let focal = p.string_opt("focal_length")?;
    let (fov, fov_axis) =
        match (fov, focal) {
            (Some(_), Some(_)) => return Err(p.doc.err(
                e,
                "give either a field of view ('fov') or a focal length ('focal_length'), not both",
            )),
            (Some(fov), None) => {
                let axis = p.string("fov_axis", "x")?;
                let fov_axis = FovAxis::parse(&axis.to_ascii_lowercase()).ok_or_else(|| {
                    p.doc.err(
                        e,
                        format!(
                            "fov_axis '{}': expected x, y, diagonal, smaller or larger",
                            crate::input::shorten(axis)
                        ),
                    )
                })?;
                (fov, fov_axis)
            }
            (None, focal) => {
                let f = focal.unwrap_or("50mm");
                let mm = f.trim().strip_suffix("mm").unwrap_or(f.trim());
                let value: f64 = mm
                    .parse()
                    .ok()
                    .filter(|v: &f64| *v > 0.0 && v.is_finite())
                    .ok_or_else(|| {
                        p.doc.err(
                            e,
                            format!(
                        "focal_length '{}': expected a positive length in millimetres such as \
                         '50mm'",
                        crate::input::shorten(f)
                    ),
                        )
                    })?;
                let diagonal = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
                let fov = 2.0 * (diagonal / (2.0 * value)).atan().to_degrees();
                (fov as f32, FovAxis::Diagonal)
            }
        };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(p
            .doc
            .err(e, format!("fov must be in (0, 180) degrees, got {fov}")));
    }
    Ok((fov, fov_axis))
}
