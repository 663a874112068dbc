//! `Noise(scale: 4)`: smooth Perlin gradient noise of `scale * p`, in [0, 1].

use super::{NoiseKind, Texture, TextureId, TextureModel};
use crate::format::{Color, Positive, Rgb, white};

/// Perlin gradient noise of `scale * p` mapped from [-1, 1] to [0, 1], times `color` (default
/// white); world space.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    /// Frequency.
    pub scale: Positive,
    /// Colour the noise multiplies (default white).
    #[serde(default = "white")]
    pub color: Rgb,
}

impl TextureModel for Noise {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Noise { kind: NoiseKind::Smooth, scale: self.scale.0, depth: 0, color: self.color.0 }
    }
}
