//! `<transform>`: translate, rotate, scale, matrix and lookat, composed in Mitsuba's order
//! (each operation is applied after the ones above it: M = Mₙ ⋯ M₂ M₁).

use super::document::{Document, Elem};
use super::props::{numbers, xyz, Result};
use glam::{Mat4, Vec3, Vec4};

pub fn parse_transform(doc: &Document, e: &Elem) -> Result<Mat4> {
    let mut m = Mat4::IDENTITY;
    for op in &e.children {
        let t = match op.tag.as_str() {
            "translate" => Mat4::from_translation(xyz(doc, op, 0.0)?),
            "scale" => {
                // `value` is uniform (one number) or per axis (three).
                let s = match op.attr("value").map(numbers) {
                    Some(Some(v)) if v.len() == 1 && v[0].is_finite() => Vec3::splat(v[0]),
                    Some(_) => xyz(doc, op, 1.0)?,
                    None => xyz(doc, op, 1.0)?,
                };
                Mat4::from_scale(s)
            }
            "rotate" => {
                let axis = xyz(doc, op, 0.0)?;
                let angle = op
                    .attr("angle")
                    .and_then(|a| a.trim().parse::<f32>().ok())
                    .filter(|a| a.is_finite())
                    .ok_or_else(|| {
                        doc.err(op, "<rotate> needs an angle in degrees, e.g. angle=\"90\"")
                    })?;
                if axis.length_squared() == 0.0 {
                    return Err(doc.err(op, "<rotate> needs a non-zero axis (x, y, z)"));
                }
                Mat4::from_axis_angle(axis.normalize(), angle.to_radians())
            }
            "matrix" => {
                let v = op.attr("value").unwrap_or("");
                if let Some(f) = super::props::numbers_fault(v) {
                    return Err(doc.err_attr(op, "value", f));
                }
                match numbers(v) {
                    Some(n) if n.len() == 16 && n.iter().all(|x| x.is_finite()) => {
                        // Row-major in the file.
                        Mat4::from_cols_array(&[
                            n[0], n[4], n[8], n[12], n[1], n[5], n[9], n[13], n[2], n[6], n[10],
                            n[14], n[3], n[7], n[11], n[15],
                        ])
                    }
                    Some(n) if n.len() == 9 && n.iter().all(|x| x.is_finite()) => Mat4::from_cols(
                        Vec4::new(n[0], n[3], n[6], 0.0),
                        Vec4::new(n[1], n[4], n[7], 0.0),
                        Vec4::new(n[2], n[5], n[8], 0.0),
                        Vec4::W,
                    ),
                    Some(n) if n.len() == 16 || n.len() == 9 => {
                        let k = n.iter().position(|x| !x.is_finite()).unwrap_or(0);
                        return Err(doc.err_attr(
                            op,
                            "value",
                            format!(
                                "<matrix> values must be finite numbers; number {} is {}",
                                k + 1,
                                n[k]
                            ),
                        ));
                    }
                    _ => {
                        return Err(doc.err_attr(
                            op,
                            "value",
                            "<matrix> needs 16 numbers (a 4×4 matrix, row by row) or 9 (3×3)",
                        ))
                    }
                }
            }
            "lookat" => {
                let get = |a: &str| -> Result<Vec3> {
                    let v = op.attr(a).ok_or_else(|| {
                        doc.err(
                            op,
                            format!("<lookat> needs origin, target and up; '{a}' is missing"),
                        )
                    })?;
                    if let Some(f) = super::props::numbers_fault(v) {
                        return Err(doc.err_attr(op, a, format!("'{a}': {f}")));
                    }
                    match numbers(v).as_deref() {
                        Some([x, y, z]) => Ok(Vec3::new(*x, *y, *z)),
                        _ => Err(doc.err_attr(
                            op,
                            a,
                            format!(
                                "'{a}': expected 'x, y, z', found '{}'",
                                crate::input::shorten(v)
                            ),
                        )),
                    }
                };
                let origin = get("origin")?;
                let target = get("target")?;
                let up = if op.attr("up").is_some() {
                    get("up")?
                } else {
                    Vec3::Y
                };
                lookat(origin, target, up).ok_or_else(|| {
                    doc.err(
                        op,
                        "<lookat>: origin equals target, or up is parallel to the view",
                    )
                })?
            }
            tag => {
                return Err(doc.err(
                    op,
                    format!(
                        "unknown transform <{tag}>; expected translate, rotate, scale, matrix or \
                         lookat"
                    ),
                ))
            }
        };
        m = t * m;
    }
    Ok(m)
}

/// Mitsuba's look-at matrix: columns (left, up, dir, origin), a camera looking along +z.
pub fn lookat(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).try_normalize()?;
    let left = up.normalize_or_zero().cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}
