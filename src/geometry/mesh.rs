//! Indexed triangle meshes, as loaded from files or written inline in a scene.

use glam::Vec3;

#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, if the file gave them (same length as `positions`).
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the file gave them.
    pub uvs: Option<Vec<glam::Vec2>>,
    /// Per-vertex tangents (glTF's TANGENT: xyz the unit tangent, w = ±1 the sign of the
    /// bitangent n × t), where a normal map's tangent frame follows them instead of the
    /// texture coordinates' dp/du.
    pub tangents: Option<Vec<glam::Vec4>>,
    pub indices: Vec<[u32; 3]>,
}

/// Segments of the polygon that stands for a disk (its radius is enlarged so that the area,
/// and so an emitter's power, is exact).
pub const DISK_SEGMENTS: u32 = 256;

/// How far (per component, between unit vectors) a vertex normal may lie from its face's
/// normal and still count as that normal ([`TriangleMesh::drop_flat_normals`]): normals
/// written with six decimals are within 5e-7, and a deliberately smooth mesh would need faces
/// under 1e-5 radians wide (billions of triangles on a sphere) to pass for flat.
pub const FLAT_NORMAL_TOLERANCE: f32 = 1e-5;

impl TriangleMesh {
    /// Mitsuba's `disk`: the unit disk in the xy plane, facing +z, as a regular polygon of
    /// [`DISK_SEGMENTS`] sides and the same area (π), a fan around the centre, with planar
    /// texture coordinates (x, y) ↦ ((x + 1)/2, (y + 1)/2).
    pub fn unit_disk() -> TriangleMesh {
        let n = DISK_SEGMENTS;
        let step = std::f32::consts::TAU / n as f32;
        // Area of the regular n-gon of circumradius R: (n/2)·R²·sin(2π/n) = π.
        let r = (std::f32::consts::TAU / (n as f32 * step.sin())).sqrt();
        let mut positions = vec![Vec3::ZERO];
        for i in 0..n {
            let a = i as f32 * step;
            positions.push(Vec3::new(r * a.cos(), r * a.sin(), 0.0));
        }
        let uvs = positions
            .iter()
            .map(|p| glam::Vec2::new(0.5 * p.x + 0.5, 0.5 * p.y + 0.5))
            .collect();
        TriangleMesh {
            positions,
            normals: None,
            uvs: Some(uvs),
            tangents: None,
            indices: (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect(),
        }
    }

    /// v ↦ 1 − v: OBJ files put v = 0 at the bottom of an image, Mitsuba's textures at the
    /// top (Mitsuba's `flip_tex_coords`, on by default). Tangents keep following u; their
    /// bitangent sign follows v.
    pub fn flip_v(&mut self) {
        if let Some(uvs) = &mut self.uvs {
            for t in uvs {
                t.y = 1.0 - t.y;
            }
        }
        if let Some(ts) = &mut self.tangents {
            for t in ts {
                t.w = -t.w;
            }
        }
    }

    /// Smooth vertex normals: each face's normal weighted by its angle at the vertex
    /// (Thürmer and Wüthrich 1998), as Mitsuba 3 computes them for meshes without normals.
    pub fn recompute_vertex_normals(&mut self) {
        let mut ns = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.indices {
            let v = t.map(|i| self.positions[i as usize]);
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            for i in 0..3 {
                let d0 = (v[(i + 1) % 3] - v[i]).normalize_or_zero();
                let d1 = (v[(i + 2) % 3] - v[i]).normalize_or_zero();
                let angle = d0.dot(d1).clamp(-1.0, 1.0).acos();
                ns[t[i] as usize] += n * angle;
            }
        }
        for n in &mut ns {
            *n = n.normalize_or_zero();
        }
        self.normals = Some(ns);
    }

    /// Drops the vertex normals where they are the faces' own: each triangle's three within
    /// [`FLAT_NORMAL_TOLERANCE`] of its unit geometric normal (on either side). Interpolated,
    /// such normals give that normal again up to rounding, so the shading stays the same,
    /// while a hit no longer looks up and interpolates three normals, and the mesh counts as
    /// flat wherever a renderer path takes only meshes without normals. Flat-shaded meshes
    /// are common: Blender exports a flat-shaded object's split vertices with its face
    /// normals, and Mitsuba's (and so mcrt's) OBJ loader computes vertex normals for a file
    /// without them, which for a mesh that shares no vertices are the faces' normals.
    /// Returns whether it dropped them.
    pub fn drop_flat_normals(&mut self) -> bool {
        use rayon::prelude::*;
        let Some(ns) = &self.normals else {
            return false;
        };
        let pos = &self.positions;
        let flat = self.indices.par_iter().with_min_len(1 << 12).all(|t| {
            let [a, b, c] = t.map(|i| pos[i as usize]);
            let ng = (b - a).cross(c - a).normalize_or_zero();
            // A degenerate triangle is never hit (the scene drops it).
            ng == Vec3::ZERO
                || t.iter().all(|&i| {
                    let n = ns[i as usize].normalize_or_zero();
                    let d = if n.dot(ng) < 0.0 { n + ng } else { n - ng };
                    d.abs().max_element() <= FLAT_NORMAL_TOLERANCE
                })
        });
        if flat {
            self.normals = None;
        }
        flat
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// Applies an affine map to positions, the matching normal map to normals, and its
    /// linear part to tangents (directions in the surface); a mirroring map (negative
    /// determinant) flips the tangents' bitangent sign, since n × t then turns the other way
    /// relative to the mapped bitangent.
    pub fn transform(&mut self, m: &glam::Mat4) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if let Some(ns) = &mut self.normals {
            let nm = glam::Mat3::from_mat4(*m).inverse().transpose();
            for n in ns {
                *n = (nm * *n).normalize_or_zero();
            }
        }
        if let Some(ts) = &mut self.tangents {
            let lin = glam::Mat3::from_mat4(*m);
            let sign = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
            for t in ts {
                let d = (lin * t.truncate()).normalize_or_zero();
                *t = d.extend(t.w * sign);
            }
        }
        // A transform with negative determinant turns the mesh inside out; keep the normals
        // facing the way the file meant by reversing the winding.
        if m.determinant() < 0.0 {
            for t in &mut self.indices {
                t.swap(1, 2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of a bent quad, sharing no vertex: z = 0 and x = 1 planes.
    fn bent() -> TriangleMesh {
        let p = |x, y, z| Vec3::new(x, y, z);
        TriangleMesh {
            positions: vec![
                p(0., 0., 0.),
                p(1., 0., 0.),
                p(0., 1., 0.),
                p(1., 0., 0.),
                p(1., 0., 1.),
                p(1., 1., 0.),
            ],
            indices: vec![[0, 1, 2], [3, 4, 5]],
            ..Default::default()
        }
    }

    #[test]
    fn face_normals_are_dropped_on_either_side() {
        let mut m = bent();
        m.recompute_vertex_normals();
        assert!(m.drop_flat_normals());
        assert!(m.normals.is_none());
        let mut m = bent();
        // The second face's normals point the other way, and are written to six decimals
        // of a slightly unnormalised vector.
        let n = Vec3::new(0.0, 0.0, 1.0);
        let w = Vec3::new(1.000001, 0.0, 0.0);
        m.normals = Some(vec![n, n, n, w, w, w]);
        assert!(m.drop_flat_normals());
    }

    #[test]
    fn normals_other_than_the_faces_are_kept() {
        let mut m = bent();
        let n = Vec3::new(0.0, 0.0, 1.0);
        let w = Vec3::new(-1.0, 0.0, 0.0);
        // One normal tilted by 1e-4: a smooth mesh, however slightly.
        let tilted = Vec3::new(1e-4, 0.0, 1.0).normalize();
        m.normals = Some(vec![n, n, tilted, w, w, w]);
        assert!(!m.drop_flat_normals());
        assert!(m.normals.is_some());
        // Shared vertices between the two faces: their computed normals are averages.
        let mut shared = bent();
        shared.indices = vec![[0, 1, 2], [1, 4, 5]];
        shared.recompute_vertex_normals();
        assert!(!shared.drop_flat_normals());
        // A zero normal is not its face's.
        let mut m = bent();
        m.normals = Some(vec![n, n, Vec3::ZERO, w, w, w]);
        assert!(!m.drop_flat_normals());
        let mut none = bent();
        assert!(!none.drop_flat_normals());
    }
}
