//! The lights a scene lists in `lights: [..]` that are not objects: each kind in its own file,
//! as a type holding its RON description (`Kind(field: value, ...)`) that implements
//! [`LightModel`]: its checks and its conversion into the runtime [`PunctualLight`] that the
//! light table samples. The `registry!` invocation below is the one list of kinds: it generates
//! [`LightDesc`] (the RON enum the scene parser fills) and [`LightKind`]. Adding a light whose
//! runtime form exists (a point light written another way) is its file, its `mod` line and its
//! line in the list; a light that shines differently also adds its variant to [`PunctualLight`]
//! (`lighting/lights.rs`), whose `match`es are the hot path of light sampling.

pub mod directional;
pub mod point;
pub mod spot;
#[cfg(feature = "test-light")]
pub mod test_point;

use crate::format::V3;
use crate::format::registry::{fields, registry};
pub use crate::lighting::lights::PunctualLight;
use crate::shape::MAX_COORDINATE;
use glam::Vec3;
use serde::{Deserialize, Deserializer, de::Error};

registry! {
    /// A light that is not an object: `Point(..)`, `Spot(..)` or `Directional(..)`.
    #[derive(Debug, Clone, Copy)]
    pub enum LightDesc, LightKind: dyn LightModel, "Light",
        "a light such as Point(position: (0, 3, 0), intensity: (10, 10, 10))", fields {
        Point(point::Point),
        Spot(spot::Spot),
        Directional(directional::Directional),
        #[cfg(feature = "test-light")]
        TestPoint(test_point::TestPoint),
    }
}

/// One kind of light, as its RON description (a struct that denies unknown fields).
pub trait LightModel {
    /// Checks what its fields' types do not (a spot's cone); the message is the scene's error,
    /// placed after the light.
    fn check(&self) -> Result<(), String> {
        Ok(())
    }

    /// The light in world space.
    fn to_light(&self) -> PunctualLight;
}

impl LightDesc {
    /// See [`LightModel::check`].
    pub fn check(&self) -> Result<(), String> {
        self.model().check()
    }

    /// The light in world space.
    pub fn to_light(&self) -> PunctualLight {
        self.model().to_light()
    }
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
