//! A light that exists to test the light registry (cargo feature `test-light`): a point light
//! given by its radiant power, `TestPoint(position: (0, 3, 0), power: (100, 100, 100))`, in
//! this one file and registered by one line in `lighting/punctual/mod.rs`. It becomes the point
//! light of intensity `power / 4 pi` (W/sr).

use super::{LightModel, LightPosition, PunctualLight};
use crate::format::Rgb;
use std::f32::consts::PI;

/// An isotropic point light of radiant power `power` (W).
#[derive(serde::Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct TestPoint {
    /// Where it is.
    pub position: LightPosition,
    /// Radiant power (W), spread evenly over the sphere of directions.
    pub power: Rgb,
}

impl LightModel for TestPoint {
    fn to_light(&self, _: &super::LightTextures) -> PunctualLight {
        PunctualLight::Point { position: self.position.0.into(), intensity: self.power.0 / (4.0 * PI) }
    }
}
