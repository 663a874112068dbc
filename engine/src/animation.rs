//! Keyframes: tracks of `(time, value)` keys in seconds, interpolated linearly or with a
//! Catmull-Rom spline (`Linear([..])`, `Smooth([..])` in RON); rotations by quaternion slerp.
//! Before the first key a track holds the first value, after the last the last.

use crate::scene::{Direction, Finite, Rgb, V3};
use glam::{Quat, Vec3};
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

impl Keyed for Quat {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.slerp(b, s)
    }
    fn catmull_rom(_: Self, p1: Self, p2: Self, _: Self, s: f32) -> Self {
        p1.slerp(p2, s * s * (3.0 - 2.0 * s))
    }
}

impl<T: Keyed> Track<T> {
    /// The value at `time`.
    pub fn at(&self, time: f32) -> T {
        let k = &self.keys;
        let last = k.len() - 1;
        if !(time > k[0].0) {
            return k[0].1;
        }
        if time >= k[last].0 {
            return k[last].1;
        }
        // The segment [k[i], k[i + 1]] holding `time`.
        let i = k.partition_point(|(t, _)| *t <= time) - 1;
        let s = (time - k[i].0) / (k[i + 1].0 - k[i].0);
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

/// A colour track (emitted radiance, components >= 0).
#[derive(Clone, Debug, PartialEq)]
pub struct RgbTrack(pub Track<Vec3>);

impl<'de> Deserialize<'de> for RgbTrack {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        track(d, |v: Rgb| v.0).map(RgbTrack)
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

impl<'de> Deserialize<'de> for Track<Quat> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut t = track(d, |r: RawRotation| match r {
            RawRotation::Euler(v) => {
                let r = v.0 * (std::f32::consts::PI / 180.0);
                Quat::from_euler(glam::EulerRot::ZYX, r.z, r.y, r.x)
            }
            RawRotation::AxisAngle { axis, degrees } => Quat::from_axis_angle(axis.0, degrees.0.to_radians()),
        })?;
        // Slerp takes the short way: keep neighbouring keys in one hemisphere.
        for i in 1..t.keys.len() {
            if t.keys[i].1.dot(t.keys[i - 1].1) < 0.0 {
                t.keys[i].1 = -t.keys[i].1;
            }
        }
        Ok(t)
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
    pub rotate: Option<Track<Quat>>,
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

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn rotations_slerp_the_short_way() {
        let t: Track<Quat> =
            ron::from_str("Linear([(0, Euler((0, 0, 0))), (1, AxisAngle(axis: (0, 1, 0), degrees: 270))])")
                .unwrap();
        // 270 degrees about +y is -90 the short way: halfway is -45.
        let half = t.at(0.5);
        let expect = Quat::from_axis_angle(Vec3::Y, -45f32.to_radians());
        assert!(half.dot(expect).abs() > 0.99999, "{half}");
        let bad = ron::from_str::<Track<f32>>("Linear([(1, 0), (1, 2)])").unwrap_err().to_string();
        assert!(bad.contains("key times must increase"), "{bad}");
    }
}
