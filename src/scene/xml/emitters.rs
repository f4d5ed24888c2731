//! Mitsuba's `spot` and `envmap` emitters ([`crate::light::spot`], [`crate::light::envmap`]).

use super::document::{Document, Elem};
use super::props::{ColorSrc, Props, Result};
use crate::light::{envmap, spot};
use crate::scene::desc::LightDesc;
use crate::Color;
use glam::Mat3;

/// `spot`: `intensity` (a colour, not a texture), `cutoff_angle` (default 20°), `beam_width`
/// (default ¾ of the cutoff), an optional projected `texture`, and `to_world`. `texture`
/// converts a texture element to its index in the scene's textures.
pub(super) fn spot<'a>(
    doc: &Document,
    e: &'a Elem,
    p: &Props<'a>,
    texture: &mut dyn FnMut(&'a Elem) -> Result<u32>,
) -> Result<LightDesc> {
    let to_world = p.transform("to_world")?;
    if let Some(f) = spot::frame_fault(Mat3::from_mat4(to_world)) {
        return Err(doc.err(e, f));
    }
    let intensity = p.color("intensity", Color::ONE)?;
    let cutoff_angle = p.float("cutoff_angle", 20.0)?;
    let beam_width = p.float("beam_width", cutoff_angle * 0.75)?;
    if let Some(f) = spot::angles_fault(cutoff_angle, beam_width) {
        let at = if p.has("beam_width") && !f.starts_with("'cutoff") {
            "beam_width"
        } else {
            "cutoff_angle"
        };
        return Err(match p.elem(at) {
            Some(x) => doc.err_attr(x, "value", f),
            None => doc.err(e, f),
        });
    }
    let texture = match p.color_src("texture", Color::ONE)? {
        _ if !p.has("texture") => None,
        ColorSrc::Texture(t) => Some(texture(t)?),
        // spot.cpp: "The parameter 'texture' must be spatially varying".
        ColorSrc::Const(_) => {
            let x = p.elem("texture").unwrap_or(e);
            return Err(doc.err(
                x,
                "a spot light's 'texture' must vary (a bitmap or checkerboard <texture>); \
                 give a constant colour as 'intensity'",
            ));
        }
    };
    Ok(LightDesc::Spot {
        to_world,
        intensity,
        cutoff_angle,
        beam_width,
        texture,
    })
}

/// `envmap`: `filename` (OpenEXR, Radiance HDR or PNG, read as a bitmap texture is, PNG
/// sRGB-decoded), `scale` (default 1, not negative) and `to_world` (a rotation).
/// `mis_compensation` changes only how Mitsuba samples, not the image: accepted, unused.
pub(super) fn envmap(doc: &Document, e: &Elem, p: &Props) -> Result<LightDesc> {
    let to_world = p.transform("to_world")?;
    let scale = p.float("scale", 1.0)?;
    if scale < 0.0 {
        let x = p.elem("scale").unwrap_or(e);
        return Err(doc.err_attr(
            x,
            "value",
            format!("'scale' must not be negative, got {scale}"),
        ));
    }
    p.bool("mis_compensation", false)?;
    let name = p
        .string_opt("filename")?
        .ok_or_else(|| doc.err(e, "an envmap emitter needs a 'filename'"))?;
    let path = doc.files[e.file]
        .parent()
        .unwrap_or(std::path::Path::new("."))
        .join(name);
    if let Some(why) = crate::input::file_problem(&path) {
        return Err(doc.err(
            e,
            format!(
                "environment map '{}' {why} (looked for {})",
                crate::input::shorten(name),
                path.display()
            ),
        ));
    }
    let image = crate::texture::Bitmap::load(&path, false).map_err(|mut err| {
        err.message = format!(
            "{} (envmap at {}:{}:{})",
            err.message
                .replace("cannot read texture", "cannot read environment map"),
            doc.files[e.file].display(),
            e.pos.0,
            e.pos.1
        );
        err
    })?;
    if let Some(f) = envmap::fault(image.width, image.height, Mat3::from_mat4(to_world)) {
        return Err(doc.err(e, f));
    }
    Ok(LightDesc::Envmap {
        image: std::sync::Arc::new(image),
        scale,
        to_world,
    })
}
