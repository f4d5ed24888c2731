//! Mitsuba 3 XML scenes (<https://mitsuba.readthedocs.io/en/stable/src/key_topics/scene_format.html>).
//!
//! Two stages. [`document`] reads the files: it parses the XML, expands `<include>`, collects
//! `<default>` values (overridden by `-D name=value`) and substitutes `$name` in attributes,
//! giving a tree of [`Elem`]s that remember their file, line and column. [`objects`] then
//! turns that tree into a [`SceneDesc`], keeping Mitsuba's meaning: one-sided BSDFs unless
//! `twosided`, front-only area emitters, `max_depth` counting path segments. Every property an
//! object does not use is an error (as in Mitsuba), so typos do not pass silently.

mod document;
mod emitters;
mod objects;
mod params;
mod props;
mod sensor;
mod transform;

use super::{SceneDesc, SceneError};
use std::path::Path;

pub use document::Elem;
pub use transform::lookat;

/// How to read an XML scene.
#[derive(Clone, Debug, Default)]
pub struct XmlOptions {
    /// `-D name=value`: values for `<default>` parameters, and for `$name` without one.
    pub defines: Vec<(String, String)>,
    /// Render what can be rendered: unknown BSDFs become grey diffuse, unknown textures
    /// their mean grey, and each replacement is listed in the scene's warnings.
    pub lenient: bool,
}

/// Loads a Mitsuba 3 XML scene.
pub fn load_xml(path: &Path, opts: &XmlOptions) -> Result<SceneDesc, SceneError> {
    let doc = document::Document::load(path, &opts.defines)?;
    objects::build(&doc, opts.lenient)
}

/// Reads a Mitsuba 3 XML scene from text (`path` names it in errors and anchors relative
/// file names).
pub fn parse_xml(path: &Path, text: &str, opts: &XmlOptions) -> Result<SceneDesc, SceneError> {
    let doc = document::Document::parse(path, text, &opts.defines)?;
    objects::build(&doc, opts.lenient)
}
