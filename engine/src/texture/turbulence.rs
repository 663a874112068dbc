//! `Turbulence(scale: 4, depth: 7)`: a sum of octaves of |noise|, in [0, 2).

use super::{NoiseKind, Texture, TextureId, TextureModel};
use crate::format::{Color, Positive, Rgb, white};
use serde::{Deserialize, Deserializer, de::Error};

/// Sum of `depth` (1 to 24, default 7) octaves of abs(noise) of `scale * p`, in [0, 2), times
/// `color` (default white); world space.
#[derive(serde::Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Turbulence {
    /// Frequency.
    pub scale: Positive,
    /// Octaves, 1 to [`MAX_OCTAVES`] (default 7).
    #[serde(default = "seven", deserialize_with = "octaves")]
    pub depth: u32,
    /// Colour the turbulence multiplies (default white).
    #[serde(default = "white")]
    pub color: Rgb,
}

impl TextureModel for Turbulence {
    fn build(&self, _color: &mut dyn FnMut(&Color<Rgb>) -> TextureId) -> Texture {
        Texture::Noise {
            kind: NoiseKind::Turbulence,
            scale: self.scale.0,
            depth: self.depth,
            color: self.color.0,
        }
    }
}

/// The default number of octaves.
pub(super) fn seven() -> u32 {
    7
}

/// The most octaves of turbulence: the 25th would weigh 2^-24 of the first, below what an f32
/// sum keeps (and a depth of billions made one texture lookup run for minutes).
pub const MAX_OCTAVES: u32 = 24;

/// A number of octaves, 1 to [`MAX_OCTAVES`].
pub(super) fn octaves<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let n = u32::deserialize(d)?;
    match (1..=MAX_OCTAVES).contains(&n) {
        true => Ok(n),
        false => Err(D::Error::custom(format!("expected 1 to {MAX_OCTAVES} octaves, found {n}"))),
    }
}
