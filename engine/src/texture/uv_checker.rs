//! `UvChecker(u: 8, v: 4, even: .., odd: .., uv_transform: ..)`: a checker over the uv square.

use super::{Texture, TextureId, TextureModel, UvTransform};
use crate::format::{Color, Positive, Rgb};

/// `u` by `v` cells over the uv square: `even` where floor(s u) + floor(t v) is even, (s, t)
/// being the surface's uv after `uv_transform`.
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
