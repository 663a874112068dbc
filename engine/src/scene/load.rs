//! Reading and parsing scene files.

use super::{
    SceneDesc, SceneError,
    desc::{MaterialNameScope, take_current_object},
};
use ron::extensions::Extensions;
use std::path::Path;

/// Reads and parses the scene file at `path`.
pub fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        path: path.to_owned(),
        line: 0,
        col: 0,
        message: format!("cannot read the scene: {e}"),
    })?;
    parse(&text, path)
}

/// Parses scene text; `path` only names the source in errors.
///
/// Parsing runs twice: the first pass collects the material names, the second checks every
/// object's `material` (and every texture name) against them while the parser still knows
/// where that name stands, and reads image files.
pub fn parse(text: &str, path: &Path) -> Result<SceneDesc, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let options = ron::Options::default().with_default_extension(Extensions::IMPLICIT_SOME);
    let error = |e: ron::error::SpannedError| SceneError {
        path: path.to_owned(),
        line: e.span.start.line,
        col: e.span.start.col,
        message: match take_current_object() {
            Some(i) => format!("in objects[{i}]: {}", e.code),
            None => e.code.to_string(),
        },
    };
    let names: SceneDesc = options.from_str(text).map_err(error)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let _scope = MaterialNameScope::enter(
        names.materials.iter().map(|(n, _)| n.clone()).collect(),
        names
            .materials
            .iter()
            .filter(|(_, m)| m.kind().shading() == crate::material::Shading::Emitter)
            .map(|(n, _)| n.clone())
            .collect(),
        names.textures.0.iter().map(|(n, _)| n.clone()).collect(),
        dir,
    );
    options.from_str(text).map_err(error)
}
