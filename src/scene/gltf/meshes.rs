//! Meshes (glTF 2.0 §3.7.2): each primitive becomes a triangle mesh in world space, with its
//! vertex normals (NORMAL), texture coordinates (TEXCOORD_0) and tangents (TANGENT, for a
//! normal map's tangent frame) where it has them; a primitive without normals is
//! flat-shaded, as the specification asks.
//!
//! A mesh that several nodes use becomes one shape group (its primitives, with their
//! materials, in the mesh's space; see [`crate::scene::instance`]) and one instance per node,
//! placed by the node's world matrix. It is copied into world space instead where a group
//! cannot hold it or place it as the file means: a mesh used once; an emissive mesh (groups
//! may not emit); a node whose world matrix is singular, or mirrors (its determinant is
//! negative: glTF reverses the winding there, §3.7.2.1, and the normal map's tangent frame
//! follows the world-space winding, which the copy reproduces).

use super::nodes::Placed;
use super::Loader;
use crate::geometry::mesh::TriangleMesh;
use crate::scene::desc::{GeometryDesc, GroupDesc, InstanceDesc, ShapeDesc, MAX_PRIMITIVES};
use crate::scene::SceneError;
use ::gltf::mesh::{Mode, Semantic};
use glam::{Affine3A, Mat4, Vec2, Vec3, Vec4};

/// Whether a node with this world matrix may place an instance (see the module's comment).
fn can_place(world: &Mat4) -> bool {
    let a = Affine3A::from_mat4(*world);
    crate::scene::instance::singular(&a).is_none() && a.matrix3.determinant() > 0.0
}

/// Counts, for each mesh, the nodes that use it and can place an instance of it.
pub fn count_uses(l: &mut Loader, placed: &[Placed]) {
    for p in placed {
        if let Some(mesh) = p.node.mesh() {
            if can_place(&p.world) {
                *l.mesh_uses.entry(mesh.index()).or_default() += 1;
            }
        }
    }
}

/// Adds a node's mesh: an instance of its group if several nodes use it, else a copy.
pub fn place_mesh(l: &mut Loader, mesh: &::gltf::Mesh, world: &Mat4) -> Result<(), SceneError> {
    let reused = l.mesh_uses.get(&mesh.index()).is_some_and(|&n| n > 1);
    if reused && can_place(world) {
        if let Some(group) = group(l, mesh)? {
            l.desc.instances.push(InstanceDesc {
                group,
                to_world: Affine3A::from_mat4(*world),
            });
            return Ok(());
        }
    }
    add_mesh(l, mesh, world)
}

/// The mesh's shape group, read on first use; None if a primitive emits (or none is a
/// surface): such a mesh is copied.
fn group(l: &mut Loader, mesh: &::gltf::Mesh) -> Result<Option<u32>, SceneError> {
    if let Some(&g) = l.mesh_groups.get(&mesh.index()) {
        return Ok(g);
    }
    let mut emits = false;
    for prim in mesh.primitives() {
        emits |= l.material(&prim.material())?.1.is_some();
    }
    let mut shapes = Vec::new();
    for prim in mesh.primitives().filter(|_| !emits) {
        let material = l.material(&prim.material())?.0;
        let what = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let Some(tm) = read_primitive(l, &prim, &what)? else {
            continue;
        };
        count(l, &tm, &what)?;
        shapes.push(ShapeDesc {
            geometry: GeometryDesc::Mesh(tm),
            material,
            emission: None,
        });
    }
    let g = if shapes.is_empty() {
        None
    } else {
        let name = match mesh.name() {
            Some(n) => format!("meshes[{}] ('{}')", mesh.index(), crate::input::shorten(n)),
            None => format!("meshes[{}]", mesh.index()),
        };
        l.desc.groups.push(GroupDesc { name, shapes });
        Some(l.desc.groups.len() as u32 - 1)
    };
    l.mesh_groups.insert(mesh.index(), g);
    Ok(g)
}

/// Counts a primitive's triangles and vertices, refusing more than the scene can hold.
fn count(l: &mut Loader, tm: &TriangleMesh, what: &str) -> Result<(), SceneError> {
    l.triangles += tm.indices.len();
    l.vertices += tm.positions.len();
    if l.triangles > MAX_PRIMITIVES {
        return Err(l.err(format!(
            "{what}: the scene's meshes, one copy per node that uses them (one per shape \
             group for instanced ones), have more than {MAX_PRIMITIVES} triangles"
        )));
    }
    Ok(())
}

/// Adds a copy of the mesh's primitives placed in world space by `world`.
fn add_mesh(l: &mut Loader, mesh: &::gltf::Mesh, world: &Mat4) -> Result<(), SceneError> {
    for prim in mesh.primitives() {
        let what = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let Some(mut tm) = read_primitive(l, &prim, &what)? else {
            continue;
        };
        count(l, &tm, &what)?;
        tm.transform(world);
        if tm.positions.iter().any(|p| !p.is_finite()) {
            return Err(l.err(format!(
                "{what}: a vertex is not finite once placed by its node's transform"
            )));
        }
        let (material, emission) = l.material(&prim.material())?;
        let emission = match emission {
            Some(e) if area(&tm) > 0.0 => {
                if let Some(t) = e.texture {
                    l.desc.emission_textures.push((l.desc.shapes.len(), t));
                }
                Some(e.radiance)
            }
            Some(_) => {
                l.note(format!(
                    "{what}: emissive but of zero area: it emits nothing"
                ));
                None
            }
            None => None,
        };
        l.desc.shapes.push(ShapeDesc {
            geometry: GeometryDesc::Mesh(tm),
            material,
            emission,
        });
    }
    Ok(())
}

fn area(m: &TriangleMesh) -> f32 {
    m.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// The primitive's triangles in its mesh's space; None (with a note) for points and lines.
fn read_primitive(
    l: &mut Loader,
    prim: &::gltf::Primitive,
    what: &str,
) -> Result<Option<TriangleMesh>, SceneError> {
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        l.note(format!(
            "{what}: mode {mode:?} (points or lines) has no surface: skipped"
        ));
        return Ok(None);
    }
    let pos = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| l.err(format!("{what} has no POSITION attribute")))?;
    let positions: Vec<Vec3> = l
        .read_floats(&pos, "POSITION", 3)?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    let n = positions.len();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(l.err(format!("{what}: POSITION {i} is not finite")));
    }
    let count_check = |l: &Loader, name: &str, len: usize| {
        if len != n {
            Err(l.err(format!(
                "{what}: {name} has {len} elements but POSITION has {n}"
            )))
        } else {
            Ok(())
        }
    };
    let normals = match prim.get(&Semantic::Normals) {
        Some(a) => {
            let v: Vec<Vec3> = l
                .read_floats(&a, "NORMAL", 3)?
                .chunks_exact(3)
                .map(|c| {
                    let v = Vec3::from_slice(c);
                    if v.is_finite() {
                        v.normalize_or_zero()
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect();
            count_check(l, "NORMAL", v.len())?;
            Some(v)
        }
        None => None,
    };
    let uvs = match prim.get(&Semantic::TexCoords(0)) {
        Some(a) => {
            let v: Vec<Vec2> = l
                .read_floats(&a, "TEXCOORD_0", 2)?
                .chunks_exact(2)
                .map(|c| {
                    let t = Vec2::from_slice(c);
                    if t.is_finite() {
                        t
                    } else {
                        Vec2::ZERO
                    }
                })
                .collect();
            count_check(l, "TEXCOORD_0", v.len())?;
            Some(v)
        }
        None => None,
    };
    // glTF 2.0 §3.7.2.1: TANGENT is VEC4 float, xyz a unit tangent, w = ±1 the bitangent's
    // sign. Only the sign of w is kept (a non-finite or zero tangent is dropped to zero,
    // where the uv-derived dp/du stands in at a hit).
    let tangents = match prim.get(&Semantic::Tangents) {
        Some(a) => {
            let v: Vec<Vec4> = l
                .read_floats(&a, "TANGENT", 4)?
                .chunks_exact(4)
                .map(|c| {
                    let t = Vec4::from_slice(c);
                    let d = t.truncate();
                    if t.is_finite() && d != Vec3::ZERO {
                        d.normalize_or_zero()
                            .extend(if t.w < 0.0 { -1.0 } else { 1.0 })
                    } else {
                        Vec4::ZERO
                    }
                })
                .collect();
            count_check(l, "TANGENT", v.len())?;
            Some(v)
        }
        None => None,
    };
    let list: Vec<u32> = match prim.indices() {
        Some(a) => {
            let idx = l.read_indices(&a, "indices")?;
            if let Some(k) = idx.iter().position(|&i| i as usize >= n) {
                return Err(l.err(format!(
                    "{what}: index {} at position {k} is out of range (the primitive has {n} \
                     vertices)",
                    idx[k]
                )));
            }
            idx
        }
        None => (0..n as u32).collect(),
    };
    Ok(Some(TriangleMesh {
        positions,
        normals,
        uvs,
        tangents,
        indices: triangles(mode, &list),
    }))
}

/// Triangles of a list, strip or fan of vertex indices (glTF 2.0 §3.7.2.1).
pub fn triangles(mode: Mode, v: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..v.len().saturating_sub(2))
            .map(|i| {
                let o = i % 2;
                [v[i], v[i + 1 + o], v[i + 2 - o]]
            })
            .collect(),
        Mode::TriangleFan => (1..v.len().saturating_sub(1))
            .map(|i| [v[i], v[i + 1], v[0]])
            .collect(),
        _ => v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Strips alternate their winding so every triangle faces the same way; fans turn
    /// about the first vertex.
    #[test]
    fn strips_and_fans() {
        let v = [0, 1, 2, 3, 4];
        assert_eq!(
            triangles(Mode::TriangleStrip, &v),
            vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]
        );
        assert_eq!(
            triangles(Mode::TriangleFan, &v),
            vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]
        );
        assert_eq!(triangles(Mode::Triangles, &v), vec![[0, 1, 2]]);
        assert!(triangles(Mode::TriangleStrip, &[0, 1]).is_empty());
    }
}
