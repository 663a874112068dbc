//! Mitsuba plugins as pathwave's RON: the scene walk, and the integrator, BSDF, shape and
//! emitter plugins that pathwave has kinds for (the sensor and film: [`super::sensor`]). Each
//! plugin converter reads the parameters it knows and [`Plugin::finish`] refuses the rest; a
//! plugin type without a converter is refused, naming what pathwave reads.
//!
//! Defaults are Mitsuba 3's, from its plugin reference (mitsuba.readthedocs.io, "Plugin
//! reference"): hdrfilm 768 x 576 with a gaussian filter, integrators' `max_depth` -1
//! (unbounded) and `rr_depth` 5, `fov_axis` x, diffuse reflectance 0.5, dielectric
//! `int_ior` bk7 and `ext_ior` air, roughconductor and roughdielectric `alpha` 0.1 and
//! `distribution` beckmann.
//!
//! The texture plugins (`checkerboard`, `bitmap`, ...) are converted in `texture`.

mod texture;

pub use texture::Read;

use super::props::{Op, Plugin, Value, compose};
use super::xml::{At, Document, Element};
use crate::scene::SceneError;
use glam::DVec3;
use std::collections::HashMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The deepest path pathwave renders (its `max_depth` bound), which Mitsuba's unbounded -1
/// becomes.
const UNBOUNDED_DEPTH: i64 = 1024;

/// The pieces of RON a scene becomes, each with the XML element it came from.
#[derive(Default)]
pub struct Pieces {
    /// `camera: (..)`.
    pub camera: Option<(String, At)>,
    /// `render: (..)` fields.
    pub render: Vec<(String, String)>,
    /// `background: ..`.
    pub background: Option<(String, At)>,
    /// `"name": Texture(..)`.
    pub textures: Vec<(String, String, At)>,
    /// `"name": Material(..)`.
    pub materials: Vec<(String, String, At)>,
    /// `(shape: .., material: .., transform: [..])`.
    pub objects: Vec<(String, At)>,
    /// `Point(..)`, ...
    pub lights: Vec<(String, At)>,
}

/// A number as RON writes it: the shortest text that reads back as the same `f64` (which
/// pathwave then rounds to `f32`, as Mitsuba rounds its doubles).
pub fn num(x: f64) -> String {
    let s = format!("{x:?}");
    s.strip_suffix(".0").map(str::to_owned).unwrap_or(s)
}

/// A computed number (not one the scene wrote) as RON writes it: rounded to the `f32` that
/// pathwave keeps, so `30` and not `29.999999999999996`.
pub fn num32(x: f64) -> String {
    num(format!("{:?}", x as f32).parse::<f64>().unwrap_or(x))
}

/// `(x, y, z)`.
pub fn v3(v: DVec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

pub(super) fn ops(list: &[Op]) -> String {
    let one = |op: &Op| match op {
        Op::Translate(t) => format!("Translate({})", v3(*t)),
        Op::Rotate(axis, deg) => format!("Rotate(axis: {}, degrees: {})", v3(*axis), num(*deg)),
        Op::Scale(s) if s.x == s.y && s.y == s.z => format!("UniformScale({})", num(s.x)),
        Op::Scale(s) => format!("Scale({})", v3(*s)),
        Op::Matrix(_) | Op::LookAt(..) => {
            let m = op.matrix().transpose().to_cols_array_2d();
            let rows: Vec<String> = m
                .iter()
                .map(|r| format!("[{}]", r.iter().map(|x| num32(*x)).collect::<Vec<_>>().join(", ")))
                .collect();
            format!("Matrix([{}])", rows.join(", "))
        }
    };
    format!("[{}]", list.iter().map(one).collect::<Vec<_>>().join(", "))
}

/// A file name as the RON writes it: relative to the RON's folder `base` where it can be.
fn file(path: &Path, base: &Path) -> String {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
    let rel = pathdiff::diff_paths(abs(path), abs(base)).unwrap_or_else(|| abs(path));
    format!("{:?}", rel.to_string_lossy().replace('\\', "/"))
}

/// Mitsuba's named indices of refraction (its `ior.h`).
const IORS: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// A scene being converted.
pub struct Converter<'d> {
    doc: &'d Document,
    /// The folder the RON's file names are relative to.
    base: PathBuf,
    ids: HashMap<String, &'d Element>,
    /// Material names given to BSDF ids (and to anonymous BSDFs, by position).
    named: HashMap<String, String>,
    /// The names of the anonymous BSDFs' materials, by their RON.
    anonymous: HashMap<String, String>,
    /// Objects made so far, for the bound.
    pub out: Pieces,
}

/// The most objects a converted scene may hold (shapes after instancing is flattened).
pub const MAX_OBJECTS: usize = 1_000_000;

impl<'d> Converter<'d> {
    /// A converter writing file names relative to `base`.
    pub fn new(doc: &'d Document, base: &Path) -> Result<Self, SceneError> {
        let mut ids = HashMap::new();
        collect_ids(&doc.root, &mut ids)?;
        Ok(Self {
            doc,
            base: base.to_owned(),
            ids,
            named: HashMap::new(),
            anonymous: HashMap::new(),
            out: Pieces::default(),
        })
    }

    fn referenced(&self, e: &'d Element) -> Result<&'d Element, SceneError> {
        match e.tag.as_str() {
            "ref" => {
                let id = e.need("id")?;
                self.ids
                    .get(id)
                    .copied()
                    .ok_or_else(|| e.at.error(format!("<ref id=\"{id}\">: no element has this id")))
            }
            _ => Ok(e),
        }
    }

    /// Converts the scene's top-level elements.
    pub fn scene(&mut self) -> Result<(), SceneError> {
        let root = &self.doc.root;
        root.only(&["version", "type", "id"])?;
        for e in &root.children {
            match e.tag.as_str() {
                "integrator" => self.integrator(e)?,
                "sensor" => self.sensor(e)?,
                "shape" => {
                    let p = Plugin::new(e)?;
                    if p.kind != "shapegroup" {
                        self.shape(e, &[])?;
                    }
                }
                "emitter" => self.emitter(e)?,
                // Converted where they are used.
                "bsdf" | "texture" => {
                    e.need("id")?;
                }
                // Converted where shapes refer to them; read here too, so that a medium pathwave
                // cannot render is refused where it is written.
                "medium" => {
                    super::medium::convert(self, e, &[])?;
                }
                t => return Err(e.at.error(format!("<{t}> does not belong at the top of a <scene>"))),
            }
        }
        if self.out.camera.is_none() {
            return Err(root.at.error("the scene has no <sensor>: pathwave needs a camera"));
        }
        Ok(())
    }

    fn integrator(&mut self, e: &Element) -> Result<(), SceneError> {
        let p = Plugin::new(e)?;
        match p.kind.as_str() {
            // The moment integrator wraps another and adds variance channels: the image is the
            // inner integrator's.
            "moment" => {
                let inner: Vec<&Element> = p.unnamed().collect();
                p.finish(&[])?;
                match inner.as_slice() {
                    [one] if one.tag == "integrator" => self.integrator(one),
                    _ => Err(p.at.error("<integrator type=\"moment\"> wraps exactly one <integrator>")),
                }
            }
            "path" | "volpath" | "direct" | "ptracer" => {
                let default_depth = if p.kind == "direct" { 2 } else { -1 };
                let depth = p.int("max_depth")?.unwrap_or(default_depth);
                let rr = p.int("rr_depth")?.unwrap_or(5);
                if p.bool("hide_emitters")?.unwrap_or(false) {
                    return Err(p.at.error(format!("{}: pathwave does not hide emitters", p.label())));
                }
                if p.kind == "direct" {
                    for n in ["emitter_samples", "bsdf_samples"] {
                        if let Some(k) = p.int(n)?
                            && k != 1 {
                                return Err(p.at.error(format!("{}: pathwave takes one sample of each kind per pixel sample, not {n} = {k}", p.label())));
                            }
                    }
                }
                let reads = ["max_depth", "rr_depth", "hide_emitters", "emitter_samples", "bsdf_samples"];
                p.finish(&reads)?;
                // Mitsuba's depth counts path vertices after the camera (1: emitters seen
                // directly); pathwave's counts scattering events.
                let depth = match depth {
                    -1 => UNBOUNDED_DEPTH,
                    d if (1..=UNBOUNDED_DEPTH + 1).contains(&d) => d - 1,
                    d => return Err(p.at.error(format!("max_depth must be -1 or 1 to {}, not {d}", UNBOUNDED_DEPTH + 1))),
                };
                if !(1..=1024).contains(&rr) {
                    return Err(p.at.error(format!("rr_depth must be 1 to 1024, not {rr}")));
                }
                self.out.render.push(("max_depth".into(), depth.to_string()));
                self.out.render.push(("rr_depth".into(), rr.to_string()));
                Ok(())
            }
            k => Err(p.at.error(format!(
                "<integrator type=\"{k}\">: pathwave renders path, volpath, direct and ptracer (all with its path tracer), and moment around one of them"
            ))),
        }
    }

    /// The name of the material a `<bsdf>` element (or `<ref>`) becomes, converting it once.
    pub fn material(&mut self, e: &'d Element) -> Result<String, SceneError> {
        self.material_as(e, false)
    }

    /// The name of the material a `<bsdf>` element (or `<ref>`) becomes inside a `twosided`:
    /// the same on both sides ([`super::bsdf::two_sided`]), converted once.
    pub fn two_sided_material(&mut self, e: &'d Element) -> Result<String, SceneError> {
        self.material_as(e, true)
    }

    fn material_as(&mut self, e: &'d Element, two_sided: bool) -> Result<String, SceneError> {
        let e = self.referenced(e)?;
        let side = if two_sided { "twosided " } else { "" };
        let key = match e.attr("id") {
            Some(id) => format!("{side}{id}"),
            None => format!("{side}{}:{}:{}", e.at.file.display(), e.at.line, e.at.col),
        };
        if let Some(name) = self.named.get(&key) {
            return Ok(name.clone());
        }
        let ron = match two_sided {
            false => super::bsdf::convert(self, e)?,
            true => super::bsdf::two_sided(self, e)?,
        };
        let name = match e.attr("id") {
            Some(id) if two_sided => format!("{id}-twosided"),
            Some(id) => id.to_owned(),
            // Anonymous BSDFs that say the same thing (one written inside each of many shapes)
            // become one material, as an author would write it.
            None => match self.anonymous.get(&ron) {
                Some(name) => {
                    let name = name.clone();
                    self.named.insert(key, name.clone());
                    return Ok(name);
                }
                None => {
                    let name = format!("{}-{}", Plugin::new(e)?.kind, self.out.materials.len());
                    self.anonymous.insert(ron.clone(), name.clone());
                    name
                }
            },
        };
        self.out.materials.push((name.clone(), ron, e.at.clone()));
        self.named.insert(key, name.clone());
        Ok(name)
    }

    /// A `<shape>` placed by `outer` (the instances around it, innermost first).
    fn shape(&mut self, e: &'d Element, outer: &[Op]) -> Result<(), SceneError> {
        let p = Plugin::new(e)?;
        if p.kind == "instance" {
            let to_world = p.transform("to_world")?.unwrap_or_default();
            let groups: Vec<&Element> = p.unnamed().collect();
            p.finish(&["to_world"])?;
            let [group] = groups.as_slice() else {
                return Err(p.at.error("<shape type=\"instance\"> holds exactly one <ref> to a shapegroup"));
            };
            let group = self.referenced(group)?;
            let g = Plugin::new(group)?;
            if g.kind != "shapegroup" {
                return Err(group.at.error("an instance refers to a <shape type=\"shapegroup\">"));
            }
            let members: Vec<&'d Element> = group.children.iter().collect();
            let mut placed = to_world;
            placed.extend_from_slice(outer);
            for m in members {
                if m.tag != "shape" {
                    return Err(m.at.error(format!("<{}> in a shapegroup: it holds shapes", m.tag)));
                }
                self.shape(m, &placed)?;
            }
            return Ok(());
        }
        if p.kind == "shapegroup" {
            return Err(p
                .at
                .error("a shapegroup inside a shape: pathwave reads shapegroups at the top of the scene"));
        }
        let mut bsdf = None;
        let mut emitter = None;
        for c in p.unnamed() {
            let c = self.referenced(c)?;
            match c.tag.as_str() {
                "bsdf" if bsdf.is_none() => bsdf = Some(c),
                "emitter" if emitter.is_none() => emitter = Some(c),
                t => {
                    return Err(c.at.error(format!(
                        "<{t}> inside {}: pathwave reads one <bsdf> and one area <emitter>",
                        p.label()
                    )));
                }
            }
        }
        let interior = self.interior(&p)?;
        // Mitsuba's `null` BSDF: no surface, only the boundary of the interior medium (if any).
        let bsdf = match bsdf {
            Some(b) if Plugin::new(b)?.kind == "null" => {
                Plugin::new(b)?.finish(&[])?;
                if let Some(em) = emitter {
                    return Err(em.at.error(format!(
                        "an area emitter on {} with a null BSDF: pathwave's emitters are surfaces; give it a BSDF",
                        p.label()
                    )));
                }
                None
            }
            Some(b) => Some(Some(b)),
            None => Some(None),
        };
        let (shape, to_world) = super::shape::convert(self, &p, outer)?;
        let interior = interior.map(|e| super::medium::convert(self, e, &to_world)).transpose()?;
        if self.out.objects.len() + 2 > MAX_OBJECTS {
            return Err(p.at.error(format!("the scene has more than {MAX_OBJECTS} shapes")));
        }
        let transform = match to_world.is_empty() {
            true => String::new(),
            false => format!(", transform: {}", ops(&to_world)),
        };
        if let Some(medium) = interior {
            self.out.objects.push((format!("(shape: {shape}, medium: {medium}{transform})"), p.at.clone()));
        }
        let Some(bsdf) = bsdf else { return Ok(()) };
        // An area emitter on a shape with no BSDF or a black diffuse one (Mitsuba's default
        // for an emitter) is an emitter; on one that reflects, the object emits besides its
        // material.
        let mut emit = None;
        let material = match (emitter, bsdf) {
            (Some(em), b) => {
                let radiance = super::emitter::area(self, em)?;
                match b {
                    Some(b) if !black_diffuse(b)? => {
                        emit = Some(radiance);
                        self.material(b)?
                    }
                    _ => {
                        let name = format!("light-{}", self.out.materials.len());
                        let ron = format!("DiffuseLight(emit: {radiance}, two_sided: false)");
                        self.out.materials.push((name.clone(), ron, em.at.clone()));
                        name
                    }
                }
            }
            (None, Some(b)) => self.material(b)?,
            (None, None) => {
                // Mitsuba's default BSDF.
                let key = "(default diffuse)".to_owned();
                match self.named.get(&key) {
                    Some(n) => n.clone(),
                    None => {
                        self.out.materials.push((
                            "default".into(),
                            "Lambertian(albedo: (0.5, 0.5, 0.5))".into(),
                            p.at.clone(),
                        ));
                        self.named.insert(key, "default".into());
                        "default".into()
                    }
                }
            }
        };
        let mut text = format!("(shape: {shape}, material: {material:?}");
        if let Some(radiance) = emit {
            write!(text, ", emit: (radiance: {radiance})").unwrap();
        }
        text += &transform;
        text.push(')');
        self.out.objects.push((text, p.at.clone()));
        Ok(())
    }

    /// The medium inside a shape (its `interior`), refusing an `exterior` (see
    /// [`super::medium`]).
    fn interior(&self, p: &Plugin<'d>) -> Result<Option<&'d Element>, SceneError> {
        if let Some(param) = p.param("exterior") {
            return Err(param.at.error(format!(
                "{}: an exterior medium: pathwave's media fill closed shapes, and outside a shape is whatever volumes surround it; give the medium as the interior of the shape that bounds it (and leave out an exterior that names the medium around this shape anyway)",
                p.label()
            )));
        }
        let Some(param) = p.param("interior") else { return Ok(None) };
        let super::props::Value::Object(e) = param.value else {
            return Err(param.at.error(format!("{}: `interior` is a <medium> or a <ref> to one", p.label())));
        };
        let e = self.referenced(e)?;
        if e.tag != "medium" {
            return Err(param.at.error(format!(
                "{}: `interior` refers to a <{}>, not a <medium>",
                p.label(),
                e.tag
            )));
        }
        Ok(Some(e))
    }

    fn emitter(&mut self, e: &'d Element) -> Result<(), SceneError> {
        match super::emitter::convert(self, e)? {
            super::emitter::Emitter::Light(l) => self.out.lights.push((l, e.at.clone())),
            super::emitter::Emitter::Background(b) => {
                if self.out.background.is_some() {
                    return Err(e.at.error("a second environment emitter: pathwave has one background"));
                }
                self.out.background = Some((b, e.at.clone()));
            }
        }
        Ok(())
    }

    /// A file named in the scene, as the RON writes it.
    pub fn file(&self, name: &str, at: &At) -> Result<String, SceneError> {
        Ok(file(&self.doc.resolve(name, at)?, &self.base))
    }

    /// A file named in the scene, as a path to read.
    pub fn resolve(&self, name: &str, at: &At) -> Result<PathBuf, SceneError> {
        self.doc.resolve(name, at)
    }

    /// The scene's elements by id.
    pub fn by_id(&self, e: &'d Element) -> Result<&'d Element, SceneError> {
        self.referenced(e)
    }

    /// Mitsuba's named or numeric index of refraction.
    pub fn ior(p: &Plugin, name: &str, default: f64) -> Result<f64, SceneError> {
        let Some(param) = p.param(name) else { return Ok(default) };
        match &param.value {
            Value::Float(v) if *v > 0.0 => Ok(*v),
            Value::Str(s) => IORS.iter().find(|(n, _)| n == s).map(|(_, v)| *v).ok_or_else(|| {
                param.at.error(format!(
                    "`{name}` \"{s}\" is not one of Mitsuba's named media ({})",
                    IORS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                ))
            }),
            _ => Err(param.at.error(format!("`{name}` is a positive number or a named medium"))),
        }
    }
}

fn black_diffuse(e: &Element) -> Result<bool, SceneError> {
    let p = Plugin::new(e)?;
    Ok(match p.kind.as_str() {
        "diffuse" => matches!(p.rgb("reflectance"), Ok(Some(c)) if c == DVec3::ZERO),
        "twosided" => match p.children.as_slice() {
            [(inner, _)] if inner.tag == "bsdf" => black_diffuse(inner)?,
            _ => false,
        },
        _ => false,
    })
}

fn collect_ids<'d>(e: &'d Element, ids: &mut HashMap<String, &'d Element>) -> Result<(), SceneError> {
    for c in &e.children {
        if c.tag != "ref"
            && let Some(id) = c.attr("id")
            && ids.insert(id.to_owned(), c).is_some()
        {
            return Err(c.at.error(format!("the id \"{id}\" is given twice")));
        }
        collect_ids(c, ids)?;
    }
    Ok(())
}

/// The world position and direction a light's `to_world` gives its origin and +z.
pub fn placed(to_world: &[Op]) -> (DVec3, DVec3) {
    let m = compose(to_world);
    (m.transform_point3(DVec3::ZERO), m.transform_vector3(DVec3::Z))
}
