//! `Point(position: (2, 3, 2), intensity: (10, 10, 10))`: an isotropic point light.

use super::{LightModel, LightPosition, PunctualLight};
use crate::format::Radiance;

/// An isotropic point light in `lights: [..]`: radiant intensity `intensity` (W/sr), the same in
/// every direction; irradiance `intensity cos / d^2` at distance d.
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
