//! The README's reference tables cannot fall behind the registries: every registered kind a
//! scene can write has a row whose first cell is `` `Kind(param, ...)` ``, naming each of the
//! kind's parameters, and whose second cell is the doc comment of the kind's description type,
//! as Mitsuba's plugin pages come from the plugins' own comments. The kinds and their parameters
//! are read from the scene format's own `Deserialize` impls (the names the parser accepts), so a
//! kind added to a registry, or a parameter added to a kind, fails here until the README
//! describes it; the doc comments are found by following each kind's line in its registry to its
//! type's file. `PATHWAVE_BLESS=1 cargo test --release --test readme_kinds` rewrites the rows
//! from the doc comments (as rust-analyzer's `sourcegen` tests and clippy's lint list do).

use pathwave::engine::material::MaterialDesc;
use pathwave::engine::scene::{LightDesc, ShapeDesc, TextureDesc};
use serde::de::{self, DeserializeSeed, Deserializer, EnumAccess, MapAccess, VariantAccess, Visitor};
use std::fmt;
use std::path::Path;

/// The registries whose kinds the README describes: the name of the list for messages, its
/// kinds with their parameters, and where the lists that name each kind's type are (a file and
/// the line that opens the list: the registry's invocation, and the lists beside it). A registry
/// is one line here.
fn registries() -> Vec<Registry> {
    let registry = |name, kinds, lists| Registry { name, kinds, lists };
    vec![
        registry(
            "materials",
            kinds::<MaterialDesc>(),
            &[
                ("engine/src/material/mod.rs", "registry! {"),
                ("engine/src/material/wrap/desc.rs", "pub enum WrapDesc {"),
            ],
        ),
        registry(
            "shapes",
            kinds::<ShapeDesc>(),
            &[
                ("engine/src/shape/mod.rs", "macro_rules! with_shapes {"),
                ("engine/src/scene/object/shape.rs", "registry! {"),
            ],
        ),
        registry("lights", kinds::<LightDesc>(), &[("engine/src/lighting/punctual/mod.rs", "registry! {")]),
        registry("textures", kinds::<TextureDesc>(), &[("engine/src/texture/mod.rs", "registry! {")]),
    ]
}

/// A registry's kinds and where their lists are.
struct Registry {
    name: &'static str,
    kinds: Vec<Kind>,
    lists: &'static [(&'static str, &'static str)],
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
    let all: Vec<Kind> = registries().into_iter().flat_map(|r| r.kinds).collect();
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

/// The README's rows of the kinds are the kinds' doc comments; with `PATHWAVE_BLESS=1` this
/// writes them into README.md (replacing the file at once: a temporary file, then a rename).
#[test]
fn the_readme_rows_are_the_kinds_doc_comments() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let expected = match with_rows(&readme, &source) {
        Ok(expected) => expected,
        Err(problems) => panic!("README.md's rows of kinds:\n{}", problems.join("\n")),
    };
    if expected == readme {
        return;
    }
    if std::env::var("PATHWAVE_BLESS").is_ok_and(|v| v == "1") {
        let temporary = path.with_extension("md.bless");
        std::fs::write(&temporary, &expected).unwrap();
        std::fs::rename(&temporary, &path).unwrap();
        return;
    }
    let mut differ = differences(&readme, &expected);
    if differ.is_empty() {
        differ.push("the rows are alike; the file's line endings or its last newline differ".into());
    }
    panic!(
        "README.md's rows of kinds are not their doc comments (PATHWAVE_BLESS=1 writes them):\n{}",
        differ.join("\n")
    );
}

/// A default changed in a doc comment changes the row that the README must have, and the rows
/// follow the doc comments' text: the trailing full stop dropped, intra-doc links as plain code.
/// (Injected: rows rendered with the full stop kept, and `[`..`]` kept: both failed here.)
#[test]
fn a_changed_doc_comment_changes_the_expected_row() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let changed = |path: &str| {
        let text = source(path)?;
        Some(match path {
            "engine/src/material/lambertian.rs" => text.replace("(default true)", "(default false)"),
            "engine/src/texture/turbulence.rs" => {
                text.replace("(1 to 24, default 7)", "(1 to 24, default 8)")
            }
            "engine/src/lighting/punctual/point.rs" => {
                text.replace("/// An isotropic point light", "/// An isotropic [`PunctualLight`]")
            }
            _ => text,
        })
    };
    let expected = with_rows(&readme, &changed).unwrap();
    let differ = differences(&readme, &expected);
    assert_eq!(differ.len(), 6, "{differ:#?}");
    assert_eq!(differ[0], "materials: `Lambertian`'s row differs from its doc comment; expected:");
    assert!(differ[1].starts_with("| `Lambertian(albedo, two_sided)` | Diffuse; albedo components"));
    assert!(
        differ[1].contains("`two_sided: false` (default false)")
            && differ[1].ends_with("its back ends there) |")
    );
    assert_eq!(differ[2], "lights: `Point`'s row differs from its doc comment; expected:");
    assert!(
        differ[3]
            .starts_with("| `Point(position, intensity)` | An isotropic `PunctualLight` in `lights: [..]`")
    );
    assert_eq!(differ[4], "textures: `Turbulence`'s row differs from its doc comment; expected:");
    assert!(differ[5].contains("(1 to 24, default 8)"), "{}", differ[5]);
    // The marble's text has the same words, in its own file: its row is unchanged.
    assert!(!differ.iter().any(|d| d.contains("`Marble")));
}

/// A row edited by hand fails, a missing row or rows out of registry order are written back by
/// blessing, and rows scattered through the table are refused (a blessing would not know where
/// the kinds' rows go).
#[test]
fn a_row_edited_by_hand_fails_and_blessing_restores_it() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let edited =
        readme.replace("| `Metal(albedo, fuzz)` | Mirror scaled", "| `Metal(albedo, fuzz)` | Mirror tinted");
    assert_ne!(edited, readme);
    let restored = with_rows(&edited, &source).unwrap();
    assert_eq!(
        differences(&edited, &restored)[0],
        "materials: `Metal`'s row differs from its doc comment; expected:"
    );
    assert_eq!(restored, readme);

    let lines: Vec<&str> = readme.lines().collect();
    let sphere = lines.iter().position(|l| l.starts_with("| `Sphere(")).unwrap();
    let without_sphere: String =
        lines.iter().filter(|l| !l.starts_with("| `Sphere(")).map(|l| format!("{l}\n")).collect();
    assert_eq!(
        differences(&without_sphere, &with_rows(&without_sphere, &source).unwrap()),
        ["shapes: `Sphere` has no row; expected:", lines[sphere]]
    );
    assert_eq!(with_rows(&without_sphere, &source).unwrap(), readme);

    let mut swapped = lines.clone();
    let point = lines.iter().position(|l| l.starts_with("| `Point(")).unwrap();
    swapped.swap(point, point + 1);
    let swapped: String = swapped.iter().map(|l| format!("{l}\n")).collect();
    assert_eq!(
        differences(&swapped, &with_rows(&swapped, &source).unwrap()),
        ["lights: the rows are not in registry order"]
    );
    assert_eq!(with_rows(&swapped, &source).unwrap(), readme);

    let mut scattered = lines.clone();
    let spot = scattered.remove(point + 1);
    scattered.insert(point - 1, spot);
    let scattered: String = scattered.iter().map(|l| format!("{l}\n")).collect();
    let refused = with_rows(&scattered, &source).unwrap_err();
    assert_eq!(refused.len(), 1);
    assert!(refused[0].starts_with("lights: the rows of its kinds are not together"), "{refused:?}");
}

/// The file at `path` (from the repository's root), if there is one.
fn source(path: &str) -> Option<String> {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).ok()
}

/// `readme` with the rows of each registry's kinds rendered from their doc comments (read by
/// `source`), in registry order where the README has them (the lines from its first kind's row
/// to its last, all rows of its kinds), or what stops that.
fn with_rows(readme: &str, source: &dyn Fn(&str) -> Option<String>) -> Result<String, Vec<String>> {
    let mut lines: Vec<String> = readme.lines().map(str::to_owned).collect();
    let mut problems = Vec::new();
    for registry in registries() {
        let mut rows = Vec::new();
        for kind in &registry.kinds {
            match reference(kind.name, registry.lists, source) {
                Ok(doc) => rows.push(row(kind, &doc)),
                Err(e) => problems.push(format!("{}: `{}`: {e}", registry.name, kind.name)),
            }
        }
        let owned: Vec<usize> = (0..lines.len())
            .filter(|&i| registry.kinds.iter().any(|k| lines[i].starts_with(&format!("| `{}(", k.name))))
            .collect();
        match (owned.first(), owned.last()) {
            (Some(&first), Some(&last)) if last - first + 1 == owned.len() => {
                lines.splice(first..=last, rows);
            }
            (Some(_), Some(_)) => problems.push(format!(
                "{}: the rows of its kinds are not together (README.md lines {})",
                registry.name,
                owned.iter().map(|i| (i + 1).to_string()).collect::<Vec<_>>().join(", ")
            )),
            _ => {
                problems.push(format!("{}: README.md has no row of its kinds to put them at", registry.name))
            }
        }
    }
    match problems.is_empty() {
        true => Ok(lines.iter().map(|l| format!("{l}\n")).collect()),
        false => Err(problems),
    }
}

/// How `readme`'s rows of kinds differ from `expected`'s: each kind whose row differs or is
/// missing, with its expected row, or a registry whose rows are out of order.
fn differences(readme: &str, expected: &str) -> Vec<String> {
    let mut differ = Vec::new();
    for registry in registries() {
        let row_of = |text: &str, name: &str| {
            text.lines().find(|l| l.starts_with(&format!("| `{name}("))).map(str::to_owned)
        };
        let mut any = false;
        for kind in &registry.kinds {
            let want = row_of(expected, kind.name).unwrap();
            match row_of(readme, kind.name) {
                Some(have) if have == want => continue,
                Some(_) => differ.push(format!(
                    "{}: `{}`'s row differs from its doc comment; expected:",
                    registry.name, kind.name
                )),
                None => differ.push(format!("{}: `{}` has no row; expected:", registry.name, kind.name)),
            }
            differ.push(want);
            any = true;
        }
        let order = |text: &str| {
            let mut at: Vec<(usize, &str)> = registry
                .kinds
                .iter()
                .filter_map(|k| {
                    text.lines().position(|l| l.starts_with(&format!("| `{}(", k.name))).map(|i| (i, k.name))
                })
                .collect();
            at.sort();
            at.into_iter().map(|(_, name)| name).collect::<Vec<_>>()
        };
        if !any && order(readme) != order(expected) {
            differ.push(format!("{}: the rows are not in registry order", registry.name));
        }
    }
    differ
}

/// The README row of `kind`: `` | `Kind(params)` | reference | `` (`Kind(..)` for a kind that
/// is one unnamed value). The reference is its doc comment as one line, without its last full
/// stop (the table's rows have none), intra-doc links written as plain code.
fn row(kind: &Kind, doc: &[String]) -> String {
    let params = match kind.params.is_empty() {
        true => "..".to_owned(),
        false => kind.params.join(", "),
    };
    let text = doc.iter().map(|l| l.trim()).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" ");
    let text = text.strip_suffix('.').unwrap_or(&text).replace("[`", "`").replace("`]", "`");
    format!("| `{}({params})` | {text} |", kind.name)
}

/// The doc comment (its lines after `///`) of the description type of the kind `name`: the type
/// its line in `lists` (files and the lines that open their lists) names (`Name(path::Type),`),
/// or the one its own reader reads (`Name(Type) = read_name,`: the first `fields::<Type` in `fn
/// read_name` of the list's file; a reader from elsewhere, as `value`, reads the type named), or
/// that type's `type Desc` (a material's or a shape's description beside its runtime form).
fn reference(
    name: &str,
    lists: &[(&str, &str)],
    source: &dyn Fn(&str) -> Option<String>,
) -> Result<Vec<String>, String> {
    let read = |path: &str| source(path).ok_or(format!("no file {path}"));
    for &(list, opening) in lists {
        let text = read(list)?;
        // The list: from its opening line to the end of the item (a `}` alone).
        let mut lines =
            text.lines().skip_while(|l| !l.trim_start().starts_with(opening)).take_while(|l| *l != "}");
        let Some((ty, reader)) = lines.find_map(|l| kind_line(l.trim(), name)) else { continue };
        // A reader of the list's file reads the kind's fields into its description type.
        let own = reader.and_then(|r| text.split(&format!("fn {r}<")).nth(1)?.split("fields::<").nth(1));
        let (file, ty) = match own {
            Some(read_ty) => (list.to_owned(), read_ty.split([',', '>']).next().unwrap().trim().to_owned()),
            None => {
                let mut module = list.to_owned();
                let mut path: Vec<&str> = ty.split("::").collect();
                let ty = path.pop().unwrap().to_owned();
                for m in path {
                    module = match m {
                        "$crate" => format!("{}src/lib.rs", &list[..list.find("src/").unwrap()]),
                        _ => submodule(&module, m, source)?,
                    }
                }
                (defining(&module, &ty, source)?, ty)
            }
        };
        let text = read(&file)?;
        let desc = text
            .split(&format!(" for {ty} {{\n"))
            .nth(1)
            .and_then(|body| body.split("\n}").next()?.split("type Desc = ").nth(1)?.split(';').next())
            .unwrap_or(&ty);
        return doc_comment(&text, desc).ok_or(format!("no doc comment on the type {desc} in {file}"));
    }
    let files: Vec<&str> = lists.iter().map(|(f, _)| *f).collect();
    Err(format!("no line `{name}(Type),` in the lists of {}", files.join(" or ")))
}

/// The type and the reader of `line` if it is `name`'s line in a list of kinds: `Name(Type),` or
/// `Name(Type) = reader,`.
fn kind_line<'a>(line: &'a str, name: &str) -> Option<(&'a str, Option<&'a str>)> {
    let (ty, rest) = line.strip_prefix(name)?.strip_prefix('(')?.split_once(')')?;
    let path = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_alphanumeric() || "_:$".contains(c));
    let reader = match rest.strip_suffix(',')? {
        "" => None,
        own => Some(own.strip_prefix(" = ").filter(|r| path(r))?),
    };
    path(ty).then_some((ty, reader))
}

/// The file of the module `m` declared in the module file `parent`.
fn submodule(parent: &str, m: &str, source: &dyn Fn(&str) -> Option<String>) -> Result<String, String> {
    let dir = match parent.rsplit_once('/') {
        Some((dir, "mod.rs" | "lib.rs")) => dir.to_owned(),
        _ => parent.strip_suffix(".rs").unwrap().to_owned(),
    };
    [format!("{dir}/{m}.rs"), format!("{dir}/{m}/mod.rs")]
        .into_iter()
        .find(|f| source(f).is_some())
        .ok_or(format!("no file for the module {m} of {parent}"))
}

/// The file that defines the type `ty` named in the module file `module`: that file, or the one
/// of the submodule it re-exports `ty` from (`pub use sub::{.., Type, ..};`).
fn defining(module: &str, ty: &str, source: &dyn Fn(&str) -> Option<String>) -> Result<String, String> {
    let text = source(module).ok_or(format!("no file {module}"))?;
    if definition(&text, ty).is_some() {
        return Ok(module.to_owned());
    }
    let from = text.split("pub use ").skip(1).find_map(|u| {
        let (m, names) = u.split(';').next()?.split_once("::")?;
        names.split(|c: char| !(c.is_alphanumeric() || c == '_')).any(|n| n == ty).then_some(m)
    });
    match from {
        Some(m) => defining(&submodule(module, m, source)?, ty, source),
        None => Err(format!("{module} neither defines nor re-exports {ty}")),
    }
}

/// The line of `text` that defines the struct or enum `ty`.
fn definition(text: &str, ty: &str) -> Option<usize> {
    text.lines().position(|l| {
        let l = l.trim_start();
        let l = l.strip_prefix("pub(crate) ").or(l.strip_prefix("pub ")).unwrap_or(l);
        let rest = l.strip_prefix("struct ").or(l.strip_prefix("enum ")).and_then(|r| r.strip_prefix(ty));
        rest.is_some_and(|r| !r.starts_with(|c: char| c.is_alphanumeric() || c == '_'))
    })
}

/// The doc comment above the definition of `ty` in `text` (above its attributes), a line each.
fn doc_comment(text: &str, ty: &str) -> Option<Vec<String>> {
    let lines: Vec<&str> = text.lines().collect();
    let mut above = lines[..definition(text, ty)?].iter().rev().map(|l| l.trim());
    let doc: Vec<String> = above
        .by_ref()
        .skip_while(|l| l.starts_with("#["))
        .map_while(|l| l.strip_prefix("///"))
        .map(str::to_owned)
        .collect();
    (!doc.is_empty()).then(|| doc.into_iter().rev().collect())
}

/// What is wrong with `readme`'s rows, one line each.
fn missing(readme: &str) -> Vec<String> {
    let mut problems = Vec::new();
    for Registry { name: list, kinds, .. } in registries() {
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
