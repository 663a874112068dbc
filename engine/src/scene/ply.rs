//! PLY meshes (the Stanford Triangle Format; Turk, "The PLY Polygon File Format", 1994): ASCII
//! and binary of either byte order. The vertex element gives positions (`x y z`), normals
//! (`nx ny nz`) and uv (`u v`, `s t` or `texture_u texture_v`); the face element gives polygons
//! (`vertex_indices` or `vertex_index`, triangulated as fans); other elements are skipped.
//! A vertex's or face's other properties become mesh attributes as Mitsuba 3's PLY loader
//! groups them (`src/shapes/ply.h`, `find_other_fields`): `r g b` or `red green blue` are
//! `vertex_color` (or `face_color`), and consecutive properties `P_x P_y P_z`, `P_r P_g P_b`,
//! `P_0 P_1 P_2` or `P_1 P_2 P_3` (or one of them alone) are `vertex_P` (`vertex_P_color` for
//! the `r g b` suffixes); groups of other sizes are skipped with a warning. Integer attribute
//! values are, as Mitsuba reads them, scaled to [0, 1] (by the type's largest value) and taken
//! from sRGB to linear. As Mitsuba, uv are read as written: pathwave's v runs the other way, so
//! its XML reader flips them (`flip_tex_coords`).
//!
//! Hand-written: the `ply-rs` crate has had no release since 2020 and reads every element
//! into a map of its properties; the grouping needs their order and types, and every count here
//! is checked against the bytes the file has left before anything is allocated for it.

use crate::accel::mesh::MeshAttribute;
use std::path::Path;

/// The longest header read (bytes up to `end_header`).
const MAX_HEADER: usize = 1 << 20;

/// A scalar type of the format.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F16,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "long" | "int64" => Scalar::I64,
            "ulong" | "uint64" => Scalar::U64,
            "half" | "float16" => Scalar::F16,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 | Scalar::F16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// The largest value of an integer type (Mitsuba's normalisation), `None` for floats.
    fn integer_max(self) -> Option<f64> {
        Some(match self {
            Scalar::I8 => i8::MAX as f64,
            Scalar::U8 => u8::MAX as f64,
            Scalar::I16 => i16::MAX as f64,
            Scalar::U16 => u16::MAX as f64,
            Scalar::I32 => i32::MAX as f64,
            Scalar::U32 => u32::MAX as f64,
            Scalar::I64 => i64::MAX as f64,
            Scalar::U64 => u64::MAX as f64,
            Scalar::F16 | Scalar::F32 | Scalar::F64 => return None,
        })
    }
}

/// A property: one value, or a list of `count`-typed length followed by its items.
#[derive(Clone, Debug)]
struct Property {
    name: String,
    ty: Scalar,
    /// The type of the list's length, for a list.
    list: Option<Scalar>,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// The header: format, elements, and where the body starts.
fn header(bytes: &[u8], fail: &dyn Fn(String) -> String) -> Result<(Format, Vec<Element>, usize), String> {
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut at = 0;
    let mut first = true;
    loop {
        let rest = &bytes[at..];
        let Some(end) = rest.iter().position(|&b| b == b'\n') else {
            return Err(fail("the header has no end_header line".into()));
        };
        if at + end > MAX_HEADER {
            return Err(fail(format!("the header is longer than {MAX_HEADER} bytes")));
        }
        let line = std::str::from_utf8(&rest[..end]).map_err(|_| fail("the header is not text".into()))?;
        at += end + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        if first {
            if words != ["ply"] {
                return Err(fail("it does not start with the line \"ply\"".into()));
            }
            first = false;
            continue;
        }
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, "1.0"] if format.is_none() => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(fail(format!("unknown format \"{f}\""))),
                });
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| fail(format!("element {name}: count \"{count}\"")))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            ["property", rest @ ..] => {
                let Some(el) = elements.last_mut() else {
                    return Err(fail("a property before any element".into()));
                };
                let ty = |t: &str| Scalar::parse(t).ok_or_else(|| fail(format!("unknown type \"{t}\"")));
                let prop = match rest {
                    ["list", count, item, name] => {
                        Property { name: name.to_string(), ty: ty(item)?, list: Some(ty(count)?) }
                    }
                    [t, name] => Property { name: name.to_string(), ty: ty(t)?, list: None },
                    _ => return Err(fail(format!("cannot read the line \"{line}\""))),
                };
                if prop.list.is_some_and(|c| c.integer_max().is_none()) {
                    return Err(fail(format!("the list {}: its length is not an integer type", prop.name)));
                }
                el.props.push(prop);
            }
            ["end_header"] => break,
            _ => return Err(fail(format!("cannot read the header line \"{line}\""))),
        }
    }
    let format = format.ok_or_else(|| fail("the header has no \"format ... 1.0\" line".into()))?;
    Ok((format, elements, at))
}

/// Reads values from the body.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    format: Format,
}

impl Body<'_> {
    fn left(&self) -> usize {
        self.bytes.len() - self.at
    }

    /// The next value as `f64`, or `None` at the end or on a malformed one.
    fn value(&mut self, ty: Scalar) -> Option<f64> {
        if self.format == Format::Ascii {
            let rest = &self.bytes[self.at..];
            let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
            let len =
                rest[start..].iter().position(|b| b.is_ascii_whitespace()).unwrap_or(rest.len() - start);
            self.at += start + len;
            let word = std::str::from_utf8(&rest[start..start + len]).ok()?;
            let v = word.parse::<f64>().ok()?;
            // An integer type's value is a whole number.
            return (ty.integer_max().is_none() || v.fract() == 0.0).then_some(v);
        }
        let n = ty.size();
        let raw = self.bytes.get(self.at..self.at + n)?;
        self.at += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.format == Format::Big {
            b[..n].reverse();
        }
        Some(match ty {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::F16 => half_to_f32(u16::from_le_bytes([b[0], b[1]])) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::I64 => i64::from_le_bytes(b) as f64,
            Scalar::U64 => u64::from_le_bytes(b) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    /// The fewest bytes one record of `props` takes (an empty list, ASCII values of one
    /// character and a separator).
    fn min_record(&self, props: &[Property]) -> usize {
        let one = |p: &Property| match (self.format, p.list) {
            (Format::Ascii, _) => 2,
            (_, Some(count)) => count.size(),
            (_, None) => p.ty.size(),
        };
        props.iter().map(one).sum::<usize>().max(1)
    }
}

/// An IEEE half's bits as `f32`.
fn half_to_f32(h: u16) -> f32 {
    let (sign, exp, frac) = ((h >> 15) as u32, ((h >> 10) & 0x1f) as u32, (h & 0x3ff) as u32);
    let magnitude = match exp {
        0 => frac as f32 * (1.0 / (1 << 24) as f32),
        31 if frac == 0 => f32::INFINITY,
        31 => f32::NAN,
        _ => f32::from_bits(((exp + 112) << 23) | (frac << 13)),
    };
    if sign == 1 { -magnitude } else { magnitude }
}

/// Where each property of an element goes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    /// Ignored (read past).
    Skip,
    /// Position, normal or uv component `k` (0-2 position, 3-5 normal, 6-7 uv).
    Vertex(usize),
    /// The polygon's vertex indices.
    Indices,
    /// Channel `c` of attribute `a`.
    Attribute(usize, usize),
}

/// Mitsuba's grouping of an element's other properties into attributes named `prefix...`:
/// each property's slot and the attributes' names and channel counts.
fn group(
    prefix: &str,
    props: &[Property],
    reserved: &[&str],
    warn: &dyn Fn(String),
) -> (Vec<Slot>, Vec<(String, usize)>) {
    let mut slots = vec![Slot::Skip; props.len()];
    let mut attrs: Vec<(String, usize)> = Vec::new();
    let index = |n: &str| props.iter().position(|p| p.name == n && p.list.is_none());
    // r g b (or red green blue): the colour.
    let rgb = ["r", "g", "b"].map(index);
    let rgb = if rgb.iter().all(Option::is_some) { rgb } else { ["red", "green", "blue"].map(index) };
    if let [Some(r), Some(g), Some(b)] = rgb {
        for (c, i) in [r, g, b].into_iter().enumerate() {
            slots[i] = Slot::Attribute(attrs.len(), c);
        }
        attrs.push((format!("{prefix}color"), 3));
    }
    let mut g = Grouping { prefix, slots, attrs, seen: Vec::new(), current: None, warn };
    for (i, p) in props.iter().enumerate() {
        let taken = g.slots[i] != Slot::Skip
            || reserved.contains(&p.name.as_str())
            || ["r", "g", "b", "a", "red", "green", "blue", "alpha"].contains(&p.name.as_str());
        if taken {
            continue;
        }
        if p.list.is_some() {
            (g.warn)(format!("the list property {} is not read", p.name));
            g.flush();
            continue;
        }
        let Some((stem, post)) = p.name.rsplit_once('_').filter(|(_, post)| post.len() == 1) else {
            (g.warn)(format!(
                "the property {} is not an attribute (PREFIX_x, _r, _0 or _1): skipped",
                p.name
            ));
            g.flush();
            continue;
        };
        let c = post.as_bytes()[0];
        if let Some((name, family, members)) = &mut g.current {
            if name == stem {
                if POSTFIXES.get(members.len()).is_some_and(|f| f[*family] == c) {
                    members.push(i);
                } else {
                    (g.warn)(format!("the attribute {prefix}{stem}'s suffixes are out of sequence: skipped"));
                    g.current = None;
                    g.seen.push(stem.to_owned());
                }
                continue;
            }
            g.flush();
        }
        if g.seen.iter().any(|s| s == stem) {
            continue;
        }
        match POSTFIXES[0].iter().position(|&f| f == c) {
            Some(family) => g.current = Some((stem.to_owned(), family, vec![i])),
            None => (g.warn)(format!(
                "the attribute {prefix}{stem} starts with the suffix {}: skipped",
                c as char
            )),
        }
    }
    g.flush();
    (g.slots, g.attrs)
}

/// The suffixes of an attribute's values, by position (rows) and family (columns): x y z w,
/// r g b a, 0 1 2 3, 1 2 3 4.
const POSTFIXES: [&[u8; 4]; 4] = [b"xr01", b"yg12", b"zb23", b"wa34"];

/// The state of [`group`].
struct Grouping<'a> {
    prefix: &'a str,
    slots: Vec<Slot>,
    attrs: Vec<(String, usize)>,
    /// Prefixes grouped or refused so far (a prefix is grouped once).
    seen: Vec<String>,
    /// The group being read: its prefix, postfix family, and its properties so far.
    current: Option<(String, usize, Vec<usize>)>,
    warn: &'a dyn Fn(String),
}

impl Grouping<'_> {
    /// Ends the group being read: an attribute of 1 or 3 values, else skipped.
    fn flush(&mut self) {
        let Some((name, family, members)) = self.current.take() else { return };
        if members.len() != 1 && members.len() != 3 {
            let prefix = self.prefix;
            (self.warn)(format!(
                "the attribute {prefix}{name} has {} values, not 1 or 3: skipped",
                members.len()
            ));
            return;
        }
        for (c, &i) in members.iter().enumerate() {
            self.slots[i] = Slot::Attribute(self.attrs.len(), c);
        }
        let color = if family == 1 { "_color" } else { "" };
        self.attrs.push((format!("{}{name}{color}", self.prefix), members.len()));
        self.seen.push(name);
    }
}

/// Positions, triangles, normals, uv and attributes of the PLY file `bytes`; `path` names it
/// in errors.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<crate::accel::mesh::MeshData, String> {
    let fail = |m: String| format!("cannot read the mesh {}: {m}", path.display());
    let warn = |m: String| tracing::warn!("the mesh {}: {m}", path.display());
    let (format, elements, start) = header(bytes, &fail)?;
    let mut body = Body { bytes, at: start, format };
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    let (mut normals, mut uvs): (Option<Vec<glam::Vec3A>>, Option<Vec<glam::Vec2>>) = (None, None);
    let mut attributes = Vec::new();
    let mut vertices_read = false;
    let mut faces_read = false;
    for el in &elements {
        // Every record takes at least this many bytes: the count is checked against what is left
        // before anything is allocated for it.
        let min = body.min_record(&el.props);
        // (An ASCII file's last value needs no separator after it.)
        let room = body.left() + (format == Format::Ascii) as usize;
        if el.count > (room / min) as u64 {
            return Err(fail(format!(
                "{} {} records cannot fit in the {} bytes left",
                el.count,
                el.name,
                body.left()
            )));
        }
        let count = el.count as usize;
        let names: Vec<&str> = el.props.iter().map(|p| p.name.as_str()).collect();
        let has = |n: &[&str]| n.iter().all(|n| names.contains(n));
        let (slots, attrs) = match el.name.as_str() {
            "vertex" if !vertices_read => {
                if !has(&["x", "y", "z"]) {
                    return Err(fail("the vertices have no x, y and z".into()));
                }
                let uv_names = [["u", "v"], ["texture_u", "texture_v"], ["s", "t"]];
                let uv = uv_names.iter().find(|n| has(&n[..])).copied();
                let with_normals = has(&["nx", "ny", "nz"]);
                let mut reserved = vec!["x", "y", "z", "nx", "ny", "nz"];
                reserved.extend(uv.iter().flatten());
                let (mut slots, attrs) = group("vertex_", &el.props, &reserved, &warn);
                for (i, p) in el.props.iter().enumerate() {
                    let k = ["x", "y", "z", "nx", "ny", "nz"].iter().position(|n| *n == p.name);
                    let k = k.filter(|&k| k < 3 || with_normals);
                    let k =
                        k.or_else(|| uv.and_then(|uv| uv.iter().position(|n| *n == p.name)).map(|k| 6 + k));
                    if let Some(k) = k.filter(|_| p.list.is_none()) {
                        slots[i] = Slot::Vertex(k);
                    }
                }
                positions.reserve_exact(count);
                normals = with_normals.then(|| Vec::with_capacity(count));
                uvs = uv.map(|_| Vec::with_capacity(count));
                vertices_read = true;
                (slots, attrs)
            }
            "face" if !faces_read => {
                let list = el.props.iter().position(|p| {
                    (p.name == "vertex_indices" || p.name == "vertex_index") && p.list.is_some()
                });
                let Some(list) = list else {
                    return Err(fail("the faces have no vertex_indices list".into()));
                };
                let reserved = ["vertex_indices", "vertex_index"];
                let (mut slots, attrs) = group("face_", &el.props, &reserved, &warn);
                slots[list] = Slot::Indices;
                triangles.reserve_exact(count);
                faces_read = true;
                (slots, attrs)
            }
            _ => {
                warn(format!("the element {} is skipped", el.name));
                (vec![Slot::Skip; el.props.len()], Vec::new())
            }
        };
        let first = attributes.len();
        for (name, channels) in &attrs {
            attributes.push(MeshAttribute { name: name.clone(), channels: *channels, values: Vec::new() });
        }
        let truncated =
            || fail(format!("the {} records end early or hold a value that is not a number", el.name));
        let mut record = [0f32; 8];
        let mut values: Vec<f32> = Vec::new();
        let mut polygon: Vec<u32> = Vec::new();
        for _ in 0..count {
            values.clear();
            values.resize(attrs.iter().map(|a| a.1).sum(), 0.0);
            polygon.clear();
            for (p, slot) in el.props.iter().zip(&slots) {
                if let Some(count_ty) = p.list {
                    let n = body.value(count_ty).ok_or_else(truncated)?;
                    // The items take at least a byte each (or two, in ASCII).
                    if !(n >= 0.0) || n > body.left() as f64 {
                        return Err(truncated());
                    }
                    for _ in 0..n as usize {
                        let v = body.value(p.ty).ok_or_else(truncated)?;
                        if *slot == Slot::Indices {
                            if !(v >= 0.0 && v < u32::MAX as f64) {
                                return Err(fail(format!("a face has the vertex index {v}")));
                            }
                            polygon.push(v as u32);
                        }
                    }
                    continue;
                }
                let v = body.value(p.ty).ok_or_else(truncated)?;
                match *slot {
                    Slot::Vertex(k) => record[k] = v as f32,
                    Slot::Attribute(a, c) => {
                        let offset: usize = attrs[..a].iter().map(|a| a.1).sum();
                        values[offset + c] = attribute_value(v, p.ty);
                    }
                    Slot::Skip | Slot::Indices => {}
                }
            }
            for (a, chunk) in attributes[first..].iter_mut().zip(split(&values, &attrs)) {
                // A polygon's triangles share its values.
                let repeat = if el.name == "face" { polygon.len().saturating_sub(2) } else { 1 };
                for _ in 0..repeat {
                    a.values.extend_from_slice(chunk);
                }
            }
            match el.name.as_str() {
                "vertex" if slots.iter().any(|s| matches!(s, Slot::Vertex(_))) => {
                    positions.push(glam::Vec3A::new(record[0], record[1], record[2]));
                    if let Some(n) = &mut normals {
                        n.push(glam::Vec3A::new(record[3], record[4], record[5]));
                    }
                    if let Some(uv) = &mut uvs {
                        uv.push(glam::Vec2::new(record[6], record[7]));
                    }
                }
                "face" if slots.contains(&Slot::Indices) => {
                    for k in 1..polygon.len().saturating_sub(1) {
                        triangles.push([polygon[0], polygon[k], polygon[k + 1]]);
                    }
                }
                _ => {}
            }
        }
    }
    if format == Format::Ascii {
        if bytes[body.at..].iter().any(|b| !b.is_ascii_whitespace()) {
            return Err(fail("there is more after the last element".into()));
        }
    } else if body.left() > 0 {
        return Err(fail(format!("{} bytes follow the last element", body.left())));
    }
    super::assets::finish_mesh(positions, triangles, normals, uvs, attributes, path)
}

/// `values` cut into the attributes' channel counts.
fn split<'a>(values: &'a [f32], attrs: &'a [(String, usize)]) -> impl Iterator<Item = &'a [f32]> {
    let mut at = 0;
    attrs.iter().map(move |(_, n)| {
        at += n;
        &values[at - n..at]
    })
}

/// An attribute's value as Mitsuba reads it: integers scaled to [0, 1] by the type's largest
/// value (negative ones to -1 at most) and taken from sRGB to linear, floats as they are.
fn attribute_value(v: f64, ty: Scalar) -> f32 {
    match ty.integer_max() {
        Some(max) => crate::texture::srgb_to_linear((v / max).clamp(0.0, 1.0) as f32),
        None => v as f32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3A};

    fn read(bytes: &[u8]) -> Result<crate::accel::mesh::MeshData, String> {
        parse_ply(bytes, Path::new("t.ply"))
    }

    const HEAD: &str = "ply\nformat ascii 1.0\ncomment a square\nelement vertex 4\nproperty float x\n\
        property float y\nproperty float z\nproperty float u\nproperty float v\n\
        property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float w_0\n\
        element face 1\nproperty list uchar int vertex_indices\nproperty float q_x\n\
        property float q_y\nproperty float q_z\nend_header\n";

    #[test]
    fn ascii_quads_are_fans_with_grouped_attributes() {
        let text = format!(
            "{HEAD}0 0 0 0 0 255 0 0 0.5\n1 0 0 1 0 0 255 0 1\n1 1 0 1 1 0 0 255 2\n0 1 0 0 1 255 255 255 3\n\
             4 0 1 2 3 0.1 0.2 0.3\n"
        );
        let m = read(text.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
        assert!(m.normals.is_none());
        let names: Vec<&str> = m.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["vertex_color", "vertex_w", "face_q"]);
        assert_eq!(&m.attributes[0].values[..6], [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        assert_eq!(m.attributes[1].values, [0.5, 1.0, 2.0, 3.0]);
        // The quad's two triangles share its values.
        assert_eq!(m.attributes[2].values, [0.1, 0.2, 0.3, 0.1, 0.2, 0.3]);
        let c = m.attributes[0].at(0, m.triangles[0], Vec2::new(0.25, 0.25));
        assert!((c - glam::Vec3::new(0.5, 0.25, 0.25)).length() < 1e-6, "{c}");
        assert_eq!(m.attributes[2].at(1, m.triangles[1], Vec2::ZERO), glam::Vec3::new(0.1, 0.2, 0.3));
    }

    /// The same mesh in both binary byte orders.
    fn binary(big: bool) -> Vec<u8> {
        let mut b = format!(
            "ply\nformat binary_{}_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty double s\n\
             property double t\nproperty float color_0\nproperty float color_1\nproperty float color_2\n\
             element face 1\nproperty list uchar uint vertex_index\nproperty ushort weight_0\n\
             element edge 1\nproperty int a\nend_header\n",
            if big { "big" } else { "little" }
        )
        .into_bytes();
        let f = |b: &mut Vec<u8>, x: f32| b.extend(if big { x.to_be_bytes() } else { x.to_le_bytes() });
        for (i, p) in [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]].iter().enumerate() {
            for x in p.iter().chain(&[0.0, 0.0, 2.0]) {
                f(&mut b, *x);
            }
            for uv in [i as f64 * 0.25, 0.5] {
                b.extend(if big { uv.to_be_bytes() } else { uv.to_le_bytes() });
            }
            for c in [0.1, 0.2, 0.3] {
                f(&mut b, c * i as f32);
            }
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        b.extend(if big { 65535u16.to_be_bytes() } else { 65535u16.to_le_bytes() });
        b.extend(7i32.to_le_bytes());
        b
    }

    #[test]
    fn binary_files_of_both_byte_orders_agree() {
        let (le, be) = (read(&binary(false)).unwrap(), read(&binary(true)).unwrap());
        assert_eq!(le, be);
        assert_eq!(le.positions[1], Vec3A::new(2.0, 0.0, 0.0));
        // Normals are stored of unit length.
        assert_eq!(le.normals.as_ref().unwrap()[0], Vec3A::Z);
        assert_eq!(le.uvs.as_ref().unwrap()[1], Vec2::new(0.25, 0.5));
        assert_eq!(le.attributes[0].name, "vertex_color");
        assert_eq!(le.attributes[0].values[6..], [0.2, 0.4, 0.6]);
        // An integer attribute is scaled to [0, 1] (and sRGB-decoded: 1 stays 1).
        assert_eq!((le.attributes[1].name.as_str(), le.attributes[1].values[0]), ("face_weight", 1.0));
    }

    #[test]
    fn malformed_files_are_refused_without_panicking_or_allocating() {
        let good = binary(false);
        let body = good.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        // Every truncation fails cleanly.
        for cut in (0..good.len()).step_by(3) {
            assert!(read(&good[..cut]).is_err(), "cut at {cut}");
        }
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"plx\n".to_vec(), "ply"),
            (b"ply\nformat ascii 2.0\nend_header\n".to_vec(), "header line"),
            (b"ply\nformat ascii 1.0\nelement vertex 99999999999999\nproperty float x\nend_header\n".to_vec(), "cannot fit"),
            (b"ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(), "cannot fit"),
            (b"ply\nformat ascii 1.0\nproperty float x\nend_header\n".to_vec(), "before any element"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n".to_vec(), "unknown type"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nend_header\n1\n".to_vec(), "no x, y and z"),
            (format!("{HEAD}0 0 0 0 0 1 1 1 0\n1 0 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n3 0 1 9 0 0 0\n").into_bytes(), "out of range"),
            (format!("{HEAD}0 0 0 0 0 1 1 1 0\n1 0 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n3 0 1 -2 0 0 0\n").into_bytes(), "vertex index"),
            (format!("{HEAD}0 0 0 0 0 1 1 1 0\n1 0 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n200000000 0 1 2 0 0 0\n").into_bytes(), "end early"),
            (format!("{HEAD}0 0 0 0 0 1 1 1 0\n1 0 nan 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n3 0 1 2 0 0 0\n").into_bytes(), "not a finite number"),
            (format!("{HEAD}0 0 0 0 0 1 1 1 0\n1 0 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n0 1 0 0 0 1 1 1 0\n3 0 1 2 0 0 0\n5\n").into_bytes(), "more after"),
            ([&good[..], &[0]].concat(), "bytes follow"),
            ([&good[..body], &[0xff; 3]].concat(), "cannot fit"),
            // The vertices (3 of 52 bytes), then a face whose list of three runs out.
            (good[..body + 3 * 52 + 3].to_vec(), "end early"),
        ];
        for (bytes, says) in cases {
            let err = read(&bytes).expect_err(says);
            assert!(err.contains("t.ply") && err.contains(says), "{says}: {err}");
        }
        assert!(read(&[b'a'; 100]).is_err());
    }

    #[test]
    fn the_shortest_ascii_file_is_read() {
        // Faces first, then the vertices' single digits without a newline after the last.
        let text = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_index\n\
                    element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n\
                    3 0 1 2\n0 0 0 1 0 0 0 1 0";
        assert_eq!(read(text.as_bytes()).unwrap().triangles, [[0, 1, 2]]);
    }

    #[test]
    fn halves_and_mitsubas_grouping_rules() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x0001), 2f32.powi(-24));
        let prop = |n: &str| Property { name: n.into(), ty: Scalar::F32, list: None };
        let props: Vec<Property> =
            ["a_x", "a_y", "a_z", "b_1", "b_2", "c_r", "c_g", "c_b", "d_0", "plain", "e_y"]
                .map(prop)
                .to_vec();
        let (slots, attrs) = group("vertex_", &props, &[], &|_| {});
        // b has two values and e starts with y: both skipped; c's rgb suffixes name a colour.
        let names: Vec<(&str, usize)> = attrs.iter().map(|(n, c)| (n.as_str(), *c)).collect();
        assert_eq!(names, [("vertex_a", 3), ("vertex_c_color", 3), ("vertex_d", 1)]);
        assert_eq!(slots[3], Slot::Skip);
        assert_eq!(slots[7], Slot::Attribute(1, 2));
    }
}
