//! Reading and parsing scene files.

use super::context::{Names, ParseScope, take_current_object};
use super::{MaterialDesc, SceneDesc, SceneError};
use ron::extensions::Extensions;
use std::path::Path;

/// Reads and parses the scene file at `path`.
pub fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    load_with(path, &[])
}

/// `-D NAME=VALUE` arguments as the `(name, value)` overrides [`load_with`] takes.
pub fn parse_defines(defines: &[String]) -> Result<Vec<(String, String)>, String> {
    defines
        .iter()
        .map(|d| match d.split_once('=') {
            Some((n, v)) if !n.trim().is_empty() => Ok((n.trim().to_owned(), v.to_owned())),
            _ => Err(format!("-D takes NAME=VALUE (a parameter the scene declares), not {d:?}")),
        })
        .collect()
}

/// [`load`] with `(name, value)` overrides of the scene's declared parameters (`-D`).
///
/// A `.xml` file is a Mitsuba 3 scene (see the `mitsuba` module), a `.gltf` or `.glb` file a
/// glTF 2.0 one (see the `gltf` module, which takes no overrides); anything else is RON.
/// The files it read are the description's `inputs`.
pub fn load_with(path: &Path, overrides: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    let (desc, inputs) = crate::format::files::recording(|| {
        if super::mitsuba::is_xml(path) {
            return super::mitsuba::load(path, overrides);
        }
        if super::gltf::is_gltf_scene(path) {
            if let Some((name, _)) = overrides.first() {
                let message = format!("-D {name}: a glTF scene declares no parameters");
                return Err(SceneError { path: path.to_owned(), line: 0, col: 0, message });
            }
            return super::gltf::load(path);
        }
        let fail = |message: String| SceneError { path: path.to_owned(), line: 0, col: 0, message };
        let bytes = crate::format::files::read_bounded(path, crate::format::files::MAX_SCENE_BYTES, "scene")
            .map_err(fail)?;
        let text = String::from_utf8(bytes).map_err(|e| fail(format!("the scene is not UTF-8 text: {e}")))?;
        parse_with(&text, path, overrides)
    });
    Ok(SceneDesc { inputs, ..desc? })
}

/// Parses scene text; `path` only names the source in errors.
///
/// Parsing runs twice: the first pass collects the material names, the second checks every
/// object's `material` (and every texture name) against them while the parser still knows
/// where that name stands, and reads image files.
pub fn parse(text: &str, path: &Path) -> Result<SceneDesc, SceneError> {
    parse_with(text, path, &[])
}

/// [`parse`] with `(name, value)` overrides of the scene's declared parameters: every `$name`
/// becomes the override's value or the declared default (see the `params` module).
pub fn parse_with(text: &str, path: &Path, overrides: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let substituted = super::params::Substituted::new(text, overrides, path)?;
    let text = substituted.text.as_str();
    let options = ron::Options::default().with_default_extension(Extensions::IMPLICIT_SOME);
    let error = |e: ron::error::SpannedError| {
        let (line, col) = substituted.map_position(e.span.start.line, e.span.start.col);
        SceneError {
            path: path.to_owned(),
            line,
            col,
            message: match take_current_object() {
                Some(i) => format!("in objects[{i}]: {}", e.code),
                None => e.code.to_string(),
            },
        }
    };
    // The first pass notes the files the scene names; what an earlier parse on this thread
    // left there (one that failed half way) is dropped.
    drop(crate::format::context::take_wanted());
    let names: SceneDesc = options.from_str(text).map_err(error)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let _scope = ParseScope::enter(Names {
        materials: names.materials.iter().map(|(n, _)| n.clone()).collect(),
        lights: names
            .materials
            .iter()
            .filter(|(_, m)| m.kind().is_some_and(|k| k.shading() == crate::material::Shading::Emitter))
            .map(|(n, _)| n.clone())
            .collect(),
        wrappers: names
            .materials
            .iter()
            .filter(|(_, m)| matches!(m, MaterialDesc::Wrap(_)))
            .map(|(n, _)| n.clone())
            .collect(),
        textures: names.textures.0.iter().map(|(n, _)| n.clone()).collect(),
        images: names
            .textures
            .0
            .iter()
            .filter(|(_, t)| {
                matches!(t, crate::texture::TextureDesc::Image(_) | crate::texture::TextureDesc::GltfImage(_))
            })
            .map(|(n, _)| n.clone())
            .collect(),
        tilting: tilting(&names),
        attributes: attributes_read(&names),
        dir: dir.clone(),
    });
    super::assets::read_ahead(&dir);
    let desc: SceneDesc = options.from_str(text).map_err(error)?;
    let keys = &desc.animation.camera;
    let placed_keys = keys.look_from.is_some() || keys.look_at.is_some() || keys.vfov.is_some();
    if placed_keys && matches!(desc.camera.view, super::CameraView::ToWorld { .. }) {
        // At the `animation` block, the first line that names it.
        let line = text.lines().position(|l| l.trim_start().starts_with("animation")).map_or(0, |i| i + 1);
        let (line, col) = if line > 0 { substituted.map_position(line, 1) } else { (0, 0) };
        return Err(SceneError {
            path: path.to_owned(),
            line,
            col,
            message: "animation: camera keys look_from, look_at and vfov need a look_from/look_at camera, \
                      not a to_world one (focus_dist keys work with both)"
                .into(),
        });
    }
    Ok(desc)
}

/// The names of the materials of `desc` that are bump or normal maps or hold one (a wrapper
/// names only materials before it: one pass in file order finds them all).
fn tilting(desc: &SceneDesc) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for (name, m) in desc.materials.iter() {
        if let MaterialDesc::Wrap(w) = m
            && (w.tilts() || w.wrapped().iter().any(|inner| out.iter().any(|o| o == inner)))
        {
            out.push(name.clone());
        }
    }
    out
}

/// The mesh attributes each material of `desc` reads through its textures, directly or inside
/// another texture (materials that read none are left out).
fn attributes_read(desc: &SceneDesc) -> Vec<(String, Vec<String>)> {
    use crate::texture::TextureDesc;
    let textures = &desc.textures.0;
    let index = |name: &str| textures.iter().position(|(n, _)| n == name);
    // Per texture in file order (a texture names only those before it).
    let mut per_texture: Vec<Vec<String>> = Vec::new();
    for (_, t) in textures {
        let mut read = match t {
            TextureDesc::MeshAttribute(a) => vec![a.name.0.clone()],
            _ => Vec::new(),
        };
        t.model().build(&mut |c| {
            if let super::Color::Texture(n) = c
                && let Some(i) = index(n)
            {
                read.extend(per_texture.get(i).into_iter().flatten().cloned());
            }
            0
        });
        per_texture.push(read);
    }
    // Per material in file order (a wrapper reads what its textures and the materials it
    // names, all before it, read).
    let mut per_material: Vec<(String, Vec<String>)> = Vec::new();
    for (name, m) in desc.materials.iter() {
        let mut read: Vec<String> = Vec::new();
        let mut texture =
            |n: &str| read.extend(index(n).and_then(|i| per_texture.get(i)).into_iter().flatten().cloned());
        match m {
            MaterialDesc::Wrap(w) => {
                w.textures().into_iter().for_each(&mut texture);
                for inner in w.wrapped() {
                    let of = per_material.iter().find(|(n, _)| n == inner);
                    read.extend(of.into_iter().flat_map(|(_, r)| r.iter().cloned()));
                }
            }
            m => {
                crate::material::Material::build(m, &mut |n| {
                    texture(n);
                    (0, glam::Vec3::ZERO)
                });
            }
        }
        read.sort_unstable();
        read.dedup();
        per_material.push((name.clone(), read));
    }
    per_material.retain(|(_, read)| !read.is_empty());
    per_material
}
