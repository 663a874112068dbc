//! `Marble(scale: 4, depth: 7)`: 0.5 (1 + sin(scale z + 10 turbulence)), in [0, 1].

use super::turbulence::{octaves, seven};
use super::{NoiseKind, Texture, TextureId, TextureModel};
use crate::format::{Color, Positive, Rgb, white};

/// Marble veins (RTNW's marble: the turbulence of the unscaled point distorts the phase): 0.5 (1 +
/// sin(scale z + 10 turbulence(p))), in [0, 1], its turbulence of `depth` (1 to 24, default 7)
/// octaves, times `color` (default white); world space.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Marble {
    /// Frequency.
    pub scale: Positive,
    /// Octaves of the turbulence, 1 to [`super::turbulence::MAX_OCTAVES`] (default 7).
    #[serde(default = "seven", deserialize_with = "octaves")]
    pub depth: u32,
    /// Colour of the veins' bright parts (default white).
    #[serde(default = "white")]
    pub color: Rgb,
}

impl TextureModel for Marble {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Noise {
            kind: NoiseKind::Marble,
            scale: self.scale.0,
            depth: self.depth,
            color: self.color.0,
        }
    }
}
