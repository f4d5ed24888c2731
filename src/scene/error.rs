//! Errors in scene files, located by file, line and column.

use std::fmt;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone)]
pub struct SceneError {
    pub path: PathBuf,
    /// 1-based line and column, where the error has a place in the file.
    pub location: Option<(usize, usize)>,
    pub message: String,
}

impl SceneError {
    pub fn new(path: &Path, location: Option<(usize, usize)>, message: impl Into<String>) -> Self {
        let message = message.into();
        SceneError {
            path: path.to_path_buf(),
            location,
            message: shorten_message(&message).into_owned(),
        }
    }

    /// An error at byte offset `offset` of `text`.
    pub fn at(path: &Path, text: &str, offset: usize, message: impl Into<String>) -> Self {
        Self::new(path, Some(line_col(text, offset)), message)
    }
}

/// Longest message kept whole, in bytes; a longer one keeps its start and its end.
const MAX_MESSAGE: usize = 2000;
/// Longest run of non-blank characters (a name, a value, a path) kept whole in a message.
const MAX_WORD: usize = 200;

/// A message with user strings cut short: every run of non-blank characters longer than
/// `MAX_WORD` bytes is [`crate::input::shorten`]ed, and a message still longer than `MAX_MESSAGE` keeps
/// its first and last parts (what is wrong, and what was expected) around an ellipsis.
pub fn shorten_message(msg: &str) -> std::borrow::Cow<'_, str> {
    let long_word = msg.split_whitespace().any(|w| w.len() > MAX_WORD);
    if !long_word && msg.len() <= MAX_MESSAGE {
        return std::borrow::Cow::Borrowed(msg);
    }
    let mut out = String::with_capacity(msg.len().min(2 * MAX_MESSAGE));
    let mut rest = msg;
    while !rest.is_empty() {
        let blank = rest
            .find(|c: char| !c.is_whitespace())
            .unwrap_or(rest.len());
        out.push_str(&rest[..blank]);
        rest = &rest[blank..];
        let word = rest.find(char::is_whitespace).unwrap_or(rest.len());
        if word > MAX_WORD {
            out.push_str(&crate::input::shorten(&rest[..word]));
        } else {
            out.push_str(&rest[..word]);
        }
        rest = &rest[word..];
    }
    if out.len() > MAX_MESSAGE {
        let head = floor_boundary(&out, MAX_MESSAGE * 2 / 3);
        let tail = ceil_boundary(&out, out.len() - MAX_MESSAGE / 3);
        out = format!("{} … {}", &out[..head], &out[tail..]);
    }
    std::borrow::Cow::Owned(out)
}

fn floor_boundary(s: &str, mut i: usize) -> usize {
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn ceil_boundary(s: &str, mut i: usize) -> usize {
    while !s.is_char_boundary(i) {
        i += 1;
    }
    i
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..text.floor_char_boundary_compat(offset)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

trait FloorCharBoundary {
    fn floor_char_boundary_compat(&self, i: usize) -> usize;
}
impl FloorCharBoundary for str {
    fn floor_char_boundary_compat(&self, mut i: usize) -> usize {
        while i > 0 && !self.is_char_boundary(i) {
            i -= 1;
        }
        i
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some((l, c)) => write!(f, "{}:{}:{}: {}", self.path.display(), l, c, self.message),
            None => write!(f, "{}: {}", self.path.display(), self.message),
        }
    }
}

impl std::error::Error for SceneError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_user_strings_are_cut_short() {
        let name = "c".repeat(50_000);
        let msg = format!("no camera named '{name}' (defined: main)");
        let m = shorten_message(&msg);
        assert!(m.len() < 200, "{m}");
        assert!(m.starts_with("no camera named 'ccc"));
        assert!(m.contains("(50002 characters)"), "{m}");
        assert!(m.ends_with("(defined: main)"));
        // Many short words: the start and the end are kept.
        let many = format!("what {} expected", "word ".repeat(10_000));
        let m = shorten_message(&many);
        assert!(m.len() <= 2100 && m.starts_with("what") && m.ends_with("expected"));
        // Short messages stay as they are.
        assert_eq!(shorten_message("a 'b' c"), "a 'b' c");
    }
}
