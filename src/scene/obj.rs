//! Wavefront OBJ meshes: `v`, `vn` and `f` (with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners,
//! negative indices counting back from the end, polygons fanned into triangles). Other
//! statements (`vt`, `o`, `g`, `s`, `usemtl`, `mtllib`, …) are read past. Errors name the
//! file, line and column.

use super::text::Fields;
use super::SceneError;
use crate::geometry::mesh::TriangleMesh;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

pub fn load_obj(path: &Path) -> Result<TriangleMesh, SceneError> {
    let text = crate::input::read_text(path)
        .map_err(|e| SceneError::new(path, None, format!("cannot read mesh file: {e}")))?;
    parse_obj(path, &text)
}

pub fn parse_obj(path: &Path, text: &str) -> Result<TriangleMesh, SceneError> {
    let mut pos: Vec<Vec3> = Vec::new();
    let mut nrm: Vec<Vec3> = Vec::new();
    let mut tex: Vec<glam::Vec2> = Vec::new();
    // Output vertices are (position, normal) pairs; faces without normals use (p, None).
    let mut remap: HashMap<(u32, Option<u32>, Option<u32>), u32> = HashMap::new();
    let mut out_pos = Vec::new();
    let mut out_nrm: Vec<Option<Vec3>> = Vec::new();
    let mut out_tex: Vec<Option<glam::Vec2>> = Vec::new();
    let mut indices = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let line_no = ln + 1;
        let content = line.split('#').next().unwrap_or("");
        let mut fields = Fields::new(content);
        let Some((_, kw)) = fields.next() else {
            continue;
        };
        let err = |col: usize, msg: String| SceneError::new(path, Some((line_no, col)), msg);
        match kw {
            "v" | "vn" => {
                let mut c = [0.0f32; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    let (col, tok) = fields.next().ok_or_else(|| {
                        err(line.len() + 1, format!("'{kw}' needs 3 numbers, found {k}"))
                    })?;
                    *slot = tok
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            err(col, format!("expected a finite number, found '{tok}'"))
                        })?;
                }
                if kw == "v" {
                    pos.push(Vec3::from(c));
                } else {
                    nrm.push(Vec3::from(c));
                }
            }
            "vt" => {
                let mut c = [0.0f32; 2];
                for (k, slot) in c.iter_mut().enumerate() {
                    let (col, tok) = fields.next().ok_or_else(|| {
                        err(line.len() + 1, format!("'vt' needs 2 numbers, found {k}"))
                    })?;
                    *slot = tok
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            err(col, format!("expected a finite number, found '{tok}'"))
                        })?;
                }
                tex.push(glam::Vec2::from(c));
            }
            "f" => {
                let mut corners = Vec::with_capacity(4);
                for (col, tok) in fields.by_ref() {
                    let mut parts = tok.split('/');
                    let resolve = |s: Option<&str>,
                                   n: usize,
                                   what: &str|
                     -> Result<Option<u32>, SceneError> {
                        let Some(s) = s.filter(|s| !s.is_empty()) else {
                            return Ok(None);
                        };
                        let i: i64 = s.parse().map_err(|_| {
                            err(col, format!("expected a {what} index, found '{s}'"))
                        })?;
                        let idx = if i > 0 { i - 1 } else { n as i64 + i };
                        if i == 0 || idx < 0 || idx >= n as i64 {
                            return Err(err(
                                col,
                                format!("{what} index {i} out of range (the file has {n} so far)"),
                            ));
                        }
                        Ok(Some(idx as u32))
                    };
                    let vi = resolve(parts.next(), pos.len(), "vertex")?
                        .ok_or_else(|| err(col, "a face corner needs a vertex index".into()))?;
                    let ti = resolve(parts.next(), tex.len(), "texture coordinate")?;
                    let ni = resolve(parts.next(), nrm.len(), "normal")?;
                    let key = (vi, ti, ni);
                    let next = out_pos.len() as u32;
                    let id = *remap.entry(key).or_insert_with(|| {
                        out_pos.push(pos[vi as usize]);
                        out_nrm.push(ni.map(|n| nrm[n as usize]));
                        out_tex.push(ti.map(|t| tex[t as usize]));
                        next
                    });
                    corners.push(id);
                }
                if corners.len() < 3 {
                    return Err(err(
                        1,
                        format!("a face needs at least 3 corners, found {}", corners.len()),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    indices.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    let normals = if !out_nrm.is_empty() && out_nrm.iter().all(|n| n.is_some()) {
        Some(
            out_nrm
                .into_iter()
                .map(|n| n.unwrap().normalize_or_zero())
                .collect(),
        )
    } else {
        None
    };
    // As in the file: v up (importers flip it where their convention asks).
    let uvs = if !out_tex.is_empty() && out_tex.iter().all(|t| t.is_some()) {
        Some(out_tex.into_iter().map(|t| t.unwrap()).collect())
    } else {
        None
    };
    Ok(TriangleMesh {
        tangents: None,
        positions: out_pos,
        normals,
        uvs,
        indices,
    })
}
