//! What the registries of shapes, lights and textures share: one list of kinds,
//! `Variant(Type)`, becomes the enum of what a scene writes (`Kind(field: value, ...)`), an enum
//! naming the kinds, and the `Deserialize` impl that reads a kind by its name. Each registry
//! invokes [`registry!`] once, in the module of its kinds; a kind is a type in its own file.
//! Materials have a macro of their own (`material/mod.rs`: it also generates the runtime enum
//! the integrators read and its dispatch) that reads a kind with the same [`VariantName`] and
//! [`fields`].
//!
//! A kind is read after its name by a function of the form of [`fields`] (named fields, the
//! default) or [`value`] (one unnamed value, `Solid((r, g, b))`), or by the registry's own
//! (a shape checks its fields once they are all read, so that its error points at the `)`
//! that closes it, as serde's `try_from` did).

use serde::Deserialize;
use serde::de::VariantAccess;
use std::marker::PhantomData;

/// The name of a kind as the scene writes it (an identifier).
pub struct VariantName(pub String);

impl<'de> Deserialize<'de> for VariantName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Name;
        impl serde::de::Visitor<'_> for Name {
            type Value = VariantName;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("the name of a kind")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<VariantName, E> {
                Ok(VariantName(v.to_owned()))
            }
        }
        d.deserialize_identifier(Name)
    }
}

/// Reads a kind's named fields, `Kind(field: value, ...)`, into `T` (a struct that denies
/// unknown fields, so that a misspelt one is refused with the names it has).
pub fn fields<'de, T: Deserialize<'de>, A: VariantAccess<'de>>(variant: A) -> Result<T, A::Error> {
    variant.struct_variant(&[], Fields::<T>(PhantomData))
}

/// Reads a kind's one unnamed value, `Kind(value)`, as `T`.
pub fn value<'de, T: Deserialize<'de>, A: VariantAccess<'de>>(variant: A) -> Result<T, A::Error> {
    variant.newtype_variant()
}

/// Reads a kind's fields into its description type.
struct Fields<T>(PhantomData<T>);

impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Fields<T> {
    type Value = T;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("the kind's fields")
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
        T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
    }
}

/// Generates, from one list of kinds, the enum of their descriptions, the enum of their names
/// and the `Deserialize` impl:
///
/// ```ignore
/// registry! {
///     /// Doc of the enum.
///     #[derive(Debug, Clone)]
///     pub enum LightDesc, LightKind: dyn LightModel, "Light", "a light such as ..", fields {
///         Point(point::Point),
///         #[cfg(feature = "test-light")]
///         TestPoint(test_point::TestPoint),
///     }
/// }
/// ```
///
/// Each variant holds its type; `fields` (or another function of its form) reads it after its
/// name, unless its line names its own (`Mesh(MeshFile) = read_mesh`). Every type implements
/// the trait after `dyn`, which [`model`](#method.model) returns for dispatch. `"Light"` is the
/// enum's name in parser messages.
macro_rules! registry {
    (
        $(#[$meta:meta])*
        pub enum $desc:ident, $kind:ident: dyn $model:path, $serde_name:literal, $expecting:literal, $read:ident {
            $($(#[$attr:meta])* $variant:ident($ty:ty) $(= $own:ident)?,)+
        }
    ) => {
        $(#[$meta])*
        pub enum $desc {
            $($(#[$attr])* #[doc = concat!("`", stringify!($variant), "(..)`: see [`", stringify!($ty), "`].")]
            $variant($ty),)+
        }

        /// The registered kinds, in registry order.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $kind {
            $($(#[$attr])* #[doc = concat!("`", stringify!($variant), "(..)`.")] $variant,)+
        }

        impl $kind {
            /// Every kind, in registry order.
            pub const ALL: &'static [$kind] = &[$($(#[$attr])* $kind::$variant,)+];

            /// The names a scene may write, in registry order.
            pub const NAMES: &'static [&'static str] = &[$($(#[$attr])* stringify!($variant),)+];

            /// The name a scene writes.
            pub const fn variant_name(self) -> &'static str {
                match self {
                    $($(#[$attr])* $kind::$variant => stringify!($variant),)+
                }
            }
        }

        impl $desc {
            /// Its kind.
            pub fn kind(&self) -> $kind {
                match self {
                    $($(#[$attr])* $desc::$variant(_) => $kind::$variant,)+
                }
            }

            /// The kind's description, for dispatch.
            pub fn model(&self) -> &dyn $model {
                match self {
                    $($(#[$attr])* $desc::$variant(k) => k,)+
                }
            }
        }

        impl<'de> serde::Deserialize<'de> for $desc {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct Kinds;
                impl<'de> serde::de::Visitor<'de> for Kinds {
                    type Value = $desc;
                    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                        f.write_str($expecting)
                    }
                    fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<$desc, A::Error> {
                        let ($crate::format::registry::VariantName(name), variant) = data.variant()?;
                        $($(#[$attr])* if name == stringify!($variant) {
                            let k: $ty = $crate::format::registry::pick!($($own)? $read)(variant)?;
                            return Ok($desc::$variant(k));
                        })+
                        Err(serde::de::Error::unknown_variant(&name, $kind::NAMES))
                    }
                }
                d.deserialize_enum($serde_name, $kind::NAMES, Kinds)
            }
        }
    };
}
pub(crate) use registry;

/// The first of one or two identifiers: a line's own reader, else the registry's.
macro_rules! pick {
    ($own:ident $default:ident) => {
        $own
    };
    ($default:ident) => {
        $default
    };
}
pub(crate) use pick;
