//! Mitsuba's `cylinder` shape (src/shapes/cylinder.cpp), also the TOML format's: the open
//! tube of radius `radius` from `p0` to `p1`, then `to_world`; normals point outwards unless
//! `flip_normals`.
//!
//! mcrt traces it as a mesh: [`SEGMENTS`] quads around the axis whose vertex normals are the
//! exact radial normals, so shading is smooth; the polygon's circumradius is enlarged so its
//! perimeter, and so the area (and an emitter's power), is exact, as for the disk. The
//! silhouette then departs from the true circle by at most 1 − cos(π/n) ≈ 8·10⁻⁵ of the
//! radius. Texture coordinates are Mitsuba's: u = φ/2π around the axis from the local frame's
//! x axis (Duff et al.'s frame around p1 − p0, as Mitsuba's `Frame3f`), v = 0 at p0 to 1
//! at p1.

use crate::geometry::mesh::TriangleMesh;
use crate::geometry::Frame;
use glam::{Mat4, Vec2, Vec3, Vec3A};

/// Quads around the axis.
pub const SEGMENTS: u32 = 256;

/// The unit cylinder of Mitsuba's object space: radius 1 around the z axis, z from 0 to 1,
/// outward normals.
pub fn unit_cylinder() -> TriangleMesh {
    let n = SEGMENTS;
    let step = std::f32::consts::TAU / n as f32;
    // Perimeter of the regular n-gon of circumradius R: 2nR·sin(π/n) = 2π.
    let r = std::f32::consts::PI / (n as f32 * (0.5 * step).sin());
    let (mut positions, mut normals, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
    // n + 1 columns: the seam's vertices twice, at u = 0 and u = 1.
    for i in 0..=n {
        let a = i as f32 * step;
        let (s, c) = if i == n { (0.0, 1.0) } else { a.sin_cos() };
        for z in [0.0, 1.0] {
            positions.push(Vec3::new(r * c, r * s, z));
            normals.push(Vec3::new(c, s, 0.0));
            uvs.push(Vec2::new(i as f32 / n as f32, z));
        }
    }
    let mut indices = Vec::new();
    for i in 0..n {
        let (b0, t0, b1, t1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        // (tangent around the axis) × (up the axis) points outwards.
        indices.push([b0, b1, t1]);
        indices.push([b0, t1, t0]);
    }
    TriangleMesh {
        tangents: None,
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
    }
}

/// The object-to-world map of the cylinder from `p0` to `p1` of radius `radius` (Mitsuba's
/// to_world · translate(p0) · to_frame(axis) · scale(r, r, length)); Err says why there is
/// none (a radius or length that is not positive).
pub fn cylinder_transform(to_world: Mat4, p0: Vec3, p1: Vec3, radius: f32) -> Result<Mat4, String> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(format!("cylinder radius must be positive, got {radius}"));
    }
    let d = p1 - p0;
    let length = d.length();
    if !(length > 0.0 && length.is_finite()) {
        return Err(format!(
            "the cylinder's p0 and p1 must be distinct points (both are ({}, {}, {}))",
            p0.x, p0.y, p0.z
        ));
    }
    let f = Frame::from_normal(Vec3A::from(d / length));
    let frame = Mat4::from_cols(
        f.s.extend(0.0),
        f.t.extend(0.0),
        f.n.extend(0.0),
        glam::Vec4::W,
    );
    Ok(to_world
        * Mat4::from_translation(p0)
        * frame
        * Mat4::from_scale(Vec3::new(radius, radius, length)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mesh's area is the cylinder's (2πrh), its faces point outwards, and its vertex
    /// normals are the radial unit vectors at the vertices.
    #[test]
    fn unit_cylinder_area_and_normals() {
        let m = unit_cylinder();
        let mut area = 0.0f64;
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0;
            assert!(
                n.dot(Vec3::new(centre.x, centre.y, 0.0)) > 0.0,
                "inward face"
            );
            area += 0.5 * n.length() as f64;
        }
        let exact = std::f64::consts::TAU;
        assert!((area - exact).abs() < 1e-5 * exact, "{area}");
        let ns = m.normals.as_ref().unwrap();
        for (p, n) in m.positions.iter().zip(ns) {
            let radial = Vec3::new(p.x, p.y, 0.0).normalize();
            assert!((radial - *n).length() < 1e-6);
        }
    }

    #[test]
    fn transform_maps_the_axis_and_radius() {
        let (p0, p1) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 5.0, 3.0));
        let m = cylinder_transform(Mat4::IDENTITY, p0, p1, 0.5).unwrap();
        assert!((m.transform_point3(Vec3::ZERO) - p0).length() < 1e-6);
        assert!((m.transform_point3(Vec3::Z) - p1).length() < 1e-6);
        let rim = m.transform_point3(Vec3::X) - p0;
        assert!((rim.length() - 0.5).abs() < 1e-6 && rim.dot(p1 - p0).abs() < 1e-6);
        assert!(cylinder_transform(Mat4::IDENTITY, p0, p0, 1.0)
            .unwrap_err()
            .contains("distinct"));
        assert!(cylinder_transform(Mat4::IDENTITY, p0, p1, 0.0)
            .unwrap_err()
            .contains("radius"));
    }
}
