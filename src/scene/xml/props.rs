//! The properties of one Mitsuba object (`<float name=… value=…/>` and the like), read on
//! demand and checked: a property of the wrong type, or one the object never asks for, is an
//! error naming its line and column.

use super::document::{Document, Elem};
use super::transform::parse_transform;
use crate::scene::SceneError;
use crate::Color;
use glam::{Mat4, Vec3};
use std::cell::{Cell, RefCell};
use std::collections::HashMap;

pub type Result<T> = std::result::Result<T, SceneError>;

/// Parses a list of numbers separated by commas and/or white space.
pub fn numbers(s: &str) -> Option<Vec<f32>> {
    tokens(s).map(|t| t.parse::<f32>().ok()).collect()
}

/// The numbers of a list, separated by commas or blanks.
fn tokens(s: &str) -> impl Iterator<Item = &str> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
}

/// Why a number of the list `s` does not fit an f32 ([`crate::scene::text::f32_fault`]).
pub fn numbers_fault(s: &str) -> Option<String> {
    tokens(s)
        .filter_map(|t| t.parse::<f64>().ok())
        .find_map(crate::scene::text::f32_fault)
}

/// Where a colour comes from: a constant or a texture element.
#[derive(Clone, Copy, Debug)]
pub enum ColorSrc<'a> {
    Const(Color),
    Texture(&'a Elem),
}

/// Where a float comes from: a constant or a texture element.
#[derive(Clone, Copy, Debug)]
pub enum FloatSrc<'a> {
    Const(f32),
    Texture(&'a Elem),
}

/// Every element with an `id`, anywhere in the scene.
pub struct Ids<'a> {
    map: HashMap<&'a str, &'a Elem>,
}

impl<'a> Ids<'a> {
    pub fn collect(doc: &'a Document) -> Result<Ids<'a>> {
        fn walk<'a>(
            doc: &Document,
            e: &'a Elem,
            map: &mut HashMap<&'a str, &'a Elem>,
        ) -> Result<()> {
            for c in &e.children {
                if c.tag != "ref" {
                    if let Some(id) = c.attr("id") {
                        if let Some(prev) = map.insert(id, c) {
                            return Err(doc.err_attr(
                                c,
                                "id",
                                format!(
                                    "id '{id}' is already used by the <{}> at {}:{}",
                                    prev.tag, prev.pos.0, prev.pos.1
                                ),
                            ));
                        }
                    }
                }
                walk(doc, c, map)?;
            }
            Ok(())
        }
        let mut map = HashMap::new();
        walk(doc, &doc.root, &mut map)?;
        Ok(Ids { map })
    }

    pub fn resolve(&self, doc: &Document, r: &'a Elem) -> Result<&'a Elem> {
        let id = r
            .attr("id")
            .ok_or_else(|| doc.err(r, "<ref> needs an id attribute"))?;
        self.map.get(id).copied().ok_or_else(|| {
            doc.err_attr(
                r,
                "id",
                format!("no object has id '{id}' (ids are case-sensitive)"),
            )
        })
    }
}

struct Prop<'a> {
    name: &'a str,
    elem: &'a Elem,
    used: Cell<bool>,
}

/// The properties and nested objects of one object element.
pub struct Props<'a> {
    pub doc: &'a Document,
    pub owner: &'a Elem,
    props: Vec<Prop<'a>>,
    /// Nested objects without a name (`<bsdf>`, `<emitter>`, `<film>`, ... or a `<ref>` to
    /// one), resolved.
    pub objects: Vec<&'a Elem>,
    asked: RefCell<Vec<&'static str>>,
}

const PROPERTY_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "point",
    "vector",
    "transform",
    "texture",
    "ref",
];

impl<'a> Props<'a> {
    pub fn new(doc: &'a Document, ids: &Ids<'a>, owner: &'a Elem) -> Result<Props<'a>> {
        let mut props: Vec<Prop<'a>> = Vec::new();
        // Names seen, so that an object of many properties is read in linear time.
        let mut names = std::collections::HashSet::new();
        let mut objects = Vec::new();
        for c in &owner.children {
            let named = c.attr("name");
            match (c.tag.as_str(), named) {
                (tag, Some(name)) if PROPERTY_TAGS.contains(&tag) => {
                    if !names.insert(name) {
                        return Err(doc.err(c, format!("property '{name}' is given twice")));
                    }
                    props.push(Prop {
                        name,
                        elem: c,
                        used: Cell::new(false),
                    });
                }
                ("ref", None) => objects.push(ids.resolve(doc, c)?),
                (
                    "bsdf" | "emitter" | "shape" | "sensor" | "film" | "sampler" | "rfilter"
                    | "integrator" | "texture" | "medium" | "phase",
                    _,
                ) => objects.push(c),
                (tag, None) if PROPERTY_TAGS.contains(&tag) => {
                    return Err(doc.err(c, format!("<{tag}> needs a name attribute")))
                }
                (tag, _) => {
                    return Err(doc.err(
                        c,
                        format!(
                            "unknown element <{tag}> inside <{}>; expected a property ({}) or a \
                             nested object",
                            owner.tag,
                            PROPERTY_TAGS.join(", ")
                        ),
                    ))
                }
            }
        }
        // Named references to objects (a texture given by id) are kept as properties but
        // resolved here so that errors come early.
        let mut resolved = Vec::with_capacity(props.len());
        for p in props {
            if p.elem.tag == "ref" {
                let target = ids.resolve(doc, p.elem)?;
                resolved.push(Prop {
                    name: p.name,
                    elem: target,
                    used: Cell::new(false),
                });
            } else {
                resolved.push(p);
            }
        }
        Ok(Props {
            doc,
            owner,
            props: resolved,
            objects,
            asked: RefCell::new(Vec::new()),
        })
    }

    /// The object's `type` attribute.
    pub fn kind(&self) -> Result<&'a str> {
        self.owner.attr("type").ok_or_else(|| {
            self.doc.err(
                self.owner,
                format!("<{}> needs a type attribute", self.owner.tag),
            )
        })
    }

    fn find(&self, name: &'static str) -> Option<&'a Elem> {
        self.asked.borrow_mut().push(name);
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p.elem)
    }

    /// The element of property `name`, for error positions (does not mark it used).
    pub fn elem(&self, name: &str) -> Option<&'a Elem> {
        self.props.iter().find(|p| p.name == name).map(|p| p.elem)
    }

    pub fn has(&self, name: &'static str) -> bool {
        self.props.iter().any(|p| p.name == name)
    }

    fn value(&self, e: &'a Elem) -> Result<&'a str> {
        e.attr("value").ok_or_else(|| {
            self.doc
                .err(e, format!("<{}> needs a value attribute", e.tag))
        })
    }

    fn type_err(&self, e: &Elem, name: &str, want: &str) -> SceneError {
        self.doc.err(
            e,
            format!(
                "property '{name}' of <{} type=\"{}\"> must be {want}, found <{}>",
                self.owner.tag,
                self.owner.attr("type").unwrap_or("?"),
                e.tag
            ),
        )
    }

    pub fn float(&self, name: &'static str, default: f32) -> Result<f32> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    pub fn float_opt(&self, name: &'static str) -> Result<Option<f32>> {
        let Some(e) = self.find(name) else {
            return Ok(None);
        };
        if e.tag != "float" && e.tag != "integer" {
            return Err(self.type_err(e, name, "a <float>"));
        }
        let v = self.value(e)?;
        // Checked as f64, read as f32 (directly, without rounding twice).
        let wide = v.trim().parse::<f64>().ok();
        if let Some(f) = wide.and_then(crate::scene::text::f32_fault) {
            return Err(self.doc.err_attr(e, "value", format!("'{name}': {f}")));
        }
        v.trim()
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .map(Some)
            .ok_or_else(|| {
                self.doc.err_attr(
                    e,
                    "value",
                    format!(
                        "'{name}': expected a finite number, found '{}'",
                        crate::input::shorten(v)
                    ),
                )
            })
    }

    /// A float or a texture (read as a float), if given.
    pub fn float_src(&self, name: &'static str) -> Result<Option<FloatSrc<'a>>> {
        match self.elem(name) {
            Some(e) if e.tag == "texture" => {
                self.find(name);
                Ok(Some(FloatSrc::Texture(e)))
            }
            _ => Ok(self.float_opt(name)?.map(FloatSrc::Const)),
        }
    }

    pub fn int(&self, name: &'static str, default: i64) -> Result<i64> {
        let Some(e) = self.find(name) else {
            return Ok(default);
        };
        if e.tag != "integer" {
            return Err(self.type_err(e, name, "an <integer>"));
        }
        let v = self.value(e)?;
        v.trim().parse::<i64>().map_err(|_| {
            self.doc.err_attr(
                e,
                "value",
                format!("'{name}': expected an integer, found '{v}'"),
            )
        })
    }

    pub fn bool(&self, name: &'static str, default: bool) -> Result<bool> {
        let Some(e) = self.find(name) else {
            return Ok(default);
        };
        if e.tag != "boolean" {
            return Err(self.type_err(e, name, "a <boolean>"));
        }
        match self.value(e)?.trim() {
            "true" | "1" => Ok(true),
            "false" | "0" => Ok(false),
            v => Err(self.doc.err_attr(
                e,
                "value",
                format!("'{name}': expected true or false, found '{v}'"),
            )),
        }
    }

    pub fn string_opt(&self, name: &'static str) -> Result<Option<&'a str>> {
        let Some(e) = self.find(name) else {
            return Ok(None);
        };
        if e.tag != "string" {
            return Err(self.type_err(e, name, "a <string>"));
        }
        self.value(e).map(Some)
    }

    pub fn string(&self, name: &'static str, default: &'a str) -> Result<&'a str> {
        Ok(self.string_opt(name)?.unwrap_or(default))
    }

    /// A point or vector: `value="x, y, z"` or `x`, `y`, `z` attributes.
    pub fn vec3_opt(&self, name: &'static str) -> Result<Option<Vec3>> {
        let Some(e) = self.find(name) else {
            return Ok(None);
        };
        if e.tag != "point" && e.tag != "vector" {
            return Err(self.type_err(e, name, "a <point> or <vector>"));
        }
        xyz(self.doc, e, 0.0).map(Some)
    }

    /// A colour or a texture. `rgb` takes one or three numbers; `spectrum` a single value.
    pub fn color_src(&self, name: &'static str, default: Color) -> Result<ColorSrc<'a>> {
        let Some(e) = self.find(name) else {
            return Ok(ColorSrc::Const(default));
        };
        match e.tag.as_str() {
            "texture" => Ok(ColorSrc::Texture(e)),
            "float" => Ok(ColorSrc::Const(Color::splat(self.float(name, 0.0)?))),
            "rgb" | "spectrum" => {
                let v = self.value(e)?;
                if let Some(f) = numbers_fault(v) {
                    return Err(self.doc.err_attr(e, "value", format!("'{name}': {f}")));
                }
                let n = numbers(v).filter(|n| n.iter().all(|x| x.is_finite()));
                let v = crate::input::shorten(v);
                if n.as_ref().is_some_and(|n| n.iter().any(|x| *x < 0.0)) {
                    return Err(self.doc.err_attr(
                        e,
                        "value",
                        format!("'{name}': colour values must not be negative, found '{v}'"),
                    ));
                }
                match n.as_deref() {
                    Some([g]) => Ok(ColorSrc::Const(Color::splat(*g))),
                    Some([r, g, b]) if e.tag == "rgb" => {
                        Ok(ColorSrc::Const(Color::new(*r, *g, *b)))
                    }
                    _ if e.tag == "spectrum" => Err(self.doc.err_attr(
                        e,
                        "value",
                        format!(
                            "'{name}': only constant spectra (one number) are supported, found \
                             '{v}'; give the colour as <rgb name=\"{name}\" value=\"r, g, b\"/>"
                        ),
                    )),
                    _ => Err(self.doc.err_attr(
                        e,
                        "value",
                        format!("'{name}': expected one or three numbers, found '{v}'"),
                    )),
                }
            }
            _ => Err(self.type_err(e, name, "an <rgb>, <spectrum> or <texture>")),
        }
    }

    /// A constant colour (textures refused).
    pub fn color(&self, name: &'static str, default: Color) -> Result<Color> {
        match self.color_src(name, default)? {
            ColorSrc::Const(c) => Ok(c),
            ColorSrc::Texture(t) => Err(self.doc.err(
                t,
                format!("'{name}' cannot be a texture here; give an <rgb> value"),
            )),
        }
    }

    pub fn transform(&self, name: &'static str) -> Result<Mat4> {
        let Some(e) = self.find(name) else {
            return Ok(Mat4::IDENTITY);
        };
        if e.tag != "transform" {
            return Err(self.type_err(e, name, "a <transform>"));
        }
        parse_transform(self.doc, e)
    }

    /// The properties that are textures, whatever their names, marked used: for objects
    /// that take a texture by its type (Mitsuba's `bumpmap`).
    pub fn textures_any_name(&self) -> Vec<&'a Elem> {
        let ts = self.props.iter().filter(|p| p.elem.tag == "texture");
        ts.map(|p| {
            p.used.set(true);
            p.elem
        })
        .collect()
    }

    /// Marks a property as known but ignored (it has no effect in mcrt).
    pub fn ignore(&self, name: &'static str) {
        self.find(name);
    }

    /// Errors for the first property the object never asked for.
    pub fn finish(&self) -> Result<()> {
        if let Some(p) = self.props.iter().find(|p| !p.used.get()) {
            let asked = self.asked.borrow();
            let mut names: Vec<&str> = asked.clone();
            names.sort_unstable();
            names.dedup();
            let e = self
                .owner
                .children
                .iter()
                .find(|c| c.attr("name") == Some(p.name))
                .unwrap_or(p.elem);
            return Err(self.doc.err(
                e,
                format!(
                    "<{} type=\"{}\"> has no parameter '{}' in mcrt; supported: {}",
                    self.owner.tag,
                    self.owner.attr("type").unwrap_or("?"),
                    p.name,
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        }
        Ok(())
    }
}

/// Three numbers from `value="x, y, z"` or from `x`, `y`, `z` attributes (missing ones take
/// `default`).
pub fn xyz(doc: &Document, e: &Elem, default: f32) -> Result<Vec3> {
    if let Some(v) = e.attr("value") {
        if let Some(f) = numbers_fault(v) {
            return Err(doc.err_attr(e, "value", f));
        }
        return match numbers(v).as_deref() {
            Some([x, y, z]) if [x, y, z].iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(doc.err_attr(
                e,
                "value",
                format!(
                    "expected three numbers 'x, y, z', found '{}'",
                    crate::input::shorten(v)
                ),
            )),
        };
    }
    let mut out = [default; 3];
    for (slot, a) in out.iter_mut().zip(["x", "y", "z"]) {
        if let Some(v) = e.attr(a) {
            *slot = v
                .trim()
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    doc.err_attr(
                        e,
                        a,
                        format!("'{a}': expected a finite number, found '{v}'"),
                    )
                })?;
        }
    }
    Ok(Vec3::from_array(out))
}
