//! Cameras. Both kinds reduce to one model, the course's: an eye point and an image plane
//! spanned by its corners. Pixel (x, y) with x to the right and y down covers the part of the
//! plane between (x/W, y/H) and ((x+1)/W, (y+1)/H); a ray leaves the eye through a uniformly
//! chosen point of that square (a box filter).
//!
//! The look-at camera (Mitsuba's `perspective`) places the plane at distance 1 in front of the
//! eye, sized by the field of view along the chosen axis.

use crate::geometry::Ray;
use glam::{Vec2, Vec3, Vec3A};

/// Which image axis a perspective camera's field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Diagonal,
    Smaller,
    Larger,
}

impl FovAxis {
    pub fn parse(s: &str) -> Option<FovAxis> {
        Some(match s {
            "x" => FovAxis::X,
            "y" => FovAxis::Y,
            "diagonal" => FovAxis::Diagonal,
            "smaller" => FovAxis::Smaller,
            "larger" => FovAxis::Larger,
            _ => return None,
        })
    }
}

/// A camera as a scene describes it; the image plane of a perspective camera depends on the
/// image's aspect ratio, which flags may change, so it is resolved at render time.
#[derive(Clone, Debug)]
pub enum CameraDesc {
    /// The course's camera: eye point and the image plane's corners.
    Pinhole {
        eye: Vec3,
        top_left: Vec3,
        top_right: Vec3,
        bottom_left: Vec3,
        bottom_right: Option<Vec3>,
    },
    /// Look-at camera with a field of view in degrees.
    Perspective {
        origin: Vec3,
        target: Vec3,
        up: Vec3,
        fov: f32,
        fov_axis: FovAxis,
    },
}

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub(crate) eye: Vec3A,
    pub(crate) tl: Vec3A,
    /// top_right − top_left
    pub(crate) right: Vec3A,
    /// bottom_left − top_left
    pub(crate) down: Vec3A,
    /// Bilinear twist: bottom_right − bottom_left − right (zero for a parallelogram).
    pub(crate) twist: Vec3A,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

/// The smallest sine of the angle between two directions that must not be parallel (a
/// perspective camera's view and up; the edges of a pinhole's image plane at a corner):
/// 0.001, about 0.06°. Below it the cross product that orients the image is mostly rounding
/// error (f32 carries about 7 digits), and the image may come out rotated or upside down.
pub const MIN_SINE: f64 = 1e-3;

/// The sine of the angle between `a` and `b`, in f64 (no overflow for any finite f32); 0
/// when either is zero.
fn sine(a: glam::DVec3, b: glam::DVec3) -> f64 {
    let (la, lb) = (a.length(), b.length());
    if la == 0.0 || lb == 0.0 {
        return 0.0;
    }
    ((a / la).cross(b / lb)).length()
}

impl CameraDesc {
    /// Refuses a camera that defines no image, or one whose orientation rounding decides:
    /// a perspective camera whose target is its origin or whose up vector is parallel to
    /// the view direction (within [`MIN_SINE`]); a pinhole whose corners coincide, lie on
    /// one line, or whose eye lies in the image plane. Err completes "the camera …".
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            CameraDesc::Perspective {
                origin, target, up, ..
            } => {
                let (o, t) = (origin.as_dvec3(), target.as_dvec3());
                let fwd = t - o;
                // The view direction as the renderer computes it, in f32, must be a direction.
                if fwd == glam::DVec3::ZERO
                    || !(target - origin).normalize_or_zero().is_normalized()
                {
                    return Err("has its target at its origin: no view direction".into());
                }
                if sine(fwd, up.as_dvec3()) < MIN_SINE {
                    return Err(format!(
                        "has its up vector ({}, {}, {}) parallel to its view direction \
                         ({}, {}, {}) (within {MIN_SINE} in the sine of their angle): \
                         which way is up is left to rounding",
                        up.x, up.y, up.z, fwd.x, fwd.y, fwd.z
                    ));
                }
                Ok(())
            }
            CameraDesc::Pinhole {
                eye,
                top_left,
                top_right,
                bottom_left,
                bottom_right,
            } => {
                let (tl, tr, bl) = (
                    top_left.as_dvec3(),
                    top_right.as_dvec3(),
                    bottom_left.as_dvec3(),
                );
                let br = bottom_right.map_or(tr + bl - tl, |b| b.as_dvec3());
                // Each corner with its two neighbours: the edges there must span a plane.
                let corners = [
                    ("top_left", tl, tr, bl),
                    ("top_right", tr, br, tl),
                    ("bottom_right", br, bl, tr),
                    ("bottom_left", bl, tl, br),
                ];
                for (name, c, a, b) in corners {
                    if sine(a - c, b - c) < MIN_SINE {
                        return Err(format!(
                            "has a degenerate image plane: at its {name} corner the edges \
                             to the neighbouring corners are zero or parallel (corners \
                             that coincide or lie on one line)"
                        ));
                    }
                }
                let n = (tr - tl).cross(bl - tl).normalize();
                let size = (tr - tl).length().max((bl - tl).length());
                if ((tl - eye.as_dvec3()).dot(n)).abs() < MIN_SINE * size {
                    return Err(
                        "has its eye in the plane of its image corners: no ray would cross \
                         the image"
                            .into(),
                    );
                }
                Ok(())
            }
        }
    }

    pub fn build(&self, width: u32, height: u32) -> Camera {
        let (eye, tl, tr, bl, br) = match *self {
            CameraDesc::Pinhole {
                eye,
                top_left,
                top_right,
                bottom_left,
                bottom_right,
            } => {
                let br = bottom_right.unwrap_or(top_right + bottom_left - top_left);
                (eye, top_left, top_right, bottom_left, br)
            }
            CameraDesc::Perspective {
                origin,
                target,
                up,
                fov,
                fov_axis,
            } => {
                let fwd = (target - origin).normalize();
                let right = fwd.cross(up).normalize();
                let up = right.cross(fwd);
                let aspect = width as f32 / height as f32;
                let t = (fov.to_radians() * 0.5).tan();
                // Half extents (hx, hy) of the plane at distance 1.
                let (hx, hy) = match fov_axis {
                    FovAxis::X => (t, t / aspect),
                    FovAxis::Y => (t * aspect, t),
                    FovAxis::Diagonal => {
                        let d = (aspect * aspect + 1.0).sqrt();
                        (t * aspect / d, t / d)
                    }
                    FovAxis::Smaller if aspect >= 1.0 => (t * aspect, t),
                    FovAxis::Smaller => (t, t / aspect),
                    FovAxis::Larger if aspect >= 1.0 => (t, t / aspect),
                    FovAxis::Larger => (t * aspect, t),
                };
                let c = origin + fwd;
                let tl = c - right * hx + up * hy;
                let tr = c + right * hx + up * hy;
                let bl = c - right * hx - up * hy;
                let br = c + right * hx - up * hy;
                (origin, tl, tr, bl, br)
            }
        };
        let (tl, tr, bl, br) = (
            Vec3A::from(tl),
            Vec3A::from(tr),
            Vec3A::from(bl),
            Vec3A::from(br),
        );
        let right = tr - tl;
        let down = bl - tl;
        Camera {
            eye: eye.into(),
            tl,
            right,
            down,
            twist: br - bl - right,
            width,
            height,
        }
    }
}

impl Camera {
    /// The point of the image plane at film coordinates (s, t) in [0,1]², s right, t down.
    #[inline]
    pub fn plane_point(&self, s: f32, t: f32) -> Vec3A {
        self.tl + self.right * s + self.down * t + self.twist * (s * t)
    }

    /// Ray through pixel (x, y) at offset `u` in [0,1)² inside the pixel.
    #[inline]
    pub fn generate_ray(&self, x: u32, y: u32, u: Vec2) -> Ray {
        let s = (x as f32 + u.x) / self.width as f32;
        let t = (y as f32 + u.y) / self.height as f32;
        let p = self.plane_point(s, t);
        Ray::new(self.eye, (p - self.eye).normalize())
    }

    /// Film coordinates (s, t) in [0,1]² (s right, t down) where the ray from the eye to
    /// `p` crosses the image plane; None for points behind the eye. The plane's bilinear
    /// twist is ignored (it is zero for every camera but a skewed pinhole).
    pub fn project(&self, p: Vec3A) -> Option<(f32, f32)> {
        let d = p - self.eye;
        // eye + λ·d = tl + s·right + t·down
        let m = glam::Mat3::from_cols(self.right.into(), self.down.into(), (-d).into());
        if m.determinant().abs() < 1e-20 {
            return None;
        }
        let x = m.inverse() * glam::Vec3::from(self.eye - self.tl);
        (x.z > 0.0).then_some((x.x, x.y))
    }

    pub fn eye(&self) -> Vec3A {
        self.eye
    }
}
