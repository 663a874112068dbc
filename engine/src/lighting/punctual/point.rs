//! `Point(position: (2, 3, 2), intensity: (10, 10, 10))`: an isotropic point light.

use super::{LightModel, LightPosition, PunctualLight};
use crate::format::Radiance;

/// Radiant intensity in W/sr, the same in every direction.
#[derive(serde::Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct Point {
    /// Where it is.
    pub position: LightPosition,
    /// Radiant intensity (W/sr).
    pub intensity: Radiance,
}

impl LightModel for Point {
    fn to_light(&self, _: &super::LightTextures) -> PunctualLight {
        PunctualLight::Point { position: self.position.0.into(), intensity: self.intensity.0 }
    }
}
