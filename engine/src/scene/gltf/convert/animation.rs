//! The first animation of a glTF scene: its node channels as objects' keyframe tracks (RON's
//! `Linear` and `Smooth`), and a moving perspective camera's path, evaluated as glTF
//! interpolates it (linear, slerp, step, cubic Hermite), as `look_from`/`look_at` keys.

use super::{Converter, fail, num, rgb};
use crate::scene::SceneError;
use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::animation::{Interpolation, Property};
use std::path::Path;

/// A node's keyframed translation, rotation and scale as RON tracks (`None`: not animated).
#[derive(Default)]
pub(super) struct NodeKeys {
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

impl Converter<'_> {
    /// Reads the file's first animation: each channel's keys as a RON track of its node.
    /// Linear keys become `Linear` tracks (rotations as axis-angle keys, each the shorter
    /// way from the one before, so that pathwave's interpolation is glTF's slerp), step keys
    /// `Linear` tracks holding each value up to the float before the next key's time, and
    /// cubic-spline keys `Smooth` tracks through their values (their tangents are not read:
    /// warned). Morph target weights are warned about.
    pub(super) fn animation(&mut self, path: &Path) -> Result<(), SceneError> {
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
    pub(super) fn animate(&self, a: usize) -> String {
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
    pub(super) fn keyed_camera(&mut self, a: usize, below: Mat4, vfov: f32, at: &str, path: &Path) -> String {
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
}
