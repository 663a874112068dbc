//! `background: ..` and `lights: [..]`: light from outside the scene and punctual lights.

use super::assets::ImageFile;
use crate::format::{Direction, Finite, NonNegative, Rgb, V3, white};
use crate::placement::MAX_COORDINATE;
use glam::Vec3;
use serde::{Deserialize, Deserializer, de::Error};

/// Radiance seen by rays that leave the scene.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields, rename = "Background")]
pub enum BackgroundDesc {
    /// No light from outside (default).
    #[default]
    Black,
    /// The same radiance in every direction.
    Constant(Rgb),
    /// `(1 - a) * bottom + a * top` with `a = 0.5 * (dir.y + 1)`.
    Sky {
        /// Radiance straight down (default (1, 1, 1)).
        #[serde(default = "white")]
        bottom: Rgb,
        /// Radiance straight up (default (0.5, 0.7, 1.0)).
        #[serde(default = "sky_blue")]
        top: Rgb,
    },
    /// `Environment(file: "sky.exr", scale: 1, rotate: 0)`: a lat-long HDR map (EXR or HDR,
    /// linear; relative to the scene file), sampled as a light by its luminance. A direction
    /// `d` looks up `u = atan2(d.x, -d.z) / 2 pi`, `v = acos(d.y) / pi` (the top row is +y, the
    /// left edge -z), bilinearly between texel centres.
    Environment {
        /// The map.
        file: ImageFile,
        /// Factor on its radiance (default 1).
        #[serde(default = "unit_scale")]
        scale: NonNegative,
        /// Rotation of the map about +y in degrees, counter-clockwise seen from above (default 0).
        #[serde(default)]
        rotate: Finite,
    },
}

fn unit_scale() -> NonNegative {
    NonNegative(1.0)
}

/// A light that is not an object: `Point(..)`, `Spot(..)` or `Directional(..)`.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields, rename = "Light")]
pub enum LightDesc {
    /// `Point(position: (2, 3, 2), intensity: (10, 10, 10))`: radiant intensity in W/sr, the
    /// same in every direction.
    Point {
        /// Where it is.
        position: LightPosition,
        /// Radiant intensity (W/sr).
        intensity: Rgb,
    },
    /// `Spot(position: (0, 4, 0), look_at: (0, 0, 0), intensity: (50, 50, 50), cone_angle: 30,
    /// falloff_start: 25)`: a point light shining into a cone about `look_at - position`.
    Spot {
        /// Where it is.
        position: LightPosition,
        /// A point on the cone's axis.
        look_at: V3,
        /// Radiant intensity on the axis (W/sr).
        intensity: Rgb,
        /// Half angle of the cone in degrees, in (0, 180) (default 30).
        #[serde(default = "default_cone")]
        cone_angle: Finite,
        /// Angle from the axis where the falloff to the cone's edge starts, in degrees, in
        /// [0, cone_angle] (default 25).
        #[serde(default = "default_falloff")]
        falloff_start: Finite,
    },
    /// `Directional(direction: (0, -1, 0), irradiance: (3, 3, 3))`: parallel light travelling
    /// along `direction`, of irradiance (W/m^2) on a surface facing it.
    Directional {
        /// The direction the light travels in.
        direction: Direction,
        /// Irradiance on a surface facing the light.
        irradiance: Rgb,
    },
}

fn default_cone() -> Finite {
    Finite(30.0)
}

fn default_falloff() -> Finite {
    Finite(25.0)
}

/// A light's position: three finite numbers within [`MAX_COORDINATE`] of the origin.
#[derive(Debug, Clone, Copy)]
pub struct LightPosition(pub Vec3);

impl<'de> Deserialize<'de> for LightPosition {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let p = V3::deserialize(d)?.0;
        match p.abs().max_element() <= MAX_COORDINATE {
            true => Ok(LightPosition(p)),
            false => {
                Err(D::Error::custom(format!("the light is beyond {MAX_COORDINATE:e} units from the origin")))
            }
        }
    }
}

impl LightDesc {
    /// Checks the cone of a spot light.
    pub(super) fn check(&self) -> Result<(), String> {
        if let LightDesc::Spot { position, look_at, cone_angle, falloff_start, .. } = *self {
            if !(cone_angle.0 > 0.0 && cone_angle.0 < 180.0) {
                return Err(format!(
                    "spot light: cone_angle must be in (0, 180) degrees, found {}",
                    cone_angle.0
                ));
            }
            if !(falloff_start.0 >= 0.0 && falloff_start.0 <= cone_angle.0) {
                return Err(format!(
                    "spot light: falloff_start must be in [0, cone_angle = {}] degrees, found {}",
                    cone_angle.0, falloff_start.0
                ));
            }
            if (look_at.0 - position.0).length_squared() == 0.0 {
                return Err("spot light: look_at is the light's position".into());
            }
        }
        Ok(())
    }

    /// The light in world space.
    pub fn to_light(&self) -> crate::lighting::lights::PunctualLight {
        use crate::lighting::lights::PunctualLight;
        match *self {
            LightDesc::Point { position, intensity } => {
                PunctualLight::Point { position: position.0.into(), intensity: intensity.0 }
            }
            LightDesc::Spot { position, look_at, intensity, cone_angle, falloff_start } => {
                PunctualLight::Spot {
                    position: position.0.into(),
                    axis: (look_at.0 - position.0).normalize().into(),
                    intensity: intensity.0,
                    // In f64, rounded: a C library's last bits reach the f32 only at a rounding tie.
                    cos_falloff: (falloff_start.0 as f64).to_radians().cos() as f32,
                    cos_total: (cone_angle.0 as f64).to_radians().cos() as f32,
                }
            }
            LightDesc::Directional { direction, irradiance } => PunctualLight::Directional {
                to_light: (-direction.0.normalize()).into(),
                irradiance: irradiance.0,
            },
        }
    }
}

fn sky_blue() -> Rgb {
    Rgb(Vec3::new(0.5, 0.7, 1.0))
}
