//! `Checker(scale: s, even: .., odd: ..)`: a 3-D checker in world space.

use super::{Texture, TextureId, TextureModel};
use crate::format::{Color, Positive, Rgb};

/// 3-D checker in world space: cells of side `scale` (s), `even` where floor(x/s) + floor(y/s) +
/// floor(z/s) is even, else `odd`.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Checker {
    /// Cell size.
    pub scale: Positive,
    /// Even cells.
    pub even: Color<Rgb>,
    /// Odd cells.
    pub odd: Color<Rgb>,
}

impl TextureModel for Checker {
    fn build(&self, color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Checker { scale: self.scale.0, even: color(&self.even), odd: color(&self.odd) }
    }
}
