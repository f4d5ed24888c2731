//! Instancing in the TOML format: `group = "NAME"` on a `[[shape]]` puts the shape in the
//! shape group NAME (stored once, not rendered by itself), and each `[[instance]]` places a
//! group by a transform (docs/scene-format.md, "Instancing").

use super::{list_or_none, span_of, Ctx, V3};
use crate::scene::desc::{GroupDesc, InstanceDesc, ShapeDesc};
use crate::scene::SceneError;
use glam::{Affine3A, Mat3, Quat, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// A scale: one number (uniform) or three.
#[derive(Deserialize)]
#[serde(
    untagged,
    expecting = "expected a number or an array of three numbers [x, y, z]"
)]
pub(super) enum ScaleT {
    Uniform(f32),
    Axes(V3),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct InstanceT {
    group: Spanned<String>,
    scale: Option<Spanned<ScaleT>>,
    rotate: Option<Spanned<[f32; 4]>>,
    translate: Option<Spanned<V3>>,
    matrix: Option<Spanned<Vec<[f32; 4]>>>,
}

/// Adds `shape` to the scene's `shapes`, or to the group of `groups` that `group` names
/// (refusing an emitting one).
pub(super) fn add_shape(
    cx: &Ctx,
    shapes: &mut Vec<ShapeDesc>,
    groups: &mut Vec<GroupDesc>,
    group: Option<&Spanned<String>>,
    shape: ShapeDesc,
) -> Result<(), SceneError> {
    let Some(g) = group else {
        shapes.push(shape);
        return Ok(());
    };
    if shape.emission.is_some() {
        return cx.err(
            g.span(),
            "instancing of emitters is not supported (a shape in a group has 'emission')",
        );
    }
    let name = g.get_ref();
    match groups.iter_mut().find(|d| &d.name == name) {
        Some(d) => d.shapes.push(shape),
        None => groups.push(GroupDesc {
            name: name.clone(),
            shapes: vec![shape],
        }),
    }
    Ok(())
}

/// The instances of the `[[instance]]` tables, of `groups`.
pub(super) fn instances(
    cx: &Ctx,
    groups: &[GroupDesc],
    tables: &[Spanned<InstanceT>],
) -> Result<Vec<InstanceDesc>, SceneError> {
    let ids: std::collections::HashMap<&str, u32> = groups
        .iter()
        .enumerate()
        .map(|(k, g)| (g.name.as_str(), k as u32))
        .collect();
    let mut placed = Vec::with_capacity(tables.len());
    for t in tables {
        let i = t.get_ref();
        let Some(&group) = ids.get(i.group.get_ref().as_str()) else {
            let mut names: Vec<&str> = ids.keys().copied().collect();
            names.sort_unstable();
            return cx.err(
                i.group.span(),
                format!(
                    "no shape has group = '{}' (groups: {})",
                    crate::input::shorten(i.group.get_ref()),
                    list_or_none(&names)
                ),
            );
        };
        if let Err(why) = crate::scene::instance::check_count(placed.len() + 1) {
            return cx.err(t.span(), why);
        }
        let to_world = to_world(cx, t)?;
        placed.push(InstanceDesc { group, to_world });
    }
    Ok(placed)
}

/// The instance's transform: `matrix` (three or four rows of four numbers, the last row
/// 0 0 0 1), or `scale`, then `rotate` ([x, y, z, degrees] about the axis), then
/// `translate`.
fn to_world(cx: &Ctx, t: &Spanned<InstanceT>) -> Result<Affine3A, SceneError> {
    let i = t.get_ref();
    let m = if let Some(rows) = &i.matrix {
        if let Some(other) = [span_of(&i.scale), span_of(&i.rotate), span_of(&i.translate)]
            .into_iter()
            .flatten()
            .next()
        {
            return cx.err(
                other,
                "an instance takes either 'matrix' or 'scale', 'rotate' and 'translate'",
            );
        }
        let r = rows.get_ref();
        let affine_row = [0.0, 0.0, 0.0, 1.0];
        if !(r.len() == 3 || (r.len() == 4 && r[3] == affine_row)) {
            return cx.err(
                rows.span(),
                "'matrix' must be three rows of four numbers (or four, the last 0 0 0 1)",
            );
        }
        let col = |c: usize| Vec3::new(r[0][c], r[1][c], r[2][c]);
        Affine3A::from_mat3_translation(Mat3::from_cols(col(0), col(1), col(2)), col(3))
    } else {
        let scale = match i.scale.as_ref().map(|s| s.get_ref()) {
            None => Vec3::ONE,
            Some(ScaleT::Uniform(s)) => Vec3::splat(*s),
            Some(ScaleT::Axes(v)) => Vec3::from(*v),
        };
        let rotation = match &i.rotate {
            None => Quat::IDENTITY,
            Some(r) => {
                let [x, y, z, deg] = *r.get_ref();
                match Vec3::new(x, y, z).try_normalize() {
                    Some(axis) if deg.is_finite() => Quat::from_axis_angle(axis, deg.to_radians()),
                    _ => {
                        return cx.err(
                            r.span(),
                            "'rotate' must be [x, y, z, degrees] with a finite, non-zero axis",
                        )
                    }
                }
            }
        };
        let translate = match &i.translate {
            None => Vec3::ZERO,
            Some(v) => cx.finite3(v, "translate")?,
        };
        Affine3A::from_translation(translate)
            * Affine3A::from_quat(rotation)
            * Affine3A::from_scale(scale)
    };
    match crate::scene::instance::singular(&m) {
        Some(why) => cx.err(t.span(), format!("the instance's transform {why}")),
        None => Ok(m),
    }
}
