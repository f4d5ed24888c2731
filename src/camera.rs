//! Cameras. Every kind reduces to one model, the course's: an eye point and an image plane
//! spanned by its corners. Pixel (x, y) with x to the right and y down covers the part of the
//! plane between (x/W, y/H) and ((x+1)/W, (y+1)/H); a ray leaves the eye through a uniformly
//! chosen point of that square (a box filter).
//!
//! The look-at camera (Mitsuba's `perspective`) places the plane at distance 1 in front of the
//! eye, sized by the field of view along the chosen axis. The thin-lens camera (Mitsuba's
//! `thinlens`) is that camera with a lens: its rays leave a uniform point of a disk of radius
//! `aperture_radius` around the eye (Shirley and Chiu's concentric map) towards the point
//! where the pinhole ray crosses the plane of focus, at `focus_distance` along the view
//! direction (pbrt-v4 §5.2.3; Mitsuba 3's `thinlens.cpp`). It needs a second 2D sample per
//! camera ray, drawn right after the pixel's ([`Camera::sample_ray`]); the other kinds draw
//! only the pixel's, so their images keep their bits. The orthographic camera (Mitsuba's
//! `orthographic`) sends parallel rays along its view direction from the points of its image
//! plane.

use crate::geometry::Ray;
use crate::sampler::Sampler;
use crate::simd::Vector3;
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
    /// The look-at camera with a thin lens of radius `aperture_radius` (≥ 0) focused at
    /// `focus_distance` (> 0) along the view direction (Mitsuba's `thinlens`).
    ThinLens {
        origin: Vec3,
        target: Vec3,
        up: Vec3,
        fov: f32,
        fov_axis: FovAxis,
        aperture_radius: f32,
        focus_distance: f32,
    },
    /// Parallel rays along `dir` (Mitsuba's `orthographic`): the image is the rectangle
    /// centre ± `half_x` ± `half_y`/aspect (width over height), `half_x` pointing to the
    /// image's left and `half_y` up, as Mitsuba's camera space (x ∈ [−1, 1], y ∈ [−1/aspect,
    /// 1/aspect], mapped by `to_world`).
    Orthographic {
        center: Vec3,
        half_x: Vec3,
        half_y: Vec3,
        dir: Vec3,
    },
}

/// How rays leave the image plane of a [`Camera`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Lens {
    /// From the eye through the plane.
    Pinhole,
    /// From a point of the disk of `radius` around the eye spanned by the unit vectors `u`
    /// and `v`, towards the pinhole ray's point at `focus` times its distance to the plane
    /// (the plane lies at distance 1 in front of the eye).
    Thin {
        radius: f32,
        focus: f32,
        u: Vec3A,
        v: Vec3A,
    },
    /// From the plane's point along the unit direction `dir`.
    Orthographic { dir: Vec3A },
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
    pub(crate) lens: Lens,
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

/// Why a look-at camera defines no orientation: its target at its origin, or its up vector
/// parallel to its view direction (within [`MIN_SINE`]); None if it does.
fn look_at_problem(origin: Vec3, target: Vec3, up: Vec3) -> Result<(), String> {
    let (o, t) = (origin.as_dvec3(), target.as_dvec3());
    let fwd = t - o;
    // The view direction as the renderer computes it, in f32, must be a direction.
    if fwd == glam::DVec3::ZERO || !(target - origin).normalize_or_zero().is_normalized() {
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

/// The image plane of a look-at camera at distance 1 in front of `origin`: its corners
/// (top left, top right, bottom left, bottom right), and the unit right and up vectors.
fn look_at_plane(
    origin: Vec3,
    target: Vec3,
    up: Vec3,
    fov: f32,
    fov_axis: FovAxis,
    aspect: f32,
) -> ([Vec3; 4], Vec3, Vec3) {
    let fwd = (target - origin).normalize();
    let right = fwd.cross(up).normalize();
    let up = right.cross(fwd);
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
    ([tl, tr, bl, br], right, up)
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
            } => look_at_problem(origin, target, up),
            CameraDesc::ThinLens {
                origin,
                target,
                up,
                aperture_radius,
                focus_distance,
                ..
            } => {
                if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
                    return Err(format!(
                        "has aperture_radius {aperture_radius}: it must be a finite number ≥ 0"
                    ));
                }
                if !(focus_distance > 0.0 && focus_distance.is_finite()) {
                    return Err(format!(
                        "has focus_distance {focus_distance}: it must be a finite number > 0"
                    ));
                }
                look_at_problem(origin, target, up)
            }
            CameraDesc::Orthographic {
                half_x,
                half_y,
                dir,
                ..
            } => {
                let (x, y, d) = (half_x.as_dvec3(), half_y.as_dvec3(), dir.as_dvec3());
                if sine(x, y) < MIN_SINE {
                    return Err(
                        "has a degenerate image: its x and y extents are zero or parallel".into(),
                    );
                }
                if !dir.normalize_or_zero().is_normalized()
                    || x.cross(y).normalize().dot(d / d.length()).abs() < MIN_SINE
                {
                    return Err(
                        "has no view direction across its image (zero, or in the image's plane)"
                            .into(),
                    );
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

    /// An orthographic camera at `origin` looking at `target`, `up` up, whose view is
    /// `view_width` wide (its height follows the image's aspect ratio). Degenerate input
    /// gives a camera that [`CameraDesc::validate`] refuses.
    pub fn orthographic_look_at(origin: Vec3, target: Vec3, up: Vec3, view_width: f32) -> Self {
        let dir = (target - origin).normalize_or_zero();
        let left = up.cross(dir).normalize_or_zero();
        let up = dir.cross(left);
        let h = 0.5 * view_width;
        CameraDesc::Orthographic {
            center: origin,
            half_x: left * h,
            half_y: up * h,
            dir,
        }
    }

    pub fn build(&self, width: u32, height: u32) -> Camera {
        let aspect = width as f32 / height as f32;
        let (eye, tl, tr, bl, br, lens) = match *self {
            CameraDesc::Pinhole {
                eye,
                top_left,
                top_right,
                bottom_left,
                bottom_right,
            } => {
                let br = bottom_right.unwrap_or(top_right + bottom_left - top_left);
                (eye, top_left, top_right, bottom_left, br, Lens::Pinhole)
            }
            CameraDesc::Perspective {
                origin,
                target,
                up,
                fov,
                fov_axis,
            } => {
                let ([tl, tr, bl, br], ..) =
                    look_at_plane(origin, target, up, fov, fov_axis, aspect);
                (origin, tl, tr, bl, br, Lens::Pinhole)
            }
            CameraDesc::ThinLens {
                origin,
                target,
                up,
                fov,
                fov_axis,
                aperture_radius,
                focus_distance,
            } => {
                let ([tl, tr, bl, br], right, up) =
                    look_at_plane(origin, target, up, fov, fov_axis, aspect);
                let lens = Lens::Thin {
                    radius: aperture_radius,
                    focus: focus_distance,
                    u: right.into(),
                    v: up.into(),
                };
                (origin, tl, tr, bl, br, lens)
            }
            CameraDesc::Orthographic {
                center,
                half_x,
                half_y,
                dir,
            } => {
                // Camera x points left: the image's left edge is centre + half_x.
                let y = half_y / aspect;
                let tl = center + half_x + y;
                let tr = center - half_x + y;
                let bl = center + half_x - y;
                let br = center - half_x - y;
                let lens = Lens::Orthographic {
                    dir: dir.normalize().into(),
                };
                (center, tl, tr, bl, br, lens)
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
            lens,
        }
    }
}

impl Camera {
    /// The point of the image plane at film coordinates (s, t) in [0,1]², s right, t down.
    #[inline]
    pub fn plane_point(&self, s: f32, t: f32) -> Vec3A {
        self.plane_point_lanes(s, t)
    }

    /// [`Camera::plane_point`] over any lanes.
    #[inline(always)]
    pub fn plane_point_lanes<V: Vector3>(&self, s: V::F, t: V::F) -> V {
        let v = V::broadcast;
        v(self.tl) + v(self.right).scale(s) + v(self.down).scale(t) + v(self.twist).scale(s * t)
    }

    /// Ray through pixel (x, y) at offset `u` in [0,1)² inside the pixel; a thin lens's from
    /// the centre of its lens (its pinhole ray).
    #[inline]
    pub fn generate_ray(&self, x: u32, y: u32, u: Vec2) -> Ray {
        let s = (x as f32 + u.x) / self.width as f32;
        let t = (y as f32 + u.y) / self.height as f32;
        let p = self.plane_point(s, t);
        match self.lens {
            Lens::Orthographic { dir } => Ray::new(p, dir),
            _ => Ray::new(self.eye, (p - self.eye).normalize()),
        }
    }

    /// Ray through pixel (x, y) at offset `u` in [0,1)² inside the pixel, leaving the lens at
    /// the point that `lens` in [0,1)² maps to (concentric map); the lens sample matters to a
    /// thin lens only.
    #[inline]
    pub fn generate_ray_lens(&self, x: u32, y: u32, u: Vec2, lens: Vec2) -> Ray {
        let Lens::Thin {
            radius,
            focus,
            u: lu,
            v: lv,
        } = self.lens
        else {
            return self.generate_ray(x, y, u);
        };
        let s = (x as f32 + u.x) / self.width as f32;
        let t = (y as f32 + u.y) / self.height as f32;
        // The plane lies at distance 1 along the view direction, so the pinhole ray reaches
        // the plane of focus at `focus` times its way to the image plane.
        let focus_p = self.eye + (self.plane_point(s, t) - self.eye) * focus;
        let a = crate::material::sampling::square_to_disk_concentric(lens) * radius;
        let o = self.eye + lu * a.x + lv * a.y;
        Ray::new(o, (focus_p - o).normalize())
    }

    /// Whether a camera ray takes a lens sample (a second 2D sample after the pixel's).
    #[inline]
    pub fn samples_lens(&self) -> bool {
        matches!(self.lens, Lens::Thin { .. })
    }

    /// Whether rays leave the eye straight through the image plane (a pinhole or a look-at
    /// camera), the rays the wavefront's lanes make.
    #[inline]
    pub fn is_pinhole(&self) -> bool {
        self.lens == Lens::Pinhole
    }

    /// The camera ray of a sample through pixel (x, y): its offset in the pixel is the
    /// sampler's next 2D request and, for a thin lens only, its point on the lens the one
    /// after, so that cameras without a lens draw what they always drew.
    #[inline]
    pub fn sample_ray(&self, x: u32, y: u32, sampler: &mut Sampler) -> Ray {
        let u = sampler.next_2d();
        if self.samples_lens() {
            let lens = sampler.next_2d();
            self.generate_ray_lens(x, y, u, lens)
        } else {
            self.generate_ray(x, y, u)
        }
    }

    /// Film coordinates (s, t) in [0,1]² (s right, t down) where the camera ray to `p`
    /// crosses the image plane (a thin lens's pinhole ray); None for points behind the
    /// camera. The plane's bilinear twist is ignored (it is zero for every camera but a
    /// skewed pinhole).
    pub fn project(&self, p: Vec3A) -> Option<(f32, f32)> {
        // Pinhole: eye + λ·d = tl + s·right + t·down, with d = p − eye.
        // Orthographic: p − λ·dir = tl + s·right + t·down.
        let (d, from) = match self.lens {
            Lens::Orthographic { dir } => (-dir, p),
            _ => (p - self.eye, self.eye),
        };
        let m = glam::Mat3::from_cols(self.right.into(), self.down.into(), (-d).into());
        if m.determinant().abs() < 1e-20 {
            return None;
        }
        let x = m.inverse() * glam::Vec3::from(from - self.tl);
        (x.z > 0.0).then_some((x.x, x.y))
    }

    pub fn eye(&self) -> Vec3A {
        self.eye
    }
}
