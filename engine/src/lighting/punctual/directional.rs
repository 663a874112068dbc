//! `Directional(direction: (0, -1, 0), irradiance: (3, 3, 3))`: parallel light.

use super::{LightModel, PunctualLight};
use crate::format::{Direction, Radiance};

/// Parallel light travelling along `direction`, of `irradiance` (W/m^2) on a surface facing it.
#[derive(serde::Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct Directional {
    /// The direction the light travels in.
    pub direction: Direction,
    /// Irradiance on a surface facing the light.
    pub irradiance: Radiance,
}

impl LightModel for Directional {
    fn to_light(&self, _: &super::LightTextures) -> PunctualLight {
        PunctualLight::Directional {
            to_light: (-self.direction.0.normalize()).into(),
            irradiance: self.irradiance.0,
        }
    }
}
