//! Mitsuba XML documents as a tree of elements: files read within bounds, `<include>` spliced
//! in, `<default>` and `-D` parameters substituted for `$name`, `<path>` folders collected and
//! 0.x names upgraded, each element remembering where it was written.
//!
//! The rules are Mitsuba 3's (its `src/core/parser.cpp`): parameters are substituted in every
//! attribute, longest name first, in document order, so a `<default>` applies to what follows
//! it; `\$` escapes a dollar sign; an included file that is a `<scene>` has its children
//! spliced in place of the `<include>`; version 0.x files name parameters in camelCase, which
//! Mitsuba 3 renames to snake_case.

use super::super::SceneError;
use crate::format::files::{MAX_SCENE_BYTES, read_bounded};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How deeply `<include>` may nest.
pub const MAX_INCLUDE_DEPTH: usize = 16;
/// The most elements a scene may hold, includes and all.
pub const MAX_ELEMENTS: usize = 4_000_000;
/// How deeply elements may nest.
pub const MAX_NESTING: usize = 64;
/// The longest attribute value after substitution: parameters that double each other cannot
/// grow a value without bound.
pub const MAX_VALUE_BYTES: usize = 1 << 20;

/// Where something was written: a file and a 1-based line and column.
#[derive(Clone, Debug, PartialEq)]
pub struct At {
    /// The file.
    pub file: Arc<PathBuf>,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub col: usize,
}

impl At {
    /// An error at this place.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError { path: (*self.file).clone(), line: self.line, col: self.col, message: message.into() }
    }
}

/// One XML element after substitution, includes spliced in.
#[derive(Clone, Debug)]
pub struct Element {
    /// The tag: `shape`, `float`, `transform`, ...
    pub tag: String,
    /// Attributes in document order, `$name`s substituted.
    pub attrs: Vec<(String, String)>,
    /// Child elements (comments and text dropped).
    pub children: Vec<Element>,
    /// Where it was written.
    pub at: At,
}

impl Element {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_str())
    }

    /// The value of attribute `name`, which must be there.
    pub fn need(&self, name: &str) -> Result<&str, SceneError> {
        self.attr(name).ok_or_else(|| self.at.error(format!("<{}> needs the attribute `{name}`", self.tag)))
    }

    /// Refuses attributes other than `allowed`.
    pub fn only(&self, allowed: &[&str]) -> Result<(), SceneError> {
        match self.attrs.iter().find(|(n, _)| !allowed.contains(&n.as_str())) {
            None => Ok(()),
            Some((n, _)) => Err(self.at.error(format!(
                "<{}> has an attribute `{n}` that Mitsuba does not define here (it takes: {})",
                self.tag,
                allowed.join(", ")
            ))),
        }
    }
}

/// A parsed scene: its root `<scene>` and the folders `<path>` named, which file names are
/// looked up in after the scene file's own folder.
#[derive(Debug)]
pub struct Document {
    /// The root element.
    pub root: Element,
    /// The scene file's folder, then the `<path>` folders in order (searched last to first).
    pub search: Vec<PathBuf>,
}

impl Document {
    /// Finds the file `name` (relative to the scene file, then to each `<path>` folder), as
    /// Mitsuba's file resolver does; `at` places the error when none has it.
    pub fn resolve(&self, name: &str, at: &At) -> Result<PathBuf, SceneError> {
        let p = Path::new(name);
        if p.is_absolute() {
            return match p.exists() {
                true => Ok(p.to_owned()),
                false => Err(at.error(format!("the file {name} does not exist"))),
            };
        }
        let own = at.file.parent().map(Path::to_path_buf).unwrap_or_default();
        std::iter::once(own)
            .chain(self.search.iter().rev().cloned())
            .map(|d| d.join(p))
            .find(|c| c.exists())
            .ok_or_else(|| {
                at.error(format!(
                    "the file {name} is not in the scene's folder nor in any <path> folder ({})",
                    self.search.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
                ))
            })
    }
}

/// Reads the scene file `path` with `(name, value)` overrides (`-D`).
pub fn read(path: &Path, overrides: &[(String, String)]) -> Result<Document, SceneError> {
    let mut params: Vec<(String, String)> = Vec::new();
    for (n, v) in overrides {
        if n.is_empty() || !n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(At { file: Arc::new(path.to_owned()), line: 0, col: 0 }
                .error(format!("-D {n}={v}: a parameter name is letters, digits and `_`")));
        }
        params.push((format!("${n}"), v.clone()));
    }
    // The scene file's folder is searched last, after the including file's own folder and the
    // <path> folders (Mitsuba's file resolver starts with it, and <path> prepends): an included
    // file may name another relative to the scene.
    let scene_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut reader = Reader { params, search: vec![scene_dir], stack: Vec::new(), elements: 0 };
    let root = reader.file(path, None)?;
    if root.tag != "scene" {
        return Err(root.at.error(format!("the root element is <{}>, not <scene>", root.tag)));
    }
    Ok(Document { root, search: reader.search })
}

struct Reader {
    /// `$name` and its value, longest name first (as Mitsuba: `$ab` before `$a`).
    params: Vec<(String, String)>,
    search: Vec<PathBuf>,
    /// The files being read, outermost first: an include cycle names them.
    stack: Vec<PathBuf>,
    elements: usize,
}

/// A Mitsuba version `major.minor.patch`.
fn version(v: &str) -> Option<(u32, u32, u32)> {
    let mut it = v.trim().split('.').map(|p| p.parse::<u32>().ok());
    let major = it.next()??;
    let minor = it.next().unwrap_or(Some(0))?;
    let patch = it.next().unwrap_or(Some(0))?;
    it.next().is_none().then_some((major, minor, patch))
}

/// Mitsuba 3's renaming of 0.x parameter names: an upper-case letter after a lower-case one
/// starts a `_` and is lowered, with the upper-case letters that follow it.
pub fn camel_to_snake(name: &str) -> String {
    let c: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < c.len() {
        if i > 0 && c[i - 1].is_ascii_lowercase() && c[i].is_ascii_uppercase() {
            out.push('_');
            out.push(c[i].to_ascii_lowercase());
            while i + 1 < c.len() && c[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(c[i].to_ascii_lowercase());
            }
        } else {
            out.push(c[i]);
        }
        i += 1;
    }
    out
}

impl Reader {
    /// Reads one file; `from` is the `<include>` that names it.
    fn file(&mut self, path: &Path, from: Option<&At>) -> Result<Element, SceneError> {
        let here = At { file: Arc::new(path.to_owned()), line: 0, col: 0 };
        let fail = |m: String| match from {
            Some(at) => at.error(m),
            None => here.error(m),
        };
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(fail(format!("includes nest more than {MAX_INCLUDE_DEPTH} deep")));
        }
        let canonical =
            std::fs::canonicalize(path).map_err(|e| fail(format!("cannot read {}: {e}", path.display())))?;
        if let Some(i) = self.stack.iter().position(|p| *p == canonical) {
            let cycle: Vec<String> = self.stack[i..].iter().map(|p| p.display().to_string()).collect();
            return Err(fail(format!(
                "include cycle: {} includes {} again",
                cycle.join(" -> "),
                path.display()
            )));
        }
        let bytes = read_bounded(path, MAX_SCENE_BYTES, "scene").map_err(fail)?;
        let text = String::from_utf8(bytes)
            .map_err(|e| fail(format!("{} is not UTF-8 text: {e}", path.display())))?;
        // No DTD (roxmltree's default): no entity can expand into a large document.
        let options = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
        let doc = roxmltree::Document::parse_with_options(&text, options).map_err(|e| {
            let p = e.pos();
            SceneError {
                path: path.to_owned(),
                line: p.row as usize,
                col: p.col as usize,
                message: e.to_string(),
            }
        })?;
        let root = doc.root_element();
        let at = self.at(&doc, root, path);
        let v = root
            .attribute("version")
            .ok_or_else(|| at.error("the root element needs a `version`, e.g. version=\"3.0.0\""))?;
        let v = version(v).ok_or_else(|| at.error(format!("version \"{v}\" is not major.minor.patch")))?;
        if !(v.0 <= 3) {
            return Err(at.error(format!(
                "version {}.{}.{} is newer than the 3.x that pathwave reads",
                v.0, v.1, v.2
            )));
        }
        // <default>, <path> and <include> act on the element around them: a file's root is a
        // <scene> or one plugin.
        let tag = root.tag_name().name();
        if matches!(tag, "default" | "path" | "include") {
            return Err(at.error(format!(
                "the root element is <{tag}>: a scene file holds a <scene> (or one plugin)"
            )));
        }
        self.stack.push(canonical);
        let mut out = Vec::new();
        self.element(&doc, root, path, v.0 < 2, 0, &mut out)?;
        self.stack.pop();
        out.pop().ok_or_else(|| at.error(format!("the root element <{tag}> holds nothing pathwave reads")))
    }

    fn at(&self, doc: &roxmltree::Document, node: roxmltree::Node, path: &Path) -> At {
        let p = doc.text_pos_at(node.range().start);
        At { file: Arc::new(path.to_owned()), line: p.row as usize, col: p.col as usize }
    }

    /// Substitutes the parameters in one attribute value.
    fn substitute(&self, value: &str, at: &At) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_owned());
        }
        let mut v = value.to_owned();
        for (key, val) in &self.params {
            let mut pos = 0;
            while let Some(i) = v[pos..].find(key.as_str()).map(|i| i + pos) {
                if i > 0 && v.as_bytes()[i - 1] == b'\\' {
                    pos = i + key.len();
                } else {
                    v.replace_range(i..i + key.len(), val);
                    pos = i + val.len();
                }
                if v.len() > MAX_VALUE_BYTES {
                    return Err(at.error(format!(
                        "parameter substitution makes a value longer than {MAX_VALUE_BYTES} bytes"
                    )));
                }
            }
        }
        let b = v.as_bytes();
        for i in 0..b.len() {
            if b[i] == b'$' && (i == 0 || b[i - 1] != b'\\') {
                let name: String =
                    v[i + 1..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                return Err(at.error(format!(
                    "the parameter ${name} has no value: declare <default name=\"{name}\" value=\"..\"/> before it or pass -D {name}=..."
                )));
            }
        }
        Ok(v.replace("\\$", "$"))
    }

    fn element(
        &mut self,
        doc: &roxmltree::Document,
        node: roxmltree::Node,
        path: &Path,
        upgrade: bool,
        depth: usize,
        out: &mut Vec<Element>,
    ) -> Result<(), SceneError> {
        let at = self.at(doc, node, path);
        self.elements += 1;
        if self.elements > MAX_ELEMENTS {
            return Err(at.error(format!("the scene has more than {MAX_ELEMENTS} elements")));
        }
        if depth > MAX_NESTING {
            return Err(at.error(format!("elements nest more than {MAX_NESTING} deep")));
        }
        let tag = node.tag_name().name().to_owned();
        let mut attrs = Vec::with_capacity(node.attributes().len());
        for a in node.attributes() {
            let mut value = self.substitute(a.value(), &at)?;
            if upgrade && a.name() == "name" && tag != "default" {
                value = camel_to_snake(&value);
            }
            attrs.push((a.name().to_owned(), value));
        }
        let mut e = Element { tag, attrs, children: Vec::new(), at };
        // A spectrum file is found now, with the <path> folders declared so far (as Mitsuba's
        // file resolver at this point of the parse).
        if e.tag == "spectrum"
            && let Some((_, name)) = e.attrs.iter_mut().find(|(n, _)| n == "filename")
        {
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            if let Some(found) = std::iter::once(dir)
                .chain(self.search.iter().rev().cloned())
                .map(|d| d.join(&*name))
                .find(|c| c.is_file())
            {
                *name = found.to_string_lossy().into_owned();
            }
        }
        match e.tag.as_str() {
            "default" => {
                e.only(&["name", "value"])?;
                let name = e.need("name")?;
                if name.is_empty() {
                    return Err(e.at.error("<default> needs a non-empty name"));
                }
                let key = format!("${name}");
                if !self.params.iter().any(|(k, _)| *k == key) {
                    let value = e.need("value")?.to_owned();
                    let i = self
                        .params
                        .iter()
                        .position(|(k, _)| k.len() < key.len())
                        .unwrap_or(self.params.len());
                    self.params.insert(i, (key, value));
                }
                return Ok(());
            }
            "path" => {
                e.only(&["value"])?;
                if depth != 1 {
                    return Err(e.at.error("<path> belongs directly in <scene>"));
                }
                let v = Path::new(e.need("value")?);
                let dir = match v.is_absolute() {
                    true => v.to_owned(),
                    false => path.parent().map(|p| p.join(v)).unwrap_or_else(|| v.to_owned()),
                };
                if !dir.is_dir() {
                    return Err(e.at.error(format!("<path>: the folder {} does not exist", dir.display())));
                }
                self.search.push(dir);
                return Ok(());
            }
            "include" => {
                e.only(&["filename", "name"])?;
                let name = e.need("filename")?;
                let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
                let file = std::iter::once(dir)
                    .chain(self.search.iter().rev().cloned())
                    .map(|d| d.join(name))
                    .find(|c| c.exists())
                    .ok_or_else(|| e.at.error(format!("<include>: the file {name} is not found")))?;
                let included = self.file(&file, Some(&e.at))?;
                match included.tag.as_str() {
                    "scene" => out.extend(included.children),
                    _ => out.push(included),
                }
                return Ok(());
            }
            _ => {}
        }
        for c in node.children().filter(|c| c.is_element()) {
            self.element(doc, c, path, upgrade, depth + 1, &mut e.children)?;
        }
        if upgrade && e.tag == "lookAt" {
            e.tag = "lookat".into();
        }
        out.push(e);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn tmp(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("pathwave-xml-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn camel_case_becomes_snake_case_as_in_mitsuba() {
        assert_eq!(camel_to_snake("fovAxis"), "fov_axis");
        assert_eq!(camel_to_snake("sampleCount"), "sample_count");
        assert_eq!(camel_to_snake("intIOR"), "int_ior");
        assert_eq!(camel_to_snake("toWorld"), "to_world");
        assert_eq!(camel_to_snake("radius"), "radius");
    }

    #[test]
    fn defaults_overrides_and_longest_name_first() {
        let d = tmp("params");
        let p = write(
            &d,
            "s.xml",
            r#"<scene version="3.0.0"><default name="a" value="1"/><default name="ab" value="2"/>
               <integer name="x" value="$ab$a"/><string name="y" value="\$a"/></scene>"#,
        );
        let doc = read(&p, &[]).unwrap();
        assert_eq!(doc.root.children[0].attr("value"), Some("21"));
        assert_eq!(doc.root.children[1].attr("value"), Some("$a"));
        let doc = read(&p, &[("a".into(), "7".into())]).unwrap();
        assert_eq!(doc.root.children[0].attr("value"), Some("27"));
    }

    #[test]
    fn an_undefined_parameter_is_placed() {
        let d = tmp("undef");
        let p =
            write(&d, "s.xml", "<scene version=\"3.0.0\">\n  <integer name=\"x\" value=\"$nope\"/></scene>");
        let e = read(&p, &[]).unwrap_err();
        assert_eq!((e.line, e.col), (2, 3), "{e}");
        assert!(e.message.contains("$nope"), "{e}");
    }

    #[test]
    fn includes_splice_and_cycles_are_refused() {
        let d = tmp("include");
        write(&d, "inner.xml", r#"<scene version="3.0.0"><float name="f" value="1"/></scene>"#);
        let p = write(&d, "s.xml", r#"<scene version="3.0.0"><include filename="inner.xml"/></scene>"#);
        let doc = read(&p, &[]).unwrap();
        assert_eq!(doc.root.children.len(), 1);
        assert_eq!(doc.root.children[0].tag, "float");
        assert!(doc.root.children[0].at.file.ends_with("inner.xml"));
        write(&d, "a.xml", r#"<scene version="3.0.0"><include filename="b.xml"/></scene>"#);
        let a = d.join("a.xml");
        write(&d, "b.xml", r#"<scene version="3.0.0"><include filename="a.xml"/></scene>"#);
        let e = read(&a, &[]).unwrap_err();
        assert!(e.message.contains("include cycle"), "{e}");
        // An included file may name another relative to the scene's folder, as Mitsuba's
        // participating_media scenes do (include/base.xml includes include/preamble.xml).
        std::fs::create_dir_all(d.join("include")).unwrap();
        write(&d.join("include"), "pre.xml", r#"<scene version="3.0.0"><float name="g" value="2"/></scene>"#);
        write(
            &d.join("include"),
            "base.xml",
            r#"<scene version="3.0.0"><include filename="include/pre.xml"/></scene>"#,
        );
        let p =
            write(&d, "m.xml", r#"<scene version="3.0.0"><include filename="include/base.xml"/></scene>"#);
        let doc = read(&p, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(doc.root.children[0].tag, "float");
    }

    #[test]
    fn old_versions_are_upgraded() {
        let d = tmp("upgrade");
        let p = write(
            &d,
            "s.xml",
            r#"<scene version="0.5.0"><sensor type="perspective"><string name="fovAxis" value="x"/>
               <transform name="toWorld"><lookAt origin="0,0,0" target="0,0,1" up="0,1,0"/></transform></sensor></scene>"#,
        );
        let doc = read(&p, &[]).unwrap();
        let s = &doc.root.children[0];
        assert_eq!(s.children[0].attr("name"), Some("fov_axis"));
        assert_eq!(s.children[1].attr("name"), Some("to_world"));
        assert_eq!(s.children[1].children[0].tag, "lookat");
    }

    #[test]
    fn hostile_documents_are_refused_with_a_reason() {
        let d = tmp("hostile");
        let bomb = r#"<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;">]>
            <scene version="3.0.0"><string name="s" value="&lol2;"/></scene>"#;
        assert!(read(&write(&d, "bomb.xml", bomb), &[]).is_err());
        let deep = format!(
            "<scene version=\"3.0.0\">{}{}</scene>",
            "<shape type=\"a\">".repeat(100),
            "</shape>".repeat(100)
        );
        let e = read(&write(&d, "deep.xml", &deep), &[]).unwrap_err();
        assert!(e.message.contains("nest"), "{e}");
        for root in [
            "<default version=\"3.0.0\" name=\"a\" value=\"1\"/>",
            "<include version=\"3.0.0\" filename=\"v.xml\"/>",
        ] {
            let e = read(&write(&d, "root.xml", root), &[]).unwrap_err();
            assert!(e.message.contains("root element"), "{e}");
        }
        let e = read(&write(&d, "v.xml", "<scene version=\"4.0.0\"/>"), &[]).unwrap_err();
        assert!(e.message.contains("newer"), "{e}");
        #[cfg(unix)]
        {
            let e = read(Path::new("/dev/zero"), &[]).unwrap_err();
            assert!(e.message.contains("not a regular file"), "{e}");
        }
    }
}
