//! The node hierarchy of a glTF scene: each node's meshes as objects under its world transform,
//! the first camera met and `KHR_lights_punctual` lights.
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
//! glTF cameras look along -z with +y up and +x to the right; pathwave's `to_world` cameras
//! (Mitsuba's) look along +z with +x to the left: the camera's `to_world` is its node's
//! rotation and translation (a scale in it is dropped) after `Scale((-1, 1, -1))`, a half turn
//! about y. A camera whose node the animation moves becomes a `look_from`/`look_at` camera
//! instead (pathwave keys cameras by those points): its node's path is evaluated as glTF
//! interpolates it (linear, slerp, step, cubic Hermite) at every key and every frame at 24 a
//! second, the eye at the node's origin, the target a unit along its -z, `vup` +y. That is the
//! node's frame where the camera does not roll (its +x stays level); a roll is warned about.

use super::{Converter, READ, fail, matrix, num, rgb};
use crate::format::gltf::{GltfFile, name};
use crate::scene::SceneError;
use crate::scene::gltf::mesh::mesh_name;
use glam::{Mat4, Quat, Vec3};
use std::fmt::Write;
use std::path::Path;

/// The luminous efficacy (lm/W) that turns the photometric units of `KHR_lights_punctual` into
/// radiometric ones.
pub const LUMENS_PER_WATT: f32 = 683.0;

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

impl Converter<'_> {
    /// Walks the file's default scene (else its first).
    pub(super) fn scene(&mut self, path: &Path) -> Result<(), SceneError> {
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
pub(super) fn default_camera(file: &GltfFile) -> (String, String) {
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
