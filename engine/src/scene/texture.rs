//! `textures: { .. }`: named textures, each naming only the textures before it (the kinds are
//! registered in `texture`).

use crate::format::context;
pub use crate::texture::turbulence::MAX_OCTAVES;
pub use crate::texture::{TextureDesc, TextureKind, TextureModel};
use serde::{Deserialize, Deserializer, de::Error};

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
