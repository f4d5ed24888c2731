//! Cameras (glTF 2.0 §3.10): a camera looks down its node's −z axis with +y up and +x to
//! the right; `yfov` is the vertical field of view in radians, and `aspectRatio`, when
//! given, the width over the height of the image.

use super::Loader;
use crate::camera::{CameraDesc, FovAxis};
use crate::scene::SceneError;
use glam::{Mat4, Vec3};

/// The image's longer side when a camera gives its aspect ratio and no size is set.
const DEFAULT_LONG_SIDE: u32 = 512;

/// The perspective camera at a node with world transform `world` and vertical field of
/// view `yfov` (radians): eye at the node's origin, looking down its −z, up its +y.
pub fn perspective(world: &Mat4, yfov: f32) -> CameraDesc {
    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
    CameraDesc::Perspective {
        origin,
        target: origin + forward,
        up: world.transform_vector3(Vec3::Y),
        fov: yfov.to_degrees(),
        fov_axis: FovAxis::Y,
    }
}

/// The orthographic camera at a node: rays along its −z from the plane `znear` in front of
/// it; `xmag` is the half width of the view. The half height is `xmag` over the image's
/// aspect ratio, which is `ymag` when the image has the camera's aspect ratio (the size mcrt
/// gives it unless told otherwise).
pub fn orthographic(world: &Mat4, xmag: f32, znear: f32) -> CameraDesc {
    let dir = world.transform_vector3(-Vec3::Z).normalize_or_zero();
    let left = world.transform_vector3(-Vec3::X).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    CameraDesc::Orthographic {
        center: world.transform_point3(Vec3::ZERO) + dir * znear.max(0.0),
        half_x: left * xmag,
        half_y: up * xmag,
        dir,
    }
}

/// Adds the camera at `node`, named after the node (and also after the camera, where its
/// name differs), for `--camera NAME`.
pub fn add_camera(
    l: &mut Loader,
    node: &::gltf::Node,
    cam: &::gltf::Camera,
    world: &Mat4,
) -> Result<(), SceneError> {
    let where_ = format!("cameras[{}] (at nodes[{}])", cam.index(), node.index());
    let (desc, aspect) = match cam.projection() {
        ::gltf::camera::Projection::Perspective(p) => {
            let yfov = p.yfov();
            if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                return Err(l.err(format!(
                    "{where_}: yfov {yfov} is not an angle in (0, π) radians"
                )));
            }
            (perspective(world, yfov), p.aspect_ratio())
        }
        ::gltf::camera::Projection::Orthographic(o) => {
            let (xmag, ymag) = (o.xmag(), o.ymag());
            if !(xmag > 0.0 && ymag > 0.0 && xmag.is_finite() && ymag.is_finite()) {
                return Err(l.err(format!(
                    "{where_}: xmag {xmag} and ymag {ymag} must be positive"
                )));
            }
            (orthographic(world, xmag, o.znear()), Some(xmag / ymag))
        }
    };
    desc.validate()
        .map_err(|e| l.err(format!("{where_}: the camera {e}")))?;
    if let Some(a) = aspect {
        if !(a > 0.0 && a.is_finite()) {
            return Err(l.err(format!("{where_}: aspectRatio {a} is not positive")));
        }
        // The first camera's shape sizes the image, unless the file set it already.
        let s = &mut l.desc.settings;
        if l.desc.cameras.is_empty() && s.width.is_none() && s.height.is_none() {
            let long = DEFAULT_LONG_SIDE as f32;
            let (w, h) = if a >= 1.0 {
                (long, long / a)
            } else {
                (long * a, long)
            };
            s.width = Some((w.round() as u32).max(1));
            s.height = Some((h.round() as u32).max(1));
        }
    }
    let name = node
        .name()
        .map(str::to_string)
        .or_else(|| cam.name().map(str::to_string))
        .unwrap_or_else(|| format!("camera{}", cam.index()));
    if let Some(alias) = cam.name().filter(|n| *n != name) {
        l.desc.cameras.push((name, desc.clone()));
        l.desc.cameras.push((alias.to_string(), desc));
    } else {
        l.desc.cameras.push((name, desc));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec2};

    fn ray_dir(desc: &CameraDesc, s: f32, t: f32) -> Vec3 {
        let cam = desc.build(200, 100);
        let x = s * 200.0;
        let y = t * 100.0;
        let r = cam.generate_ray(x as u32, y as u32, Vec2::new(x.fract(), y.fract()));
        Vec3::from(r.d)
    }

    /// An unrotated camera looks down −z; the image's top is +y, its right +x; yfov spans
    /// the image's height.
    #[test]
    fn identity_camera_looks_down_minus_z() {
        let yfov = 60f32.to_radians();
        let c = perspective(&Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)), yfov);
        let centre = ray_dir(&c, 0.5, 0.5);
        assert!((centre - Vec3::NEG_Z).length() < 1e-5, "{centre}");
        let top = ray_dir(&c, 0.5, 0.0);
        assert!((top.y / -top.z - (yfov / 2.0).tan()).abs() < 1e-4, "{top}");
        let right = ray_dir(&c, 1.0, 0.5);
        assert!(right.x > 0.0 && right.y.abs() < 1e-5, "{right}");
        // 2:1 image, vertical fov: the horizontal half extent is twice the vertical one.
        assert!((right.x / -right.z - 2.0 * (yfov / 2.0).tan()).abs() < 1e-4);
    }

    /// A camera turned 90° about +y (its −z to world −x) looks along −x; a camera rolled
    /// 90° about its view axis has world −x at the image's top.
    #[test]
    fn rotated_camera_follows_its_node() {
        let w = Mat4::from_quat(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let c = perspective(&w, 1.0);
        assert!((ray_dir(&c, 0.5, 0.5) - Vec3::NEG_X).length() < 1e-5);
        let roll = Mat4::from_quat(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2));
        let c = perspective(&roll, 1.0);
        let top = ray_dir(&c, 0.5, 0.0);
        assert!(top.x < -0.1 && top.y.abs() < 1e-5, "{top}");
    }

    /// An orthographic camera's rays are parallel, along −z; the image spans ±xmag across
    /// and ±ymag up for an image of aspect xmag/ymag, +x to the right and +y at the top.
    #[test]
    fn orthographic_camera() {
        let c = orthographic(&Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)), 2.0, 0.0);
        let cam = c.build(200, 100);
        let ray =
            |x: f32, y: f32| cam.generate_ray(x as u32, y as u32, Vec2::new(x.fract(), y.fract()));
        let (tl, br) = (ray(0.0, 0.0), ray(199.999, 99.999));
        assert!((Vec3::from(tl.d) - Vec3::NEG_Z).length() < 1e-6);
        assert!((Vec3::from(br.d) - Vec3::NEG_Z).length() < 1e-6);
        assert!(
            (Vec3::from(tl.o) - Vec3::new(-1.0, 3.0, 3.0)).length() < 1e-3,
            "{}",
            tl.o
        );
        assert!(
            (Vec3::from(br.o) - Vec3::new(3.0, 1.0, 3.0)).length() < 1e-3,
            "{}",
            br.o
        );
    }

    /// Scale in the node's transform does not change the view.
    #[test]
    fn scaled_node_keeps_the_view() {
        let w = Mat4::from_scale(Vec3::new(3.0, 0.5, 2.0));
        let c = perspective(&w, 1.0);
        let a = ray_dir(&c, 0.0, 0.0);
        let b = ray_dir(&perspective(&Mat4::IDENTITY, 1.0), 0.0, 0.0);
        assert!((a - b).length() < 1e-5);
    }
}
