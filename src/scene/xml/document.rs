//! Reading the XML files of a scene into one tree: includes expanded, `$name` substituted.

use crate::scene::SceneError;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Nesting deeper than this is refused (a hostile or broken file, not a scene).
const MAX_DEPTH: usize = 64;

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
        let mut r = Reader {
            files: Vec::new(),
            params: defines.iter().cloned().collect(),
            stack: Vec::new(),
        };
        let root = r.read_file(path, None)?;
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
        let mut r = Reader {
            files: Vec::new(),
            params: defines.iter().cloned().collect(),
            stack: Vec::new(),
        };
        let root = r.read_text(path, text)?;
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
}

impl Reader {
    /// Reads one file and returns its `<scene>` element. `from` is the include element that
    /// named it, for errors.
    fn read_file(
        &mut self,
        path: &Path,
        from: Option<(&Path, (usize, usize))>,
    ) -> Result<Elem, SceneError> {
        let fail = |msg: String| match from {
            Some((f, pos)) => SceneError::new(f, Some(pos), msg),
            None => SceneError::new(path, None, msg),
        };
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
        self.read_text(path, &text)
    }

    /// Parses one file's text and returns its `<scene>` element.
    fn read_text(&mut self, path: &Path, text: &str) -> Result<Elem, SceneError> {
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
        let pos = |n: roxmltree::Node| {
            let p = doc.text_pos_at(n.range().start);
            (p.row as usize, p.col as usize)
        };
        if root.tag_name().name() != "scene" {
            return Err(SceneError::new(
                path,
                Some(pos(root)),
                format!(
                    "expected a Mitsuba <scene> element at the root, found <{}>",
                    root.tag_name().name()
                ),
            ));
        }
        if root.attribute("version").is_none() {
            return Err(SceneError::new(
                path,
                Some(pos(root)),
                "<scene> needs a version attribute, e.g. <scene version=\"3.0.0\">",
            ));
        }
        self.stack
            .push(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()));
        let r = self.convert(&doc, root, file, path, 0);
        self.stack.pop();
        r
    }

    fn convert(
        &mut self,
        doc: &roxmltree::Document,
        node: roxmltree::Node,
        file: usize,
        path: &Path,
        depth: usize,
    ) -> Result<Elem, SceneError> {
        let at = |n: roxmltree::Node| {
            let p = doc.text_pos_at(n.range().start);
            (p.row as usize, p.col as usize)
        };
        if depth > MAX_DEPTH {
            return Err(SceneError::new(
                path,
                Some(at(node)),
                format!("elements nested more than {MAX_DEPTH} deep"),
            ));
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let p = doc.text_pos_at(a.range_value().start);
            let p = (p.row as usize, p.col as usize);
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
            pos: at(node),
        };
        for child in node.children() {
            if child.is_text() {
                if child.text().is_some_and(|t| !t.trim().is_empty()) {
                    return Err(SceneError::new(
                        path,
                        Some(at(child)),
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
                            Some(at(child)),
                            "<default> needs name and value attributes",
                        ));
                    };
                    // `-D` and earlier defaults win.
                    if !self.params.contains_key(name) {
                        let v = self
                            .substitute(value)
                            .map_err(|m| SceneError::new(path, Some(at(child)), m))?;
                        self.params.insert(name.to_string(), v);
                    }
                }
                "include" => {
                    let Some(name) = child.attribute("filename") else {
                        return Err(SceneError::new(
                            path,
                            Some(at(child)),
                            "<include> needs a filename attribute",
                        ));
                    };
                    let name = self
                        .substitute(name)
                        .map_err(|m| SceneError::new(path, Some(at(child)), m))?;
                    let inc = path.parent().unwrap_or(Path::new(".")).join(&name);
                    let sub = self.read_file(&inc, Some((path, at(child))))?;
                    e.children.extend(sub.children);
                }
                _ => e
                    .children
                    .push(self.convert(doc, child, file, path, depth + 1)?),
            }
        }
        Ok(e)
    }

    /// Replaces each `$name` by its parameter's value.
    fn substitute(&self, s: &str) -> Result<String, String> {
        if !s.contains('$') {
            return Ok(s.to_string());
        }
        let mut out = String::with_capacity(s.len());
        let mut rest = s;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let n = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..n];
            if name.is_empty() {
                out.push('$');
                rest = after;
                continue;
            }
            match self.params.get(name) {
                Some(v) => out.push_str(v),
                None => {
                    return Err(format!(
                        "undefined parameter '${name}': give it a <default name=\"{name}\" \
                         value=\"...\"/> or pass -D {name}=VALUE"
                    ))
                }
            }
            rest = &after[n..];
        }
        out.push_str(rest);
        Ok(out)
    }
}
