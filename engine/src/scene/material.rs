//! `materials: { .. }` and the references to them: each name checked against the scene's
//! materials (and, for `emit` keys, its emitters) where it is written.

use crate::format::context;
pub use crate::material::MaterialDesc;
use serde::{Deserialize, Deserializer, de::Error};

/// The `materials: { "name": Material(..), .. }` map, in file order; names are unique.
#[derive(Debug, Clone, Default)]
pub struct NamedMaterials(pub Vec<(String, MaterialDesc)>);

impl NamedMaterials {
    /// (name, material) pairs in file order.
    pub fn iter(&self) -> impl Iterator<Item = &(String, MaterialDesc)> {
        self.0.iter()
    }
}

impl<'de> Deserialize<'de> for NamedMaterials {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = NamedMaterials;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map from material names to materials")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out: Vec<(String, MaterialDesc)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if out.iter().any(|(n, _)| *n == name) {
                        return Err(A::Error::custom(format!("material \"{name}\" is defined twice")));
                    }
                    context::set_materials_before(Some(out.len()));
                    let m = map.next_value();
                    context::set_materials_before(None);
                    out.push((name, m?));
                }
                Ok(NamedMaterials(out))
            }
        }
        d.deserialize_map(V)
    }
}

pub use crate::format::MaterialRef;

/// The name of a `DiffuseLight` material.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LightRef(pub String);

impl<'de> Deserialize<'de> for LightRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let MaterialRef(name) = MaterialRef::deserialize(d)?;
        context::names(|n| match n.map(|n| &n.lights) {
            Some(lights) if !lights.contains(&name) => Err(D::Error::custom(format!(
                "material \"{name}\" is not a DiffuseLight: only emitters have `emit` keys"
            ))),
            _ => Ok(LightRef(name.clone())),
        })
    }
}
