//! Indexed triangle meshes, as loaded from files or written inline in a scene.

use glam::Vec3;

#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, if the file gave them (same length as `positions`).
    pub normals: Option<Vec<Vec3>>,
    pub indices: Vec<[u32; 3]>,
}

impl TriangleMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// Applies an affine map to positions and the matching normal map to normals.
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
        // A transform with negative determinant turns the mesh inside out; keep the normals
        // facing the way the file meant by reversing the winding.
        if m.determinant() < 0.0 {
            for t in &mut self.indices {
                t.swap(1, 2);
            }
        }
    }
}
