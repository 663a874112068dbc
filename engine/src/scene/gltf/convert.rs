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
//! Units of `KHR_lights_punctual`: point and spot intensities are luminous intensities in
//! candela (lm/sr), directional ones illuminances in lux (lm/m^2). pathwave's lights are
//! radiometric (W/sr, W/m^2), so each is divided by 683 lm/W, the luminous efficacy of light
//! at 555 nm that defines the candela: a point or spot of `I` cd has the radiant intensity
//! `I / 683` W/sr, a directional light of `E` lux the irradiance `E / 683` W/m^2, times the
//! light's colour. This is what Blender's glTF importer does in its default ("Standard")
//! lighting mode (`io_scene_gltf2/blender/imp/light.py`: a point or spot of `I / 683 * 4 pi` W,
//! which Cycles spreads over 4 pi sr, and a sun of `E / 683` W/m^2). A spot's cone is its
//! outer angle, its falloff starting at the inner one, with pathwave's smoothstep falloff (the
//! glTF spec suggests the square of a linear ramp in the cosine; Blender maps the two angles to
//! Cycles' spot size and blend, also a smoothstep). `range` is a cut-off for real-time
//! renderers: lights here fall off by the inverse square law alone (it is warned about).
//!
//! Emission: `emissiveFactor` times `KHR_materials_emissive_strength` is the emitted radiance,
//! as Blender's importer sets its emission colour and strength, on the front side (both for
//! `doubleSided` materials).
//!
//! glTF cameras look along -z with +y up and +x to the right; pathwave's `to_world` cameras
//! (Mitsuba's) look along +z with +x to the left: the camera's `to_world` is its node's
//! rotation and translation (a scale in it is dropped) after `Scale((-1, 1, -1))`, a half turn
//! about y. A camera whose node the animation moves becomes a `look_from`/`look_at` camera
//! instead (pathwave keys cameras by those points): its node's path is evaluated as glTF
//! interpolates it (linear, slerp, step, cubic Hermite) at every key and every frame at 24 a
//! second, the eye at the node's origin, the target a unit along its -z, `vup` +y. That is the
//! node's frame where the camera does not roll (its +x stays level); a roll is warned about.

use super::mesh::mesh_name;
use crate::format::gltf::{GltfFile, ImageAt, name, uri_path};
use crate::scene::{SceneDesc, SceneError};
use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::animation::{Interpolation, Property};
use gltf::material::AlphaMode;
use std::collections::HashMap;
use std::fmt::Write;
use std::path::Path;

/// The luminous efficacy (lm/W) that turns the photometric units of `KHR_lights_punctual` into
/// radiometric ones.
pub const LUMENS_PER_WATT: f32 = 683.0;

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

/// A node's keyframed translation, rotation and scale as RON tracks (`None`: not animated).
#[derive(Default)]
struct NodeKeys {
    translate: Option<String>,
    rotate: Option<String>,
    scale: Option<String>,
    /// The channels' keys as numbers (a camera's path is evaluated from them).
    channels: Vec<Channel>,
}

/// One channel's keys: times and output values (a cubic spline's in-tangent, value and
/// out-tangent per key).
struct Channel {
    property: Property,
    interpolation: Interpolation,
    times: Vec<f32>,
    values: Vec<f32>,
}

impl Channel {
    /// The value at `t` as glTF interpolates it (held before the first key and after the last;
    /// a rotation as xyzw, not yet normalised).
    fn at(&self, t: f32) -> Vec4 {
        let n = if self.property == Property::Rotation { 4 } else { 3 };
        let per = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let v = |k: usize, which: usize| {
            let s = &self.values[(k * per + which) * n..][..n];
            Vec4::new(s[0], s[1], s[2], if n == 4 { s[3] } else { 0.0 })
        };
        let mid = per / 2;
        let k = self.times.partition_point(|x| *x <= t);
        if k == 0 {
            return v(0, mid);
        }
        if k == self.times.len() {
            return v(k - 1, mid);
        }
        let (t0, t1) = (self.times[k - 1], self.times[k]);
        let s = (t - t0) / (t1 - t0);
        match self.interpolation {
            Interpolation::Step => v(k - 1, mid),
            Interpolation::Linear if n == 4 => {
                let q = |v: Vec4| Quat::from_vec4(v).normalize();
                Vec4::from(q(v(k - 1, 0)).slerp(q(v(k, 0)), s))
            }
            Interpolation::Linear => v(k - 1, 0).lerp(v(k, 0), s),
            Interpolation::CubicSpline => {
                let (s2, d) = (s * s, t1 - t0);
                let s3 = s2 * s;
                v(k - 1, 1) * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + v(k - 1, 2) * (d * (s3 - 2.0 * s2 + s))
                    + v(k, 1) * (3.0 * s2 - 2.0 * s3)
                    + v(k, 0) * (d * (s3 - s2))
            }
        }
    }
}

/// Where a node stands below the one animated node above it (or itself) on its path.
#[derive(Clone, Copy)]
enum Moved {
    /// No node on its path is animated.
    Still,
    /// Node `.0` is animated (a root, or under nodes of identity transforms); `.1` is the
    /// transform from the node to it.
    By(usize, Mat4),
    /// Two animated nodes, or one under a transformed parent: not read (warned about).
    Unread,
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

impl Converter<'_> {
    /// Walks the file's default scene (else its first).
    fn scene(&mut self, path: &Path) -> Result<(), SceneError> {
        let doc = &self.file.doc;
        for e in doc.extensions_used().filter(|e| !READ.contains(e)) {
            tracing::warn!("{}: it uses the extension {e}, which pathwave does not read", path.display());
        }
        let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
            return Err(fail(path, "the glTF file has no scene: pathwave renders a scene's nodes".into()));
        };
        if doc.scenes().len() > 1 {
            tracing::warn!(
                "{}: of its {} scenes, scene {}{} alone is rendered",
                path.display(),
                doc.scenes().len(),
                scene.index(),
                name(scene.name())
            );
        }
        let mut seen = vec![false; doc.nodes().len()];
        let mut stack: Vec<(gltf::Node, Mat4, Moved)> =
            scene.nodes().map(|n| (n, Mat4::IDENTITY, Moved::Still)).collect();
        stack.reverse();
        while let Some((node, parent, moved)) = stack.pop() {
            let at = format!("nodes[{}]{}", node.index(), name(node.name()));
            if std::mem::replace(&mut seen[node.index()], true) {
                return Err(fail(
                    path,
                    format!("{at} is met twice in the hierarchy (a node has one parent at most)"),
                ));
            }
            let own = local(&node).map_err(|m| fail(path, format!("{at}: {m}")))?;
            let world = parent * own;
            if !world.is_finite() {
                return Err(fail(path, format!("{at}: its world transform is not finite")));
            }
            let animated = self.keys.contains_key(&node.index());
            let moved = match moved {
                Moved::Still if animated && parent == Mat4::IDENTITY => {
                    Moved::By(node.index(), Mat4::IDENTITY)
                }
                Moved::Still if animated => {
                    tracing::warn!(
                        "{}: {at}: its animation is not read: pathwave keys an object's placement after its transform, and this node has a transformed parent",
                        path.display()
                    );
                    Moved::Unread
                }
                Moved::By(..) if animated => {
                    tracing::warn!(
                        "{}: {at}: its animation is not read: a node above it is animated too",
                        path.display()
                    );
                    Moved::Unread
                }
                Moved::By(a, below) => Moved::By(a, below * own),
                m => m,
            };
            self.node(&node, world, moved, &at, path)?;
            let children: Vec<_> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|c| (c, world, moved)));
        }
        Ok(())
    }

    /// Reads the file's first animation: each channel's keys as a RON track of its node.
    /// Linear keys become `Linear` tracks (rotations as axis-angle keys, each the shorter
    /// way from the one before, so that pathwave's interpolation is glTF's slerp), step keys
    /// `Linear` tracks holding each value up to the float before the next key's time, and
    /// cubic-spline keys `Smooth` tracks through their values (their tangents are not read:
    /// warned). Morph target weights are warned about.
    fn animation(&mut self, path: &Path) -> Result<(), SceneError> {
        let doc = &self.file.doc;
        let Some(anim) = doc.animations().next() else { return Ok(()) };
        if doc.animations().len() > 1 {
            tracing::warn!(
                "{}: of its {} animations the first alone is read",
                path.display(),
                doc.animations().len()
            );
        }
        use gltf::json::validation::Checked;
        for channel in anim.channels() {
            let at = format!("animations[{}] channel {}", anim.index(), channel.index());
            let err = |m: String| fail(path, format!("{at}: {m}"));
            let sampler = channel.sampler();
            // The target's node and path (and the interpolation) from the JSON: the `gltf`
            // crate's `node` and `property` (1.4.1) unwrap them, and its validation lets a
            // node past the last and a path it does not know through (found by the `gltf`
            // fuzz target).
            let json = &doc.as_json().animations[anim.index()];
            let node = json.channels[channel.index()].target.node.value();
            if node >= doc.nodes().len() {
                return Err(err(format!("its target is node {node}, but there are {}", doc.nodes().len())));
            }
            let (path_json, interpolation_json) =
                (&json.channels[channel.index()].target.path, &json.samplers[sampler.index()].interpolation);
            let (Checked::Valid(property), Checked::Valid(interpolation)) = (*path_json, *interpolation_json)
            else {
                tracing::warn!(
                    "{}: {at}: its path or interpolation is not one glTF defines: not read",
                    path.display()
                );
                continue;
            };
            if property == Property::MorphTargetWeights {
                tracing::warn!("{}: {at}: morph target weights are not read", path.display());
                continue;
            }
            let times = self
                .file
                .floats(&sampler.input(), gltf::accessor::Dimensions::Scalar, false, &at)
                .map_err(err)?;
            if let Some(w) = times.windows(2).find(|w| !(w[0] < w[1])) {
                return Err(err(format!("its key times must increase: {} comes after {}", w[1], w[0])));
            }
            if let Some(t) = times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
                return Err(err(format!("a key time is {t}, not a finite number >= 0")));
            }
            let dims = match property {
                Property::Rotation => gltf::accessor::Dimensions::Vec4,
                _ => gltf::accessor::Dimensions::Vec3,
            };
            let n = if dims == gltf::accessor::Dimensions::Vec4 { 4 } else { 3 };
            let values = self
                .file
                .floats(&sampler.output(), dims, property == Property::Rotation, &at)
                .map_err(err)?;
            let per_key = match interpolation {
                Interpolation::CubicSpline => 3,
                _ => 1,
            };
            if values.len() != times.len() * n * per_key {
                return Err(err(format!(
                    "it has {} output values for {} key times",
                    values.len() / n,
                    times.len()
                )));
            }
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(err(format!("an output value is {v}, not finite")));
            }
            // The values (a cubic spline's middle one of each key's three).
            let value = |k: usize| &values[(k * per_key + per_key / 2) * n..][..n];
            let mut keys: Vec<(f32, Vec<f32>)> = Vec::new();
            for (k, &t) in times.iter().enumerate() {
                if interpolation == Interpolation::Step && k > 0 {
                    let before = f32::from_bits(t.to_bits() - 1);
                    if before > times[k - 1] {
                        keys.push((before, value(k - 1).to_vec()));
                    }
                }
                keys.push((t, value(k).to_vec()));
            }
            if interpolation == Interpolation::CubicSpline {
                tracing::warn!(
                    "{}: {at}: its cubic-spline tangents are not read: a Catmull-Rom spline passes through its keys",
                    path.display()
                );
            }
            self.end = self.end.max(*times.last().unwrap_or(&0.0));
            let text: Vec<String> = match property {
                Property::Rotation => {
                    let mut last = Quat::IDENTITY;
                    keys.iter()
                        .map(|(t, v)| {
                            let mut q = Quat::from_array([v[0], v[1], v[2], v[3]]).normalize();
                            if !q.is_finite() {
                                q = Quat::IDENTITY;
                            }
                            if q.dot(last) < 0.0 {
                                q = -q;
                            }
                            last = q;
                            let (axis, angle) = q.to_axis_angle();
                            let axis = if angle.abs() > 0.0 && axis.is_finite() { axis } else { Vec3::Y };
                            format!(
                                "({}, AxisAngle(axis: {}, degrees: {}))",
                                num(*t),
                                rgb(axis.to_array()),
                                num(angle.to_degrees())
                            )
                        })
                        .collect()
                }
                _ => {
                    keys.iter().map(|(t, v)| format!("({}, {})", num(*t), rgb([v[0], v[1], v[2]]))).collect()
                }
            };
            let kind = match interpolation {
                Interpolation::CubicSpline => "Smooth",
                _ => "Linear",
            };
            let track = format!("{kind}([{}])", text.join(", "));
            let entry = self.keys.entry(node).or_default();
            entry.channels.push(Channel { property, interpolation, times, values });
            match property {
                Property::Translation => entry.translate = Some(track),
                Property::Rotation => entry.rotate = Some(track),
                _ => entry.scale = Some(track),
            }
        }
        Ok(())
    }

    /// The `animate` of an object under (or on) the animated node `a`: its keyed channels,
    /// and its rest translation, rotation or scale as one key where a channel has none.
    fn animate(&self, a: usize) -> String {
        let keys = &self.keys[&a];
        let node = self.file.doc.nodes().nth(a).expect("an animated node is a node of the file");
        let (t, r, sc) = node.transform().decomposed();
        let rest_r = {
            let q = Quat::from_array(r).normalize();
            let (axis, angle) = q.to_axis_angle();
            let axis = if angle.abs() > 0.0 && axis.is_finite() { axis } else { Vec3::Y };
            format!(
                "Linear([(0, AxisAngle(axis: {}, degrees: {}))])",
                rgb(axis.to_array()),
                num(angle.to_degrees())
            )
        };
        format!(
            "(translate: {}, rotate: {}, scale: {})",
            keys.translate.clone().unwrap_or_else(|| format!("Linear([(0, {})])", rgb(t))),
            keys.rotate.clone().unwrap_or(rest_r),
            keys.scale.clone().unwrap_or_else(|| format!("Linear([(0, {})])", rgb(sc))),
        )
    }

    /// The `look_from`/`look_at` camera of a camera node at `below` under the animated node `a`
    /// (a root), its keys stored for the animation block: the path evaluated at every key time
    /// of `a`'s channels and at every frame (24 a second, up to 100,000 frames), so that the
    /// frames see the glTF camera wherever pathwave's linear keys and glTF's interpolation
    /// part between keys.
    fn keyed_camera(&mut self, a: usize, below: Mat4, vfov: f32, at: &str, path: &Path) -> String {
        let keys = &self.keys[&a];
        let node = self.file.doc.nodes().nth(a).expect("an animated node is a node of the file");
        let (t0, r0, s0) = node.transform().decomposed();
        let world = |t: f32| {
            let (mut tr, mut r, mut sc) = (Vec3::from(t0), Quat::from_array(r0), Vec3::from(s0));
            for c in &keys.channels {
                let v = c.at(t);
                match c.property {
                    Property::Translation => tr = v.truncate(),
                    Property::Rotation => r = Quat::from_vec4(v),
                    _ => sc = v.truncate(),
                }
            }
            Mat4::from_scale_rotation_translation(sc, r.normalize(), tr) * below
        };
        let mut times: Vec<f32> = keys.channels.iter().flat_map(|c| c.times.iter().copied()).collect();
        let frames = (self.end * 24.0).floor();
        if frames < 100_000.0 {
            times.extend((0..=frames as u32).map(|f| f as f32 / 24.0));
        }
        times.sort_by(f32::total_cmp);
        times.dedup();
        let (mut from, mut to, mut rolls) = (Vec::new(), Vec::new(), false);
        for &t in &times {
            let m = world(t);
            let eye = m.transform_point3(Vec3::ZERO);
            let ahead = m.transform_vector3(Vec3::NEG_Z).normalize();
            let right = m.transform_vector3(Vec3::X).normalize();
            rolls |= right.y.abs() > 1e-3 || m.transform_vector3(Vec3::Y).y <= 0.0 || !ahead.is_finite();
            from.push(format!("({}, {})", num(t), rgb(eye.to_array())));
            to.push(format!("({}, {})", num(t), rgb((eye + ahead).to_array())));
        }
        if rolls {
            tracing::warn!(
                "{}: {at}: the camera rolls (its +x leaves the level) or degenerates on its path: pathwave's keys hold its eye and target, with +y up",
                path.display()
            );
        }
        self.camera_keys =
            Some(format!("(look_from: Linear([{}]), look_at: Linear([{}]))", from.join(", "), to.join(", ")));
        let m = world(0.0);
        let eye = m.transform_point3(Vec3::ZERO);
        let target = eye + m.transform_vector3(Vec3::NEG_Z).normalize();
        format!(
            "(look_from: {}, look_at: {}, vup: (0, 1, 0), vfov: {})",
            rgb(eye.to_array()),
            rgb(target.to_array()),
            num(vfov)
        )
    }

    /// What node `node` holds, at `world`.
    fn node(
        &mut self,
        node: &gltf::Node,
        world: Mat4,
        moved: Moved,
        at: &str,
        path: &Path,
    ) -> Result<(), SceneError> {
        if node.skin().is_some() {
            tracing::warn!("{}: {at}: its skin is not read (its mesh is drawn as it stands)", path.display());
        }
        if let Some(mesh) = node.mesh() {
            let size =
                (world.x_axis.abs() + world.y_axis.abs() + world.z_axis.abs()).truncate().max_element();
            let m3 = glam::Mat3::from_mat4(world) * size.recip();
            if !(m3.determinant().abs() > f32::EPSILON) {
                tracing::warn!(
                    "{}: {at}: its transform is singular (a scale of 0 hides it): its {} is left out",
                    path.display(),
                    mesh_name(&mesh)
                );
            } else {
                // A moving object: its transform up to the animated node, then the node's
                // keyed translation, rotation and scale (rest values where a channel has no
                // keys).
                let (transform, animate) = match moved {
                    Moved::By(a, below) => (matrix(below), Some(self.animate(a))),
                    _ => (matrix(world), None),
                };
                let single = mesh.primitives().len() == 1;
                for p in mesh.primitives() {
                    let (material, emit) = self.material(p.material(), path);
                    let mut o = format!("(shape: Mesh(file: {}, mesh: {}", self.file_name, mesh.index());
                    if !single {
                        write!(o, ", primitive: {}", p.index()).unwrap();
                    }
                    write!(o, "), material: {material:?}").unwrap();
                    if let Some(e) = emit {
                        write!(o, ", emit: {e}").unwrap();
                    }
                    write!(o, ", transform: [{transform}]").unwrap();
                    if let Some(a) = &animate {
                        write!(o, ", animate: {a}").unwrap();
                    }
                    o.push(')');
                    self.objects.push((o, at.to_owned()));
                }
            }
        }
        let mut keyed_camera = false;
        if let Some(camera) = node.camera()
            && self.camera.is_none()
        {
            let at = format!("{at}, cameras[{}]{}", camera.index(), name(camera.name()));
            let (mut c, r) =
                camera_ron(&self.file.doc, &camera, world).map_err(|m| fail(path, format!("{at}: {m}")))?;
            if let (Moved::By(a, below), gltf::camera::Projection::Perspective(p)) =
                (moved, camera.projection())
            {
                c = self.keyed_camera(a, below, p.yfov().to_degrees(), &at, path);
                keyed_camera = true;
            }
            self.camera = Some((c, r, (String::new(), at)));
        }
        if !matches!(moved, Moved::Still)
            && ((node.camera().is_some() && !keyed_camera) || node.light().is_some())
        {
            tracing::warn!(
                "{}: {at}: its camera or light does not move: pathwave keys objects and perspective cameras only",
                path.display()
            );
        }
        if let Some(light) = node.light() {
            let at = format!("{at}, lights[{}]{}", light.index(), name(light.name()));
            if light.range().is_some() {
                tracing::warn!(
                    "{}: {at}: its range is not read (pathwave's lights fall off by the inverse square law alone)",
                    path.display()
                );
            }
            self.lights.push((light_ron(&light, world), at));
        }
        Ok(())
    }

    /// The RON material of glTF material `m` (made on its first use) and the `emit` of the
    /// objects that have it.
    fn material(&mut self, m: gltf::Material, path: &Path) -> (String, Option<String>) {
        if let Some(done) = self.material_names.get(&m.index()) {
            return done.clone();
        }
        let at = match m.index() {
            Some(i) => format!("materials[{i}]{}", name(m.name())),
            None => "the default material".to_owned(),
        };
        let warn = |what: String| tracing::warn!("{}: {at}: {what}", path.display());
        let base_name = match (m.index(), m.name()) {
            (None, _) => "glTF default".to_owned(),
            (Some(_), Some(n)) if self.file.doc.materials().filter(|o| o.name() == Some(n)).count() == 1 => {
                n.to_owned()
            }
            (Some(i), n) => format!("{} {i}", n.unwrap_or("material")),
        };
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let mut fields = String::new();
        let base_texture =
            pbr.base_color_texture().and_then(|t| self.texture(&t, "baseColorTexture", &at, path));
        match &base_texture {
            Some(t) => {
                if [r, g, b] != [1.0; 3] {
                    warn(format!(
                        "its baseColorFactor ({r}, {g}, {b}) times its texture: pathwave takes the texture alone"
                    ));
                }
                write!(fields, "base_color: {t:?}").unwrap();
            }
            None => write!(fields, "base_color: {}", rgb([r, g, b])).unwrap(),
        }
        write!(
            fields,
            ", metallic: {}, roughness: {}",
            num(pbr.metallic_factor()),
            num(pbr.roughness_factor())
        )
        .unwrap();
        if pbr.metallic_roughness_texture().is_some() {
            warn("its metallicRoughnessTexture is not read (pathwave's textured numbers take no channel): its factors are".into());
        }
        // Opaque: the glTF BRDF itself; transmitting: the principled BSDF's refraction.
        let transmission = m.transmission().filter(|t| t.transmission_factor() > 0.0);
        let ior = m.ior().filter(|i| *i != 1.5);
        let coat = m.extension_value("KHR_materials_clearcoat");
        let kind = if let Some(t) = transmission {
            if let Some(ior) = ior {
                write!(fields, ", eta: {}", num(ior)).unwrap();
            }
            write!(fields, ", spec_trans: {}", num(t.transmission_factor())).unwrap();
            if t.transmission_texture().is_some() {
                warn("its transmissionTexture is not read: its transmissionFactor is".into());
            }
            if coat.is_some() {
                warn("it transmits: its KHR_materials_clearcoat is not read".into());
            }
            "Principled"
        } else {
            if let Some(ior) = ior {
                write!(fields, ", ior: {}", num(ior)).unwrap();
            }
            if let Some(coat) = coat {
                for (key, field) in
                    [("clearcoatFactor", "clearcoat"), ("clearcoatRoughnessFactor", "clearcoat_roughness")]
                {
                    let Some(v) = coat.get(key).and_then(|v| v.as_f64()) else { continue };
                    let clamped = v.clamp(0.0, 1.0);
                    if clamped != v {
                        warn(format!("its {key} {v} is not in [0, 1]: {clamped} is used"));
                    }
                    write!(fields, ", {field}: {}", num(clamped as f32)).unwrap();
                }
                if ["clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"]
                    .iter()
                    .any(|k| coat.get(*k).is_some())
                {
                    warn("its clear coat's textures are not read: its factors are".into());
                }
            }
            "MetallicRoughness"
        };
        if m.occlusion_texture().is_some() {
            warn("its occlusionTexture is not read (the path tracer finds occlusion)".into());
        }
        let normal_map = m.normal_texture().and_then(|n| {
            if n.scale() != 1.0 {
                warn(format!(
                    "its normalTexture's scale {} is not read: the map's normals are used",
                    n.scale()
                ));
            }
            if n.extension_value("KHR_texture_transform").is_some() {
                warn(
                    "its normalTexture's KHR_texture_transform is not read: the map is read untransformed"
                        .into(),
                );
            }
            self.image_texture(n.texture(), n.tex_coord(), String::new(), true, "normalTexture", &at, path)
        });
        let plain = format!("{kind}({fields})");
        let opacity = match m.alpha_mode() {
            AlphaMode::Opaque => 1.0,
            AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                if base_texture.is_some() {
                    warn("alpha mode MASK: its texture's alpha is not read (pathwave's textures are RGB): the factor's is".into());
                }
                if alpha >= cutoff { 1.0 } else { 0.0 }
            }
            AlphaMode::Blend => {
                if base_texture.is_some() {
                    warn("alpha mode BLEND: its texture's alpha is not read (pathwave's textures are RGB): the factor's is".into());
                }
                alpha
            }
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        let factor = Vec3::from(m.emissive_factor()) * strength;
        let emissive_texture =
            m.emissive_texture().and_then(|t| self.texture(&t, "emissiveTexture", &at, path));
        let radiance = match emissive_texture {
            Some(t) if factor == Vec3::ONE => Some(format!("{t:?}")),
            Some(_) if factor == Vec3::ZERO => None,
            Some(_) => {
                warn(format!(
                    "its emissive factor times strength {factor} times its texture: pathwave takes the factor alone"
                ));
                Some(rgb(factor.to_array()))
            }
            None if factor == Vec3::ZERO => None,
            None => Some(rgb(factor.to_array())),
        };
        let emit = radiance.map(|r| format!("(radiance: {r}, two_sided: {})", m.double_sided()));
        // A normal map wraps the material, as Mask does: a wrapper does not emit.
        let plain = match normal_map {
            Some(_) if emit.is_some() => {
                warn(
                    "it emits: its normalTexture is not read (pathwave's `emit` is for plain materials)"
                        .into(),
                );
                plain
            }
            Some(t) => {
                let surface = format!("{base_name} (surface)");
                self.materials.push((surface.clone(), (plain, at.clone())));
                format!("NormalMap(texture: {t:?}, material: {surface:?})")
            }
            None => plain,
        };
        let (ron_name, emit) = if opacity < 1.0 {
            let inner = format!("{base_name} (opaque)");
            self.materials.push((inner.clone(), (plain, at.clone())));
            let mask = format!("Mask(opacity: {}, material: {inner:?})", num(opacity));
            self.materials.push((base_name.clone(), (mask, at.clone())));
            if emit.is_some() {
                warn("it emits and is not opaque: pathwave's `emit` is for opaque materials, so it does not emit".into());
            }
            (base_name, None)
        } else {
            self.materials.push((base_name.clone(), (plain, at.clone())));
            (base_name, emit)
        };
        self.material_names.insert(m.index(), (ron_name.clone(), emit.clone()));
        (ron_name, emit)
    }

    /// The name of the RON texture for texture `info` (`what` of material `at`; sRGB), made
    /// on its first use; `None` (warned about) for one pathwave cannot read.
    fn texture(&mut self, info: &gltf::texture::Info, what: &str, at: &str, path: &Path) -> Option<String> {
        let transform = info.texture_transform();
        let set = transform.as_ref().and_then(|x| x.tex_coord()).unwrap_or(info.tex_coord());
        let uv = transform.map(|x| uv_transform(x.offset(), x.rotation(), x.scale())).unwrap_or_default();
        self.image_texture(info.texture(), set, uv, false, what, at, path)
    }

    /// [`Self::texture`] of texture `t` read through uv set `set` and the `uv_transform` `uv`
    /// (empty for none), its 8-bit values raw (a normal map) or sRGB.
    #[expect(clippy::too_many_arguments, reason = "what it reads, and where it is for messages")]
    fn image_texture(
        &mut self,
        t: gltf::Texture,
        set: u32,
        uv: String,
        raw: bool,
        what: &str,
        at: &str,
        path: &Path,
    ) -> Option<String> {
        let warn =
            |m: String| tracing::warn!("{}: {at}: {what} (textures[{}]): {m}", path.display(), t.index());
        if set != 0 {
            warn(format!("it reads TEXCOORD_{set}, which pathwave does not read: TEXCOORD_0 is used"));
        }
        let key = (t.index(), uv.clone(), raw);
        if let Some(done) = self.texture_names.get(&key) {
            return done.clone();
        }
        // The texture's source (validated as an index of the document's images).
        let image = t.source().index();
        // An image file beside the glTF is an `Image`; one inside it a `GltfImage`.
        let source = match self.file.image_at(image) {
            Ok(ImageAt::Uri(uri)) if !uri.starts_with("data:") => uri_path(uri)
                .map(|p| format!("Image(file: {}", file_name(&self.file.dir.join(p), self.base)))
                .map_err(|m| warn(format!("{m}: it is not read"))),
            Ok(_) => Ok(format!("GltfImage(file: {}, image: {image}", self.file_name)),
            Err(m) => {
                warn(format!("image {image}: {m}: it is not read"));
                Err(())
            }
        };
        let named = source.ok().map(|source| {
            let sampler = t.sampler();
            use gltf::texture::{MagFilter, WrappingMode};
            let wrap = |w: WrappingMode| match w {
                WrappingMode::Repeat => "Repeat",
                WrappingMode::ClampToEdge => "Clamp",
                WrappingMode::MirroredRepeat => "Mirror",
            };
            if sampler.wrap_s() != sampler.wrap_t() {
                warn(format!(
                    "it wraps s ({}) and t ({}) differently: pathwave wraps both as s",
                    wrap(sampler.wrap_s()),
                    wrap(sampler.wrap_t())
                ));
            }
            let filter = match sampler.mag_filter() {
                Some(MagFilter::Nearest) => "Nearest",
                _ => "Bilinear",
            };
            let mut ron = format!("{source}, wrap: {}, filter: {filter}", wrap(sampler.wrap_s()));
            if raw {
                ron.push_str(", raw: true");
            }
            if !uv.is_empty() {
                write!(ron, ", uv_transform: {uv}").unwrap();
            }
            ron.push(')');
            let name = format!(
                "texture {}{}{}",
                t.index(),
                if raw { " raw" } else { "" },
                if uv.is_empty() { String::new() } else { format!(" {}", self.textures.len()) }
            );
            self.textures.push((name.clone(), (ron, format!("{at}, textures[{}]", t.index()))));
            name
        });
        self.texture_names.insert(key, named.clone());
        named
    }
}

/// A node's own transform: its matrix, or translation * rotation * scale (the rotation a unit
/// quaternion; one that is not is normalised).
fn local(node: &gltf::Node) -> Result<Mat4, String> {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => Ok(Mat4::from_cols_array_2d(&matrix)),
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let q = Quat::from_array(rotation);
            if !(q.is_finite() && q.length() > 0.0) {
                return Err(format!("its rotation {rotation:?} is not a rotation"));
            }
            Ok(Mat4::from_scale_rotation_translation(scale.into(), q.normalize(), translation.into()))
        }
    }
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

/// `KHR_texture_transform` as pathwave's `uv_transform` (empty for none): glTF's uv' = T R S uv
/// (the spec's matrices) in glTF's uv, whose v is pathwave's 1 - v, so pathwave's map is
/// F (T R S) F with F: (u, v) -> (u, 1 - v).
fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> String {
    if offset == [0.0; 2] && rotation == 0.0 && scale == [1.0; 2] {
        return String::new();
    }
    let (s, c) = (rotation.sin(), rotation.cos());
    let t = glam::Mat3::from_cols_array_2d(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [offset[0], offset[1], 1.0]]);
    let r = glam::Mat3::from_cols_array_2d(&[[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]);
    let sc = glam::Mat3::from_diagonal(Vec3::new(scale[0], scale[1], 1.0));
    let f = glam::Mat3::from_cols_array_2d(&[[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 1.0]]);
    let m = (f * t * r * sc * f).transpose().to_cols_array_2d();
    format!(
        "(({}, {}, {}), ({}, {}, {}))",
        num(m[0][0]),
        num(m[0][1]),
        num(m[0][2]),
        num(m[1][0]),
        num(m[1][1]),
        num(m[1][2])
    )
}

/// The camera of a node at `world`, and the render settings its aspect ratio gives.
fn camera_ron(doc: &gltf::Document, camera: &gltf::Camera, world: Mat4) -> Result<(String, String), String> {
    let (_, rotation, translation) = world.to_scale_rotation_translation();
    let rigid = Mat4::from_rotation_translation(rotation.normalize(), translation);
    let place = format!("Scale((-1, 1, -1)), {}", matrix(rigid));
    let size = |aspect: f32| {
        let width = (512.0 * aspect).round().clamp(1.0, 16384.0);
        format!("width: {}, height: 512", width as u32)
    };
    let clip = |near: f32, far: Option<f32>| {
        let mut s = String::new();
        if near > 0.0 {
            write!(s, ", near_clip: {}", num(near)).unwrap();
        }
        if let Some(f) = far.filter(|f| *f > near) {
            write!(s, ", far_clip: {}", num(f)).unwrap();
        }
        s
    };
    // The `gltf` crate's `projection` (1.4.1) panics where the type's object is missing and
    // the other's is there, which its validation lets through: checked on the JSON first.
    let json = &doc.as_json().cameras[camera.index()];
    let has_object = match json.type_ {
        gltf::json::validation::Checked::Valid(gltf::json::camera::Type::Perspective) => {
            json.perspective.is_some()
        }
        gltf::json::validation::Checked::Valid(gltf::json::camera::Type::Orthographic) => {
            json.orthographic.is_some()
        }
        gltf::json::validation::Checked::Invalid => false,
    };
    if !has_object {
        return Err("its `type` names a projection whose object it lacks".into());
    }
    let projection = camera.projection();
    Ok(match projection {
        gltf::camera::Projection::Perspective(p) => (
            format!(
                "(to_world: [{place}], projection: Perspective(fov: {}, fov_axis: Y){})",
                num(p.yfov().to_degrees()),
                clip(p.znear(), p.zfar())
            ),
            p.aspect_ratio().map(size).unwrap_or_default(),
        ),
        gltf::camera::Projection::Orthographic(o) => (
            format!(
                "(to_world: [Scale(({}, {}, 1)), {place}], projection: Orthographic{})",
                num(o.xmag()),
                num(o.xmag()),
                clip(o.znear(), Some(o.zfar()))
            ),
            size(o.xmag() / o.ymag()),
        ),
    })
}

/// A camera looking along -z at the box of the file's meshes' bounds (their accessors' `min`
/// and `max`, which glTF requires), placed by the nodes, framing it in a vertical field of 40
/// degrees.
fn default_camera(file: &GltfFile) -> (String, String) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for m in file.doc.meshes() {
        for p in m.primitives() {
            let b = p.bounding_box();
            lo = lo.min(Vec3::from(b.min));
            hi = hi.max(Vec3::from(b.max));
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (Vec3::splat(-1.0), Vec3::ONE);
    }
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let from = center + Vec3::Z * (radius / 20f32.to_radians().sin());
    (
        format!("(look_from: {}, look_at: {}, vfov: 40)", rgb(from.to_array()), rgb(center.to_array())),
        String::new(),
    )
}

/// A `KHR_lights_punctual` light at `world`, in radiometric units.
fn light_ron(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> String {
    use gltf::khr_lights_punctual::Kind;
    let power = Vec3::from(light.color()) * (light.intensity() / LUMENS_PER_WATT);
    let position = world.transform_point3(Vec3::ZERO);
    let axis = world.transform_vector3(Vec3::NEG_Z).normalize();
    match light.kind() {
        Kind::Point => {
            format!("Point(position: {}, intensity: {})", rgb(position.to_array()), rgb(power.to_array()))
        }
        Kind::Directional => {
            format!("Directional(direction: {}, irradiance: {})", rgb(axis.to_array()), rgb(power.to_array()))
        }
        Kind::Spot { inner_cone_angle, outer_cone_angle } => format!(
            "Spot(position: {}, look_at: {}, intensity: {}, cone_angle: {}, falloff_start: {})",
            rgb(position.to_array()),
            rgb((position + axis).to_array()),
            rgb(power.to_array()),
            num(outer_cone_angle.to_degrees()),
            num(inner_cone_angle.to_degrees().min(outer_cone_angle.to_degrees()))
        ),
    }
}
