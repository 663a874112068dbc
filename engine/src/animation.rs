//! Keyframes: tracks of `(time, value)` keys in seconds, interpolated linearly or with a
//! Catmull-Rom spline (`Linear([..])`, `Smooth([..])` in RON). Rotations interpolate the angles
//! as written (see [`RotationTrack`]), so 0 to 720 degrees is two turns. Before the first key a
//! track holds the first value, after the last the last. [`ShutterMotion`] places an object
//! whose keys turn or scale it while the shutter is open, per ray time.

use crate::format::{Direction, Finite, MAX_EMISSION, Radiance, V3};
use crate::math::transform_box;
use glam::{Affine3A, Quat, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use serde::{Deserialize, Deserializer, de::Error};

/// How a track passes through its keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Straight lines between keys (slerp for rotations).
    Linear,
    /// A Catmull-Rom spline through the keys (for rotations: slerp with the parameter eased
    /// by smoothstep, so motion starts and stops gently at each key).
    Smooth,
}

/// Keys sorted by strictly increasing time.
#[derive(Clone, Debug, PartialEq)]
pub struct Track<T> {
    /// How values between keys are found.
    pub interpolation: Interpolation,
    /// `(time, value)`, times strictly increasing, at least one key.
    pub keys: Vec<(f32, T)>,
}

/// Values that tracks interpolate.
pub trait Keyed: Copy {
    /// `a + (b - a) s`.
    fn lerp(a: Self, b: Self, s: f32) -> Self;
    /// The Catmull-Rom spline through `p1` (at s = 0) and `p2` (at s = 1) with neighbours
    /// `p0` and `p3`.
    fn catmull_rom(p0: Self, p1: Self, p2: Self, p3: Self, s: f32) -> Self;
}

fn catmull_rom_weights(s: f32) -> [f32; 4] {
    let (s2, s3) = (s * s, s * s * s);
    [
        0.5 * (-s3 + 2.0 * s2 - s),
        0.5 * (3.0 * s3 - 5.0 * s2 + 2.0),
        0.5 * (-3.0 * s3 + 4.0 * s2 + s),
        0.5 * (s3 - s2),
    ]
}

impl Keyed for f32 {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a + (b - a) * s
    }
    fn catmull_rom(p0: Self, p1: Self, p2: Self, p3: Self, s: f32) -> Self {
        let w = catmull_rom_weights(s);
        w[0] * p0 + w[1] * p1 + w[2] * p2 + w[3] * p3
    }
}

impl Keyed for Vec3 {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.lerp(b, s)
    }
    fn catmull_rom(p0: Self, p1: Self, p2: Self, p3: Self, s: f32) -> Self {
        let w = catmull_rom_weights(s);
        w[0] * p0 + w[1] * p1 + w[2] * p2 + w[3] * p3
    }
}

impl<T> Track<T> {
    /// The segment holding `time`: `Err(key)` before the first key or after the last, else
    /// `Ok((i, s))` for the segment from key `i` to key `i + 1` at parameter `s` in [0, 1).
    fn segment(&self, time: f32) -> Result<(usize, f32), usize> {
        let k = &self.keys;
        let last = k.len() - 1;
        if !(time > k[0].0) {
            return Err(0);
        }
        if time >= k[last].0 {
            return Err(last);
        }
        let i = k.partition_point(|(t, _)| *t <= time) - 1;
        Ok((i, (time - k[i].0) / (k[i + 1].0 - k[i].0)))
    }
}

impl<T: Keyed> Track<T> {
    /// The value at `time`.
    pub fn at(&self, time: f32) -> T {
        let k = &self.keys;
        let last = k.len() - 1;
        let (i, s) = match self.segment(time) {
            Ok(seg) => seg,
            Err(key) => return k[key].1,
        };
        match self.interpolation {
            Interpolation::Linear => T::lerp(k[i].1, k[i + 1].1, s),
            Interpolation::Smooth => {
                // End segments repeat their end key as the missing neighbour.
                let p0 = k[i.saturating_sub(1)].1;
                let p3 = k[(i + 2).min(last)].1;
                T::catmull_rom(p0, k[i].1, k[i + 1].1, p3, s)
            }
        }
    }
}

/// `Linear([(t, v), ..])` or `Smooth([(t, v), ..])` as written.
#[derive(Deserialize)]
#[serde(rename = "Track")]
enum RawTrack<R> {
    Linear(Vec<(Finite, R)>),
    Smooth(Vec<(Finite, R)>),
}

/// Reads a track of raw values `R` converted to `T`, checking the times.
fn track<'de, D: Deserializer<'de>, R: Deserialize<'de>, T>(
    d: D,
    conv: impl Fn(R) -> T,
) -> Result<Track<T>, D::Error> {
    let (interpolation, raw) = match RawTrack::<R>::deserialize(d)? {
        RawTrack::Linear(k) => (Interpolation::Linear, k),
        RawTrack::Smooth(k) => (Interpolation::Smooth, k),
    };
    if raw.is_empty() {
        return Err(D::Error::custom("a track needs at least one key"));
    }
    let keys: Vec<(f32, T)> = raw.into_iter().map(|(t, v)| (t.0, conv(v))).collect();
    if let Some(w) = keys.windows(2).find(|w| !(w[1].0 > w[0].0)) {
        return Err(D::Error::custom(format!("key times must increase: {} comes after {}", w[1].0, w[0].0)));
    }
    Ok(Track { interpolation, keys })
}

impl<'de> Deserialize<'de> for Track<Vec3> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        track(d, |v: V3| v.0)
    }
}

impl<'de> Deserialize<'de> for Track<f32> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        track(d, |v: Finite| v.0)
    }
}

/// A colour track (emitted radiance, components in [0, MAX_EMISSION]).
#[derive(Clone, Debug, PartialEq)]
pub struct RgbTrack(pub Track<Vec3>);

impl<'de> Deserialize<'de> for RgbTrack {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let t = RgbTrack(track(d, |v: Radiance| v.0)?);
        match t.overshoot() {
            None => Ok(t),
            Some((time, v, (t0, t1))) => Err(D::Error::custom(format!(
                "this Smooth curve of emitted radiance reaches {v} at time {time}, between its keys at \
                 {t0} and {t1}, outside [0, {MAX_EMISSION:e}] (a Catmull-Rom curve overshoots beside a \
                 step, as keys 5, 0, 0 dip below 0): make the track Linear, or add keys that hold it"
            ))),
        }
    }
}

impl RgbTrack {
    /// Where a `Smooth` track leaves [0, [`MAX_EMISSION`]] between its keys (which lie in it):
    /// the time, the value there and the keys around it. Each channel of a segment is the cubic
    /// `a s^3 + b s^2 + c s + d` of [`catmull_rom_weights`]; its extremes inside the segment are
    /// where `3 a s^2 + 2 b s + c` is zero. Values within 1e-6 of the keys' scale of 0 are
    /// rounding, not overshoot.
    fn overshoot(&self) -> Option<(f32, f32, (f32, f32))> {
        let Track { interpolation: Interpolation::Smooth, keys } = &self.0 else { return None };
        let last = keys.len() - 1;
        for i in 0..last {
            let (t0, t1) = (keys[i].0, keys[i + 1].0);
            let p = [keys[i.saturating_sub(1)].1, keys[i].1, keys[i + 1].1, keys[(i + 2).min(last)].1];
            for ch in 0..3 {
                let [p0, p1, p2, p3] = p.map(|v| v[ch] as f64);
                let a = 0.5 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3);
                let b = 0.5 * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3);
                let c = 0.5 * (p2 - p0);
                let value = |s: f64| ((a * s + b) * s + c) * s + p1;
                let roots = match a.abs() > 1e-12 * (b.abs() + c.abs()) {
                    true => {
                        let disc = 4.0 * b * b - 12.0 * a * c;
                        let r = disc.max(0.0).sqrt();
                        vec![(-2.0 * b - r) / (6.0 * a), (-2.0 * b + r) / (6.0 * a)]
                    }
                    false if b != 0.0 => vec![-c / (2.0 * b)],
                    false => vec![],
                };
                let scale = p0.abs().max(p1.abs()).max(p2.abs()).max(p3.abs());
                for s in roots.into_iter().filter(|s| *s > 0.0 && *s < 1.0) {
                    let v = value(s);
                    if v < -1e-6 * scale || v > MAX_EMISSION as f64 {
                        return Some((t0 + (t1 - t0) * s as f32, v as f32, (t0, t1)));
                    }
                }
            }
        }
        None
    }
}

/// A rotation key as written: `Euler((x, y, z))` in degrees (applied x, then y, then z) or
/// `AxisAngle(axis: (..), degrees: ..)`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Rotation")]
enum RawRotation {
    Euler(V3),
    AxisAngle { axis: Direction, degrees: Finite },
}

/// A rotation key, its angles kept as written (radians), turns included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rotation {
    /// Angles about x, y and z, applied in that order.
    Euler(Vec3),
    /// An angle about a unit axis.
    AxisAngle {
        /// Unit axis.
        axis: Vec3,
        /// Angle.
        angle: f32,
    },
}

impl Rotation {
    /// The rotation as a quaternion.
    pub fn quat(self) -> Quat {
        match self {
            Rotation::Euler(r) => Quat::from_euler(glam::EulerRot::ZYX, r.z, r.y, r.x),
            Rotation::AxisAngle { axis, angle } => Quat::from_axis_angle(axis, angle),
        }
    }

    /// This key's angles in the terms of `like`: the three Euler angles when both are Euler
    /// keys, the angle (in every component) when both turn about the same axis.
    fn angles_like(self, like: Rotation) -> Option<Vec3> {
        match (self, like) {
            (Rotation::Euler(r), Rotation::Euler(_)) => Some(r),
            (Rotation::AxisAngle { axis, angle }, Rotation::AxisAngle { axis: a, .. })
                if axis.dot(a) > 1.0 - 1e-6 =>
            {
                Some(Vec3::splat(angle))
            }
            _ => None,
        }
    }

    /// The rotation of `like`'s kind (and axis) with angles `v`.
    fn with_angles(like: Rotation, v: Vec3) -> Rotation {
        match like {
            Rotation::Euler(_) => Rotation::Euler(v),
            Rotation::AxisAngle { axis, .. } => Rotation::AxisAngle { axis, angle: v.x },
        }
    }
}

/// Rotation keys. Between two `Euler` keys the three angles are interpolated, and between two
/// `AxisAngle` keys about the same axis the angle is, like any number (`Smooth`: Catmull-Rom
/// through the neighbouring keys of the same kind): 0 to 720 degrees turns twice and 0 to -90
/// turns the negative way. Between keys of different kinds or axes the rotation takes the
/// shortest way (slerp; eased by smoothstep for `Smooth`).
#[derive(Clone, Debug, PartialEq)]
pub struct RotationTrack(pub Track<Rotation>);

impl RotationTrack {
    /// The rotation at `time`.
    pub fn at(&self, time: f32) -> Quat {
        let k = &self.0.keys;
        let (i, s) = match self.0.segment(time) {
            Ok(seg) => seg,
            Err(key) => return k[key].1.quat(),
        };
        let (a, b) = (k[i].1, k[i + 1].1);
        let smooth = self.0.interpolation == Interpolation::Smooth;
        let Some((pa, pb)) = a.angles_like(a).zip(b.angles_like(a)) else {
            let s = if smooth { s * s * (3.0 - 2.0 * s) } else { s };
            return a.quat().slerp(b.quat(), s);
        };
        let v = match smooth {
            false => pa.lerp(pb, s),
            true => {
                // Neighbours of another kind or axis count as the segment's end keys repeated.
                let p0 = i.checked_sub(1).and_then(|j| k[j].1.angles_like(a)).unwrap_or(pa);
                let p3 = k.get(i + 2).and_then(|n| n.1.angles_like(a)).unwrap_or(pb);
                Vec3::catmull_rom(p0, pa, pb, p3, s)
            }
        };
        Rotation::with_angles(a, v).quat()
    }
}

impl<'de> Deserialize<'de> for RotationTrack {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let t = track(d, |r: RawRotation| match r {
            RawRotation::Euler(v) => Rotation::Euler(v.0 * (std::f32::consts::PI / 180.0)),
            RawRotation::AxisAngle { axis, degrees } => {
                Rotation::AxisAngle { axis: axis.0.normalize(), angle: degrees.0.to_radians() }
            }
        })?;
        Ok(RotationTrack(t))
    }
}

/// An object's keyframed placement: at time `t` it is `T(t) R(t) S(t)` applied after its
/// static `transform` list.
#[derive(Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(deny_unknown_fields, rename = "Animate")]
pub struct ObjectAnimation {
    /// Translation keys.
    #[serde(default)]
    pub translate: Option<Track<Vec3>>,
    /// Rotation keys.
    #[serde(default)]
    pub rotate: Option<RotationTrack>,
    /// Scale keys (per axis).
    #[serde(default)]
    pub scale: Option<Track<Vec3>>,
}

impl ObjectAnimation {
    /// The keyframed part of the placement at `time`.
    pub fn at(&self, time: f32) -> glam::Affine3A {
        let t = self.translate.as_ref().map_or(Vec3::ZERO, |k| k.at(time));
        let r = self.rotate.as_ref().map_or(Quat::IDENTITY, |k| k.at(time).normalize());
        let s = self.scale.as_ref().map_or(Vec3::ONE, |k| k.at(time));
        glam::Affine3A::from_scale_rotation_translation(s, r, t)
    }
}

/// The camera's keyframes.
#[derive(Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(deny_unknown_fields, rename = "Animate")]
pub struct CameraAnimation {
    /// Eye position keys.
    #[serde(default)]
    pub look_from: Option<Track<Vec3>>,
    /// Target keys.
    #[serde(default)]
    pub look_at: Option<Track<Vec3>>,
    /// Vertical field of view keys (degrees).
    #[serde(default)]
    pub vfov: Option<Track<f32>>,
    /// Focus distance keys.
    #[serde(default)]
    pub focus_dist: Option<Track<f32>>,
}

/// A keyframed placement over the shutter interval: `world_from_object(time) = A(time) base`,
/// with the scale, rotation and translation of `A` interpolated (lerp, slerp, lerp) from shutter
/// open to close, so every ray sees the object (a mesh instance, a medium) where it is at the ray's time.
#[derive(Clone, Debug, PartialEq)]
pub struct ShutterMotion {
    /// The static part.
    pub base: Affine3A,
    base_inv: Affine3A,
    /// Shutter open and close.
    pub times: (f32, f32),
    scale: (Vec3, Vec3),
    rotation: (Quat, Quat),
    translation: (Vec3, Vec3),
}

impl ShutterMotion {
    /// `open` and `close` are `A` at the shutter's open and close `times`; `None` when a
    /// transform is singular or the interval empty.
    pub fn new(base: Affine3A, open: Affine3A, close: Affine3A, times: (f32, f32)) -> Option<Self> {
        let ok = |m: &Affine3A| {
            let det = m.matrix3.determinant();
            det.abs() > 0.0 && det.is_finite() && m.translation.is_finite()
        };
        if !(ok(&base) && ok(&open) && ok(&close) && times.1 > times.0) {
            return None;
        }
        let (s0, r0, t0) = open.to_scale_rotation_translation();
        let (s1, mut r1, t1) = close.to_scale_rotation_translation();
        if r1.dot(r0) < 0.0 {
            r1 = -r1;
        }
        Some(Self {
            base,
            base_inv: base.inverse(),
            times,
            scale: (s0, s1),
            rotation: (r0, r1),
            translation: (t0, t1),
        })
    }

    /// Scale, rotation and translation of `A` at `time`.
    #[inline]
    fn srt(&self, time: f32) -> (Vec3A, Quat, Vec3A) {
        let u = ((time - self.times.0) / (self.times.1 - self.times.0)).clamp(0.0, 1.0);
        (
            self.scale.0.lerp(self.scale.1, u).into(),
            self.rotation.0.slerp(self.rotation.1, u),
            self.translation.0.lerp(self.translation.1, u).into(),
        )
    }

    /// Object to world at `time`.
    pub fn world_from_object(&self, time: f32) -> Affine3A {
        let (s, r, t) = self.srt(time);
        Affine3A::from_scale_rotation_translation(s.into(), r, t.into()) * self.base
    }

    /// The ray `o + t d` at `time` in object space (`t` unchanged).
    #[inline]
    pub(crate) fn object_ray(&self, time: f32, o: Vec3A, d: Vec3A) -> (Vec3A, Vec3A) {
        let (s, r, t) = self.srt(time);
        let inv = r.inverse();
        let (o, d) = ((inv * (o - t)) / s, (inv * d) / s);
        (self.base_inv.transform_point3a(o), self.base_inv.transform_vector3a(d))
    }

    /// World bounds of the object box `b` over the shutter: the union of its bounds at 33
    /// times, grown by how far a point of the box can move between two of them.
    pub(crate) fn bounds(&self, b: &Aabb) -> Aabb {
        const N: usize = 32;
        let local = transform_box(b, &self.base);
        let reach = local.min.abs().max(local.max.abs()).length();
        let (s, r) = (self.scale, self.rotation);
        let angle = r.0.angle_between(r.1) / N as f32;
        let smax = s.0.abs().max(s.1.abs()).max_element();
        let pad = reach * (angle * smax + (s.1 - s.0).abs().max_element() / N as f32)
            + (self.translation.1 - self.translation.0).length() / N as f32;
        let mut out = Aabb::empty();
        for k in 0..=N {
            let time = self.times.0 + (self.times.1 - self.times.0) * k as f32 / N as f32;
            out = out.union(&transform_box(b, &self.world_from_object(time)));
        }
        Aabb { min: out.min - pad, max: out.max + pad }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Smooth emission curve that dips below 0 between its keys (the light switched off:
    /// keys 5, 0, 0) is refused where it was clamped in silence; the same keys Linear, and
    /// Smooth keys that do not overshoot, are read.
    #[test]
    fn smooth_emission_that_overshoots_is_refused() {
        let read = |t: &str| ron::from_str::<RgbTrack>(t).map_err(|e| e.to_string());
        let off = "Smooth([(0, (5, 5, 5)), (1, (0, 0, 0)), (2, (0, 0, 0))])";
        let e = read(off).unwrap_err();
        assert!(e.contains("between its keys at 1 and 2"), "{e}");
        // -2.5 s (1 - s)^2 is least at s = 1/3: -0.370.
        assert!(e.contains("reaches -0.370"), "{e}");
        assert!(read(&off.replace("Smooth", "Linear")).is_ok());
        assert!(read("Smooth([(0, (0, 0, 0)), (1, (5, 5, 5)), (2, (0, 0, 0))])").is_ok());
        assert!(read("Smooth([(0, (1, 2, 3)), (1, (1, 2, 3))])").is_ok());
        let high = "Smooth([(0, (0, 0, 0)), (1, (1e10, 0, 0)), (2, (1e10, 0, 0)), (3, (0, 0, 0))])";
        assert!(read(high).unwrap_err().contains("outside [0, 1e10]"));
    }

    fn lin(keys: &[(f32, f32)]) -> Track<f32> {
        Track { interpolation: Interpolation::Linear, keys: keys.to_vec() }
    }

    #[test]
    fn tracks_hold_ends_and_pass_through_keys() {
        let k = [(0.0, 1.0), (1.0, 3.0), (3.0, -1.0)];
        let l = lin(&k);
        assert_eq!((l.at(-5.0), l.at(0.5), l.at(2.0), l.at(9.0)), (1.0, 2.0, 1.0, -1.0));
        let s = Track { interpolation: Interpolation::Smooth, ..l.clone() };
        for (t, v) in k {
            assert!((s.at(t) - v).abs() < 1e-6, "{t}");
        }
        // Catmull-Rom through collinear, evenly spaced keys is the line itself.
        let line = Track {
            interpolation: Interpolation::Smooth,
            keys: vec![(0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (3.0, 3.0)],
        };
        assert!((line.at(1.5) - 1.5).abs() < 1e-6);
    }

    fn rotation(text: &str) -> RotationTrack {
        ron::from_str(text).unwrap()
    }

    /// The angle of `q` about `axis`, in degrees in (-180, 180] (q must turn about that axis).
    fn degrees_about(q: Quat, axis: Vec3) -> f32 {
        let (a, angle) = q.to_axis_angle();
        let signed = if a.dot(axis) < 0.0 { -angle } else { angle };
        let d = signed.to_degrees();
        if d > 180.0 {
            d - 360.0
        } else if d <= -180.0 {
            d + 360.0
        } else {
            d
        }
    }

    #[test]
    fn rotations_turn_by_the_angles_written() {
        // Two full turns about y over two seconds: the object's angle at t is 360 t degrees.
        for keys in [
            "Linear([(0, Euler((0, 0, 0))), (2, Euler((0, 720, 0)))])",
            "Linear([(0, AxisAngle(axis: (0, 2, 0), degrees: 0)), (2, AxisAngle(axis: (0, 1, 0), degrees: 720))])",
        ] {
            let t = rotation(keys);
            for k in 0..=16 {
                let time = k as f32 / 8.0;
                let expect = degrees_about(Quat::from_rotation_y((360.0 * time).to_radians()), Vec3::Y);
                let got = degrees_about(t.at(time), Vec3::Y);
                let diff = (got - expect + 540.0).rem_euclid(360.0) - 180.0;
                assert!(diff.abs() < 1e-2, "{keys} at {time}: {got} vs {expect}");
            }
            // A quarter of the way is half a turn: the short way would not have moved at all.
            assert!(degrees_about(t.at(0.5), Vec3::Y).abs() > 179.9);
        }
        // -90 degrees turns the negative way; 270 turns the positive way (not -90 the short way).
        let neg = rotation("Linear([(0, Euler((0, 0, 0))), (1, Euler((0, -90, 0)))])");
        assert!((degrees_about(neg.at(0.5), Vec3::Y) + 45.0).abs() < 1e-3);
        let pos = rotation("Linear([(0, Euler((0, 0, 0))), (1, AxisAngle(axis: (0, 1, 0), degrees: 270))])");
        // Keys of different kinds: the shortest way, -45 halfway.
        assert!((degrees_about(pos.at(0.5), Vec3::Y) + 45.0).abs() < 1e-3);
        let pos = rotation("Linear([(0, Euler((0, 0, 0))), (1, Euler((0, 270, 0)))])");
        assert!((degrees_about(pos.at(0.5), Vec3::Y) - 135.0).abs() < 1e-3);
        // Smooth keys of a steady spin pass through their keys with no easing between them.
        let spin = rotation(
            "Smooth([(0, Euler((0, 0, 0))), (1, Euler((0, 90, 0))), (2, Euler((0, 180, 0))), (3, Euler((0, 270, 0)))])",
        );
        assert!((degrees_about(spin.at(1.5), Vec3::Y) - 135.0).abs() < 1e-3);
        assert!(
            (degrees_about(spin.at(2.0), Vec3::Y) - 180.0).abs() < 1e-3
                || (degrees_about(spin.at(2.0), Vec3::Y) + 180.0).abs() < 1e-3
        );
        let bad = ron::from_str::<Track<f32>>("Linear([(1, 0), (1, 2)])").unwrap_err().to_string();
        assert!(bad.contains("key times must increase"), "{bad}");
    }
}
