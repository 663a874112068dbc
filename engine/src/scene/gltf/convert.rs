//! A glTF file as a whole scene, written as RON: the scene's node hierarchy walked with each
//! node's matrix or translation, rotation and scale; each primitive of a node's mesh an object
//! `Mesh(file, mesh, primitive)` under the node's world transform (nodes sharing a mesh share
//! its triangles: instances of one BLAS); the first camera met; `KHR_lights_punctual` lights;
//! metallic-roughness materials as `MetallicRoughness` (the specification's BRDF; `Principled`
//! where they transmit), with `Mask` for the alpha modes MASK and
//! BLEND, `NormalMap` for normal textures and `emit` for emissive ones; textures as `Image`
//! (an image file beside the glTF) or `GltfImage` (one inside it); the first animation's node
//! channels as objects' keyframe tracks, and a moving perspective camera's path as
//! `look_from`/`look_at` keys.
//!
//! The conversion's parts: `nodes` walks the node hierarchy (objects, the camera, lights),
//! `material` writes materials and textures, `animation` reads the first animation's keys.

mod animation;
mod material;
mod nodes;

pub use nodes::LUMENS_PER_WATT;

use crate::format::gltf::GltfFile;
use crate::scene::{SceneDesc, SceneError};
use animation::NodeKeys;
use glam::Mat4;
use nodes::default_camera;
use std::collections::HashMap;
use std::path::Path;

/// The extensions whose meaning the conversion keeps; others a file uses are warned about.
const READ: [&str; 6] = [
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_texture_transform",
];

/// A glTF scene as RON text, with the glTF place of each line that came from an item.
pub struct Converted {
    /// The RON.
    pub ron: String,
    /// `(first line, place)`, ascending: lines from `first line` on came from `place`.
    pub origins: Vec<(usize, String)>,
}

/// A RON item and the glTF item it came from (`nodes[2] "Lamp"`).
type Item = (String, String);

struct Converter<'a> {
    file: &'a GltfFile,
    /// The glTF file as the RON names it.
    file_name: String,
    /// The RON's folder.
    base: &'a Path,
    textures: Vec<(String, Item)>,
    texture_names: HashMap<(usize, String, bool), Option<String>>,
    materials: Vec<(String, Item)>,
    /// By glTF material index (`None`: the default material): the RON material's name and
    /// the `emit` its objects get.
    material_names: HashMap<Option<usize>, (String, Option<String>)>,
    objects: Vec<Item>,
    lights: Vec<Item>,
    camera: Option<(String, String, Item)>,
    /// The keyframes of the nodes the file's first animation moves, by node index.
    keys: HashMap<usize, NodeKeys>,
    /// The `look_from` and `look_at` keys of a moving camera (`camera: (..)` of the animation).
    camera_keys: Option<String>,
    /// The time of the animation's last key.
    end: f32,
}

fn fail(path: &Path, message: String) -> SceneError {
    SceneError { path: path.to_owned(), line: 0, col: 0, message }
}

/// Reads the glTF scene `path` as RON whose file names are relative to the folder `base`.
pub fn to_ron(path: &Path, base: &Path) -> Result<Converted, SceneError> {
    let bytes = crate::format::files::read_bounded(path, crate::format::files::MAX_ASSET_BYTES, "scene")
        .map_err(|m| fail(path, m))?;
    let file = GltfFile::new(&bytes, path).map_err(|m| fail(path, m))?;
    let mut cx = Converter {
        file: &file,
        file_name: file_name(path, base),
        base,
        textures: Vec::new(),
        texture_names: HashMap::new(),
        materials: Vec::new(),
        material_names: HashMap::new(),
        objects: Vec::new(),
        lights: Vec::new(),
        camera: None,
        keys: HashMap::new(),
        camera_keys: None,
        end: 0.0,
    };
    cx.animation(path)?;
    cx.scene(path)?;
    let mut out = Converted { ron: String::new(), origins: Vec::new() };
    let line = |out: &mut Converted, text: &str, at: Option<&str>| {
        if let Some(at) = at {
            let n = out.ron.matches('\n').count() + 1;
            out.origins.push((n, at.to_owned()));
        }
        out.ron.push_str(text);
        out.ron.push('\n');
    };
    line(&mut out, &format!("// Converted by pathwave from the glTF file {}.", path.display()), None);
    line(&mut out, "#![enable(implicit_some)]", None);
    line(&mut out, "Scene(", None);
    let (camera, render, at) = match cx.camera.take() {
        Some((c, r, (_, at))) => (c, r, Some(at)),
        None => {
            let (c, r) = default_camera(&file);
            tracing::warn!(
                "{}: no node holds a camera: a default one looks at the scene along -z",
                path.display()
            );
            (c, r, None)
        }
    };
    line(&mut out, &format!("    camera: {camera},"), at.as_deref());
    line(&mut out, &format!("    render: ({render}),"), at.as_deref());
    if !cx.textures.is_empty() {
        line(&mut out, "    textures: {", None);
        for (name, (t, at)) in &cx.textures {
            line(&mut out, &format!("        {name:?}: {t},"), Some(at));
        }
        line(&mut out, "    },", None);
    }
    line(&mut out, "    materials: {", None);
    for (name, (m, at)) in &cx.materials {
        line(&mut out, &format!("        {name:?}: {m},"), Some(at));
    }
    line(&mut out, "    },", None);
    line(&mut out, "    objects: [", None);
    for (o, at) in &cx.objects {
        line(&mut out, &format!("        {o},"), Some(at));
    }
    line(&mut out, "    ],", None);
    if !cx.lights.is_empty() {
        line(&mut out, "    lights: [", None);
        for (l, at) in &cx.lights {
            line(&mut out, &format!("        {l},"), Some(at));
        }
        line(&mut out, "    ],", None);
    }
    if !cx.keys.is_empty() {
        // Frames at 24 a second up to the last key (as many as a u32 holds: the `gltf` fuzz
        // target's key at 3e38 s overflowed), with a half-frame shutter (motion blur).
        let frames = ((cx.end * 24.0).floor() as u32).saturating_add(1);
        let camera = cx.camera_keys.map(|k| format!(", camera: {k}")).unwrap_or_default();
        line(&mut out, &format!("    animation: (frames: {frames}, fps: 24, shutter: 0.5{camera}),"), None);
    }
    line(&mut out, ")", None);
    Ok(out)
}

/// Reads the glTF scene `path`.
pub fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let converted = to_ron(path, dir)?;
    crate::scene::parse(&converted.ron, path).map_err(|e| {
        let i = converted.origins.partition_point(|(l, _)| *l <= e.line);
        match i.checked_sub(1).map(|i| &converted.origins[i].1) {
            Some(at) => fail(path, format!("{at}: {} (in the RON pathwave made of it)", e.message)),
            None => e,
        }
    })
}

/// `Matrix([[..], [..], [..], [0, 0, 0, 1]])` of an affine `m` (rows).
fn matrix(m: Mat4) -> String {
    let rows = m.transpose().to_cols_array_2d();
    let rows: Vec<String> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| match i {
            3 => "[0, 0, 0, 1]".to_owned(),
            _ => format!("[{}]", r.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")),
        })
        .collect();
    format!("Matrix([{}])", rows.join(", "))
}

/// The shortest text that reads back as `x`.
fn num(x: f32) -> String {
    let s = format!("{x:?}");
    s.strip_suffix(".0").map(str::to_owned).unwrap_or(s)
}

fn rgb(c: [f32; 3]) -> String {
    format!("({}, {}, {})", num(c[0]), num(c[1]), num(c[2]))
}

/// The glTF file as a RON file at `base` names it.
fn file_name(path: &Path, base: &Path) -> String {
    let abs = |p: &Path| {
        std::fs::canonicalize(p).unwrap_or_else(|_| std::path::absolute(p).unwrap_or(p.to_owned()))
    };
    let rel = pathdiff::diff_paths(abs(path), abs(base)).unwrap_or_else(|| abs(path));
    format!("{:?}", rel.to_string_lossy().replace('\\', "/"))
}
