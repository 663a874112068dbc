//! Scene loading errors with a position in the file.

use std::path::PathBuf;

/// An error in a scene file: where it is and what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{}: {message}", path.display(), position(*.line, *.col))]
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

/// `:line:col`, or nothing for an error without a position.
fn position(line: usize, col: usize) -> String {
    if line == 0 { String::new() } else { format!(":{line}:{col}") }
}
