//! Colours and numbers that are either a value or the name of one of the scene's textures,
//! checked where they are written.

use super::context;
use serde::{Deserialize, Deserializer, de::Error};

/// A colour written out, or the name of a texture from `textures`.
#[derive(Debug, Clone, PartialEq)]
pub enum Color<T> {
    /// `(r, g, b)`.
    Value(T),
    /// `"name"`.
    Texture(String),
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Color<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for V<T> {
            type Value = Color<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a colour (r, g, b) or the name of a texture")
            }
            fn visit_str<E: Error>(self, name: &str) -> Result<Self::Value, E> {
                check_texture_name(name).map_err(E::custom)?;
                Ok(Color::Texture(name.to_owned()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
                T::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(Color::Value)
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}

/// A number written out, or the name of a texture from `textures` whose value at a hit stands
/// for it (its luminance, as Mitsuba's float textures read an RGB texture; see
/// `crate::texture::scalar`).
#[derive(Debug, Clone, PartialEq)]
pub enum Scalar<T> {
    /// `0.3`.
    Value(T),
    /// `"name"`.
    Texture(String),
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Scalar<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for V<T> {
            type Value = Scalar<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or the name of a texture")
            }
            fn visit_str<E: Error>(self, name: &str) -> Result<Self::Value, E> {
                check_texture_name(name).map_err(E::custom)?;
                Ok(Scalar::Texture(name.to_owned()))
            }
            fn visit_f64<E: Error>(self, v: f64) -> Result<Self::Value, E> {
                T::deserialize(serde::de::value::F64Deserializer::<E>::new(v)).map(Scalar::Value)
            }
            fn visit_i64<E: Error>(self, v: i64) -> Result<Self::Value, E> {
                T::deserialize(serde::de::value::I64Deserializer::<E>::new(v)).map(Scalar::Value)
            }
            fn visit_u64<E: Error>(self, v: u64) -> Result<Self::Value, E> {
                T::deserialize(serde::de::value::U64Deserializer::<E>::new(v)).map(Scalar::Value)
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}

/// Checks a texture name against the scene's textures (in the second parsing pass).
pub(crate) fn check_texture_name(name: &str) -> Result<(), String> {
    let before = context::textures_before();
    context::names(|n| match n.map(|n| &n.textures) {
        None => Ok(()),
        Some(names) => {
            let visible = &names[..before.unwrap_or(names.len()).min(names.len())];
            if visible.iter().any(|n| n == name) {
                Ok(())
            } else if before.is_some() && names.iter().any(|n| n == name) {
                Err(format!("texture \"{name}\" must be defined before the texture that uses it"))
            } else if visible.is_empty() {
                Err(format!("unknown texture \"{name}\"; no textures are defined before this point"))
            } else {
                let list: Vec<String> = visible.iter().map(|n| format!("\"{n}\"")).collect();
                Err(format!("unknown texture \"{name}\"; defined: {}", list.join(", ")))
            }
        }
    })
}
