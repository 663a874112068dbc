//! The README's reference tables cannot fall behind the registries: every registered kind a
//! scene can write has a row whose first cell is `` `Kind(param, ...)` ``, naming each of the
//! kind's parameters. The kinds and their parameters are read from the scene format's own
//! `Deserialize` impls (the names the parser accepts), so a kind added to a registry, or a
//! parameter added to a kind, fails here until the README describes it.

use pathwave::engine::material::MaterialDesc;
use pathwave::engine::scene::{LightDesc, ShapeDesc, TextureDesc};
use serde::de::{self, DeserializeSeed, Deserializer, EnumAccess, MapAccess, VariantAccess, Visitor};
use std::fmt;

/// The registries whose kinds the README describes: the name of the list for messages, and its
/// kinds with their parameters. A registry is one line here.
fn registries() -> Vec<(&'static str, Vec<Kind>)> {
    vec![
        ("materials", kinds::<MaterialDesc>()),
        ("shapes", kinds::<ShapeDesc>()),
        ("lights", kinds::<LightDesc>()),
        ("textures", kinds::<TextureDesc>()),
    ]
}

#[test]
fn every_registered_kind_has_a_readme_row_naming_its_parameters() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let problems = missing(&readme);
    assert!(problems.is_empty(), "README.md's tables:\n{}", problems.join("\n"));
}

/// A README without a kind's row, or with a row that leaves out a parameter, is caught.
#[test]
fn a_missing_row_or_parameter_is_reported() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let without_metal: String =
        readme.lines().filter(|l| !l.starts_with("| `Metal(")).collect::<Vec<_>>().join("\n");
    assert_eq!(missing(&without_metal), ["materials: `Metal` has no row in README.md"]);
    let without_radius = readme.replace("| `Sphere(center, radius, poles)` |", "| `Sphere(center, poles)` |");
    assert_eq!(missing(&without_radius), ["shapes: `Sphere`'s row does not name `radius`"]);
    let without_spot: String =
        readme.lines().filter(|l| !l.starts_with("| `Spot(")).collect::<Vec<_>>().join("\n");
    assert_eq!(missing(&without_spot), ["lights: `Spot` has no row in README.md"]);
    let without_color = readme.replace("`Marble(scale, depth, color)`", "`Marble(scale, depth)`");
    assert_eq!(missing(&without_color), ["textures: `Marble`'s row does not name `color`"]);
}

/// The probe reads kinds and their parameters; the kinds registered only to test the registries
/// (the engine's `test-material`, `test-shape`, `test-light` and `test-texture` features, tested
/// in `tests/kinds/`) are not among the user's, so the README has no row for them.
#[test]
fn the_probe_finds_the_users_kinds_and_their_parameters() {
    let all: Vec<Kind> = registries().into_iter().flat_map(|(_, k)| k).collect();
    for name in ["TestDiffuse", "TestDisk", "TestPoint", "TestStripes"] {
        assert!(!all.iter().any(|k| k.name == name), "{name} is registered in the user's build");
    }
    let metal = all.iter().find(|k| k.name == "Metal").unwrap();
    assert_eq!(metal.params, ["albedo", "fuzz"]);
    let quad = all.iter().find(|k| k.name == "Quad").unwrap();
    assert_eq!(quad.params, ["q", "u", "v", "flip_normal"]);
    let mesh = all.iter().find(|k| k.name == "Mesh").unwrap();
    assert_eq!(
        mesh.params,
        ["file", "shape_index", "mesh", "primitive", "face_normals", "flip_normals", "flip_tex_coords"]
    );
    let spot = all.iter().find(|k| k.name == "Spot").unwrap();
    assert_eq!(
        spot.params,
        ["position", "look_at", "intensity", "cone_angle", "falloff_start", "falloff", "texture", "up"]
    );
    let marble = all.iter().find(|k| k.name == "Marble").unwrap();
    assert_eq!(marble.params, ["scale", "depth", "color"]);
    // `Solid((r, g, b))`: one unnamed value, no parameter to name.
    let solid = all.iter().find(|k| k.name == "Solid").unwrap();
    assert!(solid.params.is_empty());
}

/// What is wrong with `readme`'s rows, one line each.
fn missing(readme: &str) -> Vec<String> {
    let mut problems = Vec::new();
    for (list, kinds) in registries() {
        for kind in &kinds {
            match row_params(readme, kind.name) {
                None => problems.push(format!("{list}: `{}` has no row in README.md", kind.name)),
                Some(written) => {
                    for p in kind.params.iter().filter(|p| !written.contains(p)) {
                        problems.push(format!("{list}: `{}`'s row does not name `{p}`", kind.name));
                    }
                }
            }
        }
    }
    problems
}

/// The parameters written in the first cell of `name`'s table row (`` | `Name(a, b)` | ``, or
/// one of several forms in that cell).
fn row_params<'a>(readme: &'a str, name: &str) -> Option<Vec<&'a str>> {
    let open = format!("`{name}(");
    readme.lines().filter(|l| l.starts_with("| `")).find_map(|l| {
        let cell = l[1..].split(" | ").next()?;
        let start = cell.find(&open)? + open.len();
        let end = start + cell[start..].find(")`")?;
        Some(cell[start..end].split(',').map(str::trim).filter(|p| !p.is_empty()).collect())
    })
}

/// A kind a scene can write, `Name(params)`.
struct Kind {
    name: &'static str,
    params: Vec<&'static str>,
}

/// The kinds of the enum `T` as its `Deserialize` impl names them, each with the fields it
/// accepts: the variant names from `deserialize_enum`, and each variant's fields from
/// `struct_variant` or, for a variant holding a struct, from the error that struct's
/// `deny_unknown_fields` gives for a key it does not know (none for a variant holding one
/// unnamed value that is not a struct, as `Solid((r, g, b))`).
fn kinds<T: de::DeserializeOwned>() -> Vec<Kind> {
    let names = match T::deserialize(Probe::Enum) {
        Err(Learnt::Variants(v)) => v,
        other => panic!("not an enum: {:?}", other.err()),
    };
    names
        .iter()
        .map(|&name| match T::deserialize(Probe::Variant(name)) {
            Err(Learnt::Fields(params)) => Kind { name, params: params.to_vec() },
            other => panic!("{name}: no fields learnt ({:?})", other.err()),
        })
        .collect()
}

/// What a probe learnt (the error that ends every probe).
#[derive(Debug)]
enum Learnt {
    Variants(&'static [&'static str]),
    Fields(&'static [&'static str]),
    Other(String),
}

impl fmt::Display for Learnt {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Learnt::Other(message) => f.write_str(message),
            learnt => write!(f, "{learnt:?}"),
        }
    }
}

impl std::error::Error for Learnt {}

impl de::Error for Learnt {
    fn custom<M: fmt::Display>(msg: M) -> Self {
        Learnt::Other(msg.to_string())
    }
    fn unknown_field(_: &str, expected: &'static [&'static str]) -> Self {
        Learnt::Fields(expected)
    }
}

/// A deserializer that asks for an enum's variants, or for one variant's fields.
#[derive(Clone, Copy)]
enum Probe {
    Enum,
    Variant(&'static str),
}

/// A key that no kind has, whose refusal lists the keys the kind has.
const NO_SUCH_KEY: &str = "\u{1}no such key";

impl<'de> Deserializer<'de> for Probe {
    type Error = Learnt;
    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Learnt> {
        Err(Learnt::Other("only enums are probed".into()))
    }
    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Learnt> {
        match self {
            Probe::Enum => Err(Learnt::Variants(variants)),
            Probe::Variant(name) => visitor.visit_enum(Variant(name)),
        }
    }
    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf option
        unit unit_struct newtype_struct seq tuple tuple_struct map struct identifier ignored_any
    }
}

/// The variant `.0`, whose content tells its fields.
struct Variant(&'static str);

impl<'de> EnumAccess<'de> for Variant {
    type Error = Learnt;
    type Variant = Self;
    fn variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<(S::Value, Self), Learnt> {
        let name = seed.deserialize(de::value::StrDeserializer::<Learnt>::new(self.0))?;
        Ok((name, self))
    }
}

impl<'de> VariantAccess<'de> for Variant {
    type Error = Learnt;
    fn unit_variant(self) -> Result<(), Learnt> {
        Err(Learnt::Fields(&[]))
    }
    fn newtype_variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<S::Value, Learnt> {
        seed.deserialize(Unnamed)
    }
    fn tuple_variant<V: Visitor<'de>>(self, _: usize, _: V) -> Result<V::Value, Learnt> {
        Err(Learnt::Other(format!("{}: a tuple variant", self.0)))
    }
    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Learnt> {
        match fields {
            [] => visitor.visit_map(UnknownKey),
            _ => Err(Learnt::Fields(fields)),
        }
    }
}

/// A variant's one unnamed value: a struct is asked for its fields, anything else has none.
struct Unnamed;

impl<'de> Deserializer<'de> for Unnamed {
    type Error = Learnt;
    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Learnt> {
        Err(Learnt::Fields(&[]))
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        _: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Learnt> {
        visitor.visit_map(UnknownKey)
    }
    fn deserialize_map<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Learnt> {
        visitor.visit_map(UnknownKey)
    }
    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf option
        unit unit_struct newtype_struct seq tuple tuple_struct enum identifier ignored_any
    }
}

/// A map whose one key no struct knows.
struct UnknownKey;

impl<'de> MapAccess<'de> for UnknownKey {
    type Error = Learnt;
    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>, Learnt> {
        seed.deserialize(de::value::StrDeserializer::<Learnt>::new(NO_SUCH_KEY)).map(Some)
    }
    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, _: V) -> Result<V::Value, Learnt> {
        Err(Learnt::Other("a struct that ignores unknown fields".into()))
    }
}
