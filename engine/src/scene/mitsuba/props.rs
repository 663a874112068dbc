//! A Mitsuba plugin's parameters, typed: `<float name=".." value=".."/>` and its kin, nested
//! plugins and `<ref>`s. Each parameter a converter reads is marked used; [`Plugin::finish`]
//! refuses the rest, so nothing in a scene is silently ignored.

use super::spectrum::{Spectrum, Use};
use super::xml::{At, Element};
use crate::scene::SceneError;
use glam::{DMat4, DVec3, DVec4};
use std::cell::Cell;

/// One step of a `<transform>`, in Mitsuba's terms (angles in degrees).
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// `<translate>`.
    Translate(DVec3),
    /// `<rotate>` about an axis (not normalised) by degrees.
    Rotate(DVec3, f64),
    /// `<scale>`.
    Scale(DVec3),
    /// `<matrix>`, row-major 4x4 (a 3x3 is padded).
    Matrix([[f64; 4]; 4]),
    /// `<lookat>`: origin, target, up.
    LookAt(DVec3, DVec3, DVec3),
}

impl Op {
    /// The matrix of this step, in double precision as Mitsuba builds it.
    pub fn matrix(&self) -> DMat4 {
        match *self {
            Op::Translate(t) => DMat4::from_translation(t),
            Op::Rotate(axis, deg) => DMat4::from_axis_angle(axis.normalize(), deg.to_radians()),
            Op::Scale(s) => DMat4::from_scale(s),
            Op::Matrix(m) => DMat4::from_cols_array_2d(&m).transpose(),
            Op::LookAt(o, t, up) => look_at(o, t, up),
        }
    }
}

/// Mitsuba's `look_at`: camera space looks along +z with +y up and +x to the left.
pub fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> DMat4 {
    let dir = (target - origin).normalize();
    let left = up.normalize().cross(dir).normalize();
    let new_up = dir.cross(left);
    DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        DVec4::new(origin.x, origin.y, origin.z, 1.0),
    )
}

/// The product of transform steps, first applied first.
pub fn compose(ops: &[Op]) -> DMat4 {
    ops.iter().fold(DMat4::IDENTITY, |m, op| op.matrix() * m)
}

/// A parameter's value.
#[derive(Clone, Debug)]
pub enum Value<'d> {
    /// `<float>`.
    Float(f64),
    /// `<integer>`.
    Int(i64),
    /// `<boolean>`.
    Bool(bool),
    /// `<string>`.
    Str(String),
    /// `<point>` or `<vector>`.
    Vector(DVec3),
    /// `<rgb>`.
    Rgb(DVec3),
    /// `<spectrum>`, whose RGB depends on what it describes ([`Use`]).
    Spectrum(Spectrum),
    /// `<transform>`.
    Transform(Vec<Op>),
    /// A nested plugin (`<bsdf>`, `<texture>`, ...) with a `name`, or a `<ref name=".." id=".."/>`.
    Object(&'d Element),
}

impl Value<'_> {
    fn what(&self) -> &'static str {
        match self {
            Value::Float(_) => "a float",
            Value::Int(_) => "an integer",
            Value::Bool(_) => "a boolean",
            Value::Str(_) => "a string",
            Value::Vector(_) => "a point or vector",
            Value::Rgb(_) | Value::Spectrum(_) => "a colour",
            Value::Transform(_) => "a transform",
            Value::Object(_) => "a plugin",
        }
    }
}

/// A parameter: its name, value and where it was written.
#[derive(Debug)]
pub struct Param<'d> {
    /// Its name.
    pub name: String,
    /// Its value.
    pub value: Value<'d>,
    /// Where.
    pub at: At,
    used: Cell<bool>,
}

/// The kinds of plugin element.
pub const PLUGIN_TAGS: [&str; 12] = [
    "bsdf",
    "shape",
    "emitter",
    "texture",
    "sensor",
    "film",
    "rfilter",
    "sampler",
    "integrator",
    "medium",
    "phase",
    "volume",
];

/// One plugin: `<shape type="sphere" id="..">` with its parameters and its unnamed children.
#[derive(Debug)]
pub struct Plugin<'d> {
    /// The element's tag: `shape`, `bsdf`, ...
    pub class: String,
    /// Its `type`.
    pub kind: String,
    /// Its `id`.
    pub id: Option<String>,
    /// Where it was written.
    pub at: At,
    /// Named parameters.
    pub params: Vec<Param<'d>>,
    /// Unnamed nested plugins and `<ref id>`s, in order, each marked when used.
    pub children: Vec<(&'d Element, Cell<bool>)>,
}

fn numbers(s: &str) -> impl Iterator<Item = &str> {
    s.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty())
}

fn float(s: &str, at: &At) -> Result<f64, SceneError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(at.error(format!("expected a finite number, found \"{s}\""))),
    }
}

/// `value="a, b, c"` or `x=".." y=".." z=".."` (missing ones `default`), as Mitsuba reads
/// points, vectors and transform steps.
fn xyz(e: &Element, default: Option<f64>) -> Result<DVec3, SceneError> {
    if let Some(v) = e.attr("value") {
        if e.attr("x").is_some() || e.attr("y").is_some() || e.attr("z").is_some() {
            return Err(e.at.error(format!("<{}> has `value` and x/y/z: give one or the other", e.tag)));
        }
        let t: Vec<&str> = numbers(v).collect();
        return match t.len() {
            1 => Ok(DVec3::splat(float(t[0], &e.at)?)),
            3 => Ok(DVec3::new(float(t[0], &e.at)?, float(t[1], &e.at)?, float(t[2], &e.at)?)),
            n => Err(e.at.error(format!("<{}> value needs 1 or 3 numbers, found {n}", e.tag))),
        };
    }
    let c = |n: &str| match (e.attr(n), default) {
        (Some(v), _) => float(v, &e.at),
        (None, Some(d)) => Ok(d),
        (None, None) => Err(e.at.error(format!("<{}> needs `{n}` (or `value`)", e.tag))),
    };
    Ok(DVec3::new(c("x")?, c("y")?, c("z")?))
}

fn vector_text(s: &str, at: &At) -> Result<DVec3, SceneError> {
    let t: Vec<&str> = numbers(s).collect();
    match t.len() {
        3 => Ok(DVec3::new(float(t[0], at)?, float(t[1], at)?, float(t[2], at)?)),
        n => Err(at.error(format!("expected 3 numbers, found {n} in \"{s}\""))),
    }
}

fn transform(e: &Element) -> Result<Vec<Op>, SceneError> {
    let mut ops = Vec::new();
    for c in &e.children {
        let op = match c.tag.as_str() {
            "translate" => {
                c.only(&["value", "x", "y", "z"])?;
                Op::Translate(xyz(c, Some(0.0))?)
            }
            "scale" => {
                c.only(&["value", "x", "y", "z"])?;
                Op::Scale(xyz(c, Some(1.0))?)
            }
            "rotate" => {
                c.only(&["value", "x", "y", "z", "angle"])?;
                let axis = xyz(c, Some(0.0))?;
                if axis == DVec3::ZERO {
                    return Err(c.at.error("<rotate> needs a non-zero axis"));
                }
                Op::Rotate(axis, float(c.need("angle")?, &c.at)?)
            }
            "matrix" => {
                c.only(&["value"])?;
                let t: Vec<f64> =
                    numbers(c.need("value")?).map(|t| float(t, &c.at)).collect::<Result<_, _>>()?;
                let mut m =
                    [[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
                match t.len() {
                    16 => (0..16).for_each(|i| m[i / 4][i % 4] = t[i]),
                    9 => (0..9).for_each(|i| m[i / 3][i % 3] = t[i]),
                    n => return Err(c.at.error(format!("<matrix> needs 9 or 16 numbers, found {n}"))),
                }
                if m[3] != [0.0, 0.0, 0.0, 1.0] {
                    return Err(c
                        .at
                        .error("<matrix>: pathwave reads affine transforms; the last row must be 0 0 0 1"));
                }
                Op::Matrix(m)
            }
            "lookat" => {
                c.only(&["origin", "target", "up"])?;
                let o = vector_text(c.need("origin")?, &c.at)?;
                let t = vector_text(c.need("target")?, &c.at)?;
                let up = match c.attr("up") {
                    Some(u) => vector_text(u, &c.at)?,
                    None => DVec3::ZERO,
                };
                let dir = t - o;
                let up = match up == DVec3::ZERO {
                    // Mitsuba's `coordinate_system` of the direction gives the up vector.
                    true => dir.normalize().any_orthonormal_vector(),
                    false => up,
                };
                if dir == DVec3::ZERO || up.normalize().cross(dir.normalize()).length_squared() < 1e-20 {
                    return Err(c
                        .at
                        .error("<lookat>: origin and target coincide, or up is parallel to the view"));
                }
                Op::LookAt(o, t, up)
            }
            other => return Err(c.at.error(format!("<{other}> does not belong in a <transform>"))),
        };
        ops.push(op);
    }
    Ok(ops)
}

fn param_value(e: &Element) -> Result<Value<'_>, SceneError> {
    let value = || e.need("value");
    Ok(match e.tag.as_str() {
        "float" => {
            e.only(&["name", "value"])?;
            Value::Float(float(value()?, &e.at)?)
        }
        "integer" => {
            e.only(&["name", "value"])?;
            let v = value()?;
            Value::Int(
                v.trim().parse().map_err(|_| e.at.error(format!("expected an integer, found \"{v}\"")))?,
            )
        }
        "boolean" => {
            e.only(&["name", "value"])?;
            match value()?.trim().to_ascii_lowercase().as_str() {
                "true" => Value::Bool(true),
                "false" => Value::Bool(false),
                v => return Err(e.at.error(format!("expected true or false, found \"{v}\""))),
            }
        }
        "string" => {
            e.only(&["name", "value"])?;
            Value::Str(value()?.to_owned())
        }
        "point" | "vector" => {
            e.only(&["name", "value", "x", "y", "z"])?;
            Value::Vector(xyz(e, None)?)
        }
        "rgb" => {
            e.only(&["name", "value"])?;
            let t: Vec<f64> = numbers(value()?).map(|t| float(t, &e.at)).collect::<Result<_, _>>()?;
            match t.len() {
                1 => Value::Rgb(DVec3::splat(t[0])),
                3 => Value::Rgb(DVec3::new(t[0], t[1], t[2])),
                n => return Err(e.at.error(format!("<rgb> needs 1 or 3 numbers, found {n}"))),
            }
        }
        "spectrum" => {
            e.only(&["name", "value", "filename"])?;
            match (e.attr("value"), e.attr("filename")) {
                (Some(v), None) => Value::Spectrum(Spectrum::parse(v, &e.at)?),
                (None, Some(f)) => {
                    let bytes = crate::format::files::read_bounded(
                        std::path::Path::new(f),
                        16 << 20,
                        "spectrum file",
                    )
                    .map_err(|m| e.at.error(m))?;
                    let text = String::from_utf8(bytes)
                        .map_err(|_| e.at.error(format!("the spectrum file {f} is not text")))?;
                    Value::Spectrum(Spectrum::parse_file(&text, &e.at)?)
                }
                _ => return Err(e.at.error("<spectrum> takes a `value` or a `filename`, one of them")),
            }
        }
        "transform" => {
            e.only(&["name"])?;
            Value::Transform(transform(e)?)
        }
        "ref" => {
            e.only(&["name", "id"])?;
            e.need("id")?;
            Value::Object(e)
        }
        t if PLUGIN_TAGS.contains(&t) => Value::Object(e),
        t => return Err(e.at.error(format!("<{t}> is not an element Mitsuba's scenes use"))),
    })
}

impl<'d> Plugin<'d> {
    /// Reads a plugin element's parameters.
    pub fn new(e: &'d Element) -> Result<Self, SceneError> {
        e.only(&["type", "id", "name"])?;
        let kind = e.need("type")?.to_owned();
        let mut params: Vec<Param> = Vec::new();
        let mut children = Vec::new();
        for c in &e.children {
            match c.attr("name") {
                Some(name) => {
                    if params.iter().any(|p| p.name == name) {
                        return Err(c.at.error(format!("the parameter `{name}` is given twice")));
                    }
                    params.push(Param {
                        name: name.to_owned(),
                        value: param_value(c)?,
                        at: c.at.clone(),
                        used: Cell::new(false),
                    });
                }
                _ if c.tag == "ref" || PLUGIN_TAGS.contains(&c.tag.as_str()) => {
                    if c.tag == "ref" {
                        c.only(&["id"])?;
                    }
                    children.push((c, Cell::new(false)));
                }
                _ => return Err(c.at.error(format!("<{}> inside <{}> needs a `name`", c.tag, e.tag))),
            }
        }
        Ok(Plugin {
            class: e.tag.clone(),
            kind,
            id: e.attr("id").map(str::to_owned),
            at: e.at.clone(),
            params,
            children,
        })
    }

    /// `<tag type="kind">` for messages.
    pub fn label(&self) -> String {
        format!("<{} type=\"{}\">", self.class, self.kind)
    }

    fn get(&self, name: &str) -> Option<&Param<'d>> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    fn wrong(&self, p: &Param<'_>, want: &str) -> SceneError {
        p.at.error(format!("{}: `{}` must be {want}, not {}", self.label(), p.name, p.value.what()))
    }

    /// A float parameter (an integer is taken as a float, as Mitsuba does).
    pub fn float(&self, name: &str) -> Result<Option<f64>, SceneError> {
        self.get(name)
            .map(|p| match p.value {
                Value::Float(v) => Ok(v),
                Value::Int(v) => Ok(v as f64),
                _ => Err(self.wrong(p, "a float")),
            })
            .transpose()
    }

    /// An integer parameter.
    pub fn int(&self, name: &str) -> Result<Option<i64>, SceneError> {
        self.get(name)
            .map(|p| match p.value {
                Value::Int(v) => Ok(v),
                _ => Err(self.wrong(p, "an integer")),
            })
            .transpose()
    }

    /// A boolean parameter.
    pub fn bool(&self, name: &str) -> Result<Option<bool>, SceneError> {
        self.get(name)
            .map(|p| match p.value {
                Value::Bool(v) => Ok(v),
                _ => Err(self.wrong(p, "a boolean")),
            })
            .transpose()
    }

    /// A string parameter with where it was written.
    pub fn string(&self, name: &str) -> Result<Option<(String, At)>, SceneError> {
        self.get(name)
            .map(|p| match &p.value {
                Value::Str(v) => Ok((v.clone(), p.at.clone())),
                _ => Err(self.wrong(p, "a string")),
            })
            .transpose()
    }

    /// A point or vector parameter.
    pub fn vector(&self, name: &str) -> Result<Option<DVec3>, SceneError> {
        self.get(name)
            .map(|p| match p.value {
                Value::Vector(v) => Ok(v),
                _ => Err(self.wrong(p, "a point or vector")),
            })
            .transpose()
    }

    /// A colour parameter: `<rgb>`, `<spectrum>` or `<float>` (grey), a spectrum taken to RGB
    /// as what it describes (`usage`).
    pub fn rgb_as(&self, name: &str, usage: Use) -> Result<Option<DVec3>, SceneError> {
        self.get(name)
            .map(|p| match &p.value {
                Value::Rgb(v) => Ok(*v),
                Value::Spectrum(s) => Ok(s.to_rgb(usage)),
                Value::Float(v) => Ok(DVec3::splat(*v)),
                _ => Err(self.wrong(p, "a colour (<rgb>, <spectrum> or <float>)")),
            })
            .transpose()
    }

    /// A reflectance-like colour parameter ([`Self::rgb_as`] with [`Use::Reflectance`]).
    pub fn rgb(&self, name: &str) -> Result<Option<DVec3>, SceneError> {
        self.rgb_as(name, Use::Reflectance)
    }

    /// A transform parameter.
    pub fn transform(&self, name: &str) -> Result<Option<Vec<Op>>, SceneError> {
        self.get(name)
            .map(|p| match &p.value {
                Value::Transform(v) => Ok(v.clone()),
                _ => Err(self.wrong(p, "a <transform>")),
            })
            .transpose()
    }

    /// A named nested plugin or `<ref>` (`<texture name="reflectance" ..>`), or a colour.
    pub fn param(&self, name: &str) -> Option<&Param<'d>> {
        self.get(name)
    }

    /// The unnamed nested plugins and `<ref>`s, marking them used.
    pub fn unnamed(&self) -> impl Iterator<Item = &'d Element> + '_ {
        self.children.iter().map(|(e, used)| {
            used.set(true);
            *e
        })
    }

    /// Refuses the parameters and nested plugins that the converter did not read, naming
    /// those it reads.
    pub fn finish(&self, reads: &[&str]) -> Result<(), SceneError> {
        if let Some(p) = self.params.iter().find(|p| !p.used.get()) {
            let reads = match reads.is_empty() {
                true => "no parameters".to_owned(),
                false => reads.join(", "),
            };
            return Err(p.at.error(format!(
                "{}: pathwave does not support the parameter `{}` (it reads {reads})",
                self.label(),
                p.name
            )));
        }
        if let Some((e, _)) = self.children.iter().find(|(_, u)| !u.get()) {
            return Err(e.at.error(format!(
                "{}: pathwave does not use a nested <{}> here",
                self.label(),
                e.tag
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_puts_left_in_x_as_mitsuba() {
        let m = look_at(DVec3::ZERO, DVec3::Z, DVec3::Y);
        // Looking along +z with +y up, the left is +x.
        assert!((m.x_axis.truncate() - DVec3::X).length() < 1e-12);
        let m = look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y);
        assert!((m.x_axis.truncate() + DVec3::X).length() < 1e-12, "{m}");
        assert!((m.w_axis.truncate() - DVec3::new(0.0, 0.0, 5.0)).length() < 1e-12);
    }

    #[test]
    fn steps_compose_first_applied_first() {
        let m = compose(&[Op::Scale(DVec3::splat(2.0)), Op::Translate(DVec3::X)]);
        assert_eq!(m.transform_point3(DVec3::ONE), DVec3::new(3.0, 2.0, 2.0));
        let r = compose(&[Op::Rotate(DVec3::new(0.0, 0.0, 2.0), 90.0)]);
        assert!((r.transform_vector3(DVec3::X) - DVec3::Y).length() < 1e-12);
    }
}
