//! `BlockyNoise(scale: 4)`: one random value per lattice cell, in [0, 1).

use super::{NoiseKind, Texture, TextureId, TextureModel};
use crate::format::{Color, Positive, Rgb, white};

/// One random value per lattice cell of `scale * p`, in [0, 1), times `color` (default white);
/// world space.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BlockyNoise {
    /// Frequency.
    pub scale: Positive,
    /// Colour the noise multiplies (default white).
    #[serde(default = "white")]
    pub color: Rgb,
}

impl TextureModel for BlockyNoise {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Noise { kind: NoiseKind::Blocky, scale: self.scale.0, depth: 0, color: self.color.0 }
    }
}
