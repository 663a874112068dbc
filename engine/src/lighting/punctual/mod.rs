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
pub mod projector;
pub mod spot;
#[cfg(feature = "test-light")]
pub mod test_point;

use crate::format::registry::{fields, registry};
use crate::format::{Color, Radiance, V3};
use crate::lighting::lights::LightTexture;
pub use crate::lighting::lights::PunctualLight;
use crate::shape::MAX_COORDINATE;
use crate::texture::{TextureId, Textures};
use glam::Vec3;
use serde::{Deserialize, Deserializer, de::Error};

registry! {
    /// A light that is not an object: `Point(..)`, `Spot(..)`, `Directional(..)` or
    /// `Projector(..)`.
    #[derive(Debug, Clone)]
    pub enum LightDesc, LightKind: dyn LightModel, "Light",
        "a light such as Point(position: (0, 3, 0), intensity: (10, 10, 10))", fields {
        Point(point::Point),
        Spot(spot::Spot),
        Directional(directional::Directional),
        Projector(projector::Projector),
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

    /// The light in world space; `textures` resolves the textures it names.
    fn to_light(&self, textures: &LightTextures) -> PunctualLight;
}

impl LightDesc {
    /// See [`LightModel::check`].
    pub fn check(&self) -> Result<(), String> {
        self.model().check()
    }

    /// The light in world space; `textures` resolves the textures it names.
    pub fn to_light(&self, textures: &LightTextures) -> PunctualLight {
        self.model().to_light(textures)
    }
}

/// The scene's textures as a light's conversion reads them: by name, with their mean and size.
pub struct LightTextures<'a> {
    /// The runtime textures.
    pub textures: &'a Textures,
    /// The index of a texture name (names are checked when the scene is read).
    pub id: &'a dyn Fn(&str) -> TextureId,
}

impl LightTextures<'_> {
    /// A colour written out as a factor and no texture, or a texture's name as a factor of one
    /// and the texture.
    pub fn color(&self, c: &Color<Radiance>) -> (Vec3, Option<LightTexture>) {
        match c {
            Color::Value(v) => (v.0, None),
            Color::Texture(name) => {
                let id = (self.id)(name);
                (Vec3::ONE, Some(LightTexture { id, mean: self.textures.mean(id) }))
            }
        }
    }

    /// Width over height of a texture's image (1 for textures without one, as Mitsuba's
    /// textures other than bitmaps have a resolution of 1 x 1).
    pub fn aspect(&self, t: Option<LightTexture>) -> f64 {
        match t.and_then(|t| self.textures.resolution(t.id)) {
            Some((w, h)) => w as f64 / h as f64,
            None => 1.0,
        }
    }
}

/// An orthonormal frame looking along `dir` with `up` towards its +y, as Mitsuba's `look_at`
/// builds it: x = normalize(up x dir), y = dir x x; `None` when `up` is along `dir` (or either
/// is zero).
pub fn look_frame(dir: Vec3, up: Vec3) -> Option<[Vec3; 3]> {
    let z = dir.normalize_or_zero();
    let x = up.cross(z).normalize_or_zero();
    (z != Vec3::ZERO && x != Vec3::ZERO).then(|| [x, z.cross(x), z])
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
