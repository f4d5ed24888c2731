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
        SceneError {
            path: path.to_path_buf(),
            location,
            message: message.into(),
        }
    }

    /// An error at byte offset `offset` of `text`.
    pub fn at(path: &Path, text: &str, offset: usize, message: impl Into<String>) -> Self {
        Self::new(path, Some(line_col(text, offset)), message)
    }
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
