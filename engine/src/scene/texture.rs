//! `textures: { .. }`: named textures, each naming only the textures before it.

use super::assets::ImageFile;
use crate::format::{Color, Positive, Rgb, context, white};
use crate::texture::Wrap;
use serde::{Deserialize, Deserializer, de::Error};

/// A texture as written in the scene; colours inside may name textures defined before it.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Texture")]
pub enum TextureDesc {
    /// `Solid((r, g, b))`.
    Solid(Rgb),
    /// `Checker(scale: s, even: .., odd: ..)`: 3-D cells of side s in world space.
    Checker {
        /// Cell size.
        scale: Positive,
        /// Even cells.
        even: Color<Rgb>,
        /// Odd cells.
        odd: Color<Rgb>,
    },
    /// `UvChecker(u: 8, v: 4, even: .., odd: ..)`: u by v cells over the uv square.
    UvChecker {
        /// Cells along u.
        u: Positive,
        /// Cells along v.
        v: Positive,
        /// Even cells.
        even: Color<Rgb>,
        /// Odd cells.
        odd: Color<Rgb>,
    },
    /// `Image(file: "earth.png", wrap: Repeat)`: PNG, JPEG, HDR or EXR, relative to the scene
    /// file; 8-bit images are sRGB, float ones linear.
    Image {
        /// The file.
        file: ImageFile,
        /// `Repeat` (default), `Clamp` or `Mirror`.
        #[serde(default)]
        wrap: Wrap,
    },
    /// `Noise(scale: 4)`: smooth Perlin gradient noise of `scale * p`, in [0, 1].
    Noise {
        /// Frequency.
        scale: Positive,
        /// Colour the noise multiplies (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
    /// `BlockyNoise(scale: 4)`: one random value per lattice cell, in [0, 1).
    BlockyNoise {
        /// Frequency.
        scale: Positive,
        /// Colour the noise multiplies (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
    /// `Turbulence(scale: 4, depth: 7)`: sum of octaves of |noise|, in [0, 2).
    Turbulence {
        /// Frequency.
        scale: Positive,
        /// Octaves, 1 to [`MAX_OCTAVES`] (default 7).
        #[serde(default = "seven", deserialize_with = "octaves")]
        depth: u32,
        /// Colour the turbulence multiplies (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
    /// `Marble(scale: 4, depth: 7)`: 0.5 (1 + sin(scale z + 10 turbulence)), in [0, 1].
    Marble {
        /// Frequency.
        scale: Positive,
        /// Octaves of the turbulence, 1 to [`MAX_OCTAVES`] (default 7).
        #[serde(default = "seven", deserialize_with = "octaves")]
        depth: u32,
        /// Colour of the veins' bright parts (default white).
        #[serde(default = "white")]
        color: Rgb,
    },
}

fn seven() -> u32 {
    7
}

/// The most octaves of turbulence: the 25th would weigh 2^-24 of the first, below what an f32
/// sum keeps (and a depth of billions made one texture lookup run for minutes).
pub const MAX_OCTAVES: u32 = 24;

fn octaves<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let n = u32::deserialize(d)?;
    match (1..=MAX_OCTAVES).contains(&n) {
        true => Ok(n),
        false => Err(D::Error::custom(format!("expected 1 to {MAX_OCTAVES} octaves, found {n}"))),
    }
}

/// The `textures: { "name": Texture(..), .. }` map, in file order; names are unique.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NamedTextures(pub Vec<(String, TextureDesc)>);

impl<'de> Deserialize<'de> for NamedTextures {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = NamedTextures;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map from texture names to textures")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out: Vec<(String, TextureDesc)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if out.iter().any(|(n, _)| *n == name) {
                        return Err(A::Error::custom(format!("texture \"{name}\" is defined twice")));
                    }
                    // Inside a texture, only the textures before it may be named (no cycles).
                    context::set_textures_before(Some(out.len()));
                    let t = map.next_value();
                    context::set_textures_before(None);
                    out.push((name, t?));
                }
                Ok(NamedTextures(out))
            }
        }
        d.deserialize_map(V)
    }
}
