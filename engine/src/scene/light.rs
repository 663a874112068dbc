//! `background: ..` and `lights: [..]`: light from outside the scene and punctual lights (whose
//! kinds are registered in `lighting::punctual`).

use super::assets::ImageFile;
use crate::format::{Finite, NonNegative, Radiance};
pub use crate::lighting::punctual::{LightDesc, LightKind, LightModel, LightPosition};
use glam::Vec3;
use serde::Deserialize;

/// Radiance seen by rays that leave the scene.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields, rename = "Background")]
pub enum BackgroundDesc {
    /// No light from outside (default).
    #[default]
    Black,
    /// The same radiance in every direction.
    Constant(Radiance),
    /// `(1 - a) * bottom + a * top` with `a = 0.5 * (dir.y + 1)`.
    Sky {
        /// Radiance straight down (default (1, 1, 1)).
        #[serde(default = "white")]
        bottom: Radiance,
        /// Radiance straight up (default (0.5, 0.7, 1.0)).
        #[serde(default = "sky_blue")]
        top: Radiance,
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

fn white() -> Radiance {
    Radiance(Vec3::ONE)
}

fn sky_blue() -> Radiance {
    Radiance(Vec3::new(0.5, 0.7, 1.0))
}
