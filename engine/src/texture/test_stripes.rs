//! A texture that exists to test the texture registry (cargo feature `test-texture`):
//! `TestStripes(stripes: n, even: .., odd: ..)`, in this one file and registered by one line in
//! `texture/mod.rs`. It is the [`Texture::UvChecker`] of `n` by 1 cells: `n` stripes across u,
//! `even` where floor(n u) is even (over the uv square).

use super::{Texture, TextureId, TextureModel};
use crate::format::{Color, Positive, Rgb};

/// Stripes across u.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TestStripes {
    /// How many stripes over the uv square.
    pub stripes: Positive,
    /// Even stripes.
    pub even: Color<Rgb>,
    /// Odd stripes.
    pub odd: Color<Rgb>,
}

impl TextureModel for TestStripes {
    fn build(&self, color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::UvChecker {
            u: self.stripes.0,
            v: 1.0,
            even: color(&self.even),
            odd: color(&self.odd),
            transform: None,
        }
    }
}
