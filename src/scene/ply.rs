//! Stanford PLY meshes (format 1.0: `ascii`, `binary_little_endian`, `binary_big_endian`).
//!
//! The `vertex` element gives positions (`x`, `y`, `z`), optional normals (`nx`, `ny`, `nz`)
//! and optional texture coordinates (`u`/`v`, `s`/`t`, `texture_u`/`texture_v` or
//! `texture_s`/`texture_t`); the `face` element gives polygons as a list property named
//! `vertex_indices` or `vertex_index`, fanned into triangles. Every other element and
//! property, scalar or list, is read past. All scalar types of the format are accepted
//! (`char`…`double` and `int8`…`float64`).
//!
//! Errors name the file and, for the header and ASCII data, the line and column; for binary
//! data they give the byte offset, the element and the index of the entry. Counts in the
//! header are never trusted for allocation: storage grows with the data actually present, so
//! a tiny file that declares billions of vertices fails fast without allocating.

use super::text::Fields;
use super::SceneError;
use crate::geometry::mesh::TriangleMesh;
use glam::{Vec2, Vec3};
use std::path::Path;

/// A mesh read from a PLY file. `normals` and `uvs` are empty when the file has none, else as
/// long as `positions`. Normals are normalized (a zero normal stays zero); texture coordinates
/// are as in the file, with no flip of v (as Mitsuba 3's `ply` shape with its default
/// `flip_tex_coords = false`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlyMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<[u32; 3]>,
}

impl PlyMesh {
    /// The mesh as the renderer's [`TriangleMesh`].
    pub fn into_triangle_mesh(self) -> TriangleMesh {
        TriangleMesh {
            tangents: None,
            normals: if self.normals.is_empty() {
                None
            } else {
                Some(self.normals)
            },
            uvs: if self.uvs.is_empty() {
                None
            } else {
                Some(self.uvs)
            },
            positions: self.positions,
            indices: self.indices,
        }
    }
}

/// Reads a PLY file.
pub fn load_ply(path: &Path) -> Result<PlyMesh, SceneError> {
    let data = crate::input::read(path)
        .map_err(|e| SceneError::new(path, None, format!("cannot read mesh file: {e}")))?;
    parse_ply(path, &data)
}

/// Parses the bytes of a PLY file; `path` only names the file in errors.
pub fn parse_ply(path: &Path, data: &[u8]) -> Result<PlyMesh, SceneError> {
    let header = parse_header(path, data)?;
    let body = &data[header.data_start..];
    let mut src = match header.format {
        Format::Ascii => Source::Ascii(AsciiTokens::new(body, header.lines)),
        Format::BinaryLe | Format::BinaryBe => Source::Binary {
            data,
            pos: header.data_start,
            big: header.format == Format::BinaryBe,
        },
    };
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut mesh = PlyMesh::default();
    let mut reader = Reader {
        path,
        src: &mut src,
    };
    for el in &header.elements {
        match el.name.as_str() {
            "vertex" => reader.read_vertices(el, body.len(), &mut mesh)?,
            "face" => reader.read_faces(el, vertex_count, body.len(), &mut mesh)?,
            _ => reader.skip_element(el)?,
        }
    }
    Ok(mesh)
}

// ---------------------------------------------------------------------------------------------
// Header
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
    /// 1-based header line, for errors about the declaration.
    line: usize,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
    line: usize,
}

impl Element {
    fn prop(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the first byte after the `end_header` line.
    data_start: usize,
    /// Number of header lines (the data starts on the next line).
    lines: usize,
}

fn parse_header(path: &Path, data: &[u8]) -> Result<Header, SceneError> {
    let err = |line: usize, col: usize, msg: String| SceneError::new(path, Some((line, col)), msg);
    if !(data.starts_with(b"ply\n") || data.starts_with(b"ply\r\n")) {
        return Err(err(
            1,
            1,
            "not a PLY file: it must start with a line 'ply'".into(),
        ));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    loop {
        line_no += 1;
        let Some(nl) = data[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err(
                line_no,
                1,
                "the header ends without an 'end_header' line".into(),
            ));
        };
        let raw = &data[pos..pos + nl];
        pos += nl + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let line = std::str::from_utf8(raw)
            .map_err(|_| err(line_no, 1, "the header line is not text".into()))?;
        let mut fields = Fields::new(line);
        let Some((_, kw)) = fields.next() else {
            continue;
        };
        match kw {
            "ply" if line_no == 1 => {}
            "comment" | "obj_info" => {}
            "format" => {
                let (col, f) = fields.next().ok_or_else(|| {
                    err(line_no, line.len() + 1, "'format' needs a format".into())
                })?;
                let fmt = match f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    _ => {
                        return Err(err(
                            line_no,
                            col,
                            format!(
                                "unknown format '{f}' (expected ascii, binary_little_endian \
                                 or binary_big_endian)"
                            ),
                        ))
                    }
                };
                match fields.next() {
                    Some((_, "1.0" | "1")) => {}
                    Some((col, v)) => {
                        return Err(err(
                            line_no,
                            col,
                            format!("unsupported PLY version '{v}' (expected 1.0)"),
                        ))
                    }
                    None => {
                        return Err(err(
                            line_no,
                            line.len() + 1,
                            "'format' needs a version".into(),
                        ))
                    }
                }
                format = Some(fmt);
            }
            "element" => {
                let (_, name) = fields
                    .next()
                    .ok_or_else(|| err(line_no, line.len() + 1, "'element' needs a name".into()))?;
                let (col, n) = fields.next().ok_or_else(|| {
                    err(line_no, line.len() + 1, "'element' needs a count".into())
                })?;
                let count: usize = n.parse().map_err(|_| {
                    err(
                        line_no,
                        col,
                        format!("expected an element count, found '{n}'"),
                    )
                })?;
                // Names first: a header of many other elements stays linear.
                if (name == "vertex" || name == "face") && elements.iter().any(|e| e.name == name) {
                    return Err(err(line_no, 1, format!("more than one '{name}' element")));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line: line_no,
                });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(err(line_no, 1, "'property' before any 'element'".into()));
                };
                let ty = |fields: &mut Fields, what: &str| -> Result<Scalar, SceneError> {
                    let (col, t) = fields.next().ok_or_else(|| {
                        err(line_no, line.len() + 1, format!("'property' needs {what}"))
                    })?;
                    Scalar::parse(t)
                        .ok_or_else(|| err(line_no, col, format!("unknown property type '{t}'")))
                };
                let (col, first) = fields.clone().next().ok_or_else(|| {
                    err(line_no, line.len() + 1, "'property' needs a type".into())
                })?;
                let kind = if first == "list" {
                    fields.next();
                    let count = ty(&mut fields, "a list count type")?;
                    let item = ty(&mut fields, "a list item type")?;
                    if !count.is_int() {
                        return Err(err(
                            line_no,
                            col,
                            "the count type of a list must be an integer type".into(),
                        ));
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(ty(&mut fields, "a type")?)
                };
                let (_, name) = fields.next().ok_or_else(|| {
                    err(line_no, line.len() + 1, "'property' needs a name".into())
                })?;
                el.props.push(Property {
                    name: name.to_string(),
                    kind,
                    line: line_no,
                });
            }
            "end_header" => break,
            _ => return Err(err(line_no, 1, format!("unknown header keyword '{kw}'"))),
        }
    }
    let format = format.ok_or_else(|| err(2, 1, "the header has no 'format' line".into()))?;
    Ok(Header {
        format,
        elements,
        data_start: pos,
        lines: line_no,
    })
}

// ---------------------------------------------------------------------------------------------
// Data
// ---------------------------------------------------------------------------------------------

/// 1-based line and column.
type LineCol = (usize, usize);

/// Whitespace-separated ASCII tokens with their 1-based line and column.
struct AsciiTokens<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> AsciiTokens<'a> {
    fn new(data: &'a [u8], header_lines: usize) -> Self {
        AsciiTokens {
            data,
            pos: 0,
            line: header_lines + 1,
            line_start: 0,
        }
    }

    /// The next token and its location, or the location of the end of the data.
    fn next(&mut self) -> Result<(&'a [u8], LineCol), LineCol> {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            if self.data[self.pos] == b'\n' {
                self.line += 1;
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
        let loc = (self.line, self.pos - self.line_start + 1);
        if self.pos >= self.data.len() {
            return Err(loc);
        }
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Ok((&self.data[start..self.pos], loc))
    }
}

enum Source<'a> {
    Ascii(AsciiTokens<'a>),
    /// The whole file, and the position in it.
    Binary {
        data: &'a [u8],
        pos: usize,
        big: bool,
    },
}

/// Where a value is read: element name, entry index, property name.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    element: &'a str,
    index: usize,
    prop: &'a str,
}

impl Ctx<'_> {
    fn describe(&self) -> String {
        format!(
            "element '{}' {}, property '{}'",
            self.element, self.index, self.prop
        )
    }
}

/// A value read, and where: a line and column (ASCII) or a byte offset (binary).
#[derive(Clone, Copy)]
enum Loc {
    LineCol(usize, usize),
    Offset(usize),
}

fn error_at(path: &Path, loc: Loc, msg: String) -> SceneError {
    match loc {
        Loc::LineCol(l, c) => SceneError::new(path, Some((l, c)), msg),
        Loc::Offset(o) => SceneError::new(path, None, format!("byte offset {o}: {msg}")),
    }
}

struct Reader<'a, 'b> {
    path: &'a Path,
    src: &'a mut Source<'b>,
}

impl Reader<'_, '_> {
    fn error(&self, loc: Loc, msg: String) -> SceneError {
        error_at(self.path, loc, msg)
    }

    /// Reads one value of type `ty`. Integers come back exactly (all PLY integer types fit
    /// an f64); floats as f64.
    fn value(&mut self, ty: Scalar, ctx: Ctx) -> Result<(f64, Loc), SceneError> {
        match self.src {
            Source::Ascii(tok) => {
                let (t, (l, c)) = tok.next().map_err(|(l, c)| {
                    SceneError::new(
                        self.path,
                        Some((l, c)),
                        format!("unexpected end of data, reading {}", ctx.describe()),
                    )
                })?;
                let loc = Loc::LineCol(l, c);
                let s = std::str::from_utf8(t).ok();
                let v = if ty.is_int() {
                    s.and_then(|s| s.parse::<i64>().ok()).map(|v| v as f64)
                } else {
                    s.and_then(|s| s.parse::<f64>().ok())
                };
                let v = v.ok_or_else(|| {
                    let shown: String = String::from_utf8_lossy(t).chars().take(40).collect();
                    let what = if ty.is_int() {
                        "an integer"
                    } else {
                        "a number"
                    };
                    self.error(
                        loc,
                        format!("expected {what} for {}, found '{shown}'", ctx.describe()),
                    )
                })?;
                Ok((v, loc))
            }
            Source::Binary { data, pos, big } => {
                let n = ty.size();
                let start = *pos;
                let Some(b) = data.get(start..start + n) else {
                    return Err(error_at(
                        self.path,
                        Loc::Offset(start),
                        format!(
                            "truncated data: the file ends while reading {} ({} bytes left, {} \
                             needed)",
                            ctx.describe(),
                            data.len() - start,
                            n
                        ),
                    ));
                };
                *pos += n;
                let big = *big;
                macro_rules! get {
                    ($t:ty) => {{
                        let a = b.try_into().unwrap();
                        (if big {
                            <$t>::from_be_bytes(a)
                        } else {
                            <$t>::from_le_bytes(a)
                        }) as f64
                    }};
                }
                let v = match ty {
                    Scalar::I8 => b[0] as i8 as f64,
                    Scalar::U8 => b[0] as f64,
                    Scalar::I16 => get!(i16),
                    Scalar::U16 => get!(u16),
                    Scalar::I32 => get!(i32),
                    Scalar::U32 => get!(u32),
                    Scalar::F32 => get!(f32),
                    Scalar::F64 => get!(f64),
                };
                Ok((v, Loc::Offset(start)))
            }
        }
    }

    /// Reads a list count.
    fn count(&mut self, ty: Scalar, ctx: Ctx) -> Result<(usize, Loc), SceneError> {
        let (v, loc) = self.value(ty, ctx)?;
        if v < 0.0 {
            return Err(self.error(
                loc,
                format!("negative list length {v} for {}", ctx.describe()),
            ));
        }
        Ok((v as usize, loc))
    }

    /// Reads past one property.
    fn skip(&mut self, kind: Kind, ctx: Ctx) -> Result<(), SceneError> {
        match kind {
            Kind::Scalar(t) => {
                self.value(t, ctx)?;
            }
            Kind::List { count, item } => {
                let (n, _) = self.count(count, ctx)?;
                if let Source::Binary { data, pos, .. } = self.src {
                    // Skip the items at once, after checking they are there.
                    let need = n.saturating_mul(item.size());
                    if need > data.len() - *pos {
                        return Err(error_at(
                            self.path,
                            Loc::Offset(*pos),
                            format!(
                                "truncated data: the list of {n} items of {} needs {need} bytes, \
                                 {} left",
                                ctx.describe(),
                                data.len() - *pos
                            ),
                        ));
                    }
                    *pos += need;
                } else {
                    for _ in 0..n {
                        self.value(item, ctx)?;
                    }
                }
            }
        }
        Ok(())
    }

    fn skip_element(&mut self, el: &Element) -> Result<(), SceneError> {
        if el.props.is_empty() {
            return Ok(());
        }
        // Each entry consumes at least a byte (or an ASCII token), so a hostile count ends
        // in an error after at most as many steps as the data has bytes.
        for index in 0..el.count {
            for p in &el.props {
                let ctx = Ctx {
                    element: &el.name,
                    index,
                    prop: &p.name,
                };
                self.skip(p.kind, ctx)?;
            }
        }
        Ok(())
    }

    fn header_error(&self, line: usize, msg: String) -> SceneError {
        SceneError::new(self.path, Some((line, 1)), msg)
    }

    fn read_vertices(
        &mut self,
        el: &Element,
        data_len: usize,
        mesh: &mut PlyMesh,
    ) -> Result<(), SceneError> {
        if el.count > u32::MAX as usize {
            return Err(self.header_error(
                el.line,
                format!("{} vertices is more than this reader supports", el.count),
            ));
        }
        let scalar = |name: &str| -> Result<Option<usize>, SceneError> {
            match el.prop(name) {
                None => Ok(None),
                Some(i) => match el.props[i].kind {
                    Kind::Scalar(_) => Ok(Some(i)),
                    Kind::List { .. } => Err(self.header_error(
                        el.props[i].line,
                        format!("vertex property '{name}' must be a scalar, not a list"),
                    )),
                },
            }
        };
        let all = |names: [&str; 3]| -> Result<Option<[usize; 3]>, SceneError> {
            let (a, b, c) = (scalar(names[0])?, scalar(names[1])?, scalar(names[2])?);
            Ok(match (a, b, c) {
                (Some(a), Some(b), Some(c)) => Some([a, b, c]),
                _ => None,
            })
        };
        let pos = all(["x", "y", "z"])?.ok_or_else(|| {
            self.header_error(
                el.line,
                "the 'vertex' element needs properties x, y and z".into(),
            )
        })?;
        let nrm = all(["nx", "ny", "nz"])?;
        let mut uv = None;
        // Mitsuba 3's order of preference (ply.cpp): u/v, texture_u/texture_v, s/t; then
        // texture_s/texture_t, which Mitsuba does not read.
        for (a, b) in [
            ("u", "v"),
            ("texture_u", "texture_v"),
            ("s", "t"),
            ("texture_s", "texture_t"),
        ] {
            if let (Some(a), Some(b)) = (scalar(a)?, scalar(b)?) {
                uv = Some([a, b]);
                break;
            }
        }
        // Grow with the data, never trusting the declared count beyond what the file holds.
        let cap = el.count.min(data_len / el.props.len().max(1));
        mesh.positions.reserve(cap);
        if nrm.is_some() {
            mesh.normals.reserve(cap);
        }
        if uv.is_some() {
            mesh.uvs.reserve(cap);
        }
        let mut vals = vec![(0.0f64, Loc::Offset(0)); el.props.len()];
        for index in 0..el.count {
            for (k, p) in el.props.iter().enumerate() {
                let ctx = Ctx {
                    element: &el.name,
                    index,
                    prop: &p.name,
                };
                match p.kind {
                    Kind::Scalar(t) => vals[k] = self.value(t, ctx)?,
                    kind => self.skip(kind, ctx)?,
                }
            }
            let get = |k: usize| -> Result<f32, SceneError> {
                let (v, loc) = vals[k];
                let f = v as f32;
                if !f.is_finite() {
                    return Err(self.error(
                        loc,
                        format!(
                            "vertex {index}: property '{}' is not a finite number ({v})",
                            el.props[k].name
                        ),
                    ));
                }
                Ok(f)
            };
            mesh.positions
                .push(Vec3::new(get(pos[0])?, get(pos[1])?, get(pos[2])?));
            if let Some(n) = nrm {
                mesh.normals
                    .push(Vec3::new(get(n[0])?, get(n[1])?, get(n[2])?).normalize_or_zero());
            }
            if let Some(t) = uv {
                mesh.uvs.push(Vec2::new(get(t[0])?, get(t[1])?));
            }
        }
        Ok(())
    }

    fn read_faces(
        &mut self,
        el: &Element,
        vertex_count: usize,
        data_len: usize,
        mesh: &mut PlyMesh,
    ) -> Result<(), SceneError> {
        let list = el
            .prop("vertex_indices")
            .or_else(|| el.prop("vertex_index"));
        let Some(list) = list else {
            return Err(self.header_error(
                el.line,
                "the 'face' element needs a list property 'vertex_indices' or 'vertex_index'"
                    .into(),
            ));
        };
        let Kind::List {
            count: count_ty,
            item,
        } = el.props[list].kind
        else {
            return Err(self.header_error(
                el.props[list].line,
                format!("face property '{}' must be a list", el.props[list].name),
            ));
        };
        if !item.is_int() {
            return Err(self.header_error(
                el.props[list].line,
                format!(
                    "face property '{}' must be a list of integers",
                    el.props[list].name
                ),
            ));
        }
        mesh.indices
            .reserve(el.count.min(data_len / (3 * item.size() + count_ty.size())));
        let mut corners: Vec<u32> = Vec::new();
        for index in 0..el.count {
            for (k, p) in el.props.iter().enumerate() {
                let ctx = Ctx {
                    element: &el.name,
                    index,
                    prop: &p.name,
                };
                if k != list {
                    self.skip(p.kind, ctx)?;
                    continue;
                }
                let (n, loc) = self.count(count_ty, ctx)?;
                if n < 3 {
                    return Err(self.error(
                        loc,
                        format!("face {index} has {n} vertices (a face needs at least 3)"),
                    ));
                }
                corners.clear();
                for _ in 0..n {
                    let (v, loc) = self.value(item, ctx)?;
                    if v < 0.0 || v >= vertex_count as f64 {
                        return Err(self.error(
                            loc,
                            format!(
                                "face {index}: vertex index {v} out of range (the file has \
                                 {vertex_count} vertices)"
                            ),
                        ));
                    }
                    corners.push(v as u32);
                }
                for j in 1..n - 1 {
                    mesh.indices.push([corners[0], corners[j], corners[j + 1]]);
                }
            }
        }
        Ok(())
    }
}
