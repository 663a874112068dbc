//! Mitsuba 3 XML scenes, read into the same [`SceneDesc`] as RON scenes.
//!
//! The XML becomes RON text first ([`to_ron`]), which the RON loader then reads: one scene
//! description, two syntaxes, and `pathwave convert` is the first half of loading. An error
//! that the RON loader finds in the converted text is reported at the XML element that made
//! that line.
//!
//! Layers: [`xml`] reads files into elements (includes, parameters, versions), [`props`] types
//! a plugin's parameters and refuses the unread ones, and [`convert`] with [`sensor`],
//! [`bsdf`], [`shape`], [`medium`] and [`emitter`] turn plugins into pathwave kinds. What pathwave has no
//! kind for is refused with the plugin's place and what pathwave reads instead.

pub mod bsdf;
pub mod conductors;
pub mod convert;
pub mod emitter;
pub mod medium;
pub mod props;
pub mod sensor;
pub mod shape;
pub mod spectrum;
pub mod xml;

#[cfg(test)]
mod tests;

use super::{SceneDesc, SceneError};
use std::fmt::Write;
use std::path::Path;
use xml::At;

/// Whether `path` names an XML scene (by its extension).
pub fn is_xml(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// An XML scene as RON text, with the XML place of each line that came from an element.
pub struct Converted {
    /// The RON.
    pub ron: String,
    /// `(first line, place)`, ascending: lines from `first line` on came from `place`.
    pub origins: Vec<(usize, At)>,
}

impl Converted {
    /// The XML place of RON line `line` (1-based).
    fn origin(&self, line: usize) -> Option<&At> {
        let i = self.origins.partition_point(|(l, _)| *l <= line);
        i.checked_sub(1).map(|i| &self.origins[i].1)
    }
}

/// Reads the XML scene `path` with `(name, value)` overrides (`-D`) as RON whose file names
/// are relative to the folder `base`.
pub fn to_ron(path: &Path, overrides: &[(String, String)], base: &Path) -> Result<Converted, SceneError> {
    let doc = xml::read(path, overrides)?;
    let mut cx = convert::Converter::new(&doc, base)?;
    cx.scene()?;
    let p = cx.out;
    let mut out = Converted { ron: String::new(), origins: Vec::new() };
    let line = |out: &mut Converted, text: &str, at: Option<&At>| {
        if let Some(at) = at {
            let n = out.ron.matches('\n').count() + 1;
            out.origins.push((n, at.clone()));
        }
        out.ron.push_str(text);
        out.ron.push('\n');
    };
    line(&mut out, &format!("// Converted by pathwave from the Mitsuba scene {}.", path.display()), None);
    line(&mut out, "#![enable(implicit_some)]", None);
    line(&mut out, "Scene(", None);
    let Some((camera, at)) = p.camera.as_ref() else {
        return Err(doc.root.at.error("the scene has no <sensor>: pathwave needs a camera"));
    };
    line(&mut out, &format!("    camera: {camera},"), Some(at));
    let mut render = String::new();
    for (k, v) in &p.render {
        write!(render, "{}{k}: {v}", if render.is_empty() { "" } else { ", " }).unwrap();
    }
    line(&mut out, &format!("    render: ({render}),"), Some(at));
    if let Some((b, at)) = &p.background {
        line(&mut out, &format!("    background: {b},"), Some(at));
    }
    if !p.textures.is_empty() {
        line(&mut out, "    textures: {", None);
        for (name, t, at) in &p.textures {
            line(&mut out, &format!("        {name:?}: {t},"), Some(at));
        }
        line(&mut out, "    },", None);
    }
    line(&mut out, "    materials: {", None);
    for (name, m, at) in &p.materials {
        line(&mut out, &format!("        {name:?}: {m},"), Some(at));
    }
    line(&mut out, "    },", None);
    line(&mut out, "    objects: [", None);
    for (o, at) in &p.objects {
        line(&mut out, &format!("        {o},"), Some(at));
    }
    line(&mut out, "    ],", None);
    if !p.lights.is_empty() {
        line(&mut out, "    lights: [", None);
        for (l, at) in &p.lights {
            line(&mut out, &format!("        {l},"), Some(at));
        }
        line(&mut out, "    ],", None);
    }
    line(&mut out, ")", None);
    Ok(out)
}

/// Reads the XML scene `path` with `(name, value)` overrides (`-D`).
pub fn load(path: &Path, overrides: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let converted = to_ron(path, overrides, dir)?;
    super::parse(&converted.ron, path).map_err(|e| match converted.origin(e.line) {
        Some(at) => at.error(format!("{} (in the RON pathwave made of this element)", e.message)),
        None => e,
    })
}
