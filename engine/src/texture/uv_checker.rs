//! `UvChecker(u: 8, v: 4, even: .., odd: .., uv_transform: ..)`: a checker over the uv square.

use super::{Texture, TextureId, TextureModel, UvTransform};
use crate::format::{Color, Positive, Rgb};

/// `u` by `v` cells over the surface's uv square (`even` where floor(u s) + floor(v t) is even, (s,
/// t) the uv); `uv_transform: ((a, b, c), (d, e, f))` (optional) first maps the uv to (a s + b t +
/// c, d s + e t + f).
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct UvChecker {
    /// Cells along u.
    pub u: Positive,
    /// Cells along v.
    pub v: Positive,
    /// Even cells.
    pub even: Color<Rgb>,
    /// Odd cells.
    pub odd: Color<Rgb>,
    /// Applied to the surface's uv first (default: none).
    #[serde(default)]
    pub uv_transform: Option<UvTransform>,
}

impl TextureModel for UvChecker {
    fn build(&self, color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::UvChecker {
            u: self.u.0,
            v: self.v.0,
            even: color(&self.even),
            odd: color(&self.odd),
            transform: self.uv_transform,
        }
    }
}
