//! Validated scalar and vector values. Each rejects bad input while it is being parsed, so the
//! error carries the line and column of the offending value.

use glam::Vec3;
use serde::{Deserialize, Deserializer, de::Error};

fn check<'de, D: Deserializer<'de>, T>(ok: bool, value: T, what: &str) -> Result<T, D::Error> {
    if ok { Ok(value) } else { Err(D::Error::custom(what)) }
}

fn vec3<'de, D: Deserializer<'de>>(d: D, what: &'static str) -> Result<Vec3, D::Error> {
    // Through `deserialize_any`, so that a number or a name where three numbers belong is
    // reported as that (`intensity: 30`: "expected an emitted colour (r, g, b)"), not as a
    // missing parenthesis.
    struct Three(&'static str);
    impl<'de> serde::de::Visitor<'de> for Three {
        type Value = (f32, f32, f32);
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.0)
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            <(f32, f32, f32)>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
        }
    }
    let (x, y, z) = d.deserialize_any(Three(what))?;
    let v = Vec3::new(x, y, z);
    check::<D, _>(v.is_finite(), v, &format!("expected three finite numbers, found ({x}, {y}, {z})"))
}

/// Three finite numbers `(x, y, z)`: a point or an offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3(pub Vec3);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        vec3(d, "three numbers (x, y, z)").map(V3)
    }
}

/// A non-zero vector `(x, y, z)`: a direction (stored with its largest component +-1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Direction(pub Vec3);

impl<'de> Deserialize<'de> for Direction {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = vec3(d, "a direction (x, y, z)")?;
        // Scaled so that the largest component is 1: `normalize` neither overflows nor underflows.
        let m = v.abs().max_element();
        check::<D, _>(m > 0.0, Direction(v / m), "expected a non-zero direction, found (0, 0, 0)")
    }
}

/// A linear RGB colour `(r, g, b)` with every component >= 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb(pub Vec3);

impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = vec3(d, "a colour (r, g, b)")?;
        check::<D, _>(
            v.min_element() >= 0.0,
            Rgb(v),
            &format!("expected a colour with components >= 0, found {v}"),
        )
    }
}

impl From<Rgb> for Vec3 {
    fn from(c: Rgb) -> Vec3 {
        c.0
    }
}

/// The largest component of an emitted colour ([`Radiance`]): the film sums samples exactly up
/// to 1e12 (larger ones are discarded and counted), and this leaves two orders of magnitude for
/// the gains of a path (a light seen close up, a lens focusing it) before a sample of an
/// ordinary bright light reaches that cap.
pub const MAX_EMISSION: f32 = 1e10;

/// An emitted colour `(r, g, b)` (radiance, intensity or irradiance): every component in
/// [0, [`MAX_EMISSION`]].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Radiance(pub Vec3);

impl<'de> Deserialize<'de> for Radiance {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = vec3(d, "an emitted colour (r, g, b)")?;
        let ok = v.min_element() >= 0.0 && v.max_element() <= MAX_EMISSION;
        check::<D, _>(
            ok,
            Radiance(v),
            &format!("expected an emitted colour with components in [0, {MAX_EMISSION:e}], found {v}"),
        )
    }
}

impl From<Radiance> for Vec3 {
    fn from(c: Radiance) -> Vec3 {
        c.0
    }
}

/// A reflectance `(r, g, b)` with every component in [0, 1] (more would create energy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Albedo(pub Vec3);

impl<'de> Deserialize<'de> for Albedo {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = vec3(d, "a reflectance (r, g, b)")?;
        let ok = v.min_element() >= 0.0 && v.max_element() <= 1.0;
        check::<D, _>(ok, Albedo(v), &format!("expected an albedo with components in [0, 1], found {v}"))
    }
}

impl From<Albedo> for Vec3 {
    fn from(c: Albedo) -> Vec3 {
        c.0
    }
}

/// A finite number.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Finite(pub f32);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f32::deserialize(d)?;
        check::<D, _>(x.is_finite(), Finite(x), &format!("expected a finite number, found {x}"))
    }
}

/// A finite number > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Positive(pub f32);

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f32::deserialize(d)?;
        check::<D, _>(
            x.is_finite() && x > 0.0,
            Positive(x),
            &format!("expected a finite number > 0, found {x}"),
        )
    }
}

/// A finite number >= 0.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct NonNegative(pub f32);

impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f32::deserialize(d)?;
        check::<D, _>(
            x.is_finite() && x >= 0.0,
            NonNegative(x),
            &format!("expected a finite number >= 0, found {x}"),
        )
    }
}

/// A vertical field of view in degrees, in (0, 180).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fov(pub f32);

impl<'de> Deserialize<'de> for Fov {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f32::deserialize(d)?;
        check::<D, _>(
            x > 0.0 && x < 180.0,
            Fov(x),
            &format!("expected a field of view in (0, 180) degrees, found {x}"),
        )
    }
}

/// A number in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitInterval(pub f32);

impl<'de> Deserialize<'de> for UnitInterval {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f32::deserialize(d)?;
        if (0.0..=1.0).contains(&v) {
            Ok(UnitInterval(v))
        } else {
            Err(D::Error::custom(format!("expected a number in [0, 1], found {v}")))
        }
    }
}

pub(crate) fn white() -> Rgb {
    Rgb(Vec3::ONE)
}

/// Which extent of the image a perspective `fov` spans, as Mitsuba 3's `fov_axis`
/// (`parse_fov` in mitsuba3 `src/librender/sensor.cpp`); a camera's and a projector's.
#[derive(Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[serde(rename = "FovAxis")]
pub enum FovAxis {
    /// The width (default).
    #[default]
    X,
    /// The height.
    Y,
    /// The diagonal.
    Diagonal,
    /// The smaller of width and height.
    Smaller,
    /// The larger of width and height.
    Larger,
}

impl FovAxis {
    /// tan(x_fov / 2), where x_fov is the horizontal field of view that `fov` degrees across
    /// this axis gives an image of `aspect` = width / height, as Mitsuba 3's `parse_fov` (in
    /// f64, as it).
    pub fn tan_half_x_fov(self, fov: f32, aspect: f64) -> f64 {
        let t = (0.5 * (fov as f64).to_radians()).tan();
        let axis = match self {
            FovAxis::Smaller if aspect > 1.0 => FovAxis::Y,
            FovAxis::Smaller => FovAxis::X,
            FovAxis::Larger if aspect > 1.0 => FovAxis::X,
            FovAxis::Larger => FovAxis::Y,
            other => other,
        };
        match axis {
            FovAxis::Y => t * aspect,
            FovAxis::Diagonal => t / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
            _ => t,
        }
    }
}

/// The name of a material defined in `materials`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaterialRef(pub String);

impl<'de> Deserialize<'de> for MaterialRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        super::context::names(|n| match n.map(|n| &n.materials) {
            Some(names) if names.is_empty() => {
                Err(D::Error::custom(format!("unknown material \"{name}\"; no materials are defined")))
            }
            Some(names) if !names.contains(&name) => {
                let list: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
                Err(D::Error::custom(format!("unknown material \"{name}\"; defined: {}", list.join(", "))))
            }
            _ => Ok(MaterialRef(name.clone())),
        })
    }
}

/// The kind that `names` (each kind with its spelling) gives the name `s`, or an error naming
/// `what` was asked for and listing the spellings: the command line's and the scene format's
/// enums that go by name.
pub fn by_name<K: Copy>(names: &[(&str, K)], s: &str, what: &str) -> Result<K, String> {
    names.iter().find(|(n, _)| *n == s).map(|&(_, k)| k).ok_or_else(|| {
        let spelled: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
        let list = match spelled.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
            _ => spelled.join(""),
        };
        format!("no {what} '{s}': there are {list}")
    })
}
