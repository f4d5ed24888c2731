//! The node hierarchy (glTF 2.0 §3.5): each node's local transform, either a column-major
//! `matrix` or translation T, rotation R (a unit quaternion x, y, z, w) and scale S composed
//! as `T·R·S`; a node's world transform is its parent's times its own.

use super::Loader;
use crate::scene::SceneError;
use glam::{Mat4, Quat, Vec3};

/// A node of the scene with its world transform.
pub struct Placed<'a> {
    pub node: ::gltf::Node<'a>,
    pub world: Mat4,
}

/// The local transform of a node.
pub fn local_matrix(t: ::gltf::scene::Transform) -> Result<Mat4, String> {
    match t {
        ::gltf::scene::Transform::Matrix { matrix } => {
            let m = Mat4::from_cols_array_2d(&matrix);
            if !m.is_finite() {
                return Err("its matrix has a value that is not finite".into());
            }
            Ok(m)
        }
        ::gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let (t, s) = (Vec3::from(translation), Vec3::from(scale));
            let q = Quat::from_array(rotation);
            if !(t.is_finite() && s.is_finite() && q.is_finite()) {
                return Err(
                    "its translation, rotation or scale has a value that is not finite".into(),
                );
            }
            // Exporters write quaternions rounded to a few digits: renormalize.
            let len = q.length();
            if !(len > 1e-6) {
                return Err(format!(
                    "its rotation {rotation:?} is not a unit quaternion (length {len})"
                ));
            }
            Ok(Mat4::from_scale_rotation_translation(s, q / len, t))
        }
    }
}

/// The nodes of `scene`, parents before children, with their world transforms. A node
/// reached twice (a cycle, or two parents) is refused, as the specification requires
/// ("the node hierarchy must be a set of disjoint strict trees").
pub fn flatten<'a>(
    l: &Loader<'a>,
    scene: &::gltf::Scene<'a>,
) -> Result<Vec<Placed<'a>>, SceneError> {
    let mut seen = vec![false; l.doc.nodes().len()];
    let mut out = Vec::new();
    let mut stack: Vec<(::gltf::Node<'a>, Mat4)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let i = node.index();
        if std::mem::replace(&mut seen[i], true) {
            return Err(l.err(format!(
                "nodes[{i}] is reached twice from scenes[{}]: the node hierarchy has a cycle \
                 or a node with two parents",
                scene.index()
            )));
        }
        let local =
            local_matrix(node.transform()).map_err(|e| l.err(format!("nodes[{i}]: {e}")))?;
        let world = parent * local;
        let mut kids: Vec<_> = node.children().map(|c| (c, world)).collect();
        kids.reverse();
        stack.extend(kids);
        out.push(Placed { node, world });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ::gltf::scene::Transform;

    /// T·R·S: a point is scaled, then rotated, then translated.
    #[test]
    fn trs_order() {
        // 90° about +y: x ↦ −z.
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let m = local_matrix(Transform::Decomposed {
            translation: [1.0, 2.0, 3.0],
            rotation: [0.0, h, 0.0, h],
            scale: [2.0, 1.0, 1.0],
        })
        .unwrap();
        let p = m.transform_point3(Vec3::X);
        assert!((p - Vec3::new(1.0, 2.0, 1.0)).length() < 1e-6, "{p}");
    }

    /// `matrix` is column-major: its 13th to 15th numbers are the translation.
    #[test]
    fn matrix_is_column_major() {
        let mut a = [[0.0f32; 4]; 4];
        a[0][0] = 1.0;
        a[1][1] = 1.0;
        a[2][2] = 1.0;
        a[3] = [5.0, 6.0, 7.0, 1.0];
        let m = local_matrix(Transform::Matrix { matrix: a }).unwrap();
        assert_eq!(m.transform_point3(Vec3::ZERO), Vec3::new(5.0, 6.0, 7.0));
    }

    #[test]
    fn rotation_is_renormalized_and_zero_refused() {
        let m = local_matrix(Transform::Decomposed {
            translation: [0.0; 3],
            rotation: [0.0, 0.0, 0.0, 2.0],
            scale: [1.0; 3],
        })
        .unwrap();
        assert!(m.abs_diff_eq(Mat4::IDENTITY, 1e-6));
        assert!(local_matrix(Transform::Decomposed {
            translation: [0.0; 3],
            rotation: [0.0; 4],
            scale: [1.0; 3],
        })
        .is_err());
    }
}
