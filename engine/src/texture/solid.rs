//! `Solid((r, g, b))`: one colour everywhere.

use super::{Texture, TextureId, TextureModel};
use crate::format::{Color, Rgb};

/// One colour, written as the kind's one unnamed value: `Solid((r, g, b))`.
#[derive(serde::Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(transparent)]
pub struct Solid(pub Rgb);

impl TextureModel for Solid {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Solid(self.0.0)
    }
}
