//! Mitsuba's texture plugins as pathwave's textures: `checkerboard` as a `UvChecker`, `bitmap`
//! as an `Image` (with its `to_uv` as a `uv_transform`), read as a colour or as a number, each
//! converted once.

use super::{Converter, num, num32, v3};
use crate::scene::SceneError;
use crate::scene::mitsuba::props::{Op, Plugin, Value, compose};
use crate::scene::mitsuba::xml::Element;
use glam::DVec3;
use std::fmt::Write;

impl<'d> Converter<'d> {
    /// The name of the texture an element (or `<ref>`) becomes, converting it once.
    pub fn texture(&mut self, e: &'d Element) -> Result<String, SceneError> {
        self.texture_as(e, Read::Color)
    }

    /// The name of the RON texture for a `<texture>` element read where a number belongs
    /// (Mitsuba's `eval_1`), converted on first use.
    pub fn float_texture(&mut self, e: &'d Element) -> Result<String, SceneError> {
        self.texture_as(e, Read::Float)
    }

    fn texture_as(&mut self, e: &'d Element, read: Read) -> Result<String, SceneError> {
        let e = self.referenced(e)?;
        if e.tag != "texture" {
            return Err(e.at.error(format!("<{}> where a texture or colour belongs", e.tag)));
        }
        // A checkerboard read as a number has its colours the other way round (see `texture`):
        // another RON texture.
        let float = read == Read::Float && Plugin::new(e)?.kind == "checkerboard";
        let key = match e.attr("id") {
            Some(id) => format!("texture {id}"),
            None => format!("texture {}:{}:{}", e.at.file.display(), e.at.line, e.at.col),
        } + if float { " as float" } else { "" };
        if let Some(name) = self.named.get(&key) {
            return Ok(name.clone());
        }
        let ron = texture(self, e, read)?;
        let name = match e.attr("id") {
            Some(id) if float => format!("{id}-float"),
            Some(id) => id.to_owned(),
            None => format!("{}-{}", Plugin::new(e)?.kind, self.out.textures.len()),
        };
        self.out.textures.push((name.clone(), ron, e.at.clone()));
        self.named.insert(key, name.clone());
        Ok(name)
    }
}

/// A `<texture>` as a pathwave texture.
/// How a material reads a texture: as a colour (Mitsuba's `eval`) or a number (`eval_1`).
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Read {
    /// A colour.
    Color,
    /// A number.
    Float,
}

fn texture(cx: &Converter, e: &Element, read: Read) -> Result<String, SceneError> {
    let p = Plugin::new(e)?;
    match p.kind.as_str() {
        // Mitsuba's checkerboard (`src/textures/checkerboard.cpp`): of the uv after `to_uv`,
        // color0 where the fractional parts of u and v are both below 1/2 or both above, i.e.
        // where floor(2 u) + floor(2 v) is even: a 2 by 2 UvChecker of Mitsuba's uv. Read as a
        // number (`eval_1`, which tests `neq` where `eval` tests `eq`), color0 is where they
        // differ: the colours swap.
        "checkerboard" => {
            let c0 = p.rgb("color0")?.unwrap_or(DVec3::splat(0.4));
            let c1 = p.rgb("color1")?.unwrap_or(DVec3::splat(0.2));
            let (c0, c1) = if read == Read::Float { (c1, c0) } else { (c0, c1) };
            let to_uv = p.transform("to_uv")?.unwrap_or_default();
            p.finish(&["color0", "color1", "to_uv"])?;
            let [a, b] = to_uv_rows(&to_uv);
            // Mitsuba's uv is (u, 1 - v) of pathwave's: to_uv after that flip.
            let m = [[a[0], -a[1], a[1] + a[2]], [b[0], -b[1], b[1] + b[2]]];
            Ok(format!(
                "UvChecker(u: 2, v: 2, even: {}, odd: {}, uv_transform: {})",
                v3(c0),
                v3(c1),
                uv_transform(m)
            ))
        }
        "bitmap" => bitmap(cx, &p),
        // Mitsuba's rawconstant (`src/textures/constant.cpp`'s raw twin): a value used as it
        // is, as a normal map's normal.
        "rawconstant" => {
            let v = match p.param("value").map(|q| &q.value) {
                Some(Value::Float(f)) => DVec3::splat(*f),
                _ => p.vector("value")?.ok_or_else(|| p.at.error("<texture type=\"rawconstant\"> needs a value"))?,
            };
            p.finish(&["value"])?;
            Ok(format!("Solid({})", v3(v)))
        }
        "mesh_attribute" => {
            let (name, at) = p
                .string("name")?
                .ok_or_else(|| p.at.error("<texture type=\"mesh_attribute\"> needs a name"))?;
            if !(name.starts_with("vertex_") || name.starts_with("face_")) {
                return Err(
                    at.error(format!("mesh attribute \"{name}\": its name starts with vertex_ or face_"))
                );
            }
            let scale = p.float("scale")?.unwrap_or(1.0);
            if !(scale >= 0.0) {
                return Err(p.at.error(format!("mesh_attribute scale {scale}: expected >= 0")));
            }
            p.finish(&["name", "scale"])?;
            Ok(format!("MeshAttribute(name: {name:?}, scale: {})", num(scale)))
        }
        k => Err(p.at.error(format!(
            "<texture type=\"{k}\">: pathwave reads checkerboard, bitmap, rawconstant and mesh_attribute textures from XML so far"
        ))),
    }
}

/// Mitsuba's `to_uv` as the rows of a 2-D affine map, as its `Transform::extract` makes one of
/// a 4 x 4 (`include/mitsuba/core/transform.h`: the upper-left 2 x 2 and the first two
/// entries of the last column).
fn to_uv_rows(to_uv: &[Op]) -> [[f64; 3]; 2] {
    let m = compose(to_uv);
    [[m.x_axis.x, m.y_axis.x, m.w_axis.x], [m.x_axis.y, m.y_axis.y, m.w_axis.y]]
}

/// A uv transform as RON writes it: `((a, b, c), (d, e, f))` (a negated zero written 0).
fn uv_transform(m: [[f64; 3]; 2]) -> String {
    let row = |r: [f64; 3]| format!("({}, {}, {})", num32(r[0] + 0.0), num32(r[1] + 0.0), num32(r[2] + 0.0));
    format!("({}, {})", row(m[0]), row(m[1]))
}

/// Mitsuba's `bitmap` texture (`src/textures/bitmap.cpp`) as an `Image`. Its lookups are
/// pathwave's: bilinear between texel centres at ((i + 0.5) / width, (j + 0.5) / height) of
/// Mitsuba's uv, or the texel that uv * size falls in (`nearest`); `repeat`, `mirror` and
/// `clamp` wrap texel indices; 8-bit files are sRGB-decoded per texel before interpolating
/// (Mitsuba decodes its 8-bit storage on each lookup, pathwave once at load: the same values
/// but for rounding), unless `raw`. Mitsuba's v is 1 - pathwave's, and its image rows run
/// down its v where pathwave's run down from v = 1: the lookups agree, and `to_uv` is written
/// between the two flips.
fn bitmap(cx: &Converter, p: &Plugin) -> Result<String, SceneError> {
    let (name, at) =
        p.string("filename")?.ok_or_else(|| p.at.error("<texture type=\"bitmap\"> needs a filename"))?;
    let file = cx.file(&name, &at)?;
    let filter = match p.string("filter_type")? {
        None => "Bilinear",
        Some((f, _)) if f == "bilinear" => "Bilinear",
        Some((f, _)) if f == "nearest" => "Nearest",
        Some((f, at)) => {
            return Err(
                at.error(format!("filter_type \"{f}\": Mitsuba's bitmap filters are bilinear and nearest"))
            );
        }
    };
    let wrap = match p.string("wrap_mode")? {
        None => "Repeat",
        Some((w, _)) if w == "repeat" => "Repeat",
        Some((w, _)) if w == "mirror" => "Mirror",
        Some((w, _)) if w == "clamp" => "Clamp",
        Some((w, at)) => {
            return Err(
                at.error(format!("wrap_mode \"{w}\": Mitsuba's bitmap wraps are repeat, mirror and clamp"))
            );
        }
    };
    let raw = p.bool("raw")?.unwrap_or(false);
    // pathwave keeps texels as 32-bit floats: Mitsuba's `variant` storage, and its `auto` but
    // for rounding (8-bit codes decoded once, 16-bit files read through 8 bits).
    if let Some((f, at)) = p.string("format")?
        && f != "auto"
        && f != "variant"
    {
        return Err(at.error(format!(
            "format \"{f}\": pathwave stores textures as 32-bit floats (Mitsuba's auto or variant)"
        )));
    }
    // Hardware interpolation on CUDA; on the CPU Mitsuba interpolates as pathwave does.
    p.bool("accel")?;
    let to_uv = p.transform("to_uv")?.unwrap_or_default();
    p.finish(&["filename", "filter_type", "wrap_mode", "raw", "format", "accel", "to_uv"])?;
    let mut out = format!("Image(file: {file}, wrap: {wrap}, filter: {filter}");
    if raw {
        out += ", raw: true";
    }
    let [a, b] = to_uv_rows(&to_uv);
    if [a, b] != [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        // (u, v) -> (u, 1 - v), to_uv, (u, v) -> (u, 1 - v).
        let m = [[a[0], -a[1], a[1] + a[2]], [-b[0], b[1], 1.0 - b[1] - b[2]]];
        write!(out, ", uv_transform: {}", uv_transform(m)).unwrap();
    }
    Ok(out + ")")
}
