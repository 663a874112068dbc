//! Scene loading errors with a position in the file.

use std::fmt;
use std::path::PathBuf;

/// An error in a scene file: where it is and what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line, or 0 when the error has no position (e.g. the file cannot be read).
    pub line: usize,
    /// 1-based column.
    pub col: usize,
    /// What went wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.path.display(), self.message)
        } else {
            write!(f, "{}:{}:{}: {}", self.path.display(), self.line, self.col, self.message)
        }
    }
}

impl std::error::Error for SceneError {}
