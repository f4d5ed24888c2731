//! Reading the XML files of a scene into one tree: includes expanded, `$name` substituted.

use crate::scene::SceneError;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Nesting deeper than this, counted through includes, is refused (a hostile or broken file,
/// not a scene). Checked before descending, so the reader's recursion stays this shallow.
pub const MAX_DEPTH: usize = 64;
/// Includes nested deeper than this are refused.
pub const MAX_INCLUDE_DEPTH: usize = 16;
/// Files read in all (the scene and its includes, each time it is included).
pub const MAX_FILES: usize = 1024;
/// Elements in all files together.
pub const MAX_ELEMENTS: usize = 10_000_000;
/// Longest text one `$name` substitution may produce, in bytes.
pub const MAX_SUBSTITUTED: usize = 1 << 20;
/// Bytes all substitutions together may produce: parameters that expand into parameters
/// grow geometrically, and are refused before the text is built.
pub const MAX_SUBSTITUTED_TOTAL: usize = 16 << 20;

/// An XML element after substitution, with where it came from.
#[derive(Clone, Debug)]
pub struct Elem {
    pub tag: String,
    /// Attribute name, value (after `$name` substitution) and the value's line and column.
    pub attrs: Vec<(String, String, (usize, usize))>,
    pub children: Vec<Elem>,
    /// Index into `Document::files`.
    pub file: usize,
    pub pos: (usize, usize),
}

impl Elem {
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|a| a.0 == name)
            .map(|a| a.1.as_str())
    }

    pub fn attr_pos(&self, name: &str) -> (usize, usize) {
        self.attrs
            .iter()
            .find(|a| a.0 == name)
            .map_or(self.pos, |a| a.2)
    }
}

pub struct Document {
    /// The scene file, then each included file.
    pub files: Vec<PathBuf>,
    /// The `<scene>` element, includes expanded.
    pub root: Elem,
}

impl Document {
    pub fn load(path: &Path, defines: &[(String, String)]) -> Result<Document, SceneError> {
        let mut r = Reader::new(defines);
        let root = r.read_file(path, None, 0)?;
        Ok(Document {
            files: r.files,
            root,
        })
    }

    /// Like `load`, for a scene whose text is already in memory (`path` names it in errors
    /// and anchors its includes).
    pub fn parse(
        path: &Path,
        text: &str,
        defines: &[(String, String)],
    ) -> Result<Document, SceneError> {
        let mut r = Reader::new(defines);
        let root = r.read_text(path, text, 0)?;
        Ok(Document {
            files: r.files,
            root,
        })
    }

    pub fn err(&self, e: &Elem, msg: impl Into<String>) -> SceneError {
        SceneError::new(&self.files[e.file], Some(e.pos), msg)
    }

    pub fn err_attr(&self, e: &Elem, attr: &str, msg: impl Into<String>) -> SceneError {
        SceneError::new(&self.files[e.file], Some(e.attr_pos(attr)), msg)
    }
}

struct Reader {
    files: Vec<PathBuf>,
    /// `-D` values first (they win), then `<default>`s as they are met.
    params: HashMap<String, String>,
    /// Canonical paths of the files being read, to refuse include cycles.
    stack: Vec<PathBuf>,
    /// Elements converted so far, in all files.
    elements: usize,
    /// Bytes produced by substitutions so far.
    substituted: usize,
}

impl Reader {
    fn new(defines: &[(String, String)]) -> Reader {
        Reader {
            files: Vec::new(),
            params: defines.iter().cloned().collect(),
            stack: Vec::new(),
            elements: 0,
            substituted: 0,
        }
    }
}

/// Line and column (1-based, in characters) of byte offsets of one file's text. Offsets asked
/// in increasing order, as the reader walks the document, cost the bytes between them: a
/// file's positions cost O(its size) in all. (roxmltree's `text_pos_at` counts from the
/// start of the text each time, which made a file of many elements quadratic.)
struct Locator<'t> {
    text: &'t str,
    /// The last offset asked, and its line and column.
    at: usize,
    line: usize,
    col: usize,
}

impl<'t> Locator<'t> {
    fn new(text: &'t str) -> Self {
        Locator {
            text,
            at: 0,
            line: 1,
            col: 1,
        }
    }

    fn pos(&mut self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        if offset < self.at {
            // Rare (errors): count again from the start.
            *self = Locator::new(self.text);
        }
        for &b in &self.text.as_bytes()[self.at..offset] {
            if b == b'\n' {
                self.line += 1;
                self.col = 1;
            } else if b & 0xC0 != 0x80 {
                self.col += 1;
            }
        }
        self.at = offset;
        (self.line, self.col)
    }
}

impl Reader {
    /// Reads one file and returns its `<scene>` element. `from` is the include element that
    /// named it, for errors.
    fn read_file(
        &mut self,
        path: &Path,
        from: Option<(&Path, (usize, usize))>,
        depth: usize,
    ) -> Result<Elem, SceneError> {
        let fail = |msg: String| match from {
            Some((f, pos)) => SceneError::new(f, Some(pos), msg),
            None => SceneError::new(path, None, msg),
        };
        // Bounds first: nothing of a file past them is read.
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(fail(format!(
                "includes nested more than {MAX_INCLUDE_DEPTH} deep"
            )));
        }
        if self.files.len() >= MAX_FILES {
            return Err(fail(format!("more than {MAX_FILES} files included in all")));
        }
        let text = crate::input::read_text(path)
            .map_err(|e| fail(format!("cannot read '{}': {e}", path.display())))?;
        let canon = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.stack.contains(&canon) {
            return Err(fail(format!(
                "include cycle: '{}' includes itself (through {})",
                path.display(),
                self.stack
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" → ")
            )));
        }
        self.read_text(path, &text, depth)
    }

    /// Parses one file's text and returns its `<scene>` element.
    fn read_text(&mut self, path: &Path, text: &str, depth: usize) -> Result<Elem, SceneError> {
        // roxmltree descends recursively into nested elements: bound the nesting first.
        check_nesting(path, text)?;
        let opts = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: 50_000_000,
        };
        let doc = roxmltree::Document::parse_with_options(text, opts).map_err(|e| {
            let p = e.pos();
            SceneError::new(
                path,
                Some((p.row as usize, p.col as usize)),
                format!("malformed XML: {e}"),
            )
        })?;
        let file = self.files.len();
        self.files.push(path.to_path_buf());
        let root = doc.root_element();
        let mut loc = Locator::new(text);
        let root_pos = loc.pos(root.range().start);
        if root.tag_name().name() != "scene" {
            return Err(SceneError::new(
                path,
                Some(root_pos),
                format!(
                    "expected a Mitsuba <scene> element at the root, found <{}>",
                    root.tag_name().name()
                ),
            ));
        }
        if root.attribute("version").is_none() {
            return Err(SceneError::new(
                path,
                Some(root_pos),
                "<scene> needs a version attribute, e.g. <scene version=\"3.0.0\">",
            ));
        }
        self.stack
            .push(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()));
        let r = self.convert(&mut loc, root, file, path, depth);
        self.stack.pop();
        r
    }

    /// Converts `node` (at nesting `depth`, counted through includes) and its children. The
    /// depth is checked before a child is descended into, so the recursion is at most
    /// [`MAX_DEPTH`] deep whatever the file holds.
    fn convert(
        &mut self,
        loc: &mut Locator,
        node: roxmltree::Node,
        file: usize,
        path: &Path,
        depth: usize,
    ) -> Result<Elem, SceneError> {
        let node_pos = loc.pos(node.range().start);
        self.elements += 1;
        if self.elements > MAX_ELEMENTS {
            return Err(SceneError::new(
                path,
                Some(node_pos),
                format!("more than {MAX_ELEMENTS} elements in the scene and its includes"),
            ));
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let p = loc.pos(a.range_value().start);
            let v = self
                .substitute(a.value())
                .map_err(|m| SceneError::new(path, Some(p), m))?;
            attrs.push((a.name().to_string(), v, p));
        }
        let mut e = Elem {
            tag: node.tag_name().name().to_string(),
            attrs,
            children: Vec::new(),
            file,
            pos: node_pos,
        };
        for child in node.children() {
            if child.is_element() && depth + 1 > MAX_DEPTH {
                return Err(SceneError::new(
                    path,
                    Some(loc.pos(child.range().start)),
                    format!("elements nested more than {MAX_DEPTH} deep (includes count too)"),
                ));
            }
            if child.is_text() {
                if child.text().is_some_and(|t| !t.trim().is_empty()) {
                    return Err(SceneError::new(
                        path,
                        Some(loc.pos(child.range().start)),
                        "unexpected text: Mitsuba XML gives values in attributes",
                    ));
                }
                continue;
            }
            if !child.is_element() {
                continue; // comments, processing instructions
            }
            match child.tag_name().name() {
                "default" => {
                    let (Some(name), Some(value)) =
                        (child.attribute("name"), child.attribute("value"))
                    else {
                        return Err(SceneError::new(
                            path,
                            Some(loc.pos(child.range().start)),
                            "<default> needs name and value attributes",
                        ));
                    };
                    // `-D` and earlier defaults win.
                    if !self.params.contains_key(name) {
                        let v = self.substitute(value).map_err(|m| {
                            SceneError::new(path, Some(loc.pos(child.range().start)), m)
                        })?;
                        self.params.insert(name.to_string(), v);
                    }
                }
                "include" => {
                    let Some(name) = child.attribute("filename") else {
                        return Err(SceneError::new(
                            path,
                            Some(loc.pos(child.range().start)),
                            "<include> needs a filename attribute",
                        ));
                    };
                    let name = self.substitute(name).map_err(|m| {
                        SceneError::new(path, Some(loc.pos(child.range().start)), m)
                    })?;
                    let inc = path.parent().unwrap_or(Path::new(".")).join(&name);
                    let sub = self.read_file(
                        &inc,
                        Some((path, loc.pos(child.range().start))),
                        depth + 1,
                    )?;
                    e.children.extend(sub.children);
                }
                _ => e
                    .children
                    .push(self.convert(loc, child, file, path, depth + 1)?),
            }
        }
        Ok(e)
    }

    /// Replaces each `$name` by its parameter's value. The length of the result is added up
    /// first and checked against [`MAX_SUBSTITUTED`] and [`MAX_SUBSTITUTED_TOTAL`], so no
    /// parameter that expands into parameters builds a huge string.
    fn substitute(&mut self, s: &str) -> Result<String, String> {
        if !s.contains('$') {
            return Ok(s.to_string());
        }
        let mut len = 0usize;
        self.expand(s, |piece| {
            len = len.saturating_add(piece.len());
        })?;
        if len > MAX_SUBSTITUTED {
            return Err(format!(
                "substituting the parameters here gives {len} bytes, more than the {MAX_SUBSTITUTED} allowed"
            ));
        }
        self.substituted = self.substituted.saturating_add(len);
        if self.substituted > MAX_SUBSTITUTED_TOTAL {
            return Err(format!(
                "parameter substitutions give more than {MAX_SUBSTITUTED_TOTAL} bytes in all"
            ));
        }
        let mut out = String::with_capacity(len);
        self.expand(s, |piece| out.push_str(piece))?;
        Ok(out)
    }

    /// Walks `s` with each `$name` replaced by its value, giving `out` the pieces in order.
    fn expand(&self, s: &str, mut out: impl FnMut(&str)) -> Result<(), String> {
        let mut rest = s;
        while let Some(i) = rest.find('$') {
            out(&rest[..i]);
            let after = &rest[i + 1..];
            let n = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..n];
            if name.is_empty() {
                out("$");
                rest = after;
                continue;
            }
            match self.params.get(name) {
                Some(v) => out(v),
                None => {
                    return Err(format!(
                        "undefined parameter '${name}': give it a <default name=\"{name}\" \
                         value=\"...\"/> or pass -D {name}=VALUE"
                    ))
                }
            }
            rest = &after[n..];
        }
        out(rest);
        Ok(())
    }
}

/// Refuses a file whose elements nest more than [`MAX_DEPTH`] deep (below `<scene>`), by a
/// linear scan of the text before it is parsed: the XML parser recurses once per level, so
/// 20 000 nested elements would overflow the stack. Comments, CDATA sections, processing
/// instructions and quoted attribute values are skipped; anything malformed is left for the
/// parser to report.
fn check_nesting(path: &Path, text: &str) -> Result<(), SceneError> {
    let b = text.as_bytes();
    let find = |from: usize, pat: &[u8]| -> usize {
        b[from.min(b.len())..]
            .windows(pat.len())
            .position(|w| w == pat)
            .map_or(b.len(), |i| from + i + pat.len())
    };
    let mut depth = 0usize;
    let mut i = 0;
    while let Some(k) = b[i..].iter().position(|&c| c == b'<') {
        let at = i + k;
        let rest = &b[at..];
        i = if rest.starts_with(b"<!--") {
            find(at + 4, b"-->")
        } else if rest.starts_with(b"<![CDATA[") {
            find(at + 9, b"]]>")
        } else if rest.starts_with(b"<?") {
            find(at + 2, b"?>")
        } else if rest.starts_with(b"<!") {
            find(at + 2, b">")
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            find(at + 2, b">")
        } else {
            // A start tag: to its '>' outside quotes; "/>" closes it at once.
            let mut j = at + 1;
            let mut quote = None;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, b'"' | b'\'') => quote = Some(b[j]),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if j < b.len() && b[j - 1] != b'/' {
                depth += 1;
                // The root <scene> is level 1.
                if depth > MAX_DEPTH + 1 {
                    return Err(SceneError::at(
                        path,
                        text,
                        at,
                        format!("elements nested more than {MAX_DEPTH} deep"),
                    ));
                }
            }
            j + 1
        };
        if i >= b.len() {
            break;
        }
    }
    Ok(())
}
